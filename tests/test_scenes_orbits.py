"""Scenes of Sections 3.4-3.5: the Toda lattice (system ``toda``) and the orbit extremals'
observables (``pairing``, ``second_term``, ``db_distance``, ``db_second_term``,
``sample_pairings``; ``integrator.p_guess``, ``one_sample_ivp``; ``parameters.scale``).

A scene's arrays equal the hand-written calls of the public functions on the scene's inputs bit
for bit; the planner's decisions (the route, the extra runs, what is skipped) and the errors
(key, line, allowed values) are checked, and extra runs are counted."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
from scene_helpers import problem as _problem
from scene_helpers import same as _same

import symrb
from symrb import orbits as symrb_orbits
from symrb.scenes import (
    SceneStore,
    TodaScene,
    load_scene,
    parse_scene,
    plan_scene,
    run_scene,
    scene_inputs,
    sweep,
)
from symrb.scenes.systems import orbit_extremal as scenes_orbit_extremal

ROOT = Path(__file__).resolve().parents[1]
BOOK_SCENES = ROOT / "book" / "scenes"

EFFECTS = ["terminal_cost", "potential"]


def _norm(a: np.ndarray) -> np.ndarray:
    return np.sqrt(np.maximum(symrb.pairing(a, a), 0.0))


def _second(x: np.ndarray, N: np.ndarray) -> np.ndarray:
    return _norm(symrb.commutator(N, symrb.commutator(N, x)))


def _toda(observables=None, T=6.0, **params):
    return {
        "system": "toda",
        "parameters": {"k": 4, "seed": 3, **params},
        "integrator": {"kind": "continuous", "rtol": 1e-9, "atol": 1e-10},
        "horizon": {"T": T},
        "observables": observables or {"a": {"points": 7}},
    }


def _orbit(observables, effects=(), integrator=None, T=3.0, **params):
    return {
        "system": "orbit_extremal",
        "effects": EFFECTS + list(effects),
        "parameters": {"n": 3, "seed": 4, **params},
        "integrator": {"kind": "bvp", **(integrator or {})},
        "horizon": {"T": T},
        "observables": observables,
    }


@pytest.fixture
def db_calls(monkeypatch):
    """Count the calls of symrb.orbits.double_bracket_flow (the scenes import it at run time)."""
    calls: list[np.ndarray] = []
    original = symrb_orbits.double_bracket_flow

    def counted(x0, N, t, *args, **kwargs):
        calls.append(np.asarray(t))
        return original(x0, N, t, *args, **kwargs)

    monkeypatch.setattr(symrb_orbits, "double_bracket_flow", counted)
    return calls


# ---------------------------------------------------------------------------------------------
# the Toda lattice


def test_toda_scene_equals_toda_flow_and_numpy() -> None:
    sc = parse_scene(_toda({"a": {"points": 7}, "b": {"times": [1.0, 2.5]}, "L": "end",
                            "spectrum": {"points": 4}, "off_band": {"points": 7}}))  # fmt: skip
    r = run_scene(sc, cache=False)
    x = scene_inputs(sc)
    # the random draw the schema documents
    rng = np.random.default_rng(3)
    _same(x["a0"], rng.standard_normal(4))
    _same(x["b0"], rng.uniform(0.4, 1.0, 3))
    _same(x["L0"], np.diag(x["a0"]) + np.diag(x["b0"], 1) + np.diag(x["b0"], -1))
    t = np.unique(np.concatenate([np.linspace(0, 6.0, 7), [1.0, 2.5], np.linspace(0, 6.0, 4)]))
    _same(plan_scene(sc).save["t_eval"], t)
    L = symrb.toda_flow(x["a0"], x["b0"], t, rtol=1e-9, atol=1e-10)
    at = {s: np.searchsorted(t, s) for s in t}
    i7 = [at[s] for s in np.linspace(0, 6.0, 7)]
    i4 = [at[s] for s in np.linspace(0, 6.0, 4)]
    _same(r["a"], np.diagonal(L[i7], axis1=1, axis2=2))
    _same(r["b"], np.diagonal(L[[at[1.0], at[2.5]]], 1, axis1=1, axis2=2))
    _same(r.times["b"], [1.0, 2.5])
    _same(r["L"], L[-1:])
    _same(r["spectrum"], np.linalg.eigvalsh(L[i4])[:, ::-1])
    assert np.all(np.diff(r["spectrum"], axis=1) < 0)  # largest first
    _same(r["off_band"], [max(abs(Lk[0, 2]), abs(Lk[0, 3]), abs(Lk[1, 3]), abs(Lk[2, 0]),
                              abs(Lk[3, 0]), abs(Lk[3, 1])) for Lk in L[i7]])  # fmt: skip


def test_toda_scene_with_given_band_and_small_k() -> None:
    a, b = [0.5, -1.0, 0.2], [0.8, 0.6]
    sc = parse_scene({**_toda({"b": "end", "off_band": "end"}),
                      "parameters": {"k": 3, "a": a, "b": b}})  # fmt: skip
    x = scene_inputs(sc)
    _same(x["a0"], a)
    _same(x["b0"], b)
    r = run_scene(sc, cache=False)
    L = symrb.toda_flow(a, b, [6.0], rtol=1e-9, atol=1e-10)
    _same(r["b"], np.diagonal(L, 1, axis1=1, axis2=2))
    _same(r["off_band"], np.abs(L[:, [0, 2], [2, 0]]).max(axis=1))
    k2 = run_scene({**_toda({"off_band": {"points": 3}}), "parameters": {"k": 2}}, cache=False)
    _same(k2["off_band"], np.zeros(3))  # nothing off the band of a 2 x 2 matrix


def test_toda_plan_propagates_L_and_names_what_it_skips() -> None:
    plan = plan_scene(_toda({"a": {"points": 5}, "off_band": "end"}))
    assert plan.system == "toda" and plan.propagated == ("L",)
    assert plan.route.startswith("symrb.toda_flow(rtol=1e-09, atol=1e-10)")
    assert plan.kernels == ("adjoint_orbits.double_bracket_rhs",)
    assert {"scenes.plan", "scenes.systems.toda", "orbits", "_generated.adjoint_orbits"} <= set(
        plan.modules
    )
    # the diagnostic not asked for is named; the state variables L, b are not diagnostics
    assert plan.skipped == (("spectrum", plan.skipped[0][1]),)
    assert "not asked for" in plan.skipped[0][1]
    assert plan.index == {"a": (0, 1, 2, 3, 4), "off_band": (4,)}
    text = plan.explain()
    assert "toda_flow" in text and "off_band" in text


def test_toda_scene_is_cached_and_keeps_its_input(tmp_path: Path) -> None:
    data = _toda({"a": {"points": 3}, "spectrum": "end"})
    before = copy.deepcopy(data)
    store = SceneStore(tmp_path)
    first = run_scene(data, cache=store)
    again = run_scene(data, cache=store)
    assert data == before
    assert not first.meta["from_cache"] and again.meta["from_cache"]
    assert len(store.log()) == 1
    _same(again["a"], first["a"])
    _same(again["spectrum"], first["spectrum"])


def test_toda_scene_errors_name_key_line_and_allowed() -> None:
    text = """\
