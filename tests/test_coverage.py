"""Every public numerical function of symrb and every value of its options is reached by evidence.

The coverage report (:mod:`derivations.coverage`) comes with the one run of every claim's
evidence that the tests and the book share (:func:`derivations.report.load_results`: the book
build's ``book/_build/verify.json`` when it is current, else a run here), so it costs no second
run.
"""

from __future__ import annotations

from derivations import coverage
from derivations.report import load_results


def test_universe_is_declared() -> None:
    targets = coverage.universe()
    names = [t.name for t in targets]
    assert len(names) == len(set(names))
    assert "symrb.rigid_body.simulate" in names
    tables = {o.name for t in targets for o in t.options}
    assert {"method", "order/kind", "step", "activation", "retraction", "costate"} <= tables


def test_evidence_reaches_every_function_and_option() -> None:
    payload, _source = load_results()
    cov = coverage.validated(payload["coverage"])
    missing = coverage.unreached(cov)
    assert not missing, f"{coverage.summary_line(cov)} Unreached:\n" + "\n".join(missing)
    summary = cov["summary"]
    assert summary["functions_reached"] == summary["functions"] == len(cov["functions"])


def test_recorder_sees_calls_through_every_binding() -> None:
    """A call through a module attribute, a ``from x import f`` binding and a class counts, with
    its option values (defaults included); nothing is recorded outside evidence, and the
    functions are restored afterwards."""
    import numpy as np

    import symrb.compose
    import symrb.rigid_body
    from derivations.registry import CURRENT_EVIDENCE

    original = symrb.rigid_body.simulate
    with coverage.recording() as recorder:
        symrb.composition.composition_coefficients(6)  # outside evidence: not recorded
        token = CURRENT_EVIDENCE.set("X1 test")
        try:
            symrb.composition.composition_coefficients(6)
            symrb.base_steps.MVStep(np.ones(3))
            symrb.rigid_body.simulate(np.eye(3), np.zeros((3, 3)), np.ones(3), (0, 0.1),
                                      method="mv", h=0.1)  # fmt: skip
        finally:
            CURRENT_EVIDENCE.reset(token)
    assert symrb.rigid_body.simulate is original
    hits = recorder.hits
    assert hits[("symrb.composition.composition_coefficients", "order/kind", "6/kahan_li")] == {
        "X1 test"
    }
    assert ("symrb.base_steps.MVStep", "", "") in hits
    assert ("symrb.rigid_body.simulate", "method", "mv") in hits
    assert ("symrb.engine.mv_flow", "order", "2") in hits  # reached through simulate
