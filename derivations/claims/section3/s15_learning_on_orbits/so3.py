"""S15 on so(3): the evidence on so(3) and the closed forms it ships.

The endpoint condition judged by the adjoint derivative of the cost against central differences;
one sample, whose second costate term decays like exp(-||x_0|| ||N|| T) (the displayed decay and
phase, checked exactly and against symrb.solve_orbit_bvp); two samples, whose shared control
keeps the second term above the displayed bound for every T.  The claim, its formulas and its
evidence for every n are in :mod:`derivations.claims.section3.s15_learning_on_orbits`; the
computations that do not read the displayed formulas (data, boundary value problem runs, the
adjoint derivative) are in :mod:`derivations.claims.section3._orbit_learning`.

Emitted to ``symrb/_generated/adjoint_orbits.py``: ``one_sample_second_term`` and
``two_sample_bound``.
"""

from __future__ import annotations

import functools

import numpy as np
import sympy as sp

from derivations.claims.section3._display import _Norm
from derivations.claims.section3._orbit_learning import (
    ONE_SAMPLE_HORIZONS,
    endpoint_gradient,
    exact_so3,
    half_angle,
    numeric,
    one_sample_data,
    one_sample_runs,
    rational_residual,
    second_term_norm,
    two_sample_data,
    two_sample_runs,
)
from derivations.claims.section3._orbits import (
    N,
    T,
    np_norm2,
    np_pair,
    plain,
)
from derivations.claims.section3.s14_brockett_toda import (
    DOUBLE_BRACKET_RHS,
)
from derivations.claims.section3.s15_learning_on_orbits import (
    BETA,
    BOUND,
    DECAY,
    ENDPOINT,
    GRAD_PHI,
    PHASE,
    S15,
    _beta,
    _phi_0,
    _phi_T,
    s15_corrected_endpoint,
    s15_corrected_equations,
    s15_emitted_shared_field,
    s15_one_sample_exact,
    s15_printed_endpoint,
    s15_printed_equations,
    s15_shared_control_invariant,
    x1T,
    x10,
    x20,
    x_0,
)
from derivations.registry import Level
from derivations.symbolic import Pair, explicit, hat3
from derivations.vocabulary import Arg, Kernel


def _endpoint_gradient(form: str) -> float:
    """The adjoint derivative of the cost from p^a_T of the displayed endpoint condition of
    ``form`` (the gradient of phi replaced by N) against central differences."""
    return endpoint_gradient(ENDPOINT[form].rhs.xreplace({GRAD_PHI: N}))


@S15.check(Level.FLOAT64, tol=1e-6, form="printed")
def s15_printed_endpoint_gradient() -> float:
    r"""The adjoint directional derivative of the cost with the printed $p_T$ ($\mathfrak{so}(3)$,
    two samples, $T = 1$, Brockett's $V$ from symrb.orbits.brockett_potential, emitted state-costate
    field) against central differences of the cost: relative difference (must be large)."""
    return _endpoint_gradient("printed")


@S15.check(Level.FLOAT64, tol=1e-6, form="corrected")
def s15_corrected_endpoint_gradient() -> float:
    """The same with the corrected $p_T$: the adjoint directional derivative of the cost equals the
    central differences (relative difference)."""
    return _endpoint_gradient("corrected")


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
    r"""$\mathfrak{so}(3)$, $N = s \hat e_3$, $x = r (\sin \phi\, e_1 - \cos \phi\, e_3)$ written in
    $\tau = \tan(\phi/2)$: with $\tau(T)$ from the displayed phase, $d\tau/dT = -\|x_0\| \|N\|
    \tau$, $dx/dT$ equals the emitted double bracket field, the squared displayed $\|[N, [N, x]]\|$
    equals the square of the displayed decay, and the decay divided by $\tau$ tends to $2 s^2 r$ as
    $\tau$ tends to 0: it vanishes like $\exp(-\|x_0\| \|N\| T)$ (exact rational functions of
    $\tau$)."""
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
    r"""One sample on $\mathfrak{so}(3)$, $T = 1, 2, 4, 8, 16$: symrb.solve_orbit_bvp from the guess
    $p = 0$ against the exact solution ($p = -N$, $x$ the double bracket flow in closed form from
    the displayed phase): max of $|x_T - x_T^{\mathrm{exact}}| / \|x_0\|$, $|p + N| / \|N\|$ over
    the mesh and the difference of $\|[N, [N, x_T]]\|$ from the emitted closed form
    (symrb.orbits.one_sample_second_term) relative to $\|N\|^2 \|x_0\|$."""
    import symrb

    x0, N_ = one_sample_data()
    r, s = np.sqrt(np_norm2(x0)), np.sqrt(np_norm2(N_))
    xs = exact_so3(
        x0,
        N_,
        np.array(ONE_SAMPLE_HORIZONS),
        sp.lambdify((_r, _s, _tau0, T), _phase_tau(), "numpy"),
    )
    decay = symrb.orbits.one_sample_second_term(x0, N_, ONE_SAMPLE_HORIZONS)
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
    r"""$\mathfrak{so}(3)$, $x^a = r_a \hat a_a$ with $a_1$, $a_2$ at the angles $+h$ and $-h$ from
    $e_1$ ($0 < 2h \le \pi/2$), $N = s \hat c$, $c$ a unit vector: the displayed $\cos \beta$ is
    $\cos 2h$, and the mean over $a$ of the squared displayed $\|[N, [N, x^a]]\| / (s^2 r_a)^2$
    minus the squared displayed bound at unit norms equals $c_2^2 \cos 2h + c_3^2 \cos^2 h \ge 0$,
    so the larger of the two exceeds the bound (polynomials in $C = \cos h$, $S = \sin h$ and $c$
    reduced by $C^2 + S^2 = 1$ and $|c| = 1$)."""
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
    r"""Two samples on $\mathfrak{so}(3)$ sharing the control, symrb.solve_orbit_bvp at $T = 2, 4,
    8$: the smallest over $T$ of the displayed $\max_a \|[N, [N, x^a_T]]\|$ relative to its largest
    possible value $\|N\|^2 \max_a \|x^a_0\|$ (the printed claim: it goes to zero)."""
    X0, N_ = two_sample_data()
    size = np_norm2(N_) * np.max(np.sqrt(np_norm2(X0)))
    return float(np.min([row["second"] for row in two_sample_table()]) / size)


