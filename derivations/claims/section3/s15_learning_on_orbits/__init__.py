"""S15 (Section 3.4, eqs. ``varm``, ``opbm``): the learning version on adjoint orbits, a terminal
cost and the double bracket flow.

Samples x^a steered by one shared control, with Brockett's potential for each sample and the
terminal cost phi(x^a_T) = <x^a_T, N>.  Erratum: the endpoint sign is wrong (p^a_T =
-dphi/dx^a_T), the per-sample control ignores that the samples share u (u* = sum_b [p^b, x^b]),
and for several samples the solution does not tend to the double bracket flow.  One sample follows
it for every T, its second costate term decaying like exp(-||x_0|| ||N|| T) on so(3); two samples
conserve their pairing, which on so(3) bounds the second term from below for every T.

This module holds the claim, its formulas, the kernel ``orbit_rhs_with_control`` and the evidence
for every n (trace words); :mod:`.so3` holds the evidence on so(3) (the endpoint gradient against
central differences, the one-sample decay, the two-sample bound, the boundary value problem runs)
and the so(3) closed forms ``one_sample_second_term`` and ``two_sample_bound``, all emitted to
``symrb/_generated/adjoint_orbits.py``.
"""

from __future__ import annotations

import sympy as sp
from sympy.core.function import AppliedUndef

from derivations.claims.section3._display import _Norm, minus, sample_sum
from derivations.claims.section3._orbits import (
    ARG_N,
    ARG_P,
    ARG_U,
    ARG_X,
    EPS,
    PHI,
    N,
    T,
    V,
    brockett,
    d,
    directional,
    linear_potential,
    of_sample,
    p,
    pair_poly,
    samples,
    t,
    trace_poly,
    u,
    x,
)
from derivations.claims.section3.s13_adjoint_orbits import OPTIMAL_CONTROL
from derivations.claims.section3.s14_brockett_toda import (
    DOUBLE_BRACKET,
    DOUBLE_BRACKET_RHS,
    ORBIT_EXTREMAL_RHS,
)
from derivations.registry import Level, claim
from derivations.symbolic import Bracket, Pair, Words, eq, trace_residual
from derivations.vocabulary import Kernel, matrix

_ia_s, _ib_s = sp.Symbol("a"), sp.Symbol("b")
xa, pa, xb, pb = matrix("x^a"), matrix("p^a"), matrix("x^b"), matrix("p^b")
xaT, paT = matrix("x^a_T"), matrix("p^a_T")
XDOT_A, PDOT_A = matrix(r"\dot{x}^a"), matrix(r"\dot{p}^a")
USTAR_M = matrix("u^*")
GRAD_PHI = matrix(r"\partial\phi/\partial x^a_T")
x_T, x_0 = matrix("x_T"), matrix("x_0")
x1T, x2T, x10, x20 = matrix("x^1_T"), matrix("x^2_T"), matrix("x^1_0"), matrix("x^2_0")
_phi_T, _phi_0, _beta = sp.symbols("phi_T phi_0 beta", positive=True)

