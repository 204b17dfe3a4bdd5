"""Scenes: the schema's errors, the planner's choices, equality with hand-written calls, the
cache, and sweeps in-process and on a real Dask LocalCluster."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from scene_helpers import problem as _problem
from scene_helpers import same as _same

import symrb
from symrb import scenes
from symrb.scenes import (
    RigidBodyMomentum,
    SceneError,
    SceneStore,
    load_scene,
    parse_scene,
    plan_scene,
    run_scene,
    scene_inputs,
    sweep,
)
from symrb.scenes import run as scenes_run
from symrb.scenes import store as scenes_store

ROOT = Path(__file__).resolve().parents[1]
BOOK_SCENES = sorted((ROOT / "book" / "scenes").glob("*.toml"))

BASE = """\
title = "test"
system = "rigid_body"
effects = ["attitude"]

[parameters]
n = 4
seed = 3

[integrator]
method = "DOP853"
rtol = 1e-9

[horizon]
T = 5.0

[observables]
energy = {points = 6}
Q = "end"
"""


def _rb(n=4, effects=(), integrator=None, T=5.0, observables=None, **params):
    return parse_scene(
        {
            "system": "rigid_body",
            "effects": list(effects),
            "parameters": {"n": n, "seed": 3, **params},
            "integrator": integrator or {"method": "DOP853", "rtol": 1e-9},
            "horizon": {"T": T},
            "observables": observables or {"energy": {"points": 6}},
        }
    )


# ---------------------------------------------------------------------------------------------
# the schema


def test_base_scene_is_valid() -> None:
    sc = load_scene(BASE)
    assert sc.parameters.n == 4 and sc.integrator.rtol == 1e-9 and sc.effects == ("attitude",)


@pytest.mark.parametrize(
    ("old", "new", "key", "line", "allowed"),
    [
        ('method = "DOP853"', 'method = "euler"', "integrator.method", 10, ["DOP853", "mv"]),
        ("n = 4", "n = 4\nspin = 2", "parameters.spin", 7, ["n", "lam", "seed", "M0"]),
        ('Q = "end"', 'omega = "end"', "observables.omega", 18, ["energy", "Q", "manakov"]),
        ('effects = ["attitude"]', 'effects = ["costates"]', "effects", 3, ["attitude"]),
        ('effects = ["attitude"]', "effects = []", "observables.Q", 18, ["energy", "M"]),
        ('method = "x"', "", "", 0, None),  # placeholder, replaced below
        ('system = "rigid_body"', 'system = "rigidbody"', "system", 2, ["rigid_body", "resnet"]),
        ('Q = "end"', 'Q = "start"', "observables.Q", 18, None),
    ],
)
def test_errors_name_key_line_and_allowed_values(old, new, key, line, allowed) -> None:
    if not key:
        text = BASE.replace("rtol = 1e-9", "h = 0.1")  # a keyword DOP853 does not take
        key, line, allowed = "integrator.h", 11, ["method", "rtol", "atol"]
    else:
        assert old in BASE
        text = BASE.replace(old, new)
    p = _problem(text)
    assert p["key"] == key
    assert p["line"] == line
    assert text.splitlines()[line - 1].strip().startswith(key.split(".")[-1])
    if allowed is not None:
        assert set(allowed) <= set(p["allowed"]), p
    message = str(SceneError([p]))
    assert key in message and f"line {line}" in message


def test_value_error_names_the_bound() -> None:
    p = _problem(BASE.replace("rtol = 1e-9", "rtol = -1.0"))
    assert p["key"] == "integrator.rtol" and p["line"] == 11 and "greater than 0" in p["message"]


def test_bad_toml_names_the_line() -> None:
    p = _problem(BASE.replace("T = 5.0", "T = = 5.0"))
    assert p["line"] == 14


def test_python_built_scene_errors_are_symrb_errors() -> None:
    with pytest.raises(SceneError, match="parameters.n"):
        parse_scene({"system": "resnet", "parameters": {"n": 3}})
    with pytest.raises(SceneError, match=r"horizon.steps.*terminal_cost"):
        plan_scene(
            {
                "system": "resnet",
                "integrator": {"kind": "gradient_descent"},
                "horizon": {"steps": 5},
                "observables": {"accuracy": "end"},
            }
        )


def test_a_model_built_in_python_gets_the_checks_across_keys() -> None:
    # pydantic validates the fields of a model; the checks that span keys (an observable's
    # effect, what MV-Algorithm 1 can record) run in parse_scene, for a model as for a table
    base = {"system": "rigid_body", "horizon": {"T": 2.0}}
    no_attitude = scenes.RigidBodyScene.model_validate(
        {**base, "integrator": {"method": "DOP853"}, "observables": {"Q": "end"}}
    )
    with pytest.raises(SceneError, match=r"observables.Q: needs the effect 'attitude'"):
        plan_scene(no_attitude)
    no_momentum = scenes.RigidBodyScene.model_validate(
        {
            **base,
            "effects": ["attitude"],
            "integrator": {"method": "mv_algorithm1", "h": 0.5},
            "observables": {"energy": "end"},
        }  # fmt: skip
    )
    with pytest.raises(SceneError, match=r"observables.energy: MV-Algorithm 1"):
        run_scene(no_momentum, cache=False)


def test_toml_and_python_give_the_same_scene_and_key() -> None:
    a = load_scene(BASE)
    b = _rb(effects=["attitude"], observables={"energy": {"points": 6}, "Q": "end"})
    b = parse_scene({**b.model_dump(), "title": "test"})
    assert a == b
    assert scenes.scene_key(a) == scenes.scene_key(b)
    assert scenes.scene_key(a) != scenes.scene_key(_rb(effects=["attitude"]))


@pytest.mark.parametrize("path", BOOK_SCENES, ids=lambda p: p.name)
def test_book_scenes_validate_and_explain(path: Path) -> None:
    plan = plan_scene(load_scene(path))
    text = plan.explain()
    assert "propagated" in text and "cost" in text and "record" in text


# ---------------------------------------------------------------------------------------------
# the planner


def test_momentum_only_skips_the_attitude() -> None:
    plan = plan_scene(_rb(n=10))
    assert plan.propagated == ("M",)
    assert any(what == "attitude Q" for what, _ in plan.skipped)
    assert "RigidBodyMomentum" in plan.route
    with_q = plan_scene(_rb(n=10, effects=["attitude"]))
    assert with_q.propagated == ("Q", "M") and "RigidBody," in with_q.route
    assert with_q.cost["flops"] > plan.cost["flops"]


def test_mv_momentum_only_steps_no_q_at_any_n(monkeypatch) -> None:
    """Without the attitude, "mv" propagates M alone at n = 3 too (orders 2 and 6): the fused
    n = 3 kernel gets empty Q components (no arithmetic on Q), and M is mv_flow's bit for bit."""
    mv = {"method": "mv", "h": 0.05}
    assert plan_scene(_rb(n=5, integrator=mv)).propagated == ("M",)
    attitudes: list[np.ndarray] = []  # the Q given to each call of the n = 3 kernel
    from symrb import _mv3  # where the engine's n = 3 code calls the kernel

    kernel = _mv3._kernel3

    def recording(*args):
        attitudes.append(np.concatenate([np.ravel(q) for q in args[8:]]))
        return kernel(*args)

    monkeypatch.setattr(_mv3, "_kernel3", recording)
    for order in (2, 6):
        sc = _rb(n=3, integrator={**mv, "order": order}, T=1.0, observables={"M": {"every": 5}})
        p3 = plan_scene(sc)
        assert p3.propagated == ("M",) and any(w == "attitude Q" for w, _ in p3.skipped)
        attitudes.clear()
        r = run_scene(sc, cache=False)
        # a step per call with Q empty; the solver's branch check of a cold start computes U
        # itself as I U (the identity as Q), once
        empty = sum(q.size == 0 for q in attitudes)
        checks = [q for q in attitudes if q.size]
        assert empty >= 20 and len(checks) <= 2, (empty, len(checks))
        assert all(np.array_equal(q, np.eye(3).ravel()) for q in checks)
        x = scene_inputs(sc)
        ref = symrb.engine.mv_flow(x["Q0"], x["M0"], x["lam"], 0.05, 20, save_every=5,
                                   order=order, method="numpy")  # fmt: skip
        _same(r["M"], ref.y.M)


