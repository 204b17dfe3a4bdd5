"""S9 (Section 3.3, eq. ``M_Q_P.eqn`` and the definition ``CandS.definition``): ||M||_op <= 2 is
necessary for M = Q^T P - P^T Q with P in SO(n).

If Q, P are rotations then ||Q^T P - P^T Q||_op <= 2, and the bound is attained; with A = Q^T P
orthogonal, M^T M + (A + A^T)^T (A + A^T) = 4 I.  For a costate P in gl(n) (as in S5) there is no
bound: P = Q M / 2 solves the equation for every skew M.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from derivations import reference as ref
from derivations.claims.section3._display import OpNorm
from derivations.claims.section3._symmetric import M, P, Q
from derivations.claims.section3.s06_symmetric_to_rigid_body import SYMMETRIC_MOMENTUM
from derivations.registry import Level, claim
from derivations.symbolic import Words, eq, explicit, skew_matrix
from derivations.vocabulary import matrix, n

S9 = claim(
    "S9",
    label="M_Q_P.eqn, CandS.definition",
    title="$\\|M\\|_{\\mathrm{op}} \\le 2$ is necessary for $M = Q^T P - P^T Q$ with $P$ in "
    "$\\mathrm{SO}(n)$",
    statement="If $Q, P\\in SO(n)$ and [[M]], then [[bound]], and the bound is attained. With "
    "$A$ the orthogonal matrix $Q^TP$, [[identity]]. For $P\\in\\mathfrak{gl}(n)$ there is no "
    "bound: [[gl]] solves the equation for every skew $M$. The set $C$ contains the pairs with "
    "$Q^TP$ skew and orthogonal; such pairs exist only for even $n$.",
    expected="holds",
    section="3.3",
    where="Section 3.3 (Local equivalence of classical rigid body and symmetric rigid body "
    "equations), the paragraph before the definition of $C$ and $S$ (the necessary condition "
    "$\\|M\\|_{\\mathrm{op}} \\le 2$), and that definition",
    note="The paper's argument uses $\\|P\\|_{\\mathrm{op}} \\le 1$, so $P$ is in "
    "$\\mathrm{SO}(n)$ (or $\\mathrm{O}(n)$). For a costate $P$ in $\\mathfrak{gl}(n)$, as in S5, "
    "there is no bound. With $A = Q^T P$ orthogonal the identity gives $\\|Mx\\|^2 = 4\\|x\\|^2 - "
    "\\|(A + A^T)x\\|^2$, so $\\|M\\|_{\\mathrm{op}} = 2$ exactly when $A + A^T$ is singular ($A$ "
    "has eigenvalues $\\pm i$). The paper's remark that $C$ contains pairs with $Q^TP$ skew and "
    "orthogonal is vacuous for odd $n$: a skew matrix of odd size has determinant 0, so none is "
    "orthogonal; for even $n$ the rotation by $\\pi/2$ in orthogonal planes is one.",
)
S9_M = S9.formula("M", eq(M, SYMMETRIC_MOMENTUM.outputs["M"]))
BOUND = S9.formula("bound", sp.Le(OpNorm(M), 2))
_Ao = matrix("A")
IDENTITY = S9.formula("identity", eq(M.T * M + (_Ao + _Ao.T).T * (_Ao + _Ao.T), 4 * sp.Identity(n)))
GL_SOLUTION = S9.formula("gl", eq(P, Q * M / 2))


@S9.check(Level.SYMBOLIC_GENERAL_N)
def s9_identity_general_n() -> sp.Integer:
    r"""Noncommutative orthogonal $Q$, $P$ (any $n$): the displayed identity with $M$ the emitted
    momentum and $A = Q^T P$ reduces to 0, and its constant is the square of the displayed bound (so
    $|Mx|^2 \le \mathrm{bound}^2 |x|^2$)."""
    w = Words(orthogonal=["Q", "P"])
    env = {M: SYMMETRIC_MOMENTUM["M"], _Ao: Q.T * P}
    lhs, rhs = (w.of(side.xreplace(env)) for side in (IDENTITY.lhs, IDENTITY.rhs))
    return w.is_zero(lhs - rhs) + sp.Integer(sp.expand(rhs - BOUND.rhs**2) != 0)


@S9.check(Level.SYMBOLIC_GENERAL_N)
def s9_no_bound_on_gl() -> sp.Integer:
    """Noncommutative orthogonal $Q$ and skew $M$ (any $n$): the emitted momentum at the displayed
    $P = QM/2$ reduces to $M$, whatever the size of $M$."""
    w = Words(orthogonal=["Q"], skew=["M"])
    return w.is_zero(w.of(SYMMETRIC_MOMENTUM["M"].xreplace({P: GL_SOLUTION.rhs})) - w("M"))


@S9.check(Level.FLOAT64, tol=1e-12)
def s9_sampled_bound() -> float:
    r"""symrb.symmetric.symmetric_momentum of 3000 random pairs of reference rotations ($n = 2,
    \dots, 7$): by how much its largest operator norm exceeds the displayed bound (0 when it does
    not)."""
    import symrb

    rng = np.random.default_rng(9)
    norms = []
    for k in range(2, 8):
        Qs = np.stack([ref.random_rotation(k, rng) for _ in range(500)])
        Ps = np.stack([ref.random_rotation(k, rng) for _ in range(500)])
        norms.append(
            np.linalg.norm(symrb.symmetric.symmetric_momentum(Qs, Ps), 2, axis=(-2, -1)).max()
        )
    return float(np.max([0.0, np.max(norms) - float(BOUND.rhs)]))


@S9.check(Level.FLOAT64, tol=1e-13)
def s9_bound_attained() -> float:
    r"""The bound is attained: for $Q^T P$ an orthogonal matrix with a rotation by $\pi/2$ in some
    plane (random $Q$, random rotation on the complement, $n = 3, \dots, 6$), the operator norm of
    symrb.symmetric.symmetric_momentum($Q$, $P$) minus the displayed bound, in absolute value."""
    from scipy.linalg import block_diag

    import symrb

    rng = np.random.default_rng(90)
    errs = []
    for k in range(3, 7):
        rest = ref.random_rotation(k - 2, rng) if k > 3 else np.eye(1)
        V = ref.random_rotation(k, rng)
        A = V @ block_diag(np.array([[0.0, -1.0], [1.0, 0.0]]), rest) @ V.T
        Qk = ref.random_rotation(k, rng)
        errs.append(
            np.linalg.norm(symrb.symmetric.symmetric_momentum(Qk, Qk @ A), 2) - float(BOUND.rhs)
        )
    return float(np.max(np.abs(errs)))


@S9.check(Level.EXACT_RATIONAL)
def s9_skew_orthogonal_pairs() -> sp.Integer:
    r"""The remark after the definition of $C$: for $n = 2, 4, 6$ the block rotation $A$ by $\pi/2$
    in orthogonal planes is skew, orthogonal, in $\mathrm{SO}(n)$, and at the pair $(Q, P) = (I, A)$
    the emitted momentum $M$ has every eigenvalue of $M^T M$ equal to the displayed bound squared
    (so the pair is in $C$); for $n = 3, 5$ the determinant of a general symbolic skew matrix is 0
    (no skew matrix is orthogonal: the remark is vacuous). The number of these that fail."""
    bad = 0
    for k in (2, 4, 6):
        A = sp.diag(*[sp.Matrix([[0, -1], [1, 0]])] * (k // 2))
        Mk = explicit(SYMMETRIC_MOMENTUM["M"], {"Q": sp.eye(k), "P": A})  # the emitted M
        bad += int(A.T != -A) + int(A.T * A != sp.eye(k)) + int(A.det() != 1)
        bad += int(set((Mk.T * Mk).eigenvals()) != {BOUND.rhs**2})
    bad += sum(int(sp.expand(skew_matrix("a", k).det()) != 0) for k in (3, 5))
    return sp.Integer(bad)


@S9.check(Level.FLOAT64, tol=1e-12)
def s9_S_onto_S_M() -> float:
    r"""$S_M$ is the image of $S$: for random $(Q, M)$ in $S_M$ ($Q$ a reference rotation, $M$ skew
    with $\|M\|_{\mathrm{op}} = 0.5, 1.5, 1.99$; $n = 3, \dots, 6$), $P = Q (M/2 + (I +
    M^2/4)^{1/2})$ (square root by numpy.linalg.eigh) is a rotation, and
    symrb.symmetric.symmetric_momentum($Q$, $P$) is $M$. Max of $|Q^T P - P^T Q - M|$, $|P^T P - I|$
    and $|\det P - 1|$."""
    import symrb

    rng = np.random.default_rng(91)
    worst = 0.0
    for k in range(3, 7):
        for size in (0.5, 1.5, 1.99):
            Qk, Mk = ref.random_rotation(k, rng), ref.random_skew(k, rng)
            Mk *= size / np.linalg.norm(Mk, 2)
            w, V = np.linalg.eigh(np.eye(k) + Mk @ Mk / 4)
            Pk = Qk @ (Mk / 2 + V @ np.diag(np.sqrt(w)) @ V.T)
            worst = max(
                worst,
                np.abs(symrb.symmetric.symmetric_momentum(Qk, Pk) - Mk).max(),
                np.abs(Pk.T @ Pk - np.eye(k)).max(),
                abs(np.linalg.det(Pk) - 1.0),
            )
    return float(worst)


def _lagrangian(g: np.ndarray, gdot: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """S3's L(g, gdot) = 1/2 <g^-1 gdot, J(g^-1 gdot)> in NumPy (complex entries allowed)."""
    xi = np.linalg.solve(g, gdot)
    return 0.5 * ref.pairing(xi, ref.J(xi, lam))


