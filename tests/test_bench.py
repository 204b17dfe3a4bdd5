"""``benchmarks.harness`` and ``symrb bench``: the JSON schema with its goals, a tiny run of every
section, the exit statuses, errors measured against an independent reference, and the order fit.

Nothing here is timed: the benchmark's speed is what it reports, not what these tests check.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

import symrb
import symrb.exact
from benchmarks import harness as bench
from benchmarks.harness import cli as bench_cli
from benchmarks.harness import config, goals, precision, problems, runner, timing
from symrb import cli as launcher

ROOT = Path(__file__).resolve().parents[1]

TINY: dict[str, Any] = {
    "rounds": 1,
    "min_time": 0.0005,
    "wp_T": (2.0,),
    "wp_rtols": (1e-4, 1e-7),
    "wp_h": {2: (0.2, 0.1), 4: (0.4, 0.2), 6: (0.5, 0.25), 8: (0.5, 0.25)},
    "wp_n10_T": None,
    "long_steps": 100,
    "long_n": (3,),
    "batches": (1, 10),
    "cold_batch": 10,
    "cold_budget": 1.0,
    "cost_n": (3, 4),
    "marginal_time": 0.002,
    "stage_n": (3,),
    "lh_T": 1.0,
    "lh_rtols": (1e-6,),
    "lh_symrb": (("MV-fast", 0.1),),
    "lh_budget": 5.0,
    "cold_processes": 2,
}

GOAL_NAMES = [
    "n = 3 single MV step <= 3x one 3x3 matmul",
    "n = 3 single MV step, compiled path (numba) <= 1 us",
    "n = 3, T = 10, error 1e-08",
    "n = 3, T = 100, error 1e-08",
    "n = 3, T = 100, error 1e-10",
    "exact propagator >= 100x faster than DOP853 (lean field) at rtol 1e-12",
    "exact propagator accurate to 1e-13",
    "n = 10, T = 100, error 1e-08",
    "n = 50 one MV step <= 100 matmul-equivalents",
    "batch 10^4, n = 3: >= 5e6 body-steps/s",
    "batch 10^4: a step within 3x of",
    "cold start within 10x of a warm step",
    "10^6 steps n = 3: invariant errors",
    "10^6 steps n = 3: slope",
    "10^6 steps n = 10: invariant errors",
    "10^6 steps n = 10: slope",
    "every method's order within 0.2 of nominal",
    "symrb.integrate <= 1.2x solve_ivp",
    "10^6 steps n = 3 mv_algorithm2: invariant errors",
    "10^6 steps n = 3 symmetric_flow: slope",
    "one-step mv_flow call (n = 3, whole call) <= 30 us",
    "n = 3: a mv_algorithm2 step <= 3x an mv_flow step",
    "n = 3: a symmetric_flow step <= 3x an mv_flow step",
    "n = 3: a stage of every composition, RKMK4, midpoint <= 2x an mv_flow step",
    "n = 10: a stage of every composition, RKMK4, midpoint <= 2x an mv_flow step",
    "n = 10: one compiled MV step <= 2x its minimal flop time",
    "n = 10, T = 1e4, energy and Casimir errors <= 1e-12",
    "cold start with numba (new process after the first) <= 1.5 s",
]


@pytest.fixture(scope="module")
def verify_json(tmp_path_factory: pytest.TempPathFactory) -> Path:
    data = {
        "claims": [
            {
                "id": "S1",
                "evidence": [
                    {"level": "float64", "seconds": "0.5", "passed": "True"},
                    {"level": "symbolic, general n", "seconds": "2.0", "passed": "True"},
                ],
            },
            {"id": "D2", "evidence": [{"level": "float64", "seconds": "0.25", "passed": "False"}]},
        ]
    }
    path = tmp_path_factory.mktemp("verify") / "verify.json"
    path.write_text(json.dumps(data))
    return path


@pytest.fixture(scope="module")
def tiny(verify_json: Path) -> bench.BenchResult:
    return bench.run(
        quick=True,
        methods=["DOP853", "LSODA", "integrate", "MV", "MV-fast", "MV-comp4", "exact"],
        progress=False,
        verify_json=verify_json,
        config=TINY,
    )


# ---------------------------------------------------------------------------------------------
# the result and its JSON


def test_json_has_the_machine_parameters_measurements_and_every_goal(
    tiny: bench.BenchResult, tmp_path: Path
) -> None:
    path = tiny.write_json(tmp_path / "sub" / "bench.json")
    data = json.loads(path.read_text())  # strict JSON: no NaN (allow_nan=False on writing)
    assert set(data) == {"machine", "parameters", "measurements", "goals", "notes", "seconds",
                         "previous_goals"}  # fmt: skip
    assert len(data["machine"]["load_average_start"]) == 3
    assert set(data["machine"]["section_seconds"]) == set(bench.SECTIONS)
    for key in ("platform", "cpu_count", "python", "numpy", "scipy", "blas"):
        assert key in data["machine"], key
    assert data["parameters"]["quick"] is True and data["parameters"]["rounds"] == 1
    assert set(data["measurements"]) == set(bench.SECTIONS)
    goals = data["goals"]
    for goal in goals:
        assert set(goal) == {"name", "measured", "target", "met", "note"}
        assert goal["met"] in (True, False, None)
        if goal["met"] is None:
            assert goal["note"], goal  # why it was not measured
        else:
            assert isinstance(goal["measured"], float)
    names = [g["name"] for g in goals]
    for expected in GOAL_NAMES:
        assert sum(n.startswith(expected) for n in names) == 1, (expected, names)
    long_runs = [g for g in goals if g["name"].startswith(("10^6", "n = 3, T = 100", "n = 10,"))]
    assert long_runs and all(
        g["met"] is None and "not measured in --quick" in g["note"] for g in long_runs
    )


def test_missing_optional_methods_are_listed_with_met_none(tiny: bench.BenchResult) -> None:
    exact_goals = [g for g in tiny.goals if g["name"].startswith("exact propagator")]
    try:
        import symrb.exact  # noqa: F401
    except ImportError:
        assert all(g["met"] is None and "not available" in g["note"] for g in exact_goals)
        assert any("symrb.exact" in note for note in tiny.notes)
    wp = tiny.measurements["work-precision"]["n3"][0]
    assert wp["methods"]["MV"]["available"] and wp["methods"]["DOP853"]["available"]


def test_every_section_measured_something(tiny: bench.BenchResult) -> None:
    ms = tiny.measurements
    wp = ms["work-precision"]["n3"][0]
    for point in wp["methods"]["DOP853"]["points"] + wp["methods"]["MV"]["points"]:
        cpu = point["cpu"]
        assert 0 < cpu["min"] <= cpu["median"] <= cpu["max"]
        assert point["error"] == max(point["error_Q"], point["error_M"])
    lt, *paper_runs = ms["long-time"]
    assert [d["flow_key"] for d in paper_runs] == ["mv_algorithm2", "symmetric_flow"]
    assert all(d["N"][-1] == 100 and max(d["errors"]["energy"]) < 1e-12 for d in paper_runs)
    assert lt["N"][-1] == 100 and len(lt["N"]) == len(lt["errors"]["energy"])
    assert all(np.diff(lt["errors"]["energy"]) >= 0)  # running maxima
    assert max(lt["errors"]["orthogonality"]) < 1e-12
    assert [r["batch"] for r in ms["throughput"]["rows"]] == [1, 10]
    assert ms["throughput"]["cold_start"]["ratio"] > 0
    assert [r["n"] for r in ms["cost-vs-n"]["rows"]] == [3, 4]
    ev = ms["evidence"]["levels"]
    assert ev["float64"]["checks"] == 2 and ev["float64"]["passed"] == 1
    assert ev["float64"]["claims"] == ["D2", "S1"]
    assert ev["float64"]["total_seconds"] == pytest.approx(0.75)
    assert "every n" in ev["symbolic, general n"]["certifies"]


def test_preprocessed_methods_reach_their_orders_and_skip_n_other_than_3() -> None:
    """MV-pre4 and MV-pre8 (mv_flow(order=...)) in a work-precision sweep at n = 3 show their
    orders against the exact solution; at n = 4 they are not applicable (no failure noted)."""
    p = dict(config._QUICK, rounds=1, min_time=0.0005, wp_h={4: (0.2, 0.1), 8: (0.4, 0.2)})
    notes: list[str] = []
    wp = precision._work_precision(
        3, 4.0, p, ["MV-pre4", "MV-pre8"], problems._modules(), notes, lambda _m: None
    )
    assert wp["backend"] in ("numpy", "numba")
    assert wp["reference"] == precision.REFERENCE and wp["reference_error_estimate"] < 1e-14
    assert wp["reference_vs_dop853"] < 1e-10  # the same problem, to DOP853's own error
    for name, order in (("MV-pre4", 4), ("MV-pre8", 8)):
        assert abs(wp["methods"][name]["order"] - order) < 0.3, wp["methods"][name]
    wp4 = precision._work_precision(
        4, 1.0, p, ["MV-pre4"], problems._modules(), notes, lambda _m: None
    )
    assert wp4["methods"]["MV-pre4"] == {"available": False}
    assert not notes, notes


def test_plots_are_png_and_svg(tiny: bench.BenchResult, tmp_path: Path) -> None:
    pytest.importorskip("matplotlib")
    files = tiny.plot(tmp_path)
    stems = {f.stem for f in files}
    assert stems == {"work_precision", "long_time", "throughput", "cost_vs_n"}
    assert {f.suffix for f in files} == {".png", ".svg"}
    assert all(f.stat().st_size > 1000 for f in files)


def test_bad_arguments_raise_input_error() -> None:
    with pytest.raises(symrb.errors.InputError, match="sections"):
        bench.run(sections=["nonsense"], progress=False)
    with pytest.raises(symrb.errors.InputError, match="methods"):
        bench.run(methods=["Euler"], progress=False)
    with pytest.raises(symrb.errors.InputError, match="unknown keys"):
        bench.run(config={"steps": 3}, progress=False)
    with pytest.raises(symrb.errors.InputError, match="rounds"):
        bench.time_interleaved({"f": lambda: None}, rounds=0)


# ---------------------------------------------------------------------------------------------
# errors against an independent reference


def _euler_reference(T: float) -> np.ndarray:
    """m(T) of Euler's equations in vector form, m' = m x (m / I): another route than the
    matrix field the benchmark integrates."""
    lam, _Q0, M0 = problems._problem(3, 0)
    inertia = symrb.algebra.inertia_from_lam(lam)
    sol = solve_ivp(
        lambda _t, m: np.cross(m, m / inertia),
        (0.0, T),
        symrb.vee(M0),
        method="Radau",
        rtol=1e-12,
        atol=1e-14,
    )
    return sol.y[:, -1]


def test_the_reference_agrees_with_an_independent_integration() -> None:
    lam, Q0, M0 = problems._problem(3, 0)
    _Q, M = problems._solve_ivp_end(lam, Q0, M0, 5.0, "DOP853", 1e-13)()
    assert np.abs(symrb.vee(M) - _euler_reference(5.0)).max() < 1e-9


def test_the_extended_precision_reference_converges_and_agrees_with_scipy() -> None:
    """The work-precision reference (extrapolation in np.longdouble, any n) at two macro steps
    agrees with itself far below float64 rounding of the methods judged, and with DOP853 at
    rtol 1e-13 (another route) to DOP853's own error; for n = 3 also with the exact solution."""
    for n, T in ((3, 5.0), (4, 2.0)):
        lam, Q0, M0 = problems._problem(n, 0)
        ref, est = precision._reference(lam, Q0, M0, T)
        assert est < 1e-15, (n, est)
        dop = problems._solve_ivp_end(lam, Q0, M0, T, "DOP853", 1e-13)()
        assert precision._errors(dop, ref)["error"] < 1e-11, n
    lam, Q0, M0 = problems._problem(3, 0)
    ref, _est = precision._reference(lam, Q0, M0, 5.0)
    exact = symrb.exact.rigid_body_exact(Q0, M0, lam, np.array([5.0]))
    assert precision._errors((exact.y.Q[-1], exact.y.M[-1]), ref)["error"] < 1e-13
    # a wrong inertia (reversed) is far from it: the comparison can fail
    wrong, _ = precision._reference(lam[::-1].copy(), Q0, M0, 5.0)
    assert precision._errors(wrong, ref)["error"] > 1e-2


