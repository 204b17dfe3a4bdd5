r"""The Lie algebra so(n), the group SO(n) and the inertia operators of the paper.

Conventions (the book's conventions page states them once more):

* pairing on so(n): :math:`\langle \xi, \eta\rangle = -\tfrac12 \operatorname{trace}(\xi\eta)`;
* for n = 3 the hat map :math:`\hat v w = v \times w`;
* ``lam`` is the 1-D diagonal of :math:`\Lambda`;
  :math:`J(\Omega) = \Lambda\Omega + \Omega\Lambda`,
  :math:`J^{-1}(M)_{ij} = M_{ij}/(\lambda_i + \lambda_j)`,
  :math:`J_D(U) = U\Lambda - \Lambda U^T`;
* matrices are the last two axes of an array; every function broadcasts over leading batch axes
  and never mutates its arguments.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from . import _validate as _v
from ._validate import Array
from .errors import InputError

__all__ = [
    "hat",
    "vee",
    "pairing",
    "commutator",
    "skew_part",
    "J",
    "J_inv",
    "J_D",
    "inertia_from_lam",
    "lam_from_inertia",
    "random_so",
    "random_SO",
    "random_lam",
    "as_generator",
]


def as_generator(seed: int | np.random.Generator | None) -> np.random.Generator:
    """A :class:`numpy.random.Generator` from a seed or an existing generator.

    Parameters
    ----------
    seed : int, numpy.random.Generator or None
        A seed for :func:`numpy.random.default_rng`, or a generator (returned as is).

    Returns
    -------
    numpy.random.Generator
        The generator.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> rng = np.random.default_rng(1)
    >>> symrb.algebra.as_generator(rng) is rng
    True
    >>> print(symrb.algebra.as_generator(1).integers(10) == np.random.default_rng(1).integers(10))
    True
    """
    if isinstance(seed, np.random.Generator):
        return seed
    return np.random.default_rng(seed)


def hat(v: ArrayLike) -> Array:
    r"""The hat map :math:`\mathbb R^3 \to \mathfrak{so}(3)`, :math:`\hat v w = v \times w`.

    Parameters
    ----------
    v : array_like, shape (..., 3)
        Vectors.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The skew-symmetric matrices :math:`\hat v`.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> print(symrb.hat([1, 2, 3]))
    [[ 0. -3.  2.]
     [ 3.  0. -1.]
     [-2.  1.  0.]]
    >>> print(symrb.hat([1, 2, 3]) @ [4, 5, 6], np.cross([1, 2, 3], [4, 5, 6]))
    [-3.  6. -3.] [-3  6 -3]
    """
    a = _v.as_float_array(v, "v")
    if a.ndim < 1 or a.shape[-1] != 3:
        raise InputError(f"v must have shape (..., 3), got {a.shape}")
    out = np.zeros(a.shape + (3,))
    x, y, z = a[..., 0], a[..., 1], a[..., 2]
    out[..., 0, 1], out[..., 0, 2] = -z, y
    out[..., 1, 0], out[..., 1, 2] = z, -x
    out[..., 2, 0], out[..., 2, 1] = -y, x
    return out


def vee(m: ArrayLike) -> Array:
    r"""The inverse of :func:`hat`.

    Parameters
    ----------
    m : array_like, shape (..., 3, 3)
        Skew-symmetric matrices.

    Returns
    -------
    ndarray, shape (..., 3)
        The vectors v with :math:`\hat v = m`.

    Examples
    --------
    >>> import symrb
    >>> print(symrb.vee(symrb.hat([1, 2, 3])))
    [1. 2. 3.]
    """
    a = _v.skew(m, "m", 3)
    return np.stack([a[..., 2, 1], a[..., 0, 2], a[..., 1, 0]], axis=-1)


def pairing(xi: ArrayLike, eta: ArrayLike) -> Array:
    r"""The pairing :math:`\langle\xi,\eta\rangle = -\tfrac12\operatorname{trace}(\xi\eta)` on
    :math:`\mathfrak{so}(n)`.

    For n = 3 it equals the dot product of the vectors :math:`\check\xi\cdot\check\eta` (claim S1).

    Parameters
    ----------
    xi, eta : array_like, shape (..., n, n)
        Matrices (skew-symmetric for the pairing of :math:`\mathfrak{so}(n)`); batch axes
        broadcast.

    Returns
    -------
    ndarray, shape (...)
        The pairings.

    Examples
    --------
    >>> import symrb
    >>> print(symrb.pairing(symrb.hat([1, 2, 3]), symrb.hat([4, 5, 6])))  # = 1*4 + 2*5 + 3*6
    32.0
    """
    a = _v.square(xi, "xi")
    b = _v.square(eta, "eta", a.shape[-1])
    return -0.5 * np.einsum("...ij,...ji->...", a, b)


def commutator(a: ArrayLike, b: ArrayLike) -> Array:
    """The matrix commutator :math:`[a, b] = ab - ba`.

    Parameters
    ----------
    a, b : array_like, shape (..., n, n)
        Square matrices; batch axes broadcast.

    Returns
    -------
    ndarray, shape (..., n, n)
        The commutators.

    Examples
    --------
    >>> import symrb
    >>> e1, e2 = symrb.hat([1, 0, 0]), symrb.hat([0, 1, 0])
    >>> print(symrb.vee(symrb.commutator(e1, e2)))  # [hat u, hat w] = hat(u x w)
    [0. 0. 1.]
    """
    x = _v.square(a, "a")
    y = _v.square(b, "b", x.shape[-1])
    return x @ y - y @ x


def skew_part(a: ArrayLike) -> Array:
    """The skew-symmetric part :math:`(a - a^T)/2`.

    Parameters
    ----------
    a : array_like, shape (..., n, n)
        Square matrices.

    Returns
    -------
    ndarray, shape (..., n, n)
        Their skew-symmetric parts.

    Examples
    --------
    >>> import symrb
    >>> print(symrb.algebra.skew_part([[1, 2], [0, 1]]))
    [[ 0.  1.]
     [-1.  0.]]
    """
    x = _v.square(a, "a")
    return 0.5 * (x - np.swapaxes(x, -1, -2))


def J(Omega: ArrayLike, lam: ArrayLike) -> Array:
    r"""The inertia operator :math:`J(\Omega) = \Lambda\Omega + \Omega\Lambda`.

    Parameters
    ----------
    Omega : array_like, shape (..., n, n)
        Skew-symmetric matrices (body angular velocities).
    lam : array_like, shape (..., n)
        The diagonal of :math:`\Lambda` (a 1-D array, not the matrix), with
        :math:`\lambda_i+\lambda_j>0` for :math:`i \ne j`.

    Returns
    -------
    M : ndarray, shape (..., n, n)
        :math:`M_{ij} = (\lambda_i+\lambda_j)\Omega_{ij}`.

    Examples
    --------
    >>> import symrb
    >>> print(symrb.J(symrb.hat([1, 1, 1]), [1, 2, 3]))
    [[ 0. -3.  4.]
     [ 3.  0. -5.]
     [-4.  5.  0.]]
    """
    L = _v.inertia(lam)
    W = _v.skew(Omega, "Omega", L.shape[-1])
    return (L[..., :, None] + L[..., None, :]) * W


def _Jinv_weights(lam: Array) -> Array:
    """W with W_ij = 1/(lam_i + lam_j), so that J^{-1}(M) = W * M (lam already validated)."""
    return 1.0 / (lam[..., :, None] + lam[..., None, :])


def J_inv(M: ArrayLike, lam: ArrayLike) -> Array:
    r"""The inverse inertia operator, :math:`J^{-1}(M)_{ij} = M_{ij}/(\lambda_i+\lambda_j)`.

    Parameters
    ----------
    M : array_like, shape (..., n, n)
        Skew-symmetric matrices (body momenta).
    lam : array_like, shape (..., n)
        The diagonal of :math:`\Lambda`, with :math:`\lambda_i+\lambda_j>0` for :math:`i \ne j`.

    Returns
    -------
    Omega : ndarray, shape (..., n, n)
        The body angular velocities.

    Examples
    --------
    >>> import symrb
    >>> lam = [1, 2, 3]
    >>> M = symrb.J(symrb.hat([1, 1, 1]), lam)
    >>> print(symrb.vee(symrb.J_inv(M, lam)))
    [1. 1. 1.]
    """
    L = _v.inertia(lam)
    A = _v.skew(M, "M", L.shape[-1])
    return _Jinv_weights(L) * A


def J_D(U: ArrayLike, lam: ArrayLike) -> Array:
    r"""The discrete inertia operator :math:`J_D(U) = U\Lambda - \Lambda U^T` (paper, Section 2.1).

    Its derivative at the identity is :math:`J` (claim D8).

    Parameters
    ----------
    U : array_like, shape (..., n, n)
        Square matrices (for U in SO(n) the result is in so(n)).
    lam : array_like, shape (..., n)
        The diagonal of :math:`\Lambda`, with :math:`\lambda_i+\lambda_j>0` for :math:`i \ne j`.

    Returns
    -------
    ndarray, shape (..., n, n)
        :math:`U\Lambda - \Lambda U^T`.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> lam = np.array([1.0, 2.0, 3.0])
    >>> Om = symrb.hat([1, 1, 1])
    >>> e = 1e-6  # the derivative at U = I along Omega is J(Omega)
    >>> dJD = (symrb.algebra.J_D(np.eye(3) + e * Om, lam) - symrb.algebra.J_D(np.eye(3) - e * Om, lam)) / (2 * e)
    >>> bool(np.allclose(dJD, symrb.J(Om, lam)))
    True
    """
    L = _v.inertia(lam)
    A = _v.square(U, "U", L.shape[-1])
    return A * L[..., None, :] - L[..., :, None] * np.swapaxes(A, -1, -2)


def inertia_from_lam(lam: ArrayLike) -> Array:
    r"""For n = 3: the principal moments of inertia
    :math:`I = (\lambda_2+\lambda_3, \lambda_3+\lambda_1, \lambda_1+\lambda_2)` (claim S2).

    Parameters
    ----------
    lam : array_like, shape (..., 3)
        The diagonal of :math:`\Lambda`.

    Returns
    -------
    ndarray, shape (..., 3)
        The principal moments.

    Examples
    --------
    >>> import symrb
    >>> print(symrb.algebra.inertia_from_lam([1, 2, 3]))
    [5. 4. 3.]
    """
    L = _v.as_float_array(lam, "lam")
    if L.shape[-1:] != (3,):
        raise InputError(f"lam must have shape (..., 3), got {L.shape}")
    return L.sum(axis=-1, keepdims=True) - L


def lam_from_inertia(inertia: ArrayLike) -> Array:
    r"""For n = 3: the inverse of :func:`inertia_from_lam`,
    :math:`\lambda_i = (I_1+I_2+I_3)/2 - I_i`.

    Parameters
    ----------
    inertia : array_like, shape (..., 3)
        Principal moments of inertia.

    Returns
    -------
    ndarray, shape (..., 3)
        The diagonal of :math:`\Lambda`.

    Examples
    --------
    >>> import symrb
    >>> print(symrb.algebra.lam_from_inertia([5, 4, 3]))
    [1. 2. 3.]
    """
    Ii = _v.as_float_array(inertia, "inertia")
    if Ii.shape[-1:] != (3,):
        raise InputError(f"inertia must have shape (..., 3), got {Ii.shape}")
    return 0.5 * Ii.sum(axis=-1, keepdims=True) - Ii


def random_so(
    n: int,
    size: tuple[int, ...] = (),
    scale: float = 1.0,
    seed: int | np.random.Generator | None = None,
) -> Array:
    """Random skew-symmetric matrices :math:`a - a^T`, :math:`a` with normal entries.

    Parameters
    ----------
    n : int
        The matrix size, >= 2.
    size : tuple of int, optional
        The batch shape.
    scale : float, optional
        The standard deviation of the entries of :math:`a`.
    seed : int, numpy.random.Generator or None, optional
        The random source (see :func:`as_generator`).

    Returns
    -------
    ndarray, shape size + (n, n)
        Skew-symmetric matrices.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> A = symrb.random_so(4, size=(2,), seed=0)
    >>> A.shape, bool(np.array_equal(A, -np.swapaxes(A, -1, -2)))
    ((2, 4, 4), True)
    """
    if n < 2:
        raise InputError(f"n must be >= 2, got {n}")
    rng = as_generator(seed)
    a = rng.standard_normal(tuple(size) + (n, n)) * scale
    return a - np.swapaxes(a, -1, -2)


def random_SO(
    n: int, size: tuple[int, ...] = (), seed: int | np.random.Generator | None = None
) -> Array:
    """Haar-random rotations (``scipy.stats.special_ortho_group``).

    Parameters
    ----------
    n : int
        The matrix size, >= 2.
    size : tuple of int, optional
        The batch shape.
    seed : int, numpy.random.Generator or None, optional
        The random source (see :func:`as_generator`).

    Returns
    -------
    ndarray, shape size + (n, n)
        Matrices in SO(n).

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> Q = symrb.random_SO(3, seed=0)
    >>> bool(np.allclose(Q.T @ Q, np.eye(3))), round(float(np.linalg.det(Q)), 12)
    (True, 1.0)
    """
    from scipy.stats import special_ortho_group

    if n < 2:
        raise InputError(f"n must be >= 2, got {n}")
    rng = as_generator(seed)
    count = int(np.prod(size)) if size else 1
    mats = special_ortho_group.rvs(n, size=count, random_state=rng)
    return np.asarray(mats, dtype=float).reshape(tuple(size) + (n, n))


def random_lam(
    n: int, low: float = 0.5, high: float = 2.0, seed: int | np.random.Generator | None = None
) -> Array:
    r"""A random positive diagonal of :math:`\Lambda`, sorted, with entries in [low, high).

    Parameters
    ----------
    n : int
        The number of entries.
    low, high : float, optional
        The range, ``0 < low < high``.
    seed : int, numpy.random.Generator or None, optional
        The random source (see :func:`as_generator`).

    Returns
    -------
    ndarray, shape (n,)
        The diagonal.

    Examples
    --------
    >>> import symrb
    >>> print(symrb.algebra.random_lam(4, seed=0).round(3))
    [0.525 0.561 0.905 1.455]
    """
    if not 0 < low < high:
        raise InputError(f"need 0 < low < high, got low={low}, high={high}")
    rng = as_generator(seed)
    return np.sort(rng.uniform(low, high, size=n))
