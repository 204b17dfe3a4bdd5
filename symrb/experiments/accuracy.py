"""The experiment of the book's page "What accuracy costs in time": a work-precision diagram.

:func:`work_precision` runs the discrete rigid body of Section 2 (the Moser-Veselov flow through
its symmetric representation, :func:`symrb.discrete_rigid_body_flow`) at a range of step sizes
and SciPy's explicit Runge-Kutta methods through :func:`symrb.integrate` at a range of
tolerances, on one free rigid body, and records for each run its error at the final time, the
drift of the conserved quantities and its cost in CPU time.

Timings on a shared machine are noisy: each run is timed in several rounds, the rounds
interleaved (every configuration once per round, so a slow spell of the machine touches all of
them alike), each timing long enough to be well above the clock's resolution, with
:func:`time.process_time` (the CPU time of this process, which other processes barely change),
BLAS pinned to one thread (threadpoolctl, when installed) and the garbage collector paused.
The median and the spread of the rounds are reported.
"""

from __future__ import annotations

import gc
import math
import time
from collections.abc import Callable, Sequence
from contextlib import nullcontext
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

import symrb
from symrb.errors import InputError

Array = NDArray[np.float64]

__all__ = ["Run", "WorkPrecision", "work_precision"]

MV = "Moser-Veselov"


@dataclass(frozen=True)
class Run:
    """One configuration of :func:`work_precision`.

    Attributes
    ----------
    method : str
        ``"Moser-Veselov"``, ``"RK45"`` or ``"DOP853"``.
    parameter : float
        The step size h (Moser-Veselov) or the relative tolerance rtol (Runge-Kutta).
    cpu_seconds : ndarray, shape (repeats,)
        The CPU time of one run, in seconds, in each round.
    work : int
        Steps taken (Moser-Veselov) or evaluations of the vector field (Runge-Kutta).
    error : float
        The largest entry of :math:`|Q(T) - Q_{ref}(T)|` and :math:`|M(T) - M_{ref}(T)|`.
    casimir_drift : float
        The largest change of an eigenvalue modulus of M (the spectrum of M, conserved by the
        flow), relative to the largest one.
    energy_drift : float
        :math:`|E(T) - E(0)|/E(0)` for the kinetic energy E.
    """

    method: str
    parameter: float
    cpu_seconds: Array
    work: int
    error: float
    casimir_drift: float
    energy_drift: float

    @property
    def setting(self) -> str:
        """The parameter as a table shows it (``h = 0.1``, ``rtol = 1e-05``)."""
        if self.method == MV:
            return f"h = {self.parameter:g}"
        return f"rtol = {self.parameter:.0e}"

    @property
    def median(self) -> float:
        """The median CPU time of the rounds, in seconds."""
        return float(np.median(self.cpu_seconds))

    @property
    def spread(self) -> tuple[float, float]:
        """The fastest and the slowest round, in seconds."""
        return float(self.cpu_seconds.min()), float(self.cpu_seconds.max())


@dataclass(frozen=True)
class WorkPrecision:
    """Result of :func:`work_precision`.

    Attributes
    ----------
    runs : tuple of Run
        Every configuration, Moser-Veselov first (decreasing h), then each Runge-Kutta method
        (decreasing rtol).
    T : float
        The final time.
    repeats : int
        The number of timing rounds.
    blas_pinned : bool
        Whether BLAS was limited to one thread (threadpoolctl installed).
    order : float
        The slope of log(error) against log(h) for the Moser-Veselov runs (least squares).
    """

    runs: tuple[Run, ...]
    T: float
    repeats: int
    blas_pinned: bool
    order: float

    def series(self, method: str) -> tuple[Run, ...]:
        """The runs of one method, in the order they were configured."""
        return tuple(r for r in self.runs if r.method == method)

    def cheapest(self, method: str, error: float) -> Run | None:
        """The run of ``method`` with the smallest median CPU time among those with an error at
        most ``error`` (None when none reaches it)."""
        ok = [r for r in self.series(method) if r.error <= error]
        return min(ok, key=lambda r: r.median, default=None)


def _errors(
    Q: Array, M: Array, Q_ref: Array, M_ref: Array, M0: Array, lam: Array
) -> tuple[float, float, float]:
    """(error at T, relative Casimir drift, relative energy drift)."""

    def spectrum(A: Array) -> Array:
        return np.sort(np.abs(np.linalg.eigvals(A).imag))

    s0 = spectrum(M0)
    e0 = float(symrb.kinetic_energy(M0, lam))
    error = max(float(np.abs(Q - Q_ref).max()), float(np.abs(M - M_ref).max()))
    casimir = float(np.abs(spectrum(M) - s0).max() / s0.max())
    energy = abs(float(symrb.kinetic_energy(M, lam)) - e0) / abs(e0)
    return error, casimir, energy


def _timer(fn: Callable[[], Any], min_seconds: float) -> tuple[Callable[[], float], Any]:
    """Run ``fn`` once (its output is returned) and calibrate a timer: it calls ``fn`` often
    enough to take at least ``min_seconds`` of CPU time and returns the CPU time per call."""
    start = time.process_time()
    out = fn()
    once = max(time.process_time() - start, 1e-6)
    number = max(1, math.ceil(min_seconds / once))

    def timed() -> float:
        start = time.process_time()
        for _ in range(number):
            fn()
        return (time.process_time() - start) / number

    return timed, out


