"""What the modules of :mod:`symrb.orbits` share: the validation of a state and the fixed element,
and the parameter blocks their docstrings have in common."""

from __future__ import annotations

from numpy.typing import ArrayLike

from .. import _validate as v
from .._validate import Array

#: numpydoc parameter blocks used by more than one docstring of the package
DOC = {
    "xpN": """\
x, p, N : array_like, shape (..., n, n)
    The skew-symmetric state, costate and fixed element (broadcast against each other).""",
    "xN": """\
x, N : array_like, shape (..., n, n)
    The skew-symmetric state and fixed element (broadcast against each other).""",
    "times": """\
t : array_like, shape (m,)
    Increasing output times, >= 0 (the flow starts at time 0).""",
    "tolerances": """\
rtol, atol : float, optional
    The tolerances of ``solve_ivp``.""",
}


def pair_xN(x: ArrayLike, N: ArrayLike, xname: str = "x") -> tuple[Array, Array]:
    """The skew state ``x`` (named ``xname`` in errors) and the skew fixed element ``N``, of one
    size n."""
    nn = v.skew(N, "N")
    return v.skew(x, xname, nn.shape[-1]), nn
