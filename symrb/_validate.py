"""Input validation shared by the hand-written wrappers (never mutates its inputs)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import InputError

Array = NDArray[np.float64]


#: Integers up to this size convert to float64 exactly.
_EXACT_INT = 2**53

#: The largest magnitude of an entry the flows accept: sums of squares of larger entries
#: overflow float64 (about 1.8e308) inside a step, and then no number of the result means
#: anything.  The smallest pairwise sum of an inertia is its reciprocal.
MAGNITUDE = 1e150


def as_float_array(x: ArrayLike, name: str) -> Array:
    """``x`` as a float64 array (a copy only when needed).

    The dtype policy (the book's page "Hard cases"): symrb computes and returns float64 only.
    float64 input is used as is and integer input is converted when every entry is exact in
    float64 (magnitude <= 2^53); float32, float16 and long double input is rejected rather than
    silently promoted or rounded (the stated accuracies are float64 ones, and a float32 result
    would not meet them), and so are complex input (NumPy would drop the imaginary part with only
    a warning), strings, integers too large for float64 and non-finite entries.  Every message
    says how to pass the data instead.
    """
    if type(x) is np.ndarray and x.dtype == np.float64 and np.isfinite(x).all():
        return x  # the common case, without the conversions below (as np.asarray would return it)
    try:
        raw = np.asarray(x)
    except (TypeError, ValueError, OverflowError) as exc:
        raise InputError(
            f"{name} must be a real array, got {type(x).__name__}: {exc}; pass a float64 array"
        ) from None
    kind = raw.dtype.kind
    if kind == "c":
        imag = float(np.max(np.abs(raw.imag), initial=0.0))
        raise InputError(
            f"{name} must be real, got a complex array (dtype {raw.dtype}, max |imag| = "
            f"{imag:.3g}); pass {name}.real if the imaginary part is meant to be dropped"
        )
    if kind == "f" and raw.dtype != np.float64:
        raise InputError(
            f"{name} must be float64 (symrb computes in float64 only), got dtype {raw.dtype}; "
            f"pass np.asarray({name}, dtype=np.float64)"
            + (" (exact for float32 and float16)" if raw.dtype.itemsize < 8 else "")
        )
    if kind not in "biufO":
        raise InputError(
            f"{name} must be a real array of numbers, got dtype {raw.dtype}; pass a float64 array"
        )
    if kind in "iu" and raw.size and int(np.max(np.abs(raw.astype(object)))) > _EXACT_INT:
        big = int(np.max(np.abs(raw.astype(object))))
        raise InputError(
            f"{name} has integers too large to convert to float64 exactly: max |{name}| = {big} "
            f"> 2^53; pass a float64 array (rounded as you intend)"
        )
    try:
        a = np.asarray(raw, dtype=float)
    except OverflowError as exc:
        raise InputError(
            f"{name} has an entry too large for float64 ({exc}); pass finite float64 values"
        ) from None
    except (TypeError, ValueError) as exc:
        raise InputError(
            f"{name} must be a real array, got {type(x).__name__}: {exc}; pass a float64 array"
        ) from None
    if not np.all(np.isfinite(a)):
        bad = int(np.sum(~np.isfinite(a)))
        raise InputError(
            f"{name} must be finite; it has {bad} NaN/inf entries (first at index "
            f"{tuple(int(i) for i in np.argwhere(~np.isfinite(a))[0])}); remove or replace them"
        )
    return a


def square(x: ArrayLike, name: str, n: int | None = None) -> Array:
    """A float array of shape (..., n, n)."""
    a = as_float_array(x, name)
    if a.ndim < 2 or a.shape[-1] != a.shape[-2]:
        raise InputError(
            f"{name} must have shape (..., n, n) (square matrices in the last two axes), got "
            f"{a.shape}; reshape it or pass the matrices stacked along the leading axes"
        )
    if n is not None and a.shape[-1] != n:
        raise InputError(
            f"{name} must be {n} x {n} to match lam, got {a.shape}; pass matrices of the size "
            f"of lam (or a lam of length {a.shape[-1]})"
        )
    return a


def skew(x: ArrayLike, name: str, n: int | None = None, rtol: float = 1e-10) -> Array:
    """A float array of shape (..., n, n) with x^T = -x to ``rtol`` relative to its size."""
    a = square(x, name, n)
    dev = float(np.abs(a + np.swapaxes(a, -1, -2)).max()) if a.size else 0.0
    scale = max(float(np.abs(a).max()) if a.size else 0.0, 1.0)
    if dev > rtol * scale:
        raise InputError(
            f"{name} must be skew-symmetric; max |{name} + {name}^T| = {dev:.3e} > {rtol:g} * "
            f"{scale:.3g}; pass the skew part ({name} - {name}^T) / 2 (symrb.algebra.skew_part) if the "
            "symmetric part is rounding"
        )
    return a


def orthogonal(x: ArrayLike, name: str, n: int | None = None, atol: float = 1e-8) -> Array:
    """A float array of shape (..., n, n) in SO(n): x^T x = I and det x = +1 to ``atol``."""
    a = square(x, name, n)
    eye = np.eye(a.shape[-1])
    dev = float(np.abs(np.swapaxes(a, -1, -2) @ a - eye).max()) if a.size else 0.0
    if dev > atol:
        raise InputError(
            f"{name} must be orthogonal; max |{name}^T {name} - I| = {dev:.3e} > {atol:g}; pass "
            f"the orthogonal polar factor of {name} (W @ Vt from np.linalg.svd) if the error is "
            "accumulated rounding"
        )
    det = np.linalg.det(a)
    if (det < 0).any():
        raise InputError(
            f"{name} must have det +1 (be in SO(n)); got det = {float(np.min(det)):.3f}; a "
            f"reflection is not a rotation: flip the sign of one column of {name} if that is "
            "the intent"
        )
    return a


def _brief(a: Array) -> str:
    """A one-line summary of an array's entries for error messages."""
    return " ".join(np.array2string(a, precision=4, threshold=12, edgeitems=2).split())


def _looks_like_matrix(a: Array) -> bool:
    """True when a lam of shape (..., n, n) has zero off-diagonal entries: the matrix Lambda."""
    if a.ndim < 2 or a.shape[-1] != a.shape[-2]:
        return False
    off = ~np.eye(a.shape[-1], dtype=bool)
    return bool(np.all(a[..., off] == 0))


def inertia(lam: ArrayLike, name: str = "lam", positive: bool = False) -> Array:
    """The diagonal of Lambda, shape (..., n), with lam_i + lam_j > 0 for i != j.

    With ``positive=True`` every lam_i > 0 is required (Lambda positive definite, as the discrete
    problems of Section 2 assume).  Leading axes of ``lam`` are batch axes, so a matrix cannot be
    told from a batch of diagonals by its shape alone: a square ``lam`` with zero off-diagonal
    entries (the matrix Lambda itself) is rejected, and any other square ``lam`` that fails the
    checks gets a hint in the message.
    """
    a = as_float_array(lam, name)
    what = f"{name} is the 1-D diagonal of Lambda, shape (n,) or (..., n) for a batch"
    if _looks_like_matrix(a) and a.shape[-1] >= 2:
        raise InputError(
            f"{what}; got shape {a.shape} with zero off-diagonal entries, which looks like the "
            f"matrix Lambda itself: pass its diagonal, np.diag({name})"
        )
    hint = ""
    if a.ndim >= 2 and a.shape[-1] == a.shape[-2]:
        hint = (
            f" ({what}; got the square shape {a.shape}, read as {a.shape[-2]} diagonals of "
            f"length {a.shape[-1]}: if it is the matrix Lambda, pass its diagonal)"
        )
    if a.ndim < 1 or a.shape[-1] < 2:
        raise InputError(f"{what}, with n >= 2; got shape {a.shape}; pass at least two entries")
    if positive and (a <= 0).any():
        raise InputError(
            f"{name} must be positive (Lambda positive definite); min lam_i = "
            f"{float(np.min(a)):.6g}{hint}; pass the principal moments of a body (all > 0)"
        )
    if a.ndim == 1:  # one lam: the smallest lam_i + lam_j (i != j) is the sum of the two least
        two = np.partition(a, 1)[:2]
        worst = float(two[0] + two[1])
    else:
        s_ = a[..., :, None] + a[..., None, :]
        off = ~np.eye(a.shape[-1], dtype=bool)
        worst = float(np.min(s_[..., off]))
    if worst <= 0:
        raise InputError(
            f"{name} must satisfy lam_i + lam_j > 0 for i != j (J positive definite); "
            f"min lam_i + lam_j = {worst:.6g}, lam = {_brief(a)}{hint}; pass a lam whose "
            "pairwise sums are positive"
        )
    if worst < 1.0 / MAGNITUDE:
        raise InputError(
            f"{name} must have pairwise sums lam_i + lam_j >= {1.0 / MAGNITUDE:g} (J^-1 "
            f"overflows float64 otherwise), got min lam_i + lam_j = {worst:.4g}, lam = "
            f"{_brief(a)}; rescale lam (a common factor c scales time by c)"
        )
    return bounded(a, name, hint="rescale lam (a common factor c scales time by c)")


_RESCALE = "rescale the problem (for the rigid body, M and t -> M/c and c t give the same orbit)"


def bounded(a: Array, name: str, limit: float = MAGNITUDE, hint: str = _RESCALE) -> Array:
    """``a`` unchanged when every entry has magnitude at most ``limit`` (default
    :data:`MAGNITUDE`); an :class:`InputError` naming the largest entry and saying ``hint``
    otherwise."""
    big = float(np.max(np.abs(a), initial=0.0))
    if big > limit:
        raise InputError(
            f"{name} must have entries of magnitude <= {limit:g} (their squares overflow float64 "
            f"otherwise), got max |{name}| = {big:.4g}; {hint}"
        )
    return a


def real_scalar(x: object, name: str) -> float:
    """``x`` as a finite Python float; rejects complex numbers, strings, booleans and arrays."""
    if isinstance(x, bool | np.bool_) or not isinstance(x, int | float | np.integer | np.floating):
        raise InputError(
            f"{name} must be a real number, got {type(x).__name__} {x!r}; pass a Python float"
        )
    value = float(x)
    if not np.isfinite(value):
        raise InputError(f"{name} must be finite, got {x!r}; pass a finite float")
    return value


def count(x: object, name: str, minimum: int = 0) -> int:
    """``x`` as an int >= ``minimum``; an integral float (``1e4``) is accepted, a bool is not."""
    ok = isinstance(x, int | np.integer) and not isinstance(x, bool | np.bool_)
    if isinstance(x, float | np.floating) and float(x).is_integer():
        ok = True
    if not ok or int(x) < minimum:  # type: ignore[call-overload]
        raise InputError(
            f"{name} must be an integer >= {minimum}, got {x!r}; pass a Python int >= {minimum}"
        )
    return int(x)  # type: ignore[call-overload]
