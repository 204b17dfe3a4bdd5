r"""Discrete optimal control and deep learning (paper, Section 2, first part): claims D1-D6.

Conventions fixed here (and stated on the book pages):

* :math:`H(p_{k+1},x_k,u_k) = \langle p_{k+1}, f(x_k,u_k)\rangle - g(x_k,u_k)` as printed, and the
  problem is a *minimisation*; the augmented functional whose critical points we take is
  :math:`V = \sum_k \langle p_{k+1}, f(x_k,u_k) - x_{k+1}\rangle + \langle\sigma_k, h(u_k)\rangle
  - g(x_k,u_k)\,[- \sum_a\phi(x^a_N)]`, i.e. minus the cost plus multiplier terms;
* with this sign the costate is *minus* the gradient of the cost-to-go:
  :math:`p_k = -\partial C/\partial x_k`; the weight gradient is
  :math:`\partial C/\partial u_k = -\sum_a \partial H/\partial u_k`;
* :math:`H^*(y,x) = \hat H(y,x,u^*(y,x),\sigma(y,x))` is the reduced (optimised) Hamiltonian;
  by the envelope argument :math:`\partial H^*/\partial x = \partial H/\partial x` and
  :math:`\partial H^*/\partial y = \partial H/\partial y` at :math:`u^*`;
* for matrices of second derivatives, :math:`(H^*_{xy})_{ij} = \partial^2 H^*/\partial x_i\partial y_j`.

Derived here (each claim's evidence is a function below):

* D1: the stationarity conditions of the augmented functional (undefined smooth f, g, h; n = 2,
  m = 2, l = 1, N = 3) and three errata: the proof's rewriting with :math:`\sum_{k=0}^{N}` and
  :math:`p_{N+1}=0` adds a phantom term; the costate equation at k = N does not hold (p_N is free
  for a fixed endpoint); the proof's functional V needs one multiplier :math:`\sigma_k` per step;
* D2: the implicit step needs the mixed second derivative of the *reduced* Hamiltonian H*
  invertible; the printed condition on H at fixed u is not sufficient (exact counterexample);
* D3: the linearised equations hold with H* (not H-hat at frozen u*) and with the transpose of the
  mixed-derivative matrix in the second line;
* D4: the advance map is symplectic (generic second derivatives, n = 2, 3; float64 on a random
  nonlinear family solved with scipy);
* D5: the multi-sample problem with terminal cost: free endpoint, per-sample states in the costate
  equation, :math:`p^a_N = -\nabla\phi(x^a_N)` for this H, multipliers :math:`\sigma_k`;
* D6: the costate recursion for the ResNet layers :math:`f(x,u)=x+\sigma(Kx+\beta)` and
  :math:`f(x,u)=\sigma(Kx+\beta)` is back-propagation: :math:`-p^a_k = \partial\Phi/\partial x^a_k`,
  :math:`\partial\Phi/\partial K_k = -\sum_a\partial H/\partial K_k`.

Emitted (``symrb/_generated/discrete_control.py``): ResNet forward steps and adjoint (costate and
dH/du) steps for tanh and the logistic sigmoid, residual and plain, at matrix level.
"""

from __future__ import annotations

import itertools

import numpy as np
import sympy as sp
from sympy.matrices.expressions.applyfunc import ElementwiseApplyFunction

from derivations.codegen import Arg, Kernel, n
from derivations.registry import Claim, Evidence, Level
from derivations.symbolic import residual

# ---------------------------------------------------------------------------------------------
# small helpers


def _vec(name: str, dim: int) -> sp.Matrix:
    return sp.Matrix([sp.Symbol(f"{name}_{i + 1}", real=True) for i in range(dim)])


def _grad(expr: sp.Expr, v: sp.Matrix) -> sp.Matrix:
    return sp.Matrix([sp.diff(expr, s) for s in v])


def _jac(F: sp.Matrix, v: sp.Matrix) -> sp.Matrix:
    """(dF_i / dv_j)."""
    return F.jacobian(v)


class GeneralProblem:
    """Undefined smooth f: R^n x R^m -> R^n, g: R^n x R^m -> R, h: R^m -> R^l, phi: R^n -> R.

    ``H(y, x, u)`` and ``Hhat(y, x, u, s)`` are built from the printed definitions eq8.4, eq8.5.
    """

    def __init__(self, nx: int = 2, nu: int = 2, nl: int = 1) -> None:
        self.nx, self.nu, self.nl = nx, nu, nl
        X, U = _vec("X", nx), _vec("U", nu)
        self._X, self._U = X, U
        args = (*X, *U)
        self._f = sp.Matrix([sp.Function(f"f{i + 1}")(*args) for i in range(nx)])
        self._g = sp.Function("g")(*args)
        self._h = sp.Matrix([sp.Function(f"h{i + 1}")(*U) for i in range(nl)])
        self._phi = sp.Function("phi")(*X)

    def _at(self, expr, x: sp.Matrix, u: sp.Matrix | None = None):
        sub = dict(zip(self._X, x, strict=True))
        if u is not None:
            sub.update(zip(self._U, u, strict=True))
        return expr.xreplace(sub)

    def f(self, x, u):
        return self._at(self._f, x, u)

    def g(self, x, u):
        return self._at(self._g, x, u)

    def h(self, u):
        return self._h.xreplace(dict(zip(self._U, u, strict=True)))

    def phi(self, x):
        return self._at(self._phi, x)

    def H(self, y, x, u):
        return (y.T * self.f(x, u))[0, 0] - self.g(x, u)

    def Hhat(self, y, x, u, s):
        return self.H(y, x, u) + (s.T * self.h(u))[0, 0]


# ---------------------------------------------------------------------------------------------
# D1: the discrete maximum principle (fixed endpoints)


def d1_stationarity(N: int = 3) -> sp.Expr:
    """Stationarity of V = sum_k <p_{k+1}, f(x_k,u_k) - x_{k+1}> + <sigma_k, h(u_k)> - g(x_k,u_k)
    (x_0, x_N fixed) is exactly: x_{k+1} = dH/dp (k = 0..N-1), p_k = dH/dx (k = 1..N-1),
    dHhat/du_k (with sigma_k) = 0 and h(u_k) = 0 (k = 0..N-1).  Undefined f, g, h; n = m = 2, l = 1.
    """
    P = GeneralProblem(2, 2, 1)
    xs = [_vec(f"x{k}", P.nx) for k in range(N + 1)]
    us = [_vec(f"u{k}", P.nu) for k in range(N)]
    ps = [None] + [_vec(f"p{k}", P.nx) for k in range(1, N + 1)]
    ss = [_vec(f"s{k}", P.nl) for k in range(N)]
    V = sum(
        (
            (ps[k + 1].T * (P.f(xs[k], us[k]) - xs[k + 1]))[0, 0]
            + (ss[k].T * P.h(us[k]))[0, 0]
            - P.g(xs[k], us[k])
            for k in range(N)
        ),
        sp.Integer(0),
    )
    y, x, u, s = _vec("Y", P.nx), _vec("Xg", P.nx), _vec("Ug", P.nu), _vec("S", P.nl)
    Hh = P.Hhat(y, x, u, s)
    Hp, Hx, Hu = _grad(Hh, y), _grad(Hh, x), _grad(Hh, u)

    def at(e, k):
        sub = dict(zip(y, ps[k + 1], strict=True))
        sub.update(zip(x, xs[k], strict=True))
        sub.update(zip(u, us[k], strict=True))
        sub.update(zip(s, ss[k], strict=True))
        return e.xreplace(sub)

    total = sp.Integer(0)
    for k in range(N):
        total += residual(_grad(V, ps[k + 1]) - (at(Hp, k) - xs[k + 1]))  # state equation
        total += residual(_grad(V, us[k]) - at(Hu, k))  # eq8.6 with sigma_k
        total += residual(_grad(V, ss[k]) - P.h(us[k]))  # constraint
    for k in range(1, N):
        total += residual(_grad(V, xs[k]) - (at(Hx, k) - ps[k]))  # costate, k = 1..N-1
    # x_N is fixed, so no condition ties p_N to anything else: V is affine in p_N through x_N only
    return total


