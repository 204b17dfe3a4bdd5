r"""D9: the learning version, several samples and a terminal cost (paper, Section 2.1).

Where: Section 2.1, the second definition (mvoptprobm1, discrboptm: samples :math:`Q^a` and a
terminal cost :math:`\phi`) and the second theorem (discrbopteqnsm, Ukdef2, dischamm), with its
proof.

Recorded outcome: holds after correction.  The running cost starts at :math:`k = 0`, the sum runs
over :math:`a = 1, \dots, M`, and the endpoint sign is right after the sign change (two slips
cancel).

Emitted (``symrb/_generated/discrete_rigid_body.py``): the SO(n) network of ``symrb.learning``
(layer, endpoint costate, costate step, skew gradient).  Evidence: central differences of an
independently written cost, exact directional derivatives of an independently written loss, and
symrb's ``so_network_gradients`` against central differences.
"""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
import sympy as sp
from scipy.linalg import expm

from derivations import reference as ref
from derivations.claims.section2._matrix_formulas import (
    _JD,
    _LAM3,
    _N,
    Uk,
    _cayley_rational,
    _k,
    _numeric,
)
from derivations.claims.section2.d07_optimal_control_on_so_n import JD
from derivations.registry import Level, claim
from derivations.symbolic import Words, eq, explicit, general_matrix, skew_matrix
from derivations.vocabulary import Arg, Kernel, Lam, matrix

