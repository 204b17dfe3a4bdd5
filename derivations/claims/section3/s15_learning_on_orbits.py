"""S15 (Section 3.4, eqs. ``varm``, ``opbm``): the learning version on adjoint orbits, a terminal
cost and the double bracket flow.

Samples x^a steered by one shared control, with Brockett's potential for each sample and the
terminal cost phi(x^a_T) = <x^a_T, N>.  Erratum: the endpoint sign is wrong (p^a_T =
-dphi/dx^a_T), the per-sample control ignores that the samples share u (u* = sum_b [p^b, x^b]),
and for several samples the solution does not tend to the double bracket flow.  One sample follows
it for every T, its second costate term decaying like exp(-||x_0|| ||N|| T) on so(3); two samples
conserve their pairing, which on so(3) bounds the second term from below for every T.

Emitted to ``symrb/_generated/adjoint_orbits.py``: ``orbit_rhs_with_control``, and the so(3)
closed forms ``one_sample_second_term`` (the decay at the displayed phase) and
``two_sample_bound`` (the displayed bound).  The computations that do not read the displayed
formulas (data, boundary value problem runs, the adjoint derivative of the cost) are in
:mod:`derivations.claims.section3._orbit_learning`.
"""

from __future__ import annotations

import functools

import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef

from derivations.claims.section3._display import (
    _Norm,
    minus,
    sample_sum,
)
from derivations.claims.section3._orbit_learning import (
    ONE_SAMPLE_HORIZONS,
    emitted_shared_control,
    endpoint_gradient,
    exact_so3,
    half_angle,
    kernel_of_sample,
    numeric,
    one_sample_data,
    one_sample_runs,
    rational_residual,
    second_term_norm,
    two_sample_data,
    two_sample_runs,
)
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
    np_norm2,
    np_pair,
    of_sample,
    p,
    pair_poly,
    plain,
    samples,
    t,
    trace_poly,
    u,
    x,
)
from derivations.claims.section3.s14_brockett_toda import (
    DOUBLE_BRACKET,
    DOUBLE_BRACKET_RHS,
    ORBIT_EXTREMAL_RHS,
)
from derivations.registry import Level, claim
from derivations.symbolic import Bracket, Pair, Words, eq, explicit, hat3, trace_residual
from derivations.vocabulary import Arg, Kernel, matrix

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
    """The displayed printed equations (per-sample control [p^a, x^a]) against Hamilton's
    equations of the shared problem's H* with two samples (trace words, every n): must fail."""
    return _two_sample_hamilton("printed")


@S15.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def s15_corrected_equations() -> sp.Expr:
    """The displayed corrected equations (shared control) are Hamilton's equations of the
    shared problem's H* = H at the displayed u* with two samples (trace words, every n)."""
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
    """First variation of the cost: with the displayed printed endpoint condition the boundary
    term dphi[dx_T] + <p_T, dx_T> does not vanish (trace words, every n): must fail."""
    return _endpoint_first_variation("printed")


@S15.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def s15_corrected_endpoint() -> sp.Expr:
    """First variation of the displayed cost (one sample, dx_0 = 0): along the linearised state
    and the displayed costate equation dL - d/dt <p, dx> = <u - u*, du>, so
    dJ = int <u - u*, du> dt + dphi[dx_T] + <p_T, dx_T>; with the displayed corrected endpoint
    condition the boundary term vanishes for every dx_T (trace words, every n)."""
    return _endpoint_first_variation("corrected")


def _endpoint_gradient(form: str) -> float:
    """The adjoint derivative of the cost from p^a_T of the displayed endpoint condition of
    ``form`` (the gradient of phi replaced by N) against central differences."""
    return endpoint_gradient(ENDPOINT[form].rhs.xreplace({GRAD_PHI: N}))


@S15.check(Level.FLOAT64, tol=1e-6, form="printed")
def s15_printed_endpoint_gradient() -> float:
    """The adjoint directional derivative of the cost with the printed p_T (so(3), two samples,
    T = 1, Brockett's V from symrb.brockett_potential, emitted state-costate field) against
    central differences of the cost: relative difference (must be large)."""
    return _endpoint_gradient("printed")


@S15.check(Level.FLOAT64, tol=1e-6, form="corrected")
def s15_corrected_endpoint_gradient() -> float:
    """The same with the corrected p_T: the adjoint directional derivative of the cost equals the
    central differences (relative difference)."""
    return _endpoint_gradient("corrected")