def test_a_wrong_method_gets_a_large_error(monkeypatch: pytest.MonkeyPatch) -> None:
    right = symrb.paper.discrete_rigid_body_flow

    def wrong(Q0, M0, lam, h, steps, **kw):  # the inertia in the wrong order
        return right(Q0, M0, np.asarray(lam)[::-1], h, steps, **kw)

    def measured() -> dict[str, Any]:
        wp = precision._work_precision(
            3, 2.0, dict(config._QUICK, **TINY), ["MV"], {}, [], lambda _m: None
        )
        return {p["h"]: p["error"] for p in wp["methods"]["MV"]["points"]}

    good = measured()
    monkeypatch.setattr(symrb.paper, "discrete_rigid_body_flow", wrong)
    bad = measured()
    assert max(good.values()) < 0.05
    assert min(bad.values()) > 0.1
    # the good errors are those of an independent comparison
    lam, Q0, M0 = problems._problem(3, 0)
    sol = right(Q0, M0, lam, 0.1, 20, save_every=20)
    m_end = _euler_reference(2.0)
    assert good[0.1] >= np.abs(symrb.vee(sol.y.M[-1]) - m_end).max() * (1 - 1e-6)


# ---------------------------------------------------------------------------------------------
# fitting


@settings(max_examples=50, deadline=None)
@given(
    order=st.floats(1.0, 9.0),
    const=st.floats(1e-3, 1e3),
    noise=st.lists(st.floats(-0.02, 0.02), min_size=5, max_size=5),
)
def test_the_order_fit_recovers_a_known_slope(order: float, const: float, noise: list) -> None:
    h = 0.2 / 2.0 ** np.arange(5)
    err = const * h**order * np.exp(noise)  # up to 2 % scatter
    assert abs(bench.fit_slope(h, err) - order) < 0.05


