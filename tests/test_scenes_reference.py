"""``symrb.scenes.describe_schema``: the scene file format read from the models.

The listing is judged against the scene parser itself (a key the listing calls required must be
refused when it is left out; a value outside the listed ones must be refused; every listed
value must be accepted; a listed default must give the scene it gives when left out) and
against ``simulate``'s table of methods, never against a second copy of the listing.
"""

from __future__ import annotations

import pytest

from symrb.errors import InputError
from symrb.rigid_body import METHODS
from symrb.scenes import SceneError, When, describe_model, describe_schema, load_scene
from symrb.scenes.schema import _SYSTEMS

BASE = (
    'system = "rigid_body"\neffects = ["attitude"]\n[horizon]\nT = 1.0\n[observables]\nQ = "end"\n'
)


def _rigid_body(integrator: dict[str, str]) -> str:
    lines = "".join(f"{k} = {v}\n" for k, v in integrator.items())
    return BASE + "[integrator]\n" + lines


def _forms() -> dict[str, dict[str, object]]:
    """The rigid body's integrator forms: variant -> {key: SchemaKey}."""
    out: dict[str, dict[str, object]] = {}
    for k in describe_schema("rigid_body"):
        if k.table == "integrator":
            out.setdefault(k.variant, {})[k.key] = k
    return out


def test_every_system_and_every_table_is_listed():
    keys = describe_schema()
    assert {k.system for k in keys} == set(_SYSTEMS)
    for name, model in _SYSTEMS.items():
        mine = [k for k in keys if k.system == name]
        assert {k.table for k in mine} >= {"", "parameters", "integrator", "horizon", "observables"}
        assert [k.key for k in mine if k.table == ""] == ["system", "title", "effects"]
        params = model.model_fields["parameters"].annotation
        assert [k.key for k in mine if k.table == "parameters"] == list(params.model_fields)
        assert [k.key for k in mine if k.table == "observables"] == list(model.OBSERVABLES)
        assert {k.key for k in mine if k.table == "compare"} == (
            {"system", "integrator", "rotation", "shift", "label"}
            if "compare" in model.model_fields
            else set()
        )


def test_the_rigid_body_methods_are_simulates_and_the_papers():
    methods = {m for form in _forms().values() for m in form["method"].allowed}
    methods = {m.strip('"') for m in methods}
    assert set(METHODS) <= methods
    assert methods - set(METHODS) == {"discrete", "mv_algorithm1", "mv_algorithm2"}


def test_required_keys_are_refused_when_left_out():
    for keys in _forms().values():
        required = [k for k in keys.values() if k.required]
        values = {k.key: (k.allowed[0] if k.allowed else "0.01") for k in required}
        load_scene(_rigid_body(values))  # every required key given: accepted
        for k in required:
            if k.key == "method":
                continue  # the form is chosen by it: leaving it out is another form
            with pytest.raises(SceneError):
                load_scene(_rigid_body({n: v for n, v in values.items() if n != k.key}))


def test_allowed_values_are_exactly_the_accepted_ones():
    for keys in _forms().values():
        values = {k.key: (k.allowed[0] if k.allowed else "0.01") for k in keys.values()
                  if k.required}  # fmt: skip
        for k in keys.values():
            if not k.allowed or k.key == "method":
                continue
            for value in k.allowed:
                load_scene(_rigid_body({**values, k.key: value}))
            with pytest.raises(SceneError):
                load_scene(_rigid_body({**values, k.key: '"not-a-value"'}))


def test_defaults_are_what_leaving_the_key_out_gives():
    for form, keys in _forms().items():
        values = {k.key: (k.allowed[0] if k.allowed else "0.01") for k in keys.values()
                  if k.required}  # fmt: skip
        bare = load_scene(_rigid_body(values)).integrator
        for k in keys.values():
            if k.required or k.default == "(not set)":
                continue
            given = load_scene(_rigid_body({**values, k.key: k.default})).integrator
            assert given == bare, (form, k.key, k.default)


def test_types_and_bounds_read_from_the_fields():
    mv = _forms()['method = "mv"']
    assert (mv["h"].type, mv["h"].required) == ("float > 0", True)
    assert (mv["order"].default, mv["order"].allowed) == ("2", ("2", "4", "6", "8", "10"))
    when = {k.key: k for k in describe_model(When)}
    assert when["points"].type == "integer >= 2" and when["times"].type == "list of floats"
    assert set(when["reduce"].allowed) == {'"max"', '"min"', '"max_abs"', '"max_abs_change"',
                                           '"max_rel_change"'}  # fmt: skip
    resnet = {k.key: k for k in describe_schema("resnet") if k.table == "parameters"}
    assert resnet["features"].type == "integer >= 1 and <= 64"
    body = {k.key: k for k in describe_schema("rigid_body") if k.table == "parameters"}
    assert body["M0"].type == "list of floats or matrix (list of lists of floats)"
    assert body["lam"].default == "(not set)" and body["Q0"].default == '"identity"'


def test_observables_name_the_effect_they_need():
    obs = {k.key: k.note for k in describe_schema("rigid_body") if k.table == "observables"}
    assert obs["Q"] == 'needs the effect "attitude"' and obs["energy"] == ""


def test_bad_input_raises_input_error():
    with pytest.raises(InputError, match="system must be one of"):
        describe_schema("rigid-body")
    with pytest.raises(InputError, match="pydantic model"):
        describe_model(dict)  # type: ignore[arg-type]
