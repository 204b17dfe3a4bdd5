r"""Smooth optimal control and the symmetric rigid body (paper, Sections 3.2-3.3): claims S5-S12.

Derived here, from the definitions:

* S5: the maximum principle for :math:`\min \tfrac14\int\langle U, J(U)\rangle\,dt`,
  :math:`\dot Q = QU`.  The costate :math:`P\in\mathfrak{gl}(n)` is paired with :math:`\dot Q` by
  :math:`\langle A, B\rangle_{\mathfrak{gl}} = \tfrac12\operatorname{tr}(A^TB)` (the only multiple
  of the trace form that gives the printed factor in :math:`U = J^{-1}(Q^TP-P^TQ)`; it extends
  :math:`-\tfrac12\operatorname{tr}(\xi\eta)` from :math:`\mathfrak{so}(n)`).  With
  :math:`H = \langle P, QU\rangle + \tfrac14\langle U, J(U)\rangle` as printed, :math:`H` is convex
  in :math:`U`, has no maximum, and its stationary point is :math:`U = -J^{-1}(Q^TP-P^TQ)`.  The
  maximum principle (normal case, multiplier :math:`-1` on the cost) uses
  :math:`H = \langle P, QU\rangle - \tfrac14\langle U, J(U)\rangle`, whose maximum is the printed
  :math:`U`.  The costate equations :math:`\dot Q = \partial H/\partial P = QU`,
  :math:`\dot P = -\partial H/\partial Q = PU` hold for either sign.
* S6: :math:`M = Q^TP - P^TQ` satisfies :math:`\dot M = [M, U]` on the symmetric flow, for every n
  (noncommutative symbols; only :math:`U^T = -U` is used, not :math:`Q^TQ = I`).
* S7: on the McLachlan-Scovel flow :math:`S = Q^TB + B^TQ` obeys the linear equation
  :math:`\dot S = U^TS + SU`, so :math:`S(0) = 0` implies :math:`S \equiv 0`; and
  :math:`B = P - QP^TQ` maps symmetric rigid body solutions with :math:`Q\in O(n)` to it.
* S8: the learning version: :math:`U = \sum_a J^{-1}((Q^a)^TP^a - (P^a)^TQ^a)` and the endpoint
  condition.  Checked against an independent tangent-linear computation of the derivative of the
  cost: the endpoint condition must read :math:`P^a_T = -\partial\phi/\partial Q^a_T` (gradient in
  the pairing above) for the printed :math:`U`; the printed :math:`+` sign fails.
* S9: for :math:`A = Q^TP` orthogonal, :math:`M^TM + (A+A^T)^T(A+A^T) = 4I` (every n), hence
  :math:`\|M\|_{op}\le 2`, with equality iff :math:`A + A^T` is singular.  For :math:`P\in\mathfrak{gl}(n)`
  the bound is false (:math:`P = QM/2` solves the equation for every skew M).
* S10: :math:`P = Q\exp(\sinh^{-1}(M/2)) = Q\,(M/2 + (I + M^2/4)^{1/2})` solves
  :math:`M = Q^TP - P^TQ` for :math:`\|M\|_{op}<2`; the other reading of the printed formula,
  :math:`\exp(\sinh^{-1}(M)/2)`, does not.
* S11: :math:`\tfrac{d}{dt}(QMQ^T) = 0` on the rigid body flow (every n), so
  :math:`M(t) = Q(t)^T m Q(t)` is isospectral and :math:`\|M\|_{op}` is conserved: C and S are invariant.
* S12: Hamilton's equations :math:`\Omega(X_H,\cdot) = dH` for the printed symplectic form and
  Hamiltonian on :math:`\mathfrak{gl}(n)\times\mathfrak{gl}(n)` (n = 3, symbolic entries) are
  :math:`\dot\xi = \xi U`, :math:`\dot\eta = \eta U`, :math:`U = J^{-1}(\xi^T\eta-\eta^T\xi)`;
  :math:`\xi^T\xi - I` obeys a linear homogeneous equation (SO(n) x SO(n) invariant) and
  :math:`H = \tfrac14\langle J^{-1}M, M\rangle`.

Emitted (``symrb/_generated/symmetric_rigid_body.py``): the symmetric rigid body field, the
McLachlan-Scovel field, the momentum map :math:`M = Q^TP - P^TQ`, the control flow
:math:`(QU, PU)` for a given control, and the Hamiltonian on :math:`\mathfrak{gl}(n)^2`.
"""

from __future__ import annotations

import functools
import itertools

import numpy as np
import sympy as sp

from derivations.codegen import Arg, Kernel, aux, n
from derivations.registry import Claim, Evidence, Level
from derivations.symbolic import (
    diag_matrix,
    general_matrix,
    pair,
    residual,
    skew_gradient,
    skew_matrix,
)
from symrb.algebra import random_SO, random_so

# ---------------------------------------------------------------------------------------------
# helpers

HALF = sp.Rational(1, 2)


def gl_pair(a: sp.Matrix, b: sp.Matrix) -> sp.Expr:
    """The pairing on gl(n) used for the costate: <a, b> = 1/2 trace(a^T b)."""
    return (a.T * b).trace() / 2


def _Jinv(M: sp.Matrix, L: sp.Matrix) -> sp.Matrix:
    nn = M.rows
    return sp.Matrix(nn, nn, lambda i, j: M[i, j] / (L[i, i] + L[j, j]))


def _J(Om: sp.Matrix, L: sp.Matrix) -> sp.Matrix:
    return L * Om + Om * L


def _gl_gradient(F: sp.Expr, X: sp.Matrix) -> sp.Matrix:
    """The G with <G, dX>_gl = dF for <a, b>_gl = 1/2 tr(a^T b): G_ij = 2 dF/dx_ij."""
    return sp.Matrix(X.rows, X.cols, lambda i, j: 2 * sp.diff(F, X[i, j]))


def _subs_skew(expr, U: sp.Matrix, value: sp.Matrix):
    reps = {U[i, j]: value[i, j] for i, j in itertools.combinations(range(U.rows), 2)}
    return expr.xreplace(reps)


def _nc_zero(expr: sp.Expr, rules: dict | None = None) -> sp.Expr:
    """0 when the noncommutative polynomial ``expr`` vanishes after applying ``rules`` to a fixed
    point (e.g. ``{Ut: -U}`` or ``{At*A: 1}``), else 1."""
    e = sp.expand(expr)
    for _ in range(20):
        new = sp.expand(e.subs(rules)) if rules else e
        if new == e:
            break
        e = new
    return sp.Integer(0) if e == 0 else sp.Integer(1)


def _pm_setup(nn: int = 3):
    Q, P = general_matrix("q", nn), general_matrix("p", nn)
    U = skew_matrix("u", nn)
    L = diag_matrix("lam", nn)
    M = Q.T * P - P.T * Q
    return Q, P, U, L, M


def pm_hamiltonian(Q, P, U, L, cost_sign: int = -1, c: sp.Expr = HALF) -> sp.Expr:
    """c tr(P^T Q U) + cost_sign * 1/4 <U, J U>; c = 1/2 is the pairing <.,.>_gl."""
    return c * (P.T * Q * U).trace() + cost_sign * sp.Rational(1, 4) * pair(U, _J(U, L))