def test_the_fit_leaves_out_errors_at_the_reference_floor() -> None:
    h = np.array([0.1, 0.05, 0.025, 0.0125])
    err = np.maximum(1e-10 * (h / 0.1) ** 4, 1e-13)  # the last point is at the floor
    assert bench.fit_slope(h, err, floor=1e-12) == pytest.approx(4.0)
    assert bench.fit_slope(h, err) < 3.5


def _pt(err: float, cpu: float, **knob: float) -> dict[str, Any]:
    return {"error": err, "cpu": {"median": cpu}, **knob}


def test_the_cost_at_an_error_is_the_cheapest_measured_run_reaching_it() -> None:
    pts = [_pt(1e-6, 1.0, h=0.2), _pt(1e-9, 3.0, h=0.1), _pt(2e-9, 2.0, h=0.15),
           _pt(float("nan"), 0.1, h=0.5), _pt(1e-12, 8.0, h=0.05)]  # fmt: skip
    assert timing.cheapest_measured(pts, 1e-8)["h"] == 0.15  # not the smallest error: cheapest
    assert timing.cheapest_measured(pts, 1e-9)["h"] == 0.1
    assert timing.cheapest_measured(pts, 1e-12)["h"] == 0.05
    assert timing.cheapest_measured(pts, 1e-13) is None  # no extrapolation below the grid
    assert timing.cheapest_measured(pts, 1.0)["h"] == 0.2  # NaN errors never count