def test_no_diagnostic_not_asked_for() -> None:
    r = run_scene(_rb(observables={"casimirs": "end"}), cache=False)
    assert set(r.data) == {"casimirs"}
    plan = r.plan
    assert plan.kernels == ("rigid_body.rigid_body_rhs", "rigid_body.casimir_traces")
    skipped = " ".join(w for w, _ in plan.skipped)
    assert "energy" in skipped and "manakov" in skipped


def test_no_costate_sweep_without_terminal_cost() -> None:
    base = {"system": "resnet", "integrator": {"kind": "gradient_descent"}}
    fwd = plan_scene({**base, "horizon": {"steps": 0}, "observables": {"accuracy": "end"}})
    assert "resnet_forward" in fwd.route
    assert not any("adjoint" in k for k in fwd.kernels)
    assert any("costate sweep" in w and "terminal cost" in why for w, why in fwd.skipped)
    trained = plan_scene(
        {**base, "effects": ["terminal_cost"], "horizon": {"steps": 3},
         "observables": {"loss": "end"}}
    )  # fmt: skip
    assert "train" in trained.route and any("adjoint" in k for k in trained.kernels)
    with pytest.raises(SceneError, match="observables.loss"):
        parse_scene({**base, "horizon": {"steps": 0}, "observables": {"loss": "end"}})


