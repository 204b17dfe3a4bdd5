r"""The discrete symmetric rigid body and the Moser-Veselov equations (paper, Section 2): D7-D12.

Derived here:

* D7: critical points of :math:`\operatorname{tr}(AU)` on :math:`SO(n)` satisfy :math:`AU=U^TA^T`
  (variations :math:`U\mapsto Ue^{\epsilon\xi}` and the Lagrange multiplier computation, whose
  multiplier is :math:`n\times n`, not :math:`N\times N` as printed); with
  :math:`A = P_{k+1}^TQ_k-\Lambda` this gives symequation, the costate recursion, equ_final_th_2.7
  and, after :math:`P\to-P`, Ukdef (noncommutative symbols, any n).  The dynamics printed as
  :math:`Q_{r+1}=Q_kU_r` (discrbeq) must read :math:`Q_{r+1}=Q_rU_r`.
* D8: :math:`J_D(U)=U\Lambda-\Lambda U^T` is skew, its derivative at :math:`I` is :math:`J`, it is a
  local diffeomorphism near :math:`I`; the symmetric algorithm transports :math:`M` by
  :math:`U^TMU`.
* D9: the learning version; its index range (printed :math:`\sum_{k=1}^{N-1}`) must start at
  :math:`k=0`; the endpoint sign is checked against the gradient of the cost.
* D10-D12: the Moser-Veselov equations, both algorithms, the discrete Euler-Lagrange equations of
  :math:`\sum_k\operatorname{tr}(Q_k\Lambda Q_{k+1}^T)` and the passage from the symmetric
  representation with :math:`M_{k+1}=Q_k^TP_k-P_k^TQ_k`.

Noncommutative bookkeeping: a matrix :math:`X` is a noncommutative symbol ``X`` and its transpose a
separate symbol ``Xt``; :func:`_transpose` reverses words, :func:`_reduce` cancels :math:`XX^T` and
:math:`X^TX` for orthogonal letters, :func:`_trace_coefficient` rotates trace words so that a
chosen letter comes last.

Emitted (``symrb/_generated/discrete_rigid_body.py``): :math:`J_D`, the symmetric momentum
:math:`Q^TP-P^TQ`, mv2, mv3 and one term of the Moser-Veselov action.
"""

from __future__ import annotations

import functools
import itertools

import numpy as np
import sympy as sp

from derivations.codegen import Arg, Kernel, aux, n
from derivations.registry import Claim, Evidence, Level
from derivations.symbolic import general_matrix, residual, skew_matrix

# ---------------------------------------------------------------------------------------------
# noncommutative words with transposes

_TRANSPOSE: dict[sp.Symbol, sp.Expr] = {}


def _nc(names: str, symmetric: str = "", skew: str = "") -> list[sp.Symbol]:
    """Noncommutative letters and their transposes (``X`` and ``Xt``); symmetric letters are their
    own transpose, skew letters map to minus themselves."""
    out = []
    for name in names.split():
        x = sp.Symbol(name, commutative=False)
        if name in symmetric.split():
            _TRANSPOSE[x] = x
        elif name in skew.split():
            _TRANSPOSE[x] = -x
        else:
            xt = sp.Symbol(name + "t", commutative=False)
            _TRANSPOSE[x], _TRANSPOSE[xt] = xt, x
        out.append(x)
    return out


def _letters(term: sp.Expr) -> tuple[sp.Expr, list[sp.Symbol]]:
    """A monomial as (commutative coefficient, list of noncommutative letters), powers unrolled."""
    c, nc = term.args_cnc()
    word: list[sp.Symbol] = []
    for f in nc:
        if isinstance(f, sp.Pow):
            word.extend([f.base] * int(f.exp))
        else:
            word.append(f)
    return sp.Mul(*c), word


def _transpose(expr: sp.Expr) -> sp.Expr:
    total = sp.Integer(0)
    for term in sp.Add.make_args(sp.expand(expr)):
        c, word = _letters(term)
        total += c * sp.Mul(*[_TRANSPOSE[x] for x in reversed(word)])
    return total


def _reduce(expr: sp.Expr, orthogonal: list[sp.Symbol]) -> sp.Expr:
    """Expand and cancel adjacent X Xt and Xt X for every orthogonal letter X."""
    pairs = set()
    for x in orthogonal:
        pairs.add((x, _TRANSPOSE[x]))
        pairs.add((_TRANSPOSE[x], x))
    total = sp.Integer(0)
    for term in sp.Add.make_args(sp.expand(expr)):
        c, word = _letters(term)
        changed = True
        while changed:
            changed = False
            for i in range(len(word) - 1):
                if (word[i], word[i + 1]) in pairs:
                    word = word[:i] + word[i + 2 :]
                    changed = True
                    break
        total += c * sp.Mul(*word)
    return sp.expand(total)


def _trace_coefficient(expr: sp.Expr, letter: sp.Symbol) -> sp.Expr:
    """B with tr(expr) = tr(B letter), for expr linear in ``letter`` (rotate each trace word)."""
    total = sp.Integer(0)
    for term in sp.Add.make_args(sp.expand(expr)):
        c, word = _letters(term)
        pos = [i for i, x in enumerate(word) if x == letter]
        if len(pos) != 1:
            raise ValueError(f"term {term} is not linear in {letter}")
        i = pos[0]
        total += c * sp.Mul(*(word[i + 1 :] + word[:i]))
    return sp.expand(total)


def _is_zero(expr: sp.Expr) -> sp.Expr:
    return sp.Integer(0) if sp.expand(expr) == 0 else sp.Integer(1)


# ---------------------------------------------------------------------------------------------
# D7: critical points of trace(AU), the multiplier, symequation, the costate, the sign flip


def d7_variation_trace_AU(nn: int = 3) -> sp.Expr:
    r"""d/de tr(A U (I + e xi))|_0 = sum_{i<j} xi_ij ((AU)_ji - (AU)_ij) for skew xi: it vanishes for
    every xi exactly when AU is symmetric (general A, U; n = 3)."""
    A, U = general_matrix("a", nn), general_matrix("u", nn)
    xi = skew_matrix("x", nn)
    eps = sp.Symbol("epsilon")
    f = (A * U * (sp.eye(nn) + eps * xi)).trace()
    B = A * U
    form = sum(
        (xi[i, j] * (B[j, i] - B[i, j]) for i, j in itertools.combinations(range(nn), 2)),
        sp.Integer(0),
    )
    return residual(sp.diff(f, eps).subs(eps, 0) - form)