def d1_printed_rewrite(N: int = 2) -> sp.Expr:
    """The proof rewrites sum_{k<N}(-<p_{k+1},x_{k+1}> + Hhat_k) as <p_0,x_0> + sum_{k=0}^{N}
    (-<p_k,x_k> + Hhat(p_{k+1},x_k,u_k,sigma)) with p_{N+1} = 0.  The difference is
    Hhat(0, x_N, u_N, sigma) = -g(x_N,u_N) + <sigma,h(u_N)>, not zero: a phantom control u_N."""
    P = GeneralProblem(2, 2, 1)
    xs = [_vec(f"x{k}", P.nx) for k in range(N + 1)]
    us = [_vec(f"u{k}", P.nu) for k in range(N + 1)]  # u_N is the phantom the rewrite needs
    ps = [_vec(f"p{k}", P.nx) for k in range(N + 2)]
    ps[N + 1] = sp.zeros(P.nx, 1)
    s = _vec("s", P.nl)
    line2 = sum(
        (-(ps[k + 1].T * xs[k + 1])[0, 0] + P.Hhat(ps[k + 1], xs[k], us[k], s) for k in range(N)),
        sp.Integer(0),
    )
    line3 = (ps[0].T * xs[0])[0, 0] + sum(
        (-(ps[k].T * xs[k])[0, 0] + P.Hhat(ps[k + 1], xs[k], us[k], s) for k in range(N + 1)),
        sp.Integer(0),
    )
    return residual(line2 - line3)


# exact example 1 (n = m = 1, no constraint): f = x + u, g = u^2/2, x_0 = 0, x_2 = 1


def example_terminal_costate() -> dict[str, sp.Expr]:
    """Minimise u_0^2/2 + u_1^2/2 with x_{k+1} = x_k + u_k, x_0 = 0, x_2 = 1.

    The minimiser is u_0 = u_1 = 1/2; stationarity in u_1 gives p_2 = u_1 = 1/2.  The printed
    costate equation at k = N with p_{N+1} = 0 reads p_N = dH/dx(0, x_N, u_N) = -dg/dx = 0.
    """
    u0, u1, p1, p2 = sp.symbols("u0 u1 p1 p2", real=True)
    x, u, y = sp.symbols("x u y", real=True)
    f, g = x + u, u**2 / 2
    H = y * f - g
    # direct minimisation with u_1 = 1 - u_0
    u0_opt = sp.solve(sp.diff((u0**2 + (1 - u0) ** 2) / 2, u0), u0)[0]
    sol = {u0: u0_opt, u1: 1 - u0_opt}
    # stationarity in u_k: dH/du(p_{k+1}, x_k, u_k) = 0
    eqs = [
        sp.diff(H, u).subs({y: p1, x: 0, u: sol[u0]}),
        sp.diff(H, u).subs({y: p2, x: sol[u0], u: sol[u1]}),
    ]
    ps = sp.solve(eqs, [p1, p2], dict=True)[0]
    # costate equation at k = 1 (interior): p_1 = dH/dx(p_2, x_1, u_1)
    interior = ps[p1] - sp.diff(H, x).subs({y: ps[p2], x: sol[u0], u: sol[u1]})
    printed_pN = sp.diff(H, x).subs({y: 0, x: 1})  # any u_N: -dg/dx = 0
    return {
        "u0": sol[u0],
        "u1": sol[u1],
        "p1": ps[p1],
        "p2": ps[p2],
        "interior": interior,
        "printed_pN": printed_pN,
    }


def d1_printed_costate_at_N() -> sp.Expr:
    ex = example_terminal_costate()
    return abs(ex["p2"] - ex["printed_pN"])


def d1_corrected_costate_interior() -> sp.Expr:
    ex = example_terminal_costate()
    return abs(ex["interior"])


# exact example 2 (n = 1, m = 2, l = 1): h(u) = u1 - u2, f = x + u1, g = (u1^2 + (u2 - x)^2)/2


def example_multiplier(single_sigma: bool = False) -> list[dict[sp.Symbol, sp.Expr]]:
    """KKT system of: minimise sum_k g(x_k,u_k), x_{k+1} = x_k + u_{k,1}, h(u_k) = u_{k,1} - u_{k,2}
    = 0, g = (u_1^2 + (u_2 - x)^2)/2, N = 2, x_0 = 0, x_2 = 1.  Solved exactly (it is linear).
    With ``single_sigma`` one multiplier is shared by both steps, as in the proof's functional V."""
    x, y, s = sp.symbols("x y s", real=True)
    U = sp.symbols("U1 U2", real=True)
    f = x + U[0]
    g = (U[0] ** 2 + (U[1] - x) ** 2) / 2
    h = U[0] - U[1]
    Hh = y * f - g + s * h
    x1, p1, p2 = sp.symbols("x1 p1 p2", real=True)
    u = [sp.symbols(f"u{k}_1 u{k}_2", real=True) for k in range(2)]
    sig = [sp.Symbol("sigma", real=True)] * 2 if single_sigma else list(sp.symbols("sigma0 sigma1"))
    xs, ps = [sp.Integer(0), x1, sp.Integer(1)], [None, p1, p2]

    def at(e, k):
        return e.subs({y: ps[k + 1], x: xs[k], U[0]: u[k][0], U[1]: u[k][1], s: sig[k]})

    eqs = []
    for k in range(2):
        eqs.append(xs[k + 1] - at(f, k))
        eqs += [at(sp.diff(Hh, U[i]), k) for i in range(2)]
        eqs.append(at(h, k))
    eqs.append(p1 - at(sp.diff(Hh, x), 1))
    unknowns = [x1, p1, p2, *u[0], *u[1], *sorted(set(sig), key=str)]
    return sp.solve(eqs, unknowns, dict=True)


def example_multiplier_minimiser() -> sp.Expr:
    """Direct minimisation (u_{k,1} = u_{k,2} = v_k, v_0 + v_1 = 1): v_0 = 3/7."""
    v0 = sp.Symbol("v0", real=True)
    v1 = 1 - v0
    cost = (v0**2 + v0**2) / 2 + (v1**2 + (v1 - v0) ** 2) / 2
    return sp.solve(sp.diff(cost, v0), v0)[0]


def d1_corrected_multipliers() -> sp.Expr:
    """With sigma_k per step the KKT system has one solution, and it is the true minimiser."""
    sols = example_multiplier(single_sigma=False)
    if len(sols) != 1:
        return sp.Integer(1)
    u01 = sols[0][sp.Symbol("u0_1", real=True)]
    return abs(u01 - example_multiplier_minimiser())


def d1_printed_single_sigma() -> sp.Expr:
    """|sigma_0 - sigma_1| at the minimiser (2/7): a single sigma cannot serve both steps
    (and the printed system with one sigma has no solution at all)."""
    sol = example_multiplier(single_sigma=False)[0]
    s0, s1 = sp.symbols("sigma0 sigma1")
    return abs(sol[s0] - sol[s1])


# ---------------------------------------------------------------------------------------------
# D2: the implicit step


def _reduced(H: sp.Expr, u: sp.Symbol) -> tuple[sp.Expr, sp.Expr]:
    """u*(y, x) from dH/du = 0 (unique here) and H*(y, x) = H(y, x, u*)."""
    sols = sp.solve(sp.diff(H, u), u)
    if len(sols) != 1:
        raise ValueError(f"expected a unique u*, got {sols}")
    return sols[0], sp.simplify(H.subs(u, sols[0]))


def d2_envelope_family() -> sp.Expr:
    """f = a(x) + b(x) u, g = u^2/2 + V(x) (a, b, V undefined): u* = b y, and
    d/dy [dH/dx(y, x, u*(y, x))] = d^2H*/dy dx = a' + 2 b b' y, while the printed matrix at u = u*
    is d^2H/dy dx = a' + b' u* = a' + b b' y: the step is governed by H*, not by H at fixed u."""
    x, y, u = sp.symbols("x y u", real=True)
    a, b, V = (sp.Function(c)(x) for c in "abV")
    H = y * (a + b * u) - u**2 / 2 - V
    ustar, Hstar = _reduced(H, u)
    step_map = sp.diff(H, x).subs(u, ustar)  # p_k as a function of y = p_{k+1}
    r = residual(sp.diff(step_map, y) - sp.diff(Hstar, x, y))  # IFT matrix = H*_xy
    r += residual(sp.diff(Hstar, x) - step_map)  # envelope: H*_x = H_x at u*
    r += residual(sp.diff(Hstar, y) - sp.diff(H, y).subs(u, ustar))  # H*_y = H_y at u*
    expected = sp.diff(a, x) + 2 * b * sp.diff(b, x) * y
    return r + residual(sp.diff(Hstar, x, y) - expected)


def d2_singular_not_unique() -> sp.Expr:
    """f = u (no x), g = (u^2 + x^2)/2: H*_xy = 0 and p_k = -x_k for every p_{k+1}: the step does
    not determine p_{k+1} (every y solves, none if p_k != -x_k).  Residual 0 when verified."""
    x, y, u = sp.symbols("x y u", real=True)
    H = y * u - (u**2 + x**2) / 2
    _ustar, Hstar = _reduced(H, u)
    r = residual(sp.diff(Hstar, x, y))
    r += residual(sp.diff(Hstar, x) + x)  # p_k = -x_k, independent of p_{k+1}
    return r


