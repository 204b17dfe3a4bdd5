r"""The paper's algorithms by the paper's names (Bloch, Crouch and Ratiu 2024, Section 2).

Three maps, each with a reference loop written from its own equations (sharing only the solver
of :math:`J_D(U) = U\Lambda - \Lambda U^T = M`, as :func:`symrb.solve_moser_veselov` solves it)
and computed by default by the engine (below):

* the symmetric representation of the discrete rigid body (Section 2.1, equations
  ``discrbopteqns1`` and ``Ukdef1`` of the paper's source):
  :math:`J_D(U_k) = h\,(Q_k^TP_k - P_k^TQ_k)`, :math:`Q_{k+1} = Q_kU_k`,
  :math:`P_{k+1} = P_kU_k` (:func:`symmetric_step`, :func:`symmetric_flow`, and
  :func:`discrete_rigid_body_flow` started from the body momentum);
* MV-Algorithm 1, :math:`(Q_k, Q_{k+1}) \mapsto (Q_{k+1}, Q_{k+2})` (Section 2.2,
  :func:`mv_algorithm1`);
* MV-Algorithm 2, :math:`(Q_k, M_k) \mapsto (Q_{k+1}, M_{k+1})` (Section 2.2,
  :func:`mv_algorithm2`).

MV1-MV3 below name the three Moser-Veselov equations of Section 2.2 in the order the paper
prints them (labels ``mv1``, ``mv2``, ``mv3``):
:math:`\Omega_k = Q_k^TQ_{k-1}`, :math:`M_k = \Omega_k^T\Lambda - \Lambda\Omega_k`,
:math:`M_{k+1} = \Omega_kM_k\Omega_k^T`.  :func:`jd_residual` is the residual of
:math:`J_D(U) = M`.  To simulate the rigid body by any method (these maps' fast engine among
them) use :func:`symrb.rigid_body.simulate`.

Time step.  A discrete momentum is :math:`h` times the continuous one.  In the symmetric
representation ``P`` is on the continuous scale (:math:`Q^TP - P^TQ \approx M(t_k)`, so
``P0 = Q0 @ (M0 / 2)`` starts at the body momentum ``M0``) and :math:`h` multiplies it.  The
Moser-Veselov maps take discrete momenta as the paper does, :math:`M^{MV}_{k+1} = hM(t_k)`: with
the paper's indices (:math:`\Omega_k = Q_k^TQ_{k-1}`) the momentum :math:`M_{k+1}` belongs to the
step from :math:`Q_k` (claim D12: :math:`M_{k+1} = Q_k^TP_k - P_k^TQ_k`).  With this scaling each
map is a second-order approximation of the rigid body flow :math:`\dot Q = Q\Omega`,
:math:`\dot M = [M, \Omega]` at step :math:`h` (a symmetric variational integrator; measured in the
book and the tests).

Computed by the engine.  The three maps are the map of :func:`symrb.engine.mv_flow`
(:math:`J_D(U_k) = hM_k`, :math:`Q_{k+1} = Q_kU_k`, :math:`M_{k+1} = U_k^TM_kU_k`), with other
names for the states, so each runs as one ``mv_flow`` call (the compiled n = 3 loop for long runs;
any n and batch axes) and only the saved states are converted:

* symmetric representation: :math:`(Q_k, Q_k^TP_k - P_k^TQ_k)` is ``mv_flow``'s state at step
  ``h``; :math:`P_k = P_0U_0\cdots U_{k-1} = P_0Q_0^{-1}Q_k` at the saved states;
* MV-Algorithm 2: its :math:`Q_{k+1} = Q_k\Omega_{k+1}^T` uses the next momentum's solve, so
  :math:`(Q_k, M_{k+1})` is ``mv_flow``'s state (h = 1) from :math:`(Q_0, M_1)`; a saved
  :math:`M_k` is one engine step back from :math:`-M_{k+1}` (:math:`\Omega_k` solves
  :math:`J_D(V) = -M_{k+1}`, because :math:`\Lambda U - U^T\Lambda = U^T(U\Lambda - \Lambda U^T)U`):
  one solve per saved state (a batch), none per step;
* MV-Algorithm 1: :math:`(Q_k, M_{k+1})` from :math:`(Q_0, M_1)`,
  :math:`M_1 = \Omega_1^T\Lambda - \Lambda\Omega_1`, :math:`\Omega_1 = Q_1^TQ_0`; the first engine
  step recomputes :math:`Q_1` (the given one is returned).

The results are those of the step-by-step loops (to rounding; tests/test_paper_engine.py against
a SciPy run of the paper's equations), about as fast as ``mv_flow`` and drifting as little (the
energy and Casimir errors grow like :math:`\varepsilon\sqrt N`, not :math:`\varepsilon N`).
What differs: ``iterations`` counts the engine's Newton iterations of each step (summed over a
batch), and ``residual``, ``tol`` and ``condition`` are empty (the engine checks each solve
against its own tolerance and reports no residual).  With ``progress``, ``halve`` or
``diagnostics`` (and for MV-Algorithm 1 from a :math:`Q_0^TQ_1` off the branch through the
identity, and for any run that fails on the engine, which the reference loop then redoes and
reports as it always did) the reference loop runs instead: one
:func:`symrb.solve_moser_veselov`-type Newton solve a step, started from the previous :math:`U`,
with a progress bar (tqdm), the residual, tolerance and condition number of every solve and, with
``halve``, steps past the fold taken as :math:`2^j` substeps.

Arrays are batched: ``(..., n, n)``.  The flows return a :class:`DiscreteFlowSolution` (``t``,
the states by name in ``y`` with the time axis first, the Newton iteration counts, ``success``
and ``message``); a step that has no solution on the branch through the identity (past the fold
of :math:`J_D`) ends the run early with ``success`` False rather than raising, with the fold
diagnosis of that step's momentum (``fold``, ``h_max``), from the reference loop.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from . import _validate as v
from ._docs import fill
from ._generated import discrete_rigid_body as _gen
from ._generated import symmetric_rigid_body as _srb
from ._results import STEP_FAILURES, DiscreteFlowSolution
from ._stepping import _check_h, _check_steps, _engine_result, _prepare, _Run, _Stepper
from ._validate import Array
from .engine import mv_flow

__all__ = [
    "jd_residual",
    "symmetric_step",
    "symmetric_flow",
    "mv_algorithm1",
    "mv_algorithm2",
    "discrete_rigid_body_flow",
    "DiscreteFlowSolution",
]


@fill
def jd_residual(U: ArrayLike, M: ArrayLike, lam: ArrayLike) -> Array:
    r""":math:`U\Lambda - \Lambda U^T - M` (zero when ``U`` solves :math:`J_D(U) = M`; the paper's
    :math:`J_DU := U\Lambda - \Lambda U^T`, Section 2.1).

    Parameters
    ----------
    U : array_like, shape (..., n, n)
        A candidate solution (any square matrix).
    M : array_like, shape (..., n, n)
        The skew-symmetric right-hand side.
    %(lam_positive)s

    Returns
    -------
    ndarray, shape (..., n, n)
        The residual, broadcast over the batch axes.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> lam = np.array([0.7, 1.1, 1.6])
    >>> M = symrb.hat([0.1, -0.2, 0.3])
    >>> U = symrb.solve_moser_veselov(M, lam)
    >>> bool(np.abs(symrb.paper.jd_residual(U, M, lam)).max() < 1e-14)
    True
    """
    L = v.inertia(lam, positive=True)
    nn = L.shape[-1]
    return _gen.jd(v.square(U, "U", nn), L) - v.skew(M, "M", nn)


@fill
def symmetric_step(
    Q: ArrayLike, P: ArrayLike, lam: ArrayLike, h: float = 1.0
) -> tuple[Array, Array, Array]:
    r"""One step of the symmetric representation (paper, Section 2.1, labels ``discrbopteqns1``
    and ``Ukdef1``).

    Solves :math:`U\Lambda - \Lambda U^T = h(Q^TP - P^TQ)` on the branch through the identity and
    returns :math:`(QU, PU, U)`.

    Parameters
    ----------
    Q : array_like, shape (..., n, n)
        The attitude, in SO(n).
    P : array_like, shape (..., n, n)
        The costate (any square matrix; continuous scale, see the module docstring).
    %(lam_positive)s
    h : float, optional
        The time step, > 0 (``h = 1`` is the paper's map).

    Returns
    -------
    Q1, P1, U : ndarray, shape (..., n, n)
        The next state and the control :math:`U \in SO(n)`.

    Raises
    ------
    OutOfDomainError
        If :math:`h(Q^TP - P^TQ)` is past the fold of :math:`J_D` (see :func:`fold_scale`).

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> Q0, P0 = np.eye(3), symrb.hat([0.05, 0.1, 0.15])
    >>> Q1, P1, U = symrb.paper.symmetric_step(Q0, P0, [0.7, 1.1, 1.6], h=0.1)
    >>> bool(np.allclose(Q1, Q0 @ U) and np.allclose(U.T @ U, np.eye(3)))
    True
    """
    h = _check_h(h)
    L, (Qa, Pa), batch = _prepare(lam, (Q, "Q", "SO"), (P, "P", "square"))
    U = _Stepper(L, batch).solve(h * _srb.symmetric_momentum(Qa, Pa))
    return Qa @ U, Pa @ U, U


@fill
def symmetric_flow(
    Q0: ArrayLike,
    P0: ArrayLike,
    lam: ArrayLike,
    h: float,
    steps: int,
    *,
    save_every: int = 1,
    progress: bool = False,
    halve: bool = False,
    diagnostics: bool = False,
) -> DiscreteFlowSolution:
    r"""Iterate the symmetric representation (paper, Section 2.1) ``steps`` times from
    :math:`(Q_0, P_0)`.

    Computed by :func:`symrb.engine.mv_flow` from :math:`(Q_0, M_0)`,
    :math:`M_0 = Q_0^TP_0 - P_0^TQ_0`, at step ``h``: its :math:`(Q_k, M_k)` are this map's, and
    :math:`P_k = P_0Q_0^{-1}Q_k` (:math:`P_{k+1} = P_kU_k`) at the saved states.  With
    ``progress``, ``halve`` or ``diagnostics`` the reference loop (one solve a step, the residual,
    tolerance and condition number of each) runs instead; the two agree to rounding.

    Parameters
    ----------
    %(Q0)s
    P0 : array_like, shape (..., n, n)
        The initial costate (any square matrix; continuous scale, see the module docstring).
    %(lam_positive)s
    h : float
        The time step, > 0 (``h = 1`` is the paper's map).
    %(steps)s
    save_every : int, optional
        Keep every ``save_every``-th state (``s``): the states :math:`k = 0, s, 2s, \dots`.
    %(progress)s
    %(halve)s
    %(diagnostics)s

    Returns
    -------
    DiscreteFlowSolution
        ``t`` the times :math:`kh`; ``y.Q``, ``y.P`` and the body momentum
        ``y.M`` :math:`= Q_k^TP_k - P_k^TQ_k` (continuous scale), each of shape ``(K, ..., n, n)``
        with :math:`K = \lfloor steps/s\rfloor + 1`; the Newton iterations of each step
        (``residual``, ``tol`` and ``condition`` are empty unless the reference loop ran).  When
        a step fails (past the fold of :math:`J_D`), ``success`` is False, ``message`` says why
        (with ``fold`` and ``h_max``) and the last state reached is the last one returned.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> lam = np.array([0.7, 1.1, 1.6])
    >>> Q0, P0 = np.eye(3), symrb.hat([0.05, 0.1, 0.15])
    >>> sol = symrb.symmetric_flow(Q0, P0, lam, 0.1, 100, save_every=50)
    >>> sol.t
    array([ 0.,  5., 10.])
    >>> sol.y.Q.shape
    (3, 3, 3)
    >>> H = symrb.kinetic_energy(sol.y.M, lam)  # conserved to rounding
    >>> bool(np.ptp(H) < 1e-15)
    True
    """
    h = _check_h(h)
    steps, save_every = _check_steps(steps, save_every)
    L, (Q, P), batch = _prepare(lam, (Q0, "Q0", "SO"), (P0, "P0", "square"))
    method = "symmetric representation"
    return _symmetric_engine_or_loop(Q, P, L, batch, h, steps, save_every, method, progress,
                                     halve, diagnostics)  # fmt: skip


def _symmetric_engine_or_loop(Q: Array, P: Array, L: Array, batch: tuple[int, ...], h: float,
                              steps: int, save_every: int, method: str, progress: bool,
                              halve: bool, diagnostics: bool) -> DiscreteFlowSolution:  # fmt: skip
    """A run of the symmetric algorithm from validated (Q, P): by :func:`_symmetric_engine`
    unless ``progress``, ``halve`` or ``diagnostics`` asks for the reference loop."""
    if progress or halve or diagnostics:
        return _symmetric_run(
            Q, P, L, batch, h, steps, save_every, progress, method, bool(halve), bool(diagnostics)
        )
    return _symmetric_engine(Q, P, L, batch, h, steps, save_every, method)


def _symmetric_engine(
    Q: Array,
    P: Array,
    L: Array,
    batch: tuple[int, ...],
    h: float,
    steps: int,
    save_every: int,
    method: str,
) -> DiscreteFlowSolution:
    r""":func:`symmetric_flow` by :func:`symrb.engine.mv_flow`: :math:`(Q_k, M_k)` with
    :math:`M_k = Q_k^TP_k - P_k^TQ_k` is its state at step ``h``, and
    :math:`P_k = P_0U_0\cdots U_{k-1} = P_0Q_0^{-1}Q_k` is recovered at the saved states."""
    sol = mv_flow(Q, _srb.symmetric_momentum(Q, P), L, h, steps, save_every=save_every)
    if not sol.success:  # the reference loop redoes the run and reports the failure
        return _symmetric_run(Q, P, L, batch, h, steps, save_every, False, method)
    Qs, Ms = sol.y["Q"], sol.y["M"]
    with np.errstate(over="ignore", invalid="ignore"):
        Ps = P @ np.linalg.solve(Q, Qs)
    y = {"Q": Qs, "P": Ps, "M": Ms}
    return _engine_result(sol, y, sol.k, method=method, h=h, steps=steps)


#: The most halvings of one step: 2^12 substeps at most (the work doubles with each halving;
#: j up to 30 meant up to 2^30 solves, a hang, for an h far past the fold).
_MAX_HALVINGS = 12


def _halved_step(
    stepper: _Stepper, run: _Run, Q: Array, P: Array, h: float
) -> tuple[Array, Array, int]:
    """One step of length h, as 2^j steps of h/2^j with the smallest j that works (j <= 12)."""
    for j in range(_MAX_HALVINGS + 1):
        Qj, Pj, hj = Q, P, h / 2.0**j
        try:
            for _ in range(2**j):
                U = stepper.solve(hj * _srb.symmetric_momentum(Qj, Pj))
                run.count(stepper)
                Qj, Pj = Qj @ U, Pj @ U
        except STEP_FAILURES:
            if j == _MAX_HALVINGS:
                raise
            stepper.U_prev = None  # the extrapolation assumes a fixed step
            continue
        if j:
            stepper.U_prev = None
        return Qj, Pj, j
    raise AssertionError("unreachable")  # pragma: no cover


def _symmetric_run(
    Q: Array,
    P: Array,
    L: Array,
    batch: tuple[int, ...],
    h: float,
    steps: int,
    save_every: int,
    progress: bool,
    method: str,
    halve: bool = False,
    diagnostics: bool = False,
) -> DiscreteFlowSolution:
    """The loop of :func:`symmetric_flow` on validated, broadcast input."""
    stepper = _Stepper(L, batch, diagnostics)
    run = _Run(steps, steps, method, progress)
    run.save(0, Q=Q.copy(), P=P.copy())
    k = 0
    try:
        for k in range(1, steps + 1):
            if halve:
                Q, P, j = _halved_step(stepper, run, Q, P, h)
                run.halvings.append(j)
            else:
                U = stepper.solve(h * _srb.symmetric_momentum(Q, P))
                run.count(stepper)
                Q, P = Q @ U, P @ U
            if k % save_every == 0:
                run.save(k, Q=Q, P=P)
            run.bar.step()
    except STEP_FAILURES as exc:
        scale = h / 2.0**_MAX_HALVINGS if halve else h
        run.fail(k, exc, stepper.fold(scale * _srb.symmetric_momentum(Q, P), exc), scale)
        if run.k[-1] != k - 1:
            run.save(k - 1, Q=Q, P=P)
    out = run.result(h)
    with np.errstate(over="ignore", invalid="ignore"):  # an overflow: check_finite says so
        out.y["M"] = np.asarray(_srb.symmetric_momentum(out.y["Q"], out.y["P"]), dtype=float)
    out.check_finite()
    return out


def _engine_or_loop(
    engine: Callable[..., DiscreteFlowSolution | None],
    loop: Callable[..., DiscreteFlowSolution],
    args: tuple[Any, ...],
    progress: bool,
    diagnostics: bool,
) -> DiscreteFlowSolution:
    """An MV-Algorithm run of ``args`` (the two states, ``L``, ``batch``, ``steps``,
    ``save_every``): by ``engine`` unless ``progress`` or ``diagnostics`` is asked, and by the
    reference ``loop`` then or when the engine gives None."""
    if not (progress or diagnostics):
        got = engine(*args)
        if got is not None:
            return got
    return loop(*args, progress, bool(diagnostics))


@fill
def mv_algorithm1(
    Q0: ArrayLike,
    Q1: ArrayLike,
    lam: ArrayLike,
    steps: int,
    *,
    save_every: int = 1,
    progress: bool = False,
    diagnostics: bool = False,
) -> DiscreteFlowSolution:
    r"""The paper's MV-Algorithm 1: :math:`(Q_k, Q_{k+1}) \mapsto (Q_{k+1}, Q_{k+2})`.

    Each step (paper, Section 2.2): :math:`\Omega_{k+1} = Q_{k+1}^TQ_k` (MV1),
    :math:`M_{k+1} = \Omega_{k+1}^T\Lambda - \Lambda\Omega_{k+1}` (MV2),
    :math:`M_{k+2} = \Omega_{k+1}M_{k+1}\Omega_{k+1}^T` (MV3), solve (MV2) for :math:`\Omega_{k+2}`,
    then :math:`Q_{k+2} = Q_{k+1}\Omega_{k+2}^T` (MV1).  For step h,
    start from :math:`Q_1 \approx Q(h)`.

    Computed by :func:`symrb.engine.mv_flow` (h = 1) from :math:`(Q_0, M_1)`, whose state after
    ``k`` steps is :math:`(Q_k, M_{k+1})`: ``steps + 1`` engine steps, the first recomputing
    :math:`Q_1 = Q_0U(M_1)` (the given :math:`Q_1` is returned; the later :math:`Q_k` agree with
    the reference loop's to its rounding, which forming :math:`M` from :math:`Q_{k+1}^TQ_k`
    amplifies by about :math:`|\Lambda|/|M|`).  The reference loop runs instead with ``progress``
    or ``diagnostics``, or when :math:`Q_0^TQ_1` is not on the branch through the identity.

    Parameters
    ----------
    Q0, Q1 : array_like, shape (..., n, n)
        The first two configurations, in SO(n).
    %(lam_positive)s
    steps : int
        The number of steps, >= 0; the last configuration is :math:`Q_{steps+1}`.
    save_every : int, optional
        Keep the configurations :math:`Q_0, Q_s, Q_{2s}, \dots` (``s = save_every``).
    %(progress)s
    %(diagnostics)s

    Returns
    -------
    DiscreteFlowSolution
        ``y.Q`` of shape ``(K, ..., n, n)``, ``K = floor((steps + 1)/s) + 1``; ``t`` and ``k``
        are the step indices; ``iterations`` those of the ``steps + 1`` engine steps (the
        reference loop: of its ``steps`` solves).  A failed step gives ``success`` False (see
        :class:`DiscreteFlowSolution`).

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> lam = np.array([0.7, 1.1, 1.6])
    >>> Q1 = symrb.solve_moser_veselov(symrb.hat([0.01, 0.02, 0.03]), lam)
    >>> sol = symrb.mv_algorithm1(np.eye(3), Q1, lam, 9, save_every=5)
    >>> sol.k, sol.y.Q.shape
    (array([ 0,  5, 10]), (3, 3, 3))
    """
    steps, save_every = _check_steps(steps, save_every)
    L, (Qa, Qb), batch = _prepare(lam, (Q0, "Q0", "SO"), (Q1, "Q1", "SO"))
    args = (Qa, Qb, L, batch, steps, save_every)
    return _engine_or_loop(_mv1_engine, _mv1_reference, args, progress, diagnostics)


def _mv1_engine(
    Qa: Array, Qb: Array, L: Array, batch: tuple[int, ...], steps: int, save_every: int
) -> DiscreteFlowSolution | None:
    r""":func:`mv_algorithm1` by :func:`symrb.engine.mv_flow` (h = 1): its state ``j`` is
    :math:`(Q_j, M_{j+1})` from :math:`(Q_0, M_1)`, :math:`M_1` from (MV1), (MV2); its first step
    recomputes :math:`Q_1 = Q_0U(M_1)`.  None when that :math:`U` is not the given
    :math:`Q_0^TQ_1` (off the branch through the identity, or the solve fails): the reference
    loop runs then."""
    nn = L.shape[-1]
    U1 = np.swapaxes(Qa, -1, -2) @ Qb  # Omega_1^T
    M1 = _gen.mv_momentum(np.swapaxes(U1, -1, -2), np.broadcast_to(L, batch + (nn,)))
    eig = np.linalg.eigvals(U1 * np.broadcast_to(L, batch + (nn,))[..., None, :])
    if not np.all(eig.real > 0):  # the branch through the identity (solve_moser_veselov)
        return None
    sol = mv_flow(Qa, M1, L, 1.0, steps + 1, save_every=save_every)
    if not sol.success:
        return None  # the reference loop redoes the run and reports the failure
    Qs = sol.y["Q"].copy()
    if save_every == 1 and Qs.shape[0] > 1:
        Qs[1] = Qb  # the given Q_1 (the engine's equals it to rounding)
    return _engine_result(sol, {"Q": Qs}, sol.k, method="MV-Algorithm 1", h=None, steps=steps)


def _mv1_reference(
    Qa: Array,
    Qb: Array,
    L: Array,
    batch: tuple[int, ...],
    steps: int,
    save_every: int,
    progress: bool,
    diagnostics: bool,
) -> DiscreteFlowSolution:
    """The step-by-step loop of :func:`mv_algorithm1` (the reference)."""
    stepper = _Stepper(L, batch, diagnostics)
    run = _Run(steps, steps, "MV-Algorithm 1", progress)
    run.save(0, Q=Qa.copy())
    if save_every == 1:
        run.save(1, Q=Qb.copy())
    Lb = np.broadcast_to(L, batch + L.shape[-1:])
    k = 1
    pending = np.zeros(batch + (L.shape[-1],) * 2)
    try:
        for k in range(2, steps + 2):
            Om = np.swapaxes(Qb, -1, -2) @ Qa
            M = _gen.mv_momentum(Om, Lb)
            M_next = pending = _gen.mv_transport(Om, M)
            U = stepper.solve(M_next)  # U = Omega_{k}^T
            run.count(stepper)
            Qa, Qb = Qb, Qb @ U
            if k % save_every == 0:
                run.save(k, Q=Qb)
            run.bar.step()
    except STEP_FAILURES as exc:
        run.fail(k - 1, exc, stepper.fold(pending, exc))
        if run.k[-1] != k - 1:
            run.save(k - 1, Q=Qb)
    return run.result(None)


@fill
def mv_algorithm2(
    Q: ArrayLike,
    M: ArrayLike,
    lam: ArrayLike,
    steps: int,
    *,
    save_every: int = 1,
    progress: bool = False,
    diagnostics: bool = False,
) -> DiscreteFlowSolution:
    r"""The paper's MV-Algorithm 2: :math:`(Q_k, M_k) \mapsto (Q_{k+1}, M_{k+1})` (discrete
    momenta).

    Each step (paper, Section 2.2): solve (MV2) :math:`M_k = \Omega_k^T\Lambda -
    \Lambda\Omega_k` for :math:`\Omega_k`, :math:`M_{k+1} = \Omega_kM_k\Omega_k^T` (MV3), solve the
    same (MV2) for :math:`\Omega_{k+1}`, :math:`Q_{k+1} = Q_k\Omega_{k+1}^T` (MV1).  The solution
    for :math:`\Omega_{k+1}` is the next step's :math:`\Omega_k` (same equation), so one solve per
    step (and one before the first).

    Computed by :func:`symrb.engine.mv_flow` (h = 1): one engine step of :math:`M_0` gives
    :math:`M_1`, and the run from :math:`(Q_0, M_1)` has the state :math:`(Q_k, M_{k+1})` after
    ``k`` steps; each saved :math:`M_k` (k > 0) is one batched engine step back from
    :math:`-M_{k+1}` (module docstring).  The reference loop runs instead with ``progress`` or
    ``diagnostics`` (or when a solve outside the run fails); the two agree to rounding.

    Parameters
    ----------
    Q : array_like, shape (..., n, n)
        The initial configuration, in SO(n).
    M : array_like, shape (..., n, n)
        The initial discrete momentum (skew); with the paper's indices
        :math:`M_k \approx hM(t_{k-1})` (module docstring).
    %(lam_positive)s
    %(steps)s
    %(save_every)s
    %(progress)s
    %(diagnostics)s

    Returns
    -------
    DiscreteFlowSolution
        ``y.Q`` and ``y.M`` of shape ``(K, ..., n, n)``; ``t`` and ``k`` are the step indices.
        A failed step gives ``success`` False (see :class:`DiscreteFlowSolution`).

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> lam = np.array([0.7, 1.1, 1.6])
    >>> M1 = symrb.hat([0.01, 0.02, 0.03])  # h times the body momentum, h = 0.1
    >>> sol = symrb.mv_algorithm2(np.eye(3), M1, lam, 1000, save_every=500)
    >>> sol.k
    array([   0,  500, 1000])
    >>> spectra = np.linalg.eigvals(sol.y.M).imag  # (MV3) is a conjugation: spectrum conserved
    >>> bool(np.ptp(np.sort(spectra, axis=-1), axis=0).max() < 1e-15)
    True
    """
    steps, save_every = _check_steps(steps, save_every)
    L, (Qk, Mk), batch = _prepare(lam, (Q, "Q", "SO"), (M, "M", "skew"))
    args = (Qk, Mk, L, batch, steps, save_every)
    return _engine_or_loop(_mv2_engine, _mv2_reference, args, progress, diagnostics)


def _mv2_engine(
    Q0: Array, M0: Array, L: Array, batch: tuple[int, ...], steps: int, save_every: int
) -> DiscreteFlowSolution | None:
    r""":func:`mv_algorithm2` by :func:`symrb.engine.mv_flow` (h = 1): its state ``j`` is
    :math:`(Q_j, M_{j+1})` from :math:`(Q_0, M_1)`, :math:`M_1 = \Omega_0M_0\Omega_0^T` (one
    engine step of M alone); the saved :math:`M_j` (j > 0) is one batched engine step back from
    :math:`-M_{j+1}` (:math:`J_D(V) = -M_{j+1}` is solved by :math:`V = \Omega_j`, and
    :math:`V^T(-M_{j+1})V = -M_j`).  None when a solve outside the run fails (the reference loop
    runs then and reports it)."""
    eye = np.eye(L.shape[-1])
    first = mv_flow(eye, M0, L, 1.0, 1)
    if not first.success:
        return None
    sol = mv_flow(Q0, first.y["M"][-1], L, 1.0, steps, save_every=save_every)
    if not sol.success:
        return None  # the reference loop redoes the run and reports the failure
    Ms = sol.y["M"].copy()
    Ms[0] = M0
    if Ms.shape[0] > 1:
        back = mv_flow(eye, -sol.y["M"][1:], L, 1.0, 1)
        if not back.success:
            return None
        Ms[1:] = -back.y["M"][-1]
    its = np.concatenate([first.iterations, sol.iterations], dtype=np.int64)
    return _engine_result(
        sol,
        {"Q": sol.y["Q"], "M": Ms},
        sol.k,
        method="MV-Algorithm 2",
        h=None,
        steps=steps,
        iterations=its,
    )


def _mv2_reference(
    Qk: Array,
    Mk: Array,
    L: Array,
    batch: tuple[int, ...],
    steps: int,
    save_every: int,
    progress: bool,
    diagnostics: bool,
) -> DiscreteFlowSolution:
    """The step-by-step loop of :func:`mv_algorithm2` (the reference)."""
    stepper = _Stepper(L, batch, diagnostics)
    run = _Run(steps, steps + 1, "MV-Algorithm 2", progress)
    run.save(0, Q=Qk.copy(), M=Mk.copy())
    k = 1  # the solve before the loop belongs to the first step
    pending = Mk
    try:
        Om = np.swapaxes(stepper.solve(Mk), -1, -2)  # Omega_k from the paper's (MV2)
        run.count(stepper)
        for k in range(1, steps + 1):
            Mk_next = pending = _gen.mv_transport(Om, Mk)  # MV3
            Om = np.swapaxes(stepper.solve(Mk_next), -1, -2)  # Omega_{k+1} from (MV2)
            run.count(stepper)
            Mk = Mk_next
            Qk = Qk @ np.swapaxes(Om, -1, -2)  # (MV1): Q_{k+1} = Q_k Omega_{k+1}^T
            if k % save_every == 0:
                run.save(k, Q=Qk, M=Mk)
            run.bar.step()
    except STEP_FAILURES as exc:
        run.fail(k, exc, stepper.fold(pending, exc))
        if run.k[-1] != k - 1:
            run.save(k - 1, Q=Qk, M=Mk)
    return run.result(None)


@fill
def discrete_rigid_body_flow(
    Q0: ArrayLike,
    M0: ArrayLike,
    lam: ArrayLike,
    h: float,
    steps: int,
    *,
    save_every: int = 1,
    progress: bool = False,
    halve: bool = False,
    diagnostics: bool = False,
) -> DiscreteFlowSolution:
    r"""The discrete rigid body at step ``h`` from the body momentum ``M0`` (continuous scale).

    Runs :func:`symmetric_flow` from :math:`P_0 = Q_0M_0/2` (so :math:`Q_0^TP_0 - P_0^TQ_0 = M_0`;
    this costate is not orthogonal, but every costate with the same :math:`M_0`, e.g. the one in
    :math:`SO(n)`, :math:`Q_0\exp(\sinh^{-1}(M_0/2))`, gives the same :math:`Q_k`, claim D7).
    :math:`(Q_k, M_k)` with :math:`M_k = Q_k^TP_k - P_k^TQ_k` is a second-order approximation of
    :math:`(Q(t_k), M(t_k))`, :math:`t_k = kh`, of :math:`\dot Q = Q\Omega`,
    :math:`\dot M = [M,\Omega]`, :math:`\Omega = J^{-1}(M)`.  Computed as
    :func:`symmetric_flow` is: one :func:`symrb.engine.mv_flow` run from :math:`(Q_0, M_0)`
    (the reference loop with ``progress``, ``halve`` or ``diagnostics``).

    Parameters
    ----------
    %(Q0)s
    %(M0)s
    %(lam_positive)s
    %(h)s
    %(steps)s
    %(save_every)s
    %(progress)s
    %(halve)s
    %(diagnostics)s

    Returns
    -------
    DiscreteFlowSolution
        ``t`` the times :math:`kh`; ``y.Q``, ``y.M`` (and the costate ``y.P``) of shape
        ``(K, ..., n, n)``.  A failed step gives ``success`` False (see
        :class:`DiscreteFlowSolution`).

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> lam = np.array([0.7, 1.1, 1.6])
    >>> M0 = symrb.hat([0.5, 1.0, 1.5])
    >>> sol = symrb.discrete_rigid_body_flow(np.eye(3), M0, lam, 0.01, 1000, save_every=500)
    >>> sol.t, sol.y.M.shape
    (array([ 0.,  5., 10.]), (3, 3, 3))

    Second order: halving h divides the error at t = 10 by 4.

    >>> exact = symrb.integrate(symrb.RigidBody, (0, 10), {"Q": np.eye(3), "M": M0}, lam=lam,
    ...                         rtol=1e-12, t_eval=[10.0]).y.M[-1]
    >>> def error(h):
    ...     N = round(10 / h)
    ...     sol = symrb.discrete_rigid_body_flow(np.eye(3), M0, lam, h, N, save_every=N)
    ...     return np.abs(sol.y.M[-1] - exact).max()
    >>> print(round(error(0.02) / error(0.01), 1))
    4.0
    """
    h = _check_h(h)
    steps, save_every = _check_steps(steps, save_every)
    L, (Q, M), batch = _prepare(lam, (Q0, "Q0", "SO"), (M0, "M0", "skew"))
    method = "discrete rigid body"
    P = Q @ (0.5 * M)
    return _symmetric_engine_or_loop(Q, P, L, batch, h, steps, save_every, method, progress,
                                     halve, diagnostics)  # fmt: skip
