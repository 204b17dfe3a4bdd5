"""Generated from ``derivations.claims.section2.d07_optimal_control_on_so_n``, ``derivations.claims.section2.d09_learning_version``, ``derivations.claims.section2.d10_moser_veselov``, ``derivations.methods.cayley_step``, ``derivations.methods.preprocessed_mv``; do not edit by hand.

Every function here is the expression that the evidence of the claims named in its
docstring evaluated.  Regenerate with ``python -m derivations derive`` (or ``symrb
derive``); ``--check`` only compares.
"""

from __future__ import annotations

import numpy

__all__ = [
    "jd",
    "so_network_layer",
    "so_network_endpoint",
    "so_network_costate",
    "so_network_gradient",
    "mv_momentum",
    "mv_transport",
    "mv3_cayley_s_newton",
    "mv3_cayley_step",
    "mv3_preprocessing_coefficients",
    "mv3_preprocessed_lam",
]


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
    expressions from ``derivations.claims.section2.d07_optimal_control_on_so_n``.

    Total ops per batch item: 3 elementwise (n^2).
    """
    U = numpy.asarray(U, dtype=float)
    lam = numpy.asarray(lam, dtype=float)
    return (U * lam[..., None, :]) - (lam[..., :, None] * numpy.swapaxes(U, -1, -2))


def so_network_layer(Q, U):
    r"""One layer of the SO(n) network (paper, Section 2.1, learning version): Q^a_{k+1} = Q^a_k U_k, for every sample at once when the samples are stacked by rows.

    Parameters
    ----------
    Q : array, shape (..., n, n)
        the samples Q^a_k (n x n each), stacked by rows
    U : array, shape (..., n, n)
        the control U_k, in SO(n)

    Returns
    -------
    Q_next : array

    Notes
    -----
    Checked by claim D9 (``symrb verify D9``);
    expressions from ``derivations.claims.section2.d09_learning_version``.

    Total ops per batch item: 1 matrix product (n^3).
    """
    Q = numpy.asarray(Q, dtype=float)
    U = numpy.asarray(U, dtype=float)
    return Q @ U


def so_network_endpoint(Q, T):
    r"""Endpoint costate of the SO(n) network for phi(Q) = 1/2 ||Q - T||_F^2: P^a_N = -dphi/dQ^a_N = -(Q^a_N - T^a) (claim D9, the sign before the flip).

    Parameters
    ----------
    Q : array, shape (..., n, n)
        the final layer Q^a_N, samples stacked by rows
    T : array, shape (..., n, n)
        the targets T^a, stacked the same way

    Returns
    -------
    P : array

    Notes
    -----
    Checked by claim D9 (``symrb verify D9``);
    expressions from ``derivations.claims.section2.d09_learning_version``.

    Total ops per batch item: 1 elementwise (n^2).
    """
    Q = numpy.asarray(Q, dtype=float)
    T = numpy.asarray(T, dtype=float)
    return T - Q


def so_network_costate(P_next, U):
    r"""Costate step of the SO(n) network: P^a_k = dH/dQ^a_k = P^a_{k+1} U_k^T (the back-propagation of the layer Q U).

    Parameters
    ----------
    P_next : array, shape (..., n, n)
        the costates P^a_{k+1}, samples stacked by rows
    U : array, shape (..., n, n)
        the control U_k, in SO(n)

    Returns
    -------
    P : array

    Notes
    -----
    Checked by claim D9 (``symrb verify D9``);
    expressions from ``derivations.claims.section2.d09_learning_version``.

    Total ops per batch item: 1 matrix product (n^3).
    """
    P_next = numpy.asarray(P_next, dtype=float)
    U = numpy.asarray(U, dtype=float)
    return P_next @ numpy.swapaxes(U, -1, -2)


def so_network_gradient(P_next, Q_next, U, lam):
    r"""Skew gradient of the SO(n) network's loss in the control U_k (claim D9).

    With S = sum_a (P^a_{k+1})^T Q^a_{k+1} and lam the diagonal of alpha Lambda:
    G_k = (S - S^T)/2 + (Lambda U_k - U_k^T Lambda)/2, so that d/dt L(..., U_k exp(t xi), ...) at t = 0 is tr(G_k^T xi) for every skew xi.
    Equal to U_k^T (J_D(U_k) - sum_a ((Q^a_k)^T P^a_k - (P^a_k)^T Q^a_k)) U_k / 2: it vanishes
    exactly when Ukdef2 holds (for the inertia alpha Lambda).

    Parameters
    ----------
    P_next : array, shape (..., n, n)
        the costates P^a_{k+1}, samples stacked by rows
    Q_next : array, shape (..., n, n)
        the layer Q^a_{k+1}, stacked the same way
    U : array, shape (..., n, n)
        the control U_k, in SO(n)
    lam : array, shape (..., n)
        alpha times the diagonal of Lambda (running cost alpha tr(Lambda (I - U)))

    Returns
    -------
    G : array

    Notes
    -----
    Checked by claim D9 (``symrb verify D9``);
    expressions from ``derivations.claims.section2.d09_learning_version``.

    Total ops per batch item: 1 matrix product (n^3), 8 elementwise (n^2).
    """
    P_next = numpy.asarray(P_next, dtype=float)
    Q_next = numpy.asarray(Q_next, dtype=float)
    U = numpy.asarray(U, dtype=float)
    lam = numpy.asarray(lam, dtype=float)
    t0 = numpy.swapaxes(P_next, -1, -2) @ Q_next
    return (
        (0.5 * (lam[..., :, None] * U)) - (0.5 * (numpy.swapaxes(U, -1, -2) * lam[..., None, :]))
    ) + (0.5 * (t0 - numpy.swapaxes(t0, -1, -2)))


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
    expressions from ``derivations.claims.section2.d10_moser_veselov``.

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
    expressions from ``derivations.claims.section2.d10_moser_veselov``.

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
    Checked by claim M1 (``symrb verify M1``);
    expressions from ``derivations.methods.cayley_step``.

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
    U = cay(hat x); returns the increments dm = (U - I)^T m and dQ = Q (U - I): m_next = m +
    dm = U^T m, Q_next = Q + dQ = Q U (mv3_cayley_update; the caller adds them, so that the
    state is rounded once a step).  The caller accepts the step when |ds| is small enough
    (s_next then a root to rounding).  Arguments may be floats or arrays of one broadcast
    shape (no conversion).

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
    dm1 : array
    dm2 : array
    dm3 : array
    dq11 : array
    dq12 : array
    dq13 : array
    dq21 : array
    dq22 : array
    dq23 : array
    dq31 : array
    dq32 : array
    dq33 : array

    Notes
    -----
    Checked by claim M1 (``symrb verify M1``);
    expressions from ``derivations.methods.cayley_step``.

    Total ops per batch item: 216 scalar.
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
    t20 = t18 + t8
    t21 = -t5
    t22 = m3 * t11
    t23 = h * m2 * (t15 + t19 * t20) + m1 * t22 * (t1 + t21)
    t24 = t23**2
    t25 = 2 * t24
    t26 = t18 + t6
    t27 = h * m3 * (t15 + t20 * t26) + m1 * m2 * t11 * (t0 - t1)
    t28 = t27**2
    t29 = 2 * t28
    t30 = -t25 - t29
    t31 = t19 * t26
    t32 = h * m1 * (t15 + t31) + m2 * t22 * (-t0 - t21)
    t33 = t32**2
    t34 = t12 * t20 + t13 * t26 + t14 * t19 + t20 * t31
    t35 = 1.0 / (t24 + t28 + t33 + t34**2)
    t36 = m1 * t35
    t37 = 2 * t32
    t38 = t23 * t37
    t39 = 2 * t34
    t40 = t27 * t39 + t38
    t41 = m2 * t35
    t42 = t27 * t37
    t43 = -t23 * t39 + t42
    t44 = m3 * t35
    t45 = -t27 * t39 + t38
    t46 = 2 * t33
    t47 = -t29 - t46
    t48 = 2 * t23 * t27
    t49 = t34 * t37 + t48
    t50 = t23 * t39 + t42
    t51 = -t32 * t39 + t48
    t52 = -t25 - t46
    t53 = q11 * t35
    t54 = q12 * t35
    t55 = q13 * t35
    t56 = q21 * t35
    t57 = q22 * t35
    t58 = q23 * t35
    t59 = q31 * t35
    t60 = q32 * t35
    t61 = q33 * t35
    return (
        s + t17,
        t17,
        t30 * t36 + t40 * t41 + t43 * t44,
        t36 * t45 + t41 * t47 + t44 * t49,
        t36 * t50 + t41 * t51 + t44 * t52,
        t30 * t53 + t40 * t54 + t43 * t55,
        t45 * t53 + t47 * t54 + t49 * t55,
        t50 * t53 + t51 * t54 + t52 * t55,
        t30 * t56 + t40 * t57 + t43 * t58,
        t45 * t56 + t47 * t57 + t49 * t58,
        t50 * t56 + t51 * t57 + t52 * t58,
        t30 * t59 + t40 * t60 + t43 * t61,
        t45 * t59 + t47 * t60 + t49 * t61,
        t50 * t59 + t51 * t60 + t52 * t61,
    )


def mv3_preprocessing_coefficients(l1, l2, l3):
    r"""The constants of the preprocessed Moser-Veselov method (Hairer and Vilmart 2006), n = 3.

    c_kj, d_kj (k = 1..4, j = 0..k), rational functions of the inertia I_1 = l2 + l3 (cyclic):
    the coefficients of A^(k-j) E^j in the h^(2k) terms of c and d, 1/I~_i = c/I_i + d
    (mv3_preprocessed_lam).  Order 2k + 2 uses k = 1..k and zeros for the rest.

    Parameters
    ----------
    l1 : array, shape (...)
        lam_1, diagonal of Lambda
    l2 : array, shape (...)
        lam_2, diagonal of Lambda
    l3 : array, shape (...)
        lam_3, diagonal of Lambda

    Returns
    -------
    c10 : array
    c11 : array
    c20 : array
    c21 : array
    c22 : array
    c30 : array
    c31 : array
    c32 : array
    c33 : array
    c40 : array
    c41 : array
    c42 : array
    c43 : array
    c44 : array
    d10 : array
    d11 : array
    d20 : array
    d21 : array
    d22 : array
    d30 : array
    d31 : array
    d32 : array
    d33 : array
    d40 : array
    d41 : array
    d42 : array
    d43 : array
    d44 : array

    Notes
    -----
    Checked by claim M3 (``symrb verify M3``);
    expressions from ``derivations.methods.preprocessed_mv``.

    Total ops per batch item: 407 scalar.
    """
    t0 = 2 * l1
    t1 = 2 * l2
    t2 = 2 * l3
    t3 = t0 + t1 + t2
    t4 = l1 + l2
    t5 = 1.0 / t4
    t6 = l1 + l3
    t7 = 1.0 / t6
    t8 = l2 + l3
    t9 = 1.0 / t8
    t10 = t7 * t9
    t11 = t10 * t5
    t12 = (1 / 6) * t11 * t3
    t13 = (1 / 3) * t5
    t14 = t4**2
    t15 = t6**2
    t16 = t8**2
    t17 = t15 + t16
    t18 = t14 + t17
    t19 = t5 + t7 + t9
    t20 = (1 / 30) * t11
    t21 = t2 + t4
    t22 = t21 * t5
    t23 = t1 + t6
    t24 = t23 * t7
    t25 = t0 + t8
    t26 = t25 * t9
    t27 = t22 + t24 + t26
    t28 = 1.0 / t14
    t29 = 1.0 / t15
    t30 = 1.0 / t16
    t31 = 6 * l1 + 6 * l2 + 6 * l3
    t32 = (1 / 60) * t11
    t33 = t4 * t4 * t4
    t34 = t6 * t6 * t6
    t35 = t8 * t8 * t8
    t36 = t4 * t6 * t8
    t37 = t27 * t36
    t38 = 1.0 / t33
    t39 = 1.0 / t34
    t40 = 1.0 / t35
    t41 = t38 * t39 * t40
    t42 = (1 / 2520) * t41
    t43 = t17 * t5
    t44 = t14 + t16
    t45 = t44 * t7
    t46 = t14 + t15
    t47 = t46 * t9
    t48 = t28 + t29 + t30
    t49 = t36 * t48
    t50 = t28 * t29 * t30
    t51 = (1 / 2520) * t50
    t52 = t38 + t39 + t40
    t53 = t4 * t4 * t4 * t4
    t54 = t6 * t6 * t6 * t6
    t55 = t8 * t8 * t8 * t8
    t56 = t43 + t45 + t47
    t57 = t14 * t15 * t16
    t58 = t48 * t57
    t59 = 1.0 / t53
    t60 = 1.0 / t54
    t61 = 1.0 / t55
    t62 = (1 / 45360) * t59 * t60 * t61
    t63 = t34 + t35
    t64 = t5 * t63
    t65 = t7 * (t33 + t35)
    t66 = t9 * (t33 + t34)
    t67 = t19 * t36
    t68 = t21 * t28 + t23 * t29 + t25 * t30
    t69 = t36 * t68
    t70 = (1 / 22680) * t41
    t71 = t52 * t57
    t72 = t36 * (t17 * t28 + t29 * t44 + t30 * t46)
    t73 = (1 / 7560) * t41
    t74 = t36 * (t21 * t38 + t23 * t39 + t25 * t40)
    t75 = (1 / 45360) * t50
    t76 = (1 / 60) * t50
    return (
        t12,
        -t13 - (1 / 3) * t7 - (1 / 3) * t9,
        t20 * (t18 * t5 * t7 * t9 - t19),
        t20 * (1 - t27),
        (1 / 30) * t28 + (1 / 30) * t29 + (1 / 30) * t30 + t31 * t32,
        t42 * (17 * t33 + 17 * t34 + 17 * t35 + 4 * t36 - 15 * t37),
        (1 / 420) * t50 * (18 * l1 + 18 * l2 + 18 * l3 - 6 * t43 - 6 * t45 - 6 * t47 + 10 * t49),
        t51
        * (
            53 * t14
            + 53 * t15
            + 53 * t16
            + t36 * (6 * t21 * t28 + 6 * t23 * t29 + 6 * t25 * t30 - 100 * t5 - 100 * t7 - 100 * t9)
        ),
        (1 / 630) * t11 * (-2 * t22 - 2 * t24 - 2 * t26 - t36 * t52 + 15),
        t62 * (81 * t3 * t36 - 94 * t36 * t56 + 62 * t53 + 62 * t54 + 62 * t55 + 66 * t58),
        t70
        * (
            214 * t14
            + 214 * t15
            + 214 * t16
            - 77 * t64
            - 77 * t65
            - 77 * t66
            - 240 * t67
            + 75 * t69
        ),
        t73 * (55 * t33 + 55 * t34 + 55 * t35 + 204 * t36 - 59 * t37 - 50 * t71 + 26 * t72),
        (1 / 11340) * t50 * (t31 - 69 * t43 - 69 * t45 - 69 * t47 + 137 * t49 - t74),
        t75
        * (159 * t14 + 159 * t15 + 159 * t16 + 2 * t57 * (t59 + t60 + t61) - 171 * t67 + 5 * t69),
        -t10 * t13,
        t12,
        -t3 * t76,
        (1 / 10) * t11 * t19 - t18 * t76,
        t32 * (-t27 - 9),
        t42 * (-19 * t14 - 19 * t15 - 19 * t16 + 34 * t19 * t4 * t6 * t8),
        (1 / 1260) * t41 * (t33 - 85 * t36 + 2 * t37 + t63),
        t51 * (94 * l1 + 94 * l2 + 94 * l3 + 13 * t43 + 13 * t45 + 13 * t47 - 38 * t49),
        (1 / 1260)
        * t50
        * (-11 * t14 - 11 * t15 - 11 * t16 + 9 * t19 * t4 * t6 * t8 + t4 * t6 * t68 * t8),
        t62
        * (
            -61 * t33
            - 61 * t34
            - 61 * t35
            - 247 * t36
            + t4 * t6 * t8 * (60 * t22 + 60 * t24 + 60 * t26)
        ),
        t62 * (54 * t3 * t4 * t6 * t8 + 218 * t4 * t56 * t6 * t8 - t53 - t54 - t55 - 426 * t58),
        t73
        * (
            -130 * t14
            - 130 * t15
            - 130 * t16
            + 125 * t19 * t4 * t6 * t8
            + 4 * t4 * t6 * t68 * t8
            - 5 * t64
            - 5 * t65
            - 5 * t66
        ),
        t70 * (67 * t33 + 67 * t34 + 67 * t35 - 735 * t36 + 87 * t37 + 34 * t71 - 15 * t72),
        t75 * (330 * l1 + 330 * l2 + 330 * l3 - 9 * t43 - 9 * t45 - 9 * t47 - 145 * t49 - t74),
    )


def mv3_preprocessed_lam(
    h,
    m1,
    m2,
    m3,
    l1,
    l2,
    l3,
    c10,
    c11,
    c20,
    c21,
    c22,
    c30,
    c31,
    c32,
    c33,
    c40,
    c41,
    c42,
    c43,
    c44,
    d10,
    d11,
    d20,
    d21,
    d22,
    d30,
    d31,
    d32,
    d33,
    d40,
    d41,
    d42,
    d43,
    d44,
):
    r"""The modified Lambda of one preprocessed Moser-Veselov step, n = 3.

    A = h^2 |m|^2 / 2, E = h^2 sum m_i^2/(2 I_i), c = 1 + sum c_kj A^(k-j) E^j,
    d = sum d_kj A^(k-j) E^j, I~_i = 1/(c/I_i + d), l~_i = (I~_j + I~_k - I~_i)/2.  One
    mv3_cayley_step with l~ is the step h of the flow of Lambda to order 2k + 2 (Hairer and
    Vilmart 2006).  Arguments may be floats or arrays of one broadcast shape.

    Parameters
    ----------
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
    c10 : array, shape (...)
        preprocessing constant c10 (mv3_preprocessing_coefficients)
    c11 : array, shape (...)
        preprocessing constant c11 (mv3_preprocessing_coefficients)
    c20 : array, shape (...)
        preprocessing constant c20 (mv3_preprocessing_coefficients)
    c21 : array, shape (...)
        preprocessing constant c21 (mv3_preprocessing_coefficients)
    c22 : array, shape (...)
        preprocessing constant c22 (mv3_preprocessing_coefficients)
    c30 : array, shape (...)
        preprocessing constant c30 (mv3_preprocessing_coefficients)
    c31 : array, shape (...)
        preprocessing constant c31 (mv3_preprocessing_coefficients)
    c32 : array, shape (...)
        preprocessing constant c32 (mv3_preprocessing_coefficients)
    c33 : array, shape (...)
        preprocessing constant c33 (mv3_preprocessing_coefficients)
    c40 : array, shape (...)
        preprocessing constant c40 (mv3_preprocessing_coefficients)
    c41 : array, shape (...)
        preprocessing constant c41 (mv3_preprocessing_coefficients)
    c42 : array, shape (...)
        preprocessing constant c42 (mv3_preprocessing_coefficients)
    c43 : array, shape (...)
        preprocessing constant c43 (mv3_preprocessing_coefficients)
    c44 : array, shape (...)
        preprocessing constant c44 (mv3_preprocessing_coefficients)
    d10 : array, shape (...)
        preprocessing constant d10 (mv3_preprocessing_coefficients)
    d11 : array, shape (...)
        preprocessing constant d11 (mv3_preprocessing_coefficients)
    d20 : array, shape (...)
        preprocessing constant d20 (mv3_preprocessing_coefficients)
    d21 : array, shape (...)
        preprocessing constant d21 (mv3_preprocessing_coefficients)
    d22 : array, shape (...)
        preprocessing constant d22 (mv3_preprocessing_coefficients)
    d30 : array, shape (...)
        preprocessing constant d30 (mv3_preprocessing_coefficients)
    d31 : array, shape (...)
        preprocessing constant d31 (mv3_preprocessing_coefficients)
    d32 : array, shape (...)
        preprocessing constant d32 (mv3_preprocessing_coefficients)
    d33 : array, shape (...)
        preprocessing constant d33 (mv3_preprocessing_coefficients)
    d40 : array, shape (...)
        preprocessing constant d40 (mv3_preprocessing_coefficients)
    d41 : array, shape (...)
        preprocessing constant d41 (mv3_preprocessing_coefficients)
    d42 : array, shape (...)
        preprocessing constant d42 (mv3_preprocessing_coefficients)
    d43 : array, shape (...)
        preprocessing constant d43 (mv3_preprocessing_coefficients)
    d44 : array, shape (...)
        preprocessing constant d44 (mv3_preprocessing_coefficients)

    Returns
    -------
    l1_mod : array
    l2_mod : array
    l3_mod : array

    Notes
    -----
    Checked by claim M3 (``symrb verify M3``);
    expressions from ``derivations.methods.preprocessed_mv``.

    Total ops per batch item: 126 scalar.
    """
    t0 = 1.0 / (l1 + l2)
    t1 = m1**2
    t2 = m2**2
    t3 = m3**2
    t4 = t1 + t2 + t3
    t5 = (0.5) * h**2
    t6 = t4 * t5
    t7 = 1.0 / (l2 + l3)
    t8 = 1.0 / (l1 + l3)
    t9 = t0 * t3 + t1 * t7 + t2 * t8
    t10 = t5 * t9
    t11 = t4**2
    t12 = (1 / 4) * (h * h * h * h)
    t13 = t11 * t12
    t14 = t9**2
    t15 = t12 * t14
    t16 = t4 * t4 * t4
    t17 = (1 / 8) * (h * h * h * h * h * h)
    t18 = t16 * t17
    t19 = t9 * t9 * t9
    t20 = t17 * t19
    t21 = (1 / 16) * (h * h * h * h * h * h * h * h)
    t22 = t21 * (t4 * t4 * t4 * t4)
    t23 = t21 * (t9 * t9 * t9 * t9)
    t24 = t12 * t4 * t9
    t25 = t11 * t17 * t9
    t26 = t14 * t17 * t4
    t27 = t16 * t21 * t9
    t28 = t11 * t14 * t21
    t29 = t19 * t21 * t4
    t30 = (
        c10 * t6
        + c11 * t10
        + c20 * t13
        + c21 * t24
        + c22 * t15
        + c30 * t18
        + c31 * t25
        + c32 * t26
        + c33 * t20
        + c40 * t22
        + c41 * t27
        + c42 * t28
        + c43 * t29
        + c44 * t23
        + 1
    )
    t31 = (
        d10 * t6
        + d11 * t10
        + d20 * t13
        + d21 * t24
        + d22 * t15
        + d30 * t18
        + d31 * t25
        + d32 * t26
        + d33 * t20
        + d40 * t22
        + d41 * t27
        + d42 * t28
        + d43 * t29
        + d44 * t23
    )
    t32 = (0.5) / (t0 * t30 + t31)
    t33 = (0.5) / (t30 * t8 + t31)
    t34 = (0.5) / (t30 * t7 + t31)
    return (t32 + t33 - t34, t32 - t33 + t34, -t32 + t33 + t34)
