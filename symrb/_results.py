"""Result containers shared by the continuous and the discrete flows."""

from __future__ import annotations

from ._validate import Array


class Trajectory(dict):
    """The state along a solution: a dict of arrays with time as the leading axis, also readable
    as attributes (``sol.y.Q`` is ``sol.y["Q"]``).

    Examples
    --------
    >>> import numpy as np
    >>> from symrb import Trajectory
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
