r"""D12: the symmetric representation gives a Moser-Veselov solution (Section 2.2, Mdef1).

Where: Section 2.2, the last paragraph (a solution :math:`(Q_k, P_k)` gives
:math:`M_{k+1} = Q_k^TP_k - P_k^TQ_k`) and Section 2.1 ('if we identify :math:`U` with the body
angular momentum').

Recorded outcome: holds after correction: :math:`U_k^T` is the body angular velocity
:math:`\Omega_{k+1}` and the momentum is :math:`J_D(U_k)`.  Evidence: noncommutative symbols
(every :math:`n`), the 50-digit runs of :mod:`._reference_run` (MV-Algorithm 2 against the
symmetric representation), and symrb's ``mv_algorithm2`` and ``symmetric_step`` against them.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import sympy as sp

from derivations import reference as ref
from derivations.claims.section2._matrix_formulas import (
    _JD,
    _LAM3,
    M,
    Mk1,
    Om,
    Omk1,
    Pk,
    Pk1,
    Qk,
    Qk1,
    U,
    Uk,
)
from derivations.claims.section2._reference_run import (
    _H,
    _MP_STEPS,
    _STEPS,
    _mp_gap,
    _mp_mv_runs,
    _mp_run,
)
from derivations.claims.section2.d07_optimal_control_on_so_n import DISCRBOPTEQNS, JD, UKDEF
from derivations.claims.section2.d08_discrete_inertia import _MOMENTUM_K
from derivations.claims.section2.d10_moser_veselov import MV_MOMENTUM, MV_TRANSPORT
from derivations.registry import Level, claim
from derivations.symbolic import Words, eq

D12 = claim(
    "D12",
    label="Mdef1",
    title="Symmetric representation gives a Moser-Veselov solution",
    statement="The symmetric representation [[discrbopteqns1]], [[Ukdef1]] is equivalent on a "
    "certain set to the Moser-Veselov equations: a solution $(Q_k, P_k)$ gives the "
    "Moser-Veselov solution $(Q_{k+1}, M_{k+1})$ with [[Mdef1]].",
    printed="The equivalence holds 'if we identify $U$ with the body angular momentum': "
    "[[ident_printed]].",
    corrected="$U_k$ is orthogonal, not skew: it is the transposed Moser-Veselov body angular "
    "velocity, [[ident_omega]], and the body angular momentum is [[ident_momentum]] "
    "(the momentum formula of Section 2.2, by the equation for $U_k$).  Conversely a Moser-Veselov solution gives "
    "[[converse]], a costate in $\\mathfrak{gl}(n)$; one in $SO(n)$ exists when the momentum's "
    "operator norm is below 2 (S9, S10): that is the 'certain set'.",
    note="The paper identifies $U$ with the body angular momentum, but $U_k$ is orthogonal, not "
    "skew. Corrected: $U_k^T$ is the Moser-Veselov body angular velocity $\\Omega_{k+1}$, and the "
    "momentum is $M_{k+1} = J_D(U_k)$. With $Q_{k+1} = Q_k U_k$, the first Moser-Veselov equation "
    "gives $\\Omega_{k+1} = Q_{k+1}^T Q_k = U_k^T$, the second then gives $M_{k+1} = U_k\\Lambda "
    "- \\Lambda U_k^T = J_D(U_k)$, and the third transports it as the symmetric algorithm does. "
    "With a time step $h$ the momenta are $h$ times the continuous ones (`symrb.paper`).",
    expected="holds after correction",
    headline="[[ident_omega]], [[ident_momentum]]",
    section="2.2",
    where="Section 2.2, the last paragraph: a solution $(Q_k, P_k)$ of the symmetric equations "
    "gives the Moser-Veselov momentum $M_{k+1} = Q_k^T P_k - P_k^T Q_k$ (and Section 2.1, 'if we "
    "identify $U$ with the body angular momentum')",
)
D12.formula("discrbopteqns1", DISCRBOPTEQNS)
D12.formula("Ukdef1", UKDEF)
MDEF1 = D12.formula("Mdef1", eq(Mk1, _MOMENTUM_K))
IDENT_PRINTED = D12.formula("ident_printed", eq(Mk1, Uk))
IDENT_OMEGA = D12.formula("ident_omega", eq(Omk1, Uk.T))
IDENT_MOMENTUM = D12.formula("ident_momentum", eq(Mk1, _JD(Uk)))
CONVERSE = D12.formula("converse", eq(Pk, Qk * Mk1 / 2))


@D12.check(Level.SYMBOLIC_GENERAL_N)
def d12_symmetric_gives_mv() -> sp.Expr:
    r"""With $Q_{k+1} = Q_k U_k$, $P_{k+1} = P_k U_k$ ($Q_k$, $U_k$ orthogonal): mv1 gives
    $\Omega_{k+1} = Q_{k+1}^T Q_k = U_k^T$ (displayed); the emitted mv2 at it is the emitted $J_D$
    at $U_k$; the emitted mv3 transports the displayed Mdef1 momentum at $k$ to the one at $k + 1$;
    and the displayed converse $P_k$ makes Mdef1 hold for skew $M_{k+1}$ (noncommutative, every
    $n$)."""
    w = Words(symmetric=["Lambda"], orthogonal=["Q_k", "U_k"], skew=["M_{k+1}"])
    step = {Qk1: Qk * Uk, Pk1: Pk * Uk}
    om = (Qk1.T * Qk).xreplace(step)
    r = w.is_zero(w.of(om) - w.of(IDENT_OMEGA.rhs))
    r += w.is_zero(
        w.of(MV_MOMENTUM["M"].xreplace({Om: IDENT_OMEGA.rhs})) - w.of(JD["JD"].xreplace({U: Uk}))
    )
    nxt = MV_TRANSPORT["M_next"].xreplace({Om: IDENT_OMEGA.rhs, M: MDEF1.rhs})
    r += w.is_zero(w.of(nxt) - w.of(MDEF1.rhs.xreplace({Qk: Qk1, Pk: Pk1}).xreplace(step)))
    return r + w.is_zero(w.of(MDEF1.rhs.xreplace({Pk: CONVERSE.rhs})) - w("M_{k+1}"))


def _identification_gap(identification: sp.Eq) -> float:
    """max_k |M_{k+1}(MV-Algorithm 2) - identification's right side at U_k| in 50 digits, U_k =
    Q_k^T Q_{k+1} of the symmetric reference run, J_D with the reference's Lambda."""
    run, mv = _mp_run(), _mp_mv_runs()
    mpd = run["mpd"]

    def value(e: sp.Basic, u: Any) -> Any:  # the right side at U_k = u, in 50 digits
        if e == Uk:
            return u
        if isinstance(e, sp.Transpose):
            return value(e.arg, u).T
        if isinstance(e, sp.Function) and e.func == _JD:
            x = value(e.args[0], u)
            return x * mpd.L - mpd.L * x.T
        raise TypeError(f"no 50-digit rule for {e}")

    with mpd.mp.workdps(mpd.dps):
        Us = [run["Qs"][k].T * run["Qs"][k + 1] for k in range(_MP_STEPS + 1)]
        predicted = [value(identification.rhs, u) for u in Us]
    return float(_mp_gap(mv["mv2_M"], predicted))


