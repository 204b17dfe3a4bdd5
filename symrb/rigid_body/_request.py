"""What every method adapter of :func:`symrb.rigid_body.simulate` is given and returns: the
validated request, the result type and the method descriptor of the dispatch table."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._results import DiscreteFlowSolution
from .._validate import Array


@dataclass
class RigidBodySolution:
    r"""The result of :func:`symrb.rigid_body.simulate`, the same for every method.

    Attributes
    ----------
    t : ndarray, shape (K,)
        The output times.
    Q : ndarray, shape (K, ..., n, n)
        The attitude at each output time.
    M : ndarray, shape (K, ..., n, n)
        The body momentum (continuous scale) at each output time.
    success : bool
        False when the run stopped early; ``t``, ``Q`` and ``M`` then end at the last state
        reached, and they never hold a non-finite number.
    message : str
        What happened, in words.
    method : str
        The method, as named in :data:`symrb.rigid_body.METHODS`.
    order : int or None
        The order of the method (None for the adaptive and the exact methods).
    stats : dict of str to int
        Counts of the run: ``nfev`` (``solve_ivp`` methods), ``steps`` (fixed-step methods),
        ``newton_iterations`` (``"mv"``), ``iterations`` (``"composition"``, ``"midpoint"``).
    raw : object
        The implementation's own result (:class:`symrb.continuous.FlowSolution`,
        :class:`symrb.paper.DiscreteFlowSolution` or :class:`symrb.exact.ExactSolution`), with every
        detail it reports.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> sol = symrb.rigid_body.simulate(np.eye(3), symrb.hat([0.5, 1.0, 1.5]), [0.7, 1.1, 1.6],
    ...                                 (0, 1), method="rkmk4", h=0.25)
    >>> sol.t, sol.Q.shape, sol.success, sol.stats
    (array([0.  , 0.25, 0.5 , 0.75, 1.  ]), (5, 3, 3), True, {'steps': 4})
    """

    t: Array
    Q: Array
    M: Array
    success: bool
    message: str
    method: str
    order: int | None = None
    stats: dict[str, int] = field(default_factory=dict)
    raw: Any = None


@dataclass(frozen=True)
class Request:
    """The validated arguments of one call of ``simulate`` (times checked, order resolved)."""

    Q0: ArrayLike
    M0: ArrayLike
    lam: ArrayLike
    method: str
    t0: float
    t1: float
    h: float | None
    steps: int | None
    order: int | None
    t_eval: Array | None
    save_every: int | None
    rtol: float | None
    atol: float | None
    progress: bool
    options: Mapping[str, Any]

    @property
    def keep(self) -> NDArray[np.int64] | None:
        """The step indices of ``t_eval`` on the grid of ``h`` (fixed-step methods)."""
        if self.t_eval is None or self.h is None:
            return None
        return np.rint((self.t_eval - self.t0) / self.h).astype(np.int64)

    @property
    def stride(self) -> int:
        """The ``save_every`` a fixed-step implementation runs with: the one asked for, or the
        largest that keeps every step of ``t_eval``, or 1."""
        if self.save_every is not None:
            return self.save_every
        keep = self.keep
        if keep is None:
            return 1
        return math.gcd(*(int(k) for k in keep)) or max(int(self.steps or 0), 1)

    def grid(self) -> Array | None:
        """The output times of a method without steps of its own: ``t_eval``, else the grid
        ``t0 + k h`` for ``k = 0, s, 2s, ...`` (``s = save_every``), else None."""
        if self.t_eval is not None:
            return self.t_eval
        if self.h is None or self.steps is None:
            return None
        k = np.arange(0, self.steps + 1, self.stride, dtype=np.int64)
        return self.t0 + k.astype(np.float64) * self.h

    def _steps_taken(self, raw: DiscreteFlowSolution) -> int:
        if raw.success:
            return int(self.steps or 0)
        return int(raw.k[-1]) if raw.k.size else 0

    def fixed_result(self, raw: DiscreteFlowSolution, stats: dict[str, int]) -> RigidBodySolution:
        """The solution of a fixed-step implementation's result (kept steps of ``t_eval``)."""
        rows = slice(None) if self.keep is None else np.isin(raw.k, self.keep)
        return RigidBodySolution(
            t=self.t0 + raw.t[rows],
            Q=raw.y["Q"][rows],
            M=raw.y["M"][rows],
            success=raw.success,
            message=raw.message,
            method=self.method,
            order=self.order,
            stats={"steps": self._steps_taken(raw), **stats},
            raw=raw,
        )


@dataclass(frozen=True)
class Method:
    """One entry of the dispatch table: how a method is run and what it accepts."""

    run: Callable[[Request], RigidBodySolution]
    fixed_step: bool
    summary: str
    orders: tuple[int, ...] = ()
    default_order: int | None = None
    options: tuple[str, ...] = ()
    progress: bool = False
    tolerances: bool = False
