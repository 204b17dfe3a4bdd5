"""The goals of issue 23 read from the step-costs, long-horizon and cold-start sections.

Every figure is a measured one (no fit, no extrapolation); a goal not met carries in its note the
profile recorded with the measurement (the top entries by cumulative time of one call)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from .config import _NOT_QUICK


def _goal(name: str, measured: Any, target: str, met: bool | None, note: str = "") -> dict:
    if measured is not None and not isinstance(measured, str):
        measured = float(measured)
    return {"name": name, "measured": measured, "target": target, "met": met, "note": note}


def _with_profile(goal: dict[str, Any], profile: str | None) -> dict[str, Any]:
    """``goal`` with ``profile`` appended to its note when it is not met."""
    if goal["met"] is False and profile:
        goal["note"] += f". Profile of one call (cumulative): {profile}"
    return goal


def _why(sec: str, sections: Sequence[str]) -> str:
    return "section not run" if sec not in sections else "not measured"


def _one_call_goal(sc: dict[str, Any] | None, sections: Sequence[str]) -> list[dict[str, Any]]:
    name = "one-step mv_flow call (n = 3, whole call) <= 30 us"
    one = (sc or {}).get("one_call")
    if not one:
        return [_goal(name, None, "<= 30", None, _why("step-costs", sections))]
    us = one["cpu"]["median"] * 1e6
    g = _goal(name, us, "<= 30", us <= 30, f"{one['what']}: median CPU time in us")
    return [_with_profile(g, one.get("profile"))]


def _paper_goals(sc: dict[str, Any] | None, sections: Sequence[str]) -> list[dict[str, Any]]:
    """mv_algorithm2 and symmetric_flow: a step at most 3x an mv_flow step (n = 3)."""
    goals = []
    paper = (sc or {}).get("paper", {})
    base = paper.get("mv_flow", {}).get("per_step")
    same = (sc or {}).get("paper_same_length")
    for key in ("mv_algorithm2", "symmetric_flow"):
        name = f"n = 3: a {key} step <= 3x an mv_flow step"
        d = paper.get(key)
        if d is None or not base:
            why = (
                "symrb.engine.mv_flow missing" if sc and not base else _why("step-costs", sections)
            )
            goals.append(_goal(name, None, "<= 3", None, why))
            continue
        if not (d.get("reliable", True) and paper["mv_flow"].get("reliable", True)):
            goals.append(_goal(name, None, "<= 3", None, "a marginal cost below the timing noise"))
            continue
        x = d["per_step"] / base
        how = paper["mv_flow"].get("method", "default")
        mk = paper["mv_flow"]["K"]
        note = (f"marginal CPU cost of a step: {d['per_step'] * 1e6:.3g} us (runs of {d['K'][0]} "
                f"and {d['K'][1]} steps) against {base * 1e6:.3g} us for mv_flow(method={how!r}), "
                f"its method for long runs (runs of {mk[0]} and {mk[1]} steps)")  # fmt: skip
        if same and key in same and same.get("mv_flow"):
            note += (f"; whole runs of {same['K']} steps: {same[key] / same['mv_flow']:.3g} "
                     "times mv_flow's")  # fmt: skip
        goals.append(_with_profile(_goal(name, x, "<= 3", x <= 3, note), d.get("profile")))
    return goals


_STAGED = ("MV-comp4", "MV-comp6", "MV-comp8", "RKMK4", "midpoint")


def _stage_goals(sc: dict[str, Any] | None, sections: Sequence[str]) -> list[dict[str, Any]]:
    """Compositions, RKMK4, midpoint: cost per stage at most 2x an mv_flow step, n = 3 and 10;
    one goal per n, measured by the worst of the methods (each named in the note)."""
    goals = []
    stages = (sc or {}).get("stages", {})
    for n in ("3", "10"):
        name = f"n = {n}: a stage of every composition, RKMK4, midpoint <= 2x an mv_flow step"
        got = stages.get(n, {}).get("methods", {})
        ok = {k: d for k, d in got.items() if d.get("reliable", True) and d["over_mv_flow_step"]}
        if not ok:
            why = _why("step-costs", sections) if not stages else "not available"
            goals.append(_goal(name, None, "<= 2", None, why))
            continue
        worst = max(ok, key=lambda k: ok[k]["over_mv_flow_step"])
        x = ok[worst]["over_mv_flow_step"]
        parts = [f"{k} {d['over_mv_flow_step']:.3g} ({d['per_stage'] * 1e6:.3g} us a stage, "
                 f"{d['stages']} a step)" for k, d in ok.items()]  # fmt: skip
        left = [k for k in _STAGED if k not in ok]
        note = (f"the worst, {worst}; per method, a stage over an mv_flow step "
                f"(method={stages[n].get('mv_flow_method')!r}, its method for long runs, "
                f"{stages[n]['mv_flow_per_step'] * 1e6:.3g} us): " + "; ".join(parts)
                + (f"; not measured: {', '.join(left)}" if left else ""))  # fmt: skip
        g = _goal(name, x, "<= 2", x <= 2, note)
        goals.append(_with_profile(g, ok[worst].get("profile")))
    return goals


def _n10_step_goal(sc: dict[str, Any] | None, sections: Sequence[str]) -> list[dict[str, Any]]:
    name = "n = 10: one compiled MV step <= 2x its minimal flop time"
    d = (sc or {}).get("n10_compiled")
    if not d:
        return [_goal(name, None, "<= 2", None, _why("step-costs", sections))]
    if not d.get("available"):
        return [_goal(name, None, "<= 2", None, f"unavailable: {d.get('why', '')}")]
    note = (f"marginal cost of a step of mv_flow(method='numba') {d['per_step'] * 1e6:.3g} us; "
            f"{d['iterations_per_step']:.3g} fixed-point sweeps a step (measured: "
            f"{d.get('iterations_from', 'the compiled run')}), "
            f"{d['flops']:.3g} flops at {d['flop_rate'] / 1e9:.3g} Gflop/s (a batch of 10x10 "
            f"np.matmul) = {d['flop_time'] * 1e6:.3g} us")  # fmt: skip
    g = _goal(name, d["ratio"], "<= 2", d["ratio"] <= 2, note)
    return [_with_profile(g, d.get("profile"))]


def _cheapest(runs: list[dict[str, Any]], want: set[str] | None, limit: float):
    ok = [
        x
        for x in runs
        if "cpu" in x
        and (want is None or x["method"] in want)
        and (want is not None or x["method"] != "DOP853")
        and max(x["energy"], x["casimir"]) <= limit
    ]
    return min(ok, key=lambda x: x["cpu"]) if ok else None


def _run_text(x: dict[str, Any]) -> str:
    knob = f"rtol {x['rtol']:.0e}" if "rtol" in x else f"h {x['h']:.3g}"
    return (f"{x['method']} {knob} ({x['cpu']:.3g} s, energy {x['energy']:.2g}, "
            f"Casimir {x['casimir']:.2g})")  # fmt: skip


def _long_horizon_goal(lh: dict[str, Any] | None, quick: bool, sections: Sequence[str]):
    name = ("n = 10, T = 1e4, energy and Casimir errors <= 1e-12: best symrb >= 2x faster than "
            "DOP853 (lean field)")  # fmt: skip
    if not lh:
        return [_goal(name, None, ">= 2", None, _why("long-horizon", sections))]
    if lh["T"] < 1e4:
        return [_goal(name, None, ">= 2", None, f"{_NOT_QUICK} (this run: T = {lh['T']:g})")]
    sym = _cheapest(lh["runs"], None, 1e-12)
    dop = _cheapest(lh["runs"], {"DOP853"}, 1e-12)
    if sym is None:
        return [_goal(name, None, ">= 2", None, "no symrb run kept both errors <= 1e-12")]
    if dop is None:
        tried = [x for x in lh["runs"] if x["method"] == "DOP853" and "cpu" in x]
        if not tried:
            return [_goal(name, None, ">= 2", None, "no DOP853 run within the budget")]
        tight = min(tried, key=lambda x: x["rtol"])
        x = tight["cpu"] / sym["cpu"]
        return [
            _goal(
                name,
                x,
                ">= 2",
                x >= 2,
                "no measured DOP853 run reached 1e-12; against its "
                f"tightest, {_run_text(tight)} / {_run_text(sym)} (a lower bound)",
            )
        ]
    x = dop["cpu"] / sym["cpu"]
    g = _goal(name, x, ">= 2", x >= 2, f"cheapest measured runs: {_run_text(dop)} / "
              f"{_run_text(sym)}; one run each, CPU time")  # fmt: skip
    return [_with_profile(g, sym.get("profile") and f"(1/100 of the run) {sym['profile']}")]


def _cold_goal(cs: dict[str, Any] | None, sections: Sequence[str]) -> list[dict[str, Any]]:
    name = "cold start with numba (new process after the first) <= 1.5 s"
    if not cs:
        return [_goal(name, None, "<= 1.5", None, _why("cold-start", sections))]
    if not cs.get("available"):
        return [_goal(name, None, "<= 1.5", None, cs.get("why", ""))]
    x = cs["median_cpu"]
    note = (
        f"median CPU time (process and its threads) of {len(cs['cpu'])} new processes after "
        f"a first that primes the cache (first: {cs['first']['cpu']:.2f} s); import symrb and "
        f"one mv_flow(method='numba') n = 3 call; wall {cs['median_wall']:.2f} s"
    )
    return [_goal(name, x, "<= 1.5", x <= 1.5, note)]


def issue23_goals(ms: dict[str, Any], quick: bool, sections: Sequence[str]) -> list[dict]:
    """The goals of issue 23 from the measurements ``ms`` of a run."""
    sc = ms.get("step-costs")
    return [
        *_one_call_goal(sc, sections),
        *_paper_goals(sc, sections),
        *_stage_goals(sc, sections),
        *_n10_step_goal(sc, sections),
        *_long_horizon_goal(ms.get("long-horizon"), quick, sections),
        *_cold_goal(ms.get("cold-start"), sections),
    ]
