r"""Discrete rigid body flows (paper, Section 2): the symmetric representation and Moser-Veselov.

Three maps, each implemented from its own equations and sharing only the solver of
:math:`J_D(U) = U\Lambda - \Lambda U^T = M` (:func:`symrb.solve_moser_veselov`):

* the symmetric representation (paper, Section 2.1):
  :math:`J_D(U_k) = h\,(Q_k^TP_k - P_k^TQ_k)`, :math:`Q_{k+1} = Q_kU_k`, :math:`P_{k+1} = P_kU_k`;
* MV-Algorithm 1, :math:`(Q_k, Q_{k+1}) \mapsto (Q_{k+1}, Q_{k+2})` (paper, Section 2.2);
* MV-Algorithm 2, :math:`(Q_k, M_k) \mapsto (Q_{k+1}, M_{k+1})` (paper, Section 2.2).

MV1-MV3 below name the three Moser-Veselov equations of Section 2.2 in the order the paper
prints them.

Time step.  A discrete momentum is :math:`h` times the continuous one.  In the symmetric
representation ``P`` is on the continuous scale (:math:`Q^TP - P^TQ \approx M(t_k)`, so
``P0 = Q0 @ (M0 / 2)`` starts at the body momentum ``M0``) and :math:`h` multiplies it.  The
Moser-Veselov maps take discrete momenta as the paper does, :math:`M^{MV}_{k+1} = hM(t_k)`: with
the paper's indices (:math:`\Omega_k = Q_k^TQ_{k-1}`) the momentum :math:`M_{k+1}` belongs to the
step from :math:`Q_k` (claim D12: :math:`M_{k+1} = Q_k^TP_k - P_k^TQ_k`).  With this scaling each
map is a second-order approximation of the rigid body flow :math:`\dot Q = Q\Omega`,
:math:`\dot M = [M, \Omega]` at step :math:`h` (a symmetric variational integrator; measured in the
book and the tests).

Long runs: each step starts Newton from the previous :math:`U` (it changes by :math:`O(h^2)`),
only every ``save_every``-th state is kept, and ``progress=True`` shows a progress bar (tqdm).
Arrays are batched: ``(..., n, n)``.  The flows return a :class:`DiscreteFlowSolution` (``t``,
the states by name in ``y`` with the time axis first, the Newton iteration counts, ``success``
and ``message``); a step that has no solution on the branch through the identity (past the fold
of :math:`J_D`) ends the run early with ``success`` False rather than raising.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _validate as v
from ._generated import discrete_rigid_body as _gen
from ._generated import symmetric_rigid_body as _srb
from ._progress import progress_bar
from ._results import Trajectory
from ._validate import Array
from .errors import InputError, NotConvergedError, OutOfDomainError
from .solvers import _EPS, _condition, _fold_scale_one, _solve_batch, _warm_single

__all__ = [
    "jd_residual",
    "symmetric_step",
    "symmetric_flow",
    "mv_algorithm1",
    "mv_algorithm2",
    "discrete_rigid_body_flow",
    "DiscreteFlowSolution",
]

_MAXITER = 30


@dataclass
class DiscreteFlowSolution:
    r"""Result of the discrete flows (:func:`symmetric_flow`, :func:`mv_algorithm1`,
    :func:`mv_algorithm2`, :func:`discrete_rigid_body_flow`), modelled on :class:`FlowSolution`.

    Attributes
    ----------
    t : ndarray, shape (K,)
        The times :math:`kh` of the saved states; for the Moser-Veselov maps, which have no time
        step, the step indices ``k`` (as floats).
    k : ndarray of int, shape (K,)
        The step index of each saved state (``0, s, 2s, ...`` for ``save_every = s``).
    y : Trajectory
        The saved states by name, each of shape ``(K, ..., n, n)``: ``Q`` always, ``P`` and the
        body momentum ``M`` for the symmetric representation, ``M`` for MV-Algorithm 2.
    iterations : ndarray of int, shape (number of solves,)
        Newton iterations of each solve of :math:`J_D(U) = M`, in order (summed over a batch).
    success : bool
        True when every step was taken.
    status : int
        0 when every step was taken, -1 when a step failed (then ``message`` says why and the
        last state reached is the last saved one).
    message : str
        What happened, in words.
    method : str
        The name of the map.
    h : float or None
        The time step, or None for the Moser-Veselov maps.
    residual : ndarray, shape (number of solves,)
        :math:`\|U\Lambda - \Lambda U^T - M\|_F` of each solve (the largest over a batch).
    tol : ndarray, shape (number of solves,)
        The tolerance each residual met (the default of :func:`symrb.solve_moser_veselov`: ten
        times the rounding error of evaluating the residual): every entry of ``residual`` is at
        most its ``tol``.
    condition : ndarray, shape (number of solves,)
        The solver's condition estimate :math:`\kappa` of each solve (see
        :class:`symrb.MVSolveInfo`; the largest over a batch), with ``diagnostics=True``;
        NaN otherwise.
    failed_step : int or None
        The step that failed, or None.
    fold : float or None
        When a step failed: :math:`t^*` of :func:`symrb.fold_scale` for that step's momentum
        (below 1: it is past the fold by :math:`1/t^* - 1`; the smallest over a batch).
    h_max : float or None
        When a step of a flow with a time step failed: :math:`t^*h`, the step at which that
        step's momentum reaches the fold; every step below it can be taken there.
    halvings : ndarray of int, shape (steps taken,)
        With ``halve=True``: how many times each step was halved (0: taken whole; ``j``: as
        :math:`2^j` steps of :math:`h/2^j`).  Empty otherwise.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> Q0 = np.eye(3)
    >>> M0 = symrb.hat([0.1, 0.2, 0.3])
    >>> sol = symrb.discrete_rigid_body_flow(Q0, M0, [0.7, 1.1, 1.6], 0.1, 20, save_every=10)
    >>> sol.success, sol.t, sol.k
    (True, array([0., 1., 2.]), array([ 0, 10, 20]))
    >>> sol.y.Q.shape, sorted(sol.y)
    ((3, 3, 3), ['M', 'P', 'Q'])
    >>> sol.message
    'all 20 steps taken'
    """

    t: Array
    k: NDArray[np.int64]
    y: Trajectory
    iterations: NDArray[np.int64]
    success: bool
    status: int
    message: str
    method: str
    h: float | None = None
    residual: Array = field(default_factory=lambda: np.zeros(0))
    tol: Array = field(default_factory=lambda: np.zeros(0))
    condition: Array = field(default_factory=lambda: np.zeros(0))
    failed_step: int | None = None
    fold: float | None = None
    h_max: float | None = None
    halvings: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, dtype=np.int64))

    @property
    def nit(self) -> int:
        """The total number of Newton iterations."""
        return int(self.iterations.sum())


def jd_residual(U: ArrayLike, M: ArrayLike, lam: ArrayLike) -> Array:
    r""":math:`U\Lambda - \Lambda U^T - M` (zero when ``U`` solves :math:`J_D(U) = M`).

    Parameters
    ----------
    U : array_like, shape (..., n, n)
        A candidate solution (any square matrix).
    M : array_like, shape (..., n, n)
        The skew-symmetric right-hand side.
    lam : array_like, shape (..., n)
        The diagonal of :math:`\Lambda`, all entries > 0.

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
    >>> bool(np.abs(symrb.jd_residual(U, M, lam)).max() < 1e-14)
    True
    """
    L = v.inertia(lam, positive=True)
    nn = L.shape[-1]
    return _gen.jd(v.square(U, "U", nn), L) - v.skew(M, "M", nn)


def _check_steps(steps: int, save_every: int) -> tuple[int, int]:
    return v.count(steps, "steps", 0), v.count(save_every, "save_every", 1)


def _check_h(h: float) -> float:
    value = v.real_scalar(h, "h")
    if not value > 0:
        raise InputError(f"h must be a finite number > 0, got {h!r}; pass a float > 0")
    return value


class _Stepper:
    """Solves J_D(U) = M on a flat batch, warm-starting from the previous solution.

    After each solve ``last_iterations``, ``last_residual``, ``last_tol`` (and, with
    ``diagnostics``, ``last_condition``) describe it.
    """

    def __init__(self, lam: Array, batch: tuple[int, ...], diagnostics: bool = False) -> None:
        nn = lam.shape[-1]
        self.lam = np.broadcast_to(lam, batch + (nn,)).reshape(-1, nn)
        self.U: Array | None = None
        self.U_prev: Array | None = None
        self.diagnostics = diagnostics
        self.last_iterations = 0  # Newton iterations of the last solve (summed over the batch)
        self.last_residual = 0.0
        self.last_tol = 0.0
        self.last_condition = float("nan")

    def _record(self, U: Array, res: Array, tol: Array) -> None:
        if res.size:
            i = int(np.argmax(res / np.where(tol > 0, tol, 1.0)))
            self.last_residual, self.last_tol = float(res[i]), float(tol[i])
        if self.diagnostics and U.shape[0]:
            self.last_condition = float(np.max(_condition(U, self.lam)))

    def solve(self, M: Array) -> Array:
        Mf = M.reshape(self.lam.shape[0], *M.shape[-2:])
        Mf = 0.5 * (Mf - np.swapaxes(Mf, -1, -2))  # rounding leaves M skew only to ~eps
        tol = 10.0 * _EPS * np.sqrt(np.einsum("bij,bij->b", Mf, Mf))
        if self.U is not None and Mf.shape[0] == 1:
            guess = self.U[0]
            if self.U_prev is not None:
                # U changes smoothly along a run: extrapolate U_k (U_{k-1}^T U_k) (orthogonal)
                guess = guess @ (self.U_prev[0].T @ guess)
                # one Newton-Schulz step back to SO(n), so rounding errors in U^T U - I do not
                # compound from step to step
                guess = guess @ (1.5 * np.eye(guess.shape[-1]) - 0.5 * (guess.T @ guess))
            got = _warm_single(guess, Mf[0], self.lam[0], float(tol[0]), _MAXITER, True)
            if got is not None:
                self.U_prev = self.U
                self.U = got[0][None]
                self.last_iterations = got[1]
                self._record(self.U, np.array([got[2]]), np.array([got[3]]))
                return got[0].reshape(M.shape)
        U, it, res, _margin, _start, tol = _solve_batch(
            Mf, self.lam, tol, _MAXITER, self.U, floor=True
        )
        self.U_prev, self.U = self.U, U
        self.last_iterations = int(it.sum())
        self._record(U, res, tol)
        return U.reshape(M.shape)

    def fold(self, M: Array) -> float:
        """The smallest fold_scale over the batch of M (for the failure report)."""
        Mf = M.reshape(self.lam.shape[0], *M.shape[-2:])
        Mf = 0.5 * (Mf - np.swapaxes(Mf, -1, -2))
        return min(
            (_fold_scale_one(Mf[i], self.lam[i]) for i in range(Mf.shape[0])), default=np.inf
        )


def _prepare(
    lam: ArrayLike, *mats: tuple[ArrayLike, str, str]
) -> tuple[Array, list[Array], tuple[int, ...]]:
    L = v.inertia(lam, positive=True)
    nn = L.shape[-1]
    arrays = []
    for x, name, kind in mats:
        if kind == "SO":
            arrays.append(v.orthogonal(x, name, nn))
        elif kind == "skew":
            arrays.append(v.skew(x, name, nn))
        else:
            arrays.append(v.square(x, name, nn))
    try:
        batch = np.broadcast_shapes(L.shape[:-1], *[a.shape[:-2] for a in arrays])
    except ValueError:
        shapes = ", ".join(
            f"{name} {a.shape}" for (_x, name, _k), a in zip(mats, arrays, strict=True)
        )
        raise InputError(
            f"the batch axes do not broadcast: lam {L.shape}, {shapes}; pass arrays whose "
            "leading axes broadcast (numpy rules)"
        ) from None
    arrays = [np.broadcast_to(a, batch + (nn, nn)).copy() for a in arrays]
    return L, arrays, batch


class _Run:
    """Bookkeeping of a discrete run: saved states, Newton counts, failure, progress bar."""

    def __init__(self, steps: int, solves: int, method: str, progress: bool) -> None:
        self.steps, self.method = steps, method
        self.saved: dict[str, list[Array]] = {}
        self.k: list[int] = []
        self.iterations = np.zeros(solves, dtype=np.int64)
        self.residual = np.zeros(solves)
        self.tol = np.zeros(solves)
        self.condition = np.full(solves, np.nan)
        self.solves = 0
        self.failure = ""
        self.failed_step: int | None = None
        self.fold: float | None = None
        self.h_max: float | None = None
        self.halvings: list[int] = []
        self.bar = progress_bar(steps, method, progress)

    def save(self, k: int, **states: Array) -> None:
        self.k.append(k)
        for name, x in states.items():
            self.saved.setdefault(name, []).append(x)

    def count(self, stepper: _Stepper) -> None:
        if self.solves == self.iterations.shape[0]:  # halved steps solve more often
            grow = max(16, self.solves)
            self.iterations = np.concatenate([self.iterations, np.zeros(grow, dtype=np.int64)])
            self.residual = np.concatenate([self.residual, np.zeros(grow)])
            self.tol = np.concatenate([self.tol, np.zeros(grow)])
            self.condition = np.concatenate([self.condition, np.full(grow, np.nan)])
        i = self.solves
        self.iterations[i] = stepper.last_iterations
        self.residual[i], self.tol[i] = stepper.last_residual, stepper.last_tol
        self.condition[i] = stepper.last_condition
        self.solves += 1

    def fail(
        self, k: int, exc: Exception, fold: float | None = None, h: float | None = None
    ) -> None:
        self.failed_step, self.fold = k, fold
        note = ""
        if fold is not None and np.isfinite(fold):
            if fold <= 1.0:
                note = f" (the step's momentum is {(1.0 / fold - 1.0) * 100:.4g} % past the fold"
                if h is not None:
                    self.h_max = fold * h
                    note += (
                        f"; h = {h:.10g}, the largest step that works there is just below "
                        f"h_max = {self.h_max:.10g})"
                    )
                else:
                    note += f"; the momentum scaled by less than {fold:.10g} works)"
            else:
                note = (
                    f" (the step's momentum is inside the fold by {(1.0 - 1.0 / fold) * 100:.4g} %)"
                )
        self.failure = f"step {k} of {self.steps} failed: {exc}{note}"

    def result(self, t_scale: float | None) -> DiscreteFlowSolution:
        self.bar.close()
        k = np.asarray(self.k, dtype=np.int64)
        y = Trajectory({name: np.stack(xs) for name, xs in self.saved.items()})
        t = k.astype(np.float64) * (1.0 if t_scale is None else t_scale)
        halved = sum(1 for j in self.halvings if j)
        message = self.failure or f"all {self.steps} steps taken"
        if halved:
            message += (
                f"; {halved} step(s) halved (at most {max(self.halvings)} times) to stay inside "
                "the fold of J_D"
            )
        n = self.solves
        return DiscreteFlowSolution(
            t=t,
            k=k,
            y=y,
            iterations=self.iterations[:n],
            success=not self.failure,
            status=-1 if self.failure else 0,
            message=message,
            method=self.method,
            h=t_scale,
            residual=self.residual[:n],
            tol=self.tol[:n],
            condition=self.condition[:n],
            failed_step=self.failed_step,
            fold=self.fold,
            h_max=self.h_max,
            halvings=np.asarray(self.halvings, dtype=np.int64),
        )


def symmetric_step(
    Q: ArrayLike, P: ArrayLike, lam: ArrayLike, h: float = 1.0
) -> tuple[Array, Array, Array]:
    r"""One step of the symmetric representation (paper, Section 2.1).

    Solves :math:`U\Lambda - \Lambda U^T = h(Q^TP - P^TQ)` on the branch through the identity and
    returns :math:`(QU, PU, U)`.

    Parameters
    ----------
    Q : array_like, shape (..., n, n)
        The attitude, in SO(n).
    P : array_like, shape (..., n, n)
        The costate (any square matrix; continuous scale, see the module docstring).
    lam : array_like, shape (..., n)
        The diagonal of :math:`\Lambda`, all entries > 0.
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
    >>> Q1, P1, U = symrb.symmetric_step(Q0, P0, [0.7, 1.1, 1.6], h=0.1)
    >>> bool(np.allclose(Q1, Q0 @ U) and np.allclose(U.T @ U, np.eye(3)))
    True
    """
    h = _check_h(h)
    L, (Qa, Pa), batch = _prepare(lam, (Q, "Q", "SO"), (P, "P", "square"))
    U = _Stepper(L, batch).solve(h * _srb.symmetric_momentum(Qa, Pa))
    return Qa @ U, Pa @ U, U


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
    r"""Iterate the symmetric representation ``steps`` times from :math:`(Q_0, P_0)`.

    Parameters
    ----------
    Q0 : array_like, shape (..., n, n)
        The initial attitude, in SO(n).
    P0 : array_like, shape (..., n, n)
        The initial costate (any square matrix; continuous scale, see the module docstring).
    lam : array_like, shape (..., n)
        The diagonal of :math:`\Lambda`, all entries > 0.
    h : float
        The time step, > 0 (``h = 1`` is the paper's map).
    steps : int
        The number of steps, >= 0.
    save_every : int, optional
        Keep every ``save_every``-th state (``s``): the states :math:`k = 0, s, 2s, \dots`.
    progress : bool, optional
        Show a tqdm progress bar (needs the optional package tqdm).
    halve : bool, optional
        When a step has no solution on the branch (:math:`h` times the momentum past the fold of
        :math:`J_D`) or Newton fails, take it as :math:`2^j` steps of :math:`h/2^j` with the
        smallest such :math:`j \le 30` (for the continuous-time use, where :math:`h` is only a
        resolution); ``halvings`` and ``message`` say which steps were halved.  Without it such
        a step ends the run (``failed_step``, ``fold`` and ``h_max`` say where, how far past the
        fold and the largest step that works).
    diagnostics : bool, optional
        Also estimate the solver's condition number at every solve (``condition``; costs about
        sixteen Sylvester solves a step).

    Returns
    -------
    DiscreteFlowSolution
        ``t`` the times :math:`kh`; ``y.Q``, ``y.P`` and the body momentum
        ``y.M`` :math:`= Q_k^TP_k - P_k^TQ_k` (continuous scale), each of shape ``(K, ..., n, n)``
        with :math:`K = \lfloor steps/s\rfloor + 1`; the Newton iterations of each step.  When a
        step fails (past the fold of :math:`J_D`), ``success`` is False, ``message`` says why and
        the last state reached is the last one returned.

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
    return _symmetric_run(
        Q,
        P,
        L,
        batch,
        h,
        steps,
        save_every,
        progress,
        "symmetric representation",
        bool(halve),
        bool(diagnostics),
    )


