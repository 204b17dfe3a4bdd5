"""Scenes of the rigid-body pages: several second runs (``[[compare]]``), a second run in a
rotated frame or shifted by whole steps, MV-Algorithm 1 and MV-Algorithm 2 with the paper's
indices, an adaptive run compared with a fixed-step one, and the operator norm of the symmetric
rigid body (``op_norm``, ``start = "boundary"``).

Each scene run is compared with the hand-written calls of the public functions on the same
inputs, bit for bit, and the book's scenes with the experiments they replace."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import replaced_experiments as discrete_experiments
import replaced_experiments as smooth_experiments
from scene_helpers import problems as _problems
from scene_helpers import same as _same

import symrb
from symrb.scenes import (
    SceneResult,
    SceneStore,
    load_scene,
    parse_scene,
    run_scene,
    scene_inputs,
    sweep,
)

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "book" / "scenes"
LAM3 = [0.7, 1.1, 1.6]


def _gap(a, b):
    return np.abs(a - b).max(axis=(-2, -1))


def _windows(values, w):
    """The largest value in each numpy.array_split block (the scenes' reduce = "max")."""
    return np.stack([np.max(b, axis=0) for b in np.array_split(np.asarray(values), w)])


def _agreement(integrator, compare, observables, T=40.0, **params):
    """The rigid body of the agreement scenes (n = 3, h = 1) with the given second runs."""
    return parse_scene({
        "system": "rigid_body", "effects": ["attitude"],
        "parameters": {"n": 3, "lam": LAM3, "seed": 0, "momentum": 0.1, "Q0": "random",
                       **params},
        "integrator": integrator, "horizon": {"T": T}, "observables": observables,
        "compare": compare,
    })  # fmt: skip


SYM = {"method": "discrete", "h": 1.0}
MV2_PAPER = {"method": "mv_algorithm2", "h": 1.0, "start": "Q1_M1"}
MV2 = {"method": "mv_algorithm2", "h": 1.0}
MV1 = {"method": "mv_algorithm1", "h": 1.0}


# ---------------------------------------------------------------------------------------------
# the agreement of the three algorithms (book/section2/04_moser_veselov_runs.md)


def test_three_second_runs_equal_hand_written_calls() -> None:
    # the index conventions of algorithm_agreement, written out: MV-Algorithm 2 from (Q_1, M_1)
    # of the symmetric run, the symmetric run in a rotated frame, MV-Algorithm 2 from
    # (Q_0, M_1) read one step later; M_{k+1} of MV-Algorithm 2 against M_k of the symmetric run
    N = 40
    sc = _agreement(SYM, [{"integrator": MV2_PAPER}, {"integrator": SYM, "rotation": 4},
                          {"integrator": MV2, "shift": 1}],
                    {"Q_gap": {"every": 1}, "M_gap": {"every": 1}, "M": {"times": [0.0]}})  # fmt: skip
    r = run_scene(sc, cache=False)
    x = scene_inputs(sc)
    Q0, M0, lam = x["Q0"], x["M0"], x["lam"]
    P0 = Q0 @ (0.5 * M0)
    sym = symrb.symmetric_flow(Q0, P0, lam, 1.0, N)
    Qs, Ms = sym.y.Q, sym.y.M
    M1 = symrb.symmetric.symmetric_momentum(Q0, P0)
    mv2 = symrb.mv_algorithm2(Qs[1], M1, lam, N)  # N steps: M_{N+1} is the momentum at t_N
    R = symrb.random_SO(3, seed=4)
    sym_r = symrb.symmetric_flow(R @ Q0, R @ P0, lam, 1.0, N)
    wrong = symrb.mv_algorithm2(Q0, 1.0 * M0, lam, N - 1)
    # the shifted run has no step to compare with step 0: every column starts at step 1
    _same(r.times["Q_gap"], np.arange(1.0, N + 1))
    _same(r["Q_gap"][:, 0], _gap(mv2.y.Q[:N], Qs[1:]))
    _same(r["Q_gap"][:, 1], _gap(R.T @ sym_r.y.Q[1:], Qs[1:]))
    _same(r["Q_gap"][:, 2], _gap(wrong.y.Q, Qs[1:]))
    _same(r["M_gap"][:, 0], _gap(mv2.y.M[1:], Ms[1:]))
    _same(r["M_gap"][:, 1], _gap(sym_r.y.M[1:], Ms[1:]))  # the rotated run's own momenta
    _same(r["M_gap"][:, 2], _gap(wrong.y.M, Ms[1:]))
    _same(r["M"], M1[None])
    assert r["Q_gap"][:, :2].max() < 1e-13 < 1e-3 < r["Q_gap"][:, 2].min()
    plan = r.plan
    assert isinstance(plan.compare, tuple) and len(plan.compare) == 3
    assert plan.compare[0].save == {"steps": N, "save_every": 1}
    assert plan.compare[2].save == {"steps": N - 1, "save_every": 1}  # shifted: one step less
    assert "symmetric_flow(R Q0, R P0, h=1)" in plan.compare[1].route
    assert plan.index["Q_gap"] == tuple(range(1, N + 1)) and plan.index["M"] == (0,)
    text = plan.explain()
    assert "3 second runs (one column each)" in text and "random_SO(3, seed=4)" in text
    assert "Q_gap: recorded from step 1 on" in text


def test_mv_algorithm1_scene_equals_hand_written_calls() -> None:
    N = 40
    sc = _agreement(MV1, [{"integrator": MV2_PAPER}, {"integrator": MV1, "rotation": 4}],
                    {"Q_gap": {"every": 1}, "Q": {"every": 5}, "orthogonality": "end"})  # fmt: skip
    r = run_scene(sc, cache=False)
    x = scene_inputs(sc)
    Q0, M0, lam = x["Q0"], x["M0"], x["lam"]
    sym = symrb.symmetric_flow(Q0, Q0 @ (0.5 * M0), lam, 1.0, 1)  # Q_1: the first step
    M1 = symrb.symmetric.symmetric_momentum(Q0, Q0 @ (0.5 * M0))
    mv1 = symrb.mv_algorithm1(Q0, sym.y.Q[1], lam, N - 1)
    mv2 = symrb.mv_algorithm2(sym.y.Q[1], M1, lam, N - 1)  # Q only: N - 1 steps from Q_1
    R = symrb.random_SO(3, seed=4)
    mv1_r = symrb.mv_algorithm1(R @ Q0, R @ sym.y.Q[1], lam, N - 1)
    _same(r["Q"], mv1.y.Q[::5])
    _same(r.times["Q_gap"], np.arange(N + 1.0))
    _same(r["Q_gap"][:, 0], _gap(mv1.y.Q, np.concatenate([Q0[None], mv2.y.Q])))
    _same(r["Q_gap"][:, 1], _gap(R.T @ mv1_r.y.Q, mv1.y.Q))
    Q = mv1.y.Q[-1]
    _same(r["orthogonality"], [np.abs(Q.T @ Q - np.eye(3)).max()])
    assert r["Q_gap"][0, 0] == 0.0  # both start at Q_0 itself
    plan = r.plan
    assert plan.propagated == ("Q",) and ("M", "MV-Algorithm 1 carries configurations only") in \
        plan.skipped  # fmt: skip
    assert "mv_algorithm1(Q0, Q1, lam, steps - 1)" in plan.route
    assert "mv_algorithm2(Q1, M1, lam, steps - 1)" in plan.compare[0].route
    assert "(R Q0, R Q1), then R^T Q" in plan.compare[1].route


@pytest.mark.parametrize("integrator", [
    {"method": "discrete", "h": 0.5},
    {"method": "mv", "h": 0.5},
    {"method": "mv_algorithm2", "h": 0.5},
    {"method": "mv_algorithm2", "h": 0.5, "start": "Q1_M1"},
    {"method": "mv_algorithm1", "h": 0.5},
    {"method": "DOP853", "rtol": 1e-12, "atol": 1e-14},
], ids=lambda i: i["method"] + i.get("start", ""))  # fmt: skip
def test_a_run_in_a_rotated_frame_is_rotated_back(integrator) -> None:
    # the equations are invariant under Q -> R Q: each integrator against itself in the frame of
    # R differs by its rounding (or its tolerance); a run started unrotated but rotated back
    # (or rotated but not back) is off by |R - I|, about 1.5 here; one neither rotated nor
    # rotated back would give exactly 0, which the lower bound refuses
    sc = _agreement(integrator, {"integrator": integrator, "rotation": 4},
                    {"Q_gap": {"points": 11}}, T=10.0, momentum=1.0)  # fmt: skip
    gap = run_scene(sc, cache=False)["Q_gap"]
    tol = 1e-9 if integrator["method"] == "DOP853" else 1e-12
    assert 0.0 < gap.max() < tol, gap.max()


@pytest.mark.parametrize("observables", [
    {"Q": {"every": 3}, "M": {"every": 3}},  # Q_k is the (k-1)-th state: every step is saved
    {"M": {"every": 3}, "energy": "end"},    # momenta only: saved every third step
])  # fmt: skip
def test_mv_algorithm2_from_the_first_step_every_k_steps(observables) -> None:
    N, h = 30, 0.5
    sc = _agreement(
        {"method": "mv_algorithm2", "h": h, "start": "Q1_M1"}, None, observables, T=N * h
    )
    r = run_scene(sc, cache=False)
    x = scene_inputs(sc)
    # Q_1 of the symmetric first step; M_1 = h (Q0^T P0 - P0^T Q0), P0 = Q0 M0 / 2 (D12)
    Q1 = symrb.discrete_rigid_body_flow(x["Q0"], x["M0"], x["lam"], h, 1).y.Q[1]
    M1 = h * symrb.symmetric.symmetric_momentum(x["Q0"], x["Q0"] @ (0.5 * x["M0"]))
    save = 1 if "Q" in observables else 3
    run = symrb.mv_algorithm2(Q1, M1, x["lam"], N, save_every=save)
    M = run.y.M[np.arange(0, N + 1, 3) // save] / h  # M_{k+1} / h at t_k, k = 0, 3, ..., N
    _same(r["M"], M)
    _same(r.times["M"], np.arange(0, N + 1, 3) * h)
    if "Q" in observables:
        _same(r["Q"], np.concatenate([x["Q0"][None], run.y.Q])[: N + 1 : 3])
        assert "saves every step" in " ".join(r.plan.notes)
    else:
        _same(r["energy"], symrb.kinetic_energy(M[-1:], x["lam"]))
        assert r.plan.save == {"steps": N, "save_every": 3}


def test_the_agreement_scenes_give_the_experiments_windows() -> None:
    # the book's scenes with the experiment's draws (Q0, then M, then R from default_rng(0)):
    # the windows of algorithm_agreement, bit for bit, but for the run one index off
    steps, w = 300, 6
    rng = np.random.default_rng(0)
    Q0 = symrb.random_SO(3, seed=rng)  # the scene draws it from seed 0 (no M0 drawn first)
    M = symrb.random_so(3, seed=rng, scale=0.05)
    R = symrb.random_SO(3, seed=rng)
    run = discrete_experiments.algorithm_agreement(steps=steps, windows=w)
    sym, mv1 = (load_scene(SCENES / f"agreement_{name}.toml") for name in ("symmetric", "mv1"))
    got = {}
    for base in (sym, mv1):
        data = base.model_dump(mode="json", exclude_unset=True)
        data["parameters"] |= {"M0": M.tolist()}
        data["parameters"].pop("momentum")
        data["horizon"]["T"] = float(steps)
        for cmp in data["compare"]:
            cmp["rotation"] = R.tolist() if "rotation" in cmp else None
        for when in data["observables"].values():
            if isinstance(when, dict) and "windows" in when:
                when["windows"] = w
        r = run_scene(data, cache=False)
        got[base.integrator.method] = r
    a, b = got["discrete"], got["mv_algorithm1"]
    _same(a.times["Q_gap"], run.window_k * 1.0)  # times k h, h = 1
    _same(b.times["Q_gap"], run.window_k * 1.0)
    _same(a["Q_gap"][:, 0], run.window["sym_mv2"])
    _same(a["Q_gap"][:, 1], run.window["spread_sym"])
    _same(b["Q_gap"][:, 0], run.window["mv1_mv2"])
    _same(b["Q_gap"][:, 1], run.window["spread_mv1"])
    # MV-Algorithm 2 one index off starts from h M0 here, from Q0^T P0 - P0^T Q0 there: the
    # same matrix to rounding, so the two runs part at the rounding level of the algorithm
    np.testing.assert_allclose(a["Q_gap"][:, 2], run.window["wrong_index"], rtol=1e-11)
    assert np.abs(a["Q_gap"][:, 2] - run.window["wrong_index"]).max() < steps * np.finfo(float).eps
    # the experiment's relative momentum gap: divided by the size of M_1 = Q0^T P0 - P0^T Q0
    M1 = symrb.symmetric.symmetric_momentum(Q0, Q0 @ (0.5 * M))
    _same(a["M_gap"][:, 0] / np.abs(M1).max(), run.window["momentum"])
    # the discretisation error: the experiment's reference starts from M_1 (= M0 to rounding)
    early = load_scene(SCENES / "agreement_discretisation.toml").model_dump(
        mode="json", exclude_unset=True
    )
    early["parameters"] |= {"M0": M.tolist()}
    disc = run_scene(early, cache=False)
    np.testing.assert_allclose(disc["Q_gap"].max(), run.discretisation_error, rtol=1e-11)


def test_discretisation_scene_equals_hand_written_calls() -> None:
    sc = load_scene(SCENES / "agreement_discretisation.toml")
    r = run_scene(sc, cache=False)
    x = scene_inputs(sc)
    ts = np.arange(51.0)
    ref = symrb.integrate(symrb.RigidBody, (0.0, 50.0), {"Q": x["Q0"], "M": x["M0"]},
                          lam=x["lam"], method="DOP853", rtol=1e-12, atol=1e-12, t_eval=ts)  # fmt: skip
    run = symrb.discrete_rigid_body_flow(x["Q0"], x["M0"], x["lam"], 1.0, 50)
    _same(r["Q_gap"], _gap(run.y.Q, ref.y.Q))
    _same(r.times["Q_gap"], ts)
    assert r.plan.compare.save == {"t_eval": list(ts)}
    assert 1e-5 < r["Q_gap"].max() < 1e-2  # O(h^2) at h = 1, |M| = 0.1


# ---------------------------------------------------------------------------------------------
# an adaptive run against a fixed-step one (book/section2/04_moser_veselov_runs.md, second order)


def test_second_order_sweep_equals_hand_written_runs() -> None:
    hs = [0.1, 0.05, 0.025]
    out = sweep(SCENES / "second_order.toml", {"integrator.h": hs}, cache=False)
    x = scene_inputs(load_scene(SCENES / "second_order.toml"))
    ref = symrb.integrate(symrb.RigidBody, (0.0, 2.0), {"Q": x["Q0"], "M": x["M0"]},
                          lam=x["lam"], method="DOP853", rtol=1e-13, atol=1e-13, t_eval=[2.0])  # fmt: skip
    errors = []
    for h, r in zip(hs, out.results, strict=True):
        N = round(2.0 / h)
        run = symrb.discrete_rigid_body_flow(x["Q0"], x["M0"], x["lam"], h, N, save_every=N)
        _same(r["Q_gap"], _gap(run.y.Q[-1:], ref.y.Q))
        _same(r["M_gap"], _gap(run.y.M[-1:], ref.y.M))
        assert r.plan.save == {"steps": N, "save_every": N}
        assert r.plan.compare.save == {"t_eval": [2.0]}
        errors.append(r["Q_gap"][0])
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all(np.abs(ratios - 4) < 0.1)


def _mixed(main, other, observables, T=2.0):
    return {"system": "rigid_body", "effects": ["attitude"], "parameters": {"n": 3, "seed": 1},
            "integrator": main, "horizon": {"T": T}, "observables": observables,
            "compare": {"integrator": other}}  # fmt: skip


def test_adaptive_and_fixed_step_runs_compare_at_common_times() -> None:
    fixed, adaptive = {"method": "discrete", "h": 0.25}, {"method": "DOP853", "rtol": 1e-11}
    obs = {"Q_gap": {"times": [0.5, 1.0, 2.0]}, "M_gap": {"points": 5}}
    t_eval = [0.0, 0.5, 1.0, 1.5, 2.0]
    for main, other in [(fixed, adaptive), (adaptive, fixed)]:
        sc = parse_scene(_mixed(main, other, obs))
        r = run_scene(sc, cache=False)
        x = scene_inputs(sc)
        cont = symrb.integrate(symrb.RigidBody, (0.0, 2.0), {"Q": x["Q0"], "M": x["M0"]},
                               lam=x["lam"], rtol=1e-11, atol=1e-12, t_eval=t_eval)  # fmt: skip
        disc = symrb.discrete_rigid_body_flow(x["Q0"], x["M0"], x["lam"], 0.25, 8, save_every=2)
        pick = [1, 2, 4]  # t = 0.5, 1, 2
        _same(r["Q_gap"], _gap(disc.y.Q[pick], cont.y.Q[pick]))
        _same(r["M_gap"], _gap(disc.y.M, cont.y.M))
        plans = (r.plan, r.plan.compare)
        assert {"t_eval": t_eval} in [p.save for p in plans]
        assert {"steps": 8, "save_every": 2} in [p.save for p in plans]


# ---------------------------------------------------------------------------------------------
# the operator norm of the symmetric rigid body (book/section3/02c_norm_casimir.md, S11)


def test_norm_conservation_scenes_equal_the_experiment() -> None:
    T, radii = 2.0, [0.5, 1.99]
    short = {"horizon.T": [T]}
    base = load_scene(SCENES / "norm_conservation.toml").model_dump(mode="json", exclude_unset=True)
    base["observables"] = {"op_norm": {"points": 301}}
    out = sweep(base, {**short, "parameters.op_norm": radii}, cache=False)
    edge = load_scene(SCENES / "norm_conservation_boundary.toml").model_dump(
        mode="json", exclude_unset=True
    )
    edge["observables"] = base["observables"]
    edge["horizon"]["T"] = T
    on_C = run_scene(edge, cache=False)
    run = smooth_experiments.norm_conservation(radii=radii, T=T)
    for i, res in enumerate([*out.results, on_C]):
        norms = res["op_norm"]
        _same(np.abs(norms - norms[0]), run.deviation[i])
    _same(on_C["op_norm"][0], run.initial_norms[-1])
    # by hand: Q0 from seed 2, P0 = P_from_M(Q0, M0 scaled to the operator norm), or Q0 A
    Q0 = symrb.random_SO(4, seed=2)
    M = symrb.random_so(4, seed=7)
    A = np.eye(4)
    A[:2, :2] = [[0.0, -1.0], [1.0, 0.0]]
    A[2:4, 2:4] = [[0.6, -0.8], [0.8, 0.6]]
    starts = [symrb.symmetric.P_from_M(Q0, M * (r / np.linalg.norm(M, 2))) for r in radii] + [
        Q0 @ A
    ]
    ts = np.linspace(0.0, T, 301)
    for P0, res in zip(starts, [*out.results, on_C], strict=True):
        sol = symrb.integrate(symrb.SymmetricRigidBody, (0.0, T), {"Q": Q0, "P": P0},
                              lam=[0.5, 1.0, 1.5, 2.0], rtol=1e-12, atol=1e-12, t_eval=ts)  # fmt: skip
        _same(res["op_norm"], np.linalg.norm(sol.y.M, 2, axis=(-2, -1)))
    x = scene_inputs(parse_scene(edge))
    _same(x["P0"], x["Q0"] @ A)
    assert abs(np.linalg.norm(x["M0"], 2) - 2.0) < 1e-14


def test_windowed_operator_norm_equals_array_split_of_the_series() -> None:
    sc = load_scene(SCENES / "norm_conservation.toml")
    r = run_scene(sc, cache=False)
    x = scene_inputs(sc)
    ts = np.linspace(0.0, 30.0, 301)
    sol = symrb.integrate(symrb.SymmetricRigidBody, (0.0, 30.0), {"Q": x["Q0"], "P": x["P0"]},
                          lam=x["lam"], rtol=1e-12, atol=1e-12, t_eval=ts)  # fmt: skip
    norms = np.linalg.norm(sol.y.M, 2, axis=(-2, -1))
    _same(r["op_norm"], _windows(np.abs(norms - norms[0]), 15))
    _same(r.times["op_norm"], ts[20::20])  # windows of length 2: t = 2, 4, ..., 30
    assert abs(np.linalg.norm(x["M0"], 2) - 0.5) < 1e-15
    assert r["op_norm"].max() < 1e-9
    assert "op_norm" not in r.plan.skipped[0][0]


# ---------------------------------------------------------------------------------------------
# a rotated frame, shapes, the cache, the user's input


def test_rotated_symmetric_rigid_body_and_its_own_momenta() -> None:
    R = symrb.random_SO(4, seed=9)
    sc = parse_scene({
        "system": "symmetric_rigid_body", "parameters": {"n": 4, "seed": 3, "Q0": "random"},
        "integrator": {"kind": "continuous", "rtol": 1e-9, "atol": 1e-12},
        "horizon": {"T": 2.0}, "observables": {"Q_gap": {"points": 5}, "M_gap": {"points": 5}},
        "compare": [{"integrator": {"kind": "continuous", "rtol": 1e-9, "atol": 1e-12},
                     "rotation": R.tolist()}],
    })  # fmt: skip
    r = run_scene(sc, cache=False)
    x = scene_inputs(sc)
    kw = dict(lam=x["lam"], rtol=1e-9, atol=1e-12, t_eval=np.linspace(0, 2.0, 5))
    a = symrb.integrate(symrb.SymmetricRigidBody, (0, 2.0), {"Q": x["Q0"], "P": x["P0"]}, **kw)
    b = symrb.integrate(symrb.SymmetricRigidBody, (0, 2.0),
                        {"Q": R @ x["Q0"], "P": R @ x["P0"]}, **kw)  # fmt: skip
    assert r["Q_gap"].shape == (5, 1)  # an array of one [[compare]] table: one column
    _same(r["Q_gap"][:, 0], _gap(a.y.Q, R.T @ b.y.Q))
    _same(r["M_gap"][:, 0], _gap(a.y.M, symrb.symmetric.symmetric_momentum(b.y.Q, b.y.P)))
    assert r["Q_gap"].max() < 1e-6


def test_a_cached_result_with_several_second_runs_loads_as_computed(tmp_path) -> None:
    data = {
        "system": "rigid_body", "effects": ["attitude"],
        "parameters": {"n": 3, "lam": LAM3, "seed": 0, "Q0": "random", "momentum": 0.1},
        "integrator": SYM, "horizon": {"T": 12.0},
        "observables": {"Q_gap": {"every": 2, "windows": 3, "reduce": "max"}},
        "compare": [{"integrator": MV2_PAPER, "label": "paper"},
                    {"integrator": MV2, "shift": 2, "rotation": 1}],
    }  # fmt: skip
    given = copy.deepcopy(data)
    store = SceneStore(tmp_path)
    a = run_scene(data, cache=store)
    b = run_scene(data, cache=store)
    assert data == given  # nothing the user gave is changed
    assert (a.meta["from_cache"], b.meta["from_cache"], len(store.log())) == (False, True, 1)
    _same(a["Q_gap"], b["Q_gap"])
    c = SceneResult.load(store.path(a.meta["key"]))  # the stored scene planned again
    assert c.plan.explain() == a.plan.explain() and c.plan.compare[0].title == "paper"
    # shift 2 with every 2: the gaps start at the second record (step 2)
    assert a.plan.index["Q_gap"] == (1, 2, 3, 4, 5, 6)
    assert a.plan.compare[1].save == {"steps": 10, "save_every": 2}
    assert a["Q_gap"].shape == (3, 2)


# ---------------------------------------------------------------------------------------------
# requests the runs cannot meet, and bad keys: the key, its line and what is allowed

BASE = """\
system = "rigid_body"
effects = ["attitude"]
[parameters]
n = 3
[integrator]
method = "discrete"
h = 0.5
[horizon]
T = 5.0
[observables]
Q_gap = {every = 2}
"""


@pytest.mark.parametrize(
    ("extra", "key", "line", "allowed"),
    [
        # every k steps has no counterpart in an adaptive run (both ways round)
        ("[compare]\nintegrator = {method = 'DOP853'}\n", "observables.Q_gap.every", 11,
         ["end", "times", "points"]),
        ("[[compare]]\nintegrator = {method = 'discrete', h = 0.5}\n[[compare]]\n"
         "integrator = {method = 'DOP853'}\n", "observables.Q_gap.every", 11,
         ["end", "times", "points"]),
        ("[compare]\nintegrator = {method = 'discrete', h = 0.25}\n", "compare.integrator.h", 13,
         [0.5]),
        ("[compare]\nintegrator = {method = 'DOP853'}\nshift = 1\n", "compare.shift", 14, [0]),
        ("[compare]\nintegrator = {method = 'discrete', h = 0.5}\nshift = 3\n", "compare.shift",
         14, [2, 4, 6]),
        ("[compare]\nintegrator = {method = 'discrete', h = 0.5}\nshift = 10\n", "compare.shift",
         14, None),
        ("[[compare]]\nintegrator = {method = 'discrete', h = 0.5}\n[[compare]]\n"
         "integrator = {method = 'mv', h = 0.5}\nrotation = [[1.0, 0.0], [0.0, 1.0]]\n",
         "compare.1.rotation", 16, None),
        ("[compare]\nintegrator = {method = 'discrete', h = 0.5}\n"
         "rotation = [[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]\n", "compare.rotation",
         14, None),
        ("[compare]\nintegrator = {method = 'mv_algorithm2', h = 0.5, start = 'Q2_M2'}\n",
         "compare.integrator.start", 13, ["Q0_M0", "Q1_M1"]),
        ("[compare]\nintegrator = {method = 'mv_algorithm1', h = 0.5}\nlable = 'x'\n",
         "compare.lable", 14, ["system", "integrator", "rotation", "shift", "label"]),
    ],
)  # fmt: skip
def test_second_run_requests_name_key_line_and_allowed(extra, key, line, allowed) -> None:
    problems = _problems(BASE + extra)
    p = next((q for q in problems if q["key"] == key), problems[0])
    assert (p["key"], p["line"]) == (key, line), problems
    assert p["allowed"] == allowed, p


def test_shift_needs_steps_and_mv_algorithm1_needs_no_momentum() -> None:
    shifted = BASE.replace("Q_gap = {every = 2}", "Q_gap = {times = [1.0, 2.0]}")
    (p,) = _problems(
        shifted + "[compare]\nintegrator = {method = 'discrete', h = 0.5}\nshift = 2\n"
    )
    assert (p["key"], p["line"], p["allowed"]) == ("observables.Q_gap", 11, ["end", "every"])
    mv1 = BASE.replace('method = "discrete"', 'method = "mv_algorithm1"')
    (p,) = _problems(mv1.replace("Q_gap = {every = 2}", "energy = 'end'\nQ = 'end'"))
    assert (p["key"], p["line"]) == ("observables.energy", 11)
    assert p["allowed"] == ["Q", "orthogonality", "Q_gap"]
    both = BASE.replace("Q_gap = {every = 2}", "Q_gap = 'end'\nM_gap = 'end'")
    (p,) = _problems(both + "[compare]\nintegrator = {method = 'mv_algorithm1', h = 0.5}\n")
    assert (p["key"], p["line"], p["allowed"]) == ("observables.M_gap", 12, ["Q_gap"])
    # a second run at times that are not steps of its own h: keyed as the scene's gap
    sc = _mixed({"method": "DOP853"}, {"method": "discrete", "h": 0.3},
                {"Q_gap": {"times": [0.5]}}, T=0.6)  # fmt: skip
    (p,) = _problems(parse_scene(sc))
    assert p["key"] == "observables.Q_gap.times" and "multiples of h" in p["message"]
    # a model built in Python, not through parse_scene, is checked by the planner
    built = parse_scene(_mixed({"method": "discrete", "h": 0.5}, {"method": "discrete", "h": 0.5},
                               {"Q_gap": "end"}))  # fmt: skip
    bad = built.model_copy(update={"compare": built.compare.model_copy(update={"shift": 4})})
    (p,) = _problems(bad)
    assert p["key"] == "compare.shift" and p["allowed"] is None


SYMMETRIC = """\
system = "symmetric_rigid_body"
[parameters]
n = 4
{params}
[integrator]
kind = "continuous"
[horizon]
T = 1.0
[observables]
op_norm = "end"
"""


@pytest.mark.parametrize(
    ("params", "message"),
    [
        ("op_norm = 2.0", "op_norm = 2 >= 2 has no costate"),
        ("op_norm = 1.0\nmomentum = 2.0", "momentum (the pairing norm) or op_norm"),
        ("start = 'boundary'\nM0 = [1.0, 2.0, 3.0]", "remove ['M0']"),
        ("start = 'boundary'\nop_norm = 1.0", "remove ['op_norm']"),
        ("start = 'rotations'\nQ0 = 'random'", "remove ['Q0']"),
    ],
)
def test_operator_norm_and_boundary_start_errors(params, message) -> None:
    (p,) = _problems(SYMMETRIC.format(params=params))
    assert p["key"] == "parameters" and p["line"] == 2 and message in p["message"], p


def test_op_norm_scales_a_given_or_drawn_momentum() -> None:
    M = [[0.0, -1.0, 2.0], [1.0, 0.0, -3.0], [-2.0, 3.0, 0.0]]
    for M0 in (M, None):
        params = {"n": 3, "lam": LAM3, "M0": M0, "op_norm": 1.5}
        sc = parse_scene({"system": "rigid_body", "parameters": params,
                          "integrator": {"method": "DOP853"}, "horizon": {"T": 1.0},
                          "observables": {"M": "end"}})  # fmt: skip
        x = scene_inputs(sc)
        raw = np.array(M) if M0 else symrb.random_so(3, seed=np.random.default_rng(0))
        _same(x["M0"], raw * (1.5 / np.linalg.norm(raw, 2)))
