r"""Higher order with the same structure: symmetric compositions, RKMK4 and the implicit midpoint rule.

The discrete rigid body of Section 2 (MV-Algorithm 2 at step :math:`h`, see
:func:`symrb.discrete_rigid_body_flow`) is a *symmetric* one-step map of order 2:
:math:`\Phi_{-h} = \Phi_h^{-1}`.  A symmetric composition

.. math::

    \Psi_h = \Phi_{\gamma_s h}\circ\cdots\circ\Phi_{\gamma_2 h}\circ\Phi_{\gamma_1 h},
    \qquad \gamma_{s+1-i} = \gamma_i,

is again symmetric and, for the coefficients of :func:`composition_coefficients`, of order
4, 6 or 8 (Hairer, Lubich and Wanner, *Geometric Numerical Integration*, 2nd ed., Springer 2006,
Section V.3.2).  Every stage is an MV step, so the composition keeps what one step keeps:
:math:`Q` in SO(n), :math:`M_{k+1} = U_k^TM_kU_k` (the spectrum of :math:`M`, hence every
Casimir, conserved to rounding) and the energy (to rounding, each MV step conserves it) and
symplecticity of the map.

The textbook alternatives, with the same result object
(:class:`symrb.paper.DiscreteFlowSolution`):

* RKMK4 (Munthe-Kaas 1998; Hairer, Lubich and Wanner, Section IV.8.2): the classical
  Runge-Kutta method of order 4 applied to :math:`\dot\Theta = \mathrm{dexp}^{-1}_{-\Theta}(\Omega)`
  with :math:`g = \exp\Theta` acting by :math:`(Q, M)\mapsto(Qg, g^TMg)`; order 4, Casimirs and
  orthogonality to rounding, not symmetric, energy drifts at order 4.
* the implicit midpoint rule on the Lie-Poisson equation,
  :math:`M_{k+1} = M_k + h[\bar M, \bar\Omega]`, :math:`\bar M = (M_k + M_{k+1})/2`,
  :math:`\bar\Omega = J^{-1}(\bar M)`, with :math:`Q_{k+1} = Q_k\,\mathrm{cay}(h\bar\Omega)`
  (:math:`\mathrm{cay}(A) = (I - A/2)^{-1}(I + A/2)`, so :math:`Q` stays orthogonal); symmetric,
  order 2, conserves the quadratic invariants (energy and :math:`\mathrm{tr}\,M^2`) but not
  the higher Casimirs (:math:`\mathrm{tr}\,M^4` for :math:`n\ge 5`).

Momenta here are on the continuous scale (the body momentum :math:`M(t_k)`; a base step at
step :math:`h` solves :math:`J_D(U) = hM`).  A *base step* is any object with a method
``step(Q, M, h) -> (Q, M)`` that advances by a real ``h`` of either sign (compositions of order
4 and more take negative substeps); :class:`~symrb.base_steps.MVStep` and
:class:`~symrb.base_steps.MidpointStep` (in :mod:`symrb.base_steps`) are the symmetric ones
shipped; the coefficients are in :mod:`symrb.composition`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from . import _compiled_n, _compiled_stages
from . import _validate as v
from ._docs import fill
from ._mv3 import _composed3
from ._progress import progress_bar
from ._results import STEP_FAILURES, DiscreteFlowSolution, Trajectory, step_failure
from ._validate import Array
from .base_steps import BaseStep, MidpointStep, RKMK4Step, _lam, _skew
from .composition import _DEFAULT_KIND, compose_steps, composition_coefficients
from .engine import MVStepper
from .errors import InputError

__all__ = [
    "composed_rigid_body_flow",
    "rkmk4_rigid_body_flow",
    "midpoint_rigid_body_flow",
]

_BACKENDS = ("auto", "numpy", "numba")
#: method="auto" runs RKMK4 and the midpoint rule compiled from this many body-steps
_NUMBA_MIN_STEPS = 500
#: compositions at n != 3 run compiled from this many sub-steps * bodies * n^3 (mv_flow's)
_NUMBA_MIN_WORK_N = 2_000_000

# ---------------------------------------------------------------------------------------------
# flows


def _prepare(
    Q0: ArrayLike, M0: ArrayLike, lam: ArrayLike, h: float, steps: int, save_every: int
) -> tuple[Array, Array, Array, float, int, int]:
    L = _lam(lam)
    nn = L.shape[-1]
    Q = v.orthogonal(Q0, "Q0", nn)
    M = v.bounded(v.skew(M0, "M0", nn), "M0")
    hv = v.real_scalar(h, "h")
    if not hv > 0:
        raise InputError(f"h must be a finite number > 0, got {h!r}")
    steps = v.count(steps, "steps", 0)
    save_every = v.count(save_every, "save_every", 1)
    try:
        batch = np.broadcast_shapes(Q.shape[:-2], M.shape[:-2], L.shape[:-1])
    except ValueError:
        raise InputError(
            f"the batch axes do not broadcast: lam {L.shape}, Q0 {Q.shape}, M0 {M.shape}"
        ) from None
    Q = np.broadcast_to(Q, batch + (nn, nn)).copy()
    M = _skew(np.broadcast_to(M, batch + (nn, nn)).copy())
    return Q, M, L, hv, steps, save_every


def _run(
    advance: Callable[[Array, Array], tuple[Array, Array]],
    counter: _Counter | None,
    Q: Array,
    M: Array,
    h: float,
    steps: int,
    save_every: int,
    method: str,
    progress: bool,
    compiled: Callable[[Array, Array], tuple[Array, Array, Any] | None] | None = None,
) -> DiscreteFlowSolution:
    """The loop shared by the flows: save every ``save_every``-th state, stop on a failed step.
    ``compiled``: a function of ``(Q, M)`` that takes the whole run at once (a loop of
    :mod:`symrb._compiled_stages`) and returns the saved states after the first and the iterations,
    or None when a step failed there (the loop then runs, and reports the failure)."""
    got = None if compiled is None else compiled(Q, M)
    if got is not None:
        bar = progress_bar(steps, method, progress)
        for _ in range(steps):
            bar.step()
        bar.close()
        ks = list(range(0, steps + 1, save_every))
        return _solution(ks, [Q, *got[0]], [M, *got[1]], got[2], "", h, steps, method)
    ks, Qs, Ms, its = [0], [Q.copy()], [M.copy()], []
    bar = progress_bar(steps, method, progress)
    failure = ""
    k = 0
    try:
        for k in range(1, steps + 1):
            Q, M = advance(Q, M)
            if counter is not None:
                its.extend(counter.pop())
            if k % save_every == 0:
                ks.append(k)
                Qs.append(Q)
                Ms.append(M)
            bar.step()
    except STEP_FAILURES as exc:
        failure = f"step {k} of {steps} failed: {step_failure(exc)}"
        if ks[-1] != k - 1:
            ks.append(k - 1)
            Qs.append(Q)
            Ms.append(M)
    bar.close()
    return _solution(ks, Qs, Ms, its, failure, h, steps, method)


def _solution(ks: list[int], Qs: list[Array], Ms: list[Array], its: Any, failure: str, h: float,
              steps: int, method: str) -> DiscreteFlowSolution:  # fmt: skip
    kk = np.asarray(ks, dtype=np.int64)
    return DiscreteFlowSolution(
        t=kk.astype(float) * h,
        k=kk,
        y=Trajectory(Q=np.stack(Qs), M=np.stack(Ms)),
        iterations=np.asarray(its, dtype=np.int64),
        success=not failure,
        status=-1 if failure else 0,
        message=failure or f"all {steps} steps taken",
        method=method,
        h=h,
    )


def _backend(method: str, steps: int, size: int) -> bool:
    """Whether a flow with option ``method`` runs compiled (:mod:`symrb._compiled_stages`)."""
    if method not in _BACKENDS:
        raise InputError(f"method must be one of {', '.join(_BACKENDS)}, got {method!r}")
    if method == "numba" and not _compiled_stages.AVAILABLE:
        raise InputError("method 'numba' needs numba installed (pip install numba)")
    return method == "numba" or (
        method == "auto" and _compiled_stages.AVAILABLE and steps * size >= _NUMBA_MIN_STEPS
    )


def _compiled_run(kind: str, L: Array, h: float, steps: int, save_every: int) -> Callable[
        [Array, Array], tuple[Array, Array, Any] | None]:  # fmt: skip
    """The ``compiled`` argument of :func:`_run` for ``kind`` "rkmk4" or "midpoint"."""

    def run(Q: Array, M: Array) -> tuple[Array, Array, Any] | None:
        n = Q.shape[-1]
        lam = np.broadcast_to(L, Q.shape[:-2] + (n,)).reshape(-1, n)
        Qf, Mf = Q.reshape(-1, n, n), M.reshape(-1, n, n)
        if kind == "rkmk4":
            Qs, Ms, fail = _compiled_stages.run_rkmk4(Qf, Mf, lam, h, steps, save_every)
            its: Any = np.zeros(0, dtype=np.int64)
        else:
            Qs, Ms, its, fail = _compiled_stages.run_midpoint(Qf, Mf, lam, h, steps, save_every)
        if fail or not (np.isfinite(Qs).all() and np.isfinite(Ms).all()):
            return None
        shape = (Qs.shape[0],) + Q.shape
        return Qs.reshape(shape), Ms.reshape(shape), its

    return run


def _mv_loops(Q: Array, M: Array, L: Array, batch: tuple[int, ...], h: float, steps: int,
              save_every: int, gammas: Array, method: str) -> DiscreteFlowSolution | None:  # fmt: skip
    """The MV composition without a Python object per stage, or None (the NumPy loop then runs).
    n = 3: :func:`symrb._mv3._composed3` (compiled with numba for runs worth it).  n != 3:
    :func:`_composed_n` when numba is importable and the run has at least
    ``_NUMBA_MIN_WORK_N`` stage-body-n^3 (mv_flow's threshold), else None."""
    n = Q.shape[-1]
    if n == 3:
        return _composed3(Q, M, MVStepper(L, batch), h, steps, save_every, gammas, method)
    work = steps * gammas.size * Q[..., 0, 0].size * n**3
    if steps == 0 or not _compiled_n.AVAILABLE or work < _NUMBA_MIN_WORK_N:
        return None
    return _composed_n(Q, M, L, batch, h, steps, save_every, gammas, method)


def _composed_n(Q: Array, M: Array, L: Array, batch: tuple[int, ...], h: float, steps: int,
                save_every: int, gammas: Array, method: str) -> DiscreteFlowSolution | None:  # fmt: skip
    """:func:`composed_rigid_body_flow` with the MV base step at n != 3, compiled: the first step
    on the NumPy path (:class:`symrb.engine.MVStepper`, the cold start with its branch check and
    Riccati fallback), the rest by :func:`symrb._compiled_n.run_composed_n`, each sub-step warm
    started from the same sub-step of the step before.  None when a stage fails (on either path,
    or non-finite): the caller runs its NumPy loop, which reports the failure."""
    n = Q.shape[-1]
    stepper = MVStepper(L, batch)
    g = np.asarray(gammas, dtype=float).ravel()
    Qf, Mf = Q.reshape(-1, n, n), M.reshape(-1, n, n)
    ws = []
    try:
        Q1, M1 = Qf, Mf
        for c in g:
            Q1, M1 = stepper.step(Q1, M1, c * h)
            ws.append(stepper._w)
    except STEP_FAILURES:
        return None
    Qs, Ms, fail = _compiled_n.run_composed_n(Q1, M1, np.stack(ws), h, g, stepper.lam, steps - 1,
                                              save_every, k0=1)  # fmt: skip
    if fail.any() or not (np.isfinite(Qs).all() and np.isfinite(Ms).all()):
        return None
    first = [(Q1, M1)] if save_every == 1 else []  # the first step, saved by neither loop
    states = [(Qf, Mf), *first, *zip(Qs, Ms, strict=True)]
    ks = list(range(0, steps + 1, save_every))
    Qk, Mk = [q.reshape(Q.shape) for q, _ in states], [m.reshape(M.shape) for _, m in states]
    return _solution(ks, Qk, Mk, [], "", h, steps, method)


class _Counter:
    """Collects ``last_iterations`` of a base step after each call (when it has one)."""

    def __init__(self, base: Any) -> None:
        self.base = base
        self.items: list[int] = []

    def wrap(self, state: tuple[Array, Array], h: float) -> tuple[Array, Array]:
        out = self.base.step(state[0], state[1], h)
        n = getattr(self.base, "last_iterations", None)
        if n is not None:
            self.items.append(int(n))
        return out

    def pop(self) -> list[int]:
        got, self.items = self.items, []
        return got


@fill
def composed_rigid_body_flow(
    Q0: ArrayLike,
    M0: ArrayLike,
    lam: ArrayLike,
    h: float,
    steps: int,
    order: int = 4,
    *,
    kind: str | None = None,
    step: str | BaseStep = "mv",
    save_every: int = 1,
    progress: bool = False,
) -> DiscreteFlowSolution:
    r"""The rigid body by a symmetric composition of a symmetric base step.

    Each step is :math:`\Phi_{\gamma_s h}\circ\cdots\circ\Phi_{\gamma_1 h}` with the
    coefficients :func:`composition_coefficients` ``(order, kind)`` and the base step
    :math:`\Phi` (by default one MV-Algorithm 2 step of :class:`symrb.engine.MVStepper`),
    approximating :math:`\dot Q = Q\Omega`, :math:`\dot M = [M, \Omega]`,
    :math:`\Omega = J^{-1}(M)` to order ``order``.

    Parameters
    ----------
    %(Q0)s
    %(M0)s
    %(lam_positive)s
    %(h)s
    steps : int
        The number of (composed) steps, >= 0.
    order : {2, 4, 6, 8}, optional
        The order of the composition (2: the base step alone).
    kind : str, optional
        The coefficients (see :func:`composition_coefficients`; by default Suzuki's 5 stages at
        order 4 and Kahan-Li at orders 6 and 8).
    step : {"mv", "midpoint"} or object, optional
        The base step: ``"mv"`` (:class:`symrb.engine.MVStepper`, the fast Moser-Veselov step;
        :class:`MVStep` is the same map through :func:`symrb.solve_moser_veselov`; without
        ``progress`` every stage runs in one loop: at n = 3 on the generated kernels, compiled
        by numba, when installed, for runs of at least 2 * 10^4 body-stages; at other n, when
        numba is installed and the run has at least 2 * 10^6 body-stages times n^3, the first
        step on :class:`symrb.engine.MVStepper` and the rest compiled
        (:func:`symrb._compiled_n.run_composed_n`, results equal to rounding; a run that fails
        there is redone by the stepper, which reports the failure)),
        ``"midpoint"`` (:class:`MidpointStep`), or any
        object with a method ``step(Q, M, h) -> (Q, M)`` that is symmetric and of order 2 (e.g.
        a faster engine); its ``last_iterations`` attribute, if any, is recorded.
    %(save_every)s
    %(progress)s

    Returns
    -------
    DiscreteFlowSolution
        ``t`` the times :math:`kh`; ``y.Q`` and ``y.M`` of shape ``(K, ..., n, n)``;
        ``iterations`` the solver iterations of each stage when the base step reports them in
        an attribute ``last_iterations`` (:class:`MidpointStep` does, :class:`MVStep` does not).
        A failed stage (e.g. past the fold of :math:`J_D` at a large :math:`|\gamma_i| h`)
        ends the run with ``success`` False.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> from symrb.compose import composed_rigid_body_flow
    >>> lam = np.array([0.7, 1.1, 1.6])
    >>> M0 = symrb.hat([0.5, 1.0, 1.5])
    >>> exact = symrb.integrate(symrb.RigidBody, (0, 1), {"Q": np.eye(3), "M": M0}, lam=lam,
    ...                         rtol=1e-13, atol=1e-13, t_eval=[1.0]).y.M[-1]
    >>> def error(h):
    ...     sol = composed_rigid_body_flow(np.eye(3), M0, lam, h, round(1 / h), order=4)
    ...     return np.abs(sol.y.M[-1] - exact).max()
    >>> print(round(float(np.log2(error(0.1) / error(0.05)))))  # fourth order
    4
    """
    Q, M, L, hv, steps, save_every = _prepare(Q0, M0, lam, h, steps, save_every)
    gammas = composition_coefficients(order, kind)
    kind_name = kind or _DEFAULT_KIND[int(order)]
    batch = np.broadcast_shapes(Q.shape[:-2], M.shape[:-2])
    if isinstance(step, str) and step == "mv" and not progress:
        # every stage in one loop, no Python object per stage; a failed stage leaves the run to
        # the general loop below
        sol = _mv_loops(Q, M, L, batch, hv, steps, save_every, gammas,
                        f"MV-Algorithm 2 composed to order {int(order)} ({kind_name}, "
                        f"{gammas.size} stages)")  # fmt: skip
        if sol is not None:
            return sol
    if isinstance(step, str):
        if step == "mv":  # the fast engine (Cayley-parametrised Newton, warm started)
            base: Any = MVStepper(L, batch)
            name = "MV-Algorithm 2"
        elif step == "midpoint":
            base = MidpointStep(L)
            name = "implicit midpoint"
        else:
            raise InputError(f'step must be "mv", "midpoint" or an object, got {step!r}')
    elif callable(getattr(step, "step", None)):
        base = step
        name = type(step).__name__
    else:
        raise InputError(
            f"step must be 'mv', 'midpoint' or an object with a method step(Q, M, h), got "
            f"{type(step).__name__}"
        )
    counter = _Counter(base)
    psi = compose_steps(counter.wrap, gammas)
    method = f"{name} composed to order {int(order)} ({kind_name}, {gammas.size} stages)"
    return _run(
        lambda q, m: psi((q, m), hv), counter, Q, M, hv, steps, save_every, method, progress
    )


@fill
def rkmk4_rigid_body_flow(
    Q0: ArrayLike,
    M0: ArrayLike,
    lam: ArrayLike,
    h: float,
    steps: int,
    *,
    save_every: int = 1,
    progress: bool = False,
    method: str = "auto",
) -> DiscreteFlowSolution:
    r"""The rigid body by RKMK4 (:class:`RKMK4Step`), order 4, explicit.

    Parameters
    ----------
    %(Q0)s
    %(M0)s
    %(lam_positive)s
    %(h)s
    %(steps)s
    %(save_every)s
    %(progress)s
    method : {"auto", "numpy", "numba"}, optional
        The backend: ``"numpy"`` the NumPy path (:class:`~symrb.base_steps.RKMK4Step`, the
        reference), ``"numba"`` the compiled loop of :mod:`symrb._compiled_stages` (needs numba; the
        same arithmetic, results equal to rounding; a run that fails there is redone on the
        NumPy path, which reports the failure), ``"auto"`` the compiled loop when numba is
        importable and the run has at least 500 body-steps.

    Returns
    -------
    DiscreteFlowSolution
        ``t`` the times :math:`kh`; ``y.Q`` and ``y.M``; no iterations (explicit).

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> from symrb.compose import rkmk4_rigid_body_flow
    >>> M0 = symrb.hat([0.5, 1.0, 1.5])
    >>> sol = rkmk4_rigid_body_flow(np.eye(3), M0, [0.7, 1.1, 1.6], 0.1, 100, save_every=50)
    >>> sol.t
    array([ 0.,  5., 10.])
    >>> c = symrb.casimir_traces(sol.y.M)[:, 0]  # tr M^2: conserved to rounding
    >>> bool(np.ptp(c) < 1e-13)
    True
    """
    Q, M, L, hv, steps, save_every = _prepare(Q0, M0, lam, h, steps, save_every)
    base = RKMK4Step(L)
    fast = _backend(method, steps, M[..., 0, 0].size)
    return _run(
        lambda q, m: base.step(q, m, hv), None, Q, M, hv, steps, save_every, "RKMK4", progress,
        _compiled_run("rkmk4", L, hv, steps, save_every) if fast else None,
    )  # fmt: skip


@fill
def midpoint_rigid_body_flow(
    Q0: ArrayLike,
    M0: ArrayLike,
    lam: ArrayLike,
    h: float,
    steps: int,
    *,
    save_every: int = 1,
    progress: bool = False,
    method: str = "auto",
) -> DiscreteFlowSolution:
    r"""The rigid body by the implicit midpoint rule (:class:`MidpointStep`), order 2, symmetric.

    Parameters
    ----------
    %(Q0)s
    %(M0)s
    %(lam_positive)s
    %(h)s
    %(steps)s
    %(save_every)s
    %(progress)s
    method : {"auto", "numpy", "numba"}, optional
        The backend: ``"numpy"`` the NumPy path (:class:`~symrb.base_steps.MidpointStep`, the
        reference), ``"numba"`` the compiled loop of :mod:`symrb._compiled_stages` (needs numba; the
        same arithmetic, results equal to rounding; a run that fails there is redone on the
        NumPy path, which reports the failure), ``"auto"`` the compiled loop when numba is
        importable and the run has at least 500 body-steps.

    Returns
    -------
    DiscreteFlowSolution
        ``t`` the times :math:`kh`; ``y.Q`` and ``y.M``; ``iterations`` the fixed-point
        iterations of each step.  A step whose iteration does not converge ends the run with
        ``success`` False.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> from symrb.compose import midpoint_rigid_body_flow
    >>> lam = [0.7, 1.1, 1.6]
    >>> M0 = symrb.hat([0.5, 1.0, 1.5])
    >>> sol = midpoint_rigid_body_flow(np.eye(3), M0, lam, 0.1, 100, save_every=100)
    >>> H = symrb.kinetic_energy(sol.y.M, lam)  # a quadratic invariant: conserved
    >>> bool(np.ptp(H) < 1e-13), sol.message
    (True, 'all 100 steps taken')
    """
    Q, M, L, hv, steps, save_every = _prepare(Q0, M0, lam, h, steps, save_every)
    counter = _Counter(MidpointStep(L))
    fast = _backend(method, steps, M[..., 0, 0].size)
    return _run(
        lambda q, m: counter.wrap((q, m), hv), counter, Q, M, hv, steps, save_every,
        "implicit midpoint", progress,
        _compiled_run("midpoint", L, hv, steps, save_every) if fast else None,
    )  # fmt: skip
