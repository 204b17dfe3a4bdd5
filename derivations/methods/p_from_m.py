"""M6: symrb's solver of M = Q^T P - P^T Q for a rotation P (``symrb.symmetric.P_from_M``).

Not a statement of the paper: S10 shows that P = Q exp(sinh^-1(M/2)) solves the equation for
||M||_op < 2, and that on skew matrices exp(sinh^-1 X) = X + (I + X^2)^(1/2).  symrb computes this
P on the real Schur form of M (a rotation by arcsin(theta/2) in each rotation plane of M).  These
checks hold it against S10's displayed formulas, evaluated independently, across the domain and,
near its boundary ||M||_op = 2, against S10's 60-digit reference: there the error grows like
eps / sqrt(delta), the conditioning of asinh, and no faster.
"""

from __future__ import annotations

import mpmath as mp
import numpy as np

from derivations import reference as ref
from derivations.claims.section3.s10_asinh_solution import (
    CLOSED,
    DOMAIN,
    DPS,
    S10,
    evaluate,
    near_boundary,
    numpy_ops,
)
from derivations.registry import Level, claim

M6 = claim(
    "M6",
    label="",
    title="$P$ from $M$ on the real Schur form",
    statement="`symrb.symmetric.P_from_M(Q, M)` returns the rotation $P$ of S10 for every skew $M$ with "
    "$\\|M\\|_{\\mathrm{op}}$ below 2, to rounding away from the boundary and within the "
    "conditioning of $\\sinh^{-1}$ near it.",
    expected="holds",
    section="symrb",
    where="`symrb.symmetric.P_from_M` (`symrb/continuous.py`), used by the scenes and experiments to start "
    "the symmetric rigid body from a body momentum",
)


@M6.check(Level.FLOAT64, tol=1e-11)
def m6_against_displayed_formulas() -> float:
    r"""symrb.symmetric.P_from_M (real Schur form) against S10's displayed corrected formula
    (Hermitian eigen-decomposition and expm) and its displayed closed form (symmetric
    eigen-decomposition), $n = 3, \dots, 6$, $\|M\|_{\mathrm{op}}$ from 0.1 to 0.995 times S10's
    displayed domain bound: max difference."""
    import symrb

    rng = np.random.default_rng(11)
    errs = []
    for k in range(3, 7):
        ops = numpy_ops(k)
        for r in np.linspace(0.1, 0.995 * float(DOMAIN.rhs), 12):
            Mk = ref.random_skew(k, rng)
            Mk *= r / np.linalg.norm(Mk, 2)
            Qk = ref.random_rotation(k, rng)
            got = symrb.symmetric.P_from_M(Qk, Mk)
            for formula in (S10.formulas["corrected"], CLOSED):
                errs.append(np.abs(got - evaluate(formula.rhs, {"Q": Qk, "M": Mk}, ops)).max())
    return float(np.max(errs))


@M6.check(Level.MPMATH, tol=10.0)
def m6_conditioning_near_boundary() -> float:
    r"""symrb.symmetric.P_from_M at $\|M\|_{\mathrm{op}} = 2(1 - \delta)$, $\delta = 10^{-4},
    10^{-8}, 10^{-12}$ ($n = 4$), against the 60-digit $P$ of S10's displayed closed form: the error
    in units of $\varepsilon/\sqrt{\delta}$, the conditioning of $\operatorname{asinh}$ at the
    boundary."""
    import symrb

    Qf, points, _identity = near_boundary()
    ratio = []
    with mp.workdps(DPS):
        for delta, Mf, Pm in points:
            err = float(mp.mnorm(mp.matrix(symrb.symmetric.P_from_M(Qf, Mf).tolist()) - Pm, 1))
            ratio.append(err * np.sqrt(delta) / np.finfo(float).eps)
    return float(np.max(ratio))
