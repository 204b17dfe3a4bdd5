"""S14 (Section 3.4, eq. ``opb``): Brockett's potential, the extremal equations and the Toda
lattice.

For Brockett's potential V(x) = -1/2 ||[x, N]||^2 the gradient is V_x = [N, [N, x]], so the
extremals of S13 solve xdot = [x, [p, x]], pdot = [p, [p, x]] - [N, [N, x]].  For x = iL with L
real symmetric tridiagonal and N = iD, D = diag(1, ..., k), the double bracket flow
xdot = [x, [x, N]] keeps L tridiagonal and is Flaschka's Toda lattice.

Emitted to ``symrb/_generated/adjoint_orbits.py``: ``brockett_potential``, ``orbit_extremal_rhs``
and ``double_bracket_rhs``.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from derivations import reference as ref
from derivations.claims.section3._display import minus
from derivations.claims.section3._orbits import (
    ARG_N,
    ARG_P,
    ARG_X,
    PDOT,
    XDOT,
    N,
    V,
    V_x,
    brockett,
    d,
    directional,
    np_comm,
    np_norm2,
    p,
    pair_poly,
    plain,
    so_basis,
    t,
    trace_poly,
    x,
)
from derivations.claims.section3.s13_adjoint_orbits import ORBIT_HAMILTONIAN, PDOT_EQ, XDOT_EQ
from derivations.registry import Level, claim
from derivations.symbolic import Bracket, Pair, Words, eq, explicit, residual, trace_residual
from derivations.vocabulary import Kernel, matrix

S14 = claim(
    "S14",
    label="opb",
    title="Brockett's potential: extremal equations and the Toda lattice",
    statement="For Brockett's potential [[V]] (the proof uses [[V_rewritten]]) the gradient is "
    "[[V_x]], so the extremals of S13 solve [[opb]]. Toda link (what we check): for $x$ the "
    "product of $i$ and a real symmetric tridiagonal $L$ (diagonal $a_i$, off-diagonal $b_i$) in "
    "su(k), and $N$ the product of $i$ and $D$, $D$ the diagonal matrix of $1,\\dots,k$, the double "
    "bracket flow [[double_bracket]] keeps $L$ tridiagonal and is Flaschka's Toda lattice "
    "[[toda_a]], [[toda_b]] (with $b_0$ and $b_k$ zero), that is [[lax]] with [[toda_B]], the "
    "strictly upper minus the strictly lower part of $L$.",
    expected="holds",
    section="3.4",
    where="Section 3.4, the first corollary (Brockett's potential $V(x) = -\\tfrac12\\|[x, "
    "n]\\|^2$) and the paragraph after it (the link with the Toda lattice)",
    note="Holds as printed (the first line of the printed equations lacks a closing bracket, "
    "$[x,[p,x]$). The sign of $V_x$ is decided by the checks: $V_x = +[N,[N,x]]$ (the opposite "
    "sign fails, see `tests/test_orbits.py`). On real symmetric $L$ the flow $\\dot L = "
    "[L,[L,D]]$ is the Toda flow run backwards in time; the compact form $x = iL$ reverses it.",
)
# the potential is built by _orbits.brockett, which S13's optimal Hamiltonian kernel also reads
BROCKETT = S14.formula("V", eq(V(x), brockett(x)))
BROCKETT_REWRITTEN = S14.formula("V_rewritten", eq(V(x), Pair(x, Bracket(N, Bracket(N, x))) / 2))
BROCKETT_GRADIENT = S14.formula("V_x", eq(V_x, Bracket(N, Bracket(N, x))))
OPB = S14.formula(
    "opb",
    (
        eq(XDOT, Bracket(x, Bracket(p, x))),
        eq(PDOT, minus(Bracket(p, Bracket(p, x)), Bracket(N, Bracket(N, x)))),
    ),
)
DOUBLE_BRACKET = S14.formula("double_bracket", eq(XDOT, Bracket(x, Bracket(x, N))))


BROCKETT_POTENTIAL = Kernel(
    name="brockett_potential",
    target="adjoint_orbits",
    args=[ARG_X, ARG_N],
    outputs={"V": plain(BROCKETT.rhs)},
    doc="Brockett's potential V(x) = -1/2 ||[x, N]||^2.\n\n||a||^2 = <a, a> = -1/2 trace(a a).",
    claims=("S14",),
)
ORBIT_EXTREMAL_RHS = Kernel(
    name="orbit_extremal_rhs",
    target="adjoint_orbits",
    args=[ARG_X, ARG_P, ARG_N],
    outputs={"xdot": OPB[0].rhs.doit(), "pdot": OPB[1].rhs.doit()},
    doc="Extremal equations with Brockett's potential (paper, Section 3.4).\n\n"
    "xdot = [x, [p, x]], pdot = [p, [p, x]] - [N, [N, x]].",
    claims=("S14", "S15"),
)
DOUBLE_BRACKET_RHS = Kernel(
    name="double_bracket_rhs",
    target="adjoint_orbits",
    args=[ARG_X, ARG_N],
    outputs={"xdot": DOUBLE_BRACKET.rhs.doit()},
    doc="Double bracket vector field xdot = [x, [x, N]].",
    claims=("S14", "S15"),
)


@S14.check(Level.SYMBOLIC_GENERAL_N)
def s14_potential() -> sp.Expr:
    """The displayed V, its displayed rewriting 1/2 <x, [N, [N, x]]> and the emitted potential
    are the same trace polynomial (every n)."""
    w = Words()
    v = trace_poly(BROCKETT.rhs, w)
    r = trace_residual(v - trace_poly(BROCKETT_REWRITTEN.rhs, w))
    return r + trace_residual(v - trace_poly(BROCKETT_POTENTIAL["V"], w))


@S14.check(Level.SYMBOLIC_GENERAL_N)
def s14_gradient() -> sp.Expr:
    """The derivative of the emitted potential along every d is <V_x, d> with the displayed
    V_x = [N, [N, x]], and S13's displayed pdot with this V_x is the displayed pdot of eq. opb
    (trace words, every n)."""
    w = Words()
    dV = directional(BROCKETT_POTENTIAL["V"], {x: d}, w)
    r = trace_residual(dV - pair_poly(BROCKETT_GRADIENT.rhs, d, w))
    s13_pdot = PDOT_EQ.rhs.xreplace({V_x: BROCKETT_GRADIENT.rhs})
    r += trace_residual(pair_poly(s13_pdot - OPB[1].rhs, d, w))
    return r + trace_residual(pair_poly(XDOT_EQ.rhs - OPB[0].rhs, d, w))


@S14.check(Level.SYMBOLIC_GENERAL_N)
def s14_emitted_field_is_hamiltonian() -> sp.Expr:
    """The emitted extremal field is Hamilton's equations of the emitted H*: dH*/dp [d] equals
    <xdot, d> and -dH*/dx [d] equals <pdot, d> for every d, and it is the displayed eq. opb
    (trace words, every n)."""
    w = Words()
    H = ORBIT_HAMILTONIAN["H"]
    xdot, pdot = ORBIT_EXTREMAL_RHS["xdot"], ORBIT_EXTREMAL_RHS["pdot"]
    r = trace_residual(directional(H, {p: d}, w) - pair_poly(xdot, d, w))
    r += trace_residual(-directional(H, {x: d}, w) - pair_poly(pdot, d, w))
    r += trace_residual(pair_poly(xdot - OPB[0].rhs, d, w))
    return r + trace_residual(pair_poly(pdot - OPB[1].rhs, d, w))


# --- the Toda lattice --------------------------------------------------------------------------

_ia, _ib = sp.IndexedBase("a"), sp.IndexedBase("b")
_i = sp.Symbol("i", integer=True)
TODA_A = S14.formula("toda_a", eq(sp.Derivative(_ia[_i], t), 2 * (_ib[_i] ** 2 - _ib[_i - 1] ** 2)))
TODA_B = S14.formula("toda_b", eq(sp.Derivative(_ib[_i], t), _ib[_i] * (_ia[_i + 1] - _ia[_i])))
_L, _B, _D = matrix("L"), matrix("B"), matrix("D")
LAX = S14.formula("lax", eq(matrix(r"\dot{L}"), Bracket(_B, _L)))
TODA_BMAT = S14.formula("toda_B", eq(_B, Bracket(_L, _D)))


def toda_residuals(k: int) -> dict[str, sp.Expr]:
    """x = iL, N = iD in su(k), L symbolic real symmetric tridiagonal: the emitted double bracket
    field gives Ldot = x-dot / i; residuals of (tridiagonal) its entries off the band, (toda) its
    band minus the displayed Toda equations, (lax) Ldot minus the displayed [B, L] with the
    displayed B = [L, D], and (B) B minus the strictly upper minus the strictly lower part of L."""
    a = sp.symbols(f"a1:{k + 1}", real=True)
    b = sp.symbols(f"b1:{k}", real=True)
    L = sp.zeros(k, k)
    for i in range(k):
        L[i, i] = a[i]
    for i in range(k - 1):
        L[i, i + 1] = L[i + 1, i] = b[i]
    D = sp.diag(*range(1, k + 1))
    Ldot = sp.expand(explicit(DOUBLE_BRACKET_RHS["xdot"], {"x": sp.I * L, "N": sp.I * D}) / sp.I)
    off = [Ldot[i, j] for i in range(k) for j in range(k) if abs(i - j) > 1]
    values = {_ia[i + 1]: a[i] for i in range(k)} | {_ib[i + 1]: b[i] for i in range(k - 1)}
    values |= {_ib[0]: 0, _ib[k]: 0}
    toda = [Ldot[i - 1, i - 1] - TODA_A.rhs.subs(_i, i).xreplace(values) for i in range(1, k + 1)]
    toda += [Ldot[i - 1, i] - TODA_B.rhs.subs(_i, i).xreplace(values) for i in range(1, k)]
    B = explicit(TODA_BMAT.rhs, {"L": L, "D": D})
    parts = sp.Matrix(k, k, lambda i, j: sp.sign(j - i) * L[i, j])
    return {
        "tridiagonal": residual(sp.Matrix(off)) if off else sp.Integer(0),
        "toda": residual(sp.Matrix(toda)),
        "lax": residual(Ldot - explicit(LAX.rhs, {"B": B, "L": L})),
        "B": residual(B - parts),
    }


@S14.check(Level.SYMBOLIC_FIXED_N)
def s14_toda() -> sp.Expr:
    """x = iL, N = iD, L symbolic real symmetric tridiagonal, k = 3, 4, 5: the emitted double
    bracket field keeps L tridiagonal and equals the displayed Toda equations, the displayed
    [B, L] with the displayed B, and B is the strictly upper minus the strictly lower part of L."""
    return sum((sum(toda_residuals(k).values()) for k in (3, 4, 5)), sp.Integer(0))


@S14.check(Level.FLOAT64, tol=1e-14)
def s14_symrb_potential_and_double_bracket() -> float:
    """symrb.orbits.brockett_potential against -1/2 ||[x, N]||^2 in NumPy (n = 3..6) and
    symrb.orbits.double_bracket_rhs against hat(xi x (xi x nu)) with numpy.cross (n = 3) and NumPy
    commutators (n = 4..6), 20 random skew pairs each: max difference relative to ||x||^2 ||N||^2
    (potential) and ||x||^2 ||N|| (field)."""
    import symrb

    rng = np.random.default_rng(141)
    worst = []
    for k in range(3, 7):
        x_, N_ = (np.stack([ref.random_skew(k, rng) for _ in range(20)]) for _ in range(2))
        nx, nN = np.sqrt(np_norm2(x_)), np.sqrt(np_norm2(N_))
        want_V = -0.5 * np_norm2(np_comm(x_, N_))
        worst.append(
            np.max(np.abs(symrb.orbits.brockett_potential(x_, N_) - want_V) / (nx * nN) ** 2)
        )
        if k == 3:
            xi, nu = ref.vee(x_), ref.vee(N_)
            want = ref.hat(np.cross(xi, np.cross(xi, nu)))
        else:
            want = np_comm(x_, np_comm(x_, N_))
        err = np.abs(symrb.orbits.double_bracket_rhs(x_, N_) - want).max(axis=(-2, -1))
        worst.append(np.max(err / (nx**2 * nN)))
    return float(np.max(worst))


def _complex_step_field(
    x_: np.ndarray, p_: np.ndarray, N_: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Hamilton's equations of the NumPy H* = 1/2 ||[p, x]||^2 - 1/2 ||[x, N]||^2 by complex-step
    derivatives along the orthonormal basis E_ij of so(k): xdot = sum_E dH/dp[E] E,
    pdot = -sum_E dH/dx[E] E (exact to rounding: no cancellation)."""

    def H(xx: np.ndarray, pp: np.ndarray) -> np.ndarray:
        return 0.5 * np_norm2(np_comm(pp, xx)) - 0.5 * np_norm2(np_comm(xx, N_))

    h = 1e-30
    xdot, pdot = np.zeros_like(x_), np.zeros_like(p_)
    for E in (np.array(e, dtype=float) for e in so_basis(x_.shape[-1])):
        xdot += np.imag(H(x_, p_ + 1j * h * E))[..., None, None] / h * E
        pdot -= np.imag(H(x_ + 1j * h * E, p_))[..., None, None] / h * E
    return xdot, pdot