system = "toda"
[parameters]
k = 4
a = [1.0, 2.0, 3.0, 4.0]
b = [0.5, 0.5]
[integrator]
kind = "continuous"
[horizon]
T = 1.0
[observables]
a = "end"
"""
    p = _problem(text)
    assert (p["key"], p["line"]) == ("parameters.b", 5)
    assert "k - 1 = 3" in p["message"]
    good = text.replace("b = [0.5, 0.5]", "b = [0.5, 0.5, 0.5]")
    assert isinstance(load_scene(good), TodaScene)
    p = _problem(good.replace("b = [0.5, 0.5, 0.5]", "b = [0.5, 0.5, 0.5]\nseed = 1"))
    assert (p["key"], p["line"]) == ("parameters.seed", 6)
    p = _problem(good.replace("b = [0.5, 0.5, 0.5]\n", ""))
    assert p["key"] == "parameters" and "both a and b" in p["message"]
    p = _problem(good.replace('a = "end"', 'eigenvalues = "end"'))
    assert p["key"] == "observables.eigenvalues" and p["line"] == 11
    assert p["allowed"] == ["L", "a", "b", "spectrum", "off_band"]
    p = _problem(good.replace('kind = "continuous"', 'kind = "bvp"'))
    assert (p["key"], p["line"], p["allowed"]) == ("integrator.kind", 7, ["continuous"])
    p = _problem(good.replace("k = 4", "k = 1").replace("a = [1.0, 2.0, 3.0, 4.0]\n", "")
                 .replace("b = [0.5, 0.5, 0.5]\n", ""))  # fmt: skip
    assert (p["key"], p["line"]) == ("parameters.k", 3)
    p = _problem(_toda({"a": {"every": 2}}), "observables.a.every")
    assert p["allowed"] == ["end", "times", "points"]
    p = _problem(good.replace("[parameters]", 'effects = ["samples"]\n[parameters]'))
    assert p["key"] == "effects" and p["line"] == 2


# ---------------------------------------------------------------------------------------------
# orbit extremals: the new observables


@pytest.mark.parametrize("costate", ["corrected", "printed"])
def test_one_sample_bvp_scene_equals_solve_orbit_bvp(costate: str, db_calls) -> None:
    """one_sample_ivp = false solves the BVP (from p = 0) even for one sample; the observables
    equal solve_orbit_bvp + pairing/commutator, and db_distance the double bracket flow."""
    sc = parse_scene(_orbit(
        {"pairing": {"points": 5}, "second_term": {"points": 5}, "p": {"times": [1.5]},
         "db_distance": {"times": [0.75, 1.5]}},
        effects=["costates"],
        integrator={"costate": costate, "p_guess": "zero", "one_sample_ivp": False},
    ))  # fmt: skip
    plan = plan_scene(sc)
    assert "solve_orbit_bvp" in plan.route and "p_guess=0" in plan.route
    assert plan.propagated == ("x (1 sample)", "p (1 sample)", "x_db (1 own double bracket flow)")
    r = run_scene(sc, cache=False)
    assert r.meta["success"]
    assert len(db_calls) == 1
    x = scene_inputs(sc)
    x0, N = x["x0"], x["N"]
    t = np.array(plan.save["t_eval"])
    _same(t, [0.0, 0.75, 1.5, 2.25, 3.0])
    res = symrb.solve_orbit_bvp(x0, N, 3.0, costate=costate, p_guess=np.zeros((3, 3)))
    xs, ps = res.at(t)
    _same(r["pairing"], symrb.pairing(xs, N))
    _same(r["second_term"], _second(xs, N))
    _same(r["p"], ps[[2]])
    own = symrb_orbits.double_bracket_flow(x0, N, [0.75, 1.5])
    _same(db_calls[0], [0.75, 1.5])  # to the last time asked for (1.5 < T = 3), not beyond
    _same(r["db_distance"], _norm(xs[[1, 2]] - own[:, None]))
    assert r["pairing"].shape == (5, 1) and r["db_distance"].shape == (2, 1)
    # p is constant: -N (corrected) or +N (printed), from the guess 0
    sign = -1.0 if costate == "corrected" else 1.0
    assert np.abs(r["p"] - sign * N).max() < 1e-6
    if costate == "corrected":
        assert r["db_distance"].max() < 1e-6
    else:
        assert r["db_distance"].max() > 0.1


def test_two_sample_scene_equals_hand_written(db_calls) -> None:
    sc = parse_scene(_orbit(
        {"db_distance": {"times": [1.0, 2.0]}, "db_second_term": {"points": 3},
         "second_term": {"points": 3}, "sample_pairings": {"points": 5},
         "u": {"times": [2.0]}},
        effects=["samples"], integrator={"tol": 1e-5}, T=3.0,
        samples=2, seed=150, scale=0.5,
    ))  # fmt: skip
    r = run_scene(sc, cache=False)
    assert r.meta["success"]
    x = scene_inputs(sc)
    rng = np.random.default_rng(150)
    _same(x["N"], symrb.random_so(3, scale=0.5, seed=rng))  # N first, then the samples
    _same(x["x0"], symrb.random_so(3, (2,), scale=0.5, seed=rng))
    X0, N = x["x0"], x["N"]
    t = np.array(plan_scene(sc).save["t_eval"])
    _same(t, [0.0, 0.75, 1.0, 1.5, 2.0, 2.25, 3.0])
    res = symrb.solve_orbit_bvp(X0, N, 3.0, tol=1e-5)
    xs, ps = res.at(t)
    # one run per sample, at the union of the db_* times
    assert len(db_calls) == 2
    tdb = [0.0, 1.0, 1.5, 2.0, 3.0]
    own = np.stack([symrb_orbits.double_bracket_flow(X0[a], N, tdb) for a in range(2)], axis=1)
    _same(r["db_distance"], _norm(xs[[2, 4]] - own[[1, 3]]))
    _same(r["db_second_term"], _second(own[[0, 2, 4]], N))
    _same(r["second_term"], _second(xs[[0, 3, 6]], N))
    i5 = [0, 1, 3, 5, 6]
    _same(r["sample_pairings"], symrb.pairing(xs[i5][:, :, None], xs[i5][:, None, :]))
    _same(r["u"], np.sum(symrb.commutator(ps[[4]], xs[[4]]), axis=1))
    assert r["sample_pairings"].shape == (5, 2, 2)
    G = r["sample_pairings"]
    _same(G, np.swapaxes(G, 1, 2))
    assert np.abs(G - G[0]).max() < 1e-5  # conserved by the shared control


def test_extra_runs_only_when_asked_for(db_calls, monkeypatch) -> None:
    """Without db_* observables no double bracket flow is run beside the BVP, and a diagnostic
    not asked for is not evaluated."""
    base = _orbit({"pairing": "end"}, effects=["samples"], samples=2, T=1.0)
    plan = plan_scene(base)
    assert not any("x_db" in s for s in plan.propagated)
    assert ("each sample's own double bracket flow",
            "db_distance, db_second_term not asked for") in plan.skipped  # fmt: skip
    assert "db_distance, db_second_term, sample_pairings, second_term, u" in plan.skipped[0][0]

    def forbidden(*args, **kwargs):
        raise AssertionError("evaluated without being asked for")

    monkeypatch.setattr(scenes_orbit_extremal, "_second_term", forbidden)
    monkeypatch.setattr(scenes_orbit_extremal, "_pairing_norm", forbidden)
    r = run_scene(base, cache=False)
    assert db_calls == [] and set(r.data) == {"pairing"}
    with_db = plan_scene({**base, "observables": {"db_distance": "end"}})
    assert with_db.propagated[-1] == "x_db (2 own double bracket flows)"
    assert any("2 extra runs of symrb.double_bracket_flow" in n for n in with_db.notes)
    assert with_db.cost["seconds"] > plan.cost["seconds"]


def test_one_sample_initial_value_route_makes_no_extra_run(db_calls) -> None:
    sc = _orbit({"db_distance": {"points": 3}, "db_second_term": {"points": 3},
                 "second_term": {"points": 3}, "pairing": {"points": 3}})  # fmt: skip
    plan = plan_scene(sc)
    assert plan.propagated == ("x",) and "double_bracket_flow" in plan.route
    assert any("no extra run" in n for n in plan.notes)
    r = run_scene(sc, cache=False)
    assert len(db_calls) == 1  # the state itself
    x = scene_inputs(parse_scene(sc))
    xs = symrb_orbits.double_bracket_flow(x["x0"], x["N"], [0.0, 1.5, 3.0])[:, None]
    _same(r["pairing"], symrb.pairing(xs, x["N"]))
    _same(r["second_term"], _second(xs, x["N"]))
    _same(r["db_second_term"], r["second_term"])
    _same(r["db_distance"], np.zeros((3, 1)))  # the state is its own double bracket flow


def test_orbit_plan_choices_and_errors() -> None:
    one = _orbit({"x": "end"})
    # the known solution replaces the BVP unless one_sample_ivp = false
    ivp = plan_scene(one)
    assert ivp.propagated == ("x",)
    assert not any("BVP, not used" in n for n in ivp.notes)
    bvp = plan_scene({**one, "integrator": {"kind": "bvp", "one_sample_ivp": False}})
    assert bvp.propagated[0] == "x (1 sample)" and "p_guess" not in bvp.route
    assert any("one_sample_ivp = false" in n for n in bvp.notes)
    printed = plan_scene({**one, "integrator": {"kind": "bvp", "costate": "printed"}})
    assert "solve_orbit_bvp" in printed.route and "costate='printed'" in printed.route
    noted = plan_scene({**one, "integrator": {"kind": "bvp", "nodes": 21}})
    assert any("integrator.nodes: settings of the BVP, not used" in n for n in noted.notes)
    # a guess the initial value route cannot use
    p = _problem({**one, "integrator": {"kind": "bvp", "p_guess": "zero"}}, "one_sample_ivp")
    assert (p["key"], p["allowed"]) == ("integrator.p_guess", ["terminal"])
    p = _problem({**one, "integrator": {"kind": "bvp", "p_guess": "random"}})
    assert p["key"] == "integrator.p_guess" and p["allowed"] == ["terminal", "zero"]
    # sample_pairings needs the samples; scale needs something to draw
    text = """\
