"""Every public numerical function of symrb and every value of its options is reached by evidence.

The coverage report (:mod:`derivations.coverage`) comes with the one run of every claim's
evidence that the tests and the book share (:func:`derivations.report.load_results`: the book
build's ``book/_build/verify.json`` when it is current, else a run here), so it costs no second
run.
"""

from __future__ import annotations

from derivations import coverage
from derivations.report import load_results

#: How many functions and option values no evidence reaches yet (the goal is 0; this may only go
#: down).
ALLOWED_UNREACHED = 56


def test_universe_is_declared() -> None:
    targets = coverage.universe()
    names = [t.name for t in targets]
    assert len(names) == len(set(names))
    assert "symrb.rigid_body.simulate" in names
    tables = {o.name for t in targets for o in t.options}
    assert {"method", "order/kind", "step", "activation", "retraction", "costate"} <= tables


def test_evidence_reaches_every_function_and_option() -> None:
    payload, _source = load_results()
    cov = payload["coverage"]
    assert [f["function"] for f in cov["functions"]] == [t.name for t in coverage.universe()]
    missing = coverage.unreached(cov)
    assert len(missing) <= ALLOWED_UNREACHED, (
        f"{coverage.summary_line(cov)} Unreached:\n" + "\n".join(missing)
    )
