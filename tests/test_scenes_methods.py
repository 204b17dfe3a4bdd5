"""The rigid body's ``[integrator]`` table is the keyword arguments of
:func:`symrb.rigid_body.simulate`: a scene of each method equals ``simulate`` called by hand
with the same keywords, bit for bit; a keyword the method does not take is refused with its key,
its line and the keys the method takes."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from scene_helpers import problem as _problem
from scene_helpers import same as _same

import symrb
from symrb.composition import _KINDS
from symrb.rigid_body import METHODS, simulate
from symrb.scenes import parse_scene, plan_scene, run_scene, scene_inputs
from symrb.scenes.systems._rigid_body_methods import METHOD_NAMES, PAPER, Composition

LAM3 = [0.7, 1.1, 1.6]
T = 5.0
#: Q at t = 1 and 5, M at the end, the energy at 0, 1, ..., 5: steps 0, 4, ..., 20 of h = 0.25
OBSERVABLES = {"Q": {"times": [1.0, T]}, "M": "end", "energy": {"points": 6}}

SIMULATED = [
    {"method": "mv", "h": 0.25, "order": 4},
    {"method": "mv", "h": 0.25, "backend": "newton"},
    {"method": "composition", "h": 0.25},
    {"method": "composition", "h": 0.25, "order": 6, "kind": "yoshida"},
    {"method": "composition", "h": 0.25, "order": 2, "step": "midpoint"},
    {"method": "rkmk4", "h": 0.25},
    {"method": "midpoint", "h": 0.25},
    {"method": "exact"},
    {"method": "splitting", "h": 0.25},
    {"method": "splitting", "h": 0.25, "order": 8, "backend": "numba"},
    {"method": "DOP853", "rtol": 1e-9, "atol": 1e-11},
    {"method": "Radau"},
    {},  # simulate's default method, DOP853
]


def _scene(integrator: dict[str, Any], effects: tuple[str, ...] = ("attitude",), n: int = 3,
           observables: dict[str, Any] | None = None) -> Any:  # fmt: skip
    return parse_scene({
        "system": "rigid_body", "effects": list(effects),
        "parameters": {"n": n, "lam": LAM3 if n == 3 else None, "seed": 2},
        "integrator": integrator, "horizon": {"T": T},
        "observables": observables or OBSERVABLES,
    })  # fmt: skip


@pytest.mark.parametrize("integrator", SIMULATED, ids=lambda i: "-".join(map(str, i.values())))
def test_a_scene_of_each_method_equals_simulate_by_hand(integrator: dict[str, Any]) -> None:
    sc = _scene(integrator)
    r = run_scene(sc, cache=False)
    x = scene_inputs(sc)
    save: dict[str, Any] = (
        {"save_every": 4} if "h" in integrator else {"t_eval": np.linspace(0.0, T, 6)}
    )
    sol = simulate(x["Q0"], x["M0"], x["lam"], (0.0, T), **integrator, **save)
    assert sol.success
    _same(r.times["energy"], sol.t)
    _same(r["energy"], symrb.kinetic_energy(sol.M, x["lam"]))
    _same(r["Q"], sol.Q[[1, 5]])
    _same(r["M"], sol.M[-1:])
    assert "symrb.rigid_body.simulate(" in r.plan.route
    assert f"method={sol.method!r}" in r.plan.route


@pytest.mark.parametrize("integrator", [
    {"method": "composition", "h": 0.25, "order": 8}, {"method": "rkmk4", "h": 0.25},
    {"method": "splitting", "h": 0.25, "order": 6},
])  # fmt: skip
def test_without_the_attitude_simulate_steps_q_but_records_m_only(integrator) -> None:
    sc = _scene(integrator, effects=(), n=4, observables={"M": {"every": 5}})
    r = run_scene(sc, cache=False)
    x = scene_inputs(sc)
    sol = simulate(x["Q0"], x["M0"], x["lam"], (0.0, T), **integrator, save_every=5)
    _same(r["M"], sol.M)
    assert set(r.data) == {"M"} and r.plan.propagated == ("Q", "M")
    assert any("though not recorded" in note for note in r.plan.notes)


def test_the_table_names_every_method_of_simulate_and_the_papers() -> None:
    paper = {"discrete", "mv_algorithm1", "mv_algorithm2"}
    assert set(METHOD_NAMES) == set(METHODS) | paper
    assert {str(m.model_fields["method"].annotation.__args__[0]) for m in PAPER} == paper
    assert _scene({}).integrator.method == "DOP853"  # simulate's default
    # the kinds of composition the table takes are composition_coefficients' own
    (kinds, _) = Composition.model_fields["kind"].annotation.__args__
    assert set(kinds.__args__) == {k for ks in _KINDS.values() for k in ks}


TEXT = """\
system = "rigid_body"
[parameters]
n = 3
[integrator]
method = "{method}"
{extra}
[horizon]
T = 1.0
[observables]
energy = "end"
"""


@pytest.mark.parametrize(
    ("method", "extra", "key", "allowed"),
    [
        ("rkmk4", "h = 0.5\nbackend = 'numba'", "integrator.backend", ["method", "h", "order"]),
        ("exact", "h = 0.5", "integrator.h", ["method", "check"]),
        ("DOP853", "order = 4", "integrator.order", ["method", "rtol", "atol", "condition"]),
        ("mv", "h = 0.5\nrtol = 1e-8", "integrator.rtol", ["method", "h", "order", "backend"]),
        ("mv_algorithm1", "h = 0.5\nstart = 'Q1_M1'", "integrator.start", ["method", "h", "loop"]),
        ("midpoint", "h = 0.5\nprogress = true", "integrator.progress", ["method", "h", "order"]),
    ],
)  # fmt: skip
def test_a_keyword_the_method_does_not_take_is_refused(method, extra, key, allowed) -> None:
    text = TEXT.format(method=method, extra=extra)
    p = _problem(text)
    line = next(i for i, ln in enumerate(text.splitlines(), 1) if ln.startswith(key[11:]))
    assert (p["key"], p["line"], p["allowed"], p["message"]) == (key, line, allowed, "unknown key")


@pytest.mark.parametrize(
    ("method", "extra", "key", "allowed"),
    [
        ("rk4", "", "integrator.method", METHOD_NAMES),
        ("mv", "h = 0.5\norder = 3", "integrator.order", [2, 4, 6, 8, 10]),
        ("composition", "h = 0.5\norder = 4\nkind = 'leapfrog'", "integrator.kind", None),
        ("splitting", "h = 0.5\norder = 10", "integrator.order", [2, 4, 6, 8]),
    ],
)  # fmt: skip
def test_a_value_the_method_does_not_take_is_refused(method, extra, key, allowed) -> None:
    p = _problem(TEXT.format(method=method, extra=extra))
    assert p["key"] == key and p["line"] is not None, p
    if allowed is not None:
        assert sorted(map(str, p["allowed"])) == sorted(map(str, allowed)), p


def test_what_the_plan_refuses() -> None:
    p = _problem(_scene({"method": "exact"}, n=4, observables={"M": "end"}))
    assert p["key"] == "integrator.method" and "n = 3" in p["message"]
    p = _problem(_scene({"method": "composition", "h": 0.25, "order": 6, "kind": "suzuki"}))
    assert p["key"] == "integrator.kind" and "order 6" in p["message"]
    p = _problem(_scene({"method": "rkmk4", "h": 0.3}))
    assert p["key"] == "horizon.T"
    assert plan_scene(_scene({"method": "composition", "h": 0.25})).cost["seconds"] > 0
