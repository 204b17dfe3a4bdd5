r"""Benchmarks of symrb's rigid body integrators, with the speed and accuracy goals of issue 9.

:func:`run` measures, in one process and one run (``symrb bench`` on the command line):

1. **work-precision** (n = 3, T = 10 and 100): the largest entry of the error in :math:`M(T)` and
   :math:`Q(T)` against a reference, versus process CPU time, for SciPy's ``solve_ivp`` (RK45,
   DOP853, LSODA, called directly on a plain NumPy field built from the generated kernel
   :func:`symrb._generated.rigid_body.rigid_body_rhs`), :func:`symrb.integrate` (DOP853, to measure
   its overhead on the same field), :func:`symrb.discrete_rigid_body_flow` at several steps h, and
   the optional methods found by import (the fast Moser-Veselov engine ``symrb.engine.mv_flow``,
   the compositions and RKMK4/implicit midpoint of ``symrb.compose``, the exact solution
   ``symrb.exact.rigid_body_exact``).  The reference is DOP853 at ``rtol = atol = 1e-13`` and,
   when ``symrb.exact`` imports and agrees with it, the exact solution.  Each fixed-step method's
   order is the slope of :math:`\log(\text{error})` against :math:`\log h`.
2. **long-time invariants**: relative energy and Casimir (:math:`\operatorname{tr}M^2`) errors and
   :math:`\|Q^TQ - I\|` of the Moser-Veselov flow against the step number N (running maxima),
   with the line :math:`\varepsilon\sqrt N` of a random walk of rounding errors and the fitted
   slope of :math:`\log(\text{error})` against :math:`\log N`.
3. **throughput**: body-steps per second of a Moser-Veselov step on batches of 1 to :math:`10^4`
   bodies (n = 3) next to a batched 3x3 matrix product, and a cold start against a warm step.
4. **cost against n**: one step of a single body for n = 3, 5, 10, 20, 50 in units of one
   n x n matrix product.
5. **evidence**: the time of each evidence level of ``symrb verify --json`` (read from a file)
   next to what that level certifies.

Timing discipline: every configuration is timed once per round and the rounds are interleaved
(drifts of a shared machine hit all configurations alike); a timing repeats its call until it
lasts ``min_time`` (far above the resolution of :func:`time.process_time`); medians are reported
with the min and max over the rounds; the garbage collector is paused while timing; BLAS is pinned
to one thread with ``threadpoolctl`` (without it a warning is recorded).  All times are process
CPU time (:func:`time.process_time`).

The goals are returned as ``{name, measured, target, met, note}``; a goal whose method is not
available, or that needs a long run skipped by ``quick=True``, has ``met = None`` and a note.
"""

from __future__ import annotations

import argparse
import gc
import importlib
import json
import math
import os
import platform
import sys
import textwrap
import time
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ._validate import Array
from .errors import InputError

__all__ = ["SECTIONS", "BenchResult", "run", "load", "time_interleaved", "fit_slope", "main"]

#: The sections of :func:`run`, in order.
SECTIONS = ("work-precision", "long-time", "throughput", "cost-vs-n", "evidence")

EPS = float(np.finfo(float).eps)

#: Symrb step methods (the candidates for "best symrb step method") and their nominal orders.
_STEP_ORDERS = {
    "MV": 2,
    "MV-fast": 2,
    "MV-comp4": 4,
    "MV-comp6": 6,
    "MV-comp8": 8,
    "MV-pre4": 4,
    "MV-pre6": 6,
    "MV-pre8": 8,
    "MV-pre10": 10,
    "RKMK4": 4,
    "midpoint": 2,
}
_SCIPY = ("RK45", "DOP853", "LSODA")
ALL_METHODS = (*_SCIPY, "integrate", *_STEP_ORDERS, "exact")

_FULL: dict[str, Any] = {
    "rounds": 5,
    "min_time": 0.02,
    "wp_T": (10.0, 100.0),
    "wp_rtols": tuple(10.0**-k for k in range(3, 14)),
    "wp_h": {
        2: (0.1, 0.05, 0.025, 0.0125),
        4: (0.2, 0.1, 0.05, 0.025),
        6: (0.25, 0.125, 0.0625),
        8: (0.4, 0.2, 0.1),
        10: (0.5, 0.35, 0.25, 0.18, 0.125),
    },
    "wp_n10_T": 100.0,
    "long_steps": 10**6,
    "long_n": (3, 10),
    "long_h": 0.01,
    "batches": (1, 10, 100, 1000, 10000),
    "cold_batch": 10000,
    "cold_budget": 30.0,
    "cost_n": (3, 5, 10, 20, 50),
    "seed": 0,
}
_QUICK: dict[str, Any] = dict(
    _FULL,
    rounds=3,
    min_time=0.005,
    wp_T=(10.0,),
    wp_rtols=(1e-3, 1e-5, 1e-7, 1e-9, 1e-11, 1e-12),
    wp_h={
        2: (0.1, 0.05, 0.025),
        4: (0.2, 0.1, 0.05),
        6: (0.25, 0.125),
        8: (0.4, 0.2),
        10: (0.5, 0.35, 0.25),
    },
    wp_n10_T=None,
    long_steps=10**4,
    long_n=(3,),
    cold_budget=2.0,
)

_NOT_QUICK = "not measured in --quick (needs a long run)"


# ---------------------------------------------------------------------------------------------
# timing and fitting


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
    >>> from symrb.bench import time_interleaved
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
    >>> from symrb.bench import fit_slope
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


def _cost_at(errors: Sequence[float], costs: Sequence[float], target: float, order: float | None):
    """CPU time to reach ``target`` error: log-log interpolation between measured points, or for a
    fixed-step method of known order an extrapolation from the nearest point (cost ~ 1/h ~
    error^(-1/order)).  Returns (cost or None, how)."""
    pts = sorted(
        (e, c) for e, c in zip(errors, costs, strict=True) if np.isfinite(e) and e > 0 and c > 0
    )
    if not pts:
        return None, "no finite error"
    es = np.log([p[0] for p in pts])
    cs = np.log([p[1] for p in pts])
    lt = math.log(target)
    if es[0] <= lt <= es[-1]:
        # the cheapest measured point at or below the target bounds the cost from the right side
        below = [i for i in range(len(es)) if es[i] <= lt]
        above = [i for i in range(len(es)) if es[i] >= lt]
        i = max(below, key=lambda j: es[j])
        j = min(above, key=lambda j: es[j])
        if es[i] == es[j]:
            return float(math.exp(cs[i])), "measured"
        w = (lt - es[i]) / (es[j] - es[i])
        return float(math.exp(cs[i] + w * (cs[j] - cs[i]))), "interpolated"
    if order and order > 0:
        k = 0 if lt < es[0] else len(es) - 1
        return float(math.exp(cs[k] + (es[k] - lt) / order)), "extrapolated with the fitted order"
    return None, "target error outside the measured range"


# ---------------------------------------------------------------------------------------------
# the problems and the methods


def _problem(n: int, seed: int) -> tuple[Array, Array, Array]:
    """(lam, Q0, M0) of the benchmarks: for n = 3 the body of the README, else random."""
    from .algebra import hat, random_lam, random_SO, random_so

    rng = np.random.default_rng(seed)
    Q0 = random_SO(n, seed=rng)
    if n == 3:
        return np.array([0.7, 1.1, 1.6]), Q0, hat([0.5, 1.0, 1.5])
    lam = random_lam(n, seed=rng)
    M0 = random_so(n, seed=rng)
    return lam, Q0, M0 * (2.65 / np.linalg.norm(M0))  # |M0|_F as for n = 3


def _plain_field(lam: Array) -> Callable[[float, Array], Array]:
    """The rigid body field on a flat state (Q, M) for ``solve_ivp``, from the generated kernel,
    with no validation: what a user would write by hand."""
    from ._generated import rigid_body as _rb

    n = lam.shape[-1]
    nn = n * n

    def f(_t: float, y: Array) -> Array:
        dQ, dM = _rb.rigid_body_rhs(y[:nn].reshape(n, n), y[nn:].reshape(n, n), lam)
        return np.concatenate((dQ.ravel(), dM.ravel()))

    return f


