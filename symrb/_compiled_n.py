r"""Optional compiled loops at any n: the general-n Moser-Veselov step, and the dense kernels
(products, LU, the matrix exponential) of :mod:`symrb._compiled_stages`.

``numba`` is not a run-time dependency: :data:`AVAILABLE` is False without it, and the callers
(:func:`symrb.engine.mv_flow`, :func:`symrb.compose.composed_rigid_body_flow`,
:func:`symrb.compose.rkmk4_rigid_body_flow`, :func:`symrb.compose.midpoint_rigid_body_flow`)
then run their NumPy paths, which stay the reference.  With it, each function here is a module-level ``numba.njit(cache=True)`` function
(compiled on its first call, then loaded from numba's cache in a new process; no fast-math), and
each loop reproduces its NumPy path operation for operation in plain loops (matrix products,
LU with partial pivoting), so the results agree with it to rounding:

* :func:`run_mv_n` continues :class:`symrb.engine.MVStepper`'s general-n step (the fixed point
  :math:`X \leftarrow X - W\circ G(X)/2` and Newton with the Lyapunov solve on the skew unknowns,
  the warm start extrapolated from the last two steps, the increment update
  :math:`Q + QD`, :math:`M + (MD - (MD)^T) + (D^TMD - (D^TMD)^T)/2`, :math:`D = 2(I - X)^{-1}X`).
  A body whose iteration fails is reported; the caller redoes the run on the NumPy path (the
  Riccati fallback and the fold diagnosis).
* :func:`run_composed_n` is the same step in a composition of sub-steps
  :math:`\gamma_1 h, \dots, \gamma_s h` (:func:`symrb.compose.composed_rigid_body_flow` at
  n != 3), each sub-step warm started from the same sub-step of the step before.
* :func:`expm` is a scaling and squaring Pade exponential (Higham 2005: the orders 3 to 13 and
  the thresholds :math:`\theta_m` of his Table 2.3 on the 1-norm of the argument), the one
  RKMK4's compiled stages use.

Examples
--------
>>> from symrb import _compiled_n
>>> isinstance(_compiled_n.AVAILABLE, bool)
True
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray

from ._validate import Array

try:  # pragma: no cover - depends on the environment
    import numba

    AVAILABLE = True
except ImportError:  # pragma: no cover
    numba = None  # type: ignore[assignment]
    AVAILABLE = False

__all__ = ["AVAILABLE", "expm", "run_mv_n", "continue_mv_n", "run_composed_n"]

_F = TypeVar("_F", bound=Callable[..., Any])


def _jit(f: _F) -> _F:
    """numba.njit(cache=True) (compiled on the first call), or ``f`` itself without numba."""
    return numba.njit(cache=True)(f) if AVAILABLE else f  # type: ignore[return-value]


_EPS = 2.220446049250313e-16
_NEWTON_DX = 1e-9  # symrb.engine._NEWTON_DX
_MAXITER = 12  # symrb.engine._MAXITER
_MAXITER_FP = 60  # symrb.engine._MAXITER_FP
_KRON_MAX_N = 6  # symrb.engine._KRON_MAX_N: Newton (auto) up to this n
_KRON_TOP_N = 12  # the Newton fallback of the fixed point up to this n

# Pade coefficients b_0..b_m of exp (Higham 2005) and the largest 1-norm each order takes
_PADE3 = (120.0, 60.0, 12.0, 1.0)
_PADE5 = (30240.0, 15120.0, 3360.0, 420.0, 30.0, 1.0)
_PADE7 = (17297280.0, 8648640.0, 1995840.0, 277200.0, 25200.0, 1512.0, 56.0, 1.0)
_PADE9 = (17643225600.0, 8821612800.0, 2075673600.0, 302702400.0, 30270240.0, 2162160.0,
          110880.0, 3960.0, 90.0, 1.0)  # fmt: skip
_PADE13 = (64764752532480000.0, 32382376266240000.0, 7771770303897600.0, 1187353796428800.0,
           129060195264000.0, 10559470521600.0, 670442572800.0, 33522128640.0, 1323241920.0,
           40840800.0, 960960.0, 16380.0, 182.0, 1.0)  # fmt: skip
_THETA = (1.495585217958292e-2, 2.539398330063230e-1, 9.504178996162932e-1, 2.097847961257068,
          5.371920351148152)  # fmt: skip


# ---------------------------------------------------------------------------------------------
# dense kernels (row-major loops whose inner loop is an axpy, which vectorises without fast-math)


@_jit
def _mm(A: Array, B: Array, C: Array) -> None:  # pragma: no cover - compiled
    """C = A @ B."""
    n, p, m = A.shape[0], A.shape[1], B.shape[1]
    for i in range(n):
        for j in range(m):
            C[i, j] = 0.0
        for k in range(p):
            a = A[i, k]
            for j in range(m):
                C[i, j] += a * B[k, j]


@_jit
def _mtm(A: Array, B: Array, C: Array) -> None:  # pragma: no cover - compiled
    """C = A^T @ B."""
    n, p, m = A.shape[1], A.shape[0], B.shape[1]
    for i in range(n):
        for j in range(m):
            C[i, j] = 0.0
    for k in range(p):
        for i in range(n):
            a = A[k, i]
            for j in range(m):
                C[i, j] += a * B[k, j]


@_jit
def _solve(A: Array, R: Array, LU: Array, X: Array) -> bool:  # pragma: no cover - compiled
    """X = A^{-1} R by LU with partial pivoting (LU a work array); False if A is singular."""
    n, m = A.shape[0], R.shape[1]
    LU[:, :] = A
    X[:, :] = R
    for k in range(n):
        p, big = k, abs(LU[k, k])
        for i in range(k + 1, n):
            if abs(LU[i, k]) > big:
                p, big = i, abs(LU[i, k])
        if p != k:
            for j in range(n):
                LU[k, j], LU[p, j] = LU[p, j], LU[k, j]
            for j in range(m):
                X[k, j], X[p, j] = X[p, j], X[k, j]
        d = LU[k, k]
        if d == 0.0 or not math.isfinite(d):
            return False
        for i in range(k + 1, n):
            f = LU[i, k] / d
            for j in range(k + 1, n):
                LU[i, j] -= f * LU[k, j]
            for j in range(m):
                X[i, j] -= f * X[k, j]
    for k in range(n - 1, -1, -1):
        d = LU[k, k]
        for j in range(m):
            X[k, j] /= d
        for i in range(k):
            f = LU[i, k]
            for j in range(m):
                X[i, j] -= f * X[k, j]
    return True


@_jit
def _skew_into(A: Array, out: Array) -> None:  # pragma: no cover - compiled
    """out = (A - A^T) / 2 (out may not be A)."""
    n = A.shape[0]
    for i in range(n):
        for j in range(n):
            out[i, j] = 0.5 * (A[i, j] - A[j, i])


# ---------------------------------------------------------------------------------------------
# the matrix exponential


@_jit
def _pade_low(A: Array, b: Any, P: Array, U: Array, V: Array, T: Array) -> None:  # pragma: no cover
    """U, V of the Pade approximant of order len(b) - 1 in (3, 5, 7, 9); P (5, n, n) holds
    I, A^2, A^4, ... and T (work)."""
    n = A.shape[0]
    half = (len(b) - 1) // 2
    for j in range(1, half + 1):
        if j == 1:
            _mm(A, A, P[1])
        else:
            _mm(P[j - 1], P[1], P[j])
    for i in range(n):
        for j in range(n):
            u = 0.0
            v = 0.0
            for k in range(half + 1):
                u += b[2 * k + 1] * P[k, i, j]
                v += b[2 * k] * P[k, i, j]
            T[i, j] = u
            V[i, j] = v
    _mm(A, T, U)


@_jit
def _pade13(A: Array, P: Array, U: Array, V: Array, T: Array) -> None:  # pragma: no cover
    """U, V of the Pade approximant of order 13 (Higham 2005); P (5, n, n) work, P[0] = I."""
    b = _PADE13
    _mm(A, A, P[1])
    _mm(P[1], P[1], P[2])
    _mm(P[2], P[1], P[3])
    n = A.shape[0]
    for i in range(n):
        for j in range(n):
            T[i, j] = b[13] * P[3, i, j] + b[11] * P[2, i, j] + b[9] * P[1, i, j]
    _mm(P[3], T, P[4])
    for i in range(n):
        for j in range(n):
            T[i, j] = (P[4, i, j] + b[7] * P[3, i, j] + b[5] * P[2, i, j] + b[3] * P[1, i, j]
                       + b[1] * P[0, i, j])  # fmt: skip
    _mm(A, T, U)
    for i in range(n):
        for j in range(n):
            T[i, j] = b[12] * P[3, i, j] + b[10] * P[2, i, j] + b[8] * P[1, i, j]
    _mm(P[3], T, V)
    for i in range(n):
        for j in range(n):
            V[i, j] += b[6] * P[3, i, j] + b[4] * P[2, i, j] + b[2] * P[1, i, j] + b[0] * P[0, i, j]


@_jit
def _expm_into(A: Array, out: Array, W: Array) -> bool:  # pragma: no cover - compiled
    """out = exp(A) by scaling and squaring with Pade (Higham 2005); W (10, n, n) work."""
    n = A.shape[0]
    norm = 0.0
    for j in range(n):
        s = 0.0
        for i in range(n):
            s += abs(A[i, j])
        norm = max(norm, s)
    P, U, V, S, T, LU = W[0:5], W[5], W[6], W[7], W[8], W[9]
    for i in range(n):
        for j in range(n):
            P[0, i, j] = 1.0 if i == j else 0.0
    squarings = 0
    if norm <= _THETA[0]:
        _pade_low(A, _PADE3, P, U, V, T)
    elif norm <= _THETA[1]:
        _pade_low(A, _PADE5, P, U, V, T)
    elif norm <= _THETA[2]:
        _pade_low(A, _PADE7, P, U, V, T)
    elif norm <= _THETA[3]:
        _pade_low(A, _PADE9, P, U, V, T)
    else:
        if not math.isfinite(norm):
            return False
        squarings = max(0, int(math.ceil(math.log2(norm / _THETA[4]))))
        scale = 0.5**squarings
        for i in range(n):
            for j in range(n):
                S[i, j] = scale * A[i, j]
        _pade13(S, P, U, V, T)
    for i in range(n):
        for j in range(n):
            S[i, j] = V[i, j] - U[i, j]
            T[i, j] = V[i, j] + U[i, j]
    if not _solve(S, T, LU, out):
        return False
    for _ in range(squarings):
        _mm(out, out, S)
        out[:, :] = S
    return True


@_jit
def _expm_batch(A: Array, out: Array) -> bool:  # pragma: no cover - compiled
    n = A.shape[-1]
    W = np.empty((10, n, n))
    ok = True
    for b in range(A.shape[0]):
        ok = _expm_into(A[b], out[b], W) and ok
    return ok


def expm(A: Array) -> Array:
    """exp(A) of a batch of square matrices by the compiled scaling-and-squaring Pade method.

    Parameters
    ----------
    A : ndarray, shape (..., n, n)

    Returns
    -------
    ndarray, shape (..., n, n)
        NaN where ``A`` is not finite.

    Raises
    ------
    RuntimeError
        Without numba.

    Examples
    --------
    >>> import numpy as np
    >>> from symrb import _compiled_n
    >>> A = np.array([[0.0, -0.3], [0.3, 0.0]])
    >>> g = _compiled_n.expm(A) if _compiled_n.AVAILABLE else np.array(
    ...     [[np.cos(0.3), -np.sin(0.3)], [np.sin(0.3), np.cos(0.3)]])
    >>> bool(abs(g[1, 0] - np.sin(0.3)) < 1e-15)
    True
    """
    _need()
    a = np.ascontiguousarray(A, dtype=float)
    flat = a.reshape((-1,) + a.shape[-2:])
    out = np.full(flat.shape, np.nan)
    _expm_batch(flat, out)
    return out.reshape(a.shape)


def _need() -> None:
    if not AVAILABLE:
        raise RuntimeError("numba is not installed (pip install numba)")


def _saves(M: Array, steps: int, save_every: int, k0: int = 0) -> tuple[Array, Array]:
    """The arrays ``Qs, Ms`` (K, B, n, n), NaN, that a compiled loop of the batch ``M``
    (B, n, n) fills: K the steps among k0 + 1, ..., k0 + steps whose number is a multiple of
    ``save_every``."""
    B, n = M.shape[0], M.shape[-1]
    K = (k0 + steps) // save_every - k0 // save_every
    return np.full((K, B, n, n), np.nan), np.full((K, B, n, n), np.nan)


# ---------------------------------------------------------------------------------------------
# the general-n Moser-Veselov step (symrb.engine: _G, _fixed_point_n, _newton_n, the update)


@_jit
def _G_into(
    X: Array, B: Array, lam: Array, BX: Array, XBX: Array, G: Array
) -> None:  # pragma: no cover
    """G = 2J(X) - B - BX + XB + XBX (symrb.engine._G, XB = (BX)^T)."""
    _mm(B, X, BX)
    _mm(X, BX, XBX)
    n = X.shape[0]
    for i in range(n):
        for j in range(n):
            G[i, j] = (2.0 * (lam[i] * X[i, j] + X[i, j] * lam[j]) - B[i, j] - BX[i, j]
                       + BX[j, i] + XBX[i, j])  # fmt: skip


@_jit
def _fixed_point(X: Array, B: Array, lam: Array, Wh: Array, W: Array) -> int:  # pragma: no cover
    """X <- X - Wh o G(X) with symrb.engine._fixed_point_n's stopping rule; the sweeps, negative
    if not converged."""
    n = X.shape[0]
    prev = np.inf
    for it in range(1, _MAXITER_FP + 1):
        _G_into(X, B, lam, W[0], W[1], W[2])
        err = 0.0
        big = 0.0
        finite = True
        for i in range(n):
            for j in range(n):
                d = Wh[i, j] * W[2, i, j]
                X[i, j] = X[i, j] - d
                finite = finite and math.isfinite(d)
                err = max(err, abs(d))
                big = max(big, abs(X[i, j]))
        floor = 8.0 * _EPS * big
        if finite and (err <= floor or (err <= 8.0 * floor and err >= 0.9 * prev)):
            return it
        if not (finite and err < 1e3):
            return -it
        prev = err
    return -_MAXITER_FP


@_jit
def _newton(X: Array, B: Array, lam: Array, W: Array, iu: Any, ju: Any, K: Array, LU: Array,
            y: Array, dy: Array) -> int:  # fmt: skip  # pragma: no cover
    """Newton with the Lyapunov solve on the skew unknowns (symrb.engine._newton_n); the sweeps,
    negative if not converged."""
    n, m = X.shape[0], iu.shape[0]
    G, P = W[2], W[3]
    for it in range(1, _MAXITER + 1):
        _G_into(X, B, lam, W[0], W[1], G)
        _mm(X, B, P)
        for i in range(n):
            for j in range(n):
                P[i, j] = (2.0 * lam[i] * (1.0 if i == j else 0.0) - B[i, j]) + P[i, j]
        for r in range(m):
            i, j = iu[r], ju[r]
            for c in range(m):
                a, b = iu[c], ju[c]
                K[r, c] = ((P[i, a] * (j == b) - P[i, b] * (j == a)) + P[j, b] * (i == a)
                           - P[j, a] * (i == b))  # fmt: skip
            y[r, 0] = -G[i, j]
        if not _solve(K, y, LU, dy):
            return -it
        err = 0.0
        finite = True
        for r in range(m):
            d = dy[r, 0]
            X[iu[r], ju[r]] += d
            X[ju[r], iu[r]] += -d
            finite = finite and math.isfinite(d)
            err = max(err, abs(d))
        if finite and err <= _NEWTON_DX:
            return it
        if not (finite and err < 1e3):
            return -it
    return -_MAXITER


@_jit
def _mv_solve(X: Array, X0: Array, B: Array, lam: Array, Wh: Array, W: Array, iu: Any, ju: Any,
              K: Array, LU: Array, y: Array, dy: Array) -> int:  # fmt: skip  # pragma: no cover
    """MVStepper's "auto" solver: Newton for 3 < n <= 6, else the fixed point with Newton for
    the items it leaves (n <= 12); the sweeps, negative if not converged."""
    n = X.shape[0]
    X[:, :] = X0
    if 3 < n <= _KRON_MAX_N:
        return _newton(X, B, lam, W, iu, ju, K, LU, y, dy)
    it = _fixed_point(X, B, lam, Wh, W)
    if it > 0 or not 3 < n <= _KRON_TOP_N:
        return it
    X[:, :] = X0
    it2 = _newton(X, B, lam, W, iu, ju, K, LU, y, dy)
    return -it + it2 if it2 > 0 else it - _MAXITER


@_jit
def _mv_update(Q: Array, M: Array, X: Array, W: Array) -> bool:  # pragma: no cover - compiled
    """D = 2 (I - X)^{-1} X; Q += QD; M += (MD - (MD)^T) + (D^TMD - (D^TMD)^T)/2."""
    n = X.shape[0]
    A, D, MD, DMD, LU = W[0], W[1], W[2], W[3], W[4]
    for i in range(n):
        for j in range(n):
            A[i, j] = (1.0 if i == j else 0.0) - X[i, j]
    if not _solve(A, X, LU, D):
        return False
    for i in range(n):
        for j in range(n):
            D[i, j] = 2.0 * D[i, j]
    _mm(M, D, MD)
    _mtm(D, MD, DMD)
    _mm(Q, D, A)
    for i in range(n):
        for j in range(n):
            Q[i, j] = Q[i, j] + A[i, j]
    for i in range(n):
        for j in range(n):
            A[i, j] = (MD[i, j] - MD[j, i]) + 0.5 * (DMD[i, j] - DMD[j, i])
    for i in range(n):
        for j in range(n):
            M[i, j] = M[i, j] + A[i, j]
    return True


@_jit
def _mv_work(n: int) -> Any:  # pragma: no cover - compiled
    """The work arrays of a general-n Moser-Veselov loop: the skew index pairs ``iu, ju``,
    Newton's ``K, LU, y, dy``, ``W`` (5, n, n), the state ``Q, M``, ``Wh`` and ``V`` (3, n, n)
    (:func:`_mv_step`'s ``B, X0, X``)."""
    iu, ju = np.triu_indices(n, 1)
    m = iu.shape[0]
    K, LUk, y, dy = np.empty((m, m)), np.empty((m, m)), np.empty((m, 1)), np.empty((m, 1))
    W, V = np.empty((5, n, n)), np.empty((3, n, n))
    Q, M, Wh = np.empty((n, n)), np.empty((n, n)), np.empty((n, n))
    return iu, ju, K, LUk, y, dy, W, Q, M, Wh, V


@_jit
def _wh_into(lam: Array, Wh: Array) -> None:  # pragma: no cover - compiled
    """Wh = 1 / (2 (lam_i + lam_j)), the fixed point's weights of one body."""
    n = lam.shape[0]
    for i in range(n):
        for j in range(n):
            Wh[i, j] = 0.5 / (lam[i] + lam[j])


@_jit
def _mv_step(Q: Array, M: Array, w: Array, wp: Array, prev: bool, h: float, lam: Array,
             Wh: Array, W: Array, V: Array, iu: Any, ju: Any, K: Array, LU: Array, y: Array,
             dy: Array) -> int:  # fmt: skip  # pragma: no cover - compiled
    """One step h of (Q, M) in place, warm started from w = X/h (extrapolated with the one
    before, wp, when ``prev``); w, wp move on.  The sweeps, negative if the step failed."""
    n = Q.shape[0]
    B, X0, X = V[0], V[1], V[2]
    for i in range(n):
        for j in range(n):
            B[i, j] = h * M[i, j]
            X0[i, j] = h * (2.0 * w[i, j] - wp[i, j]) if prev else h * w[i, j]
    it = _mv_solve(X, X0, B, lam, Wh, W, iu, ju, K, LU, y, dy)
    if it < 0 or not _mv_update(Q, M, X, W):
        return min(it, -1)
    wp[:, :] = w
    for i in range(n):
        for j in range(n):
            w[i, j] = X[i, j] / h
    return it


@_jit
def _mv_loop(Q0: Array, M0: Array, w0: Array, wp0: Array, has_prev: bool, h: float, lam: Array,
             steps: int, k0: int, save_every: int, Qs: Array, Ms: Array, fail: Any,
             iters: Any) -> None:  # fmt: skip  # pragma: no cover - compiled
    nb, n = M0.shape[0], M0.shape[1]
    iu, ju, K, LUk, y, dy, W, Q, M, Wh, V = _mv_work(n)
    w, wp = np.empty((n, n)), np.empty((n, n))
    for b in range(nb):
        Q[:, :], M[:, :], w[:, :], wp[:, :] = Q0[b], M0[b], w0[b], wp0[b]
        prev = has_prev
        _wh_into(lam[b], Wh)
        jsave = 0
        for k in range(1, steps + 1):
            it = _mv_step(Q, M, w, wp, prev, h, lam[b], Wh, W, V, iu, ju, K, LUk, y, dy)
            if it < 0:
                fail[b] = k0 + k
                break
            iters[k - 1] = max(iters[k - 1], it)
            prev = True
            if (k0 + k) % save_every == 0:
                Qs[jsave, b], Ms[jsave, b] = Q, M
                jsave += 1


def run_mv_n(
    Q: Array,
    M: Array,
    w: Array,
    w_prev: Array | None,
    h: float,
    lam: Array,
    steps: int,
    save_every: int,
    k0: int = 0,
) -> tuple[Array, Array, NDArray[np.int64], NDArray[np.int64]]:
    r"""Continue ``steps`` general-n Moser-Veselov steps of a batch (compiled loop).

    Parameters
    ----------
    Q, M : ndarray, shape (B, n, n)
        The attitudes and (skew) body momenta after step ``k0``.
    w, w_prev : ndarray, shape (B, n, n)
        The warm start :math:`X/h` of the last step and, when the step before it had the same
        ``h``, of that one (None otherwise): :class:`symrb.engine.MVStepper`'s ``_w`` and
        ``_w_prev``.
    h : float
        The step.
    lam : ndarray, shape (B, n)
        The diagonals of :math:`\Lambda`.
    steps, save_every, k0 : int
        Steps to take, numbered k0 + 1, ..., k0 + steps; the states after the steps whose number
        is a multiple of ``save_every`` are saved.

    Returns
    -------
    Qs, Ms : ndarray, shape (K, B, n, n)
        The saved states (NaN after a failure).
    fail : ndarray of int, shape (B,)
        0, or the step whose iteration failed (that body's saves stop before it).
    iters : ndarray of int, shape (steps,)
        The largest number of sweeps over the bodies at each step.

    Raises
    ------
    RuntimeError
        Without numba.

    Examples
    --------
    >>> import numpy as np
    >>> from symrb import _compiled_n
    >>> z = np.zeros((1, 4, 4))
    >>> if _compiled_n.AVAILABLE:
    ...     Qs, Ms, fail, it = _compiled_n.run_mv_n(np.eye(4)[None], z, z, None, 0.1,
    ...                                             np.ones((1, 4)), 4, 2)
    ...     print(Qs.shape, int(fail[0]))
    ... else:
    ...     print((2, 1, 4, 4), 0)
    (2, 1, 4, 4) 0
    """
    _need()
    f = np.ascontiguousarray
    Qs, Ms = _saves(M, steps, save_every, k0)
    fail = np.zeros(M.shape[0], dtype=np.int64)
    iters = np.zeros(steps, dtype=np.int64)
    wp = w if w_prev is None else w_prev
    _mv_loop(f(Q, dtype=float), f(M, dtype=float), f(w, dtype=float), f(wp, dtype=float),
             w_prev is not None, float(h), f(lam, dtype=float), int(steps), int(k0),
             int(save_every), Qs, Ms, fail, iters)  # fmt: skip
    return Qs, Ms, fail, iters


def continue_mv_n(run: Any, h: float) -> bool:
    """Steps 2, 3, ... of a general-n :func:`symrb.engine.mv_flow` run by :func:`run_mv_n`.

    Parameters
    ----------
    run : symrb.engine._FlowRun
        The run after its first step (taken by :class:`symrb.engine.MVStepper`, whose warm
        start the loop continues); its saved states, iteration counts and step are extended.
    h : float
        The step.

    Returns
    -------
    bool
        False (the run unchanged) if an item's iteration failed: the caller redoes the run on
        the NumPy path.
    """
    st, n = run.stepper, run.n
    w_prev = st._w_prev if st._h_prev == (h, h) else None
    Qs, Ms, fail, iters = run_mv_n(run.Qk.reshape(-1, n, n), run.Mk.reshape(-1, n, n), st._w,
                                   w_prev, h, st.lam, run.steps - 1, run.save_every, k0=1)  # fmt: skip
    if fail.any():
        return False
    for j, kj in enumerate(range(max(run.save_every, 2), run.steps + 1, run.save_every)):
        run.ks.append(kj)
        run.Qs.append(Qs[j].reshape(run.shapes[0]))
        run.Ms.append(Ms[j].reshape(run.shapes[1]))
    run.iters[1:] = iters * run.size
    run.k = run.steps
    return True


# ---------------------------------------------------------------------------------------------
# compositions of Moser-Veselov sub-steps (symrb.compose.composed_rigid_body_flow, n != 3)


@_jit
def _mv_comp_loop(Q0: Array, M0: Array, w0: Array, h: float, gammas: Array, lam: Array,
                  steps: int, k0: int, save_every: int, Qs: Array, Ms: Array,
                  fail: Any) -> None:  # fmt: skip  # pragma: no cover - compiled
    nb, n, ng = M0.shape[0], M0.shape[1], gammas.shape[0]
    iu, ju, K, LUk, y, dy, W, Q, M, Wh, V = _mv_work(n)
    w, wp = np.empty((ng, n, n)), np.empty((ng, n, n))
    for b in range(nb):
        Q[:, :], M[:, :] = Q0[b], M0[b]
        for g in range(ng):
            w[g] = w0[g, b]
        prev = False  # w_prev holds the sub-step of the step before the last one
        _wh_into(lam[b], Wh)
        jsave = 0
        for k in range(1, steps + 1):
            for g in range(ng):
                it = _mv_step(Q, M, w[g], wp[g], prev, h * gammas[g], lam[b], Wh, W, V, iu, ju,
                              K, LUk, y, dy)  # fmt: skip
                if it < 0:
                    fail[b] = k0 + k
                    break
            if fail[b]:
                break
            prev = True
            if (k0 + k) % save_every == 0:
                Qs[jsave, b], Ms[jsave, b] = Q, M
                jsave += 1


def run_composed_n(Q: Array, M: Array, w: Array, h: float, gammas: Array, lam: Array, steps: int,
                   save_every: int, k0: int = 0) -> tuple[Array, Array, NDArray[np.int64]]:  # fmt: skip
    r"""Continue ``steps`` steps of a composition of general-n Moser-Veselov sub-steps (compiled).

    A step is the sub-steps :math:`\gamma_1 h, \dots, \gamma_s h` in turn, each one
    :class:`symrb.engine.MVStepper` step (the solver and the update of :func:`run_mv_n`, the same
    arithmetic).  The sub-step :math:`\gamma_i h` is warm started from the same sub-step of the
    previous step, :math:`X_0 = \gamma_i h\,w_i` with :math:`w_i = X/(\gamma_i h)`, and from
    the third step on extrapolated from the last two, :math:`X_0 = \gamma_i h(2w_i - w_i')`.

    Parameters
    ----------
    Q, M : ndarray, shape (B, n, n)
        The attitudes and (skew) body momenta after step ``k0``.
    w : ndarray, shape (S, B, n, n)
        The warm starts :math:`X/(\gamma_i h)` of the sub-steps of step ``k0``.
    h : float
        The step.
    gammas : ndarray, shape (S,)
        The sub-step factors.
    lam : ndarray, shape (B, n)
        The diagonals of :math:`\Lambda`.
    steps, save_every, k0 : int
        Steps to take, numbered k0 + 1, ..., k0 + steps; the states after the steps whose number
        is a multiple of ``save_every`` are saved.

    Returns
    -------
    Qs, Ms : ndarray, shape (K, B, n, n)
        The saved states (NaN after a failure).
    fail : ndarray of int, shape (B,)
        0, or the step in which a sub-step's iteration failed (that body's saves stop before it).

    Raises
    ------
    RuntimeError
        Without numba.

    Examples
    --------
    >>> import numpy as np
    >>> from symrb import _compiled_n
    >>> z = np.zeros((1, 4, 4))
    >>> if _compiled_n.AVAILABLE:
    ...     Qs, Ms, fail = _compiled_n.run_composed_n(np.eye(4)[None], z, np.zeros((3, 1, 4, 4)),
    ...                                               0.1, np.array([1.35, -1.7, 1.35]),
    ...                                               np.ones((1, 4)), 4, 2)
    ...     print(Qs.shape, int(fail[0]))
    ... else:
    ...     print((2, 1, 4, 4), 0)
    (2, 1, 4, 4) 0
    """
    _need()
    f = np.ascontiguousarray
    Qs, Ms = _saves(M, steps, save_every, k0)
    fail = np.zeros(M.shape[0], dtype=np.int64)
    _mv_comp_loop(f(Q, dtype=float), f(M, dtype=float), f(w, dtype=float), float(h),
                  f(gammas, dtype=float), f(lam, dtype=float), int(steps), int(k0),
                  int(save_every), Qs, Ms, fail)  # fmt: skip
    return Qs, Ms, fail
