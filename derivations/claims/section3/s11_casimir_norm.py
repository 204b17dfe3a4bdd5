"""S11 (Section 3.3, the invariance of C and S): ||M||_op is a Casimir.

Along the symmetric rigid body flow the spatial momentum Q M Q^T is constant; as Q stays
orthogonal (S12), M(t) is orthogonally conjugate to M(0), so its operator norm is constant and the
sets C (norm equal to 2) and S (norm below 2) are invariant.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import sympy as sp

from derivations import reference as ref
from derivations.claims.section3._display import Ddt
from derivations.claims.section3._symmetric import M, Q
from derivations.claims.section3._words import ddt, jinv_letters
from derivations.claims.section3.s05_maximum_principle import SYMMETRIC_RIGID_BODY_RHS
from derivations.claims.section3.s06_symmetric_to_rigid_body import SYMMETRIC_MOMENTUM
from derivations.registry import Level, claim
from derivations.symbolic import Pair, Words, eq, trace_residual
from derivations.vocabulary import Jinv, matrix, n

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
    r"""Noncommutative $Q$, $P$ (any $n$): $\frac{d}{dt}$ of the displayed $Q M Q^T$, with $M$ the
    emitted momentum and $(\dot Q, \dot P)$ the emitted field ($J^{-1}(M)$ a skew letter), reduces
    to the displayed 0."""
    w = Words(skew=["U"])
    Mk = SYMMETRIC_MOMENTUM["M"]
    rates = {
        o[0]: w.of(jinv_letters(SYMMETRIC_RIGID_BODY_RHS[o], w, {"U": Jinv(Mk)}))
        for o in ("Qdot", "Pdot")
    }
    spatial = w.of(SPATIAL.lhs.args[0].xreplace({M: Mk}))
    return w.is_zero(ddt(w, spatial, rates) - w.of(SPATIAL.rhs))


@S11.check(Level.SYMBOLIC_GENERAL_N)
def s11_conjugation_keeps_norm_general_n() -> sp.Integer:
    """The operator norm is invariant under conjugation, for every $n$: with $Q$ orthogonal and $M$
    skew (noncommutative letters), $X = Q M Q^T$ has $X^T X = Q (M^T M) Q^T$ and $y = Q^T x$ has
    $y^T y = x^T x$, so $|Xx|^2 = |My|^2$ and the suprema over unit vectors agree (each identity
    reduces to 0)."""
    w = Words(orthogonal=["Q"], skew=["M"])
    q, m, x = w("Q"), w("M"), w("x")
    conj = q * m * w.T(q)
    y = w.T(q) * x
    gram = w.reduce(w.T(conj) * conj - q * w.T(m) * m * w.T(q))
    lengths = w.reduce(w.T(y) * y - w.T(x) * x)
    images = w.reduce(w.T(conj * x) * (conj * x) - w.T(m * y) * (m * y))
    return w.is_zero(gram) + w.is_zero(lengths) + w.is_zero(images)


@S11.check(Level.SYMBOLIC_GENERAL_N)
def s11_coadjoint_is_conjugation() -> sp.Integer:
    r"""Under the identification of $\mathfrak{so}(n)^*$ with $\mathfrak{so}(n)$ by the pairing of
    S1, the coadjoint action is conjugation: $\langle \mu, g^{-1} \xi g\rangle = \langle g \mu
    g^{-1}, \xi\rangle$ for $g$ orthogonal ($g^{-1} = g^T$), as trace words in noncommutative $\mu$,
    $g$, $\xi$ (every $n$)."""
    w = Words()
    mu, g, xi = matrix("mu"), matrix("g"), matrix("xi")
    diff = Pair(mu, g.T * xi * g) - Pair(g * mu * g.T, xi)
    return trace_residual(w.trace_argument(diff.doit()))


def _norm_drift(k: int, lam: np.ndarray, Q0: np.ndarray, P0: np.ndarray) -> float:
    """Largest change of ||M(t)||_op along symrb's symmetric rigid body flow, t in [0, 10]."""
    import symrb

    kw: dict[str, Any] = dict(method="DOP853", rtol=1e-12, atol=1e-12)
    sol = symrb.integrate(
        symrb.SymmetricRigidBody,
        (0.0, 10.0),
        {"Q": Q0, "P": P0},
        lam=lam,
        t_eval=np.linspace(0.0, 10.0, 21),
        **kw,
    )
    norms = np.linalg.norm(sol.y.M, 2, axis=(-2, -1))
    return float(np.abs(norms - norms[0]).max())


