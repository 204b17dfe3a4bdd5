"""Result containers shared by the continuous and the discrete flows."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ._validate import Array
from .errors import NotConvergedError, OutOfDomainError, SymrbError

#: What ends a step of a flow early: no solution (past the fold, no convergence), or float64
#: arithmetic that overflowed or divided by zero on the way (extreme finite input).
STEP_FAILURES = (OutOfDomainError, NotConvergedError, ArithmeticError, np.linalg.LinAlgError)


def step_failure(exc: Exception) -> str:
    """Why a step failed, in words (a symrb error says it itself)."""
    if isinstance(exc, SymrbError):
        return str(exc)
    return (
        f"float64 arithmetic failed ({type(exc).__name__}: {exc}): the step's numbers overflow "
        "or vanish; take a step nearer 1/|M| or rescale the input"
    )


class Trajectory(dict):
    """The state along a solution: a dict of arrays with time as the leading axis, also readable
    as attributes (``sol.y.Q`` is ``sol.y["Q"]``).

    Examples
    --------
    >>> import numpy as np
    >>> from symrb.continuous import Trajectory
    >>> y = Trajectory(Q=np.zeros((5, 3, 3)))
    >>> y.Q.shape
    (5, 3, 3)
    >>> sorted(y)
    ['Q']
    """

    def __getattr__(self, key: str) -> Array:
        try:
            return self[key]
        except KeyError:
            raise AttributeError(f"trajectory has no variable {key!r}; has {list(self)}") from None

    def __dir__(self) -> list[str]:
        return sorted(set(super().__dir__()) | {str(k) for k in self})


_sum = np.add.reduce


def first_nonfinite(t: Array, y: Mapping[str, Array]) -> tuple[int, list[str]] | None:
    """The first index of the time axis at which ``t`` or a state of ``y`` (time first) holds a
    non-finite number, with the names of what is not finite there; None when all is finite."""
    K = t.shape[0]
    arrays = [np.asarray(x) for x in y.values()]
    # the common case, without the rows below: a sum is finite only if every term is (inf - inf
    # is nan); a finite array whose sum overflows goes on to the exact test below
    if math.isfinite(_sum(t.ravel())) and all(
        a.dtype.kind not in "fc" or (a.dtype.kind == "f" and math.isfinite(_sum(a.ravel())))
        for a in arrays
    ):
        return None
    rows: dict[str, NDArray[np.bool_]] = {"t": np.asarray(np.isfinite(t))}
    for name, x in y.items():
        a = np.asarray(x)
        if a.dtype.kind in "fc" and a.shape[:1] == (K,):
            rows[f"y.{name}"] = np.asarray(np.isfinite(a.reshape(K, -1)).all(axis=1))
    ok = np.logical_and.reduce(list(rows.values()))
    if ok.all():
        return None
    i = int(np.argmin(ok))
    return i, [name for name, row in rows.items() if not row[i]]


def cut(t: Array, y: Trajectory, i: int) -> Trajectory:
    """The states of ``y`` before time index ``i``."""
    return Trajectory(
        {name: x[:i] if np.shape(x)[:1] == t.shape[:1] else x for name, x in y.items()}
    )


@dataclass
class DiscreteFlowSolution:
    r"""Result of the discrete flows (:func:`symmetric_flow`, :func:`mv_algorithm1`,
    :func:`mv_algorithm2`, :func:`discrete_rigid_body_flow`), modelled on :class:`FlowSolution`.

    Attributes
    ----------
    t : ndarray, shape (K,)
        The times :math:`kh` of the saved states; for the Moser-Veselov maps, which have no time
        step, the step indices ``k`` (as floats).
    k : ndarray of int, shape (K,)
        The step index of each saved state (``0, s, 2s, ...`` for ``save_every = s``).
    y : Trajectory
        The saved states by name, each of shape ``(K, ..., n, n)``: ``Q`` always, ``P`` and the
        body momentum ``M`` for the symmetric representation, ``M`` for MV-Algorithm 2.
    iterations : ndarray of int, shape (number of solves,)
        Newton iterations of each solve of :math:`J_D(U) = M`, in order (summed over a batch);
        for a run by the engine (the default of :mod:`symrb.paper`), of each engine step.
    success : bool
        True when every step was taken and every number of ``t``, ``y``, ``residual`` and
        ``tol`` is finite (``condition`` is NaN unless computed).  A run whose state, residual
        or tolerance overflowed is never a success (see :meth:`check_finite`).
    status : int
        0 when every step was taken, -1 when a step failed (then ``message`` says why and the
        last state reached is the last saved one).
    message : str
        What happened, in words.
    method : str
        The name of the map.
    h : float or None
        The time step, or None for the Moser-Veselov maps.
    residual : ndarray, shape (number of solves,)
        :math:`\|U\Lambda - \Lambda U^T - M\|_F` of each solve (the largest over a batch).
        ``residual``, ``tol`` and ``condition`` are those of the reference loop (with
        ``progress``, ``halve`` or ``diagnostics``); empty for a run by the engine, which checks
        each solve against its own tolerance.
    tol : ndarray, shape (number of solves,)
        The tolerance each residual met (the default of :func:`symrb.solve_moser_veselov`: ten
        times the rounding error of evaluating the residual): every entry of ``residual`` is at
        most its ``tol``.
    condition : ndarray, shape (number of solves,)
        The solver's condition estimate :math:`\kappa` of each solve (see
        :class:`symrb.solvers.MVSolveInfo`; the largest over a batch), with ``diagnostics=True``;
        NaN otherwise.
    failed_step : int or None
        The step that failed, or None.
    fold : float or None
        When a step failed: :math:`t^*` of :func:`symrb.fold_scale` for that step's momentum
        (below 1: it is past the fold by :math:`1/t^* - 1`; the smallest over a batch).
    h_max : float or None
        When a step of a flow with a time step failed: :math:`t^*h`, the step at which that
        step's momentum reaches the fold; every step below it can be taken there.
    halvings : ndarray of int, shape (steps taken,)
        With ``halve=True``: how many times each step was halved (0: taken whole; ``j``: as
        :math:`2^j` steps of :math:`h/2^j`).  Empty otherwise.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> Q0 = np.eye(3)
    >>> M0 = symrb.hat([0.1, 0.2, 0.3])
    >>> sol = symrb.discrete_rigid_body_flow(Q0, M0, [0.7, 1.1, 1.6], 0.1, 20, save_every=10)
    >>> sol.success, sol.t, sol.k
    (True, array([0., 1., 2.]), array([ 0, 10, 20]))
    >>> sol.y.Q.shape, sorted(sol.y)
    ((3, 3, 3), ['M', 'P', 'Q'])
    >>> sol.message
    'all 20 steps taken'
    """

    t: Array
    k: NDArray[np.int64]
    y: Trajectory
    iterations: NDArray[np.int64]
    success: bool
    status: int
    message: str
    method: str
    h: float | None = None
    residual: Array = field(default_factory=lambda: np.zeros(0))
    tol: Array = field(default_factory=lambda: np.zeros(0))
    condition: Array = field(default_factory=lambda: np.zeros(0))
    failed_step: int | None = None
    fold: float | None = None
    h_max: float | None = None
    halvings: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, dtype=np.int64))

    def __post_init__(self) -> None:
        self.check_finite()

    def check_finite(self) -> None:
        """Mark a successful result holding a non-finite number as failed.

        The states are cut before the first saved state with a non-finite entry (whose step
        becomes ``failed_step``); ``message`` names that step and every solve whose residual or
        tolerance is not finite.  Called on construction, and again by a flow that adds states
        to ``y`` afterwards.
        """
        if not self.success:
            return
        notes = []
        bad = first_nonfinite(self.t, self.y)
        if bad is not None:
            i, names = bad
            step = int(self.k[i])
            notes.append(f"{', '.join(names)} not finite from step {step} on (cut there)")
            self.y, self.t, self.k = cut(self.t, self.y, i), self.t[:i], self.k[:i]
            self.failed_step = step
        for name in ("residual", "tol"):
            values = np.asarray(getattr(self, name))
            if values.size and not np.isfinite(values).all():
                j = int(np.argmin(np.isfinite(values)))
                notes.append(f"the {name} of solve {j} (of J_D(U) = M, in order) is {values[j]}")
        if notes:
            self.success, self.status = False, -1
            self.message += (
                "; but " + "; ".join(notes) + ": the numbers overflowed float64 (inputs or step "
                "too large), so the run is not a success"
            )

    @property
    def nit(self) -> int:
        """The total number of Newton iterations."""
        return int(self.iterations.sum())