def _solve_ivp_end(lam: Array, Q0: Array, M0: Array, T: float, method: str, rtol: float):
    from scipy.integrate import solve_ivp

    n = lam.shape[-1]
    y0 = np.concatenate((Q0.ravel(), M0.ravel()))
    f = _plain_field(lam)

    def go() -> tuple[Array, Array]:
        sol = solve_ivp(f, (0.0, T), y0, method=method, rtol=rtol, atol=rtol)
        if not sol.success:
            raise RuntimeError(f"solve_ivp {method} failed: {sol.message}")
        y = sol.y[:, -1]
        return y[: n * n].reshape(n, n), y[n * n :].reshape(n, n)

    return go


def _last(sol: Any, n: int) -> tuple[Array, Array]:
    """The last (Q, M) of a result object (``y.Q``, ``y.M``) or a pair."""
    if hasattr(sol, "y"):
        if getattr(sol, "success", True) is False:
            raise RuntimeError(str(getattr(sol, "message", "the run failed")))
        Q, M = sol.y["Q"], sol.y["M"]
    else:
        Q, M = sol
    return np.asarray(Q).reshape(-1, n, n)[-1], np.asarray(M).reshape(-1, n, n)[-1]


class _NotApplicable(Exception):
    """A method that does not apply to the problem (not a failure)."""


def _backend() -> str:
    """The n = 3 backend of symrb.engine.mv_flow that the benchmark times: the compiled loop when
    numba is importable (``symrb[fast]``), else the NumPy path."""
    from . import _compiled

    return "numba" if _compiled.AVAILABLE else "numpy"


def _optional(module: str) -> tuple[Any, str]:
    """(module or None, why not)."""
    try:
        return importlib.import_module(f"symrb.{module}"), ""
    except Exception as exc:  # noqa: BLE001 - any failure means "not available"
        return None, f"symrb.{module} not importable ({type(exc).__name__}: {exc})"


def _modules(notes: list[str] | None = None) -> dict[str, Any]:
    """symrb's engine, compose and exact modules (None, with a note, for one that fails to
    import: the benchmark then reports its methods as unavailable)."""
    mods: dict[str, Any] = {}
    for mod in ("engine", "compose", "exact"):
        mods[mod], why = _optional(mod)
        if why and notes is not None:
            notes.append(why)
    return mods


def _find(mod: Any, names: Iterable[str]) -> Callable[..., Any] | None:
    for name in names:
        fn = getattr(mod, name, None) if mod is not None else None
        if callable(fn):
            return fn
    return None


def _fixed_step_runner(kind: str, mods: dict[str, Any]) -> Callable[..., Any] | None:
    """A function (lam, Q0, M0, T, h) -> thunk returning (Q(T), M(T)), or None if unavailable."""
    from . import discrete

    engine, compose = mods.get("engine"), mods.get("compose")
    if kind == "MV":
        fn: Callable[..., Any] | None = discrete.discrete_rigid_body_flow
    elif kind == "MV-fast" or kind.startswith("MV-pre"):
        mv = _find(engine, ["mv_flow"])
        if mv is None:
            return None
        order = int(kind[len("MV-pre") :]) if kind.startswith("MV-pre") else 2
        backend = _backend()

        def fn(Q0: Array, M0: Array, lam: Array, h: float, steps: int, **kw: Any) -> Any:
            n = np.shape(lam)[-1]
            if order != 2 and n != 3:
                raise _NotApplicable(f"{kind} is for n = 3")
            method = backend if n == 3 else "auto"
            return mv(Q0, M0, lam, h, steps, order=order, method=method, **kw)
    elif kind.startswith("MV-comp"):
        base = _find(compose, ["composed_rigid_body_flow"])
        if base is None:
            return None
        order = int(kind[len("MV-comp") :])

        def fn(Q0: Array, M0: Array, lam: Array, h: float, steps: int, **kw: Any) -> Any:
            return base(Q0, M0, lam, h, steps, order=order, **kw)

    elif kind == "RKMK4":
        fn = _find(compose, ["rkmk4_rigid_body_flow"])
    elif kind == "midpoint":
        fn = _find(compose, ["midpoint_rigid_body_flow"])
    else:  # pragma: no cover - internal
        raise ValueError(kind)
    if fn is None:
        return None
    flow = fn

    def make(lam: Array, Q0: Array, M0: Array, T: float, h: float):
        steps = max(1, round(T / h))
        hh = T / steps
        n = lam.shape[-1]

        def go() -> tuple[Array, Array]:
            try:
                sol = flow(Q0, M0, lam, hh, steps, save_every=steps)
            except TypeError:
                sol = flow(Q0, M0, lam, hh, steps)
            Q, M = _last(sol, n)
            M0_out = np.asarray(sol.y["M"]).reshape(-1, n, n)[0] if hasattr(sol, "y") else None
            if M0_out is not None and not np.allclose(M0_out, M0) and np.allclose(M0_out, hh * M0):
                M = M / hh  # a flow that returns discrete momenta (h times the continuous one)
            return Q, M

        return go

    return make


# ---------------------------------------------------------------------------------------------
# section 1: work-precision


def _errors(got: tuple[Array, Array], ref: tuple[Array, Array]) -> dict[str, float]:
    eQ = float(np.abs(got[0] - ref[0]).max())
    eM = float(np.abs(got[1] - ref[1]).max())
    return {"error_Q": eQ, "error_M": eM, "error": max(eQ, eM)}


def _work_precision(
    n: int,
    T: float,
    p: dict[str, Any],
    methods: Sequence[str],
    mods: dict[str, Any],
    notes: list[str],
    log: Callable[[str], None],
) -> dict[str, Any]:
    """One work-precision diagram: every configuration's error and CPU time."""
    lam, Q0, M0 = _problem(n, p["seed"])
    ref_dop = _solve_ivp_end(lam, Q0, M0, T, "DOP853", 1e-13)()
    # the reference's own error, estimated against a tighter run (rtol near its floor 100 eps)
    tighter = _solve_ivp_end(lam, Q0, M0, T, "DOP853", 3e-14)()
    out: dict[str, Any] = {
        "n": n,
        "T": T,
        "lam": lam.tolist(),
        "reference": "scipy DOP853, rtol = atol = 1e-13",
        "reference_error_estimate": _errors(ref_dop, tighter)["error"],
        "backend": _backend(),
        "methods": {},
    }
    ref = ref_dop
    exact = _find(mods.get("exact"), ["rigid_body_exact"])
    exact_go: Callable[[], tuple[Array, Array]] | None = None
    if exact is not None and n == 3:

        def exact_go() -> tuple[Array, Array]:
            return _last(exact(Q0, M0, lam, np.array([T])), 3)

        try:
            ex = exact_go()
            agree = _errors(ex, ref_dop)["error"]
            out["exact_vs_dop853"] = agree
            mv = _find(mods.get("engine"), ["mv_flow"])
            if mv is not None:
                # an independent check at rounding level: the preprocessed method of order 10 at
                # h = 0.02 (truncation error ~ 1e-20 here; what is left is rounding)
                k = round(T / 0.02)
                pre = mv(Q0, M0, lam, T / k, k, save_every=k, order=10, method="numpy")
                out["exact_vs_mv_pre10"] = _errors(ex, _last(pre, 3))["error"]
                out["mv_pre10_h"] = T / k
            if agree < 1e-9:
                ref = ex
                out["reference"] = "symrb.exact.rigid_body_exact (agrees with DOP853 1e-13 to "
                out["reference"] += f"{agree:.1e})"
            else:
                notes.append(
                    f"symrb.exact disagrees with DOP853 at T = {T} by {agree:.1e}; "
                    "the reference is DOP853"
                )
        except Exception as exc:  # noqa: BLE001
            notes.append(f"symrb.exact failed ({type(exc).__name__}: {exc})")
            exact_go = None

    configs: dict[str, Callable[[], Any]] = {}
    meta: dict[str, dict[str, Any]] = {}
    for m in methods:
        if m in _SCIPY:
            for r in p["wp_rtols"]:
                configs[f"{m} rtol={r:.0e}"] = _solve_ivp_end(lam, Q0, M0, T, m, r)
                meta[f"{m} rtol={r:.0e}"] = {"method": m, "rtol": r}
        elif m == "integrate":
            from .continuous import RigidBody, integrate

            for r in p["wp_rtols"]:

                def go(r: float = r) -> tuple[Array, Array]:
                    sol = integrate(
                        RigidBody, (0.0, T), {"Q": Q0, "M": M0}, lam=lam, rtol=r, atol=r
                    )
                    return _last(sol, n)

                configs[f"integrate rtol={r:.0e}"] = go
                meta[f"integrate rtol={r:.0e}"] = {"method": m, "rtol": r}
        elif m in _STEP_ORDERS:
            make = _fixed_step_runner(m, mods)
            if make is None:
                out["methods"][m] = {"available": False}
                continue
            for h in p["wp_h"].get(_STEP_ORDERS[m], ()):
                key = f"{m} h={h:g}"
                configs[key] = make(lam, Q0, M0, T, h)
                meta[key] = {"method": m, "h": T / max(1, round(T / h))}
        elif m == "exact":
            if exact_go is None:
                out["methods"][m] = {"available": False}
                continue
            configs["exact"] = exact_go
            meta["exact"] = {"method": m}
    # accuracy (first call), dropping configurations that fail
    for key in list(configs):
        try:
            got = configs[key]()
        except _NotApplicable:
            del configs[key]
            out["methods"].setdefault(meta[key]["method"], {"available": False})
            continue
        except Exception as exc:  # noqa: BLE001
            notes.append(f"{key} (n = {n}, T = {T}) failed: {type(exc).__name__}: {exc}")
            del configs[key]
            out["methods"].setdefault(meta[key]["method"], {"available": False})
            out["methods"][meta[key]["method"]].setdefault("failures", []).append(str(exc))
            continue
        # the exact solution is checked against DOP853, never against itself
        meta[key].update(_errors(got, ref_dop if key == "exact" else ref))
    log(f"work-precision n = {n}, T = {T:g}: timing {len(configs)} configurations")
    timing = time_interleaved(configs, rounds=p["rounds"], min_time=p["min_time"])
    for key, t in timing.items():
        meta[key]["cpu"] = t
    for m in methods:
        rows = [meta[k] for k in configs if meta[k]["method"] == m]
        if not rows:
            out["methods"].setdefault(m, {"available": False})
            continue
        entry: dict[str, Any] = {"available": True, "points": rows}
        if m in _STEP_ORDERS:
            # fit where errors are well above the reference's own error: 100x DOP853's estimated
            # error, or 20x the exact solution's distance from the order-10 method at rounding
            if out["reference"].startswith("symrb.exact") and "exact_vs_mv_pre10" in out:
                floor = 20 * max(out["exact_vs_mv_pre10"], EPS)
            else:
                floor = 100 * max(out["reference_error_estimate"], EPS)
            entry["nominal_order"] = _STEP_ORDERS[m]
            entry["order"] = fit_slope(
                [r["h"] for r in rows], [r["error"] for r in rows], floor=floor
            )
        elif m != "exact":  # adaptive: error against work, err ~ cost^-slope
            entry["error_vs_cpu_slope"] = fit_slope(
                [r["cpu"]["median"] for r in rows], [r["error"] for r in rows], floor=1e-13
            )
        out["methods"][m] = entry
    return out