def stationary_control(cost_sign: int, c: sp.Expr, nn: int = 3) -> tuple[sp.Matrix, sp.Matrix]:
    """Solve dH/dU = 0 for U (n = nn, symbolic); returns (U*, J^{-1}(Q^T P - P^T Q))."""
    Q, P, U, L, M = _pm_setup(nn)
    G = skew_gradient(pm_hamiltonian(Q, P, U, L, cost_sign, c), U)
    unknowns = [U[i, j] for i, j in itertools.combinations(range(nn), 2)]
    eqs = [G[i, j] for i, j in itertools.combinations(range(nn), 2)]
    sol = sp.solve(eqs, unknowns, dict=True)[0]
    return U.xreplace(sol), _Jinv(M, L)


# ---------------------------------------------------------------------------------------------
# S5: maximum principle, single problem


def s5_corrected_stationary() -> sp.Expr:
    """H = <P,QU>_gl - 1/4 <U,JU>: dH/dU vanishes at U = J^{-1}(Q^T P - P^T Q) (n = 3)."""
    Q, P, U, L, M = _pm_setup()
    G = skew_gradient(pm_hamiltonian(Q, P, U, L, -1), U)
    return residual(_subs_skew(G, U, _Jinv(M, L)))


def s5_corrected_is_maximum() -> sp.Expr:
    """The Hessian of the corrected H in U is -1/2 diag(lam_i + lam_j): negative definite."""
    Q, P, U, L, _M = _pm_setup()
    H = pm_hamiltonian(Q, P, U, L, -1)
    us = [U[i, j] for i, j in itertools.combinations(range(3), 2)]
    target = sp.diag(*[-(L[i, i] + L[j, j]) / 2 for i, j in itertools.combinations(range(3), 2)])
    return residual(sp.hessian(H, us) - target)


def s5_printed_stationary() -> sp.Expr:
    """Printed H = <P,QU>_gl + 1/4 <U,JU>: dH/dU at the printed U = J^{-1}(Q^TP - P^TQ) (n = 3).

    Nonzero: the stationary point of the printed H is U = -J^{-1}(Q^TP - P^TQ), and it is a
    minimum (the Hessian is +1/2 diag(lam_i + lam_j)), so "maximizing" has no solution."""
    Q, P, U, L, M = _pm_setup()
    G = skew_gradient(pm_hamiltonian(Q, P, U, L, +1), U)
    return residual(_subs_skew(G, U, _Jinv(M, L)))


def s5_printed_has_no_maximum() -> sp.Expr:
    """The printed H = <P,QU> + 1/4 <U,JU> is strictly convex in U whatever the pairing on gl(n)
    (the <P,QU> term is linear in U): its Hessian is +1/2 diag(lam_i + lam_j), so "maximizing with
    respect to U" has no solution.  Residual: the smallest Hessian eigenvalue at lam = (1, 2, 3),
    positive (printed form fails) for every choice of pairing."""
    Q, P, U, L, _M = _pm_setup()
    us = [U[i, j] for i, j in itertools.combinations(range(3), 2)]
    Hess = sp.hessian(pm_hamiltonian(Q, P, U, L, +1), us)
    free = sorted(Hess.free_symbols - set(L.diagonal()), key=str)
    if free:  # the Hessian of the linear term vanishes: nothing but Lambda may remain
        return sp.Integer(0)
    Hnum = Hess.subs({L[i, i]: i + 1 for i in range(3)})
    return min(sp.Matrix(Hnum).eigenvals())


def s5_pairing_factor() -> sp.Expr:
    """With the pairing c tr(P^T Q U), the maximiser is U = 2c J^{-1}(Q^TP - P^TQ): c = 1/2."""
    c = sp.Symbol("c", positive=True)
    Ustar, JinvM = stationary_control(-1, c)
    return residual(Ustar - 2 * c * JinvM)


def s5_costate_equations() -> sp.Expr:
    """Qdot = dH/dP = QU and Pdot = -dH/dQ = PU (gradients in <.,.>_gl, n = 3), both signs."""
    Q, P, U, L, _M = _pm_setup()
    total = sp.Integer(0)
    for sign in (-1, 1):
        H = pm_hamiltonian(Q, P, U, L, sign)
        total += residual(_gl_gradient(H, P) - Q * U) + residual(-_gl_gradient(H, Q) - P * U)
    return total


def s5_first_variation(seed: int = 5) -> float:
    """float64: along an extremal (Q, P) of the symmetric flow (n = 4, P in gl(n), t in [0, 2]),
    the first variation of the cost in a control direction dU equals <P_T, dQ_T>_gl, where dQ
    solves the tangent-linear equation dQdot = dQ U + Q dU, dQ(0) = 0:

        int_0^T 1/2 <J U, dU> dt = 1/2 tr(P_T^T dQ_T).

    So every control variation that keeps Q(T) fixed leaves the cost stationary: the extremals are
    critical points of the fixed-endpoint problem with multiplier P_T.  Returns the relative
    mismatch."""
    from scipy.integrate import solve_ivp

    from symrb._generated.symmetric_rigid_body import symmetric_momentum

    rng = np.random.default_rng(seed)
    nn, T = 4, 2.0
    lam = np.array([0.6, 0.9, 1.3, 1.9])
    W = 1.0 / (lam[:, None] + lam[None, :])
    Q0 = random_SO(nn, seed=rng)
    P0 = rng.standard_normal((nn, nn))
    V0, V1 = random_so(nn, seed=rng), random_so(nn, seed=rng)
    k = nn * nn

    def dU(t):
        return V0 + t * V1

    def f(t, y):
        Q, P, dQ = (y[i * k : (i + 1) * k].reshape(nn, nn) for i in range(3))
        U = W * symmetric_momentum(Q, P)
        return np.concatenate([(Q @ U).ravel(), (P @ U).ravel(), (dQ @ U + Q @ dU(t)).ravel()])

    y0 = np.concatenate([Q0.ravel(), P0.ravel(), np.zeros(k)])
    sol = solve_ivp(f, (0, T), y0, method="DOP853", rtol=1e-13, atol=1e-13, dense_output=True)
    nodes, weights = np.polynomial.legendre.leggauss(60)
    ts, ws = T * (nodes + 1) / 2, T * weights / 2
    lhs = 0.0
    for t, w in zip(ts, ws, strict=True):
        y = sol.sol(t)
        U = W * symmetric_momentum(y[:k].reshape(nn, nn), y[k : 2 * k].reshape(nn, nn))
        lhs += w * 0.5 * (-0.5) * np.trace((U / W) @ dU(t))  # 1/2 <J U, dU>
    PT, dQT = sol.y[k : 2 * k, -1].reshape(nn, nn), sol.y[2 * k :, -1].reshape(nn, nn)
    rhs = 0.5 * np.trace(PT.T @ dQT)
    return float(abs(lhs - rhs) / abs(rhs))


# ---------------------------------------------------------------------------------------------
# S6, S7: general n with noncommutative symbols


def _nc(names: str):
    return sp.symbols(names, commutative=False)


def s6_momentum_general_n() -> sp.Expr:
    """d/dt (Qt P - Pt Q) - [M, U] with Qdot = QU, Pdot = PU, (QU)^T = Ut Qt, Ut = -U: zero."""
    Q, Qt, P, Pt, U, Ut = _nc("Q Qt P Pt U Ut")
    dQ, dP, dQt, dPt = Q * U, P * U, Ut * Qt, Ut * Pt
    M = Qt * P - Pt * Q
    Mdot = dQt * P + Qt * dP - dPt * Q - Pt * dQ
    return _nc_zero(Mdot - (M * U - U * M), {Ut: -U})


def s6_momentum_is_skew() -> sp.Expr:
    """M = Q^T P - P^T Q is skew for general symbolic Q, P (n = 4)."""
    Q, P = general_matrix("q", 4), general_matrix("p", 4)
    M = Q.T * P - P.T * Q
    return residual(M + M.T)


