"""Experiments of the book's Section 3 pages: the smooth flows and the adjoint-orbit problems.

Each function runs one experiment of a page (claims S6 to S15) and returns a frozen result object
with the arrays the page plots and the numbers the tests assert on.  Noisy series (differences
and drifts at the level of rounding) come with their maxima over windows of time, which is what
the figures draw.  The functions use only the public API of :mod:`symrb`; the claims' own evidence
is run by ``symrb verify`` and is not repeated here.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

import symrb
from symrb.errors import InputError, OutOfDomainError

Array = NDArray[np.float64]

__all__ = [
    "window_max",
    "FlowAgreement",
    "flow_agreement",
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
    "NormConservation",
    "norm_conservation",
    "HamiltonianDrift",
    "hamiltonian_drift",
    "TodaLattice",
    "toda_lattice",
    "OneSampleLearning",
    "one_sample_learning",
    "TwoSampleLearning",
    "two_sample_learning",
]


def _positive(x: float, name: str) -> float:
    value = float(x)
    if not (np.isfinite(value) and value > 0):
        raise InputError(f"{name} must be a positive finite number, got {x!r}")
    return value


def _count(x: int, name: str, minimum: int) -> int:
    if isinstance(x, bool) or int(x) != x or int(x) < minimum:
        raise InputError(f"{name} must be an integer >= {minimum}, got {x!r}")
    return int(x)


def _with_norm(n: int, norm: float, seed: int | np.random.Generator) -> Array:
    """A random skew (n, n) matrix scaled to the operator norm ``norm``."""
    M = symrb.random_so(n, seed=seed)
    return M * (norm / np.linalg.norm(M, 2))


def _max_abs(a: Array) -> Array:
    """The largest absolute entry of each matrix of a (time, ..., n, n) array, per time."""
    return np.abs(a).reshape(a.shape[0], -1).max(axis=1)


def window_max(t: ArrayLike, values: ArrayLike, windows: int) -> tuple[Array, Array]:
    """The largest value of a sampled series in each of ``windows`` equal windows of time.

    A series that is rounding noise (a drift of 1e-13, a difference of two integrations) is
    unreadable when drawn point by point; its maximum per window shows its size and its growth.

    Parameters
    ----------
    t : array_like, shape (K,)
        Increasing sample times.
    values : array_like, shape (..., K)
        The series (the last axis is time); NaN values are ignored.
    windows : int
        The number of windows, >= 1, dividing ``[t[0], t[-1]]`` equally.

    Returns
    -------
    edges : ndarray, shape (windows + 1,)
        The window boundaries (for ``matplotlib.axes.Axes.stairs``).
    maxima : ndarray, shape (..., windows)
        The largest value in each window (NaN for a window without samples).

    Examples
    --------
    >>> import numpy as np
    >>> from symrb.experiments.smooth import window_max
    >>> edges, top = window_max(np.arange(6.0), [1, 5, 2, 0, 3, 4], 2)
    >>> print(edges, top)
    [0.  2.5 5. ] [5. 4.]
    """
    ts = np.asarray(t, dtype=float)
    vals = np.asarray(values, dtype=float)
    count = _count(windows, "windows", 1)
    if ts.ndim != 1 or ts.size < 2 or np.any(np.diff(ts) <= 0):
        raise InputError(f"t must be an increasing 1-D array of >= 2 times, got shape {ts.shape}")
    if vals.shape[-1:] != ts.shape:
        raise InputError(f"values must end with the time axis {ts.shape}, got {vals.shape}")
    edges = np.linspace(ts[0], ts[-1], count + 1)
    which = np.minimum(np.searchsorted(edges, ts, side="right") - 1, count - 1)
    maxima = np.full(vals.shape[:-1] + (count,), np.nan)
    for w in range(count):
        inside = vals[..., which == w]
        if inside.shape[-1]:
            maxima[..., w] = np.fmax.reduce(inside, axis=-1)  # fmax skips NaN
    return edges, maxima


# ---------------------------------------------------------------------------------------------
# S6-S8: the symmetric representation and the rigid body


@dataclass(frozen=True)
class FlowAgreement:
    r"""Result of :func:`flow_agreement`.

    Attributes
    ----------
    tolerances : ndarray, shape (m,)
        The integrator tolerances (``rtol = atol``).
    t : ndarray, shape (K,)
        The output times.
    difference : ndarray, shape (m, K)
        :math:`\max_{ij}|(Q^TP - P^TQ)_{ij} - (M_{rb})_{ij}|` at each time, per tolerance.
    edges : ndarray, shape (W + 1,)
        The time windows of ``difference_max``.
    difference_max : ndarray, shape (m, W)
        The largest difference in each window.
    nfev_symmetric, nfev_rigid_body : ndarray of int, shape (m,)
        Evaluations of the vector field of each flow.
    """

    tolerances: Array
    t: Array
    difference: Array
    edges: Array
    difference_max: Array
    nfev_symmetric: NDArray[np.int64]
    nfev_rigid_body: NDArray[np.int64]


def flow_agreement(
    tolerances: Sequence[float] = (1e-6, 1e-9, 1e-12),
    T: float = 20.0,
    n: int = 4,
    seed: int = 3,
    samples: int = 201,
    windows: int = 20,
) -> FlowAgreement:
    r"""The symmetric rigid body flow and the rigid body flow from the same state (claim S6).

    From :math:`Q_0` (Haar-random in SO(n)) and :math:`M_0` (random skew, scaled to
    :math:`\|M_0\|_{op} = 1.4`), with :math:`P_0 = Q_0\exp(\sinh^{-1}(M_0/2))`
    (:func:`symrb.P_from_M`), both flows are integrated by :func:`symrb.integrate` (DOP853) at
    each tolerance, and :math:`Q^TP - P^TQ` is compared with the rigid body's M.  They describe
    the same motion, so the difference is integration error only.

    Parameters
    ----------
    tolerances : sequence of float
        The tolerances ``rtol = atol`` of the runs.
    T : float
        The final time.
    n : int
        The matrix size, >= 2.
    seed : int
        The random data: ``Q0`` from ``seed``, ``M0`` from ``seed + 1``.
    samples : int
        The number of output times, >= 2.
    windows : int
        The number of time windows of ``difference_max``.

    Returns
    -------
    FlowAgreement
        The differences and the work of each run.

    Examples
    --------
    >>> from symrb.experiments.smooth import flow_agreement
    >>> run = flow_agreement(tolerances=(1e-6, 1e-12), T=2.0, samples=11, windows=2)
    >>> bool(run.difference[1].max() < 1e-10 < run.difference[0].max())
    True
    """
    tols = np.array([_positive(x, "tolerances") for x in tolerances])
    T = _positive(T, "T")
    n = _count(n, "n", 2)
    samples = _count(samples, "samples", 2)
    lam = np.linspace(0.6, 1.9, n)
    Q0 = symrb.random_SO(n, seed=seed)
    M0 = _with_norm(n, 1.4, seed + 1)
    P0 = symrb.P_from_M(Q0, M0)
    ts = np.linspace(0.0, T, samples)
    diffs, nfev_sym, nfev_rb = [], [], []
    for tol in tols:
        kw: dict[str, Any] = dict(lam=lam, rtol=tol, atol=tol, t_eval=ts)
        sym = symrb.integrate(symrb.SymmetricRigidBody, (0.0, T), {"Q": Q0, "P": P0}, **kw)
        rb = symrb.integrate(symrb.RigidBody, (0.0, T), {"Q": Q0, "M": M0}, **kw)
        if not (sym.success and rb.success):
            raise RuntimeError(
                f"integration failed at tolerance {tol}: {sym.message}, {rb.message}"
            )
        diffs.append(_max_abs(sym.y.M - rb.y.M))
        nfev_sym.append(sym.nfev)
        nfev_rb.append(rb.nfev)
    difference = np.array(diffs)
    edges, top = window_max(ts, difference, windows)
    return FlowAgreement(
        tolerances=tols,
        t=ts,
        difference=difference,
        edges=edges,
        difference_max=top,
        nfev_symmetric=np.array(nfev_sym),
        nfev_rigid_body=np.array(nfev_rb),
    )


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
    >>> from symrb.experiments.smooth import mclachlan_scovel_map
    >>> run = mclachlan_scovel_map(T=2.0, samples=5)
    >>> bool(run.skew_defect.max() < 1e-10 and run.gap.max() < 1e-10)
    True
    """
    T = _positive(T, "T")
    n = _count(n, "n", 2)
    tol = _positive(tol, "tol")
    lam = np.linspace(0.6, 1.9, n)
    Q0 = symrb.random_SO(n, seed=seed)
    P0 = symrb.P_from_M(Q0, _with_norm(n, 1.4, seed + 1))
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
    (:func:`symrb.symmetric_momentum`).

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
    >>> from symrb.experiments.smooth import shared_control
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
    total = symrb.symmetric_momentum(learn.y.Q, learn.y.P).sum(axis=-3)
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
    >>> from symrb.experiments.smooth import momentum_norms
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
        rows.append(np.linalg.norm(symrb.symmetric_momentum(Q, P), 2, axis=(-2, -1)))
    return MomentumNorms(sizes=ns, norms=np.array(rows))


