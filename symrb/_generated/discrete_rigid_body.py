"""Generated from ``derivations.parts.discrete_rigid_body``; do not edit by hand.

Every function here is the expression that the evidence of the claims named in its
docstring evaluated.  Regenerate with ``python -m derivations derive`` (or ``symrb
derive``); ``--check`` only compares.
"""

from __future__ import annotations

import numpy

__all__ = ["jd", "mv_momentum", "mv_transport", "mv3_cayley_s_newton", "mv3_cayley_step"]


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


def mv3_cayley_s_newton(s, h, m1, m2, m3, l1, l2, l3):
    r"""Newton step for the scalar form of the second Moser-Veselov equation, n = 3.

    b = h m, d_i = 2 I_i - s (I_1 = l2 + l3, cyclic), det = d1 d2 d3 + sum b_i^2 d_i,
    p(s) = s det - |b|^4 - sum b_i^2 d_j d_k; returns s + ds and ds = -p(s)/p'(s).  At a root
    s of p, x = adj(D_s - hat b) b / det solves G(x) = 0 (mv3_cayley_newton).  Arguments may be
    floats or arrays of one broadcast shape (no conversion).

    Parameters
    ----------
    s : array, shape (...)
        the scalar unknown s = b.x (b = h m, x the Cayley vector)
    h : array, shape (...)
        the step
    m1 : array, shape (...)
        body momentum, component 1
    m2 : array, shape (...)
        body momentum, component 2
    m3 : array, shape (...)
        body momentum, component 3
    l1 : array, shape (...)
        lam_1, diagonal of Lambda
    l2 : array, shape (...)
        lam_2, diagonal of Lambda
    l3 : array, shape (...)
        lam_3, diagonal of Lambda

    Returns
    -------
    s_next : array
    ds : array

    Notes
    -----
    Checked by claim D10 (``symrb verify D10``);
    expressions from ``derivations.parts.discrete_rigid_body``.

    Total ops per batch item: 62 scalar.
    """
    t0 = 2 * l2
    t1 = -s
    t2 = 2 * l1 + t1
    t3 = t0 + t2
    t4 = 2 * l3
    t5 = t2 + t4
    t6 = t3 * t5
    t7 = t0 + t1 + t4
    t8 = t3 * t7
    t9 = t5 * t7
    t10 = h**2
    t11 = m1**2 * t10
    t12 = m2**2 * t10
    t13 = m3**2 * t10
    t14 = t11 + t12 + t13
    t15 = t11 * t7 + t12 * t5 + t13 * t3 + t6 * t7
    t16 = (-s * t15 + t11 * t6 + t12 * t8 + t13 * t9 + t14**2) / (
        s * (-t14 - t6 - t8 - t9)
        + t11 * t3
        + t11 * t5
        + t12 * t3
        + t12 * t7
        + t13 * t5
        + t13 * t7
        + t15
    )
    return (s + t16, t16)


def mv3_cayley_step(s, h, m1, m2, m3, l1, l2, l3, q11, q12, q13, q21, q22, q23, q31, q32, q33):
    r"""One Moser-Veselov step, n = 3: one Newton step on the scalar form, then the update.

    s_next = s + ds with ds of mv3_cayley_s_newton; x = adj(D - hat b) b / det at s_next,
    U = cay(hat x), m_next = U^T m, Q_next = Q U (mv3_cayley_update).  The caller accepts the
    step when |ds| is small enough (s_next then a root to rounding).  Arguments may be floats
    or arrays of one broadcast shape (no conversion).

    Parameters
    ----------
    s : array, shape (...)
        the scalar unknown s = b.x (b = h m, x the Cayley vector)
    h : array, shape (...)
        the step
    m1 : array, shape (...)
        body momentum, component 1
    m2 : array, shape (...)
        body momentum, component 2
    m3 : array, shape (...)
        body momentum, component 3
    l1 : array, shape (...)
        lam_1, diagonal of Lambda
    l2 : array, shape (...)
        lam_2, diagonal of Lambda
    l3 : array, shape (...)
        lam_3, diagonal of Lambda
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
    s_next : array
    ds : array
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

    Total ops per batch item: 222 scalar.
    """
    t0 = 2 * l2
    t1 = 2 * l1
    t2 = -s
    t3 = t1 + t2
    t4 = t0 + t3
    t5 = 2 * l3
    t6 = t3 + t5
    t7 = t4 * t6
    t8 = t0 + t2 + t5
    t9 = t4 * t8
    t10 = t6 * t8
    t11 = h**2
    t12 = m1**2 * t11
    t13 = m2**2 * t11
    t14 = m3**2 * t11
    t15 = t12 + t13 + t14
    t16 = t12 * t8 + t13 * t6 + t14 * t4 + t7 * t8
    t17 = (-s * t16 + t10 * t14 + t12 * t7 + t13 * t9 + t15**2) / (
        s * (-t10 - t15 - t7 - t9)
        + t12 * t4
        + t12 * t6
        + t13 * t4
        + t13 * t8
        + t14 * t6
        + t14 * t8
        + t16
    )
    t18 = -t17
    t19 = t18 + t4
    t20 = t18 + t6
    t21 = t19 * t20
    t22 = -t5
    t23 = m3 * t11
    t24 = h * m1 * (t15 + t21) + m2 * t23 * (-t0 - t22)
    t25 = t24**2
    t26 = t18 + t8
    t27 = h * m2 * (t15 + t19 * t26) + m1 * t23 * (t1 + t22)
    t28 = t27**2
    t29 = h * m3 * (t15 + t20 * t26) + m1 * m2 * t11 * (t0 - t1)
    t30 = t29**2
    t31 = t12 * t26 + t13 * t20 + t14 * t19 + t21 * t26
    t32 = 1.0 / (t25 + t28 + t30 + t31**2)
    t33 = 2 * t28
    t34 = 2 * t30
    t35 = t32 * (-t33 - t34) + 1
    t36 = 2 * t24
    t37 = t27 * t36
    t38 = 2 * t31
    t39 = t29 * t38 + t37
    t40 = m2 * t32
    t41 = t29 * t36
    t42 = -t27 * t38 + t41
    t43 = m3 * t32
    t44 = 2 * t25
    t45 = t32 * (-t34 - t44) + 1
    t46 = -t29 * t38 + t37
    t47 = m1 * t32
    t48 = 2 * t27 * t29
    t49 = t31 * t36 + t48
    t50 = t32 * (-t33 - t44) + 1
    t51 = t27 * t38 + t41
    t52 = -t24 * t38 + t48
    t53 = q12 * t32
    t54 = q13 * t32
    t55 = q11 * t32
    t56 = q22 * t32
    t57 = q23 * t32
    t58 = q21 * t32
    t59 = q32 * t32
    t60 = q33 * t32
    t61 = q31 * t32
    return (
        s + t17,
        t17,
        m1 * t35 + t39 * t40 + t42 * t43,
        m2 * t45 + t43 * t49 + t46 * t47,
        m3 * t50 + t40 * t52 + t47 * t51,
        q11 * t35 + t39 * t53 + t42 * t54,
        q12 * t45 + t46 * t55 + t49 * t54,
        q13 * t50 + t51 * t55 + t52 * t53,
        q21 * t35 + t39 * t56 + t42 * t57,
        q22 * t45 + t46 * t58 + t49 * t57,
        q23 * t50 + t51 * t58 + t52 * t56,
        q31 * t35 + t39 * t59 + t42 * t60,
        q32 * t45 + t46 * t61 + t49 * t60,
        q33 * t50 + t51 * t61 + t52 * t59,
    )