@S14.check(Level.FLOAT64, tol=1e-13)
def s14_symrb_extremal_field() -> float:
    """symrb.orbits.orbit_extremal_rhs against Hamilton's equations of the independent NumPy
    H* = 1/2 ||[p, x]||^2 - 1/2 ||[x, N]||^2, differentiated by the complex step along an
    orthonormal basis of so(n), n = 3..5, 20 random skew (x, p, N) each: max difference relative
    to the largest entry of the reference field."""
    import symrb

    rng = np.random.default_rng(142)
    worst = []
    for k in range(3, 6):
        x_, p_, N_ = (np.stack([ref.random_skew(k, rng) for _ in range(20)]) for _ in range(3))
        want = _complex_step_field(x_, p_, N_)
        got = symrb.orbits.orbit_extremal_rhs(x_, p_, N_)
        for g, w_ in zip(got, want, strict=True):
            worst.append(np.max(np.abs(g - w_)) / np.max(np.abs(w_)))
    return float(np.max(worst))


@S14.check(Level.FLOAT64, tol=1e-8)
def s14_toda_flow() -> float:
    """The emitted double bracket field on x = iL, N = iD, integrated as Ldot = -[L, [L, D]]
    (DOP853, rtol 1e-11, k = 5, t in [0, 3]), against Flaschka's Toda equations integrated on
    (a, b): max entry difference.  It calls the generated kernel symrb._generated.adjoint_orbits
    directly because the public symrb.orbits.double_bracket_rhs accepts skew x only (L is symmetric)."""
    from scipy.integrate import solve_ivp

    from symrb._generated.adjoint_orbits import double_bracket_rhs

    k = 5
    rng = np.random.default_rng(5)
    a0, b0 = rng.standard_normal(k), rng.uniform(0.3, 1.0, k - 1)
    L0 = np.diag(a0) + np.diag(b0, 1) + np.diag(b0, -1)
    D = np.diag(np.arange(1.0, k + 1))
    ts = np.linspace(0, 3, 31)
    opts = {"t_eval": ts, "method": "DOP853", "rtol": 1e-11, "atol": 1e-12}
    s1 = solve_ivp(
        lambda _t, y: -double_bracket_rhs(y.reshape(k, k), D).ravel(), (0, 3), L0.ravel(), **opts
    )

    def toda(_t: float, y: np.ndarray) -> np.ndarray:
        a, b = y[:k], y[k:]
        bb = np.concatenate([[0.0], b, [0.0]])
        return np.concatenate([2 * (bb[1:] ** 2 - bb[:-1] ** 2), b * (a[1:] - a[:-1])])

    s2 = solve_ivp(toda, (0, 3), np.concatenate([a0, b0]), **opts)
    Ls = s1.y.T.reshape(-1, k, k)
    Lt = np.zeros_like(Ls)
    idx = np.arange(k)
    Lt[:, idx, idx] = s2.y[:k].T
    Lt[:, idx[:-1], idx[1:]] = Lt[:, idx[1:], idx[:-1]] = s2.y[k:].T
    return float(np.max(np.abs(Ls - Lt)))


