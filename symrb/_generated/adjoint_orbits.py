"""Generated from ``derivations.claims.section3.s13_adjoint_orbits``, ``derivations.claims.section3.s14_brockett_toda``, ``derivations.claims.section3.s15_learning_on_orbits``, ``derivations.claims.section3.s15_learning_on_orbits.so3``; do not edit by hand.

Every function here is the expression that the evidence of the claims named in its
docstring evaluated.  Regenerate with ``python -m derivations derive`` (or ``symrb
derive``); ``--check`` only compares.
"""

from __future__ import annotations

import numpy

__all__ = [
    "optimal_control",
    "orbit_hamiltonian",
    "brockett_potential",
    "orbit_extremal_rhs",
    "double_bracket_rhs",
    "orbit_rhs_with_control",
    "one_sample_second_term",
    "two_sample_bound",
]


def optimal_control(x, p):
    r"""The maximiser of H in u: u* = [p, x].

    For samples sharing one control, sum it over the samples: u* = sum_b [p^b, x^b].

    Parameters
    ----------
    x : array, shape (..., n, n)
        state on an adjoint orbit (skew for so(n))
    p : array, shape (..., n, n)
        costate, identified with the algebra through the pairing

    Returns
    -------
    u : array

    Notes
    -----
    Checked by claims S13, S15 (``symrb verify S13 S15``);
    expressions from ``derivations.claims.section3.s13_adjoint_orbits``.

    Total ops per batch item: 2 matrix products (n^3), 1 elementwise (n^2).
    """
    x = numpy.asarray(x, dtype=float)
    p = numpy.asarray(p, dtype=float)
    return (p @ x) - (x @ p)


def orbit_hamiltonian(x, p, N):
    r"""Optimal Hamiltonian H* = -1/2 <x, [p, [p, x]]> + V(x) with Brockett's potential.

    V(x) = -1/2 ||[x, N]||^2, <a, b> = -1/2 trace(a b); H* = 1/2 ||[p, x]||^2 + V(x).

    Parameters
    ----------
    x : array, shape (..., n, n)
        state on an adjoint orbit (skew for so(n))
    p : array, shape (..., n, n)
        costate, identified with the algebra through the pairing
    N : array, shape (..., n, n)
        the fixed element n of Brockett's potential

    Returns
    -------
    H : array

    Notes
    -----
    Checked by claims S13, S14 (``symrb verify S13 S14``);
    expressions from ``derivations.claims.section3.s13_adjoint_orbits``.

    Total ops per batch item: 6 matrix products (n^3), 3 elementwise (n^2), 2 traces (n^2), 3 scalar.
    """
    x = numpy.asarray(x, dtype=float)
    p = numpy.asarray(p, dtype=float)
    N = numpy.asarray(N, dtype=float)
    t0 = (x @ N) - (N @ x)
    t1 = (p @ x) - (x @ p)
    return (1 / 4) * numpy.einsum("...ij,...ji->...", t0, t0) + (1 / 4) * numpy.einsum(
        "...ij,...ji->...", x, ((p @ t1) - (t1 @ p))
    )


def brockett_potential(x, N):
    r"""Brockett's potential V(x) = -1/2 ||[x, N]||^2.

    ||a||^2 = <a, a> = -1/2 trace(a a).

    Parameters
    ----------
    x : array, shape (..., n, n)
        state on an adjoint orbit (skew for so(n))
    N : array, shape (..., n, n)
        the fixed element n of Brockett's potential

    Returns
    -------
    V : array

    Notes
    -----
    Checked by claim S14 (``symrb verify S14``);
    expressions from ``derivations.claims.section3.s14_brockett_toda``.

    Total ops per batch item: 2 matrix products (n^3), 1 elementwise (n^2), 1 trace (n^2), 1 scalar.
    """
    x = numpy.asarray(x, dtype=float)
    N = numpy.asarray(N, dtype=float)
    t0 = (x @ N) - (N @ x)
    return (1 / 4) * numpy.einsum("...ij,...ji->...", t0, t0)


def orbit_extremal_rhs(x, p, N):
    r"""Extremal equations with Brockett's potential (paper, Section 3.4).

    xdot = [x, [p, x]], pdot = [p, [p, x]] - [N, [N, x]].

    Parameters
    ----------
    x : array, shape (..., n, n)
        state on an adjoint orbit (skew for so(n))
    p : array, shape (..., n, n)
        costate, identified with the algebra through the pairing
    N : array, shape (..., n, n)
        the fixed element n of Brockett's potential

    Returns
    -------
    xdot : array
    pdot : array

    Notes
    -----
    Checked by claims S14, S15 (``symrb verify S14 S15``);
    expressions from ``derivations.claims.section3.s14_brockett_toda``.

    Total ops per batch item: 10 matrix products (n^3), 6 elementwise (n^2).
    """
    x = numpy.asarray(x, dtype=float)
    p = numpy.asarray(p, dtype=float)
    N = numpy.asarray(N, dtype=float)
    t0 = (p @ x) - (x @ p)
    t1 = (N @ x) - (x @ N)
    return (((x @ t0) - (t0 @ x)), ((p @ t0) + (t1 @ N) - (N @ t1) - (t0 @ p)))


