r"""M1: the n = 3 Moser-Veselov step in Cayley coordinates (symrb's engine; not a paper claim).

With :math:`U = \operatorname{cay}(X) = (I + X)(I - X)^{-1}`, :math:`X = \hat x`, multiplying
:math:`J_D(U) = B` (:math:`B = hM = \hat b`) by :math:`I - X` on the left and :math:`I + X` on the
right gives :math:`2J(X) = (I - X)B(I + X)`, the quadratic vector equation
:math:`G(x) = 2I\circ x - b - b\times x - (b\cdot x)x = 0` (:math:`I_1 = \lambda_2 + \lambda_3`,
cyclic).  A Newton step on it (``mv3_cayley_newton``) and the state update
(``mv3_cayley_update``: :math:`Q_{k+1} = Q_kU`, :math:`M_{k+1} = U^TM_kU`, mv3 with
:math:`\Omega_k = U^T`) are the checked references; the engine uses the scalar form (a quartic in
:math:`s = b\cdot x`) and the fused step ``mv3_cayley_step``.

Emitted (``symrb/_generated/discrete_rigid_body.py``): ``mv3_cayley_s_newton`` and
``mv3_cayley_step``.  Evidence: symbolic and exact-rational identities between the kernels, the
emitted :math:`J_D` (D7) and mv3 (D10).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import sympy as sp

from derivations.claims.section2.d07_optimal_control_on_so_n import JD
from derivations.claims.section2.d10_moser_veselov import MV_TRANSPORT
from derivations.registry import Level, claim
from derivations.symbolic import explicit, hat3, residual, sym_vector
from derivations.vocabulary import Arg, Kernel

M1 = claim(
    "M1",
    label="",
    title="The $n=3$ Moser-Veselov step in Cayley coordinates",
    statement="For $n=3$, with $U$ the Cayley transform of $\\hat x$, the second Moser-Veselov "
    "equation is a quadratic equation in the vector $x$ and a quartic in the scalar $s$, the dot "
    "product of $b$ and $x$; the emitted kernels take one Newton step on the quartic and return "
    "the increments of the momentum and the attitude over one Moser-Veselov step (the third "
    "equation, and $Q_{k+1}$ from $Q_k$ and $U$).",
    expected="holds",
    section="symrb",
    where="symrb.engine.mv_flow for n = 3: the kernels mv3_cayley_s_newton and mv3_cayley_step",
)


_CX, _CB, _CL = sym_vector("x", 3), sym_vector("b", 3), sym_vector("l", 3)
_CM = sym_vector("m", 3)
_CQ = sp.Matrix(3, 3, lambda i, j: sp.Symbol(f"q{i + 1}{j + 1}", real=True))


def _cayley3_inertia(lam: sp.Matrix) -> sp.Matrix:
    return sp.Matrix([lam[1] + lam[2], lam[0] + lam[2], lam[0] + lam[1]])


def _cayley3_G(x: sp.Matrix, b: sp.Matrix, lam: sp.Matrix) -> sp.Matrix:
    """G(x) = 2 I o x - b - b x x - (b.x) x, zero exactly when J_D(cay(hat x)) = hat(b)."""
    inertia = _cayley3_inertia(lam)
    lin = sp.Matrix([2 * inertia[i] * x[i] for i in range(3)])
    return lin - b - b.cross(x) - b.dot(x) * x


def _cayley3_jacobian(x: sp.Matrix, b: sp.Matrix, lam: sp.Matrix) -> sp.Matrix:
    """G'(x) = 2 diag(I) - (b.x) Id - hat(b) - x b^T (closed form; the evidence compares it with
    SymPy's Jacobian of G)."""
    inertia = _cayley3_inertia(lam)
    return sp.diag(*[2 * inertia[i] for i in range(3)]) - b.dot(x) * sp.eye(3) - hat3(b) - x * b.T


