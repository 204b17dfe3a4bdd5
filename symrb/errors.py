"""Exceptions raised by symrb.

Every exception names the argument, the violated condition and the offending value, so that bad
input never turns into a silent NaN or a wrong answer.
"""

from __future__ import annotations

__all__ = ["SymrbError", "InputError", "NotConvergedError", "OutOfDomainError"]


class SymrbError(Exception):
    """Base class of every error raised by symrb."""


class InputError(SymrbError, ValueError):
    """An argument violates a documented precondition (shape, skew-symmetry, positivity, ...)."""


class OutOfDomainError(SymrbError, ValueError):
    """The input lies outside the set where the requested map is defined (e.g. ||M||_op >= 2)."""


class NotConvergedError(SymrbError, RuntimeError):
    """An iterative solver stopped without meeting its tolerance; carries the final residual."""

    def __init__(self, message: str, residual: float, iterations: int) -> None:
        super().__init__(message)
        self.residual = residual
        self.iterations = iterations
