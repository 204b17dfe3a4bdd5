"""Generated from ``derivations.claims.section3.s02_rigid_body_equations``, ``derivations.claims.section3.s03_euler_poincare``, ``derivations.claims.section3.s04_manakov_integrals``; do not edit by hand.

Every function here is the expression that the evidence of the claims named in its
docstring evaluated.  Regenerate with ``python -m derivations derive`` (or ``symrb
derive``); ``--check`` only compares.
"""

from __future__ import annotations

import numpy

__all__ = [
    "rigid_body_rhs",
    "euler_rhs_so3",
    "kinetic_energy",
    "manakov_integrals",
    "casimir_traces",
]


def rigid_body_rhs(Q, M, lam):
    r"""Rigid body vector field (paper, Section 3.1).

    Qdot = Q Omega, Mdot = [M, Omega], Omega = J^{-1}(M), J^{-1}(M)_ij = M_ij / (lam_i + lam_j).

    Parameters
    ----------
    Q : array, shape (..., n, n)
        attitude, in SO(n)
    M : array, shape (..., n, n)
        body angular momentum, skew
    lam : array, shape (..., n)
        diagonal of Lambda, lam_i + lam_j > 0

    Returns
    -------
    Qdot : array
    Mdot : array

    Notes
    -----
    Checked by claim S2 (``symrb verify S2``);
    expressions from ``derivations.claims.section3.s02_rigid_body_equations``.

    Total ops per batch item: 3 matrix products (n^3), 2 elementwise (n^2).
    """
    Q = numpy.asarray(Q, dtype=float)
    M = numpy.asarray(M, dtype=float)
    lam = numpy.asarray(lam, dtype=float)
    W = 1.0 / (lam[..., :, None] + lam[..., None, :])
    t0 = M * W
    return ((Q @ t0), ((M @ t0) - (t0 @ M)))


def euler_rhs_so3(m, lam):
    r"""Euler's equations for n = 3.

    mdot = m x omega, omega_i = m_i / I_i, I_1 = lam_2 + lam_3 (cyclic): the components of the
    rigid body field at M = hat(m).

    Parameters
    ----------
    m : array, shape (..., 3)
        body angular momentum vector, M = hat(m)
    lam : array, shape (..., 3)
        diagonal of Lambda

    Returns
    -------
    array, shape (..., 3)
        mdot1, mdot2, mdot3, stacked along the last axis

    Notes
    -----
    Checked by claim S2 (``symrb verify S2``);
    expressions from ``derivations.claims.section3.s02_rigid_body_equations``.

    Total ops per batch item: 18 scalar.
    """
    m = numpy.asarray(m, dtype=float)
    lam = numpy.asarray(lam, dtype=float)
    l1 = lam[..., 0]
    l2 = lam[..., 1]
    l3 = lam[..., 2]
    m1 = m[..., 0]
    m2 = m[..., 1]
    m3 = m[..., 2]
    x0 = -l3
    x1 = m3 / (l1 + l2)
    x2 = m2 / (l1 + l3)
    x3 = m1 / (l2 + l3)
    return numpy.stack(
        numpy.broadcast_arrays(-x1 * x2 * (l2 + x0), x1 * x3 * (l1 + x0), -x2 * x3 * (l1 - l2)),
        axis=-1,
    )


def kinetic_energy(M, lam):
    r"""Kinetic energy 1/2 <J^{-1}(M), M>.

    The Lagrangian l(Omega) = 1/2 <Omega, J Omega> at Omega = J^{-1}(M), with the pairing
    <a, b> = -1/2 trace(a b).

    Parameters
    ----------
    M : array, shape (..., n, n)
        body angular momentum, skew
    lam : array, shape (..., n)
        diagonal of Lambda, lam_i + lam_j > 0

    Returns
    -------
    E : array

    Notes
    -----
    Checked by claim S3 (``symrb verify S3``);
    expressions from ``derivations.claims.section3.s03_euler_poincare``.

    Total ops per batch item: 1 elementwise (n^2), 1 trace (n^2), 1 scalar.
    """
    M = numpy.asarray(M, dtype=float)
    lam = numpy.asarray(lam, dtype=float)
    W = 1.0 / (lam[..., :, None] + lam[..., None, :])
    return -(1 / 4) * numpy.einsum("...ij,...ji->...", (M * W), M)


def manakov_integrals(M, lam):
    r"""Manakov's integrals of the rigid body.

    The non-trivial coefficients of lambda^j in trace((M + lambda Lambda^2)^k), 2 <= k <= 5
    (A = Lambda^2), in this order:

    - k=2, lambda^0: 1 tr(MM)
    - k=3, lambda^1: 3 tr(AMM)
    - k=4, lambda^0: 1 tr(MMMM)
    - k=4, lambda^2: 4 tr(AAMM) + 2 tr(AMAM)
    - k=5, lambda^1: 5 tr(AMMMM)
    - k=5, lambda^3: 5 tr(AAAMM) + 5 tr(AAMAM)

    Parameters
    ----------
    M : array, shape (..., n, n)
        body angular momentum, skew
    lam : array, shape (..., n)
        diagonal of Lambda, lam_i + lam_j > 0

    Returns
    -------
    array, shape (..., 6)
        k2_j0, k3_j1, k4_j0, k4_j2, k5_j1, k5_j3, stacked along the last axis

    Notes
    -----
    Checked by claim S4 (``symrb verify S4``);
    expressions from ``derivations.claims.section3.s04_manakov_integrals``.

    Total ops per batch item: 1 matrix product (n^3), 3 elementwise (n^2), 8 traces (n^2), 8 scalar.
    """
    M = numpy.asarray(M, dtype=float)
    lam = numpy.asarray(lam, dtype=float)
    t0 = (lam**2)[..., :, None] * M
    t1 = M @ M
    return numpy.stack(
        numpy.broadcast_arrays(
            numpy.einsum("...ij,...ji->...", M, M),
            3 * numpy.einsum("...ij,...ji->...", t0, M),
            numpy.einsum("...ij,...ji->...", t1, t1),
            4 * numpy.einsum("...i,...ii->...", (lam**4), t1)
            + 2 * numpy.einsum("...ij,...ji->...", t0, t0),
            5 * numpy.einsum("...ij,...ji->...", ((lam**2)[..., :, None] * t1), t1),
            5 * numpy.einsum("...ij,...ji->...", ((lam**4)[..., :, None] * M), t0)
            + 5 * numpy.einsum("...i,...ii->...", (lam**6), t1),
        ),
        axis=-1,
    )


def casimir_traces(M):
    r"""Casimirs of so(n): trace(M^2), trace(M^4), trace(M^6).

    The lambda^0 coefficients of trace((M + lambda Lambda^2)^k); odd powers vanish.

    Parameters
    ----------
    M : array, shape (..., n, n)
        body angular momentum, skew

    Returns
    -------
    array, shape (..., 3)
        tr_M2, tr_M4, tr_M6, stacked along the last axis

    Notes
    -----
    Checked by claim S4 (``symrb verify S4``);
    expressions from ``derivations.claims.section3.s04_manakov_integrals``.

    Total ops per batch item: 2 matrix products (n^3), 3 traces (n^2).
    """
    M = numpy.asarray(M, dtype=float)
    t0 = M @ M
    t1 = t0 @ M
    return numpy.stack(
        numpy.broadcast_arrays(
            numpy.einsum("...ij,...ji->...", M, M),
            numpy.einsum("...ij,...ji->...", t0, t0),
            numpy.einsum("...ij,...ji->...", t1, t1),
        ),
        axis=-1,
    )
