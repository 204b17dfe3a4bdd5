r"""Experiments of the book's rigid-body and Section 2 pages, one function each.

Each function runs one experiment of a page (the rigid body, the conventions, back-propagation,
the discrete symmetric rigid body, Moser-Veselov and the solver of :math:`J_D(U) = M`) through
the public functions of :mod:`symrb` and returns a frozen dataclass with the arrays the page plots
and the numbers its test asserts on.  The page and ``tests/test_experiments_discrete.py`` call the
same function, the test with smaller sizes where the page's run is long.

Noisy series (drifts at rounding level) come with a summary per window: the largest absolute value
over each of a few consecutive blocks of samples (:attr:`ManakovDrift.window_t` and the like), which
is what the figures draw.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import expm
from scipy.optimize import minimize

import symrb
from symrb import _validate as v
from symrb._validate import Array
from symrb.errors import InputError, SymrbError

__all__ = [
    "ManakovDrift",
    "manakov_drift",
    "TimeStepScaling",
    "time_step_scaling",
    "LayerJacobian",
    "layer_jacobian",
    "ToyTraining",
    "train_toy_classifier",
    "TraceMaximum",
    "trace_maximum",
    "AlgorithmAgreement",
    "algorithm_agreement",
    "InvariantDrift",
    "invariant_drift",
    "SecondOrder",
    "second_order",
    "SolverAccuracy",
    "solver_accuracy",
    "FoldApproach",
    "fold_approach",
    "SolverCost",
    "solver_cost",
]

_EPS = float(np.finfo(float).eps)
#: Manakov's integrals in the column order of :func:`symrb.manakov_integrals`: (k, j) is the
#: coefficient of lambda^j in tr(M + lambda Lambda^2)^k.
MANAKOV_LABELS = ("(2,0)", "(3,1)", "(4,0)", "(4,2)", "(5,1)", "(5,3)")


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


def _positive(x: object, name: str) -> float:
    value = v.real_scalar(x, name)
    if not value > 0:
        raise InputError(f"{name} must be a finite number > 0, got {x!r}")
    return value


@contextlib.contextmanager
def _one_blas_thread() -> Iterator[bool]:
    """Hold BLAS to one thread inside the block; yields whether it could (threadpoolctl)."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # pragma: no cover - threadpoolctl comes with the book extra
        yield False
        return
    with threadpool_limits(limits=1, user_api="blas"):
        yield True


# ---------------------------------------------------------------------------------------------
# The classical rigid body (book/rigid_body.md)


@dataclass(frozen=True, eq=False)
class ManakovDrift:
    r"""Result of :func:`manakov_drift`.

    Attributes
    ----------
    t : ndarray, shape (K,)
        The sample times.
    integrals : ndarray, shape (K, 6)
        Manakov's six integrals along the trajectory, in the order of ``labels``.
    labels : tuple of str
        The :math:`(k, j)` of each integral (coefficient of :math:`\lambda^j` in
        :math:`\operatorname{tr}(M + \lambda\Lambda^2)^k`).
    drift : ndarray, shape (K, 6)
        :math:`|F(t) - F(0)| / |F(0)|` for each integral.
    energy_drift : ndarray, shape (K,)
        The same for the kinetic energy.
    casimir_drift : ndarray, shape (K,)
        The largest of the same for the Casimirs :math:`\operatorname{tr}M^{2j}`.
    window_t : ndarray, shape (W,)
        The time at the end of each window.
    window_integrals, window_energy, window_casimirs : ndarray, shape (W,)
        The largest drift in each window (over the six integrals for ``window_integrals``).
    max_drift : ndarray, shape (6,)
        The largest drift of each integral over the whole run.
    max_energy_drift : float
        The largest drift of the energy.
    m12_range : float
        The range of the entry :math:`M_{12}` relative to :math:`\max|M(0)|`: a quantity that is
        not conserved, for comparison.
    rtol : float
        The integrator's relative (and absolute) tolerance.
    """

    t: Array
    integrals: Array
    labels: tuple[str, ...]
    drift: Array
    energy_drift: Array
    casimir_drift: Array
    window_t: Array
    window_integrals: Array
    window_energy: Array
    window_casimirs: Array
    max_drift: Array
    max_energy_drift: float
    m12_range: float
    rtol: float


