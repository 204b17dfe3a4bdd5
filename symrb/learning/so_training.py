r"""Training the SO(n) network of claim D9 three ways: Riemannian gradient descent, the
extended method of successive approximations (with the special orthogonal Procrustes problem as
its layer-wise maximisation) and shooting on the extremal equations (a discrete rigid body
trajectory of the controls, claim D8).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import expm, svd
from scipy.optimize import root

from .. import _validate as v
from .._docfill import fill_doc
from .._generated import symmetric_rigid_body as _gsr
from .._progress import progress_bar
from .._validate import Array
from ..errors import InputError, OutOfDomainError
from ..solvers import solve_moser_veselov
from ._common import DOC, _positive
from .so_network import _so_backward, _so_controls, _so_forward, _so_loss, _SOProblem

__all__ = [
    "SOTrainResult",
    "train_so_gradient",
    "so_procrustes",
    "train_so_msa",
    "train_so_shooting",
]


@dataclass(frozen=True)
class SOTrainResult:
    r"""Outcome of :func:`train_so_gradient`, :func:`train_so_msa` and :func:`train_so_shooting`.

    Attributes
    ----------
    U : ndarray, shape (N, n, n)
        The final controls, in SO(n).
    losses : ndarray, shape (iterations + 1,)
        The loss before each iteration and at the end.
    residuals : ndarray, shape (iterations + 1,)
        The first-order optimality residual :math:`\max_k\|G_k\|_F` (the Riemannian gradient,
        :func:`~symrb.learning.so_network.so_network_gradients`) at the same points.
    iterations : int
        The number of iterations done.
    residual : float
        The final first-order residual, ``residuals[-1]``.
    converged : bool
        Whether the method's stopping test was met (shooting: the root finder's test, or the
        shooting residual at the rounding floor of the sweep, :math:`10(N+1)n\varepsilon
        (1 + \|x\|)`).
    method : str
        ``"gradient"``, ``"msa"`` or ``"shooting"``.
    M0 : ndarray, shape (n, n), or None
        :func:`train_so_shooting`: the momentum :math:`M_0` found.  None for the other methods.
    shooting_residual : float or None
        :func:`train_so_shooting`: :math:`\|F(M_0)\|_2`, the residual of the shooting equation.
        None for the other methods.
    condition : float or None
        :func:`train_so_shooting` with ``condition=True``: :math:`1/\sigma_{\min}(\partial
        F/\partial M_0)`, which bounds :math:`\|M_0 - M_0^*\|` by :math:`\kappa` times
        ``shooting_residual`` to first order.  None otherwise.

    Examples
    --------
    >>> import numpy as np
    >>> from symrb.learning import so_rotation_task, train_so_gradient
    >>> Q0, T = so_rotation_task(3, samples=8, seed=0)
    >>> res = train_so_gradient(Q0, T, np.tile(np.eye(3), (2, 1, 1)), [1.0, 2.0, 3.0], alpha=0.1,
    ...                         steps=20, lr=0.05)
    >>> res.losses.shape, res.iterations, res.method
    ((21,), 20, 'gradient')
    """

    U: Array
    losses: Array
    residuals: Array
    iterations: int
    residual: float
    converged: bool
    method: str
    M0: Array | None = None
    shooting_residual: float | None = None
    condition: float | None = None


def _grad_norm(G: Array) -> float:
    return float(np.max(np.linalg.norm(G, axis=(-2, -1))))


def _retract(U: Array, step: Array, retraction: str) -> Array:
    """U_k R(step_k) with R the Cayley map (I - A/2)^-1 (I + A/2) or the exponential."""
    if retraction == "exp":
        return np.asarray(U @ expm(step))
    eye = np.eye(U.shape[-1])
    return np.asarray(U @ np.linalg.solve(eye - 0.5 * step, eye + 0.5 * step))


def _so_start(U0: ArrayLike, Q0: ArrayLike, targets: ArrayLike, lam: ArrayLike, alpha: object):
    UU = _so_controls(U0).copy()
    return UU, _SOProblem(Q0, targets, lam, alpha, UU.shape[-1])


@fill_doc(DOC)
def train_so_gradient(
    Q0: ArrayLike,
    targets: ArrayLike,
    U0: ArrayLike,
    lam: ArrayLike,
    alpha: float = 0.0,
    steps: int = 500,
    lr: float = 0.1,
    retraction: str = "cayley",
    line_search: bool = False,
    momentum: float = 0.0,
    tol: float = 1e-10,
    progress: bool = False,
) -> SOTrainResult:
    r"""Riemannian gradient descent on :math:`SO(n)^N` for the loss of
    :func:`~symrb.learning.so_network.so_network_gradients`.

    Each step runs the forward and the costate sweep, then :math:`U_k \leftarrow U_k R(-t\,d_k)`
    with :math:`R` the Cayley map :math:`(I - A/2)^{-1}(I + A/2)` or the exponential, the
    direction :math:`d_k = G_k` (or with heavy-ball momentum :math:`d \leftarrow G + \mu d`, in
    the body frame), and :math:`t` = ``lr`` or, with ``line_search``, the Armijo step
    (backtracking from twice the last accepted step until the loss drops by at least
    :math:`10^{-4}\,t\,\langle G, d\rangle`).  Stops when :math:`\max_k\|G_k\|_F \le` ``tol``.

    Parameters
    ----------
    %(Q0)s
    %(T)s
    %(U0)s
    %(lam)s
    %(alpha)s
    %(steps)s
    lr : float, optional
        The step (the first trial step with ``line_search``), > 0.
    retraction : {"cayley", "exp"}, optional
        The retraction.
    line_search : bool, optional
        Armijo backtracking instead of a fixed step.
    momentum : float, optional
        The heavy-ball coefficient :math:`0 \le \mu < 1`.
    %(tol)s
    %(progress)s

    Returns
    -------
    SOTrainResult
        The final controls, the losses and residuals before each step, the iterations.

    Raises
    ------
    InputError
        Bad arguments, or a loss that became non-finite.

    Examples
    --------
    >>> import numpy as np
    >>> from symrb.learning import so_rotation_task, train_so_gradient
    >>> Q0, T = so_rotation_task(3, samples=8, seed=0)
    >>> U0 = np.tile(np.eye(3), (3, 1, 1))
    >>> res = train_so_gradient(Q0, T, U0, [1.0, 2.0, 3.0], alpha=1.0, steps=500,
    ...                         line_search=True, tol=1e-9)
    >>> bool(res.converged), bool(res.losses[-1] < res.losses[0])
    (True, True)
    """
    U, prob = _so_start(U0, Q0, targets, lam, alpha)
    steps = v.count(steps, "steps")
    lr = _positive(lr, "lr")
    tol = _positive(tol, "tol")
    mu = v.real_scalar(momentum, "momentum")
    if not 0 <= mu < 1:
        raise InputError(f"momentum must be in [0, 1), got {momentum!r}")
    if retraction not in ("cayley", "exp"):
        raise InputError(f"retraction must be 'cayley' or 'exp', got {retraction!r}")
    if not isinstance(line_search, bool | np.bool_):
        raise InputError(f"line_search must be True or False, got {line_search!r}")
    losses, residuals = [], []
    d = np.zeros_like(U)
    t = lr
    converged = False
    it = 0
    with progress_bar(steps, "SO(n) gradient descent", progress) as bar:
        loss, G = prob.gradients(U)
        while True:
            if not np.isfinite(loss):
                raise InputError(f"loss became non-finite at iteration {it} (lr = {lr} too large?)")
            losses.append(loss)
            residuals.append(_grad_norm(G))
            if residuals[-1] <= tol:
                converged = True
                break
            if it == steps:
                break
            d = G + mu * d
            slope = float(np.sum(G * d))
            if slope <= 0:  # momentum turned uphill: restart it
                d, slope = G.copy(), float(np.sum(G * G))
            if line_search:
                t = min(2 * t, 1e3 * lr)
                while True:
                    trial = _retract(U, -t * d, retraction)
                    new = prob.loss(trial)
                    if new <= loss - 1e-4 * t * slope or t < 1e-14:
                        break
                    t *= 0.5
                U = trial
            else:
                U = _retract(U, -lr * d, retraction)
            loss, G = prob.gradients(U)
            it += 1
            bar.step()
    return SOTrainResult(
        U=U,
        losses=np.array(losses),
        residuals=np.array(residuals),
        iterations=it,
        residual=residuals[-1],
        converged=converged,
        method="gradient",
    )


def so_procrustes(A: ArrayLike) -> Array:
    r"""The rotation maximising :math:`\operatorname{tr}(AU)` over :math:`U \in SO(n)`.

    With the singular value decomposition :math:`A = XSY^T` (``scipy.linalg.svd``), the maximiser
    is :math:`U = Y D X^T`, :math:`D = \operatorname{diag}(1, \dots, 1, \det(YX^T))` (the special
    orthogonal Procrustes problem; the determinant fix flips the direction of the smallest
    singular value when :math:`YX^T` is a reflection).  Unique when the smallest singular value
    is simple and, for :math:`\det(YX^T) = -1`, positive.

    Parameters
    ----------
    A : array_like, shape (..., n, n)
        The matrices.

    Returns
    -------
    U : ndarray, shape (..., n, n)
        The maximisers, in SO(n).

    Examples
    --------
    >>> import numpy as np
    >>> from symrb.learning import so_procrustes
    >>> A = np.diag([3.0, -2.0, -1.0])  # the best rotation turns the last two axes
    >>> print(so_procrustes(A).round(12) + 0.0)
    [[ 1.  0.  0.]
     [ 0. -1.  0.]
     [ 0.  0. -1.]]
    """
    a = v.square(A, "A")
    flat = a.reshape(-1, a.shape[-1], a.shape[-1])
    out = np.empty_like(flat)
    for i, Ai in enumerate(flat):
        X, _s, Yt = svd(Ai)
        D = np.ones(a.shape[-1])
        D[-1] = np.sign(np.linalg.det(Yt.T @ X.T))
        out[i] = (Yt.T * D) @ X.T
    return out.reshape(a.shape)


@fill_doc(DOC)
def train_so_msa(
    Q0: ArrayLike,
    targets: ArrayLike,
    U0: ArrayLike,
    lam: ArrayLike,
    alpha: float = 0.0,
    steps: int = 200,
    rho: float = 2.0,
    tol: float = 1e-10,
    progress: bool = False,
) -> SOTrainResult:
    r"""The extended method of successive approximations (Li, Chen, Tai and E 2018) on SO(n).

    Each iteration runs the forward and the costate sweep with the current controls, then sets
    every :math:`U_k` to the maximiser over :math:`SO(n)` of the augmented Hamiltonian

    .. math::

        \tilde H_k(U) = \sum_a\Bigl(\langle P^a_{k+1}, Q^a_kU\rangle
        - \tfrac\rho2\|Q^a_{k+1} - Q^a_kU\|_F^2 - \tfrac\rho2\|P^a_k - P^a_{k+1}U^T\|_F^2\Bigr)
        - \alpha\operatorname{tr}(\Lambda(I - U)),

    which for orthogonal :math:`Q^a_k` and :math:`U` is :math:`\operatorname{tr}(A_kU)` plus a
    constant with

    .. math::

        A_k = \sum_a\bigl((P^a_{k+1})^TQ^a_k + \rho((Q^a_{k+1})^TQ^a_k + (P^a_{k+1})^TP^a_k)
        \bigr) + \alpha\Lambda,

    so the layer-wise maximisation is the special orthogonal Procrustes problem, solved exactly
    by :func:`so_procrustes`.  :math:`\rho = 0` is the basic MSA (which may oscillate); the
    :math:`\rho` terms keep the step close to the current controls.  Stops when
    :math:`\max_k\|G_k\|_F \le` ``tol``.

    Parameters
    ----------
    %(Q0)s
    %(T)s
    %(U0)s
    %(lam)s
    %(alpha)s
    %(steps)s
    rho : float, optional
        The penalty :math:`\rho \ge 0` of the extended MSA.
    %(tol)s
    %(progress)s

    Returns
    -------
    SOTrainResult
        The final controls, the losses and residuals before each iteration, the iterations.

    Examples
    --------
    >>> import numpy as np
    >>> from symrb.learning import so_rotation_task, train_so_msa
    >>> Q0, T = so_rotation_task(3, samples=8, seed=0)
    >>> res = train_so_msa(Q0, T, np.tile(np.eye(3), (3, 1, 1)), [1.0, 2.0, 3.0], alpha=1.0,
    ...                    steps=500, tol=1e-9)
    >>> bool(res.converged), bool(res.losses[-1] < res.losses[0])
    (True, True)
    """
    U, prob = _so_start(U0, Q0, targets, lam, alpha)
    steps = v.count(steps, "steps")
    rho = v.real_scalar(rho, "rho")
    if rho < 0:
        raise InputError(f"rho must be >= 0, got {rho!r}")
    tol = _positive(tol, "tol")
    losses, residuals = [], []
    converged = False
    it = 0
    aL = prob.alpha * np.diag(prob.lam)
    with progress_bar(steps, "SO(n) extended MSA", progress) as bar:
        while True:
            Qs = _so_forward(prob.Qs0, U)
            G, Ps = _so_backward(Qs, U, prob.lam, prob.Ts, prob.alpha, costates=True)
            assert Ps is not None
            loss = _so_loss(Qs[-1], prob.Ts, U, prob.lam, prob.alpha)
            if not np.isfinite(loss):
                raise InputError(f"loss became non-finite at iteration {it}")
            losses.append(loss)
            residuals.append(_grad_norm(G))
            if residuals[-1] <= tol:
                converged = True
                break
            if it == steps:
                break
            A = np.empty_like(U)
            for k in range(U.shape[0]):
                A[k] = Ps[k + 1].T @ Qs[k] + aL
                if rho:
                    A[k] += rho * (Qs[k + 1].T @ Qs[k] + Ps[k + 1].T @ Ps[k])
            U = so_procrustes(A)
            it += 1
            bar.step()
    return SOTrainResult(
        U=U,
        losses=np.array(losses),
        residuals=np.array(residuals),
        iterations=it,
        residual=residuals[-1],
        converged=converged,
        method="msa",
    )


def _skew_from_upper(x: Array, n: int) -> Array:
    iu = np.triu_indices(n, 1)
    S = np.zeros((n, n))
    S[iu] = x
    return S - S.T


@fill_doc(DOC)
def train_so_shooting(
    Q0: ArrayLike,
    targets: ArrayLike,
    lam: ArrayLike,
    alpha: float,
    layers: int,
    M0: ArrayLike | None = None,
    tol: float = 1e-12,
    maxfev: int = 400,
    progress: bool = False,
    condition: bool = False,
) -> SOTrainResult:
    r"""The extremal equations of claim D9 as a two-point boundary value problem, by shooting.

    The extremals of the loss of :func:`~symrb.learning.so_network.so_network_gradients`
    (:math:`\alpha > 0`) satisfy the discrete system

    .. math::

        Q^a_{k+1} = Q^a_kU_k,\quad P^a_{k+1} = P^a_kU_k,\quad
        \alpha J_D(U_k) = M_k := \sum_a\bigl((Q^a_k)^TP^a_k - (P^a_k)^TQ^a_k\bigr),

    with :math:`Q^a_0` given and :math:`P^a_N = -(Q^a_N - T^a)`.  The momentum is transported,
    :math:`M_{k+1} = U_k^TM_kU_k` (claim D8), so the controls are a discrete rigid body
    (Moser-Veselov) trajectory of inertia :math:`\alpha\Lambda` and are fixed by the single
    unknown :math:`M_0 \in \mathfrak{so}(n)`: :math:`U_k` solves :math:`J_D(U_k) = M_k/\alpha`
    on the branch through the identity (:func:`symrb.solve_moser_veselov`).  Shooting solves
    :math:`F(M_0) = \sum_a((Q^a_0)^TP^a_0 - (P^a_0)^TQ^a_0) - M_0 = 0` (the costates from the
    backward sweep of the controls of :math:`M_0`) with ``scipy.optimize.root`` (Powell's hybrid
    method) from ``M0`` (default 0, all :math:`U_k = I`).

    Parameters
    ----------
    %(Q0)s
    %(T)s
    %(lam)s
    alpha : float
        The weight of the running cost, > 0.
    layers : int
        The number of layers :math:`N \ge 1`.
    M0 : array_like, shape (n, n), optional
        The initial guess of :math:`M_0` (skew).
    tol : float, optional
        The relative tolerance of the root finder on :math:`M_0` (``xtol``).
    maxfev : int, optional
        The most evaluations of :math:`F`.
    progress : bool, optional
        Show a progress bar (tqdm) over the evaluations.
    condition : bool, optional
        Also compute the condition number of the shooting equation at the solution
        (``SOTrainResult.condition``: :math:`\kappa = 1/\sigma_{\min}(\partial F/\partial
        M_0)` by central differences, :math:`n(n-1)` more evaluations of F).  Not computed by
        default.

    Returns
    -------
    SOTrainResult
        ``losses`` and ``residuals`` at every evaluation of :math:`F`; ``iterations`` is the
        number of evaluations; ``M0`` the returned :math:`M_0` and ``shooting_residual``
        :math:`\|F(M_0)\|_2` (on the strict upper triangle).

    Notes
    -----
    The equation solved is :math:`F(M_0) = 0` on :math:`\mathfrak{so}(n)` (coordinates: the
    strict upper triangle).  To first order :math:`M_0 - M_0^* = (\partial F/\partial M_0)^{-1}
    F(M_0)`, so :math:`\|M_0 - M_0^*\| \le \kappa\|F(M_0)\|` with
    :math:`\kappa = 1/\sigma_{\min}(\partial F/\partial M_0)` (dimensionless: F and
    :math:`M_0` are both momenta), and rounding in evaluating F (about
    :math:`(N+1)Mn\varepsilon` times the size of its terms) bounds how small
    ``shooting_residual`` can get.  Stated and tested (tests/test_conditions.py, against a
    solve from another starting guess): two solutions differ by at most
    :math:`10\kappa(\|F_1\| + \|F_2\| + 2(N+1)Mn\varepsilon\sqrt n\,(\sqrt n +
    \max_a\|P^a_0\|_F))`.

    Raises
    ------
    InputError
        Bad arguments.

    Examples
    --------
    >>> import numpy as np
    >>> from symrb.learning import so_rotation_task, train_so_shooting
    >>> Q0, T = so_rotation_task(3, samples=8, seed=0)
    >>> res = train_so_shooting(Q0, T, [1.0, 2.0, 3.0], alpha=1.0, layers=3)
    >>> bool(res.converged), bool(res.residual < 1e-9)
    (True, True)
    >>> res = train_so_shooting(Q0, T, [1.0, 2.0, 3.0], alpha=1.0, layers=3, condition=True)
    >>> bool(res.shooting_residual < 1e-13), round(res.condition, 3)
    (True, 0.095)
    """
    shoot, x0, tol, maxfev = _shooting_inputs(
        Q0, targets, lam, alpha, layers, M0, tol, maxfev, condition
    )
    prob, n = shoot.prob, shoot.n
    losses: list[float] = []
    residuals: list[float] = []
    last: dict[str, Array] = {}
    with progress_bar(maxfev, "SO(n) shooting", progress) as bar:

        def F(x: Array) -> Array:
            out = shoot(x)
            if out is None:  # beyond the fold of J_D: push the root finder back
                return -10.0 * (1.0 + np.abs(x)) * np.sign(x + (x == 0))
            Fx, U, G = out
            losses.append(_so_loss(shoot.last_Qs[-1], prob.Ts, U, prob.lam, prob.alpha))
            residuals.append(_grad_norm(G))
            last["U"] = U
            last["F"] = Fx
            bar.step()
            return Fx

        sol = root(F, x0, method="hybr", options={"xtol": tol, "maxfev": maxfev})
        F(sol.x)  # the reported controls are those of the returned M_0
    kappa = _shooting_condition(shoot, sol.x) if condition else None
    shooting_residual = float(np.linalg.norm(last["F"])) if "F" in last else float("inf")
    # hybr reports "not making good progress" once F is at rounding level and xtol cannot be
    # met (the thorough profile found converged = False with |F| = 5.6e-16): F at the rounding
    # floor of the sweep counts as converged
    layers_n = 0 if last.get("U") is None else int(np.shape(last["U"])[0])
    converged = bool(sol.success) or shooting_residual <= _rounding_floor(layers_n, n, sol.x)
    return SOTrainResult(
        U=last["U"],
        losses=np.array(losses),
        residuals=np.array(residuals),
        iterations=len(losses) - 1,
        residual=residuals[-1],
        converged=converged,
        method="shooting",
        M0=_skew_from_upper(sol.x, n),
        shooting_residual=shooting_residual,
        condition=kappa,
    )


class _Shooting:
    """The shooting function of :func:`train_so_shooting`: the strict upper triangle x of
    :math:`M_0` -> (F(x), the controls U, the skew gradients G), or None beyond the fold of
    :math:`J_D`; ``last_Qs`` keeps the layers of the last evaluation."""

    def __init__(self, prob: _SOProblem, layers: int) -> None:
        self.prob, self.N, self.n = prob, layers, prob.n
        self.iu = np.triu_indices(self.n, 1)
        self.lam_a = prob.alpha * prob.lam
        self.last_Qs: Array = np.empty(0)

    def controls(self, x: Array) -> Array:
        """The controls of the discrete rigid body trajectory from the momentum of x."""
        N, n = self.N, self.n
        M = _skew_from_upper(x, n)
        U = np.empty((N, n, n))
        guess: Array | None = None
        for k in range(N):
            U[k] = np.asarray(solve_moser_veselov(M, self.lam_a, U0=guess))
            guess = U[k]
            M = U[k].T @ M @ U[k]
        return U

    def __call__(self, x: Array) -> tuple[Array, Array, Array] | None:
        prob = self.prob
        try:
            U = self.controls(x)
        except OutOfDomainError:
            return None
        Qs = _so_forward(prob.Qs0, U)
        G, Ps = _so_backward(Qs, U, prob.lam, prob.Ts, prob.alpha, costates=True)
        assert Ps is not None
        self.last_Qs = Qs
        R = _gsr.symmetric_momentum(Qs[0], Ps[0])
        return np.asarray(R[self.iu] - x), U, G


def _shooting_inputs(
    Q0: ArrayLike,
    targets: ArrayLike,
    lam: ArrayLike,
    alpha: object,
    layers: object,
    M0: ArrayLike | None,
    tol: object,
    maxfev: object,
    condition: object,
) -> tuple[_Shooting, Array, float, int]:
    """The validated arguments of :func:`train_so_shooting`: the shooting function, the start
    (the strict upper triangle of ``M0``, 0 by default), ``tol`` and ``maxfev``."""
    N = v.count(layers, "layers", 1)
    Q = v.orthogonal(Q0, "Q0")
    if Q.ndim != 3:
        raise InputError(f"Q0 must have shape (M, n, n), got {Q.shape}")
    n = Q.shape[-1]
    prob = _SOProblem(Q, targets, lam, alpha, n)
    if not prob.alpha > 0:
        raise InputError(f"alpha must be > 0 for shooting (J_D is inverted), got {alpha!r}")
    tol = _positive(tol, "tol")
    maxfev = v.count(maxfev, "maxfev", 1)
    iu = np.triu_indices(n, 1)
    x0 = np.zeros(len(iu[0]))
    if M0 is not None:
        x0 = v.skew(M0, "M0", n)[iu].copy()
    if not isinstance(condition, bool | np.bool_):
        raise InputError(f"condition must be True or False, got {condition!r}; pass a bool")
    return _Shooting(prob, N), x0, tol, maxfev


def _rounding_floor(layers: int, n: int, x: Array) -> float:
    """The rounding floor of the shooting residual, 10 (N + 1) n eps (1 + |x|)."""
    return 10.0 * (layers + 1) * n * float(np.finfo(float).eps) * (1.0 + float(np.linalg.norm(x)))


def _shooting_condition(
    shoot: Callable[[Array], tuple[Array, Array, Array] | None], x: Array
) -> float:
    """1 / the smallest singular value of dF/dm at m = x (central differences, relative step
    1e-6; the nonlinearity error is O(1e-12) relative, the rounding error O(eps / 1e-6)); NaN
    when a difference crosses the fold of J_D."""
    d = x.size
    step = 1e-6 * max(1.0, float(np.linalg.norm(x)))
    J = np.empty((d, d))
    for j in range(d):
        e = np.zeros(d)
        e[j] = step
        plus, minus = shoot(x + e), shoot(x - e)
        if plus is None or minus is None:
            return float("nan")
        J[:, j] = (plus[0] - minus[0]) / (2 * step)
    smallest = float(np.linalg.svd(J, compute_uv=False)[-1])
    return 1.0 / smallest if smallest > 0 else float("inf")
