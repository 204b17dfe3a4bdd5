"""The registry's outcome logic: a check proves something only if it can fail."""

from __future__ import annotations

import pytest

from derivations.registry import Claim, Evidence, Level, get_claim, outcome_of, verify_claim


def _claim(*evidence: Evidence, expected: str = "holds", **kw: str) -> Claim:
    return Claim(
        id="S99", label="x", title="t", statement="s", expected=expected, evidence=evidence, **kw
    )  # type: ignore[arg-type]


def _ev(value: float, form: str = "claim", tol: float = 1e-12) -> Evidence:
    return Evidence(Level.FLOAT64, "synthetic", lambda: value, tol=tol, form=form)  # type: ignore[arg-type]


def test_holds_and_fails() -> None:
    assert verify_claim(_claim(_ev(0.0), _ev(1e-13))).outcome == "holds"
    assert verify_claim(_claim(_ev(0.0), _ev(1e-3))).outcome == "fails"


def test_erratum_needs_failing_printed_and_passing_corrected() -> None:
    kw = {"printed": "p", "corrected": "c"}
    ok = verify_claim(_claim(_ev(0.5, "printed"), _ev(0.0, "corrected"), **kw))
    assert ok.outcome == "holds after correction"
    # printed form that in fact holds: no erratum
    assert verify_claim(_claim(_ev(0.0, "printed"), _ev(0.0, "corrected"), **kw)).outcome == "holds"
    # correction that does not hold
    assert verify_claim(_claim(_ev(0.5, "printed"), _ev(0.5, "corrected"), **kw)).outcome == "fails"


def test_crashing_or_nan_evidence_fails() -> None:
    def boom() -> float:
        raise RuntimeError("no")

    r = verify_claim(_claim(Evidence(Level.FLOAT64, "crash", boom)))
    assert r.outcome == "fails" and "RuntimeError" in (r.evidence[0].error or "")
    assert verify_claim(_claim(_ev(float("nan")))).outcome == "fails"


def test_no_evidence_is_not_checkable() -> None:
    assert outcome_of([]) == "not checkable"


def test_mismatch_with_recorded_outcome_is_reported() -> None:
    r = verify_claim(_claim(_ev(1.0), expected="holds"))
    assert not r.ok


def test_bad_claims_are_rejected() -> None:
    with pytest.raises(ValueError, match="id"):
        Claim(id="X1", label="", title="", statement="", expected="holds")
    with pytest.raises(ValueError, match="expected"):
        Claim(id="S1", label="", title="", statement="", expected="maybe")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="printed"):
        _claim(_ev(0.5, "printed"))


def test_unknown_id() -> None:
    with pytest.raises(KeyError, match="unknown claim"):
        get_claim("S999")


def test_numpy_residuals_serialise_to_json() -> None:
    import json

    import numpy as np

    r = verify_claim(_claim(Evidence(Level.FLOAT64, "numpy", lambda: np.float64(1e-20), tol=1e-12)))
    text = json.dumps(r.to_dict())
    assert json.loads(text)["evidence"][0]["passed"] is True


def test_report_escapes_markdown_but_not_math() -> None:
    from derivations.report import plain

    assert plain("u*_k and ||M||_op") == r"u\*\_k and \|\|M\|\|\_op"
    assert plain("keep $x_k^*$ as is") == "keep $x_k^*$ as is"


def test_report_check_fails_on_unexpected_outcome(monkeypatch: pytest.MonkeyPatch) -> None:
    from derivations import report

    assert report.check("S1", show=False).ok
    bad = _claim(_ev(1.0), expected="holds")
    monkeypatch.setattr(report, "get_claim", lambda cid: bad)
    with pytest.raises(AssertionError, match="outcome 'fails', recorded 'holds'"):
        report.check("S99", show=False)
