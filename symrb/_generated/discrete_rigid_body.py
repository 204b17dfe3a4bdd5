"""Generated from ``derivations.parts.discrete_rigid_body``; do not edit by hand.

Every function here is the expression that the evidence of the claims named in its
docstring evaluated.  Regenerate with ``python -m derivations derive`` (or ``symrb
derive``); ``--check`` only compares.
"""

from __future__ import annotations

import numpy

__all__ = ["jd", "mv_momentum", "mv_transport"]


def jd(U, lam):
    r"""The discrete inertia operator J_D(U) = U Lambda - Lambda U^T (paper, Section 2.1).

    Its derivative at the identity is J(Omega) = Omega Lambda + Lambda Omega (claim D8).

    Parameters
    ----------
    U : array, shape (..., n, n)
        a square matrix (in SO(n) for the discrete rigid body)
    lam : array, shape (..., n)
        diagonal of Lambda, positive

    Returns
    -------
    JD : array

    Notes
    -----
    Checked by claims D7, D8, D10, D12 (``symrb verify D7 D8 D10 D12``);
    expressions from ``derivations.parts.discrete_rigid_body``.

    Total ops per batch item: 3 elementwise (n^2).
    """
    U = numpy.asarray(U, dtype=float)
    lam = numpy.asarray(lam, dtype=float)
    return (U * lam[..., None, :]) - (lam[..., :, None] * numpy.swapaxes(U, -1, -2))


def mv_momentum(Omega, lam):
    r"""Second Moser-Veselov equation (paper, Section 2.2): M_k = Omega_k^T Lambda - Lambda Omega_k.

    Parameters
    ----------
    Omega : array, shape (..., n, n)
        discrete body angular velocity, in SO(n)
    lam : array, shape (..., n)
        diagonal of Lambda, positive

    Returns
    -------
    M : array

    Notes
    -----
    Checked by claims D10, D11, D12 (``symrb verify D10 D11 D12``);
    expressions from ``derivations.parts.discrete_rigid_body``.

    Total ops per batch item: 3 elementwise (n^2).
    """
    Omega = numpy.asarray(Omega, dtype=float)
    lam = numpy.asarray(lam, dtype=float)
    return (numpy.swapaxes(Omega, -1, -2) * lam[..., None, :]) - (lam[..., :, None] * Omega)


def mv_transport(Omega, M):
    r"""Third Moser-Veselov equation (paper, Section 2.2): M_{k+1} = Omega_k M_k Omega_k^T.

    Parameters
    ----------
    Omega : array, shape (..., n, n)
        discrete body angular velocity, in SO(n)
    M : array, shape (..., n, n)
        discrete body angular momentum, skew

    Returns
    -------
    M_next : array

    Notes
    -----
    Checked by claims D10, D11, D12 (``symrb verify D10 D11 D12``);
    expressions from ``derivations.parts.discrete_rigid_body``.

    Total ops per batch item: 2 matrix products (n^3).
    """
    Omega = numpy.asarray(Omega, dtype=float)
    M = numpy.asarray(M, dtype=float)
    return (Omega @ M) @ numpy.swapaxes(Omega, -1, -2)