def _lagrange_residual(nn: int, sigma_size: int) -> sp.Expr:
    A, U, dU = general_matrix("a", nn), general_matrix("u", nn), general_matrix("d", nn)
    Sig = sp.Matrix(
        sigma_size,
        sigma_size,
        lambda i, j: sp.Symbol(f"s{min(i, j) + 1}{max(i, j) + 1}", real=True),
    )
    eps = sp.Symbol("epsilon")
    Ue = U + eps * dU
    try:
        V = (A * Ue).trace() + sp.Rational(1, 2) * (Sig * (Ue.T * Ue - sp.eye(nn))).trace()
        lhs = sp.diff(V, eps).subs(eps, 0)
        rhs = ((A + Sig * U.T) * dU).trace()
    except sp.ShapeError:
        return sp.Integer(1)  # the multiplier term is not even defined
    return residual(lhs - rhs)


def d7_multiplier_n_by_n() -> sp.Expr:
    """With a symmetric n x n multiplier Sigma: d V~(U + e dU)/de = tr((A + Sigma U^T) dU) (n = 3)."""
    return _lagrange_residual(3, 3)


def d7_multiplier_N_by_N() -> sp.Expr:
    """As printed, Sigma is N x N (N = number of steps, here N = 4, n = 3): tr(Sigma (U^T U - I))
    is not defined; residual 1."""
    return _lagrange_residual(3, 4)


def d7_trace_AU_optimisation() -> float:
    """float64: maximise and minimise tr(AU) over SO(n) with scipy (BFGS on U = U_c expm(xi), chart
    re-centred once, gtol 1e-12) for random A, n = 3, 4; return max ||AU - (AU)^T|| / ||A|| at the
    optima found (the asymmetry is the Riemannian gradient, so it is as small as the optimiser makes
    the gradient)."""
    from scipy.linalg import expm, expm_frechet
    from scipy.optimize import minimize

    rng = np.random.default_rng(7)
    worst = 0.0
    for nn in (3, 4):
        pairs = list(itertools.combinations(range(nn), 2))
        basis = []
        for i, j in pairs:
            E = np.zeros((nn, nn))
            E[i, j], E[j, i] = 1.0, -1.0
            basis.append(E)
        A = rng.standard_normal((nn, nn))
        for sign in (1.0, -1.0):
            Uc = np.eye(nn)
            for _restart in range(2):  # re-centre the chart at the last optimum

                def f(x, Uc=Uc, A=A, sign=sign, basis=basis):
                    X = sum(c * E for c, E in zip(x, basis, strict=True))
                    return -sign * np.trace(A @ Uc @ expm(X))

                def g(x, Uc=Uc, A=A, sign=sign, basis=basis):
                    X = sum(c * E for c, E in zip(x, basis, strict=True))
                    return np.array(
                        [
                            -sign * np.trace(A @ Uc @ expm_frechet(X, E, compute_expm=False))
                            for E in basis
                        ]
                    )

                x0 = rng.standard_normal(len(basis)) * 0.1
                r = minimize(f, x0, jac=g, method="BFGS", options={"gtol": 1e-12, "maxiter": 500})
                X = sum(c * E for c, E in zip(r.x, basis, strict=True))
                Uc = Uc @ expm(X)
            B = A @ Uc
            worst = max(worst, float(np.linalg.norm(B - B.T) / np.linalg.norm(A)))
    return worst


def d7_symequation_general_n() -> sp.Expr:
    """Noncommutative, any n: with A = P1^T Q - L (L = Lambda) and U orthogonal,
    U (A U - U^T A^T) U^T = -(U L - L U^T - (-Q^T P1 U^T + U P1^T Q)): AU = U^T A^T is symequation."""
    U, Q, P1, L = _nc("U Q P1 L", symmetric="L")
    Ut, Qt, P1t = (_TRANSPOSE[x] for x in (U, Q, P1))
    A = P1t * Q - L
    crit = A * U - Ut * _transpose(A)
    lhs = U * L - L * Ut
    rhs = -Qt * P1 * Ut + U * P1t * Q
    return _is_zero(_reduce(U * crit * Ut + (lhs - rhs), [U]))


def d7_costate_gradients(nn: int = 3) -> sp.Expr:
    """H = tr(P1^T Q U) - tr(Lambda U): dH/dQ = P1 U^T and dH/dP1 = Q U entrywise (n = 3)."""
    Q, P1, U = general_matrix("q", nn), general_matrix("p", nn), general_matrix("u", nn)
    L = sp.diag(*[sp.Symbol(f"lam{i + 1}") for i in range(nn)])
    H = (P1.T * Q * U).trace() - (L * U).trace()
    gQ = sp.Matrix(nn, nn, lambda i, j: sp.diff(H, Q[i, j]))
    gP = sp.Matrix(nn, nn, lambda i, j: sp.diff(H, P1[i, j]))
    return residual(gQ - P1 * U.T) + residual(gP - Q * U)


def d7_final_and_flip_general_n() -> sp.Expr:
    """Noncommutative, any n: with P1 = P U (U orthogonal) the right side of symequation equals
    P^T Q - Q^T P (equ_final_th_2.7), and P -> -P turns it into Q^T P - P^T Q (Ukdef)."""
    U, Q, P = _nc("U Q P")
    Ut, Qt, Pt = (_TRANSPOSE[x] for x in (U, Q, P))
    P1, P1t = P * U, Ut * Pt
    rhs = -Qt * P1 * Ut + U * P1t * Q
    final = Pt * Q - Qt * P
    r1 = _reduce(rhs - final, [U])
    flipped = final.subs({P: -P, Pt: -Pt}, simultaneous=True)
    return _is_zero(r1) + _is_zero(flipped - (Qt * P - Pt * Q))


def _mv_functional_residual(printed: bool) -> float:
    rng = np.random.default_rng(11)
    from symrb.algebra import random_SO

    nn, N = 4, 6
    lam = np.array([0.6, 0.9, 1.3, 1.7])
    U = random_SO(nn, size=(N,), seed=rng)
    Q = [random_SO(nn, seed=rng)]
    for r in range(N):
        base = (
            Q[0] if printed else Q[r]
        )  # printed discrbeq: Q_{r+1} = Q_k U_r with k frozen (k = 0)
        Q.append(base @ U[r])
    lhs = sum(np.trace(np.diag(lam) @ U[r]) for r in range(N))
    rhs = sum(np.trace(Q[r] @ np.diag(lam) @ Q[r + 1].T) for r in range(N))
    return float(abs(lhs - rhs) / abs(lhs))


def d7_mv_functional_printed() -> float:
    """float64: dynamics as printed in discrbeq, Q_{r+1} = Q_k U_r (k = 0): the proof's identity
    sum tr(Lambda U_k) = sum tr(Q_k Lambda Q_{k+1}^T) fails (relative residual)."""
    return _mv_functional_residual(printed=True)