def _cost_table(wp: dict[str, Any], target: float) -> dict[str, dict[str, Any]]:
    table = {}
    for m, entry in wp["methods"].items():
        if not entry.get("available") or m == "exact":
            continue
        pts = entry["points"]
        cost, how = _cost_at(
            [r["error"] for r in pts], [r["cpu"]["median"] for r in pts], target, entry.get("order")
        )
        table[m] = {"cpu": cost, "how": how}
    return table


# ---------------------------------------------------------------------------------------------
# section 2: long-time invariants


def _mv_flow_function(mods: dict[str, Any]) -> tuple[Callable[..., Any], str, bool]:
    """(flow(Q, M, lam, h, steps, save_every), name, takes continuous momenta)."""
    fast = _find(mods.get("engine"), ["mv_flow"])
    if fast is not None:
        return fast, "symrb.engine.mv_flow", True
    from .discrete import mv_algorithm2

    def slow(Q: Array, M: Array, lam: Array, _h: float, steps: int, *, save_every: int) -> Any:
        return mv_algorithm2(Q, M, lam, steps, save_every=save_every)

    return slow, "symrb.mv_algorithm2", False


def _long_time(
    n: int, p: dict[str, Any], mods: dict[str, Any], progress: bool, log: Callable[[str], None]
) -> dict[str, Any]:
    from ._progress import progress_bar
    from .rigid_body import casimir_traces, kinetic_energy

    flow, name, continuous = _mv_flow_function(mods)
    lam, Q, M0 = _problem(n, p["seed"] + 1)
    h, total = float(p["long_h"]), int(p["long_steps"])
    M = M0.copy() if continuous else h * M0
    H0 = float(kinetic_energy(M, lam))
    C0 = float(casimir_traces(M)[0])
    marks = np.unique(np.round(np.logspace(0, math.log10(total), 8 * int(math.log10(total)) + 1)))
    marks = marks.astype(np.int64)
    Ns: list[int] = []
    energy: list[float] = []
    casimir: list[float] = []
    orth: list[float] = []
    run_max = [0.0, 0.0, 0.0]
    done = 0
    cpu = 0.0
    log(f"long-time n = {n}: {total} steps of {name}")
    bar = progress_bar(total, f"long run n={n}", progress)
    try:
        for mark in marks:
            chunk = int(mark) - done
            if chunk <= 0:
                continue
            every = max(1, chunk // 16)
            t0 = time.process_time()
            sol = flow(Q, M, lam, h, chunk, save_every=every)
            cpu += time.process_time() - t0
            if not sol.success:
                raise RuntimeError(f"the long run stopped at step {done}: {sol.message}")
            Qs = np.asarray(sol.y["Q"])[1:]
            Ms = np.asarray(sol.y["M"])[1:]
            eH = np.abs(kinetic_energy(Ms, lam) - H0) / abs(H0)
            eC = np.abs(casimir_traces(Ms)[..., 0] - C0) / abs(C0)
            eO = np.abs(np.swapaxes(Qs, -1, -2) @ Qs - np.eye(n)).max(axis=(-2, -1))
            run_max = [
                max(run_max[0], eH.max()),
                max(run_max[1], eC.max()),
                max(run_max[2], eO.max()),
            ]
            done = int(mark)
            Ns.append(done)
            energy.append(float(run_max[0]))
            casimir.append(float(run_max[1]))
            orth.append(float(run_max[2]))
            Q, M = Qs[-1], Ms[-1]
            if bar.bar is not None:
                bar.bar.update(chunk)
    finally:
        bar.close()
    Na = np.asarray(Ns, dtype=float)
    series = {"energy": energy, "casimir": casimir, "orthogonality": orth}
    fit_from = Na >= min(100.0, Na[-1] / 10)
    out: dict[str, Any] = {
        "n": n,
        "h": h,
        "steps": total,
        "flow": name,
        "cpu_seconds": cpu,
        "cpu_per_step": cpu / total,
        "N": Ns,
        "errors": series,
        "eps_sqrt_N": (EPS * np.sqrt(Na)).tolist(),
        "slope": {},
        "max_ratio_to_eps_sqrt_N": {},
    }
    for key, vals in series.items():
        va = np.asarray(vals)
        out["slope"][key] = fit_slope(Na[fit_from], va[fit_from], floor=0.0)
        out["max_ratio_to_eps_sqrt_N"][key] = float(np.max(va / (EPS * np.sqrt(Na))))
    return out


# ---------------------------------------------------------------------------------------------
# sections 3 and 4: throughput and cost against n


def _stepper(
    lam: Array, Q: Array, M0: Array, h: float, mods: dict[str, Any], warm: bool = True
) -> tuple[Callable[[], None], str]:
    """(a thunk advancing one step of a batch in place, its name).  Uses ``symrb.engine``'s
    ``MVStepper`` when available, else the warm-started solver loop of ``mv_algorithm2``.  With
    ``warm`` the slow path's first solve on a batch starts from one body's solution."""
    engine = mods.get("engine")
    cls = getattr(engine, "MVStepper", None) if engine is not None else None
    batch = Q.shape[:-2]
    if cls is not None:
        try:
            st = cls(lam, batch)
            state = [Q.copy(), M0.copy()]

            def fast() -> None:
                state[0], state[1] = st.step(state[0], state[1], h)

            return fast, "symrb.engine.MVStepper.step"
        except Exception as exc:  # noqa: BLE001
            warnings.warn(f"symrb.engine.MVStepper unusable: {exc}", stacklevel=2)
    from ._generated import discrete_rigid_body as _gen
    from .discrete import _Stepper

    st2 = _Stepper(lam, batch)
    Mk = h * M0
    if warm and batch:
        # a warm step is what is timed: start the batch's Newton from the solution of its first
        # body (the bodies are close), not from one Riccati solve per body
        first = _Stepper(lam, ())
        st2.U = np.broadcast_to(first.solve(Mk.reshape(-1, *Mk.shape[-2:])[0]), Mk.shape)
        st2.U = st2.U.reshape(-1, *Mk.shape[-2:]).copy()
    Om = np.swapaxes(st2.solve(Mk), -1, -2)
    s2 = [Q.copy(), Mk, Om]

    def slow() -> None:
        Qk, Mk, Om = s2
        Mn = _gen.mv_transport(Om, Mk)
        Om = np.swapaxes(st2.solve(Mn), -1, -2)
        s2[0], s2[1], s2[2] = Qk @ np.swapaxes(Om, -1, -2), Mn, Om

    return slow, "MV-Algorithm 2 step (symrb.discrete solver, warm started)"


def _batch_problem(n: int, batch: int, seed: int) -> tuple[Array, Array, Array]:
    lam, Q0, M0 = _problem(n, seed)
    from .algebra import random_so

    rng = np.random.default_rng(seed + 7)
    dM = random_so(n, (batch,), scale=0.05, seed=rng)
    return lam, np.broadcast_to(Q0, (batch, n, n)).copy(), M0 + dM


#: The step counts of two runs of a flow whose time difference gives the marginal cost of a step
#: (the one-off validation, set-up and cold start cancel).
_MARGINAL_K = (4, 24)


def _flow_thunk(
    mv: Callable[..., Any], Q: Array, M: Array, lam: Array, h: float, K: int, method: str
) -> Callable[[], Any]:
    return lambda: mv(Q, M, lam, h, K, save_every=K, method=method)


def _throughput_scale(backend: str, batch: int) -> int:
    """The factor on _MARGINAL_K for a batch: the runs take well above the one-off cost."""
    return max(1, math.ceil((5e4 if backend == "numba" else 5e2) / batch))


def _marginal(t: Mapping[str, Any], pattern: str, scale: int = 1) -> float:
    """(median time at the larger K - at the smaller K) / (difference in steps)."""
    k1, k2 = (k * scale for k in _MARGINAL_K)
    lo = t[pattern.format(K=k1)]["median"]
    hi = t[pattern.format(K=k2)]["median"]
    return float((hi - lo) / (k2 - k1))


def _matmul_thunk(A1: Array, A2: Array, out: Array | None) -> Callable[[], Any]:
    if out is None:
        return lambda: A1 @ A2
    return lambda: np.matmul(A1, A2, out=out)


def _throughput(p: dict[str, Any], mods: dict[str, Any], log: Callable[[str], None]):
    h = 0.01
    fns: dict[str, Callable[[], Any]] = {}
    name = ""
    for B in p["batches"]:
        lam, Q, M = _batch_problem(3, B, p["seed"])
        fns[f"step B={B}"], name = _stepper(lam, Q, M, h, mods)
        A1 = np.asarray(np.random.default_rng(B).standard_normal((B, 3, 3)))
        A2 = np.asarray(np.random.default_rng(B + 1).standard_normal((B, 3, 3)))
        C = np.empty_like(A1)
        fns[f"matmul B={B}"] = _matmul_thunk(A1, A2, C)
    mv = _find(mods.get("engine"), ["mv_flow"])
    backends = ("numpy", "numba") if _backend() == "numba" else ("numpy",)
    if mv is not None:
        for B in p["batches"]:
            lam, Q, M = _batch_problem(3, B, p["seed"])
            for be in backends:
                # enough steps that the difference of the two runs is far above the one-off
                # cost and its noise: about 2e3 body-steps a step of K for NumPy, 2e5 compiled
                scale = _throughput_scale(be, B)
                for K in _MARGINAL_K:
                    k = K * scale
                    fns[f"flow {be} K={k} B={B}"] = _flow_thunk(mv, Q, M, lam, h, k, be)
    log(f"throughput: batches {list(p['batches'])}")
    t = time_interleaved(fns, rounds=p["rounds"], min_time=p["min_time"])
    rows = []
    for B in p["batches"]:
        ts, tm = t[f"step B={B}"], t[f"matmul B={B}"]
        row: dict[str, Any] = {
            "batch": B,
            "step": ts,
            "matmul": tm,
            "step_body_steps_per_s": B / ts["median"],
            "matmul_products_per_s": B / tm["median"],
            "step_over_matmul": ts["median"] / tm["median"],
        }
        if mv is not None:
            for be in backends:
                per = _marginal(t, f"flow {be} K={{K}} B={B}", _throughput_scale(be, B))
                row[f"flow_{be}_per_step"] = per
                row[f"flow_{be}_body_steps_per_s"] = B / per
                row[f"flow_{be}_over_matmul"] = per / tm["median"]
        rows.append(row)

    # cold start (a fresh stepper and its first step) against a warm step, same batch; the batch
    # is cut down (recorded) when a cold start of ``cold_batch`` bodies would exceed the budget
    def cold_run(B: int) -> tuple[float, Callable[[], None]]:
        lam, Q, M = _batch_problem(3, B, p["seed"])
        t0 = time.process_time()
        step, _n = _stepper(lam, Q, M, h, mods, warm=False)
        step()
        return time.process_time() - t0, step

    probe, _s = cold_run(10)
    budget = float(p["cold_budget"])
    Bc = int(p["cold_batch"])
    while Bc > 10 and probe / 10 * Bc > budget:
        Bc //= 10
    colds = []
    for _ in range(max(1, min(3, p["rounds"]))):
        c, step = cold_run(Bc)
        colds.append(c)
        if sum(colds) > budget:
            break
    warm = time_interleaved({"warm": step}, rounds=p["rounds"], min_time=p["min_time"])["warm"]
    cold = {"median": float(np.median(colds)), "min": min(colds), "max": max(colds)}
    return {
        "n": 3,
        "h": h,
        "stepper": name,
        "rows": rows,
        "cold_start": {
            "batch": Bc,
            "cold": cold,
            "warm": warm,
            "ratio": cold["median"] / warm["median"],
        },
    }


def _cost_vs_n(p: dict[str, Any], mods: dict[str, Any], log: Callable[[str], None]):
    h = 0.01
    fns: dict[str, Callable[[], Any]] = {}
    name = ""
    mv = _find(mods.get("engine"), ["mv_flow"])
    scale = {n: max(1, 400 // n**2) for n in p["cost_n"]}  # more steps where a step is cheap
    for n in p["cost_n"]:
        lam, Q0, M0 = _problem(n, p["seed"])
        if mv is not None:
            name = "symrb.engine.mv_flow (NumPy path), marginal cost of a step"
            for K in _MARGINAL_K:
                k = K * scale[n]
                fns[f"flow K={k} n={n}"] = _flow_thunk(mv, Q0, M0, lam, h, k, "numpy")
                if n == 3 and _backend() == "numba":
                    fns[f"numba K={k * 100} n=3"] = _flow_thunk(
                        mv, Q0, M0, lam, h, 100 * k, "numba"
                    )
        else:
            fns[f"step n={n}"], name = _stepper(lam, Q0, M0, h, mods)
        rng = np.random.default_rng(n)
        A1, A2 = rng.standard_normal((n, n)), rng.standard_normal((n, n))
        fns[f"matmul n={n}"] = _matmul_thunk(A1, A2, None)
    log(f"cost against n: {list(p['cost_n'])}")
    t = time_interleaved(fns, rounds=p["rounds"], min_time=p["min_time"])
    rows = []
    compiled = None
    for n in p["cost_n"]:
        tm = t[f"matmul n={n}"]
        if mv is not None:
            per = _marginal(t, f"flow K={{K}} n={n}", scale[n])
            step: dict[str, Any] = {
                "median": per,
                "how": "marginal: (t(K2) - t(K1)) / (K2 - K1)",
            }
        else:
            step = t[f"step n={n}"]
        rows.append(
            {
                "n": n,
                "step": step,
                "matmul": tm,
                "matmul_equivalents": step["median"] / tm["median"],
            }
        )
        if n == 3 and mv is not None and _backend() == "numba":
            per = _marginal(t, "numba K={K} n=3", 100 * scale[3])
            compiled = {"per_step": per, "matmul": tm, "matmul_equivalents": per / tm["median"]}
    return {"h": h, "stepper": name, "rows": rows, "compiled_n3": compiled}


# ---------------------------------------------------------------------------------------------
# section 5: evidence

_CERTIFIES = {
    "symbolic, general n": "an identity for every n (SymPy, noncommutative symbols)",
    "symbolic, fixed n": "an identity for the stated n (SymPy, explicit matrices)",
    "exact rational": "an identity on sample rational data (exact arithmetic)",
    "high precision": "agreement with an independent high-precision (mpmath) computation",
    "float64": "agreement to rounding with an independent route on random float data",
}


def _evidence(path: str | os.PathLike[str]) -> dict[str, Any]:
    data = json.loads(Path(path).read_text())
    levels: dict[str, dict[str, Any]] = {}
    for claim in data.get("claims", []):
        for e in claim.get("evidence", []):
            lv = str(e.get("level"))
            row = levels.setdefault(lv, {"checks": 0, "seconds": [], "claims": set(), "passed": 0})
            row["checks"] += 1
            row["seconds"].append(float(e.get("seconds") or 0.0))
            row["claims"].add(str(claim.get("id")))
            row["passed"] += str(e.get("passed")) == "True" or e.get("passed") is True
    out = {}
    for lv, row in sorted(levels.items(), key=lambda kv: -sum(kv[1]["seconds"])):
        s = row["seconds"]
        out[lv] = {
            "checks": row["checks"],
            "passed": int(row["passed"]),
            "claims": sorted(row["claims"]),
            "total_seconds": float(sum(s)),
            "median_seconds": float(np.median(s)),
            "max_seconds": float(max(s)),
            "certifies": _CERTIFIES.get(lv, "see symrb show ID"),
        }
    return {"source": Path(path).name, "levels": out, "timer": "as recorded by symrb verify"}


# ---------------------------------------------------------------------------------------------
# machine, goals, result


def _machine() -> dict[str, Any]:
    import scipy

    info: dict[str, Any] = {
        "platform": platform.platform(),
        "machine": platform.machine(),
        "processor": platform.processor(),
        "cpu_count": os.cpu_count(),
        "python": f"{platform.python_implementation()} {platform.python_version()}",
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "timer": "time.process_time",
        "timer_resolution": time.get_clock_info("process_time").resolution,
    }
    try:
        from threadpoolctl import threadpool_info

        info["blas"] = [
            {  # the library's file name only: no path of the machine in a committed result
                "internal_api": str(d.get("internal_api")),
                "version": str(d.get("version")),
                "num_threads": str(d.get("num_threads")),
                "library": os.path.basename(str(d.get("filepath"))),
            }
            for d in threadpool_info()
        ]
    except ImportError:
        info["blas"] = "threadpoolctl not installed"
    return info


def _goal(name: str, measured: Any, target: str, met: bool | None, note: str = "") -> dict:
    if measured is not None and not isinstance(measured, str):
        measured = float(measured)
    return {"name": name, "measured": measured, "target": target, "met": met, "note": note}


@dataclass
class BenchResult:
    """The measurements of :func:`run`, with the machine, the parameters and the goals.

    Attributes
    ----------
    machine : dict
        Platform, CPU count, Python, NumPy/SciPy versions, BLAS libraries (threadpoolctl).
    parameters : dict
        The configuration run (grids, steps, rounds, methods, sections).
    measurements : dict
        One entry per section run (see :data:`SECTIONS`).
    goals : list of dict
        ``{name, measured, target, met, note}``; ``met`` is None when not measured.
    notes : list of str
        Warnings recorded during the run (missing optional methods, failures).
    seconds : float
        Wall time of the whole run.

    Examples
    --------
    >>> from symrb.bench import run
    >>> res = run(quick=True, sections=["cost-vs-n"], progress=False,
    ...           config={"cost_n": (3,), "rounds": 1, "min_time": 0.001})
    >>> sorted(res.to_dict())
    ['goals', 'machine', 'measurements', 'notes', 'parameters', 'seconds']
    >>> sorted(res.goals[0])
    ['measured', 'met', 'name', 'note', 'target']
    """

    machine: dict[str, Any]
    parameters: dict[str, Any]
    measurements: dict[str, Any] = field(default_factory=dict)
    goals: list[dict[str, Any]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    seconds: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        """The result as JSON-ready data."""
        return _jsonable(
            {
                "machine": self.machine,
                "parameters": self.parameters,
                "measurements": self.measurements,
                "goals": self.goals,
                "notes": self.notes,
                "seconds": self.seconds,
            }
        )

    def write_json(self, path: str | os.PathLike[str]) -> Path:
        """Write :meth:`to_dict` to ``path`` (directories created); returns the path."""
        out = Path(path)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(self.to_dict(), indent=1, allow_nan=False) + "\n")
        return out

    def summary(self) -> str:
        """The goals as a plain-text table (100 columns)."""
        lines = [f"{'goal':<62} {'measured':>12} {'target':>12}  met"]
        for g in self.goals:
            m = g["measured"]
            ms = "-" if m is None else (m if isinstance(m, str) else f"{m:.3g}")
            met = {True: "yes", False: "NO", None: "-"}[g["met"]]
            name = textwrap.wrap(g["name"], 62) or [""]
            lines.append(f"{name[0]:<62} {ms:>12} {g['target'][:12]:>12}  {met}")
            lines += [f"  {more}" for more in name[1:]]
            if g["note"]:
                lines += textwrap.wrap(
                    g["note"], 100, initial_indent="    ", subsequent_indent="    "
                )
        return "\n".join(lines)

    def plot(self, directory: str | os.PathLike[str]) -> list[Path]:
        """PNG and SVG diagrams of the sections run (matplotlib, Agg backend); returns the files."""
        return _plot(self, Path(directory))

    def figures(self, *names: str) -> dict[str, Any]:
        """The diagrams of the sections run as matplotlib figures, by name (``work_precision``,
        ``long_time``, ``throughput``, ``cost_vs_n``; all when no name is given), e.g. to show
        them in a notebook."""
        return _figures(self, set(names))


def _jsonable(x: Any) -> Any:
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_jsonable(v) for v in x]
    if isinstance(x, set):
        return sorted(_jsonable(v) for v in x)
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def _best_symrb(table: dict[str, dict[str, Any]]) -> tuple[str | None, float | None]:
    cands = [(v["cpu"], m) for m, v in table.items() if m in _STEP_ORDERS and v["cpu"] is not None]
    if not cands:
        return None, None
    c, m = min(cands)
    return m, c


def _speed_goal(
    res: BenchResult,
    wp: dict[str, Any] | None,
    target_err: float,
    factor: float,
    label: str,
    why: str = _NOT_QUICK,
) -> dict[str, Any]:
    name = f"{label}: best symrb step method >= {factor:g}x faster than DOP853"
    if factor == 1.0:
        name = f"{label}: best symrb step method faster than DOP853"
    if wp is None:
        return _goal(name, None, f">= {factor:g}", None, why)
    table = _cost_table(wp, target_err)
    dop = table.get("DOP853", {}).get("cpu")
    best, c = _best_symrb(table)
    if dop is None or best is None:
        return _goal(name, None, f">= {factor:g}", None, "DOP853 or every symrb method missing")
    ratio = dop / c
    how = table[best]["how"]
    met = ratio > 1.0 if factor == 1.0 else ratio >= factor
    return _goal(
        name,
        ratio,
        "> 1" if factor == 1.0 else f">= {factor:g}",
        met,
        f"DOP853 / {best} CPU time at error {target_err:g} ({how})",
    )


def _goals(res: BenchResult, quick: bool, sections: Sequence[str]) -> list[dict[str, Any]]:
    ms = res.measurements
    goals: list[dict[str, Any]] = []
    wp = {w["T"]: w for w in ms.get("work-precision", {}).get("n3", [])}
    wp10 = ms.get("work-precision", {}).get("n10")
    cost = {r["n"]: r for r in ms.get("cost-vs-n", {}).get("rows", [])}
    thr = ms.get("throughput")
    lt = {d["n"]: d for d in ms.get("long-time", [])}
    absent = "section not run"

    def missing(name: str, target: str, sec: str, long: bool = False) -> dict[str, Any]:
        why = _NOT_QUICK if quick and long else absent if sec not in sections else "not measured"
        return _goal(name, None, target, None, why)

    name = "n = 3 single MV step <= 3x one 3x3 matmul"
    if 3 in cost:
        r = cost[3]["matmul_equivalents"]
        goals.append(_goal(name, r, "<= 3", r <= 3, f"stepper: {ms['cost-vs-n']['stepper']}"))
    else:
        goals.append(missing(name, "<= 3", "cost-vs-n"))
    name = "n = 3 single MV step, compiled path (numba) <= 1 us"
    comp = ms.get("cost-vs-n", {}).get("compiled_n3")
    if comp:
        us = comp["per_step"] * 1e6
        note = "marginal cost of a step of mv_flow(method='numba') in us; "
        note += f"{comp['matmul_equivalents']:.2f} 3x3 matmuls"
        goals.append(_goal(name, us, "<= 1", us <= 1, note))
    else:
        why = "numba not installed (pip install symrb[fast])" if "cost-vs-n" in sections else absent
        goals.append(_goal(name, None, "<= 1", None, why))
    for T, err, factor, long in (
        (10.0, 1e-8, 1.0, False),
        (100.0, 1e-8, 1.0, True),
        (100.0, 1e-10, 3.0, True),
    ):
        label = f"n = 3, T = {T:g}, error {err:g}"
        if "work-precision" not in sections:
            goals.append(
                missing(f"{label}: best symrb step method vs DOP853", ">= 1", "work-precision")
            )
        elif T not in wp:
            why = _NOT_QUICK if long and quick else f"T = {T:g} not in this run"
            goals.append(_speed_goal(res, None, err, factor, label, why))
        else:
            goals.append(_speed_goal(res, wp[T], err, factor, label))
    # the exact propagator
    name = "exact propagator >= 100x faster than DOP853 at rtol 1e-12"
    name2 = "exact propagator accurate to 1e-13"
    w = wp.get(10.0) or next(iter(wp.values()), None)
    ex = w["methods"].get("exact", {}) if w else {}
    if w is not None and ex.get("available"):
        dop_points = w["methods"].get("DOP853", {}).get("points", [])
        dops = [q for q in dop_points if abs(q["rtol"] - 1e-12) < 1e-20]
        pt = ex["points"][0]
        if dops:
            ratio = dops[0]["cpu"]["median"] / pt["cpu"]["median"]
            goals.append(
                _goal(name, ratio, ">= 100", ratio >= 100, f"T = {w['T']:g}, CPU time ratio")
            )
        else:
            goals.append(_goal(name, None, ">= 100", None, "DOP853 at rtol 1e-12 not in the grid"))
        est = w["reference_error_estimate"]
        if "exact_vs_mv_pre10" in w:
            e = w["exact_vs_mv_pre10"]
            goals.append(
                _goal(
                    name2,
                    e,
                    "<= 1e-13",
                    e <= 1e-13,
                    f"T = {w['T']:g}, max entry difference from the preprocessed MV method of "
                    f"order 10 at h = {w['mv_pre10_h']:g} (an independent method at rounding "
                    f"level; DOP853 rtol 1e-13 differs by {pt['error']:.1e}, its own error about "
                    f"{est:.1e})",
                )
            )
        else:
            met = pt["error"] <= 1e-13 if est <= 1e-13 else None
            goals.append(
                _goal(
                    name2,
                    pt["error"],
                    "<= 1e-13",
                    met,
                    f"T = {w['T']:g}, max entry error against DOP853 rtol 1e-13, whose own error is "
                    f"about {est:.1e}" + ("" if met is not None else ": cannot certify 1e-13"),
                )
            )
    else:
        why = "symrb.exact not available" if w else absent
        goals.append(_goal(name, None, ">= 100", None, why))
        goals.append(_goal(name2, None, "<= 1e-13", None, why))
    label = "n = 10, T = 100, error 1e-08"
    if "work-precision" in sections and wp10 is None and quick:
        goals.append(_speed_goal(res, None, 1e-8, 2.0, label))
    elif wp10 is not None:
        goals.append(_speed_goal(res, wp10, 1e-8, 2.0, label))
    else:
        goals.append(
            missing(
                f"{label}: best symrb step method >= 2x faster than DOP853",
                ">= 2",
                "work-precision",
            )
        )
    name = "n = 50 one MV step <= 100 matmul-equivalents"
    if 50 in cost:
        r = cost[50]["matmul_equivalents"]
        goals.append(_goal(name, r, "<= 100", r <= 100, f"stepper: {ms['cost-vs-n']['stepper']}"))
    else:
        goals.append(missing(name, "<= 100", "cost-vs-n"))
    rows = {r["batch"]: r for r in thr["rows"]} if thr else {}
    name, name2 = "batch 10^4, n = 3: >= 5e6 body-steps/s", "batch 10^4 within 3x of batched matmul"
    if thr is not None and 10000 in rows:
        r = rows[10000]
        key = "flow_numpy" if "flow_numpy_per_step" in r else None
        rate = r[f"{key}_body_steps_per_s"] if key else r["step_body_steps_per_s"]
        over = r[f"{key}_over_matmul"] if key else r["step_over_matmul"]
        how = (
            "symrb.engine.mv_flow NumPy path, marginal cost of a step"
            if key
            else f"stepper: {thr['stepper']}"
        )
        if "flow_numba_body_steps_per_s" in r:
            how += f" (compiled path: {r['flow_numba_body_steps_per_s']:.3g} body-steps/s)"
        how += f"; one MVStepper.step call: {r['step_body_steps_per_s']:.3g} body-steps/s"
        goals.append(_goal(name, rate, ">= 5e6", rate >= 5e6, how))
        goals.append(
            _goal(
                name2,
                over,
                "<= 3",
                over <= 3,
                "CPU time of one step of the batch / one batched 3x3 matmul",
            )
        )
    else:
        goals.append(missing(name, ">= 5e6", "throughput"))
        goals.append(missing(name2, "<= 3", "throughput"))
    name = "cold start within 10x of a warm step"
    if thr:
        c = thr["cold_start"]
        goals.append(
            _goal(
                name,
                c["ratio"],
                "<= 10",
                c["ratio"] <= 10,
                f"batch {c['batch']}, n = 3: fresh stepper + first step / warm step",
            )
        )
    else:
        goals.append(missing(name, "<= 10", "throughput"))
    for n in (3, 10):
        name = f"10^6 steps n = {n}: invariant errors within 10 eps sqrt(N)"
        name2 = f"10^6 steps n = {n}: slope of log error vs log N <= 0.6"
        d = lt.get(n)
        if d is None or d["steps"] < 10**6:
            note = _NOT_QUICK if quick or d is not None else absent
            if d is not None:
                note += f" (a {d['steps']}-step run gave ratio "
                note += f"{max(d['max_ratio_to_eps_sqrt_N'].values()):.2g})"
            goals.append(_goal(name, None, "<= 10", None, note))
            goals.append(_goal(name2, None, "<= 0.6", None, _NOT_QUICK if quick else absent))
            continue
        r = max(d["max_ratio_to_eps_sqrt_N"].values())
        goals.append(
            _goal(
                name,
                r,
                "<= 10",
                r <= 10,
                "max over N and over energy, Casimir, "
                f"orthogonality of error / (eps sqrt(N)); {d['flow']}",
            )
        )
        slopes = [s for s in d["slope"].values() if s is not None]
        s = max(slopes) if slopes else None
        goals.append(
            _goal(
                name2,
                s,
                "<= 0.6",
                None if s is None else s <= 0.6,
                "largest of the three fitted slopes (N >= 100)",
            )
        )
    name = "every method's order within 0.2 of nominal"
    orders = {}
    for w in wp.values():
        for m, e in w["methods"].items():
            if e.get("available") and "nominal_order" in e:
                orders[f"{m} T={w['T']:g}"] = (e["order"], e["nominal_order"])
    if orders:
        bad = [k for k, (o, nom) in orders.items() if o is None or abs(o - nom) > 0.2]
        worst = max(
            (abs(o - nom) for o, nom in orders.values() if o is not None), default=float("nan")
        )
        goals.append(
            _goal(
                name,
                worst,
                "<= 0.2",
                not bad,
                "largest |fitted - nominal|" + (f"; off: {', '.join(bad)}" if bad else ""),
            )
        )
    else:
        goals.append(missing(name, "<= 0.2", "work-precision"))
    name = "symrb.integrate <= 1.2x solve_ivp (DOP853, same field)"
    ratios = []
    for w in wp.values():
        pi = {q["rtol"]: q for q in w["methods"].get("integrate", {}).get("points", [])}
        pd = {q["rtol"]: q for q in w["methods"].get("DOP853", {}).get("points", [])}
        ratios += [pi[r]["cpu"]["median"] / pd[r]["cpu"]["median"] for r in pi if r in pd]
    if ratios:
        r = float(np.median(ratios))
        goals.append(
            _goal(
                name,
                r,
                "<= 1.2",
                r <= 1.2,
                f"median over {len(ratios)} tolerances (range {min(ratios):.2f}-{max(ratios):.2f})",
            )
        )
    else:
        goals.append(missing(name, "<= 1.2", "work-precision"))
    return goals


# ---------------------------------------------------------------------------------------------
# run


def _sections(only: Iterable[str] | None) -> list[str]:
    if only is None:
        return list(SECTIONS)
    chosen = []
    for s in only:
        key = str(s).strip().lower().replace("_", "-")
        if key.isdigit() and 1 <= int(key) <= len(SECTIONS):
            key = SECTIONS[int(key) - 1]
        if key not in SECTIONS:
            raise InputError(f"sections must be among {SECTIONS} (or 1-5), got {s!r}")
        chosen.append(key)
    return [s for s in SECTIONS if s in chosen]


def run(
    quick: bool = False,
    methods: Iterable[str] | None = None,
    progress: bool = True,
    *,
    sections: Iterable[str] | None = None,
    verify_json: str | os.PathLike[str] | None = None,
    config: Mapping[str, Any] | None = None,
    checkpoint: str | os.PathLike[str] | None = None,
) -> BenchResult:
    """Run the benchmarks and evaluate the goals of issue 9.

    Parameters
    ----------
    quick : bool, optional
        A short run (about 30 s on two cores): T = 10 only, smaller grids, :math:`10^4` steps for
        the long-time section; goals that need long runs get ``met = None``.
    methods : iterable of str, optional
        The work-precision methods among ``RK45, DOP853, LSODA, integrate, MV, MV-fast,
        MV-comp4, MV-comp6, MV-comp8, RKMK4, midpoint, exact`` (default: all; the optional ones
        are skipped with a note when their module does not import).
    progress : bool, optional
        Progress lines on stderr and a progress bar for the long run (tqdm, when installed).
    sections : iterable of str, optional
        Some of :data:`SECTIONS` (or their numbers 1-5); default all.
    verify_json : path, optional
        A ``symrb verify --json`` output for the evidence section (skipped with a note if None).
    config : mapping, optional
        Overrides of the parameters (keys as in ``BenchResult.parameters``), e.g. for a tiny run.
    checkpoint : path, optional
        Write the results so far (JSON, goals not yet evaluated) to this file after each part,
        so that a long run interrupted keeps what it measured.

    Returns
    -------
    BenchResult
        Measurements, machine, parameters and goals.

    Examples
    --------
    >>> from symrb.bench import run
    >>> res = run(quick=True, methods=["DOP853", "MV"], sections=["work-precision"],
    ...           progress=False, config={"rounds": 1, "min_time": 0.001,
    ...                                   "wp_rtols": (1e-4, 1e-6), "wp_h": {2: (0.2, 0.1)}})
    >>> mv = res.measurements["work-precision"]["n3"][0]["methods"]["MV"]
    >>> round(mv["order"])  # second order
    2
    """
    p = dict(_QUICK if quick else _FULL)
    if config:
        unknown = set(config) - set(p)
        if unknown:
            raise InputError(f"config has unknown keys {sorted(unknown)}; known: {sorted(p)}")
        p.update(config)
    chosen = _sections(sections)
    meths = list(ALL_METHODS) if methods is None else [str(m) for m in methods]
    bad = [m for m in meths if m not in ALL_METHODS]
    if bad:
        raise InputError(f"methods must be among {ALL_METHODS}, got {bad}")
    if not isinstance(progress, bool | int):
        raise InputError(f"progress must be True or False, got {progress!r}")

    def log(msg: str) -> None:
        if checkpoint is not None and res.measurements:
            res.seconds = time.perf_counter() - start
            res.write_json(checkpoint)
        if progress:
            print(f"[bench {time.perf_counter() - start:6.1f} s] {msg}", file=sys.stderr)

    start = time.perf_counter()
    notes: list[str] = []
    res = BenchResult(
        machine=_machine(),
        parameters=_jsonable(
            dict(
                p,
                quick=bool(quick),
                methods=meths,
                sections=chosen,
                wp_h={str(k): v for k, v in p["wp_h"].items()},
            )
        ),
        notes=notes,
    )
    mods = _modules(notes)
    limiter: Any = None
    try:
        from threadpoolctl import threadpool_limits

        limiter = threadpool_limits(limits=1)
        res.machine["blas_threads_while_timing"] = 1
    except ImportError:
        notes.append(
            "threadpoolctl not installed: BLAS threads not pinned (pip install threadpoolctl)"
        )
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            if "work-precision" in chosen:
                wp = res.measurements.setdefault("work-precision", {})
                wp["n3"] = []
                for T in p["wp_T"]:
                    wp["n3"].append(_work_precision(3, float(T), p, meths, mods, notes, log))
                if p["wp_n10_T"]:
                    sub = [m for m in meths if m in ("DOP853", *_STEP_ORDERS)]
                    wp["n10"] = _work_precision(10, float(p["wp_n10_T"]), p, sub, mods, notes, log)
            if "long-time" in chosen:
                lts = res.measurements.setdefault("long-time", [])
                for n in p["long_n"]:
                    lts.append(_long_time(n, p, mods, progress, log))
            if "throughput" in chosen:
                res.measurements["throughput"] = _throughput(p, mods, log)
            if "cost-vs-n" in chosen:
                res.measurements["cost-vs-n"] = _cost_vs_n(p, mods, log)
            if "evidence" in chosen:
                if verify_json is None:
                    notes.append(
                        "evidence section skipped: pass --verify-json PATH "
                        "(written by symrb verify --json --output PATH)"
                    )
                else:
                    res.measurements["evidence"] = _evidence(verify_json)
        notes.extend(f"warning: {w.message}" for w in caught)
    finally:
        if limiter is not None:
            limiter.restore_original_limits()
    res.goals = _goals(res, bool(quick), chosen)
    res.seconds = time.perf_counter() - start
    log(f"done in {res.seconds:.1f} s")
    return res


# ---------------------------------------------------------------------------------------------
# plots


def _figures(res: BenchResult, names: set[str] | None = None) -> dict[str, Any]:
    import matplotlib.pyplot as plt

    figs: dict[str, Any] = {}
    unknown = (names or set()) - {"work_precision", "long_time", "throughput", "cost_vs_n"}
    if unknown:
        raise InputError(
            f"figures: names must be among work_precision, long_time, throughput, cost_vs_n; "
            f"got {sorted(unknown)}"
        )

    def wanted(stem: str) -> bool:
        return not names or stem in names

    def save(fig: Any, stem: str) -> None:
        fig.tight_layout()
        figs[stem] = fig

    ms = res.measurements
    wps = list(ms.get("work-precision", {}).get("n3", []))
    if ms.get("work-precision", {}).get("n10"):
        wps.append(ms["work-precision"]["n10"])
    if wps and wanted("work_precision"):
        # one panel under another, so that each stays legible at a page's width
        fig, axes = plt.subplots(len(wps), 1, figsize=(7.5, 5.2 * len(wps)), squeeze=False)
        for ax, w in zip(axes[:, 0], wps, strict=True):
            for i, (m, e) in enumerate(w["methods"].items()):
                if not e.get("available"):
                    continue
                # SciPy's methods dashed, symrb's solid; twelve methods, twelve colours
                style = {
                    "color": plt.get_cmap("tab20")(i % 20),
                    "marker": "osD^v<>ph*XP"[i % 12],
                    "ls": "--" if m in ("RK45", "DOP853", "LSODA", "integrate") else "-",
                }
                pts = sorted(e["points"], key=lambda q: q["error"])
                err = [max(q["error"], 1e-17) for q in pts]
                med = [q["cpu"]["median"] for q in pts]
                lo = [q["cpu"]["median"] - q["cpu"]["min"] for q in pts]
                hi = [q["cpu"]["max"] - q["cpu"]["median"] for q in pts]
                ax.errorbar(err, med, yerr=[lo, hi], ms=5, capsize=2, label=m, **style)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel("error: largest entry of M(T) and Q(T) minus the reference")
            ax.set_ylabel("CPU time per run [s] (median, min-max)")
            ax.set_title(f"work-precision, n = {w['n']}, T = {w['T']:g}")
            ax.grid(True, which="major", alpha=0.3)
            ax.legend(fontsize=8, ncol=2)
        save(fig, "work_precision")
    lts = ms.get("long-time", [])
    if lts and wanted("long_time"):
        fig, axes = plt.subplots(len(lts), 1, figsize=(7.5, 4.6 * len(lts)), squeeze=False)
        for ax, d in zip(axes[:, 0], lts, strict=True):
            N = np.asarray(d["N"], dtype=float)
            for key, vals in d["errors"].items():
                s = d["slope"][key]
                lab = f"{key} (slope {s:.2f})" if s is not None else key
                ax.loglog(N, np.maximum(vals, 1e-18), marker=".", label=lab)
            ax.loglog(N, EPS * np.sqrt(N), "k--", label="eps sqrt(N)")
            ax.loglog(N, 10 * EPS * np.sqrt(N), "k:", label="10 eps sqrt(N)")
            ax.set_xlabel("step number N")
            ax.set_ylabel("largest relative error up to step N")
            ax.set_title(f"long-time invariants, n = {d['n']}, h = {d['h']:g} ({d['flow']})")
            ax.legend(fontsize=8)
        save(fig, "long_time")
    thr = ms.get("throughput")
    if thr and wanted("throughput"):
        fig, ax = plt.subplots(figsize=(6.5, 5))
        B = [r["batch"] for r in thr["rows"]]
        ax.loglog(
            B,
            [r["step_body_steps_per_s"] for r in thr["rows"]],
            "o-",
            label="MVStepper.step (one call)",
        )
        for be, mk in (("numpy", "^-"), ("numba", "v-")):
            key = f"flow_{be}_body_steps_per_s"
            if all(key in r for r in thr["rows"]):
                lab = f"mv_flow, {'NumPy path' if be == 'numpy' else 'compiled (numba)'}"
                ax.loglog(B, [r[key] for r in thr["rows"]], mk, label=lab)
        ax.loglog(
            B, [r["matmul_products_per_s"] for r in thr["rows"]], "s-", label="batched 3x3 matmul"
        )
        ax.axhline(5e6, color="gray", ls=":", label="goal 5e6")
        ax.set_xlabel("batch size (bodies)")
        ax.set_ylabel("body-steps (or products) per CPU second")
        ax.set_title("throughput, n = 3")
        ax.legend(fontsize=8)
        save(fig, "throughput")
    cost = ms.get("cost-vs-n")
    if cost and wanted("cost_vs_n"):
        fig, ax = plt.subplots(figsize=(6.5, 5))
        ns = [r["n"] for r in cost["rows"]]
        ax.loglog(
            ns, [r["matmul_equivalents"] for r in cost["rows"]], "o-", label="one MV step (NumPy)"
        )
        comp = cost.get("compiled_n3")
        if comp:
            ax.loglog([3], [comp["matmul_equivalents"]], "v", ms=9, label="n = 3, compiled (numba)")
        ax.set_xlabel("n")
        ax.set_ylabel("CPU time in units of one n x n matmul")
        ax.set_title("per-step cost against n (single body)")
        ax.legend(fontsize=8)
        save(fig, "cost_vs_n")
    return figs


def _plot(res: BenchResult, directory: Path) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    directory.mkdir(parents=True, exist_ok=True)
    files: list[Path] = []
    for stem, fig in _figures(res).items():
        for ext in ("png", "svg"):
            path = directory / f"{stem}.{ext}"
            fig.savefig(path, dpi=120)
            files.append(path)
        plt.close(fig)
    return files


def load(path: str | os.PathLike[str]) -> BenchResult:
    """Read a :class:`BenchResult` written by :meth:`BenchResult.write_json` (``--json``).

    Parameters
    ----------
    path : str or path-like
        The JSON file.

    Returns
    -------
    BenchResult

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from symrb.bench import load, run
    >>> res = run(quick=True, sections=["cost-vs-n"], progress=False,
    ...           config={"cost_n": (3,), "rounds": 1, "min_time": 0.001})
    >>> with tempfile.TemporaryDirectory() as d:
    ...     f = pathlib.Path(d) / "bench.json"
    ...     _ = res.write_json(f)
    ...     again = load(f)
    >>> again.goals == res.to_dict()["goals"]
    True
    """
    data = json.loads(Path(path).read_text())
    missing = {"machine", "parameters", "measurements", "goals"} - set(data)
    if missing:
        raise InputError(f"path {str(path)!r} is not a symrb bench result: no {sorted(missing)}")
    return BenchResult(
        machine=data["machine"],
        parameters=data["parameters"],
        measurements=data["measurements"],
        goals=data["goals"],
        notes=data.get("notes", []),
        seconds=float(data.get("seconds", 0.0)),
    )


# ---------------------------------------------------------------------------------------------
# command line

_EXIT = """\
exit status:
  0 the benchmarks ran (goals not met are reported, not failures, unless --strict)
  1 with --strict: a measured goal was not met
  2 usage or environment (bad arguments, an unreadable --verify-json, matplotlib missing for
    --plots)
"""


def build_parser(prog: str = "symrb bench") -> argparse.ArgumentParser:
    """The parser of ``symrb bench``."""
    parser = argparse.ArgumentParser(
        prog=prog,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description=(
            "Time symrb's rigid body integrators against SciPy (work-precision, long-time\n"
            "invariants, throughput, cost against n, evidence) and report the goals of issue 9.\n"
            "Needs only NumPy and SciPy (threadpoolctl pins BLAS to one thread; tqdm shows\n"
            "progress; matplotlib draws --plots)."
        ),
        epilog=_EXIT,
    )
    parser.add_argument("--quick", action="store_true", help="a short run (about 30 s)")
    parser.add_argument("--json", metavar="PATH", help="write the results as JSON to PATH")
    parser.add_argument("--plots", metavar="DIR", help="write PNG and SVG diagrams into DIR")
    parser.add_argument(
        "--only", nargs="+", metavar="SECTION", help=f"only these sections: {', '.join(SECTIONS)}"
    )
    parser.add_argument("--methods", nargs="+", metavar="NAME", help="only these methods")
    parser.add_argument("--verify-json", metavar="PATH", help="symrb verify --json output")
    parser.add_argument("--no-progress", action="store_true", help="no progress output")
    parser.add_argument("--strict", action="store_true", help="exit 1 when a goal is not met")
    return parser


def main(argv: Sequence[str] | None = None, prog: str = "symrb bench") -> int:
    """Run ``symrb bench`` with ``argv``; returns the exit status (0, 1 or 2, see ``--help``).

    Parameters
    ----------
    argv : sequence of str, optional
        The arguments after ``bench`` (default ``sys.argv[1:]``).
    prog : str, optional
        The program name shown in the usage.

    Returns
    -------
    int
        0 the benchmarks ran, 1 with ``--strict`` a measured goal was not met, 2 bad usage or
        environment.

    Examples
    --------
    >>> from symrb.bench import main
    >>> main(["--only", "no-such-section"])  # the reason goes to stderr
    2
    """
    parser = build_parser(prog)
    try:
        args = parser.parse_args(list(sys.argv[1:] if argv is None else argv))
    except SystemExit as exc:
        return int(exc.code or 0) if not isinstance(exc.code, str) else 2
    if args.plots:
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            print(f"{prog} --plots needs matplotlib: pip install matplotlib", file=sys.stderr)
            return 2
    if args.verify_json and not Path(args.verify_json).is_file():
        print(f"{prog}: --verify-json {args.verify_json}: no such file", file=sys.stderr)
        return 2
    try:
        res = run(
            quick=args.quick,
            methods=args.methods,
            progress=not args.no_progress,
            sections=args.only,
            verify_json=args.verify_json,
            checkpoint=args.json,
        )
    except InputError as exc:
        print(f"{prog}: {exc}", file=sys.stderr)
        return 2
    except (OSError, json.JSONDecodeError) as exc:
        print(f"{prog}: {exc}", file=sys.stderr)
        return 2
    print(res.summary())
    for note in res.notes:
        print(f"note: {note}")
    if args.json:
        print(f"wrote {res.write_json(args.json)}")
    if args.plots:
        for f in res.plot(args.plots):
            print(f"wrote {f}")
    unmet = [g for g in res.goals if g["met"] is False]
    return 1 if args.strict and unmet else 0
