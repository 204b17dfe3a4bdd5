r"""D1: the discrete maximum principle with fixed endpoints (paper, Section 2).

Where: Section 2, the first definition (prob8.1: minimise the running cost subject to the
dynamics, with :math:`x_0`, :math:`x_N` given and the constraint :math:`h(u_k) = 0`) and the first
proposition (gendiscprop, eq8.3-eq8.6: the extremal equations of :math:`H` and :math:`\hat H`),
with its proof.

The claim: a solution satisfies the extremal equations, the critical points of an augmented
functional :math:`V`.  Recorded outcome: holds after correction.  The costate equation holds for
:math:`1 \le k \le N-1` only (:math:`p_N` is free for a fixed endpoint), :math:`V` needs one
multiplier :math:`\sigma_k` per step, the proof's rewriting of :math:`V` with the sum up to
:math:`N` adds :math:`\hat H(0, x_N, u_N, \sigma)`, and the rule with cost multiplier one needs
regular constraints at the solution (an exact abnormal example shows it).

Evidence, from the displayed formulas only (independent of symrb): the derivatives of the
displayed :math:`V` with undefined :math:`f, g, h` are the displayed equations; exact examples at
their exact minimisers separate the printed forms from the corrected ones.
"""

from __future__ import annotations

from typing import Any

import sympy as sp

from derivations.claims.section2._any_dimension import DIMS, Evaluator, gradient, minus
from derivations.claims.section2._any_dimension import nonzero as any_nonzero
from derivations.claims.section2._hamiltonians import (
    _C,
    _H,
    _V,
    H_DEF,
    HHAT_DEF,
    _f,
    _g,
    _generic,
    _h,
    _Hhat,
    _p,
    _sig,
    _sigma1,
    _u,
    _with_hamiltonians,
    _x,
)
from derivations.claims.section2._indexed import (
    _N,
    _N1,
    _coverage_defect,
    _Dot,
    _grad,
    _instance,
    _k,
    _k1,
    _key,
    _least_squares_residual,
    _minus,
    _Nm1,
    _nonzero,
    _plus,
    _Steps,
    _substituted,
    _value,
    _vec,
)
from derivations.registry import Level, claim
from derivations.symbolic import eq