def d7_mv_functional_corrected() -> float:
    """float64: with Q_{r+1} = Q_r U_r the identity sum tr(Lambda U_k) = sum tr(Q_k Lambda Q_{k+1}^T)
    holds to rounding (n = 4, N = 6)."""
    return _mv_functional_residual(printed=False)


# ---------------------------------------------------------------------------------------------
# D8: J_D, its derivative at I, local diffeomorphism, the symmetric algorithm


def d8_jd_skew(nn: int = 4) -> sp.Expr:
    """J_D(U)^T = -J_D(U) for every (even non-orthogonal) U: J_D maps into so(n) (n = 4)."""
    U = general_matrix("u", nn)
    L = sp.diag(*[sp.Symbol(f"lam{i + 1}") for i in range(nn)])
    JD = U * L - L * U.T
    return residual(JD.T + JD)


def d8_derivative_general_n() -> sp.Expr:
    """Noncommutative, any n: with U = exp(e Om) = 1 + e Om + e^2 Om^2/2 + ..., U^T = exp(-e Om),
    d/de J_D(U) at e = 0 equals Om L + L Om = J(Om)."""
    Om, L = _nc("Om L", symmetric="L", skew="Om")
    eps = sp.Symbol("epsilon")
    U = 1 + eps * Om + eps**2 * Om**2 / 2
    Ut = _transpose(U)
    JD = sp.expand(U * L - L * Ut)
    return _is_zero(sp.diff(JD, eps).subs(eps, 0) - (Om * L + L * Om))


def d8_local_diffeomorphism() -> float:
    """float64: the matrix of xi -> xi Lambda + Lambda xi on so(n) (n = 6) has singular values
    lam_i + lam_j > 0 (invertible), and the solver inverts J_D near I: J_D(solve(M)) = M,
    solve(J_D(U)) = U for U = expm(small skew).  Returns the largest of: the singular value
    mismatch (relative), ||solve(J_D(U)) - U||_F, ||J_D(solve(M)) - M||_F / ||M||_F."""
    from scipy.linalg import expm

    from symrb.algebra import J_D, random_so
    from symrb.solvers import solve_moser_veselov

    rng = np.random.default_rng(8)
    nn = 6
    lam = np.sort(rng.uniform(0.5, 2.0, nn))
    pairs = list(itertools.combinations(range(nn), 2))
    Jmat = np.zeros((len(pairs), len(pairs)))
    for c, (i, j) in enumerate(pairs):
        E = np.zeros((nn, nn))
        E[i, j], E[j, i] = 1.0, -1.0
        out = E @ np.diag(lam) + np.diag(lam) @ E
        Jmat[:, c] = [out[a, b] for a, b in pairs]
    sv = np.sort(np.linalg.svd(Jmat, compute_uv=False))
    expected = np.sort([lam[i] + lam[j] for i, j in pairs])
    err = float(np.max(np.abs(sv - expected)) / expected.max())
    for scale in (1e-6, 1e-3, 1e-1):
        xi = random_so(nn, seed=rng, scale=scale)
        U = expm(xi)
        M = J_D(U, lam)
        U2 = solve_moser_veselov(M, lam)
        err = max(err, float(np.linalg.norm(U2 - U)))  # entries of U are O(1): absolute
        err = max(err, float(np.linalg.norm(J_D(U2, lam) - M) / np.linalg.norm(M)))
    return err


def d8_symmetric_transport_general_n() -> sp.Expr:
    """Noncommutative, any n: Q1 = Q U, P1 = P U give Q1^T P1 - P1^T Q1 = U^T (Q^T P - P^T Q) U."""
    U, Q, P = _nc("U Q P")
    Ut, Qt, Pt = (_TRANSPOSE[x] for x in (U, Q, P))
    Q1, P1 = Q * U, P * U
    lhs = _transpose(Q1) * P1 - _transpose(P1) * Q1
    return _is_zero(lhs - Ut * (Qt * P - Pt * Q) * U)


# ---------------------------------------------------------------------------------------------
# D9: the learning version (several samples, terminal cost)


def _d9_setup(seed: int = 9):
    from scipy.linalg import expm

    from symrb.algebra import random_SO, random_so

    rng = np.random.default_rng(seed)
    nn, N, S = 3, 4, 2
    lam = np.array([0.7, 1.1, 1.6])
    U = np.array([expm(random_so(nn, seed=rng, scale=0.3)) for _ in range(N)])
    Q0 = random_SO(nn, size=(S,), seed=rng)
    targets = random_SO(nn, size=(S,), seed=rng)
    return nn, N, S, lam, U, Q0, targets


def _d9_cost(U, lam, Q0, targets, k_start: int) -> float:
    Q = Q0.copy()
    for k in range(U.shape[0]):
        Q = Q @ U[k]
    run = sum(np.trace(np.diag(lam) @ U[k]) for k in range(k_start, U.shape[0]))
    return float(run + 0.5 * np.sum((Q - targets) ** 2))  # phi(Q) = 1/2 ||Q - T||_F^2


def _d9_mismatch(k_start: int, endpoint_sign: float, flipped: bool) -> float:
    """Largest relative gap between directional derivatives of the cost along U_k -> U_k e^{e xi}
    (central differences) and 1/2 tr(U^T (J_D(U_k) - R_k) U xi), where R_k is the right side of
    Ukdef2 (or, unflipped, of equ_final_th_2.7) built from costates with P_N = sign * dphi/dQ_N."""
    from scipy.linalg import expm

    nn, N, S, lam, U, Q0, targets = _d9_setup()
    Qs = [Q0]
    for k in range(N):
        Qs.append(Qs[-1] @ U[k])
    P = [None] * (N + 1)
    P[N] = endpoint_sign * (Qs[N] - targets)  # dphi/dQ_N = Q_N - T
    for k in range(N - 1, -1, -1):
        P[k] = P[k + 1] @ U[k].T
    L = np.diag(lam)
    worst = 0.0
    h = 1e-5
    for k in range(N):
        Mk = np.einsum("aji,ajk->ik", Qs[k], P[k]) - np.einsum("aji,ajk->ik", P[k], Qs[k])
        R = -Mk if flipped is False else Mk
        G = 0.5 * U[k].T @ (U[k] @ L - L @ U[k].T - R) @ U[k]
        for i, j in itertools.combinations(range(nn), 2):
            xi = np.zeros((nn, nn))
            xi[i, j], xi[j, i] = 1.0, -1.0
            Up, Um = U.copy(), U.copy()
            Up[k] = U[k] @ expm(h * xi)
            Um[k] = U[k] @ expm(-h * xi)
            fd = (
                _d9_cost(Up, lam, Q0, targets, k_start) - _d9_cost(Um, lam, Q0, targets, k_start)
            ) / (2 * h)
            worst = max(worst, abs(fd - np.trace(G @ xi)) / max(1.0, abs(fd)))
    return float(worst)