@dataclass(frozen=True)
class RotationAngles:
    r"""Result of :func:`rotation_angles`.

    Attributes
    ----------
    theta : ndarray, shape (K,)
        The rotation speeds: :math:`M` has the eigenvalues :math:`\pm i\theta`.
    angle : ndarray, shape (K,)
        The rotation angle of :math:`Q^TP` for :math:`P` from :func:`symrb.P_from_M` (NaN where
        it refuses, :math:`\theta \ge 2`).
    exact : ndarray, shape (K,)
        :math:`\arcsin(\theta/2)` (NaN for :math:`\theta > 2`, where it is not real).
    refused : ndarray of bool, shape (K,)
        Where :func:`symrb.P_from_M` raised :class:`symrb.OutOfDomainError`.
    """

    theta: Array
    angle: Array
    exact: Array
    refused: NDArray[np.bool_]


def rotation_angles(theta: ArrayLike) -> RotationAngles:
    r"""The angle by which :math:`Q^TP` rotates a plane of :math:`M` with eigenvalues
    :math:`\pm i\theta` (S10).

    For :math:`M = \theta\begin{pmatrix}0&-1\\1&0\end{pmatrix}` (and :math:`Q = I`), the
    rotation :math:`P` from :func:`symrb.P_from_M` has the angle
    :math:`\operatorname{atan2}(P_{10}, P_{00})`, which should be :math:`\arcsin(\theta/2)`.

    Parameters
    ----------
    theta : array_like, shape (K,)
        Non-negative rotation speeds.

    Returns
    -------
    RotationAngles
        The angles of :func:`symrb.P_from_M` and :math:`\arcsin(\theta/2)`.

    Examples
    --------
    >>> import numpy as np
    >>> from symrb.experiments.smooth import rotation_angles
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
            P = symrb.P_from_M(np.eye(2), M)
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
    r"""How accurate :func:`symrb.P_from_M` is as :math:`\|M\|_{op}` approaches 2 (S10).

    One random skew :math:`M` (size n) is scaled to :math:`\|M\|_{op} = 2(1 - \delta)` for each
    :math:`\delta`; :math:`P` from :func:`symrb.P_from_M` with :math:`Q = I` is compared with the
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
    >>> from symrb.experiments.smooth import boundary_accuracy
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
        P = symrb.P_from_M(eye, M)
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