def test_one_sample_orbit_extremal_is_an_initial_value_problem() -> None:
    sc = {
        "system": "orbit_extremal",
        "effects": ["terminal_cost", "potential"],
        "integrator": {"kind": "bvp"},
        "horizon": {"T": 2.0},
        "observables": {"x": {"points": 5}},
    }
    plan = plan_scene(sc)
    assert "double_bracket_flow" in plan.route and plan.propagated == ("x",)
    r = run_scene(sc, cache=False)
    x = scene_inputs(parse_scene(sc))
    bvp = symrb.solve_orbit_bvp(x["x0"], x["N"], 2.0)
    np.testing.assert_allclose(r["x"][:, 0], bvp.at(r.times["x"])[0][:, 0], atol=1e-5)
    with pytest.raises(SceneError, match="effects"):
        parse_scene({**sc, "effects": ["potential"]})


def test_save_times_are_the_union_of_the_requests() -> None:
    sc = _rb(observables={"energy": {"points": 3}, "M": {"times": [1.0, 2.0]}, "Omega": "end"})
    plan = plan_scene(sc)
    assert plan.save["t_eval"] == [0.0, 1.0, 2.0, 2.5, 5.0]
    assert plan.index == {"M": (1, 2), "Omega": (4,), "energy": (0, 3, 4)}
    r = run_scene(sc, cache=False)
    np.testing.assert_array_equal(r.times["M"], [1.0, 2.0])
    np.testing.assert_array_equal(r.times["energy"], [0.0, 2.5, 5.0])


def test_fixed_step_saves_every_gcd() -> None:
    mv = {"method": "mv", "h": 0.1}
    sc = _rb(n=3, integrator=mv, observables={"energy": {"every": 4}, "M": {"times": [0.6]}})
    plan = plan_scene(sc)
    assert plan.save == {"steps": 50, "save_every": 2}
    assert plan.index["M"] == (3,)
    with pytest.raises(SceneError, match=r"observables.M.times"):
        plan_scene(_rb(n=3, integrator=mv, observables={"M": {"times": [0.25]}}))
    with pytest.raises(SceneError, match=r"observables.M.every"):
        plan_scene(_rb(observables={"M": {"every": 3}}))
    with pytest.raises(SceneError, match=r"horizon.T"):
        plan_scene(_rb(n=3, integrator={"method": "mv", "h": 0.3}))


# ---------------------------------------------------------------------------------------------
# a scene equals hand-written calls


def test_rigid_body_scene_equals_integrate() -> None:
    sc = load_scene(BASE)
    r = run_scene(sc, cache=False)
    x = scene_inputs(sc)
    t = np.linspace(0.0, 5.0, 6)
    sol = symrb.integrate(
        symrb.RigidBody, (0, 5.0), {"Q": x["Q0"], "M": x["M0"]}, lam=x["lam"], rtol=1e-9,
        t_eval=t,
    )  # fmt: skip
    _same(r["energy"], symrb.kinetic_energy(sol.y.M, x["lam"]))
    _same(r["Q"], sol.y.Q[-1:])


def test_momentum_only_scene_equals_integrate() -> None:
    sc = _rb(n=6, observables={"M": {"points": 4}, "manakov": "end"})
    r = run_scene(sc, cache=False)
    x = scene_inputs(sc)
    sol = symrb.integrate(
        RigidBodyMomentum, (0, 5.0), {"M": x["M0"]}, lam=x["lam"], rtol=1e-9,
        t_eval=np.linspace(0, 5.0, 4),
    )  # fmt: skip
    _same(r["M"], sol.y.M)
    _same(r["manakov"], symrb.manakov_integrals(sol.y.M[-1:], x["lam"]))
    # the momentum-only flow is the rigid body's momentum equation (to the tolerance)
    full = symrb.integrate(
        symrb.RigidBody, (0, 5.0), {"Q": x["Q0"], "M": x["M0"]}, lam=x["lam"], rtol=1e-12,
        atol=1e-14, t_eval=[5.0],
    )  # fmt: skip
    assert np.abs(full.y.M[-1] - r["M"][-1]).max() < 1e-7


@pytest.mark.parametrize("n", [3, 5])
def test_mv_scene_equals_mv_flow(n: int) -> None:
    sc = _rb(n=n, integrator={"method": "mv", "h": 0.05}, T=2.0,
             observables={"M": {"every": 8}, "energy": "end"})  # fmt: skip
    r = run_scene(sc, cache=False)
    x = scene_inputs(sc)
    sol = symrb.engine.mv_flow(x["Q0"], x["M0"], x["lam"], 0.05, 40, save_every=8)
    _same(r["M"], sol.y.M)
    _same(r["energy"], symrb.kinetic_energy(sol.y.M[-1:], x["lam"]))