def d9_corrected() -> float:
    """float64: cost sum_{k=0}^{N-1} tr(Lambda U_k) + sum_a phi(Q_N^a); P_N^a = +dphi/dQ_N^a,
    P_k = P_{k+1} U_k^T: the gradient in U_k vanishes exactly when Ukdef2 holds (n=3, N=4, 2 samples)."""
    return _d9_mismatch(k_start=0, endpoint_sign=1.0, flipped=True)


def d9_printed_index() -> float:
    """float64: with the printed range sum_{k=1}^{N-1} (discrboptm) the gradient in U_0 is not given
    by Ukdef2: the mismatch at k = 0 is O(1)."""
    return _d9_mismatch(k_start=1, endpoint_sign=1.0, flipped=True)


def d9_unflipped_endpoint_printed() -> float:
    """float64: the proof's route before the flip P -> -P: H of dischamm with m8's endpoint
    p_N = +dphi/dx_N gives U Lambda - Lambda U^T = sum (P^T Q - Q^T P): it does not match the gradient."""
    return _d9_mismatch(k_start=0, endpoint_sign=1.0, flipped=False)


def d9_unflipped_endpoint_corrected() -> float:
    """float64: before the flip the costate of H = <P, QU> - tr(Lambda U) has P_N = -dphi/dQ_N; then
    U Lambda - Lambda U^T = sum (P^T Q - Q^T P) matches the gradient."""
    return _d9_mismatch(k_start=0, endpoint_sign=-1.0, flipped=False)


# ---------------------------------------------------------------------------------------------
# D10: Moser-Veselov equations and algorithms


def d10_mv3_is_conjugation_general_n() -> sp.Expr:
    """Noncommutative, any n: for orthogonal Om, mv2 and mv3 give
    M_{k+1} = Om (Om^T L - L Om) Om^T = L Om^T - Om L."""
    Om, L = _nc("W L", symmetric="L")
    Omt = _TRANSPOSE[Om]
    Mk = Omt * L - L * Om
    return _is_zero(_reduce(Om * Mk * Omt - (L * Omt - Om * L), [Om]))


def d10_solvability_n2() -> sp.Expr:
    """n = 2: J_D(R(theta)) = (lam1 + lam2) sin(theta) [[0, -1], [1, 0]]: mv2 is solvable exactly when
    |M_21| <= lam1 + lam2, on the branch through I by theta = asin(M_21/(lam1 + lam2))."""
    th = sp.Symbol("theta", real=True)
    l1, l2 = sp.symbols("lam1 lam2", positive=True)
    R = sp.Matrix([[sp.cos(th), -sp.sin(th)], [sp.sin(th), sp.cos(th)]])
    L = sp.diag(l1, l2)
    JD = R * L - L * R.T
    return residual(sp.simplify(JD - (l1 + l2) * sp.sin(th) * sp.Matrix([[0, -1], [1, 0]])))


def d10_fold_n2() -> float:
    """float64: symrb.fold_scale for n = 2 equals (lam1 + lam2)/|M_21| (relative error)."""
    from symrb.solvers import fold_scale

    lam = np.array([0.7, 1.9])
    M = np.array([[0.0, -0.37], [0.37, 0.0]])
    return float(abs(fold_scale(M, lam) - lam.sum() / 0.37) / (lam.sum() / 0.37))


@functools.lru_cache(maxsize=1)
def _d10_runs(steps: int = 1000):
    from scipy.linalg import expm

    from symrb.algebra import random_SO, random_so
    from symrb.discrete import mv_algorithm1, mv_algorithm2
    from symrb.solvers import solve_moser_veselov

    rng = np.random.default_rng(10)
    lam = np.array([0.6, 0.9, 1.3, 1.7])
    M1 = random_so(4, seed=rng, scale=0.05)
    Q1 = random_SO(4, seed=rng)
    Om1 = solve_moser_veselov(M1, lam).T  # mv2: M_1 = Om_1^T Lam - Lam Om_1
    Q0 = Q1 @ Om1  # mv1: Om_1 = Q_1^T Q_0
    QA = mv_algorithm1(Q0, Q1, lam, steps)
    QB, MB = mv_algorithm2(Q1, M1, lam, steps)
    # the same MV-Algorithm 1 from Q_1 moved by one rounding unit: its own sensitivity to rounding
    Q1p = Q1 @ expm(random_so(4, seed=rng, scale=float(np.finfo(float).eps)))
    QAp = mv_algorithm1(Q0, Q1p, lam, steps)
    return QA, QB, MB, QAp, M1


def d10_algorithms_agree() -> float:
    """float64: MV-Algorithm 1 from (Q_0, Q_1) and MV-Algorithm 2 from (Q_1, M_1) give the same
    Q_k over 1000 steps (n = 4).  Algorithm 1 computes M from Q_{k+1}^T Q_k, so it amplifies
    rounding; the residual is max|Q_k(alg 1) - Q_k(alg 2)| divided by max|Q_k(alg 1) - Q_k(alg 1
    from Q_1 moved by one rounding unit)|: at most 10 means agreement to rounding."""
    QA, QB, _MB, QAp, _M1 = _d10_runs()
    dev = float(np.max(np.abs(QA[1:] - QB)))
    sens = float(np.max(np.abs(QA - QAp)))
    return dev / sens


def d10_spectrum() -> float:
    """float64: the spectrum of M_k along MV-Algorithm 2 (1000 steps, n = 4) stays that of M_1
    (mv3 is a conjugation): max relative deviation of the eigenvalues."""
    _QA, _QB, MB, _QAp, M1 = _d10_runs()
    ev0 = np.sort(np.linalg.eigvals(M1).imag)
    evs = np.sort(np.linalg.eigvals(MB).imag, axis=-1)
    return float(np.max(np.abs(evs - ev0)) / np.max(np.abs(ev0)))


# ---------------------------------------------------------------------------------------------
# D11: the discrete variational principle