D1 = claim(
    "D1",
    label="prob8.1, gendiscprop, eq8.3-eq8.6",
    title="Discrete maximum principle (fixed endpoints, control constraint)",
    statement="The discrete maximum principle (the first proposition of Section 2): a solution of the problem of minimising [[cost]] subject to "
    "[[dynamics]], with $x_0$ and $x_N$ given, and [[constraint]] satisfies the extremal equations "
    "of [[H]] and [[Hhat]], the critical points of an augmented functional $V$.",
    printed="The costate equation is stated for every step up to $N$, [[costate_printed]], with "
    "[[terminal_printed]]; the proof's functional has one multiplier for all steps, "
    "[[V_printed]], and the proof rewrites it as [[rewrite_printed]]. The proposition asserts "
    "these equations, the cost entering with coefficient one, for every solution, with no "
    "hypothesis beyond $h$ being a submersion.",
    corrected="[[state]]; [[costate]] only (the equation at step 0 merely defines $p_0$, and $p_N$ "
    "is a free unknown fixed by the endpoint $x_N$); [[stationary]] with one multiplier $\\sigma_k$ "
    "per step. These are exactly the critical points of [[V]], which equals [[rewrite]]. They "
    "hold at a solution where the constraints are regular (normality): the Jacobian of the "
    "dynamics (with $x_0$ and $x_N$ fixed) and of $h$ in $(x_1, \\dots, x_{N-1}, u_0, \\dots, "
    "u_{N-1})$ has full row rank $N(n + l)$, that is, the linearised dynamics with controls "
    "tangent to $E$ reach every direction at $x_N$. Without it a solution is only a critical "
    "point of [[V_lambda]] for a cost multiplier $\\lambda_0$ equal to one or zero, the "
    "multipliers not all zero; with $\\lambda_0$ zero (abnormal) the cost drops out.",
    expected="holds after correction",
    headline="[[costate]], one multiplier $\\sigma_k$ per step",
    section="2",
    where="Section 2, the first definition (the problem with fixed endpoints $x_0$, $x_N$ and the "
    "constraint $h(u_k) = 0$) and the first proposition (the extremal equations with $H = "
    "\\langle p_{k+1}, f(x_k, u_k)\\rangle - g(x_k, u_k)$ and the multiplier $\\sigma$), with its "
    "proof",
    note="The costate equation is stated up to $k = N$, the proof uses one multiplier "
    "$\\sigma$ for all steps, and the multiplier rule is stated without the regularity "
    "(normality) it needs. Corrected: the costate equation holds for $1 \\le k \\le N-1$ only, "
    "$p_N$ is a free unknown, there is one multiplier $\\sigma_k$ per step, and the equations "
    "with cost multiplier one hold where the constraint Jacobian has full row rank (otherwise "
    "with cost multiplier zero). The structure of the principle is right, but four details are "
    "not. (i) The costate equation at $k = N$ with "
    "$p_{N+1} = 0$ would force $p_N = -\\partial g/\\partial x(x_N, u_N)$ for a phantom control "
    "$u_N$; for a fixed endpoint $p_N$ is free (exact example $f = x + u$, $g = u^2/2$, $x_0 = "
    "0$, $x_2 = 1$: $p_2 = 1/2$ while the printed equation gives $0$). (ii) The proof's $V$ needs "
    "one multiplier per step (the proposition's $\\sigma = \\sigma(p_{k+1}, x_k)$ already allows "
    "that; $V$ does not): in an exact example the minimiser has $\\sigma_0 = -3/7$, $\\sigma_1 = "
    "-1/7$, and with one shared $\\sigma$ the stationarity equations at the minimiser have no "
    "solution. (iii) The proof's rewriting with the sum up to $N$ adds $\\hat H(0, x_N, u_N, "
    "\\sigma) = -g(x_N, u_N) + \\langle \\sigma, h(u_N)\\rangle$. (iv) That $h$ is a "
    "submersion makes the control constraint regular, but the fixed endpoint can be reached "
    "degenerately: with $f = x + (u_1 + u_2)^2$, $g = ((u_1 - 1)^2 + u_2^2)/2$, $h = u_1 - u_2$, "
    "$x_0 = x_2 = 0$ the only admissible control is $u_k = 0$, where stationarity in $u_k$ "
    "demands $\\sigma_k = -1$ and $\\sigma_k = 0$ at once (least-squares residual 1); the "
    "constraint Jacobian has rank 3 of 4, and $\\lambda_0 = 0$, $p_1 = p_2 = 1$, $\\sigma_k = 0$ "
    "is an abnormal multiplier. With $x_2 = 8$ (minimiser $u_k = (1, 1)$, rank 4 of 4) the normal "
    "multipliers are $p_1 = p_2 = 1/8$, $\\sigma_k = -1/2$. An all-dimension symbolic check "
    "(matrix symbols of sizes $n, m, l$) derives the extremal equations from $V$.",
)
COST = D1.formula("cost", eq(_C, sp.Sum(_g(_x[_k], _u[_k]), (_k, 0, _Nm1))))
DYNAMICS = D1.formula("dynamics", _Steps([eq(_x[_k1], _f(_x[_k], _u[_k]))], _k, 0, _Nm1))
CONSTRAINT = D1.formula("constraint", _Steps([eq(_h(_u[_k]), 0)], _k, 0, _Nm1))
D1.formula("H", H_DEF)
D1.formula("Hhat", HHAT_DEF)
_H_k = _H(_p[_k1], _x[_k], _u[_k])
STATE = D1.formula("state", _Steps([eq(_x[_k1], sp.Derivative(_H_k, _p[_k1]))], _k, 0, _Nm1))
_COSTATE_EQ = eq(_p[_k], sp.Derivative(_H_k, _x[_k]))
COSTATE = D1.formula("costate", _Steps([_COSTATE_EQ], _k, 1, _Nm1))
COSTATE_PRINTED = D1.formula("costate_printed", _Steps([_COSTATE_EQ], _k, 0, _N))
TERMINAL_PRINTED = D1.formula("terminal_printed", eq(_p[_N1], 0))
STATIONARY = D1.formula(
    "stationary",
    _Steps([eq(sp.Derivative(_Hhat(_p[_k1], _x[_k], _u[_k], _sig[_k]), _u[_k]), 0)], _k, 0, _Nm1),
)


def _functional(multiplier: sp.Basic, cost: sp.Expr = sp.S.NegativeOne) -> sp.Sum:
    term = _plus(
        _Dot(_p[_k1], _plus(_f(_x[_k], _u[_k]), -_x[_k1])),
        _Dot(multiplier, _h(_u[_k])),
        cost * _g(_x[_k], _u[_k]),
    )
    return sp.Sum(term, (_k, 0, _Nm1))


V_DEF = D1.formula("V", eq(_V, _functional(_sig[_k])))
V_PRINTED = D1.formula("V_printed", eq(_V, _functional(_sigma1)))
#: the functional with a cost multiplier lambda_0 (1: the printed normal form; 0: abnormal)
_lam0 = sp.Symbol(r"\lambda_0", nonnegative=True)
V_LAMBDA = D1.formula("V_lambda", eq(_V, _functional(_sig[_k], -_lam0)))


