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
