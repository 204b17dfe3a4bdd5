"""M12: the SO(n) network of the learning theorem as shipped: sweeps, gradients and trainers.

Not a statement of the paper.  Claim D9 checks the network's kernels; the coverage report found
that no evidence ran the public forward and costate sweeps, the extremal residual, the Procrustes
step or the three trainers (gradient descent with either retraction, with and without the line
search; the method of successive approximations; shooting, with its condition number).  Here
they run against the network written in plain NumPy: its loss differentiated by the complex
step along :math:`U_k e^{t\\xi}`, the trainers written from their documented definitions, the
largest value of :math:`\\operatorname{tr}(AU)` over SO(n) in closed form (von Neumann), and the
shooting map with the discrete rigid body solved by ``scipy.optimize.root``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.linalg import expm

from derivations import reference as ref
from derivations.registry import Level, claim

M12 = claim(
    "M12",
    label="",
    title="The SO(n) network's sweeps and trainers",
    statement="The SO(n) network's sweeps, gradient and extremal residual are those of its loss; "
    "gradient descent (Cayley or exponential retraction, fixed step or line search), the "
    "method of successive approximations and shooting are the methods they name; "
    "`so_procrustes` maximises $\\operatorname{tr}(AU)$ over SO(n).",
    expected="holds",
    section="symrb",
    where="`symrb.learning`: `so_network_forward`, `so_network_costates`, "
    "`so_network_gradients`, `so_extremal_residual`, `so_procrustes`, `train_so_gradient`, "
    "`train_so_msa`, `train_so_shooting`",
)

_LAM = np.array([0.7, 1.1, 1.6])
_ALPHA = 0.3


def _data(layers: int = 3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Samples Q_0 (4), targets and controls U (n = 3), random rotations."""
    rng = np.random.default_rng(121)
    Q0, T = (np.stack([ref.random_rotation(3, rng) for _ in range(4)]) for _ in range(2))
    U = np.stack([ref.random_rotation(3, rng) for _ in range(layers)])
    return Q0, T, U


def _sweeps(Q0: Any, U: Any, T: Any) -> tuple[list[Any], list[Any]]:
    """Q_(k+1) = Q_k U_k and P_N = -(Q_N - T), P_k = P_(k+1) U_k^T (NumPy)."""
    Qs = [Q0]
    for Uk in U:
        Qs.append(Qs[-1] @ Uk)
    Ps = [-(Qs[-1] - T)]
    for Uk in U[::-1]:
        Ps.insert(0, Ps[0] @ Uk.T)
    return Qs, Ps


def _loss(Q0: Any, U: Any, T: Any) -> Any:
    QN = Q0
    for Uk in U:
        QN = QN @ Uk
    return 0.5 * np.sum((QN - T) ** 2) + _ALPHA * sum(np.sum(_LAM * (1 - np.diagonal(Uk)))
                                                      for Uk in U)  # fmt: skip


def _gradient(Q0: np.ndarray, U: np.ndarray, T: np.ndarray) -> np.ndarray:
    """G_k with d/dt L(U_k e^(t xi)) = tr(G_k^T xi): the complex step along U_k (I + i h E) for
    an orthonormal basis E of so(3)."""
    basis = [ref.hat(e) / math.sqrt(2) for e in np.eye(3)]
    G = np.zeros_like(U)
    for k in range(len(U)):
        for E in basis:
            V = U.astype(complex)
            V[k] = U[k] @ (np.eye(3) + 1e-30j * E)
            G[k] += _loss(Q0, V, T).imag / 1e-30 * E
    return G


