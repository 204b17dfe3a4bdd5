r"""Two experiments the book's scenes replaced, kept as the reference the scene tests compare
against bit for bit (``tests/test_scenes_bodies.py``): the agreement of the three discrete
rigid-body algorithms (the Moser-Veselov page's agreement scenes) and the conservation of the
momentum's operator norm (the local equivalence page's norm conservation scenes).  They call only
the public API of :mod:`symrb`, independently of :mod:`symrb.scenes`.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from symrb_book._inputs import count as _count
from symrb_book._inputs import finite_positive as _finite_positive
from symrb_book._inputs import one_blas_thread as _one_blas_thread
from symrb_book._inputs import positive as _positive
from symrb_book._inputs import with_norm as _with_norm

import symrb
from symrb import _validate as v
from symrb._validate import Array
from symrb.errors import InputError, SymrbError

__all__ = [
    "AlgorithmAgreement",
    "algorithm_agreement",
    "window_max",
    "NormConservation",
    "norm_conservation",
]


def _window_max(values: ArrayLike, windows: int) -> Array:
    """The largest absolute value over each of ``windows`` consecutive blocks of the leading axis
    (and over every trailing axis): a summary of a noisy series that keeps its envelope."""
    a = np.abs(np.asarray(values, dtype=float))
    a = a.reshape(a.shape[0], -1).max(axis=1)
    blocks = np.array_split(a, min(windows, a.shape[0]))
    return np.array([b.max() for b in blocks])


def _window_last(values: NDArray[Any], windows: int) -> NDArray[Any]:
    """The last entry of each block of :func:`_window_max` (the time at which a window ends)."""
    a = np.asarray(values)
    return np.array([b[-1] for b in np.array_split(a, min(windows, a.shape[0]))])


# ---------------------------------------------------------------------------------------------
# Moser-Veselov (book/section2/04_moser_veselov_runs.md)


@dataclass(frozen=True, eq=False)
class AlgorithmAgreement:
    r"""Result of :func:`algorithm_agreement`.

    Attributes
    ----------
    steps : int
        The number of steps of each run.
    k : ndarray, shape (K,)
        The step index of each saved configuration :math:`Q_k`, :math:`k = 1, \dots, steps`.
    gap_sym_mv2 : ndarray, shape (K,)
        :math:`\max|Q_k^{sym} - Q_k^{MV2}|` at each step.
    gap_momentum : ndarray, shape (K,)
        :math:`\max|M^{MV2}_{k+1} - (Q_k^TP_k - P_k^TQ_k)|/\max|M_1|` at each step.
    gap_mv1_mv2 : ndarray, shape (K,)
        :math:`\max|Q_k^{MV1} - Q_k^{MV2}|` at each step.
    spread_sym, spread_mv1 : ndarray, shape (K,)
        The difference between each algorithm's run and the same run in a rotated frame
        (:math:`RQ_0`, :math:`RP_0`; the equations are invariant), rotated back: the size of the
        algorithm's own rounding.
    wrong_index_gap : ndarray, shape (K,)
        :math:`\max|Q_k^{sym} - Q_k|` for MV-Algorithm 2 started one index off, at
        :math:`(Q_0, M_1)`: what a mistaken index looks like.
    discretisation_error : float
        :math:`\max|Q_k^{sym} - Q(k)|` over the first 50 steps against :func:`symrb.integrate`
        of the rigid body from :math:`(Q_0, M_1)` (DOP853, tolerance :math:`10^{-12}`): the size
        of an :math:`O(h^2)` error at this step.
    window_k : ndarray, shape (W,)
        The last step of each window of the summary.
    window : dict of str to ndarray
        The largest value of each gap and spread above in each window (keys ``"sym_mv2"``,
        ``"momentum"``, ``"mv1_mv2"``, ``"spread_sym"``, ``"spread_mv1"``, ``"wrong_index"``).
    seconds : float
        Wall time of the five runs.
    """

    steps: int
    k: NDArray[np.int64]
    gap_sym_mv2: Array
    gap_momentum: Array
    gap_mv1_mv2: Array
    spread_sym: Array
    spread_mv1: Array
    wrong_index_gap: Array
    discretisation_error: float
    window_k: NDArray[np.int64]
    window: dict[str, Array]
    seconds: float

    def largest(self) -> dict[str, float]:
        """The largest value of each gap and spread over the run."""
        return {key: float(val.max()) for key, val in self.window.items()}


def algorithm_agreement(
    steps: int = 10_000,
    lam: ArrayLike = (0.7, 1.1, 1.6),
    scale: float = 0.05,
    windows: int = 40,
    seed: int = 0,
) -> AlgorithmAgreement:
    r"""Run the symmetric representation, MV-Algorithm 2 and MV-Algorithm 1 from the same data for
    ``steps`` steps (time step 1, :math:`n = 3`) and compare their configurations.

    The symmetric algorithm starts at :math:`(Q_0, P_0)` with :math:`P_0 = Q_0M/2` (so the body
    momentum is a random skew :math:`M` of size ``scale``); MV-Algorithm 2 at :math:`(Q_1, M_1)`
    with :math:`M_1 = Q_0^TP_0 - P_0^TQ_0` (:func:`symrb.symmetric.symmetric_momentum`, claim D12); and
    MV-Algorithm 1 at :math:`(Q_0, Q_1)`.  For scale, each of the first and the last is also run
    in a rotated frame, and MV-Algorithm 2 is run from the wrong index :math:`(Q_0, M_1)`.  BLAS
    is held to one thread during the runs (with threadpoolctl, when installed): small matrix
    products are much slower with several.

    Parameters
    ----------
    steps : int, optional
        The number of steps, >= 2.
    lam : array_like, shape (3,)
        The diagonal of :math:`\Lambda`.
    scale : float, optional
        The size of the random momentum (:func:`symrb.random_so`'s ``scale``), > 0.
    windows : int, optional
        The number of windows of the summary, >= 1.
    seed : int, optional
        The seed of :math:`Q_0`, :math:`M` and the rotation :math:`R`.

    Returns
    -------
    AlgorithmAgreement
        The gaps and spreads at every step, and their summary per window.

    Examples
    --------
    >>> from replaced_experiments import algorithm_agreement
    >>> run = algorithm_agreement(steps=50, windows=5)
    >>> big = run.largest()
    >>> bool(big["sym_mv2"] < 1e-13), bool(big["wrong_index"] > 1e-4)
    (True, True)
    """
    steps = v.count(steps, "steps", 2)
    L = v.inertia(lam, positive=True)
    if L.shape != (3,):
        raise InputError(f"lam must have shape (3,), got shape {L.shape}")
    scale = _positive(scale, "scale")
    windows = v.count(windows, "windows", 1)
    rng = np.random.default_rng(seed)
    Q0 = symrb.random_SO(3, seed=rng)
    P0 = Q0 @ (0.5 * symrb.random_so(3, seed=rng, scale=scale))
    R = symrb.random_SO(3, seed=rng)
    Rt = R.T

    start = time.perf_counter()
    # the step-by-step loops (diagnostics=True), as the agreement scenes run them (loop =
    # "reference"): by default the three algorithms are one engine run each
    ref = {"diagnostics": True}
    with _one_blas_thread():
        sym = symrb.symmetric_flow(Q0, P0, L, 1.0, steps, **ref)
        Qs, Ms = sym.y.Q, sym.y.M
        M1 = symrb.symmetric.symmetric_momentum(Q0, P0)
        mv2 = symrb.mv_algorithm2(Qs[1], M1, L, steps - 1, **ref)
        mv1 = symrb.mv_algorithm1(Q0, Qs[1], L, steps - 1, **ref)
        sym_r = symrb.symmetric_flow(R @ Q0, R @ P0, L, 1.0, steps, **ref)
        mv1_r = symrb.mv_algorithm1(R @ Q0, R @ Qs[1], L, steps - 1, **ref)
        wrong = symrb.mv_algorithm2(Q0, M1, L, steps - 1, **ref)
    seconds = time.perf_counter() - start
    runs = (sym, mv2, mv1, sym_r, mv1_r, wrong)
    failed = [r.message for r in runs if not r.success]
    if failed:
        raise SymrbError(f"a run stopped early: {failed[0]}")

    def gap(a: Array, b: Array) -> Array:
        return np.asarray(np.abs(a - b).max(axis=(-2, -1)))

    QB = mv2.y.Q  # Q_1 ... Q_steps
    gaps = {
        "sym_mv2": gap(QB, Qs[1:]),
        "momentum": gap(mv2.y.M, Ms[:-1]) / np.abs(M1).max(),
        "mv1_mv2": gap(mv1.y.Q[1:], QB),
        "spread_sym": gap(Rt @ sym_r.y.Q[1:], Qs[1:]),
        "spread_mv1": gap(Rt @ mv1_r.y.Q[1:], mv1.y.Q[1:]),
        "wrong_index": gap(wrong.y.Q, Qs[1:]),
    }
    k = np.arange(1, steps + 1)
    early = min(50, steps)
    exact = symrb.integrate(
        symrb.RigidBody, (0.0, float(early)), {"Q": Q0, "M": M1}, lam=L, method="DOP853",
        rtol=1e-12, atol=1e-12, t_eval=np.arange(early + 1.0),
    )  # fmt: skip
    return AlgorithmAgreement(
        steps=steps,
        k=k,
        gap_sym_mv2=gaps["sym_mv2"],
        gap_momentum=gaps["momentum"],
        gap_mv1_mv2=gaps["mv1_mv2"],
        spread_sym=gaps["spread_sym"],
        spread_mv1=gaps["spread_mv1"],
        wrong_index_gap=gaps["wrong_index"],
        discretisation_error=float(np.abs(exact.y.Q - Qs[: early + 1]).max()),
        window_k=_window_last(k, windows),
        window={key: _window_max(val, windows) for key, val in gaps.items()},
        seconds=seconds,
    )


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
    >>> from replaced_experiments import window_max
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
    :math:`P_0` = :func:`symrb.symmetric.P_from_M` of a random :math:`M_0` scaled to each radius, and one
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
    >>> from replaced_experiments import norm_conservation
    >>> run = norm_conservation(radii=(1.0,), T=2.0, windows=2)
    >>> print(run.initial_norms.round(12))
    [1. 2.]
    >>> bool(run.deviation.max() < 1e-10)
    True
    """
    rs = [_finite_positive(r, "radii") for r in radii]
    if any(r >= 2 for r in rs):
        raise InputError(f"radii must be in (0, 2), got {list(radii)}")
    T = _finite_positive(T, "T")
    n = _count(n, "n", 4)
    tol = _finite_positive(tol, "tol")
    lam = np.linspace(0.5, 2.0, n)
    ts = np.linspace(0.0, T, 301)
    Q0 = symrb.random_SO(n, seed=seed)
    A = np.eye(n)
    A[:2, :2] = [[0.0, -1.0], [1.0, 0.0]]
    A[2:4, 2:4] = [[0.6, -0.8], [0.8, 0.6]]
    starts = [symrb.symmetric.P_from_M(Q0, _with_norm(n, r, seed + 5)) for r in rs] + [Q0 @ A]
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
