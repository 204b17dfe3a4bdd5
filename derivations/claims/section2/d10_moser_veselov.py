r"""D10: the Moser-Veselov equations and the two MV algorithms (paper, Section 2.2).

Where: Section 2.2 (Classical Moser-Veselov equations): mv1, mv2, mv3 for :math:`\Omega_k`,
:math:`M_k`, :math:`M_{k+1}`, and the paragraphs 'MV-Algorithm 1' and 'MV-Algorithm 2'.

Recorded outcome: holds.  The third equation with the second transports the momentum by a
conjugation; the second can be solved for :math:`\Omega_k` up to a fold (for :math:`n = 2`
exactly when :math:`|M_{21}| \le \lambda_1 + \lambda_2`); the algorithms define the same dynamics.

Emitted (``symrb/_generated/discrete_rigid_body.py``): ``mv_momentum`` (mv2) and ``mv_transport``
(mv3).  Evidence: noncommutative symbols (every :math:`n`), :math:`n = 2` in closed form, the fold
for :math:`n = 3` against the enumeration of :mod:`._jd_solutions`, symrb's algorithms against
the 50-digit run of :mod:`._reference_run`.  symrb's own engine (Cayley-Newton, preprocessed,
compositions) is checked apart, in :mod:`derivations.methods` (M1-M4).
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from derivations import reference as ref
from derivations.claims.section2._jd_solutions import _all_jd_solutions, _on_branch
from derivations.claims.section2._matrix_formulas import (
    _JD,
    _LAM3,
    ARG_LAM,
    M,
    Mk,
    Mk1,
    Om,
    Omk,
    Qk,
    Qkm1,
    U,
)
from derivations.claims.section2._reference_run import (
    _H,
    _MP_STEPS,
    _STEPS,
    _mp_gap,
    _mp_mv_runs,
    _mp_run,
)
from derivations.claims.section2.d07_optimal_control_on_so_n import JD
from derivations.registry import Level, claim
from derivations.symbolic import Words, eq, explicit, residual
from derivations.vocabulary import Arg, Kernel, Lam, matrix

D10 = claim(
    "D10",
    label="mv1, mv2, mv3",
    title="Moser-Veselov equations and the two MV algorithms",
    statement="The Moser-Veselov equations [[mv1]], [[mv2]], [[mv3]].  MV-Algorithm 1 maps "
    "$(Q_k, Q_{k+1})$ to $(Q_{k+1}, Q_{k+2})$ and MV-Algorithm 2 maps $(Q_k, M_k)$ to "
    "$(Q_{k+1}, M_{k+1})$; they define the same dynamics.  The second Moser-Veselov equation can be solved for $\\Omega_k$ "
    "for small $M_k$, up to a fold; for $n=2$, [[n2]].",
    expected="holds",
    section="2.2",
    where="Section 2.2 (Classical Moser-Veselov equations), the three Moser-Veselov equations for "
    "$\\Omega_k$, $M_k$ and $M_{k+1}$, and the paragraphs 'MV-Algorithm 1' and 'MV-Algorithm 2'",
    note="The third Moser-Veselov equation with the second gives $M_{k+1} = \\Lambda\\Omega_k^T - "
    "\\Omega_k\\Lambda = -J_D(\\Omega_k)$: the momentum is transported by a conjugation. symrb's "
    "`mv_algorithm1`, `mv_algorithm2` and `symmetric_flow` have step-by-step loops written from "
    "their own equations (run with `diagnostics=True`), sharing only the solver of the second "
    "equation; by default each is one run of the engine `mv_flow`, whose state is theirs with "
    "the momentum index shifted by one for the two MV-Algorithms.",
)


# the kernels: the second and third Moser-Veselov equations

ARG_OMEGA = Arg("Omega", "(..., n, n)", "discrete body angular velocity, in SO(n)")
MV_MOMENTUM = Kernel(
    name="mv_momentum",
    target="discrete_rigid_body",
    args=[ARG_OMEGA, ARG_LAM],
    outputs={"M": Om.T * Lam - Lam * Om},
    doc="Second Moser-Veselov equation (paper, Section 2.2): M_k = Omega_k^T Lambda - Lambda Omega_k.",
    claims=("D10", "D11", "D12"),
)
MV_TRANSPORT = Kernel(
    name="mv_transport",
    target="discrete_rigid_body",
    args=[ARG_OMEGA, Arg("M", "(..., n, n)", "discrete body angular momentum, skew")],
    outputs={"M_next": Om * M * Om.T},
    doc="Third Moser-Veselov equation (paper, Section 2.2): M_{k+1} = Omega_k M_k Omega_k^T.",
    claims=("D10", "D11", "D12"),
)


MV1 = D10.formula("mv1", eq(Omk, Qk.T * Qkm1))
MV2 = D10.formula("mv2", eq(Mk, MV_MOMENTUM.outputs["M"].xreplace({Om: Omk})))
MV3 = D10.formula("mv3", eq(Mk1, MV_TRANSPORT.outputs["M_next"].xreplace({Om: Omk, M: Mk})))
_theta = sp.Symbol("theta", real=True)
_l1, _l2 = sp.symbols("lambda_1 lambda_2", positive=True)
N2 = D10.formula(
    "n2", eq(_JD(sp.Function("R")(_theta)), (_l1 + _l2) * sp.sin(_theta) * matrix("E"))
)


@D10.check(Level.SYMBOLIC_GENERAL_N)
def d10_mv3_conjugation() -> sp.Expr:
    r"""The emitted mv3 applied to the emitted mv2 momentum, for orthogonal $\Omega$, equals
    $\Lambda\Omega^T - \Omega\Lambda = -J_D(\Omega)$ (the emitted $J_D$); and the emitted kernels
    are the displayed mv2, mv3 (noncommutative, every $n$)."""
    w = Words(symmetric=["Lambda"], orthogonal=["Omega"])
    nxt = MV_TRANSPORT["M_next"].xreplace({M: MV_MOMENTUM["M"]})
    r = w.is_zero(w.of(nxt) + w.of(JD["JD"].xreplace({U: Om})))
    r += w.is_zero(w.of(MV2.rhs.xreplace({Omk: Om})) - w.of(MV_MOMENTUM["M"]))
    return r + w.is_zero(w.of(MV3.rhs.xreplace({Omk: Om, Mk: M})) - w.of(MV_TRANSPORT["M_next"]))


@D10.check(Level.SYMBOLIC_FIXED_N)
def d10_solvability_n2() -> sp.Expr:
    r"""$n = 2$: the emitted mv2 at $\Omega = R(\theta)^T$, i.e. $J_D(R(\theta))$, equals the
    displayed $(\lambda_1 + \lambda_2) \sin \theta\, E$ with $E = \begin{pmatrix} 0 & -1 \\ 1 & 0
    \end{pmatrix}$ (symbolic): mv2 is solvable exactly when $|M_{21}| \le \lambda_1 + \lambda_2$."""
    R = sp.Matrix([[sp.cos(_theta), -sp.sin(_theta)], [sp.sin(_theta), sp.cos(_theta)]])
    got = explicit(MV_MOMENTUM["M"], {"Omega": R.T}, [_l1, _l2])
    want = explicit(N2.rhs, {"E": sp.Matrix([[0, -1], [1, 0]])})
    return residual(sp.simplify(got - want))


@D10.check(Level.FLOAT64, tol=1e-12)
def d10_fold_n2() -> float:
    r"""symrb.fold_scale for $n = 2$ against the closed form $(\lambda_1 + \lambda_2)/|M_{21}|$ from
    the displayed formula, three momenta: max relative error."""
    import symrb

    lam = np.array([0.7, 1.9])
    errs = []
    for m in (0.05, 0.37, 4.0):
        Mx = np.array([[0.0, -m], [m, 0.0]])
        want = lam.sum() / m
        errs.append(abs(float(symrb.fold_scale(Mx, lam)) - want) / want)
    return float(np.max(errs))


@D10.check(Level.FLOAT64, tol=1e-13)
def d10_fold_n3() -> float:
    r"""$n = 3$, $M = t M_1$ with $t^*$ from symrb.fold_scale at $M_1$: at $0.999\, t^*$
    symrb.solve_moser_veselov's $U$ solves $J_D(U) = M$ (reference $J_D$) and is the only solution
    on the branch among all solutions in $\mathrm{O}(3)$ (invariant-subspace enumeration); at
    $1.001\, t^*$ the enumeration finds no solution on the branch and symrb raises OutOfDomainError.
    Residual: the $J_D$ error plus the miscounts."""
    import symrb

    M1 = ref.hat(np.array([0.3, -0.2, 0.4]))
    t = float(symrb.fold_scale(M1, _LAM3))
    inside, past = 0.999 * t * M1, 1.001 * t * M1
    Uin = symrb.solve_moser_veselov(inside, _LAM3)
    branch_in = [x for x in _all_jd_solutions(inside, _LAM3) if _on_branch(x, _LAM3)]
    branch_past = [x for x in _all_jd_solutions(past, _LAM3) if _on_branch(x, _LAM3)]
    miss = abs(len(branch_in) - 1) + len(branch_past)
    miss += 0 if len(branch_in) == 1 and np.abs(branch_in[0] - Uin).max() < 1e-8 else 1
    try:
        symrb.solve_moser_veselov(past, _LAM3)
        miss += 1  # a solution was returned past the fold
    except symrb.OutOfDomainError:
        pass
    return float(np.abs(ref.J_D(Uin, _LAM3) - inside).max() + miss)


@D10.check(Level.FLOAT64, tol=1e-13)
def d10_symrb_algorithms_against_50_digits() -> float:
    """symrb.mv_algorithm1 from $(Q_0, Q_1)$, symrb.mv_algorithm2 from $(Q_1, M_1)$ and
    symrb.symmetric_flow from $(Q_0, P_0)$ (float64, $n = 3$, 12 steps), each by the engine (the
    default) and by its step-by-step loop (diagnostics=True), against the $Q_k$ of the 50-digit
    reference run of the symmetric representation ($h = 0.1$; $M_1 = h(Q_0^T P_0 - P_0^T Q_0)$):
    max absolute error."""
    import symrb

    run = _mp_run()
    Qf = run["Qf"]
    errs = []
    for diagnostics in (False, True):
        QA = symrb.mv_algorithm1(run["Q0"], Qf[1], _LAM3, _STEPS - 1, diagnostics=diagnostics)
        QB = symrb.mv_algorithm2(Qf[1], run["Msf"][0], _LAM3, _STEPS - 1, diagnostics=diagnostics)
        QS = symrb.symmetric_flow(run["Q0"], run["P0"], _LAM3, _H, _STEPS, diagnostics=diagnostics)
        errs += [np.abs(QA.y.Q - Qf).max(), np.abs(QB.y.Q - Qf[1:]).max()]
        errs.append(np.abs(QS.y.Q - Qf).max())
    return float(np.max(errs))


@D10.check(Level.MPMATH, tol=1e-40)
def d10_mv1_equals_symmetric_50_digits() -> float:
    """50 digits: MV-Algorithm 1 (MPDiscrete.mv1) from $(Q_0, Q_1)$ of the reference run reproduces
    the symmetric representation's $Q_k$ ($n = 3$, 6 steps)."""
    run, mv = _mp_run(), _mp_mv_runs()
    return float(_mp_gap(mv["mv1_Q"], run["Qs"][: _MP_STEPS + 2]))