def _rewrite(multiplier: sp.Basic, last: sp.Expr) -> sp.Expr:
    term = _plus(-_Dot(_p[_k], _x[_k]), _Hhat(_p[_k1], _x[_k], _u[_k], multiplier))
    return _plus(_Dot(_p[0], _x[0]), sp.Sum(term, (_k, 0, last)))


REWRITE = D1.formula("rewrite", eq(_V, _plus(_rewrite(_sig[_k], _Nm1), -_Dot(_p[_N], _x[_N]))))
REWRITE_PRINTED = D1.formula("rewrite_printed", eq(_V, _rewrite(_sigma1, _N)))


def _d1_variables(N: int, nx: int, nu: int, nl: int, phantom: bool = False) -> dict[Any, Any]:
    """Symbolic vectors x_0..x_N, u_k, p_0..p_{N+1}, sigma_k and one sigma (u_N with phantom)."""
    values: dict[Any, Any] = {"N": N, "sigma": _vec("s", nl)}
    for k in range(N + 2):
        values[("p", k)] = _vec(f"p{k}", nx)
    for k in range(N + 1):
        values[("x", k)] = _vec(f"x{k}", nx)
    for k in range(N + 1 if phantom else N):
        values[("u", k)] = _vec(f"u{k}", nu)
        values[(r"\sigma", k)] = _vec(f"s{k}", nl)
    return values


@D1.check(Level.SYMBOLIC_FIXED_N, form="corrected")
def d1_stationarity() -> sp.Expr:
    r"""The derivatives of the displayed $V$ (one multiplier per step, $x_0$ and $x_N$ fixed) in
    $p_{k+1}$, $x_k$, $u_k$ and $\sigma_k$ are the displayed state, costate, stationarity and
    constraint equations over their displayed ranges, and these cover every variable of $V$ once
    (undefined $f$, $g$, $h$; $n = m = 2$, $l = 1$, $N = 3$)."""
    N = 3
    values = _d1_variables(N, 2, 2, 1)
    fn = _with_hamiltonians(_generic(2, 2, 1))
    V = _value(V_DEF.rhs, values, fn)
    total = sp.Integer(0)
    covered = []
    # dV/dvar is rhs - lhs of "x_{k+1} = dH/dp" and lhs - rhs of "dHhat/du = 0"
    for steps, var, sign in ((STATE, _p[_k + 1], -1), (COSTATE, _x[_k], -1),
                             (STATIONARY, _u[_k], 1), (CONSTRAINT, _sig[_k], 1)):  # fmt: skip
        for k in steps.steps(N):
            lhs, rhs = steps.at(k)
            key = _key(var.xreplace({_k: k}))
            covered.append(key)
            side = _minus(_value(lhs, values, fn), _value(rhs, values, fn))
            total += _nonzero(_minus(_grad(V, values[key]), sign * side))
    fixed = {("x", 0), ("x", N)}
    total += _coverage_defect(V, values, fixed, covered)
    return total


def _d1_costate_range_defect(costate: _Steps) -> sp.Expr:
    """Minimise u_0^2/2 + u_1^2/2 with x_{k+1} = x_k + u_k, x_0 = 0, x_2 = 1 (n = m = 1); take
    p_1, p_2 from the displayed stationarity conditions at the minimiser and p_3 from the printed
    terminal convention; return sum |lhs - rhs| of the costate equation over its displayed steps
    k >= 1 (p_0 does not occur in V: the equation at k = 0 defines it)."""
    N, v, uN = 2, sp.Symbol("v"), sp.Symbol("u_N")
    fn = _with_hamiltonians(
        {"f": lambda x, u: x + u, "g": lambda x, u: u[0] ** 2 / 2, "h": lambda u: sp.zeros(1, 1)}
    )
    values: dict[Any, Any] = {"N": N, ("x", 0): sp.Matrix([0])}
    values.update(
        {("u", 0): sp.Matrix([v]), ("u", 1): sp.Matrix([1 - v]), ("u", N): sp.Matrix([uN])}
    )
    for k in DYNAMICS.steps(N):
        lhs, rhs = DYNAMICS.at(k)
        values[_key(lhs)] = _value(rhs, values, fn)
    best = sp.solve(sp.diff(_value(COST.rhs, values, fn), v), v)[0]
    values = _substituted(values, {v: best})
    ps = sp.symbols("P1:3")
    values.update({("p", k + 1): sp.Matrix([ps[k]]) for k in range(N)})
    values.update({(r"\sigma", k): sp.zeros(1, 1) for k in range(N)})
    eqs = []
    for k in STATIONARY.steps(N):
        lhs, rhs = STATIONARY.at(k)
        eqs += list(_value(lhs, values, fn) - sp.Matrix([_value(rhs, values, fn)]))
    sol = sp.solve(eqs, ps, dict=True)[0]
    values.update({("p", k + 1): sp.Matrix([sol[ps[k]]]) for k in range(N)})
    lhs, rhs = _instance(TERMINAL_PRINTED, {_N: N})
    values[_key(lhs)] = sp.Matrix([_value(rhs, values, fn)])
    total = sp.Integer(0)
    for k in costate.steps(N):
        if k >= 1:
            lhs, rhs = costate.at(k)
            total += sum(abs(e) for e in _value(lhs, values, fn) - _value(rhs, values, fn))
    return sp.nsimplify(total)


