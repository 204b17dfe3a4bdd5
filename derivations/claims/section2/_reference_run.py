r"""The shared 50-digit reference run of Section 2 (:math:`n = 3`).

:class:`derivations.reference.MPDiscrete` runs the symmetric representation from
:math:`P_0 = Q_0M_0/2` at step :math:`h = 0.1` in 50 digits, and MV-Algorithm 1 and 2 from its
first states; D7, D8, D10, D12 and symrb's engine check (M2) compare with it.  Computed once
(cached).
"""

from __future__ import annotations

import functools
import itertools
from typing import Any

import numpy as np

from derivations import reference as ref
from derivations.claims.section2._matrix_formulas import _LAM3

_H = 0.1
_STEPS = 12
_MP_STEPS = 6  # steps of the 50-digit MV-Algorithm 1 and 2 runs (each solve costs 0.17 s)


def _mp_to_numpy(a: Any) -> np.ndarray:
    return np.array(a.tolist(), dtype=float)


@functools.cache
def _mp_run() -> dict[str, Any]:
    """The reference: MPDiscrete.symmetric (50 digits, n = 3, h = 0.1, 12 steps) from Q_0 (random,
    orthonormalised in 50 digits) and P_0 = Q_0 M_0/2 with the continuous momentum M_0 =
    hat(1.2, -0.7, 0.9) (||M_0||_op = 1.66); the float64 starting data; and the trajectories
    rounded to float64 (rounding below 1e-16, far under the 1e-13 tolerances of the float64
    evidence, and NumPy comparisons with them see a NaN)."""
    rng = np.random.default_rng(1212)
    mpd = ref.MPDiscrete(_LAM3)
    M0f = ref.hat(np.array([1.2, -0.7, 0.9]))
    Q0m = mpd.orthonormal(ref.random_rotation(3, rng))
    with mpd.mp.workdps(mpd.dps):
        P0m = Q0m * mpd.matrix(0.5 * M0f)
        Qs, Ps = mpd.symmetric(Q0m, P0m, _H, _STEPS)
        h = mpd.mp.mpf(_H)
        Mc = [q.T * p - p.T * q for q, p in zip(Qs, Ps, strict=True)]  # Mdef1, continuous scale
        Ms = [h * m for m in Mc]  # the discrete momenta M^MV_{k+1}
    Q0f = _mp_to_numpy(Q0m)

    def rounded(mats: list[Any]) -> np.ndarray:  # float64 copies: comparisons that see NaN
        return np.stack([_mp_to_numpy(x) for x in mats])

    return {
        "mpd": mpd, "Q0": Q0f, "M0": M0f, "P0": Q0f @ (0.5 * M0f),
        "Qs": Qs, "Ps": Ps, "Mc": Mc, "Ms": Ms,
        "Qf": rounded(Qs), "Pf": rounded(Ps), "Mcf": rounded(Mc), "Msf": rounded(Ms),
    }  # fmt: skip


@functools.cache
def _mp_mv_runs() -> dict[str, Any]:
    """MPDiscrete.mv2 from (Q_1, M_1) and MPDiscrete.mv1 from (Q_0, Q_1) of the reference run,
    50 digits, 6 steps each."""
    run = _mp_run()
    mpd = run["mpd"]
    Qb, Mb = mpd.mv2(run["Qs"][1], run["Ms"][0], _MP_STEPS)
    Qa = mpd.mv1(run["Qs"][0], run["Qs"][1], _MP_STEPS)
    return {"mv2_Q": Qb, "mv2_M": Mb, "mv1_Q": Qa}


_ENTRIES = list(itertools.product(range(3), range(3)))


def _mp_gap(a: list[Any], b: list[Any]) -> Any:
    """max over k of the largest entry of |a_k - b_k| (both in high precision)."""
    mpd = _mp_run()["mpd"]
    with mpd.mp.workdps(mpd.dps):
        gaps = [abs((x - y)[i, j]) for x, y in zip(a, b, strict=True) for i, j in _ENTRIES]
        if any(mpd.mp.isnan(g) for g in gaps):
            return float("nan")
        return max(gaps)