def d11_euler_lagrange_general_n() -> sp.Expr:
    """Noncommutative, any n: varying Q_k -> Q_k (1 + e xi) in tr(Q_{k-1} L Q_k^T) + tr(Q_k L Q_{k+1}^T)
    gives d/de = tr(B xi) (xi skew), and B - B^T = Om_k M_k Om_k^T - M_{k+1} with mv1-mv2
    (Om_k = Q_k^T Q_{k-1}, M_k = Om_k^T L - L Om_k): stationarity is exactly mv3."""
    Qa, Qb, Qc, L, xi = _nc("Qa Qb Qc L xi", symmetric="L", skew="xi")  # Q_{k-1}, Q_k, Q_{k+1}
    Qat, Qbt, Qct = (_TRANSPOSE[x] for x in (Qa, Qb, Qc))
    eps = sp.Symbol("epsilon")
    Qb_e = Qb * (1 + eps * xi)
    S = Qa * L * _transpose(Qb_e) + Qb_e * L * Qct  # inside the trace
    dS = sp.diff(sp.expand(S), eps)
    B = _trace_coefficient(dS, xi)
    Om_k, Om_k1 = Qbt * Qa, Qct * Qb  # mv1 at k and k+1
    M_k = _transpose(Om_k) * L - L * Om_k  # mv2
    M_k1 = _transpose(Om_k1) * L - L * Om_k1
    target = Om_k * M_k * _transpose(Om_k) - M_k1
    return _is_zero(_reduce(B - _transpose(B) - target, [Qa, Qb, Qc]))


def d11_stationary_numeric() -> float:
    """float64: along an MV-Algorithm-1 sequence (n = 4, 8 steps) every directional derivative of
    S = sum tr(Q_k Lambda Q_{k+1}^T) in an interior Q_k (Q_k -> Q_k(1 + e xi), exact first-order
    formula) vanishes; relative to the same derivative on a perturbed sequence, which is O(1)."""
    from symrb.algebra import random_SO, random_so
    from symrb.discrete import mv_algorithm1

    rng = np.random.default_rng(12)
    nn = 4
    lam = np.array([0.6, 0.9, 1.3, 1.7])
    L = np.diag(lam)
    Q0 = random_SO(nn, seed=rng)
    from scipy.linalg import expm

    Q1 = Q0 @ expm(random_so(nn, seed=rng, scale=0.2))
    Q = mv_algorithm1(Q0, Q1, lam, 7)

    def grad(Qs):
        worst = 0.0
        for k in range(1, len(Qs) - 1):
            for i, j in itertools.combinations(range(nn), 2):
                xi = np.zeros((nn, nn))
                xi[i, j], xi[j, i] = 1.0, -1.0
                d = np.trace(Qs[k - 1] @ L @ (Qs[k] @ xi).T) + np.trace(
                    Qs[k] @ xi @ L @ Qs[k + 1].T
                )
                worst = max(worst, abs(d))
        return worst

    Qp = Q.copy()
    Qp[3] = Qp[3] @ expm(random_so(nn, seed=rng, scale=0.05))
    return float(grad(Q) / grad(Qp))


# ---------------------------------------------------------------------------------------------
# D12: from the symmetric representation to Moser-Veselov


def d12_general_n() -> sp.Expr:
    """Noncommutative, any n: with Q_{k+1} = Q_k U, P_{k+1} = P_k U and Om_{k+1} := Q_{k+1}^T Q_k
    (mv1): mv2 gives Om_{k+1}^T L - L Om_{k+1} = U L - L U^T = J_D(U) (= M_{k+1} of Mdef1 by
    Ukdef1), and mv3 gives Om_{k+1} (Q_k^T P_k - P_k^T Q_k) Om_{k+1}^T = Q_{k+1}^T P_{k+1} - P_{k+1}^T
    Q_{k+1}, i.e. Mdef1 at the next step."""
    U, Q, P, L = _nc("U Q P L", symmetric="L")
    Ut, Qt, Pt = (_TRANSPOSE[x] for x in (U, Q, P))
    Q1, P1 = Q * U, P * U
    Om1 = _reduce(_transpose(Q1) * Q, [Q])  # = U^T
    r = _is_zero(_reduce(_transpose(Om1) * L - L * Om1 - (U * L - L * Ut), [Q]))
    Mk = Qt * P - Pt * Q
    Mk1 = _transpose(Q1) * P1 - _transpose(P1) * Q1
    r += _is_zero(_reduce(Om1 * Mk * _transpose(Om1) - Mk1, [U, Q]))
    return r


def d12_numeric() -> float:
    """float64: the symmetric algorithm from (Q_0, P_0) and MV-Algorithm 2 from
    (Q_1, M_1 = Q_0^T P_0 - P_0^T Q_0) agree over 2000 steps (n = 4): max |Q_k - Q_k|, and
    M_{k+1}(MV) against Q_k^T P_k - P_k^T Q_k (relative)."""
    from symrb.algebra import random_SO, random_so
    from symrb.discrete import mv_algorithm2, symmetric_flow

    rng = np.random.default_rng(13)
    lam = np.array([0.6, 0.9, 1.3, 1.7])
    Q0 = random_SO(4, seed=rng)
    M0 = random_so(4, seed=rng, scale=0.05)
    P0 = Q0 @ (0.5 * M0)  # Q0^T P0 - P0^T Q0 = M0
    steps = 2000
    Qs, Ps = symmetric_flow(Q0, P0, lam, 1.0, steps)
    Msym = np.swapaxes(Qs, -1, -2) @ Ps - np.swapaxes(Ps, -1, -2) @ Qs
    QB, MB = mv_algorithm2(Qs[1], Msym[0], lam, steps - 1)
    dq = float(np.max(np.abs(QB - Qs[1:])))
    dm = float(np.max(np.abs(MB - Msym[:steps])) / np.max(np.abs(Msym)))
    return max(dq, dm)