@dataclass(frozen=True)
class NormConservation:
    r"""Result of :func:`norm_conservation`.

    Attributes
    ----------
    t : ndarray, shape (K,)
        The output times.
    initial_norms : ndarray, shape (m,)
        :math:`\|M_0\|_{op}` of each run; the last run starts on C (norm 2).
    deviation : ndarray, shape (m, K)
        :math:`|\,\|M(t)\|_{op} - \|M_0\|_{op}|` along the symmetric flow.
    edges : ndarray, shape (W + 1,)
        The time windows of ``deviation_max``.
    deviation_max : ndarray, shape (m, W)
        The largest deviation in each window.
    """

    t: Array
    initial_norms: Array
    deviation: Array
    edges: Array
    deviation_max: Array


def norm_conservation(
    radii: Sequence[float] = (0.5, 1.5, 1.99),
    T: float = 30.0,
    n: int = 4,
    seed: int = 2,
    windows: int = 15,
    tol: float = 1e-12,
) -> NormConservation:
    r""":math:`\|M\|_{op}` along the symmetric rigid body flow, inside S and on C (S11).

    Runs of :class:`symrb.SymmetricRigidBody` (n = 4 by default) from :math:`Q_0` Haar-random and
    :math:`P_0` = :func:`symrb.P_from_M` of a random :math:`M_0` scaled to each radius, and one
    from :math:`P_0 = Q_0A` with :math:`A` orthogonal with a rotation by :math:`\pi/2` (so
    :math:`\|M_0\|_{op} = 2`, the set C; only for n >= 4).

    Parameters
    ----------
    radii : sequence of float
        The initial norms in (0, 2).
    T : float
        The final time.
    n : int
        The matrix size, >= 4.
    seed : int
        The random source: ``Q0`` from ``seed``, the direction of ``M0`` from ``seed + 5``.
    windows : int
        The number of time windows of ``deviation_max``.
    tol : float
        The integrator tolerance ``rtol = atol``.

    Returns
    -------
    NormConservation
        The deviation of the norm from its initial value, per run.

    Examples
    --------
    >>> from symrb.experiments.smooth import norm_conservation
    >>> run = norm_conservation(radii=(1.0,), T=2.0, windows=2)
    >>> print(run.initial_norms.round(12))
    [1. 2.]
    >>> bool(run.deviation.max() < 1e-10)
    True
    """
    rs = [_positive(r, "radii") for r in radii]
    if any(r >= 2 for r in rs):
        raise InputError(f"radii must be in (0, 2), got {list(radii)}")
    T = _positive(T, "T")
    n = _count(n, "n", 4)
    tol = _positive(tol, "tol")
    lam = np.linspace(0.5, 2.0, n)
    ts = np.linspace(0.0, T, 301)
    Q0 = symrb.random_SO(n, seed=seed)
    A = np.eye(n)
    A[:2, :2] = [[0.0, -1.0], [1.0, 0.0]]
    A[2:4, 2:4] = [[0.6, -0.8], [0.8, 0.6]]
    starts = [symrb.P_from_M(Q0, _with_norm(n, r, seed + 5)) for r in rs] + [Q0 @ A]
    kw: dict[str, Any] = dict(lam=lam, rtol=tol, atol=tol, t_eval=ts)
    initial, deviation = [], []
    for P0 in starts:
        sol = symrb.integrate(symrb.SymmetricRigidBody, (0.0, T), {"Q": Q0, "P": P0}, **kw)
        if not sol.success:
            raise RuntimeError(f"integration failed: {sol.message}")
        norms = np.linalg.norm(sol.y.M, 2, axis=(-2, -1))
        initial.append(norms[0])
        deviation.append(np.abs(norms - norms[0]))
    dev = np.array(deviation)
    edges, top = window_max(ts, dev, windows)
    return NormConservation(
        t=ts, initial_norms=np.array(initial), deviation=dev, edges=edges, deviation_max=top
    )


