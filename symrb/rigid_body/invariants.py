r"""The classical n-dimensional rigid body (paper, Section 3.1).

.. math::

    \dot Q = Q\Omega,\qquad \dot M = [M,\Omega],\qquad M = J(\Omega) = \Lambda\Omega + \Omega\Lambda.

Each function validates its input and calls one kernel generated in
:mod:`symrb._generated.rigid_body` by the claims S2-S4 of :mod:`derivations.claims.section3`.
"""

from __future__ import annotations

from numpy.typing import ArrayLike

from .. import _validate as v
from .._docs import fill
from .._generated import rigid_body as _gen
from .._validate import Array
from ..errors import InputError

__all__ = [
    "rigid_body_rhs",
    "kinetic_energy",
    "casimir_traces",
    "manakov_integrals",
    "euler_rhs_so3",
]


@fill
def rigid_body_rhs(Q: ArrayLike, M: ArrayLike, lam: ArrayLike) -> tuple[Array, Array]:
    r"""The rigid body vector field :math:`(\dot Q, \dot M) = (Q\Omega, [M, \Omega])`,
    :math:`\Omega = J^{-1}(M)`.

    Parameters
    ----------
    Q : array_like, shape (..., n, n)
        The attitude (any square matrix is accepted; SO(n) is invariant).
    M : array_like, shape (..., n, n)
        The skew-symmetric body angular momentum.
    %(lam)s

    Returns
    -------
    Qdot, Mdot : ndarray, shape (..., n, n)
        The vector field, broadcast to the common batch shape.

    Examples
    --------
    For n = 3 the momentum equation is Euler's, :math:`\dot m = m \times \omega`:

    >>> import numpy as np
    >>> import symrb
    >>> lam, m = np.array([0.7, 1.1, 1.6]), np.array([0.5, 1.0, 1.5])
    >>> Qdot, Mdot = symrb.rigid_body.rigid_body_rhs(np.eye(3), symrb.hat(m), lam)
    >>> print(symrb.vee(Mdot).round(4), symrb.rigid_body.euler_rhs_so3(m, lam).round(4))
    [ 0.1812 -0.1389  0.0322] [ 0.1812 -0.1389  0.0322]
    """
    L = v.inertia(lam)
    nn = L.shape[-1]
    return _gen.rigid_body_rhs(v.square(Q, "Q", nn), v.skew(M, "M", nn), L)


@fill
def kinetic_energy(M: ArrayLike, lam: ArrayLike) -> Array:
    r"""The kinetic energy :math:`\tfrac12\langle J^{-1}M, M\rangle = \tfrac12\langle\Omega, J\Omega\rangle`.

    The paper's Hamiltonians (S5, S12) are half of it: :math:`\tfrac14\langle J^{-1}M, M\rangle`.

    Parameters
    ----------
    M : array_like, shape (..., n, n)
        Skew-symmetric body momenta.
    %(lam)s

    Returns
    -------
    ndarray, shape (...)
        The kinetic energies.

    Examples
    --------
    For n = 3 it is :math:`\sum_i m_i^2/(2I_i)` with the principal moments :math:`I`:

    >>> import numpy as np
    >>> import symrb
    >>> lam, m = np.array([0.7, 1.1, 1.6]), np.array([0.5, 1.0, 1.5])
    >>> I = symrb.algebra.inertia_from_lam(lam)
    >>> print(round(float(symrb.kinetic_energy(symrb.hat(m), lam)), 6))
    0.888688
    >>> print(round(float(np.sum(m**2 / (2 * I))), 6))
    0.888688
    """
    L = v.inertia(lam)
    return _gen.kinetic_energy(v.skew(M, "M", L.shape[-1]), L)


def casimir_traces(M: ArrayLike) -> Array:
    r"""The Casimirs :math:`(\operatorname{tr}M^2, \operatorname{tr}M^4, \operatorname{tr}M^6)`.

    Parameters
    ----------
    M : array_like, shape (..., n, n)
        Skew-symmetric matrices.

    Returns
    -------
    ndarray, shape (..., 3)
        The three traces.

    Examples
    --------
    >>> import symrb
    >>> print(symrb.casimir_traces(symrb.hat([0.5, 1.0, 1.5])))  # -2|m|^2, 2|m|^4, -2|m|^6
    [ -7.    24.5  -85.75]
    """
    return _gen.casimir_traces(v.skew(M, "M"))


@fill
def manakov_integrals(M: ArrayLike, lam: ArrayLike) -> Array:
    r"""Manakov's integrals: coefficients of :math:`\lambda^j` in :math:`\operatorname{tr}(M+\lambda\Lambda^2)^k`.

    The six non-trivial ones for :math:`2\le k\le 5` (words with an odd number of M's vanish for
    skew M), shape (..., 6), in the order
    :math:`(k,j) = (2,0), (3,1), (4,0), (4,2), (5,1), (5,3)`:
    :math:`\operatorname{tr}M^2`, :math:`3\operatorname{tr}(\Lambda^2M^2)`, :math:`\operatorname{tr}M^4`,
    :math:`4\operatorname{tr}(\Lambda^4M^2)+2\operatorname{tr}(\Lambda^2M\Lambda^2M)`,
    :math:`5\operatorname{tr}(\Lambda^2M^4)`,
    :math:`5\operatorname{tr}(\Lambda^6M^2)+5\operatorname{tr}(\Lambda^4M\Lambda^2M)`.

    Parameters
    ----------
    M : array_like, shape (..., n, n)
        Skew-symmetric body momenta.
    %(lam)s

    Returns
    -------
    ndarray, shape (..., 6)
        The six integrals.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> lam = np.array([0.7, 1.1, 1.6])
    >>> y0 = {"Q": np.eye(3), "M": symrb.hat([0.5, 1.0, 1.5])}
    >>> sol = symrb.integrate(symrb.RigidBody, (0, 5), y0, lam=lam, rtol=1e-12, t_eval=[0, 5])
    >>> F = symrb.manakov_integrals(sol.y.M, lam)
    >>> F.shape, bool(np.abs(F[1] - F[0]).max() < 1e-9)  # conserved along the flow
    ((2, 6), True)
    """
    L = v.inertia(lam)
    return _gen.manakov_integrals(v.skew(M, "M", L.shape[-1]), L)


def euler_rhs_so3(m: ArrayLike, lam: ArrayLike) -> Array:
    r"""Euler's equations for n = 3: :math:`\dot m = m\times\omega`, :math:`\omega_i = m_i/I_i`,
    :math:`I_1=\lambda_2+\lambda_3` (cyclic).

    Parameters
    ----------
    m : array_like, shape (..., 3)
        Body angular momenta (vectors).
    lam : array_like, shape (..., 3)
        The diagonal of :math:`\Lambda`.

    Returns
    -------
    ndarray, shape (..., 3)
        :math:`\dot m`.

    Examples
    --------
    >>> import symrb
    >>> print(symrb.rigid_body.euler_rhs_so3([0.5, 1.0, 1.5], [0.7, 1.1, 1.6]).round(4))
    [ 0.1812 -0.1389  0.0322]
    """
    L = v.inertia(lam)
    if L.shape[-1] != 3:
        raise InputError(f"lam must have shape (..., 3) for euler_rhs_so3, got {L.shape}")
    mm = v.as_float_array(m, "m")
    if mm.shape[-1:] != (3,):
        raise InputError(f"m must have shape (..., 3), got {mm.shape}")
    return _gen.euler_rhs_so3(mm, L)
