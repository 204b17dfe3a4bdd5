"""S3 (Section 3.1, eq. ``RBLag_group.eqn``): the rigid body is Euler-Poincare for the kinetic
energy.

For l(Omega) = 1/2 <Omega, J(Omega)> the variational derivative is J(Omega) = M and
ad*_xi mu = [mu, xi] for the pairing of S1, so the Euler-Poincare equation is Mdot = [M, Omega].
The Lagrangian is the paper's definition; the kinetic energy kernel is that Lagrangian at
Omega = J^-1(M), which the evidence checks.

Emitted to ``symrb/_generated/rigid_body.py``: ``kinetic_energy``.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from derivations import reference as ref
from derivations.claims.section3._inertia import ARG_LAM, lam_symbols
from derivations.claims.section3.s02_rigid_body_equations import ARG_M, J_DEF, J_explicit, M, Om
from derivations.registry import Level, claim
from derivations.symbolic import (
    Bracket,
    Pair,
    Words,
    eq,
    explicit,
    lhs_minus_rhs,
    residual,
    skew_matrix,
    trace_residual,
)
from derivations.vocabulary import Jinv, Kernel, matrix

S3 = claim(
    "S3",
    label="RBLag_group.eqn",
    title="$\\dot M = [M, \\Omega]$ is Euler-Poincaré for $l(\\Omega) = \\tfrac12\\langle "
    "\\Omega, J(\\Omega)\\rangle$",
    statement="For [[lagrangian]] the variational derivative is [[derivative]] and "
    "[[coadjoint]], so the Euler-Poincare equation reads [[euler_poincare]].",
    expected="holds",
    section="3.1",
    where="Section 3.1, the paragraph after the rigid body equations: the Euler-Poincaré "
    "equations of $l(\\Omega) = \\tfrac12\\langle \\Omega, J(\\Omega)\\rangle$ and the Lagrangian "
    "$L(g, \\dot g)$ on $T\\,\\mathrm{SO}(n)$",
    note="The Lagrangian is the paper's definition; the kinetic energy kernel is that Lagrangian "
    "evaluated at $\\Omega = J^{-1}(M)$, which the evidence checks.",
)
_eta3 = matrix("eta")
_ell = sp.Function("l")
LAGRANGIAN = S3.formula("lagrangian", eq(_ell(Om), Pair(Om, J_DEF.rhs) / 2))
S3.formula("derivative", eq(matrix("delta_l/delta_Omega"), J_DEF.rhs))
_mu, _xi3 = matrix("mu"), matrix("xi")
COADJOINT = S3.formula(
    "coadjoint", eq(Pair(_mu, Bracket(_xi3, _eta3)), Pair(Bracket(_mu, _xi3), _eta3))
)
EULER_POINCARE = S3.formula("euler_poincare", eq(matrix("Mdot"), Bracket(M, Om)))

KINETIC_ENERGY = Kernel(
    name="kinetic_energy",
    target="rigid_body",
    args=[ARG_M, ARG_LAM],
    outputs={"E": Pair(Jinv(M), M).doit() / 2},
    doc="Kinetic energy 1/2 <J^{-1}(M), M>.\n\n"
    "The Lagrangian l(Omega) = 1/2 <Omega, J Omega> at Omega = J^{-1}(M), with the pairing\n"
    "<a, b> = -1/2 trace(a b).",
    claims=("S3",),
)


@S3.check(Level.SYMBOLIC_FIXED_N)
def s3_variational_derivative() -> sp.Expr:
    r"""$\frac{d}{de}\, l(\Omega + e\eta)$ at $e = 0$ equals $\langle J\Omega, \eta\rangle$ for the
    displayed $l$ ($n = 4$)."""
    lam, Omega, eta = lam_symbols(4), skew_matrix("w", 4), skew_matrix("e", 4)
    eps = sp.Symbol("epsilon")
    lag = explicit(LAGRANGIAN.rhs, {"Omega": Omega + eps * eta}, lam)
    return residual(
        sp.diff(lag, eps).subs(eps, 0)
        - explicit(Pair(J_DEF.rhs, _eta3), {"Omega": Omega, "eta": eta}, lam)
    )


@S3.check(Level.SYMBOLIC_GENERAL_N)
def s3_coadjoint() -> sp.Expr:
    r"""The displayed $\langle \mu, [\xi, \eta]\rangle = \langle [\mu, \xi], \eta\rangle$ holds as
    trace words for every $n$, and with it $\langle M, [\Omega, \eta]\rangle = \langle [M, \Omega],
    \eta\rangle$: $\mathrm{ad}^*_\Omega M$ is the right side of the displayed Euler-Poincare
    equation (noncommutative symbols)."""
    w = Words()
    r = trace_residual(w.trace_argument(lhs_minus_rhs(COADJOINT).doit()))
    ad_star = Pair(M, Bracket(Om, _eta3)) - Pair(EULER_POINCARE.rhs, _eta3)
    return r + trace_residual(w.trace_argument(ad_star.doit()))


@S3.check(Level.SYMBOLIC_FIXED_N)
def s3_kinetic_energy_kernel() -> sp.Expr:
    r"""The emitted kinetic energy at $M = J(\Omega)$ equals the displayed $l(\Omega)$ (symbolic
    skew $\Omega$, $n = 4$)."""
    lam, Omega = lam_symbols(4), skew_matrix("w", 4)
    Mx = J_explicit(Omega, lam)
    E = explicit(KINETIC_ENERGY["E"], {"M": Mx}, lam)
    return residual(sp.simplify(E - explicit(LAGRANGIAN.rhs, {"Omega": Omega}, lam)))


@S3.check(Level.FLOAT64, tol=1e-13)
def s3_symrb_kinetic_energy() -> float:
    r"""symrb.kinetic_energy($M$) against $\frac12 \langle \Omega, J\Omega\rangle$ with $\Omega$
    from the reference linear solve, $n = 2, \dots, 6$, 20 random $M$ each: max relative difference.
    """
    import symrb

    rng = np.random.default_rng(4)
    worst = 0.0
    for k in range(2, 7):
        lam = rng.uniform(0.3, 2.0, k)
        Ms = np.stack([ref.random_skew(k, rng) for _ in range(20)])
        Omega = ref.J_inv(Ms, lam)
        want = 0.5 * ref.pairing(Omega, ref.J(Omega, lam))
        worst = max(worst, float(np.abs(symrb.kinetic_energy(Ms, lam) - want).max() / want.max()))
    return worst


def _group_lagrangian(g: np.ndarray, gdot: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """The paper's L(g, gdot) = 1/2 <g^-1 gdot, J(g^-1 gdot)> in NumPy (numpy.linalg.inv, the
    reference J and pairing; complex entries allowed)."""
    xi = np.linalg.solve(g, gdot)
    return 0.5 * ref.pairing(xi, ref.J(xi, lam))


def _action_variation(
    sol_Q: np.ndarray,
    Om: np.ndarray,
    t: np.ndarray,
    w: np.ndarray,
    eta0: np.ndarray,
    T: float,
    lam: np.ndarray,
) -> tuple[float, float]:
    """d/de of the action of L along g_e = Q exp(e s(t) eta0), s = sin(pi t / T), at e = 0 by
    the complex step (exp(i h s eta0) = I + i h s eta0 to double precision at h = 1e-30); and
    the size of the terms it sums."""
    h = 1e-30
    total, scale = 0.0, 0.0
    for Qi, Oi, ti, wi in zip(sol_Q, Om, t, w, strict=True):
        s, sdot = np.sin(np.pi * ti / T), np.pi / T * np.cos(np.pi * ti / T)
        E = np.eye(len(eta0)) + 1j * h * s * eta0
        g = Qi @ E
        gdot = Qi @ Oi @ E + Qi @ (1j * h * sdot * eta0) @ E
        total += wi * float(np.imag(_group_lagrangian(g, gdot, lam))) / h
        scale += wi * abs(float(ref.pairing(ref.J(Oi, lam), sdot * eta0)))
    return total, scale


@S3.check(Level.FLOAT64, tol=1e-9)
def s3_hamiltons_principle_on_the_group() -> float:
    r"""The Lagrangian on $T\,\mathrm{SO}(n)$ corresponds to $l$: the displayed $L(g, \dot g)$
    (NumPy) is left invariant, $L(hg, h\dot g) = L(g, \dot g)$, and equals $l(g^{-1} \dot g)$; and
    along a solution of the rigid body equations (symrb.integrate(RigidBody), $n = 4$, DOP853, rtol
    1e-12, $t$ in $[0, 2]$) its action is stationary: for variations $g = Q \exp(e\, s(t)\, \eta_0)$
    with fixed ends ($s = \sin(\pi t/2)$, 3 random skew $\eta_0$) the derivative in $e$ (complex
    step, 48-point Gauss-Legendre quadrature) vanishes. Max of the relative invariance error and of
    the derivative relative to the size of its terms."""
    import symrb

    rng = np.random.default_rng(33)
    k, T, lam = 4, 2.0, np.array([0.6, 0.9, 1.3, 1.9])
    Q0, M0 = ref.random_rotation(k, rng), ref.random_skew(k, rng, 0.5)
    x, w = np.polynomial.legendre.leggauss(48)
    t, w = T * (x + 1) / 2, T * w / 2
    sol = symrb.integrate(
        symrb.RigidBody, (0.0, T), {"Q": Q0, "M": M0}, lam=lam,
        method="DOP853", rtol=1e-12, atol=1e-12, t_eval=t,
    )  # fmt: skip
    Om = ref.J_inv(sol.y.M, lam)
    worst = 0.0
    for _ in range(3):
        total, scale = _action_variation(sol.y.Q, Om, t, w, ref.random_skew(k, rng), T, lam)
        worst = max(worst, abs(total) / scale)
    g, h, Omr = ref.random_rotation(k, rng), ref.random_rotation(k, rng), ref.random_skew(k, rng)
    base = _group_lagrangian(g, g @ Omr, lam)
    reduced = 0.5 * ref.pairing(Omr, ref.J(Omr, lam))
    worst = max(worst, abs(_group_lagrangian(h @ g, h @ g @ Omr, lam) - base) / abs(base))
    return float(max(worst, abs(base - reduced) / abs(reduced)))


# the paper's sentences
S3.sentence(
    r"The equations $\dot{M} = [M, \Omega]$ are readily checked to be the Euler-Poincaré "
    r"equations on $\mathfrak{so}(n)$ for the Lagrangian $l(\Omega) = \frac{1}{2} \left\langle "
    r"\Omega, J(\Omega) \right\rangle$.",
    s3_variational_derivative,
    s3_coadjoint,
    s3_kinetic_energy_kernel,
    s3_symrb_kinetic_energy,
)
S3.sentence(
    r"This corresponds to the Lagrangian on $T \operatorname{SO}(n)$ given by $L(g, \dot{g}) = "
    r"\frac{1}{2} \left\langle g^{-1} \dot{g}, J(g^{-1} \dot{g}) \right\rangle\,.$",
    s3_hamiltons_principle_on_the_group,
)
