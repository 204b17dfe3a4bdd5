r"""D4: the advance map of the extremal equations is symplectic (paper, Section 2, eq8.13).

Where: Section 2, the remark after the corollary: :math:`\Phi^*(dx_{k+1}\wedge dp_{k+1}) =
dx_k\wedge dp_k` for the advance map :math:`\Phi`.

Recorded outcome: holds.  Evidence: for every :math:`n`, :math:`D\Phi` in :math:`n\times n`
blocks that are noncommutative symbols (:math:`H^*_{xx}`, :math:`H^*_{yy}` symmetric,
:math:`H^*_{xy}` invertible), checked to solve D3's corrected equations and to satisfy the
displayed identity; :math:`D\Phi` from D3's corrected equations for generic symbolic entries
(:math:`n = 2`) and exact rational blocks (:math:`n = 3`); and on the nonlinear float64 family of
:mod:`._nonlinear_family` by implicit differentiation and by central differences; independent of
symrb.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import sympy as sp

from derivations.claims.section2._general_n import Alphabet, blocks
from derivations.claims.section2._indexed import _nonzero, _vec
from derivations.claims.section2._nonlinear_family import NonlinearFamily
from derivations.claims.section2.d03_linearised_equations import _R, LINEARISED
from derivations.registry import Level, claim
from derivations.symbolic import eq, explicit, lhs_minus_rhs
from derivations.vocabulary import n

D4 = claim(
    "D4",
    label="eq8.13",
    title="The advance map $(x_k, p_k) \\mapsto (x_{k+1}, p_{k+1})$ is symplectic",
    statement="The implicit advance map $\\Phi$ of the extremal equations preserves "
    "$dx\\wedge dp$: its Jacobian $D\\Phi$, obtained from the corrected linearised equations of D3 "
    "where $H^*_{xy}$ is invertible, satisfies [[symplectic]] with [[omega]].",
    expected="holds",
    section="2",
    where="Section 2, the remark after the corollary: the advance map $\\Phi$ is symplectic, "
    "$\\Phi^*(dx_{k+1} \\wedge dp_{k+1}) = dx_k \\wedge dp_k$",
    note="Shown for every symmetric $H^*_{xx}$, $H^*_{yy}$ and invertible $H^*_{xy}$ (so for "
    "every smooth $H^*$ with invertible mixed derivative): for every $n$ with the blocks as "
    "noncommutative symbols, symbolic entries for $n = 2$, exact rational random blocks for "
    "$n = 3$, and on a nonlinear family solved numerically.",
)
_DPhi, _Omega = sp.MatrixSymbol(r"D\Phi", 2 * n, 2 * n), sp.MatrixSymbol(r"\Omega", 2 * n, 2 * n)
OMEGA = D4.formula(
    "omega",
    eq(_Omega, sp.BlockMatrix([[sp.ZeroMatrix(n, n), sp.Identity(n)],
                               [-sp.Identity(n), sp.ZeroMatrix(n, n)]])),
)  # fmt: skip
SYMPLECTIC = D4.formula("symplectic", eq(_DPhi.T * _Omega * _DPhi, _Omega))


def _advance_jacobian(Hxx: sp.Matrix, Hxy: sp.Matrix, Hyy: sp.Matrix) -> sp.Matrix:
    """D Phi obtained by solving D3's displayed corrected equations for (dx_{k+1}, dp_{k+1})."""
    dim = Hxx.rows
    dxk, dpk, dx1, dp1 = (_vec(s, dim) for s in ("dxk", "dpk", "dx1", "dp1"))
    env = {"dx_k": dxk, "dp_k": dpk, "dx_{k+1}": dx1, "dp_{k+1}": dp1,
           "H^*_{xx}": Hxx, "H^*_{xy}": Hxy, "H^*_{yy}": Hyy}  # fmt: skip
    eqs = [e for f in LINEARISED for e in explicit(lhs_minus_rhs(f), env)]
    sol = sp.solve(eqs, [*dx1, *dp1], dict=True)[0]
    new = dx1.col_join(dp1).xreplace(sol)
    return new.jacobian(dxk.col_join(dpk))


def _symplectic_defect(J: sp.Matrix) -> sp.Matrix:
    dim = J.rows // 2
    om = OMEGA.rhs.subs(n, dim).as_explicit()
    return explicit(lhs_minus_rhs(SYMPLECTIC), {r"D\Phi": J, r"\Omega": sp.Matrix(om)})


@D4.check(Level.SYMBOLIC_FIXED_N)
def d4_symbolic() -> sp.Expr:
    r"""$D\Phi$ from D3's corrected equations with generic symmetric $H^*_{xx}$, $H^*_{yy}$ and
    generic $H^*_{xy}$ (symbolic entries, $n = 2$): the displayed $D\Phi^T \Omega\, D\Phi - \Omega$
    cancels entrywise."""
    dim = 2
    Hxx = sp.Matrix(dim, dim, lambda i, j: sp.Symbol(f"s{min(i, j)}{max(i, j)}"))
    Hyy = sp.Matrix(dim, dim, lambda i, j: sp.Symbol(f"t{min(i, j)}{max(i, j)}"))
    Hxy = sp.Matrix(dim, dim, lambda i, j: sp.Symbol(f"a{i}{j}"))
    return _nonzero(_symplectic_defect(_advance_jacobian(Hxx, Hxy, Hyy)).applyfunc(sp.cancel))


