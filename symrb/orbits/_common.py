"""What the modules of :mod:`symrb.orbits` share: the validation of a state and the fixed element,
and the parameter blocks their docstrings have in common."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .. import _validate as v
from .._validate import Array
from ..errors import InputError

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


def symmetric(x: ArrayLike, name: str, n: int | None = None, rtol: float = 1e-10) -> Array:
    """A float array of shape (..., n, n) with x^T = x to ``rtol`` relative to its size (a real
    symmetric L standing for iL in u(n))."""
    a = v.square(x, name, n)
    dev = float(np.abs(a - np.swapaxes(a, -1, -2)).max()) if a.size else 0.0
    scale = max(float(np.abs(a).max()) if a.size else 0.0, 1.0)
    if dev > rtol * scale:
        raise InputError(
            f"{name} must be symmetric (it stands for i {name} in u(n)); max |{name} - {name}^T| "
            f"= {dev:.3e} > {rtol:g} * {scale:.3g}; pass ({name} + {name}^T) / 2 if the skew "
            "part is rounding"
        )
    return a
