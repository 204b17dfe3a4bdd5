"""S8 (Section 3.2, eqs. ``rboptcontprobm``, ``optrm``, ``eqnrm``): the learning version, samples
sharing one control.

For samples Qdot^a = Q^a U sharing one control, with the cost of S5 plus sum_a phi(Q^a_T), the
extremals satisfy Qdot^a = Q^a U, Pdot^a = P^a U with U = sum_a J^-1((Q^a)^T P^a - (P^a)^T Q^a).
Erratum: the endpoints Q^a_T are free (the definition keeps Q_T fixed beside the terminal cost, the
slip D5 corrects in Section 2), and the endpoint condition is P^a_T = -2 dphi/dQ^a_T (minus the
gradient in the pairing of S5), not +dphi/dQ^a_T.

Emitted to ``symrb/_generated/symmetric_rigid_body.py``: ``control_rhs``.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from derivations import reference as ref
from derivations.claims.section3._display import GlPair
from derivations.claims.section3._exact import count_nonzero
from derivations.claims.section3._inertia import lam_symbols
from derivations.claims.section3._symmetric import ARG_P, ARG_Q, ARG_U, P, Q, U
from derivations.claims.section3.s05_maximum_principle import (
    COST,
    COSTATE,
    H_SYM,
    P_SYM,
    derivative_rule,
    gl_gradient,
    maximiser,
    unfold,
)
from derivations.registry import Level, claim
from derivations.symbolic import Words, eq, explicit, general_matrix, skew_matrix, trace_residual
from derivations.vocabulary import Jinv, Kernel, W, matrix

S8 = claim(
    "S8",
    label="rboptcontprobm, optrm, eqnrm",
    title="Learning version: shared control, per-sample costates, endpoint condition",
    statement="For the samples [[eqnrm]] sharing one control, with the cost of S5 plus "
    "$\\sum_a\\phi(Q^a_T)$, the extremals satisfy [[costates]] with [[control]], the maximiser "
    "of [[H]], and an endpoint condition on $P^a_T$.",
    expected="holds after correction",
    headline="[[endpoint_corrected]], with $Q^a_T$ free",
    printed="The definition keeps $Q_T$ given and fixed beside the terminal cost "
    "$\\sum_a\\phi(Q^a_T)$; [[endpoint_printed]] (with the printed $U$).",
    corrected="The endpoints $Q^a_T$ are free (fixed, they make the terminal cost a constant "
    "and give no endpoint condition); [[endpoint_corrected]], where "
    "$\\partial\\phi/\\partial Q$ is the matrix of entrywise partial derivatives: minus the "
    "gradient in the pairing of S5.",
    note="The definition keeps $Q_T$ given and fixed beside the terminal cost, and the endpoint "
    "condition $P^a_T = \\partial\\phi/\\partial Q^a_T$ has the wrong sign and factor for the "
    "printed control. Corrected: the endpoints $Q^a_T$ are free and $P^a_T = "
    "-2\\,\\partial\\phi/\\partial Q^a_T$, minus the gradient of $\\phi$ in the pairing of S5. "
    "The fixed endpoint is the slip D5 corrects in Section 2: with $Q_T$ fixed, "
    "$\\phi(Q_T)$ is a constant and no endpoint condition follows; in an exact example ($Q_0 = "
    "I$, the fixed $Q_T$ a rational rotation $R$, $\\phi(Q) = \\tfrac12\\|Q - R\\|_F^2$) either "
    "endpoint condition gives $P_T = 0$, where the extremal equations are at rest, so the "
    "extremal meeting it starts at $R$ instead of $Q_0$ ($\\|R - I\\|_F^2 = 48/55$). With the running cost entering the "
    "maximum principle with multiplier $-1$ (so that $U$ is the printed $+J^{-1}(\\cdots)$, see "
    "S5), transversality gives $P_T = -\\nabla\\phi$, and the gradient in the pairing "
    "$\\tfrac12\\operatorname{tr}(A^T B)$ is twice the entrywise derivative. Checked against a "
    "forward tangent-linear derivative of the cost: with the corrected endpoint the reduced "
    "gradient is $\\tfrac12 J(U - \\sum_a J^{-1}(M^a))$ and vanishes exactly at the printed $U$; "
    "with the printed one it does not match. Equivalently the printed sign is right after $P "
    "\\mapsto -P$, $U \\mapsto -J^{-1}(\\cdots)$. For every $n$ (noncommutative symbols): "
    "along the extremal fields $\\tfrac{d}{dt}\\langle P^a, \\delta Q^a\\rangle$ is "
    "$\\tfrac12\\langle M^a, \\delta U\\rangle$, so the two derivatives agree exactly when "
    "$\\operatorname{tr}(G^T\\delta Q_T) + \\langle P_T, \\delta Q_T\\rangle$ vanishes for every "
    "free $\\delta Q_T$, which the corrected condition gives and the printed one does not.",
    section="3.2",
    where="Section 3.2, the second definition (several samples $Q^a$ and a terminal cost "
    "$\\phi$), the third proposition ($U = \\sum_a J^{-1}((Q^a)^T P^a - (P^a)^T Q^a)$) and the "
    "endpoint condition after it, $P^a_T = \\partial\\phi/\\partial Q^a_T$",
)
_a, _m = sp.symbols("a m", integer=True, positive=True)
Qa, Pa = matrix("Q^a"), matrix("P^a")
EQNRM = S8.formula("eqnrm", eq(matrix("Qdot^a"), Qa * U))
COSTATES = S8.formula("costates", (EQNRM, eq(matrix("Pdot^a"), Pa * U)))
CONTROL = S8.formula("control", eq(U, sp.Sum(Jinv(Qa.T * Pa - Pa.T * Qa), (_a, 1, _m))))
S8_H = S8.formula("H", eq(H_SYM, sp.Sum(GlPair(Pa, Qa * U), (_a, 1, _m)) - COST))
_phi = sp.Function("phi")
_QT, _PT = sp.symbols("Q^a_T P^a_T")
S8.formula("endpoint_printed", eq(_PT, sp.Derivative(_phi(_QT), _QT)))
S8.formula("endpoint_corrected", eq(_PT, -2 * sp.Derivative(_phi(_QT), _QT)))

CONTROL_RHS = Kernel(
    name="control_rhs",
    target="symmetric_rigid_body",
    args=[ARG_Q, ARG_P, ARG_U],
    outputs={"Qdot": Q * U, "Pdot": P * U},
    doc="State and costate fields for a given control U: Qdot = Q U, Pdot = P U.\n\n"
    "The learning version (paper, Section 3.2), one sample per batch entry.",
    claims=("S8",),
)


def _samples(expr: sp.Basic, count: int) -> sp.Basic:
    """A displayed sum over the samples a = 1..m written out for m = count, with Q^a, P^a
    renamed Q1, P1, Q2, ..."""

    def expand_sum(s: sp.Sum) -> sp.Basic:
        return sp.Add(
            *[
                s.function.xreplace({Qa: matrix(f"Q{i}"), Pa: matrix(f"P{i}")})
                for i in range(1, count + 1)
            ]
        )

    return expr.replace(lambda e: isinstance(e, sp.Sum), expand_sum)


@S8.check(Level.SYMBOLIC_FIXED_N)
def s8_two_samples() -> sp.Integer:
    r"""Two samples, $n = 3$, general $Q^a$, $P^a$, skew $U$, symbolic $\Lambda$: the displayed
    Hamiltonian (pairing of S5) is maximised (Hessian $-c (\lambda_i + \lambda_j)$) at the displayed
    control $U = \sum_a J^{-1}(\dots)$; for every sample the emitted control field equals the
    displayed $(Q^a U, P^a U)$ and the costate equations $\dot Q^a = \partial H/\partial P^a$, $\dot
    P^a = -\partial H/\partial Q^a$ of S5."""
    lam, Ux = lam_symbols(3), skew_matrix("u", 3)
    env: dict[str, sp.Matrix] = {"U": Ux}
    for i in (1, 2):
        env[f"Q{i}"], env[f"P{i}"] = general_matrix(f"q{i}", 3), general_matrix(f"p{i}", 3)
    Hx = sp.expand(explicit(unfold(_samples(S8_H.rhs, 2)), env, lam))
    Ustar, total = maximiser(Hx, Ux, lam)
    total += count_nonzero(Ustar - explicit(_samples(CONTROL.rhs, 2), env, lam))
    for i in (1, 2):
        Qi, Pi = env[f"Q{i}"], env[f"P{i}"]
        one = {"Q": Qi, "P": Pi, "U": Ux, "Q^a": Qi, "P^a": Pi}
        for out, rel, costate in zip(("Qdot", "Pdot"), COSTATES, COSTATE, strict=True):
            kernel = explicit(CONTROL_RHS[out], one, lam)
            total += count_nonzero(kernel - explicit(rel.rhs, one, lam))
            c, var = derivative_rule(costate)
            total += count_nonzero(kernel - c * gl_gradient(Hx, Pi if var == P_SYM else Qi))
    return total


@S8.check(Level.FLOAT64, tol=1e-13)
def s8_symrb_multi_sample() -> float:
    r"""symrb.symmetric.multi_sample_control against $\sum_a J^{-1}(M^a)$, $M^a = (Q^a)^T P^a -
    (P^a)^T Q^a$, with $J^{-1}$ from the reference linear solve, and
    symrb.symmetric.multi_sample_rhs against $(Q^a U, P^a U)$, for $m = 1, 2, 5$ samples, $n = 3,
    4$, batches of 3: max difference relative to the size of the reference $U$."""
    import symrb

    rng = np.random.default_rng(81)
    errs = []
    for k in (3, 4):
        lam = rng.uniform(0.3, 2.0, k)
        for count in (1, 2, 5):
            Qs = np.stack([[ref.random_rotation(k, rng) for _ in range(count)] for _ in range(3)])
            Ps = rng.standard_normal((3, count, k, k))
            moments = np.swapaxes(Qs, -1, -2) @ Ps - np.swapaxes(Ps, -1, -2) @ Qs
            want = ref.J_inv(moments, lam).sum(axis=1)
            size = np.abs(want).max()
            errs.append(
                np.abs(symrb.symmetric.multi_sample_control(Qs, Ps, lam) - want).max() / size
            )
            dQ, dP = symrb.symmetric.multi_sample_rhs(Qs, Ps, lam)
            errs.append(np.abs(dQ - Qs @ want[:, None]).max() / size)
            errs.append(np.abs(dP - Ps @ want[:, None]).max() / size / np.abs(Ps).max())
    return float(np.max(errs))


def endpoint_mismatch(coefficient: float) -> float:
    """Relative mismatch of two computations of the derivative of the learning cost
    int_0^1 1/4 <U, JU> dt + sum_a phi(Q^a_1), phi(Q) = 1/2 |Q - R|_F^2 (two samples, n = 3,
    controls linear in t) in a direction dU: forward with the tangent-linear equation, and by the
    maximum principle as int 1/2 <J(U - symrb.symmetric.multi_sample_control(Q, P)), dU> dt with P
    integrated backward from P^a_1 = coefficient * dphi/dQ^a_1 (entrywise derivative Q - R).
    Zero only for the coefficient -2."""
    from scipy.integrate import solve_ivp

    import symrb

    rng = np.random.default_rng(8)
    k, count = 3, 2
    lam = np.array([0.7, 1.1, 1.6])
    U0, U1, V0, V1 = (ref.random_skew(k, rng, 0.7) for _ in range(4))
    R = ref.random_rotation(k, rng)
    Q0 = np.stack([ref.random_rotation(k, rng) for _ in range(count)])
    size = count * k * k

    def fwd(t: float, y: np.ndarray) -> np.ndarray:
        Qy, dQ = y[:size].reshape(count, k, k), y[size:].reshape(count, k, k)
        Ut, dUt = U0 + t * U1, V0 + t * V1
        return np.concatenate([(Qy @ Ut).ravel(), (dQ @ Ut + Qy @ dUt).ravel()])

    kw = dict(method="DOP853", rtol=1e-13, atol=1e-13, dense_output=True)
    a = solve_ivp(fwd, (0, 1), np.concatenate([Q0.ravel(), np.zeros(size)]), **kw)
    Q1, dQ1 = a.y[:size, -1].reshape(count, k, k), a.y[size:, -1].reshape(count, k, k)
    nodes, weights = np.polynomial.legendre.leggauss(40)
    ts, ws = (nodes + 1) / 2, weights / 2
    # forward: d/de of int 1/4 <U, JU> + sum_a phi(Q^a_1), phi(Q) = 1/2 |Q - R|_F^2
    d_forward = sum(
        wt * 0.5 * float(ref.pairing(ref.J(U0 + t * U1, lam), V0 + t * V1))
        for t, wt in zip(ts, ws, strict=True)
    )
    d_forward += float(np.sum((Q1 - R) * dQ1))
    # backward: P from the displayed endpoint condition, dphi/dQ = Q - R entrywise
    P1 = coefficient * (Q1 - R)
    b = solve_ivp(
        lambda t, y: (y.reshape(count, k, k) @ (U0 + t * U1)).ravel(), (1, 0), P1.ravel(), **kw
    )
    # reduced gradient of the maximum principle: 1/2 <J(U - sum_a J^-1(M^a)), dU>
    d_adjoint = 0.0
    for t, wt in zip(ts, ws, strict=True):
        Qt = a.sol(t)[:size].reshape(count, k, k)
        Pt = b.sol(t).reshape(count, k, k)
        gap = U0 + t * U1 - symrb.symmetric.multi_sample_control(Qt, Pt, lam)
        d_adjoint += wt * 0.5 * float(ref.pairing(ref.J(gap, lam), V0 + t * V1))
    return abs(d_forward - d_adjoint) / abs(d_forward)


def _endpoint_mismatch(form: str) -> float:
    coeff, deriv = S8.formulas[f"endpoint_{form}"].rhs.as_coeff_Mul()
    if not (isinstance(deriv, sp.Derivative) and deriv.variables == (_QT,)):
        raise ValueError("the endpoint condition is not a multiple of d phi / d Q^a_T")
    return endpoint_mismatch(float(coeff))


@S8.check(Level.FLOAT64, tol=1e-8, form="printed")
def s8_printed_endpoint() -> float:
    r"""The derivative of the learning cost (two samples, $n = 3$, $\phi = \frac12 |Q - R|_F^2$,
    controls linear in $t$) in a direction $dU$, forward (tangent-linear $dQ$) against the adjoint
    form $\int \frac12 \langle J(U - U^*), dU\rangle\, dt$, $U^*$ the control of
    symrb.symmetric.multi_sample_control at $(Q, P)$, with $P$ integrated backward from the printed
    endpoint condition (its coefficient read from the displayed formula): relative mismatch."""
    return _endpoint_mismatch("printed")


@S8.check(Level.FLOAT64, tol=1e-8, form="corrected")
def s8_corrected_endpoint() -> float:
    """The same with $P$ integrated backward from the displayed corrected endpoint condition."""
    return _endpoint_mismatch("corrected")


def _s8_endpoint_extremal_start(target: sp.Matrix, form: str) -> sp.Matrix:
    """Where the extremal through the endpoint (Q_T, P_T) starts, one sample, n = 3, rational
    Lambda: Q_T is the target R of phi(Q) = 1/2 ||Q - R||_F^2, P_T from the displayed endpoint
    condition ``form`` (its coefficient times the entrywise derivative of phi, by SymPy), U from
    the displayed control.  There the displayed fields Q U and P U vanish, so the extremal is
    constant and starts at Q_T (anything else raises: the example would need an integration)."""
    coeff, deriv = S8.formulas[f"endpoint_{form}"].rhs.as_coeff_Mul()
    if not (isinstance(deriv, sp.Derivative) and deriv.variables == (_QT,)):
        raise ValueError("the endpoint condition is not a multiple of d phi / d Q^a_T")
    lam = [sp.Rational(7, 10), sp.Rational(11, 10), sp.Rational(8, 5)]
    Qs = general_matrix("q", 3)
    phi = sum(((e - r) ** 2 for e, r in zip(Qs, target, strict=True)), sp.Integer(0)) / 2
    point = dict(zip(Qs, target, strict=True))
    P_T = (coeff * Qs.applyfunc(lambda e: sp.diff(phi, e))).xreplace(point)
    env = {"Q1": target, "P1": P_T}
    Ux = explicit(_samples(CONTROL.rhs, 1), env, lam)
    one = {"Q^a": target, "P^a": P_T, "U": Ux}
    fields = [explicit(rel.rhs, one, lam) for rel in COSTATES]
    if any(f != sp.zeros(3, 3) for f in fields):
        raise ValueError("the extremal through the endpoint is not an equilibrium")
    return target


def _rational_rotation(a: int, b: int, c: int, d: int) -> sp.Matrix:
    """The Cayley rotation (I - A)^{-1}(I + A) of the skew A with entries a, b, c over d."""
    A = sp.Matrix([[0, a, b], [-a, 0, c], [-b, -c, 0]]) / d
    return (sp.eye(3) - A).inv() * (sp.eye(3) + A)


@S8.check(Level.EXACT_RATIONAL, form="printed")
def s8_printed_fixed_endpoint() -> sp.Expr:
    r"""The definition keeps $Q_T$ given and fixed beside the terminal cost: with $Q_0 = I$, the
    fixed $Q_T$ a rational rotation $R$ (Cayley, entries 1, 2, -1 over 7) and $\phi(Q) = \frac12\|Q
    - R\|^2$, an admissible control is not zero, yet either displayed endpoint condition gives $P_T
    = 0$, where the displayed extremal equations are at rest, so the extremal meeting it starts at
    $R$, not at $Q_0$: the smaller of $\|Q(0) - Q_0\|_F^2$ over the printed and corrected
    conditions."""
    R = _rational_rotation(1, 2, -1, 7)
    gaps = [_s8_endpoint_extremal_start(R, form) - sp.eye(3) for form in ("printed", "corrected")]
    return sp.Min(*(sp.nsimplify(sum(e**2 for e in g)) for g in gaps))


@S8.check(Level.EXACT_RATIONAL, form="corrected")
def s8_free_endpoint() -> sp.Expr:
    r"""The same terminal cost with $Q_T$ free and $Q_0 = R$: $U = 0$ is optimal (the cost, a sum of
    non-negative terms, vanishes there), so $Q_T = R$, and the corrected endpoint condition with the
    displayed extremal equations gives the extremal that starts at $Q_0$: $\|Q(0) - Q_0\|_F^2$."""
    R = _rational_rotation(1, 2, -1, 7)
    return sp.nsimplify(sum(e**2 for e in _s8_endpoint_extremal_start(R, "corrected") - R))


def _s8_adjoint_defect(form: str) -> sp.Integer:
    """Trace words left in the two identities behind the endpoint condition, every n (one
    sample: the sum over samples is linear).  (A) Along the displayed fields, with dQ the
    variation of the displayed dynamics in a direction dU (skew) and U skew: d/dt <P, dQ> minus
    1/2 <M, dU>, M the displayed momentum in U, both in the displayed pairing of S5.  (B) At the
    free endpoint, with P_T from the displayed endpoint condition (coefficient c times G, the
    entrywise derivative of phi, so that dphi is tr(G^T dQ_T)): tr(G^T dQ_T) + <P_T, dQ_T>.
    Traces vanish for all matrices when the words of (E + E^T)/2 cancel cyclically."""
    w = Words(skew=["U", "dU"])
    dQ, dU, G = matrix("dQ^a"), matrix("dU"), matrix("G^a")
    eps = sp.Symbol("epsilon")
    qdot, pdot = (rel.rhs for rel in COSTATES)
    moved = w.of(qdot.xreplace({Qa: Qa + eps * dQ, U: U + eps * dU}))
    dqdot = sp.expand(sp.diff(sp.expand(moved), eps)).subs(eps, 0)
    # (A) the product rule on the displayed pairing, then the pairing unfolded into traces
    pair = w.trace_argument(unfold(GlPair(Pa, dQ)))  # c * P^T dQ
    c_pair = sp.expand(pair).coeff(w.T(w("P^a")) * w("dQ^a"))
    rate = c_pair * (w.T(w.of(pdot)) * w("dQ^a") + w.T(w("P^a")) * dqdot)
    (momentum,) = (x for x in CONTROL.rhs.function.args if x != W)
    adjoint = w.trace_argument(unfold(GlPair(momentum, dU))) / 2
    identity_a = sp.expand(rate - adjoint)
    # (B) the endpoint condition with its displayed coefficient
    coeff, deriv = S8.formulas[f"endpoint_{form}"].rhs.as_coeff_Mul()
    if not (isinstance(deriv, sp.Derivative) and deriv.variables == (_QT,)):
        raise ValueError("the endpoint condition is not a multiple of d phi / d Q^a_T")
    identity_b = w.T(w("G^a")) * w("dQ^a") + w.trace_argument(unfold(GlPair(coeff * G, dQ)))
    return sum(
        (trace_residual(sp.expand((e + w.T(e)) / 2)) for e in (identity_a, identity_b)),
        sp.Integer(0),
    )


@S8.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def s8_endpoint_any_n() -> sp.Integer:
    r"""Why the corrected endpoint condition, for every $n$ (noncommutative symbols): along the
    displayed fields $\frac{d}{dt} \langle P^a, dQ^a\rangle$ equals $\frac12 \langle M^a, dU\rangle$
    ($dQ^a$ the variation of the displayed dynamics, $U$ and $dU$ skew), so the cost's derivative,
    $\operatorname{tr}(G^T dQ_T)$ plus the running part, equals the adjoint form $\int \frac12
    \langle J(U - \sum_a J^{-1}(M^a)), dU\rangle\, dt$ exactly when $\operatorname{tr}(G^T dQ_T) +
    \langle P_T, dQ_T\rangle$ vanishes for every free $dQ_T$; with the displayed corrected $P_T$ it
    does ($G$ the entrywise derivative of $\phi$; count of trace words left)."""
    return _s8_adjoint_defect("corrected")


@S8.check(Level.SYMBOLIC_GENERAL_N, form="printed")
def s8_printed_endpoint_any_n() -> sp.Integer:
    r"""The same with the printed endpoint condition: $\operatorname{tr}(G^T dQ_T) + \langle P_T,
    dQ_T\rangle$ does not vanish (every $n$)."""
    return _s8_adjoint_defect("printed")


# the paper's sentences
S8.sentence(
    r"We can now generalize to the machine learning setting:",
    kind="prose",
    reason="announces the definition that follows",
)
S8.sentence(
    r"Let $T >0$, $Q_0, Q_T \in \operatorname{SO}(n)$ be given and fixed.",
    s8_printed_fixed_endpoint,
    s8_free_endpoint,
)
S8.sentence(
    r"Let the rigid body optimal control problem be given by $\min_{U\in \mathfrak{so}(n)} "
    r"\frac{1}{4}\int_0^T \langle U,J(U)\rangle dt +\sum_{a=1}^M\phi(Q^a_T)$ subject to the "
    r"constraint on $U$ that there be a curve $Q(t) \in \operatorname{SO}(n)$ such that $\dot "
    r"Q^a=Q^aU\qquad Q^a(0)=Q^a_0,\, a=1\dots M.$",
    s8_two_samples,
    s8_printed_endpoint,
    s8_corrected_endpoint,
    s8_printed_fixed_endpoint,
    s8_free_endpoint,
    s8_endpoint_any_n,
    s8_printed_endpoint_any_n,
)
S8.sentence(
    r"The smooth machine learning symmetric rigid body flow has optimal evolution equations $\dot "
    r"Q^a=Q^aU,\, \dot P^a=P^aU$ where $P$ is the costate vector given by the maximum principle",
    s8_two_samples,
    s8_symrb_multi_sample,
)
S8.sentence(
    r"The optimal controls in this case are given by $U=\sum_aJ^{-1}((Q^a)^TP^a-(P^a)^TQ^a).$",
    s8_two_samples,
    s8_symrb_multi_sample,
    s8_endpoint_any_n,
    s8_printed_endpoint_any_n,
)
S8.sentence(
    r"and we have the endpoint conditions $P^a_T=\frac{\partial\phi (Q^a_T)}{\partial Q^a_T}$",
    s8_printed_endpoint,
    s8_corrected_endpoint,
    s8_printed_fixed_endpoint,
    s8_free_endpoint,
    s8_endpoint_any_n,
    s8_printed_endpoint_any_n,
)