D9 = claim(
    "D9",
    label="mvoptprobm1, discrboptm, discrbopteqnsm, Ukdef2, dischamm",
    title="Learning version: several samples and a terminal cost",
    statement="Minimising [[cost]] subject to [[dynamics]] gives [[costate]], [[Ukdef2]] and "
    "[[endpoint]].",
    printed="The cost of the learning problem starts the running cost at one, [[cost_printed]], and writes "
    "$\\phi(\\overline Q^a_N)$ for the free end point while the definition keeps "
    "$\\overline Q^a_N$ given and fixed; the theorem's equation for $U_k$ typesets the sum's limits as "
    "`\\sum_{^Ma=1}`; the proof applies the multi-sample maximum principle, whose endpoint "
    "condition for the Hamiltonian of the proof, before the sign change, reads [[endpoint_m8]].",
    corrected="The running cost starts at zero, [[cost]], with $\\phi$ a function of the matrix "
    "$Q^a_N$, which is free; the sum in the equation for $U_k$ runs over the samples one to M; for the Hamiltonian of the proof "
    "the costate ends at [[endpoint_unflipped]], where [[final_unflipped]]; after the sign "
    "change used for the equation for $U_k$ this becomes the theorem's [[endpoint]] with [[Ukdef2]], so the "
    "theorem's equations hold as stated. The multiplier rule behind them needs no regularity "
    "hypothesis here: with the endpoint free the dynamics constraints have full row rank at "
    "every point (the next states enter with an identity block) and the orthogonality of the "
    "controls is a regular constraint, so there is no abnormal case.",
    note="The running cost starts at $k = 1$ (so the equation for $U_0$ fails), the sum over the "
    "samples is mistyped, the endpoint sign rests on two slips that cancel, and the definition "
    "fixes $\\overline Q^a_N$ beside the terminal cost. Corrected: the running cost starts at "
    "$k = 0$, the sum runs over $a = 1, \\dots, M$, the theorem's $P^a_N = "
    "\\partial\\phi/\\partial Q^a_N$ is right after the sign change $P \\mapsto -P$, and $Q^a_N$ "
    "is free. With $Q^a_N$ fixed, $\\phi(Q^a_N)$ is a constant and no endpoint condition follows "
    "(the slip D5 corrects): for $N = 1$, $Q_0 = I$, a fixed rational rotation $Q_1 = R$ and "
    "$\\phi(Q) = \\tfrac12\\|Q - R\\|_F^2$ either endpoint condition gives $P_1 = 0$, so the "
    "equation for $U_0$ would need $J_D(R) = 0$, while the only admissible control is $U_0 = R$ "
    "($\\|J_D(R)\\|_F^2 = 311052/75625$). "
    "With the sum starting at $k = 1$ the first control $U_0$ carries no running cost and the "
    "equation for $U_k$ fails at $k = 0$. The endpoint sign of the second proposition of Section "
    "2 is wrong for the Hamiltonian's sign (the maximum principle gives $p_N = "
    "-\\partial\\phi/\\partial x_N$ there), but the theorem applies the flip $P \\mapsto -P$, so "
    "its final $P_N = +\\partial\\phi/\\partial Q_N$ is right: two sign slips cancel. The "
    "evidence compares the derivative of the cost along $U_k e^{\\epsilon\\xi}$ (central "
    "differences of an independently written cost, $n = 3$, $N = 4$, two samples, $\\phi(Q) = "
    "\\tfrac12\\|Q - T\\|_F^2$) with $\\tfrac12 \\operatorname{tr}(U_k^T (J_D(U_k) - R_k) U_k "
    "\\xi)$, $R_k$ the right side of the variant of the equation for $U_k$, so it vanishes for "
    "every $\\xi$ exactly when that variant holds. Normality (the hypothesis of D1's multiplier "
    "rule): with $Q^a_N$ free the Jacobian of the dynamics in the states and the control "
    "directions $U_k(I + \\xi_k)$ has full row rank, computed as 54 of 54 on a rational network "
    "($n = 3$, $N = 3$, $M = 2$), so no abnormal multiplier occurs.",
    expected="holds after correction",
    headline="[[cost]], with $Q^a_N$ free",
    section="2.1",
    where="Section 2.1, the second definition (several samples $Q^a$ and a terminal cost $\\phi$) "
    "and the second theorem (with $P^a_N = \\partial\\phi/\\partial Q^a_N$), with its proof",
)
_a, _Msamples = sp.symbols("a M", integer=True, positive=True)
Qa, Pa, QaN, PaN = matrix("Q^a_k"), matrix("P^a_k"), matrix("Q^a_N"), matrix("P^a_N")
Qa1, Pa1 = matrix("Q^a_{k+1}"), matrix("P^a_{k+1}")
_dphi = matrix(r"\partial\phi/\partial Q^a_N")
_phi = sp.Function(r"\phi")
D9_COST = D9.formula(
    "cost",
    sp.Sum(sp.Trace(Lam * Uk), (_k, 0, _N - 1)) + sp.Sum(_phi(QaN), (_a, 1, _Msamples)),
)
D9_COST_PRINTED = D9.formula(
    "cost_printed",
    sp.Sum(sp.Trace(Lam * Uk), (_k, 1, _N - 1)) + sp.Sum(_phi(QaN), (_a, 1, _Msamples)),
)
D9_DYNAMICS = D9.formula("dynamics", eq(Qa1, Qa * Uk))
D9.formula("costate", eq(Pa1, Pa * Uk))
UKDEF2 = D9.formula("Ukdef2", eq(_JD(Uk), sp.Sum(Qa.T * Pa - Pa.T * Qa, (_a, 1, _Msamples))))
FINAL_UNFLIPPED = D9.formula(
    "final_unflipped", eq(_JD(Uk), sp.Sum(Pa.T * Qa - Qa.T * Pa, (_a, 1, _Msamples)))
)
ENDPOINT = D9.formula("endpoint", eq(PaN, _dphi))
ENDPOINT_M8 = D9.formula("endpoint_m8", eq(PaN, _dphi))
ENDPOINT_UNFLIPPED = D9.formula("endpoint_unflipped", eq(PaN, -_dphi))


# ---------------------------------------------------------------------------------------------
# D9 kernels: the SO(n) network of symrb.learning (forward layer, endpoint, costate, gradient)
#
# symrb.learning minimises L(U) = sum_a phi(Q^a_N) + alpha sum_k tr(Lambda (I - U_k)) with
# phi(Q) = 1/2 ||Q - T||_F^2: the displayed cost with Lambda replaced by -alpha Lambda, plus the
# constant alpha N tr(Lambda).  Its costates carry the sign of the proof before the flip
# (endpoint_unflipped, P^a_N = -dphi/dQ^a_N), so that P^a_k is minus the back-propagated gradient
# as in symrb's ResNet (D5, D6).  Samples are stacked by rows: the (M n) x n matrix [Q^1; ...;
# Q^M] times U is every sample's layer at once, and [P^1; ...; P^M]^T [Q^1; ...; Q^M] is
# sum_a (P^a)^T Q^a, so one matrix product sums over the samples.