def _P_from_M_float(Q, M):
    """Q (M/2 + sqrt(I + M^2/4)) via eigh (the symrb implementation is tested against this)."""
    S = np.eye(M.shape[-1]) + M @ M / 4
    w, V = np.linalg.eigh((S + S.T) / 2)
    return Q @ (M / 2 + (V * np.sqrt(np.clip(w, 0, None))) @ V.T)


def s6_trajectory() -> float:
    """float64: M from the symmetric flow (Q, P) vs the rigid body flow from (Q0, M0), n = 4, t <= 5."""
    from scipy.integrate import solve_ivp

    from symrb._generated.rigid_body import rigid_body_rhs
    from symrb._generated.symmetric_rigid_body import symmetric_momentum, symmetric_rigid_body_rhs

    rng = np.random.default_rng(6)
    nn = 4
    lam = np.array([0.6, 0.9, 1.3, 1.9])
    Q0 = random_SO(nn, seed=rng)
    M0 = random_so(nn, scale=0.4, seed=rng)
    P0 = _P_from_M_float(Q0, M0)
    k = nn * nn
    ts = np.linspace(0, 5, 11)

    def f_sym(_t, y):
        return np.concatenate(
            [
                a.ravel()
                for a in symmetric_rigid_body_rhs(y[:k].reshape(4, 4), y[k:].reshape(4, 4), lam)
            ]
        )

    def f_rb(_t, y):
        return np.concatenate(
            [a.ravel() for a in rigid_body_rhs(y[:k].reshape(4, 4), y[k:].reshape(4, 4), lam)]
        )

    kw = dict(method="DOP853", rtol=1e-12, atol=1e-12, t_eval=ts)
    a = solve_ivp(f_sym, (0, 5), np.concatenate([Q0.ravel(), P0.ravel()]), **kw)
    b = solve_ivp(f_rb, (0, 5), np.concatenate([Q0.ravel(), M0.ravel()]), **kw)
    Ms = symmetric_momentum(a.y[:k].T.reshape(-1, 4, 4), a.y[k:].T.reshape(-1, 4, 4))
    Mr = b.y[k:].T.reshape(-1, 4, 4)
    Qs, Qr = a.y[:k].T, b.y[:k].T
    return float(max(np.abs(Ms - Mr).max(), np.abs(Qs - Qr).max()))


def s7_skew_invariant_general_n() -> sp.Expr:
    """S = Qt B + Bt Q obeys Sdot = Ut S + S U on Qdot = QU, Bdot = BU (any U, any n)."""
    Q, Qt, B, Bt, U, Ut = _nc("Q Qt B Bt U Ut")
    S = Qt * B + Bt * Q
    Sdot = (Ut * Qt) * B + Qt * (B * U) + (Ut * Bt) * Q + Bt * (Q * U)
    return _nc_zero(Sdot - (Ut * S + S * U))


def s7_from_symmetric_general_n() -> sp.Expr:
    """B = P - Q Pt Q: Qt B = Qt P - Pt Q (with Qt Q = 1) and Bdot = B U on the symmetric flow."""
    Q, Qt, P, Pt, U, Ut = _nc("Q Qt P Pt U Ut")
    B = P - Q * Pt * Q
    Bdot = P * U - ((Q * U) * Pt * Q + Q * (Ut * Pt) * Q + Q * Pt * (Q * U))
    return _nc_zero(Qt * B - (Qt * P - Pt * Q), {Qt * Q: 1}) + _nc_zero(Bdot - B * U, {Ut: -U})


def s7_trajectory() -> float:
    """float64: max |Q^T B + B^T Q| along the generated McLachlan-Scovel field (n = 5, t <= 10)."""
    from scipy.integrate import solve_ivp

    from symrb._generated.symmetric_rigid_body import mclachlan_scovel_rhs

    rng = np.random.default_rng(7)
    nn = 5
    lam = np.sort(rng.uniform(0.5, 2.0, nn))
    Q0 = random_SO(nn, seed=rng)
    B0 = Q0 @ random_so(nn, seed=rng)
    k = nn * nn

    def f(_t, y):
        dQ, dB = mclachlan_scovel_rhs(y[:k].reshape(nn, nn), y[k:].reshape(nn, nn), lam)
        return np.concatenate([dQ.ravel(), dB.ravel()])

    sol = solve_ivp(
        f,
        (0, 10),
        np.concatenate([Q0.ravel(), B0.ravel()]),
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
        t_eval=np.linspace(0, 10, 21),
    )
    Q, B = sol.y[:k].T.reshape(-1, nn, nn), sol.y[k:].T.reshape(-1, nn, nn)
    X = np.swapaxes(Q, -1, -2) @ B
    return float(np.abs(X + np.swapaxes(X, -1, -2)).max())


# ---------------------------------------------------------------------------------------------
# S8: multi-sample, terminal cost


def s8_stationary_two_samples() -> sp.Expr:
    """H = sum_a <P^a, Q^a U>_gl - 1/4 <U, JU> (two samples, n = 3) is stationary at
    U = sum_a J^{-1}((Q^a)^T P^a - (P^a)^T Q^a)."""
    nn = 3
    Qs = [general_matrix(f"q{a}", nn) for a in (1, 2)]
    Ps = [general_matrix(f"p{a}", nn) for a in (1, 2)]
    U, L = skew_matrix("u", nn), diag_matrix("lam", nn)
    H = sum(gl_pair(P, Q * U) for Q, P in zip(Qs, Ps, strict=True)) - pair(U, _J(U, L)) / 4
    Ustar = sum((_Jinv(Q.T * P - P.T * Q, L) for Q, P in zip(Qs, Ps, strict=True)), sp.zeros(nn))
    return residual(_subs_skew(skew_gradient(H, U), U, Ustar))


