r"""Continuous-time flows on matrix variables and a ``solve_ivp``-style driver.

:class:`Flow` is a vector field on named ``(..., n, n)`` matrix variables; :class:`RigidBody` is
the rigid body :math:`\dot Q = Q\Omega`, :math:`\dot M = [M, \Omega]`,
:math:`\Omega = J^{-1}(M)` (paper, Section 3.1); the flows of Section 3.2 are in
:mod:`symrb.symmetric`.  :func:`integrate` runs any of them through
:func:`scipy.integrate.solve_ivp`; :func:`symrb.rigid_body.simulate` is the one entry point for
the rigid body by any method.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from . import _conditioning as _cond
from . import _validate as v
from ._generated import rigid_body as _rb
from ._ivp import MAX_NFEV, check_budget, solve_ivp_budget
from ._results import Trajectory, cut, first_nonfinite
from ._validate import Array
from .algebra import _Jinv_weights
from .errors import InputError

__all__ = [
    "Flow",
    "RigidBody",
    "Trajectory",
    "FlowSolution",
    "integrate",
]


# ---------------------------------------------------------------------------------------------
# flows and the driver


class Flow:
    r"""A vector field on named (..., n, n) matrix variables.

    Subclasses set ``name``, ``state`` (the names of the variables, in order) and implement
    :meth:`rhs` (raw, unvalidated: used inside the integrator), :meth:`check` (validation of an
    initial state) and optionally :meth:`derived` (quantities computed from a state, e.g. M).
    :func:`integrate` runs any of them.

    Examples
    --------
    A flow of one variable, :math:`\dot Q = QA` for a fixed skew :math:`A` (rotation at a constant
    body rate):

    >>> import numpy as np
    >>> import symrb
    >>> class ConstantRate(symrb.continuous.Flow):
    ...     name = "constant rate"
    ...     state = ("Q",)
    ...     def rhs(self, y, lam):
    ...         return (y["Q"] @ symrb.hat([0.0, 0.0, 1.0]),)
    >>> sol = symrb.integrate(ConstantRate, (0, np.pi / 2), {"Q": np.eye(3)}, lam=[1, 1, 1])
    >>> print(sol.y.Q[-1].round(6) + 0.0)
    [[ 0. -1.  0.]
     [ 1.  0.  0.]
     [ 0.  0.  1.]]
    """

    name: str = "flow"
    state: tuple[str, ...] = ()
    #: extra axes of each state variable before the matrix axes (1 for a sample axis)
    sample_axes: int = 0

    def rhs(self, y: Mapping[str, Array], lam: Array) -> tuple[Array, ...]:  # pragma: no cover
        raise NotImplementedError

    def check(self, y: Mapping[str, Array], lam: Array) -> None:
        """Validate an initial state (shapes are checked by :func:`integrate`)."""

    def derived(self, y: Mapping[str, Array], lam: Array) -> dict[str, Array]:
        """Quantities computed from the states along a solution (none by default)."""
        return {}

    def __repr__(self) -> str:
        return f"{type(self).__name__}(state={self.state})"


class RigidBody(Flow):
    r"""The rigid body :math:`\dot Q = Q\Omega`, :math:`\dot M = [M,\Omega]`,
    :math:`\Omega = J^{-1}M`.

    State ``("Q", "M")`` with Q in SO(n) and M skew-symmetric; derived ``Omega``.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> lam = np.array([0.7, 1.1, 1.6])
    >>> y0 = {"Q": np.eye(3), "M": symrb.hat([0.5, 1.0, 1.5])}
    >>> sol = symrb.integrate(symrb.RigidBody, (0, 10), y0, lam=lam, t_eval=[0, 5, 10])
    >>> sorted(sol.y), sol.y.M.shape
    (['M', 'Omega', 'Q'], (3, 3, 3))
    >>> print(np.ptp(symrb.kinetic_energy(sol.y.M, lam)) < 1e-9)
    True
    """

    name = "rigid body"
    state = ("Q", "M")

    def rhs(self, y, lam):
        return _rb.rigid_body_rhs(y["Q"], y["M"], lam)

    def check(self, y, lam):
        v.orthogonal(y["Q"], "y0['Q']")
        v.skew(y["M"], "y0['M']")

    def derived(self, y, lam):
        return {"Omega": _Jinv_weights(lam) * y["M"]}


@dataclass
class FlowSolution:
    r"""Result of :func:`integrate` (modelled on :func:`scipy.integrate.solve_ivp`'s result).

    Attributes
    ----------
    t : ndarray, shape (K,)
        The output times.
    y : Trajectory
        Each state variable and each derived quantity of the flow, time first: shape
        ``(K, ..., n, n)`` for matrices.
    success : bool
        False when the solver stopped early, or when a number of ``t`` or ``y`` is not finite
        (an overflow: the states are then cut before the first such time).
    status : int
        ``solve_ivp``'s status (0: reached the end, -1: failed).
    message : str
        Why the solver stopped.
    nfev : int
        The number of evaluations of the vector field.
    flow : Flow
        The flow that was integrated.
    condition : ndarray, shape (K,), or None
        With ``condition=True``: the relative condition number of the flow map from ``t0`` to
        each output time, :math:`\kappa(t) = \max_\delta \frac{\|D\varphi_t(y_0)\delta\|
        /\|y(t)\|}{\|\delta\|/\|y_0\|}` (norms of the whole state, every variable and batch
        item concatenated), estimated as described in :func:`integrate`.  None otherwise.
    error_estimate : ndarray, shape (K,), or None
        With ``condition=True``: :math:`\|y(t) - \hat y(t)\|/\|y(t)\|` for a run
        :math:`\hat y` at tolerances ``rtol / 100``, ``atol / 100`` (the residual of the
        trajectory against the equation's flow, to the accuracy of that run).  None otherwise.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> y0 = {"Q": np.eye(3), "M": symrb.hat([0.5, 1.0, 1.5])}
    >>> sol = symrb.integrate(symrb.RigidBody, (0, 1), y0, lam=[0.7, 1.1, 1.6], t_eval=[0, 1])
    >>> sol.success, sol.t, sol.y.Q.shape, sol.condition
    (True, array([0., 1.]), (2, 3, 3), None)
    """

    t: Array
    y: Trajectory
    success: bool
    status: int
    message: str
    nfev: int
    flow: Flow
    condition: Array | None = None
    error_estimate: Array | None = None

    def __post_init__(self) -> None:
        bad = first_nonfinite(self.t, self.y) if self.success else None
        if bad is None:
            return
        i, names = bad
        at = float(self.t[i]) if np.isfinite(self.t[i]) else i
        self.y, self.t = cut(self.t, self.y, i), self.t[:i]
        if self.condition is not None and self.error_estimate is not None:
            self.condition, self.error_estimate = self.condition[:i], self.error_estimate[:i]
        self.success, self.status = False, -1
        self.message += (
            f"; but {', '.join(names)} not finite from t = {at!r} on (cut there): the numbers "
            "overflowed float64, so the run is not a success"
        )


def _as_flow(flow: Any) -> Flow:
    if isinstance(flow, type) and issubclass(flow, Flow):
        return flow()
    if isinstance(flow, Flow):
        return flow
    raise InputError(
        f"flow must be a Flow (e.g. symrb.SymmetricRigidBody), got {type(flow).__name__} "
        f"{flow!r}; pass a subclass of symrb.continuous.Flow or an instance"
    )


def _solve_flat(
    fl: Flow,
    L: Array,
    shape: tuple[int, ...],
    y_init: Array,
    span: tuple[float, float],
    method: str,
    rtol: float,
    atol: float,
    te: Array | None,
    max_nfev: int = MAX_NFEV,
) -> tuple[Any, bool]:
    """``solve_ivp`` on the flat state (the variables of ``fl.state``, each of ``shape``,
    concatenated); returns the result and whether the vector field overflowed."""
    size = int(np.prod(shape))
    # The vector field as solve_ivp sees it: kept lean, since solve_ivp calls it thousands of
    # times (the state was validated once by the caller; views, not copies, of the flat state).
    blocks = [(name, slice(i * size, (i + 1) * size)) for i, name in enumerate(fl.state)]
    rhs = fl.rhs
    overflow = False

    def f_checked(_t: float, y: Array) -> Array:
        return np.concatenate(rhs({name: y[s].reshape(shape) for name, s in blocks}, L), axis=None)

    def on_overflow(_kind: str, _flag: int) -> None:  # NumPy calls it on overflow or inf - inf
        nonlocal overflow
        overflow = True

    try:
        # overflow is reported through ``success``/``message`` by the caller, not as warnings;
        # NumPy reports it through on_overflow, which costs nothing while no overflow happens
        with np.errstate(over="call", invalid="call", call=on_overflow):
            sol = solve_ivp_budget(f_checked, span, y_init, max_nfev=max_nfev, method=method,
                                   rtol=rtol, atol=atol, t_eval=te)  # fmt: skip
    except ValueError as exc:
        raise InputError(f"integrate: {exc}") from None
    return sol, overflow


#: the smallest rtol DOP853 and RK45 accept (scipy raises smaller ones to it with a warning)
_MIN_RTOL = 100 * float(np.finfo(float).eps)


def _flow_condition(
    fl: Flow,
    L: Array,
    shape: tuple[int, ...],
    y_init: Array,
    sol: Any,
    span: tuple[float, float],
    method: str,
    rtol: float,
    atol: float,
    max_nfev: int = MAX_NFEV,
) -> tuple[Array, Array]:
    """(kappa, error estimate) at the output times ``sol.t`` of a successful solve (see
    :func:`integrate`): the sensitivity of the batch of perturbed copies integrated with one
    step-size sequence, and the difference to a run at tolerances divided by 100."""
    nvar, size = len(fl.state), int(np.prod(shape))
    y = sol.y.T  # (K, d)

    def batch(Y0: Array) -> Array:
        b = Y0.shape[0]
        flat = Y0.reshape(b, nvar, size).transpose(1, 0, 2).reshape(-1)
        run, _ = _solve_flat(fl, L, (b,) + shape, flat, span, method, rtol, atol, sol.t, max_nfev)
        if not run.success:
            return np.full((sol.t.size, b, y_init.size), np.nan)
        return np.asarray(run.y.T.reshape(-1, nvar, b, size).transpose(0, 2, 1, 3)).reshape(
            -1, b, nvar * size
        )

    with np.errstate(over="ignore", invalid="ignore"):
        kappa = _cond.sensitivity(batch, y_init)
        tight = max(rtol / _cond.TIGHTER, _MIN_RTOL)
        ref, _ = _solve_flat(
            fl, L, shape, y_init, span, method, tight, atol / _cond.TIGHTER, sol.t, max_nfev
        )
        err = _cond.relative_difference(y, ref.y.T) if ref.success else np.full(sol.t.size, np.nan)
    return kappa, err


def _initial_state(
    fl: Flow, y0: Mapping[str, ArrayLike] | Sequence[ArrayLike], L: Array
) -> tuple[dict[str, Array], tuple[int, ...]]:
    """The validated initial state of ``fl`` (a float copy of each variable, broadcast to the
    common batch shape) and that shape."""
    nn = L.shape[-1]
    if isinstance(y0, Mapping):
        missing = [k for k in fl.state if k not in y0]
        extra = [k for k in y0 if k not in fl.state]
        if missing or extra:
            raise InputError(
                f"y0 for {fl.name} needs exactly the variables {fl.state}; "
                f"missing {missing}, unexpected {extra}; pass exactly those names"
            )
        items = [y0[k] for k in fl.state]
    else:
        items = list(y0)
        if len(items) != len(fl.state):
            raise InputError(
                f"y0 for {fl.name} must have {len(fl.state)} arrays {fl.state}, got {len(items)}; "
                "pass one array per state variable"
            )
    arrays = [v.square(a, f"y0[{k!r}]", nn) for a, k in zip(items, fl.state, strict=True)]
    if fl.sample_axes and any(a.ndim < 3 for a in arrays):
        raise InputError(
            f"y0 for {fl.name} needs a sample axis: shape (..., m, n, n); pass the samples "
            "stacked along axis -3"
        )
    try:
        arrays = list(np.broadcast_arrays(*arrays))
        Lb = L[(Ellipsis,) + (None,) * fl.sample_axes + (slice(None),)] if fl.sample_axes else L
        np.broadcast_shapes(Lb.shape[:-1] + (nn, nn), arrays[0].shape)
    except ValueError as exc:
        raise InputError(
            f"y0 and lam batch shapes do not broadcast: {exc}; pass arrays whose leading axes "
            "broadcast"
        ) from None
    shape = arrays[0].shape
    state0 = {k: np.array(a, dtype=float) for k, a in zip(fl.state, arrays, strict=True)}
    fl.check(state0, L)
    return state0, shape


def integrate(
    flow: Flow | type[Flow],
    t_span: Sequence[float],
    y0: Mapping[str, ArrayLike] | Sequence[ArrayLike],
    *,
    lam: ArrayLike,
    method: str = "DOP853",
    rtol: float = 1e-10,
    atol: float = 1e-12,
    t_eval: ArrayLike | None = None,
    condition: bool = False,
    max_nfev: int = MAX_NFEV,
) -> FlowSolution:
    r"""Integrate a :class:`Flow` with :func:`scipy.integrate.solve_ivp`.

    Parameters
    ----------
    flow : Flow or type of Flow
        The flow: :class:`RigidBody`, :class:`SymmetricRigidBody`, :class:`McLachlanScovel`,
        :class:`MultiSampleSymmetricRigidBody` (a class or an instance) or a subclass of
        :class:`Flow`.
    t_span : tuple of float
        The interval ``(t0, t1)``.
    y0 : mapping or sequence of array_like
        The initial state: a mapping from the flow's state names to arrays of shape
        ``(..., n, n)`` (``(..., m, n, n)`` with a sample axis for the multi-sample flow), or a
        sequence in the order of ``flow.state``.  Leading batch axes broadcast; the whole batch
        is integrated with one step-size sequence.  An attitude ``Q`` of :class:`RigidBody`,
        :class:`McLachlanScovel` and :class:`MultiSampleSymmetricRigidBody` must be in SO(n).
    lam : array_like, shape (..., n)
        The diagonal of :math:`\Lambda` (broadcast against the batch).
    method : str, optional
        The ``solve_ivp`` method (default ``"DOP853"``).
    rtol, atol : float, optional
        The relative and absolute tolerances of ``solve_ivp``.
    t_eval : array_like, optional
        Times at which to store the solution; ``None`` keeps the solver's steps.
    condition : bool, optional
        Also estimate the condition number of the flow and the error of the solution
        (``FlowSolution.condition`` and ``error_estimate``; see Notes).  Costs about five more
        integrations of the flow; nothing of it is computed by default.
    max_nfev : int, optional
        The budget of each integration: at most this many evaluations of the vector field
        (default 10^6, about a minute for the rigid body).  A stiff or long run that needs more
        stops with ``success`` False, no output times and the message saying where it stopped.

    Returns
    -------
    FlowSolution
        ``y`` holds each state variable and the flow's derived quantities, time first.
        ``success`` is False (and ``message`` says why) when the solver stops early.  Inputs are
        never mutated.

    Notes
    -----
    The equation is :math:`\dot y = f(y)`, :math:`y(t_0) = y_0` for the flow's field f.
    ``solve_ivp`` keeps each local error below about ``rtol`` :math:`|y|` + ``atol``; a local
    error committed at time s reaches time t multiplied by the derivative of the flow map
    :math:`D\varphi_{t-s}`, so the relative error at t is about the tolerance times

    .. math::

        \kappa(t) = \max_\delta\frac{\|D\varphi_t(y_0)\delta\|/\|y(t)\|}
        {\|\delta\|/\|y_0\|},

    the relative condition number of the solution (for the rigid body it grows linearly in t:
    a change of the energy changes the rotation rates).  With ``condition=True`` it is estimated
    at every output time by internal numerical differentiation: the solution and two copies
    started at :math:`y_0 + 10^{-7}\|y_0\|v_j` (random unit directions :math:`v_j` of the whole
    state, fixed seed, off the constraint sets too, as rounding is) are integrated as one batch
    with one step-size sequence, and :math:`\kappa(t)` is the largest relative growth of their
    differences (a lower bound of the norm, usually within a factor of a few).  The error
    estimate is the relative difference to a run at tolerances divided by 100 (limited by
    ``rtol / 100`` :math:`\ge 100\varepsilon`).

    Accuracy stated and tested (tests/test_conditions.py, the rigid body against its exact
    solution :func:`symrb.exact.rigid_body_exact`, the other flows against a run at
    ``rtol = 1e-13``; DOP853): the relative error at each output time is at most
    :math:`2\,e(t) + 10\,\tau(t)\,\kappa(t)`, with :math:`e(t)` the error estimate and
    :math:`\tau(t) = \mathrm{rtol} + \mathrm{atol}/\|y(t)\|_{rms}`
    (:math:`\|y\|_{rms} = \|y\|/\sqrt{\dim y}`).  The error is usually near
    :math:`\tau(t)\kappa(t)`, but a fixed multiple of that alone is not a bound: the global
    error adds up the local errors of all the steps (19 times it was found for the double
    bracket flow at :math:`\kappa = 0.5`); and the estimate alone misses errors the two runs
    share.
    For :class:`MultiSampleSymmetricRigidBody` (not conservative: the costates grow) this is
    not stated: an error committed at a later time s is amplified by :math:`D\varphi_{t-s}`,
    which the estimate from :math:`t_0` can underestimate (measured: 1.5 times the bound at
    ``rtol = 1e-6``).

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> lam = np.array([0.7, 1.1, 1.6])
    >>> M0 = symrb.hat([0.5, 1.0, 1.5])
    >>> sol = symrb.integrate(symrb.RigidBody, (0, 10), {"Q": np.eye(3), "M": M0}, lam=lam,
    ...                       t_eval=np.linspace(0, 10, 11))
    >>> sol.y.Q.shape
    (11, 3, 3)
    >>> casimir = symrb.casimir_traces(sol.y.M)[:, 0]  # tr M^2 is conserved
    >>> bool(np.ptp(casimir) < 1e-8)
    True

    The condition number grows linearly in time; the error stays below ``rtol`` times it:

    >>> sol = symrb.integrate(symrb.RigidBody, (0, 10), {"Q": np.eye(3), "M": M0}, lam=lam,
    ...                       t_eval=[0, 5, 10], condition=True)
    >>> print(sol.condition.round(1))
    [1.  2.4 4.4]
    >>> bool(np.all(sol.error_estimate <= 10 * 1e-10 * sol.condition))
    True
    """
    fl = _as_flow(flow)
    L = v.inertia(lam)
    state0, shape = _initial_state(fl, y0, L)

    ts = v.as_float_array(t_span, "t_span")
    if ts.shape != (2,):
        raise InputError(f"t_span must be (t0, t1), got shape {ts.shape}; pass two times")
    if not (v.real_scalar(rtol, "rtol") > 0 and v.real_scalar(atol, "atol") >= 0):
        raise InputError(
            f"need rtol > 0 and atol >= 0, got rtol={rtol}, atol={atol}; pass values in those "
            "ranges"
        )
    te = None if t_eval is None else v.as_float_array(t_eval, "t_eval")
    if not isinstance(condition, bool | np.bool_):
        raise InputError(f"condition must be True or False, got {condition!r}; pass a bool")
    max_nfev = check_budget(max_nfev)
    size = int(np.prod(shape))
    y_init = np.concatenate([state0[name].ravel() for name in fl.state])
    span = (float(ts[0]), float(ts[1]))
    sol, overflow = _solve_flat(fl, L, shape, y_init, span, method, rtol, atol, te, max_nfev)
    message = str(sol.message)
    if overflow and not sol.success:
        message += " (the vector field overflowed to inf/NaN: the state is too large)"
    nt = sol.t.shape[0]
    traj = Trajectory()
    for i, name in enumerate(fl.state):
        traj[name] = sol.y[i * size : (i + 1) * size].T.reshape((nt,) + shape)
    with np.errstate(over="ignore", invalid="ignore"):  # only after an overflow (see message)
        traj.update(fl.derived({name: traj[name] for name in fl.state}, L))
    kappa = err = None
    if condition and sol.success and nt:
        kappa, err = _flow_condition(fl, L, shape, y_init, sol, span, method, rtol, atol, max_nfev)
    return FlowSolution(
        t=sol.t,
        y=traj,
        success=bool(sol.success),
        status=int(sol.status),
        message=message,
        nfev=int(sol.nfev),
        flow=fl,
        condition=kappa,
        error_estimate=err,
    )
