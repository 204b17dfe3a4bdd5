r"""The classical n-dimensional rigid body (paper, Section 3.1).

.. math::

    \dot Q = Q\Omega,\qquad \dot M = [M,\Omega],\qquad M = J(\Omega) = \Lambda\Omega + \Omega\Lambda.

Each function validates its input and calls one kernel generated in
:mod:`symrb._generated.rigid_body` by :mod:`derivations.parts.rigid_body`.
"""

from __future__ import annotations

from numpy.typing import ArrayLike

from . import _validate as v
from ._generated import rigid_body as _gen
from ._validate import Array
from .errors import InputError

__all__ = [
    "rigid_body_rhs",
    "kinetic_energy",
    "casimir_traces",
    "manakov_integrals",
    "euler_rhs_so3",
]


def rigid_body_rhs(Q: ArrayLike, M: ArrayLike, lam: ArrayLike) -> tuple[Array, Array]:
    r"""The rigid body vector field :math:`(\dot Q, \dot M) = (Q\Omega, [M, \Omega])`,
    :math:`\Omega = J^{-1}(M)`.

    Parameters
    ----------
    Q : array (..., n, n), the attitude (any square matrix is accepted; SO(n) is invariant)
    M : array (..., n, n), skew-symmetric body angular momentum
    lam : array (..., n), diagonal of :math:`\Lambda` with :math:`\lambda_i+\lambda_j>0`

    Returns
    -------
    (Qdot, Mdot) : arrays broadcast to the common batch shape.
    """
    L = v.inertia(lam)
    nn = L.shape[-1]
    return _gen.rigid_body_rhs(v.square(Q, "Q", nn), v.skew(M, "M", nn), L)


def kinetic_energy(M: ArrayLike, lam: ArrayLike) -> Array:
    r"""The kinetic energy :math:`\tfrac12\langle J^{-1}M, M\rangle = \tfrac12\langle\Omega, J\Omega\rangle`.

    The paper's Hamiltonians (S5, S12) are half of it: :math:`\tfrac14\langle J^{-1}M, M\rangle`.
    """
    L = v.inertia(lam)
    return _gen.kinetic_energy(v.skew(M, "M", L.shape[-1]), L)


def casimir_traces(M: ArrayLike) -> Array:
    r"""The Casimirs :math:`(\operatorname{tr}M^2, \operatorname{tr}M^4, \operatorname{tr}M^6)`, shape (..., 3)."""
    return _gen.casimir_traces(v.skew(M, "M"))


def manakov_integrals(M: ArrayLike, lam: ArrayLike) -> Array:
    r"""Manakov's integrals: coefficients of :math:`\lambda^j` in :math:`\operatorname{tr}(M+\lambda\Lambda^2)^k`.

    The six non-trivial ones for :math:`2\le k\le 5` (words with an odd number of M's vanish for
    skew M), shape (..., 6), in the order
    :math:`(k,j) = (2,0), (3,1), (4,0), (4,2), (5,1), (5,3)`:
    :math:`\operatorname{tr}M^2`, :math:`3\operatorname{tr}(\Lambda^2M^2)`, :math:`\operatorname{tr}M^4`,
    :math:`4\operatorname{tr}(\Lambda^4M^2)+2\operatorname{tr}(\Lambda^2M\Lambda^2M)`,
    :math:`5\operatorname{tr}(\Lambda^2M^4)`,
    :math:`5\operatorname{tr}(\Lambda^6M^2)+5\operatorname{tr}(\Lambda^4M\Lambda^2M)`.
    """
    L = v.inertia(lam)
    return _gen.manakov_integrals(v.skew(M, "M", L.shape[-1]), L)


def euler_rhs_so3(m: ArrayLike, lam: ArrayLike) -> Array:
    r"""Euler's equations for n = 3: :math:`\dot m = m\times\omega`, :math:`\omega_i = m_i/I_i`,
    :math:`I_1=\lambda_2+\lambda_3` (cyclic).  ``m`` and ``lam`` have shape (..., 3)."""
    L = v.inertia(lam)
    if L.shape[-1] != 3:
        raise InputError(f"lam must have shape (..., 3) for euler_rhs_so3, got {L.shape}")
    mm = v.as_float_array(m, "m")
    if mm.shape[-1:] != (3,):
        raise InputError(f"m must have shape (..., 3), got {mm.shape}")
    return _gen.euler_rhs_so3(mm, L)
