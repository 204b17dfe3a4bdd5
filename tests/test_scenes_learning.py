"""Scenes of the learning page: the SO(n) network (system so_network) against the hand-written
trainers bit for bit, its planner and its errors; the ResNet's digits data and extended MSA
against train, train_msa and resnet_predict."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from scene_helpers import problem as _problem
from scene_helpers import same as _same

import symrb
from symrb import learning
from symrb.scenes import (
    SceneStore,
    SONetworkScene,
    load_scene,
    parse_scene,
    plan_scene,
    run_scene,
    scene_inputs,
    sweep,
)

SO = """\
system = "so_network"
effects = ["terminal_cost", "running_cost"]

[parameters]
n = 3
samples = 8
seed = 1
layers = 3
alpha = 0.5

[integrator]
kind = "gradient"
lr = 0.05
line_search = true
tol = 1e-9

[horizon]
steps = 400

[observables]
loss = {every = 1}
residual = {every = 1}
U = "end"
"""

#: the task of SO, by hand
TASK = dict(n=3, samples=8, seed=1)


def _task():
    Q0, T = learning.so_rotation_task(TASK["n"], samples=TASK["samples"], seed=TASK["seed"])
    return Q0, T, np.linspace(1.0, 2.0, 3), np.tile(np.eye(3), (3, 1, 1))


def _so(integrator=None, observables=None, effects=("terminal_cost", "running_cost"), steps=400,
        **params):  # fmt: skip
    base = {"n": 3, "samples": 8, "seed": 1, "layers": 3}
    if "running_cost" in effects:
        base["alpha"] = 0.5
    return parse_scene({
        "system": "so_network", "effects": list(effects), "parameters": {**base, **params},
        "integrator": integrator or {"kind": "gradient", "lr": 0.05, "line_search": True,
                                     "tol": 1e-9},
        "horizon": {"steps": steps},
        "observables": observables or {"loss": {"every": 1}, "residual": {"every": 1},
                                       "U": "end"},
    })  # fmt: skip


# ---------------------------------------------------------------------------------------------
# so_network equals the hand-written trainers


def test_inputs_are_the_task_the_default_lam_and_identities() -> None:
    x = scene_inputs(load_scene(SO))
    Q0, T, lam, U0 = _task()
    _same(x["Q0"], Q0)
    _same(x["targets"], T)
    _same(x["lam"], lam)
    _same(x["U0"], U0)
    assert x["alpha"] == 0.5
    # without the running cost, alpha is 0 (and lam, unused, the default)
    assert scene_inputs(_so(effects=["terminal_cost"]))["alpha"] == 0.0


def test_gradient_scene_equals_train_so_gradient() -> None:
    obs = {"loss": {"every": 1}, "residual": {"every": 3}, "U": "end", "Q": "end",
           "costates": "end", "extremal_residual": "end", "iterations": "end",
           "converged": "end"}  # fmt: skip
    sc = _so(observables=obs, effects=["terminal_cost", "running_cost", "costates"])
    r = run_scene(sc, cache=False)
    Q0, T, lam, U0 = _task()
    res = symrb.train_so_gradient(Q0, T, U0, lam, alpha=0.5, steps=400, lr=0.05,
                                  line_search=True, tol=1e-9)  # fmt: skip
    assert res.converged and 10 < res.iterations < 400
    _same(r["loss"], res.losses)
    _same(r.times["loss"], np.arange(res.iterations + 1, dtype=float))
    _same(r["residual"], res.residuals[::3])
    _same(r.times["residual"], np.arange(0, res.iterations + 1, 3, dtype=float))
    _same(r["U"], res.U[None])
    Q, P = symrb.learning.so_network_costates(Q0, res.U, T)
    _same(r["Q"], Q[None])
    _same(r["Q"], symrb.learning.so_network_forward(Q0, res.U)[None])
    _same(r["costates"], P[None])
    _same(r["extremal_residual"], symrb.learning.so_extremal_residual(Q0, res.U, lam, T, 0.5)[None])
    _same(r["iterations"], [res.iterations])
    _same(r["converged"], [1])
    for name in ("U", "Q", "costates", "extremal_residual", "iterations", "converged"):
        _same(r.times[name], [float(res.iterations)])


@pytest.mark.parametrize(
    ("settings", "kw"),
    [
        ({"lr": 0.02, "momentum": 0.5}, {"lr": 0.02, "momentum": 0.5}),
        ({"lr": 0.05, "retraction": "exp"}, {"lr": 0.05, "retraction": "exp"}),
    ],
)
def test_gradient_options_reach_the_trainer(settings: dict, kw: dict) -> None:
    sc = _so(integrator={"kind": "gradient", **settings}, steps=60,
             observables={"loss": {"every": 1}, "U": "end"})  # fmt: skip
    r = run_scene(sc, cache=False)
    Q0, T, lam, U0 = _task()
    res = symrb.train_so_gradient(Q0, T, U0, lam, alpha=0.5, steps=60, **kw)
    _same(r["loss"], res.losses)
    _same(r["U"], res.U[None])


def test_msa_scene_equals_train_so_msa_and_a_spent_budget_is_stored(tmp_path) -> None:
    obs = {"loss": "end", "residual": {"every": 5}, "U": "end", "iterations": "end",
           "converged": "end"}  # fmt: skip
    sc = _so(integrator={"kind": "msa", "rho": 2.0, "tol": 1e-7}, observables=obs)
    r = run_scene(sc, cache=False)
    Q0, T, lam, U0 = _task()
    res = symrb.train_so_msa(Q0, T, U0, lam, alpha=0.5, steps=400, rho=2.0, tol=1e-7)
    assert res.converged
    _same(r["loss"], res.losses[-1:])
    _same(r.times["loss"], [float(res.iterations)])
    _same(r["residual"], res.residuals[::5])
    _same(r["U"], res.U[None])
    _same(r["iterations"], [res.iterations])
    # the basic MSA (rho = 0) with a budget it cannot converge in: not a failure, stored
    short = _so(integrator={"kind": "msa", "rho": 0.0}, steps=7, observables=obs)
    store = SceneStore(tmp_path)
    a = run_scene(short, cache=store)
    basic = symrb.train_so_msa(Q0, T, U0, lam, alpha=0.5, steps=7, rho=0.0)
    assert not basic.converged
    _same(a["converged"], [0])
    _same(a["iterations"], [7])
    _same(a["residual"], basic.residuals[::5])
    assert a.meta["success"] and run_scene(short, cache=store).meta["from_cache"]


def test_shooting_scene_equals_train_so_shooting() -> None:
    obs = {"loss": {"every": 1}, "residual": {"every": 1}, "U": "end", "iterations": "end",
           "converged": "end"}  # fmt: skip
    sc = _so(integrator={"kind": "shooting", "tol": 1e-13}, steps=300, observables=obs)
    r = run_scene(sc, cache=False)
    Q0, T, lam, _ = _task()
    res = symrb.train_so_shooting(Q0, T, lam, 0.5, 3, tol=1e-13, maxfev=300)
    _same(r["loss"], res.losses)
    _same(r["residual"], res.residuals)
    _same(r["U"], res.U[None])
    _same(r["iterations"], [res.iterations])
    _same(r["converged"], [int(res.converged)])
    # horizon.steps is the budget of evaluations (maxfev): a smaller one stops shooting early
    few = run_scene(_so(integrator={"kind": "shooting"}, steps=4, observables=obs), cache=False)
    cut = symrb.train_so_shooting(Q0, T, lam, 0.5, 3, maxfev=4)
    _same(few["loss"], cut.losses)
    assert few["loss"].shape[0] < r["loss"].shape[0]
    # integrator.tol reaches the trainer: a loose one stops after fewer evaluations
    loose = run_scene(_so(integrator={"kind": "shooting", "tol": 1e-6}, steps=300,
                          observables=obs), cache=False)  # fmt: skip
    ref = symrb.train_so_shooting(Q0, T, lam, 0.5, 3, tol=1e-6, maxfev=300)
    _same(loose["loss"], ref.losses)
    assert loose["iterations"][0] < r["iterations"][0]


def test_running_cost_weight_defaults_to_one() -> None:
    # running_cost without parameters.alpha: alpha = 1, as the docstring says
    sc = parse_scene({
        "system": "so_network", "effects": ["terminal_cost", "running_cost"],
        "parameters": {"n": 3, "samples": 8, "seed": 1, "layers": 3},
        "integrator": {"kind": "msa", "rho": 2.0}, "horizon": {"steps": 20},
        "observables": {"loss": {"every": 1}},
    })  # fmt: skip
    Q0, T, lam, U0 = _task()
    res = symrb.train_so_msa(Q0, T, U0, lam, alpha=1.0, steps=20, rho=2.0)
    _same(run_scene(sc, cache=False)["loss"], res.losses)


def test_without_running_cost_alpha_is_zero() -> None:
    sc = _so(effects=["terminal_cost"], steps=50, observables={"loss": {"every": 1}})
    r = run_scene(sc, cache=False)
    Q0, T, lam, U0 = _task()
    res = symrb.train_so_gradient(Q0, T, U0, lam, alpha=0.0, steps=50, lr=0.05,
                                  line_search=True, tol=1e-9)  # fmt: skip
    _same(r["loss"], res.losses)
    with_cost = run_scene(_so(steps=50, observables={"loss": {"every": 1}}), cache=False)
    assert not np.array_equal(with_cost["loss"], r["loss"])


def test_lam_reaches_the_trainer() -> None:
    lam = [0.5, 1.0, 3.0]
    sc = _so(lam=lam, steps=30, observables={"loss": {"every": 1}})
    r = run_scene(sc, cache=False)
    Q0, T, _, U0 = _task()
    res = symrb.train_so_gradient(Q0, T, U0, np.array(lam), alpha=0.5, steps=30, lr=0.05,
                                  line_search=True, tol=1e-9)  # fmt: skip
    _same(r["loss"], res.losses)


def test_windows_reduce_the_loss_per_iteration() -> None:
    sc = _so(observables={"loss": {"every": 1, "windows": 4, "reduce": ["min", "max"]}})
    r = run_scene(sc, cache=False)
    Q0, T, lam, U0 = _task()
    losses = symrb.train_so_gradient(Q0, T, U0, lam, alpha=0.5, steps=400, lr=0.05,
                                     line_search=True, tol=1e-9).losses  # fmt: skip
    blocks = np.array_split(np.arange(losses.size), 4)
    _same(r["loss"], np.stack([[losses[b].min(), losses[b].max()] for b in blocks]))
    _same(r.times["loss"], [float(b[-1]) for b in blocks])


def test_user_input_is_not_mutated_and_the_cache_recomputes_nothing(tmp_path) -> None:
    data = _so().model_dump(exclude_unset=True)
    before = copy.deepcopy(data)
    store = SceneStore(tmp_path)
    a = run_scene(data, cache=store)
    b = run_scene(data, cache=store)
    assert data == before
    assert not a.meta["from_cache"] and b.meta["from_cache"] and len(store.log()) == 1
    for name in a.data:
        _same(a[name], b[name])
    other = {**data, "integrator": {"kind": "msa"}}
    assert run_scene(other, cache=store).meta["key"] != a.meta["key"]


def test_sweep_over_rho_equals_the_trainer() -> None:
    base = _so(integrator={"kind": "msa", "tol": 1e-7},
               observables={"loss": "end", "converged": "end"})  # fmt: skip
    out = sweep(base, {"integrator.rho": [1.0, 2.0]}, cache=False)
    Q0, T, lam, U0 = _task()
    for rho, res in zip([1.0, 2.0], out.results, strict=True):
        hand = symrb.train_so_msa(Q0, T, U0, lam, alpha=0.5, steps=400, rho=rho, tol=1e-7)
        _same(res["loss"], hand.losses[-1:])
        _same(res["converged"], [int(hand.converged)])
    assert list(out.table["converged"]) == [0.0, 1.0]  # rho = 1 is too small to converge here


# ---------------------------------------------------------------------------------------------
# so_network: the planner


def test_plan_names_the_trainer_and_what_an_iteration_costs() -> None:
    gd = plan_scene(_so())
    assert gd.route.startswith("symrb.train_so_gradient(steps=400, lr=0.05, line_search=True")
    assert "forward sweep over the 3 layers and a backward costate sweep" in gd.route
    assert "Armijo" in gd.route
    assert gd.kernels == (
        "discrete_rigid_body.so_network_layer", "discrete_rigid_body.so_network_endpoint",
        "discrete_rigid_body.so_network_gradient", "discrete_rigid_body.so_network_costate",
    )  # fmt: skip
    fixed = plan_scene(_so(integrator={"kind": "gradient", "lr": 0.05}))
    assert "Armijo" not in fixed.route and fixed.cost["flops"] < gd.cost["flops"]
    msa = plan_scene(_so(integrator={"kind": "msa", "rho": 3.0}))
    assert "Procrustes" in msa.route and "SVD" in msa.route
    shoot = plan_scene(_so(integrator={"kind": "shooting"}, steps=50))
    assert "maxfev=50" in shoot.route and "Moser-Veselov" in shoot.route
    assert shoot.propagated[0] == "momentum M_0 (n(n-1)/2 = 3 unknowns)"
    assert "solvers" in shoot.modules and "solvers" not in gd.modules
    assert "discrete_rigid_body.jd" in shoot.kernels
    assert any("evaluations" in n and "maxfev" in n for n in shoot.notes)
    for plan in (gd, msa, shoot):
        assert "scenes.systems.so_network" in plan.modules and "learning" in plan.modules
        assert plan.save == {"steps": plan.index["U"][0]}


def test_plan_skips_what_is_not_asked_for() -> None:
    plan = plan_scene(_so())
    skipped = dict(plan.skipped)
    assert "extremal_residual" in skipped and "Q (the final layers)" in skipped  # no end sweeps
    assert "effect 'costates' not named" in skipped["recording the costates P^a_k"]
    assert "running cost" not in " ".join(skipped)
    assert "discrete_rigid_body.jd" not in plan.kernels  # no extremal residual
    off = plan_scene(_so(effects=["terminal_cost"]))
    assert any(w.startswith("running cost") for w, _ in off.skipped)
    asked = plan_scene(_so(effects=["terminal_cost", "running_cost", "costates"],
                           observables={"costates": "end", "extremal_residual": "end"}))  # fmt: skip
    assert not any(w.startswith("recording the costates") for w, _ in asked.skipped)
    assert "symmetric_rigid_body.symmetric_momentum" in asked.kernels
    assert any("costates (and Q)" in n and "extremal_residual" in n for n in asked.notes)
    # the records planned are the budget's; the run keeps those of the iterations done
    assert plan.record["loss"] == ("every 1 steps", 401)


def test_explain_prints_the_plan() -> None:
    text = plan_scene(_so(integrator={"kind": "msa"})).explain()
    assert "system      so_network" in text and "train_so_msa" in text and "cost" in text


# ---------------------------------------------------------------------------------------------
# so_network: errors name the key, its line and the allowed values


@pytest.mark.parametrize(
    ("old", "new", "key", "allowed"),
    [
        ('U = "end"', "U = {every = 2}", "observables.U", ["end"]),
        ("loss = {every = 1}", "loss = {points = 5}", "observables.loss", ["end", "every"]),
        ('effects = ["terminal_cost", "running_cost"]', 'effects = ["terminal_cost"]',
         "parameters.alpha", ["n", "samples", "layers"]),
        ('kind = "gradient"\nlr = 0.05\nline_search = true\ntol = 1e-9',
         'kind = "shooting"\nmaxfev = 50', "integrator.maxfev", ["kind", "tol"]),
        ("alpha = 0.5", "alpha = 0.5\nlam = [1.0, 2.0]", "parameters.lam", None),
        ("lr = 0.05", "lr = 0.05\nrho = 2.0", "integrator.rho",
         ["lr", "line_search", "momentum", "retraction", "tol"]),
        ('kind = "gradient"', 'kind = "adam"', "integrator.kind", ["gradient", "msa", "shooting"]),
        ('effects = ["terminal_cost", "running_cost"]', 'effects = ["running_cost"]', "effects",
         ["terminal_cost", "running_cost", "costates"]),
        ('U = "end"', 'costates = "end"', "observables.costates", ["loss", "U"]),
        ("alpha = 0.5", "alpha = 0.0", "parameters.alpha", None),
    ],
)  # fmt: skip
def test_errors_name_key_line_and_allowed(old, new, key, allowed) -> None:
    assert old in SO
    text = SO.replace(old, new)
    p = _problem(text)
    assert p["key"] == key, p
    lines = text.splitlines()
    assert p["line"] is not None and lines[p["line"] - 1].strip().startswith(key.split(".")[-1])
    if allowed is not None:
        assert set(allowed) <= set(p["allowed"]), p


def test_shooting_needs_the_running_cost() -> None:
    text = SO.replace('effects = ["terminal_cost", "running_cost"]', 'effects = ["terminal_cost"]')
    text = text.replace("alpha = 0.5\n", "").replace(
        'kind = "gradient"\nlr = 0.05\nline_search = true\ntol = 1e-9', 'kind = "shooting"'
    )  # fmt: skip
    p = _problem(text)
    assert p["key"] == "integrator.kind" and p["allowed"] == ["gradient", "msa"]
    assert text.splitlines()[p["line"] - 1].startswith("kind")
    assert "running_cost" in p["message"]
    p = _problem(SO.replace('kind = "gradient"\nlr = 0.05\nline_search = true\ntol = 1e-9',
                            'kind = "shooting"').replace("steps = 400", "steps = 0"))  # fmt: skip
    assert p["key"] == "horizon.steps"


def test_the_scene_class_is_public_and_documented() -> None:
    assert symrb.scenes.SONetworkScene is SONetworkScene
    assert SONetworkScene.__module__ == "symrb.scenes"
    assert type(load_scene(SO)) is SONetworkScene


# ---------------------------------------------------------------------------------------------
# the ResNet: digits and the extended MSA

DIGITS = {"system": "resnet", "effects": ["terminal_cost"],
          "parameters": {"data": "digits", "features": 6, "layers": 2, "seed": 4},
          "integrator": {"kind": "gradient_descent", "lr": 2e-4}, "horizon": {"steps": 3},
          "observables": {"loss": {"every": 1}, "accuracy": "end", "test_accuracy": "end",
                          "K": "end"}}  # fmt: skip


def test_digits_scene_equals_train_and_resnet_predict() -> None:
    r = run_scene(DIGITS, cache=False)
    task = symrb.learning.digits_task(6, seed=4)
    n = task.x_train.shape[1]
    assert n == 16
    x = scene_inputs(parse_scene(DIGITS))
    _same(x["x0"], task.x_train)
    _same(x["labels_test"], task.labels_test)
    K0, b0 = np.zeros((2, n, n)), np.zeros((2, n))
    tr = symrb.train(task.x_train, task.y_train, K0, b0, steps=3, lr=2e-4)
    _same(r["loss"], tr.losses)
    _same(r["K"], tr.K[None])
    acc = np.mean(
        symrb.learning.resnet_predict(task.x_train, tr.K, tr.beta, 10) == task.labels_train
    )
    test = np.mean(
        symrb.learning.resnet_predict(task.x_test, tr.K, tr.beta, 10) == task.labels_test
    )
    _same(r["accuracy"], [acc])
    _same(r["test_accuracy"], [test])
    assert acc != test  # the two observables read different images
    # parameters.test_fraction reaches digits_task
    held = {**DIGITS["parameters"], "test_fraction": 0.2}
    y = scene_inputs(parse_scene({**DIGITS, "parameters": held}))
    other = symrb.learning.digits_task(6, 0.2, seed=4)
    _same(y["x0"], other.x_train)
    _same(y["labels_test"], other.labels_test)
    assert len(y["labels_test"]) < len(x["labels_test"])


@pytest.mark.parametrize("data", ["toy", "digits"])
def test_resnet_msa_scene_equals_train_msa(data: str) -> None:
    params = DIGITS["parameters"] if data == "digits" else {"samples": 50, "layers": 2}
    sc = {**DIGITS, "parameters": params,
          "integrator": {"kind": "msa", "rho": 0.5, "inner_steps": 2, "inner_lr": 1e-4},
          "observables": {"loss": {"every": 1}, "beta": "end", "accuracy": "end"}}  # fmt: skip
    r = run_scene(sc, cache=False)
    x = scene_inputs(parse_scene(sc))
    tr = symrb.train_msa(x["x0"], x["targets"], x["K0"], x["beta0"], steps=3, rho=0.5,
                         inner_steps=2, inner_lr=1e-4)  # fmt: skip
    _same(r["loss"], tr.losses)
    _same(r["beta"], tr.beta[None])
    if data == "toy":  # the toy accuracy is the sign of x_2, as before
        states = symrb.learning.resnet_forward(x["x0"], tr.K, tr.beta)
        _same(r["accuracy"], [np.mean(np.sign(states[-1][:, 1]) == x["labels"])])
    plan = plan_scene(sc)
    assert plan.route.startswith("symrb.train_msa(steps=3, rho=0.5, inner_steps=2")
    gd = plan_scene({**sc, "integrator": {"kind": "gradient_descent"}})
    assert plan.cost["seconds"] > gd.cost["seconds"]


def test_digits_initial_weights_have_the_data_width() -> None:
    sc = parse_scene({**DIGITS, "parameters": {**DIGITS["parameters"], "K0_scale": 0.1}})
    x = scene_inputs(sc)
    assert x["K0"].shape == (2, 16, 16) and x["beta0"].shape == (2, 16)
    _same(x["K0"], 0.1 * np.random.default_rng(0).standard_normal((2, 16, 16)))


def test_resnet_data_errors() -> None:
    toy = ('system = "resnet"\neffects = ["terminal_cost"]\n[parameters]\nlayers = 2\n'
           '[integrator]\nkind = "msa"\n[horizon]\nsteps = 2\n[observables]\nloss = "end"\n'
           'test_accuracy = "end"\n')  # fmt: skip
    p = _problem(toy)
    assert (p["key"], p["line"]) == ("observables.test_accuracy", 11)
    assert "test_accuracy" not in p["allowed"] and "accuracy" in p["allowed"]
    p = _problem(toy.replace("layers = 2", "layers = 2\nfeatures = 8"))
    assert (p["key"], p["line"]) == ("parameters.features", 5)
    assert "samples" in p["allowed"] and "features" not in p["allowed"]
    digits = toy.replace("layers = 2", 'data = "digits"\nsamples = 100')
    p = _problem(digits)
    assert (p["key"], p["line"]) == ("parameters.samples", 5)
    assert "features" in p["allowed"] and "samples" not in p["allowed"]
    p = _problem(toy.replace('kind = "msa"', 'kind = "msa"\nlr = 0.1'))
    assert (p["key"], p["line"]) == ("integrator.lr", 7)
    assert {"rho", "inner_steps", "inner_lr"} <= set(p["allowed"])
    p = _problem(toy.replace('kind = "msa"', 'kind = "adam"'))
    assert p["key"] == "integrator.kind" and p["allowed"] == ["gradient_descent", "msa"]
    p = _problem(toy.replace('"msa"', '"msa"\ninner_steps = 0'))
    assert p["key"] == "integrator.inner_steps" and p["line"] == 7


def test_digits_plan_counts_the_training_images() -> None:
    plan = plan_scene(DIGITS)
    assert any("1258 training images" in n and "width 16" in n for n in plan.notes)
    assert "3 layers" not in plan.cost["formula"] and "2 layers x 1258 samples" in (
        plan.cost["formula"])  # fmt: skip