# ---------------------------------------------------------------------------------------------
# S12: the Hamiltonian form


@dataclass(frozen=True)
class HamiltonianDrift:
    r"""Result of :func:`hamiltonian_drift`.

    Attributes
    ----------
    t : ndarray, shape (K,)
        The output times.
    series : dict of str to ndarray, shape (K,)
        ``"orthogonality"``: :math:`\max(|Q^TQ - I|, |P^TP - I|)` from a start on
        :math:`SO(n)^2`; ``"H on SO"``, ``"H on gl"``: :math:`|H(t)/H(0) - 1|` from a start on
        :math:`SO(n)^2` and from a general point of :math:`\mathfrak{gl}(n)^2`;
        ``"spectrum on gl"``: the largest change of an eigenvalue of :math:`\xi^T\xi` relative
        to the largest eigenvalue, from the general point.
    edges : ndarray, shape (W + 1,)
        The time windows of ``series_max``.
    series_max : dict of str to ndarray, shape (W,)
        The largest value of each series in each window.
    """

    t: Array
    series: dict[str, Array]
    edges: Array
    series_max: dict[str, Array]


def hamiltonian_drift(
    T: float = 50.0, n: int = 4, seed: int = 12, windows: int = 25, tol: float = 1e-12
) -> HamiltonianDrift:
    r"""What the symmetric rigid body field conserves, on and off :math:`SO(n)\times SO(n)` (S12).

    Two runs of :class:`symrb.SymmetricRigidBody` (DOP853, ``rtol = atol = tol``): from
    :math:`(Q_0, P_0)` Haar-random in :math:`SO(n)^2`, and from :math:`(\xi_0, \eta_0)` with
    normal entries.

    Parameters
    ----------
    T : float
        The final time.
    n : int
        The matrix size, >= 2.
    seed : int
        The random source: the rotations from ``seed``, the general point from ``seed + 1``.
    windows : int
        The number of time windows of ``series_max``.
    tol : float
        The integrator tolerance.

    Returns
    -------
    HamiltonianDrift
        The conserved quantities' drifts, raw and as maxima per window.

    Examples
    --------
    >>> from symrb.experiments.smooth import hamiltonian_drift
    >>> run = hamiltonian_drift(T=2.0, windows=2)
    >>> sorted(run.series_max)
    ['H on SO', 'H on gl', 'orthogonality', 'spectrum on gl']
    >>> bool(max(v.max() for v in run.series.values()) < 1e-9)
    True
    """
    T = _positive(T, "T")
    n = _count(n, "n", 2)
    tol = _positive(tol, "tol")
    lam = np.linspace(0.5, 2.0, n)
    ts = np.linspace(0.0, T, 10 * int(np.ceil(T)) + 1)
    kw: dict[str, Any] = dict(lam=lam, rtol=tol, atol=tol, t_eval=ts)
    Q0, P0 = symrb.random_SO(n, (2,), seed=seed)
    X0, Y0 = np.random.default_rng(seed + 1).standard_normal((2, n, n))
    on = symrb.integrate(symrb.SymmetricRigidBody, (0.0, T), {"Q": Q0, "P": P0}, **kw)
    off = symrb.integrate(symrb.SymmetricRigidBody, (0.0, T), {"Q": X0, "P": Y0}, **kw)
    if not (on.success and off.success):
        raise RuntimeError(f"integration failed: {on.message}, {off.message}")
    eye = np.eye(n)

    def gram(X: Array) -> Array:
        return np.swapaxes(X, -1, -2) @ X

    spec = np.linalg.eigvalsh(gram(off.y.Q))
    series = {
        "orthogonality": np.maximum(_max_abs(gram(on.y.Q) - eye), _max_abs(gram(on.y.P) - eye)),
        "H on SO": np.abs(on.y.H / on.y.H[0] - 1),
        "H on gl": np.abs(off.y.H / off.y.H[0] - 1),
        "spectrum on gl": np.abs(spec - spec[0]).max(axis=-1) / spec[0].max(),
    }
    edges, _ = window_max(ts, series["H on SO"], windows)
    tops = {k: window_max(ts, s, windows)[1] for k, s in series.items()}
    return HamiltonianDrift(t=ts, series=series, edges=edges, series_max=tops)


