"""S6 (Section 3.2, Proposition ``SRBtoRB.prop``): from the symmetric representation to the rigid
body.

If (Q, P) solves the symmetric rigid body equations Qdot = Q U, Pdot = P U with U = J^-1(M), then
Q and M = Q^T P - P^T Q solve the rigid body equations of S2.  Only U^T = -U is used, so the
statement holds on all of gl(n) x gl(n).

Emitted to ``symrb/_generated/symmetric_rigid_body.py``: ``symmetric_momentum`` (S9, S10 and S11
read it from here).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import sympy as sp

from derivations import reference as ref
from derivations.claims.section3._symmetric import ARG_P, ARG_Q, MOMENTUM, M, Mdot, Om, Q, Qdot
from derivations.claims.section3._words import ddt, jinv_letters
from derivations.claims.section3.s05_maximum_principle import (
    OPTIMAL_U,
    SRB1,
    SYMMETRIC_RIGID_BODY_RHS,
)
from derivations.registry import Level, claim
from derivations.symbolic import Bracket, Words, eq
from derivations.vocabulary import Jinv, Kernel

S6 = claim(
    "S6",
    label="SRBtoRB.prop",
    title="$(Q, M = Q^T P - P^T Q)$ solves the rigid body equations",
    statement="If $(Q, P)$ solves [[srb1]] with [[U]], then $Q$ and [[M]] satisfy the rigid body "
    "equations [[rbl]] with [[Omega]].",
    expected="holds",
    section="3.2",
    where="Section 3.2, the second proposition: if $(Q, P)$ solves the symmetric equations, $(Q, "
    "M)$ solves the rigid body equations (with its one-line proof)",
    note="Only $U^T = -U$ is used; $Q^T Q = I$ is not needed, so the statement holds on all of "
    "$\\mathfrak{gl}(n) \\times \\mathfrak{gl}(n)$.",
)

SYMMETRIC_MOMENTUM = Kernel(
    name="symmetric_momentum",
    target="symmetric_rigid_body",
    args=[ARG_Q, ARG_P],
    outputs={"M": MOMENTUM},
    doc="The body momentum of the symmetric representation, M = Q^T P - P^T Q.\n\n"
    "Skew for any square Q, P; on the symmetric rigid body flow it follows the rigid body\n"
    "equations (paper, Proposition SRBtoRB).",
    claims=("S6", "S9", "S11"),
)
S6.formula("srb1", SRB1)
S6.formula("U", OPTIMAL_U)
S6_M = S6.formula("M", eq(M, SYMMETRIC_MOMENTUM.outputs["M"]))
RBL = S6.formula("rbl", (eq(Qdot, Q * Om), eq(Mdot, Bracket(M, Om))))
OMEGA = S6.formula("Omega", eq(Om, Jinv(M)))


@S6.check(Level.SYMBOLIC_GENERAL_N)
def s6_rigid_body_general_n() -> sp.Integer:
    r"""Noncommutative $Q$, $P$ (any $n$): with the emitted field, every $J^{-1}$ in it is the
    displayed $\Omega = J^{-1}(M)$ of the emitted $M$ ($J^{-1}$ is linear), $\dot Q$ equals the
    displayed $Q\Omega$, and $\frac{d}{dt} M$ (product rule) equals the displayed $[M, \Omega]$,
    using only $\Omega^T = -\Omega$."""
    w = Words(skew=["Omega"])
    Mk = SYMMETRIC_MOMENTUM["M"]
    target = {"Omega": OMEGA.rhs.xreplace({M: Mk})}
    rates = {
        out[0]: w.of(jinv_letters(SYMMETRIC_RIGID_BODY_RHS[out], w, target))
        for out in ("Qdot", "Pdot")
    }
    env = {M: Mk}
    total = w.is_zero(rates["Q"] - w.of(RBL[0].rhs))
    return total + w.is_zero(ddt(w, w.of(Mk), rates) - w.of(RBL[1].rhs.xreplace(env)))


@S6.check(Level.SYMBOLIC_GENERAL_N)
def s6_momentum_skew() -> sp.Integer:
    """The emitted $M = Q^T P - P^T Q$ is skew for noncommutative $Q$, $P$ (any $n$): $M + M^T$
    reduces to 0."""
    w = Words()
    Mw = w.of(SYMMETRIC_MOMENTUM["M"])
    return w.is_zero(Mw + w.T(Mw))


def _costate_for(Q0: np.ndarray, M0: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """A costate in gl(n) with Q0^T P0 - P0^T Q0 = M0 (Q0 orthogonal): Q0 (M0/2 + S), S a random
    symmetric matrix (which does not change M)."""
    S = rng.standard_normal(M0.shape)
    return Q0 @ (M0 / 2 + S + S.T)


@S6.check(Level.FLOAT64, tol=1e-9)
def s6_flow_against_elliptic() -> float:
    r"""symrb.integrate(SymmetricRigidBody) ($n = 3$, DOP853, rtol 1e-12) from $Q_0$ in
    $\mathrm{SO}(3)$ and a costate in $\mathfrak{gl}(3)$ with $M(0) = \hat m_0$: its $M(t) = Q^T P -
    P^T Q$ against the Jacobi elliptic solution of Euler's equations at 41 times in $[0, 20]$: $\max
    |M \text{ error}| / |m_0|$."""
    import symrb

    rng = np.random.default_rng(61)
    inertia = np.array([1.0, 1.7, 2.6])
    lam = 0.5 * inertia.sum() - inertia  # I_1 = lam_2 + lam_3 (cyclic)
    t = np.linspace(0.0, 20.0, 41)
    m = ref.euler_elliptic(inertia, 0.8, 1.1, t)
    Q0 = ref.random_rotation(3, rng)
    P0 = _costate_for(Q0, ref.hat(m[0]), rng)
    sol = symrb.integrate(
        symrb.SymmetricRigidBody, (0.0, 20.0), {"Q": Q0, "P": P0}, lam=lam,
        rtol=1e-12, atol=1e-12, t_eval=t,
    )  # fmt: skip
    return float(np.abs(ref.vee(sol.y.M) - m).max() / np.linalg.norm(m[0]))


@S6.check(Level.FLOAT64, tol=1e-9)
def s6_flow_against_reference_rigid_body() -> float:
    """symrb.integrate(SymmetricRigidBody) ($n = 4$, rtol 1e-12) against the reference rigid body
    field ($J^{-1}$ by a linear solve) integrated by solve_ivp from $(Q_0, M_0)$, at 11 times in
    $[0, 5]$: max difference of $Q$ and of $M = Q^T P - P^T Q$, relative to $|M_0|$."""
    from scipy.integrate import solve_ivp

    import symrb

    rng = np.random.default_rng(62)
    k = 4
    lam = np.array([0.6, 0.9, 1.3, 1.9])
    Q0, M0 = ref.random_rotation(k, rng), ref.random_skew(k, rng, 0.4)
    P0 = _costate_for(Q0, M0, rng)
    ts = np.linspace(0.0, 5.0, 11)
    kw: dict[str, Any] = dict(method="DOP853", rtol=1e-12, atol=1e-12, t_eval=ts)

    def field(_t: float, y: np.ndarray) -> np.ndarray:
        dQ, dM = ref.rigid_body_field(y[: k * k].reshape(k, k), y[k * k :].reshape(k, k), lam)
        return np.concatenate([dQ.ravel(), dM.ravel()])

    want = solve_ivp(field, (0.0, 5.0), np.concatenate([Q0.ravel(), M0.ravel()]), **kw)
    got = symrb.integrate(symrb.SymmetricRigidBody, (0.0, 5.0), {"Q": Q0, "P": P0}, lam=lam, **kw)
    Qw, Mw = (want.y[i * k * k : (i + 1) * k * k].T.reshape(-1, k, k) for i in range(2))
    err = np.max([np.abs(got.y.Q - Qw).max(), np.abs(got.y.M - Mw).max()])
    return float(err / np.abs(M0).max())


# the paper's sentences
S6.sentence(
    r"If $(Q, P)$ is a solution of (srb1), then $(Q, M)$ where $M = J(\Omega)$, $\Omega=U$, and "
    r"$\Omega = Q^{-1}\dot{Q}$ satisfies the rigid body equations (rbl).",
    s6_rigid_body_general_n,
    s6_momentum_skew,
    s6_flow_against_elliptic,
    s6_flow_against_reference_rigid_body,
)
S6.sentence(
    r"Differentiating $M=Q^TP-P^TQ$ and using the equations (srb1) gives the second of the "
    r"equations (rbl).",
    s6_rigid_body_general_n,
    s6_momentum_skew,
)
