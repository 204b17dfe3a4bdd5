"""The goals of issues 9 and 23, evaluated on the measurements of a run."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .config import _NOT_QUICK, _STEP_ORDERS
from .goals23 import _goal, _with_profile, issue23_goals
from .precision import _cost_table
from .result import BenchResult


def _best_symrb(table: dict[str, dict[str, Any]]) -> tuple[str | None, float | None]:
    cands = [(v["cpu"], m) for m, v in table.items() if m in _STEP_ORDERS and v["cpu"] is not None]
    if not cands:
        return None, None
    c, m = min(cands)
    return m, c


def _point_text(m: str, pt: dict[str, Any]) -> str:
    """A measured run in words: method, its rtol or h, error and median CPU time."""
    knob = f"rtol {pt['rtol']:.0e}" if "rtol" in pt else f"h {pt['h']:.4g}" if "h" in pt else ""
    return f"{m} {knob} (error {pt['error']:.2g}, {pt['cpu']['median'] * 1e3:.3g} ms)"


def _speed_goal(
    res: BenchResult,
    wp: dict[str, Any] | None,
    target_err: float,
    factor: float,
    label: str,
    why: str = _NOT_QUICK,
) -> dict[str, Any]:
    """DOP853 (lean field) / the best symrb step method, each at its cheapest MEASURED run with
    error at most ``target_err`` (no interpolation, no extrapolation).  ``factor`` < 1 means
    "within 1/factor of DOP853"."""
    name = f"{label}: best symrb step method >= {factor:g}x faster than DOP853 (lean field)"
    if factor < 1.0:
        name = f"{label}: best symrb step method within {1 / factor:g}x of DOP853 (lean field)"
    target = f">= {factor:g}"
    if wp is None:
        return _goal(name, None, target, None, why)
    table = _cost_table(wp, target_err)
    dop = table.get("DOP853", {}).get("cpu")
    best, c = _best_symrb(table)
    if dop is None or best is None:
        miss = "DOP853" if dop is None else "every symrb step method"
        return _goal(name, None, target, None, f"no measured run of {miss} reaches {target_err:g}")
    ratio = dop / c
    used = f"{_point_text('DOP853', table['DOP853']['point'])} / "
    used += _point_text(best, table[best]["point"])
    field = wp.get("baselines", {}).get("variant") or "the generated field (an old run)"
    note = f"cheapest measured runs with error <= {target_err:g}: {used}; DOP853 on {field}"
    g = _goal(name, ratio, target, ratio >= factor, note)
    return _with_profile(g, wp["methods"][best].get("profile"))


@dataclass(frozen=True)
class _Run:
    """What the goals read from a run: its measurements by section, and how it was run."""

    quick: bool
    sections: Sequence[str]
    ms: dict[str, Any]
    wp: dict[float, Any]  # the n = 3 work-precision diagrams by T
    wp10: dict[str, Any] | None
    cost: dict[int, Any]  # the cost-vs-n rows by n
    thr: dict[str, Any] | None
    lt: dict[tuple[str, int], Any]  # the long-time runs by (flow, n)

    @classmethod
    def of(cls, res: BenchResult, quick: bool, sections: Sequence[str]) -> _Run:
        ms = res.measurements
        return cls(
            quick=quick,
            sections=sections,
            ms=ms,
            wp={w["T"]: w for w in ms.get("work-precision", {}).get("n3", [])},
            wp10=ms.get("work-precision", {}).get("n10"),
            cost={r["n"]: r for r in ms.get("cost-vs-n", {}).get("rows", [])},
            thr=ms.get("throughput"),
            lt={(d.get("flow_key", "mv_flow"), d["n"]): d for d in ms.get("long-time", [])},
        )

    def missing(self, name: str, target: str, sec: str, long: bool = False) -> dict[str, Any]:
        """The goal ``name`` unmeasured, with why."""
        if self.quick and long:
            why = _NOT_QUICK
        else:
            why = _ABSENT if sec not in self.sections else "not measured"
        return _goal(name, None, target, None, why)


_ABSENT = "section not run"


def _step_cost_goals(r: _Run) -> list[dict[str, Any]]:
    """One MV step for n = 3 against a 3x3 matmul, and on the compiled path in microseconds."""
    goals = []
    name = "n = 3 single MV step <= 3x one 3x3 matmul"
    if 3 in r.cost:
        x = r.cost[3]["matmul_equivalents"]
        goals.append(_goal(name, x, "<= 3", x <= 3, f"stepper: {r.ms['cost-vs-n']['stepper']}"))
    else:
        goals.append(r.missing(name, "<= 3", "cost-vs-n"))
    name = "n = 3 single MV step, compiled path (numba) <= 1 us"
    comp = r.ms.get("cost-vs-n", {}).get("compiled_n3")
    if comp:
        us = comp["per_step"] * 1e6
        note = "marginal cost of a step of mv_flow(method='numba') in us; "
        note += f"{comp['matmul_equivalents']:.2f} 3x3 matmuls"
        goals.append(_goal(name, us, "<= 1", us <= 1, note))
    else:
        why = (
            "numba not installed (pip install symrb[fast])"
            if "cost-vs-n" in r.sections
            else _ABSENT
        )
        goals.append(_goal(name, None, "<= 1", None, why))
    return goals


def _n3_speed_goals(r: _Run, res: BenchResult) -> list[dict[str, Any]]:
    """The best symrb step method against DOP853 for n = 3 at three (T, error) targets."""
    goals = []
    for T, err, factor, long in (
        (10.0, 1e-8, 30.0, False),
        (100.0, 1e-8, 200.0, True),
        (100.0, 1e-10, 3.0, True),
    ):
        label = f"n = 3, T = {T:g}, error {err:g}"
        if "work-precision" not in r.sections:
            goals.append(
                r.missing(
                    f"{label}: best symrb step method vs DOP853", f">= {factor:g}", "work-precision"
                )  # fmt: skip
            )
        elif T not in r.wp:
            why = _NOT_QUICK if long and r.quick else f"T = {T:g} not in this run"
            goals.append(_speed_goal(res, None, err, factor, label, why))
        else:
            goals.append(_speed_goal(res, r.wp[T], err, factor, label))
    return goals


def _exact_accuracy_goal(w: dict[str, Any], pt: dict[str, Any], name: str) -> dict[str, Any]:
    """The exact propagator's error against the reference (certified only when the reference's
    own error is at least ten times smaller than the target)."""
    est = w["reference_error_estimate"]
    met = pt["error"] <= 1e-13 if est <= 1e-14 else None
    return _goal(
        name,
        pt["error"],
        "<= 1e-13",
        met,
        f"T = {w['T']:g}, max entry error against the extended-precision reference, whose own "
        f"error is about {est:.1e}" + ("" if met is not None else ": cannot certify 1e-13"),
    )


def _exact_goals(r: _Run) -> list[dict[str, Any]]:
    """The exact propagator: its speed against DOP853 at rtol 1e-12, and its accuracy."""
    name = "exact propagator >= 100x faster than DOP853 (lean field) at rtol 1e-12"
    name2 = "exact propagator accurate to 1e-13"
    w = r.wp.get(10.0) or next(iter(r.wp.values()), None)
    ex = w["methods"].get("exact", {}) if w else {}
    if w is None or not ex.get("available"):
        why = "symrb.exact not available" if w else _ABSENT
        return [_goal(name, None, ">= 100", None, why), _goal(name2, None, "<= 1e-13", None, why)]
    dop_points = w["methods"].get("DOP853", {}).get("points", [])
    dops = [q for q in dop_points if abs(q["rtol"] - 1e-12) < 1e-20]
    pt = ex["points"][0]
    if dops:
        ratio = dops[0]["cpu"]["median"] / pt["cpu"]["median"]
        field = w.get("baselines", {}).get("variant") or "the generated field (an old run)"
        speed = _goal(name, ratio, ">= 100", ratio >= 100,
                      f"T = {w['T']:g}, CPU time ratio of the measured runs "
                      f"{_point_text('DOP853', dops[0])} / exact "
                      f"({pt['cpu']['median'] * 1e3:.3g} ms); DOP853 on {field}")  # fmt: skip
        speed = _with_profile(speed, ex.get("profile"))
    else:
        speed = _goal(name, None, ">= 100", None, "DOP853 at rtol 1e-12 not in the grid")
    return [speed, _exact_accuracy_goal(w, pt, name2)]


def _n10_goals(r: _Run, res: BenchResult) -> list[dict[str, Any]]:
    """The best symrb step method against DOP853 for n = 10, and one step for n = 50."""
    label = "n = 10, T = 100, error 1e-08"
    if "work-precision" in r.sections and r.wp10 is None and r.quick:
        goals = [_speed_goal(res, None, 1e-8, 0.5, label)]
    elif r.wp10 is not None:
        goals = [_speed_goal(res, r.wp10, 1e-8, 0.5, label)]
    else:
        goals = [
            r.missing(
                f"{label}: best symrb step method within 2x of DOP853 (lean field)",
                ">= 0.5",
                "work-precision",
            )
        ]
    name = "n = 50 one MV step <= 100 matmul-equivalents"
    if 50 in r.cost:
        x = r.cost[50]["matmul_equivalents"]
        goals.append(_goal(name, x, "<= 100", x <= 100, f"stepper: {r.ms['cost-vs-n']['stepper']}"))
    else:
        goals.append(r.missing(name, "<= 100", "cost-vs-n"))
    return goals


def _throughput_goals(r: _Run) -> list[dict[str, Any]]:
    """A batch of 10^4 bodies: body-steps per second, against a batched matmul; the cold start."""
    thr = r.thr
    rows = {x["batch"]: x for x in thr["rows"]} if thr else {}
    name = "batch 10^4, n = 3: >= 5e6 body-steps/s"
    soa = thr is not None and "matmul_soa" in thr.get("matmul", {})
    name2 = "batch 10^4: a step within 3x of " + (
        "one batched 3x3 product in the engine's layout (einsum on (3, 3, B))"
        if soa
        else "one batched 3x3 matmul"
    )
    goals = []
    if thr is not None and 10000 in rows:
        row = rows[10000]
        key = "flow_numpy" if "flow_numpy_per_step" in row else None
        rate = row[f"{key}_body_steps_per_s"] if key else row["step_body_steps_per_s"]
        over = row[f"{key}_over_matmul"] if key else row["step_over_matmul"]
        what = "CPU time of one step of the batch / one np.matmul(A, B, out=C) on (B, 3, 3)"
        if soa and key:
            over = row[f"{key}_over_matmul_soa"]
            what = (f"CPU time of one step of the batch / one {thr['matmul']['matmul_soa']}; "
                    f"against {thr['matmul']['matmul']}: {row[f'{key}_over_matmul']:.2f}")  # fmt: skip
        how = (
            "symrb.engine.mv_flow NumPy path, marginal cost of a step"
            if key
            else f"stepper: {thr['stepper']}"
        )
        if "flow_numba_body_steps_per_s" in row:
            how += f" (compiled path: {row['flow_numba_body_steps_per_s']:.3g} body-steps/s)"
        how += f"; one MVStepper.step call: {row['step_body_steps_per_s']:.3g} body-steps/s"
        goals.append(_goal(name, rate, ">= 5e6", rate >= 5e6, how))
        goals.append(
            _goal(
                name2,
                over,
                "<= 3",
                over <= 3,
                what,
            )
        )
    else:
        goals.append(r.missing(name, ">= 5e6", "throughput"))
        goals.append(r.missing(name2, "<= 3", "throughput"))
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
        goals.append(r.missing(name, "<= 10", "throughput"))
    return goals


def _long_time_goals(r: _Run) -> list[dict[str, Any]]:
    """10^6 steps (mv_flow at n = 3 and 10, the paper's maps at n = 3): the invariants' errors
    against eps sqrt(N), and their slope."""
    goals = []
    for key, n in (("mv_flow", 3), ("mv_flow", 10), ("mv_algorithm2", 3), ("symmetric_flow", 3)):
        who = "" if key == "mv_flow" else f" {key}"
        name = f"10^6 steps n = {n}{who}: invariant errors within 10 eps sqrt(N)"
        name2 = f"10^6 steps n = {n}{who}: slope of log error vs log N <= 0.6"
        d = r.lt.get((key, n))
        if d is None or d["steps"] < 10**6:
            note = _NOT_QUICK if r.quick or d is not None else _ABSENT
            if d is not None:
                note = d.get("stopped") or note
                note += f" (a {d['steps']}-step run gave ratio "
                note += f"{max(d['max_ratio_to_eps_sqrt_N'].values()):.2g})"
            goals.append(_goal(name, None, "<= 10", None, note))
            goals.append(_goal(name2, None, "<= 0.6", None, note))
            continue
        x = max(d["max_ratio_to_eps_sqrt_N"].values())
        goals.append(_goal(name, x, "<= 10", x <= 10, "max over N and over energy, Casimir, "
                           f"orthogonality of error / (eps sqrt(N)); {d['flow']}"))  # fmt: skip
        slopes = [s for s in d["slope"].values() if s is not None]
        s = max(slopes) if slopes else None
        goals.append(_goal(name2, s, "<= 0.6", None if s is None else s <= 0.6,
                           "largest of the three fitted slopes (N >= 100)"))  # fmt: skip
    return goals


def _order_goal(r: _Run) -> list[dict[str, Any]]:
    """Every fixed-step method's fitted order against its nominal order."""
    name = "every method's order within 0.2 of nominal"
    orders = {}
    for w in r.wp.values():
        for m, e in w["methods"].items():
            if e.get("available") and "nominal_order" in e:
                orders[f"{m} T={w['T']:g}"] = (e["order"], e["nominal_order"])
    if not orders:
        return [r.missing(name, "<= 0.2", "work-precision")]
    bad = [k for k, (o, nom) in orders.items() if o is None or abs(o - nom) > 0.2]
    worst = max((abs(o - nom) for o, nom in orders.values() if o is not None), default=float("nan"))
    return [
        _goal(
            name,
            worst,
            "<= 0.2",
            not bad,
            "largest |fitted - nominal|" + (f"; off: {', '.join(bad)}" if bad else ""),
        )
    ]


def _integrate_goal(r: _Run) -> list[dict[str, Any]]:
    """The overhead of symrb.integrate over solve_ivp on the same field."""
    name = "symrb.integrate <= 1.2x solve_ivp (DOP853, same field)"
    ratios = []
    for w in r.wp.values():
        pi = {q["rtol"]: q for q in w["methods"].get("integrate", {}).get("points", [])}
        # the same field: the generated one (an old run's DOP853 ran on it)
        same = "DOP853-gen" if w["methods"].get("DOP853-gen", {}).get("available") else "DOP853"
        pd = {q["rtol"]: q for q in w["methods"].get(same, {}).get("points", [])}
        ratios += [pi[t]["cpu"]["median"] / pd[t]["cpu"]["median"] for t in pi if t in pd]
    if not ratios:
        return [r.missing(name, "<= 1.2", "work-precision")]
    x = float(np.median(ratios))
    return [
        _goal(
            name,
            x,
            "<= 1.2",
            x <= 1.2,
            f"median over {len(ratios)} tolerances (range {min(ratios):.2f}-{max(ratios):.2f})",
        )
    ]


def _goals(res: BenchResult, quick: bool, sections: Sequence[str]) -> list[dict[str, Any]]:
    """Every goal of issues 9 and 23, in the order of the report, measured or with why not."""
    r = _Run.of(res, quick, sections)
    return [
        *_step_cost_goals(r),
        *_n3_speed_goals(r, res),
        *_exact_goals(r),
        *_n10_goals(r, res),
        *_throughput_goals(r),
        *_long_time_goals(r),
        *_order_goal(r),
        *_integrate_goal(r),
        *issue23_goals(r.ms, r.quick, r.sections),
    ]
