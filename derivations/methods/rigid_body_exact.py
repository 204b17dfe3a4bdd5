"""M5: symrb's exact solution of the rigid body for n = 3 (``symrb.exact.rigid_body_exact``).

Not a statement of the paper: symrb ships the rigid body of S2 for n = 3 in closed form (Jacobi
elliptic functions for the body momentum, an elliptic integral of the third kind for the attitude;
Celledoni, Fasso, Safstrom and Zanna 2008), both as an array route over many bodies and times and
as a float route for one body at a few times.  These checks hold it against the Landau-Lifshitz
elliptic solution of Euler's equations, against symrb's integration of the rigid body field and
against a 20-digit Taylor integration.
"""

from __future__ import annotations

import numpy as np

from derivations import reference as ref
from derivations.registry import Level, claim

M5 = claim(
    "M5",
    label="",
    title="The exact solution of the rigid body for $n = 3$",
    statement="`symrb.exact.rigid_body_exact` returns the attitude and body momentum of the rigid body "
    "of S2 for $n = 3$ at the requested times, for every body with $J$ positive definite (a "
    "steady rotation, a symmetric body, a momentum circling the largest or the smallest axis), "
    "to the accuracy of an independent solution.",
    expected="holds",
    section="symrb",
    where="`symrb.exact.rigid_body_exact` (`symrb/exact.py`), the reference of `symrb bench` and of "
    "the accuracy tests of `symrb.integrate` for the rigid body",
)


@M5.check(Level.FLOAT64, tol=1e-12)
def m5_exact_against_elliptic() -> float:
    r"""symrb.exact.rigid_body_exact ($n = 3$) against the Landau-Lifshitz Jacobi elliptic solution
    (reference.euler_elliptic) at 201 times in $[0, 200]$, with the principal axes in the three
    cyclic orders of $\lambda$ (the body momentum circles the largest axis), as one call for all
    times (the array route) and one call per six of them (one body and at most 8 times: the float
    route): $\max |M \text{ error}| / |M|$."""
    from symrb.exact import rigid_body_exact

    inertia = np.array([1.0, 1.7, 2.6])
    t = np.linspace(0.0, 200.0, 201)
    m = ref.euler_elliptic(inertia, 0.8, 1.1, t)
    worst = 0.0
    for shift in range(3):  # a cyclic relabelling of the axes is a rotation: same dynamics
        I_s, m_s = np.roll(inertia, shift), np.roll(m, shift, axis=-1)
        lam = 0.5 * I_s.sum() - I_s  # I_1 = lam_2 + lam_3 (cyclic)
        Q0 = ref.random_rotation(3, np.random.default_rng(shift))
        sol = rigid_body_exact(Q0, ref.hat(m_s[0]), lam, t)
        err = np.abs(ref.vee(sol.y.M) - m_s).max() / np.linalg.norm(m_s[0])
        worst = max(worst, float(err))
        for part in np.array_split(np.arange(len(t)), 34):
            one = rigid_body_exact(Q0, ref.hat(m_s[0]), lam, t[part])
            err = np.abs(ref.vee(one.y.M) - m_s[part]).max() / np.linalg.norm(m_s[0])
            worst = max(worst, float(err))
    return worst


# the 6 random bodies of the next check, and the special cases it adds
_EXACT_SPECIAL = [
    ([0.0, 0.0, 1.3], [0.7, 1.1, 1.6]),  # a steady rotation about a principal axis
    ([0.5, 1.0, 1.5], [0.8, 0.8, 1.5]),  # a symmetric body
    ([0.7, 0.3, -1.1], [-0.2, 1.1, 1.6]),  # lam_1 < 0 with J positive definite
]


@M5.check(Level.FLOAT64, tol=1e-10)
def m5_exact_against_flow() -> float:
    r"""symrb.exact.rigid_body_exact against symrb.integrate(RigidBody) (DOP853, rtol and atol
    1e-13) at 11 times in $[0, 60]$, for 6 random bodies ($|m| = 1$; the momentum circles the
    largest axis for some, the smallest for others) plus a steady rotation, a symmetric body and a
    body with $\lambda_1 < 0$, all in one call (the array route) and each body alone at the last
    three times (one body: the float route, except the steady rotation): $\max |Q \text{ error}|$
    and $|M \text{ error}| / |M|$."""
    import symrb
    from symrb.exact import rigid_body_exact

    rng = np.random.default_rng(17)
    lam = rng.uniform(0.4, 2.0, (6, 3))
    m = rng.standard_normal((6, 3))
    m /= np.linalg.norm(m, axis=-1, keepdims=True)
    lam = np.concatenate([lam, [c[1] for c in _EXACT_SPECIAL]])
    m = np.concatenate([m, [c[0] for c in _EXACT_SPECIAL]])
    Q0 = np.stack([ref.random_rotation(3, rng) for _ in range(len(m))])
    M0 = ref.hat(m)
    t = np.linspace(0.0, 60.0, 11)
    sol = rigid_body_exact(Q0, M0, lam, t)
    inertia = lam.sum(axis=-1, keepdims=True) - lam
    circled = np.take_along_axis(inertia, np.maximum(sol.axis, 0)[:, None], -1)[:, 0]
    if not (np.any(circled == inertia.max(-1)) and np.any(circled == inertia.min(-1))):
        return np.inf  # both elliptic cases must be exercised
    flow = symrb.integrate(
        symrb.RigidBody, (0.0, 60.0), {"Q": Q0, "M": M0}, lam=lam, rtol=1e-13, atol=1e-13,
        t_eval=t,
    )  # fmt: skip
    eQ = np.abs(sol.y.Q - flow.y.Q).max()
    eM = (np.abs(sol.y.M - flow.y.M).max(axis=(0, -2, -1)) / np.abs(M0).max(axis=(-2, -1))).max()
    for b in range(len(m)):
        one = rigid_body_exact(Q0[b], M0[b], lam[b], t[-3:])
        eQ = max(eQ, np.abs(one.y.Q - flow.y.Q[-3:, b]).max())
        eM = max(eM, np.abs(one.y.M - flow.y.M[-3:, b]).max() / np.abs(M0[b]).max())
    return float(max(eQ, eM))


@M5.check(Level.MPMATH, tol=1e-13)
def m5_exact_against_mpmath_ode() -> float:
    r"""symrb.exact.rigid_body_exact at $t = 4$ against a 20-digit Taylor integration of the rigid
    body (mpmath.odefun on $\dot Q = Q \hat\omega$, $\dot m = m \times \omega$), for a body whose
    momentum circles its largest axis and one whose momentum circles its smallest: $\max |Q \text{
    error}|$ and $|m \text{ error}| / |m|$."""
    from symrb.exact import rigid_body_exact

    worst = 0.0
    rng = np.random.default_rng(5)
    for lam, m0 in (([0.7, 1.1, 1.6], [0.5, 1.0, 1.5]), ([0.7, 1.1, 1.6], [1.5, 1.0, 0.5])):
        lam_a, m0_a = np.array(lam), np.array(m0)
        inertia = lam_a.sum() - lam_a
        Q0 = ref.random_rotation(3, rng)
        QT, mT = ref.rigid_body_mp(inertia, Q0, m0_a, 20)(4.0)
        sol = rigid_body_exact(Q0, ref.hat(m0_a), lam_a, [4.0])
        eQ = np.abs(sol.y.Q[0] - QT).max()
        eM = np.abs(ref.vee(sol.y.M[0]) - mT).max() / np.linalg.norm(m0_a)
        worst = max(worst, float(eQ), float(eM))
    return worst