@M12.check(Level.FLOAT64, tol=1e-12)
def m12_sweeps_and_gradient() -> float:
    r"""symrb.learning.so_network_forward, so_network_costates (with and without its report),
    so_network_gradients (with its report, $\alpha = 0.3$) and so_extremal_residual ($n = 3$, 4
    samples, 3 layers) against the NumPy sweeps, the loss, its complex-step derivative along $U_k
    e^{t\xi}$ and $\|\alpha J_D(U_k) - \sum_a M^a_k\|_F$, $M^a_k = Q_k^T P_k - P_k^T Q_k$ of sample
    $a$; the reports' condition number is that of multiplying by rotations, 1: max relative
    difference."""
    import symrb.learning as sl

    Q0, T, U = _data()
    Qs, Ps = _sweeps(Q0, U, T)
    L = np.diag(_LAM)
    gaps = [np.abs(sl.so_network_forward(Q0, U) - np.stack(Qs)).max()]
    Qc, Pc = sl.so_network_costates(Q0, U, T)
    Qi, Pi, info = sl.so_network_costates(Q0, U, T, return_info=True)
    gaps += [np.abs(Qc - np.stack(Qs)).max(), np.abs(Pc - np.stack(Ps)).max()]
    gaps += [np.abs(Pi - np.stack(Ps)).max(), abs(info.condition - 1)]
    loss, G, info2 = sl.so_network_gradients(Q0, U, _LAM, T, _ALPHA, return_info=True)
    Gr = _gradient(Q0, U, T)
    gaps += [abs(loss / _loss(Q0, U, T) - 1), np.abs(G - Gr).max() / np.abs(Gr).max()]
    gaps.append(abs(info2.condition - 1))
    r = sl.so_extremal_residual(Q0, U, _LAM, T, _ALPHA)
    for k in range(len(U)):
        M = sum(q.T @ p - p.T @ q for q, p in zip(Qs[k], Ps[k], strict=True))
        want = np.linalg.norm(_ALPHA * (U[k] @ L - L @ U[k].T) - M)
        gaps.append(abs(r[k] / want - 1))
    return float(np.max(gaps))


def _retract(U: np.ndarray, A: np.ndarray, retraction: str) -> np.ndarray:
    if retraction == "exp":
        return U @ expm(A)
    return U @ np.linalg.inv(np.eye(3) - A / 2) @ (np.eye(3) + A / 2)


def _descent(Q0: Any, T: Any, U: Any, steps: int, lr: float, retraction: str, search: bool) -> Any:
    """Riemannian gradient descent as documented: U_k <- U_k R(-t G_k), t = lr or the Armijo
    step (halving from twice the last accepted one until the loss drops by 1e-4 t <G, G>)."""
    losses, t = [], lr
    for _ in range(steps):
        loss, G = _loss(Q0, U, T), _gradient(Q0, U, T)
        losses.append(loss)
        if search:
            t = 2 * t
            while _loss(Q0, _retract_all(U, -t * G, retraction), T) > loss - 1e-4 * t * np.sum(
                G * G
            ):
                t /= 2
        U = _retract_all(U, -(t if search else lr) * G, retraction)
    losses.append(_loss(Q0, U, T))
    return U, np.array(losses)


def _retract_all(U: np.ndarray, A: np.ndarray, retraction: str) -> np.ndarray:
    return np.stack([_retract(u, a, retraction) for u, a in zip(U, A, strict=True)])


def _procrustes_value(A: np.ndarray) -> float:
    """max tr(AU) over SO(n): the sum of the singular values, minus twice the smallest when
    det A < 0 (von Neumann's trace inequality with the determinant constraint)."""
    s = np.linalg.svd(A, compute_uv=False)
    return float(s.sum() - (2 * s[-1] if np.linalg.det(A) < 0 else 0.0))


