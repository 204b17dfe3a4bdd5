"""S13 (Section 3.4, eqs. ``orb``, ``var``, ``op``): the maximum principle on adjoint orbits.

For the control system xdot = [x, u] on an adjoint orbit and the cost int 1/2 ||u||^2 - V(x) dt,
with one bilinear form (the pairing, or the negative Killing form) for the pairing, the norm and the
gradient V_x, the Hamiltonian H = <p, [x, u]> - 1/2 ||u||^2 + V(x) is maximised at u* = [p, x],
H* = -1/2 <x, [p, [p, x]]> + V(x), and the extremals solve xdot = [x, [p, x]],
pdot = [p, [p, x]] - V_x.  How the checks work (trace words for every n, coordinates for so(3)
and su(2), float64): see :mod:`derivations.claims.section3._orbits`.

Emitted to ``symrb/_generated/adjoint_orbits.py``: ``optimal_control`` and ``orbit_hamiltonian``
(H* with Brockett's potential of S14).
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Sequence
from typing import Any

import numpy as np
import sympy as sp

from derivations import reference as ref
from derivations.claims.section3._display import _Norm, minus
from derivations.claims.section3._orbits import (
    ARG_N,
    ARG_P,
    ARG_X,
    EPS,
    PDOT,
    XDOT,
    V,
    V_x,
    brockett,
    d,
    directional,
    linear_potential,
    np_comm,
    np_norm2,
    p,
    pair_poly,
    plain,
    so_basis,
    t,
    t_f,
    trace_poly,
    u,
    x,
)
from derivations.registry import Level, claim
from derivations.symbolic import (
    Bracket,
    Pair,
    Words,
    eq,
    explicit,
    general_matrix,
    residual,
    trace_residual,
)
from derivations.vocabulary import Kernel, matrix, n

S13 = claim(
    "S13",
    label="orb, var, op",
    title="Maximum principle on adjoint orbits",
    statement="For the control system [[orb]] on an adjoint orbit and the cost [[cost]], with the "
    "pairing and the norm of the negative Killing form ([[killing_so]] on so(n), [[killing_su]] on "
    "su(n)) and $V_x$ the gradient of $V$, the Hamiltonian [[H]] has [[dHdu]] for every $d$, so "
    "[[ustar]] and [[Hstar]], and the extremals solve [[xdot]], [[pdot]].",
    expected="holds",
    section="3.4",
    where="Section 3.4 (Optimality on adjoint orbits and learning), the control system $\\dot x = "
    "[x, u]$, the functional $\\eta(x, u)$ and the theorem on the equations of the maximum "
    "principle, with its proof ($u^* = [p, x]$ and $H^*$)",
    note="Holds as printed provided one bilinear form $B$ is used throughout (pairing, norm and "
    "gradient $V_x$): the checks for general $n$ use only cyclicity of the trace, so they hold "
    "for $B = -c\\operatorname{tr}$ with any $c$, in particular for the pairing "
    "$-\\tfrac12\\operatorname{tr}$ on $\\mathfrak{so}(n)$ and for the negative Killing form, "
    "which is $(n-2)\\operatorname{tr}$ on $\\mathfrak{so}(n)$ and $2n\\operatorname{tr}$ on "
    "$\\mathfrak{su}(n)$. Mixing forms rescales the control: on $\\mathfrak{su}(n)$ with "
    "$\\langle p, \\cdot\\rangle = -\\tfrac12\\operatorname{tr}$ but $\\|u\\|^2 = -\\kappa(u, "
    "u)$, $u^* = [p, x]/(4n)$ ($1/8$ on $\\mathfrak{su}(2)$; see `tests/test_orbits.py`).",
)
_a, _b = matrix("a"), matrix("b")
_kappa = sp.Function("kappa")
KILLING_SO = S13.formula("killing_so", eq(_kappa(_a, _b), (n - 2) * sp.Trace(_a * _b)))
KILLING_SU = S13.formula("killing_su", eq(_kappa(_a, _b), 2 * n * sp.Trace(_a * _b)))
ORB = S13.formula("orb", eq(XDOT, Bracket(x, u)))
COST = S13.formula(
    "cost", eq(sp.Function("eta")(x, u), sp.Integral(_Norm(u) ** 2 / 2 - V(x), (t, 0, t_f)))
)
HAMILTONIAN = S13.formula(
    "H", eq(sp.Function("H")(x, p, u), Pair(p, ORB.rhs) - _Norm(u) ** 2 / 2 + V(x))
)
DHDU = S13.formula(
    "dHdu", eq(Pair(matrix(r"\partial H/\partial u"), d), -Pair(Bracket(x, p), d) - Pair(u, d))
)
USTAR = S13.formula("ustar", eq(matrix("u^*"), Bracket(p, x)))
HSTAR = S13.formula(
    "Hstar", eq(sp.Function("H^*")(x, p), -Pair(x, Bracket(p, Bracket(p, x))) / 2 + V(x))
)
XDOT_EQ = S13.formula("xdot", eq(XDOT, Bracket(x, Bracket(p, x))))
PDOT_EQ = S13.formula("pdot", eq(PDOT, minus(Bracket(p, Bracket(p, x)), V_x)))

OPTIMAL_CONTROL = Kernel(
    name="optimal_control",
    target="adjoint_orbits",
    args=[ARG_X, ARG_P],
    outputs={"u": USTAR.rhs.doit()},
    doc="The maximiser of H in u: u* = [p, x].\n\n"
    "For samples sharing one control, sum it over the samples: u* = sum_b [p^b, x^b].",
    claims=("S13", "S15"),
)


ORBIT_HAMILTONIAN = Kernel(
    name="orbit_hamiltonian",
    target="adjoint_orbits",
    args=[ARG_X, ARG_P, ARG_N],
    outputs={"H": plain(HSTAR.rhs, brockett)},
    doc="Optimal Hamiltonian H* = -1/2 <x, [p, [p, x]]> + V(x) with Brockett's potential.\n\n"
    "V(x) = -1/2 ||[x, N]||^2, <a, b> = -1/2 trace(a b); H* = 1/2 ||[p, x]||^2 + V(x).",
    claims=("S13", "S14"),
)


@S13.check(Level.SYMBOLIC_GENERAL_N)
def s13_hamiltonian_convention() -> sp.Expr:
    r"""The displayed $H$ is $\langle p, f\rangle - L$ for $f$ the right side of the displayed
    dynamics and $L$ the integrand of the displayed cost (the convention under which the maximum
    principle maximises $H$; trace words, every $n$)."""
    w = Words()
    (integral,) = COST.rhs.atoms(sp.Integral)
    convention = Pair(p, ORB.rhs) - integral.function
    return trace_residual(trace_poly(HAMILTONIAN.rhs - convention, w, linear_potential))


def stationarity(control: sp.MatrixExpr) -> sp.Expr:
    """d/de H(x, p, control + e d) at e = 0 for the displayed H, as a trace polynomial in the
    letters x, p, d (zero for every d exactly when ``control`` is a critical point of H)."""
    moved = HAMILTONIAN.rhs.xreplace({u: control + EPS * d})
    return sp.diff(trace_poly(moved, Words(), linear_potential), EPS).subs(EPS, 0)


@S13.check(Level.SYMBOLIC_GENERAL_N)
def s13_stationary_control() -> sp.Expr:
    r"""The derivative of the displayed $H$ along a direction $d$ of $u$ is the displayed $\partial
    H/\partial u$, and it vanishes at the emitted optimal control for every $d$ (trace words, every
    $n$)."""
    w = Words()
    dH = directional(HAMILTONIAN.rhs, {u: d}, w, linear_potential)
    r = trace_residual(dH - trace_poly(DHDU.rhs, w))
    return r + trace_residual(stationarity(OPTIMAL_CONTROL["u"]))


@S13.check(Level.SYMBOLIC_GENERAL_N)
def s13_optimal_hamiltonian() -> sp.Expr:
    """$H$ at the emitted $u^*$ minus the displayed $H^*$ (for any $V$) has no trace words left, and
    the emitted $H^*$ kernel equals the displayed $H^*$ with Brockett's potential of S14 (every
    $n$)."""
    w = Words()
    at_ustar = HAMILTONIAN.rhs.xreplace({u: OPTIMAL_CONTROL["u"]})
    r = trace_residual(trace_poly(at_ustar - HSTAR.rhs, w, linear_potential))
    emitted = trace_poly(ORBIT_HAMILTONIAN["H"], w)
    displayed = trace_poly(HSTAR.rhs, w, brockett)
    return r + trace_residual(emitted - displayed)


@S13.check(Level.SYMBOLIC_GENERAL_N)
def s13_hamilton_equations() -> sp.Expr:
    r"""Hamilton's equations of the displayed $H^*$: $\partial H^*/\partial p\,[d]$ equals $\langle
    \dot x, d\rangle$ and $-\partial H^*/\partial x\,[d]$ equals $\langle \dot p, d\rangle$ for the
    displayed $\dot x$ and $\dot p$, every direction $d$ ($V$ through its gradient $V_x$; trace
    words, every $n$)."""
    w = Words()
    dp = directional(HSTAR.rhs, {p: d}, w, linear_potential)
    dx = directional(HSTAR.rhs, {x: d}, w, linear_potential)
    r = trace_residual(dp - pair_poly(XDOT_EQ.rhs, d, w))
    return r + trace_residual(-dx - pair_poly(PDOT_EQ.rhs, d, w))


# --- fixed n: explicit coordinates --------------------------------------------------------------


def su_basis(k: int) -> list[sp.Matrix]:
    """A basis of su(k): the so(k) basis, i (E_ij + E_ji) for i < j and i (E_jj - E_j+1,j+1)."""
    out = so_basis(k)
    for i, j in itertools.combinations(range(k), 2):
        e = sp.zeros(k, k)
        e[i, j] = e[j, i] = sp.I
        out.append(e)
    for j in range(k - 1):
        e = sp.zeros(k, k)
        e[j, j], e[j + 1, j + 1] = sp.I, -sp.I
        out.append(e)
    return out


def _trace_form(a: sp.Matrix, b: sp.Matrix) -> sp.Expr:
    return sp.expand((a * b).trace())


def killing_form(basis: Sequence[sp.Matrix]) -> sp.Matrix:
    """kappa(e_i, e_j) = tr(ad_e_i ad_e_j) from the structure constants: the coordinates of
    [e_i, e_j] are found with the (non-degenerate) trace form, nothing about kappa is assumed."""
    dim = len(basis)
    gram = sp.Matrix(dim, dim, lambda i, j: _trace_form(basis[i], basis[j]))
    ginv = gram.inv()

    def coords(v: sp.Matrix) -> sp.Matrix:
        return ginv * sp.Matrix([_trace_form(e, v) for e in basis])

    ad = [sp.Matrix.hstack(*[coords(ei * ej - ej * ei) for ej in basis]) for ei in basis]
    return sp.Matrix(dim, dim, lambda i, j: sp.expand((ad[i] * ad[j]).trace()))


@S13.check(Level.SYMBOLIC_FIXED_N)
def s13_killing_forms() -> sp.Expr:
    r"""$\kappa(e_i, e_j)$ from the structure constants equals the displayed $(n-2)
    \operatorname{tr}(e_i e_j)$ on $\mathfrak{so}(3)$, $\mathfrak{so}(4)$ and $2n
    \operatorname{tr}(e_i e_j)$ on $\mathfrak{su}(2)$, $\mathfrak{su}(3)$, for every pair of basis
    elements."""
    total = sp.Integer(0)
    for formula, basis in (
        (KILLING_SO, so_basis(3)),
        (KILLING_SO, so_basis(4)),
        (KILLING_SU, su_basis(2)),
        (KILLING_SU, su_basis(3)),
    ):
        shown = formula.rhs.subs(n, basis[0].rows)
        claimed = sp.Matrix([[explicit(shown, {"a": ei, "b": ej}) for ej in basis] for ei in basis])
        total += residual(killing_form(basis) - claimed)
    return total


def _coordinates(basis: Sequence[sp.Matrix], c: sp.Expr, m: sp.Matrix) -> dict[str, sp.Expr]:
    r"""The maximum principle for the displayed H with B = -c tr, written in coordinates.

    x = sum x^k e_k, u = sum u^k e_k, the costate a covector pi_k = B(p, e_k); the potential is
    V(x) = B(x, m)^3 (gradient 3 B(x, m)^2 m).  dH/du = 0 is solved as a linear system, H* is H
    there, and Hamilton's equations xdot^k = dH*/dpi_k, pidot_k = -dH*/dx^k are taken literally.
    Returns residuals: u* minus the emitted optimal control, H* minus the displayed H*, and the
    literal xdot, pdot minus the displayed ones.
    """
    scale = 2 * c
    dim = len(basis)
    zero = sp.zeros(*basis[0].shape)
    gram = sp.Matrix(dim, dim, lambda i, j: -c * _trace_form(basis[i], basis[j]))
    ginv = gram.inv()
    xs = sp.symbols(f"x1:{dim + 1}", real=True)
    pis = sp.symbols(f"pi1:{dim + 1}", real=True)
    us = sp.symbols(f"u1:{dim + 1}", real=True)

    def mat(cs: Sequence[sp.Expr]) -> sp.Matrix:
        return sum((ci * e for ci, e in zip(cs, basis, strict=True)), zero)

    X, P, U = mat(xs), mat(list(ginv * sp.Matrix(pis))), mat(us)
    M = matrix("m")

    def cubic(y: sp.Basic) -> sp.Basic:
        return Pair(y, M) ** 3  # scaled with every other pairing by plain

    def value(expr: sp.Basic, env: dict[str, Any], potential: Any = cubic) -> Any:
        return explicit(plain(expr, potential, scale), {**env, "m": m})

    env = {"x": X, "p": P}
    gens = (*xs, *pis)

    def poly(e: sp.Expr) -> sp.Poly:
        return sp.Poly(e, *gens)

    def mismatches(a: sp.Matrix, b: sp.Matrix) -> sp.Integer:
        """The number of entries of a - b that are not the zero polynomial."""
        return sp.Integer(sum(not poly(ai - bi).is_zero for ai, bi in zip(a, b, strict=True)))

    H = sp.Poly(value(HAMILTONIAN.rhs, {**env, "u": U}), *us, *gens)
    A, rhs = sp.linear_eq_to_matrix([H.diff(ui).as_expr() for ui in us], us)
    ustar = mat(list(A.LUsolve(rhs)))
    Hstar = poly(value(HAMILTONIAN.rhs, {**env, "u": ustar}))
    xdot = mat([Hstar.diff(q).as_expr() for q in pis])
    pdot = mat(list(ginv * sp.Matrix([-Hstar.diff(y).as_expr() for y in xs])))
    grad_V = 3 * (-c * _trace_form(X, m)) ** 2 * m
    pdot_shown = explicit(plain(PDOT_EQ.rhs, None, scale), {**env, "V_x": grad_V})
    return {
        "u": mismatches(ustar, explicit(OPTIMAL_CONTROL["u"], env)),
        "Hstar": sp.Integer(int(not (Hstar - poly(value(HSTAR.rhs, env))).is_zero)),
        "xdot": mismatches(xdot, value(XDOT_EQ.rhs, env)),
        "pdot": mismatches(pdot, pdot_shown),
    }


def killing_factor(basis: Sequence[sp.Matrix]) -> sp.Expr:
    """kappa(e_0, e_0) / tr(e_0 e_0) (the factor c of kappa = c tr, see s13_killing_forms)."""
    return sp.nsimplify(killing_form(basis)[0, 0] / _trace_form(basis[0], basis[0]))


def mixed_form_control_scale() -> sp.Expr:
    """su(2) with the costate paired by -1/2 tr but ||u||^2 = -kappa(u, u): the s with
    u* = s [p, x] (coordinates, dH/du = 0 solved as a linear system; used by the tests and the
    book to show what mixing forms does, not evidence)."""
    basis = su_basis(2)
    c_kill = killing_factor(basis)
    xs, ps, us = (sp.symbols(f"{v}1:4", real=True) for v in ("x", "q", "u"))

    def mat(cs: Sequence[sp.Expr]) -> sp.Matrix:
        return sum((ci * e for ci, e in zip(cs, basis, strict=True)), sp.zeros(2, 2))

    X, P, U = mat(xs), mat(ps), mat(us)
    H = sp.expand(-_trace_form(P, X * U - U * X) / 2 + c_kill * _trace_form(U, U) / 2)
    A, rhs = sp.linear_eq_to_matrix([sp.diff(H, ui) for ui in us], us)
    ustar = mat(list(A.LUsolve(rhs)))
    bracket = P * X - X * P
    k = next(i for i in range(4) if sp.expand(bracket[i]) != 0)
    return sp.simplify(ustar[k] / bracket[k])


def _algebras() -> list[tuple[str, list[sp.Matrix], sp.Expr]]:
    """(name, basis, c): so(3) with the pairing (c = 1/2) in the basis E_ij and in a basis that
    is not orthogonal for it (so the costate covector and the matrix p differ by a non-diagonal
    Gram matrix), and su(2) with the negative Killing form (c from the structure constants)."""
    e = so_basis(3)
    skewed = [e[0], e[0] + e[1], e[2]]
    su2 = su_basis(2)
    return [
        ("so(3), pairing -1/2 tr", e, sp.Rational(1, 2)),
        ("so(3), pairing -1/2 tr, non-orthogonal basis", skewed, sp.Rational(1, 2)),
        ("su(2), negative Killing form", su2, killing_factor(su2)),
    ]


@functools.cache
def coordinate_residuals() -> dict[str, dict[str, sp.Expr]]:
    """For each algebra of :func:`_algebras`: the residuals of :func:`_coordinates` with a fixed
    rational m (a genuine cubic potential)."""
    out = {}
    for name, basis, c in _algebras():
        coeffs = [sp.Rational(3, 2), -1, sp.Rational(1, 3), 2, -sp.Rational(1, 2), 1][: len(basis)]
        m = sum((ci * e for ci, e in zip(coeffs, basis, strict=True)), sp.zeros(*basis[0].shape))
        out[name] = _coordinates(basis, c, m)
    return out


@S13.check(Level.SYMBOLIC_FIXED_N)
def s13_coordinates() -> sp.Expr:
    r"""In coordinates, with the costate a covector and $V(x) = B(x, m)^3$: solving $\partial
    H/\partial u = 0$ gives the emitted $u^*$, $H$ there is the displayed $H^*$, and the literal
    Hamilton equations are the displayed $\dot x$ and $\dot p$ with $V_x = 3 B(x, m)^2 m$
    ($\mathfrak{so}(3)$ with the pairing, in an orthonormal and in a non-orthogonal basis;
    $\mathfrak{su}(2)$ with the negative Killing form)."""
    return sum((sum(r.values()) for r in coordinate_residuals().values()), sp.Integer(0))


@S13.check(Level.FLOAT64, tol=1e-14)
def s13_symrb_hamiltonian() -> float:
    r"""symrb.orbits.orbit_hamiltonian against $\frac12 \|[p, x]\|^2 - \frac12 \|[x, N]\|^2$
    computed in NumPy with $\|a\|^2 = -\frac12 \operatorname{tr}(aa)$, $n = 3, \dots, 6$, 20 random
    skew $(x, p, N)$ each: max difference relative to $\|p\|^2 \|x\|^2 + \|x\|^2 \|N\|^2$."""
    import symrb

    rng = np.random.default_rng(13)
    worst = []
    for k in range(3, 7):
        x_, p_, N_ = (np.stack([ref.random_skew(k, rng) for _ in range(20)]) for _ in range(3))
        want = 0.5 * np_norm2(np_comm(p_, x_)) - 0.5 * np_norm2(np_comm(x_, N_))
        size = np_norm2(p_) * np_norm2(x_) + np_norm2(x_) * np_norm2(N_)
        worst.append(np.max(np.abs(symrb.orbits.orbit_hamiltonian(x_, p_, N_) - want) / size))
    return float(np.max(worst))


@S13.check(Level.SYMBOLIC_GENERAL_N)
def s13_flow_stays_on_the_orbit() -> sp.Expr:
    r"""The displayed control system keeps $x$ on the adjoint orbit of $x(0)$: for any control
    $u(t)$, $x = g x_0 g^{-1}$ with $\dot g = -u g$ (so $g$ stays in the group of $u$) has
    derivative $-u g x_0 g^{-1} + g x_0 g^{-1} u$, which equals the displayed $[x, u]$ (matrix
    symbols, every $n$). The opposite sign of $\dot g$ leaves a nonzero residual."""
    g, x0, g_inv = matrix("g"), matrix("x_0"), matrix("g^{-1}")
    product_rule = (-u * g) * x0 * g_inv + g * x0 * (g_inv * u)
    difference = sp.expand(ORB.rhs.doit().xreplace({x: g * x0 * g_inv}) - product_rule)
    return sp.Integer(0 if difference == sp.ZeroMatrix(*difference.shape) else 1)


@S13.check(Level.EXACT_RATIONAL)
def s13_so_is_compact_and_normal() -> int:
    r"""$\mathfrak{so}(k)$ is the intersection of the compact real form $\mathfrak{su}(k)$ and the
    normal real form $\mathfrak{sl}(k, \mathbb{R})$ of $\mathfrak{sl}(k, \mathbb{C})$: the
    conditions $A^* = -A$, $\operatorname{tr} A = 0$ and $A$ real on a general complex $k \times k$
    matrix $A = B + iC$ ($B$, $C$ real, $k = 2, \dots, 5$) are solved exactly; the solution space is
    the skew-symmetric real matrices, of dimension $k(k-1)/2$. Residual: the number of $k$ whose
    solutions are not exactly $\mathfrak{so}(k)$."""
    wrong = 0
    for k in range(2, 6):
        B, C = general_matrix("b", k), general_matrix("c", k)
        A = B + sp.I * C
        conditions = list(A.H + A) + [A.trace()] + list(C)  # compact, traceless, real
        unknowns = list(B) + list(C)
        equations = [e for c in conditions for e in (sp.re(c), sp.im(c)) if e != 0]
        (solution,) = sp.linsolve(equations, unknowns)
        A_solved = B.xreplace(dict(zip(unknowns, solution, strict=True)))
        free = A_solved.free_symbols
        skew = A_solved.T + A_solved == sp.zeros(k, k)
        wrong += int(not (skew and len(free) == k * (k - 1) // 2))
    return wrong


# the paper's sentences
S13.sentence(
    r"These general ideas can also be extended to a variational problem on the adjoint orbits of "
    r"compact Lie groups as in [BlCr1996].",
    kind="prose",
    reason="announces the problem, with a citation",
)
S13.sentence(
    r"Let $\mathfrak{g}$ be a complex semisimple Lie algebra, $\mathfrak{g}_u$ its compact real "
    r"form, and $G_u$ the corresponding compact group.",
    kind="prose",
    reason="fixes notation; the evidence works in the instances so(n) and su(n) the paper names next",
)
S13.sentence(
    r"In this case a natural drift free control system on an orbit of $G_u$ takes the form "
    r"$\dot x=[x,u]$",
    s13_flow_stays_on_the_orbit,
)
S13.sentence(
    r"We remark that we formulate the problem in this generality for convenience, but the most "
    r"useful case to bear in mind is the algebra $\mathfrak{su}(n)$ of skew-Hermitian matrices or "
    r"the algebra $\mathfrak{so}(n)$ of skew symmetric matrices (the intersection of the compact "
    r"and normal real forms of the the algebra $\mathfrak{sl}(n, \mathbb{C})$).",
    s13_so_is_compact_and_normal,
)
S13.sentence(
    r"Orbits in this case are similarity orbits under the group action.",
    s13_flow_stays_on_the_orbit,
)
S13.sentence(
    r"We then consider the following generalization of the functional suggested by Brockett "
    r"[1994] (we shall return to Brockett's precise problem shortly): $\eta(x,u)=\int_0^{t_f} "
    r"1/2||u||^2-V(x)dt$",
    s13_hamiltonian_convention,
    s13_coordinates,
)
S13.sentence(
    r"where $||\cdot || = < \cdot ,\cdot >^{1/2}$ is the norm induced on $\mathfrak{g}_u$ by "
    r"the negative of the Killing form $\kappa (\cdot, \cdot)$ on $\mathfrak{g}$ and V is a "
    r"smooth function on $\mathfrak{g}_u$.",
    s13_killing_forms,
    s13_coordinates,
)
S13.sentence(
    r"The pairing between vectors $x$ in $\mathfrak{g}$ and dual vectors $p$ in "
    r"$\mathfrak{g}^*$ may be written $< p,x > = -\kappa(x,p)$.",
    s13_killing_forms,
    s13_coordinates,
)
S13.sentence(r"We have", kind="prose", reason="introduces the theorem")
S13.sentence(
    r"The equations of the maximum principle for the variational problem with functional (var) "
    r"subject to the dynamics (orb) are $\begin{aligned} \dot x &= [x,[p,x]] \\ \dot p &= "
    r"[p,[p,x]]-V_x\,. \end{aligned}$",
    s13_hamilton_equations,
    s13_coordinates,
)
S13.sentence(
    r"The Hamiltonian is given by $H(x,p,u)=< p,[x,u] > -1/2||u||^2+V(x)\,.$",
    s13_hamiltonian_convention,
    s13_coordinates,
    s13_symrb_hamiltonian,
)
S13.sentence(
    r"Hence ${\partial H\over\partial u}=-< [x,p],\cdot > - < u,\cdot >$ and thus the "
    r"optimal control is given by $u^*=[p,x]$",
    s13_stationary_control,
    s13_coordinates,
)
S13.sentence(
    r"Substituting this into $H$ we find the Hamiltonian evaluated along the optimal trajectory is "
    r"given by $H^*(p,x)=-1/2 < x,[p,[p,x]] > +V(x)$",
    s13_optimal_hamiltonian,
    s13_coordinates,
    s13_symrb_hamiltonian,
)
S13.sentence(
    r"Computing $\dot x=\left({\partial H^*\over \partial p}\right)^T$ and $\dot p=-\left("
    r"{\partial H^*\over \partial x}\right)^T$ gives the result.",
    s13_hamilton_equations,
    s13_coordinates,
)