_SQ, _SP, _ST, _SU = matrix("Q"), matrix("P_next"), matrix("T"), matrix("U")
_SQ1 = matrix("Q_next")
_ARG_STACK = "(..., n, n)"  # or (..., m n, n): m samples stacked by rows
SO_LAYER = Kernel(
    name="so_network_layer",
    target="discrete_rigid_body",
    args=[
        Arg("Q", _ARG_STACK, "the samples Q^a_k (n x n each), stacked by rows"),
        Arg("U", "(..., n, n)", "the control U_k, in SO(n)"),
    ],
    outputs={"Q_next": _SQ * _SU},
    doc="One layer of the SO(n) network (paper, Section 2.1, learning version): Q^a_{k+1} = "
    "Q^a_k U_k,\nfor every sample at once when the samples are stacked by rows.",
    claims=("D9",),
)
SO_ENDPOINT = Kernel(
    name="so_network_endpoint",
    target="discrete_rigid_body",
    args=[
        Arg("Q", _ARG_STACK, "the final layer Q^a_N, samples stacked by rows"),
        Arg("T", _ARG_STACK, "the targets T^a, stacked the same way"),
    ],
    outputs={"P": -(_SQ - _ST)},
    doc="Endpoint costate of the SO(n) network for phi(Q) = 1/2 ||Q - T||_F^2:\n"
    "P^a_N = -dphi/dQ^a_N = -(Q^a_N - T^a) (claim D9, the sign before the flip).",
    claims=("D9",),
)
SO_COSTATE = Kernel(
    name="so_network_costate",
    target="discrete_rigid_body",
    args=[
        Arg("P_next", _ARG_STACK, "the costates P^a_{k+1}, samples stacked by rows"),
        Arg("U", "(..., n, n)", "the control U_k, in SO(n)"),
    ],
    outputs={"P": _SP * _SU.T},
    doc="Costate step of the SO(n) network: P^a_k = dH/dQ^a_k = P^a_{k+1} U_k^T\n"
    "(the back-propagation of the layer Q U).",
    claims=("D9",),
)
_SO_S = _SP.T * _SQ1  # sum_a (P^a_{k+1})^T Q^a_{k+1} on stacked samples
# S - S^T unevaluated (SymPy would expand S^T to Q^T P): one matrix product for the sum
_SO_G = sp.MatAdd(
    sp.MatMul(
        sp.Rational(1, 2),
        sp.MatAdd(_SO_S, sp.MatMul(-1, sp.Transpose(_SO_S), evaluate=False), evaluate=False),
        evaluate=False,
    ),
    (Lam * _SU - _SU.T * Lam) / 2,
    evaluate=False,
)
SO_GRADIENT = Kernel(
    name="so_network_gradient",
    target="discrete_rigid_body",
    args=[
        Arg("P_next", _ARG_STACK, "the costates P^a_{k+1}, samples stacked by rows"),
        Arg("Q_next", _ARG_STACK, "the layer Q^a_{k+1}, stacked the same way"),
        Arg("U", "(..., n, n)", "the control U_k, in SO(n)"),
        Arg(
            "lam",
            "(..., n)",
            "alpha times the diagonal of Lambda (running cost alpha tr(Lambda (I - U)))",
        ),
    ],
    outputs={"G": _SO_G},
    doc="Skew gradient of the SO(n) network's loss in the control U_k (claim D9).\n\n"
    "With S = sum_a (P^a_{k+1})^T Q^a_{k+1} and lam the diagonal of alpha Lambda:\n"
    "G_k = (S - S^T)/2 + (Lambda U_k - U_k^T Lambda)/2, so that d/dt L(..., U_k exp(t xi), ...) at t = 0 is tr(G_k^T xi) for every "
    "skew xi.\nEqual to U_k^T (J_D(U_k) - sum_a ((Q^a_k)^T P^a_k - (P^a_k)^T Q^a_k)) "
    "U_k / 2: it vanishes\nexactly when Ukdef2 holds (for the inertia alpha Lambda).",
    claims=("D9",),
)