@M12.check(Level.FLOAT64, tol=1e-10)
def m12_trainers() -> float:
    r"""symrb.learning.train_so_gradient (3 steps; Cayley and exponential retraction, fixed step 0.2
    and line search) against Riemannian gradient descent written in NumPy on the complex-step
    gradient; so_procrustes (random $A$, determinant of both signs) reaches the largest
    $\operatorname{tr}(AU)$ over $\mathrm{SO}(3)$ in closed form; train_so_msa (2 iterations, $\rho
    = 2$) against the documented layer-wise maximisation of $\operatorname{tr}(A_k U)$ (its value in
    closed form, the NumPy sweeps): max relative difference of the controls, losses and values."""
    import symrb.learning as sl

    Q0, T, U = _data()
    gaps = []
    for retraction in ("cayley", "exp"):
        for search in (False, True):
            got = sl.train_so_gradient(Q0, T, U, _LAM, _ALPHA, steps=3, lr=0.2,
                                       retraction=retraction, line_search=search)  # fmt: skip
            Ur, losses = _descent(Q0, T, U, 3, 0.2, retraction, search)
            gaps += [np.abs(got.U - Ur).max(), np.abs(got.losses / losses - 1).max()]
    rng = np.random.default_rng(122)
    for _ in range(6):
        A = rng.standard_normal((3, 3))
        P = sl.so_procrustes(A)
        gaps += [np.abs(P.T @ P - np.eye(3)).max(), abs(np.linalg.det(P) - 1)]
        gaps.append(abs(np.trace(A @ P) / _procrustes_value(A) - 1))
    got = sl.train_so_msa(Q0, T, U, _LAM, _ALPHA, steps=2, rho=2.0)
    V = U.copy()
    for _ in range(2):
        Qs, Ps = _sweeps(Q0, V, T)
        for k in range(len(V)):
            A = sum(p1.T @ q + 2.0 * (q1.T @ q + p1.T @ p) for q, p, q1, p1
                    in zip(Qs[k], Ps[k], Qs[k + 1], Ps[k + 1], strict=True)) + _ALPHA * np.diag(_LAM)  # fmt: skip
            X, _s, Yt = np.linalg.svd(A)
            D = np.diag([1.0, 1.0, np.linalg.det(Yt.T @ X.T)])
            V[k] = Yt.T @ D @ X.T
            gaps.append(abs(np.trace(A @ V[k]) / _procrustes_value(A) - 1))
    gaps += [np.abs(got.U - V).max(), abs(got.losses[-1] / _loss(Q0, V, T) - 1)]
    return float(np.max(gaps))


def _shooting_map(Q0: np.ndarray, T: np.ndarray, layers: int) -> Any:
    """F(M_0) = sum_a (Q_0^T P_0 - P_0^T Q_0) - M_0 on the strict upper triangle, the controls
    from alpha J_D(U_k) = M_k on the branch through I (scipy.optimize.root on the Cayley
    parameters, reference.MPDiscrete) and M_(k+1) = U_k^T M_k U_k."""
    mpd = ref.MPDiscrete(_ALPHA * _LAM, dps=15)
    iu = np.triu_indices(3, 1)

    def controls(M0: np.ndarray) -> np.ndarray:
        U, M = [], M0
        for _ in range(layers):
            A = ref.hat(mpd._float_branch(M))
            U.append(np.linalg.solve(np.eye(3) - A, np.eye(3) + A))
            M = U[-1].T @ M @ U[-1]
        return np.stack(U)

    def F(m: np.ndarray) -> np.ndarray:
        M0 = np.zeros((3, 3))
        M0[iu] = m
        M0 = M0 - M0.T
        Qs, Ps = _sweeps(Q0, controls(M0), T)
        R = sum(q.T @ p - p.T @ q for q, p in zip(Qs[0], Ps[0], strict=True)) - M0
        return R[iu]

    return F, controls


@M12.check(Level.FLOAT64, tol=1e-5)
def m12_shooting() -> float:
    r"""symrb.learning.train_so_shooting ($\alpha = 0.3$, 3 layers; without condition, then with
    condition=True from the $M_0$ found): each $M_0$ is a root of the shooting map $F$ written in
    NumPy (controls from $\alpha J_D(U_k) = M_k$ by scipy.optimize.root, momenta transported, the
    NumPy sweeps), its controls are the map's, and the reported condition number
    $1/\sigma_{\min}(\partial F/\partial M_0)$ agrees with central differences of the NumPy map: max
    of $\|F(M_0)\|$, the control difference and the relative difference of the condition numbers."""
    import symrb.learning as sl

    Q0, T, _U = _data()
    F, controls = _shooting_map(Q0, T, 3)
    iu = np.triu_indices(3, 1)
    plain = sl.train_so_shooting(Q0, T, _LAM, _ALPHA, 3)
    got = sl.train_so_shooting(Q0, T, _LAM, _ALPHA, 3, M0=plain.M0, condition=True)
    if got.condition is None or plain.condition is not None or got.M0 is None or plain.M0 is None:
        return math.inf
    m = got.M0[iu]
    gaps = [np.abs(F(plain.M0[iu])).max(), np.abs(plain.U - controls(plain.M0)).max()]
    gaps += [np.abs(F(m)).max(), np.abs(got.U - controls(got.M0)).max()]
    step = 1e-5
    J = np.stack([(F(m + step * e) - F(m - step * e)) / (2 * step) for e in np.eye(3)], axis=1)
    gaps.append(abs(got.condition * np.linalg.svd(J, compute_uv=False).min() - 1))
    return float(np.max(gaps))
