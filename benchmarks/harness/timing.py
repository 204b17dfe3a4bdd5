"""Timing and fitting: interleaved CPU-time medians, log-log slopes, the cost at a target error."""

from __future__ import annotations

import gc
import math
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from symrb.errors import InputError


def time_interleaved(
    fns: Mapping[str, Callable[[], Any]], *, rounds: int = 3, min_time: float = 0.01
) -> dict[str, dict[str, float]]:
    """Process CPU time per call of each function: medians of interleaved rounds.

    Each function is first called once (a warm-up that also sets how many calls one timing
    repeats so that it lasts at least ``min_time``); then, ``rounds`` times, each function is
    timed once, in turn.  The garbage collector is paused while timing.

    Parameters
    ----------
    fns : mapping of str to callable
        The configurations; each is called without arguments.
    rounds : int, optional
        The number of rounds, >= 1.
    min_time : float, optional
        The least duration of one timing, in seconds of process time.

    Returns
    -------
    dict
        For each name: ``median``, ``min``, ``max`` (seconds per call), ``rounds`` and ``loops``
        (calls per timing).

    Examples
    --------
    >>> from benchmarks.harness import time_interleaved
    >>> t = time_interleaved({"sum": lambda: sum(range(1000))}, rounds=3, min_time=0.001)
    >>> t["sum"]["min"] <= t["sum"]["median"] <= t["sum"]["max"], t["sum"]["rounds"]
    (True, 3)
    """
    if int(rounds) < 1:
        raise InputError(f"rounds must be >= 1, got {rounds!r}")
    resolution = time.get_clock_info("process_time").resolution
    floor = max(float(min_time), 1000.0 * resolution)
    loops: dict[str, int] = {}
    for name, fn in fns.items():
        t0 = time.process_time()
        fn()
        once = time.process_time() - t0
        loops[name] = max(1, math.ceil(floor / max(once, resolution, 1e-9)))
    samples: dict[str, list[float]] = {name: [] for name in fns}
    enabled = gc.isenabled()
    gc.collect()
    gc.disable()
    try:
        for _ in range(int(rounds)):
            for name, fn in fns.items():
                k = loops[name]
                t0 = time.process_time()
                for _ in range(k):
                    fn()
                samples[name].append((time.process_time() - t0) / k)
    finally:
        if enabled:
            gc.enable()
    return {
        name: {
            "median": float(np.median(s)),
            "min": float(np.min(s)),
            "max": float(np.max(s)),
            "rounds": int(rounds),
            "loops": loops[name],
        }
        for name, s in samples.items()
    }


def fit_slope(x: Sequence[float], y: Sequence[float], *, floor: float = 0.0) -> float | None:
    r"""Least-squares slope of :math:`\log y` against :math:`\log x`.

    Points with :math:`y \le` ``floor`` (for errors: at the level of the reference) or non-finite
    values are left out; with fewer than two points left the slope is None.

    Parameters
    ----------
    x, y : sequence of float
        Positive abscissae (step sizes, step numbers) and values (errors).
    floor : float, optional
        Values at or below it are not used.

    Returns
    -------
    float or None
        The slope; for errors against h, the observed order.

    Examples
    --------
    >>> from benchmarks.harness import fit_slope
    >>> h = [0.1, 0.05, 0.025]
    >>> round(fit_slope(h, [3 * x**4 for x in h]), 6)
    4.0
    >>> fit_slope([0.1, 0.05], [1e-15, 1e-16], floor=1e-13) is None
    True
    """
    xa = np.asarray(x, dtype=float)
    ya = np.asarray(y, dtype=float)
    keep = np.isfinite(xa) & np.isfinite(ya) & (xa > 0) & (ya > floor) & (ya > 0)
    if keep.sum() < 2 or np.ptp(np.log(xa[keep])) == 0:
        return None
    return float(np.polyfit(np.log(xa[keep]), np.log(ya[keep]), 1)[0])


def cheapest_measured(points: Sequence[Mapping[str, Any]], target: float) -> dict | None:
    """The measured point of least median CPU time whose error is at most ``target``.

    No interpolation and no extrapolation: a method none of whose runs reaches ``target`` has
    no cost at it (None).

    Parameters
    ----------
    points : sequence of dict
        Runs with ``error`` and ``cpu["median"]``.
    target : float
        The largest error accepted.

    Returns
    -------
    dict or None
        The point (as given), or None.

    Examples
    --------
    >>> from benchmarks.harness.timing import cheapest_measured
    >>> pts = [{"h": h, "error": e, "cpu": {"median": c}}
    ...        for h, e, c in ((0.2, 1e-6, 1.0), (0.1, 1e-9, 2.0), (0.05, 1e-12, 4.0))]
    >>> cheapest_measured(pts, 1e-8)["h"], cheapest_measured(pts, 1e-13)
    (0.1, None)
    """
    ok = [
        q
        for q in points
        if q.get("error") is not None
        and math.isfinite(q["error"])
        and q["error"] <= target
        and q.get("cpu", {}).get("median") is not None
    ]
    return dict(min(ok, key=lambda q: q["cpu"]["median"])) if ok else None