def _setting(methods: dict[str, list[dict[str, Any]]]) -> dict[str, Any]:
    return {
        "n": 3,
        "T": 100.0,
        "baselines": {"variant": "lean"},
        "methods": {m: {"available": True, "points": p} for m, p in methods.items()},
    }


def test_speed_goals_use_measured_points_only() -> None:
    w = _setting({
        "DOP853": [_pt(1e-7, 0.01, rtol=1e-8), _pt(5e-9, 0.02, rtol=1e-9), _pt(1e-11, 0.05, rtol=1e-11)],
        "DOP853-gen": [_pt(5e-9, 0.001, rtol=1e-9)],  # cheaper, but not the baseline of the goals
        # a steep method whose grid stops above the target: an extrapolation would favour it
        "MV-pre10": [_pt(1e-6, 1e-5, h=0.5), _pt(2e-8, 2e-5, h=0.4)],
        "MV-pre8": [_pt(9e-9, 4e-4, h=0.2), _pt(1e-12, 5e-4, h=0.1)],
        "exact": [_pt(1e-15, 1e-6)],  # not a step method
    })  # fmt: skip
    g = goals._speed_goal(None, w, 1e-8, 30.0, "n = 3, T = 100, error 1e-08")  # type: ignore[arg-type]
    assert g["measured"] == pytest.approx(0.02 / 4e-4) and g["met"] is True
    assert "MV-pre8 h 0.2" in g["note"] and "DOP853 rtol 1e-09" in g["note"]
    g = goals._speed_goal(None, w, 1e-8, 200.0, "x")  # type: ignore[arg-type]
    assert g["met"] is False and g["measured"] == pytest.approx(50.0)
    g = goals._speed_goal(None, w, 1e-13, 2.0, "x")  # type: ignore[arg-type]
    assert g["met"] is None and "no measured run" in g["note"]
    # within 2x (factor 1/2): met at a ratio of 0.5, not below
    w2 = _setting({"DOP853": [_pt(1e-9, 1.0, rtol=1e-10)], "MV-comp8": [_pt(1e-9, 2.0, h=0.2)]})
    assert goals._speed_goal(None, w2, 1e-8, 0.5, "x")["met"] is True  # type: ignore[arg-type]
    w2["methods"]["MV-comp8"]["points"][0]["cpu"]["median"] = 2.1
    assert goals._speed_goal(None, w2, 1e-8, 0.5, "x")["met"] is False  # type: ignore[arg-type]


