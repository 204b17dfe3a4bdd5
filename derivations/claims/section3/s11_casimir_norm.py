"""S11 (Section 3.3, the invariance of C and S): ||M||_op is a Casimir.

Along the symmetric rigid body flow the spatial momentum Q M Q^T is constant; as Q stays
orthogonal (S12), M(t) is orthogonally conjugate to M(0), so its operator norm is constant and the
sets C (norm equal to 2) and S (norm below 2) are invariant.
"""

from __future__ import annotations

import sympy as sp

from derivations.claims.section3._display import Ddt
from derivations.claims.section3._symmetric import M, Q
from derivations.claims.section3._words import ddt, jinv_letters
from derivations.claims.section3.s05_maximum_principle import SYMMETRIC_RIGID_BODY_RHS
from derivations.claims.section3.s06_symmetric_to_rigid_body import SYMMETRIC_MOMENTUM
from derivations.registry import Level, claim
from derivations.symbolic import Words, eq
from derivations.vocabulary import Jinv, n

S11 = claim(
    "S11",
    label="invariance of C and S",
    title="$\\|M\\|_{\\mathrm{op}}$ is a Casimir; $C$ and $S$ are invariant",
    statement="Along the symmetric rigid body flow, [[spatial]] with [[M]]; as $Q$ stays "
    "orthogonal (S12), $M(t)$ is orthogonally conjugate to $M(0)$, so its operator norm is "
    "constant and the sets $C$ (norm equal to 2) and $S$ (norm below 2) are invariant.",
    expected="holds",
    section="3.3",
    where="Section 3.3, the second proposition ($C$ and $S$ are invariant under the rigid body "
    "equations) and its proof (the operator norm is a Casimir)",
    note="The paper argues with the coadjoint action; the check is the equivalent statement that "
    "the spatial momentum $QMQ^T$ is constant. Only $U^T = -U$ is used.",
)
SPATIAL = S11.formula("spatial", eq(Ddt(Q * M * Q.T), sp.ZeroMatrix(n, n)))
S11.formula("M", eq(M, SYMMETRIC_MOMENTUM.outputs["M"]))


@S11.check(Level.SYMBOLIC_GENERAL_N)
def s11_spatial_momentum_general_n() -> sp.Integer:
    """Noncommutative Q, P (any n): d/dt of the displayed Q M Q^T, with M the emitted momentum
    and (Qdot, Pdot) the emitted field (J^-1(M) a skew letter), reduces to the displayed 0."""
    w = Words(skew=["U"])
    Mk = SYMMETRIC_MOMENTUM["M"]
    rates = {
        o[0]: w.of(jinv_letters(SYMMETRIC_RIGID_BODY_RHS[o], w, {"U": Jinv(Mk)}))
        for o in ("Qdot", "Pdot")
    }
    spatial = w.of(SPATIAL.lhs.args[0].xreplace({M: Mk}))
    return w.is_zero(ddt(w, spatial, rates) - w.of(SPATIAL.rhs))


# the paper's sentences
S11.sentence(
    r"The sets $C$ and $S$ are invariant under the double rigid body equations.",
    s11_spatial_momentum_general_n,
)
S11.sentence(
    r"Notice that the operator norm is invariant under conjugation; that is, for $Q \in "
    r"\operatorname{SO}(n)$ and $M \in \mathfrak{so}(n)$, we have $\| Q M Q^{-1} \|_{\mathrm{op}} "
    r"= \| M \|_{\mathrm{op}}$.",
)
S11.sentence(
    r"This is readily checked from the definition of the operator norm.",
    kind="prose",
    reason="points to the proof of the previous sentence",
)
S11.sentence(
    r"Recall that under the identification of the dual $\mathfrak{so}(n)^\ast$ with the space "
    r"$\mathfrak{so}(n)$, the coadjoint action agrees with conjugation.",
)
S11.sentence(
    r"Thus, the map $f: \mathfrak{so}(n) \rightarrow \mathbb{R}$; $M \mapsto \| M \|_{\mathrm{op}}$ "
    r"is a Casimir function and so is invariant under the dynamics.",
    s11_spatial_momentum_general_n,
)
S11.sentence(
    r"In particular, its level sets are invariant and so the sets $S$ and $C$ are invariant.",
    s11_spatial_momentum_general_n,
)