@functools.cache
def _d12_mp_runs(steps: int = 12, dps: int = 50) -> tuple[float, float, float]:
    """The three maps in 50-digit arithmetic (n = 3): returns (symmetric vs MV-Algorithm 2 gap,
    float64 error of symrb.symmetric_flow, symmetric vs MV-Algorithm 1 gap).

    The solve of J_D(U) = M is Newton (mpmath.findroot) on the Cayley parameters of U, started
    from the float64 solution; the two algorithms are written here from eqs. discrbopteqns1,
    Ukdef1 and mv1-mv3, independently of symrb.  The float64 error is the largest distance of
    symrb.symmetric_flow's Q_k from the 50-digit one.
    """
    import mpmath as mp

    from symrb.algebra import random_SO, random_so
    from symrb.discrete import symmetric_flow
    from symrb.solvers import solve_moser_veselov

    rng = np.random.default_rng(1212)
    lam = np.array([0.7, 1.1, 1.6])
    Q0 = random_SO(3, seed=rng)
    P0 = Q0 @ (0.5 * random_so(3, seed=rng, scale=0.3))
    with mp.workdps(dps):
        L = mp.diag([mp.mpf(x) for x in lam])
        eye = mp.eye(3)

        def skew3(a: object, b: object, c: object) -> object:
            return mp.matrix([[0, -c, b], [c, 0, -a], [-b, a, 0]])

        def solve_jd(M: object) -> object:
            Uf = solve_moser_veselov(np.array(M.tolist(), dtype=float), lam)
            Af = (Uf - np.eye(3)) @ np.linalg.inv(Uf + np.eye(3))
            x0 = [Af[2, 1], Af[0, 2], Af[1, 0]]

            def F(a: object, b: object, c: object) -> list[object]:
                A = skew3(a, b, c)
                U = mp.inverse(eye - A) * (eye + A)
                R = U * L - L * U.T - M
                return [R[2, 1], R[0, 2], R[1, 0]]

            a, b, c = mp.findroot(F, x0, tol=mp.mpf(10) ** (-dps + 5))
            A = skew3(a, b, c)
            return mp.inverse(eye - A) * (eye + A)

        # Q0 orthogonal to 50 digits (MV-Algorithm 1 reads momenta off Q_{k+1}^T Q_k, so a Q0 that
        # is orthogonal only to rounding would show up as a 1e-16 momentum error)
        Q, R = mp.qr(mp.matrix(Q0.tolist()))
        Q = Q * mp.diag([mp.sign(R[i, i]) for i in range(3)])
        P = mp.matrix(P0.tolist())
        Qsym, Msym = [Q], []
        for _ in range(steps):
            Mk1 = Q.T * P - P.T * Q  # Mdef1: M_{k+1}
            Msym.append(Mk1)
            U = solve_jd(Mk1)
            Q, P = Q * U, P * U
            Qsym.append(Q)
        # MV-Algorithm 2 from (Q_1, M_1)
        Qk, Mk = Qsym[1], Msym[0]
        Om = solve_jd(Mk).T  # mv2: M_k = Om_k^T Lam - Lam Om_k, i.e. J_D(Om_k^T) = M_k
        gap = mp.mpf(0)
        for k in range(1, steps):
            Mk = Om * Mk * Om.T  # mv3
            Om = solve_jd(Mk).T
            Qk = Qk * Om.T  # mv1: Om_{k+1} = Q_{k+1}^T Q_k
            gap = max(gap, mp.mnorm(Qk - Qsym[k + 1], 1))
        # MV-Algorithm 1 from (Q_0, Q_1)
        gap1 = mp.mpf(0)
        Qa, Qb = Qsym[0], Qsym[1]
        for k in range(2, steps + 1):
            Om = Qb.T * Qa  # mv1: Om_{k-1} = Q_{k-1}^T Q_{k-2}
            Mk = Om.T * L - L * Om  # mv2
            Mk = Om * Mk * Om.T  # mv3
            Om = solve_jd(Mk).T  # mv2 for Om_k
            Qa, Qb = Qb, Qb * Om.T  # mv1: Q_k = Q_{k-1} Om_k^T
            gap1 = max(gap1, mp.mnorm(Qb - Qsym[k], 1))
        Qf, _ = symmetric_flow(Q0, P0, lam, 1.0, steps)
        err = max(float(mp.mnorm(mp.matrix(Qf[k].tolist()) - Qsym[k], 1)) for k in range(steps + 1))
        return float(gap), err, float(gap1)


def d12_high_precision_equivalence() -> float:
    """50 digits: the symmetric algorithm and MV-Algorithm 2 give the same Q_k (n = 3, 12 steps)."""
    return _d12_mp_runs()[0]


def d10_high_precision_mv1() -> float:
    """50 digits: MV-Algorithm 1 from (Q_0, Q_1) gives the symmetric algorithm's Q_k (12 steps)."""
    return _d12_mp_runs()[2]


def d12_float64_against_high_precision() -> float:
    """symrb.symmetric_flow (float64) against the 50-digit run: error of Q_k over 12 steps."""
    return _d12_mp_runs()[1]


# ---------------------------------------------------------------------------------------------

_FLOAT_TOL = 1e-9