@D10.check(Level.SYMBOLIC_GENERAL_N)
def d10_quantities_in_their_spaces() -> sp.Expr:
    r"""The displayed mv1 gives an orthogonal $\Omega_k$ when $Q_k$ and $Q_{k-1}$ are ($\Omega_k^T
    \Omega_k$ and $\Omega_k \Omega_k^T$ reduce to 1), the emitted mv2 momentum is skew for every
    $\Omega$ ($M + M^T$ expands to 0, $\Omega$ not even orthogonal), and the emitted mv3 keeps a
    skew $M$ skew (noncommutative, every $n$)."""
    w = Words(symmetric=["Lambda"], skew=["M"], orthogonal=["Q_k", "Q_{k-1}"])
    om = w.of(MV1.rhs)
    r = w.is_zero(w.T(om) * om - 1) + w.is_zero(om * w.T(om) - 1)
    momentum = w.of(MV_MOMENTUM["M"])
    r += w.is_zero(momentum + w.T(momentum))
    nxt = w.of(MV_TRANSPORT["M_next"])
    return r + w.is_zero(nxt + w.T(nxt))


# the paper's sentences

D10.sentence(
    r"We briefly review the [MoVe1991] discrete rigid body equations.",
    kind="prose",
    reason="announces the review that follows",
)
D10.sentence(
    r"Let $Q_k \in\operatorname{SO}(n)$ denote the rigid body configuration at time $k$, let "
    r"$\Omega_k\in\operatorname{SO}(n)$ denote the body angular velocity at time $k$, and let "
    r"$M_k$ denote the body angular momentum at time $k$.",
    d10_quantities_in_their_spaces,
)
D10.sentence(
    r"These quantities are related by the Moser-Veselov equations "
    r"$\Omega_k= Q_k^TQ_{k-1}, \quad M_k= \Omega_k^T\Lambda-\Lambda\Omega_k, \quad "
    r"M_{k+1}=\Omega_kM_k\Omega_k^T.$",
    d10_mv3_conjugation,
    d10_symrb_algorithms_against_50_digits,
    d10_mv1_equals_symmetric_50_digits,
)
D10.sentence(
    r"These equations may be viewed as defining two different algorithms.",
    d10_symrb_algorithms_against_50_digits,
)
D10.sentence(
    r"MV-Algorithm 1. Define the step ahead map "
    r"$\left(Q_k, Q_{k+1}\right)\mapsto \left(Q_{k+1}, Q_{k+2}\right)$ as follows: compute "
    r"$\Omega_{k+1}$ from (mv1), compute $M_{k+1}$ from (mv2), compute $M_{k+2}$ from (mv3), "
    r"compute $\Omega_{k+2}$ from (mv2) and then compute $Q_{k+2}$ from (mv1).",
    d10_symrb_algorithms_against_50_digits,
    d10_mv1_equals_symmetric_50_digits,
)
D10.sentence(
    r"Remark. Given $M_k$, conditions under which equation (mv2) is solvable for $\Omega_k$ are "
    r"discussed in [MoVe1991] and [CaLe2001].",
    d10_solvability_n2,
    d10_fold_n2,
    d10_fold_n3,
)
D10.sentence(
    r"MV-Algorithm 2. Define the map: $\left(Q_k, M_{k}\right)\mapsto \left(Q_{k+1}, "
    r"M_{k+1}\right)$ as follows: compute $\Omega_k$ from (mv2), compute $M_{k+1}$ from (mv3), "
    r"compute $\Omega_{k+1}$ from (mv2) and compute $Q_{k+1}$ from (mv1).",
    d10_symrb_algorithms_against_50_digits,
)