S15 = claim(
    "S15",
    label="varm, opbm",
    title="Learning version on adjoint orbits: terminal cost and the double bracket flow",
    statement="Samples $x^a$ steered by one shared control, [[orb_m]], with the cost [[cost_m]], "
    "Brockett's potential for each sample and the terminal cost [[phi]].",
    printed="The extremals solve [[opbm_printed]] with [[endpoint_printed]]; then the solution "
    "tends to the double bracket equation [[double_bracket]] and the second term of the costate "
    "equation, [[second_term]], goes to zero.",
    corrected="With the shared control [[shared_control]] the extremals solve [[opbm_corrected]] "
    "with [[endpoint_corrected]]. For one sample the extremal is [[p_one]] on all of $[0,T]$ and "
    "$x$ follows the double bracket flow for every $T$; on so(3) the second term decays as "
    "[[decay]] where [[phase]] ($\\phi_T$ the angle between $x_T$ and $-N$), exponentially at the "
    "rate $\\|x_0\\|\\|N\\|$. For two or more samples the shared control conserves the pairings, "
    "[[invariant]], and on so(3) this gives [[bound]] for every $T$, where [[beta]]: the second "
    "term does not go to zero unless the samples start on one line.",
    expected="holds after correction",
    headline="[[endpoint_corrected]], [[shared_control]]",
    section="3.4",
    where="Section 3.4, the second corollary (several samples $x^a$ with a terminal cost, $p^a_T "
    "= \\partial\\phi/\\partial x^a_T$) and the last paragraph of the section (with $\\phi(x^a_T) "
    "= \\langle x^a_T, n\\rangle$ the solution is said to tend to the double bracket equation "
    "$\\dot x = [x, [x, n]]$)",
    note="The endpoint sign is wrong, the per-sample control ignores that the samples share $u$, "
    "and for several samples the solution does not tend to the double bracket flow. Corrected: "
    "$p^a_T = -\\partial\\phi/\\partial x^a_T$ and $u^* = \\sum_b [p^b, x^b]$; one sample follows "
    "the double bracket flow for every $T$, several do not. (1) Endpoint sign: with $H = \\langle "
    "p, f\\rangle - L$ (the convention of S13), minimising $\\int L + \\phi(x_T)$ needs $p_T = "
    "-\\partial\\phi/\\partial x_T = -N$; the printed $+\\partial\\phi/\\partial x_T$ makes the "
    "adjoint gradient of the cost wrong (relative error 0.53) and its extremal $p = +N$ drives "
    "$x$ along $\\dot x = -[x,[x,N]]$, maximising $\\langle x_T, N\\rangle$. (2) The samples "
    "share the control, so $u^* = \\sum_b [p^b, x^b]$; the printed per-sample $[p^a, x^a]$ is not "
    "Hamilton's equation of the shared problem (and $x$ in $[p^a,[p^a,x]]$ lacks its index; we "
    "read it as $x^a$). (3) The limit: for one sample the corrected extremal is the double "
    "bracket flow for every $T$ ($p = -N$ exactly) and $\\|[N,[N,x_T]]\\|$ decays like "
    "$e^{-\\|x_0\\| \\|N\\| T}$: on $\\mathfrak{so}(3)$ with $\\|x_0\\| = 0.5$, $\\|N\\| = 1$ it "
    "is 0.499, 0.431, 0.202, 0.029, 5.2e-4 at $T$ = 1, 2, 4, 8, 16 (times $e^{T/2}$ it tends to "
    "$2\\tan(\\phi_0/2)\\|N\\|^2 \\|x_0\\| = 1.557$), and `solve_orbit_bvp` from the guess $p = "
    "0$ reproduces the exact solution to 5e-8 (collocation tolerance 1e-6). For two samples the "
    "shared control rotates both by the same rotation (it conserves $\\langle x^1, x^2\\rangle$ "
    "for every $n$), so on $\\mathfrak{so}(3)$ the angle between the lines of $x^1$ and $x^2$ is "
    "fixed and $\\max_a \\|[N,[N,x^a_T]]\\|$ stays above $\\|N\\|^2 \\min_a \\|x^a_0\\| "
    "\\sin(\\beta/2)$ for every $T$ (sharp: attained by samples of equal norm placed "
    "symmetrically about $N$). On the $\\mathfrak{so}(3)$ example (seed 150) the bound is 1.708 "
    "and the BVP solutions give 2.152, 2.176, 2.176 at $T$ = 2, 4, 8: the second term settles at "
    "a positive value instead of going to zero, and neither sample follows its own double bracket "
    "flow.",
)
ORB_M = S15.formula("orb_m", eq(XDOT_A, Bracket(xa, u)))
PHI_EQ = S15.formula("phi", eq(PHI(xaT), Pair(xaT, N)))
COST_M = S15.formula(
    "cost_m",
    eq(
        sp.Function("eta")(u),
        sp.Integral(_Norm(u) ** 2 / 2 - sample_sum(V(xa), _ia_s), (t, 0, T))
        + sample_sum(PHI(xaT), _ia_s),
    ),
)
OPBM_PRINTED = S15.formula(
    "opbm_printed",
    (
        eq(XDOT_A, Bracket(xa, Bracket(pa, xa))),
        eq(PDOT_A, minus(Bracket(pa, Bracket(pa, xa)), Bracket(N, Bracket(N, xa)))),
    ),
)
ENDPOINT = {
    "printed": S15.formula("endpoint_printed", eq(paT, GRAD_PHI)),
    "corrected": S15.formula("endpoint_corrected", eq(paT, -GRAD_PHI)),
}
S15.formula("double_bracket", DOUBLE_BRACKET)
SECOND_TERM = S15.formula("second_term", Bracket(N, Bracket(N, xa)))
SHARED_CONTROL = S15.formula("shared_control", eq(USTAR_M, sample_sum(Bracket(pb, xb), _ib_s)))
OPBM_CORRECTED = S15.formula(
    "opbm_corrected",
    (
        eq(XDOT_A, ORB_M.rhs.xreplace({u: USTAR_M})),
        eq(PDOT_A, minus(Bracket(pa, USTAR_M), SECOND_TERM)),
    ),
)
P_ONE = S15.formula("p_one", eq(p, -N))
DECAY = S15.formula(
    "decay",
    eq(_Norm(Bracket(N, Bracket(N, x_T))), _Norm(N) ** 2 * _Norm(x_0) * sp.sin(_phi_T)),
)
PHASE = S15.formula(
    "phase",
    eq(sp.tan(_phi_T / 2), sp.tan(_phi_0 / 2) * sp.exp(-_Norm(x_0) * _Norm(N) * T)),
)
_x1, _x2 = matrix("x^1"), matrix("x^2")
INVARIANT = S15.formula("invariant", eq(sp.Derivative(Pair(_x1, _x2), t), 0))
BETA = S15.formula("beta", eq(sp.cos(_beta), sp.Abs(Pair(x10, x20)) / (_Norm(x10) * _Norm(x20))))
BOUND = S15.formula(
    "bound",
    sp.Ge(
        sp.Max(_Norm(Bracket(N, Bracket(N, x1T))), _Norm(Bracket(N, Bracket(N, x2T)))),
        _Norm(N) ** 2 * sp.Min(_Norm(x10), _Norm(x20)) * sp.sin(_beta / 2),
    ),
)
# the Hamiltonian of the shared problem (not displayed: H of S13 summed over the samples)
H_SHARED = sample_sum(Pair(pa, ORB_M.rhs), _ia_s) - _Norm(u) ** 2 / 2 + sample_sum(V(xa), _ia_s)

