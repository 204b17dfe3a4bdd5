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

from ._compiled_n import (
    _EPS,
    AVAILABLE,
    _expm_into,
    _jit,
    _mm,
    _mtm,
    _need,
    _saves,
    _skew_into,
    _solve,
)
from ._validate import Array

__all__ = ["AVAILABLE", "run_rkmk4", "run_midpoint"]


def _vee(A: Array) -> Array:
    """(B, 3, 3) -> the (B, 3) components (A_32, A_13, A_21)."""
    return np.ascontiguousarray(
        np.stack([A[:, 2, 1], A[:, 0, 2], A[:, 1, 0]], axis=-1), dtype=float
    )


def _inertia_weights(lam: Array) -> Array:
    """(B, n) diagonals of Lambda -> the (B, n, n) weights 1 / (lam_i + lam_j) of J^{-1}."""
    lam = np.ascontiguousarray(lam, dtype=float)
    return 1.0 / (lam[:, :, None] + lam[:, None, :])


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
    Wl, (Qs, Ms) = _inertia_weights(lam), _saves(M, steps, save_every)
    if n == 3:
        fail = _rkmk4_loop3(f(Q.reshape(B, 9), dtype=float), _vee(M), _vee(Wl), float(h),
                            int(steps), int(save_every), Qs, Ms)  # fmt: skip
    else:
        fail = _rkmk4_loop(f(Q, dtype=float), f(M, dtype=float), Wl, float(h), int(steps),
                           int(save_every), Qs, Ms)  # fmt: skip
    return Qs, Ms, int(fail)


# ---------------------------------------------------------------------------------------------
# n = 3: the same steps on vectors (hat(a) hat(b) - hat(b) hat(a) = hat(a x b), Rodrigues)


@_jit
def _cross(
    a0: float, a1: float, a2: float, b0: float, b1: float, b2: float
) -> Any:  # pragma: no cover
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@_jit
def _rodrigues(t0: float, t1: float, t2: float) -> Any:  # pragma: no cover - compiled
    """(a, b) with exp(hat(t)) = I + a hat(t) + b hat(t)^2 (series below |t| = 1e-4)."""
    p2 = t0 * t0 + t1 * t1 + t2 * t2
    if p2 < 1e-8:
        return 1.0 - p2 / 6.0, 0.5 - p2 / 24.0
    p = math.sqrt(p2)
    s = math.sin(0.5 * p) / p
    return math.sin(p) / p, 2.0 * s * s


@_jit
def _rotate_t(
    t0: float, t1: float, t2: float, m0: float, m1: float, m2: float
) -> Any:  # pragma: no cover
    """exp(hat(t))^T m = m - a t x m + b t x (t x m)."""
    a, b = _rodrigues(t0, t1, t2)
    c0, c1, c2 = _cross(t0, t1, t2, m0, m1, m2)
    d0, d1, d2 = _cross(t0, t1, t2, c0, c1, c2)
    return m0 - a * c0 + b * d0, m1 - a * c1 + b * d1, m2 - a * c2 + b * d2


@_jit
def _rkmk4_F3(t: Any, m: Any, w: Any) -> Any:  # pragma: no cover - compiled
    """F(theta) of RKMK4 on vectors: om = J^{-1}(g^T m), om + c/2 + theta x c / 12, c = theta x om."""
    g0, g1, g2 = _rotate_t(t[0], t[1], t[2], m[0], m[1], m[2])
    o0, o1, o2 = g0 * w[0], g1 * w[1], g2 * w[2]
    c0, c1, c2 = _cross(t[0], t[1], t[2], o0, o1, o2)
    d0, d1, d2 = _cross(t[0], t[1], t[2], c0, c1, c2)
    return o0 + 0.5 * c0 + d0 / 12.0, o1 + 0.5 * c1 + d1 / 12.0, o2 + 0.5 * c2 + d2 / 12.0


@_jit
def _times3(q: Array, g: Array) -> None:  # pragma: no cover - compiled
    """q <- q g, both (9,) row-major 3x3, in place."""
    for i in range(3):
        r0, r1, r2 = q[3 * i], q[3 * i + 1], q[3 * i + 2]
        for j in range(3):
            q[3 * i + j] = r0 * g[j] + r1 * g[3 + j] + r2 * g[6 + j]


@_jit
def _exp3(
    g: Array, t0: float, t1: float, t2: float, a: float, b: float
) -> None:  # pragma: no cover
    """g (9,) = I + a hat(t) + b hat(t)^2 (row-major 3x3; hat(t)^2 = t t^T - |t|^2 I)."""
    s = t0 * t0 + t1 * t1 + t2 * t2
    b0, b1, b2 = b * t0, b * t1, b * t2
    g[0], g[4], g[8] = 1.0 + (b0 * t0 - b * s), 1.0 + (b1 * t1 - b * s), 1.0 + (b2 * t2 - b * s)
    g[1], g[3] = b0 * t1 - a * t2, b1 * t0 + a * t2
    g[2], g[6] = b0 * t2 + a * t1, b2 * t0 - a * t1
    g[5], g[7] = b1 * t2 - a * t0, b2 * t1 + a * t0


