r"""D11: the discrete variational principle of the Moser-Veselov equations (Section 2.2).

Where: Section 2.2, the paragraph 'Discrete Variational Principle' (mvl): stationary points of
:math:`\hat S = \sum_k\operatorname{tr}(Q_k\Lambda Q_{k+1}^T)` on sequences in :math:`SO(n)`.

Recorded outcome: holds.  Evidence: the first variation in noncommutative symbols is mv3 (every
:math:`n`, with D10's emitted kernels), and vanishes along symrb's MV-Algorithm 1 and 2 runs.
"""

from __future__ import annotations

import itertools

import numpy as np
import sympy as sp
from scipy.linalg import expm

from derivations import reference as ref
from derivations.claims.section2._matrix_formulas import _N, M, Om, Qk, Qk1, Qkm1, _k, _numeric
from derivations.claims.section2.d10_moser_veselov import MV1, MV2, MV3, MV_MOMENTUM, MV_TRANSPORT
from derivations.registry import Level, claim
from derivations.symbolic import Words, eq
from derivations.vocabulary import Lam, matrix

D11 = claim(
    "D11",
    label="mvl",
    title="Discrete variational principle for the Moser-Veselov equations",
    statement="Stationary points of [[mvl]] on sequences in $SO(n)$ yield the Moser-Veselov "
    "equations: with [[mv1]] and [[mv2]], the first variation in $Q_k$ vanishes exactly when "
    "[[mv3]].",
    expected="holds",
    section="2.2",
    where="Section 2.2, the paragraph 'Discrete Variational Principle': stationary points of "
    "$\\hat S = \\sum_k \\operatorname{tr}(Q_k \\Lambda Q_{k+1}^T)$ on sequences of orthogonal "
    "matrices",
)
S_TERM = sp.Trace(Qk * Lam * Qk1.T)
_eps = sp.Symbol("epsilon")
D11.formula("mvl", eq(sp.Symbol(r"\hat{S}"), sp.Sum(S_TERM, (_k, 0, _N - 1))))
D11.formula("mv1", MV1)
D11.formula("mv2", MV2)
D11.formula("mv3", MV3)


@D11.check(Level.SYMBOLIC_GENERAL_N)
def d11_euler_lagrange() -> sp.Expr:
    r"""Varying $Q_k$ to $Q_k(1 + e\xi)$ ($\xi$ skew) in the two displayed terms that contain $Q_k$
    gives $\operatorname{tr}(B\xi)$; with $\Omega_k = Q_k^T Q_{k-1}$, $\Omega_{k+1} = Q_{k+1}^T Q_k$
    (mv1) and the emitted mv2 and mv3 kernels, $B - B^T$ equals mv3's right side minus $M_{k+1}$:
    stationarity is mv3 (noncommutative, every $n$)."""
    w = Words(symmetric=["Lambda"], skew=["xi"], orthogonal=["Q_{k-1}", "Q_k", "Q_{k+1}"])
    xi = matrix("xi")
    moved = Qk + _eps * Qk * xi
    terms = S_TERM.xreplace({Qk1: moved, Qk: Qkm1}) + S_TERM.xreplace({Qk: moved})
    dS = sp.diff(sp.expand(w.trace_argument(terms)), _eps)
    # B with tr(dS) = tr(B xi): rotate each word so that xi comes last
    B = sp.Integer(0)
    for term in sp.Add.make_args(sp.expand(dS)):
        c, factors = term.args_cnc()
        word = [f for x in factors for f in ([x.base] * int(x.exp) if x.is_Pow else [x])]
        i = word.index(w("xi"))
        B += sp.Mul(*c) * sp.Mul(*(word[i + 1 :] + word[:i]))
    om_k, om_k1 = Qk.T * Qkm1, Qk1.T * Qk
    M_k = MV_MOMENTUM["M"].xreplace({Om: om_k})
    M_k1 = MV_MOMENTUM["M"].xreplace({Om: om_k1})
    target = MV_TRANSPORT["M_next"].xreplace({Om: om_k, M: M_k}) - M_k1
    return w.is_zero(B - w.T(B) - w.of(target))


@D11.check(Level.FLOAT64, tol=1e-13)
def d11_symrb_sequences_stationary() -> float:
    r"""Along symrb.mv_algorithm1 from $(Q_0, Q_1)$ and symrb.mv_algorithm2 from $(Q_1, M_1)$ ($n =
    4$, 8 steps, $\lambda$ in $[0.6, 1.7]$) the first variation of the displayed $\hat S$ at every
    interior $Q_k$ along $Q_k(I + e\xi)$, $\xi$ a basis element of $\mathfrak{so}(4)$, is
    $\operatorname{tr}(Q_{k-1} \Lambda (Q_k \xi)^T)$ plus $\operatorname{tr}(Q_k \xi \Lambda
    Q_{k+1}^T)$ (the displayed summand, linear in $Q_k$): largest absolute value (the terms are at
    most $4 \max \lambda$)."""
    import symrb

    rng = np.random.default_rng(111)
    lam = np.array([0.6, 0.9, 1.3, 1.7])
    Q0x = ref.random_rotation(4, rng)
    Q1x = Q0x @ expm(ref.random_skew(4, rng, 0.1))
    QA = symrb.mv_algorithm1(Q0x, Q1x, lam, 7).y.Q
    M1 = ref.J_D((Q1x.T @ Q0x).T, lam)  # mv2: M_1 = Omega_1^T Lam - Lam Omega_1 = J_D(Omega_1^T)
    QB = symrb.mv_algorithm2(Q1x, M1, lam, 7).y.Q
    worst = []
    for seq in (QA, np.concatenate([Q0x[None], QB])):
        for k in range(1, len(seq) - 1):
            for i, j in itertools.combinations(range(4), 2):
                xi = np.zeros((4, 4))
                xi[i, j], xi[j, i] = 1.0, -1.0
                d = _numeric(S_TERM, {"Q_k": seq[k - 1], "Q_{k+1}": seq[k] @ xi}, lam)
                d += _numeric(S_TERM, {"Q_k": seq[k] @ xi, "Q_{k+1}": seq[k + 1]}, lam)
                worst.append(abs(d))
    return float(np.max(worst))


# the paper's sentences

D11.sentence(
    r"Discrete Variational Principle. The Moser-Veselov equations (mv1)-(mv3) can be obtained by "
    r"a discrete variational principle, as was done in [MoVe1991].",
    d11_euler_lagrange,
)
D11.sentence(
    r"This variational principle has the general form described in discrete mechanics; see, "
    r"e.g., [MaWe1997], [BoSu1999], and [MaWe2001].",
    kind="prose",
    reason="places the principle in the literature (citations)",
)
D11.sentence(
    r"Namely, stationary points of the functional "
    r"$\hat{S}= \sum_k \operatorname{trace}(Q_k \Lambda Q_{k+1}^T)$ on sequences of orthogonal "
    r"$n\times n$ matrices yield the Moser-Veselov equations.",
    d11_euler_lagrange,
    d11_symrb_sequences_stationary,
)
D11.sentence(
    r"This variational approach can be justified as in [MaPeSh1999].",
    kind="prose",
    reason="points to a justification in the literature (a citation)",
)