@D1.check(Level.EXACT_RATIONAL, form="printed")
def d1_printed_costate_at_N() -> sp.Expr:
    r"""$f = x + u$, $g = u^2/2$, $x_0 = 0$, $x_2 = 1$ ($n = m = 1$): at the exact minimiser, with
    $p_1$, $p_2$ from the stationarity conditions, the printed costate equation over its range up to
    $N$ (with $p_3 = 0$ and a phantom $u_2$) is off by $|p_2 - \partial H/\partial x(0, x_2, u_2)| =
    1/2$."""
    return _d1_costate_range_defect(COSTATE_PRINTED)


@D1.check(Level.EXACT_RATIONAL, form="corrected")
def d1_corrected_costate_range() -> sp.Expr:
    r"""The same computation with the corrected range $1 \le k \le N-1$: the costate equation holds
    at the minimiser."""
    return _d1_costate_range_defect(COSTATE)


def _d1_multiplier_defect(functional: sp.Eq) -> sp.Expr:
    """f = x + u_1, g = (u_1^2 + (u_2 - x)^2)/2, h = u_1 - u_2, N = 2, x_0 = 0, x_2 = 1 (n = 1,
    m = 2, l = 1).  At the exact minimiser (from the displayed cost, dynamics and constraint), the
    derivatives of the given V in x_1, u_0, u_1 are linear in the costates and multipliers;
    returns the least-squares residual of that linear system (0 exactly when multipliers exist)."""
    N = 2
    fn = _with_hamiltonians({
        "f": lambda x, u: x + sp.Matrix([u[0]]),
        "g": lambda x, u: (u[0] ** 2 + (u[1] - x[0]) ** 2) / 2,
        "h": lambda u: sp.Matrix([u[0] - u[1]]),
    })  # fmt: skip
    values = _d1_variables(N, 1, 2, 1)
    values[("x", 0)], values[("x", 2)] = sp.Matrix([0]), sp.Matrix([1])
    # the minimiser: u_k on h(u_k) = 0, v_0 + v_1 fixed by x_2 = 1
    v = sp.Symbol("v")
    point = dict(values)
    for k, vk in enumerate((v, 1 - v)):
        w = sp.Symbol("w")
        point[("u", k)] = sp.Matrix([vk, w])
        lhs, _rhs = CONSTRAINT.at(k)
        point[("u", k)] = point[("u", k)].subs(w, sp.solve(_value(lhs, point, fn)[0], w)[0])
    point[("x", 1)] = _value(DYNAMICS.at(0)[1], point, fn)
    best = sp.solve(sp.diff(_value(COST.rhs, point, fn), v), v)[0]
    at_min = {values[key][i]: point[key][i].subs(v, best)
              for key in (("x", 1), ("u", 0), ("u", 1)) for i in range(values[key].rows)}  # fmt: skip
    V = _value(functional.rhs, values, fn)
    eqs = []
    for key in (("x", 1), ("u", 0), ("u", 1)):
        eqs += [e.xreplace(at_min) for e in _grad(V, values[key])]
    unknowns = sorted({s for e in eqs for s in e.free_symbols}, key=str)
    return _least_squares_residual(eqs, unknowns)


@D1.check(Level.EXACT_RATIONAL, form="printed")
def d1_printed_single_multiplier() -> sp.Expr:
    r"""$f = x + u_1$, $g = (u_1^2 + (u_2 - x)^2)/2$, $h = u_1 - u_2$, $N = 2$, $x_0 = 0$, $x_2 =
    1$: at the exact minimiser, the stationarity equations of the printed $V$ (one $\sigma$) in
    $x_1$, $u_0$, $u_1$ have no solution for $(p_1, p_2, \sigma)$: least-squares residual of that
    linear system."""
    return _d1_multiplier_defect(V_PRINTED)