# ---------------------------------------------------------------------------------------------
# S14: the Toda lattice


@dataclass(frozen=True)
class TodaLattice:
    """Result of :func:`toda_lattice`.

    Attributes
    ----------
    t : ndarray, shape (K,)
        The output times.
    a : ndarray, shape (K, k)
        The diagonal of :math:`L(t)`.
    b : ndarray, shape (K, k - 1)
        The off-diagonal of :math:`L(t)`.
    eigenvalues : ndarray, shape (k,)
        The eigenvalues of :math:`L(0)`, decreasing.
    spectrum_drift : float
        The largest change of an eigenvalue of :math:`L(t)` over the run.
    off_band : float
        The largest entry of :math:`L(t)` off the tridiagonal band over the run.
    """

    t: Array
    a: Array
    b: Array
    eigenvalues: Array
    spectrum_drift: float
    off_band: float


def toda_lattice(k: int = 5, T: float = 12.0, seed: int = 7, samples: int = 241) -> TodaLattice:
    r"""The Toda lattice as the double bracket flow :math:`\dot L = [L, [L, D]]` backwards (S14).

    With :math:`x = iL` (L real symmetric tridiagonal), :math:`N = iD`,
    :math:`D = \operatorname{diag}(1, \dots, k)`, the double bracket flow
    :math:`\dot x = [x, [x, N]]` reads :math:`\dot L = -[L, [L, D]]`, Flaschka's form of the
    Toda lattice.  It is integrated by :func:`symrb.toda_flow` (DOP853, rtol 1e-10), from a
    random L (diagonal normal, off-diagonal uniform in [0.4, 1]); the scene
    ``book/scenes/toda_lattice.toml`` runs the same.

    Parameters
    ----------
    k : int
        The size of L, >= 2.
    T : float
        The final time.
    seed : int
        The random source of L(0).
    samples : int
        The number of output times, >= 2.

    Returns
    -------
    TodaLattice
        The entries of L(t), the spectrum and what the flow keeps.

    Examples
    --------
    >>> from symrb.experiments.smooth import toda_lattice
    >>> run = toda_lattice(k=3, T=20.0)
    >>> print((run.a[-1] - run.eigenvalues).round(6) + 0.0)  # sorted to the eigenvalues
    [0. 0. 0.]
    """
    k = _count(k, "k", 2)
    T = _positive(T, "T")
    rng = np.random.default_rng(seed)
    a0, b0 = rng.standard_normal(k), rng.uniform(0.4, 1.0, k - 1)
    L0 = np.diag(a0) + np.diag(b0, 1) + np.diag(b0, -1)
    ts = np.linspace(0.0, T, _count(samples, "samples", 2))
    Ls = symrb.toda_flow(a0, b0, ts, rtol=1e-10, atol=1e-12)
    eig0 = np.sort(np.linalg.eigvalsh(L0))[::-1]
    spectra = np.sort(np.linalg.eigvalsh(Ls), axis=-1)[:, ::-1]
    return TodaLattice(
        t=ts,
        a=np.diagonal(Ls, axis1=1, axis2=2).copy(),
        b=np.diagonal(Ls, 1, axis1=1, axis2=2).copy(),
        eigenvalues=eig0,
        spectrum_drift=float(np.abs(spectra - eig0).max()),
        off_band=float(np.abs(np.triu(Ls, 2)).max()),
    )