# the paper's sentences
S14.sentence(
    r"A particularly interesting special case of this problem is that of Brockett [1994] where we "
    r"have",
    kind="prose",
    reason="introduces the corollary, with a citation",
)
S14.sentence(
    r"The equations of the maximum principle for the variational problem (var) subject to "
    r"equations (orb) with $V(x)=-\tfrac{1}{2} \|[x,n]\|^2$ are $$\begin{aligned} \dot x &= "
    r"[x,[p,x] \\ \dot p &= [p,[p,x]]-[n,[n,x]]\,. \end{aligned}$$",
    s14_potential,
    s14_gradient,
    s14_emitted_field_is_hamiltonian,
    s14_symrb_potential_and_double_bracket,
    s14_symrb_extremal_field,
)
S14.sentence(
    r"The proof of the corollary follows immediately, setting $V(x)=\tfrac{1}{2} \left\langle "
    r"x,[n,[n,x]]\right\rangle$.",
    s14_potential,
    s14_gradient,
)
S14.sentence(
    r"Note that with this functional the equations lie naturally on an adjoint orbit.",
)
S14.sentence(
    r"In addition, these equations are interesting in that the optimal flow may be related to the "
    r"integrable Toda lattice equations (see [Bloch1990], [BlBrRa1992] and Brockett [1994].)",
    s14_toda,
    s14_toda_flow,
)