def test_the_long_horizon_goal_takes_the_cheapest_runs_within_the_invariant_error() -> None:
    from benchmarks.harness import goals23

    def run(method: str, cpu: float, err: float, **knob: float) -> dict[str, Any]:
        return {"method": method, "cpu": cpu, "energy": err, "casimir": err / 2, **knob}

    runs = [run("DOP853", 1.0, 1e-11, rtol=1e-11), run("DOP853", 3.0, 5e-13, rtol=1e-12),
            run("DOP853", 9.0, 1e-14, rtol=1e-14), run("MV-fast", 0.5, 3e-12, h=0.4),
            run("MV-fast", 1.2, 2e-14, h=0.2), run("MV-comp4", 4.0, 1e-14, h=0.4),
            {"method": "split4", "h": 0.4, "skipped": "not available"}]  # fmt: skip
    (g,) = goals23._long_horizon_goal({"T": 1e4, "runs": runs}, False, ["long-horizon"])
    assert g["measured"] == pytest.approx(3.0 / 1.2) and g["met"] is True
    assert "DOP853 rtol 1e-12" in g["note"] and "MV-fast h 0.2" in g["note"]
    (g,) = goals23._long_horizon_goal({"T": 1e4, "runs": runs[:1] + runs[3:]}, False, [])
    assert "lower bound" in g["note"] and g["measured"] == pytest.approx(1.0 / 1.2)
    (g,) = goals23._long_horizon_goal({"T": 100.0, "runs": runs}, True, ["long-horizon"])
    assert g["met"] is None and "not measured in --quick" in g["note"]