def _d9_setup() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(9)
    controls = np.array([expm(ref.random_skew(3, rng, 0.3)) for _ in range(4)])
    starts = np.stack([ref.random_rotation(3, rng) for _ in range(2)])
    targets = np.stack([ref.random_rotation(3, rng) for _ in range(2)])
    return _LAM3, controls, starts, targets


def _d9_cost(cost: sp.Expr, controls: np.ndarray, starts: np.ndarray, targets: np.ndarray) -> float:
    """The displayed cost (its running sum from the formula's lower limit), phi(Q) = 1/2||Q-T||^2."""
    running = cost.args[0] if cost.args[0].has(Lam) else cost.args[1]
    k_start = int(running.limits[0][1])
    Q = starts.copy()
    for Ux in controls:
        Q = Q @ Ux
    run = sum(_numeric(running.function, {"U_k": controls[k]}, _LAM3) for k in range(k_start, 4))
    return float(run + 0.5 * np.sum((Q - targets) ** 2))


def _d9_mismatch(cost: sp.Expr, endpoint: sp.Eq, relation: sp.Eq) -> float:
    """Largest |central difference of the cost along U_k e^(e xi) - 1/2 tr(U_k^T (J_D(U_k) - R_k)
    U_k xi)| over k and a basis of so(3), with costates from P_N = the endpoint formula and
    P_k = P_{k+1} U_k^T, and R_k the right side of ``relation`` summed over the samples."""
    lam, controls, starts, targets = _d9_setup()
    Qs = [starts]
    for Ux in controls:
        Qs.append(Qs[-1] @ Ux)
    P = [np.empty(0)] * 5
    P[4] = np.stack(
        [
            _numeric(endpoint.rhs, {r"\partial\phi/\partial Q^a_N": Qs[4][a] - targets[a]})
            for a in range(2)
        ]
    )
    for k in range(3, -1, -1):
        P[k] = P[k + 1] @ controls[k].T
    L = np.diag(lam)
    worst, h = [], 1e-5
    for k in range(4):
        R = sum(
            _numeric(relation.rhs.function, {"Q^a_k": Qs[k][a], "P^a_k": P[k][a]}) for a in range(2)
        )
        G = 0.5 * controls[k].T @ (controls[k] @ L - L @ controls[k].T - R) @ controls[k]
        for i, j in itertools.combinations(range(3), 2):
            xi = np.zeros((3, 3))
            xi[i, j], xi[j, i] = 1.0, -1.0
            up, um = controls.copy(), controls.copy()
            up[k] = controls[k] @ expm(h * xi)
            um[k] = controls[k] @ expm(-h * xi)
            fd = _d9_cost(cost, up, starts, targets) - _d9_cost(cost, um, starts, targets)
            fd /= 2 * h
            worst.append(abs(fd - np.trace(G @ xi)))
    return float(np.max(worst))


@D9.check(Level.FLOAT64, tol=1e-8, form="corrected")
def d9_theorem() -> float:
    r"""The displayed cost (sum from $k = 0$), $P_N = +\partial\phi/\partial Q_N$ and Ukdef2: the
    cost's derivative in every $U_k$ matches the gradient that vanishes exactly when Ukdef2 holds
    (absolute)."""
    return _d9_mismatch(D9_COST, ENDPOINT, UKDEF2)


@D9.check(Level.FLOAT64, tol=1e-8, form="printed")
def d9_printed_index() -> float:
    """The same mismatch with the printed running cost (sum from $k = 1$): wrong at $k = 0$."""
    return _d9_mismatch(D9_COST_PRINTED, ENDPOINT, UKDEF2)


@D9.check(Level.FLOAT64, tol=1e-8, form="corrected")
def d9_unflipped_endpoint() -> float:
    r"""Before the sign change: $P_N = -\partial\phi/\partial Q_N$ with equ_final_th_2.7's sign
    (displayed) matches the derivative of the cost."""
    return _d9_mismatch(D9_COST, ENDPOINT_UNFLIPPED, FINAL_UNFLIPPED)


