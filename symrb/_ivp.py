"""``scipy.integrate.solve_ivp`` with a budget: the adaptive solvers of symrb (:func:`integrate`,
the double bracket, Toda and orbit extremal flows) never run without bound.

An adaptive step can shrink without end (a stiff field, a long interval, a field that overflows:
a step size of NaN makes ``solve_ivp`` retry forever), so every solve counts the evaluations of
its vector field and stops at ``max_nfev`` of them; a field that is not finite at the initial
state stops it before the first step.  Either way the result says so (``success`` False, status
-1, the message naming the budget or the overflow) instead of hanging.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import OptimizeResult

from . import _validate as v
from ._validate import Array

#: The default budget: evaluations of the vector field per solve (seconds to a minute of work
#: for the flows of symrb; the longest runs of the claims take about 10^5).
MAX_NFEV = 1_000_000


class _OutOfBudget(Exception):
    def __init__(self, t: float) -> None:
        self.t = t


def check_budget(max_nfev: object) -> int:
    """``max_nfev`` as an int >= 1 (an :class:`InputError` otherwise)."""
    return v.count(max_nfev, "max_nfev", 1)


def _failed(y0: Array, nfev: int, message: str) -> OptimizeResult:
    return OptimizeResult(
        t=np.zeros(0), y=np.zeros((y0.size, 0)), success=False, status=-1, nfev=nfev,
        message=message,
    )  # fmt: skip


def solve_ivp_budget(
    fun: Callable[[float, Array], Array],
    span: tuple[float, float],
    y0: Array,
    *,
    max_nfev: int = MAX_NFEV,
    **kwargs: Any,
) -> Any:
    """``solve_ivp(fun, span, y0, **kwargs)`` stopped after ``max_nfev`` evaluations of ``fun``.

    A stopped run (budget out, or ``fun(t0, y0)`` not finite) returns a result with
    ``success`` False, status -1, no output times and the reason in ``message``.
    """
    with np.errstate(over="ignore", invalid="ignore"):
        f0 = np.asarray(fun(span[0], y0))
    if not np.isfinite(f0).all():
        return _failed(
            y0, 1, f"the vector field is not finite at the initial state, t = {span[0]:g} (it "
            f"overflowed float64: max |y0| = {float(np.max(np.abs(y0), initial=0.0)):.4g}); "
            "rescale the initial state",
        )  # fmt: skip
    count = 0

    def counted(t: float, y: Array) -> Array:
        nonlocal count
        if count >= max_nfev:
            raise _OutOfBudget(t)
        count += 1
        return fun(t, y)

    try:
        return solve_ivp(counted, span, y0, **kwargs)
    except _OutOfBudget as exc:
        return _failed(
            y0, count, f"the budget of max_nfev = {max_nfev} evaluations of the vector field "
            f"ran out at t = {exc.t:.6g} of [{span[0]:g}, {span[1]:g}] (a stiff field or a long "
            "interval); pass a larger max_nfev or a shorter interval",
        )  # fmt: skip