def test_discrete_scene_equals_discrete_rigid_body_flow() -> None:
    sc = _rb(n=4, effects=["attitude"], integrator={"method": "discrete", "h": 0.1}, T=1.0,
             observables={"Q": {"every": 5}, "orthogonality": "end"})  # fmt: skip
    r = run_scene(sc, cache=False)
    x = scene_inputs(sc)
    sol = symrb.discrete_rigid_body_flow(x["Q0"], x["M0"], x["lam"], 0.1, 10, save_every=5)
    _same(r["Q"], sol.y.Q)
    Q = sol.y.Q[-1]
    _same(r["orthogonality"], [np.abs(Q.T @ Q - np.eye(4)).max()])


def test_resnet_scene_equals_train() -> None:
    sc = parse_scene(
        {"system": "resnet", "effects": ["terminal_cost", "costates"],
         "parameters": {"layers": 3, "samples": 40, "seed": 2},
         "integrator": {"kind": "gradient_descent", "lr": 0.01}, "horizon": {"steps": 12},
         "observables": {"loss": {"every": 4}, "K": "end", "costates": "end"}}
    )  # fmt: skip
    r = run_scene(sc, cache=False)
    x = scene_inputs(sc)
    tr = symrb.train(x["x0"], x["targets"], x["K0"], x["beta0"], steps=12, lr=0.01)
    _same(r["loss"], tr.losses[[0, 4, 8, 12]])
    _same(r["K"], tr.K[None])
    states = symrb.learning.resnet_forward(x["x0"], tr.K, tr.beta)
    _same(r["costates"], symrb.learning.costate_sweep(states, tr.K, tr.beta, x["targets"])[None])


def test_double_bracket_and_symmetric_scenes_equal_their_functions() -> None:
    path = ROOT / "book" / "scenes" / "double_bracket.toml"
    sc = load_scene(path)
    r = run_scene(sc, cache=False)
    x = scene_inputs(sc)
    t = np.linspace(0, 8.0, 81)
    _same(r["pairing"], symrb.pairing(symrb.double_bracket_flow(x["x0"], x["N"], t), x["N"]))
    sym = parse_scene(
        {"system": "symmetric_rigid_body", "effects": ["samples"],
         "parameters": {"n": 3, "samples": 3, "Q0": "random", "momentum": 0.5},
         "integrator": {"kind": "continuous"}, "horizon": {"T": 2.0},
         "observables": {"U": "end", "H": {"points": 3}}}
    )  # fmt: skip
    r = run_scene(sym, cache=False)
    x = scene_inputs(sym)
    sol = symrb.integrate(
        symrb.MultiSampleSymmetricRigidBody, (0, 2.0), {"Q": x["Q0"], "P": x["P0"]},
        lam=x["lam"], rtol=1e-10, atol=1e-12, t_eval=[0, 1.0, 2.0],
    )  # fmt: skip
    _same(r["U"], sol.y.U[-1:])
    _same(r["H"], symrb.symmetric.gl_hamiltonian(sol.y.Q, sol.y.P, x["lam"]))


@pytest.mark.parametrize("start", ["rotations", "general"])
def test_symmetric_body_start_and_gram_observables_equal_hand_written(start: str) -> None:
    sc = parse_scene(
        {"system": "symmetric_rigid_body",
         "parameters": {"n": 4, "lam": [0.5, 1.0, 1.5, 2.0], "start": start, "seed": 12},
         "integrator": {"kind": "continuous", "rtol": 1e-11, "atol": 1e-11},
         "horizon": {"T": 3.0},
         "observables": {"gram_spectrum": {"points": 7}, "P_orthogonality": {"points": 7},
                         "H": {"points": 7, "windows": 3, "reduce": "max_rel_change"}}}
    )  # fmt: skip
    x = scene_inputs(sc)
    if start == "rotations":
        Q0, P0 = symrb.random_SO(4, (2,), seed=12)
    else:
        Q0, P0 = np.random.default_rng(12).standard_normal((2, 4, 4))
    _same(x["Q0"], Q0)
    _same(x["P0"], P0)
    r = run_scene(sc, cache=False)
    t = np.linspace(0.0, 3.0, 7)
    sol = symrb.integrate(symrb.SymmetricRigidBody, (0.0, 3.0), {"Q": Q0, "P": P0},
                          lam=x["lam"], rtol=1e-11, atol=1e-11, t_eval=t)  # fmt: skip
    Q, P = sol.y.Q, sol.y.P
    _same(r["gram_spectrum"], np.linalg.eigvalsh(np.swapaxes(Q, -1, -2) @ Q))
    _same(r["P_orthogonality"], np.abs(np.swapaxes(P, -1, -2) @ P - np.eye(4)).max(axis=(1, 2)))
    H = symrb.symmetric.gl_hamiltonian(Q, P, x["lam"])
    _same(r["H"], _windows(t, H, 3, "max_rel_change")[1])
    on_so = start == "rotations"
    assert (r["P_orthogonality"].max() < 1e-9) == on_so  # a general point is far from SO(4)
    with pytest.raises(SceneError, match="remove"):
        parse_scene({**sc.model_dump(mode="json", exclude_unset=True),
                     "parameters": {"n": 4, "start": start, "M0": [1.0, 2.0, 3.0]}})  # fmt: skip


