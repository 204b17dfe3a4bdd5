r"""Optional compiled RKMK4 and implicit midpoint loops at any n (numba).

The loops behind ``method="numba"`` (and ``"auto"`` on long runs) of
:func:`symrb.compose.rkmk4_rigid_body_flow` and :func:`symrb.compose.midpoint_rigid_body_flow`,
built on the dense kernels of :mod:`symrb._compiled_n` (module-level ``numba.njit(cache=True)``
functions, no fast-math).  Each reproduces its NumPy base step operation for operation, which
stays the reference (results equal to rounding):

* :func:`run_rkmk4` is :class:`symrb.base_steps.RKMK4Step`: four evaluations of
  :math:`F(\Theta) = \mathrm{dexp}^{-1}_{-\Theta}(J^{-1}(e^{-\Theta}M_0e^{\Theta}))` (the series
  to the :math:`[\Theta, [\Theta, \cdot]]` term) with the Pade exponential
  :func:`symrb._compiled_n.expm` in place of :func:`scipy.linalg.expm`;
* :func:`run_midpoint` is :class:`symrb.base_steps.MidpointStep`: the fixed point over the whole
  batch with its stopping rule (the largest change at most :math:`4\varepsilon\max|M_k|`), then
  :math:`Q\,\mathrm{cay}(h\bar\Omega)`; a step that does not converge is reported (the caller
  redoes the run on the NumPy path, which reports the failure).

Examples
--------
>>> from symrb import _compiled_stages
>>> isinstance(_compiled_stages.AVAILABLE, bool)
True
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ._compiled_n import _EPS, AVAILABLE, _expm_into, _jit, _mm, _mtm, _need, _skew_into, _solve
from ._validate import Array

__all__ = ["AVAILABLE", "run_rkmk4", "run_midpoint"]


# ---------------------------------------------------------------------------------------------
# RKMK4 (symrb.base_steps.RKMK4Step)


@_jit
def _rkmk4_F(
    th: Array, M0: Array, Wl: Array, out: Array, W: Array, E: Array
) -> bool:  # pragma: no cover
    """out = dexp^{-1}_{-th}(J^{-1}(e^{-th} M0 e^{th})) to the [th, [th, .]] term."""
    n = th.shape[0]
    g, T1, T2, c, d = W[0], W[1], W[2], W[3], W[4]
    if not _expm_into(th, g, E):
        return False
    _mtm(g, M0, T1)
    _mm(T1, g, T2)
    for i in range(n):
        for j in range(n):
            T1[i, j] = 0.5 * (T2[i, j] - T2[j, i]) * Wl[i, j]  # Om
    _mm(th, T1, T2)
    _mm(T1, th, d)
    for i in range(n):
        for j in range(n):
            c[i, j] = T2[i, j] - d[i, j]
    _mm(th, c, T2)
    _mm(c, th, d)
    for i in range(n):
        for j in range(n):
            out[i, j] = T1[i, j] + 0.5 * c[i, j] + (T2[i, j] - d[i, j]) / 12.0
    return True


@_jit
def _rkmk4_step(Q: Array, M: Array, Wl: Array, h: float, k: Array, th: Array, W: Array,
                E: Array) -> bool:  # fmt: skip  # pragma: no cover
    """One RKMK4 step of (Q, M) in place; k (4, n, n), th (n, n) work."""
    n = Q.shape[0]
    for i in range(n):
        for j in range(n):
            k[0, i, j] = h * (M[i, j] * Wl[i, j])
    for s in range(1, 4):
        a = 1.0 if s == 3 else 0.5
        for i in range(n):
            for j in range(n):
                th[i, j] = a * k[s - 1, i, j] if s < 3 else k[s - 1, i, j]
        if not _rkmk4_F(th, M, Wl, k[s], W, E):
            return False
        for i in range(n):
            for j in range(n):
                k[s, i, j] = h * k[s, i, j]
    for i in range(n):
        for j in range(n):
            W[5, i, j] = (k[0, i, j] + 2.0 * k[1, i, j] + 2.0 * k[2, i, j] + k[3, i, j]) / 6.0
    _skew_into(W[5], th)
    g = W[0]
    if not _expm_into(th, g, E):
        return False
    _mm(Q, g, W[1])
    Q[:, :] = W[1]
    _mtm(g, M, W[1])
    _mm(W[1], g, W[2])
    _skew_into(W[2], M)
    return True


@_jit
def _rkmk4_loop(Q0: Array, M0: Array, Wl: Array, h: float, steps: int, save_every: int,
                Qs: Array, Ms: Array) -> int:  # fmt: skip  # pragma: no cover - compiled
    nb, n = M0.shape[0], M0.shape[1]
    k, th, W, E = np.empty((4, n, n)), np.empty((n, n)), np.empty((6, n, n)), np.empty((10, n, n))
    Q, M = np.empty((n, n)), np.empty((n, n))
    for b in range(nb):
        Q[:, :], M[:, :] = Q0[b], M0[b]
        jsave = 0
        for s in range(1, steps + 1):
            if not _rkmk4_step(Q, M, Wl[b], h, k, th, W, E):
                return s
            if s % save_every == 0:
                Qs[jsave, b], Ms[jsave, b] = Q, M
                jsave += 1
    return 0


def run_rkmk4(
    Q: Array, M: Array, lam: Array, h: float, steps: int, save_every: int
) -> tuple[Array, Array, int]:
    r"""``steps`` steps of RKMK4 (:class:`symrb.base_steps.RKMK4Step`) of a batch, compiled.

    Parameters
    ----------
    Q, M : ndarray, shape (B, n, n)
        The attitudes and (skew) body momenta.
    lam : ndarray, shape (B, n)
        The diagonals of :math:`\Lambda`.
    h : float
        The step.
    steps, save_every : int
        Steps to take; the states after every ``save_every``-th are saved.

    Returns
    -------
    Qs, Ms : ndarray, shape (steps // save_every, B, n, n)
        The saved states.
    fail : int
        0, or a step whose exponential failed (a state not finite): the caller redoes the run on
        the NumPy path.

    Raises
    ------
    RuntimeError
        Without numba.

    Examples
    --------
    >>> import numpy as np
    >>> from symrb import _compiled_stages
    >>> M = np.array([[[0.0, -1.5, 1.0], [1.5, 0.0, -0.5], [-1.0, 0.5, 0.0]]])
    >>> if _compiled_stages.AVAILABLE:
    ...     Qs, Ms, fail = _compiled_stages.run_rkmk4(np.eye(3)[None], M, np.ones((1, 3)), 0.1, 4, 2)
    ...     print(Qs.shape, fail, bool(np.abs(Ms[-1] - M).max() < 1e-15))  # lam = 1: M fixed
    ... else:
    ...     print((2, 1, 3, 3), 0, True)
    (2, 1, 3, 3) 0 True
    """
    _need()
    f = np.ascontiguousarray
    B, n = M.shape[0], M.shape[-1]
    lam = f(lam, dtype=float)
    Wl = 1.0 / (lam[:, :, None] + lam[:, None, :])
    K = steps // save_every
    Qs, Ms = np.full((K, B, n, n), np.nan), np.full((K, B, n, n), np.nan)
    fail = _rkmk4_loop(f(Q, dtype=float), f(M, dtype=float), Wl, float(h), int(steps),
                       int(save_every), Qs, Ms)  # fmt: skip
    return Qs, Ms, int(fail)


# ---------------------------------------------------------------------------------------------
# the implicit midpoint rule (symrb.base_steps.MidpointStep)


@_jit
def _midpoint_sweep(
    M: Array, Mb: Array, Wl: Array, c: float, W: Array
) -> float:  # pragma: no cover
    """Mb <- M + c (Mb Om - Om Mb), Om = Mb o W, for every body; the largest change (NaN if
    one is not finite)."""
    nb, n = M.shape[0], M.shape[1]
    Om, P1, P2 = W[0], W[1], W[2]
    diff = 0.0
    finite = True
    for b in range(nb):
        for i in range(n):
            for j in range(n):
                Om[i, j] = Mb[b, i, j] * Wl[b, i, j]
        _mm(Mb[b], Om, P1)
        _mm(Om, Mb[b], P2)
        for i in range(n):
            for j in range(n):
                new = M[b, i, j] + c * (P1[i, j] - P2[i, j])
                d = abs(new - Mb[b, i, j])
                finite = finite and math.isfinite(d)
                diff = max(diff, d)
                Mb[b, i, j] = new
    return diff if finite else np.nan


@_jit
def _midpoint_update(
    Q: Array, M: Array, Mb: Array, Wl: Array, h: float, W: Array
) -> None:  # pragma: no cover
    """Q <- Q cay(h Om), M <- skew(2 Mb - M), Om = Mb o W (one body)."""
    n = Q.shape[0]
    S, T, C, LU = W[0], W[1], W[2], W[3]
    for i in range(n):
        for j in range(n):
            a = h * (Mb[i, j] * Wl[i, j])
            e = 1.0 if i == j else 0.0
            S[i, j] = e - 0.5 * a
            T[i, j] = e + 0.5 * a
    _solve(S, T, LU, C)
    _mm(Q, C, S)
    Q[:, :] = S
    for i in range(n):
        for j in range(n):
            S[i, j] = 2.0 * Mb[i, j] - M[i, j]
    _skew_into(S, M)


@_jit
def _midpoint_loop(Q: Array, M: Array, Wl: Array, h: float, steps: int, save_every: int,
                   maxiter: int, Qs: Array, Ms: Array, iters: Any) -> int:  # fmt: skip  # pragma: no cover
    nb, n = M.shape[0], M.shape[1]
    Mb, W = np.empty_like(M), np.empty((4, n, n))
    jsave = 0
    for k in range(1, steps + 1):
        big = 0.0
        for b in range(nb):
            for i in range(n):
                for j in range(n):
                    big = max(big, abs(M[b, i, j]))
        tol = 4.0 * _EPS * max(big, 1e-300)
        Mb[:] = M
        it = 0
        while True:
            diff = _midpoint_sweep(M, Mb, Wl, 0.5 * h, W)
            it += 1
            if diff <= tol:
                break
            if it >= maxiter or not math.isfinite(diff):
                return k
        iters[k - 1] = it
        for b in range(nb):
            _midpoint_update(Q[b], M[b], Mb[b], Wl[b], h, W)
        if k % save_every == 0:
            Qs[jsave], Ms[jsave] = Q, M
            jsave += 1
    return 0


def run_midpoint(
    Q: Array, M: Array, lam: Array, h: float, steps: int, save_every: int, maxiter: int = 100
) -> tuple[Array, Array, NDArray[np.int64], int]:
    r"""``steps`` steps of the implicit midpoint rule (:class:`symrb.base_steps.MidpointStep`)
    of a batch, compiled.

    Parameters
    ----------
    Q, M : ndarray, shape (B, n, n)
        The attitudes and (skew) body momenta.
    lam : ndarray, shape (B, n)
        The diagonals of :math:`\Lambda`.
    h : float
        The step.
    steps, save_every : int
        Steps to take; the states after every ``save_every``-th are saved.
    maxiter : int, optional
        The most fixed-point iterations of a step.

    Returns
    -------
    Qs, Ms : ndarray, shape (steps // save_every, B, n, n)
        The saved states (NaN from a failed step on).
    iters : ndarray of int, shape (steps,)
        The fixed-point iterations of each step.
    fail : int
        0, or the step whose iteration did not converge.

    Raises
    ------
    RuntimeError
        Without numba.

    Examples
    --------
    >>> import numpy as np
    >>> from symrb import _compiled_stages
    >>> M = np.array([[[0.0, -1.5, 1.0], [1.5, 0.0, -0.5], [-1.0, 0.5, 0.0]]])
    >>> if _compiled_stages.AVAILABLE:
    ...     Qs, Ms, it, fail = _compiled_stages.run_midpoint(np.eye(3)[None], M, np.ones((1, 3)),
    ...                                                 0.1, 4, 2)
    ...     print(Qs.shape, fail, bool(np.abs(Ms[-1] - M).max() < 1e-15))  # lam = 1: M fixed
    ... else:
    ...     print((2, 1, 3, 3), 0, True)
    (2, 1, 3, 3) 0 True
    """
    _need()
    f = np.ascontiguousarray
    B, n = M.shape[0], M.shape[-1]
    lam = f(lam, dtype=float)
    Wl = 1.0 / (lam[:, :, None] + lam[:, None, :])
    K = steps // save_every
    Qs, Ms = np.full((K, B, n, n), np.nan), np.full((K, B, n, n), np.nan)
    iters = np.zeros(steps, dtype=np.int64)
    fail = _midpoint_loop(np.array(Q, dtype=float), np.array(M, dtype=float), Wl, float(h),
                          int(steps), int(save_every), int(maxiter), Qs, Ms, iters)  # fmt: skip
    return Qs, Ms, iters, int(fail)