# ---------------------------------------------------------------------------------------------
# S15: learning on adjoint orbits


def _second_term(x: Array, N: Array) -> Array:
    r""":math:`\|[N, [N, x]]\|` in the norm of :func:`symrb.pairing`."""
    c = symrb.commutator(N, symrb.commutator(N, x))
    return np.sqrt(np.maximum(symrb.pairing(c, c), 0.0))


def _norm(x: Array) -> Array:
    return np.sqrt(np.maximum(symrb.pairing(x, x), 0.0))


@dataclass(frozen=True)
class OneSampleLearning:
    r"""Result of :func:`one_sample_learning`.

    Attributes
    ----------
    t : ndarray, shape (K,)
        Times on [0, T].
    cost_corrected, cost_printed : ndarray, shape (K,)
        :math:`\langle x(t), N\rangle` along the extremal with the corrected endpoint
        :math:`p_T = -N` and with the printed :math:`p_T = +N`.
    second_corrected, second_printed : ndarray, shape (K,)
        :math:`\|[N, [N, x(t)]]\|` along them.
    second_exact : ndarray, shape (K,)
        The closed form of the corrected statement (:func:`symrb.one_sample_second_term`),
        :math:`\|N\|^2\|x_0\|\sin\phi_t` with
        :math:`\tan(\phi_t/2) = \tan(\phi_0/2)e^{-\|x_0\|\|N\|t}`.
    rate : float
        :math:`\|x_0\|\|N\|`.
    flow_deviation : float
        The largest :math:`|x - x_{db}|` entry on the mesh, :math:`x_{db}` from
        :func:`symrb.double_bracket_flow`.
    costate_deviation : float
        The largest :math:`|p + N|` entry on the mesh (the corrected extremal has
        :math:`p \equiv -N`).
    """

    t: Array
    cost_corrected: Array
    cost_printed: Array
    second_corrected: Array
    second_printed: Array
    second_exact: Array
    rate: float
    flow_deviation: float
    costate_deviation: float