@_jit
def _save3(Qs: Array, Ms: Array, j: int, b: int, q: Array, m: Array) -> None:  # pragma: no cover
    for i in range(3):
        for k in range(3):
            Qs[j, b, i, k] = q[3 * i + k]
    Ms[j, b, 0, 0], Ms[j, b, 1, 1], Ms[j, b, 2, 2] = 0.0, 0.0, 0.0
    Ms[j, b, 2, 1], Ms[j, b, 0, 2], Ms[j, b, 1, 0] = m[0], m[1], m[2]
    Ms[j, b, 1, 2], Ms[j, b, 2, 0], Ms[j, b, 0, 1] = -m[0], -m[1], -m[2]


@_jit
def _rkmk4_loop3(q0: Array, m0: Array, w: Array, h: float, steps: int, save_every: int,
                 Qs: Array, Ms: Array) -> int:  # fmt: skip  # pragma: no cover - compiled
    k = np.empty((4, 3))
    q, m, g = np.empty(9), np.empty(3), np.empty(9)
    for b in range(m0.shape[0]):
        q[:], m[:] = q0[b], m0[b]
        wb = (w[b, 0], w[b, 1], w[b, 2])
        jsave = 0
        for s in range(1, steps + 1):
            for i in range(3):
                k[0, i] = h * (m[i] * wb[i])
            for st in range(1, 4):
                a = 1.0 if st == 3 else 0.5
                th = (a * k[st - 1, 0], a * k[st - 1, 1], a * k[st - 1, 2])
                f0, f1, f2 = _rkmk4_F3(th, (m[0], m[1], m[2]), wb)
                k[st, 0], k[st, 1], k[st, 2] = h * f0, h * f1, h * f2
            t0 = (k[0, 0] + 2.0 * k[1, 0] + 2.0 * k[2, 0] + k[3, 0]) / 6.0
            t1 = (k[0, 1] + 2.0 * k[1, 1] + 2.0 * k[2, 1] + k[3, 1]) / 6.0
            t2 = (k[0, 2] + 2.0 * k[1, 2] + 2.0 * k[2, 2] + k[3, 2]) / 6.0
            if not (math.isfinite(t0) and math.isfinite(t1) and math.isfinite(t2)):
                return s
            a, bb = _rodrigues(t0, t1, t2)
            _exp3(g, t0, t1, t2, a, bb)
            _times3(q, g)
            m[0], m[1], m[2] = _rotate_t(t0, t1, t2, m[0], m[1], m[2])
            if s % save_every == 0:
                _save3(Qs, Ms, jsave, b, q, m)
                jsave += 1
    return 0


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


@_jit
def _midpoint_loop3(q: Array, m: Array, w: Array, h: float, steps: int, save_every: int,
                    maxiter: int, Qs: Array, Ms: Array, iters: Any) -> int:  # fmt: skip  # pragma: no cover
    """The n = 3 midpoint loop on vectors: mb <- m + (h/2) mb x (w o mb); m <- 2 mb - m,
    q <- q cay(h w o mb) (the fixed point over the whole batch, as the NumPy step)."""
    nb = m.shape[0]
    mb, g = np.empty((nb, 3)), np.empty(9)
    c = 0.5 * h
    jsave = 0
    for k in range(1, steps + 1):
        big = 0.0
        for b in range(nb):
            big = max(big, abs(m[b, 0]), abs(m[b, 1]), abs(m[b, 2]))
        tol = 4.0 * _EPS * max(big, 1e-300)
        mb[:] = m
        it = 0
        while True:
            diff = 0.0
            finite = True
            for b in range(nb):
                x0, x1, x2 = mb[b, 0], mb[b, 1], mb[b, 2]
                p0, p1, p2 = _cross(x0, x1, x2, x0 * w[b, 0], x1 * w[b, 1], x2 * w[b, 2])
                n0, n1, n2 = m[b, 0] + c * p0, m[b, 1] + c * p1, m[b, 2] + c * p2
                d = max(abs(n0 - x0), abs(n1 - x1), abs(n2 - x2))
                finite = finite and math.isfinite(d)
                diff = max(diff, d)
                mb[b, 0], mb[b, 1], mb[b, 2] = n0, n1, n2
            it += 1
            if finite and diff <= tol:
                break
            if it >= maxiter or not finite:
                return k
        iters[k - 1] = it
        for b in range(nb):
            v0, v1, v2 = (
                0.5 * h * (mb[b, 0] * w[b, 0]),
                0.5 * h * (mb[b, 1] * w[b, 1]),
                0.5 * h * (mb[b, 2] * w[b, 2]),
            )
            f = 2.0 / (1.0 + v0 * v0 + v1 * v1 + v2 * v2)  # cay = I + f (hat(v) + hat(v)^2)
            _exp3(g, v0, v1, v2, f, f)
            _times3(q[b], g)
            for i in range(3):
                m[b, i] = 2.0 * mb[b, i] - m[b, i]
            if k % save_every == 0:
                _save3(Qs, Ms, jsave, b, q[b], m[b])
        if k % save_every == 0:
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
    B, n = M.shape[0], M.shape[-1]
    Wl, (Qs, Ms) = _inertia_weights(lam), _saves(M, steps, save_every)
    iters = np.zeros(steps, dtype=np.int64)
    if n == 3:
        fail = _midpoint_loop3(np.array(Q.reshape(B, 9), dtype=float), _vee(M), _vee(Wl),
                               float(h), int(steps), int(save_every), int(maxiter), Qs, Ms,
                               iters)  # fmt: skip
    else:
        fail = _midpoint_loop(np.array(Q, dtype=float), np.array(M, dtype=float), Wl, float(h),
                              int(steps), int(save_every), int(maxiter), Qs, Ms, iters)  # fmt: skip
    return Qs, Ms, iters, int(fail)