def manakov_drift(
    lam: ArrayLike = (0.6, 0.9, 1.3, 1.9),
    t_end: float = 50.0,
    samples: int = 1001,
    windows: int = 25,
    rtol: float = 1e-12,
    seed: int = 4,
) -> ManakovDrift:
    r"""Manakov's integrals, the energy and the Casimirs along a rigid body trajectory.

    Integrates :class:`symrb.RigidBody` with :func:`symrb.integrate` (DOP853, ``rtol = atol``)
    from :math:`Q = I` and a random skew :math:`M_0` (``symrb.random_so(n, seed=...)``) and
    evaluates :func:`symrb.manakov_integrals`, :func:`symrb.kinetic_energy` and
    :func:`symrb.casimir_traces` at ``samples`` equally spaced times.

    Parameters
    ----------
    lam : array_like, shape (n,)
        The diagonal of :math:`\Lambda`.
    t_end : float, optional
        The final time, > 0.
    samples : int, optional
        The number of sample times in :math:`[0, t_{end}]`, >= 2.
    windows : int, optional
        The number of windows of the summary, >= 1.
    rtol : float, optional
        The integrator's tolerance, > 0.
    seed : int, optional
        The seed of :math:`M_0`.

    Returns
    -------
    ManakovDrift
        The trajectory's integrals, their drifts and the summary per window.

    Examples
    --------
    >>> from symrb.experiments.discrete import manakov_drift
    >>> run = manakov_drift(t_end=5.0, samples=51, windows=5)
    >>> run.integrals.shape, run.window_t.shape
    ((51, 6), (5,))
    >>> bool(run.max_drift.max() < 1e-9), bool(run.m12_range > 0.1)
    (True, True)
    """
    L = v.inertia(lam, positive=True)
    if L.ndim != 1:
        raise InputError(f"lam must be one diagonal of shape (n,), got shape {L.shape}")
    t_end = _positive(t_end, "t_end")
    samples = v.count(samples, "samples", 2)
    windows = v.count(windows, "windows", 1)
    rtol = _positive(rtol, "rtol")
    n = L.shape[0]
    M0 = symrb.random_so(n, seed=seed)
    t = np.linspace(0.0, t_end, samples)
    sol = symrb.integrate(
        symrb.RigidBody, (0.0, t_end), {"Q": np.eye(n), "M": M0}, lam=L,
        method="DOP853", rtol=rtol, atol=rtol, t_eval=t,
    )  # fmt: skip
    if not sol.success:
        raise SymrbError(f"the rigid body integration failed: {sol.message}")
    Ms = sol.y.M
    F = symrb.manakov_integrals(Ms, L)
    E = symrb.kinetic_energy(Ms, L)
    C = symrb.casimir_traces(Ms)
    drift = np.abs(F - F[0]) / np.abs(F[0])
    e_drift = np.abs(E - E[0]) / abs(E[0])
    c_drift = (np.abs(C - C[0]) / np.abs(C[0])).max(axis=-1)
    return ManakovDrift(
        t=t,
        integrals=F,
        labels=MANAKOV_LABELS,
        drift=drift,
        energy_drift=e_drift,
        casimir_drift=c_drift,
        window_t=_window_last(t, windows),
        window_integrals=_window_max(drift, windows),
        window_energy=_window_max(e_drift, windows),
        window_casimirs=_window_max(c_drift, windows),
        max_drift=drift.max(axis=0),
        max_energy_drift=float(e_drift.max()),
        m12_range=float(np.ptp(Ms[:, 0, 1]) / np.abs(M0).max()),
        rtol=rtol,
    )


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
        :func:`symrb.random_lam`).

    Returns
    -------
    TimeStepScaling
        The steps, the errors and the observed orders.

    Examples
    --------
    >>> from symrb.experiments.discrete import time_step_scaling
    >>> run = time_step_scaling(n=3, halvings=3)
    >>> [round(float(p), 2) for p in run.order]
    [2.0, 2.0]
    """
    n = v.count(n, "n", 2)
    h0 = _positive(h0, "h0")
    halvings = v.count(halvings, "halvings", 2)
    rng = np.random.default_rng(seed)
    Omega = symrb.random_so(n, seed=rng)
    lam = symrb.random_lam(n, seed=rng)
    M = symrb.J(Omega, lam)
    hs = np.asarray(h0 / 2.0 ** np.arange(halvings), dtype=float)
    err = np.array([np.linalg.norm(symrb.J_D(expm(h * Omega), lam) - h * M) for h in hs])
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
    r"""The Jacobian in :math:`x` of one layer of :func:`symrb.resnet_forward` as the weights
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
    >>> from symrb.experiments.discrete import layer_jacobian
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
            plus = symrb.resnet_forward(x1 + step * e, c * K1, b1, residual=residual)[-1]
            minus = symrb.resnet_forward(x1 - step * e, c * K1, b1, residual=residual)[-1]
            cols.append((plus - minus) / (2 * step))
        return np.array(cols).T

    gaps = {
        res: np.array([np.abs(jacobian(c, res) - np.eye(n)).max() for c in eps])
        for res in (True, False)
    }
    return LayerJacobian(scale=eps, residual_gap=gaps[True], plain_gap=gaps[False])