@D9.check(Level.FLOAT64, tol=1e-8, form="printed")
def d9_unflipped_endpoint_printed() -> float:
    r"""Before the sign change with m8's $P_N = +\partial\phi/\partial Q_N$ (displayed): it does not
    match."""
    return _d9_mismatch(D9_COST, ENDPOINT_M8, FINAL_UNFLIPPED)


def _so_exact_network() -> tuple[Any, ...]:
    """A rational SO(3) network: N = 3 controls, M = 2 samples, rational targets and lam."""
    controls = [_cayley_rational(e, 7) for e in ([1, 2, -1], [-3, 1, 2], [2, -2, 1])]
    starts = [_cayley_rational(e, 5) for e in ([1, -1, 3], [2, 0, -1])]
    targets = [_cayley_rational(e, 4) for e in ([0, 1, 1], [-1, 2, 0])]
    lam = [sp.Rational(7, 10), sp.Rational(11, 10), sp.Rational(8, 5)]
    return controls, starts, targets, lam, sp.Rational(3, 7)


def _so_loss_direct(
    controls: list[Any], starts: list[Any], targets: list[Any], lam: Any, alpha: Any
) -> Any:
    """The loss sum_a 1/2 ||Q^a_N - T^a||_F^2 + alpha sum_k tr(Lambda (I - U_k)), written out
    with explicit matrices (not through any kernel)."""
    L = sp.diag(*lam)
    total = sp.Integer(0)
    for Q, T in zip(starts, targets, strict=True):
        for Ux in controls:
            Q = Q * Ux
        total += sum((e**2 for e in (Q - T)), sp.Integer(0)) / 2
    for Ux in controls:
        total += alpha * (L * (sp.eye(L.rows) - Ux)).trace()
    return total


def _so_emitted_gradients(
    controls: list[Any], starts: list[Any], targets: list[Any], lam: Any, alpha: Any
) -> list[Any]:
    """G_k from the emitted kernels: forward layer, endpoint, costate sweep and gradient, on the
    samples stacked by rows (explicit rational matrices)."""
    Qs = [sp.Matrix.vstack(*starts)]
    for Ux in controls:
        Qs.append(explicit(SO_LAYER["Q_next"], {"Q": Qs[-1], "U": Ux}))
    P = explicit(SO_ENDPOINT["P"], {"Q": Qs[-1], "T": sp.Matrix.vstack(*targets)})
    grads: list[Any] = [None] * len(controls)
    for k in range(len(controls) - 1, -1, -1):
        env = {"P_next": P, "Q_next": Qs[k + 1], "U": controls[k]}
        grads[k] = explicit(SO_GRADIENT["G"], env, [alpha * x for x in lam])
        P = explicit(SO_COSTATE["P"], {"P_next": P, "U": controls[k]})
    return grads


@D9.check(Level.EXACT_RATIONAL, form="corrected")
def d9_so_network_gradient_exact() -> sp.Expr:
    r"""The emitted $\mathrm{SO}(n)$ network kernels (layer, endpoint $P_N = -\partial\phi/\partial
    Q_N$, costate $P_k = P_{k+1} U_k^T$ and skew gradient) against the directional derivative of an
    independently written loss $L$, the sum over samples of $\frac12\|Q^a_N - T^a\|^2$ plus $\alpha
    \sum_k \operatorname{tr}(\Lambda(I - U_k))$, along $U_k \exp(t\xi)$ (which has the tangent $U_k
    \xi$ of $U_k (I + t\xi)$ at $t = 0$): sum over $k$ and a basis $\xi$ of $\mathfrak{so}(3)$ of
    $|\frac{d}{dt} L - \operatorname{tr}(G_k^T \xi)|$, exact rationals ($n = 3$, $N = 3$, $M = 2$
    samples)."""
    controls, starts, targets, lam, alpha = _so_exact_network()
    grads = _so_emitted_gradients(controls, starts, targets, lam, alpha)
    t = sp.Symbol("t")
    total = sp.Integer(0)
    for k in range(len(controls)):
        for i, j in itertools.combinations(range(3), 2):
            xi = sp.zeros(3, 3)
            xi[i, j], xi[j, i] = 1, -1
            moved = list(controls)
            moved[k] = controls[k] * (sp.eye(3) + t * xi)
            d = sp.diff(_so_loss_direct(moved, starts, targets, lam, alpha), t).subs(t, 0)
            total += sp.Abs(sp.nsimplify(d - (grads[k].T * xi).trace()))
    skew_defect = sum((sp.Abs(e) for G in grads for e in G + G.T), sp.Integer(0))
    return total + skew_defect