@D12.check(Level.MPMATH, tol=1e-40, form="corrected")
def d12_identification() -> float:
    """50 digits: $M_{k+1}$ of MV-Algorithm 2 (MPDiscrete.mv2 from $(Q_1, M_1)$) against the
    displayed $J_D(U_k)$, $U_k = Q_k^T Q_{k+1}$ of the symmetric reference run ($n = 3$, 7 momenta).
    """
    return _identification_gap(IDENT_MOMENTUM)


@D12.check(Level.MPMATH, tol=1e-40, form="printed")
def d12_identification_printed() -> float:
    """The same comparison with the printed identification $M_{k+1} = U_k$."""
    return _identification_gap(IDENT_PRINTED)


@D12.check(Level.MPMATH, tol=1e-40)
def d12_mv2_equals_symmetric_50_digits() -> float:
    """50 digits: MV-Algorithm 2 (MPDiscrete.mv2) from $(Q_1, M_1)$, $M_1 = h(Q_0^T P_0 - P_0^T
    Q_0)$, reproduces the symmetric representation's $Q_{k+1}$ ($n = 3$, 6 steps)."""
    run, mv = _mp_run(), _mp_mv_runs()
    return float(_mp_gap(mv["mv2_Q"], run["Qs"][1 : _MP_STEPS + 2]))


@D12.check(Level.FLOAT64, tol=1e-13)
def d12_symrb_momenta_against_50_digits() -> float:
    """symrb.mv_algorithm2 from $(Q_1, M_1)$ returns $M_{k+1}$ equal to the 50-digit Mdef1 momenta
    $h(Q_k^T P_k - P_k^T Q_k)$ of the symmetric reference run, and symrb.paper.symmetric_step's
    $U_k$ at the reference states has $J_D(U_k)$ (reference.J_D) equal to them ($n = 3$, 12 steps):
    max absolute error."""
    import symrb

    run = _mp_run()
    Qf, Pf, Msf = run["Qf"], run["Pf"], run["Msf"]
    MB = symrb.mv_algorithm2(Qf[1], Msf[0], _LAM3, _STEPS - 1).y.M
    _Q1, _P1, Us = symrb.paper.symmetric_step(Qf[:-1], Pf[:-1], _LAM3, _H)  # a batch of 12 states
    errs = [np.abs(MB - Msf[:-1]).max(), np.abs(ref.J_D(Us, _LAM3) - Msf[:-1]).max()]
    return float(np.max(errs))


# the paper's sentences (the first two are in Section 2.1, after the symmetric algorithm)

D12.sentence(
    r"As discussed in [BlCrMaRa2002] these equations are equivalent on a certain set to the "
    r"discrete Moser-Veselov equations for the classical rigid body if we identify $U$ with the "
    r"body angular momentum.",
    d12_symmetric_gives_mv,
    d12_identification,
    d12_identification_printed,
)
D12.sentence(
    r"We shall say more about Moser-Veselov as well as equivalence in the smooth setting below.",
    kind="prose",
    reason="points to later sections (the smooth equivalence is S6, S9-S11)",
)
D12.sentence(
    r"As mentioned above we can prove that symmetric representation of the rigid body equations "
    r"and the Moser-Veselov equations are equivalent when restricted to a suitable set.",
    d12_symmetric_gives_mv,
    d12_mv2_equals_symmetric_50_digits,
)
D12.sentence(
    r"It is easy to see the following: suppose that we have a solution $(Q_k, P_k)$ to the "
    r"symmetric discrete rigid body equations We can then produce a solution "
    r"$(Q_{k + 1}, M_{k + 1})$ of the Moser-Veselov equations: "
    r"$M_{k + 1}=Q_k^TP_k-P_k^TQ_k$ will give us the required $M_{k + 1}$ that does the job.",
    d12_symmetric_gives_mv,
    d12_mv2_equals_symmetric_50_digits,
    d12_symrb_momenta_against_50_digits,
)
D12.sentence(
    r"We refer to [BlCrMaRa2002] for the full proof of equivalence in the discrete setting and "
    r"we shall discuss below equivalence of the symmetric and standard rigid body in the smooth "
    r"setting.",
    kind="prose",
    reason="points to the literature for the proof and to Section 3 (S6) for the smooth setting",
)