def endpoint_gradient_check(sign: float, factor: float = 2.0, seed: int = 8) -> float:
    """Relative mismatch between two computations of the derivative of the learning cost
    C(U) = int_0^1 1/4 <U, JU> dt + sum_a phi(Q^a_1), phi(Q) = 1/2 ||Q - R||_F^2, in a direction dU:

    * tangent-linear (forward): int 1/2 <JU, dU> dt + sum_a <grad phi, dQ^a_1>, with
      dQdot = dQ U + Q dU, dQ(0) = 0;
    * adjoint (backward): int 1/2 <JU - sum_a (Q^a^T P^a - P^a^T Q^a), dU> dt with Pdot = PU and
      P^a_1 = sign * factor * (Q^a_1 - R); factor 2 turns the entrywise derivative Q - R into the
      gradient in <.,.>_gl.

    Zero for sign = -1, factor = 2: then the reduced gradient is 1/2 (JU - M) and the optimal
    control is U = J^{-1}(sum_a ...), as printed.  n = 3, two samples, controls linear in t.
    """
    from scipy.integrate import solve_ivp

    rng = np.random.default_rng(seed)
    nn, m = 3, 2
    lam = np.array([0.7, 1.1, 1.6])
    W = 1.0 / (lam[:, None] + lam[None, :])
    U0, U1, V0, V1 = (random_so(nn, scale=0.7, seed=rng) for _ in range(4))
    R = random_SO(nn, seed=rng)
    Q0 = np.stack([random_SO(nn, seed=rng) for _ in range(m)])

    def Uf(t):
        return U0 + t * U1

    def dUf(t):
        return V0 + t * V1

    nodes, weights = np.polynomial.legendre.leggauss(40)
    ts, ws = (nodes + 1) / 2, weights / 2
    k = m * nn * nn

    def fwd(t, y):
        Q, dQ = y[:k].reshape(m, nn, nn), y[k:].reshape(m, nn, nn)
        return np.concatenate([(Q @ Uf(t)).ravel(), (dQ @ Uf(t) + Q @ dUf(t)).ravel()])

    kw = dict(method="DOP853", rtol=1e-13, atol=1e-13)
    a = solve_ivp(fwd, (0, 1), np.concatenate([Q0.ravel(), np.zeros(k)]), dense_output=True, **kw)
    Q1, dQ1 = a.y[:k, -1].reshape(m, nn, nn), a.y[k:, -1].reshape(m, nn, nn)

    def so(x, y):
        return -0.5 * np.trace(x @ y)

    J = lambda X: X / W  # noqa: E731  (J on so(n): (lam_i + lam_j) X_ij)
    d_forward = sum(w * 0.5 * so(J(Uf(t)), dUf(t)) for t, w in zip(ts, ws, strict=True))
    # d phi = sum_ij (Q - R)_ij dQ_ij: the entrywise derivative, independent of the convention
    d_forward += sum(float(np.sum((Q1[i] - R) * dQ1[i])) for i in range(m))

    P1 = sign * factor * (Q1 - R)
    b = solve_ivp(
        lambda t, y: (y.reshape(m, nn, nn) @ Uf(t)).ravel(),
        (1, 0),
        P1.ravel(),
        dense_output=True,
        **kw,
    )
    d_adjoint = 0.0
    for t, w in zip(ts, ws, strict=True):
        Q = a.sol(t)[:k].reshape(m, nn, nn)
        P = b.sol(t).reshape(m, nn, nn)
        Mtot = np.sum(np.swapaxes(Q, -1, -2) @ P - np.swapaxes(P, -1, -2) @ Q, axis=0)
        d_adjoint += w * 0.5 * so(J(Uf(t)) - Mtot, dUf(t))
    return float(abs(d_forward - d_adjoint) / abs(d_forward))


# ---------------------------------------------------------------------------------------------
# S9-S11: local equivalence


def s9_norm_identity_general_n() -> sp.Expr:
    """A^T A = A A^T = I implies M^T M + (A + A^T)^T (A + A^T) = 4 I for M = A - A^T (any n)."""
    A, At = _nc("A At")
    M, Mt = A - At, At - A
    S, St = A + At, At + A
    return _nc_zero(Mt * M + St * S - 4, {At * A: 1, A * At: 1})


def s9_sampled_bound() -> float:
    """float64: max(0, ||Q^TP - P^TQ||_op - 2) over 3000 random Q, P in SO(n), n = 2..7."""
    from scipy.stats import special_ortho_group

    rng = np.random.default_rng(9)
    worst = 0.0
    for nn in range(2, 8):
        Q = special_ortho_group.rvs(nn, size=500, random_state=rng)
        P = special_ortho_group.rvs(nn, size=500, random_state=rng)
        M = np.swapaxes(Q, -1, -2) @ P - np.swapaxes(P, -1, -2) @ Q
        worst = max(worst, float(np.linalg.norm(M, 2, axis=(-2, -1)).max()))
    return max(0.0, worst - 2.0)


def s9_bound_attained() -> float:
    """The bound is sharp: Q^TP a rotation by pi/2 in a plane gives ||M||_op = 2 (n = 3), so C is
    not empty; |  ||M||_op - 2 | is returned."""
    A = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    return abs(float(np.linalg.norm(A - A.T, 2)) - 2.0)


def s9_gl_has_no_bound() -> sp.Expr:
    """For P in gl(n) there is no bound: P = Q M / 2 gives Q^T P - P^T Q = M when Q^T Q = I and
    M^T = -M, for every M (noncommutative symbols, any n)."""
    Q, Qt, M, Mt = _nc("Q Qt M Mt")
    P, Pt = Q * M / 2, Mt * Qt / 2
    return _nc_zero(Qt * P - Pt * Q - M, {Qt * Q: 1, Mt: -M})


def s10_scalar_identity() -> sp.Expr:
    """exp(asinh x) = x + sqrt(1 + x^2) and 2 sinh(asinh(x/2)) = x (scalars)."""
    x = sp.Symbol("x", real=True)
    a = sp.simplify(sp.exp(sp.asinh(x)) - x - sp.sqrt(1 + x**2))
    b = sp.simplify(2 * sp.sinh(sp.asinh(x / 2)) - x)
    return residual(sp.Matrix([a, b]))


def _asinh_skew(X: np.ndarray) -> np.ndarray:
    """asinh of a real skew matrix with ||X||_op < 1 via the Hermitian matrix iX: asinh(iy) = i arcsin(y)."""
    w, V = np.linalg.eigh(1j * X)  # iX = V diag(w) V^*, X = V diag(-i w) V^*
    return np.real(V @ np.diag(-1j * np.arcsin(w)) @ V.conj().T)


def s10_reading_half_inside(reading: str = "asinh(M/2)", seed: int = 10) -> float:
    """float64: max |Q^TP - P^TQ - M| for P = Q expm(X), over random skew M with ||M||_op in (0, 2),
    n = 3..6; X = asinh(M/2) or, for the other reading, asinh(M)/2 (with ||M||_op < 1 so that the
    series converges)."""
    from scipy.linalg import expm

    rng = np.random.default_rng(seed)
    worst = 0.0
    for nn in range(3, 7):
        for _ in range(40):
            M = random_so(nn, seed=rng)
            top = 1.9 if reading == "asinh(M/2)" else 0.9
            M *= rng.uniform(0.05, top) / np.linalg.norm(M, 2)
            Q = random_SO(nn, seed=rng)
            X = _asinh_skew(M / 2) if reading == "asinh(M/2)" else _asinh_skew(M) / 2
            P = Q @ expm(X)
            worst = max(worst, float(np.abs(Q.T @ P - P.T @ Q - M).max()))
    return worst


@functools.cache
def _s10_near_boundary(dps: int = 60) -> tuple[float, float]:
    """60 digits, n = 4, ||M||_op = 2(1 - delta) for delta = 1e-4, 1e-8, 1e-12.

    Returns (worst residual of the corrected formula in 60-digit arithmetic, worst float64 error
    of symrb.P_from_M measured in units of eps / sqrt(delta), the conditioning of asinh near 1).
    The reference is P = Q (M/2 + sqrt(I + M^2/4)), the square root through mpmath's symmetric
    eigen-decomposition (symrb uses a real Schur form instead), checked for
    Q^T P - P^T Q = M and P^T P = I in 60 digits.
    """
    import mpmath as mp

    from symrb.algebra import random_SO, random_so
    from symrb.continuous import P_from_M

    rng = np.random.default_rng(1010)
    Q = random_SO(4, seed=rng)
    D = random_so(4, seed=rng)
    D = D / np.linalg.norm(D, 2)
    worst_identity, worst_ratio = 0.0, 0.0
    with mp.workdps(dps):
        for delta in (1e-4, 1e-8, 1e-12):
            M = 2.0 * (1.0 - delta) * D  # exactly representable up to rounding of the product
            Mm = mp.matrix(M.tolist())
            Qm, Rm = mp.qr(mp.matrix(Q.tolist()))  # orthogonal to 60 digits, not just to rounding
            Qm = Qm * mp.diag([mp.sign(Rm[i, i]) for i in range(4)])
            X = Mm / 2
            E, V = mp.eigsy(mp.eye(4) + X * X)  # symmetric positive semidefinite
            P = Qm * (X + V * mp.diag([mp.sqrt(max(e, 0)) for e in E]) * V.T)
            r1 = mp.mnorm(Qm.T * P - P.T * Qm - Mm, 1)
            r2 = mp.mnorm(P.T * P - mp.eye(4), 1)
            worst_identity = max(worst_identity, float(max(r1, r2)))
            Pf = P_from_M(Q, M)
            err = float(mp.mnorm(mp.matrix(Pf.tolist()) - P, 1))
            worst_ratio = max(worst_ratio, err * np.sqrt(delta) / np.finfo(float).eps)
    return worst_identity, worst_ratio