@dataclass(frozen=True, eq=False)
class ToyTraining:
    r"""Result of :func:`train_toy_classifier`.

    Attributes
    ----------
    losses : ndarray, shape (steps + 1,)
        The loss :math:`\Phi` before each gradient step and at the end.
    inputs, outputs : ndarray, shape (samples, 2)
        The points :math:`x_0` and their images :math:`x_N` under the trained network.
    labels : ndarray, shape (samples,)
        The classes :math:`\pm1`.
    accuracy : float
        The fraction of points whose output has the sign of their class in :math:`x_2`.
    window_step : ndarray, shape (W,)
        The last step of each window of the loss summary.
    window_min, window_max : ndarray, shape (W,)
        The smallest and largest loss in each window.
    """

    losses: Array
    inputs: Array
    outputs: Array
    labels: Array
    accuracy: float
    window_step: NDArray[np.int64]
    window_min: Array
    window_max: Array


def train_toy_classifier(
    samples: int = 200,
    layers: int = 8,
    steps: int = 1500,
    lr: float = 0.002,
    windows: int = 75,
    seed: int = 1,
) -> ToyTraining:
    """Train a residual tanh network on :func:`symrb.toy_classification` with :func:`symrb.train`
    (plain gradient descent on the gradients of :func:`symrb.loss_gradients`).

    Parameters
    ----------
    samples : int, optional
        The number of points, >= 1.
    layers : int, optional
        The number of layers, >= 1.
    steps : int, optional
        The number of gradient steps, >= 1.
    lr : float, optional
        The step size, > 0.
    windows : int, optional
        The number of windows of the loss summary (smallest and largest loss in each), >= 1.
    seed : int, optional
        The seed of the points; the initial weights are :math:`0.1` times standard normal
        numbers from ``seed - 1``, the biases zero.

    Returns
    -------
    ToyTraining
        The losses, the points before and after the network, and the accuracy.

    Examples
    --------
    >>> from symrb.experiments.discrete import train_toy_classifier
    >>> run = train_toy_classifier(samples=50, layers=2, steps=20, windows=4)
    >>> run.losses.shape, run.window_min.shape
    ((21,), (4,))
    >>> bool(run.losses[-1] < run.losses[0])
    True
    """
    samples = v.count(samples, "samples", 1)
    layers = v.count(layers, "layers", 1)
    steps = v.count(steps, "steps", 1)
    lr = _positive(lr, "lr")
    windows = v.count(windows, "windows", 1)
    x0, targets, labels = symrb.toy_classification(samples, seed=seed)
    rng = np.random.default_rng(seed - 1)
    K0 = 0.1 * rng.standard_normal((layers, 2, 2))
    run = symrb.train(x0, targets, K0, np.zeros((layers, 2)), steps=steps, lr=lr)
    out = symrb.resnet_forward(x0, run.K, run.beta)[-1]
    losses = run.losses
    blocks = np.array_split(np.arange(losses.shape[0]), min(windows, losses.shape[0]))
    return ToyTraining(
        losses=losses,
        inputs=x0,
        outputs=out,
        labels=labels,
        accuracy=float(np.mean(np.sign(out[:, 1]) == labels)),
        window_step=np.array([b[-1] for b in blocks]),
        window_min=np.array([losses[b].min() for b in blocks]),
        window_max=np.array([losses[b].max() for b in blocks]),
    )


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
    >>> from symrb.experiments.discrete import trace_maximum
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
# Moser-Veselov (book/section2/04_moser_veselov.md)


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
    with :math:`M_1 = Q_0^TP_0 - P_0^TQ_0` (:func:`symrb.symmetric_momentum`, claim D12); and
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
    >>> from symrb.experiments.discrete import algorithm_agreement
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
    with _one_blas_thread():
        sym = symrb.symmetric_flow(Q0, P0, L, 1.0, steps)
        Qs, Ms = sym.y.Q, sym.y.M
        M1 = symrb.symmetric_momentum(Q0, P0)
        mv2 = symrb.mv_algorithm2(Qs[1], M1, L, steps - 1)
        mv1 = symrb.mv_algorithm1(Q0, Qs[1], L, steps - 1)
        sym_r = symrb.symmetric_flow(R @ Q0, R @ P0, L, 1.0, steps)
        mv1_r = symrb.mv_algorithm1(R @ Q0, R @ Qs[1], L, steps - 1)
        wrong = symrb.mv_algorithm2(Q0, M1, L, steps - 1)
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


