"""Result containers shared by the continuous and the discrete flows."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ._validate import Array


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
        Newton iterations of each solve of :math:`J_D(U) = M`, in order (summed over a batch).
    success : bool
        True when every step was taken.
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

    @property
    def nit(self) -> int:
        """The total number of Newton iterations."""
        return int(self.iterations.sum())