def work_precision(
    steps: Sequence[float] = (0.2, 0.1, 0.05, 0.025, 0.0125, 0.00625),
    tolerances: Sequence[float] = (1e-3, 1e-5, 1e-7, 1e-9, 1e-11),
    methods: Sequence[str] = ("RK45", "DOP853"),
    T: float = 10.0,
    repeats: int = 5,
    min_seconds: float = 0.05,
    seed: int = 7,
) -> WorkPrecision:
    r"""Error and CPU time of the discrete rigid body and of Runge-Kutta methods (n = 3).

    The rigid body starts at :math:`Q_0` (Haar-random) and :math:`M_0` (random skew) with
    :math:`\Lambda = \operatorname{diag}(0.6, 1, 1.7)`; the reference at T is
    :func:`symrb.integrate` with DOP853 at ``rtol = 1e-13``, ``atol = 1e-14``.  The
    Moser-Veselov runs take ``round(T / h)`` steps of :func:`symrb.discrete_rigid_body_flow`;
    the Runge-Kutta runs use ``atol = rtol / 100``.  Each configuration is timed in ``repeats``
    interleaved rounds (see the module docstring).

    Parameters
    ----------
    steps : sequence of float
        The step sizes h of the Moser-Veselov runs (at least two, for the order).
    tolerances : sequence of float
        The relative tolerances of the Runge-Kutta runs.
    methods : sequence of str
        The ``solve_ivp`` methods.
    T : float
        The final time, > 0.
    repeats : int
        The number of timing rounds, >= 1.
    min_seconds : float
        The least CPU time of one timing (short runs are repeated within it), >= 0.
    seed : int
        The random source of the initial state.

    Returns
    -------
    WorkPrecision
        Every run with its CPU times, error and drifts, and the observed order of the discrete
        flow.

    Examples
    --------
    >>> from symrb.experiments.accuracy import work_precision
    >>> wp = work_precision(steps=(0.1, 0.05), tolerances=(1e-6,), methods=("DOP853",),
    ...                     T=2.0, repeats=3, min_seconds=0.0)
    >>> [r.setting for r in wp.runs]
    ['h = 0.1', 'h = 0.05', 'rtol = 1e-06']
    >>> round(wp.order)  # second order in h
    2
    >>> wp.runs[0].cpu_seconds.shape
    (3,)
    """
    hs = [float(h) for h in steps]
    tols = [float(x) for x in tolerances]
    if len(hs) < 2 or any(not h > 0 for h in hs):
        raise InputError(f"steps must hold at least two step sizes > 0, got {list(steps)}")
    if any(not 0 < x < 1 for x in tols):
        raise InputError(f"tolerances must be in (0, 1), got {list(tolerances)}")
    if not (np.isfinite(T) and T > 0):
        raise InputError(f"T must be a positive finite time, got {T!r}")
    if isinstance(repeats, bool) or int(repeats) != repeats or repeats < 1:
        raise InputError(f"repeats must be an integer >= 1, got {repeats!r}")
    if not min_seconds >= 0:
        raise InputError(f"min_seconds must be >= 0, got {min_seconds!r}")
    T = float(T)
    rng = np.random.default_rng(seed)
    lam = np.array([0.6, 1.0, 1.7])
    Q0 = symrb.random_SO(3, seed=rng)
    M0 = symrb.random_so(3, seed=rng)
    y0 = {"Q": Q0, "M": M0}
    ref = symrb.integrate(
        symrb.RigidBody, (0.0, T), y0, lam=lam, method="DOP853", rtol=1e-13, atol=1e-14
    )
    if not ref.success:
        raise RuntimeError(f"the reference integration failed: {ref.message}")
    Q_ref, M_ref = ref.y.Q[-1], ref.y.M[-1]

    def discrete(h: float) -> Callable[[], Any]:
        count = round(T / h)
        return lambda: symrb.discrete_rigid_body_flow(Q0, M0, lam, h, count, save_every=count)

    def runge_kutta(method: str, rtol: float) -> Callable[[], Any]:
        return lambda: symrb.integrate(
            symrb.RigidBody, (0.0, T), y0, lam=lam, method=method, rtol=rtol,
            atol=rtol * 1e-2, t_eval=[T],
        )  # fmt: skip

    configs = [(MV, h, discrete(h)) for h in hs]
    configs += [(m, rtol, runge_kutta(m, rtol)) for m in methods for rtol in tols]

    try:
        from threadpoolctl import threadpool_limits

        limits: Any = threadpool_limits(limits=1)
        pinned = True
    except ImportError:  # pragma: no cover - threadpoolctl comes with the book extra
        limits, pinned = nullcontext(), False

    gc_was_enabled = gc.isenabled()
    with limits:
        timers, outputs = [], []
        for _name, _param, fn in configs:
            timer, out = _timer(fn, min_seconds)
            if not out.success:
                raise RuntimeError(f"{_name} at {_param:g} failed: {out.message}")
            timers.append(timer)
            outputs.append(out)
        times = np.empty((len(configs), int(repeats)))
        gc.disable()
        try:
            for k in range(int(repeats)):
                for i, timer in enumerate(timers):
                    times[i, k] = timer()
        finally:
            if gc_was_enabled:
                gc.enable()

    runs = []
    for (name, param, _fn), out, cpu in zip(configs, outputs, times, strict=True):
        error, casimir, energy = _errors(out.y.Q[-1], out.y.M[-1], Q_ref, M_ref, M0, lam)
        work = round(T / param) if name == MV else int(out.nfev)
        runs.append(Run(name, param, cpu, work, error, casimir, energy))
    mv = [r for r in runs if r.method == MV]
    slope = np.polyfit(np.log([r.parameter for r in mv]), np.log([r.error for r in mv]), 1)[0]
    return WorkPrecision(
        runs=tuple(runs), T=T, repeats=int(repeats), blas_pinned=pinned, order=float(slope)
    )