@S15.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def s15_emitted_shared_field() -> sp.Expr:
    """Two samples: dH/du of the shared problem vanishes at the sum over samples of the emitted
    optimal control for every direction, and the emitted state-costate field at that control is
    the displayed corrected equations (trace words, every n)."""
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
    """One sample: at the displayed p = -N the emitted extremal field has pdot = 0 for every x and
    xdot equal to the emitted double bracket field (trace words, every n), so p = -N and the
    double bracket flow solve the boundary value problem for every T."""
    w = Words()
    at = {p: P_ONE.rhs}
    pdot = ORBIT_EXTREMAL_RHS["pdot"].xreplace(at)
    xdot = ORBIT_EXTREMAL_RHS["xdot"].xreplace(at)
    r = trace_residual(pair_poly(pdot, d, w))
    return r + trace_residual(pair_poly(xdot - DOUBLE_BRACKET_RHS["xdot"], d, w))


@S15.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def s15_shared_control_invariant() -> sp.Expr:
    """Under one shared control the time derivative of the displayed pairing <x^1, x^2>, along
    the emitted state field of each sample, vanishes for any control and any n (trace words)."""
    w = Words()
    moves = {
        xk: kernel_of_sample(ORBIT_RHS_WITH_CONTROL["xdot"], k) for k, xk in ((1, _x1), (2, _x2))
    }
    (derivative,) = INVARIANT.lhs.args[:1]
    r = trace_residual(directional(derivative, moves, w) - trace_poly(INVARIANT.rhs, w))
    return r


# --- the one-sample decay on so(3) -------------------------------------------------------------

_r, _s, _tau, _tau0 = sp.symbols("r s tau tau_0", positive=True)


def _phase_tau() -> sp.Expr:
    """tan(phi_T / 2) from the displayed phase formula with ||x_0|| = r, ||N|| = s and
    tan(phi_0 / 2) = tau_0."""
    norms = {_Norm(x_0): _r, _Norm(N): _s}
    return PHASE.rhs.xreplace(norms).subs(sp.tan(_phi_0 / 2), _tau0)


def _decay_closed_form() -> sp.Expr:
    """The displayed decay ||N||^2 ||x_0|| sin(phi_T) with sin(phi_T) = 2 tau / (1 + tau^2),
    tau = tan(phi_T / 2) from the displayed phase (||x_0|| = r, ||N|| = s, tan(phi_0 / 2) =
    tau_0)."""
    sin_T, _ = half_angle(_phase_tau())
    return DECAY.rhs.xreplace({_Norm(x_0): _r, _Norm(N): _s}).subs(sp.sin(_phi_T), sin_T)


ONE_SAMPLE_SECOND_TERM = Kernel(
    name="one_sample_second_term",
    target="adjoint_orbits",
    args=[
        Arg("r", "(...)", "||x_0||, the norm of the sample"),
        Arg("s", "(...)", "||N||"),
        Arg("tau_0", "(...)", "tan(phi_0 / 2), phi_0 the angle of x_0 from -N"),
        Arg("T", "(...)", "the time, >= 0"),
    ],
    outputs={"second_term": _decay_closed_form()},
    doc="||[N, [N, x(T)]]|| along the one-sample extremal on so(3), in closed form.\n\n"
    "The displayed decay ||N||^2 ||x_0|| sin(phi_T), with the displayed phase\n"
    "tan(phi_T / 2) = tan(phi_0 / 2) exp(-||x_0|| ||N|| T): x(T) is the double bracket flow.",
    claims=("S15",),
)


@S15.check(Level.SYMBOLIC_FIXED_N, form="corrected")
def s15_decay_exact_so3() -> sp.Expr:
    """so(3), N = s hat(e3), x = r (sin phi e1 - cos phi e3) written in tau = tan(phi/2): with
    tau(T) from the displayed phase, dtau/dT = -||x_0|| ||N|| tau, dx/dT equals the emitted double
    bracket field, the squared displayed ||[N, [N, x]]|| equals the square of the displayed decay,
    and the decay divided by tau tends to 2 s^2 r as tau tends to 0: it vanishes like
    exp(-||x_0|| ||N|| T) (exact rational functions of tau)."""
    tau_T = _phase_tau()
    rate = sp.simplify(sp.diff(tau_T, T) / tau_T)  # -r s
    sin_t, cos_t = half_angle(_tau)
    x_tau = hat3([_r * sin_t, 0, -_r * cos_t])
    Nm = hat3([0, 0, _s])
    field = explicit(DOUBLE_BRACKET_RHS["xdot"], {"x": x_tau, "N": Nm})
    r = rational_residual(sp.diff(x_tau, _tau) * rate * _tau - field)
    env = {"x_T": x_tau, "N": Nm, "x_0": hat3([0, 0, _r])}  # only ||x_0|| = r enters the decay
    lhs = explicit(plain(DECAY.lhs**2), env)
    rhs_sq = explicit(plain(DECAY.rhs**2), env).subs(sp.sin(_phi_T), sin_t)
    r += rational_residual(lhs - rhs_sq)
    decay = _s**2 * _r * sin_t  # the displayed decay: its square is rhs_sq, and it is positive
    r += rational_residual(decay**2 - rhs_sq)
    limit = sp.cancel(decay / _tau).subs(_tau, 0)
    r += rational_residual(rate + _r * _s) + rational_residual(limit - 2 * _s**2 * _r)
    # the emitted closed form is this decay at tau = tau(T) of the displayed phase
    emitted = ONE_SAMPLE_SECOND_TERM["second_term"]
    r += rational_residual(sp.simplify(emitted - decay.subs(_tau, tau_T)))
    return r