def _cayley3_newton_step() -> sp.Matrix:
    """dx = -G'^{-1} G by cross products of the rows r_i of G' (the adjugate's columns are
    r_2 x r_3, r_3 x r_1, r_1 x r_2 and det G' = r_1 . (r_2 x r_3)), kept unexpanded so that CSE
    shares the entries of G'."""
    Jg = _cayley3_jacobian(_CX, _CB, _CL)
    G = _cayley3_G(_CX, _CB, _CL)
    r1, r2, r3 = (Jg[i, :].T for i in range(3))
    c1, c2, c3 = r2.cross(r3), r3.cross(r1), r1.cross(r2)
    det = r1.dot(c1)
    return -(G[0] * c1 + G[1] * c2 + G[2] * c3) / det


def _cayley3_matrix(x: sp.Matrix) -> sp.Matrix:
    """cay(hat x) = I + 2 (X + X^2)/(1 + |x|^2) (closed form)."""
    X = hat3(x)
    return sp.eye(3) + 2 * (X + X * X) / (1 + x.dot(x))


_CDX = _cayley3_newton_step()
_CU = _cayley3_matrix(_CX)
_CM_NEXT = _CU.T * _CM
_CQ_NEXT = _CQ * _CU
_SCALAR3 = "(...)"
MV3_CAYLEY_NEWTON = Kernel(
    name="mv3_cayley_newton",
    target="discrete_rigid_body",
    args=[Arg(f"x{i}", _SCALAR3, f"Cayley vector, component {i}") for i in (1, 2, 3)]
    + [Arg(f"b{i}", _SCALAR3, f"discrete momentum h m, component {i}") for i in (1, 2, 3)]
    + [Arg(f"l{i}", _SCALAR3, f"lam_{i}, diagonal of Lambda") for i in (1, 2, 3)],
    outputs={f"dx{i + 1}": _CDX[i] for i in range(3)},
    doc="Newton step for the second Moser-Veselov equation in Cayley coordinates, n = 3.\n\n"
    "With U = cay(hat x) = (I + X)(I - X)^{-1}, J_D(U) = hat(b) is equivalent to\n"
    "G(x) = 2 I o x - b - b x x - (b.x) x = 0 (I_1 = l2 + l3, cyclic); returns the Newton step\n"
    "dx = -G'(x)^{-1} G(x), G'(x) = 2 diag(I) - (b.x) Id - hat(b) - x b^T, by the adjugate.\n"
    "Arguments may be floats or arrays of one broadcast shape (no conversion).",
    claims=("M1",),
    convert=False,
    register=False,  # the engine uses mv3_cayley_step; kept as the checked reference
)
MV3_CAYLEY_UPDATE = Kernel(
    name="mv3_cayley_update",
    target="discrete_rigid_body",
    args=[Arg(f"x{i}", _SCALAR3, f"Cayley vector, component {i}") for i in (1, 2, 3)]
    + [Arg(f"m{i}", _SCALAR3, f"body momentum, component {i}") for i in (1, 2, 3)]
    + [
        Arg(f"q{i}{j}", _SCALAR3, f"attitude Q, entry ({i}, {j})")
        for i in (1, 2, 3)
        for j in (1, 2, 3)
    ],
    outputs={f"m{i + 1}_next": _CM_NEXT[i] for i in range(3)}
    | {f"q{i + 1}{j + 1}_next": _CQ_NEXT[i, j] for i in range(3) for j in range(3)},
    doc="One Moser-Veselov step of the state given the Cayley vector x of U, n = 3.\n\n"
    "U = cay(hat x) = I + 2 (X + X^2)/(1 + |x|^2), m_next = U^T m (M_{k+1} = U^T M_k U, the\n"
    "third Moser-Veselov equation with Omega_k = U^T), Q_next = Q U.  Arguments may be floats\n"
    "or arrays of one broadcast shape (no conversion).",
    claims=("M1",),
    convert=False,
    register=False,  # the engine uses mv3_cayley_step; kept as the checked reference
)


# The scalar form.  With s = b.x and D_s = diag(2 I - s), G(x) = 0 reads (D_s - hat b) x = b and
# s = b.x: x = z(s)/det(s) with z = adj(D_s - hat b) b, det = det(D_s - hat b), and s is a root of
# the quartic p(s) = s det(s) - b.z(s) (d_i = 2 I_i - s; z_i = b_i (|b|^2 + d_j d_k) +
# b_j b_k (d_j - d_k), cyclic; b.z = |b|^4 + sum b_i^2 d_j d_k).  The Moser-Veselov map conserves
# s/h^2 (to rounding; M2's float check), so a step at the previous step's s needs one scalar
# Newton step on p, whose size the caller checks: mv3_cayley_step fuses that Newton step, x and
# the state update; mv3_cayley_s_newton is the bare Newton step (cold starts, changed h).
_CS, _CH = sp.Symbol("s", real=True), sp.Symbol("h", real=True)


