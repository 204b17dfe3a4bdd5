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
    """A :class:`numpy.random.Generator` from a seed or an existing generator."""
    if isinstance(seed, np.random.Generator):
        return seed
    return np.random.default_rng(seed)


def hat(v: ArrayLike) -> Array:
    r"""The hat map :math:`\mathbb R^3 \to \mathfrak{so}(3)`, :math:`\hat v w = v \times w`.

    ``v`` has shape (..., 3); the result has shape (..., 3, 3).
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
    """The inverse of :func:`hat`: a skew (..., 3, 3) array to its (..., 3) vector."""
    a = _v.skew(m, "m", 3)
    return np.stack([a[..., 2, 1], a[..., 0, 2], a[..., 1, 0]], axis=-1)


def pairing(xi: ArrayLike, eta: ArrayLike) -> Array:
    r""":math:`\langle\xi,\eta\rangle = -\tfrac12\operatorname{trace}(\xi\eta)`, batched.

    For n = 3 it equals the dot product of the vectors :math:`\check\xi\cdot\check\eta` (claim S1).
    """
    a = _v.square(xi, "xi")
    b = _v.square(eta, "eta", a.shape[-1])
    return -0.5 * np.einsum("...ij,...ji->...", a, b)


def commutator(a: ArrayLike, b: ArrayLike) -> Array:
    """The matrix commutator [a, b] = a b - b a, batched."""
    x = _v.square(a, "a")
    y = _v.square(b, "b", x.shape[-1])
    return x @ y - y @ x


def skew_part(a: ArrayLike) -> Array:
    """(a - a^T)/2, batched."""
    x = _v.square(a, "a")
    return 0.5 * (x - np.swapaxes(x, -1, -2))


def J(Omega: ArrayLike, lam: ArrayLike) -> Array:
    r"""The inertia operator :math:`J(\Omega) = \Lambda\Omega + \Omega\Lambda`.

    Parameters
    ----------
    Omega : array (..., n, n), skew-symmetric (the body angular velocity)
    lam : array (..., n), the diagonal of :math:`\Lambda`, with :math:`\lambda_i+\lambda_j>0`

    Returns
    -------
    M : array (..., n, n), :math:`M_{ij} = (\lambda_i+\lambda_j)\Omega_{ij}`.
    """
    L = _v.inertia(lam)
    W = _v.skew(Omega, "Omega", L.shape[-1])
    return (L[..., :, None] + L[..., None, :]) * W


def _Jinv_weights(lam: Array) -> Array:
    """W with W_ij = 1/(lam_i + lam_j), so that J^{-1}(M) = W * M (lam already validated)."""
    return 1.0 / (lam[..., :, None] + lam[..., None, :])


def J_inv(M: ArrayLike, lam: ArrayLike) -> Array:
    r"""The inverse inertia operator, :math:`J^{-1}(M)_{ij} = M_{ij}/(\lambda_i+\lambda_j)`.

    Shapes as in :func:`J`; ``M`` must be skew-symmetric.
    """
    L = _v.inertia(lam)
    A = _v.skew(M, "M", L.shape[-1])
    return _Jinv_weights(L) * A


def J_D(U: ArrayLike, lam: ArrayLike) -> Array:
    r"""The discrete inertia operator :math:`J_D(U) = U\Lambda - \Lambda U^T` (paper, eq. Ukdef1).

    ``U`` has shape (..., n, n) (any square matrix; for U in SO(n) the result is in so(n)).  Its
    derivative at the identity is :math:`J` (claim D8).
    """
    L = _v.inertia(lam)
    A = _v.square(U, "U", L.shape[-1])
    return A * L[..., None, :] - L[..., :, None] * np.swapaxes(A, -1, -2)


def inertia_from_lam(lam: ArrayLike) -> Array:
    """For n = 3: the principal moments I = (lam2+lam3, lam3+lam1, lam1+lam2) (claim S2)."""
    L = _v.as_float_array(lam, "lam")
    if L.shape[-1:] != (3,):
        raise InputError(f"lam must have shape (..., 3), got {L.shape}")
    return L.sum(axis=-1, keepdims=True) - L


def lam_from_inertia(inertia: ArrayLike) -> Array:
    """For n = 3: the inverse of :func:`inertia_from_lam`, lam_i = (I_1+I_2+I_3)/2 - I_i."""
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
    """Random skew-symmetric matrices of shape ``size + (n, n)`` with standard normal entries times ``scale``."""
    if n < 2:
        raise InputError(f"n must be >= 2, got {n}")
    rng = as_generator(seed)
    a = rng.standard_normal(tuple(size) + (n, n)) * scale
    return a - np.swapaxes(a, -1, -2)


def random_SO(
    n: int, size: tuple[int, ...] = (), seed: int | np.random.Generator | None = None
) -> Array:
    """Haar-random rotations of shape ``size + (n, n)`` (scipy.stats.special_ortho_group)."""
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
    """A random positive diagonal of Lambda with distinct entries in [low, high)."""
    if not 0 < low < high:
        raise InputError(f"need 0 < low < high, got low={low}, high={high}")
    rng = as_generator(seed)
    return np.sort(rng.uniform(low, high, size=n))