@dataclass(frozen=True, eq=False)
class InvariantDrift:
    r"""Result of :func:`invariant_drift`.

    Attributes
    ----------
    steps : int
        The number of steps.
    k : ndarray, shape (K,)
        The step index of each saved state.
    drift : dict of str to ndarray
        The drift at each saved state, relative to the initial value: ``"spectrum"`` (largest
        change of an eigenvalue of :math:`M_k` over the largest), ``"casimir"``
        (:math:`\operatorname{tr}M^2`), ``"energy"``, ``"manakov"`` (largest over the six), and
        ``"orthogonality"`` (:math:`\|Q_k^TQ_k - I\|_F`, absolute).
    window_k : ndarray, shape (W,)
        The last step of each window of the summary.
    window : dict of str to ndarray
        The largest drift of each kind in each window.
    max_drift : dict of str to float
        The largest drift of each kind over the run.
    seconds : float
        Wall time of the run.
    """

    steps: int
    k: NDArray[np.int64]
    drift: dict[str, Array]
    window_k: NDArray[np.int64]
    window: dict[str, Array]
    max_drift: dict[str, float]
    seconds: float


def invariant_drift(
    steps: int = 50_000,
    save_every: int = 50,
    lam: ArrayLike = (0.7, 1.1, 1.6),
    scale: float = 0.05,
    windows: int = 25,
    seed: int = 5,
    progress: bool = False,
) -> InvariantDrift:
    r"""Run MV-Algorithm 2 (:func:`symrb.mv_algorithm2`) for ``steps`` steps and record how far its
    invariants drift: the spectrum of :math:`M_k`, the Casimir :math:`\operatorname{tr}M^2`, the
    kinetic energy, Manakov's integrals, and the orthogonality of :math:`Q_k`.  BLAS is held to
    one thread during the run (with threadpoolctl, when installed).

    Parameters
    ----------
    steps : int, optional
        The number of steps, >= 1.
    save_every : int, optional
        Record every ``save_every``-th state, >= 1.
    lam : array_like, shape (n,)
        The diagonal of :math:`\Lambda`.
    scale : float, optional
        The size of the random discrete momentum :math:`M_1`, > 0.
    windows : int, optional
        The number of windows of the summary, >= 1.
    seed : int, optional
        The seed of :math:`Q_1` and :math:`M_1`.
    progress : bool, optional
        Show a progress bar (tqdm).

    Returns
    -------
    InvariantDrift
        The drifts at the saved states, and their summary per window.

    Examples
    --------
    >>> from symrb.experiments.discrete import invariant_drift
    >>> run = invariant_drift(steps=200, save_every=10, windows=4)
    >>> int(run.k[-1]), sorted(run.max_drift)
    (200, ['casimir', 'energy', 'manakov', 'orthogonality', 'spectrum'])
    >>> bool(max(run.max_drift.values()) < 200 * 2.3e-16)
    True
    """
    steps = v.count(steps, "steps", 1)
    save_every = v.count(save_every, "save_every", 1)
    L = v.inertia(lam, positive=True)
    if L.ndim != 1:
        raise InputError(f"lam must be one diagonal of shape (n,), got shape {L.shape}")
    scale = _positive(scale, "scale")
    windows = v.count(windows, "windows", 1)
    n = L.shape[0]
    rng = np.random.default_rng(seed)
    Q1 = symrb.random_SO(n, seed=rng)
    M1 = symrb.random_so(n, seed=rng, scale=scale)
    start = time.perf_counter()
    with _one_blas_thread():
        run = symrb.mv_algorithm2(Q1, M1, L, steps, save_every=save_every, progress=progress)
    seconds = time.perf_counter() - start
    if not run.success:
        raise SymrbError(f"MV-Algorithm 2 stopped early: {run.message}")
    Qr, Mr = run.y.Q, run.y.M
    eig = np.sort(np.linalg.eigvals(Mr).imag, axis=-1)
    cas = symrb.casimir_traces(Mr)[:, 0]
    energy = symrb.kinetic_energy(Mr, L)
    man = symrb.manakov_integrals(Mr, L)
    drift = {
        "spectrum": np.abs(eig - eig[0]).max(axis=-1) / np.abs(eig[0]).max(),
        "casimir": np.abs(cas / cas[0] - 1),
        "energy": np.abs(energy / energy[0] - 1),
        "manakov": (np.abs(man - man[0]) / np.abs(man[0])).max(axis=-1),
        "orthogonality": np.linalg.norm(np.swapaxes(Qr, -1, -2) @ Qr - np.eye(n), axis=(-2, -1)),
    }
    k = np.asarray(run.k)
    return InvariantDrift(
        steps=steps,
        k=k,
        drift=drift,
        window_k=_window_last(k[1:], windows),
        window={key: _window_max(val[1:], windows) for key, val in drift.items()},
        max_drift={key: float(val.max()) for key, val in drift.items()},
        seconds=seconds,
    )