def d2_printed_condition_insufficient() -> sp.Expr:
    """Exact counterexample to the printed condition: f = x + u, g = (u + x)^2/2 >= 0.
    d^2H/dy dx = 1 at every (y, x, u) (the printed matrix is invertible everywhere), yet
    u* = y - x and p_k = dH/dx(y, x, u*) = 0 for every y: p_{k+1} is not determined.
    Returns 1 when this is confirmed (the printed sufficiency claim fails), else 0."""
    x, y, u = sp.symbols("x y u", real=True)
    H = y * (x + u) - (u + x) ** 2 / 2
    ustar, Hstar = _reduced(H, u)
    printed_matrix = sp.diff(H, y, x)
    step = sp.diff(H, x).subs(u, ustar)
    confirmed = (
        sp.simplify(printed_matrix - 1) == 0
        and sp.simplify(sp.diff(step, y)) == 0
        and sp.simplify(sp.diff(Hstar, x, y)) == 0
    )
    return sp.Integer(1) if confirmed else sp.Integer(0)


# ---------------------------------------------------------------------------------------------
# D3: linearised extremal equations


def _d3_family():
    """n = m = 2: f = a(x) + B u (a undefined, B a constant symbolic matrix), g = |u|^2/2 + V(x).
    u* = B^T y.  Returns (x, y, H(y,x,u), u, u*, H*)."""
    x, y, u = _vec("x", 2), _vec("y", 2), _vec("u", 2)
    a = sp.Matrix([sp.Function(f"a{i + 1}")(*x) for i in range(2)])
    V = sp.Function("V")(*x)
    B = sp.Matrix(2, 2, sp.symbols("b11 b12 b21 b22", real=True))
    H = (y.T * (a + B * u))[0, 0] - (u.T * u)[0, 0] / 2 - V
    sols = sp.solve(list(_grad(H, u)), list(u), dict=True)
    ustar = sp.Matrix([sols[0][ui] for ui in u])
    Hstar = sp.expand(H.xreplace(dict(zip(u, ustar, strict=True))))
    return x, y, H, u, ustar, Hstar


def _d3_true_linearisation():
    """Jacobians of the actual maps (x_k, y) -> p_k = H_x(y, x_k, u*), x_{k+1} = H_y(y, x_k, u*)."""
    x, y, H, u, ustar, Hstar = _d3_family()
    sub = dict(zip(u, ustar, strict=True))
    Pk = _grad(H, x).xreplace(sub)
    Xk1 = _grad(H, y).xreplace(sub)
    return x, y, H, u, ustar, Hstar, (_jac(Pk, x), _jac(Pk, y), _jac(Xk1, x), _jac(Xk1, y))


def d3_corrected() -> sp.Expr:
    """dp_k = H*_xx dx_k + H*_xy dp_{k+1}, dx_{k+1} = (H*_xy)^T dx_k + H*_yy dp_{k+1}."""
    x, y, _H, _u, _us, Hs, (Pxx, Pxy, Xx, Xy) = _d3_true_linearisation()
    Hxx = sp.hessian(Hs, x)
    Hyy = sp.hessian(Hs, y)
    Hxy = sp.Matrix(2, 2, lambda i, j: sp.diff(Hs, x[i], y[j]))
    return residual(Pxx - Hxx) + residual(Pxy - Hxy) + residual(Xx - Hxy.T) + residual(Xy - Hyy)


def d3_printed_frozen_control() -> sp.Expr:
    """The printed corollary with second derivatives of Hhat at frozen (u*, sigma): the dp_{k+1}
    coefficient of dx_{k+1} is d^2Hhat/dp^2 = 0 (Hhat is linear in p), but the true one is
    H*_yy = B B^T.  Returns the number of mismatching entries (printed form fails when > 0)."""
    x, y, H, u, ustar, _Hs, (Pxx, Pxy, Xx, Xy) = _d3_true_linearisation()
    sub = dict(zip(u, ustar, strict=True))
    frozen_yy = sp.hessian(H, y).xreplace(sub)
    frozen_xx = sp.hessian(H, x).xreplace(sub)
    return residual(Xy - frozen_yy) + residual(Pxx - frozen_xx)


def d3_printed_same_matrix() -> sp.Expr:
    """Even with H*, the printed corollary uses one matrix d^2H/dp dx in both lines.  Whichever
    index convention it denotes, one of the two lines is off by a transpose for n = 2 (a(x)
    generic): returns the smaller of the two mismatch counts."""
    x, y, _H, _u, _us, Hs, (_Pxx, Pxy, Xx, _Xy) = _d3_true_linearisation()
    Hxy = sp.Matrix(2, 2, lambda i, j: sp.diff(Hs, x[i], y[j]))
    Hyx = Hxy.T
    as_xy = residual(Pxy - Hxy) + residual(Xx - Hxy)
    as_yx = residual(Pxy - Hyx) + residual(Xx - Hyx)
    return sp.Min(as_xy, as_yx)


def _d3_nonlinear_gap(blocks: str, seeds=range(3)) -> float:
    """Largest |J_blocks - J_true| on the nonlinear family (u* depends on x and on p_{k+1}),
    J_true by implicit differentiation of the advance map, J_blocks from the D3 linearisation
    with the given second-derivative blocks ("reduced": of H*, "frozen": of Hhat at fixed u*)."""
    worst = 0.0
    for seed in seeds:
        fam = NonlinearFamily(3, 2, seed=seed)
        rng = np.random.default_rng(100 + seed)
        xk, pk = 0.5 * rng.standard_normal(3), 0.5 * rng.standard_normal(3)
        _, y, u = fam.advance(xk, pk)
        get = fam.reduced_hessian_blocks if blocks == "reduced" else fam.frozen_hessian_blocks
        J_blocks = advance_jacobian_from_blocks(*get(xk, y, u))
        worst = max(worst, float(np.abs(J_blocks - fam.advance_jacobian(xk, pk)).max()))
    return worst


# ---------------------------------------------------------------------------------------------
# D4: symplecticity of the advance map


def advance_jacobian_from_blocks(Hxx, Hxy, Hyy):
    """Jacobian of (x_k, p_k) -> (x_{k+1}, p_{k+1}) from the corrected linearisation (D3):
    dp_{k+1} = Hxy^{-1} (dp_k - Hxx dx_k), dx_{k+1} = Hxy^T dx_k + Hyy dp_{k+1}.
    Works for SymPy matrices and NumPy arrays."""
    if isinstance(Hxx, sp.MatrixBase):
        A_inv = Hxy.inv()
        top = (Hxy.T - Hyy * A_inv * Hxx).row_join(Hyy * A_inv)
        bot = (-A_inv * Hxx).row_join(A_inv)
        return top.col_join(bot)
    A_inv = np.linalg.inv(Hxy)
    top = np.hstack([Hxy.T - Hyy @ A_inv @ Hxx, Hyy @ A_inv])
    bot = np.hstack([-A_inv @ Hxx, A_inv])
    return np.vstack([top, bot])


def omega(dim: int):
    """The canonical form Omega = [[0, I], [-I, 0]] in coordinates (x, p) (dx ^ dp)."""
    return np.block([[np.zeros((dim, dim)), np.eye(dim)], [-np.eye(dim), np.zeros((dim, dim))]])


def d4_symbolic(dim: int = 2) -> sp.Expr:
    """Jac^T Omega Jac = Omega for generic symmetric Hxx, Hyy and generic invertible Hxy (n = dim):
    every smooth H* with invertible mixed derivative.  Denominators are cleared with det(Hxy)."""
    Hxx = sp.Matrix(dim, dim, lambda i, j: sp.Symbol(f"s{min(i, j)}{max(i, j)}"))
    Hyy = sp.Matrix(dim, dim, lambda i, j: sp.Symbol(f"t{min(i, j)}{max(i, j)}"))
    A = sp.Matrix(dim, dim, lambda i, j: sp.Symbol(f"a{i}{j}"))
    det = A.det()
    adj = A.adjugate()  # A^{-1} = adj / det
    top = (det * A.T - Hyy * adj * Hxx).row_join(Hyy * adj)
    bot = (-adj * Hxx).row_join(adj)
    Jd = top.col_join(bot)  # = det * Jac
    Om = sp.Matrix(omega(dim).astype(int))
    return residual(Jd.T * Om * Jd - det**2 * Om)