@D1.check(Level.EXACT_RATIONAL, form="corrected")
def d1_corrected_multipliers() -> sp.Expr:
    r"""The same with the corrected $V$ ($\sigma_k$ per step): the linear system for $(p_1, p_2,
    \sigma_0, \sigma_1)$ is solvable at the minimiser (residual 0)."""
    return _d1_multiplier_defect(V_DEF)


def _d1_rewrite_defect(functional: sp.Eq, rewrite: sp.Eq) -> sp.Expr:
    """The displayed functional minus its displayed rewrite, for undefined f, g, h, N = 2,
    n = m = 2, l = 1 (p_{N+1} and a phantom u_N from the printed terminal convention)."""
    N = 2
    values = _d1_variables(N, 2, 2, 1, phantom=True)
    fn = _with_hamiltonians(_generic(2, 2, 1))
    lhs, rhs = _instance(TERMINAL_PRINTED, {_N: N})
    values[_key(lhs)] = _value(rhs, values, fn) * sp.ones(2, 1)
    return _nonzero(_value(functional.rhs, values, fn) - _value(rewrite.rhs, values, fn))


@D1.check(Level.SYMBOLIC_FIXED_N, form="printed")
def d1_printed_rewrite() -> sp.Expr:
    r"""The printed $V$ minus the proof's rewrite with the sum up to $N$ and $p_{N+1} = 0$ does not
    vanish: it is $-\hat H(0, x_N, u_N, \sigma)$ (undefined $f$, $g$, $h$, $N = 2$)."""
    return _d1_rewrite_defect(V_PRINTED, REWRITE_PRINTED)


@D1.check(Level.SYMBOLIC_FIXED_N, form="corrected")
def d1_corrected_rewrite() -> sp.Expr:
    r"""The corrected $V$ minus the corrected rewrite (sum up to $N-1$, minus $\langle p_N,
    x_N\rangle$) vanishes identically (undefined $f$, $g$, $h$, $N = 2$)."""
    return _d1_rewrite_defect(V_DEF, REWRITE)


def d1_any_dimension_defect(v_formula: sp.Eq, N: int = 3) -> int:
    """Number of displayed equations (state, costate, stationarity, constraint over their displayed
    ranges) that differ from the gradient of the first variation of the given V in their variable,
    plus the coverage defect, with x_k, p_k of size n, u_k of size m, sigma_k of size l (symbols)
    and undefined f, g, h."""
    n, m, l = DIMS
    columns = {("x", k): sp.MatrixSymbol(f"x_{k}", n, 1) for k in range(N + 1)}
    columns.update({("p", k): sp.MatrixSymbol(f"p_{k}", n, 1) for k in range(1, N + 1)})
    columns.update({("u", k): sp.MatrixSymbol(f"u_{k}", m, 1) for k in range(N)})
    columns.update({(r"\sigma", k): sp.MatrixSymbol(f"sigma_{k}", l, 1) for k in range(N)})
    defined = {"H": H_DEF, r"\hat{H}": HHAT_DEF}
    ev = Evaluator(columns, {("x", 0), ("x", N)}, {"f": n, "g": 1, "h": l}, defined, {"N": N})
    _value_V, dV = ev(v_formula.rhs)
    total, covered = 0, []
    for steps, var, sign in ((STATE, _p[_k + 1], -1), (COSTATE, _x[_k], -1),
                             (STATIONARY, _u[_k], 1), (CONSTRAINT, _sig[_k], 1)):  # fmt: skip
        for k in steps.steps(N):
            key = _key(var.xreplace({_k: k}))
            covered.append(key)
            lhs, rhs = (ev(side)[0] for side in steps.at(k))
            total += any_nonzero(minus(gradient(dV, ev.deltas[key]), sign * minus(lhs, rhs)))
    variables = {key for key, d in ev.deltas.items() if ev.free(key) and dV.has(d)}
    return total + len(variables.symmetric_difference(covered)) + len(covered) - len(set(covered))


@D1.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def d1_extremals_any_dimension() -> int:
    r"""The displayed $V$ (one multiplier per step, $x_0$ and $x_N$ fixed) on columns of symbolic
    sizes $n$, $m$, $l$, undefined $f$, $g$, $h$ (Jacobians as matrix symbols): the gradients of its
    first variation in $p_{k+1}$, $x_k$, $u_k$ and $\sigma_k$ (SymPy matrix calculus) are the
    displayed state, costate, stationarity and constraint equations over their displayed ranges,
    each variable once ($N = 3$; every dimension)."""
    return d1_any_dimension_defect(V_DEF)