CLAIMS = [
    Claim(
        id="D7",
        label="mvoptprobm, discrbopteqns, Ukdef, discham, symequation, equ_final_th_2.7",
        title="Discrete symmetric rigid body from optimal control on SO(n)",
        statement=r"Minimising $\sum_{k=0}^{N-1}\operatorname{tr}(\Lambda U_k)$ subject to "
        r"$Q_{k+1}=Q_kU_k$ gives $Q_{k+1}=Q_kU_k$, $P_{k+1}=P_kU_k$ with "
        r"$U_k\Lambda-\Lambda U_k^T=Q_k^TP_k-P_k^TQ_k$: $H=\operatorname{tr}((P_{k+1}^TQ_k-\Lambda)U_k)$; "
        r"critical points of $\operatorname{tr}(AU)$ on $SO(n)$ satisfy $AU=U^TA^T$, which gives "
        r"symequation, then equ_final_th_2.7, and $P\to-P$ gives Ukdef.",
        printed=r"discrbeq: $Q_{r+1}=Q_kU_r$; proof: the Lagrange multiplier $\Sigma=\Sigma^T$ is "
        r"an $N\times N$ matrix.",
        corrected=r"$Q_{r+1}=Q_rU_r$; $\Sigma$ is $n\times n$ (the size of $U^TU-I$).  Everything "
        r"else (symequation, the costate $P_k=P_{k+1}U_k^T$, equ_final_th_2.7, the flip) holds as printed.",
        note="Two typos, both harmless to the result: the dynamics in discrbeq carry a frozen index k "
        "(with it the proof's identity sum tr(Lambda U_k) = sum tr(Q_k Lambda Q_{k+1}^T) fails), and "
        "the multiplier has the size n of the matrices, not the number N of steps.",
        expected="holds after correction",
        section="2.2",
        evidence=(
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "d/de tr(AU(I + e xi)) at 0 = sum_{i<j} xi_ij((AU)_ji - (AU)_ij): zero for all skew "
                "xi iff AU symmetric (n = 3)",
                d7_variation_trace_AU,
            ),
            Evidence(
                Level.FLOAT64,
                "scipy BFGS maxima and minima of tr(AU) on SO(n), n = 3, 4: ||AU - (AU)^T||/||A|| "
                "(optimiser gtol 1e-12)",
                d7_trace_AU_optimisation,
                tol=1e-8,
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "corrected: n x n symmetric Sigma, dV~ = tr((A + Sigma U^T) dU) (n = 3)",
                d7_multiplier_n_by_n,
                form="corrected",
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "printed: N x N Sigma (N = 4 steps, n = 3): tr(Sigma (U^T U - I)) undefined",
                d7_multiplier_N_by_N,
                form="printed",
            ),
            Evidence(
                Level.SYMBOLIC_GENERAL_N,
                "noncommutative: U(AU - U^T A^T)U^T = -(symequation), A = P_{k+1}^T Q_k - Lambda",
                d7_symequation_general_n,
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "dH/dQ_k = P_{k+1} U_k^T and dH/dP_{k+1} = Q_k U_k (n = 3)",
                d7_costate_gradients,
            ),
            Evidence(
                Level.SYMBOLIC_GENERAL_N,
                "noncommutative: P_{k+1} = P_k U_k turns symequation into equ_final_th_2.7; P -> -P gives Ukdef",
                d7_final_and_flip_general_n,
            ),
            Evidence(
                Level.FLOAT64,
                "corrected: Q_{r+1} = Q_r U_r gives sum tr(Lambda U_k) = sum tr(Q_k Lambda Q_{k+1}^T)",
                d7_mv_functional_corrected,
                tol=1e-13,
                form="corrected",
            ),
            Evidence(
                Level.FLOAT64,
                "printed: Q_{r+1} = Q_k U_r (k = 0): the same identity fails",
                d7_mv_functional_printed,
                tol=1e-13,
                form="printed",
            ),
        ),
    ),
    Claim(
        id="D8",
        label="discrbopteqns1, Ukdef1",
        title="Symmetric representation of the discrete rigid body; J_D and its derivative J",
        statement=r"$Q_{k+1}=Q_kU_k$, $P_{k+1}=P_kU_k$, $J_D(U_k)=Q_k^TP_k-P_k^TQ_k$ with "
        r"$J_D(U)=U\Lambda-\Lambda U^T\in\mathfrak{so}(n)$; $dJ_D(I)\cdot\Omega=\Omega\Lambda+\Lambda\Omega=J(\Omega)$, "
        r"so $J_D$ is a diffeomorphism from a neighbourhood of $I$ onto a neighbourhood of $0$.",
        expected="holds",
        section="2.2",
        evidence=(
            Evidence(
                Level.SYMBOLIC_FIXED_N, "J_D(U)^T = -J_D(U) for general U (n = 4)", d8_jd_skew
            ),
            Evidence(
                Level.SYMBOLIC_GENERAL_N,
                "noncommutative: d/de J_D(exp(e Om)) at 0 = Om L + L Om",
                d8_derivative_general_n,
            ),
            Evidence(
                Level.SYMBOLIC_GENERAL_N,
                "noncommutative: the algorithm transports Q^T P - P^T Q to U^T (Q^T P - P^T Q) U",
                d8_symmetric_transport_general_n,
            ),
            Evidence(
                Level.FLOAT64,
                "singular values of J on so(6) are lam_i + lam_j; J_D(solve(M)) = M, solve(J_D(U)) = U near I",
                d8_local_diffeomorphism,
                tol=1e-12,
            ),
        ),
    ),
    Claim(
        id="D9",
        label="mvoptprobm1, discrboptm, discrbopteqnsm, Ukdef2, dischamm",
        title="Learning version: several samples and a terminal cost",
        statement=r"Minimising $\sum_k\operatorname{tr}(\Lambda U_k)+\sum_a\phi(Q_N^a)$ subject to "
        r"$Q^a_{k+1}=Q^a_kU_k$ gives $P^a_{k+1}=P^a_kU_k$, "
        r"$U_k\Lambda-\Lambda U_k^T=\sum_{a=1}^M((Q^a_k)^TP^a_k-(P^a_k)^TQ^a_k)$, "
        r"$P^a_N=\partial\phi/\partial Q^a_N$.",
        printed=r"discrboptm: $\hat V=\sum_{k=1}^{N-1}\operatorname{tr}(\Lambda U_k)+\sum_a\phi(\overline Q^a_N)$; "
        r"Ukdef2 typeset $\sum_{^Ma=1}$; the proof applies Proposition gendiscpropm, whose endpoint "
        r"condition m8 reads $p^a_N=+\partial\phi/\partial x^a_N$ for $H=\langle p,f\rangle-g$.",
        corrected=r"$\hat V=\sum_{k=0}^{N-1}\operatorname{tr}(\Lambda U_k)+\sum_a\phi(Q^a_N)$ (the "
        r"free end point $Q_N^a$, $\phi$ a function of a matrix), $\sum_{a=1}^M$; for "
        r"$H=\langle P,QU\rangle-\operatorname{tr}(\Lambda U)$ the costate ends at "
        r"$P^a_N=-\partial\phi/\partial Q^a_N$, and after the flip $P\to-P$ used for Ukdef this becomes "
        r"the theorem's $P^a_N=+\partial\phi/\partial Q^a_N$: the theorem's equations hold as stated.",
        note="With the sum starting at k = 1 the first control U_0 carries no running cost and Ukdef2 "
        "fails at k = 0.  The endpoint sign of m8 is wrong for the Hamiltonian's sign (the maximum "
        "principle gives p_N = -dphi/dx_N there), but the theorem applies the flip P -> -P, so its "
        "final statement P_N = +dphi/dQ_N is right: two sign slips cancel.",
        expected="holds after correction",
        section="2.2",
        evidence=(
            Evidence(
                Level.FLOAT64,
                "corrected: k from 0, P_N = +dphi/dQ_N: gradient of the cost in U_k = 1/2 U^T(J_D(U_k) - "
                "sum(Q^T P - P^T Q))U (so zero iff Ukdef2), every k, central differences",
                d9_corrected,
                tol=1e-8,
                form="corrected",
            ),
            Evidence(
                Level.FLOAT64,
                "printed: sum from k = 1: the same gradient identity fails at k = 0",
                d9_printed_index,
                tol=1e-8,
                form="printed",
            ),
            Evidence(
                Level.FLOAT64,
                "corrected: before the flip, P_N = -dphi/dQ_N and equ_final_th_2.7's sign match the gradient",
                d9_unflipped_endpoint_corrected,
                tol=1e-8,
                form="corrected",
            ),
            Evidence(
                Level.FLOAT64,
                "printed: before the flip with m8's P_N = +dphi/dQ_N the gradient does not match",
                d9_unflipped_endpoint_printed,
                tol=1e-8,
                form="printed",
            ),
        ),
    ),
    Claim(
        id="D10",
        label="mv1, mv2, mv3",
        title="Moser-Veselov equations and the two MV algorithms",
        statement=r"$\Omega_k=Q_k^TQ_{k-1}$, $M_k=\Omega_k^T\Lambda-\Lambda\Omega_k$, "
        r"$M_{k+1}=\Omega_kM_k\Omega_k^T$; MV-Algorithm 1 $(Q_k,Q_{k+1})\mapsto(Q_{k+1},Q_{k+2})$ and "
        r"MV-Algorithm 2 $(Q_k,M_k)\mapsto(Q_{k+1},M_{k+1})$ define the same dynamics; mv2 is solvable "
        r"for $\Omega_k$ near $M_k=0$ (up to a fold).",
        expected="holds",
        section="2.3",
        evidence=(
            Evidence(
                Level.SYMBOLIC_GENERAL_N,
                "noncommutative: for orthogonal Om, Om (Om^T L - L Om) Om^T = L Om^T - Om L",
                d10_mv3_is_conjugation_general_n,
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "n = 2: J_D(R(theta)) = (lam1 + lam2) sin(theta) J: solvable iff |M_21| <= lam1 + lam2",
                d10_solvability_n2,
            ),
            Evidence(
                Level.FLOAT64,
                "symrb.fold_scale for n = 2 equals (lam1 + lam2)/|M_21|",
                d10_fold_n2,
                tol=1e-12,
            ),
            Evidence(
                Level.FLOAT64,
                "MV-Algorithm 1 and 2 give the same Q_k over 1000 steps (n = 4): gap / (gap caused "
                "by moving Q_1 one rounding unit)",
                d10_algorithms_agree,
                tol=10.0,
            ),
            Evidence(
                Level.FLOAT64,
                "spectrum of M_k conserved along MV-Algorithm 2 (1000 steps, n = 4)",
                d10_spectrum,
                tol=1e-12,
            ),
            Evidence(
                Level.MPMATH,
                "50 digits: MV-Algorithm 1 from (Q_0, Q_1) reproduces the symmetric algorithm's Q_k "
                "(n = 3, 12 steps; written independently of symrb)",
                d10_high_precision_mv1,
                tol=1e-40,
            ),
        ),
    ),
    Claim(
        id="D11",
        label="mvl",
        title="Discrete variational principle for the Moser-Veselov equations",
        statement=r"Stationary points of $\hat S=\sum_k\operatorname{tr}(Q_k\Lambda Q_{k+1}^T)$ on "
        r"sequences in $SO(n)$ satisfy mv1-mv3.",
        expected="holds",
        section="2.3",
        evidence=(
            Evidence(
                Level.SYMBOLIC_GENERAL_N,
                "noncommutative: Q_k -> Q_k(1 + e xi) gives tr(B xi) with B - B^T = Om_k M_k Om_k^T - M_{k+1}",
                d11_euler_lagrange_general_n,
            ),
            Evidence(
                Level.FLOAT64,
                "first variations of S vanish along an MV-Algorithm-1 sequence (relative to a perturbed one)",
                d11_stationary_numeric,
                tol=1e-12,
            ),
        ),
    ),
    Claim(
        id="D12",
        label="Mdef1",
        title="Symmetric representation gives a Moser-Veselov solution",
        statement=r"If $(Q_k,P_k)$ solves the symmetric discrete equations, then $(Q_{k+1},M_{k+1})$ "
        r"with $M_{k+1}=Q_k^TP_k-P_k^TQ_k$ solves mv1-mv3 (with $\Omega_{k+1}=U_k^T$).",
        expected="holds",
        section="2.3",
        evidence=(
            Evidence(
                Level.SYMBOLIC_GENERAL_N,
                "noncommutative: mv2 with Om_{k+1} = Q_{k+1}^T Q_k is Ukdef1, mv3 is Mdef1 at k + 1",
                d12_general_n,
            ),
            Evidence(
                Level.FLOAT64,
                "symmetric algorithm and MV-Algorithm 2 agree over 2000 steps (n = 4)",
                d12_numeric,
                tol=_FLOAT_TOL,
            ),
            Evidence(
                Level.MPMATH,
                "50 digits: symmetric algorithm and MV-Algorithm 2 give the same Q_k over 12 steps "
                "(n = 3; both written independently of symrb, J_D solved by findroot)",
                d12_high_precision_equivalence,
                tol=1e-40,
            ),
            Evidence(
                Level.MPMATH,
                "symrb.symmetric_flow in float64 against that 50-digit run: max |Q_k error| (n = 3)",
                d12_float64_against_high_precision,
                tol=1e-13,
            ),
        ),
    ),
]