@D9.check(Level.SYMBOLIC_GENERAL_N)
def d9_so_network_gradient_is_ukdef2() -> sp.Expr:
    r"""The emitted costate step is the displayed costate equation solved for $P_k$ ($P_{k+1} = P_k
    U_k$ with $U_k$ orthogonal), and with it the emitted gradient equals $\frac12 U_k^T (\alpha
    J_D(U_k) - M_k) U_k$, $M_k = Q_k^T P_k - P_k^T Q_k$ (the emitted $J_D$; both with the inertia
    $\alpha\Lambda$), so it vanishes exactly when Ukdef2 holds (one sample; the sum over samples is
    linear; noncommutative symbols, every $n$)."""
    w = Words(symmetric=["Lambda"], orthogonal=["U"])
    q, p, u = w("Q"), w("P"), w("U")
    # costate: the displayed P^a_{k+1} = P^a_k U_k, then the emitted step must give back P_k
    back = w.of(SO_COSTATE["P"]).xreplace({w("P_next"): p * u, w.T(w("P_next")): w.T(u) * w.T(p)})
    r = w.is_zero(back - p)
    step = {
        w("P_next"): p * u,
        w.T(w("P_next")): w.T(u) * w.T(p),
        w("Q_next"): q * u,
        w.T(w("Q_next")): w.T(u) * w.T(q),
    }
    grad = w.of(SO_GRADIENT["G"]).xreplace(step)
    momentum = w.T(q) * p - w.T(p) * q
    target = w.T(u) * (w.of(JD["JD"]) - momentum) * u / 2
    return r + w.is_zero(grad - sp.expand(target))


@D9.check(Level.FLOAT64, tol=1e-7, form="corrected")
def d9_symrb_so_network_gradients() -> float:
    r"""symrb.learning.so_network_gradients against central differences (step 1e-5) of an
    independently written NumPy loss along $U_k \operatorname{expm}(t\xi)$, $n = 4$, $N = 3$, $M =
    5$, $\alpha = 0.3$, for every $k$ and a basis of $\mathfrak{so}(4)$: largest absolute difference
    over the largest $|G|$."""
    from symrb.learning import so_network_gradients

    rng = np.random.default_rng(12)
    n_, N_, M_ = 4, 3, 5
    lam = np.array([0.6, 0.9, 1.3, 1.7])
    controls = np.array([expm(ref.random_skew(n_, rng, 0.4)) for _ in range(N_)])
    starts = np.array([ref.random_rotation(n_, rng) for _ in range(M_)])
    targets = np.array([ref.random_rotation(n_, rng) for _ in range(M_)])

    def loss(Us: np.ndarray) -> float:
        Q = starts.copy()
        for Ux in Us:
            Q = np.einsum("aij,jk->aik", Q, Ux)
        run = sum(float(np.trace(np.diag(lam) @ (np.eye(n_) - Ux))) for Ux in Us)
        return 0.5 * float(np.sum((Q - targets) ** 2)) + 0.3 * run

    _loss, G = so_network_gradients(starts, controls, lam, targets, alpha=0.3)
    worst, h = 0.0, 1e-5
    for k in range(N_):
        for i, j in itertools.combinations(range(n_), 2):
            xi = np.zeros((n_, n_))
            xi[i, j], xi[j, i] = 1.0, -1.0
            up, um = controls.copy(), controls.copy()
            up[k] = controls[k] @ expm(h * xi)
            um[k] = controls[k] @ expm(-h * xi)
            fd = (loss(up) - loss(um)) / (2 * h)
            worst = max(worst, abs(fd - float(np.sum(G[k] * xi))))
    return worst / float(np.max(np.abs(G)))