@D4.check(Level.SYMBOLIC_GENERAL_N)
def d4_general_n() -> sp.Expr:
    r"""Every $n$: with $H^*_{xx}$, $H^*_{yy}$ symmetric and $H^*_{xy}$ invertible as noncommutative
    symbols, the blocks of $D\Phi$, $(D\Phi)_{11} = H^{*T}_{xy} - H^*_{yy} H^{*-1}_{xy} H^*_{xx}$,
    $(D\Phi)_{12} = H^*_{yy} H^{*-1}_{xy}$, $(D\Phi)_{21} = -H^{*-1}_{xy} H^*_{xx}$ and
    $(D\Phi)_{22} = H^{*-1}_{xy}$, solve D3's displayed corrected equations (the unique solution:
    $H^*_{xy}$ is invertible), and the displayed $D\Phi^T \Omega\, D\Phi - \Omega$, multiplied out
    in blocks with the displayed $\Omega$, reduces to zero (number of words left)."""
    Hxx, Hxy, Hyy = _R["xx"], _R["xy"], _R["yy"]
    w = Alphabet(symmetric=[str(Hxx.name), str(Hyy.name)], invertible=[str(Hxy.name)])
    Hi = sp.Inverse(Hxy)
    J = sp.Matrix([[Hxy.T - Hyy * Hi * Hxx, Hyy * Hi], [-Hi * Hxx, Hi]])
    dxk, dpk, dx1, dp1 = (
        sp.MatrixSymbol(s, n, 1) for s in ("dx_k", "dp_k", "dx_{k+1}", "dp_{k+1}")
    )
    solved = {dx1: J[0, 0] * dxk + J[0, 1] * dpk, dp1: J[1, 0] * dxk + J[1, 1] * dpk}
    total = sum((w.is_zero(w.nc(lhs_minus_rhs(f).xreplace(solved))) for f in LINEARISED),
                sp.Integer(0))  # fmt: skip
    env = {str(_DPhi.name): J.applyfunc(w.nc), str(_Omega.name): blocks(OMEGA.rhs, {}, w)}
    return total + sum(w.is_zero(b) for b in blocks(lhs_minus_rhs(SYMPLECTIC), env, w))


@D4.check(Level.EXACT_RATIONAL)
def d4_exact_n3() -> sp.Expr:
    """The same for $n = 3$ at 4 random rational symmetric $H^*_{xx}$, $H^*_{yy}$ and invertible
    rational $H^*_{xy}$."""
    rng = np.random.default_rng(4)
    total = sp.Integer(0)
    done = 0
    while done < 4:
        A, B, C = (sp.Matrix(3, 3, [sp.Rational(int(v), 7) for v in rng.integers(-9, 10, 9)])
                   for _ in range(3))  # fmt: skip
        if C.det() == 0:  # the statement assumes an invertible H*_xy
            continue
        total += _nonzero(_symplectic_defect(_advance_jacobian(A + A.T, C, B + B.T)))
        done += 1
    return total


def symplecticity_defects(seeds: Sequence[int] = range(5), fd: bool = False) -> list[float]:
    """Largest entry of the displayed D Phi^T Omega D Phi - Omega on NonlinearFamily(3, 2, seed)
    at a random point, D Phi by implicit differentiation or central differences."""
    out = []
    for seed in seeds:
        fam = NonlinearFamily(3, 2, seed)
        rng = np.random.default_rng(100 + seed)
        x, p = rng.standard_normal(3), 0.5 * rng.standard_normal(3)
        J = fam.advance_jacobian_fd(x, p) if fd else fam.advance_jacobian(x, p)
        out.append(float(np.max([float(abs(v)) for v in _symplectic_defect(sp.Matrix(J))])))
    return out


@D4.check(Level.FLOAT64, tol=1e-12)
def d4_float64() -> float:
    r"""$f = x + 0.3 \tanh(W x + B u + c)$, $g = |u|^2/2 + |x|^2/4$ (5 random families and points,
    $n = 3$, $m = 2$): implicit step by scipy root, $D\Phi$ by implicit differentiation, largest
    entry of the displayed $D\Phi^T \Omega\, D\Phi - \Omega$ (entries of order 1)."""
    return float(np.max(symplecticity_defects()))


@D4.check(Level.FLOAT64, tol=1e-7)
def d4_float64_fd() -> float:
    r"""The same with $D\Phi$ by central differences of the implicit step (step 1e-6, 3 points; the
    tolerance is the differences' truncation and round-off error)."""
    return float(np.max(symplecticity_defects(range(3), fd=True)))


# the paper's sentences (the remark after the corollary)

D4.sentence(
    r"We remark that the implicit advance map $\Phi:(x_k,p_k) \mapsto (x_{k+1},p_{k+1})$ "
    r"generated by the extremal evolution (eq8.3) is symplectic, i.e., "
    r"$\Phi^*(dx_{k+1}\wedge dp_{k+1})=dx_k\wedge dp_k.$",
    d4_symbolic,
    d4_exact_n3,
    d4_float64,
    d4_float64_fd,
    d4_general_n,
)
D4.sentence(
    r"This is easily demonstrated by using Corollary (C:8.3).",
    d4_symbolic,
    d4_exact_n3,
    d4_general_n,
)
D4.sentence(
    r"One can also derive symplecticity directly from Hamilton's phase space principle; see "
    r"[MaWe2001].",
    kind="prose",
    reason="points to another proof in the literature",
)