class NonlinearFamily:
    """f(x, u) = x + tau tanh(W x + B u + c), g(x, u) = |u|^2/2 + alpha |x|^2/2 (float64).

    The implicit advance map solves p_k = H_x(y, x_k, u) and H_u(y, x_k, u) = 0 for (y, u) with
    scipy.optimize.root (analytic Jacobian), then x_{k+1} = f(x_k, u); its Jacobian follows by
    implicit differentiation.
    """

    def __init__(self, nx: int, nu: int, seed: int, tau: float = 0.3, alpha: float = 0.5):
        rng = np.random.default_rng(seed)
        self.nx, self.nu, self.tau, self.alpha = nx, nu, tau, alpha
        self.W = rng.standard_normal((nx, nx))
        self.B = rng.standard_normal((nx, nu))
        self.c = rng.standard_normal(nx)

    def f(self, x, u):
        return x + self.tau * np.tanh(self.W @ x + self.B @ u + self.c)

    def _parts(self, x, y, u):
        z = self.W @ x + self.B @ u + self.c
        t = np.tanh(z)
        d = 1.0 - t**2
        dd = -2.0 * t * d
        return d, dd

    def equations(self, x, p, y, u):
        d, dd = self._parts(x, y, u)
        tau, W, B = self.tau, self.W, self.B
        F = np.concatenate([y + tau * W.T @ (d * y) - self.alpha * x - p, tau * B.T @ (d * y) - u])
        Jy = np.vstack([np.eye(self.nx) + tau * W.T * d, tau * B.T * d])
        Ju = np.vstack([tau * W.T @ np.diag(y * dd) @ B, tau * B.T @ np.diag(y * dd) @ B])
        Ju[self.nx :] -= np.eye(self.nu)
        Jx = np.vstack(
            [
                tau * W.T @ np.diag(y * dd) @ W - self.alpha * np.eye(self.nx),
                tau * B.T @ np.diag(y * dd) @ W,
            ]
        )
        Jp = np.vstack([-np.eye(self.nx), np.zeros((self.nu, self.nx))])
        return F, np.hstack([Jy, Ju]), Jx, Jp

    def reduced_hessian_blocks(self, x, y, u):
        """Second derivatives of H*(y, x) = H(y, x, u*(y, x)) by the Schur complement
        H*_ab = H_ab - H_au H_uu^{-1} H_ub (unconstrained u): returns (H*_xx, H*_xy, H*_yy)."""
        d, dd = self._parts(x, y, u)
        tau, W, B = self.tau, self.W, self.B
        Hxx = tau * W.T @ np.diag(y * dd) @ W - self.alpha * np.eye(self.nx)
        Hxy = (np.eye(self.nx) + tau * d[:, None] * W).T  # (H_xy)_ij = d2H/dx_i dy_j = (f_x)_ji
        Huu = tau * B.T @ np.diag(y * dd) @ B - np.eye(self.nu)
        Hux = tau * B.T @ np.diag(y * dd) @ W
        Huy = tau * B.T * d
        S = np.linalg.solve(Huu, np.hstack([Hux, Huy]))
        Sx, Sy = S[:, : self.nx], S[:, self.nx :]
        return Hxx - Hux.T @ Sx, Hxy - Hux.T @ Sy, -Huy.T @ Sy

    def frozen_hessian_blocks(self, x, y, u):
        """Second derivatives of Hhat at the control held fixed at u* (the printed corollary's
        reading): (H_xx, H_xy, H_yy) with H_yy = 0 since H is linear in the costate."""
        d, dd = self._parts(x, y, u)
        Hxx = self.tau * self.W.T @ np.diag(y * dd) @ self.W - self.alpha * np.eye(self.nx)
        Hxy = (np.eye(self.nx) + self.tau * d[:, None] * self.W).T
        return Hxx, Hxy, np.zeros((self.nx, self.nx))

    def advance(self, x, p, guess=None):
        from scipy.optimize import root

        nx = self.nx
        z0 = np.concatenate([p, np.zeros(self.nu)]) if guess is None else guess

        def fun(zz):
            F, J, _, _ = self.equations(x, p, zz[:nx], zz[nx:])
            return F, J

        sol = root(fun, z0, jac=True, method="hybr", options={"xtol": 1e-14})
        y, u = sol.x[:nx], sol.x[nx:]
        F, _, _, _ = self.equations(x, p, y, u)
        if not np.max(np.abs(F)) <= 1e-12:  # hybr may flag xtol as unmet at round-off
            raise RuntimeError(f"implicit step did not converge: |F| = {np.max(np.abs(F)):.2e}")
        return self.f(x, u), y, u

    def advance_jacobian(self, x, p):
        """Exact Jacobian of (x_k, p_k) -> (x_{k+1}, p_{k+1}) by implicit differentiation."""
        nx = self.nx
        _x1, y, u = self.advance(x, p)
        _F, Jyu, Jx, Jp = self.equations(x, p, y, u)
        dyu = -np.linalg.solve(Jyu, np.hstack([Jx, Jp]))  # d(y, u) / d(x, p)
        d, _ = self._parts(x, y, u)
        fx = np.eye(nx) + self.tau * d[:, None] * self.W
        fu = self.tau * d[:, None] * self.B
        dx1 = np.hstack([fx, np.zeros((nx, nx))]) + fu @ dyu[nx:]
        return np.vstack([dx1, dyu[:nx]])

    def advance_jacobian_fd(self, x, p, step: float = 1e-6):
        """Central finite-difference Jacobian (each perturbed solve starts from the base point)."""
        nx = self.nx
        _x1, y, u = self.advance(x, p)
        guess = np.concatenate([y, u])
        z = np.concatenate([x, p])
        cols = []
        for j in range(2 * nx):
            e = np.zeros(2 * nx)
            e[j] = step
            xp, pp = (z + e)[:nx], (z + e)[nx:]
            xm, pm = (z - e)[:nx], (z - e)[nx:]
            a1, b1, _ = self.advance(xp, pp, guess)
            a2, b2, _ = self.advance(xm, pm, guess)
            cols.append((np.concatenate([a1, b1]) - np.concatenate([a2, b2])) / (2 * step))
        return np.array(cols).T


def symplecticity_defects(
    seeds=range(5), nx: int = 3, nu: int = 2, fd: bool = False
) -> list[float]:
    """max |Jac^T Omega Jac - Omega| for random families and points (exact or FD Jacobian)."""
    out = []
    for seed in seeds:
        fam = NonlinearFamily(nx, nu, seed)
        rng = np.random.default_rng(100 + seed)
        x, p = rng.standard_normal(nx), 0.5 * rng.standard_normal(nx)
        Jac = fam.advance_jacobian_fd(x, p) if fd else fam.advance_jacobian(x, p)
        out.append(float(np.max(np.abs(Jac.T @ omega(nx) @ Jac - omega(nx)))))
    return out


def d4_float64() -> float:
    return max(symplecticity_defects())


def d4_float64_fd() -> float:
    return max(symplecticity_defects(range(3), fd=True))


# ---------------------------------------------------------------------------------------------
# D5: multi-sample problem with terminal cost


def d5_stationarity(N: int = 2, M: int = 2) -> sp.Expr:
    """Free endpoint, cost sum_a sum_k g(x^a_k,u_k) + sum_a phi(x^a_N), controls shared by the
    samples.  V = sum_a sum_k [<p^a_{k+1}, f(x^a_k,u_k) - x^a_{k+1}> - g(x^a_k,u_k)]
    + sum_k <sigma_k, h(u_k)> - sum_a phi(x^a_N) is stationary exactly when
    x^a_{k+1} = H_y(p^a_{k+1}, x^a_k, u_k), p^a_k = H_x(p^a_{k+1}, x^a_k, u_k) (1 <= k <= N-1),
    p^a_N = -grad phi(x^a_N), sum_a H_u(p^a_{k+1}, x^a_k, u_k) + h_u(u_k)^T sigma_k = 0, h(u_k) = 0.
    Undefined f, g, h, phi; n = m = 2, l = 1."""
    P = GeneralProblem(2, 2, 1)
    xs = [[_vec(f"x{a}_{k}", P.nx) for k in range(N + 1)] for a in range(M)]
    ps = [[None] + [_vec(f"p{a}_{k}", P.nx) for k in range(1, N + 1)] for a in range(M)]
    us = [_vec(f"u{k}", P.nu) for k in range(N)]
    ss = [_vec(f"s{k}", P.nl) for k in range(N)]
    V = sp.Integer(0)
    for a in range(M):
        for k in range(N):
            V += (ps[a][k + 1].T * (P.f(xs[a][k], us[k]) - xs[a][k + 1]))[0, 0]
            V -= P.g(xs[a][k], us[k])
        V -= P.phi(xs[a][N])
    for k in range(N):
        V += (ss[k].T * P.h(us[k]))[0, 0]
    y, x, u = _vec("Y", P.nx), _vec("Xg", P.nx), _vec("Ug", P.nu)
    H = P.H(y, x, u)
    Hy, Hx, Hu = _grad(H, y), _grad(H, x), _grad(H, u)
    xi = _vec("Xi", P.nx)
    gphi = _grad(P.phi(xi), xi)

    def at(e, a, k):
        sub = dict(zip(y, ps[a][k + 1], strict=True))
        sub.update(zip(x, xs[a][k], strict=True))
        sub.update(zip(u, us[k], strict=True))
        return e.xreplace(sub)

    total = sp.Integer(0)
    for k in range(N):
        hu = _jac(P.h(us[k]), us[k])
        total += residual(
            _grad(V, us[k])
            - (sum((at(Hu, a, k) for a in range(M)), sp.zeros(P.nu, 1)) + hu.T * ss[k])
        )
        total += residual(_grad(V, ss[k]) - P.h(us[k]))
        for a in range(M):
            total += residual(_grad(V, ps[a][k + 1]) - (at(Hy, a, k) - xs[a][k + 1]))
    for a in range(M):
        for k in range(1, N):
            total += residual(_grad(V, xs[a][k]) - (at(Hx, a, k) - ps[a][k]))
        endpoint = -gphi.xreplace(dict(zip(xi, xs[a][N], strict=True)))
        total += residual(_grad(V, xs[a][N]) - (-ps[a][N] + endpoint))
    return total


