"""The computations of the Section 3 pages that are not scenes: the symmetric representation, the
shared control and the local equivalence (claims S6 to S11).

Each function runs one experiment of a page and returns a frozen result object with the arrays the
page plots and the numbers the tests (``tests/test_book_lib.py``) assert on.  The functions use
only the public API of :mod:`symrb`; the claims' own evidence is run by ``symrb verify`` and is
not repeated here.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

import symrb
from symrb.errors import InputError, OutOfDomainError
from symrb_book._inputs import count as _count
from symrb_book._inputs import finite_positive as _positive
from symrb_book._inputs import with_norm as _with_norm

Array = NDArray[np.float64]

__all__ = [
    "McLachlanScovelMap",
    "mclachlan_scovel_map",
    "SharedControl",
    "shared_control",
    "MomentumNorms",
    "momentum_norms",
    "RotationAngles",
    "rotation_angles",
    "BoundaryAccuracy",
    "boundary_accuracy",
]


def _max_abs(a: Array) -> Array:
    """The largest absolute entry of each matrix of a (time, ..., n, n) array, per time."""
    return np.abs(a).reshape(a.shape[0], -1).max(axis=1)


# ---------------------------------------------------------------------------------------------
# S6-S8: the symmetric representation and the rigid body


@dataclass(frozen=True)
class McLachlanScovelMap:
    r"""Result of :func:`mclachlan_scovel_map`.

    Attributes
    ----------
    t : ndarray, shape (K,)
        The output times.
    skew_defect : ndarray, shape (K,)
        :math:`\max_{ij}|(Q^TB + B^TQ)_{ij}|` along the McLachlan-Scovel flow.
    gap : ndarray, shape (K,)
        :math:`\max_{ij}|Q^TB - (Q^TP - P^TQ)|_{ij}`, the McLachlan-Scovel momentum against the
        symmetric flow's.
    """

    t: Array
    skew_defect: Array
    gap: Array


def mclachlan_scovel_map(
    T: float = 20.0, n: int = 4, seed: int = 3, samples: int = 201, tol: float = 1e-12
) -> McLachlanScovelMap:
    """The map :math:`B = P - QP^TQ` from the symmetric flow to the McLachlan-Scovel flow (S7).

    The same data as :func:`flow_agreement`; :math:`B_0 = P_0 - Q_0P_0^TQ_0`, both flows by
    :func:`symrb.integrate` at ``rtol = atol = tol``.

    Parameters
    ----------
    T : float
        The final time.
    n : int
        The matrix size, >= 2.
    seed : int
        The random data (as in :func:`flow_agreement`).
    samples : int
        The number of output times, >= 2.
    tol : float
        The integrator tolerance.

    Returns
    -------
    McLachlanScovelMap
        The skew defect of :math:`Q^TB` and its gap to the symmetric flow's momentum.

    Examples
    --------
    >>> from symrb_book.smooth import mclachlan_scovel_map
    >>> run = mclachlan_scovel_map(T=2.0, samples=5)
    >>> bool(run.skew_defect.max() < 1e-10 and run.gap.max() < 1e-10)
    True
    """
    T = _positive(T, "T")
    n = _count(n, "n", 2)
    tol = _positive(tol, "tol")
    lam = np.linspace(0.6, 1.9, n)
    Q0 = symrb.random_SO(n, seed=seed)
    P0 = symrb.symmetric.P_from_M(Q0, _with_norm(n, 1.4, seed + 1))
    B0 = P0 - Q0 @ P0.T @ Q0
    ts = np.linspace(0.0, T, _count(samples, "samples", 2))
    kw: dict[str, Any] = dict(lam=lam, rtol=tol, atol=tol, t_eval=ts)
    ms = symrb.integrate(symrb.McLachlanScovel, (0.0, T), {"Q": Q0, "B": B0}, **kw)
    sym = symrb.integrate(symrb.SymmetricRigidBody, (0.0, T), {"Q": Q0, "P": P0}, **kw)
    if not (ms.success and sym.success):
        raise RuntimeError(f"integration failed: {ms.message}, {sym.message}")
    return McLachlanScovelMap(
        t=ts,
        skew_defect=_max_abs(ms.y.M + np.swapaxes(ms.y.M, -1, -2)),
        gap=_max_abs(ms.y.M - sym.y.M),
    )


@dataclass(frozen=True)
class SharedControl:
    r"""Result of :func:`shared_control`.

    Attributes
    ----------
    t : ndarray, shape (K,)
        The output times.
    gap : ndarray, shape (K,)
        :math:`\max_{ij}|U - \Omega_{rb}|_{ij}`: the shared control of the learning flow against
        the angular velocity of the rigid body with momentum :math:`\sum_a M^a`.
    """

    t: Array
    gap: Array


def shared_control(
    samples: int = 5, n: int = 3, T: float = 10.0, seed: int = 30, tol: float = 1e-12
) -> SharedControl:
    r"""The shared control of the learning flow is a rigid body's angular velocity (S8).

    ``samples`` pairs :math:`(Q^a, P^a)`, :math:`Q^a` Haar-random in SO(n) and :math:`P^a` with
    normal entries (standard deviation 0.3), are integrated by
    :class:`symrb.MultiSampleSymmetricRigidBody`; the rigid body starts at :math:`Q = I`,
    :math:`M = \sum_a M^a(0)` with :math:`M^a = (Q^a)^TP^a - (P^a)^TQ^a`
    (:func:`symrb.symmetric.symmetric_momentum`).

    Parameters
    ----------
    samples : int
        The number of samples, >= 1.
    n : int
        The matrix size, >= 2.
    T : float
        The final time.
    seed : int
        The random data: ``Q^a`` from ``seed``, ``P^a`` from ``seed + 1``.
    tol : float
        The integrator tolerance ``rtol = atol``.

    Returns
    -------
    SharedControl
        The gap between the two at 101 times.

    Examples
    --------
    >>> from symrb_book.smooth import shared_control
    >>> bool(shared_control(samples=2, T=1.0).gap.max() < 1e-10)
    True
    """
    m = _count(samples, "samples", 1)
    n = _count(n, "n", 2)
    T = _positive(T, "T")
    tol = _positive(tol, "tol")
    lam = np.linspace(0.7, 1.6, n)
    Qa = symrb.random_SO(n, (m,), seed=seed)
    Pa = 0.3 * np.random.default_rng(seed + 1).standard_normal((m, n, n))
    ts = np.linspace(0.0, T, 101)
    kw: dict[str, Any] = dict(lam=lam, rtol=tol, atol=tol, t_eval=ts)
    learn = symrb.integrate(symrb.MultiSampleSymmetricRigidBody, (0.0, T), {"Q": Qa, "P": Pa}, **kw)
    total = symrb.symmetric.symmetric_momentum(learn.y.Q, learn.y.P).sum(axis=-3)
    rb = symrb.integrate(symrb.RigidBody, (0.0, T), {"Q": np.eye(n), "M": total[0]}, **kw)
    if not (learn.success and rb.success):
        raise RuntimeError(f"integration failed: {learn.message}, {rb.message}")
    return SharedControl(t=ts, gap=_max_abs(learn.y.U - rb.y.Omega))


# ---------------------------------------------------------------------------------------------
# S9-S11: local equivalence


@dataclass(frozen=True)
class MomentumNorms:
    r"""Result of :func:`momentum_norms`.

    Attributes
    ----------
    sizes : tuple of int
        The matrix sizes n.
    norms : ndarray, shape (len(sizes), count)
        :math:`\|Q^TP - P^TQ\|_{op}` for the random pairs, one row per size.
    """

    sizes: tuple[int, ...]
    norms: Array


def momentum_norms(
    sizes: Sequence[int] = (3, 4, 6), count: int = 4000, seed: int = 0
) -> MomentumNorms:
    r"""Operator norms of :math:`M = Q^TP - P^TQ` for Haar-random :math:`Q, P\in SO(n)` (S9).

    Parameters
    ----------
    sizes : sequence of int
        The matrix sizes, each >= 2.
    count : int
        The number of pairs per size, >= 1.
    seed : int
        The random source: size n uses the seeds ``seed + n`` and ``seed + n + 100``.

    Returns
    -------
    MomentumNorms
        The norms, one row per size.

    Examples
    --------
    >>> from symrb_book.smooth import momentum_norms
    >>> run = momentum_norms(sizes=(3,), count=200)
    >>> bool(run.norms.max() <= 2 + 1e-12), run.norms.shape
    (True, (1, 200))
    """
    ns = tuple(_count(k, "sizes", 2) for k in sizes)
    count = _count(count, "count", 1)
    rows = []
    for k in ns:
        Q = symrb.random_SO(k, (count,), seed=seed + k)
        P = symrb.random_SO(k, (count,), seed=seed + k + 100)
        rows.append(np.linalg.norm(symrb.symmetric.symmetric_momentum(Q, P), 2, axis=(-2, -1)))
    return MomentumNorms(sizes=ns, norms=np.array(rows))


@dataclass(frozen=True)
class RotationAngles:
    r"""Result of :func:`rotation_angles`.

    Attributes
    ----------
    theta : ndarray, shape (K,)
        The rotation speeds: :math:`M` has the eigenvalues :math:`\pm i\theta`.
    angle : ndarray, shape (K,)
        The rotation angle of :math:`Q^TP` for :math:`P` from :func:`symrb.symmetric.P_from_M` (NaN where
        it refuses, :math:`\theta \ge 2`).
    exact : ndarray, shape (K,)
        :math:`\arcsin(\theta/2)` (NaN for :math:`\theta > 2`, where it is not real).
    refused : ndarray of bool, shape (K,)
        Where :func:`symrb.symmetric.P_from_M` raised :class:`symrb.OutOfDomainError`.
    """

    theta: Array
    angle: Array
    exact: Array
    refused: NDArray[np.bool_]


def rotation_angles(theta: ArrayLike) -> RotationAngles:
    r"""The angle by which :math:`Q^TP` rotates a plane of :math:`M` with eigenvalues
    :math:`\pm i\theta` (S10).

    For :math:`M = \theta\begin{pmatrix}0&-1\\1&0\end{pmatrix}` (and :math:`Q = I`), the
    rotation :math:`P` from :func:`symrb.symmetric.P_from_M` has the angle
    :math:`\operatorname{atan2}(P_{10}, P_{00})`, which should be :math:`\arcsin(\theta/2)`.

    Parameters
    ----------
    theta : array_like, shape (K,)
        Non-negative rotation speeds.

    Returns
    -------
    RotationAngles
        The angles of :func:`symrb.symmetric.P_from_M` and :math:`\arcsin(\theta/2)`.

    Examples
    --------
    >>> import numpy as np
    >>> from symrb_book.smooth import rotation_angles
    >>> run = rotation_angles([0.0, 1.0, 2.0, 2.5])
    >>> print(run.angle.round(6), run.refused)
    [0.       0.523599      nan      nan] [False False  True  True]
    """
    th = np.asarray(theta, dtype=float)
    if th.ndim != 1 or np.any(~np.isfinite(th)) or np.any(th < 0):
        raise InputError(f"theta must be a 1-D array of finite values >= 0, got {th!r}")
    angle = np.full(th.shape, np.nan)
    refused = np.zeros(th.shape, dtype=bool)
    for i, value in enumerate(th):
        M = value * np.array([[0.0, -1.0], [1.0, 0.0]])
        try:
            P = symrb.symmetric.P_from_M(np.eye(2), M)
        except OutOfDomainError:
            refused[i] = True
            continue
        angle[i] = np.arctan2(P[1, 0], P[0, 0])
    with np.errstate(invalid="ignore"):
        exact = np.where(th <= 2, np.arcsin(np.minimum(th, 2) / 2), np.nan)
    return RotationAngles(theta=th, angle=angle, exact=exact, refused=refused)


@dataclass(frozen=True)
class BoundaryAccuracy:
    r"""Result of :func:`boundary_accuracy`.

    Attributes
    ----------
    delta : ndarray, shape (K,)
        :math:`\delta = 1 - \|M\|_{op}/2`.
    residual : ndarray, shape (K,)
        :math:`\max|Q^TP - P^TQ - M|`.
    orthogonality : ndarray, shape (K,)
        :math:`\max|P^TP - I|`.
    forward_error : ndarray, shape (K,)
        :math:`\max|P - P_{ref}|`, :math:`P_{ref}` computed with ``dps`` digits.
    eps_over_sqrt_delta : ndarray, shape (K,)
        :math:`\epsilon/\sqrt{\delta}` (:math:`\epsilon = 2^{-52}`): the size of the forward
        error that the conditioning of the problem allows.
    """

    delta: Array
    residual: Array
    orthogonality: Array
    forward_error: Array
    eps_over_sqrt_delta: Array


def _exp_asinh_half_reference(M: Array, dps: int) -> Array:
    """:math:`M/2 + (I + M^2/4)^{1/2}` for a real skew M in ``dps``-digit arithmetic (mpmath)."""
    try:
        import mpmath
    except ImportError:  # pragma: no cover - mpmath comes with the derive and book extras
        raise ImportError("boundary_accuracy needs mpmath: pip install 'symrb[derive]'") from None
    with mpmath.workdps(dps):
        Mm = mpmath.matrix(M.tolist())
        E, V = mpmath.eigsy(mpmath.eye(M.shape[0]) + Mm * Mm / 4)
        root = V * mpmath.diag([mpmath.sqrt(max(e, 0)) for e in E]) * V.T
        return np.array((Mm / 2 + root).tolist(), dtype=float)


def boundary_accuracy(
    deltas: ArrayLike | None = None, n: int = 5, seed: int = 5, dps: int = 60
) -> BoundaryAccuracy:
    r"""How accurate :func:`symrb.symmetric.P_from_M` is as :math:`\|M\|_{op}` approaches 2 (S10).

    One random skew :math:`M` (size n) is scaled to :math:`\|M\|_{op} = 2(1 - \delta)` for each
    :math:`\delta`; :math:`P` from :func:`symrb.symmetric.P_from_M` with :math:`Q = I` is compared with the
    closed form :math:`M/2 + (I + M^2/4)^{1/2}` evaluated in ``dps`` digits (mpmath, needed).

    Parameters
    ----------
    deltas : array_like, optional
        The values of :math:`\delta` in (0, 1) (default: 30 values spaced evenly on a log scale
        from 0.1 down to 3e-16).
    n : int
        The matrix size, >= 2.
    seed : int
        The random source of M.
    dps : int
        The digits of the reference, >= 30.

    Returns
    -------
    BoundaryAccuracy
        Residuals, orthogonality defect and forward error for each :math:`\delta`.

    Examples
    --------
    >>> from symrb_book.smooth import boundary_accuracy
    >>> run = boundary_accuracy([1e-2, 1e-12], n=3)
    >>> bool(run.residual.max() < 1e-14 and run.forward_error[1] > run.forward_error[0])
    True
    """
    ds = np.logspace(-1, -15.5, 30) if deltas is None else np.asarray(deltas, dtype=float)
    if ds.ndim != 1 or np.any(~(ds > 0)) or np.any(ds >= 1):
        raise InputError(f"deltas must be a 1-D array of values in (0, 1), got {ds!r}")
    n = _count(n, "n", 2)
    dps = _count(dps, "dps", 30)
    base = symrb.random_so(n, seed=seed)
    base = base / np.linalg.norm(base, 2)
    eye = np.eye(n)
    res, orth, fwd = [], [], []
    for d in ds:
        M = base * (2 * (1 - d))
        P = symrb.symmetric.P_from_M(eye, M)
        res.append(np.abs(P - P.T - M).max())
        orth.append(np.abs(P.T @ P - eye).max())
        fwd.append(np.abs(P - _exp_asinh_half_reference(M, dps)).max())
    return BoundaryAccuracy(
        delta=ds,
        residual=np.array(res),
        orthogonality=np.array(orth),
        forward_error=np.array(fwd),
        eps_over_sqrt_delta=np.finfo(float).eps / np.sqrt(ds),
    )