system = "orbit_extremal"
effects = ["terminal_cost", "potential"]
[parameters]
x0 = [1.0, 0.0, 0.0]
N = [0.0, 0.0, 1.0]
[integrator]
kind = "bvp"
[horizon]
T = 1.0
[observables]
sample_pairings = "end"
"""
    p = _problem(text)
    assert (p["key"], p["line"]) == ("observables.sample_pairings", 11)
    assert "samples" in p["message"] and "sample_pairings" not in p["allowed"]
    assert {"pairing", "second_term", "db_distance", "db_second_term"} <= set(p["allowed"])
    p = _problem(text.replace("[integrator]", "scale = 0.5\n[integrator]"))
    assert (p["key"], p["line"]) == ("parameters.scale", 6)
    p = _problem(text.replace('sample_pairings = "end"', "second_term = {every = 2}"))
    assert p["key"] == "observables.second_term.every"
    # the double bracket scene keeps its own observables
    p = _problem(
        {"system": "double_bracket", "integrator": {"kind": "continuous"}, "horizon": {"T": 1.0},
         "observables": {"second_term": "end"}}
    )  # fmt: skip
    assert p["key"] == "observables.second_term"


def test_scale_scales_the_random_draws() -> None:
    a = scene_inputs(parse_scene(_orbit({"x": "end"}, samples=2, effects=["samples"])))
    b = scene_inputs(parse_scene(_orbit({"x": "end"}, samples=2, effects=["samples"],
                                        scale=0.25)))  # fmt: skip
    _same(b["N"], symrb.random_so(3, scale=0.25, seed=np.random.default_rng(4)))
    np.testing.assert_allclose(b["x0"], 0.25 * a["x0"], rtol=1e-15)


# ---------------------------------------------------------------------------------------------
# the book's scenes


def test_book_orbit_scenes_plan_what_the_pages_check() -> None:
    toda = load_scene(BOOK_SCENES / "toda_lattice.toml")
    assert isinstance(toda, TodaScene)
    assert toda.parameters.k == 5 and toda.integrator.rtol == 1e-10
    one = plan_scene(load_scene(BOOK_SCENES / "orbit_one_sample.toml"))
    # the page's "the BVP converges to p = -N" needs the BVP, from p = 0, not the known answer
    assert "solve_orbit_bvp" in one.route and "p_guess=0" in one.route
    assert one.propagated[-1].startswith("x_db")
    two = plan_scene(load_scene(BOOK_SCENES / "orbit_two_samples_shared.toml"))
    assert two.propagated == ("x (2 samples)", "p (2 samples)", "x_db (2 own double bracket flows)")
    assert "recording p" in dict(two.skipped)


def test_book_one_sample_sweep_runs_both_signs_as_bvps(tmp_path: Path) -> None:
    out = sweep(BOOK_SCENES / "orbit_one_sample.toml",
                ["integrator.costate=corrected,printed"], cache=tmp_path)  # fmt: skip
    assert [r.scene.integrator.costate for r in out.results] == ["corrected", "printed"]
    assert all("solve_orbit_bvp" in r.plan.route for r in out.results)
    corrected, printed = out.results
    N = scene_inputs(corrected.scene)["N"]
    assert np.abs(corrected["p"] + N).max() < 1e-6 and np.abs(printed["p"] - N).max() < 1e-6
    # <x, N> falls with the corrected sign and rises with the printed one
    assert np.all(np.diff(corrected["pairing"][:, 0]) < 0)
    assert np.all(np.diff(printed["pairing"][:, 0]) > 0)
    again = sweep(BOOK_SCENES / "orbit_one_sample.toml",
                  ["integrator.costate=corrected,printed"], cache=tmp_path)  # fmt: skip
    assert list(again.table["from_cache"]) == [True, True]
