"""S7 (Section 3.2, eq. ``rbnlms``): a costate B with Q^T B skew gives the McLachlan-Scovel
equations.

For a costate B with Q^T B skew the extremal equations of S5 become Qdot = Q J^-1(Q^T B),
Bdot = B J^-1(Q^T B); the set where Q^T B is skew is invariant and on it Q^T B follows the rigid
body equations.  Erratum: for a costate B with Q^T B skew the extremal control is J^-1(2 Q^T B),
so (rbnlms) holds for 2B (equivalently for P - Q P^T Q, the paper's commented-out remark), not for
the costate itself.

Emitted to ``symrb/_generated/symmetric_rigid_body.py``: ``mclachlan_scovel_rhs``.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from derivations import reference as ref
from derivations.claims.section3._inertia import ARG_LAM
from derivations.claims.section3._symmetric import ARG_B, ARG_Q, MOMENTUM, B, Bdot, P, Q, Qdot
from derivations.claims.section3._words import ddt, jinv_letters, reduce_words, rule
from derivations.claims.section3.s05_maximum_principle import SYMMETRIC_RIGID_BODY_RHS
from derivations.registry import Level, claim
from derivations.symbolic import Words, eq, explicit
from derivations.vocabulary import Jinv, Kernel, matrix

S7 = claim(
    "S7",
    label="rbnlms",
    title="A costate $B$ with $Q^T B$ skew: the McLachlan-Scovel equations",
    statement="For a costate $B$ with [[skew]], the extremal equations of S5 become [[rbnlms]]; "
    "these equations leave the set where $Q^TB$ is skew invariant, and on it $Q^TB$ follows the "
    "rigid body equations (the McLachlan-Scovel equations).",
    expected="holds after correction",
    headline="[[extremal_B]]",
    printed="The extremal equations for a costate $B$ with [[skew]] are [[rbnlms]].",
    corrected="The extremal equations for a costate $B$ with [[skew]] are [[extremal_B]]: "
    "the McLachlan-Scovel equations hold for the rescaled costate [[rescaled]], which on this set is "
    "[[remark]], the map the paper's commented-out remark names.",
    note="Read for the costate itself, the printed McLachlan-Scovel equations run the extremal "
    "flow at half speed. Corrected: the extremals are $\\dot Q = QJ^{-1}(2Q^T B)$, $\\dot B = "
    "BJ^{-1}(2Q^T B)$, so the printed equations hold for the rescaled costate $B' = 2B$. With "
    "$Q^T B$ skew, $Q^T B - B^T Q = 2Q^T B$, so the control of S5 is $U = J^{-1}(2Q^T B)$; on "
    "this set $B' = 2B$ equals $B - QB^T Q$. That map, $B' = P - QP^T Q$, takes every solution of "
    "the symmetric rigid body equations with $Q$ orthogonal to a solution of the McLachlan-Scovel "
    "equations with $Q^T B' = M$ (the paper's commented-out remark). The invariance of the set "
    "where $Q^T B$ is skew holds for any $U$: $S = Q^T B + B^T Q$ obeys $\\dot S = U^T S + SU$.",
    section="3.2",
    where="Section 3.2, the paragraph after the proof of the second proposition: the "
    "McLachlan-Scovel equations $\\dot Q = QJ^{-1}(Q^T B)$, $\\dot B = BJ^{-1}(Q^T B)$ for a "
    "costate $B$ with $Q^T B$ skew",
)
SKEW_B = S7.formula("skew", eq(sp.Transpose(Q.T * B), -Q.T * B))
MCLACHLAN_SCOVEL_RHS = Kernel(
    name="mclachlan_scovel_rhs",
    target="symmetric_rigid_body",
    args=[ARG_Q, ARG_B, ARG_LAM],
    outputs={"Qdot": Q * Jinv(Q.T * B), "Bdot": B * Jinv(Q.T * B)},
    doc="McLachlan-Scovel field (paper, Section 3.2).\n\n"
    "Qdot = Q U, Bdot = B U, U = J^{-1}(Q^T B), for Q^T B skew.",
    claims=("S7",),
)
RBNLMS = S7.formula(
    "rbnlms",
    tuple(eq(d, MCLACHLAN_SCOVEL_RHS.outputs[o]) for d, o in ((Qdot, "Qdot"), (Bdot, "Bdot"))),
)
EXTREMAL_B = S7.formula(
    "extremal_B", (eq(Qdot, Q * Jinv(2 * Q.T * B)), eq(Bdot, B * Jinv(2 * Q.T * B)))
)
_Bs = matrix("B'")
RESCALED = S7.formula("rescaled", eq(_Bs, 2 * B))
REMARK = S7.formula("remark", eq(_Bs, B - Q * B.T * Q))


def _s7_extremals(form: str) -> sp.Integer:
    w = Words()
    rules = rule(w, SKEW_B)
    target = {"V": Jinv(Q.T * B)}
    shown = S7.formulas["rbnlms" if form == "printed" else "extremal_B"]
    total = sp.Integer(0)
    for out, rel in zip(("Qdot", "Pdot"), shown, strict=True):
        field = SYMMETRIC_RIGID_BODY_RHS[out].xreplace({P: B})  # S5's extremals, costate B
        lhs = reduce_words(w, w.of(jinv_letters(field, w, target, rules)), rules)
        rhs = reduce_words(w, w.of(jinv_letters(rel.rhs, w, target, rules)), rules)
        total += w.is_zero(lhs - rhs)
    return total


@S7.check(Level.SYMBOLIC_GENERAL_N, form="printed")
def s7_printed_extremals() -> sp.Integer:
    r"""The emitted S5 extremal field $(QU, BU)$, $U = J^{-1}(Q^T B - B^T Q)$, for a costate $B$
    with the displayed skewness (a rewriting rule $B^T Q \mapsto -Q^T B$) against the printed
    (rbnlms), any $n$ (noncommutative $Q$, $B$; $J^{-1}$ linear): number of equations that differ.
    """
    return _s7_extremals("printed")


@S7.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def s7_corrected_extremals() -> sp.Integer:
    """The same field against the corrected equations with $U = J^{-1}(2 Q^T B)$, any $n$."""
    return _s7_extremals("corrected")


@S7.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def s7_remark_maps_symmetric_flow() -> sp.Integer:
    r"""Noncommutative $Q$ (orthogonal), $P$, any $n$: for $B$ from the displayed remark, $Q^T B$ is
    the momentum, so the emitted McLachlan-Scovel field at $(Q, B)$ has the $U$ of the emitted
    symmetric field; $\frac{d}{dt} B$ along the symmetric field (product rule) equals its $\dot B$,
    and its $\dot Q$ equals the symmetric $\dot Q$. And on the displayed skew set ($B^T Q \mapsto
    -Q^T B$) the remark equals the displayed rescaling $2B$."""
    w = Words(orthogonal=["Q"], skew=["U"])
    target = {"U": Jinv(MOMENTUM)}
    sym = {o: w.of(jinv_letters(SYMMETRIC_RIGID_BODY_RHS[o], w, target)) for o in ("Qdot", "Pdot")}
    Bp = REMARK.rhs.xreplace({B: P})  # the remark applied to the symmetric costate P
    ms = {
        o: reduce_words(
            w, w.of(jinv_letters(MCLACHLAN_SCOVEL_RHS[o].xreplace({B: Bp}), w, target)), {}
        )
        for o in ("Qdot", "Bdot")
    }
    dB = ddt(w, w.of(Bp), {"Q": sym["Qdot"], "P": sym["Pdot"]})
    total = w.is_zero(ms["Qdot"] - sym["Qdot"]) + w.is_zero(ms["Bdot"] - dB)
    rules = rule(w, SKEW_B)
    return total + w.is_zero(reduce_words(w, w.of(REMARK.rhs) - w.of(RESCALED.rhs), rules))


@S7.check(Level.SYMBOLIC_GENERAL_N)
def s7_skew_set_invariant() -> sp.Integer:
    r"""Noncommutative $Q$, $B$, any $n$: along the emitted McLachlan-Scovel field ($\dot Q = QU$,
    $\dot B = BU$ with one $U$, not assumed skew), $S = Q^T B + B^T Q$ obeys the linear equation
    $\dot S = U^T S + S U$, so $S(0) = 0$ gives $S = 0$."""
    w = Words()
    rates = {
        o[0]: w.of(jinv_letters(MCLACHLAN_SCOVEL_RHS[o], w, {"U": Jinv(Q.T * B)}))
        for o in ("Qdot", "Bdot")
    }
    S = w.of(Q.T * B + B.T * Q)
    Uw = w("U")
    return w.is_zero(ddt(w, S, rates) - (w.T(Uw) * S + S * Uw))


@S7.check(Level.FLOAT64, tol=1e-9)
def s7_flow_against_elliptic() -> float:
    r"""symrb.integrate(McLachlanScovel) ($n = 3$, DOP853, rtol 1e-12) from $Q_0$ in
    $\mathrm{SO}(3)$, $B_0 = Q_0 \hat m_0$: its $M = Q^T B$ against the Jacobi elliptic solution of
    Euler's equations at 41 times in $[0, 20]$: $\max |M \text{ error}| / |m_0|$ (a factor in $U$
    changes the speed)."""
    import symrb

    rng = np.random.default_rng(71)
    inertia = np.array([1.0, 1.7, 2.6])
    lam = 0.5 * inertia.sum() - inertia
    t = np.linspace(0.0, 20.0, 41)
    m = ref.euler_elliptic(inertia, 0.8, 1.1, t)
    Q0 = ref.random_rotation(3, rng)
    sol = symrb.integrate(
        symrb.McLachlanScovel, (0.0, 20.0), {"Q": Q0, "B": Q0 @ ref.hat(m[0])}, lam=lam,
        rtol=1e-12, atol=1e-12, t_eval=t,
    )  # fmt: skip
    return float(np.abs(ref.vee(sol.y.M) - m).max() / np.linalg.norm(m[0]))


def _rational_rotation(k: int, rng: np.random.Generator) -> sp.Matrix:
    """The Cayley transform (I - A)^-1 (I + A) of a random rational skew A: an exact rotation."""
    A = sp.zeros(k, k)
    for i in range(k):
        for j in range(i + 1, k):
            A[i, j] = sp.Rational(int(rng.integers(-9, 10)), int(rng.integers(1, 7)))
            A[j, i] = -A[i, j]
    return (sp.eye(k) - A).inv() * (sp.eye(k) + A)


@S7.check(Level.EXACT_RATIONAL)
def s7_restricts_to_SO_x_SO() -> sp.Integer:
    r"""The symmetric rigid body system restricts to $\mathrm{SO}(n) \times \mathrm{SO}(n)$: at
    exact rational rotations $(Q, P)$ (Cayley transforms, 3 pairs each for $n = 3, 4$, rational
    $\Lambda$) the emitted field is tangent to $\mathrm{SO}(n) \times \mathrm{SO}(n)$, $Q^T \dot Q$
    and $P^T \dot P$ skew, so the closed set $\mathrm{SO}(n) \times \mathrm{SO}(n)$ is invariant.
    The number of entries of $Q^T \dot Q + \dot Q^T Q$ and $P^T \dot P + \dot P^T P$ that are not 0.
    """
    rng = np.random.default_rng(7)
    bad = 0
    for k in (3, 4):
        lam = [sp.Rational(int(rng.integers(3, 30)), 10) for _ in range(k)]
        for _ in range(3):
            env = {"Q": _rational_rotation(k, rng), "P": _rational_rotation(k, rng)}
            for name, rate in (("Q", "Qdot"), ("P", "Pdot")):
                X, Xdot = env[name], explicit(SYMMETRIC_RIGID_BODY_RHS[rate], env, lam)
                sym = X.T * Xdot + Xdot.T * X
                bad += sum(1 for e in sym if sp.simplify(e) != 0)
    return sp.Integer(bad)


# the paper's sentences
S7.sentence(
    r"While in general there are no constraints on the costate vector $P\in\mathfrak{gl}(n)$ one "
    r"can consider the restriction of the extremal flows to invariant submanifolds.",
    kind="prose",
    reason="introduces the restrictions that follow; each invariant set is checked in its own "
    "sentence",
)
S7.sentence(
    r"This limits possible extremal trajectories that can be recovered.",
    kind="prose",
    reason="a comment on the restrictions; it asserts nothing checkable",
)
S7.sentence(
    r"For example this system restricts to a system on $\operatorname{SO}(n)\times "
    r"\operatorname{SO}(n)$.",
    s7_restricts_to_SO_x_SO,
)
S7.sentence(
    r"One can make other assumptions on the costate vector.",
    kind="prose",
    reason="announces the next example",
)
S7.sentence(
    r"For example, suppose we assume a costate vector $B$ such that $Q^TB$ is skew.",
    s7_printed_extremals,
    s7_corrected_extremals,
    s7_skew_set_invariant,
)
S7.sentence(
    r"Then it is easy to check that that the extremal evolution equations become $\dot Q = "
    r"QJ^{-1}(Q^TB); \qquad \dot B = BJ^{-1}(Q^TB)\,,$ and that these equations restrict to an "
    r"invariant submanifold defined by the condition that $Q^TB$ is skew symmetric.",
    s7_printed_extremals,
    s7_corrected_extremals,
    s7_remark_maps_symmetric_flow,
    s7_skew_set_invariant,
    s7_flow_against_elliptic,
)
S7.sentence(
    r"These are the McLachlan-Scovel equations ([McSc1995]).",
    kind="prose",
    reason="names the equations and cites their source",
)