def one_sample_learning(
    T: float = 8.0, x0_norm: float = 0.5, angle: float = 2.0, samples: int = 201
) -> OneSampleLearning:
    r"""One sample on :math:`\mathfrak{so}(3)`: the boundary value problem with either endpoint
    sign (S15).

    :math:`N = \hat e_3` (:math:`\|N\| = 1`) and :math:`x_0` of norm ``x0_norm`` at the angle
    ``angle`` from :math:`-N`; :func:`symrb.solve_orbit_bvp` from the guess :math:`p = 0` with
    ``costate="corrected"`` and from its default guess with ``costate="printed"``.

    Parameters
    ----------
    T : float
        The horizon.
    x0_norm : float
        :math:`\|x_0\|`, > 0.
    angle : float
        The angle :math:`\phi_0` between :math:`x_0` and :math:`-N`, in (0, pi).
    samples : int
        The number of times on [0, T] of the output, >= 2.

    Returns
    -------
    OneSampleLearning
        Cost and second costate term along both extremals, and the closed form.

    Examples
    --------
    >>> import numpy as np
    >>> from symrb.experiments.smooth import one_sample_learning
    >>> run = one_sample_learning(T=2.0, samples=5)
    >>> bool(np.abs(run.second_corrected - run.second_exact).max() < 1e-6)
    True
    """
    T = _positive(T, "T")
    r = _positive(x0_norm, "x0_norm")
    phi0 = float(angle)
    if not 0 < phi0 < np.pi:
        raise InputError(f"angle must be in (0, pi), got {angle!r}")
    N = symrb.hat([0.0, 0.0, 1.0])
    x0 = symrb.hat([r * np.sin(phi0), 0.0, -r * np.cos(phi0)])
    res = symrb.solve_orbit_bvp(x0, N, T, p_guess=np.zeros((3, 3)))
    printed = symrb.solve_orbit_bvp(x0, N, T, costate="printed")
    if not (res.success and printed.success):
        raise RuntimeError(f"solve_orbit_bvp failed: {res.message}; {printed.message}")
    ts = np.linspace(0.0, T, _count(samples, "samples", 2))
    xc = res.at(ts)[0][:, 0]
    xp = printed.at(ts)[0][:, 0]
    rate = float(r * _norm(N))
    flow = symrb.double_bracket_flow(x0, N, res.t)
    return OneSampleLearning(
        t=ts,
        cost_corrected=symrb.pairing(xc, N),
        cost_printed=symrb.pairing(xp, N),
        second_corrected=_second_term(xc, N),
        second_printed=_second_term(xp, N),
        second_exact=symrb.one_sample_second_term(x0, N, ts),
        rate=rate,
        flow_deviation=float(np.abs(res.x[:, 0] - flow).max()),
        costate_deviation=float(np.abs(res.p + N).max()),
    )