def double_bracket_rhs(x, N):
    r"""Double bracket vector field xdot = [x, [x, N]].

    Parameters
    ----------
    x : array, shape (..., n, n)
        state on an adjoint orbit (skew for so(n))
    N : array, shape (..., n, n)
        the fixed element n of Brockett's potential

    Returns
    -------
    xdot : array

    Notes
    -----
    Checked by claims S14, S15 (``symrb verify S14 S15``);
    expressions from ``derivations.claims.section3.s14_brockett_toda``.

    Total ops per batch item: 4 matrix products (n^3), 2 elementwise (n^2).
    """
    x = numpy.asarray(x, dtype=float)
    N = numpy.asarray(N, dtype=float)
    t0 = (x @ N) - (N @ x)
    return (x @ t0) - (t0 @ x)


def orbit_rhs_with_control(x, p, u, N):
    r"""State and costate fields of one sample for a given control u.

    xdot = [x, u], pdot = [p, u] - [N, [N, x]] (Brockett's potential); with the shared optimal
    control u = sum_b [p^b, x^b] these are the extremal equations of the learning version.

    Parameters
    ----------
    x : array, shape (..., n, n)
        state on an adjoint orbit (skew for so(n))
    p : array, shape (..., n, n)
        costate, identified with the algebra through the pairing
    u : array, shape (..., n, n)
        the control (shared by all samples in the learning version)
    N : array, shape (..., n, n)
        the fixed element n of Brockett's potential

    Returns
    -------
    xdot : array
    pdot : array

    Notes
    -----
    Checked by claim S15 (``symrb verify S15``);
    expressions from ``derivations.claims.section3.s15_learning_on_orbits``.

    Total ops per batch item: 8 matrix products (n^3), 5 elementwise (n^2).
    """
    x = numpy.asarray(x, dtype=float)
    p = numpy.asarray(p, dtype=float)
    u = numpy.asarray(u, dtype=float)
    N = numpy.asarray(N, dtype=float)
    t0 = (N @ x) - (x @ N)
    return (((x @ u) - (u @ x)), ((p @ u) + (t0 @ N) - (N @ t0) - (u @ p)))


def one_sample_second_term(r, s, tau_0, T):
    r"""||[N, [N, x(T)]]|| along the one-sample extremal on so(3), in closed form.

    The displayed decay ||N||^2 ||x_0|| sin(phi_T), with the displayed phase
    tan(phi_T / 2) = tan(phi_0 / 2) exp(-||x_0|| ||N|| T): x(T) is the double bracket flow.

    Parameters
    ----------
    r : array, shape (...)
        ||x_0||, the norm of the sample
    s : array, shape (...)
        ||N||
    tau_0 : array, shape (...)
        tan(phi_0 / 2), phi_0 the angle of x_0 from -N
    T : array, shape (...)
        the time, >= 0

    Returns
    -------
    second_term : array

    Notes
    -----
    Checked by claim S15 (``symrb verify S15``);
    expressions from ``derivations.claims.section3.s15_learning_on_orbits.so3``.

    Total ops per batch item: 14 scalar.
    """
    r = numpy.asarray(r, dtype=float)
    s = numpy.asarray(s, dtype=float)
    tau_0 = numpy.asarray(tau_0, dtype=float)
    T = numpy.asarray(T, dtype=float)
    t0 = T * r * s
    return 2 * r * s**2 * tau_0 * numpy.exp(-t0) / (tau_0**2 * numpy.exp(-2 * t0) + 1)


def two_sample_bound(r_1, r_2, s, p_12):
    r"""The lower bound of the larger second costate term of two samples on so(3).

    ||N||^2 min(||x^1_0||, ||x^2_0||) sin(beta / 2), cos beta = |<x^1_0, x^2_0>| /
    (||x^1_0|| ||x^2_0||): the displayed bound of the corrected statement.

    Parameters
    ----------
    r_1 : array, shape (...)
        ||x^1_0||
    r_2 : array, shape (...)
        ||x^2_0||
    s : array, shape (...)
        ||N||
    p_12 : array, shape (...)
        <x^1_0, x^2_0>, at most r_1 r_2 in size

    Returns
    -------
    bound : array

    Notes
    -----
    Checked by claim S15 (``symrb verify S15``);
    expressions from ``derivations.claims.section3.s15_learning_on_orbits.so3``.

    Total ops per batch item: 8 scalar.
    """
    r_1 = numpy.asarray(r_1, dtype=float)
    r_2 = numpy.asarray(r_2, dtype=float)
    s = numpy.asarray(s, dtype=float)
    p_12 = numpy.asarray(p_12, dtype=float)
    return s**2 * numpy.sin((0.5) * numpy.arccos(abs(p_12) / (r_1 * r_2))) * numpy.minimum(r_1, r_2)
