"""Generated from ``derivations.parts.discrete_rigid_body``; do not edit by hand.

Every function here is the expression that the evidence of the claims named in its
docstring evaluated.  Regenerate with ``python -m derivations derive`` (or ``symrb
derive``); ``--check`` only compares.
"""

from __future__ import annotations

import numpy

__all__ = ["jd", "mv_momentum", "mv_transport", "mv3_cayley_newton", "mv3_cayley_update"]


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


def mv3_cayley_newton(x1, x2, x3, b1, b2, b3, l1, l2, l3):
    r"""Newton step for the second Moser-Veselov equation in Cayley coordinates, n = 3.

    With U = cay(hat x) = (I + X)(I - X)^{-1}, J_D(U) = hat(b) is equivalent to
    G(x) = 2 I o x - b - b x x - (b.x) x = 0 (I_1 = l2 + l3, cyclic); returns the Newton step
    dx = -G'(x)^{-1} G(x), G'(x) = 2 diag(I) - (b.x) Id - hat(b) - x b^T, by the adjugate.
    Arguments may be floats or arrays of one broadcast shape (no conversion).

    Parameters
    ----------
    x1 : array, shape (...)
        Cayley vector, component 1
    x2 : array, shape (...)
        Cayley vector, component 2
    x3 : array, shape (...)
        Cayley vector, component 3
    b1 : array, shape (...)
        discrete momentum h m, component 1
    b2 : array, shape (...)
        discrete momentum h m, component 2
    b3 : array, shape (...)
        discrete momentum h m, component 3
    l1 : array, shape (...)
        lam_1, diagonal of Lambda
    l2 : array, shape (...)
        lam_2, diagonal of Lambda
    l3 : array, shape (...)
        lam_3, diagonal of Lambda

    Returns
    -------
    dx1 : array
    dx2 : array
    dx3 : array

    Notes
    -----
    Checked by claim D10 (``symrb verify D10``);
    expressions from ``derivations.parts.discrete_rigid_body``.

    Total ops per batch item: 146 scalar.
    """
    t0 = b2 * x1
    t1 = b3 - t0
    t2 = b1 - b3 * x2
    t3 = b1 * x3
    t4 = b2 - t3
    t5 = b1 * x2 + b3
    t6 = -t5
    t7 = -2 * l1
    t8 = -2 * l2
    t9 = b3 * x3
    t10 = b1 * x1
    t11 = b2 * x2
    t12 = t10 + t11
    t13 = -t12 - t7 - t8 - 2 * t9
    t14 = -t13 * t6 + t2 * t4
    t15 = b2 + b3 * x1
    t16 = -t15
    t17 = b2 * x3
    t18 = -b1 - t17
    t19 = -2 * l3 + t9
    t20 = -t10 - 2 * t11 - t19 - t7
    t21 = t18 * t6 - t20 * t4
    t22 = t13 * t20 - t18 * t2
    t23 = -2 * t10 - t11 - t19 - t8
    t24 = 1.0 / (t1 * t14 + t16 * t21 + t22 * t23)
    t25 = t12 + t9
    t26 = 2 * l1
    t27 = 2 * l2
    t28 = t0 - t25 * x3 - t5 + x3 * (t26 + t27)
    t29 = 2 * l3
    t30 = -t15 - t25 * x2 + t3 + x2 * (t26 + t29)
    t31 = -t17 - t2 - t25 * x1 + x1 * (t27 + t29)
    return (
        t24 * (-t22 * t31 - t28 * (t1 * t2 - t16 * t20) - t30 * (-t1 * t13 + t16 * t18)),
        t24 * (-t14 * t31 - t28 * (t16 * t6 - t2 * t23) - t30 * (t13 * t23 - t16 * t4)),
        t24 * (-t21 * t31 - t28 * (-t1 * t6 + t20 * t23) - t30 * (t1 * t4 - t18 * t23)),
    )


