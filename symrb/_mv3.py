r"""The n = 3 Moser-Veselov engine's scalar machinery (used by :mod:`symrb.engine`).

The solve of the quartic :math:`p(s)` with its branch check and Riccati fallback (floats for one
body, component vectors for a batch), the constants of the preprocessed method, the validation
fast path of :func:`symrb.engine.mv_flow` for one body, and the loop of a composition of
Moser-Veselov sub-steps (:func:`symrb.compose.composed_rigid_body_flow` at n = 3), compiled by
:mod:`symrb._compiled` when numba is installed, on the NumPy kernels otherwise.  The formulas
are in the module docstring of :mod:`symrb.engine`.
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from . import _compiled
from ._generated import discrete_rigid_body as _gen
from ._results import STEP_FAILURES, DiscreteFlowSolution, Trajectory
from ._validate import MAGNITUDE, Array
from .errors import OutOfDomainError
from .solvers import solve_moser_veselov

_MAXITER = 12


def _on_branch(U: Array, lam: Array) -> NDArray[np.bool_]:
    """Every eigenvalue of U Lambda in the open right half-plane (the branch through I)."""
    UL = U * lam[:, None, :]
    S = 0.5 * (UL + np.swapaxes(UL, -1, -2))
    try:
        np.linalg.cholesky(S)  # a positive definite symmetric part suffices
        return np.ones(U.shape[0], dtype=bool)
    except np.linalg.LinAlgError:
        return np.linalg.eigvals(UL).real.min(axis=-1) > 0


_snewton3 = _gen.mv3_cayley_s_newton
_kernel3 = _gen.mv3_cayley_step  # returns increments dm, dQ: the caller adds them


def _step3(s: Any, h: Any, m1: Any, m2: Any, m3: Any, l1: Any, l2: Any, l3: Any, *q: Any) -> Any:
    """mv3_cayley_step with its increments added: (s_next, ds, m_next (3), Q_next (9))."""
    o = _kernel3(s, h, m1, m2, m3, l1, l2, l3, *q)
    return (o[0], o[1], m1 + o[2], m2 + o[3], m3 + o[4], q[0] + o[5], q[1] + o[6], q[2] + o[7],
            q[3] + o[8], q[4] + o[9], q[5] + o[10], q[6] + o[11], q[7] + o[12], q[8] + o[13])  # fmt: skip


# ---------------------------------------------------------------------------------------------
# n = 3


def _cay_inverse3(U: Array) -> Array:
    """The Cayley vector x of U in SO(3): x = vee(U - U^T) / (1 + tr U)."""
    d = 1.0 + np.trace(U, axis1=-2, axis2=-1)
    return (
        np.stack(
            [U[..., 2, 1] - U[..., 1, 2], U[..., 0, 2] - U[..., 2, 0], U[..., 1, 0] - U[..., 0, 1]],
            axis=-1,
        )
        / d[..., None]
    )


def _riccati3_s(b: Array, lam: Array) -> Array:
    """s = b.x from symrb.solve_moser_veselov (raises past the fold); b, lam (k, 3)."""
    B = np.zeros(b.shape[:-1] + (3, 3))
    B[..., 2, 1], B[..., 0, 2], B[..., 1, 0] = b[..., 0], b[..., 1], b[..., 2]
    B = B - np.swapaxes(B, -1, -2)
    x = _cay_inverse3(np.asarray(solve_moser_veselov(B, lam)))
    out: Array = np.einsum("...i,...i->...", b, x)
    return out


_I3: tuple[float, ...] = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)


def _s_cold(h: Any, m: Any, lam: Any) -> Any:
    """The first-order root s = sum b_i^2 / (2 I_i) (x = J^{-1}(b)/2, b = h m)."""
    l1, l2, l3 = lam
    b1, b2, b3 = h * m[0], h * m[1], h * m[2]
    return b1 * b1 / (2.0 * (l2 + l3)) + b2 * b2 / (2.0 * (l1 + l3)) + b3 * b3 / (2.0 * (l1 + l2))


def _branch3(s: float, h: float, m: Any, lam: Any) -> bool:
    """One body: U of the root s on the branch through I (every eigenvalue of U Lambda in the
    open right half-plane), U from the kernel at Q = I (:func:`_branch3_u`)."""
    o = _kernel3(s, h, *m, *lam, *_I3)  # the increments D = U - I (Q = I)
    u = (1.0 + o[5], o[6], o[7], o[8], 1.0 + o[9], o[10], o[11], o[12], 1.0 + o[13])
    return _branch3_u(u, lam)


def _branch3_u(u: Any, lam: Any) -> bool:
    """U (9 floats, row-major) on the branch through I: a Cholesky factorisation of the
    symmetric part of U Lambda in scalars (it exists when that part is positive definite, which
    suffices); when it does not, :func:`_on_branch` decides from the eigenvalues."""
    l1, l2, l3 = lam
    u11, u12, u13, u21, u22, u23, u31, u32, u33 = u
    a11, a22, a33 = u11 * l1, u22 * l2, u33 * l3
    a21, a31, a32 = (
        0.5 * (u21 * l1 + u12 * l2),
        0.5 * (u31 * l1 + u13 * l3),
        0.5 * (u32 * l2 + u23 * l3),
    )
    if a11 > 0.0:
        c11 = math.sqrt(a11)
        c21, c31 = a21 / c11, a31 / c11
        d2 = a22 - c21 * c21
        if d2 > 0.0:
            c32 = (a32 - c31 * c21) / math.sqrt(d2)
            if a33 - c31 * c31 - c32 * c32 > 0.0:
                return True
    U = np.array([[u11, u12, u13], [u21, u22, u23], [u31, u32, u33]])
    return bool(_on_branch(U[None], np.array([[l1, l2, l3]]))[0])


def _first_step_one(s: float, h: float, m: Any, lam: Any, q: Any, tol: float
                    ) -> tuple[tuple[Any, ...], int]:  # fmt: skip
    """The first step of one body with an attitude (floats): :func:`_solve_s3_one` then
    :func:`_step3`, with the branch check made on the step's own U = Q^T Q_1 instead of a
    second kernel call; the outputs of :func:`_step3` and the iterations (Newton's + 1)."""
    s1, ds, it = s, math.inf, 0
    for it in range(1, _MAXITER + 1):  # noqa: B007
        s1, ds = _snewton3(s1, h, *m, *lam)
        if abs(ds) <= tol or not abs(ds) < 1e3:  # converged, or nan or diverging
            break
    if abs(ds) <= tol:
        out = _step3(s1, h, *m, *lam, *q)
        a, b, c, d, e, f, g, k, p = q
        x1, x2, x3, x4, x5, x6, x7, x8, x9 = out[5:]
        u = (
            a * x1 + d * x4 + g * x7, a * x2 + d * x5 + g * x8, a * x3 + d * x6 + g * x9,
            b * x1 + e * x4 + k * x7, b * x2 + e * x5 + k * x8, b * x3 + e * x6 + k * x9,
            c * x1 + f * x4 + p * x7, c * x2 + f * x5 + p * x8, c * x3 + f * x6 + p * x9,
        )  # U = Q^T Q_1  # fmt: skip
        if _branch3_u(u, lam):
            return out, it + 1
    s1, it = _solve_s3_one(s, h, m, lam, tol)
    return _step3(s1, h, *m, *lam, *q), it + 1


def _solve_s3_one(s: float, h: float, m: Any, lam: Any, tol: float) -> tuple[float, int]:
    """:func:`_solve_s3` (with the branch check) for one body, in Python floats."""
    ds = math.inf
    it = 0
    for it in range(1, _MAXITER + 1):  # noqa: B007
        s, ds = _snewton3(s, h, *m, *lam)
        if abs(ds) <= tol or not abs(ds) < 1e3:  # converged, or nan or diverging
            break
    if not (abs(ds) <= tol and _branch3(s, h, m, lam)):
        b = np.array([[h * m[0], h * m[1], h * m[2]]])
        s = float(_riccati3_s(b, np.array([[float(x) for x in lam]]))[0])
    return s, it


def _solve_s3(s: Any, h: float, m: Any, lam: Any, tol: Any, *, check: bool) -> tuple[Any, int]:
    """Newton on the quartic p(s) (floats or arrays) from s until |ds| <= tol; then, when
    ``check``, every item whose U is off the branch through I, and every item not converged,
    is solved by symrb.solve_moser_veselov (raises past the fold)."""
    if check and isinstance(s, float) and isinstance(m[0], float) and isinstance(tol, float):
        return _solve_s3_one(s, h, m, lam, tol)
    ds: Any = np.inf
    it = 0
    for it in range(1, _MAXITER + 1):  # noqa: B007
        s, ds = _snewton3(s, h, *m, *lam)
        if np.all(np.abs(ds) <= tol):
            break
        if not np.all(np.abs(ds) < 1e3):  # nan or diverging
            break
    conv = np.abs(ds) <= tol
    if check:
        U = np.stack(np.broadcast_arrays(*_step3(s, h, *m, *lam, *_I3)[5:]), axis=-1)
        U = U.reshape(np.shape(U)[:-1] + (3, 3))
        L = np.broadcast_to(np.stack(np.broadcast_arrays(*lam), -1), U.shape[:-1])
        conv = conv & _on_branch(U.reshape(-1, 3, 3), L.reshape(-1, 3)).reshape(np.shape(conv))
    if not np.all(conv):
        bad = ~np.atleast_1d(conv)
        b = h * np.stack(np.broadcast_arrays(*m), axis=-1).reshape(-1, 3)
        L = np.broadcast_to(np.stack(np.broadcast_arrays(*lam), -1), b.shape)
        sa = np.array(np.broadcast_to(s, bad.shape), dtype=float)
        sa[bad] = _riccati3_s(b[bad], L[bad])
        s = float(sa[0]) if np.ndim(conv) == 0 else sa
    return s, it


def _vee_cols(M: Array) -> list[Array]:
    return [M[:, 2, 1].copy(), M[:, 0, 2].copy(), M[:, 1, 0].copy()]


def _hat_cols(m: list[Array]) -> Array:
    out = np.zeros(m[0].shape + (3, 3))
    out[..., 2, 1], out[..., 0, 2], out[..., 1, 0] = m
    out[..., 1, 2], out[..., 2, 0], out[..., 0, 1] = -m[0], -m[1], -m[2]
    return out


# ---------------------------------------------------------------------------------------------
# preprocessing (n = 3)


def _preprocessing(order: int, lam_c: Any) -> tuple[Any, ...] | None:
    """The 28 constants of mv3_preprocessed_lam for ``order`` (zeros above it), or None; for
    one body (``lam_c`` floats) kept from call to call (:func:`_preprocessing_one`)."""
    if order == 2:
        return None
    if all(type(x) is float for x in lam_c):
        return _preprocessing_one(order, tuple(lam_c))
    return _preprocessing_of(order, lam_c)


@functools.lru_cache(maxsize=64)
def _preprocessing_one(order: int, lam_c: tuple[float, ...]) -> tuple[Any, ...]:
    """:func:`_preprocessing_of` for one body, cached on (order, lam): the constants depend on
    nothing else, and a run of a few hundred compiled steps would spend a tenth of its time
    recomputing them."""
    return _preprocessing_of(order, lam_c)


def _preprocessing_of(order: int, lam_c: Any) -> tuple[Any, ...]:
    c = _gen.mv3_preprocessing_coefficients(*lam_c)
    keep = order // 2 - 1  # the h^2k terms kept, k = 1..keep
    # the constants come as c_kj (k = 1..4, j = 0..k), then d_kj in the same order
    sizes = [k + 2 for k in range(4)]
    out: list[Any] = []
    for half in (c[:14], c[14:]):
        i = 0
        for k, size in enumerate(sizes):
            out += [x if k < keep else 0.0 * x for x in half[i : i + size]]
            i += size
    return tuple(out)


def _columns(parts: Any, size: int) -> Array:
    """Floats or arrays (each broadcasting to (size,)) as the columns of a (size, k) array."""
    if size == 1:  # floats: one row at once
        row = np.array(parts, dtype=float)
        if row.shape == (len(parts),):
            return row.reshape(1, len(parts))
    out = np.empty((size, len(parts)))
    for i, x in enumerate(parts):
        out[:, i] = x
    return out


def _check_modified(lam_k: Any, h: float, order: int) -> None:
    """The modified Lambda must be finite and positive (h small enough for the series)."""
    if all(type(x) is float for x in lam_k):
        low = min(lam_k)  # (a NaN among them makes min NaN or skips it: checked again below)
        low = low if all(x == x for x in lam_k) else math.nan
    else:
        low = min(float(np.min(x)) for x in lam_k)
    if not np.isfinite(low) or low <= 0:
        raise OutOfDomainError(
            f"h = {h:g}: the preprocessed method of order {order} gives a modified Lambda with "
            f"min = {low:.3g} (must be finite and > 0); h |m| is too large for the series, "
            "take a smaller h or a lower order"
        )


# ---------------------------------------------------------------------------------------------
# the validation fast path of mv_flow (one body)

_F64 = np.dtype(np.float64)


def _one_body(Q0: Any, M0: Any, lam: Any) -> tuple[Array, Array, tuple[float, ...]] | None:
    """``(Q, M, lam)`` for the common case of :func:`symrb.engine.mv_flow`, or None.

    The common case: ``Q0``, ``M0`` float64 arrays of shape (3, 3) and ``lam`` one of shape (3,)
    that pass the checks of :func:`symrb._stepping._prepare` (finite, entries at most
    MAGNITUDE, lam_i > 0, M0 skew to 1e-10 relative, Q0 orthogonal to 1e-8 with det > 0), each
    made in a few scalar operations.  Every comparison is written so that a NaN fails it, and
    ``Q0`` is only accepted well inside the tolerance (within 1e-9), so a case this function
    accepts is one the full checks accept; None sends everything else (every error) to them.
    Returns a copy of ``Q0``, the skew part of ``M0`` and ``lam`` as floats.
    """
    if not (type(Q0) is np.ndarray and type(M0) is np.ndarray and type(lam) is np.ndarray):
        return None
    if Q0.shape != (3, 3) or M0.shape != (3, 3) or lam.shape != (3,):
        return None
    if Q0.dtype != _F64 or M0.dtype != _F64 or lam.dtype != _F64:
        return None
    lam_t = tuple(lam.tolist())
    l1, l2, l3 = lam_t
    if not (1e-140 <= l1 <= MAGNITUDE and 1e-140 <= l2 <= MAGNITUDE and 1e-140 <= l3 <= MAGNITUDE):
        return None  # (lam_i >= 1e-140: the pairwise sums >= 1/MAGNITUDE)
    m = M0.ravel().tolist()
    am = list(map(abs, m))
    if not sum(am) <= MAGNITUDE:  # finite (a NaN fails), each entry bounded
        return None
    m11, m12, m13, m21, m22, m23, m31, m32, m33 = m
    d = max(2.0 * abs(m11), 2.0 * abs(m22), 2.0 * abs(m33))
    dev = max(d, abs(m12 + m21), abs(m13 + m31), abs(m23 + m32))  # max |M0 + M0^T|
    if not dev <= 1e-10 * max(max(am), 1.0):
        return None
    a, b, c, d, e, f, g, h, k = Q0.ravel().tolist()
    gram = max(
        abs(a * a + d * d + g * g - 1.0),
        abs(b * b + e * e + h * h - 1.0),
        abs(c * c + f * f + k * k - 1.0),
        abs(a * b + d * e + g * h),
        abs(a * c + d * f + g * k),
        abs(b * c + e * f + h * k),
    )
    if not (gram <= 1e-9 and a * (e * k - f * h) - b * (d * k - f * g) + c * (d * h - e * g) > 0.0):
        return None  # (a NaN or inf in Q0 fails too)
    u, v, w = 0.5 * (m12 - m21), 0.5 * (m13 - m31), 0.5 * (m23 - m32)  # the skew part of M0
    return Q0.copy(), np.array([[0.0, u, v], [-u, 0.0, w], [-v, -w, 0.0]]), lam_t


# ---------------------------------------------------------------------------------------------
# compositions of Moser-Veselov sub-steps (composed_rigid_body_flow, n = 3)


def _composed3(Q: Array, M: Array, stepper: Any, h: float, steps: int, save_every: int,
               gammas: Any, method: str) -> DiscreteFlowSolution | None:  # fmt: skip
    """The run of :func:`symrb.compose.composed_rigid_body_flow` with the MV base step at n = 3,
    without a Python object per stage (``method`` its name), or None when a stage fails (the
    caller then runs its general loop, which reports the failure).

    ``Q``, ``M`` of shape (..., 3, 3), broadcast to the batch of ``stepper`` (a fresh
    :class:`symrb.engine.MVStepper`); the sub-steps are ``gamma * h``.  NumPy: the stepper's
    ``_step3`` on floats (one body) or component vectors (a batch), the very arithmetic of
    ``MVStepper.step``.  Compiled (``use_numba``): the first root (cold start, branch check,
    Riccati fallback) here, then every stage in :func:`symrb._compiled.run_mv3`; when numba is
    installed and the run has at least ``_compiled.MIN_WORK`` body-stages, as in ``mv_flow``.
    """
    use_numba = _compiled.AVAILABLE and steps * len(gammas) * stepper.size >= _compiled.MIN_WORK
    got = _composed3_run(Q, M, stepper, h, steps, save_every, gammas, use_numba)
    if got is None:
        return None
    kk = np.asarray(got[0], dtype=np.int64)
    return DiscreteFlowSolution(
        t=kk.astype(float) * h,
        k=kk,
        y=Trajectory(Q=got[1], M=got[2]),
        iterations=np.zeros(0, dtype=np.int64),  # (MVStepper reports no last_iterations)
        success=True,
        status=0,
        message=f"all {steps} steps taken",
        method=method,
        h=h,
    )


def _max_abs(x: Any) -> Any:
    """max |x| of a float or an array."""
    return abs(x) if isinstance(x, float) else np.max(np.abs(x))


def _composed3_run(Q: Array, M: Array, stepper: Any, h: float, steps: int, save_every: int,
                   gammas: Any, use_numba: bool) -> tuple[list[int], Array, Array] | None:  # fmt: skip
    """The saved ``(k, Q, M)`` of :func:`_composed3`, or None."""
    from . import _compiled

    Qf, Mf = Q.reshape(-1, 3, 3), M.reshape(-1, 3, 3)
    g = tuple(float(x) for x in np.asarray(gammas).ravel())
    if stepper.size == 1:
        q: Any = tuple(Qf[0].ravel().tolist())
        m: Any = (float(Mf[0, 2, 1]), float(Mf[0, 0, 2]), float(Mf[0, 1, 0]))
    else:
        m = tuple(_vee_cols(Mf))
        q = tuple(Qf[:, i, j].copy() for i in range(3) for j in range(3))
    ks = list(range(0, steps + 1, save_every))
    try:
        if not use_numba:
            Qs, Ms = [Qf.copy()], [Mf.copy()]
            lam, tol = stepper._lam_c, stepper._tol_max
            sg: list[Any] = [None] * len(g)  # the s of each sub-step, as in _compiled
            for k in range(1, steps + 1):
                for i, c in enumerate(g):
                    out = None if k == 1 else _step3(sg[i], c * h, *m, *lam, *q)
                    if out is None or not _max_abs(out[1]) <= tol:
                        out = stepper._step3(c * h, m, q)  # from s/h^2 of the last sub-step
                    stepper._sigma = out[0] / (c * h * c * h)
                    m, q, sg[i] = out[2:5], out[5:], out[0]
                if k % save_every == 0:
                    Qs.append(np.stack(np.broadcast_arrays(*q), axis=-1).reshape(Qf.shape))
                    Ms.append(_hat_cols(list(np.broadcast_arrays(*m))).reshape(Mf.shape))
            return ks, np.array(Qs).reshape((-1,) + Q.shape), np.array(Ms).reshape((-1,) + M.shape)
        h0 = g[0] * h
        s, _ = _solve_s3(_s_cold(h0, m, stepper._lam_c), h0, m, stepper._lam_c, stepper._tol,
                         check=True)  # fmt: skip
    except STEP_FAILURES:
        return None
    size = stepper.size
    ms, qs, fail, _ = _compiled.run_mv3(
        np.broadcast_to(np.asarray(s, dtype=float), (size,)), h, _columns(m, size), stepper.lam,
        _columns(q, size), np.broadcast_to(np.asarray(stepper._tol, dtype=float), (size,)),
        steps, save_every, gammas=np.array(g),
    )  # fmt: skip
    if fail.any() or not np.isfinite(ms).all():
        return None
    Qk = np.concatenate([Qf[None], qs.reshape(-1, size, 3, 3)])
    Mk = np.concatenate([Mf[None], _hat_cols([ms[..., 0], ms[..., 1], ms[..., 2]])])
    return ks, Qk.reshape((-1,) + Q.shape), Mk.reshape((-1,) + M.shape)
