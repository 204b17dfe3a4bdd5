r"""Global optima of the problem of D7 on :math:`SO(3)^N`, found independently of symrb.

The problem: optimise :math:`\sum_k\operatorname{tr}(\Lambda U_k)` over :math:`U_0,\dots,U_{N-1}`
in :math:`SO(3)` with :math:`U_0U_1\cdots U_{N-1} = Q_0^TQ_N` given.  :func:`_global_optimum`
parametrises :math:`U_0,\dots,U_{N-2}` by rotation vectors (the last control is then fixed by the
product), runs BFGS from fixed random starts, keeps the best, and polishes it with a root finder on
the stationarity conditions of the interior :math:`Q_k`, so the optimum is an extremal to rounding.
:func:`_continued_to` names the solution branch of :math:`U\Lambda - \Lambda U^T = M` a control
lies on, by following :math:`J_D(V) = tM` from :math:`t = 1` to :math:`t = 0` with Newton's method
to a diagonal sign matrix.  NumPy and SciPy only (used by D7 and by the book's page on D7).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize, root
from scipy.spatial.transform import Rotation

from derivations import reference as ref


def _rot(v: np.ndarray) -> np.ndarray:
    """The rotation with rotation vector v (3,) or vectors (..., 3)."""
    return Rotation.from_rotvec(np.reshape(v, (-1, 3))).as_matrix().reshape(*np.shape(v), 3)


def _controls(x: np.ndarray, target: np.ndarray, steps: int) -> np.ndarray:
    """U_0..U_{N-2} from the rotation vectors x, and U_{N-1} = (U_0 ... U_{N-2})^T target."""
    Us = list(_rot(np.reshape(x, (steps - 1, 3))))
    prod = np.eye(3)
    for U in Us:
        prod = prod @ U
    return np.array([*Us, prod.T @ target])


def _value(Us: np.ndarray, lam: np.ndarray) -> float:
    """sum_k tr(Lambda U_k)."""
    return float(np.einsum("i,kii->", lam, Us))


def _stationarity(Us: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """The derivative of the cost along Q_k(I + e xi), xi = hat(e_i), for every interior k:
    tr(xi (Lambda U_{k-1} - U_k Lambda)), as a vector of length 3(N - 1)."""
    L = np.diag(lam)
    out = [
        [np.trace(ref.hat(e) @ (L @ Us[k - 1] - Us[k] @ L)) for e in np.eye(3)]
        for k in range(1, len(Us))
    ]
    return np.ravel(out)


def _polish(Us: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """The controls of the nearby extremal: Newton (MINPACK hybrd) on the stationarity of the
    interior Q_k = Q_k^* exp(hat y_k), with Q_0 and Q_N kept."""
    Qs = _states(Us)

    def controls(y: np.ndarray) -> np.ndarray:
        Q = Qs.copy()
        Q[1:-1] = Q[1:-1] @ _rot(np.reshape(y, (-1, 3)))
        return np.swapaxes(Q[:-1], -1, -2) @ Q[1:]

    sol = root(lambda y: _stationarity(controls(y), lam), np.zeros(3 * (len(Us) - 1)), tol=1e-15)
    return controls(sol.x)


def _states(Us: np.ndarray, Q0: np.ndarray | None = None) -> np.ndarray:
    """Q_0 = Q0 (default I) and Q_{k+1} = Q_k U_k."""
    Qs = [np.eye(3) if Q0 is None else Q0]
    for U in Us:
        Qs.append(Qs[-1] @ U)
    return np.array(Qs)


def _global_optimum(
    lam: np.ndarray, target: np.ndarray, steps: int, sign: int, starts: int = 12, seed: int = 0
) -> np.ndarray:
    """The controls (N, 3, 3) of the global minimiser (``sign`` = 1) or maximiser (``sign`` = -1)
    of sum_k tr(Lambda U_k) subject to U_0 ... U_{N-1} = target: the best of ``starts`` BFGS runs
    from rotation vectors uniform in [-pi, pi], polished to an extremal."""
    rng = np.random.default_rng(seed)

    def f(x: np.ndarray) -> float:
        return sign * _value(_controls(x, target, steps), lam)

    best = None
    for _ in range(starts):
        run = minimize(f, rng.uniform(-np.pi, np.pi, 3 * (steps - 1)), method="BFGS")
        if best is None or run.fun < best.fun:
            best = run
    assert best is not None
    return _polish(_controls(best.x, target, steps), lam)


def _margin(U: np.ndarray, lam: np.ndarray) -> float:
    """min Re of the eigenvalues of U Lambda: positive exactly on the branch through I."""
    return float(np.linalg.eigvals(U * lam[None, :]).real.min())


def _continued_to(U: np.ndarray, lam: np.ndarray, steps: int = 100) -> str:
    """Where the solution U of J_D(U) = M (M = J_D(U)) goes along J_D(V) = tM, t: 1 -> 0.

    Newton's method on V exp(hat(d)) at each of ``steps`` values of t.  Returns ``"I"``,
    ``"R1"``, ``"R2"`` or ``"R3"`` (the half-turn about the i-th principal axis, the axis of
    lambda_i), or ``"fold"`` when the derivative of J_D becomes singular on the way.
    """
    L = np.diag(lam)
    M = U @ L - L @ U.T
    V = U.copy()
    basis = [ref.hat(e) for e in np.eye(3)]
    for t in np.linspace(1.0, 0.0, steps + 1)[1:]:
        for _ in range(50):
            F = ref.vee(V @ L - L @ V.T - t * M)
            jac = np.array([ref.vee(V @ b @ L + L @ b @ V.T) for b in basis]).T
            if np.linalg.cond(jac) > 1e10:
                return "fold"
            d = np.linalg.solve(jac, -F)
            V = V @ _rot(d)
            if np.abs(d).max() < 1e-14:
                break
    signs = np.round(np.diag(V))
    if np.abs(V - np.diag(signs)).max() > 1e-8:  # pragma: no cover - Newton lost the branch
        return "?"
    return "I" if (signs > 0).all() else f"R{int(np.argmax(signs)) + 1}"


#: Rotation vectors of Q_0^T Q_N for the book's table: no turn, 1.41 and 2.68 rad.
TABLE_TARGETS = ((0.0, 0.0, 0.0), (1.0, -0.6, 0.8), (0.3, 2.2, -1.5))


def optima_rows(
    lam: np.ndarray, steps: tuple[int, ...] = (2, 3, 4), targets: tuple = TABLE_TARGETS
) -> list[dict]:
    """For each N in ``steps`` and rotation vector in ``targets`` (of Q_0^T Q_N): the global
    minimum and maximum of sum_k tr(Lambda U_k), the branch each U_k continues to
    (:func:`_continued_to`), the least real part of the eigenvalues of U_k Lambda over k, and
    the largest stationarity residual of the two optima."""
    rows = []
    for N in steps:
        for v in targets:
            row: dict = {"N": N, "turn": float(np.linalg.norm(v))}
            for name, sign in (("min", 1), ("max", -1)):
                Us = _global_optimum(lam, _rot(np.array(v)), N, sign)
                row[name] = _value(Us, lam)
                row[name + "_branch"] = [_continued_to(U, lam) for U in Us]
                row[name + "_margin"] = min(_margin(U, lam) for U in Us)
                row[name + "_stationarity"] = float(np.abs(_stationarity(Us, lam)).max())
            rows.append(row)
    return rows