def example_multisample(sign: int = -1, shared_state: bool = False) -> sp.Expr:
    """Two samples, N = 2, n = m = 1: f = x + u, g = (u^2 + x^2)/2, phi^a = (x - y^a)^2/2,
    x^1_0 = 0, x^2_0 = 1, y = (1, -1).  The exact minimiser (u_0, u_1) solves grad C = 0.
    Costates from p^a_N = sign * grad phi(x^a_N) and p^a_k = H_x(p^a_{k+1}, x^{b}_k, u_k) with
    b = a (corrected) or b = 1 for all a (``shared_state``: eq8.3m's un-indexed x_k).
    Returns |sum_a H_u(p^a_1, x^a_0, u_0)| + |sum_a H_u(p^a_2, x^a_1, u_1)| at the minimiser:
    zero exactly when these costates satisfy the stationarity condition eq8.6m."""
    x, u, yv = sp.symbols("x u y", real=True)
    f, g = x + u, (u**2 + x**2) / 2
    H = yv * f - g
    u0, u1 = sp.symbols("u0 u1", real=True)
    x0s, targets = [sp.Integer(0), sp.Integer(1)], [sp.Integer(1), sp.Integer(-1)]
    traj = []
    C = sp.Integer(0)
    for a in range(2):
        xa = [x0s[a]]
        for uk in (u0, u1):
            C += g.subs({x: xa[-1], u: uk})
            xa.append(f.subs({x: xa[-1], u: uk}))
        C += (xa[-1] - targets[a]) ** 2 / 2
        traj.append(xa)
    sol = sp.solve([sp.diff(C, u0), sp.diff(C, u1)], [u0, u1], dict=True)[0]
    if not sp.hessian(C, (u0, u1)).is_positive_definite:
        raise ValueError("example is not convex")
    controls = [sol[u0], sol[u1]]
    traj = [[sp.sympify(e).subs(sol) for e in xa] for xa in traj]
    costates = []
    for a in range(2):
        pa = [None, None, sign * (traj[a][2] - targets[a])]
        b = 0 if shared_state else a
        pa[1] = sp.diff(H, x).subs({yv: pa[2], x: traj[b][1], u: controls[1]})
        costates.append(pa)
    total = sp.Integer(0)
    for k in range(2):
        total += abs(
            sum(
                sp.diff(H, u).subs({yv: costates[a][k + 1], x: traj[a][k], u: controls[k]})
                for a in range(2)
            )
        )
    return sp.nsimplify(total)


def d5_corrected_example() -> sp.Expr:
    return example_multisample(sign=-1, shared_state=False)


def d5_printed_endpoint_sign() -> sp.Expr:
    return example_multisample(sign=+1, shared_state=False)


def d5_printed_shared_state() -> sp.Expr:
    return example_multisample(sign=-1, shared_state=True)


def d5_printed_fixed_endpoint() -> sp.Expr:
    """prob8.1m fixes x^a_N = X^a_N *and* adds phi(x^a_N).  N = 1, f = x + u, g = u^2/2,
    x_0 = 0, X_1 = 1, phi = (x - 3)^2/2: u_0 = 1 is forced, eq8.6m gives p_1 = u_0 = 1, while
    grad phi(1) = -2: neither p_N = +grad phi (m8) nor -grad phi holds.  Returns
    min(|p_1 - phi'|, |p_1 + phi'|) = 1."""
    x, u, yv = sp.symbols("x u y", real=True)
    H = yv * (x + u) - u**2 / 2
    p1 = sp.solve(sp.diff(H, u).subs({u: 1}), yv)[0]
    dphi = sp.diff((x - 3) ** 2 / 2, x).subs(x, 1)
    return sp.Min(abs(p1 - dphi), abs(p1 + dphi))


# ---------------------------------------------------------------------------------------------
# D6: the costate recursion is back-propagation


class _act(sp.Function):
    """A generic smooth activation sigma with derivative dsigma (both undefined)."""

    nargs = 1

    def fdiff(self, argindex=1):
        return sp.Function("dsigma")(self.args[0])


def _layer(x: sp.Matrix, K: sp.Matrix, b: sp.Matrix, residual_layer: bool) -> sp.Matrix:
    z = K * x + b
    out = z.applyfunc(_act)
    return x + out if residual_layer else out


def d6_symbolic(residual_layer: bool = True, N: int = 2, M: int = 2, dim: int = 2) -> sp.Expr:
    """For a generic activation (n = 2, N = 2, M = 2 samples), Phi = sum_a |x^a_N - y^a|^2/2:
    with p^a_N = -(x^a_N - y^a) and p^a_k = H_x(p^a_{k+1}, x^a_k, u_k), H = <p, f(x, u)>:
    -p^a_k = dPhi/dx^a_k (k = 0..N), and dPhi/dK_k = -sum_a dH/dK_k, dPhi/dbeta_k likewise."""
    Ks = [sp.Matrix(dim, dim, lambda i, j, k=k: sp.Symbol(f"K{k}_{i}{j}")) for k in range(N)]
    bs = [_vec(f"beta{k}", dim) for k in range(N)]
    x0 = [_vec(f"xa{a}", dim) for a in range(M)]
    ys = [_vec(f"ya{a}", dim) for a in range(M)]
    states = []
    for a in range(M):
        xa = [x0[a]]
        for k in range(N):
            xa.append(_layer(xa[-1], Ks[k], bs[k], residual_layer))
        states.append(xa)
    Phi = sum(((states[a][N] - ys[a]).T * (states[a][N] - ys[a]))[0, 0] / 2 for a in range(M))
    # costate recursion from H(y, x, u) = <y, f(x, u)> at generic points, then substituted
    Y, X = _vec("Y", dim), _vec("X", dim)
    Hk = [(Y.T * _layer(X, Ks[k], bs[k], residual_layer))[0, 0] for k in range(N)]
    total = sp.Integer(0)
    for a in range(M):
        p = [None] * (N + 1)
        p[N] = -(states[a][N] - ys[a])
        for k in range(N - 1, -1, -1):
            sub = {**dict(zip(Y, p[k + 1], strict=True)), **dict(zip(X, states[a][k], strict=True))}
            p[k] = _grad(Hk[k], X).xreplace(sub)
        for k in range(N + 1):
            # Phi as a function of a free state xi at layer k, differentiated, then xi = x^a_k
            xi = _vec("xi", dim)
            xk = xi
            for j in range(k, N):
                xk = _layer(xk, Ks[j], bs[j], residual_layer)
            tail = ((xk - ys[a]).T * (xk - ys[a]))[0, 0] / 2
            grad = _grad(tail, xi).xreplace(dict(zip(xi, states[a][k], strict=True)))
            total += residual(grad + p[k])
        if a == 0:
            costates = [p]
        else:
            costates.append(p)
    for k in range(N):
        params = list(Ks[k]) + list(bs[k])
        for w in params:
            dH = sp.Integer(0)
            for a in range(M):
                sub = {
                    **dict(zip(Y, costates[a][k + 1], strict=True)),
                    **dict(zip(X, states[a][k], strict=True)),
                }
                dH += sp.diff(Hk[k], w).xreplace(sub)
            total += residual(sp.diff(Phi, w) + dH)
    return total


def d6_symbolic_residual() -> sp.Expr:
    return d6_symbolic(residual_layer=True)


def d6_symbolic_plain() -> sp.Expr:
    return d6_symbolic(residual_layer=False)


ACTIVATIONS = ("tanh", "logistic")


def activation(name: str) -> sp.Lambda:
    """sigma as a SymPy Lambda; the logistic function is written (1 + tanh(z/2))/2, which equals
    1/(1 + exp(-z)) and never overflows in floating point."""
    z = sp.Dummy("z", real=True)
    if name == "tanh":
        return sp.Lambda(z, sp.tanh(z))
    if name == "logistic":
        return sp.Lambda(z, (1 + sp.tanh(z / 2)) / 2)
    raise KeyError(name)


def activation_derivative(name: str) -> sp.Lambda:
    lam = activation(name)
    (z,) = lam.variables
    # no simplification: sympy would turn 1 - tanh^2 into cosh^-2, which overflows in float64
    return sp.Lambda(z, sp.expand(sp.diff(lam.expr, z)))