@S9.check(Level.FLOAT64, tol=1e-12)
def s9_left_trivialisation() -> float:
    r"""The trivialisation of the definition: the fibre derivative of the rigid body Lagrangian
    $L(g, \dot g) = \frac12 \langle g^{-1} \dot g, J(g^{-1} \dot g)\rangle$ (S3) at $(Q, Q\Omega)$,
    evaluated on the left translates $Q E_{ij}$ of the basis of $\mathfrak{so}(n)$ (complex step),
    and identified with $\mathfrak{so}(n)$ by the Gram matrix of the pairing (killing.eqn), is $M =
    J(\Omega)$: the point $(Q, M)$ of $T^*\mathrm{SO}(n)$ in which $S_M$ is stated is the rigid
    body's attitude and momentum ($n = 3, \dots, 5$, 5 random points each; max difference relative
    to $|M|$)."""
    rng = np.random.default_rng(92)
    worst = 0.0
    for k in range(3, 6):
        pairs = [(i, j) for i in range(k) for j in range(i + 1, k)]
        basis = []
        for i, j in pairs:
            e = np.zeros((k, k))
            e[i, j], e[j, i] = 1.0, -1.0
            basis.append(e)
        gram = np.array([[ref.pairing(a, b) for b in basis] for a in basis])
        lam = rng.uniform(0.3, 2.0, k)
        for _ in range(5):
            Qk, Om = ref.random_rotation(k, rng), ref.random_skew(k, rng)
            h = 1e-30
            mu = [np.imag(_lagrangian(Qk, Qk @ (Om + 1j * h * e), lam)) / h for e in basis]
            coeffs = np.linalg.solve(gram, np.array(mu))
            m = sum(c * e for c, e in zip(coeffs, basis, strict=True))
            want = ref.J(Om, lam)
            worst = max(worst, np.abs(m - want).max() / np.abs(want).max())
    return float(worst)


