"""Generated from ``derivations.claims.section3.s05_maximum_principle``, ``derivations.claims.section3.s06_symmetric_to_rigid_body``, ``derivations.claims.section3.s07_mclachlan_scovel``, ``derivations.claims.section3.s08_learning_version``, ``derivations.claims.section3.s12_hamiltonian_on_gl``; do not edit by hand.

Every function here is the expression that the evidence of the claims named in its
docstring evaluated.  Regenerate with ``python -m derivations derive`` (or ``symrb
derive``); ``--check`` only compares.
"""

from __future__ import annotations

import numpy

__all__ = [
    "symmetric_rigid_body_rhs",
    "symmetric_momentum",
    "mclachlan_scovel_rhs",
    "control_rhs",
    "gl_hamiltonian",
]


def symmetric_rigid_body_rhs(Q, P, lam):
    r"""Symmetric rigid body field (paper, Section 3.2).

    Qdot = Q U, Pdot = P U, U = J^{-1}(Q^T P - P^T Q), J^{-1}(X)_ij = X_ij / (lam_i + lam_j).

    Parameters
    ----------
    Q : array, shape (..., n, n)
        configuration (SO(n) is invariant; any square matrix accepted)
    P : array, shape (..., n, n)
        costate
    lam : array, shape (..., n)
        diagonal of Lambda, lam_i + lam_j > 0

    Returns
    -------
    Qdot : array
    Pdot : array

    Notes
    -----
    Checked by claims S5, S6, S7, S11, S12 (``symrb verify S5 S6 S7 S11 S12``);
    expressions from ``derivations.claims.section3.s05_maximum_principle``.

    Total ops per batch item: 4 matrix products (n^3), 2 elementwise (n^2).
    """
    Q = numpy.asarray(Q, dtype=float)
    P = numpy.asarray(P, dtype=float)
    lam = numpy.asarray(lam, dtype=float)
    W = 1.0 / (lam[..., :, None] + lam[..., None, :])
    t0 = ((numpy.swapaxes(Q, -1, -2) @ P) - (numpy.swapaxes(P, -1, -2) @ Q)) * W
    return ((Q @ t0), (P @ t0))


def symmetric_momentum(Q, P):
    r"""The body momentum of the symmetric representation, M = Q^T P - P^T Q.

    Skew for any square Q, P; on the symmetric rigid body flow it follows the rigid body
    equations (paper, Proposition SRBtoRB).

    Parameters
    ----------
    Q : array, shape (..., n, n)
        configuration (SO(n) is invariant; any square matrix accepted)
    P : array, shape (..., n, n)
        costate

    Returns
    -------
    M : array

    Notes
    -----
    Checked by claims S6, S9, S11 (``symrb verify S6 S9 S11``);
    expressions from ``derivations.claims.section3.s06_symmetric_to_rigid_body``.

    Total ops per batch item: 2 matrix products (n^3), 1 elementwise (n^2).
    """
    Q = numpy.asarray(Q, dtype=float)
    P = numpy.asarray(P, dtype=float)
    return (numpy.swapaxes(Q, -1, -2) @ P) - (numpy.swapaxes(P, -1, -2) @ Q)


def mclachlan_scovel_rhs(Q, B, lam):
    r"""McLachlan-Scovel field (paper, Section 3.2).

    Qdot = Q U, Bdot = B U, U = J^{-1}(Q^T B), for Q^T B skew.

    Parameters
    ----------
    Q : array, shape (..., n, n)
        configuration (SO(n) is invariant; any square matrix accepted)
    B : array, shape (..., n, n)
        McLachlan-Scovel costate, Q^T B skew
    lam : array, shape (..., n)
        diagonal of Lambda, lam_i + lam_j > 0

    Returns
    -------
    Qdot : array
    Bdot : array

    Notes
    -----
    Checked by claim S7 (``symrb verify S7``);
    expressions from ``derivations.claims.section3.s07_mclachlan_scovel``.

    Total ops per batch item: 3 matrix products (n^3), 1 elementwise (n^2).
    """
    Q = numpy.asarray(Q, dtype=float)
    B = numpy.asarray(B, dtype=float)
    lam = numpy.asarray(lam, dtype=float)
    W = 1.0 / (lam[..., :, None] + lam[..., None, :])
    t0 = (numpy.swapaxes(Q, -1, -2) @ B) * W
    return ((Q @ t0), (B @ t0))


def control_rhs(Q, P, U):
    r"""State and costate fields for a given control U: Qdot = Q U, Pdot = P U.

    The learning version (paper, Section 3.2), one sample per batch entry.

    Parameters
    ----------
    Q : array, shape (..., n, n)
        configuration (SO(n) is invariant; any square matrix accepted)
    P : array, shape (..., n, n)
        costate
    U : array, shape (..., n, n)
        control, skew

    Returns
    -------
    Qdot : array
    Pdot : array

    Notes
    -----
    Checked by claim S8 (``symrb verify S8``);
    expressions from ``derivations.claims.section3.s08_learning_version``.

    Total ops per batch item: 2 matrix products (n^3).
    """
    Q = numpy.asarray(Q, dtype=float)
    P = numpy.asarray(P, dtype=float)
    U = numpy.asarray(U, dtype=float)
    return ((Q @ U), (P @ U))


def gl_hamiltonian(Q, P, lam):
    r"""The Hamiltonian on gl(n) x gl(n) (paper, Section 3.3).

    H = -1/8 trace(J^{-1}(M) M) = 1/4 <J^{-1}(M), M>, M = Q^T P - P^T Q: half the kinetic
    energy of the rigid body with momentum M.

    Parameters
    ----------
    Q : array, shape (..., n, n)
        configuration (SO(n) is invariant; any square matrix accepted)
    P : array, shape (..., n, n)
        costate
    lam : array, shape (..., n)
        diagonal of Lambda, lam_i + lam_j > 0

    Returns
    -------
    H : array

    Notes
    -----
    Checked by claim S12 (``symrb verify S12``);
    expressions from ``derivations.claims.section3.s12_hamiltonian_on_gl``.

    Total ops per batch item: 2 matrix products (n^3), 2 elementwise (n^2), 1 trace (n^2), 1 scalar.
    """
    Q = numpy.asarray(Q, dtype=float)
    P = numpy.asarray(P, dtype=float)
    lam = numpy.asarray(lam, dtype=float)
    W = 1.0 / (lam[..., :, None] + lam[..., None, :])
    t0 = (numpy.swapaxes(Q, -1, -2) @ P) - (numpy.swapaxes(P, -1, -2) @ Q)
    return -(1 / 8) * numpy.einsum("...ij,...ji->...", (W * t0), t0)