def _normality_example(endpoint: int) -> tuple[dict[str, Any], dict[Any, Any], dict[Any, Any]]:
    """f = x + (u_1 + u_2)^2, g = ((u_1 - 1)^2 + u_2^2)/2, h = u_1 - u_2 (a submersion), N = 2,
    n = 1, m = 2, l = 1, x_0 = 0 and x_2 = ``endpoint``.  Returns the functions, the symbolic
    values and the exact minimiser of the displayed cost under the displayed dynamics and
    constraint (as a substitution of x_1, u_0, u_1).  On h = 0 the controls are (v_k, v_k) and
    the endpoint condition reads c(v) = 0; the minimiser is the cheapest of the candidates of a
    minimum on that set: the Lagrange points and the points where grad c vanishes."""
    N = 2
    fn = _with_hamiltonians({
        "f": lambda x, u: x + sp.Matrix([(u[0] + u[1]) ** 2]),
        "g": lambda x, u: ((u[0] - 1) ** 2 + u[1] ** 2) / 2,
        "h": lambda u: sp.Matrix([u[0] - u[1]]),
    })  # fmt: skip
    values = _d1_variables(N, 1, 2, 1)
    values[("x", 0)], values[("x", N)] = sp.Matrix([0]), sp.Matrix([endpoint])
    vs, w, mu = sp.symbols("v0 v1 w mu", real=True)[:2], sp.Symbol("w"), sp.Symbol("mu")
    point = dict(values)
    for k in range(N):
        point[("u", k)] = sp.Matrix([vs[k], w])
        lhs, _rhs = CONSTRAINT.at(k)
        point[("u", k)] = point[("u", k)].subs(w, sp.solve(_value(lhs, point, fn)[0], w)[0])
    point[("x", 1)] = _value(DYNAMICS.at(0)[1], point, fn)
    c = _value(DYNAMICS.at(1)[1], point, fn)[0] - endpoint
    cost = _value(COST.rhs, point, fn)
    lagrange = [c, *(sp.diff(cost, v) - mu * sp.diff(c, v) for v in vs)]
    singular = [c, *(sp.diff(c, v) for v in vs)]
    candidates = sp.solve(lagrange, [*vs, mu], dict=True) + sp.solve(singular, vs, dict=True)
    real = [s for s in candidates if all(s[v].is_real for v in vs)]
    best = min(real, key=lambda s: cost.subs(s))
    at_min = {values[key][i]: point[key][i].subs(best)
              for key in (("x", 1), ("u", 0), ("u", 1)) for i in range(values[key].rows)}  # fmt: skip
    return fn, values, at_min


_PRIMAL, _DUAL = (
    (("x", 1), ("u", 0), ("u", 1)),
    (("p", 1), ("p", 2), (r"\sigma", 0), (r"\sigma", 1)),
)


def _multiplier_system(endpoint: int, cost_multiplier: int) -> tuple[list[sp.Expr], list[Any]]:
    """The derivatives of the displayed V_lambda (cost multiplier lambda_0 given) in x_1, u_0,
    u_1 at the exact minimiser of the example: linear equations in p_1, p_2, sigma_0, sigma_1."""
    fn, values, at_min = _normality_example(endpoint)
    values[_key(_lam0)] = sp.Integer(cost_multiplier)
    V = _value(V_LAMBDA.rhs, values, fn)
    eqs = [e.xreplace(at_min) for key in _PRIMAL for e in _grad(V, values[key])]
    return eqs, [s for key in _DUAL for s in values[key]]


def _constraint_rank(endpoint: int) -> tuple[int, int]:
    """(rank, rows) of the Jacobian of the constraints in the free variables x_1, u_0, u_1 at
    the minimiser; the constraints are the derivatives of the displayed V in the multipliers."""
    fn, values, at_min = _normality_example(endpoint)
    values[_key(_lam0)] = sp.Integer(1)
    V = _value(V_LAMBDA.rhs, values, fn)
    constraints = sp.Matrix([e for key in _DUAL for e in _grad(V, values[key])])
    primal = sp.Matrix([s for key in _PRIMAL for s in values[key]])
    jac = constraints.jacobian(primal).xreplace(at_min)
    return jac.rank(), jac.rows


