"""Every registered claim gets its recorded outcome, and every kernel is checked by its claims.

The evidence runs once: these tests read ``book/_build/verify.json`` when the book build wrote it
for the current code (see :func:`derivations.report.load_results`), else they run it here once.
"""

from __future__ import annotations

import functools

import pytest

from derivations.registry import ClaimResult, all_claims
from derivations.report import load_results, result_of

CLAIMS = all_claims()


@functools.cache
def _results() -> dict[str, ClaimResult]:
    return {c.id: result_of(c.id) for c in CLAIMS}


@pytest.mark.parametrize("claim", CLAIMS, ids=[c.id for c in CLAIMS])
def test_claim_outcome(claim: object) -> None:
    result = _results()[claim.id]  # type: ignore[attr-defined]
    details = "\n".join(
        f"  [{e.form}] {e.level}: residual {e.residual:.3e} (tol {e.tol:.1e}) {e.error or ''}"
        f" - {e.name}"
        for e in result.evidence
    )
    assert result.ok, (
        f"{result.id}: outcome {result.outcome!r}, recorded {result.expected!r}\n{details}"
    )
    assert result.evidence, f"{result.id} has no evidence"


def test_every_kernel_is_evaluated_by_the_claims_it_names() -> None:
    payload, _source = load_results()
    for k in payload["kernels"]:
        missing = set(k["claims"]) - set(k["checked_by"])
        assert not missing, f"{k['kernel']}: names {k['claims']}, evaluated by {k['checked_by']}"