# the paper's sentences
S9.sentence(
    r"Above we saw that solutions of the symmetric rigid body equations can be mapped to solutions "
    r"of the rigid body system.",
    kind="prose",
    reason="recalls S6, checked there",
)
S9.sentence(
    r"As in [BlCrMaRa2002] we can consider the converse question.",
    kind="prose",
    reason="announces the question, with a citation",
)
S9.sentence(
    r"Thus, suppose we have a solution $(Q, M)$ of the standard left invariant rigid body "
    r"equations.",
    kind="prose",
    reason="sets up the question; the rigid body equations are S2",
)
S9.sentence(
    r"We seek to solve for $P$ in the expression $M=Q^TP-P^TQ.$",
    s9_no_bound_on_gl,
)
S9.sentence(
    r"For the following discussion, it will be convenient to make use of the operator norm on "
    r"matrices.",
    kind="prose",
    reason="announces the tool used next",
)
S9.sentence(
    r"Recall that this norm is given by $\| A \|_{\mathrm{op}} = \sup \left\{ \| A x \| \mid \| x "
    r"\| = 1 \right\}$, where the norms on the right hand side are the usual Euclidean space "
    r"norms.",
    s9_identity_general_n,
)
S9.sentence(
    r"Since elements of $\operatorname{SO}(n)$ have operator norms bounded by $1$ and since the "
    r"operator norm satisfies $\| A B \|_{\mathrm{op}} \leq \| A \|_{\mathrm{op}} \| B "
    r"\|_{\mathrm{op}}$, we see that if $M$ satisfies $M=Q^TP-P^TQ$, then $\| M \|_{\mathrm{op}} "
    r"\leq 2$.",
    s9_identity_general_n,
    s9_sampled_bound,
    s9_bound_attained,
)
S9.sentence(
    r"Therefore, $\| M \|_{\mathrm{op}} \leq 2$ is a necessary condition for solvability of "
    r"(M_Q_P.eqn) for $P$.",
    s9_identity_general_n,
    s9_sampled_bound,
    s9_no_bound_on_gl,
)
S9.sentence(
    r"Let $C$ denote the set of $(Q,P)$ that map to $M$'s with operator norm equal to 2 and let "
    r"$S$ denote the set of $(Q,P)$ that map to $M$'s with operator norm strictly less than 2.",
    s9_bound_attained,
    s9_skew_orthogonal_pairs,
)
S9.sentence(
    r"Also denote by $S_M$ the set of points $(Q,M) \in T^*\operatorname{SO}(n)$ with $\| M "
    r"\|_{\mathrm{op}} < 2$.",
    s9_S_onto_S_M,
)
S9.sentence(
    r"For the left invariant system we trivialize $T^*\operatorname{SO}(n) \cong "
    r"\operatorname{SO}(n) \times \mathfrak{so}(n)^\ast$ by means of left translation to the "
    r"identity and we identify $\mathfrak{so}(n)^\ast$ with $\mathfrak{so}(n)$ using the Killing "
    r"metric (killing.eqn).",
    s9_left_trivialisation,
)
S9.sentence(
    r"Note that $C$ contains pairs $(Q,P)$ with the property that $Q^TP$ is both skew and "
    r"orthogonal.",
    s9_skew_orthogonal_pairs,
)