def test_inputs_are_not_mutated_and_scenes_are_frozen() -> None:
    data = {"system": "rigid_body", "integrator": {"method": "DOP853"},
            "horizon": {"T": 1.0}, "observables": {"M": "end"}}  # fmt: skip
    before = json.dumps(data)
    sc = parse_scene(data)
    run_scene(data, cache=False)
    assert json.dumps(data) == before
    with pytest.raises(Exception):  # noqa: B017 - pydantic's frozen-instance error
        sc.title = "x"  # type: ignore[misc]


# ---------------------------------------------------------------------------------------------
# the cache


def test_second_run_loads_and_recomputes_nothing(tmp_path, monkeypatch) -> None:
    calls = []
    real = scenes_run._execute

    def counting(sc, plan):
        calls.append(sc.system)
        return real(sc, plan)

    monkeypatch.setattr(scenes_run, "_execute", counting)
    sc = load_scene(BASE)
    a = run_scene(sc, cache=tmp_path)
    b = run_scene(sc, cache=tmp_path)
    assert calls == ["rigid_body"]
    assert not a.meta["from_cache"] and b.meta["from_cache"]
    for k in a.data:
        _same(a[k], b[k])
        _same(a.times[k], b.times[k])
    assert b.plan == a.plan and b.scene == a.scene
    meta = json.loads((SceneStore(tmp_path).path(a.meta["key"]) / "scene.json").read_text())
    assert meta["scene"]["system"] == "rigid_body" and "numpy" in meta["meta"]["versions"]
    assert "propagated" in meta["plan"]
    run_scene(_rb(effects=["attitude"]), cache=tmp_path)  # another scene: computed
    assert len(calls) == 2 and len(SceneStore(tmp_path).log()) == 2


def test_key_depends_on_the_code(monkeypatch) -> None:
    sc = load_scene(BASE)
    key = scenes.scene_key(sc)
    real = scenes_store._code_digest
    monkeypatch.setattr(scenes_store, "_code_digest", lambda mods: real(mods) + "changed")
    assert scenes.scene_key(sc) != key
    # and on the modules the plan uses: the engine's source enters an MV scene's key only
    assert "engine" in plan_scene(_rb(n=3, integrator={"method": "mv", "h": 0.1})).modules
    assert "engine" not in plan_scene(sc).modules


def test_key_covers_every_file_of_a_package() -> None:
    """A plan naming a package (orbits, learning, rigid_body) hashes all of its files, so an edit
    of ``symrb/orbits/bvp.py`` changes the key of an orbit scene."""
    import symrb.orbits

    files = {Path(p).name for p in scenes_store._module_files(symrb.orbits)}
    assert {"__init__.py", "bvp.py", "double_bracket.py"} <= files


def test_damaged_entry_is_recomputed(tmp_path) -> None:
    sc = load_scene(BASE)
    a = run_scene(sc, cache=tmp_path)
    (SceneStore(tmp_path).path(a.meta["key"]) / "arrays.npz").write_bytes(b"garbage")
    with pytest.warns(symrb.errors.CacheWarning, match="damaged"):
        b = run_scene(sc, cache=tmp_path)
    assert not b.meta["from_cache"]


# ---------------------------------------------------------------------------------------------
# sweeps and the command line


def test_serial_sweep_table_and_arrays(tmp_path) -> None:
    res = sweep(BASE_PATH(tmp_path), ["parameters.seed=1,2", "integrator.rtol=1e-6,1e-9"],
                cache=tmp_path / "c")  # fmt: skip
    assert len(res.table) == 4 and len(res.results) == 4
    assert list(res.table["parameters.seed"]) == [1, 1, 2, 2]
    for row, r in zip(res.table.itertuples(), res.results, strict=True):
        assert r.scene.parameters.seed == row._1
        assert row.energy == r["energy"][-1]
    with pytest.raises(SceneError, match="integrator.rtol"):
        sweep(BASE_PATH(tmp_path), ["integrator.rtol=-1"], cache=False)


def BASE_PATH(tmp_path: Path) -> Path:  # noqa: N802
    p = tmp_path / "base.toml"
    p.write_text(BASE)
    return p


def _cli(*args: str, env: dict | None = None) -> subprocess.CompletedProcess:
    code = "import sys; sys.modules['sympy'] = None; from symrb.cli import main; sys.exit(main())"
    return subprocess.run(
        [sys.executable, "-c", code, *args], capture_output=True, text=True, cwd=ROOT,
        env={**os.environ, **(env or {})}, timeout=300,
    )  # fmt: skip