def _cayley3_scalar_form(s: sp.Expr, b: sp.Matrix, lam: sp.Matrix) -> tuple[Any, ...]:
    """(z, det, p) of the scalar form at s (unexpanded, for CSE)."""
    c = [2 * e for e in _cayley3_inertia(lam)]
    d = [ci - s for ci in c]
    bb = b.dot(b)
    sq = [bi**2 for bi in b]
    cyc = ((0, 1, 2), (1, 2, 0), (2, 0, 1))
    z = sp.Matrix([b[i] * (bb + d[j] * d[k]) + b[j] * b[k] * (c[j] - c[k]) for i, j, k in cyc])
    det = d[0] * d[1] * d[2] + sq[0] * d[0] + sq[1] * d[1] + sq[2] * d[2]
    bz = bb**2 + sum(sq[i] * d[j] * d[k] for i, j, k in cyc)
    return z, det, s * det - bz


def _cayley3_s_newton(s: sp.Expr, b: sp.Matrix, lam: sp.Matrix) -> sp.Expr:
    """-p(s)/p'(s), p' by SymPy's derivative of the unexpanded p."""
    p = _cayley3_scalar_form(s, b, lam)[2]
    return -p / sp.diff(p, s)


_CB_H = _CH * _CM
_CDS = _cayley3_s_newton(_CS, _CB_H, _CL)
_CS1 = _CS + _CDS
_CZ1, _CDET1, _ = _cayley3_scalar_form(_CS1, _CB_H, _CL)


def _cayley3_matrix_zd(z: sp.Matrix, det: sp.Expr) -> sp.Matrix:
    """cay(hat(z/det)) = I + 2 (det Z + z z^T - |z|^2 I)/(det^2 + |z|^2), Z = hat z (no
    division of z by det; the evidence compares it with _cayley3_matrix)."""
    zz = z.dot(z)
    return sp.eye(3) + 2 * (det * hat3(z) + z * z.T - zz * sp.eye(3)) / (det**2 + zz)


_CU1 = _cayley3_matrix_zd(_CZ1, _CDET1)
# The step returns increments, m_next - m = (U - I)^T m and Q_next - Q = Q (U - I), which the
# caller adds to the state.  Written as U^T m (or m plus the terms one by one) the update rounds
# terms of size |U - I| |m| that cancel (near a steady rotation U^T m is close to m), the same
# terms step after step: with an inertia spread of 1e6 the energy and Q^T Q - I then drifted
# linearly, up to 1.2 eps a step (17 times 10 eps sqrt(N) after 2e4 steps).  Summed first and
# added once, the increments leave a random walk (0.05 to 0.1 times 10 eps sqrt(N)).
_CD1 = _CU1 - sp.eye(3)
_SARGS = [Arg("s", _SCALAR3, "the scalar unknown s = b.x (b = h m, x the Cayley vector)"),
          Arg("h", _SCALAR3, "the step")]  # fmt: skip
_MARGS = [Arg(f"m{i}", _SCALAR3, f"body momentum, component {i}") for i in (1, 2, 3)]
_LARGS = [Arg(f"l{i}", _SCALAR3, f"lam_{i}, diagonal of Lambda") for i in (1, 2, 3)]
_QARGS = [Arg(f"q{i}{j}", _SCALAR3, f"attitude Q, entry ({i}, {j})") for i in (1, 2, 3)
          for j in (1, 2, 3)]  # fmt: skip