@S15.check(Level.FLOAT64, tol=1e-6, form="corrected")
def s15_one_sample_bvp() -> float:
    """One sample on so(3), T = 1, 2, 4, 8, 16: symrb.solve_orbit_bvp from the guess p = 0 against
    the exact solution (p = -N, x the double bracket flow in closed form from the displayed
    phase): max of |x_T - exact| / ||x_0||, |p + N| / ||N|| over the mesh and the difference of
    ||[N, [N, x_T]]|| from the emitted closed form (symrb.one_sample_second_term) relative to
    ||N||^2 ||x_0||."""
    import symrb

    x0, N_ = one_sample_data()
    r, s = np.sqrt(np_norm2(x0)), np.sqrt(np_norm2(N_))
    xs = exact_so3(
        x0,
        N_,
        np.array(ONE_SAMPLE_HORIZONS),
        sp.lambdify((_r, _s, _tau0, T), _phase_tau(), "numpy"),
    )
    decay = symrb.one_sample_second_term(x0, N_, ONE_SAMPLE_HORIZONS)
    errs = []
    for i, Tk in enumerate(ONE_SAMPLE_HORIZONS):
        res = one_sample_runs()[Tk]
        if not res.success:
            return float("inf")
        xT = res.x[-1, 0]
        errs += [
            np.max(np.abs(xT - xs[i])) / r,
            np.max(np.abs(res.p + N_)) / s,
            abs(second_term_norm(xT, N_) - decay[i]) / (s**2 * r),
        ]
    return float(np.max(errs))


# --- two samples: the lower bound ---------------------------------------------------------------


@S15.check(Level.SYMBOLIC_FIXED_N, form="corrected")
def s15_bound_so3() -> sp.Expr:
    """so(3), x^a = r_a hat(a_a) with a_1, a_2 at the angles +h and -h from e1 (0 < 2h <= pi/2),
    N = s hat(c), c a unit vector: the displayed cos beta is cos 2h, and the mean over a of the
    squared displayed ||[N, [N, x^a]]|| / (s^2 r_a)^2 minus the squared displayed bound at unit
    norms equals c_2^2 cos 2h + c_3^2 cos^2 h >= 0, so the larger of the two exceeds the bound
    (polynomials in C = cos h, S = sin h and c reduced by C^2 + S^2 = 1 and |c| = 1)."""
    C, S, r1, r2 = sp.symbols("C S r_1 r_2", positive=True)
    c1, c2, c3 = sp.symbols("c1:4", real=True)
    a1, a2 = [C, S, 0], [C, -S, 0]
    env = {
        "x^1_0": r1 * hat3(a1),
        "x^2_0": r2 * hat3(a2),
        "x^1_T": r1 * hat3(a1),
        "x^2_T": r2 * hat3(a2),
        "N": _s * hat3([c1, c2, c3]),
    }

    def reduce(e: sp.Expr) -> sp.Expr:
        """Numerator of e on C^2 + S^2 = 1, |c| = 1 (even powers of S and c3 only)."""
        num, den = sp.fraction(sp.together(e))
        on = {S**2: 1 - C**2, c3**2: 1 - c1**2 - c2**2}
        return sp.expand(sp.expand(num).subs(on)) / sp.expand(sp.expand(den).subs(on))

    cos_2h = C**2 - S**2
    cos_beta = explicit(plain(BETA.rhs), env)
    r = rational_residual(reduce(cos_beta**2 - cos_2h**2))  # |.| squared; cos 2h >= 0
    mean = sp.Integer(0)
    for term in BOUND.lhs.args:  # ||[N, [N, x^a_T]]|| for a = 1, 2 (in Max's order)
        rk = r1 if x1T in term.atoms(sp.MatrixSymbol) else r2
        mean += explicit(plain(term**2), env) / (_s**2 * rk) ** 2 / 2
    unit_norms = {**env, "x^1_0": hat3(a1), "x^2_0": hat3(a2), "N": hat3([c1, c2, c3])}
    bound_unit = explicit(plain(BOUND.rhs), unit_norms).subs(sp.sin(_beta / 2), S)
    claimed = c2**2 * cos_2h + c3**2 * C**2
    return r + rational_residual(reduce(mean - bound_unit**2 - claimed))


