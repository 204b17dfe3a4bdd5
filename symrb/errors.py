"""Exceptions raised by symrb.

Every exception names the argument, the violated condition and the offending value, so that bad
input never turns into a silent NaN or a wrong answer.
"""

from __future__ import annotations

__all__ = [
    "SymrbError",
    "InputError",
    "NotConvergedError",
    "OutOfDomainError",
    "SymrbWarning",
    "CacheWarning",
]


class SymrbError(Exception):
    """Base class of every error raised by symrb.

    Examples
    --------
    >>> import symrb
    >>> try:
    ...     symrb.J(symrb.hat([1, 2, 3]), [1.0, 2.0])
    ... except symrb.SymrbError as exc:
    ...     print(type(exc).__name__, exc)
    InputError Omega must be 2 x 2 to match lam, got (3, 3); pass matrices of the size of lam (or a lam of length 3)
    """


class InputError(SymrbError, ValueError):
    """An argument violates a documented precondition (shape, skew-symmetry, positivity, ...).

    A subclass of :class:`ValueError`; the message names the argument, the condition and the
    offending value.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> symrb.J_inv(np.ones((3, 3)), [0.7, 1.1, 1.6])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    symrb.errors.InputError: M must be skew-symmetric; max |M + M^T| = 2.000e+00 > 1e-10 * 1; pass the skew part ...
    >>> symrb.J_inv(symrb.hat([1, 2, 3]), np.diag([0.7, 1.1, 1.6]))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    symrb.errors.InputError: lam is the 1-D diagonal of Lambda, ...: pass its diagonal, np.diag(lam)
    """


class OutOfDomainError(SymrbError, ValueError):
    """The input lies outside the set where the requested map is defined (e.g. ||M||_op >= 2).

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> symrb.symmetric.P_from_M(np.eye(3), symrb.hat([0.0, 0.0, 2.5]))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    symrb.errors.OutOfDomainError: P_from_M needs ||M||_op < 2 ...; got ||M||_op = 2.5 ...
    """


class NotConvergedError(SymrbError, RuntimeError):
    """An iterative solver stopped without meeting its tolerance; carries the final residual.

    Attributes
    ----------
    residual : float
        The residual when the solver stopped.
    iterations : int
        The iterations it used.

    Examples
    --------
    An exactly zero residual (``tol=0``) within one Newton iteration: for n = 8 the 64 entries
    of the residual do not all round to zero (for n = 3 they can, and then it converges).

    >>> import symrb
    >>> lam = symrb.algebra.random_lam(8, seed=6)
    >>> M = symrb.random_so(8, seed=7)
    >>> M = 0.5 * symrb.fold_scale(M, lam) * M
    >>> try:
    ...     symrb.solve_moser_veselov(M, lam, tol=0.0, maxiter=1)
    ... except symrb.NotConvergedError as exc:
    ...     print(exc.iterations, exc.residual > 0)
    1 True
    """

    def __init__(self, message: str, residual: float, iterations: int) -> None:
        super().__init__(message)
        self.residual = residual
        self.iterations = iterations


class SymrbWarning(UserWarning):
    """Base class of every warning issued by symrb: something went wrong that symrb worked
    around, and the result returned is still correct.

    Examples
    --------
    >>> import symrb.errors
    >>> issubclass(symrb.errors.CacheWarning, symrb.errors.SymrbWarning)
    True
    """


class CacheWarning(SymrbWarning):
    """The scene cache could not be used as it should: an entry failed its checksums (it is
    recomputed and replaced), or the cache directory cannot be read or written (the result is
    computed and returned all the same).

    Examples
    --------
    Turn the warnings of the cache into errors, e.g. in a test that must not recompute:

    >>> import warnings
    >>> from symrb.errors import CacheWarning
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("error", CacheWarning)
    ...     pass
    """
