"""Input checks and small helpers shared by the book's computations (and the replaced experiments
the scene tests compare against)."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import numpy as np

import symrb
from symrb import _validate as v
from symrb._validate import Array
from symrb.errors import InputError


def positive(x: object, name: str) -> float:
    """A real scalar > 0 (``symrb._validate.real_scalar`` first: finite, not a bool or array)."""
    value = v.real_scalar(x, name)
    if not value > 0:
        raise InputError(f"{name} must be a finite number > 0, got {x!r}")
    return value


def finite_positive(x: float, name: str) -> float:
    """``float(x)``, finite and > 0."""
    value = float(x)
    if not (np.isfinite(value) and value > 0):
        raise InputError(f"{name} must be a positive finite number, got {x!r}")
    return value


def count(x: int, name: str, minimum: int) -> int:
    """An integer >= ``minimum`` (not a bool)."""
    if isinstance(x, bool) or int(x) != x or int(x) < minimum:
        raise InputError(f"{name} must be an integer >= {minimum}, got {x!r}")
    return int(x)


def with_norm(n: int, norm: float, seed: int | np.random.Generator) -> Array:
    """A random skew (n, n) matrix scaled to the operator norm ``norm``."""
    M = symrb.random_so(n, seed=seed)
    return M * (norm / np.linalg.norm(M, 2))


@contextlib.contextmanager
def one_blas_thread() -> Iterator[bool]:
    """Hold BLAS to one thread inside the block; yields whether it could (threadpoolctl)."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # pragma: no cover - threadpoolctl comes with the book extra
        yield False
        return
    with threadpool_limits(limits=1, user_api="blas"):
        yield True