def s10_high_precision_identity() -> float:
    """60 digits: Q^T P - P^T Q - M and P^T P - I for P = Q(M/2 + sqrt(I + M^2/4)) near ||M|| = 2."""
    return _s10_near_boundary()[0]


def s10_float64_conditioning() -> float:
    """symrb.P_from_M error against the 60-digit P, in units of eps/sqrt(1 - ||M||_op/2)."""
    return _s10_near_boundary()[1]


def s10_closed_form_matches() -> float:
    """float64: Q expm(asinh(M/2)) (Hermitian eigen + expm) equals Q (M/2 + sqrt(I + M^2/4))
    (symmetric eigen) and symrb.P_from_M (real Schur), ||M||_op up to 1.99, n = 3..6; P in SO(n)."""
    from scipy.linalg import expm

    from symrb.continuous import P_from_M

    rng = np.random.default_rng(11)
    worst = 0.0
    for nn in range(3, 7):
        for r in np.linspace(0.1, 1.99, 12):
            M = random_so(nn, seed=rng)
            M *= r / np.linalg.norm(M, 2)
            Q = random_SO(nn, seed=rng)
            P1 = Q @ expm(_asinh_skew(M / 2))
            P2 = _P_from_M_float(Q, M)
            P3 = P_from_M(Q, M)  # the shipped implementation (real Schur form)
            orth = np.abs(P2.T @ P2 - np.eye(nn)).max() + abs(np.linalg.det(P2) - 1)
            diff = max(np.abs(P1 - P2).max(), np.abs(P1 - P3).max())
            worst = max(worst, float(diff), float(orth))
    return worst


def s11_spatial_momentum_general_n() -> sp.Expr:
    """d/dt (Q M Qt) = 0 on Qdot = Q Om, Mdot = [M, Om], Om^T = -Om (noncommutative, any n):
    M(t) = Q(t)^T m Q(t) is orthogonally conjugate to m, so its spectrum and ||M||_op are constant."""
    Q, Qt, M, Om, Omt = _nc("Q Qt M Omega Omegat")
    d = (Q * Om) * M * Qt + Q * (M * Om - Om * M) * Qt + Q * M * (Omt * Qt)
    return _nc_zero(d, {Omt: -Om})


def s11_norm_drift() -> float:
    """float64: drift of ||M||_op along the rigid body flow for ||M0||_op = 1.5 (in S) and = 2
    (on C) and along the symmetric flow from (Q, P) in C, n = 4, t <= 10, rtol 1e-12."""
    from scipy.integrate import solve_ivp

    from symrb._generated.rigid_body import rigid_body_rhs
    from symrb._generated.symmetric_rigid_body import symmetric_momentum, symmetric_rigid_body_rhs

    rng = np.random.default_rng(12)
    nn, k = 4, 16
    lam = np.array([0.5, 0.8, 1.4, 2.0])
    worst = 0.0
    kw = dict(method="DOP853", rtol=1e-12, atol=1e-12, t_eval=np.linspace(0, 10, 41))
    for r in (1.5, 2.0):
        M0 = random_so(nn, seed=rng)
        M0 *= r / np.linalg.norm(M0, 2)

        def f(_t, y):
            return rigid_body_rhs(np.eye(nn), y.reshape(nn, nn), lam)[1].ravel()

        sol = solve_ivp(f, (0, 10), M0.ravel(), **kw)
        norms = np.linalg.norm(sol.y.T.reshape(-1, nn, nn), 2, axis=(-2, -1))
        worst = max(worst, float(np.abs(norms - r).max()))
    Q0 = random_SO(nn, seed=rng)
    A = np.array([[0, -1, 0, 0], [1, 0, 0, 0], [0, 0, 0.6, -0.8], [0, 0, 0.8, 0.6]])
    P0 = Q0 @ A  # Q^T P has a rotation by pi/2: ||M||_op = 2, (Q, P) in C

    def g(_t, y):
        return np.concatenate(
            [
                a.ravel()
                for a in symmetric_rigid_body_rhs(y[:k].reshape(4, 4), y[k:].reshape(4, 4), lam)
            ]
        )

    sol = solve_ivp(g, (0, 10), np.concatenate([Q0.ravel(), P0.ravel()]), **kw)
    Ms = symmetric_momentum(sol.y[:k].T.reshape(-1, 4, 4), sol.y[k:].T.reshape(-1, 4, 4))
    norms = np.linalg.norm(Ms, 2, axis=(-2, -1))
    return max(worst, float(np.abs(norms - 2.0).max()))


# ---------------------------------------------------------------------------------------------
# S12: Hamiltonian form on gl(n) x gl(n)


def gl_symplectic_form(X1, Y1, X2, Y2) -> sp.Expr:
    """The printed form Omega((xi1, eta1), (xi2, eta2)) = 1/2 tr(eta2^T xi1 - eta1^T xi2)."""
    return (Y2.T * X1 - Y1.T * X2).trace() / 2


def gl_hamiltonian_expr(X: sp.Matrix, Y: sp.Matrix, L: sp.Matrix) -> sp.Expr:
    """The printed H(xi, eta) = -1/8 tr[J^{-1}(xi^T eta - eta^T xi) (xi^T eta - eta^T xi)]."""
    M = X.T * Y - Y.T * X
    return -sp.Rational(1, 8) * (_Jinv(M, L) * M).trace()


def hamilton_equations(nn: int = 3, convention: int = 1):
    """Solve Omega(X_H, v) = convention * dH(v) for every v (symbolic entries, n = nn).

    The printed form is turned into its 2n^2 x 2n^2 matrix by evaluating it on basis vectors; no
    coefficient is assumed.  Returns (xi, eta, Lambda, xidot, etadot).
    """
    X, Y, L = general_matrix("x", nn), general_matrix("y", nn), diag_matrix("lam", nn)
    coords = list(X) + list(Y)
    N = len(coords)

    def unflatten(vec):
        return sp.Matrix(nn, nn, vec[: nn * nn]), sp.Matrix(nn, nn, vec[nn * nn :])

    basis = [unflatten([1 if k == a else 0 for k in range(N)]) for a in range(N)]
    Wm = sp.Matrix(N, N, lambda a, b: gl_symplectic_form(*basis[a], *basis[b]))
    H = gl_hamiltonian_expr(X, Y, L)
    dH = sp.Matrix([sp.diff(H, c) for c in coords])
    # Omega(Z, v) = Z^T Wm v = dH . v for all v  <=>  Wm^T Z = convention * dH
    Z = Wm.T.solve(convention * dH)
    Xdot, Ydot = unflatten(list(Z))
    return X, Y, L, Xdot, Ydot