@dataclass(frozen=True, eq=False)
class SecondOrder:
    r"""Result of :func:`second_order`.

    Attributes
    ----------
    h : ndarray, shape (m,)
        The time steps.
    error_Q, error_M : ndarray, shape (m,)
        :math:`\max|Q_N - Q(T)|` and :math:`\max|M_N - M(T)|` at :math:`T = Nh`.
    ratio_Q, ratio_M : ndarray, shape (m - 1,)
        The ratios of consecutive errors (4 for a second-order method as h halves).
    T : float
        The final time.
    """

    h: Array
    error_Q: Array
    error_M: Array
    ratio_Q: Array
    ratio_M: Array
    T: float


def second_order(
    hs: Sequence[float] = (0.1, 0.05, 0.025, 0.0125),
    T: float = 2.0,
    lam: ArrayLike = (0.6, 0.9, 1.3, 1.7),
    scale: float = 0.5,
    seed: int = 3,
) -> SecondOrder:
    r"""The error of :func:`symrb.discrete_rigid_body_flow` at time ``T`` against the rigid body
    flow, for several steps :math:`h`.

    The reference is :func:`symrb.integrate` of :class:`symrb.RigidBody` (DOP853, tolerances
    :math:`10^{-13}`); the start is a random :math:`Q_0` and a random skew :math:`M_0` of size
    ``scale``.

    Parameters
    ----------
    hs : sequence of float
        The steps, each dividing ``T`` into a whole number of steps.
    T : float, optional
        The final time, > 0.
    lam : array_like, shape (n,)
        The diagonal of :math:`\Lambda`.
    scale : float, optional
        The size of :math:`M_0`, > 0.
    seed : int, optional
        The seed of :math:`M_0` and :math:`Q_0`.

    Returns
    -------
    SecondOrder
        The errors in Q and M and their ratios.

    Examples
    --------
    >>> from symrb.experiments.discrete import second_order
    >>> run = second_order(hs=(0.1, 0.05), T=1.0)
    >>> [round(float(r), 1) for r in run.ratio_M]
    [4.0]
    """
    T = _positive(T, "T")
    h = np.asarray(v.as_float_array(hs, "hs"), dtype=float).reshape(-1)
    if h.size < 2 or not np.all(h > 0):
        raise InputError(f"hs must be at least two steps > 0, got {list(hs)!r}")
    counts = np.rint(T / h)
    if np.any(np.abs(counts * h - T) > 1e-9 * T):
        raise InputError(f"every step in hs must divide T = {T} evenly, got {list(hs)!r}")
    L = v.inertia(lam, positive=True)
    if L.ndim != 1:
        raise InputError(f"lam must be one diagonal of shape (n,), got shape {L.shape}")
    scale = _positive(scale, "scale")
    n = L.shape[0]
    rng = np.random.default_rng(seed)
    M0, Q0 = symrb.random_so(n, seed=rng, scale=scale), symrb.random_SO(n, seed=rng)
    ref = symrb.integrate(
        symrb.RigidBody, (0.0, T), {"Q": Q0, "M": M0}, lam=L, method="DOP853",
        rtol=1e-13, atol=1e-13, t_eval=[T],
    )  # fmt: skip
    QT, MT = ref.y.Q[-1], ref.y.M[-1]
    eQ, eM = [], []
    for step, N in zip(h, counts.astype(int), strict=True):
        run = symrb.discrete_rigid_body_flow(Q0, M0, L, float(step), int(N), save_every=int(N))
        eQ.append(np.abs(run.y.Q[-1] - QT).max())
        eM.append(np.abs(run.y.M[-1] - MT).max())
    errQ, errM = np.array(eQ), np.array(eM)
    return SecondOrder(
        h=h, error_Q=errQ, error_M=errM, ratio_Q=errQ[:-1] / errQ[1:],
        ratio_M=errM[:-1] / errM[1:], T=T,
    )  # fmt: skip


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

    For each dimension the diagonal of :math:`\Lambda` is drawn by :func:`symrb.random_lam` and a
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
    >>> from symrb.experiments.discrete import solver_accuracy
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
        lam = symrb.random_lam(nn, seed=rng)
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
        The seeds of :math:`\Lambda` (:func:`symrb.random_lam`) and of the direction :math:`D`
        (:func:`symrb.random_so`).

    Returns
    -------
    FoldApproach
        The margin, the smallest singular value of the linearisation, the residual and the
        iterations at each distance, and the fitted exponent of the margin.

    Examples
    --------
    >>> from symrb.experiments.discrete import fold_approach
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
    lam = symrb.random_lam(n, seed=seed_lam)
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
    >>> from symrb.experiments.discrete import solver_cost
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
            lam = symrb.random_lam(nn, seed=rng)
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
