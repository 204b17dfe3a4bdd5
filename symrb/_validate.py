"""Input validation shared by the hand-written wrappers (never mutates its inputs)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import InputError

Array = NDArray[np.float64]


def as_float_array(x: ArrayLike, name: str) -> Array:
    """``x`` as a float64 array (a copy only when needed); rejects non-finite entries."""
    try:
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be a real array, got {type(x).__name__}: {exc}") from None
    if not np.all(np.isfinite(a)):
        raise InputError(
            f"{name} must be finite; it has {int(np.sum(~np.isfinite(a)))} NaN/inf entries"
        )
    return a


def square(x: ArrayLike, name: str, n: int | None = None) -> Array:
    """A float array of shape (..., n, n)."""
    a = as_float_array(x, name)
    if a.ndim < 2 or a.shape[-1] != a.shape[-2]:
        raise InputError(f"{name} must have shape (..., n, n), got {a.shape}")
    if n is not None and a.shape[-1] != n:
        raise InputError(f"{name} must be {n} x {n} to match lam, got {a.shape}")
    return a


def skew(x: ArrayLike, name: str, n: int | None = None, rtol: float = 1e-10) -> Array:
    """A float array of shape (..., n, n) with x^T = -x to ``rtol`` relative to its size."""
    a = square(x, name, n)
    dev = float(np.max(np.abs(a + np.swapaxes(a, -1, -2)), initial=0.0))
    scale = max(float(np.max(np.abs(a), initial=0.0)), 1.0)
    if dev > rtol * scale:
        raise InputError(f"{name} must be skew-symmetric; max |{name} + {name}^T| = {dev:.3e}")
    return a


def orthogonal(x: ArrayLike, name: str, n: int | None = None, atol: float = 1e-8) -> Array:
    """A float array of shape (..., n, n) in SO(n): x^T x = I and det x = +1 to ``atol``."""
    a = square(x, name, n)
    eye = np.eye(a.shape[-1])
    dev = float(np.max(np.abs(np.swapaxes(a, -1, -2) @ a - eye), initial=0.0))
    if dev > atol:
        raise InputError(f"{name} must be orthogonal; max |{name}^T {name} - I| = {dev:.3e}")
    det = np.linalg.det(a)
    if np.any(det < 0):
        raise InputError(
            f"{name} must have det +1 (be in SO(n)); got det = {float(np.min(det)):.3f}"
        )
    return a


def inertia(lam: ArrayLike, name: str = "lam", positive: bool = False) -> Array:
    """The diagonal of Lambda, shape (..., n), with lam_i + lam_j > 0 for i != j.

    With ``positive=True`` every lam_i > 0 is required (Lambda positive definite, as the discrete
    problems of Section 2 assume).
    """
    a = as_float_array(lam, name)
    if a.ndim < 1 or a.shape[-1] < 2:
        raise InputError(f"{name} must have shape (..., n) with n >= 2, got {a.shape}")
    if positive and np.any(a <= 0):
        raise InputError(
            f"{name} must be positive (Lambda positive definite); min lam_i = {float(np.min(a)):.6g}"
        )
    s = a[..., :, None] + a[..., None, :]
    nn = a.shape[-1]
    off = ~np.eye(nn, dtype=bool)
    worst = float(np.min(s[..., off]))
    if worst <= 0:
        raise InputError(
            f"{name} must satisfy lam_i + lam_j > 0 for i != j (J positive definite); "
            f"min lam_i + lam_j = {worst:.6g}, lam = {np.array2string(a, precision=4)}"
        )
    return a
