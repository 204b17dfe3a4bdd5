"""One run of the benchmark: the machine, the sections chosen, the measurements and the goals."""

from __future__ import annotations

import os
import platform
import sys
import time
import warnings
from collections.abc import Callable, Iterable, Mapping
from typing import Any

import numpy as np
import scipy

from symrb.errors import InputError

from .config import _FULL, _QUICK, _STEP_ORDERS, ALL_METHODS, SECTIONS
from .costs import _cold_start, _long_horizon, _step_costs
from .goals import _goals
from .precision import LONG_FLOWS, _long_time, _work_precision
from .problems import _modules
from .result import BenchResult, _jsonable, previous_goals
from .speed import _cost_vs_n, _evidence, _throughput


def _machine() -> dict[str, Any]:
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
        "load_average_start": list(os.getloadavg()),
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


def _sections(only: Iterable[str] | None) -> list[str]:
    if only is None:
        return list(SECTIONS)
    chosen = []
    for s in only:
        key = str(s).strip().lower().replace("_", "-")
        if key.isdigit() and 1 <= int(key) <= len(SECTIONS):
            key = SECTIONS[int(key) - 1]
        if key not in SECTIONS:
            raise InputError(f"sections must be among {SECTIONS} (or 1-{len(SECTIONS)}), got {s!r}")
        chosen.append(key)
    return [s for s in SECTIONS if s in chosen]


def _arguments(
    quick: bool,
    methods: Iterable[str] | None,
    progress: bool,
    sections: Iterable[str] | None,
    config: Mapping[str, Any] | None,
) -> tuple[dict[str, Any], list[str], list[str]]:
    """(the parameters, the sections, the methods) of :func:`run`, checked."""
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
    return p, chosen, meths


def _measure(
    res: BenchResult,
    chosen: list[str],
    p: dict[str, Any],
    meths: list[str],
    mods: dict[str, Any],
    progress: bool,
    log: Callable[[str], None],
    verify_json: str | os.PathLike[str] | None,
) -> dict[str, float]:
    """Run the sections ``chosen``, in order, into ``res.measurements``; returns the wall time
    of each section."""
    notes = res.notes
    ms = res.measurements

    def work_precision() -> None:
        wp = ms.setdefault("work-precision", {})
        wp["n3"] = [_work_precision(3, float(T), p, meths, mods, notes, log) for T in p["wp_T"]]
        if p["wp_n10_T"]:
            sub = [m for m in meths if m in ("DOP853", "DOP853-gen", *_STEP_ORDERS)]
            wp["n10"] = _work_precision(10, float(p["wp_n10_T"]), p, sub, mods, notes, log)

    def long_time() -> None:
        lts = ms.setdefault("long-time", [])
        for n in p["long_n"]:
            lts.append(_long_time(n, p, mods, progress, log))
        for which in LONG_FLOWS[1:]:  # the paper's maps, n = 3
            lts.append(_long_time(3, p, mods, progress, log, which))

    def evidence() -> None:
        if verify_json is None:
            notes.append(
                "evidence section skipped: pass --verify-json PATH "
                "(written by symrb verify --json --output PATH)"
            )
        else:
            ms["evidence"] = _evidence(verify_json)

    steps: dict[str, Callable[[], None]] = {
        "work-precision": work_precision,
        "long-time": long_time,
        "throughput": lambda: ms.__setitem__("throughput", _throughput(p, mods, log)),
        "cost-vs-n": lambda: ms.__setitem__("cost-vs-n", _cost_vs_n(p, mods, log)),
        "evidence": evidence,
        "step-costs": lambda: ms.__setitem__("step-costs", _step_costs(p, mods, log)),
        "long-horizon": lambda: ms.__setitem__("long-horizon", _long_horizon(p, mods, log)),
        "cold-start": lambda: ms.__setitem__("cold-start", _cold_start(p, log)),
    }
    seconds: dict[str, float] = {}
    for sec in chosen:
        t0 = time.perf_counter()
        steps[sec]()
        seconds[sec] = time.perf_counter() - t0
    return seconds


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
    """Run the benchmarks and evaluate the goals of issues 9 and 23.

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
        Some of :data:`SECTIONS` (or their numbers 1-8); default all.
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
    >>> from benchmarks.harness import run
    >>> res = run(quick=True, methods=["DOP853", "MV"], sections=["work-precision"],
    ...           progress=False, config={"rounds": 1, "min_time": 0.001,
    ...                                   "wp_rtols": (1e-4, 1e-6), "wp_h": {2: (0.2, 0.1)}})
    >>> mv = res.measurements["work-precision"]["n3"][0]["methods"]["MV"]
    >>> round(mv["order"])  # second order
    2
    """
    p, chosen, meths = _arguments(quick, methods, progress, sections, config)

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
    if checkpoint is not None:  # the goals of the run the file holds, before it is overwritten
        res.previous_goals = previous_goals(checkpoint)
    mods = _modules(notes)
    limiter: Any = None
    section_seconds: dict[str, float] = {}
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
            section_seconds = _measure(res, chosen, p, meths, mods, progress, log, verify_json)
        notes.extend(f"warning: {w.message}" for w in caught)
    finally:
        if limiter is not None:
            limiter.restore_original_limits()
    res.machine["load_average_end"] = list(os.getloadavg())
    res.machine["section_seconds"] = section_seconds
    res.goals = _goals(res, bool(quick), chosen)
    res.seconds = time.perf_counter() - start
    log(f"done in {res.seconds:.1f} s")
    return res