@S11.check(Level.FLOAT64, tol=1e-9)
def s11_norm_constant_on_flow() -> float:
    r"""The level sets are invariant: along symrb.integrate(SymmetricRigidBody) ($n = 4$, DOP853,
    rtol 1e-12, $t$ in $[0, 10]$) the operator norm of $M = Q^T P - P^T Q$ (numpy.linalg.norm, ord
    2) stays 2 from a pair in $C$ ($Q^T P$ a rotation by $\pi/2$ in one plane) and stays at its
    value below 2 from a random pair in $S$; and $\|Q M Q^T\|_{\mathrm{op}} = \|M\|_{\mathrm{op}}$
    for 20 random rotations $Q$ and skew $M$ ($n = 3, \dots, 6$). Max absolute change."""
    from scipy.linalg import block_diag

    rng = np.random.default_rng(111)
    k, lam = 4, np.array([0.6, 0.9, 1.3, 1.9])
    Q0 = ref.random_rotation(k, rng)
    V = ref.random_rotation(k, rng)
    quarter = np.array([[0.0, -1.0], [1.0, 0.0]])
    on_C = Q0 @ V @ block_diag(quarter, ref.random_rotation(2, rng)) @ V.T
    on_S = ref.random_rotation(k, rng)
    worst = max(_norm_drift(k, lam, Q0, on_C), _norm_drift(k, lam, Q0, on_S))
    start_C = np.linalg.norm(Q0.T @ on_C - on_C.T @ Q0, 2)
    start_S = np.linalg.norm(Q0.T @ on_S - on_S.T @ Q0, 2)
    worst = max(worst, abs(start_C - 2.0), float(start_S >= 2.0 - 1e-6))
    for size in range(3, 7):
        for _ in range(20):
            Qr, Mr = ref.random_rotation(size, rng), ref.random_skew(size, rng)
            worst = max(worst, abs(np.linalg.norm(Qr @ Mr @ Qr.T, 2) - np.linalg.norm(Mr, 2)))
    return float(worst)


# the paper's sentences
S11.sentence(
    r"The sets $C$ and $S$ are invariant under the double rigid body equations.",
    s11_spatial_momentum_general_n,
    s11_norm_constant_on_flow,
)
S11.sentence(
    r"Notice that the operator norm is invariant under conjugation; that is, for $Q \in "
    r"\operatorname{SO}(n)$ and $M \in \mathfrak{so}(n)$, we have $\| Q M Q^{-1} \|_{\mathrm{op}} "
    r"= \| M \|_{\mathrm{op}}$.",
    s11_conjugation_keeps_norm_general_n,
    s11_norm_constant_on_flow,
)
S11.sentence(
    r"This is readily checked from the definition of the operator norm.",
    kind="prose",
    reason="points to the proof of the previous sentence",
)
S11.sentence(
    r"Recall that under the identification of the dual $\mathfrak{so}(n)^\ast$ with the space "
    r"$\mathfrak{so}(n)$, the coadjoint action agrees with conjugation.",
    s11_coadjoint_is_conjugation,
)
S11.sentence(
    r"Thus, the map $f: \mathfrak{so}(n) \rightarrow \mathbb{R}$; $M \mapsto \| M \|_{\mathrm{op}}$ "
    r"is a Casimir function and so is invariant under the dynamics.",
    s11_spatial_momentum_general_n,
    s11_coadjoint_is_conjugation,
    s11_norm_constant_on_flow,
)
S11.sentence(
    r"In particular, its level sets are invariant and so the sets $S$ and $C$ are invariant.",
    s11_spatial_momentum_general_n,
    s11_norm_constant_on_flow,
)
