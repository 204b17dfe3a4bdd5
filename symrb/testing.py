r"""Hypothesis strategies for the hard cases of symrb (needs the ``test`` extra).

The strategies draw the *structure* of a case from Hypothesis (the dimension, the kind of
inertia, the exponent of a norm, the relative distance to the fold, the batch shape) and the
remaining random directions from a NumPy generator seeded by a Hypothesis integer, so that every
example is reproducible and shrinks towards small n, simple kinds and moderate scales.

The regimes covered (the ones where the numerics are hard):

* inertia :math:`\lambda` (:func:`inertias`): entries spread over :math:`[10^{-6}, 10^6]`, a
  nearly equal pair :math:`\lambda_j = \lambda_i(1 + \delta)` with :math:`\delta` down to
  :math:`10^{-12}`, an exactly equal pair (a symmetric top), and the spherical top;
* momenta for :math:`J_D(U) = U\Lambda - \Lambda U^T = M` (:func:`jd_momenta`): :math:`\|M\|_F`
  from :math:`10^{-14}` up to :math:`t^*(1 - \delta)` with :math:`t^*` the fold along the ray
  (:func:`symrb.fold_scale`) and :math:`\delta` down to :math:`10^{-9}`;
* momenta for :func:`symrb.symmetric.P_from_M` (:func:`pfm_momenta`): :math:`\|M\|_{op} = 2(1 - \delta)`,
  :math:`\delta` down to :math:`10^{-12}`, including two equal planes;
* attitudes (:func:`attitudes`): Haar-random rotations and rotations near a half-turn
  (:math:`\pi - \epsilon` in one or more planes, :math:`\epsilon` down to 0);
* dimensions :math:`2 \le n \le 64` (:func:`dimensions`), batch shapes with empty and size-1 axes
  (:func:`batch_shapes`), dtypes (:func:`dtypes`) and time steps up to the fold
  (:func:`step_sizes`).

Examples
--------
>>> from hypothesis import given, settings
>>> import numpy as np
>>> import symrb
>>> from symrb.testing import inertias
>>> @settings(max_examples=5, derandomize=True, database=None)
... @given(inertias(n=3))
... def check(lam):
...     assert lam.shape == (3,) and np.all(lam > 0)
>>> check()
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

try:
    from hypothesis import strategies as st
    from hypothesis.extra import numpy as hnp
except ImportError as exc:  # pragma: no cover - exercised in the clean-venv wheel test
    raise ImportError(
        "symrb.testing needs hypothesis, which comes with the test extra: "
        "pip install 'symrb[test]' (or pip install hypothesis)"
    ) from exc

from .algebra import random_SO, random_so
from .solvers import fold_scale

__all__ = [
    "INERTIA_KINDS",
    "HardCase",
    "dimensions",
    "batch_shapes",
    "dtypes",
    "seeds",
    "inertias",
    "attitudes",
    "jd_momenta",
    "jd_cases",
    "hard_inertia",
    "pfm_momenta",
    "step_sizes",
]

#: The kinds of inertia :func:`inertias` draws.
INERTIA_KINDS = ("moderate", "spread", "near_equal", "equal_pair", "spherical")

#: Relative distances to the fold (``1 - t/t*``) that :func:`jd_momenta` reaches.
_NEAR_FOLD = (1e-9, 1e-6, 1e-3)


@dataclass(frozen=True)
class HardCase:
    r"""A generated problem :math:`J_D(U) = M` with what is known about it.

    Attributes
    ----------
    M : ndarray, shape (n, n)
        The skew right-hand side.
    lam : ndarray, shape (n,)
        The diagonal of :math:`\Lambda`.
    kind : str
        The kind of inertia (one of :data:`INERTIA_KINDS`).
    fold : float
        :math:`t^*` of :func:`symrb.fold_scale` (``inf`` for ``M = 0``): ``M`` is solvable when
        ``fold > 1``.
    distance : float
        The relative distance to the fold the case was drawn at, :math:`1 - 1/t^*`
        (1 for tiny momenta).

    Examples
    --------
    >>> import numpy as np
    >>> from symrb.testing import HardCase
    >>> case = HardCase(np.zeros((2, 2)), np.ones(2), "spherical", float("inf"), 1.0)
    >>> case.n
    2
    """

    M: np.ndarray
    lam: np.ndarray
    kind: str
    fold: float
    distance: float

    @property
    def n(self) -> int:
        """The dimension."""
        return int(self.lam.shape[-1])


def seeds() -> st.SearchStrategy[np.random.Generator]:
    """NumPy generators seeded from a Hypothesis integer (shrinks to seed 0).

    Returns
    -------
    SearchStrategy of numpy.random.Generator
        Generators, one per drawn seed.

    Examples
    --------
    >>> from hypothesis import given, settings
    >>> from symrb.testing import seeds
    >>> @settings(max_examples=3, derandomize=True, database=None)
    ... @given(seeds())
    ... def check(rng):
    ...     assert 0 <= rng.uniform() < 1
    >>> check()
    """
    return st.integers(0, 2**32 - 1).map(np.random.default_rng)


def dimensions(min_n: int = 2, max_n: int = 64) -> st.SearchStrategy[int]:
    """Matrix sizes n in ``[min_n, max_n]``, small ones (2-5) drawn more often.

    Parameters
    ----------
    min_n, max_n : int, optional
        The range, ``2 <= min_n <= max_n``.

    Returns
    -------
    SearchStrategy of int
        The drawn sizes.

    Examples
    --------
    >>> from hypothesis import given, settings
    >>> from symrb.testing import dimensions
    >>> @settings(max_examples=10, derandomize=True, database=None)
    ... @given(dimensions(2, 8))
    ... def check(n):
    ...     assert 2 <= n <= 8
    >>> check()
    """
    if not 2 <= min_n <= max_n:
        raise ValueError(f"need 2 <= min_n <= max_n, got {min_n}, {max_n}")
    small = st.integers(min_n, min(max_n, max(min_n, 5)))
    return st.one_of(small, st.integers(min_n, max_n))


def batch_shapes(max_dims: int = 2, max_side: int = 3) -> st.SearchStrategy[tuple[int, ...]]:
    """Batch shapes ``(...)`` with 0 to ``max_dims`` axes, including empty and size-1 axes.

    Parameters
    ----------
    max_dims : int, optional
        The most batch axes.
    max_side : int, optional
        The largest axis length.

    Returns
    -------
    SearchStrategy of tuple of int
        The drawn shapes.

    Examples
    --------
    >>> from hypothesis import given, settings
    >>> from symrb.testing import batch_shapes
    >>> @settings(max_examples=10, derandomize=True, database=None)
    ... @given(batch_shapes())
    ... def check(shape):
    ...     assert len(shape) <= 2 and all(0 <= s <= 3 for s in shape)
    >>> check()
    """
    return hnp.array_shapes(min_dims=0, max_dims=max_dims, min_side=0, max_side=max_side)


def dtypes() -> st.SearchStrategy[np.dtype]:
    """The dtypes a user may pass: float64, float32, int64 and complex128.

    symrb computes in float64: integer input is converted exactly; float32 and complex input is
    rejected with an :class:`symrb.InputError` (see the book's page "Hard cases").

    Returns
    -------
    SearchStrategy of numpy.dtype
        The drawn dtypes.

    Examples
    --------
    >>> from hypothesis import given, settings
    >>> from symrb.testing import dtypes
    >>> @settings(max_examples=8, derandomize=True, database=None)
    ... @given(dtypes())
    ... def check(dt):
    ...     assert dt.kind in "fic"
    >>> check()
    """
    return st.sampled_from(
        [np.dtype(np.float64), np.dtype(np.float32), np.dtype(np.int64), np.dtype(np.complex128)]
    )


def _log_uniform(rng: np.random.Generator, lo: float, hi: float, size: int) -> np.ndarray:
    return np.exp(rng.uniform(np.log(lo), np.log(hi), size=size))


@st.composite
def inertias(
    draw: st.DrawFn,
    n: int | None = None,
    kinds: tuple[str, ...] = INERTIA_KINDS,
    max_n: int = 64,
) -> np.ndarray:
    r"""Diagonals :math:`\lambda` of :math:`\Lambda`, shape (n,), every entry > 0.

    Kinds (``kinds`` selects among them):

    ``"moderate"``
        entries uniform in [0.5, 2];
    ``"spread"``
        log-uniform entries in :math:`[10^{-k/2}, 10^{k/2}]`, :math:`k \in [1, 12]`, both
        extremes present (spread :math:`10^k`, up to :math:`10^{12}` with entries from
        :math:`10^{-6}` to :math:`10^6`);
    ``"near_equal"``
        moderate entries with one pair :math:`\lambda_j = \lambda_i(1 + \delta)`,
        :math:`\delta = 10^{-k}`, :math:`k \in [1, 12]`;
    ``"equal_pair"``
        moderate entries with one exactly equal pair (a symmetric top);
    ``"spherical"``
        all entries equal (the spherical top).

    Parameters
    ----------
    n : int, optional
        The dimension; drawn from :func:`dimensions` when None.
    kinds : tuple of str, optional
        The kinds to draw from.
    max_n : int, optional
        The largest dimension when ``n`` is None.

    Returns
    -------
    SearchStrategy of ndarray
        Diagonals of :math:`\Lambda`, shape (..., n).

    Examples
    --------
    >>> from hypothesis import given, settings
    >>> import numpy as np
    >>> from symrb.testing import inertias
    >>> @settings(max_examples=10, derandomize=True, database=None)
    ... @given(inertias(n=4, kinds=("spherical",)))
    ... def check(lam):
    ...     assert np.ptp(lam) == 0
    >>> check()
    """
    unknown = set(kinds) - set(INERTIA_KINDS)
    if unknown or not kinds:
        raise ValueError(f"kinds must be a non-empty subset of {INERTIA_KINDS}, got {kinds}")
    nn = draw(dimensions(2, max_n)) if n is None else int(n)
    kind = draw(st.sampled_from(kinds))
    return _inertia_of_kind(kind, nn, draw(seeds()), draw(st.integers(1, 12)))


def hard_inertia(
    kind: str, n: int, k: int, seed: int | np.random.Generator | None = None
) -> np.ndarray:
    r"""One inertia :math:`\lambda \in \mathbb{R}^n_{>0}` of a kind, as :func:`inertias` draws it.

    The kinds: ``"spread"``, entries log-uniform in :math:`[10^{-k/2}, 10^{k/2}]` with both ends
    present (spread :math:`\max\lambda/\min\lambda = 10^k`); ``"near_equal"``, moderate entries
    with one pair :math:`\lambda_j = \lambda_i(1 + 10^{-k})`; ``"equal_pair"``, ``"moderate"``
    (uniform in [0.5, 2]) and ``"spherical"`` (all equal), for which ``k`` is not used.

    Parameters
    ----------
    kind : str
        One of :data:`INERTIA_KINDS`.
    n : int
        The dimension, >= 2.
    k : int
        The exponent: the spread is :math:`10^k`, or the pair's relative gap :math:`10^{-k}`.
    seed : int or numpy.random.Generator, optional
        The random source (a Generator is advanced, so that the same sequence of calls gives
        the same cases).

    Returns
    -------
    ndarray, shape (n,)
        The diagonal of :math:`\Lambda`.

    Raises
    ------
    symrb.errors.InputError
        For an unknown kind or n < 2.

    Examples
    --------
    >>> import numpy as np
    >>> from symrb.testing import hard_inertia
    >>> lam = hard_inertia("spread", 4, 8, seed=1)
    >>> float(lam.max() / lam.min())
    100000000.0
    """
    from .errors import InputError

    if kind not in INERTIA_KINDS:
        raise InputError(f"kind must be one of {INERTIA_KINDS}, got {kind!r}")
    if int(n) < 2:
        raise InputError(f"n must be at least 2, got {n!r}")
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    return _inertia_of_kind(kind, int(n), rng, int(k))


def _inertia_of_kind(kind: str, nn: int, rng: np.random.Generator, k: int) -> np.ndarray:
    if kind == "moderate":
        return np.sort(rng.uniform(0.5, 2.0, nn))
    if kind == "spread":
        # k = 12: entries in [1e-6, 1e6] with both extremes (spread 1e12); smaller k: a spread
        # of 10^k around 1 (Hypothesis shrinks k towards 1)
        lo, hi = 10.0 ** (-k / 2), 10.0 ** (k / 2)
        lam = _log_uniform(rng, lo, hi, nn)
        lam[:2] = lo, hi
        return np.asarray(rng.permutation(lam))
    if kind == "near_equal":
        lam = rng.uniform(0.5, 2.0, nn)
        i, j = rng.choice(nn, 2, replace=False)
        lam[j] = lam[i] * (1.0 + 10.0 ** (-k))
        return lam
    if kind == "equal_pair":
        lam = rng.uniform(0.5, 2.0, nn)
        i, j = rng.choice(nn, 2, replace=False)
        lam[j] = lam[i]
        return lam
    return np.full(nn, float(rng.uniform(0.5, 2.0)))


def _half_turns(nn: int, rng: np.random.Generator, eps: float, planes: int) -> np.ndarray:
    """A rotation by pi - eps in ``planes`` random orthogonal planes."""
    Z = random_SO(nn, seed=rng)
    R = np.eye(nn)
    c, s = np.cos(np.pi - eps), np.sin(np.pi - eps)
    for p in range(min(planes, nn // 2)):
        i = 2 * p
        R[i : i + 2, i : i + 2] = [[c, -s], [s, c]]
    return Z @ R @ Z.T


@st.composite
def attitudes(draw: st.DrawFn, n: int, near_half_turn: bool | None = None) -> np.ndarray:
    r"""Attitudes :math:`Q \in SO(n)`: Haar-random, or near a rotation by :math:`\pi`.

    Near a half-turn: :math:`Q = Z R Z^T` with :math:`Z` Haar-random and :math:`R` a rotation by
    :math:`\pi - \epsilon` in one to :math:`\lfloor n/2\rfloor` coordinate planes,
    :math:`\epsilon \in \{0\} \cup [10^{-12}, 10^{-1}]`.

    Parameters
    ----------
    n : int
        The dimension, >= 2.
    near_half_turn : bool, optional
        Force the near-half-turn kind (True) or the Haar-random one (False); drawn when None.

    Returns
    -------
    SearchStrategy of ndarray
        Attitudes, shape (n, n).

    Examples
    --------
    >>> from hypothesis import given, settings
    >>> import numpy as np
    >>> from symrb.testing import attitudes
    >>> @settings(max_examples=5, derandomize=True, database=None)
    ... @given(attitudes(3, near_half_turn=True))
    ... def check(Q):
    ...     assert np.allclose(Q.T @ Q, np.eye(3)) and np.trace(Q) < -0.9
    >>> check()
    """
    rng = draw(seeds())
    half = draw(st.booleans()) if near_half_turn is None else near_half_turn
    if not half:
        return random_SO(n, seed=rng)
    k = draw(st.integers(1, 13))
    eps = 0.0 if k == 13 else 10.0 ** (-k)
    planes = draw(st.integers(1, max(1, n // 2)))
    return _half_turns(n, rng, eps, planes)


@st.composite
def jd_momenta(
    draw: st.DrawFn, lam: np.ndarray, near_fold: bool | None = None
) -> tuple[np.ndarray, float, float]:
    r"""A skew :math:`M` for :math:`J_D(U) = M` with the given ``lam``, and its fold.

    A random direction :math:`A` (normal entries) is scaled either to a tiny norm
    :math:`\|M\|_F = 10^{-k}`, :math:`k \in [6, 14]`, or to a fraction of the fold,
    :math:`M = (1 - \delta)t^*A` with :math:`t^*` = ``fold_scale(A, lam)`` and
    :math:`\delta \in \{0.5, 0.1, 10^{-3}, 10^{-6}, 10^{-9}\}`, but at least
    :math:`10^6\varepsilon\max\lambda/\min\lambda` (closer than that,
    :func:`symrb.fold_scale` cannot tell the sides apart: see its accuracy).

    Parameters
    ----------
    lam : ndarray, shape (n,)
        The diagonal of :math:`\Lambda`.
    near_fold : bool, optional
        Force a momentum near the fold (True) or a tiny one (False); drawn when None.

    Returns
    -------
    SearchStrategy of (M, fold, distance)
        ``fold`` is :func:`symrb.fold_scale` of ``M`` itself and ``distance`` the :math:`\delta`
        it was drawn at (1 for tiny momenta).

    Examples
    --------
    >>> from hypothesis import given, settings
    >>> import numpy as np
    >>> from symrb.testing import jd_momenta
    >>> @settings(max_examples=5, derandomize=True, database=None)
    ... @given(jd_momenta(np.array([0.7, 1.1, 1.6]), near_fold=True))
    ... def check(case):
    ...     M, fold, delta = case
    ...     assert fold > 1 and abs(fold * (1 - delta) - 1) < 1e-6
    >>> check()
    """
    nn = lam.shape[-1]
    A = random_so(nn, seed=draw(seeds()))
    near = draw(st.booleans()) if near_fold is None else near_fold
    if not near:
        k = draw(st.integers(6, 14))
        M = A * (10.0 ** (-k) / np.linalg.norm(A))
        return M, float(fold_scale(M, lam)), 1.0
    # closer to the fold than ten times fold_scale's accuracy (1e5 eps spread) the side is unknown
    floor = min(0.5, 1e6 * float(np.finfo(float).eps) * float(lam.max() / lam.min()))
    delta = max(draw(st.sampled_from((0.5, 0.1) + _NEAR_FOLD)), floor)
    t = float(fold_scale(A, lam))
    M = (1.0 - delta) * t * A
    return M, 1.0 / (1.0 - delta), delta


@st.composite
def jd_cases(
    draw: st.DrawFn,
    min_n: int = 2,
    max_n: int = 12,
    kinds: tuple[str, ...] = INERTIA_KINDS,
    near_fold: bool | None = None,
) -> HardCase:
    r"""Complete problems :math:`J_D(U) = M` (a :class:`HardCase`): inertia and momentum.

    ``max_n`` is 12 by default because locating the fold of each case costs about a hundred
    eigenvalue problems of size 2n; pass ``max_n=64`` for the largest cases.

    Parameters
    ----------
    min_n, max_n : int, optional
        The range of dimensions.
    kinds : tuple of str, optional
        The kinds of inertia (see :func:`inertias`).
    near_fold : bool, optional
        As for :func:`jd_momenta`.

    Returns
    -------
    SearchStrategy of HardCase
        The drawn cases.

    Examples
    --------
    >>> from hypothesis import given, settings
    >>> import symrb
    >>> from symrb.testing import jd_cases
    >>> @settings(max_examples=5, derandomize=True, database=None, deadline=None)
    ... @given(jd_cases(max_n=4))
    ... def check(case):
    ...     U = symrb.solve_moser_veselov(case.M, case.lam)
    ...     assert U.shape == case.M.shape
    >>> check()
    """
    nn = draw(dimensions(min_n, max_n))
    kind = draw(st.sampled_from(kinds))
    lam = _inertia_of_kind(kind, nn, draw(seeds()), draw(st.integers(1, 12)))
    M, fold, delta = draw(jd_momenta(lam, near_fold=near_fold))
    return HardCase(M=M, lam=lam, kind=kind, fold=fold, distance=delta)


@st.composite
def pfm_momenta(draw: st.DrawFn, n: int, tiny: bool | None = None) -> tuple[np.ndarray, float]:
    r"""Skew :math:`M` for :func:`symrb.symmetric.P_from_M` with :math:`\|M\|_{op} = 2(1 - \delta)`.

    :math:`\delta = 10^{-k}`, :math:`k \in [0, 12]` (down to 1e-12 from the branch point at 2);
    for even n a case with all planes at the same rate (equal eigenvalue pairs) is drawn too;
    with ``tiny`` the norm is :math:`10^{-k}`, :math:`k \in [6, 14]`, instead.

    Parameters
    ----------
    n : int
        The dimension, >= 2.
    tiny : bool, optional
        Force a tiny norm (True) or one near 2 (False); drawn when None.

    Returns
    -------
    SearchStrategy of (M, delta)
        ``delta`` is :math:`1 - \|M\|_{op}/2` as drawn.

    Examples
    --------
    >>> from hypothesis import given, settings
    >>> import numpy as np
    >>> from symrb.testing import pfm_momenta
    >>> @settings(max_examples=5, derandomize=True, database=None)
    ... @given(pfm_momenta(4, tiny=False))
    ... def check(case):
    ...     M, delta = case
    ...     assert abs(np.linalg.norm(M, 2) - 2 * (1 - delta)) < 1e-14
    >>> check()
    """
    rng = draw(seeds())
    small = draw(st.booleans()) if tiny is None else tiny
    if small:
        k = draw(st.integers(6, 14))
        A = random_so(n, seed=rng)
        return A * (10.0 ** (-k) / np.linalg.norm(A, 2)), 1.0 - 10.0 ** (-k) / 2
    k = draw(st.integers(0, 12))
    delta = 0.5 if k == 0 else 10.0 ** (-k)
    top = 2.0 * (1.0 - delta)
    equal = n >= 4 and draw(st.booleans())
    Z = random_SO(n, seed=rng)
    B = np.zeros((n, n))
    rates = np.full(n // 2, top) if equal else np.concatenate([[top], rng.uniform(0, top, n // 2)])
    for p in range(n // 2):
        B[2 * p, 2 * p + 1], B[2 * p + 1, 2 * p] = rates[p], -rates[p]
    M = Z @ B @ Z.T
    return 0.5 * (M - M.T), delta


@st.composite
def step_sizes(
    draw: st.DrawFn, M: np.ndarray, lam: np.ndarray, beyond: bool = False
) -> tuple[float, float]:
    r"""Time steps :math:`h` up to the fold for a continuous momentum ``M``: :math:`hM` is at
    relative distance :math:`\delta` from the fold, :math:`h = (1 - \delta)h^*`,
    :math:`h^* = ` ``fold_scale(M, lam)``.

    Parameters
    ----------
    M : ndarray, shape (n, n)
        A skew momentum (continuous scale), not zero.
    lam : ndarray, shape (n,)
        The diagonal of :math:`\Lambda`.
    beyond : bool, optional
        Draw steps past the fold instead (:math:`h = (1 + \delta)h^*`).

    Returns
    -------
    SearchStrategy of (h, h_fold)
        The step and the fold scale of ``M``.

    Examples
    --------
    >>> from hypothesis import given, settings
    >>> import numpy as np
    >>> import symrb
    >>> from symrb.testing import step_sizes
    >>> M = symrb.hat([0.5, 1.0, 1.5])
    >>> @settings(max_examples=5, derandomize=True, database=None)
    ... @given(step_sizes(M, np.array([0.7, 1.1, 1.6])))
    ... def check(hs):
    ...     h, h_fold = hs
    ...     assert 0 < h < h_fold
    >>> check()
    """
    hf = float(fold_scale(M, lam))
    floor = min(0.5, 1e6 * float(np.finfo(float).eps) * float(lam.max() / lam.min()))
    delta = max(draw(st.sampled_from((0.9, 0.5, 0.1) + _NEAR_FOLD)), floor)
    return ((1.0 + delta) if beyond else (1.0 - delta)) * hf, hf
