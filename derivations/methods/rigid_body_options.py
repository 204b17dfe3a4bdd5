"""M8: the rigid-body wrappers and options that no other check runs.

Not a statement of the paper.  The coverage report (:mod:`derivations.coverage`) found public
functions and option values of symrb that no evidence called: a base step passed to the
compositions as an object (``MVStep``, ``MidpointStep``, ``RKMK4Step``), the solver reports
(``return_info=True`` of ``solve_moser_veselov`` and ``P_from_M``), the small operators of
``symrb.algebra`` and the McLachlan-Scovel and multi-sample fields through ``integrate``.  Each is
held here against an independent reference: mpmath's 20-digit Taylor solution of the rigid body,
plain NumPy formulas of the reported quantities, and ``scipy.integrate.solve_ivp`` on fields
written in NumPy from :mod:`derivations.reference`.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable

import numpy as np

from derivations import reference as ref
from derivations.registry import Level, claim

M8 = claim(
    "M8",
    label="",
    title="The remaining rigid-body wrappers and options",
    statement="A base step given to the compositions as an object keeps the composition's "
    "order; the reports of `solve_moser_veselov` and `P_from_M` state the residual, "
    "orthogonality, margin, distance to the branch point and condition number of what they "
    "return; the operators of `symrb.algebra` and the McLachlan-Scovel and multi-sample fields "
    "(also integrated by `integrate`) are the ones of the paper.",
    expected="holds",
    section="symrb",
    where="`symrb.compose.composed_rigid_body_flow(step=...)`, `symrb.base_steps`, "
    "`symrb.solve_moser_veselov(return_info=True)`, `symrb.symmetric.P_from_M(return_info=True)`, "
    "`symrb.algebra`, `symrb.symmetric.mclachlan_scovel_rhs`, `symrb.integrate`",
)

_LAM = np.array([0.7, 1.1, 1.6])
_M0 = np.array([0.5, 1.0, 1.5])


def _max(*values: float) -> float:
    """The largest of ``values``, NaN when any is NaN (Python's max would drop it)."""
    return float(np.max(values))


@functools.cache
def _reference() -> tuple[np.ndarray, Callable[[float], tuple[np.ndarray, np.ndarray]]]:
    """A start attitude and the 20-digit reference solution from it (mpmath, independent)."""
    Q0 = ref.random_rotation(3, np.random.default_rng(8))
    return Q0, ref.rigid_body_mp(_LAM.sum() - _LAM, Q0, _M0, 20)


@M8.check(Level.MPMATH, tol=0.3)
def m8_base_step_objects() -> float:
    r"""symrb.compose.composed_rigid_body_flow with the base step given as an object: MVStep and
    MidpointStep under the order-4 composition (order 4), RKMK4Step under the order-2 one (the step
    itself, order 4); the order observed from the errors at $T = 1$ with steps $h = 0.1$ and 0.05
    against the 20-digit reference (mpmath): $\max |\mathrm{observed} - \mathrm{nominal}|$; inf when
    the MV and the midpoint objects give the same result (an object ignored)."""
    from symrb.base_steps import MidpointStep, MVStep, RKMK4Step
    from symrb.compose import composed_rigid_body_flow

    Q0, at = _reference()
    Qr, mr = at(1.0)
    worst = 0.0
    finals = []
    for step, order in ((MVStep(_LAM), 4), (MidpointStep(_LAM), 4), (RKMK4Step(_LAM), 2)):
        errors = []
        for h in (0.1, 0.05):
            n = round(1.0 / h)
            sol = composed_rigid_body_flow(Q0, ref.hat(_M0), _LAM, h, n, order, step=step,
                                           save_every=n)  # fmt: skip
            eQ = np.abs(sol.y.Q[-1] - Qr).max()
            eM = np.abs(ref.vee(sol.y.M[-1]) - mr).max() / np.linalg.norm(_M0)
            errors.append(_max(eQ, eM))
        worst = _max(worst, abs(math.log2(errors[0] / errors[1]) - 4))
        finals.append(sol.y.M[-1])
    if np.array_equal(finals[0], finals[1]):
        return math.inf
    return worst


def _kappa(U: np.ndarray, lam: np.ndarray) -> float:
    """max lam / sigma_min of L_U(xi) = U xi Lam + Lam xi U^T on so(n), in the orthonormal basis
    (E_ij - E_ji)/sqrt(2) of the Frobenius inner product (plain NumPy)."""
    k = len(lam)
    basis = ref.so_orthonormal_basis(k)
    L = np.diag(lam)
    cols = [U @ E @ L + L @ E @ U.T for E in basis]
    A = np.array([[np.sum(B * C) for C in cols] for B in basis])
    return float(lam.max() / np.linalg.svd(A, compute_uv=False).min())


@M8.check(Level.FLOAT64, tol=1.0)
def m8_solver_reports() -> float:
    r"""The reports of symrb.solve_moser_veselov and symrb.symmetric.P_from_M (return_info=True), $n
    = 3, \dots, 5$, four random momenta each (0.1 to 0.95 of the way to the fold of $J_D$, and
    $\|M\|_{\mathrm{op}}$ from 0.2 to 1.9 for P_from_M), against the quantities recomputed in NumPy
    from the returned $U$ and $P$: residual $\|U\Lambda - \Lambda U^T - M\|_F$, $\|U^T U - I\|_F$,
    the margin $\min \operatorname{Re} \operatorname{spec}(U\Lambda)$, the condition number
    $\max \lambda / \sigma_{\min}(L_U)$ (the report's estimate is a lower bound from a power method,
    0.94 to 1 times it here: between 0.9 and 1), and for P_from_M $\|Q^T P - P^T Q - M\|_F$, $\|P^T
    P - I\|_F$, $\delta = 1 - \|M\|_{\mathrm{op}}/2$ and $1/\sqrt{1 - (\|M\|_{\mathrm{op}}/2)^2}$;
    max discrepancy over its allowance (1e-13 for residuals, 1e-10 relative for the rest)."""
    import symrb

    rng = np.random.default_rng(88)
    worst = 0.0
    for k in range(3, 6):
        lam = rng.uniform(0.5, 2.0, k)
        for scale in (0.1, 0.5, 0.8, 0.95):  # of the way to the fold (inputs, not the check)
            M = ref.random_skew(k, rng)
            M *= scale * float(symrb.fold_scale(M, lam))
            U, info = symrb.solve_moser_veselov(M, lam, return_info=True)
            L = np.diag(lam)
            kappa = _kappa(U, lam)
            gaps = [
                abs(float(info.residual) - np.linalg.norm(U @ L - L @ U.T - M)) / 1e-13,
                abs(float(info.orthogonality) - np.linalg.norm(U.T @ U - np.eye(k))) / 1e-13,
                abs(float(info.margin) / np.linalg.eigvals(U @ L).real.min() - 1) / 1e-10,
                0.0 if 0.9 * kappa <= float(info.condition) <= kappa * (1 + 1e-10) else math.inf,
            ]
            Q = ref.random_rotation(k, rng)
            Mp = M * (2 * scale / np.linalg.norm(M, 2))
            P, pinfo = symrb.symmetric.P_from_M(Q, Mp, return_info=True)
            r = np.linalg.norm(Mp, 2) / 2
            gaps += [
                abs(float(pinfo.residual) - np.linalg.norm(Q.T @ P - P.T @ Q - Mp)) / 1e-13,
                abs(float(pinfo.orthogonality) - np.linalg.norm(P.T @ P - np.eye(k))) / 1e-13,
                abs(float(pinfo.delta) / (1 - r) - 1) / 1e-10,
                abs(float(pinfo.condition) * math.sqrt(1 - r * r) - 1) / 1e-10,
            ]
            worst = _max(worst, *gaps)
    return worst


@M8.check(Level.FLOAT64, tol=1e-14)
def m8_algebra_operators() -> float:
    r"""symrb.vee, symrb.commutator, symrb.algebra.skew_part, inertia_from_lam and lam_from_inertia
    against their NumPy definitions (reference.vee, $ab - ba$, $(a - a^T)/2$, $I_i = \lambda_j +
    \lambda_k$ and its inverse), $n = 3, \dots, 6$, batches of random matrices: max difference
    relative to the size of the entries."""
    import symrb

    rng = np.random.default_rng(89)
    v = rng.standard_normal((5, 3))

    def gap(got: np.ndarray, want: np.ndarray) -> float:
        return float(np.abs(got - want).max() / np.abs(want).max())

    worst = [gap(symrb.vee(ref.hat(v)), v)]
    for k in range(3, 7):
        a, b = rng.standard_normal((2, 4, k, k))
        worst.append(gap(symrb.commutator(a, b), a @ b - b @ a))
        worst.append(gap(symrb.algebra.skew_part(a), (a - np.swapaxes(a, -1, -2)) / 2))
    lam = rng.uniform(0.5, 2.0, (5, 3))
    inertia = lam.sum(axis=-1, keepdims=True) - lam
    worst.append(gap(symrb.algebra.inertia_from_lam(lam), inertia))
    worst.append(gap(symrb.algebra.lam_from_inertia(inertia), lam))
    return float(np.max(worst))


def _ms_field(lam: np.ndarray) -> Callable[[float, np.ndarray], np.ndarray]:
    """The multi-sample field Q^a' = Q^a U, P^a' = P^a U, U = sum_a J^-1(Q^aT P^a - P^aT Q^a),
    in NumPy (reference.J_inv), on the flattened (Q, P) of shape (2, m, 3, 3)."""

    def f(_t: float, y: np.ndarray) -> np.ndarray:
        Q, P = y.reshape(2, -1, 3, 3)
        U = sum(ref.J_inv(q.T @ p - p.T @ q, lam) for q, p in zip(Q, P, strict=True))
        return np.stack([Q @ U, P @ U]).ravel()

    return f


@M8.check(Level.FLOAT64, tol=1e-9)
def m8_fields_through_integrate() -> float:
    """symrb.symmetric.mclachlan_scovel_rhs against $(Q J^{-1}(Q^T B), B J^{-1}(Q^T B))$ in NumPy
    (reference.J_inv; $B = QS$ with $S$ skew, $n = 3$), and symrb.integrate of
    MultiSampleSymmetricRigidBody (three samples, $t$ in $[0, 1]$, rtol 1e-12) against
    scipy.integrate.solve_ivp on the multi-sample field written in NumPy: max difference."""
    from scipy.integrate import solve_ivp

    import symrb

    rng = np.random.default_rng(90)
    worst = []
    for _ in range(5):
        Q = ref.random_rotation(3, rng)
        B = Q @ ref.random_skew(3, rng)
        U = ref.J_inv(Q.T @ B, _LAM)
        Qd, Bd = symrb.symmetric.mclachlan_scovel_rhs(Q, B, _LAM)
        worst += [np.abs(Qd - Q @ U).max(), np.abs(Bd - B @ U).max()]
    Q0 = np.stack([ref.random_rotation(3, rng) for _ in range(3)])
    P0 = 0.3 * rng.standard_normal((3, 3, 3))
    times = np.array([0.0, 0.5, 1.0])
    sol = symrb.integrate(symrb.MultiSampleSymmetricRigidBody, (0.0, 1.0), {"Q": Q0, "P": P0},
                          lam=_LAM, rtol=1e-12, atol=1e-14, t_eval=times)  # fmt: skip
    want = solve_ivp(_ms_field(_LAM), (0.0, 1.0), np.stack([Q0, P0]).ravel(), method="DOP853",
                     rtol=1e-12, atol=1e-14, t_eval=times).y.T.reshape(3, 2, 3, 3, 3)  # fmt: skip
    worst += [np.abs(sol.y.Q - want[:, 0]).max(), np.abs(sol.y.P - want[:, 1]).max()]
    return float(np.max(worst))
