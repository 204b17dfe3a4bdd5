"""M9: the options of the paper's algorithms in ``symrb.paper`` (``halve``, ``diagnostics``).

Not a statement of the paper.  The coverage report found that no evidence ran the paper's
algorithms with ``halve=True`` (a step past the fold of :math:`J_D` taken as :math:`2^j` steps of
:math:`h/2^j`) or ``diagnostics=True`` (the solver's condition number at every solve).  Here the
halved runs are held against the 30-digit runs of the symmetric representation
(:class:`derivations.reference.MPDiscrete`) with the same substeps, and the reported condition
numbers against the condition number of each step's :math:`U` recomputed in NumPy (a singular
value decomposition of the derivative of :math:`J_D` on so(n)).
"""

from __future__ import annotations

import math

import numpy as np

from derivations import reference as ref
from derivations.methods.rigid_body_options import _kappa, _max
from derivations.registry import Level, claim

M9 = claim(
    "M9",
    label="",
    title="The options of the paper's algorithms",
    statement="With `halve=True` the symmetric algorithm and the discrete rigid body take a step "
    "past the fold of $J_D$ as $2^j$ steps of $h/2^j$ and continue on the branch (without it "
    "the run stops there); with `diagnostics=True` the symmetric algorithm, MV-Algorithm 1 and 2 "
    "and the discrete rigid body report the condition number of every solve.",
    expected="holds",
    section="symrb",
    where="`symrb.paper`: `symmetric_flow`, `discrete_rigid_body_flow`, `mv_algorithm1`, "
    "`mv_algorithm2` (options `halve`, `diagnostics`)",
)

_LAM = np.array([0.7, 1.1, 1.6])
_H = 0.5
_STEPS = 2


def _past_fold(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Q_0 and a skew X with h M = 2 h X 25 % past the fold of J_D (symrb.fold_scale only
    places the input)."""
    import symrb

    Q0 = ref.random_rotation(3, rng)
    X = ref.random_skew(3, rng)
    X *= 1.25 * float(symrb.fold_scale(2 * _H * X, _LAM))
    return Q0, X


@M9.check(Level.MPMATH, tol=1e-12)
def m9_halve_against_30_digits() -> float:
    """symrb.symmetric_flow with $P_0 = Q_0 X$ and symrb.discrete_rigid_body_flow with $M_0 = 2X$
    (from the same $Q_0$), with halve=True, $h = 0.5$ and $hM$ 25 % past the fold of $J_D$ ($n = 3$,
    2 steps): every state against the 30-digit symmetric representation (MPDiscrete) run from the
    previous reference state with $2^j$ substeps of $h/2^j$, $j$ the halvings reported for that
    step: max error; inf when no step was halved or when the run without halve does not stop at the
    first halved step."""
    import symrb

    Q0, X = _past_fold(np.random.default_rng(91))
    mpd = ref.MPDiscrete(_LAM, dps=30)
    worst = 0.0
    sym = symrb.symmetric_flow(Q0, Q0 @ X, _LAM, _H, _STEPS, halve=True)
    rb = symrb.discrete_rigid_body_flow(Q0, 2 * X, _LAM, _H, _STEPS, halve=True)
    plain = symrb.symmetric_flow(Q0, Q0 @ X, _LAM, _H, _STEPS)
    first = int(np.argmax(sym.halvings > 0)) + 1
    if not sym.success or sym.halvings.max() < 1 or plain.success or plain.failed_step != first:
        return math.inf
    Q, P = mpd.matrix(Q0), mpd.matrix(Q0 @ X)
    for k, j in enumerate(sym.halvings, start=1):
        Qs, Ps = mpd.symmetric(Q, P, _H / 2**j, 2 ** int(j))
        Q, P = Qs[-1], Ps[-1]
        worst = _max(worst, mpd.distance(Q, sym.y.Q[k]), mpd.distance(P, sym.y.P[k]))
        worst = _max(worst, mpd.distance(Q, rb.y.Q[k]))
    if not np.array_equal(rb.halvings, sym.halvings):
        return math.inf
    return worst


@M9.check(Level.FLOAT64, tol=1e-9)
def m9_diagnostics_condition() -> float:
    r"""The condition numbers reported with diagnostics=True by symrb.symmetric_flow,
    symrb.discrete_rigid_body_flow ($h = 0.3$, 4 steps), symrb.mv_algorithm1 and symrb.mv_algorithm2
    (4 steps), $n = 3$, $hM$ at 0.8 of the fold of $J_D$ (where the condition number depends on the
    order of $\Lambda$'s diagonal by 6 %), against $\max \lambda / \sigma_{\min}$ of the derivative
    $\xi \mapsto U\xi\Lambda + \Lambda\xi U^T$ of $J_D$ at each step's $U = Q_k^T Q_{k+1}$,
    recomputed in NumPy from the returned states: the report is a lower bound from a power method
    (within 1e-4 here); max over the solves of the amount by which it leaves $[0.98, 1]$ times the
    recomputed value (inf when a report is missing)."""
    import symrb

    rng = np.random.default_rng(92)
    Q0 = ref.random_rotation(3, rng)
    S = ref.random_skew(3, rng)
    X = 0.8 * float(symrb.fold_scale(0.6 * S, _LAM)) * S  # h M = 0.6 X at 0.8 of the fold
    runs = []  # (condition numbers, states, index of the first solve whose U is Q_0^T Q_1)
    for flow, arg in ((symrb.symmetric_flow, Q0 @ X), (symrb.discrete_rigid_body_flow, 2 * X)):
        sol = flow(Q0, arg, _LAM, 0.3, 4, diagnostics=True)
        runs.append((sol.condition, sol.y.Q, 0))
    a2 = symrb.mv_algorithm2(Q0, 0.6 * X, _LAM, 4, diagnostics=True)
    runs.append((a2.condition, a2.y.Q, 1))  # its first solve gives Omega_1 = Q_1^T Q_0
    a1 = symrb.mv_algorithm1(a2.y.Q[0], a2.y.Q[1], _LAM, 4, diagnostics=True)
    runs.append((a1.condition, a1.y.Q[1:], 0))  # Q_0 -> Q_1 is given: no solve
    worst = 0.0
    for condition, Qs, skip in runs:
        Us = [Qs[k].T @ Qs[k + 1] for k in range(len(Qs) - 1)]
        reported = np.asarray(condition)[skip : skip + len(Us)]
        if reported.shape != (len(Us),) or not np.all(np.isfinite(reported)):
            return math.inf
        for got, U in zip(reported, Us, strict=True):
            kappa = _kappa(U, _LAM)
            worst = _max(worst, 0.0, 0.98 - got / kappa, got / kappa - 1 - 1e-9)
    return worst
