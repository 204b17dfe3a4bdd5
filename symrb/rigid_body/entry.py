r"""One entry point to simulate the rigid body by any method: :func:`simulate`.

The dispatch table :data:`METHODS` maps each method name to its adapter (one module per method
family in this package); each adapter is a thin call of the implementation that stays the
reference (:func:`symrb.integrate`, :func:`symrb.engine.mv_flow`,
:func:`symrb.compose.composed_rigid_body_flow`, ...).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .. import _validate as v
from .._docs import fill
from .._validate import Array
from ..errors import InputError
from . import composition, exact, ivp, midpoint, mv, rkmk4, splitting
from ._request import Method, Request, RigidBodySolution

__all__ = ["simulate", "METHODS"]

#: method name -> how it is run and what it accepts (its keys are the methods of
#: :func:`simulate`; the value, a dict of adapters, is left out of the API reference)
#:
#: :meta hide-value:
METHODS: dict[str, Method] = {
    **ivp.METHODS,
    "mv": mv.METHOD,
    "composition": composition.METHOD,
    "rkmk4": rkmk4.METHOD,
    "midpoint": midpoint.METHOD,
    "exact": exact.METHOD,
    "splitting": splitting.METHOD,
}

#: how far (in steps) a time may be off the grid t0 + k h and still be read as on it
_GRID_TOL = 1e-6


def _method(method: object, options: dict[str, Any]) -> Method:
    if not isinstance(method, str) or method not in METHODS:
        raise InputError(f"method must be one of {list(METHODS)}, got {method!r}")
    spec = METHODS[method]
    unknown = sorted(set(options) - set(spec.options))
    if unknown:
        takes = f"its options are {list(spec.options)}" if spec.options else "it takes none"
        raise InputError(f"method {method!r} takes no option {unknown}; {takes}")
    return spec


def _order(method: str, spec: Method, order: object) -> int | None:
    if order is None:
        return spec.default_order
    if not spec.orders:
        raise InputError(f"order: method {method!r} has no order to choose; pass order=None")
    if isinstance(order, bool) or order not in spec.orders:
        raise InputError(f"order must be one of {spec.orders} for method {method!r}, got {order!r}")
    return int(order)  # type: ignore[call-overload]


def _span(t_span: Sequence[float]) -> tuple[float, float]:
    ts = v.as_float_array(t_span, "t_span")
    if ts.shape != (2,) or not ts[1] > ts[0]:
        raise InputError(f"t_span must be (t0, t1) with t1 > t0, got {t_span!r}")
    return float(ts[0]), float(ts[1])


def _steps(t0: float, t1: float, h: object) -> tuple[float, int] | tuple[None, None]:
    if h is None:
        return None, None
    hv = v.real_scalar(h, "h")
    if not hv > 0:
        raise InputError(f"h must be a finite number > 0, got {h!r}")
    steps = round((t1 - t0) / hv)
    if abs(steps * hv - (t1 - t0)) > _GRID_TOL * hv:
        raise InputError(
            f"h = {hv!r} does not divide t_span ({t0!r}, {t1!r}) into whole steps; pass h = "
            f"(t1 - t0) / N, e.g. {(t1 - t0) / max(steps, 1)!r}"
        )
    return hv, steps


def _times(
    t_eval: ArrayLike | None, t0: float, t1: float, h: float | None, on_grid: bool
) -> Array | None:
    if t_eval is None:
        return None
    te = v.as_float_array(t_eval, "t_eval")
    if te.ndim != 1 or te.size == 0 or np.any(np.diff(te) <= 0):
        raise InputError(f"t_eval must be a non-empty increasing 1-D array, got {t_eval!r}")
    if te[0] < t0 or te[-1] > t1:
        raise InputError(
            f"t_eval must lie in t_span ({t0!r}, {t1!r}), got {float(te[0])!r}..{float(te[-1])!r}"
        )
    if on_grid and h is not None:
        k = np.rint((te - t0) / h)
        off = np.abs(t0 + k * h - te) > _GRID_TOL * h
        if np.any(off):
            raise InputError(
                f"t_eval must be on the step grid t0 + k h (h = {h!r}) for a fixed-step method; "
                f"{te[off][:3].tolist()} are not"
            )
    return te


def _check_choices(
    method: str, spec: Method, h: float | None, save_every: object, t_eval: object, **given: Any
) -> int | None:
    """What a method refuses; returns the validated save_every."""
    if spec.fixed_step and h is None:
        raise InputError(f"h: method {method!r} is a fixed-step method; pass the step h > 0")
    if given["rtol"] is not None or given["atol"] is not None:
        if not spec.tolerances:
            raise InputError(
                f"rtol, atol: method {method!r} has a fixed step (or is exact) and takes no "
                "tolerances; pass h (its accuracy follows from h and the order)"
            )
    if not isinstance(given["progress"], bool | np.bool_):
        raise InputError(f"progress must be True or False, got {given['progress']!r}")
    if given["progress"] and not spec.progress:
        raise InputError(f"progress: method {method!r} has no progress bar; pass progress=False")
    if save_every is None:
        return None
    if t_eval is not None:
        raise InputError("pass t_eval or save_every, not both")
    if h is None:
        raise InputError("save_every needs h: the states kept are at t0 + k h, k = 0, s, 2s, ...")
    return v.count(save_every, "save_every", 1)


def _finite(sol: RigidBodySolution) -> RigidBodySolution:
    """Cut the solution before its first non-finite state (and mark it failed)."""
    axes = tuple(range(1, sol.Q.ndim))
    ok = np.isfinite(sol.Q).all(axis=axes) & np.isfinite(sol.M).all(axis=axes)
    if ok.all():
        return sol
    first = int(np.argmin(ok))
    at = float(sol.t[first])
    sol.t, sol.Q, sol.M = sol.t[:first], sol.Q[:first], sol.M[:first]
    sol.success = False
    sol.message += f"; the state is not finite from t = {at!r} on (cut there)"
    return sol


@fill
def simulate(
    Q0: ArrayLike,
    M0: ArrayLike,
    lam: ArrayLike,
    t_span: Sequence[float],
    *,
    method: str = "DOP853",
    h: float | None = None,
    order: int | None = None,
    t_eval: ArrayLike | None = None,
    save_every: int | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    progress: bool = False,
    **options: Any,
) -> RigidBodySolution:
    r"""Simulate the rigid body :math:`\dot Q = Q\Omega`, :math:`\dot M = [M, \Omega]`,
    :math:`\Omega = J^{-1}(M)`, by the method ``method``.

    Every method takes the continuous body momentum ``M0`` (the fixed-step methods solve
    :math:`J_D(U) = hM` inside) and returns a :class:`RigidBodySolution`.  The paper's own
    algorithms keep their names and signatures in :mod:`symrb.paper`.

    Parameters
    ----------
    %(Q0)s
    %(M0)s
    %(lam)s
        All entries > 0 for ``"mv"``, ``"composition"``, ``"rkmk4"`` and ``"midpoint"``.
    t_span : tuple of float
        ``(t0, t1)`` with ``t1 > t0``.
    method : str, optional
        One of :data:`METHODS`: ``"RK45"``, ``"RK23"``, ``"DOP853"`` (default), ``"Radau"``,
        ``"BDF"``, ``"LSODA"`` (:func:`scipy.integrate.solve_ivp` through
        :func:`symrb.integrate`), ``"mv"`` (:func:`symrb.engine.mv_flow`), ``"composition"``
        (:func:`symrb.compose.composed_rigid_body_flow`), ``"rkmk4"``, ``"midpoint"``
        (:mod:`symrb.compose`), ``"exact"`` (:func:`symrb.exact.rigid_body_exact`, n = 3) and
        ``"splitting"`` (:func:`symrb.splitting.splitting_flow`, explicit, any n).
    h : float, optional
        The time step, needed by the fixed-step methods (``"mv"``, ``"composition"``,
        ``"rkmk4"``, ``"midpoint"``, ``"splitting"``), which take ``(t1 - t0) / h`` steps (a
        whole number).  For the other methods it only sets the output grid :math:`t_0 + kh`.
    order : int, optional
        ``"mv"``: 2 (default), or 4, 6, 8, 10 (the preprocessed method, n = 3);
        ``"composition"`` and ``"splitting"``: 2, 4 (default), 6, 8; ``"rkmk4"`` is 4 and
        ``"midpoint"`` 2; the others take none.
    t_eval : array_like, optional
        Increasing output times in ``t_span``.  Fixed-step methods need them on the grid
        :math:`t_0 + kh` (they return the grid times); the others take any.
    save_every : int, optional
        Keep the states at :math:`t_0 + kh`, :math:`k = 0, s, 2s, \dots` (``s = save_every``),
        for every method (it needs ``h``; not with ``t_eval``).  With neither ``t_eval`` nor
        ``save_every``: every step for the fixed-step methods, the grid of ``h`` (when given)
        or the solver's own steps for the ``solve_ivp`` methods; ``"exact"`` needs ``t_eval`` or
        ``h``.
    rtol, atol : float, optional
        The tolerances of the ``solve_ivp`` methods (default ``1e-10``, ``1e-12``); the
        others refuse them.
    progress : bool, optional
        Show a tqdm progress bar (``"composition"``, ``"rkmk4"``, ``"midpoint"``).
    **options
        Options of one method: ``backend`` (``"mv"``: ``"auto"``, ``"newton"``,
        ``"fixed-point"``, ``"numpy"``, ``"numba"``, the ``method`` of
        :func:`~symrb.engine.mv_flow`; ``"splitting"``: ``"auto"``, ``"numpy"``, ``"numba"``,
        the ``method`` of :func:`~symrb.splitting.splitting_flow`), ``kind`` and ``step``
        (``"composition"``), ``condition`` (``solve_ivp`` methods), ``check`` (``"exact"``).

    Returns
    -------
    RigidBodySolution
        ``t``, ``Q``, ``M`` (time first), ``success``, ``message``, ``stats`` and the
        implementation's own result ``raw``.  A run that stops early (a step past the fold of
        :math:`J_D`, an overflow) has ``success`` False and ends at the last finite state.

    Raises
    ------
    InputError
        An unknown method (the message lists the known ones), an option or an order the method
        does not take, ``h`` missing for a fixed-step method, ``t_eval`` off the step grid, or
        invalid arrays (from the implementation).

    Examples
    --------
    >>> import numpy as np
    >>> from symrb import hat
    >>> from symrb.rigid_body import simulate
    >>> Q0, M0, lam = np.eye(3), hat([0.5, 1.0, 1.5]), [0.7, 1.1, 1.6]
    >>> exact = simulate(Q0, M0, lam, (0, 10), method="exact", t_eval=[10.0])
    >>> runs = [("mv", 2, 1e-2), ("mv", 10, 1e-13), ("composition", 8, 1e-11), ("rkmk4", None, 1e-6)]
    >>> for method, order, bound in runs:
    ...     sol = simulate(Q0, M0, lam, (0, 10), method=method, h=0.1, order=order,
    ...                    save_every=50)
    ...     print(method, sol.order, sol.t, bool(np.abs(sol.M[-1] - exact.M[-1]).max() < bound))
    mv 2 [ 0.  5. 10.] True
    mv 10 [ 0.  5. 10.] True
    composition 8 [ 0.  5. 10.] True
    rkmk4 4 [ 0.  5. 10.] True
    >>> sol = simulate(Q0, M0, lam, (0, 10), t_eval=[5.0, 10.0])  # DOP853
    >>> sol.method, sol.success, bool(np.abs(sol.M[-1] - exact.M[-1]).max() < 1e-9)
    ('DOP853', True, True)
    """
    spec = _method(method, options)
    t0, t1 = _span(t_span)
    hv, steps = _steps(t0, t1, h)
    req = Request(
        Q0=Q0,
        M0=M0,
        lam=lam,
        method=method,
        t0=t0,
        t1=t1,
        h=hv,
        steps=steps,
        order=_order(method, spec, order),
        t_eval=_times(t_eval, t0, t1, hv, spec.fixed_step),
        save_every=_check_choices(
            method, spec, hv, save_every, t_eval, rtol=rtol, atol=atol, progress=progress
        ),
        rtol=None if rtol is None else v.real_scalar(rtol, "rtol"),
        atol=None if atol is None else v.real_scalar(atol, "atol"),
        progress=bool(progress),
        options=options,
    )
    return _finite(spec.run(req))
