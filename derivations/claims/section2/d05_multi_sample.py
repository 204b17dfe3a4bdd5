r"""D5: the multi-sample problem with terminal cost (paper, Section 2, second proposition).

Where: Section 2, the second definition (prob8.1m: samples :math:`a = 1, \dots, M`, shared
controls, terminal cost :math:`\phi`) and the second proposition (gendiscpropm, eq8.3m-eq8.6m and
the endpoint condition m8), with its proof.

Recorded outcome: holds after correction.  The endpoint is free, the costate equation uses
:math:`x^a_k`, and the endpoint condition is :math:`p^a_N = -\partial\phi/\partial x^a_N` for
:math:`H = \langle p, f\rangle - g`.  Evidence: the derivatives of the displayed :math:`V`
(undefined :math:`f, g, h, \phi`) are the displayed equations; exact examples at their exact
minimisers separate the printed forms; independent of symrb.  With the endpoint free the
constraints are always regular (no abnormal multiplier), checked on the displayed :math:`V`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import sympy as sp

from derivations.claims.section2._any_dimension import DIMS, Evaluator, gradient, minus
from derivations.claims.section2._any_dimension import nonzero as any_nonzero
from derivations.claims.section2._hamiltonians import (
    _C,
    _H,
    _V,
    H_DEF,
    _f,
    _g,
    _generic,
    _h,
    _pa,
    _phi,
    _sig,
    _u,
    _with_hamiltonians,
    _x,
    _xa,
)
from derivations.claims.section2._indexed import (
    _M,
    _N,
    _a,
    _coverage_defect,
    _Dot,
    _grad,
    _instance,
    _k,
    _k1,
    _key,
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

D5 = claim(
    "D5",
    label="prob8.1m, gendiscpropm, eq8.3m-eq8.6m, m8",
    title="Multi-sample problem with terminal cost: shared controls, per-sample costates",
    statement="The multi-sample maximum principle (the second proposition of Section 2): for the problem of minimising [[cost]] subject to "
    "[[dynamics]] and the control constraint, with controls shared by the samples, the "
    "extremal equations of [[H]] have per-sample costates and an endpoint condition.",
    printed="The multi-sample problem also fixes the endpoints $x^a_N$; its costate equation is "
    "[[costate_printed]] with the un-indexed $x_k$; its endpoint condition is [[m8]].",
    corrected="The endpoint is free. The extremal equations are the critical points of [[V]]: "
    "[[state]], [[costate]], [[stationary]] with one multiplier per step, and [[endpoint]] for this "
    "$H$ (equivalently the costates are minus the gradients of the cost, D6). With the endpoint "
    "free and $h$ a submersion the constraints are always regular, so these hold with the cost "
    "multiplier one at every solution (no abnormal case, unlike the fixed endpoint of D1).",
    expected="holds after correction",
    headline="[[endpoint]], the endpoint free",
    section="2",
    where="Section 2, the second definition (several samples $a = 1, \\dots, M$ and an endpoint "
    "cost $\\phi$) and the second proposition (extremal equations and the endpoint condition "
    "$p^a_N = \\partial\\phi/\\partial x^a_N$), with its proof",
    note="The problem fixes the endpoints $x^a_N$, the costate equation uses the un-indexed "
    "$x_k$, and the endpoint condition has the wrong sign. Corrected: the endpoint is free, the "
    "costate equation uses $x^a_k$, and $p^a_N = -\\partial\\phi/\\partial x^a_N$ for $H = "
    "\\langle p, f\\rangle - g$. With $H = \\langle p, f\\rangle - g$ and a minimisation, $V = "
    "-(\\text{cost}) + \\langle p, f - x\\rangle + \\langle \\sigma, h\\rangle$, so $\\partial "
    "V/\\partial x^a_N = -p^a_N - \\phi'(x^a_N)$: the endpoint sign is minus (the paper's $V$ "
    "carries $+\\phi$ and an extra $-p_N x_N$). If $x^a_N$ is fixed, $\\phi(x^a_N)$ is a constant "
    "and no endpoint condition follows. The term $-\\phi(x^a_N)$ inside the proposition's "
    "Hamiltonian is harmless (constant in the variables of $H$). The proof's $V$ needs "
    "$\\sigma_k$ per step, as in D1 (checked there). Normality: with $x^a_N$ free the "
    "dynamics rows of the constraint Jacobian have a unit triangular block in the states and "
    "$h$ is a submersion, so the Jacobian always has full row rank and no abnormal multiplier "
    "is needed; with the printed fixed endpoints the regularity condition of D1 would be needed "
    "(its abnormal example is an instance with one sample). An all-dimension symbolic check "
    "(matrix symbols of sizes $n, m, l$) derives the extremal equations from $V$.",
)
COST5 = D5.formula(
    "cost",
    eq(
        _C,
        _plus(
            sp.Sum(sp.Sum(_g(_xa(_a, _k), _u[_k]), (_k, 0, _Nm1)), (_a, 1, _M)),
            sp.Sum(_phi(_xa(_a, _N)), (_a, 1, _M)),
        ),
    ),
)
DYNAMICS5 = D5.formula("dynamics", _Steps([eq(_xa(_a, _k1), _f(_xa(_a, _k), _u[_k]))], _k, 0, _Nm1))
D5.formula("H", H_DEF)
_H_ak = _H(_pa(_a, _k1), _xa(_a, _k), _u[_k])
V5 = D5.formula(
    "V",
    eq(
        _V,
        _plus(
            sp.Sum(
                sp.Sum(_plus(_Dot(_pa(_a, _k1), _plus(_f(_xa(_a, _k), _u[_k]), -_xa(_a, _k1))),
                             -_g(_xa(_a, _k), _u[_k])), (_k, 0, _Nm1)),
                (_a, 1, _M),
            ),
            sp.Sum(_Dot(_sig[_k], _h(_u[_k])), (_k, 0, _Nm1)),
            -sp.Sum(_phi(_xa(_a, _N)), (_a, 1, _M)),
        ),
    ),
)  # fmt: skip
STATE5 = D5.formula(
    "state", _Steps([eq(_xa(_a, _k1), sp.Derivative(_H_ak, _pa(_a, _k1)))], _k, 0, _Nm1)
)
_COSTATE5_EQ = eq(_pa(_a, _k), sp.Derivative(_H_ak, _xa(_a, _k)))
COSTATE5 = D5.formula("costate", _Steps([_COSTATE5_EQ], _k, 1, _Nm1))
COSTATE5_PRINTED = D5.formula(
    "costate_printed",
    _Steps(
        [eq(_pa(_a, _k), sp.Derivative(_H(_pa(_a, _k1), _x[_k], _u[_k]), _x[_k]))],
        _k, 0, _Nm1,
    ),
)  # fmt: skip
STATIONARY5 = D5.formula(
    "stationary",
    _Steps(
        [
            eq(
                _plus(
                    sp.Sum(sp.Derivative(_H_ak, _u[_k]), (_a, 1, _M)),
                    sp.Derivative(_Dot(_sig[_k], _h(_u[_k])), _u[_k]),
                ),
                0,
            ),
            eq(_h(_u[_k]), 0),
        ],
        _k,
        0,
        _Nm1,
    ),
)
_dphi = sp.Derivative(_phi(_xa(_a, _N)), _xa(_a, _N))
ENDPOINT = D5.formula("endpoint", eq(_pa(_a, _N), -_dphi))
M8 = D5.formula("m8", eq(_pa(_a, _N), _dphi))


def _d5_variables(N: int, M: int, nx: int, nu: int, nl: int) -> dict[Any, Any]:
    values: dict[Any, Any] = {"N": N, "M": M}
    for a in range(1, M + 1):
        for k in range(N + 1):
            values[("x", a, k)] = _vec(f"x{a}{k}", nx)
            if k:
                values[("p", a, k)] = _vec(f"p{a}{k}", nx)
    for k in range(N):
        values[("u", k)] = _vec(f"u{k}", nu)
        values[(r"\sigma", k)] = _vec(f"s{k}", nl)
    return values


def _each_displayed_equation(compare: Callable[..., Any], N: int, M: int) -> Any:
    """The sum of ``compare(lhs, rhs, variable, sign)`` over the displayed state, costate and
    endpoint equations of every sample and the stationarity and constraint equations of every
    step (sign -1 for "p = dH/dx"-type equations, +1 for "... = 0")."""
    total: Any = 0
    for a in range(1, M + 1):
        for k in STATE5.steps(N):
            total += compare(*STATE5.at(k, a=a), _pa(a, k + 1), -1)
        for k in COSTATE5.steps(N):
            total += compare(*COSTATE5.at(k, a=a), _xa(a, k), -1)
        total += compare(*_instance(ENDPOINT, {_a: a, _N: N}), _xa(a, N), -1)
    for k in STATIONARY5.steps(N):
        total += compare(*STATIONARY5.at(k, 0), _u[k], 1)
        total += compare(*STATIONARY5.at(k, 1), _sig[k], 1)
    return total


@D5.check(Level.SYMBOLIC_FIXED_N, form="corrected")
def d5_stationarity() -> sp.Expr:
    r"""The derivatives of the displayed $V$ (free endpoint) in $p^a_{k+1}$, $x^a_k$, $x^a_N$, $u_k$
    and $\sigma_k$ are the displayed state, costate, endpoint, stationarity and constraint equations
    over their displayed ranges, covering every variable of $V$ once (undefined $f$, $g$, $h$,
    $\phi$; $n = m = 2$, $l = 1$, $M = 2$ samples, $N = 2$)."""
    N, M = 2, 2
    values = _d5_variables(N, M, 2, 2, 1)
    fn = _with_hamiltonians(_generic(2, 2, 1))
    V = _value(V5.rhs, values, fn)
    total = sp.Integer(0)
    covered = []

    def compare(lhs: sp.Basic, rhs: sp.Basic, var: sp.Basic, sign: int) -> sp.Expr:
        """dV/dvar against +-(lhs - rhs): rhs - lhs of "p = dH/dx", lhs - rhs of "... = 0"."""
        covered.append(_key(var))
        side = _minus(_value(lhs, values, fn), _value(rhs, values, fn))
        return _nonzero(_minus(_grad(V, values[_key(var)]), sign * side))

    total += _each_displayed_equation(compare, N, M)
    fixed = {("x", a, 0) for a in range(1, M + 1)}
    total += _coverage_defect(V, values, fixed, covered)
    return total


def _two_sample_example() -> tuple[dict[str, Any], dict[Any, Any]]:
    """M = 2 samples, N = 2, n = m = 1: f = x + u, g = (u^2 + x^2)/2, phi(x) = (x - 1)^2/2,
    x^1_0 = 0, x^2_0 = 2, no constraint.  The exact minimiser of the displayed cost along the
    displayed dynamics, as values."""
    N, M = 2, 2
    fn = _with_hamiltonians({
        "f": lambda x, u: x + u,
        "g": lambda x, u: (u[0] ** 2 + x[0] ** 2) / 2,
        "h": lambda u: sp.zeros(1, 1),
        r"\phi": lambda x: (x[0] - 1) ** 2 / 2,
    })  # fmt: skip
    us = sp.symbols("v0 v1")
    values: dict[Any, Any] = {"N": N, "M": M}
    values.update({("u", k): sp.Matrix([us[k]]) for k in range(N)})
    values.update({(r"\sigma", k): sp.zeros(1, 1) for k in range(N)})
    for a, x0 in ((1, 0), (2, 2)):
        values[("x", a, 0)] = sp.Matrix([x0])
        for k in DYNAMICS5.steps(N):
            lhs, rhs = DYNAMICS5.at(k, a=a)
            values[_key(lhs)] = _value(rhs, values, fn)
    cost = _value(COST5.rhs, values, fn)
    if not sp.hessian(cost, us).is_positive_definite:
        raise ValueError("the example is not convex")
    best = sp.solve([sp.diff(cost, v) for v in us], us, dict=True)[0]
    return fn, _substituted(values, best)


def _d5_example_defect(endpoint: sp.Eq, costate: _Steps) -> sp.Expr:
    """In the two-sample example: costates from the given endpoint condition and costate equation
    (for the un-indexed x_k of the printed eq8.3m, sample 1's state), then sum over k of
    |lhs - rhs| of the displayed stationarity condition at the exact minimiser."""
    fn, values = _two_sample_example()
    N, M = values["N"], values["M"]
    for k in range(N + 1):
        values[("x", k)] = values[("x", 1, k)]
    for a in range(1, M + 1):
        lhs, rhs = _instance(endpoint, {_a: a, _N: N})
        values[_key(lhs)] = _value(rhs, values, fn)
        for k in reversed([k for k in costate.steps(N) if k >= 1]):
            lhs, rhs = costate.at(k, a=a)
            values[_key(lhs)] = _value(rhs, values, fn)
    total = sp.Integer(0)
    for k in STATIONARY5.steps(N):
        lhs, rhs = STATIONARY5.at(k, 0)
        total += sum(abs(e) for e in _value(lhs, values, fn) - sp.Matrix([_value(rhs, values, fn)]))
    return sp.nsimplify(total)


@D5.check(Level.EXACT_RATIONAL, form="corrected")
def d5_corrected_example() -> sp.Expr:
    r"""2 samples, $N = 2$, $f = x + u$, $g = (u^2 + x^2)/2$, $\phi = (x - 1)^2/2$, $x_0 = 0$ and 2:
    costates from the displayed endpoint condition and costate equation satisfy the displayed
    stationarity condition at the exact minimiser ($\sum_k |\sum_a H_u|$)."""
    return _d5_example_defect(ENDPOINT, COSTATE5)


@D5.check(Level.EXACT_RATIONAL, form="printed")
def d5_printed_endpoint_sign() -> sp.Expr:
    """Same example with m8's endpoint sign: the stationarity condition fails at the minimiser."""
    return _d5_example_defect(M8, COSTATE5)


@D5.check(Level.EXACT_RATIONAL, form="printed")
def d5_printed_shared_state() -> sp.Expr:
    """Same example with eq8.3m's un-indexed $x_k$ (sample 1's state for both samples): the
    stationarity condition fails at the minimiser."""
    return _d5_example_defect(ENDPOINT, COSTATE5_PRINTED)


def _d5_endpoint_defect(fixed: bool) -> sp.Expr:
    """N = 1, one sample, f = x + u, g = u^2/2, phi(x) = (x - 3)^2/2, x_0 = 0; the control is the
    minimiser of the displayed cost (free endpoint) or forced by x_1 = 1 (fixed endpoint); p_1
    from the displayed stationarity condition.  Returns the smaller mismatch of the two endpoint
    conditions, displayed corrected and m8."""
    N, M = 1, 1
    fn = _with_hamiltonians({
        "f": lambda x, u: x + u,
        "g": lambda x, u: u[0] ** 2 / 2,
        "h": lambda u: sp.zeros(1, 1),
        r"\phi": lambda x: (x[0] - 3) ** 2 / 2,
    })  # fmt: skip
    v, P = sp.symbols("v P")
    values: dict[Any, Any] = {"N": N, "M": M, ("x", 1, 0): sp.Matrix([0]), ("u", 0): sp.Matrix([v])}
    values[(r"\sigma", 0)] = sp.zeros(1, 1)
    lhs, rhs = DYNAMICS5.at(0, a=1)
    values[_key(lhs)] = _value(rhs, values, fn)
    if fixed:
        best = sp.solve(values[("x", 1, 1)][0] - 1, v)[0]
    else:
        best = sp.solve(sp.diff(_value(COST5.rhs, values, fn), v), v)[0]
    values = _substituted(values, {v: best})
    values[("p", 1, 1)] = sp.Matrix([P])
    lhs, rhs = STATIONARY5.at(0, 0)
    values[("p", 1, 1)] = sp.Matrix(
        [sp.solve(_value(lhs, values, fn)[0] - _value(rhs, values, fn), P)[0]]
    )
    gaps = []
    for condition in (ENDPOINT, M8):
        lhs, rhs = _instance(condition, {_a: 1, _N: N})
        gaps.append(abs((_value(lhs, values, fn) - _value(rhs, values, fn))[0]))
    return sp.Min(*gaps)


@D5.check(Level.EXACT_RATIONAL, form="printed")
def d5_printed_fixed_endpoint() -> sp.Expr:
    r"""prob8.1m fixes $x_N$ and adds $\phi(x_N)$: with $N = 1$, $f = x + u$, $g = u^2/2$, $x_0 =
    0$, $x_1 = 1$, $\phi = (x - 3)^2/2$, the stationarity condition gives $p_1 = 1$ while $\phi'(1)
    = -2$, so neither endpoint condition holds (smaller mismatch 1)."""
    return _d5_endpoint_defect(fixed=True)


@D5.check(Level.EXACT_RATIONAL, form="corrected")
def d5_free_endpoint() -> sp.Expr:
    """The same problem with a free endpoint: at the exact minimiser one of the endpoint
    conditions holds (the corrected one, as the stationarity check above shows in general)."""
    return _d5_endpoint_defect(fixed=False)


def d5_any_dimension_defect(N: int = 2, M: int = 2) -> int:
    """Number of displayed equations (state, costate, endpoint, stationarity, constraint) that
    differ from the gradient of the first variation of the displayed V in their variable, plus the
    coverage defect: x^a_k, p^a_k of size n, u_k of size m, sigma_k of size l (symbols), undefined
    f, g, h, phi, x^a_0 fixed."""
    n, m, l = DIMS
    columns: dict[Any, sp.MatrixSymbol] = {}
    for a in range(1, M + 1):
        columns.update({("x", a, k): sp.MatrixSymbol(f"x^{a}_{k}", n, 1) for k in range(N + 1)})
        columns.update({("p", a, k): sp.MatrixSymbol(f"p^{a}_{k}", n, 1) for k in range(1, N + 1)})
    columns.update({("u", k): sp.MatrixSymbol(f"u_{k}", m, 1) for k in range(N)})
    columns.update({(r"\sigma", k): sp.MatrixSymbol(f"sigma_{k}", l, 1) for k in range(N)})
    fixed = {("x", a, 0) for a in range(1, M + 1)}
    outputs = {"f": n, "g": 1, "h": l, r"\phi": 1}
    ev = Evaluator(columns, fixed, outputs, {"H": H_DEF}, {"N": N, "M": M})
    _value_V, dV = ev(V5.rhs)
    total, covered = 0, []

    def compare(lhs: sp.Basic, rhs: sp.Basic, var: sp.Basic, sign: int) -> int:
        key = _key(var)
        covered.append(key)
        side = minus(ev(lhs)[0], ev(rhs)[0])
        return any_nonzero(minus(gradient(dV, ev.deltas[key]), sign * side))

    total += _each_displayed_equation(compare, N, M)
    variables = {key for key, d in ev.deltas.items() if ev.free(key) and dV.has(d)}
    return total + len(variables.symmetric_difference(covered)) + len(covered) - len(set(covered))


@D5.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def d5_extremals_any_dimension() -> int:
    r"""The displayed $V$ (free endpoint) on columns of symbolic sizes $n$, $m$, $l$ with undefined
    $f$, $g$, $h$, $\phi$ (Jacobians as matrix symbols): the gradients of its first variation in
    $p^a_{k+1}$, $x^a_k$, $x^a_N$, $u_k$ and $\sigma_k$ (SymPy matrix calculus) are the displayed
    state, costate, endpoint, stationarity and constraint equations over their displayed ranges,
    each variable once ($M = 2$ samples, $N = 2$; every dimension)."""
    return d5_any_dimension_defect()


@D5.check(Level.SYMBOLIC_FIXED_N, form="corrected")
def d5_free_endpoint_is_normal() -> sp.Expr:
    r"""With the endpoint free the multiplier rule needs no extra hypothesis: the Jacobian of the
    constraints (the derivatives of the displayed $V$ in $p^a_{k+1}$ and $\sigma_k$) in the free
    variables $x^a_1, \dots, x^a_N$, $u_k$ has, for undefined $f$ and $h$, a block in the
    $x$-columns of the dynamics rows with determinant $\pm 1$ and zero $x$-columns in the constraint
    rows, so its row rank is $N M n$ plus that of the $h'(u_k)$, full since $h$ is a submersion ($n
    = m = 2$, $l = 1$, $M = 2$, $N = 2$): $|\det| - 1$ and the nonzero $x$-entries of the constraint
    rows."""
    N, M = 2, 2
    values = _d5_variables(N, M, 2, 2, 1)
    fn = _with_hamiltonians(_generic(2, 2, 1))
    V = _value(V5.rhs, values, fn)
    dynamics = sp.Matrix([e for a in range(1, M + 1) for k in range(1, N + 1)
                          for e in _grad(V, values[("p", a, k)])])  # fmt: skip
    constraint = sp.Matrix([e for k in range(N) for e in _grad(V, values[(r"\sigma", k)])])
    states = sp.Matrix([s for a in range(1, M + 1) for k in range(1, N + 1)
                        for s in values[("x", a, k)]])  # fmt: skip
    det = sp.expand(dynamics.jacobian(states).det())
    return sp.Abs(sp.Abs(det) - 1) + _nonzero(constraint.jacobian(states))


# the paper's sentences (the definition, the proposition and its proof)

D5.sentence(
    r"Let $N, M$ be a positive integers and $X_0,X_N^a\in\mathbb{R}^n$, $a=1, \ldots, M$ be "
    r"given.",
    d5_stationarity,
    d5_printed_fixed_endpoint,
    d5_free_endpoint,
)
D5.sentence(
    r"Let $f:\mathbb{R}^n\times\mathbb{R}^m \times \mathbb{R}^n \rightarrow \mathbb{R}^n$, "
    r"$g:\mathbb{R}^n\times\mathbb{R}^m \rightarrow \mathbb{R}^+:=[0,\infty)$, and "
    r"$\phi: \mathbb{R}^n \rightarrow \mathbb{R}^+$ be smooth functions.",
    d5_stationarity,
)
D5.sentence(
    r"Let $E\subset\mathbb{R}^m$ be a control constraint set and assume that $E = h^{-1}(0)$, "
    r"where $h:\mathbb{R}^m\to\mathbb{R}^l$ is a submersion.",
    d5_stationarity,
    d5_free_endpoint_is_normal,
)
D5.sentence(
    r"Define the optimal control problem: $\min_{u_k\in E}\sum_{a=1}^M\sum^{N-1}_{k=0}"
    r"g(x^a_k,u_k) +\sum_{a=1}^M\phi(x^a_N)$ subject to "
    r"$x^a_{k+1}=f^a(x_k,u_k):=f(x_k,u_k,X_0^a)$ with $x_0=X^a_0$ and $x^a_N = X_N^a$, for "
    r"$u_k\in E$, $k=0, \ldots, N-1$, and $a=1,\ldots, M$.",
    d5_stationarity,
    d5_corrected_example,
    d5_printed_fixed_endpoint,
    d5_free_endpoint,
)
D5.sentence(
    r"The proof of the next proposition is analogous to that of Proposition (gendiscprop).",
    kind="prose",
    reason="points to the proof of the first proposition (D1)",
)
D5.sentence(
    r"A solution to problem (eq8.1m) satisfies the following extremal solution equations "
    r"$p^a_k = \frac{\partial H}{\partial x_k}(p^a_{k+1},x_k,u^*_k), \qquad "
    r"x^a_{k+1} = \frac{\partial H}{\partial p_{k+1}}(p^a_{k+1},x_k,u^*_k),$ where "
    r"$k=0,\ldots, N-1$, $p^a_{N+1}=0$ for all $a=1,\ldots, M$, and "
    r"$H(p_{k+1},x_k,u_k)=\sum_{a=1}^M\left( \langle p^a_{k+1},f^a(x_k,u_k)\rangle-g(x^a_k,u_k) "
    r"-\phi(x^a_N)\right).$",
    d5_stationarity,
    d5_corrected_example,
    d5_printed_shared_state,
    d5_extremals_any_dimension,
    d5_free_endpoint_is_normal,
)
D5.sentence(
    r"In these equations, $u _k ^\ast$ is determined as follows.",
    kind="prose",
    reason="announces the next sentences",
)
D5.sentence(
    r"Let $\hat{H}(p_{k+1},x_k,u_k,\sigma):= \sum_{a=1}^M\left( \langle "
    r"p^a_{k+1},f^a(x_k,u_k)\rangle-g(x^a_k,u_k)\right)+ \left\langle \sigma,h(u_k)\right\rangle$ "
    r"for $\sigma\in\mathbb{R}^l$, $\sigma$ a Lagrange multiplier.",
    d5_stationarity,
)
D5.sentence(
    r"Then $u^*_k$ and $\sigma$ are solutions of the equations "
    r"$\frac{\partial\hat{H}}{\partial u_k}(p^a_{k+1},x^a_k,u^*_k,\sigma)=0,\quad h(u^*_k)=0.$",
    d5_stationarity,
    d5_corrected_example,
)
D5.sentence(
    r"In addition we have the endpoint condition "
    r"$p^a_N=\frac{\partial\phi(x^a_N)}{\partial x^a_N}, \quad a=1, \ldots, M.$",
    d5_stationarity,
    d5_corrected_example,
    d5_printed_endpoint_sign,
    d5_printed_fixed_endpoint,
    d5_free_endpoint,
    d5_extremals_any_dimension,
)
D5.sentence(r"Proof. Use the discrete maximum principle.", kind="prose", reason="names the method")
D5.sentence(
    r"We wish to minimize $\sum_{a=1}^M\sum^{N-1}_{k=0}g(x^a_k,u_k)+\sum_{a=1}^M\phi(x^a_N)$ "
    r"subject to the given discrete dynamics and control constraint set $E$.",
    kind="prose",
    reason="restates the problem of the definition (its sentence above is mapped)",
)
D5.sentence(
    r"To implement the constraints defining $E$, we consider maximizing the augmented functional "
    r"(which is independent of $p_0$) $V(p_{0},\ldots, p_N, x_0,\ldots x_{N-1},u_0, \ldots, "
    r"u_{N-1}) := \sum^{N-1}_{k=0}\sum^{M}_{a=1}\left( \langle p^a_{k+1},f^a(x^a_k,u_k)-"
    r"x^a_{k+1}\rangle+ \left\langle \sigma ,h(u_k)\right\rangle -g(x^a_k,u_k) \right) "
    r"-\sum_{a=1}^M(p^a(N)x^a(N)-\phi(x^a_N)) = \sum_{a-1}^M\sum^{N-1}_{k=0}\left( -\langle "
    r"p^a_{k+1},x^a_{k+1}\rangle+ \hat{H}(p^a_{k+1},x^a_k,u_k,\sigma) \right) "
    r"-\sum_{a=1}^M(p^a(N)x^a(N)-\phi(x^a_N)) =\sum_{a=1}^M\left( \left\langle p^a_0, x^a_0 "
    r"\right\rangle + \sum^N_{k=0} ( -\langle p^a_k,x^a_k\rangle+\hat{H}(p^a_{k+1},x^a_k,u_k,"
    r"\sigma)) \right) -\sum_{a=1}^M(p^a(N)x^a(N)-\phi(x^a_N))$ where we set $p^a_{N+1}=0$ for "
    r"notational convenience since there is no $x_{N+1}$.",
    d5_stationarity,
    d5_printed_endpoint_sign,
)
D5.sentence(
    r"The critical points of $V$ are hence given by $0= \delta V = \left\langle \delta p_0, x_0 "
    r"\right\rangle + \sum^N_{k=0}\left( \sum_{a=1}^M(-\langle p^a_k,\delta "
    r"x^a_k\rangle-\langle\delta p^a_k,x^a_k\rangle+\frac{\partial \hat{H}}{\partial "
    r"p^a_{k+1}}\delta p^a_{k+1} +\frac{\partial\hat{H}}{\partial x^a_k}\delta x^a_k)+ "
    r"\frac{\partial\hat{H}}{\partial u_k}\delta u_k \right) +\sum_{a=1}^M\left(\delta "
    r"p^a(N)x^a(N)+p^a(N)\delta x^a(N)-\frac{\partial\phi(x^a(N)}{\partial x^a(N)}\delta "
    r"x^a(N)\right),$ since $\delta x_0 = 0$ because $x_0 = X_0$ is a given constant vector.",
    d5_stationarity,
    d5_printed_endpoint_sign,
    d5_extremals_any_dimension,
)
D5.sentence(
    r"This gives the extremal equations (eq8.3m), (eq8.6m) and (m8) since "
    r"$\frac{\partial\hat{H}}{\partial p_{k+1}}(p_{k+1},x_k,u_k,\sigma)= \frac{\partial "
    r"H}{\partial p_{k+1}}(p_{k+1},x_k,u_k), \quad \frac{\partial\hat{H}}{\partial "
    r"x_k}(p_{k+1},x_k,u_k,\sigma)= \frac{\partial H}{\partial x_k}(p_{k+1},x_k,u_k),$ and "
    r"$h(u_k)=0$, for $k=0, \ldots , N$ and $p_{N+1}=0$ and $p_N$ is fixed",
    d5_stationarity,
    d5_printed_endpoint_sign,
    d5_corrected_example,
)