# ---------------------------------------------------------------------------------------------
# code emission


def emit() -> tuple[str, list[Kernel]]:
    U = sp.MatrixSymbol("U", n, n)
    Q = sp.MatrixSymbol("Q", n, n)
    P = sp.MatrixSymbol("P", n, n)
    Q1 = sp.MatrixSymbol("Q1", n, n)
    M = sp.MatrixSymbol("M", n, n)
    Om = sp.MatrixSymbol("Omega", n, n)
    Lam = aux("Lam")
    arg_lam = Arg("lam", "(..., n)", "diagonal of Lambda, positive")
    kernels = [
        Kernel(
            name="jd",
            args=[
                Arg("U", "(..., n, n)", "a matrix, in SO(n) for the discrete rigid body"),
                arg_lam,
            ],
            outputs={"JD": U * Lam - Lam * U.T},
            doc="The discrete inertia operator J_D(U) = U Lambda - Lambda U^T (paper, eq. Ukdef1).",
        ),
        Kernel(
            name="sym_momentum",
            args=[
                Arg("Q", "(..., n, n)", "attitude"),
                Arg("P", "(..., n, n)", "costate of the symmetric representation"),
            ],
            outputs={"M": Q.T * P - P.T * Q},
            doc="The momentum of the symmetric representation, Q^T P - P^T Q (eqs. Ukdef1, Mdef1).",
        ),
        Kernel(
            name="mv_momentum",
            args=[Arg("Omega", "(..., n, n)", "discrete body angular velocity, in SO(n)"), arg_lam],
            outputs={"M": Om.T * Lam - Lam * Om},
            doc="Moser-Veselov eq. mv2: M_k = Omega_k^T Lambda - Lambda Omega_k.",
        ),
        Kernel(
            name="mv_transport",
            args=[
                Arg("Omega", "(..., n, n)", "discrete body angular velocity, in SO(n)"),
                Arg("M", "(..., n, n)", "discrete body angular momentum, skew"),
            ],
            outputs={"M_next": Om * M * Om.T},
            doc="Moser-Veselov eq. mv3: M_{k+1} = Omega_k M_k Omega_k^T.",
        ),
        Kernel(
            name="mv_action_term",
            args=[
                Arg("Q", "(..., n, n)", "Q_k"),
                Arg("Q1", "(..., n, n)", "Q_{k+1}"),
                arg_lam,
            ],
            outputs={"S": sp.Trace(Q * Lam * Q1.T)},
            doc="One term of the Moser-Veselov action (eq. mvl): trace(Q_k Lambda Q_{k+1}^T).",
        ),
    ]
    return "discrete_rigid_body", kernels