@dataclass(frozen=True)
class TwoSampleLearning:
    r"""Result of :func:`two_sample_learning`.

    Attributes
    ----------
    t : ndarray, shape (K,)
        Times on [0, T].
    deviation : ndarray, shape (2, K)
        :math:`\|x^a(t) - x^a_{db}(t)\|` (the norm of :func:`symrb.pairing`): each sample
        against its own double bracket flow.
    second_shared : ndarray, shape (2, K)
        :math:`\|[N, [N, x^a(t)]]\|` along the extremal with the shared control.
    second_own : ndarray, shape (2, K)
        The same along each sample's own double bracket flow.
    bound : float
        :math:`\|N\|^2\min_a\|x^a_0\|\sin(\beta/2)`, :math:`\beta` the angle between the
        lines of :math:`x^1_0` and :math:`x^2_0`.
    pairing_drift : float
        The largest change of :math:`\langle x^1, x^2\rangle` on the mesh.
    """

    t: Array
    deviation: Array
    second_shared: Array
    second_own: Array
    bound: float
    pairing_drift: float


def two_sample_learning(T: float = 8.0, seed: int = 150, samples: int = 201) -> TwoSampleLearning:
    r"""Two samples on :math:`\mathfrak{so}(3)` sharing one control (S15).

    :math:`N` and :math:`x^1_0, x^2_0` are :func:`symrb.random_so` matrices (entries of
    standard deviation 0.5, from ``seed``); :func:`symrb.solve_orbit_bvp` with the corrected
    endpoint (collocation tolerance 1e-5).

    Parameters
    ----------
    T : float
        The horizon.
    seed : int
        The random source of the data.
    samples : int
        The number of times on [0, T] of the output, >= 2.

    Returns
    -------
    TwoSampleLearning
        The samples against their own double bracket flows, the second costate terms and the
        lower bound.

    Examples
    --------
    >>> from symrb.experiments.smooth import two_sample_learning
    >>> run = two_sample_learning(T=2.0, samples=5)
    >>> bool(run.second_shared[:, -1].max() > run.bound and run.pairing_drift < 1e-6)
    True
    """
    T = _positive(T, "T")
    rng = np.random.default_rng(seed)
    N = symrb.random_so(3, scale=0.5, seed=rng)
    X0 = symrb.random_so(3, (2,), scale=0.5, seed=rng)
    res = symrb.solve_orbit_bvp(X0, N, T, tol=1e-5)
    if not res.success:
        raise RuntimeError(f"solve_orbit_bvp failed: {res.message}")
    ts = np.linspace(0.0, T, _count(samples, "samples", 2))
    xs = res.at(ts)[0]
    own = np.stack([symrb.double_bracket_flow(X0[a], N, ts) for a in range(2)])
    shared = np.moveaxis(xs, 1, 0)
    bound = symrb.two_sample_bound(X0, N)
    mesh_pairing = symrb.pairing(res.x[:, 0], res.x[:, 1])
    return TwoSampleLearning(
        t=ts,
        deviation=_norm(shared - own),
        second_shared=_second_term(shared, N),
        second_own=_second_term(own, N),
        bound=bound,
        pairing_drift=float(np.abs(mesh_pairing - symrb.pairing(X0[0], X0[1])).max()),
    )