def mv3_cayley_update(x1, x2, x3, m1, m2, m3, q11, q12, q13, q21, q22, q23, q31, q32, q33):
    r"""One Moser-Veselov step of the state given the Cayley vector x of U, n = 3.

    U = cay(hat x) = I + 2 (X + X^2)/(1 + |x|^2), m_next = U^T m (M_{k+1} = U^T M_k U, the
    third Moser-Veselov equation with Omega_k = U^T), Q_next = Q U.  Arguments may be floats
    or arrays of one broadcast shape (no conversion).

    Parameters
    ----------
    x1 : array, shape (...)
        Cayley vector, component 1
    x2 : array, shape (...)
        Cayley vector, component 2
    x3 : array, shape (...)
        Cayley vector, component 3
    m1 : array, shape (...)
        body momentum, component 1
    m2 : array, shape (...)
        body momentum, component 2
    m3 : array, shape (...)
        body momentum, component 3
    q11 : array, shape (...)
        attitude Q, entry (1, 1)
    q12 : array, shape (...)
        attitude Q, entry (1, 2)
    q13 : array, shape (...)
        attitude Q, entry (1, 3)
    q21 : array, shape (...)
        attitude Q, entry (2, 1)
    q22 : array, shape (...)
        attitude Q, entry (2, 2)
    q23 : array, shape (...)
        attitude Q, entry (2, 3)
    q31 : array, shape (...)
        attitude Q, entry (3, 1)
    q32 : array, shape (...)
        attitude Q, entry (3, 2)
    q33 : array, shape (...)
        attitude Q, entry (3, 3)

    Returns
    -------
    m1_next : array
    m2_next : array
    m3_next : array
    q11_next : array
    q12_next : array
    q13_next : array
    q21_next : array
    q22_next : array
    q23_next : array
    q31_next : array
    q32_next : array
    q33_next : array

    Notes
    -----
    Checked by claim D10 (``symrb verify D10``);
    expressions from ``derivations.parts.discrete_rigid_body``.

    Total ops per batch item: 114 scalar.
    """
    t0 = x1**2
    t1 = x2**2
    t2 = x3**2
    t3 = 1.0 / (t0 + t1 + t2 + 1)
    t4 = 2 * t1
    t5 = 2 * t2
    t6 = t3 * (-t4 - t5) + 1
    t7 = 2 * x3
    t8 = 2 * x2
    t9 = t8 * x1
    t10 = t7 + t9
    t11 = m2 * t3
    t12 = t7 * x1
    t13 = t12 - t8
    t14 = m3 * t3
    t15 = 2 * t0
    t16 = t3 * (-t15 - t5) + 1
    t17 = -t7 + t9
    t18 = m1 * t3
    t19 = 2 * x1
    t20 = t19 + t7 * x2
    t21 = t3 * (-t15 - t4) + 1
    t22 = t12 + t8
    t23 = -t19 + 2 * x2 * x3
    t24 = q12 * t3
    t25 = q13 * t3
    t26 = q11 * t3
    t27 = q22 * t3
    t28 = q23 * t3
    t29 = q21 * t3
    t30 = q32 * t3
    t31 = q33 * t3
    t32 = q31 * t3
    return (
        m1 * t6 + t10 * t11 + t13 * t14,
        m2 * t16 + t14 * t20 + t17 * t18,
        m3 * t21 + t11 * t23 + t18 * t22,
        q11 * t6 + t10 * t24 + t13 * t25,
        q12 * t16 + t17 * t26 + t20 * t25,
        q13 * t21 + t22 * t26 + t23 * t24,
        q21 * t6 + t10 * t27 + t13 * t28,
        q22 * t16 + t17 * t29 + t20 * t28,
        q23 * t21 + t22 * t29 + t23 * t27,
        q31 * t6 + t10 * t30 + t13 * t31,
        q32 * t16 + t17 * t32 + t20 * t31,
        q33 * t21 + t22 * t32 + t23 * t30,
    )