def d6_logistic_form() -> sp.Expr:
    """(1 + tanh(z/2))/2 = 1/(1 + exp(-z)) and sigma' = sigma (1 - sigma) (logistic);
    tanh' = 1 - tanh^2."""
    z = sp.Symbol("z", real=True)
    s = activation("logistic")(z)
    r = residual(sp.simplify((s - 1 / (1 + sp.exp(-z))).rewrite(sp.exp)))
    r += residual(activation_derivative("logistic")(z) - s * (1 - s))
    r += residual(activation_derivative("tanh")(z) - (1 - sp.tanh(z) ** 2))
    return r


def layer_exprs(size, act: str, residual_layer: bool):
    """Matrix-level expressions of one layer and its adjoint (size n symbolic or an integer).

    z = K x + beta; x_next = [x +] sigma(z); s = sigma'(z) o p;
    p_prev = dH/dx = [p +] K^T s; dH/dK = s x^T; dH/dbeta = s, for H = <p, x_next>.
    """
    K = sp.MatrixSymbol("K", size, size)
    x = sp.MatrixSymbol("x", size, 1)
    b = sp.MatrixSymbol("beta", size, 1)
    p = sp.MatrixSymbol("p", size, 1)
    z = K * x + b
    sig = ElementwiseApplyFunction(activation(act), z)
    dsig = ElementwiseApplyFunction(activation_derivative(act), z)
    s = sp.HadamardProduct(dsig, p)
    x_next = x + sig if residual_layer else sig
    p_prev = p + K.T * s if residual_layer else K.T * s
    syms = {"K": K, "x": x, "beta": b, "p": p, "z": z, "s": s}
    return syms, x_next, p_prev, s * x.T, s


def d6_emitted_formulas(size: int = 3) -> sp.Expr:
    """The emitted layer formulas equal the explicit derivatives of H = <p, f(x, K, beta)>
    (n = 3, both activations, residual and plain)."""
    total = sp.Integer(0)
    for act, res in itertools.product(ACTIVATIONS, (True, False)):
        syms, x_next, p_prev, dK, db = layer_exprs(size, act, res)
        exp = {
            "K": sp.Matrix(size, size, lambda i, j: sp.Symbol(f"k{i}{j}", real=True)),
            "x": _vec("x", size),
            "beta": _vec("b", size),
            "p": _vec("p", size),
        }
        sub = {syms[name]: exp[name] for name in exp}

        def explicit(e, sub=sub):
            return sp.Matrix(e.subs(sub).doit())

        xn = explicit(x_next)
        H = (exp["p"].T * xn)[0, 0]
        total += residual(explicit(p_prev) - _grad(H, exp["x"]))
        total += residual(explicit(db) - _grad(H, exp["beta"]))
        dK_true = sp.Matrix(size, size, lambda i, j, H=H, Km=exp["K"]: sp.diff(H, Km[i, j]))
        total += residual(explicit(dK) - dK_true)
    return total


def _reference_loss(x0, Ks, bs, targets, act: str, residual_layer: bool):
    """Independent plain-NumPy forward pass (complex-safe, no generated code) and loss."""
    sig = np.tanh if act == "tanh" else (lambda z: 1.0 / (1.0 + np.exp(-z)))
    x = x0
    for K, b in zip(Ks, bs, strict=True):
        y = sig(x @ K.T + b)
        x = x + y if residual_layer else y
    return 0.5 * np.sum((x - targets) ** 2)


def complex_step_gradients(x0, Ks, bs, targets, act, residual_layer, h=1e-30):
    """dPhi/dK_k, dPhi/dbeta_k by the complex step Im Phi(w + i h e)/h (exact to round-off)."""
    Ks = np.asarray(Ks, dtype=complex)
    bs = np.asarray(bs, dtype=complex)
    gK, gb = np.zeros(Ks.shape), np.zeros(bs.shape)
    for idx in np.ndindex(Ks.shape):
        Kp = Ks.copy()
        Kp[idx] += 1j * h
        gK[idx] = _reference_loss(x0, Kp, bs, targets, act, residual_layer).imag / h
    for idx in np.ndindex(bs.shape):
        bp = bs.copy()
        bp[idx] += 1j * h
        gb[idx] = _reference_loss(x0, Ks, bp, targets, act, residual_layer).imag / h
    return gK, gb


def complex_step_state_gradients(states, Ks, bs, targets, act, residual_layer, h=1e-30):
    """dPhi/dx^a_k for every layer k and sample a, by the complex step on the tail network."""
    out = np.zeros(states.shape)
    N = len(Ks)
    for k in range(N + 1):
        for idx in np.ndindex(states.shape[1:]):
            xk = states[k].astype(complex)
            xk[idx] += 1j * h
            out[(k, *idx)] = (
                _reference_loss(xk, Ks[k:], bs[k:], targets, act, residual_layer).imag / h
            )
    return out


def random_network(seed: int, N: int = 4, M: int = 5, dim: int = 3, scale: float = 0.8):
    rng = np.random.default_rng(seed)
    return (
        rng.standard_normal((M, dim)),
        scale * rng.standard_normal((N, dim, dim)),
        scale * rng.standard_normal((N, dim)),
        rng.standard_normal((M, dim)),
    )


def d6_float64() -> float:
    """Relative error of symrb.learning's costates and weight gradients (generated kernels)
    against complex-step derivatives of an independent forward pass (n = 3, N = 4, M = 5)."""
    from symrb import learning

    worst = 0.0
    for seed, act, res in itertools.product(range(2), ACTIVATIONS, (True, False)):
        x0, Ks, bs, ys = random_network(seed)
        states = learning.resnet_forward(x0, Ks, bs, activation=act, residual=res)
        p = learning.costate_sweep(states, Ks, bs, ys, activation=act, residual=res)
        _loss, gK, gb = learning.loss_gradients(x0, Ks, bs, ys, activation=act, residual=res)
        cK, cb = complex_step_gradients(x0, Ks, bs, ys, act, res)
        cx = complex_step_state_gradients(states, Ks, bs, ys, act, res)
        for got, ref in ((gK, cK), (gb, cb), (-p, cx)):
            worst = max(worst, float(np.max(np.abs(got - ref)) / np.max(np.abs(ref))))
    return worst


# ---------------------------------------------------------------------------------------------

_D1_PRINTED = (
    r"eq8.3 for $k=0,\dots,N$ with $p_{N+1}=0$, i.e. also $p_N=\partial H/\partial x_N(0,x_N,u_N)"
    r"=-\partial g/\partial x(x_N,u_N)$; the proof's augmented functional $V$ carries one "
    r"multiplier $\sigma$ for all $k$ (the proposition itself lets $\sigma=\sigma(p_{k+1},x_k)$ "
    r"vary, but a single $\sigma$ in $V$ only yields $\sum_k h(u_k)=0$); the "
    r"proof rewrites $\sum_{k=0}^{N-1}(-\langle p_{k+1},x_{k+1}\rangle+\hat H_k)$ as "
    r"$\langle p_0,x_0\rangle+\sum_{k=0}^{N}(-\langle p_k,x_k\rangle+\hat H(p_{k+1},x_k,u_k,\sigma))$."
)
_D1_CORRECTED = (
    r"$x_{k+1}=\partial H/\partial p_{k+1}$ for $k=0,\dots,N-1$; $p_k=\partial H/\partial x_k"
    r"(p_{k+1},x_k,u_k)$ for $k=1,\dots,N-1$ ($k=0$ merely defines $p_0$); $p_N$ is free, fixed "
    r"by $x_N=X_N$; $\partial\hat H/\partial u_k(p_{k+1},x_k,u_k,\sigma_k)=0$, $h(u_k)=0$ with one "
    r"multiplier $\sigma_k\in\mathbb R^l$ per step; the rewrite has the extra term "
    r"$\hat H(0,x_N,u_N,\sigma)$ and must stop at $k=N-1$."
)