ORBIT_RHS_WITH_CONTROL = Kernel(
    name="orbit_rhs_with_control",
    target="adjoint_orbits",
    args=[ARG_X, ARG_P, ARG_U, ARG_N],
    outputs={
        "xdot": OPBM_CORRECTED[0].rhs.xreplace({xa: x, USTAR_M: u}).doit(),
        "pdot": OPBM_CORRECTED[1].rhs.xreplace({xa: x, pa: p, USTAR_M: u}).doit(),
    },
    doc="State and costate fields of one sample for a given control u.\n\n"
    "xdot = [x, u], pdot = [p, u] - [N, [N, x]] (Brockett's potential); with the shared optimal\n"
    "control u = sum_b [p^b, x^b] these are the extremal equations of the learning version.",
    claims=("S15",),
)


def kernel_of_sample(expr: sp.Basic, k: int, control: sp.MatrixExpr | None = None) -> sp.Basic:
    """A kernel output for sample k: x -> x^k, p -> p^k (and u -> ``control``)."""
    reps = {x: matrix(f"x^{k}"), p: matrix(f"p^{k}")}
    if control is not None:
        reps[u] = control
    return expr.xreplace(reps)


def emitted_shared_control(count: int) -> sp.MatrixExpr:
    """sum over the samples of the emitted optimal control (how solve_orbit_bvp computes u*)."""
    return sp.MatAdd(*[kernel_of_sample(OPTIMAL_CONTROL["u"], k) for k in range(1, count + 1)])


