"""Generated from ``derivations.claims.section2.d06_backprop``; do not edit by hand.

Every function here is the expression that the evidence of the claims named in its
docstring evaluated.  Regenerate with ``python -m derivations derive`` (or ``symrb
derive``); ``--check`` only compares.
"""

from __future__ import annotations

import numpy

__all__ = [
    "resnet_step_tanh",
    "resnet_adjoint_tanh",
    "resnet_step_tanh_plain",
    "resnet_adjoint_tanh_plain",
    "resnet_step_logistic",
    "resnet_adjoint_logistic",
    "resnet_step_logistic_plain",
    "resnet_adjoint_logistic_plain",
]


def resnet_step_tanh(K, beta, x):
    r"""One residual layer x_(k+1) = f(x_k, u_k) = x + tanh(K x + beta).

    The control is u = (K, beta); the activation acts entrywise.

    Parameters
    ----------
    K : array, shape (..., n, n)
        layer weight K_k
    beta : array, shape (..., n, 1)
        layer bias beta_k
    x : array, shape (..., n, 1)
        state x_k

    Returns
    -------
    x_next : array

    Notes
    -----
    Checked by claim D6 (``symrb verify D6``);
    expressions from ``derivations.claims.section2.d06_backprop``.

    Total ops per batch item: 1 matrix product (n^3), 3 elementwise (n^2).
    """
    K = numpy.asarray(K, dtype=float)
    beta = numpy.asarray(beta, dtype=float)
    x = numpy.asarray(x, dtype=float)
    return (numpy.tanh((K @ x) + beta)) + x


def resnet_adjoint_tanh(K, beta, x, p):
    r"""Adjoint step of the layer f(x, u) = x + tanh(K x + beta) for H = <p, f(x, u)>.

    With z = K x + beta and s = tanh'(z) * p (entrywise):
    p_k = dH/dx = p + K^T s, dH/dK = s x^T, dH/dbeta = s.

    Parameters
    ----------
    K : array, shape (..., n, n)
        layer weight K_k
    beta : array, shape (..., n, 1)
        layer bias beta_k
    x : array, shape (..., n, 1)
        state x_k
    p : array, shape (..., n, 1)
        costate p_{k+1}

    Returns
    -------
    p_prev : array
    dH_dK : array
    dH_dbeta : array

    Notes
    -----
    Checked by claim D6 (``symrb verify D6``);
    expressions from ``derivations.claims.section2.d06_backprop``.

    Total ops per batch item: 3 matrix products (n^3), 4 elementwise (n^2).
    """
    K = numpy.asarray(K, dtype=float)
    beta = numpy.asarray(beta, dtype=float)
    x = numpy.asarray(x, dtype=float)
    p = numpy.asarray(p, dtype=float)
    t0 = (1 - numpy.tanh((K @ x) + beta) ** 2) * p
    return (((numpy.swapaxes(K, -1, -2) @ t0) + p), (t0 @ numpy.swapaxes(x, -1, -2)), t0)


def resnet_step_tanh_plain(K, beta, x):
    r"""One plain layer x_(k+1) = f(x_k, u_k) = tanh(K x + beta).

    The control is u = (K, beta); the activation acts entrywise.

    Parameters
    ----------
    K : array, shape (..., n, n)
        layer weight K_k
    beta : array, shape (..., n, 1)
        layer bias beta_k
    x : array, shape (..., n, 1)
        state x_k

    Returns
    -------
    x_next : array

    Notes
    -----
    Checked by claim D6 (``symrb verify D6``);
    expressions from ``derivations.claims.section2.d06_backprop``.

    Total ops per batch item: 1 matrix product (n^3), 2 elementwise (n^2).
    """
    K = numpy.asarray(K, dtype=float)
    beta = numpy.asarray(beta, dtype=float)
    x = numpy.asarray(x, dtype=float)
    return numpy.tanh((K @ x) + beta)


def resnet_adjoint_tanh_plain(K, beta, x, p):
    r"""Adjoint step of the layer f(x, u) = tanh(K x + beta) for H = <p, f(x, u)>.

    With z = K x + beta and s = tanh'(z) * p (entrywise):
    p_k = dH/dx = K^T s, dH/dK = s x^T, dH/dbeta = s.

    Parameters
    ----------
    K : array, shape (..., n, n)
        layer weight K_k
    beta : array, shape (..., n, 1)
        layer bias beta_k
    x : array, shape (..., n, 1)
        state x_k
    p : array, shape (..., n, 1)
        costate p_{k+1}

    Returns
    -------
    p_prev : array
    dH_dK : array
    dH_dbeta : array

    Notes
    -----
    Checked by claim D6 (``symrb verify D6``);
    expressions from ``derivations.claims.section2.d06_backprop``.

    Total ops per batch item: 3 matrix products (n^3), 3 elementwise (n^2).
    """
    K = numpy.asarray(K, dtype=float)
    beta = numpy.asarray(beta, dtype=float)
    x = numpy.asarray(x, dtype=float)
    p = numpy.asarray(p, dtype=float)
    t0 = (1 - numpy.tanh((K @ x) + beta) ** 2) * p
    return ((numpy.swapaxes(K, -1, -2) @ t0), (t0 @ numpy.swapaxes(x, -1, -2)), t0)