CLAIMS = [
    Claim(
        id="D1",
        label="prob8.1, gendiscprop, eq8.3-eq8.6",
        title="Discrete maximum principle (fixed endpoints, control constraint)",
        statement=r"A solution of $\min\sum_{k<N}g(x_k,u_k)$, $x_{k+1}=f(x_k,u_k)$, $x_0=X_0$, "
        r"$x_N=X_N$, $h(u_k)=0$ satisfies $p_k=\partial H/\partial x_k$, $x_{k+1}=\partial H/"
        r"\partial p_{k+1}$ with $H=\langle p_{k+1},f\rangle-g$, and $\partial\hat H/\partial u_k=0$, "
        r"$h(u_k)=0$ with $\hat H=H+\langle\sigma,h\rangle$.",
        printed=_D1_PRINTED,
        corrected=_D1_CORRECTED,
        expected="holds after correction",
        section="2",
        note="The structure of the principle is right (stationarity of the augmented functional, "
        "derived here for undefined f, g, h), but three details are not: (i) the costate equation "
        "at k = N with p_{N+1} = 0 would force p_N = -dg/dx(x_N, u_N) for a phantom control u_N; for "
        "a fixed endpoint p_N is free (exact example: p_2 = 1/2, the printed form gives 0); "
        "(ii) in the proof's functional V the multiplier must depend on k (the proposition's "
        "text, sigma = sigma(p_{k+1}, x_k), already allows that; V does not): in an exact example "
        "the minimiser has sigma_0 = -3/7, sigma_1 = -1/7, and with one shared sigma the "
        "extremal system has no solution at all; (iii) the proof's rewriting of V with the sum up to N adds "
        "Hhat(0, x_N, u_N, sigma) = -g(x_N, u_N) + <sigma, h(u_N)>.",
        evidence=(
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "stationarity of V (sigma_k per step, x_0 and x_N fixed) equals the corrected "
                "system; undefined f, g, h, n = m = 2, l = 1, N = 3",
                d1_stationarity,
                form="corrected",
            ),
            Evidence(
                Level.EXACT_RATIONAL,
                "f = x + u1, g = (u1^2 + (u2 - x)^2)/2, h = u1 - u2, N = 2: the KKT system with "
                "sigma_k has one solution, the direct minimiser v_0 = 3/7",
                d1_corrected_multipliers,
                form="corrected",
            ),
            Evidence(
                Level.EXACT_RATIONAL,
                "same example: |sigma_0 - sigma_1| = 2/7 at the minimiser (one sigma cannot serve)",
                d1_printed_single_sigma,
                form="printed",
            ),
            Evidence(
                Level.EXACT_RATIONAL,
                "f = x + u, g = u^2/2, x_0 = 0, x_2 = 1: interior costate equation holds",
                d1_corrected_costate_interior,
                form="corrected",
            ),
            Evidence(
                Level.EXACT_RATIONAL,
                "same example: |p_N - dH/dx(p_{N+1} = 0, x_N, u_N)| = |1/2 - 0|",
                d1_printed_costate_at_N,
                form="printed",
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "the proof's rewrite with sum to N and p_{N+1} = 0 differs from V by "
                "Hhat(0, x_N, u_N, sigma) (undefined g, h)",
                d1_printed_rewrite,
                form="printed",
            ),
        ),
    ),
    Claim(
        id="D2",
        label="remark after gendiscprop",
        title="The implicit step needs an invertible mixed second derivative",
        statement=r"Computing $p_{k+1}$ from $p_k=\partial H/\partial x(p_{k+1},x_k,u^*_k)$ needs "
        r"the matrix $\partial^2H/\partial y_i\partial x_j$ invertible.",
        printed=r"invertibility of $\left(\partial^2H/\partial y_i\partial x_j(y,x,u)\right)$ at "
        r"every $(y,x,u)$ (u held fixed) lets one compute $p_{k+1}$.",
        corrected=r"by the implicit function theorem the step is locally unique when "
        r"$\partial^2H^*/\partial y\,\partial x$ is invertible, where $H^*(y,x)=\hat H(y,x,u^*(y,x),"
        r"\sigma(y,x))$ is the reduced Hamiltonian ($\partial H^*/\partial x=\partial H/\partial x$ at "
        r"$u^*$, so this is the Jacobian of $y\mapsto\partial H/\partial x(y,x,u^*(y,x))$); it equals "
        r"the printed matrix only when $u^*$ does not depend on $y$.",
        expected="holds after correction",
        section="2",
        note="u*_k depends on p_{k+1}, so the implicit equation's Jacobian picks up "
        "H_xu du*/dy. Exact counterexample: f = x + u, g = (u + x)^2/2 >= 0 has d^2H/dy dx = 1 "
        "everywhere, yet u* = y - x and p_k = 0 for every p_{k+1}: the step does not determine "
        "p_{k+1}. The index order (y_i x_j vs x_i y_j) is a transpose and does not matter for "
        "invertibility.",
        evidence=(
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "f = a(x) + b(x) u, g = u^2/2 + V(x) (undefined a, b, V): envelope H*_x = H_x(u*), "
                "d/dy H_x(y, x, u*) = H*_xy = a' + 2 b b' y",
                d2_envelope_family,
                form="corrected",
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "f = u, g = (u^2 + x^2)/2: H*_xy = 0 and p_k = -x_k whatever p_{k+1} (not unique)",
                d2_singular_not_unique,
                form="corrected",
            ),
            Evidence(
                Level.EXACT_RATIONAL,
                "f = x + u, g = (u + x)^2/2: printed matrix = 1 everywhere but d p_k/d p_{k+1} = 0 "
                "(1 = counterexample confirmed)",
                d2_printed_condition_insufficient,
                form="printed",
            ),
        ),
    ),
    Claim(
        id="D3",
        label="C:8.3",
        title="Linearised extremal equations",
        statement=r"$dp_k=\hat H_{xx}dx_k+\hat H_{px}dp_{k+1}$, $dx_{k+1}=\hat H_{px}dx_k+"
        r"\hat H_{pp}dp_{k+1}$.",
        printed=r"$dp_k=\frac{\partial^2\hat H}{\partial x_k^2}dx_k+\frac{\partial^2\hat H}"
        r"{\partial p_{k+1}\partial x_k}dp_{k+1}$, $dx_{k+1}=\frac{\partial^2\hat H}{\partial p_{k+1}"
        r"\partial x_k}dx_k+\frac{\partial^2\hat H}{\partial p_{k+1}^2}dp_{k+1}$, derivatives of "
        r"$\hat H$ at $(p_{k+1},x_k,u^*_k)$.",
        corrected=r"$dp_k=H^*_{xx}dx_k+H^*_{xy}dp_{k+1}$, $dx_{k+1}=(H^*_{xy})^Tdx_k+H^*_{yy}"
        r"dp_{k+1}$ with $H^*(y,x)=\hat H(y,x,u^*(y,x),\sigma(y,x))$ and "
        r"$(H^*_{xy})_{ij}=\partial^2H^*/\partial x_i\partial y_j$.",
        expected="holds after correction",
        section="2",
        note="Two slips. (i) Second derivatives must be those of the reduced Hamiltonian H* "
        "(u* and sigma depend on (p_{k+1}, x_k)); at frozen u*, Hhat is linear in p, so the printed "
        "coefficient of dp_{k+1} in dx_{k+1} is always 0, while it is H*_yy = B B^T in the family "
        "f = a(x) + B u, g = |u|^2/2 + V(x). (ii) For n > 1 the two lines need transposed mixed "
        "matrices; the printed form uses the same one (if the printed symbol is read as the mixed "
        "derivative contracted in the right slot, this second point is notation only). In the "
        "symbolic family u* does not depend on x, so there only the H*_yy block separates H* from "
        "frozen Hhat; the float64 family with u*(x, p_{k+1}) separates every block.",
        evidence=(
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "Jacobians of the true maps (x_k, p_{k+1}) -> (p_k, x_{k+1}) equal the corrected "
                "blocks; f = a(x) + B u, g = |u|^2/2 + V(x), undefined a, V, n = m = 2",
                d3_corrected,
                form="corrected",
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "same family: blocks of Hhat at frozen u* mismatch (count of entries)",
                d3_printed_frozen_control,
                form="printed",
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "same family with H*: one mixed matrix in both lines mismatches for either index "
                "convention (min count of entries)",
                d3_printed_same_matrix,
                form="printed",
            ),
            Evidence(
                Level.FLOAT64,
                "f = x + 0.3 tanh(Wx + Bu + c), g = |u|^2/2 + |x|^2/4 (u* depends on x and p_{k+1}; "
                "n = 3, m = 2, 3 random points): corrected blocks of H* give the Jacobian of the "
                "implicit advance map",
                lambda: _d3_nonlinear_gap("reduced"),
                tol=1e-11,
                form="corrected",
            ),
            Evidence(
                Level.FLOAT64,
                "same family: blocks of Hhat at frozen u* (printed reading) miss that Jacobian",
                lambda: _d3_nonlinear_gap("frozen"),
                tol=1e-11,
                form="printed",
            ),
        ),
    ),
    Claim(
        id="D4",
        label="eq8.13",
        title="The advance map (x_k, p_k) -> (x_{k+1}, p_{k+1}) is symplectic",
        statement=r"$\Phi^*(dx_{k+1}\wedge dp_{k+1})=dx_k\wedge dp_k$, i.e. $D\Phi^T\Omega\, D\Phi="
        r"\Omega$ with $\Omega=\begin{pmatrix}0&I\\-I&0\end{pmatrix}$ (where $H^*_{xy}$ is "
        r"invertible).",
        expected="holds",
        section="2",
        evidence=(
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "Jac from the corrected D3 blocks with generic symmetric H*_xx, H*_yy and generic "
                "H*_xy: det^2 (Jac^T Omega Jac - Omega) expands to 0, n = 2",
                d4_symbolic,
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "the same, n = 3",
                lambda: d4_symbolic(3),
            ),
            Evidence(
                Level.FLOAT64,
                "f = x + 0.3 tanh(Wx + Bu + c), g = |u|^2/2 + |x|^2/4 (5 random, n = 3, m = 2): "
                "implicit step by scipy root, Jacobian by implicit differentiation, "
                "max |Jac^T Omega Jac - Omega|",
                d4_float64,
                tol=1e-12,
            ),
            Evidence(
                Level.FLOAT64,
                "the same with central finite differences (step 1e-6; 3 random examples)",
                d4_float64_fd,
                tol=1e-7,
            ),
        ),
    ),
    Claim(
        id="D5",
        label="prob8.1m, gendiscpropm, eq8.3m-eq8.6m, m8",
        title="Multi-sample problem with terminal cost: shared controls, per-sample costates",
        statement=r"$\min\sum_a\sum_k g(x^a_k,u_k)+\sum_a\phi(x^a_N)$: $p^a_k=\partial H/\partial "
        r"x_k(p^a_{k+1},x_k,u_k)$, $x^a_{k+1}=\partial H/\partial p$, $\partial\hat H/\partial u_k=0$, "
        r"and $p^a_N=\partial\phi/\partial x^a_N$.",
        printed=r"prob8.1m fixes $x^a_N=X^a_N$ and adds $\sum_a\phi(x^a_N)$; eq8.3m evaluates "
        r"$\partial H/\partial x$ at the un-indexed $x_k$; one $\sigma$ for all $k$ in the proof's $V$; "
        r"m8: $p^a_N=+\partial\phi/\partial x^a_N$.",
        corrected=r"free endpoint (no $x^a_N=X^a_N$); $p^a_k=\partial H/\partial x(p^a_{k+1},x^a_k,"
        r"u_k)$ for $1\le k\le N-1$; $\sum_a\partial H/\partial u(p^a_{k+1},x^a_k,u_k)+h'(u_k)^T"
        r"\sigma_k=0$, $h(u_k)=0$; $p^a_N=-\partial\phi/\partial x^a_N$ for $H=\langle p,f\rangle-g$ "
        r"(equivalently $p^a_k=-\partial C/\partial x^a_k$).",
        expected="holds after correction",
        section="2",
        note="With H = <p, f> - g and a minimisation, V = -(cost) + <p, f - x> + <sigma, h>, so "
        "dV/dx^a_N = -p^a_N - phi'(x^a_N): the endpoint sign is minus (the paper's V carries "
        "+phi and an extra -p_N x_N). If x^a_N is fixed, phi is a constant and no endpoint "
        "condition follows. eq8.3m must use x^a_k. The -phi(x^a_N) inside eq8.4m is harmless "
        "(constant in the variables of H). sigma must be sigma_k in the proof's V, as in D1.",
        evidence=(
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "stationarity of the corrected V equals the corrected system; undefined f, g, h, "
                "phi, n = m = 2, l = 1, M = 2 samples, N = 2",
                d5_stationarity,
                form="corrected",
            ),
            Evidence(
                Level.EXACT_RATIONAL,
                "2 samples, f = x + u, g = (u^2 + x^2)/2, phi = (x - y^a)^2/2: corrected costates "
                "satisfy sum_a H_u = 0 at the exact minimiser",
                d5_corrected_example,
                form="corrected",
            ),
            Evidence(
                Level.EXACT_RATIONAL,
                "same example with p^a_N = +phi'(x^a_N) (m8): sum_k |sum_a H_u| = 4/5",
                d5_printed_endpoint_sign,
                form="printed",
            ),
            Evidence(
                Level.EXACT_RATIONAL,
                "same example with eq8.3m's shared x_k (sample 1's state for all): |sum_a H_u| = 1",
                d5_printed_shared_state,
                form="printed",
            ),
            Evidence(
                Level.EXACT_RATIONAL,
                "fixed x_1 = 1 plus phi = (x - 3)^2/2: p_1 = 1 but phi'(1) = -2, "
                "min |p_1 -+ phi'| = 1",
                d5_printed_fixed_endpoint,
                form="printed",
            ),
        ),
    ),
    Claim(
        id="D6",
        label="Remark 1, Remark 2",
        title="ResNet layers: the costate recursion is back-propagation",
        statement=r"For $f(x,u)=x+\sigma(Kx+\beta)$ or $\sigma(Kx+\beta)$, $u=(K,\beta)$, "
        r"$g=0$, loss $\Phi=\sum_a\phi(x^a_N)$: with $p^a_N=-\nabla\phi(x^a_N)$ (D5, corrected "
        r"sign), $-p^a_k=\partial\Phi/\partial x^a_k$ and $\partial\Phi/\partial K_k="
        r"-\sum_a\partial H/\partial K_k=-\sum_a(\sigma'(z^a_k)\odot p^a_{k+1})(x^a_k)^T$, "
        r"$\partial\Phi/\partial\beta_k=-\sum_a\sigma'(z^a_k)\odot p^a_{k+1}$, $z^a_k=K_kx^a_k+"
        r"\beta_k$; $p^a_k=(\partial f/\partial x)^Tp^a_{k+1}=p^a_{k+1}+K_k^T(\sigma'(z^a_k)\odot "
        r"p^a_{k+1})$ (residual; without the first term for the plain layer).",
        expected="holds",
        section="2",
        note="Remark 1 calls sigma(Kx + beta) the ResNet layer; the residual network of "
        "BeCeEhOwSc2019 is x + h sigma(Kx + beta). Both are checked. Sign convention: the paper's "
        "costates are minus the back-propagated gradients (adjoints).",
        evidence=(
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "generic activation sigma (undefined, derivative dsigma), residual layer, n = 2, "
                "N = 2, M = 2: costates = -state gradients, -sum_a dH/du = weight gradients",
                d6_symbolic_residual,
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "the same for the plain layer sigma(Kx + beta)",
                d6_symbolic_plain,
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "logistic = (1 + tanh(z/2))/2 = 1/(1 + e^-z), sigma' = sigma(1 - sigma); "
                "tanh' = 1 - tanh^2",
                d6_logistic_form,
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "emitted layer/adjoint formulas equal explicit derivatives of <p, f> (n = 3, both "
                "activations, residual and plain)",
                d6_emitted_formulas,
            ),
            Evidence(
                Level.FLOAT64,
                "symrb.learning costates and weight gradients vs complex-step derivatives of an "
                "independent forward pass (n = 3, N = 4, M = 5; max relative error)",
                d6_float64,
                tol=1e-12,
            ),
        ),
    ),
]