def s12_hamilton_equations() -> sp.Expr:
    """Omega(X_H, .) = dH gives xidot = xi U, etadot = eta U, U = J^{-1}(xi^T eta - eta^T xi) (n = 3)."""
    X, Y, L, Xdot, Ydot = hamilton_equations(3, 1)
    U = _Jinv(X.T * Y - Y.T * X, L)
    return residual(Xdot - X * U) + residual(Ydot - Y * U)


def s12_SO_invariant_general_n() -> sp.Expr:
    """On xidot = xi U with U^T = -U: d/dt (xi^T xi) = [xi^T xi, U], linear homogeneous in
    xi^T xi - I, so xi^T xi = I is invariant (noncommutative, any n); likewise for eta."""
    X, Xt, U, Ut = _nc("X Xt U Ut")
    d = (Ut * Xt) * X + Xt * (X * U)
    return _nc_zero(d - ((Xt * X - 1) * U - U * (Xt * X - 1)), {Ut: -U})


def s12_hamiltonian_is_quarter_energy() -> sp.Expr:
    """-1/8 tr(J^{-1}(M) M) = 1/4 <J^{-1} M, M> with M = xi^T eta - eta^T xi (n = 3)."""
    X, Y, L = general_matrix("x", 3), general_matrix("y", 3), diag_matrix("lam", 3)
    M = X.T * Y - Y.T * X
    return residual(gl_hamiltonian_expr(X, Y, L) - pair(_Jinv(M, L), M) / 4)


def s12_trajectory() -> float:
    """float64: along the generated symmetric field from SO(4) x SO(4) (t <= 10): deviation of
    Q, P from SO(4) and drift of the gl Hamiltonian."""
    from scipy.integrate import solve_ivp

    from symrb._generated.symmetric_rigid_body import gl_hamiltonian, symmetric_rigid_body_rhs

    rng = np.random.default_rng(13)
    nn, k = 4, 16
    lam = np.array([0.5, 0.8, 1.4, 2.0])
    Q0, P0 = random_SO(nn, seed=rng), random_SO(nn, seed=rng)

    def g(_t, y):
        return np.concatenate(
            [
                a.ravel()
                for a in symmetric_rigid_body_rhs(y[:k].reshape(4, 4), y[k:].reshape(4, 4), lam)
            ]
        )

    sol = solve_ivp(
        g,
        (0, 10),
        np.concatenate([Q0.ravel(), P0.ravel()]),
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
        t_eval=np.linspace(0, 10, 41),
    )
    Q, P = sol.y[:k].T.reshape(-1, 4, 4), sol.y[k:].T.reshape(-1, 4, 4)
    eye = np.eye(nn)
    dev = max(
        np.abs(np.swapaxes(Q, -1, -2) @ Q - eye).max(),
        np.abs(np.swapaxes(P, -1, -2) @ P - eye).max(),
    )
    H = gl_hamiltonian(Q, P, lam)
    return float(max(dev, np.abs(H - H[0]).max() / abs(H[0])))


# ---------------------------------------------------------------------------------------------

_S5_PRINTED = (
    r"$H=\langle P,QU\rangle+\tfrac14\langle U,J(U)\rangle$, maximised over $U$, gives "
    r"$U=J^{-1}(Q^TP-P^TQ)$; $\dot Q=QU$, $\dot P=PU$."
)
_S5_CORRECTED = (
    r"With $\langle A,B\rangle=\tfrac12\operatorname{tr}(A^TB)$ on $\mathfrak{gl}(n)$: "
    r"$H=\langle P,QU\rangle-\tfrac14\langle U,J(U)\rangle$ is maximised (Hessian "
    r"$-\tfrac12 J$) at $U=J^{-1}(Q^TP-P^TQ)$; $\dot Q=\partial H/\partial P=QU$, "
    r"$\dot P=-\partial H/\partial Q=PU$.  (Equivalently: the printed $H$ is minimised at "
    r"$U=-J^{-1}(Q^TP-P^TQ)$, i.e. the printed $U$ after $P\to-P$.)"
)

