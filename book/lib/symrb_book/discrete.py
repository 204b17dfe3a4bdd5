r"""The computations of the conventions page and the Section 2 pages that are not scenes.

Each function runs one experiment of a page (the conventions, back-propagation, the discrete
symmetric rigid body and the solver of :math:`J_D(U) = M`) through the public functions of
:mod:`symrb` and returns a frozen dataclass with the arrays the page plots and the numbers its test
asserts on.  The page and ``tests/test_book_lib.py`` call the same function, the test with smaller
sizes where the page's run is long.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import expm
from scipy.optimize import minimize

import symrb
from symrb import _validate as v
from symrb._validate import Array
from symrb.errors import InputError
from symrb_book._inputs import one_blas_thread as _one_blas_thread
from symrb_book._inputs import positive as _positive

__all__ = [
    "TimeStepScaling",
    "time_step_scaling",
    "LayerJacobian",
    "layer_jacobian",
    "TraceMaximum",
    "trace_maximum",
    "SolverAccuracy",
    "solver_accuracy",
    "FoldApproach",
    "fold_approach",
    "SolverCost",
    "solver_cost",
]

_EPS = float(np.finfo(float).eps)


# ---------------------------------------------------------------------------------------------
# Conventions (book/conventions.md)


@dataclass(frozen=True, eq=False)
class TimeStepScaling:
    r"""Result of :func:`time_step_scaling`.

    Attributes
    ----------
    h : ndarray, shape (m,)
        The time steps.
    error : ndarray, shape (m,)
        :math:`\|J_D(\exp(h\Omega)) - hJ(\Omega)\|_F`.
    order : ndarray, shape (m - 1,)
        :math:`\log_2` of the ratio of consecutive errors (the steps halve).
    leading : float
        :math:`\|\tfrac12(\Omega^2\Lambda - \Lambda\Omega^2)\|_F`, the coefficient of
        :math:`h^2` in the error, to which ``error / h**2`` tends.
    Omega : ndarray, shape (n, n)
        The body angular velocity used.
    lam : ndarray, shape (n,)
        The diagonal of :math:`\Lambda` used.
    """

    h: Array
    error: Array
    order: Array
    leading: float
    Omega: Array
    lam: Array


def time_step_scaling(
    n: int = 4, h0: float = 0.004, halvings: int = 4, seed: int = 20240601
) -> TimeStepScaling:
    r"""How far a discrete momentum :math:`J_D(U)`, :math:`U = \exp(h\Omega)`, is from
    :math:`hM = hJ(\Omega)`: the error and its observed order as :math:`h` halves.

    Parameters
    ----------
    n : int, optional
        The dimension, >= 2.
    h0 : float, optional
        The largest step, > 0.
    halvings : int, optional
        The number of steps :math:`h_0, h_0/2, \dots`, >= 2.
    seed : int, optional
        The seed of :math:`\Omega` and :math:`\Lambda` (:func:`symrb.random_so`,
        :func:`symrb.algebra.random_lam`).

    Returns
    -------
    TimeStepScaling
        The steps, the errors and the observed orders.

    Examples
    --------
    >>> from symrb_book.discrete import time_step_scaling
    >>> run = time_step_scaling(n=3, halvings=3)
    >>> [round(float(p), 2) for p in run.order]
    [2.0, 2.0]
    """
    n = v.count(n, "n", 2)
    h0 = _positive(h0, "h0")
    halvings = v.count(halvings, "halvings", 2)
    rng = np.random.default_rng(seed)
    Omega = symrb.random_so(n, seed=rng)
    lam = symrb.algebra.random_lam(n, seed=rng)
    M = symrb.J(Omega, lam)
    hs = np.asarray(h0 / 2.0 ** np.arange(halvings), dtype=float)
    err = np.array([np.linalg.norm(symrb.algebra.J_D(expm(h * Omega), lam) - h * M) for h in hs])
    O2L = Omega @ Omega * lam  # Omega^2 Lambda: column j scaled by lam_j
    leading = float(np.linalg.norm(O2L - O2L.T) / 2)  # (Omega^2 Lambda)^T = Lambda Omega^2
    return TimeStepScaling(
        h=hs, error=err, order=np.log2(err[:-1] / err[1:]), leading=leading, Omega=Omega, lam=lam
    )


# ---------------------------------------------------------------------------------------------
# Back-propagation (book/section2/02_backprop.md)


@dataclass(frozen=True, eq=False)
class LayerJacobian:
    r"""Result of :func:`layer_jacobian`.

    Attributes
    ----------
    scale : ndarray, shape (m,)
        The weight scales :math:`\varepsilon` (weights :math:`\varepsilon K_1`).
    residual_gap : ndarray, shape (m,)
        :math:`\max|\partial f/\partial x - I|` for the residual layer
        :math:`x + \tanh(Kx + \beta)`.
    plain_gap : ndarray, shape (m,)
        The same for the plain layer :math:`\tanh(Kx + \beta)`.
    """

    scale: Array
    residual_gap: Array
    plain_gap: Array


def layer_jacobian(scales: ArrayLike | None = None, n: int = 3, seed: int = 0) -> LayerJacobian:
    r"""The Jacobian in :math:`x` of one layer of :func:`symrb.learning.resnet_forward` as the weights
    shrink: a residual layer tends to the identity, a plain layer to zero.

    The Jacobian is taken by central differences (step :math:`10^{-6}`) at a random point, with
    random weights :math:`K_1` and bias :math:`\beta` scaled by :math:`\varepsilon` (only
    :math:`K`) and :math:`\sigma = \tanh`.

    Parameters
    ----------
    scales : array_like, shape (m,), optional
        The scales :math:`\varepsilon > 0`; default 9 from :math:`10^{-4}` to 1, evenly spaced
        in the logarithm.
    n : int, optional
        The state dimension, >= 1.
    seed : int, optional
        The seed of :math:`K_1`, :math:`\beta` and the point.

    Returns
    -------
    LayerJacobian
        The distances of both Jacobians to the identity.

    Examples
    --------
    >>> from symrb_book.discrete import layer_jacobian
    >>> run = layer_jacobian(scales=[1e-4, 1.0])
    >>> bool(run.residual_gap[0] < 1e-3), bool(abs(run.plain_gap[0] - 1) < 1e-3)
    (True, True)
    """
    if scales is None:
        scales = np.logspace(-4, 0, 9)
    eps = np.asarray(v.as_float_array(scales, "scales"), dtype=float).reshape(-1)
    if eps.size == 0 or not np.all(eps > 0):
        raise InputError(f"scales must be numbers > 0, got {np.asarray(scales)!r}")
    n = v.count(n, "n", 1)
    rng = np.random.default_rng(seed)
    K1, b1, x1 = rng.standard_normal((1, n, n)), rng.standard_normal((1, n)), rng.standard_normal(n)
    step = 1e-6

    def jacobian(c: float, residual: bool) -> Array:
        cols = []
        for e in np.eye(n):
            plus = symrb.learning.resnet_forward(x1 + step * e, c * K1, b1, residual=residual)[-1]
            minus = symrb.learning.resnet_forward(x1 - step * e, c * K1, b1, residual=residual)[-1]
            cols.append((plus - minus) / (2 * step))
        return np.array(cols).T

    gaps = {
        res: np.array([np.abs(jacobian(c, res) - np.eye(n)).max() for c in eps])
        for res in (True, False)
    }
    return LayerJacobian(scale=eps, residual_gap=gaps[True], plain_gap=gaps[False])


# ---------------------------------------------------------------------------------------------
# The discrete symmetric rigid body (book/section2/03_discrete_rigid_body.md)


@dataclass(frozen=True, eq=False)
class TraceMaximum:
    r"""Result of :func:`trace_maximum`.

    Attributes
    ----------
    A : ndarray, shape (n, n)
        The matrix.
    U_search : ndarray, shape (n, n)
        The maximiser found by BFGS over :math:`U = \exp(\xi)`, :math:`\xi` skew.
    U_closed : ndarray, shape (n, n)
        The closed form :math:`W\operatorname{diag}(1, \dots, 1, \det WV^T)V^T` from
        :math:`A = V\Sigma W^T`.
    value_search, value_closed : float
        :math:`\operatorname{tr}(AU)` at both.
    asymmetry : float
        :math:`\|AU - (AU)^T\|_F / \|A\|_F` at the BFGS maximiser (zero at a critical point).
    """

    A: Array
    U_search: Array
    U_closed: Array
    value_search: float
    value_closed: float
    asymmetry: float


def trace_maximum(n: int = 4, seed: int = 1) -> TraceMaximum:
    r"""Maximise :math:`\operatorname{tr}(AU)` over :math:`SO(n)` for a random :math:`A`, by a
    generic optimiser (BFGS on :math:`\xi \mapsto -\operatorname{tr}(A\exp\xi)`, from
    :math:`\xi = 0`) and by the closed form from the singular value decomposition.

    Parameters
    ----------
    n : int, optional
        The dimension, >= 2.
    seed : int, optional
        The seed of :math:`A` (standard normal entries).

    Returns
    -------
    TraceMaximum
        Both maximisers, their values and the asymmetry of :math:`AU` at the one found.

    Examples
    --------
    >>> from symrb_book.discrete import trace_maximum
    >>> run = trace_maximum(n=3)
    >>> bool(abs(run.value_search - run.value_closed) < 1e-9), bool(run.asymmetry < 1e-6)
    (True, True)
    """
    n = v.count(n, "n", 2)
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    pairs = [(i, j) for i in range(n) for j in range(i + 1, n)]

    def rotation(x: Array) -> Array:
        xi = np.zeros((n, n))
        for c, (i, j) in zip(x, pairs, strict=True):
            xi[i, j], xi[j, i] = c, -c
        return np.asarray(expm(xi))

    best = minimize(
        lambda x: -np.trace(A @ rotation(x)), np.zeros(len(pairs)), method="BFGS",
        options={"gtol": 1e-10},
    )  # fmt: skip
    U = rotation(best.x)
    V, _s, Wt = np.linalg.svd(A)
    D = np.eye(n)
    D[-1, -1] = np.sign(np.linalg.det(Wt.T @ V.T))
    U_svd = Wt.T @ D @ V.T
    AU = A @ U
    return TraceMaximum(
        A=A,
        U_search=U,
        U_closed=U_svd,
        value_search=float(np.trace(AU)),
        value_closed=float(np.trace(A @ U_svd)),
        asymmetry=float(np.linalg.norm(AU - AU.T) / np.linalg.norm(A)),
    )


# ---------------------------------------------------------------------------------------------
# The solver of J_D(U) = M (book/section2/05_solver.md)


@dataclass(frozen=True, eq=False)
class SolverAccuracy:
    r"""Result of :func:`solver_accuracy`: one entry per (dimension, fraction) pair.

    Attributes
    ----------
    n : ndarray of int, shape (m,)
        The dimension.
    fraction : ndarray, shape (m,)
        :math:`t/t^*`: how far along the ray to the fold.
    residual : ndarray, shape (m,)
        :math:`\|J_D(U) - M\|_F / (\varepsilon\|M\|_F)` (:math:`\varepsilon` the float64
        rounding unit).
    orthogonality : ndarray, shape (m,)
        :math:`\|U^TU - I\|_F / \varepsilon`.
    det_error : ndarray, shape (m,)
        :math:`\det U - 1`.
    iterations : ndarray of int, shape (m,)
        Newton iterations after the Riccati start.
    margin : ndarray, shape (m,)
        :math:`\min\operatorname{Re}\sigma(U\Lambda)`, which tends to 0 at the fold.
    """

    n: NDArray[np.int64]
    fraction: Array
    residual: Array
    orthogonality: Array
    det_error: Array
    iterations: NDArray[np.int64]
    margin: Array


def solver_accuracy(
    sizes: Sequence[int] = (2, 3, 4, 5, 8, 12, 20, 30, 40, 50),
    fractions: Sequence[float] = (0.3, 0.9, 0.999),
    seed: int = 2024,
) -> SolverAccuracy:
    r"""Solve :math:`J_D(U) = M` with :func:`symrb.solve_moser_veselov` on random problems at given
    fractions of the way to the fold (:func:`symrb.fold_scale`), and measure the solution.

    For each dimension the diagonal of :math:`\Lambda` is drawn by :func:`symrb.algebra.random_lam` and a
    direction :math:`D` by :func:`symrb.random_so`; :math:`M = f\,t^*D` for each fraction
    :math:`f`.

    Parameters
    ----------
    sizes : sequence of int
        The dimensions, each >= 2.
    fractions : sequence of float
        The fractions, each in (0, 1).
    seed : int, optional
        The seed of every draw.

    Returns
    -------
    SolverAccuracy
        Residual, orthogonality, determinant, iterations and margin of each solve.

    Examples
    --------
    >>> from symrb_book.discrete import solver_accuracy
    >>> run = solver_accuracy(sizes=(3, 5), fractions=(0.5,))
    >>> run.n.tolist(), bool(run.residual.max() <= 10)
    ([3, 5], True)
    """
    dims = [v.count(s, "sizes", 2) for s in sizes]
    fr = np.asarray(v.as_float_array(fractions, "fractions"), dtype=float).reshape(-1)
    if not dims or fr.size == 0 or not np.all((fr > 0) & (fr < 1)):
        raise InputError(
            f"sizes must be non-empty and fractions in (0, 1), got {list(sizes)!r}, "
            f"{list(fractions)!r}"
        )
    rng = np.random.default_rng(seed)
    rows: list[tuple[int, float, float, float, float, int, float]] = []
    for nn in dims:
        lam = symrb.algebra.random_lam(nn, seed=rng)
        D = symrb.random_so(nn, seed=rng)
        t_star = float(symrb.fold_scale(D, lam))
        for f in fr:
            M = f * t_star * D
            U, info = symrb.solve_moser_veselov(M, lam, return_info=True)
            scale = _EPS * np.linalg.norm(M)
            rows.append((
                nn, float(f), float(info.residual / scale), float(info.orthogonality) / _EPS,
                float(np.linalg.det(U)) - 1.0, int(info.iterations), float(info.margin),
            ))  # fmt: skip
    cols = list(zip(*rows, strict=True))
    return SolverAccuracy(
        n=np.array(cols[0], dtype=np.int64),
        fraction=np.array(cols[1]),
        residual=np.array(cols[2]),
        orthogonality=np.array(cols[3]),
        det_error=np.array(cols[4]),
        iterations=np.array(cols[5], dtype=np.int64),
        margin=np.array(cols[6]),
    )


@dataclass(frozen=True, eq=False)
class FoldApproach:
    r"""Result of :func:`fold_approach`.

    Attributes
    ----------
    n : int
        The dimension.
    distance : ndarray, shape (m,)
        :math:`1 - t/t^*`.
    margin : ndarray, shape (m,)
        :math:`\min\operatorname{Re}\sigma(U\Lambda)`.
    sigma_min : ndarray, shape (m,)
        The smallest singular value of :math:`\xi \mapsto U\xi\Lambda + \Lambda\xi U^T` on
        :math:`\mathfrak{so}(n)` (basis :math:`E_{ij} - E_{ji}`).
    residual : ndarray, shape (m,)
        :math:`\|J_D(U) - M\|_F / (\varepsilon\|M\|_F)`.
    iterations : ndarray of int, shape (m,)
        Newton iterations after the Riccati start.
    t_star : float
        The fold :math:`t^*` of the ray.
    exponent : float
        The slope of :math:`\log` margin against :math:`\log` distance, fitted over the
        distances below :math:`10^{-5}`.
    past_fold : str
        The message of the :class:`symrb.OutOfDomainError` raised at :math:`(1 + 10^{-3})t^*`.
    """

    n: int
    distance: Array
    margin: Array
    sigma_min: Array
    residual: Array
    iterations: NDArray[np.int64]
    t_star: float
    exponent: float
    past_fold: str


def fold_approach(
    n: int = 6, distances: ArrayLike | None = None, seed_lam: int = 1, seed_dir: int = 2
) -> FoldApproach:
    r"""Solve :math:`J_D(U) = (1 - d)t^*D` along one ray as :math:`d \to 0` and measure how the
    branch ends; then try one point past the fold.

    Parameters
    ----------
    n : int, optional
        The dimension, >= 2.
    distances : array_like, optional
        The distances :math:`d` to the fold, in (0, 1); default 40 from :math:`10^{-10}` to
        :math:`0.5`, evenly spaced in the logarithm.
    seed_lam, seed_dir : int, optional
        The seeds of :math:`\Lambda` (:func:`symrb.algebra.random_lam`) and of the direction :math:`D`
        (:func:`symrb.random_so`).

    Returns
    -------
    FoldApproach
        The margin, the smallest singular value of the linearisation, the residual and the
        iterations at each distance, and the fitted exponent of the margin.

    Examples
    --------
    >>> from symrb_book.discrete import fold_approach
    >>> run = fold_approach(n=3, distances=[1e-8, 1e-7, 1e-6])
    >>> round(run.exponent, 1), "fold" in run.past_fold
    (0.5, True)
    """
    n = v.count(n, "n", 2)
    if distances is None:
        dist = np.logspace(-10, np.log10(0.5), 40)
    else:
        dist = np.asarray(v.as_float_array(distances, "distances"), dtype=float).reshape(-1)
    if dist.size < 2 or not np.all((dist > 0) & (dist < 1)):
        raise InputError(f"distances must be at least two numbers in (0, 1), got {dist!r}")
    lam = symrb.algebra.random_lam(n, seed=seed_lam)
    D = symrb.random_so(n, seed=seed_dir)
    t_star = float(symrb.fold_scale(D, lam))
    pairs = [(i, j) for i in range(n) for j in range(i + 1, n)]
    Lam = np.diag(lam)

    def sigma_min(U: Array) -> float:
        cols = []
        for i, j in pairs:
            E = np.zeros((n, n))
            E[i, j], E[j, i] = 1.0, -1.0
            out = U @ E @ Lam + Lam @ E @ U.T
            cols.append([out[a, b] for a, b in pairs])
        return float(np.linalg.svd(np.array(cols).T, compute_uv=False).min())

    margin, smin, res, its = [], [], [], []
    for d in dist:
        M = (1 - d) * t_star * D
        U, info = symrb.solve_moser_veselov(M, lam, return_info=True)
        margin.append(float(info.margin))
        smin.append(sigma_min(U))
        res.append(float(info.residual) / (_EPS * np.linalg.norm(M)))
        its.append(int(info.iterations))
    near = np.flatnonzero(dist < 1e-5)
    if near.size < 2:
        near = np.argsort(dist)[:2]
    exponent = float(np.polyfit(np.log(dist[near]), np.log(np.asarray(margin)[near]), 1)[0])
    try:
        symrb.solve_moser_veselov((1 + 1e-3) * t_star * D, lam)
    except symrb.OutOfDomainError as exc:
        past = str(exc)
    else:  # pragma: no cover - the solver would have returned a non-solution
        raise AssertionError("solve_moser_veselov returned a solution past the fold")
    return FoldApproach(
        n=n,
        distance=dist,
        margin=np.array(margin),
        sigma_min=np.array(smin),
        residual=np.array(res),
        iterations=np.array(its, dtype=np.int64),
        t_star=t_star,
        exponent=exponent,
        past_fold=past,
    )


@dataclass(frozen=True, eq=False)
class SolverCost:
    """Result of :func:`solver_cost`.

    Attributes
    ----------
    n : ndarray of int, shape (m,)
        The dimensions.
    cold_ms : ndarray, shape (m, repeats)
        Process CPU time of one cold solve (Riccati start), in milliseconds, per repeat.
    warm_ms : ndarray, shape (m, repeats)
        The same for a warm solve (started from the solution of a nearby momentum, as the time
        steppers do).
    cold_median, warm_median : ndarray, shape (m,)
        The medians over the repeats.
    pinned : bool
        Whether BLAS was held to one thread (threadpoolctl available).
    """

    n: NDArray[np.int64]
    cold_ms: Array
    warm_ms: Array
    cold_median: Array
    warm_median: Array
    pinned: bool


def solver_cost(
    sizes: Sequence[int] = (3, 5, 10, 20, 50), repeats: int = 9, inner: int = 5, seed: int = 7
) -> SolverCost:
    r"""Process CPU time (:func:`time.process_time`) of :func:`symrb.solve_moser_veselov`, cold and
    warm, with BLAS held to one thread.

    Each repeat times ``inner`` solves and divides by ``inner``; the result keeps every repeat, so
    a figure can show the median and the spread.  The momentum is half-way to the fold, and the
    warm start is the solution for a momentum 1 % smaller.

    Parameters
    ----------
    sizes : sequence of int
        The dimensions, each >= 2.
    repeats : int, optional
        The number of repeats, >= 1.
    inner : int, optional
        Solves per repeat, >= 1.
    seed : int, optional
        The seed of :math:`\Lambda` and of the momentum direction.

    Returns
    -------
    SolverCost
        CPU milliseconds per solve, per repeat, and their medians.

    Examples
    --------
    >>> from symrb_book.discrete import solver_cost
    >>> run = solver_cost(sizes=(3,), repeats=3, inner=2)
    >>> run.cold_ms.shape, bool(run.cold_median[0] > 0)
    ((1, 3), True)
    """
    dims = [v.count(s, "sizes", 2) for s in sizes]
    if not dims:
        raise InputError(f"sizes must name at least one dimension, got {list(sizes)!r}")
    repeats = v.count(repeats, "repeats", 1)
    inner = v.count(inner, "inner", 1)
    rng = np.random.default_rng(seed)
    cold = np.empty((len(dims), repeats))
    warm = np.empty((len(dims), repeats))
    with _one_blas_thread() as pinned:
        for row, nn in enumerate(dims):
            lam = symrb.algebra.random_lam(nn, seed=rng)
            D = symrb.random_so(nn, seed=rng)
            M = 0.5 * float(symrb.fold_scale(D, lam)) * D
            U0 = np.asarray(symrb.solve_moser_veselov(0.99 * M, lam))
            for r in range(repeats):
                for table, start_U in ((cold, None), (warm, U0)):
                    start = time.process_time()
                    for _ in range(inner):
                        symrb.solve_moser_veselov(M, lam, U0=start_U)
                    table[row, r] = (time.process_time() - start) / inner * 1e3
    return SolverCost(
        n=np.array(dims, dtype=np.int64),
        cold_ms=cold,
        warm_ms=warm,
        cold_median=np.median(cold, axis=1),
        warm_median=np.median(warm, axis=1),
        pinned=bool(pinned),
    )