_r1, _r2 = sp.symbols("r_1 r_2", positive=True)
_p12 = sp.Symbol("p_12", real=True)


def _bound_closed_form() -> sp.Expr:
    """The displayed bound ||N||^2 min_a ||x^a_0|| sin(beta / 2) with the displayed beta, in the
    norms r_1, r_2, s and the pairing p_12 = <x^1_0, x^2_0>."""
    norms = {_Norm(x10): _r1, _Norm(x20): _r2}
    cos_beta = BETA.rhs.xreplace({**norms, sp.Abs(Pair(x10, x20)): sp.Abs(_p12)})
    return BOUND.rhs.xreplace({**norms, _Norm(N): _s}).subs(_beta, sp.acos(cos_beta))


TWO_SAMPLE_BOUND = Kernel(
    name="two_sample_bound",
    target="adjoint_orbits",
    args=[
        Arg("r_1", "(...)", "||x^1_0||"),
        Arg("r_2", "(...)", "||x^2_0||"),
        Arg("s", "(...)", "||N||"),
        Arg("p_12", "(...)", "<x^1_0, x^2_0>, at most r_1 r_2 in size"),
    ],
    outputs={"bound": _bound_closed_form()},
    doc="The lower bound of the larger second costate term of two samples on so(3).\n\n"
    "||N||^2 min(||x^1_0||, ||x^2_0||) sin(beta / 2), cos beta = |<x^1_0, x^2_0>| /\n"
    "(||x^1_0|| ||x^2_0||): the displayed bound of the corrected statement.",
    claims=("S15",),
)


@functools.cache
def two_sample_table() -> tuple[dict[str, float], ...]:
    """For each horizon: the displayed max_a ||[N, [N, x^a_T]]|| of the BVP solution, the
    displayed bound, and the drifts of <x^1, x^2> and ||x^a|| relative to their sizes."""
    X0, N_ = two_sample_data()
    env0 = {"x^1_0": X0[0], "x^2_0": X0[1], "N": N_}
    beta = float(np.arccos(numeric(BETA.rhs, env0)))
    bound = numeric(BOUND.rhs.subs(_beta, beta), env0)
    rows = []
    for Tk, res in two_sample_runs().items():
        if not res.success:
            rows.append({"T": Tk, "second": float("nan"), "bound": bound, "drift": float("inf")})
            continue
        xT = res.x[-1]
        second = numeric(BOUND.lhs, {"x^1_T": xT[0], "x^2_T": xT[1], "N": N_})
        size = np.sqrt(np_norm2(X0))
        drift = [
            abs(np_pair(xT[0], xT[1]) - np_pair(X0[0], X0[1])) / (size[0] * size[1]),
            *np.abs(np.sqrt(np_norm2(xT)) - size) / size,
        ]
        rows.append({"T": Tk, "second": second, "bound": bound, "drift": float(np.max(drift))})
    return tuple(rows)


@S15.check(Level.FLOAT64, tol=1e-3, form="printed")
def s15_two_samples_second_term() -> float:
    """Two samples on so(3) sharing the control, symrb.solve_orbit_bvp at T = 2, 4, 8: the
    smallest over T of the displayed max_a ||[N, [N, x^a_T]]|| relative to its largest possible
    value ||N||^2 max_a ||x^a_0|| (the printed claim: it goes to zero)."""
    X0, N_ = two_sample_data()
    size = np_norm2(N_) * np.max(np.sqrt(np_norm2(X0)))
    return float(np.min([row["second"] for row in two_sample_table()]) / size)


@S15.check(Level.FLOAT64, tol=1e-5, form="corrected")
def s15_two_samples_above_bound() -> float:
    """The same solutions stay above the bound and conserve <x^1, x^2> and ||x^a||: max over T of
    the relative shortfall below symrb.two_sample_bound (the emitted kernel) plus the relative
    drift of the invariants, plus the relative difference of that bound (and of the emitted
    expression) from the displayed bound evaluated on the data."""
    import symrb

    rows = two_sample_table()
    second = np.array([row["second"] for row in rows])  # NaN for a failed solve: stays NaN
    displayed = rows[0]["bound"]
    X0, N_ = two_sample_data()
    shipped = float(symrb.two_sample_bound(X0, N_))  # the emitted kernel, through its wrapper
    norms = np.sqrt(np_norm2(X0))
    emitted = float(TWO_SAMPLE_BOUND["bound"].subs({  # the emitted expression, by SymPy
        _r1: norms[0], _r2: norms[1], _s: np.sqrt(np_norm2(N_)), _p12: np_pair(X0[0], X0[1]),
    }))  # fmt: skip
    shortfall = np.maximum(shipped - second, 0.0) / shipped
    agree = max(abs(shipped - displayed), abs(emitted - displayed)) / displayed
    return float(np.max(shortfall + np.array([row["drift"] for row in rows])) + agree)