CLAIMS = [
    Claim(
        id="S5",
        label="rboptcontprob, optr, eqnr, srb1",
        title="Maximum principle for the smooth rigid body control problem",
        statement=r"The extremals of $\min\tfrac14\int_0^T\langle U,J(U)\rangle dt$, $\dot Q=QU$, "
        r"satisfy $\dot Q=QU$, $\dot P=PU$ with $U=J^{-1}(Q^TP-P^TQ)$.",
        expected="holds after correction",
        printed=_S5_PRINTED,
        corrected=_S5_CORRECTED,
        note="The printed Hamiltonian has the cost with a plus sign and is 'maximized': it is convex "
        "in U (Hessian +J/2), so it has no maximum, and its stationary point is "
        "U = -J^{-1}(Q^T P - P^T Q). The maximum principle with the normal multiplier -1 on the "
        "running cost gives H = <P, QU> - 1/4 <U, J(U)>, maximised exactly at the printed U. The "
        "printed factor of U fixes the pairing of P with Qdot as 1/2 tr(P^T Qdot) (with c tr(P^T QU) "
        "the maximiser is 2c J^{-1}(...)). The costate equations do not depend on the sign.",
        section="3.2",
        evidence=(
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "printed H = <P,QU> + 1/4<U,JU>, pairing <A,B> = 1/2 tr(A^T B): dH/dU at "
                "U = J^{-1}(Q^TP - P^TQ) is not 0 (n = 3; with the pairing -1/2 tr it would be)",
                s5_printed_stationary,
                form="printed",
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "printed H is strictly convex in U for any pairing (Hessian +1/2 diag(lam_i + lam_j)): "
                "no maximum; residual = smallest Hessian eigenvalue at lam = (1, 2, 3)",
                s5_printed_has_no_maximum,
                form="printed",
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "corrected H = <P,QU> - 1/4<U,JU>: dH/dU = 0 at U = J^{-1}(Q^TP - P^TQ) (n = 3)",
                s5_corrected_stationary,
                form="corrected",
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "Hessian of the corrected H in U is -1/2 diag(lam_i + lam_j): a maximum (n = 3)",
                s5_corrected_is_maximum,
                form="corrected",
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "pairing c tr(P^T Q U): the maximiser is 2c J^{-1}(Q^TP - P^TQ), so c = 1/2 (n = 3)",
                s5_pairing_factor,
                form="corrected",
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "Qdot = dH/dP = QU, Pdot = -dH/dQ = PU for either sign of the cost (n = 3)",
                s5_costate_equations,
                form="corrected",
            ),
            Evidence(
                Level.FLOAT64,
                "along an extremal: first variation of the cost = <P_T, dQ_T> (tangent-linear dQ), "
                "so endpoint-preserving variations are stationary (n = 4, P in gl(n))",
                s5_first_variation,
                tol=1e-9,
                form="corrected",
            ),
        ),
    ),
    Claim(
        id="S6",
        label="SRBtoRB.prop",
        title="(Q, M = Q^T P - P^T Q) solves the rigid body equations",
        statement=r"If $\dot Q=QU$, $\dot P=PU$, $U=J^{-1}(M)$, $M=Q^TP-P^TQ$, then "
        r"$\dot Q=Q\Omega$, $\dot M=[M,\Omega]$ with $\Omega=U$, $M=J(\Omega)$.",
        expected="holds",
        section="3.2",
        note="Only U^T = -U is used; Q^T Q = I is not needed, so the statement holds on all of "
        "gl(n) x gl(n).",
        evidence=(
            Evidence(
                Level.SYMBOLIC_GENERAL_N,
                "noncommutative Q, P, U: d/dt(Q^TP - P^TQ) - [M, U] expands to 0 using U^T = -U",
                s6_momentum_general_n,
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "Q^T P - P^T Q is skew for general Q, P (n = 4)",
                s6_momentum_is_skew,
            ),
            Evidence(
                Level.FLOAT64,
                "symmetric flow (Q, P) vs rigid body flow (Q, M): max difference of Q and M, "
                "DOP853 rtol 1e-12, n = 4, t <= 5",
                s6_trajectory,
                tol=1e-9,
            ),
        ),
    ),
    Claim(
        id="S7",
        label="rbnlms",
        title="McLachlan-Scovel equations keep Q^T B skew",
        statement=r"$\dot Q=QJ^{-1}(Q^TB)$, $\dot B=BJ^{-1}(Q^TB)$ leave $\{Q^TB$ skew$\}$ invariant.",
        expected="holds",
        section="3.2",
        note="S = Q^T B + B^T Q satisfies the linear equation Sdot = U^T S + S U for any U, so "
        "S(0) = 0 gives S = 0. B = P - Q P^T Q maps symmetric rigid body solutions with Q "
        "orthogonal to McLachlan-Scovel solutions (the paper's commented-out remark).",
        evidence=(
            Evidence(
                Level.SYMBOLIC_GENERAL_N,
                "noncommutative: d/dt(Q^TB + B^TQ) = U^T S + S U with S = Q^TB + B^TQ",
                s7_skew_invariant_general_n,
            ),
            Evidence(
                Level.SYMBOLIC_GENERAL_N,
                "B = P - QP^TQ: Q^TB = Q^TP - P^TQ (Q^TQ = I) and Bdot = BU on the symmetric flow",
                s7_from_symmetric_general_n,
            ),
            Evidence(
                Level.FLOAT64,
                "max |Q^TB + B^TQ| along the generated field, DOP853 rtol 1e-12, n = 5, t <= 10",
                s7_trajectory,
                tol=1e-9,
            ),
        ),
    ),
    Claim(
        id="S8",
        label="rboptcontprobm, optrm, eqnrm",
        title="Learning version: shared control, per-sample costates, endpoint condition",
        statement=r"$\dot Q^a=Q^aU$, $\dot P^a=P^aU$, "
        r"$U=\sum_aJ^{-1}((Q^a)^TP^a-(P^a)^TQ^a)$, endpoint condition on $P^a_T$.",
        expected="holds after correction",
        printed=r"$P^a_T=\partial\phi(Q^a_T)/\partial Q^a_T$ (with the printed $U$).",
        corrected=r"$P^a_T=-\partial\phi(Q^a_T)/\partial Q^a_T$, the gradient taken in "
        r"$\langle A,B\rangle=\tfrac12\operatorname{tr}(A^TB)$ (twice the entrywise derivative).",
        note="With the running cost entering the maximum principle with multiplier -1 (so that U "
        "is the printed +J^{-1}(...), see S5), transversality gives P_T = -grad phi. Checked "
        "against a forward tangent-linear derivative of the cost: with P_T = -grad phi the "
        "reduced gradient is 1/2 (JU - sum_a M^a) and vanishes exactly at the printed U; with "
        "the printed +grad phi it does not match. The gradient must be taken in the pairing "
        "1/2 tr(A^T B) that gives the printed factor of U (entrywise partials need a factor 2). "
        "Equivalently the printed sign is right after P -> -P, U -> -J^{-1}(...).",
        section="3.2",
        evidence=(
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "two samples: sum_a <P^a, Q^a U> - 1/4<U,JU> is stationary at "
                "U = sum_a J^{-1}(Q^aT P^a - P^aT Q^a) (n = 3)",
                s8_stationary_two_samples,
                form="corrected",
            ),
            Evidence(
                Level.FLOAT64,
                "printed P_T = +grad phi: relative mismatch of adjoint vs tangent-linear derivative "
                "of the cost (n = 3, two samples)",
                lambda: endpoint_gradient_check(+1.0),
                tol=1e-8,
                form="printed",
            ),
            Evidence(
                Level.FLOAT64,
                "corrected P_T = -grad phi: relative mismatch of adjoint vs tangent-linear "
                "derivative of the cost (n = 3, two samples)",
                lambda: endpoint_gradient_check(-1.0),
                tol=1e-8,
                form="corrected",
            ),
        ),
    ),
    Claim(
        id="S9",
        label="M_Q_P.eqn, CandS.definition",
        title="||M||_op <= 2 is necessary for M = Q^T P - P^T Q with P in SO(n)",
        statement=r"If $Q,P\in SO(n)$ and $M=Q^TP-P^TQ$ then $\|M\|_{op}\le2$; the bound is attained.",
        expected="holds",
        section="3.3",
        note="The paper's argument uses ||P||_op <= 1, so P is in SO(n) (or O(n)). For a costate "
        "P in gl(n), as in S5, there is no bound: P = Q M/2 solves the equation for every skew M. "
        "Sharper, for A = Q^T P orthogonal: M^T M + (A + A^T)^T (A + A^T) = 4 I, so ||M||_op = 2 "
        "exactly when A + A^T is singular (A has eigenvalues +-i).",
        evidence=(
            Evidence(
                Level.SYMBOLIC_GENERAL_N,
                "noncommutative A with A^TA = AA^T = 1: M^TM + (A + A^T)^T(A + A^T) = 4",
                s9_norm_identity_general_n,
            ),
            Evidence(
                Level.FLOAT64,
                "max(0, max ||Q^TP - P^TQ||_op - 2) over 3000 random pairs in SO(n), n = 2..7",
                s9_sampled_bound,
                tol=1e-12,
            ),
            Evidence(
                Level.FLOAT64,
                "Q^TP = rotation by pi/2 in a plane gives ||M||_op = 2 (the set C is not empty)",
                s9_bound_attained,
                tol=1e-14,
            ),
            Evidence(
                Level.SYMBOLIC_GENERAL_N,
                "scope: for P in gl(n), P = QM/2 solves M = Q^TP - P^TQ for any skew M (no bound)",
                s9_gl_has_no_bound,
            ),
        ),
    ),
    Claim(
        id="S10",
        label="Pequ",
        title="P = Q exp(asinh(M/2)) solves M = Q^T P - P^T Q for ||M||_op < 2",
        statement=r"For $\|M\|_{op}<2$, $P=Qe^{\sinh^{-1}(M/2)}\in SO(n)$ solves $M=Q^TP-P^TQ$.",
        expected="holds after correction",
        printed=r"$P=Q\,e^{\sinh^{-1}M/2}$, read as $e^{(\sinh^{-1}M)/2}$.",
        corrected=r"$P=Q\,e^{\sinh^{-1}(M/2)}=Q\,(M/2+(I+M^2/4)^{1/2})$.",
        note="Notational: the printed exponent is ambiguous. Read as sinh^{-1}(M/2) (the reading "
        "that matches the domain ||M/2||_op < 1 of the series) it holds; read as (sinh^{-1} M)/2 it "
        "fails even where the series converges. On skew matrices exp(asinh X) = X + sqrt(I + X^2), "
        "which is how symrb.P_from_M computes it. The solution is not unique: eigen-angles "
        "phi and pi - phi of Q^T P give the same M; this one has |phi| < pi/2.",
        section="3.3",
        evidence=(
            Evidence(
                Level.FLOAT64,
                "reading asinh(M)/2: max |Q^TP - P^TQ - M| over random ||M||_op < 1, n = 3..6",
                lambda: s10_reading_half_inside("asinh(M)/2"),
                tol=1e-10,
                form="printed",
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "scalars: exp(asinh x) = x + sqrt(1 + x^2), 2 sinh(asinh(x/2)) = x",
                s10_scalar_identity,
                form="corrected",
            ),
            Evidence(
                Level.FLOAT64,
                "reading asinh(M/2): max |Q^TP - P^TQ - M| over random ||M||_op < 1.9, n = 3..6",
                lambda: s10_reading_half_inside("asinh(M/2)"),
                tol=1e-12,
                form="corrected",
            ),
            Evidence(
                Level.FLOAT64,
                "Q expm(asinh(M/2)) = Q(M/2 + sqrt(I + M^2/4)) = symrb.P_from_M, in SO(n), ||M||_op <= 1.99, n = 3..6",
                s10_closed_form_matches,
                tol=1e-11,
                form="corrected",
            ),
            Evidence(
                Level.MPMATH,
                "60 digits: P = Q(M/2 + sqrt(I + M^2/4)) solves M = Q^TP - P^TQ with P^TP = I at "
                "||M||_op = 2(1 - delta), delta = 1e-4, 1e-8, 1e-12 (n = 4)",
                s10_high_precision_identity,
                tol=1e-50,
                form="corrected",
            ),
            Evidence(
                Level.MPMATH,
                "symrb.P_from_M against that 60-digit P: error in units of eps/sqrt(delta) "
                "(the conditioning of asinh at the boundary)",
                s10_float64_conditioning,
                tol=10.0,
                form="corrected",
            ),
        ),
    ),
    Claim(
        id="S11",
        label="invariance of C and S",
        title="||M||_op is a Casimir; C and S are invariant",
        statement=r"$\|M\|_{op}$ is constant along $\dot M=[M,\Omega]$, so $C=\{\|M\|_{op}=2\}$ and "
        r"$S=\{\|M\|_{op}<2\}$ are invariant under the symmetric rigid body flow.",
        expected="holds",
        section="3.3",
        evidence=(
            Evidence(
                Level.SYMBOLIC_GENERAL_N,
                "noncommutative: d/dt(Q M Q^T) = 0 on the rigid body flow (M(t) = Q^T m Q)",
                s11_spatial_momentum_general_n,
            ),
            Evidence(
                Level.FLOAT64,
                "drift of ||M||_op along the rigid body flow (||M||=1.5, 2) and the symmetric flow "
                "from C, n = 4, t <= 10",
                s11_norm_drift,
                tol=1e-9,
            ),
        ),
    ),
    Claim(
        id="S12",
        label="gln_symp, ourHam",
        title="Hamiltonian form of the symmetric rigid body on gl(n) x gl(n)",
        statement=r"With $\Omega_{\mathfrak{gl}}((\xi_1,\eta_1),(\xi_2,\eta_2))=\tfrac12\operatorname{tr}"
        r"(\eta_2^T\xi_1-\eta_1^T\xi_2)$, $\Omega(X_H,\cdot)=dH$ and $H=-\tfrac18\operatorname{tr}"
        r"[J^{-1}(\xi^T\eta-\eta^T\xi)(\xi^T\eta-\eta^T\xi)]$: $\dot\xi=\xi U$, $\dot\eta=\eta U$, "
        r"$U=J^{-1}(\xi^T\eta-\eta^T\xi)$; $SO(n)\times SO(n)$ is invariant; "
        r"$H=\tfrac14\langle J^{-1}M,M\rangle$.",
        expected="holds",
        section="3.3",
        note="With the convention Omega(X_H, .) = dH the equations are exactly the symmetric rigid "
        "body equations (the factor 1/2 of the form and the 1/8 of H match); the opposite "
        "convention Omega(X_H, .) = -dH reverses time. H is half the kinetic energy "
        "1/2 <J^{-1}M, M>, consistent with the cost 1/4 <U, JU>.",
        evidence=(
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "Omega(X_H, .) = dH solved from the printed form: xidot = xi U, etadot = eta U (n = 3)",
                s12_hamilton_equations,
            ),
            Evidence(
                Level.SYMBOLIC_GENERAL_N,
                "noncommutative: d/dt(xi^T xi) = [xi^T xi - I, U], so xi^T xi = I is invariant",
                s12_SO_invariant_general_n,
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "-1/8 tr(J^{-1}(M) M) = 1/4 <J^{-1}M, M> (n = 3)",
                s12_hamiltonian_is_quarter_energy,
            ),
            Evidence(
                Level.FLOAT64,
                "generated field from SO(4) x SO(4): orthogonality defect and relative drift of H, t <= 10",
                s12_trajectory,
                tol=1e-9,
            ),
        ),
    ),
]


