r"""D6: ResNet layers, and the costate recursion is back-propagation (paper, Section 2, Remark).

Where: Section 2, the closing remark before Section 2.1: item 1 (the layer
:math:`\sigma(Kx + \beta)` of Benning et al.) and item 2 (the link with back-propagation).

Recorded outcome: holds after correction.  The ResNet layer is the residual layer
:math:`x + h\sigma(Kx + \beta)`; with a running cost only D5's endpoint sign makes the costates
(minus) the gradients of the cost.

Emitted (``symrb/_generated/discrete_control.py``): the steps and adjoint steps of the residual and
plain layers for tanh and the logistic function, built by :func:`._layers.layer`.  Evidence: the
kernels against the displayed layer and the gradients of the displayed :math:`H`; exact networks
with generic :math:`\sigma`; and symrb's ResNet against the independent NumPy network and
complex-step derivatives of :mod:`._resnet_reference`.  For every width (every n): the
displayed layers, adjoint formulas, endpoint, costate, backprop and weights relations in matrix
symbols of symbolic size, differentiated along directions by SymPy (:mod:`._general_n`), with
the entrywise activation's derivative as a diagonal letter.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import sympy as sp
from sympy.matrices.expressions.applyfunc import ElementwiseApplyFunction

from derivations.claims.section2._general_n import (
    Alphabet,
    directional,
    gradient,
    pairing_defect,
    substitute,
)
from derivations.claims.section2._hamiltonians import (
    H_DEF,
    _g,
    _pa,
    _u,
    _us,
    _with_hamiltonians,
    _xs,
)
from derivations.claims.section2._indexed import (
    _M,
    _N,
    _a,
    _define,
    _dot,
    _grad,
    _hider,
    _instance,
    _k,
    _key,
    _minus,
    _nonzero,
    _Sample,
    _value,
    _vec,
)
from derivations.claims.section2._layers import (
    _SIGMA,
    ACTIVATIONS,
    _bv,
    _hstep,
    _Km,
    _layer_env,
    _layer_function,
    _pv,
    _unflatten,
    _xv,
    layer,
)
from derivations.claims.section2._resnet_reference import (
    _reference_forward,
    complex_step_gradients,
    complex_step_state_gradients,
    random_network,
)
from derivations.claims.section2.d05_multi_sample import (
    _COSTATE5_EQ,
    COST5,
    ENDPOINT,
    M8,
    _dphi,
    _H_ak,
)
from derivations.registry import Level, claim
from derivations.symbolic import eq, explicit, lhs_minus_rhs, residual
from derivations.vocabulary import Arg, Kernel, matrix, n, vector

D6 = claim(
    "D6",
    label="Remark 1, Remark 2",
    title="ResNet layers: the costate recursion is back-propagation",
    statement="Remark 1: in the ResNet framework of Benning et al. (2019) a layer is $f(x, u)$ "
    "with controls $u$ the pair $(K, \\beta)$ and $\\sigma$ the sigmoid [[sigmoid]] applied "
    "entrywise. Remark 2: the solution of the multi-sample maximum principle is back-propagation (LeCun "
    "1988). With [[H]] and no running cost, [[no_running_cost]], the costate recursion of the "
    "layers is [[adjoint]] (for the plain layer [[adjoint_plain]]), and for the endpoint condition "
    "[[endpoint]] with either sign, $s=1$ or $s=-1$, the costates and weight gradients are "
    "[[backprop]] and [[weights]] with [[cost]].",
    printed="Remark 1: the ResNet layer is [[plain_layer]]. Remark 2, read for Proposition "
    "the multi-sample maximum principle with its endpoint condition [[m8]], and a running cost $g$: the costates "
    "are the back-propagated gradients of the cost, [[backprop]] and [[weights]] with $s=1$.",
    corrected="The ResNet layer of Benning et al. is the residual layer [[residual_layer]], a "
    "perturbation of the identity, [[identity]], which the plain layer is not. The costate "
    "recursion is back-propagation for both layers when there is no running cost, with either "
    "endpoint sign (the printed sign gives the gradients, D5's sign minus the gradients); with a running "
    "cost only D5's endpoint condition [[endpoint_minus]] gives the gradients of the cost, "
    "[[backprop]] and [[weights]] with $s=-1$.",
    expected="holds after correction",
    headline="the ResNet layer is [[residual_layer]]",
    section="2",
    where="Section 2, the paragraph 'Remark' that closes the section before Section 2.1: item 1 "
    "(the ResNet layer $f(x, u) = \\sigma(Kx + \\beta)$) and item 2 (the link with "
    "back-propagation)",
    note="Remark 1's layer $\\sigma(Kx + \\beta)$ is not the residual (ResNet) layer, and with a "
    "running cost the printed endpoint sign does not make the costates the back-propagated "
    "gradients. Corrected: the ResNet layer is $x + h\\,\\sigma(Kx + \\beta)$, and with $p^a_N = "
    "-\\partial\\phi/\\partial x^a_N$ the costates are minus the gradients of the cost, for "
    "either layer. The symrb implementation has both layers with $h = 1$ and the D5 sign (its "
    "costates are minus the back-propagated gradients). For $g = 0$ the recursion $p_k = "
    "(\\partial f/\\partial x)^T p_{k+1}$ is linear and homogeneous, so the endpoint sign is a "
    "global sign: the printed endpoint condition gives $p_k = +\\partial\\Phi/\\partial x_k$, "
    "D5's gives $p_k = -\\partial\\Phi/\\partial x_k$. With $g \\ne 0$ the recursion $p_k = "
    "(\\partial f/\\partial x)^T p_{k+1} - \\partial g/\\partial x$ is affine and only $p_N = "
    "-\\partial\\phi/\\partial x_N$ makes $p_k = -\\partial C/\\partial x_k$; with the printed "
    "sign the costates are neither plus nor minus the gradients.",
)
SIGMOID_DEF = D6.formula(
    "sigmoid", eq(sp.Function(r"\sigma")(sp.Symbol("z")), 1 / (1 + sp.exp(-sp.Symbol("z"))))
)
D6.formula("H", H_DEF)
G0 = D6.formula("no_running_cost", eq(_g(_xs, _us), 0))


_fxu = vector("f(x,u)")
PLAIN_LAYER = D6.formula("plain_layer", eq(_fxu, layer("sigma", False)["x_next"]))
RESIDUAL_LAYER = D6.formula("residual_layer", eq(_fxu, layer("sigma", True, _hstep)["x_next"]))
IDENTITY = D6.formula(
    "identity", eq(matrix(r"\left.\partial f/\partial x\right|_{K=0}"), sp.Identity(n))
)
_ADJ_NAMES = {
    "p_prev": vector(r"\partial H/\partial x"),
    "dH_dK": matrix(r"\partial H/\partial K"),
    "dH_dbeta": vector(r"\partial H/\partial \beta"),
}
ADJOINT = D6.formula(
    "adjoint",
    tuple(eq(_ADJ_NAMES[k], v) for k, v in layer("sigma", True, _hstep).items() if k in _ADJ_NAMES),
)
ADJOINT_PLAIN = D6.formula(
    "adjoint_plain",
    tuple(eq(_ADJ_NAMES[k], v) for k, v in layer("sigma", False).items() if k in _ADJ_NAMES),
)
_s = sp.Symbol("s")
ENDPOINT_S = D6.formula("endpoint", eq(_pa(_a, _N), _s * _dphi))
D6.formula("m8", M8)
D6.formula("endpoint_minus", ENDPOINT)
_dCdx, _dCdu = sp.IndexedBase(r"\partial C/\partial x"), sp.IndexedBase(r"\partial C/\partial u")
BACKPROP = D6.formula("backprop", eq(_pa(_a, _k), _s * _Sample(_dCdx, _a, _k)))
WEIGHTS = D6.formula(
    "weights", eq(_dCdu[_k], _s * sp.Sum(sp.Derivative(_H_ak, _u[_k]), (_a, 1, _M)))
)
D6.formula("cost", COST5)

# ---------------------------------------------------------------------------------------------
# the kernels

ARG_K = Arg("K", "(..., n, n)", "layer weight K_k")
ARG_BETA = Arg("beta", "(..., n, 1)", "layer bias beta_k")
ARG_X = Arg("x", "(..., n, 1)", "state x_k")
ARG_P = Arg("p", "(..., n, 1)", "costate p_{k+1}")
STEP_KERNELS: dict[tuple[str, bool], Kernel] = {}
ADJOINT_KERNELS: dict[tuple[str, bool], Kernel] = {}
for _act, _res in itertools.product(ACTIVATIONS, (True, False)):
    _exprs = layer(_act, _res)
    _suffix = _act + ("" if _res else "_plain")
    _form = f"x + {_act}(K x + beta)" if _res else f"{_act}(K x + beta)"
    STEP_KERNELS[(_act, _res)] = Kernel(
        name=f"resnet_step_{_suffix}",
        target="discrete_control",
        args=[ARG_K, ARG_BETA, ARG_X],
        outputs={"x_next": _exprs["x_next"]},
        doc=f"One {'residual' if _res else 'plain'} layer x_(k+1) = f(x_k, u_k) = {_form}.\n\n"
        "The control is u = (K, beta); the activation acts entrywise.",
        claims=("D6",),
    )
    ADJOINT_KERNELS[(_act, _res)] = Kernel(
        name=f"resnet_adjoint_{_suffix}",
        target="discrete_control",
        args=[ARG_K, ARG_BETA, ARG_X, ARG_P],
        outputs={k: _exprs[k] for k in ("p_prev", "dH_dK", "dH_dbeta")},
        doc=f"Adjoint step of the layer f(x, u) = {_form} for H = <p, f(x, u)>.\n\n"
        f"With z = K x + beta and s = {_act}'(z) * p (entrywise):\n"
        + ("p_k = dH/dx = p + K^T s" if _res else "p_k = dH/dx = K^T s")
        + ", dH/dK = s x^T, dH/dbeta = s.",
        claims=("D6",),
    )


# ---------------------------------------------------------------------------------------------
# D6 evidence


@D6.check(Level.SYMBOLIC_FIXED_N)
def d6_sigmoid() -> sp.Expr:
    """The activation of the logistic kernels is the displayed sigmoid $1/(1 + e^{-z})$ (read from
    the emitted step's expression; symbolic $z$)."""
    z = sp.Symbol("z", real=True)
    total = sp.Integer(0)
    for res in (True, False):
        step = STEP_KERNELS[("logistic", res)]["x_next"]
        (fn,) = {e.function for e in step.atoms(ElementwiseApplyFunction)}
        want = SIGMOID_DEF.rhs.xreplace({sp.Symbol("z"): z})
        total += residual(sp.simplify((fn(z) - want).rewrite(sp.exp)))
    return total


@D6.check(Level.SYMBOLIC_FIXED_N)
def d6_kernels() -> sp.Expr:
    r"""Each emitted step equals the displayed layer with $\sigma$ its activation and $h = 1$, and
    each emitted adjoint returns the explicit gradients in $x$, $K$ and $\beta$ of the displayed $H$
    with $f$ the emitted step and $g = 0$ (symbolic entries, $n = 3$, tanh and logistic, residual
    and plain)."""
    env = _layer_env(3)
    total = sp.Integer(0)
    for (act, res), kernel in STEP_KERNELS.items():
        x_next = explicit(kernel["x_next"], env)
        shown = RESIDUAL_LAYER if res else PLAIN_LAYER
        want = explicit(shown.rhs, {**env, "h": 1}).replace(_SIGMA, ACTIVATIONS[act][0])
        total += _nonzero(x_next - want)
        fn = {"f": lambda x, u, x_next=x_next: x_next, "g": _define(G0, {})}
        H = _define(H_DEF, fn)(env["p"], env["x"], sp.Symbol("u"))
        adjoint = ADJOINT_KERNELS[(act, res)]
        grads = {
            "p_prev": _grad(H, env["x"]),
            "dH_dK": env["K"].applyfunc(lambda kij, H=H: sp.diff(H, kij)),
            "dH_dbeta": _grad(H, env["beta"]),
        }
        for name, value in grads.items():
            total += _nonzero(explicit(adjoint[name], env) - value)
    return total


@D6.check(Level.SYMBOLIC_FIXED_N)
def d6_adjoint_formulas() -> sp.Expr:
    r"""The displayed adjoint formulas of both layers (generic activation $\sigma$, step $h$) are
    the gradients in $x$, $K$ and $\beta$ of the displayed $H$ with $f$ the displayed layer and $g =
    0$ (symbolic entries, $n = 2$)."""
    dim = 2
    env = _layer_env(dim)
    u = sp.Matrix([*env["K"], *env["beta"]])
    total = sp.Integer(0)
    for shown, adjoint in ((RESIDUAL_LAYER, ADJOINT), (PLAIN_LAYER, ADJOINT_PLAIN)):
        fn = {"f": _layer_function(shown, dim, _hstep), "g": _define(G0, {})}
        H = _define(H_DEF, fn)(env["p"], env["x"], u)
        du = _grad(H, u)
        grads = {
            r"\partial H/\partial x": _grad(H, env["x"]),
            r"\partial H/\partial K": _unflatten(du, dim)[0],
            r"\partial H/\partial \beta": _unflatten(du, dim)[1],
        }
        for formula in adjoint:
            total += _nonzero(explicit(lhs_minus_rhs(formula), {**env, **grads, "h": _hstep}))
    return total


def _cost_gradient(
    functions: dict[str, Any],
    values: dict[Any, Any],
    tails: list[tuple[int, int]],
    run: Callable[..., None],
    fresh: sp.Matrix,
    key: tuple[Any, ...],
) -> sp.Matrix:
    """Gradient of the displayed cost in the value ``key`` (a state x^a_k or a control u_k), the
    states of the given (sample, step) tails recomputed as functions of it.  The other values
    are constants of this partial derivative and are hidden behind symbols while differentiating.
    """
    hide, hidden = _hider()
    tail = {k: hide(v) for k, v in values.items()}
    tail[key] = fresh
    for a, k in tails:
        run(tail, a, k, tail[("x", a, k)])
    grad = _grad(_value(COST5.rhs, tail, functions), fresh)
    grad = grad.xreplace({d: v for v, d in hidden.items()})
    return grad.xreplace(dict(zip(fresh, values[key], strict=True)))


def _backprop_defect(
    endpoint: sp.Eq,
    signs: Sequence[int],
    running_cost: bool,
    layers: Sequence[sp.Eq] = (RESIDUAL_LAYER, PLAIN_LAYER),
    M: int = 2,
) -> int:
    """Networks of N = 2 displayed layers (generic sigma, h = 1), M samples, n = 2, random
    rational weights, inputs and target c, terminal cost phi(x) = |x - c|^2/2 and running cost
    g = 0 (the displayed no_running_cost) or g = (|x|^2 + |u|^2)/3.  Costates from the given
    endpoint condition and the costate equation p^a_k = dH/dx(p^a_{k+1}, x^a_k, u_k) of the
    displayed H; gradients of the displayed cost C in x^a_k and in u_k, the later states as
    functions of them.  Returns the number of entries of the displayed backprop and weights
    relations that fail for each sign s in ``signs``."""
    dim, N = 2, 2
    rng = np.random.default_rng(6)

    def rational(*shape: int) -> sp.Matrix:
        return sp.Matrix(
            *shape, [sp.Rational(int(v), 5) for v in rng.integers(-7, 8, int(np.prod(shape)))]
        )

    c = rational(dim, 1)
    if running_cost:

        def g(x: Any, u: Any) -> Any:
            return (_dot(x, x) + _dot(u, u)) / 3
    else:
        g = _define(G0, {})
    total = 0
    for shown in layers:
        f = _layer_function(shown, dim, sp.Integer(1))
        fn = _with_hamiltonians({"f": f, "g": g, "h": lambda u: sp.zeros(1, 1)})
        fn[r"\phi"] = lambda x: _dot(x - c, x - c) / 2
        values: dict[Any, Any] = {"N": N, "M": M, "s": _s}
        values.update({("u", k): rational(dim * dim + dim, 1) for k in range(N)})

        def run(values: dict[Any, Any], a: int, k: int, start: sp.Matrix, f: Any = f) -> None:
            values[("x", a, k)] = start
            for j in range(k, N):
                values[("x", a, j + 1)] = f(values[("x", a, j)], values[("u", j)])

        for a in range(1, M + 1):
            run(values, a, 0, rational(dim, 1))
        checks = []
        for a in range(1, M + 1):
            lhs, rhs = _instance(endpoint, {_a: a, _N: N})
            values[_key(lhs)] = _value(rhs, values, fn)
            for k in reversed(range(N)):
                lhs, rhs = _instance(_COSTATE5_EQ, {_a: a, _k: k})
                values[_key(lhs)] = _value(rhs, values, fn)
            for k in range(N + 1):
                xi = _vec("xi", dim)
                grad = _cost_gradient(fn, values, [(a, k)], run, xi, ("x", a, k))
                values[(str(_dCdx.label), a, k)] = grad
                checks.append(_instance(BACKPROP, {_a: a, _k: k}))
        for k in range(N):
            w = _vec("w", dim * dim + dim)
            grad = _cost_gradient(fn, values, [(a, k) for a in range(1, M + 1)], run, w, ("u", k))
            values[(str(_dCdu.label), k)] = grad
            checks.append(_instance(WEIGHTS, {_k: k}))
        for lhs, rhs in checks:
            gap = _minus(_value(lhs, values, fn), _value(rhs, values, fn))
            total += sum(_nonzero(gap.xreplace({_s: sign})) for sign in signs)
    return total


@D6.check(Level.EXACT_RATIONAL)
def d6_backprop_no_running_cost() -> int:
    r"""Both layers with a generic activation $\sigma$, $N = 2$ layers, $M = 2$ samples, $n = 2$,
    random rational weights, inputs and target, $\phi = |x - c|^2/2$, $g = 0$: with the displayed
    endpoint condition, the costates satisfy the displayed backprop relation at every layer and the
    weight gradients of the cost the displayed weights relation, for $s = 1$ (m8) and $s = -1$ (D5).
    """
    return _backprop_defect(ENDPOINT_S, (1, -1), running_cost=False)


@D6.check(Level.EXACT_RATIONAL, form="printed")
def d6_printed_m8_running_cost() -> int:
    """The same computation (residual layer, one sample) with a running cost $g = (|x|^2 + |u|^2)/3$
    and m8's endpoint condition: the backprop and weights relations with $s = 1$ fail (count of
    failing entries)."""
    return _backprop_defect(M8, (1,), running_cost=True, layers=(RESIDUAL_LAYER,), M=1)


@D6.check(Level.EXACT_RATIONAL, form="corrected")
def d6_corrected_running_cost() -> int:
    """The same with D5's endpoint condition: the backprop and weights relations with $s = -1$ hold."""
    return _backprop_defect(ENDPOINT, (-1,), running_cost=True, layers=(RESIDUAL_LAYER,), M=1)


def _identity_defect(shown: sp.Eq) -> sp.Expr:
    """The displayed property of a residual layer evaluated on a displayed layer: its Jacobian in
    x at K = 0 (generic sigma, symbolic beta and h, n = 2) minus the identity (count of entries)."""
    env = _layer_env(2)
    J = (
        explicit(shown.rhs, {**env, "h": _hstep})
        .jacobian(env["x"])
        .xreplace({kij: 0 for kij in env["K"]})
    )
    return _nonzero(explicit(lhs_minus_rhs(IDENTITY), {IDENTITY.lhs.name: J}))


@D6.check(Level.SYMBOLIC_FIXED_N, form="printed")
def d6_printed_plain_is_not_residual() -> sp.Expr:
    r"""Remark 1's layer $\sigma(K x + \beta)$ is not a perturbation of the identity: its Jacobian
    in $x$ at $K = 0$ is 0, not $I$ (count of mismatching entries, generic $\sigma$, $n = 2$)."""
    return _identity_defect(PLAIN_LAYER)


@D6.check(Level.SYMBOLIC_FIXED_N, form="corrected")
def d6_residual_layer_is_residual() -> sp.Expr:
    r"""The residual layer $x + h \sigma(K x + \beta)$ has Jacobian $I$ in $x$ at $K = 0$, for every
    $\beta$ and $h$ (generic $\sigma$, $n = 2$)."""
    return _identity_defect(RESIDUAL_LAYER)


@D6.check(Level.FLOAT64, tol=1e-12)
def d6_float64() -> float:
    r"""symrb.learning.resnet_forward, symrb.learning.costate_sweep and
    symrb.learning.loss_gradients (both activations, both layers; $n = 3$, $N = 4$, $M = 5$, 2
    random networks) against an independent NumPy forward pass and complex-step derivatives of its
    loss: states, $-p$ (D5's sign) against $\partial\Phi/\partial x^a_k$, and the weight gradients;
    largest error relative to the largest reference entry."""
    import symrb

    errors = []
    for seed, act, res in itertools.product(range(2), ACTIVATIONS, (True, False)):
        x0, Ks, bs, ys = random_network(seed)
        states = symrb.learning.resnet_forward(x0, Ks, bs, activation=act, residual=res)
        p = symrb.learning.costate_sweep(states, Ks, bs, ys, activation=act, residual=res)
        _loss, gK, gb = symrb.learning.loss_gradients(x0, Ks, bs, ys, activation=act, residual=res)
        ref_states = _reference_forward(x0, Ks, bs, act, res)
        cK, cb = complex_step_gradients(x0, Ks, bs, ys, act, res)
        cx = complex_step_state_gradients(ref_states, Ks, bs, ys, act, res)
        for got, want in ((states, ref_states), (gK, cK), (gb, cb), (-p, cx)):
            errors.append(np.max(np.abs(got - want)) / np.max(np.abs(want)))
    return float(np.max(errors))


# ---------------------------------------------------------------------------------------------
# every n: the layers in matrix symbols of symbolic size


def _layer_at(shown: sp.Basic, K: Any, x: Any, beta: Any, p: Any = None) -> Any:
    """A displayed layer or adjoint formula with its K, x, beta (and p) replaced."""
    sub = {_Km: K, _xv: x, _bv: beta}
    return shown.xreplace({**sub, _pv: p} if p is not None else sub)


@D6.check(Level.SYMBOLIC_GENERAL_N)
def d6_adjoint_formulas_general_n() -> sp.Expr:
    r"""Every $n$: the displayed adjoint formulas of both layers (generic $\sigma$, step $h$) are
    the gradients of the displayed $H$ with $f$ the displayed layer and $g = 0$: the derivative of
    $H$ along $dx$, $dK$ and $d\beta$ (SymPy's differentiation in $t$ of $H(x + t\,dx, \dots)$,
    $\sigma'$ entrywise) equals $\langle \partial H/\partial x, dx\rangle$,
    $\operatorname{tr}((\partial H/\partial K)^T dK)$ and $\langle \partial H/\partial\beta,
    d\beta\rangle$ from the displayed formulas (trace words left; $\sigma'(z) \circ v$ is
    $\operatorname{diag}(\sigma'(z))\, v$, a symmetric letter)."""
    w = Alphabet(symmetric=[])
    d = {"x": vector("dx"), "K": matrix("dK"), "beta": vector("dbeta")}
    fn = {"f": lambda x, u: _layer_at(u[2], u[0], x, u[1]), "g": lambda x, u: sp.ZeroMatrix(1, 1)}
    total = sp.Integer(0)
    for shown, adjoint in ((RESIDUAL_LAYER, ADJOINT), (PLAIN_LAYER, ADJOINT_PLAIN)):
        H = _define(H_DEF, fn)(_pv, _xv, (_Km, _bv, shown.rhs))
        grads = {str(f.lhs.name): f.rhs for f in adjoint}
        for var, name in ((_xv, r"\partial H/\partial x"), (_Km, r"\partial H/\partial K"),
                          (_bv, r"\partial H/\partial \beta")):  # fmt: skip
            dv = d[str(var.name)]
            along = w.nc(directional(H, {var: dv}))
            total += pairing_defect(
                along, w.T(w.nc(grads[name])) * w(str(dv.name)), w(str(dv.name)), w
            )
    return total


def _network_defect(shown: sp.Eq, adjoint: tuple[sp.Eq, ...], widths: Sequence[Any]) -> sp.Expr:
    """Two displayed layers x_1 = f(x_0, u_0), x_2 = f(x_1, u_1) in matrix symbols (widths
    n_0, n_1, n_2), phi(x) = G^T x (so G is the loss gradient at x_2; a gradient involves nothing
    more of phi), costates from the displayed endpoint condition and the displayed adjoint
    p_k = dH/dx: trace words left in the displayed backprop relation paired with dx (k = 0, 1) and
    in the weights relation (one sample) paired with dK_k, dbeta_k, for s = 1 and s = -1."""
    w = Alphabet(symmetric=[])
    X = [sp.MatrixSymbol(f"x_{k}", widths[k], 1) for k in range(3)]
    Ks = [sp.MatrixSymbol(f"K_{k}", widths[k + 1], widths[k]) for k in range(2)]
    bs = [sp.MatrixSymbol(f"beta_{k}", widths[k + 1], 1) for k in range(2)]
    G = sp.MatrixSymbol("G", widths[2], 1)
    grads = {str(f.lhs.name): f.rhs for f in adjoint}
    x1 = _layer_at(shown.rhs, Ks[0], X[0], bs[0])
    states = [X[0], x1, _layer_at(shown.rhs, Ks[1], x1, bs[1])]
    fn = {r"\phi": lambda x: G.T * x}
    _lhs, end = _instance(ENDPOINT_S, {_a: 1, _N: 2})
    p = {2: _value(end, {("x", 1, 2): X[2], "s": _s}, fn)}
    for k in (1, 0):
        p[k] = _layer_at(grads[r"\partial H/\partial x"], Ks[k], states[k], bs[k], p[k + 1])
    total = sp.Integer(0)
    for k in (0, 1):  # dC along dx_k, the later states recomputed from a free x_k
        tail = X[k]
        for j in range(k, 2):
            tail = _layer_at(shown.rhs, Ks[j], tail, bs[j])
        dx = sp.MatrixSymbol(f"dx_{k}", widths[k], 1)
        dC = (G.T * directional(tail, {X[k]: dx})).xreplace({X[1]: x1})
        vals = {
            ("p", 1, k): w.T(w.nc(p[k])) * w(str(dx.name)),
            (str(_dCdx.label), 1, k): w.nc(dC),
            "s": _s,
        }
        lhs, rhs = _instance(BACKPROP, {_a: 1, _k: k})
        total += pairing_defect(_value(lhs, vals, {}), _value(rhs, vals, {}), w(str(dx.name)), w)
        for var, name in ((Ks[k], r"\partial H/\partial K"), (bs[k], r"\partial H/\partial \beta")):
            dv = w(f"d{var.name}")
            along = w.nc(G.T * directional(states[2], {var: sp.MatrixSymbol(str(dv), *var.shape)}))
            dH = _layer_at(grads[name], Ks[k], states[k], bs[k], p[k + 1])
            vals = {"dHdu": w.T(w.nc(dH)) * dv, "M": 1, "s": _s}
            weights = WEIGHTS.rhs.xreplace({sp.Derivative(_H_ak, _u[_k]): _dHdu})
            for sign in (1, -1):  # s^2 = 1: the weights relation needs s = +-1
                total += pairing_defect(along, _value(weights, vals, {}).subs(_s, sign), dv, w)
    return total


_dHdu = sp.Symbol("dHdu")
_n0, _n1, _n2 = sp.symbols("n_0 n_1 n_2", integer=True, positive=True)


@D6.check(Level.SYMBOLIC_GENERAL_N)
def d6_backprop_general_n() -> sp.Expr:
    r"""Every width: two displayed plain layers $\mathbb{R}^{n_0} \to \mathbb{R}^{n_1} \to
    \mathbb{R}^{n_2}$ ($K_k$ of size $n_{k+1} \times n_k$) and two residual layers (width $n$),
    generic $\sigma$, one sample, the loss gradient at $x_2$ a vector symbol $G$: with the displayed
    endpoint condition $p_2 = s G$ and the displayed adjoint, $p_k$ paired with $dx_k$ equals $s$
    times the derivative of the loss along $dx_k$ (SymPy's differentiation of the composed layers),
    the displayed backprop relation; and the derivatives along $dK_k$, $d\beta_k$ equal $s$ times
    the pairing with the displayed $\partial H/\partial K$, $\partial H/\partial\beta$, the
    displayed weights relation ($s = 1$ and $s = -1$). Any number of layers follows by induction:
    each step is the chain rule through one layer (trace words left)."""
    return _network_defect(PLAIN_LAYER, ADJOINT_PLAIN, (_n0, _n1, _n2)) + _network_defect(
        RESIDUAL_LAYER, ADJOINT, (n, n, n)
    )


def _identity_general_n(shown: sp.Eq) -> sp.Expr:
    """Words left in (J - displayed right side of the identity property) dx, J dx the derivative
    of the displayed layer along dx at K = 0 (every n, generic sigma, symbolic beta and h)."""
    w = Alphabet()
    dx = vector("dx")
    J_dx = directional(shown.rhs, {_xv: dx}).xreplace({_Km: sp.ZeroMatrix(n, n)})
    return w.is_zero(w.nc(J_dx) - w.nc(IDENTITY.rhs * dx))


@D6.check(Level.SYMBOLIC_GENERAL_N, form="printed")
def d6_printed_plain_is_not_residual_general_n() -> sp.Expr:
    r"""Every $n$: the derivative of Remark 1's layer $\sigma(K x + \beta)$ along $dx$ at $K = 0$ is
    0, not the displayed $I\,dx$ (words left)."""
    return _identity_general_n(PLAIN_LAYER)


@D6.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def d6_residual_layer_is_residual_general_n() -> sp.Expr:
    r"""Every $n$: the derivative of $x + h \sigma(K x + \beta)$ along $dx$ at $K = 0$ is the
    displayed $I\,dx$, for every $\beta$ and $h$ (words left)."""
    return _identity_general_n(RESIDUAL_LAYER)


def _running_cost_general_n(endpoint: sp.Eq, s: int) -> sp.Expr:
    """Two displayed residual layers of width n (generic sigma, h), one sample, running cost
    g(x, u) = x^T R x/2 (R a symmetric matrix symbol), phi(x) = G^T x: costates from the given
    endpoint condition and the displayed costate equation p_k = dH/dx(p_{k+1}, x_k, u_k) (the
    gradient of the displayed H along dx, p_{k+1} held as a letter and then substituted), against
    s times the derivative of the displayed cost C along dx_k, the later states recomputed
    (trace words left, k = 0, 1, 2)."""
    w = Alphabet(symmetric=["R"])
    X0, G, R, P = vector("x_0"), vector("G"), matrix("R"), vector("P")
    us = [(matrix(f"K_{k}"), vector(f"beta_{k}")) for k in range(2)]
    fn = _with_hamiltonians({
        "f": lambda x, u: _layer_at(RESIDUAL_LAYER.rhs, u[0], x, u[1]),
        "g": lambda x, u: x.T * R * x / 2,
        "h": lambda u: sp.ZeroMatrix(1, 1),
        r"\phi": lambda x: G.T * x,
    })  # fmt: skip
    states = [X0]
    for k in range(2):
        states.append(fn["f"](states[k], us[k]))
    values = {"N": 2, "M": 1, **{("u", k): us[k] for k in range(2)}}
    t, dx = sp.Symbol("t"), vector("dx")
    lhs, rhs = _instance(endpoint, {_a: 1, _N: 2})
    p = {2: w.nc(_value(rhs, {**values, ("x", 1, 2): states[2]}, fn))}
    for k in (1, 0):
        H = fn["H"](P, states[k] + t * dx, us[k])
        along = w.nc(sp.diff(H, t).xreplace({t: 0}))
        p[k] = substitute(gradient(along, w("dx"), w), w("P"), p[k + 1], w)
    total = sp.Integer(0)
    for k in range(3):
        moved = {**values, **{("x", 1, j): states[j] for j in range(k)}}
        moved[("x", 1, k)] = states[k] + t * dx
        for j in range(k, 2):
            moved[("x", 1, j + 1)] = fn["f"](moved[("x", 1, j)], us[j])
        dC = w.nc(sp.diff(_value(COST5.rhs, moved, fn), t).xreplace({t: 0}))
        total += pairing_defect(w.T(p[k]) * w("dx"), s * dC, w("dx"), w)
    return total


@D6.check(Level.SYMBOLIC_GENERAL_N, form="printed")
def d6_printed_m8_running_cost_general_n() -> sp.Expr:
    r"""Every $n$, with a running cost $g = x^T R x/2$ ($R$ a symmetric matrix symbol), two
    displayed residual layers, $\phi = G^T x$: with m8's endpoint condition the costates are not the
    gradients of the displayed cost ($s = 1$), for every $n$ (trace words left)."""
    return _running_cost_general_n(M8, 1)


@D6.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def d6_corrected_running_cost_general_n() -> sp.Expr:
    """The same with D5's endpoint condition: the costates are minus the gradients of the displayed
    cost ($s = -1$) at every layer, for every $n$."""
    return _running_cost_general_n(ENDPOINT, -1)


# the paper's sentences (the paragraph 'Remark' closing Section 2 before Section 2.1)

D6.sentence(
    r"Remark 1. As described in [BeCeEhOwSc2019], a common choice for $f$ is "
    r"$f(x,u)=\sigma(Kx+\beta)$, where $u=(K,\beta)$ and $sigma$ is the sigmoid function.",
    d6_sigmoid,
    d6_kernels,
    d6_adjoint_formulas,
    d6_float64,
    d6_adjoint_formulas_general_n,
)
D6.sentence(
    r"This is the so-called ResNet framework.",
    d6_printed_plain_is_not_residual,
    d6_residual_layer_is_residual,
    d6_printed_plain_is_not_residual_general_n,
    d6_residual_layer_is_residual_general_n,
)
D6.sentence(
    r"We can, of course, consider other problems of this type but here we are interested in a "
    r"particular group theoretic form.",
    kind="prose",
    reason="motivation for Section 2.1",
)
D6.sentence(
    r"2. The form of the solution in Proposition (gendiscpropm) is very close to that of "
    r"[LeCun1988] and, at least on a superficial level, even more so in the rigid body case.",
    d6_backprop_no_running_cost,
    d6_printed_m8_running_cost,
    d6_corrected_running_cost,
    d6_float64,
    d6_backprop_general_n,
    d6_printed_m8_running_cost_general_n,
    d6_corrected_running_cost_general_n,
)