def test_cli_run_explain_and_errors(tmp_path) -> None:
    env = {"SYMRB_CACHE_DIR": str(tmp_path / "cache")}
    path = BASE_PATH(tmp_path)
    out = _cli("run", str(path), "--explain", env=env)
    assert out.returncode == 0, out.stderr
    assert "propagated  Q, M" in out.stdout and "result" not in out.stdout
    first = _cli("run", str(path), "--out", str(tmp_path / "out"), env=env)
    assert first.returncode == 0 and "computed in" in first.stdout, first.stderr
    again = _cli("run", str(path), env=env)
    assert "loaded from the cache" in again.stdout
    assert (tmp_path / "out" / "arrays.npz").is_file()
    bad = tmp_path / "bad.toml"
    bad.write_text(BASE.replace('method = "DOP853"', 'method = "rk4"'))
    err = _cli("run", str(bad), env=env)
    assert err.returncode == 2 and "integrator.method (line 10)" in err.stderr
    sw = _cli("sweep", str(path), "--grid", "parameters.seed=1,2", "--out",
              str(tmp_path / "sw"), "--no-progress", env=env)  # fmt: skip
    assert sw.returncode == 0, sw.stderr
    assert (tmp_path / "sw" / "table.csv").read_text().count("\n") == 3


# ---------------------------------------------------------------------------------------------
# Dask

dask_marks = [pytest.mark.dask, pytest.mark.timeout(600)]


@pytest.fixture(scope="module")
def cluster_client():
    distributed = pytest.importorskip("dask.distributed")
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
        dashboard_address=None,
    )  # fmt: skip
    client = distributed.Client(cluster)
    yield client
    client.close()
    cluster.close()


def _grid_scene() -> dict:
    return {"system": "rigid_body", "parameters": {"n": 6},
            "integrator": {"method": "DOP853", "rtol": 1e-10}, "horizon": {"T": 20.0},
            "observables": {"energy": {"points": 5}, "M": "end"}}  # fmt: skip


@pytest.mark.dask
@pytest.mark.timeout(600)
def test_dask_sweep_equals_serial_bit_for_bit(cluster_client) -> None:
    grid = {"parameters.seed": list(range(8)), "parameters.momentum": [0.5, 1.5]}
    serial = sweep(_grid_scene(), grid, cache=False)
    dist = sweep(_grid_scene(), grid, cache=False, client=cluster_client, chunk_size=3)
    assert len(dist.results) == 16
    for a, b in zip(serial.results, dist.results, strict=True):
        assert a.scene == b.scene
        for k in a.data:
            _same(a[k], b[k])
    cols = [c for c in serial.table.columns if c not in ("seconds",)]
    assert serial.table[cols].equals(dist.table[cols])


@pytest.mark.dask
@pytest.mark.timeout(600)
def test_killed_worker_loses_nothing(cluster_client, tmp_path) -> None:
    store = SceneStore(tmp_path / "cache")
    sc = _grid_scene()
    sc["horizon"] = {"T": 150.0}  # ~0.1-0.3 s a point
    grid = {"parameters.seed": list(range(16))}
    pids = cluster_client.run(os.getpid)
    killed: list[int] = []

    def killer() -> None:
        deadline = time.time() + 120
        while time.time() < deadline and len(store.log()) < 3:
            time.sleep(0.02)
        pid = sorted(pids.values())[0]
        os.kill(pid, signal.SIGKILL)
        killed.append(pid)

    thread = threading.Thread(target=killer)
    thread.start()
    res = sweep(sc, grid, cache=store, client=cluster_client, chunk_size=4)
    thread.join()
    assert killed, "no worker was killed"
    assert len(res.results) == 16 and all(r.meta["success"] for r in res.results)
    log = [e["key"] for e in store.log()]
    assert len(set(log)) == 16
    # points finished before the kill were loaded, not recomputed: at most the one point in
    # progress on the killed worker ran twice
    assert len(log) - 16 <= 1, log
    serial = sweep(sc, grid, cache=False)
    for a, b in zip(serial.results, res.results, strict=True):
        _same(a["M"], b["M"])
    cluster_client.wait_for_workers(2, timeout=60)


# ---------------------------------------------------------------------------------------------
# windowed reductions, a second run to compare with, MV-Algorithm 2


def _windows(t, values, w, how):
    """The reduction written out by hand: numpy.array_split blocks, the last time of each."""
    a = np.asarray(values)
    blocks = np.array_split(np.arange(len(a)), w)
    if how == "max_abs":
        ref = np.abs(a)
    elif how == "max_abs_change":
        ref = np.abs(a - a[0])
    elif how == "max_rel_change":
        ref = np.abs(a - a[0]) / np.abs(a[0])
    else:
        ref = a
    fn = np.min if how == "min" else np.max
    return np.array([t[b[-1]] for b in blocks]), np.stack([fn(ref[b], axis=0) for b in blocks])


