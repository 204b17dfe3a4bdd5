"""Recompute the errors of a recorded run against the current reference, keeping its timings.

The errors of the work-precision section are deterministic (each configuration's end state); its
timings are not and take the full run's twenty minutes.  When the reference changes, this module
reruns every configuration once (no timing), measures its error against the new reference,
refits the orders, re-evaluates the goals and records what it did in ``notes``.

Usage: ``python -m benchmarks.harness.rescore benchmarks/results/bench.json`` (rewrites the file).
"""

from __future__ import annotations

import datetime
import sys
from pathlib import Path
from typing import Any

from .config import _STEP_ORDERS
from .goals import _goals
from .precision import (
    REFERENCE,
    _accuracy,
    _configurations,
    _errors,
    _exact_thunk,
    _method_entry,
    _reference,
)
from .problems import _modules, _problem, _solve_ivp_end
from .result import BenchResult, load

_STALE = ("exact_vs_dop853", "exact_vs_mv_pre10", "mv_pre10_h")


def _same_config(point: dict[str, Any], meta: dict[str, Any]) -> bool:
    if point["method"] != meta["method"]:
        return False
    for key in ("rtol", "h"):
        if key in point and abs(point[key] - meta[key]) > 1e-12 * abs(point[key]):
            return False
    return True


def _rescore_setting(w: dict[str, Any], p: dict[str, Any], mods: dict[str, Any]) -> None:
    """One work-precision setting, in place."""
    n, T = int(w["n"]), float(w["T"])
    lam, Q0, M0 = _problem(n, int(p["seed"]))
    ref, estimate = _reference(lam, Q0, M0, T)
    for key in _STALE:
        w.pop(key, None)
    w["reference"] = REFERENCE
    w["reference_error_estimate"] = estimate
    dop = _solve_ivp_end(lam, Q0, M0, T, "DOP853", 1e-13)()
    w["reference_vs_dop853"] = _errors(dop, ref)["error"]
    methods = [m for m, e in w["methods"].items() if e.get("available")]
    pp = dict(p, wp_h={int(k): v for k, v in p["wp_h"].items()})
    # an old run has no lean baselines: its SciPy methods ran on the generated field
    out: dict[str, Any] = {"n": n, "T": T, "methods": {},
                           "baselines": w.get("baselines") or {"variant": None}}  # fmt: skip
    exact_go = _exact_thunk(lam, Q0, M0, T, mods)
    configs, meta = _configurations(lam, Q0, M0, T, pp, methods, mods, exact_go, out)
    notes: list[str] = []
    _accuracy(configs, meta, ref, out, notes)
    if notes:
        raise RuntimeError(f"rescore n = {n}, T = {T:g}: {notes}")
    for m in methods:
        rows = w["methods"][m]["points"]
        for point in rows:
            (new,) = [meta[k] for k in configs if _same_config(point, meta[k])]
            point.update({k: new[k] for k in ("error", "error_Q", "error_M")})
        profile = w["methods"][m].get("profile")  # of the timed run: kept
        w["methods"][m] = _method_entry(m, rows, w)
        if profile:
            w["methods"][m]["profile"] = profile
        if m in _STEP_ORDERS and "nominal_order" not in w["methods"][m]:  # pragma: no cover
            raise RuntimeError(m)


def rescore(res: BenchResult) -> BenchResult:
    """``res`` with the work-precision errors measured against :data:`REFERENCE`, the orders
    refitted and the goals re-evaluated (timings unchanged)."""
    mods = _modules()
    wp = res.measurements.get("work-precision", {})
    for w in [*wp.get("n3", []), *([wp["n10"]] if wp.get("n10") else [])]:
        _rescore_setting(w, res.parameters, mods)
    res.goals = _goals(res, bool(res.parameters.get("quick")), res.parameters["sections"])
    day = datetime.date.today().isoformat()
    res.notes.append(
        f"{day}: work-precision errors recomputed against {REFERENCE} "
        "(python -m benchmarks.harness.rescore); the timings are those of the original run"
    )
    return res


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    path = Path(sys.argv[1])
    rescore(load(path)).write_json(path)
    print(f"rescored {path}")