# ---------------------------------------------------------------------------------------------
# code emission


def emit() -> tuple[str, list[Kernel]]:
    kernels = []
    z_sym = sp.MatrixSymbol("z", n, 1)
    s_sym = sp.MatrixSymbol("s", n, 1)
    args_fwd = [
        Arg("K", "(..., n, n)", "layer weight K_k"),
        Arg("beta", "(..., n, 1)", "layer bias beta_k"),
        Arg("x", "(..., n, 1)", "state x_k"),
    ]
    arg_p = Arg("p", "(..., n, 1)", "costate p_{k+1}")
    for act, res in itertools.product(ACTIVATIONS, (True, False)):
        syms, x_next, p_prev, dK, db = layer_exprs(n, act, res)
        z_expr, s_expr = syms.pop("z"), syms.pop("s")
        suffix = act + ("" if res else "_plain")
        layer = f"x + {act}(K x + beta)" if res else f"{act}(K x + beta)"
        kernels.append(
            Kernel(
                name=f"resnet_step_{suffix}",
                args=args_fwd,
                intermediates={"z": z_expr},
                outputs={"x_next": x_next.xreplace({z_expr: z_sym})},
                doc=f"One layer x_(k+1) = f(x_k, u_k) = {layer}, u = (K, beta).",
            )
        )
        rep = {s_expr: s_sym}
        kernels.append(
            Kernel(
                name=f"resnet_adjoint_{suffix}",
                args=[*args_fwd, arg_p],
                intermediates={"z": z_expr, "s": s_expr.xreplace({z_expr: z_sym})},
                outputs={
                    "p_prev": p_prev.xreplace(rep),
                    "dH_dK": dK.xreplace(rep),
                    "dH_dbeta": db.xreplace(rep),
                },
                doc=f"Adjoint of the layer f(x, u) = {layer} for H = <p, f(x, u)>: with "
                f"z = K x + beta and s = {act}'(z) * p (entrywise), returns "
                "p_k = dH/dx = "
                + ("p + K^T s" if res else "K^T s")
                + ", dH/dK = s x^T and dH/dbeta = s.",
            )
        )
    return "discrete_control", kernels