_MAX_HALVINGS = 30


def _halved_step(
    stepper: _Stepper, run: _Run, Q: Array, P: Array, h: float
) -> tuple[Array, Array, int]:
    """One step of length h, as 2^j steps of h/2^j with the smallest j that works (j <= 30)."""
    for j in range(_MAX_HALVINGS + 1):
        Qj, Pj, hj = Q, P, h / 2.0**j
        try:
            for _ in range(2**j):
                U = stepper.solve(hj * _srb.symmetric_momentum(Qj, Pj))
                run.count(stepper)
                Qj, Pj = Qj @ U, Pj @ U
        except (OutOfDomainError, NotConvergedError):
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
    except (OutOfDomainError, NotConvergedError) as exc:
        scale = h / 2.0**_MAX_HALVINGS if halve else h
        run.fail(k, exc, stepper.fold(scale * _srb.symmetric_momentum(Q, P)), scale)
        if run.k[-1] != k - 1:
            run.save(k - 1, Q=Q, P=P)
    out = run.result(h)
    out.y["M"] = np.asarray(_srb.symmetric_momentum(out.y["Q"], out.y["P"]), dtype=float)
    return out


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
    r"""MV-Algorithm 1: :math:`(Q_k, Q_{k+1}) \mapsto (Q_{k+1}, Q_{k+2})`.

    Each step (paper, Section 2.2): :math:`\Omega_{k+1} = Q_{k+1}^TQ_k` (MV1),
    :math:`M_{k+1} = \Omega_{k+1}^T\Lambda - \Lambda\Omega_{k+1}` (MV2),
    :math:`M_{k+2} = \Omega_{k+1}M_{k+1}\Omega_{k+1}^T` (MV3), solve (MV2) for :math:`\Omega_{k+2}`,
    then :math:`Q_{k+2} = Q_{k+1}\Omega_{k+2}^T` (MV1).  For step h,
    start from :math:`Q_1 \approx Q(h)`.

    Parameters
    ----------
    Q0, Q1 : array_like, shape (..., n, n)
        The first two configurations, in SO(n).
    lam : array_like, shape (..., n)
        The diagonal of :math:`\Lambda`, all entries > 0.
    steps : int
        The number of steps, >= 0; the last configuration is :math:`Q_{steps+1}`.
    save_every : int, optional
        Keep the configurations :math:`Q_0, Q_s, Q_{2s}, \dots` (``s = save_every``).
    progress : bool, optional
        Show a tqdm progress bar (needs the optional package tqdm).
    diagnostics : bool, optional
        Also estimate the solver's condition number at every solve (``condition``; costs about
        sixteen Sylvester solves a step).

    Returns
    -------
    DiscreteFlowSolution
        ``y.Q`` of shape ``(K, ..., n, n)``, ``K = floor((steps + 1)/s) + 1``; ``t`` and ``k``
        are the step indices.  A failed step gives ``success`` False (see
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
    stepper = _Stepper(L, batch, bool(diagnostics))
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
    except (OutOfDomainError, NotConvergedError) as exc:
        run.fail(k - 1, exc, stepper.fold(pending))
        if run.k[-1] != k - 1:
            run.save(k - 1, Q=Qb)
    return run.result(None)


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
    r"""MV-Algorithm 2: :math:`(Q_k, M_k) \mapsto (Q_{k+1}, M_{k+1})` (discrete momenta).

    Each step (paper, Section 2.2): solve (MV2) :math:`M_k = \Omega_k^T\Lambda -
    \Lambda\Omega_k` for :math:`\Omega_k`, :math:`M_{k+1} = \Omega_kM_k\Omega_k^T` (MV3), solve the
    same (MV2) for :math:`\Omega_{k+1}`, :math:`Q_{k+1} = Q_k\Omega_{k+1}^T` (MV1).  The solution
    for :math:`\Omega_{k+1}` is the next step's :math:`\Omega_k` (same equation), so one solve per
    step (and one before the first).

    Parameters
    ----------
    Q : array_like, shape (..., n, n)
        The initial configuration, in SO(n).
    M : array_like, shape (..., n, n)
        The initial discrete momentum (skew); with the paper's indices
        :math:`M_k \approx hM(t_{k-1})` (module docstring).
    lam : array_like, shape (..., n)
        The diagonal of :math:`\Lambda`, all entries > 0.
    steps : int
        The number of steps, >= 0.
    save_every : int, optional
        Keep the states :math:`k = 0, s, 2s, \dots` (``s = save_every``).
    progress : bool, optional
        Show a tqdm progress bar (needs the optional package tqdm).
    diagnostics : bool, optional
        Also estimate the solver's condition number at every solve (``condition``; costs about
        sixteen Sylvester solves a step).

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
    stepper = _Stepper(L, batch, bool(diagnostics))
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
    except (OutOfDomainError, NotConvergedError) as exc:
        run.fail(k, exc, stepper.fold(pending))
        if run.k[-1] != k - 1:
            run.save(k - 1, Q=Qk, M=Mk)
    return run.result(None)


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
    :math:`\dot M = [M,\Omega]`, :math:`\Omega = J^{-1}(M)`.

    Parameters
    ----------
    Q0 : array_like, shape (..., n, n)
        The initial attitude, in SO(n).
    M0 : array_like, shape (..., n, n)
        The initial body momentum (skew-symmetric, continuous scale).
    lam : array_like, shape (..., n)
        The diagonal of :math:`\Lambda`, all entries > 0.
    h : float
        The time step, > 0.
    steps : int
        The number of steps, >= 0.
    save_every : int, optional
        Keep the states :math:`k = 0, s, 2s, \dots` (``s = save_every``).
    progress : bool, optional
        Show a tqdm progress bar (needs the optional package tqdm).
    halve : bool, optional
        When a step has no solution on the branch (:math:`h` times the momentum past the fold of
        :math:`J_D`) or Newton fails, take it as :math:`2^j` steps of :math:`h/2^j` with the
        smallest such :math:`j \le 30` (for the continuous-time use, where :math:`h` is only a
        resolution); ``halvings`` and ``message`` say which steps were halved.  Without it such
        a step ends the run (``failed_step``, ``fold`` and ``h_max`` say where, how far past the
        fold and the largest step that works).
    diagnostics : bool, optional
        Also estimate the solver's condition number at every solve (``condition``; costs about
        sixteen Sylvester solves a step).

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
    return _symmetric_run(
        Q, P, L, batch, h, steps, save_every, progress, method, bool(halve), bool(diagnostics)
    )