def test_a_goal_not_met_carries_its_profile_and_a_met_one_does_not() -> None:
    from benchmarks.harness import goals23

    sc = {"one_call": {"cpu": {"median": 5e-5}, "what": "one call", "profile": "f (x.py:1)"}}
    (g,) = goals23._one_call_goal(sc, ["step-costs"])
    assert g["met"] is False and g["measured"] == pytest.approx(50.0) and "f (x.py:1)" in g["note"]
    sc["one_call"]["cpu"]["median"] = 2e-5
    (g,) = goals23._one_call_goal(sc, ["step-costs"])
    assert g["met"] is True and "x.py" not in g["note"]
    paper = {"mv_flow": {"per_step": 1e-6, "K": [10, 60]},
             "mv_algorithm2": {"per_step": 2.9e-6, "K": [10, 60]},
             "symmetric_flow": {"per_step": 3.1e-6, "K": [10, 60], "profile": "g"}}  # fmt: skip
    a2, sym = goals23._paper_goals({"paper": paper}, ["step-costs"])
    assert (a2["met"], sym["met"]) == (True, False) and sym["note"].endswith("g")


def test_the_stage_goal_is_the_worst_method_and_leaves_out_noise() -> None:
    from benchmarks.harness import goals23

    def m(over: float, reliable: bool = True) -> dict[str, Any]:
        return {"over_mv_flow_step": over, "per_stage": over * 1e-6, "stages": 5,
                "reliable": reliable, "profile": f"p{over}"}  # fmt: skip

    st = {
        "3": {
            "mv_flow_per_step": 1e-6,
            "mv_flow_method": "numba",
            "methods": {"MV-comp4": m(1.5), "RKMK4": m(2.5), "midpoint": m(9.0, False)},
        }
    }
    g3, g10 = goals23._stage_goals({"stages": st}, ["step-costs"])
    assert g3["measured"] == 2.5 and g3["met"] is False and g3["note"].endswith("p2.5")
    assert "midpoint" in g3["note"].split("not measured:")[1] and g10["met"] is None
    st["3"]["methods"]["RKMK4"] = m(1.9)
    (g3, _g10) = goals23._stage_goals({"stages": st}, ["step-costs"])
    assert g3["measured"] == 1.9 and g3["met"] is True and "p1.9" not in g3["note"]