@D9.check(Level.EXACT_RATIONAL, form="corrected")
def d9_free_endpoint_is_normal() -> int:
    r"""Normality on $\mathrm{SO}(n)$ with a free endpoint: on the rational network ($n = 3$, $N =
    3$, $M = 2$) the Jacobian of the displayed dynamics, $Q^a_{k+1} - Q^a_k U_k$ in
    $\mathfrak{gl}(3)$, in the free variables (the entries of $Q^a_1, \dots, Q^a_N$ and $\xi_k$, the
    control moved to $U_k (I + \xi_k)$ with $\xi_k$ in $\mathfrak{so}(3)$) at the network has full
    row rank: rows minus rank (54 rows)."""
    controls, starts, _targets, _lam, _alpha = _so_exact_network()
    N, M = len(controls), len(starts)
    states = {(a, k): general_matrix(f"q{a}{k}_", 3) for a in range(M) for k in range(1, N + 1)}
    xis = [skew_matrix(f"xi{k}_", 3) for k in range(N)]
    rows, point = [], {}
    for a in range(M):
        Q = starts[a]
        for k in range(N):
            prev = starts[a] if k == 0 else states[(a, k)]
            env = {"Q^a_{k+1}": states[(a, k + 1)], "Q^a_k": prev,
                   "U_k": controls[k] * (sp.eye(3) + xis[k])}  # fmt: skip
            rows += list(explicit(D9_DYNAMICS.lhs, env) - explicit(D9_DYNAMICS.rhs, env))
            Q = Q * controls[k]
            point.update(zip(states[(a, k + 1)], Q, strict=True))
    skew = [xi[i, j] for xi in xis for i, j in itertools.combinations(range(3), 2)]
    free = [s for m in states.values() for s in m] + skew
    point.update(dict.fromkeys(skew, 0))
    jac = sp.Matrix(rows).jacobian(free).xreplace(point)
    return jac.rows - jac.rank()


def _d9_fixed_endpoint_gap(endpoint: sp.Eq) -> sp.Expr:
    """One sample, N = 1, Q_0 = I, Q_1 fixed to a rational rotation R (Cayley, entries 1, 2, -1
    over 7), phi(Q) = 1/2 ||Q - R||_F^2, Lambda = diag(7/10, 11/10, 8/5).  The only admissible
    control is U_0 = R.  P_1 from the given endpoint formula (the entrywise derivative of phi by
    SymPy, at Q_1 = R), P_0 from the displayed costate equation, then ||J_D(U_0) - (Q_0^T P_0 -
    P_0^T Q_0)||_F^2, the defect of the displayed equation for U_k at the admissible control."""
    R = _cayley_rational([1, 2, -1], 7)
    lam = [sp.Rational(7, 10), sp.Rational(11, 10), sp.Rational(8, 5)]
    Qs = general_matrix("q", 3)
    phi = sum(((e - r) ** 2 for e, r in zip(Qs, R, strict=True)), sp.Integer(0)) / 2
    G = Qs.applyfunc(lambda e: sp.diff(phi, e)).xreplace(dict(zip(Qs, R, strict=True)))
    P1 = explicit(endpoint.rhs, {r"\partial\phi/\partial Q^a_N": G})
    P0 = general_matrix("p", 3)
    costate = D9.formulas["costate"]
    env = {"P^a_{k+1}": P1, "P^a_k": P0, "U_k": R}
    eqs = list(explicit(costate.lhs, env) - explicit(costate.rhs, env))
    P0 = P0.xreplace(sp.solve(eqs, list(P0), dict=True)[0])
    lhs = explicit(JD["JD"], {"U": R}, lam)
    rhs = explicit(UKDEF2.rhs.function, {"Q^a_k": sp.eye(3), "P^a_k": P0})
    return sp.nsimplify(sum(e**2 for e in lhs - rhs))