def _two_sample_hamilton(form: str) -> sp.Expr:
    """Hamilton's equations of the shared problem with two samples: H* is H_SHARED at the
    displayed shared control; its derivatives in p^1, x^1 along d against the displayed printed
    or corrected equations of sample 1."""
    w = Words()
    ustar = samples(SHARED_CONTROL.rhs, 2)
    Hstar = samples(H_SHARED, 2).xreplace({u: ustar})
    eqs = OPBM_PRINTED if form == "printed" else OPBM_CORRECTED
    xdot, pdot = (of_sample(e.rhs.xreplace({USTAR_M: SHARED_CONTROL.rhs}), "a", 1) for e in eqs)
    xdot, pdot = samples(xdot, 2), samples(pdot, 2)
    x1, p1 = matrix("x^1"), matrix("p^1")
    r = trace_residual(directional(Hstar, {p1: d}, w, brockett) - pair_poly(xdot, d, w))
    return r + trace_residual(-directional(Hstar, {x1: d}, w, brockett) - pair_poly(pdot, d, w))


@S15.check(Level.SYMBOLIC_GENERAL_N, form="printed")
def s15_printed_equations() -> sp.Expr:
    """The displayed printed equations (per-sample control $[p^a, x^a]$) against Hamilton's
    equations of the shared problem's $H^*$ with two samples (trace words, every $n$): must fail."""
    return _two_sample_hamilton("printed")


@S15.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def s15_corrected_equations() -> sp.Expr:
    """The displayed corrected equations (shared control) are Hamilton's equations of the shared
    problem's $H^* = H$ at the displayed $u^*$ with two samples (trace words, every $n$)."""
    return _two_sample_hamilton("corrected")


def _phi(y: sp.Basic) -> sp.Basic:
    """The displayed terminal cost at y."""
    return PHI_EQ.rhs.xreplace({xaT: y})


def _endpoint_first_variation(form: str) -> sp.Expr:
    """First variation of the displayed cost for one sample along a control variation du, with
    dx_0 = 0 and dxdot = d/de [x + e dx, u + e du].

    With the displayed costate equation (general control u), dL - d/dt <p, dx> = <u - u*, du>
    for L the integrand of the displayed cost and u* the displayed shared control (one sample), so
    that dJ = int <u - u*, du> dt + <p_T, dx_T> + dphi[dx_T].  Returns the trace residual of that
    identity, of dphi[d] = <N, d> for the displayed terminal cost, and of the boundary term
    dphi[dx_T] + <p_T, dx_T> with p_T from the displayed endpoint condition of ``form``.
    """
    w = Words()
    dx, du, dxT = matrix("dx"), matrix("du"), matrix("dx_T")
    x1, p1, x1T = matrix("x^1"), matrix("p^1"), matrix("x^1_T")
    (integral,) = COST_M.rhs.atoms(sp.Integral)
    dL = directional(samples(integral.function, 1), {x1: dx, u: du}, w, brockett)
    pdot = of_sample(OPBM_CORRECTED[1].rhs.xreplace({USTAR_M: u}), "a", 1)
    dxdot = of_sample(ORB_M.rhs, "a", 1).xreplace({x1: x1 + EPS * dx, u: u + EPS * du})
    d_dt = pair_poly(pdot, dx, w) + sp.diff(trace_poly(Pair(p1, dxdot), w), EPS).subs(EPS, 0)
    ustar = samples(SHARED_CONTROL.rhs, 1)
    r = trace_residual(dL - d_dt - pair_poly(minus(u, ustar), du, w))
    terminal = (COST_M.rhs - integral).replace(
        lambda e: isinstance(e, AppliedUndef) and e.func == PHI, lambda e: _phi(e.args[0])
    )
    dphi = directional(samples(terminal, 1), {x1T: dxT}, w)
    r += trace_residual(dphi - pair_poly(N, dxT, w))  # the gradient of phi is N
    pT = of_sample(ENDPOINT[form].rhs.xreplace({GRAD_PHI: N}), "a", 1)
    return r + trace_residual(dphi + pair_poly(pT, dxT, w))