def test_the_n10_compiled_step_is_set_against_its_flops_with_measured_sweeps(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A compiled n = 10 path that reports no sweeps: they are counted on the NumPy fixed point,
    and the ratio is the marginal step over flops / flop rate."""
    from types import SimpleNamespace

    from benchmarks.harness import costs
    from symrb import _compiled
    from symrb.engine import mv_flow

    def fake(Q, M, lam, h, K, save_every=1, method="auto"):  # type: ignore[no-untyped-def]
        sol = mv_flow(Q, M, lam, h, K, save_every=save_every,
                      method="auto" if method == "numba" else method)  # fmt: skip
        return SimpleNamespace(iterations=np.array([]), y=sol.y) if method == "numba" else sol

    monkeypatch.setattr(_compiled, "AVAILABLE", True)
    p = {"rounds": 1, "min_time": 0.0005, "marginal_time": 0.002, "seed": 0}
    out = costs._n10_compiled(p, {"engine": SimpleNamespace(mv_flow=fake)})
    assert out["available"] and "fixed-point" in out["iterations_from"]
    lam, Q0, M0 = problems._problem(10, 0)
    ref = mv_flow(Q0, M0, lam, 0.01, 200, save_every=200, method="fixed-point")
    assert out["iterations_per_step"] == pytest.approx(np.sum(ref.iterations) / 200)
    assert out["flops"] == pytest.approx(costs.mv_step_flops(10, out["iterations_per_step"]))
    assert out["ratio"] == pytest.approx(out["per_step"] * out["flop_rate"] / out["flops"])
    monkeypatch.setattr(_compiled, "AVAILABLE", False)
    assert costs._n10_compiled(p, {"engine": SimpleNamespace(mv_flow=fake)})["available"] is False


def test_the_flop_count_of_a_step_is_counted_from_its_operations() -> None:
    from benchmarks.harness.costs import mv_step_flops

    n = 10
    # k sweeps of two products and 12 n^2 entrywise, then 8 2/3 n^3 and 6 n^2
    assert mv_step_flops(n, 0) == pytest.approx((2 / 3 + 8) * n**3 + 6 * n**2)
    assert mv_step_flops(n, 8) - mv_step_flops(n, 7) == pytest.approx(4 * n**3 + 12 * n**2)


# ---------------------------------------------------------------------------------------------
# the lean baselines


@pytest.mark.parametrize("n", [3, 4, 10])
def test_every_lean_field_is_the_generated_field(n: int) -> None:
    """Each lean variant gives the derivative of symrb's generated field at random states (not
    only the initial one), to rounding, and solve_ivp follows the same trajectory on both."""
    rng = np.random.default_rng(n)
    lam, Q0, M0 = problems._problem(n, 0)
    gen = problems._plain_field(lam)
    for name in problems._lean_candidates(n):
        f = problems.LEAN_VARIANTS[name](lam)
        for _ in range(5):
            Q = symrb.random_SO(n, seed=rng)
            M = symrb.random_so(n, seed=rng) * 3
            want = gen(0.0, np.concatenate((Q.ravel(), M.ravel())))
            dQ, dM = problems._from_lean(f(0.0, problems._to_lean(Q, M, name)), n, name)
            got = np.concatenate((dQ.ravel(), dM.ravel()))
            assert np.abs(got - want).max() <= 1e-14 * max(1.0, np.abs(want).max()), name
        a = problems._solve_ivp_end(lam, Q0, M0, 3.0, "DOP853", 1e-11, name)()
        b = problems._solve_ivp_end(lam, Q0, M0, 3.0, "DOP853", 1e-11)()
        assert max(np.abs(a[0] - b[0]).max(), np.abs(a[1] - b[1]).max()) < 1e-8, name
    assert (
        problems._lean_candidates(3)[0].startswith("n3") and len(problems._lean_candidates(4)) == 1
    )


def test_the_lean_field_chosen_is_recorded_with_both_sizes(tiny: bench.BenchResult) -> None:
    w = tiny.measurements["work-precision"]["n3"][0]
    base = w["baselines"]
    assert base["variant"] in problems._lean_candidates(3)
    assert (base["unknowns"], base["generated_unknowns"]) in ((12, 18), (18, 18))
    assert all(d <= 1e-13 for d in base["max_difference_from_generated"].values())


# ---------------------------------------------------------------------------------------------
# the sections of issue 23


def test_issue23_sections_record_their_fields(tiny: bench.BenchResult) -> None:
    ms = tiny.measurements
    sc = ms["step-costs"]
    assert sc["one_call"]["cpu"]["median"] > 0 and sc["one_call"]["profile"]
    assert set(sc["paper"]) == {"mv_flow", "mv_algorithm2", "symmetric_flow"}
    same = sc["paper_same_length"]  # whole runs of one length, beside the marginal costs
    assert set(same) == {"K", "mv_flow", "mv_algorithm2", "symmetric_flow"}
    assert same["K"] == sc["paper"]["mv_algorithm2"]["K"][1]
    assert all(isinstance(d["reliable"], bool) for d in sc["paper"].values())
    st = sc["stages"]["3"]["methods"]
    assert st["MV-comp8"]["stages"] == 17 and st["RKMK4"]["stages"] == 4
    assert st["midpoint"]["stages"] == 1
    assert "available" in sc["n10_compiled"]
    lh = ms["long-horizon"]
    assert lh["n"] == 10 and {r["method"] for r in lh["runs"]} >= {"DOP853", "MV-fast"}
    for r in lh["runs"]:
        assert "skipped" in r or (r["cpu"] > 0 and r["energy"] < 1e-5)
    cs = ms["cold-start"]
    assert not cs["available"] or (len(cs["cpu"]) == 1 and cs["median_cpu"] > 0)
    thr = ms["throughput"]
    assert set(thr["matmul"]) == {"matmul", "matmul_soa"}
    assert all("matmul_soa" in r for r in thr["rows"])


def test_previous_goals_are_kept_from_the_file_a_run_overwrites(tmp_path: Path) -> None:
    from benchmarks.harness.result import previous_goals

    old = bench.BenchResult(machine={}, parameters={}, goals=[
        {"name": "a", "measured": 2.0, "target": "<= 1", "met": False, "note": ""}])  # fmt: skip
    path = old.write_json(tmp_path / "bench.json")
    assert previous_goals(path) == [{"name": "a", "measured": 2.0, "met": False}]
    assert previous_goals(tmp_path / "none.json") == []
    res = bench.run(quick=True, sections=["cost-vs-n"], progress=False, checkpoint=path,
                    config={"cost_n": (3,), "rounds": 1, "min_time": 0.001})  # fmt: skip
    assert res.previous_goals == [{"name": "a", "measured": 2.0, "met": False}]


# ---------------------------------------------------------------------------------------------
# the command line


def test_cli_help_and_usage_errors(capsys: pytest.CaptureFixture[str]) -> None:
    assert launcher.main(["bench", "--help"]) == 0
    out = capsys.readouterr().out
    assert "exit status:" in out and "--quick" in out
    assert launcher.main(["bench", "--bogus"]) == 2
    assert launcher.main(["bench", "--only", "nonsense"]) == 2
    assert "sections must be among" in capsys.readouterr().err
    assert launcher.main(["bench", "--verify-json", "/nonexistent/verify.json"]) == 2
    assert launcher.main(["--help"]) == 0
    assert "bench [--quick]" in capsys.readouterr().out


def test_cli_runs_and_writes_json(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(runner, "_QUICK", dict(config._QUICK, **TINY))
    path = tmp_path / "out.json"
    argv = ["bench", "--quick", "--only", "cost-vs-n", "--no-progress", "--json", str(path)]
    assert launcher.main(argv) == 0
    out = capsys.readouterr().out
    assert "n = 3 single MV step" in out and f"wrote {path}" in out
    assert json.loads(path.read_text())["parameters"]["sections"] == ["cost-vs-n"]


def test_cli_strict_exits_1_on_an_unmet_goal(monkeypatch: pytest.MonkeyPatch) -> None:
    def fake(met: bool | None):
        def run(**_kw: Any) -> bench.BenchResult:
            res = bench.BenchResult(machine={}, parameters={})
            res.goals = [goals._goal("g", 1.0, "<= 0", met, "")]
            return res

        return run

    for met, plain, strict in ((False, 0, 1), (True, 0, 0), (None, 0, 0)):
        monkeypatch.setattr(bench_cli, "run", fake(met))
        assert launcher.main(["bench", "--no-progress"]) == plain
        assert launcher.main(["bench", "--no-progress", "--strict"]) == strict


def test_bench_needs_neither_sympy_nor_the_derivations() -> None:
    code = (
        "import sys; sys.modules['sympy'] = None; sys.modules['derivations'] = None\n"
        "sys.modules['derivations.cli'] = None\n"
        "from symrb.cli import main\n"
        "assert main(['bench', '--help']) == 0\n"
        "assert main(['bench', '--bogus']) == 2\n"
        "import benchmarks.harness\n"
        "r = benchmarks.harness.run(quick=True, sections=['cost-vs-n'], progress=False,\n"
        "                           config={'cost_n': (3,), 'rounds': 1, 'min_time': 0.001})\n"
        "assert r.measurements['cost-vs-n']['rows'][0]['n'] == 3\n"
    )
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, env=env
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_bench_without_the_harness_exits_2_and_says_why() -> None:
    """In a wheel there is no ``benchmarks`` package: ``symrb bench`` says it needs a checkout."""
    code = (
        "import sys; sys.modules['benchmarks'] = None\n"
        "from symrb.cli import main\n"
        "sys.exit(main(['bench', '--quick']))\n"
    )
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, env=env
    )
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert "source checkout" in proc.stderr and "pip install -e '.[bench]'" in proc.stderr


def test_committed_results_carry_no_path_of_the_machine() -> None:
    """Benchmark results in the repository name files, never where they were on the machine."""
    import re
    from pathlib import Path

    results = Path(__file__).resolve().parents[1] / "benchmarks" / "results"
    for f in sorted(results.glob("*.json")):
        hits = re.findall(r"(?:/root/|/home/|/work/|/tmp/|[A-Z]:\\\\)[^\s\"]*", f.read_text())
        assert not hits, f"{f.name}: {hits[:3]}"