def test_windowed_reductions_equal_hand_written_calls() -> None:
    obs = {
        "manakov": {"points": 41, "windows": 6, "reduce": "max_rel_change"},
        "energy": {"points": 41, "windows": 6, "reduce": "max_abs_change"},
        "M": {"points": 41, "windows": 5, "reduce": ["min", "max"]},
        "casimirs": {"points": 41, "windows": 4, "reduce": "max_abs"},
    }
    sc = _rb(n=4, observables=obs)
    r = run_scene(sc, cache=False)
    x = scene_inputs(sc)
    t = np.linspace(0.0, 5.0, 41)
    sol = symrb.integrate(RigidBodyMomentum, (0, 5.0), {"M": x["M0"]}, lam=x["lam"], rtol=1e-9,
                          t_eval=t)  # fmt: skip
    M = sol.y.M
    for name, values, w, how in [
        ("manakov", symrb.manakov_integrals(M, x["lam"]), 6, "max_rel_change"),
        ("energy", symrb.kinetic_energy(M, x["lam"]), 6, "max_abs_change"),
        ("casimirs", symrb.casimir_traces(M), 4, "max_abs"),
    ]:
        tw, ref = _windows(t, values, w, how)
        _same(r.times[name], tw)
        _same(r[name], ref)
    tw, low = _windows(t, M, 5, "min")
    _, high = _windows(t, M, 5, "max")
    _same(r.times["M"], tw)
    _same(r["M"], np.stack([low, high], axis=1))
    plan = r.plan
    assert plan.windows["M"] == (("min", "max"), 5) and plan.record["M"][1] == 5
    text = plan.explain()
    assert "reduce      M: 41 records -> 5 windows" in text and "not kept" in text


def test_windowed_loss_and_initial_weights_equal_train() -> None:
    sc = parse_scene(
        {"system": "resnet", "effects": ["terminal_cost"],
         "parameters": {"layers": 3, "samples": 30, "seed": 2, "K0_scale": 0.1, "K0_seed": 5},
         "integrator": {"kind": "gradient_descent", "lr": 0.01}, "horizon": {"steps": 20},
         "observables": {"loss": {"every": 1, "windows": 4, "reduce": ["min", "max"]}}}
    )  # fmt: skip
    r = run_scene(sc, cache=False)
    x0, targets, _ = symrb.learning.toy_classification(30, seed=2)
    K0 = 0.1 * np.random.default_rng(5).standard_normal((3, 2, 2))
    tr = symrb.train(x0, targets, K0, np.zeros((3, 2)), steps=20, lr=0.01)
    steps = np.arange(21.0)
    tw, low = _windows(steps, tr.losses, 4, "min")
    _, high = _windows(steps, tr.losses, 4, "max")
    _same(r.times["loss"], tw)
    _same(r["loss"], np.stack([low, high], axis=1))


def test_gap_equals_two_hand_written_runs() -> None:
    sc = parse_scene(
        {"system": "symmetric_rigid_body", "parameters": {"n": 4, "seed": 3, "Q0": "random"},
         "integrator": {"kind": "continuous", "rtol": 1e-7, "atol": 1e-9},
         "compare": {"system": "rigid_body",
                     "integrator": {"method": "DOP853", "rtol": 1e-11, "atol": 1e-13}},
         "horizon": {"T": 4.0},
         "observables": {"M_gap": {"points": 21, "windows": 5, "reduce": "max"},
                         "Q_gap": {"times": [1.0, 4.0]}}}
    )  # fmt: skip
    r = run_scene(sc, cache=False)
    x = scene_inputs(sc)
    t_eval = np.unique(np.r_[np.linspace(0, 4.0, 21), 1.0, 4.0])
    sym = symrb.integrate(symrb.SymmetricRigidBody, (0, 4.0), {"Q": x["Q0"], "P": x["P0"]},
                          lam=x["lam"], rtol=1e-7, atol=1e-9, t_eval=t_eval)  # fmt: skip
    # the second run: the rigid body with its attitude (Q_gap asks for Q) at its own times
    rb = symrb.integrate(symrb.RigidBody, (0, 4.0), {"Q": x["Q0"], "M": x["M0"]}, lam=x["lam"],
                         rtol=1e-11, atol=1e-13, t_eval=t_eval)  # fmt: skip
    gap = np.abs(sym.y.M - rb.y.M).max(axis=(-2, -1))
    tw, ref = _windows(t_eval, gap, 5, "max")
    _same(r.times["M_gap"], tw)
    _same(r["M_gap"], ref)
    pick = np.searchsorted(t_eval, [1.0, 4.0])
    _same(r["Q_gap"], np.abs(sym.y.Q[pick] - rb.y.Q[pick]).max(axis=(-2, -1)))
    assert 1e-9 < r["M_gap"].max() < 1e-5
    text = r.plan.explain()
    assert "compare     M_gap, Q_gap" in text and "  propagated  Q, M" in text
    assert r.plan.compare is not None and "RigidBody," in r.plan.compare.route