@D1.check(Level.EXACT_RATIONAL, form="printed")
def d1_printed_abnormal_example() -> sp.Expr:
    r"""The printed rule (cost multiplier 1) fails where the optimum is forced: $f = x + (u_1 +
    u_2)^2$, $g = ((u_1 - 1)^2 + u_2^2)/2$, $h = u_1 - u_2$, $N = 2$, $x_0 = 0$, $x_2 = 0$ ($n = 1$,
    $m = 2$, $l = 1$). The only admissible control is $u_k = 0$; there the stationarity equations of
    the displayed $V$ (one multiplier per step) in $x_1$, $u_0$, $u_1$ have no solution $(p_1, p_2,
    \sigma_0, \sigma_1)$: least-squares residual of that linear system (1)."""
    return _least_squares_residual(*_multiplier_system(0, 1))


@D1.check(Level.EXACT_RATIONAL, form="corrected")
def d1_corrected_normality() -> sp.Expr:
    r"""The same $f$, $g$, $h$ with $x_2 = 0$ and with $x_2 = 8$: the rank of the constraint
    Jacobian in $(x_1, u_0, u_1)$ at the exact minimiser decides which multiplier exists. With full
    row rank ($x_2 = 8$, minimiser $u_k = (1, 1)$, rank 4 of 4) the normal one ($\lambda_0 = 1$)
    does (least-squares residual); without it ($x_2 = 0$, rank 3 of 4) an abnormal one ($\lambda_0 =
    0$, $(p, \sigma)$ not zero) does (1 if the homogeneous system has only the zero solution); and
    $V_\lambda$ with $\lambda_0 = 1$ is the displayed $V$."""
    total, kinds = sp.Integer(0), set()
    for endpoint in (0, 8):
        rank, rows = _constraint_rank(endpoint)
        kinds.add(rank == rows)
        if rank == rows:
            total += _least_squares_residual(*_multiplier_system(endpoint, 1))
        else:
            eqs, unknowns = _multiplier_system(endpoint, 0)
            A, _b = sp.linear_eq_to_matrix([sp.expand(e) for e in eqs], unknowns)
            total += 0 if A.nullspace() else 1
    if kinds != {True, False}:
        raise ValueError("the two examples must be one regular and one degenerate")
    # V_lambda with lambda_0 = 1 is the displayed V (undefined f, g, h, N = 2)
    values = _d1_variables(2, 2, 2, 1)
    fn = _with_hamiltonians(_generic(2, 2, 1))
    normal = _value(V_LAMBDA.rhs, {**values, _key(_lam0): sp.Integer(1)}, fn)
    return total + _nonzero(normal - _value(V_DEF.rhs, values, fn))


# the paper's sentences (the definition, the proposition and its proof)