# ---------------------------------------------------------------------------------------------
# code emission


def emit() -> tuple[str, list[Kernel]]:
    Q = sp.MatrixSymbol("Q", n, n)
    P = sp.MatrixSymbol("P", n, n)
    B = sp.MatrixSymbol("B", n, n)
    U = sp.MatrixSymbol("U", n, n)
    Msym = sp.MatrixSymbol("M", n, n)
    W = aux("W")
    arg_Q = Arg(
        "Q", "(..., n, n)", "configuration (SO(n) is invariant; any square matrix accepted)"
    )
    arg_P = Arg("P", "(..., n, n)", "costate")
    arg_B = Arg("B", "(..., n, n)", "McLachlan-Scovel costate, Q^T B skew")
    arg_U = Arg("U", "(..., n, n)", "control, skew")
    arg_lam = Arg("lam", "(..., n)", "diagonal of Lambda, lam_i + lam_j > 0")
    momentum = Q.T * P - P.T * Q
    kernels = [
        Kernel(
            name="symmetric_momentum",
            args=[arg_Q, arg_P],
            outputs={"M": momentum},
            doc="The body momentum of the symmetric representation, M = Q^T P - P^T Q (paper, S6).",
        ),
        Kernel(
            name="symmetric_rigid_body_rhs",
            args=[arg_Q, arg_P, arg_lam],
            intermediates={"M": momentum, "U": sp.HadamardProduct(W, Msym)},
            outputs={"Qdot": Q * U, "Pdot": P * U},
            doc="Symmetric rigid body field (paper, srb1): U = J^{-1}(Q^T P - P^T Q), Qdot = Q U, "
            "Pdot = P U.",
        ),
        Kernel(
            name="mclachlan_scovel_rhs",
            args=[arg_Q, arg_B, arg_lam],
            intermediates={"U": sp.HadamardProduct(W, Q.T * B)},
            outputs={"Qdot": Q * U, "Bdot": B * U},
            doc="McLachlan-Scovel field (paper, rbnlms): U = J^{-1}(Q^T B), Qdot = Q U, Bdot = B U.",
        ),
        Kernel(
            name="control_rhs",
            args=[arg_Q, arg_P, arg_U],
            outputs={"Qdot": Q * U, "Pdot": P * U},
            doc="State and costate fields for a given control U: Qdot = Q U, Pdot = P U "
            "(paper, srb1 and its learning version, one sample per batch entry).",
        ),
        Kernel(
            name="gl_hamiltonian",
            args=[arg_Q, arg_P, arg_lam],
            intermediates={"M": momentum},
            outputs={"H": -sp.Rational(1, 8) * sp.Trace(sp.HadamardProduct(W, Msym) * Msym)},
            doc="The Hamiltonian on gl(n) x gl(n) (paper, ourHam): "
            "H = -1/8 trace(J^{-1}(M) M) = 1/4 <J^{-1} M, M>, M = Q^T P - P^T Q.",
        ),
    ]
    return "symmetric_rigid_body", kernels