def test_mv_algorithm2_scene_equals_mv_algorithm2() -> None:
    sc = _rb(n=3, effects=["attitude"], integrator={"method": "mv_algorithm2", "h": 0.5}, T=20.0,
             observables={"M": {"every": 5}, "orthogonality": {"every": 1, "windows": 4,
                                                               "reduce": "max_abs"}})  # fmt: skip
    r = run_scene(sc, cache=False)
    x = scene_inputs(sc)
    sol = symrb.mv_algorithm2(x["Q0"], 0.5 * x["M0"], x["lam"], 40)
    _same(r["M"], sol.y.M[::5] / 0.5)
    _same(r.times["M"], np.arange(0, 41, 5) * 0.5)
    Q = sol.y.Q
    orth = np.abs(np.swapaxes(Q, -1, -2) @ Q - np.eye(3)).max(axis=(-2, -1))
    _same(r["orthogonality"], _windows(np.arange(41) * 0.5, orth, 4, "max_abs")[1])
    assert "mv_algorithm2" in r.plan.route


def test_sweep_over_the_integrator_method() -> None:
    # "mv" fills in its default order; a grid point of another method must not inherit that key
    sc = _rb(n=3, effects=["attitude"], integrator={"method": "mv", "h": 0.5}, T=10.0,
             observables={"energy": {"every": 4}})  # fmt: skip
    out = sweep(sc, {"integrator.method": ["mv", "mv_algorithm2"]}, cache=False, progress=False)
    assert list(out.table["integrator.method"]) == ["mv", "mv_algorithm2"]
    x = scene_inputs(sc)
    ref = symrb.mv_algorithm2(x["Q0"], 0.5 * x["M0"], x["lam"], 20, save_every=4)
    _same(out.results[1]["energy"], symrb.kinetic_energy(ref.y.M / 0.5, x["lam"]))
    assert "mv_algorithm2" in out.results[1].plan.route and "mv_flow" in out.results[0].plan.route
    with pytest.raises(SceneError, match="integrator.order"):  # set by the user: named
        sweep(_rb(n=3, integrator={"method": "mv", "h": 0.5, "order": 4}),
              {"integrator.method": ["mv_algorithm2"]}, cache=False, progress=False)  # fmt: skip


REDUCED = BASE.replace(
    "energy = {points = 6}", "energy = {points = 6, windows = 2, reduce = 'max'}"
)


@pytest.mark.parametrize(
    ("old", "new", "key", "allowed"),
    [
        ("reduce = 'max'", "reduce = 'mean'", "observables.energy.reduce", ["max", "min"]),
        (", reduce = 'max'", "", "observables.energy", None),
        ("windows = 2", "windows = 0", "observables.energy.windows", None),
        ("reduce = 'max'", "reduce = ['max', 'max']", "observables.energy", None),
    ],
)
def test_reduction_errors_name_key_and_line(old, new, key, allowed) -> None:
    text = REDUCED.replace(old, new)
    p = _problem(text)
    assert p["key"] == key, p
    assert p["line"] == 17
    if allowed is not None:
        assert set(allowed) <= set(p["allowed"]), p


def test_reduction_and_compare_requests_the_run_cannot_meet() -> None:
    with pytest.raises(SceneError, match=r"observables.energy.windows.*7 windows of 6 records"):
        plan_scene(_rb(observables={"energy": {"points": 6, "windows": 7, "reduce": "max"}}))
    with pytest.raises(SceneError, match=r"observables.M_gap.*\[compare\]"):
        parse_scene(_rb().model_dump() | {"observables": {"M_gap": "end"}})
    with pytest.raises(SceneError, match=r"compare.*_gap"):
        parse_scene(_rb().model_dump() | {"compare": {"integrator": {"method": "DOP853"}}})
    mv = {"method": "mv", "h": 0.1}

    def gap_scene(integrator, compare):
        return {"system": "rigid_body", "parameters": {"n": 3}, "integrator": integrator,
                "horizon": {"T": 1.0}, "observables": {"M_gap": "end"}, "compare": compare}  # fmt: skip

    # adaptive against fixed steps at the end: allowed (the refusals left: test_scenes_bodies.py)
    assert plan_scene(gap_scene({"method": "DOP853"}, {"integrator": mv})).compare
    with pytest.raises(SceneError, match=r"compare.integrator.h"):
        plan_scene(gap_scene({"method": "mv", "h": 0.5}, {"integrator": mv}))
    with pytest.raises(SceneError, match=r"compare.integrator.kind"):
        plan_scene(gap_scene(mv, {"system": "symmetric_rigid_body", "integrator": mv}))
    assert plan_scene(gap_scene(mv, {"integrator": {"method": "discrete", "h": 0.1}})).compare
    with pytest.raises(SceneError, match=r"windowed reduction needs a series"):
        _rb(observables={"energy": {"end": True, "windows": 2, "reduce": "max"}})