D1.sentence(
    r"Let $N$ be a positive integer and $X_0,X_N\in\mathbb{R}^n$ be given.",
    d1_stationarity,
)
D1.sentence(
    r"Let $f:\mathbb{R}^n\times\mathbb{R}^m \rightarrow \mathbb{R}^n$ and "
    r"$g:\mathbb{R}^n\times\mathbb{R}^m \rightarrow \mathbb{R}^+:=[0,\infty)$ be smooth functions.",
    d1_stationarity,
)
D1.sentence(
    r"Denote points in $\mathbb{R}^n$ by $x$, points in $\mathbb{R}^m$ by $u$.",
    kind="prose",
    reason="fixes notation",
)
D1.sentence(
    r"Let $E\subset\mathbb{R}^m$ be a control constraint set and assume that $E = h^{-1}(0)$, "
    r"where $h:\mathbb{R}^m\to\mathbb{R}^l$ is a submersion.",
    d1_stationarity,
    d1_corrected_multipliers,
    d1_printed_abnormal_example,
    d1_corrected_normality,
)
D1.sentence(
    r"Let $\langle\cdot,\cdot\rangle$ denote the pairing between vectors in $\mathbb{R}^p$ given "
    r"by the dot product; $p$ can be $n$, $m$, or $l$.",
    kind="prose",
    reason="fixes notation (the dot product, which every check uses)",
)
D1.sentence(
    r"Define the optimal control problem: $\min_{u_k\in E}\sum^{N-1}_{k=0}g(x_k,u_k)$ subject to "
    r"$x_{k+1}=f(x_k,u_k)$, with $x_0=X_0$ and $x_N=X_N$, for $u_k\in E$.",
    d1_stationarity,
    d1_corrected_costate_range,
    d1_corrected_multipliers,
)
D1.sentence(
    r"A solution to problem (prob8.1) satisfies the following extremal solution equations "
    r"$p_k = \frac{\partial H}{\partial x_k}(p_{k+1},x_k,u^*_k), \qquad "
    r"x_{k+1} = \frac{\partial H}{\partial p_{k+1}}(p_{k+1},x_k,u^*_k),$ where "
    r"$H(p_{k+1},x_k,u_k):=\langle p_{k+1},f(x_k,u_k)\rangle-g(x_k,u_k), \quad k=0, \ldots, N, "
    r"\quad p_{N+1} =0,$ and $\partial/ \partial x$, $\partial/ \partial p$ denote the partial "
    r"$x$- and $p$-gradients.",
    d1_stationarity,
    d1_printed_costate_at_N,
    d1_corrected_costate_range,
    d1_extremals_any_dimension,
    d1_printed_abnormal_example,
    d1_corrected_normality,
)
D1.sentence(
    r"In these equations, $u_k^\ast$ is determined as follows.",
    kind="prose",
    reason="announces the next sentence",
)
D1.sentence(
    r"Define $\hat{H}(p_{k+1},x_k,u_k,\sigma):=H(p_{k+1},x_k,u_k)+ "
    r"\left\langle \sigma,h(u_k)\right\rangle$ for $\sigma\in\mathbb{R}^l$, $\sigma$ a Lagrange "
    r"multiplier; then $u^*_k$ and $\sigma$ are solutions of the equations "
    r"$\frac{\partial\hat{H}}{\partial u_k}(p_{k+1},x_k,u^*_k,\sigma)=0,\quad h(u^*_k)=0.$",
    d1_stationarity,
    d1_printed_single_multiplier,
    d1_corrected_multipliers,
    d1_extremals_any_dimension,
    d1_printed_abnormal_example,
    d1_corrected_normality,
)
D1.sentence(
    r"Proof. Use the discrete maximum principle.",
    kind="prose",
    reason="names the method of the proof",
)
D1.sentence(
    r"We wish to minimize $\sum^{N-1}_{k=0}g(x_k,u_k)$ subject to the given discrete dynamics "
    r"and control constraint set $E$.",
    kind="prose",
    reason="restates the problem of the definition (its sentence above is mapped)",
)
D1.sentence(
    r"To implement the constraints defining $E$, we consider maximizing the augmented functional "
    r"(which is independent of $p_0$) "
    r"$V(p_{0},\ldots, p_N, x_0,\ldots x_{N-1},u_0, \ldots, u_{N-1}) := \sum^{N-1}_{k=0}\left( "
    r"\langle p_{k+1},f(x_k,u_k)-x_{k+1}\rangle+ \left\langle \sigma ,h(u_k)\right\rangle "
    r"-g(x_k,u_k) \right) = \sum^{N-1}_{k=0}\left( -\langle p_{k+1},x_{k+1}\rangle+ "
    r"\hat{H}(p_{k+1},x_k,u_k,\sigma) \right) = \left\langle p_0, x_0 \right\rangle + "
    r"\sum^N_{k=0} \left( -\langle p_k,x_k\rangle+\hat{H}(p_{k+1},x_k,u_k,\sigma)\right),$ "
    r"where we set $p_{N+1}=0$ for notational convenience since there is no $x_{N+1}$.",
    d1_stationarity,
    d1_printed_rewrite,
    d1_corrected_rewrite,
    d1_printed_single_multiplier,
    d1_corrected_multipliers,
)
D1.sentence(
    r"The critical points of $V$ are hence given by $0= \delta V = \left\langle \delta p_0, x_0 "
    r"\right\rangle + \sum^N_{k=0}\left( -\langle p_k,\delta x_k\rangle-\langle\delta "
    r"p_k,x_k\rangle+\frac{\partial \hat{H}}{\partial p_{k+1}}\delta p_{k+1} "
    r"+\frac{\partial\hat{H}}{\partial x_k}\delta x_k+ \frac{\partial\hat{H}}{\partial u_k}\delta "
    r"u_k \right)$ since $\delta x_0 = 0$ because $x_0 = X_0$ is a given constant vector.",
    d1_stationarity,
    d1_extremals_any_dimension,
)
D1.sentence(
    r"This gives the extremal equations (eq8.3) and (eq8.6) since "
    r"$\frac{\partial\hat{H}}{\partial p_{k+1}}(p_{k+1},x_k,u_k,\sigma)= \frac{\partial "
    r"H}{\partial p_{k+1}}(p_{k+1},x_k,u_k), \quad \frac{\partial\hat{H}}{\partial "
    r"x_k}(p_{k+1},x_k,u_k,\sigma)= \frac{\partial H}{\partial x_k}(p_{k+1},x_k,u_k),$ and "
    r"$h(u_k)=0$, for $k=0, \ldots , N$ and $p_{N+1}=0$.",
    d1_stationarity,
    d1_printed_costate_at_N,
    d1_corrected_costate_range,
    d1_extremals_any_dimension,
)