MV3_CAYLEY_S_NEWTON = Kernel(
    name="mv3_cayley_s_newton",
    target="discrete_rigid_body",
    args=_SARGS + _MARGS + _LARGS,
    outputs={"s_next": _CS1, "ds": _CDS},
    doc="Newton step for the scalar form of the second Moser-Veselov equation, n = 3.\n\n"
    "b = h m, d_i = 2 I_i - s (I_1 = l2 + l3, cyclic), det = d1 d2 d3 + sum b_i^2 d_i,\n"
    "p(s) = s det - |b|^4 - sum b_i^2 d_j d_k; returns s + ds and ds = -p(s)/p'(s).  At a root\n"
    "s of p,"
    " x = adj(D_s - hat b) b / det solves G(x) = 0 (mv3_cayley_newton).  Arguments may be\n"
    "floats or arrays of one broadcast shape (no conversion).",
    claims=("M1",),
    convert=False,
)
MV3_CAYLEY_STEP = Kernel(
    name="mv3_cayley_step",
    target="discrete_rigid_body",
    args=_SARGS + _MARGS + _LARGS + _QARGS,
    outputs={"s_next": _CS1, "ds": _CDS}
    | {f"dm{i + 1}": (_CD1.T * _CM)[i] for i in range(3)}
    | {f"dq{i + 1}{j + 1}": (_CQ * _CD1)[i, j] for i in range(3) for j in range(3)},
    doc="One Moser-Veselov step, n = 3: one Newton step on the scalar form, then the update.\n\n"
    "s_next = s + ds with ds of mv3_cayley_s_newton; x = adj(D - hat b) b / det at s_next,\n"
    "U = cay(hat x); returns the increments dm = (U - I)^T m and dQ = Q (U - I): m_next = m +\n"
    "dm = U^T m, Q_next = Q + dQ = Q U (mv3_cayley_update; the caller adds them, so that the\n"
    "state is rounded once a step).  The caller accepts the step when |ds| is small enough\n"
    "(s_next then a root to rounding).  Arguments may be floats or arrays of one broadcast\n"
    "shape (no conversion).",
    claims=("M1",),
    convert=False,
)


@M1.check(Level.SYMBOLIC_FIXED_N)
def m1_cayley_equation_n3() -> sp.Expr:
    r"""$n = 3$, Cayley coordinates (symbolic): the emitted update's $U$ is $\operatorname{cay}(X) =
    (I + X)(I - X)^{-1}$ and in $\mathrm{SO}(3)$; $(I - X)(J_D(U) - \hat b)(I + X)$ is
    $\widehat{G(x)}$ with the emitted $J_D$, so $G(x) = 0$ exactly when $J_D(U) = \hat b$; the
    emitted Newton step solves $G'(x)\, dx = -G(x)$ with $G'$ the Jacobian computed by SymPy; the
    emitted momentum update is the emitted mv3 at $\Omega = U^T$ and the attitude update is $QU$."""
    x, b, lam = _CX, _CB, list(_CL)
    X, eye = hat3(x), sp.eye(3)
    U = _cayley3_matrix(x)
    r = residual(sp.simplify(U * (eye - X) - (eye + X)))  # U = (I + X)(I - X)^{-1}
    r += residual(sp.simplify(U.T * U - eye)) + residual(sp.simplify(U.det() - 1))
    jd = explicit(JD["JD"], {"U": U}, lam)
    r += residual(sp.simplify((eye - X) * (jd - hat3(b)) * (eye + X) - hat3(_cayley3_G(x, b, _CL))))
    G = _cayley3_G(x, b, _CL)
    dx = sp.Matrix([MV3_CAYLEY_NEWTON[f"dx{i + 1}"] for i in range(3)])
    r += residual(sp.simplify(G.jacobian(x) - _cayley3_jacobian(x, b, _CL)))
    r += residual(sp.Matrix([sp.numer(sp.together(e)) for e in G.jacobian(x) * dx + G]))
    m_next = sp.Matrix([MV3_CAYLEY_UPDATE[f"m{i + 1}_next"] for i in range(3)])
    mv3 = explicit(MV_TRANSPORT["M_next"], {"Omega": U.T, "M": hat3(_CM)})
    r += residual(sp.simplify(hat3(m_next) - mv3))
    q_next = sp.Matrix(3, 3, lambda i, j: MV3_CAYLEY_UPDATE[f"q{i + 1}{j + 1}_next"])
    r += residual(sp.simplify(q_next - _CQ * U))
    return r


