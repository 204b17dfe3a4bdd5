r"""The extremal vector field of the orbit problem with Brockett's potential, its Hamiltonian and
the potential (paper, Sections 3.4-3.5; the fields are the kernels generated in
:mod:`symrb._generated.adjoint_orbits`)."""

from __future__ import annotations

from numpy.typing import ArrayLike

from .. import _validate as v
from .._docs import fill_doc
from .._generated import adjoint_orbits as _gen
from .._validate import Array
from ._common import DOC, pair_xN

__all__ = ["orbit_extremal_rhs", "orbit_hamiltonian", "brockett_potential"]


@fill_doc(DOC)
def orbit_extremal_rhs(x: ArrayLike, p: ArrayLike, N: ArrayLike) -> tuple[Array, Array]:
    r"""The extremal vector field of the orbit problem with Brockett's potential (paper, Section 3.4).

    .. math:: \dot x = [x, [p, x]],\qquad \dot p = [p, [p, x]] - [N, [N, x]].

    Parameters
    ----------
    %(xpN)s

    Returns
    -------
    xdot, pdot : ndarray, shape (..., n, n)
        The vector field, of the broadcast shape.

    Examples
    --------
    With the costate :math:`p = -N` of the one-sample extremal the state follows the double
    bracket flow:

    >>> import numpy as np
    >>> import symrb
    >>> x, N = symrb.hat([1.0, 0.5, 0.2]), symrb.hat([0.0, 0.0, 1.0])
    >>> xdot, pdot = symrb.orbits.orbit_extremal_rhs(x, -N, N)
    >>> bool(np.allclose(xdot, symrb.orbits.double_bracket_rhs(x, N)))
    True
    """
    xx, nn = pair_xN(x, N)
    pp = v.skew(p, "p", nn.shape[-1])
    return _gen.orbit_extremal_rhs(xx, pp, nn)


@fill_doc(DOC)
def orbit_hamiltonian(x: ArrayLike, p: ArrayLike, N: ArrayLike) -> Array:
    r"""The optimal Hamiltonian with Brockett's potential, conserved by :func:`orbit_extremal_rhs`.

    .. math:: H^* = -\tfrac12\langle x,[p,[p,x]]\rangle + V(x)
        = \tfrac12\|[p,x]\|^2 - \tfrac12\|[x,N]\|^2.

    Parameters
    ----------
    %(xpN)s

    Returns
    -------
    ndarray, shape (...)
        The Hamiltonian.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> x, N = symrb.hat([1.0, 0.5, 0.2]), symrb.hat([0.0, 0.0, 1.0])
    >>> print(round(float(symrb.orbits.orbit_hamiltonian(x, -N, N)), 6) + 0.0)  # 0 on this extremal
    0.0
    """
    xx, nn = pair_xN(x, N)
    pp = v.skew(p, "p", nn.shape[-1])
    return _gen.orbit_hamiltonian(xx, pp, nn)


@fill_doc(DOC)
def brockett_potential(x: ArrayLike, N: ArrayLike) -> Array:
    r"""Brockett's potential :math:`V(x) = -\tfrac12\|[x, N]\|^2 = \tfrac12\langle x, [N,[N,x]]\rangle`.

    Parameters
    ----------
    %(xN)s

    Returns
    -------
    ndarray, shape (...)
        The potential.

    Examples
    --------
    >>> import symrb
    >>> x, N = symrb.hat([1.0, 0.5, 0.2]), symrb.hat([0.0, 0.0, 1.0])
    >>> print(symrb.orbits.brockett_potential(x, N))  # -|x x n|^2 / 2 for n = 3
    -0.625
    """
    xx, nn = pair_xN(x, N)
    return _gen.brockett_potential(xx, nn)