@S15.check(Level.FLOAT64, tol=1e-5, form="corrected")
def s15_two_samples_above_bound() -> float:
    r"""The same solutions stay above the bound and conserve $\langle x^1, x^2\rangle$ and
    $\|x^a\|$: max over $T$ of the relative shortfall below symrb.orbits.two_sample_bound (the
    emitted kernel) plus the relative drift of the invariants, plus the relative difference of that
    bound (and of the emitted expression) from the displayed bound evaluated on the data."""
    import symrb

    rows = two_sample_table()
    second = np.array([row["second"] for row in rows])  # NaN for a failed solve: stays NaN
    displayed = rows[0]["bound"]
    X0, N_ = two_sample_data()
    shipped = float(
        symrb.orbits.two_sample_bound(X0, N_)
    )  # the emitted kernel, through its wrapper
    norms = np.sqrt(np_norm2(X0))
    emitted = float(TWO_SAMPLE_BOUND["bound"].subs({  # the emitted expression, by SymPy
        _r1: norms[0], _r2: norms[1], _s: np.sqrt(np_norm2(N_)), _p12: np_pair(X0[0], X0[1]),
    }))  # fmt: skip
    shortfall = np.maximum(shipped - second, 0.0) / shipped
    agree = max(abs(shipped - displayed), abs(emitted - displayed)) / displayed
    return float(np.max(shortfall + np.array([row["drift"] for row in rows])) + agree)


# the paper's sentences (here, below the last of S15's evidence in this package)
S15.sentence(
    r"The smooth machine learning version of this problem considers for smooth functions "
    r"$\phi^a:\mathbb{R}\times\mathbb{R}\rightarrow\mathbb{R}^+$, $a=1,\dots, M$ $\eta(x,u)="
    r"\tfrac{1}{2} \int_0^{T}\|u\|^2-V(x)dt +\sum_{a=1}^M\phi(x^a_T)$ with $\dot{x^a}=[x^a,u],"
    r"\,a=1\dots M$",
    s15_corrected_endpoint,
    s15_emitted_shared_field,
    s15_printed_endpoint_gradient,
    s15_corrected_endpoint_gradient,
)
S15.sentence(r"As before we now have", kind="prose", reason="introduces the corollary")
S15.sentence(
    r"The equations of the maximum principle for the variational problem subject to equations "
    r"(orb) with $V(x)=-1/2||[x,n]||^2$ are $\begin{aligned} \dot x^a &= [x^a,[p^a,x^a]] \\ "
    r"\dot p^a &= [p^a,[p^a,x]]-[n,[n,x^a]]\,. \end{aligned}$ with $p^a_T=\frac{\partial"
    r"\phi(x^a_T)}{\partial x^a_T}$",
    s15_printed_equations,
    s15_corrected_equations,
    s15_printed_endpoint,
    s15_corrected_endpoint,
    s15_emitted_shared_field,
    s15_printed_endpoint_gradient,
    s15_corrected_endpoint_gradient,
)
S15.sentence(
    r"In particular we would like to consider $\phi(x^a_T)=< x^a_T,n >$.",
    s15_one_sample_exact,
    s15_one_sample_bvp,
    s15_two_samples_above_bound,
)
S15.sentence(
    r"Then we can see the final solution tends to the double bracket equation $\dot{x}=[x,[x,n]]$ "
    r"and the second term in the costate equation goes to zero.",
    s15_one_sample_exact,
    s15_decay_exact_so3,
    s15_one_sample_bvp,
    s15_shared_control_invariant,
    s15_bound_so3,
    s15_two_samples_second_term,
    s15_two_samples_above_bound,
)
S15.sentence(
    r"One can then write a discrete version of these equations using an appropriate discrete "
    r"algorithm and following our formalism above.",
    kind="prose",
    reason="points to future work",
)
S15.sentence(r"This will be considered in future work.", kind="prose", reason="future work")