@M1.check(Level.SYMBOLIC_FIXED_N)
def m1_cayley_scalar_form_n3() -> sp.Expr:
    r"""$n = 3$, the scalar form (symbolic): $(D_s - \hat b) z = \det b$ with $D_s =
    \operatorname{diag}(2I - s)$, and $\det^2 G(z/\det) = p(s) z$ ($G(zt)$ as a polynomial in $t$),
    so $x = z/\det$ solves $G(x) = 0$ exactly when $p(s) = 0$; the emitted Newton steps
    (mv3_cayley_s_newton, the $ds$ of mv3_cayley_step) are $-p/p'$ at $b = hm$ with $p'$ SymPy's
    derivative of $p$, $s_{\mathrm{next}} = s + ds$; and the emitted update's
    $\operatorname{cay}(\widehat{z/\det})$ written without the division equals
    $\operatorname{cay}(\hat x)$ of mv3_cayley_update."""
    s, b, lam = _CS, _CB, _CL
    z, det, p = _cayley3_scalar_form(s, b, lam)
    Ds = sp.diag(*[2 * e - s for e in _cayley3_inertia(lam)])
    r = residual((Ds - hat3(b)) * z - det * b)
    t = sp.Symbol("t")
    for i, Gi in enumerate(_cayley3_G(z * t, b, lam)):
        g0, g1, g2 = (sp.expand(Gi).coeff(t, k) for k in range(3))
        r += residual(det**2 * g0 + det * g1 + g2 - p * z[i])
    p_h = _cayley3_scalar_form(s, _CB_H, lam)[2]
    r += residual(p_h - p.xreplace({b[i]: _CB_H[i] for i in range(3)}))
    for k in (MV3_CAYLEY_S_NEWTON, MV3_CAYLEY_STEP):
        r += 0 if k["ds"] == -p_h / sp.diff(p_h, s) else 1  # the emitted tree itself
        r += residual(k["s_next"] - s - k["ds"])
    zs, dd = sym_vector("z", 3), sp.Symbol("det", positive=True)
    diff = _cayley3_matrix_zd(zs, dd) - _cayley3_matrix(zs / dd)
    return r + residual(diff.applyfunc(lambda e: sp.numer(sp.together(e))))


@M1.check(Level.EXACT_RATIONAL)
def m1_cayley_step_composition_n3() -> sp.Expr:
    r"""$n = 3$ (exact rationals, 4 random points): $m + dm$ and $Q + dQ$ of mv3_cayley_step are the
    checked mv3_cayley_update at $x = z(s_{\mathrm{next}})/\det(s_{\mathrm{next}})$ (the scalar
    form's $x$, which m1_cayley_scalar_form_n3 shows solves $G(x) = 0$ at a root of $p$)."""
    rng = np.random.default_rng(10)
    total = sp.Integer(0)
    for _ in range(4):
        vals = {_CS: sp.Rational(int(rng.integers(1, 50)), 1000), _CH: sp.Rational(1, 10)}
        vals |= {_CM[i]: sp.Rational(int(rng.integers(-20, 21)), 10) for i in range(3)}
        vals |= {_CL[i]: sp.Rational(int(rng.integers(5, 20)), 10) for i in range(3)}
        vals |= {_CQ[i, j]: sp.Rational(int(rng.integers(-9, 10)), 7) for i in range(3)
                 for j in range(3)}  # fmt: skip
        s1 = MV3_CAYLEY_STEP["s_next"].xreplace(vals)
        z, det, _ = _cayley3_scalar_form(s1, _CB_H.xreplace(vals), _CL.xreplace(vals))
        x = z / det
        upd = {_CX[i]: x[i] for i in range(3)} | vals
        for i in range(3):
            total += abs((_CM[i] + MV3_CAYLEY_STEP[f"dm{i + 1}"]).xreplace(vals)
                         - MV3_CAYLEY_UPDATE[f"m{i + 1}_next"].xreplace(upd))  # fmt: skip
            for j in range(3):
                key = f"{i + 1}{j + 1}"
                total += abs((_CQ[i, j] + MV3_CAYLEY_STEP[f"dq{key}"]).xreplace(vals)
                             - MV3_CAYLEY_UPDATE[f"q{key}_next"].xreplace(upd))  # fmt: skip
    return total