@S15.check(Level.SYMBOLIC_GENERAL_N, form="printed")
def s15_printed_endpoint() -> sp.Expr:
    r"""First variation of the cost: with the displayed printed endpoint condition the boundary term
    $d\phi[dx_T] + \langle p_T, dx_T\rangle$ does not vanish (trace words, every $n$): must fail."""
    return _endpoint_first_variation("printed")


@S15.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def s15_corrected_endpoint() -> sp.Expr:
    r"""First variation of the displayed cost (one sample, $dx_0 = 0$): along the linearised state
    and the displayed costate equation $dL - \frac{d}{dt} \langle p, dx\rangle = \langle u - u^*,
    du\rangle$, so $dJ$ is $\int \langle u - u^*, du\rangle\, dt$ plus the boundary term
    $d\phi[dx_T] + \langle p_T, dx_T\rangle$; with the displayed corrected endpoint condition the
    boundary term vanishes for every $dx_T$ (trace words, every $n$)."""
    return _endpoint_first_variation("corrected")


@S15.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def s15_emitted_shared_field() -> sp.Expr:
    r"""Two samples: $\partial H/\partial u$ of the shared problem vanishes at the sum over samples
    of the emitted optimal control for every direction, and the emitted state-costate field at that
    control is the displayed corrected equations (trace words, every $n$)."""
    w = Words()
    ustar = emitted_shared_control(2)
    moved = samples(H_SHARED, 2).xreplace({u: ustar + EPS * d})
    r = trace_residual(sp.diff(trace_poly(moved, w, linear_potential), EPS).subs(EPS, 0))
    for k in (1, 2):
        for out, formula in zip(("xdot", "pdot"), OPBM_CORRECTED, strict=True):
            emitted = kernel_of_sample(ORBIT_RHS_WITH_CONTROL[out], k, ustar)
            want = samples(
                of_sample(formula.rhs.xreplace({USTAR_M: SHARED_CONTROL.rhs}), "a", k), 2
            )
            r += trace_residual(pair_poly(emitted - want, d, w))
    return r


@S15.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def s15_one_sample_exact() -> sp.Expr:
    r"""One sample: at the displayed $p = -N$ the emitted extremal field has $\dot p = 0$ for every
    $x$ and $\dot x$ equal to the emitted double bracket field (trace words, every $n$), so $p = -N$
    and the double bracket flow solve the boundary value problem for every $T$."""
    w = Words()
    at = {p: P_ONE.rhs}
    pdot = ORBIT_EXTREMAL_RHS["pdot"].xreplace(at)
    xdot = ORBIT_EXTREMAL_RHS["xdot"].xreplace(at)
    r = trace_residual(pair_poly(pdot, d, w))
    return r + trace_residual(pair_poly(xdot - DOUBLE_BRACKET_RHS["xdot"], d, w))


@S15.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def s15_shared_control_invariant() -> sp.Expr:
    r"""Under one shared control the time derivative of the displayed pairing $\langle x^1,
    x^2\rangle$, along the emitted state field of each sample, vanishes for any control and any $n$
    (trace words)."""
    w = Words()
    moves = {
        xk: kernel_of_sample(ORBIT_RHS_WITH_CONTROL["xdot"], k) for k, xk in ((1, _x1), (2, _x2))
    }
    (derivative,) = INVARIANT.lhs.args[:1]
    r = trace_residual(directional(derivative, moves, w) - trace_poly(INVARIANT.rhs, w))
    return r