def resnet_step_logistic(K, beta, x):
    r"""One residual layer x_(k+1) = f(x_k, u_k) = x + logistic(K x + beta).

    The control is u = (K, beta); the activation acts entrywise.

    Parameters
    ----------
    K : array, shape (..., n, n)
        layer weight K_k
    beta : array, shape (..., n, 1)
        layer bias beta_k
    x : array, shape (..., n, 1)
        state x_k

    Returns
    -------
    x_next : array

    Notes
    -----
    Checked by claim D6 (``symrb verify D6``);
    expressions from ``derivations.claims.section2.d06_backprop``.

    Total ops per batch item: 1 matrix product (n^3), 3 elementwise (n^2).
    """
    K = numpy.asarray(K, dtype=float)
    beta = numpy.asarray(beta, dtype=float)
    x = numpy.asarray(x, dtype=float)
    return ((0.5) * numpy.tanh((0.5) * ((K @ x) + beta)) + 0.5) + x


def resnet_adjoint_logistic(K, beta, x, p):
    r"""Adjoint step of the layer f(x, u) = x + logistic(K x + beta) for H = <p, f(x, u)>.

    With z = K x + beta and s = logistic'(z) * p (entrywise):
    p_k = dH/dx = p + K^T s, dH/dK = s x^T, dH/dbeta = s.

    Parameters
    ----------
    K : array, shape (..., n, n)
        layer weight K_k
    beta : array, shape (..., n, 1)
        layer bias beta_k
    x : array, shape (..., n, 1)
        state x_k
    p : array, shape (..., n, 1)
        costate p_{k+1}

    Returns
    -------
    p_prev : array
    dH_dK : array
    dH_dbeta : array

    Notes
    -----
    Checked by claim D6 (``symrb verify D6``);
    expressions from ``derivations.claims.section2.d06_backprop``.

    Total ops per batch item: 3 matrix products (n^3), 4 elementwise (n^2).
    """
    K = numpy.asarray(K, dtype=float)
    beta = numpy.asarray(beta, dtype=float)
    x = numpy.asarray(x, dtype=float)
    p = numpy.asarray(p, dtype=float)
    t0 = ((1 / 4) - (1 / 4) * numpy.tanh((0.5) * ((K @ x) + beta)) ** 2) * p
    return (((numpy.swapaxes(K, -1, -2) @ t0) + p), (t0 @ numpy.swapaxes(x, -1, -2)), t0)


def resnet_step_logistic_plain(K, beta, x):
    r"""One plain layer x_(k+1) = f(x_k, u_k) = logistic(K x + beta).

    The control is u = (K, beta); the activation acts entrywise.

    Parameters
    ----------
    K : array, shape (..., n, n)
        layer weight K_k
    beta : array, shape (..., n, 1)
        layer bias beta_k
    x : array, shape (..., n, 1)
        state x_k

    Returns
    -------
    x_next : array

    Notes
    -----
    Checked by claim D6 (``symrb verify D6``);
    expressions from ``derivations.claims.section2.d06_backprop``.

    Total ops per batch item: 1 matrix product (n^3), 2 elementwise (n^2).
    """
    K = numpy.asarray(K, dtype=float)
    beta = numpy.asarray(beta, dtype=float)
    x = numpy.asarray(x, dtype=float)
    return (0.5) * numpy.tanh((0.5) * ((K @ x) + beta)) + 0.5


def resnet_adjoint_logistic_plain(K, beta, x, p):
    r"""Adjoint step of the layer f(x, u) = logistic(K x + beta) for H = <p, f(x, u)>.

    With z = K x + beta and s = logistic'(z) * p (entrywise):
    p_k = dH/dx = K^T s, dH/dK = s x^T, dH/dbeta = s.

    Parameters
    ----------
    K : array, shape (..., n, n)
        layer weight K_k
    beta : array, shape (..., n, 1)
        layer bias beta_k
    x : array, shape (..., n, 1)
        state x_k
    p : array, shape (..., n, 1)
        costate p_{k+1}

    Returns
    -------
    p_prev : array
    dH_dK : array
    dH_dbeta : array

    Notes
    -----
    Checked by claim D6 (``symrb verify D6``);
    expressions from ``derivations.claims.section2.d06_backprop``.

    Total ops per batch item: 3 matrix products (n^3), 3 elementwise (n^2).
    """
    K = numpy.asarray(K, dtype=float)
    beta = numpy.asarray(beta, dtype=float)
    x = numpy.asarray(x, dtype=float)
    p = numpy.asarray(p, dtype=float)
    t0 = ((1 / 4) - (1 / 4) * numpy.tanh((0.5) * ((K @ x) + beta)) ** 2) * p
    return ((numpy.swapaxes(K, -1, -2) @ t0), (t0 @ numpy.swapaxes(x, -1, -2)), t0)