@D9.check(Level.EXACT_RATIONAL, form="printed")
def d9_printed_fixed_endpoint() -> sp.Expr:
    r"""The definition keeps $Q^a_N$ given and fixed beside the terminal cost $\phi(Q^a_N)$: with $N
    = 1$, $Q_0 = I$, the fixed $Q_1 = R$ (a rational rotation) and $\phi(Q) = \frac12\|Q - R\|^2$,
    the admissible control $U_0 = R$ violates the equation for $U_k$ with the costate of either
    displayed endpoint condition (both give $P_1 = 0$): the smaller $\|J_D(U_0) - M_0\|_F^2$, $M_0 =
    Q_0^T P_0 - P_0^T Q_0$."""
    return sp.Min(*(_d9_fixed_endpoint_gap(e) for e in (ENDPOINT, ENDPOINT_UNFLIPPED)))


# the paper's sentences (the definition, the theorem and its proof)

D9.sentence(
    r"We can now obtain the machine learning generalization of the discrete rigid body equations.",
    kind="prose",
    reason="announces the definition and theorem",
)
D9.sentence(r"Let $\Lambda$ be a positive definite diagonal matrix.", d9_theorem)
D9.sentence(
    r"Let $\overline{Q}_0, \overline{Q}_N^a\in \operatorname{SO}(n)$, $a=1, \ldots, M$, be given "
    r"and fixed.",
    d9_printed_fixed_endpoint,
    d9_theorem,
)
D9.sentence(
    r"Let $\hat{V}(U_0, \ldots, U_{N-1}) :=\sum_{k=1}^{N-1}\operatorname{trace}(\Lambda U_{k}) "
    r"+\sum_{a=1}^M\phi(\overline{Q}^a_N)$ and let "
    r"$\phi:\mathbb{R}^n\times\mathbb{R}^n\rightarrow\mathbb{R}^+$ be a given smooth function.",
    d9_theorem,
    d9_printed_index,
)
D9.sentence(
    r"Define the optimal control problem $\mathop{\rm min}_{U_k\in \operatorname{SO}(n)}"
    r"\hat{V}(U_0, \ldots, U_{N-1})= \mathop{\rm min}_{U_k\in \operatorname{SO}(n)} "
    r"\sum_{k=1}^{N-1}\operatorname{trace}(\Lambda U_{k}) +\sum_{a=1}^M\phi(\overline{Q}^a_N)$ "
    r"subject to dynamics and initial data $Q^a_{r+1}=Q^a_rU_{r}, \qquad "
    r"Q^a_0=\overline{Q}^a_0, \qquad r=0, \ldots, N-1,$ for $Q_k, U_k\in \operatorname{SO}(n)$.",
    d9_theorem,
    d9_printed_index,
    d9_so_network_gradient_exact,
)
D9.sentence(
    r"Theorem. A solution of the optimal control problem in Defintion (mvoptprobm1) satisfies the "
    r"optimal evolution equations for each $a=1, \ldots, M$, $Q^a_{k+1} = Q^a_kU_{k} \qquad "
    r"P^a_{k+1} = P^a_kU_{k}\,, \qquad k=0, \ldots, N-1, \qquad Q^a_0 = \overline{Q}^a_0,$ where "
    r"$P^a_k$ is the discrete covector in the discrete maximum principle and $U_{k}$ is defined "
    r"by $U_{k}\Lambda-\Lambda U^T_{k}=\sum_{^Ma=1}((Q^a_k)^TP^a_k-(P^a_k)^TQ^a_k)\,.$ with "
    r"$P^a_N=\frac{\partial\phi(Q^a_N)}{\partial Q^a_N}\,.$",
    d9_theorem,
    d9_printed_index,
    d9_so_network_gradient_is_ukdef2,
    d9_so_network_gradient_exact,
    d9_symrb_so_network_gradients,
)
D9.sentence(
    r"Proof. We apply Proposition (gendiscpropm) with "
    r"$H(P_{k+1},Q_k,U_{k})= \sum_{a=1}^M\operatorname{trace}((P^a_{k+1})^TQ^a_kU_{k})"
    r"+\sum_{a=1}^M\phi(Q^a_N) -\operatorname{trace}(\Lambda U_{k})$",
    d9_unflipped_endpoint,
    d9_unflipped_endpoint_printed,
)
D9.sentence(
    r"Then the computation is as above for the optimal control setting.",
    d9_so_network_gradient_is_ukdef2,
    d9_unflipped_endpoint,
)
