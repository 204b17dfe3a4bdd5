"""Every registered claim of the paper gets its recorded outcome (parametrised over the registry)."""

from __future__ import annotations

import pytest

from derivations.registry import Claim, all_claims, verify_claim

CLAIMS = all_claims()


def test_registry_ids_are_those_of_claims_md() -> None:
    allowed = {f"D{i}" for i in range(1, 13)} | {f"S{i}" for i in range(1, 16)}
    ids = [c.id for c in CLAIMS]
    assert set(ids) <= allowed, set(ids) - allowed
    assert len(ids) == len(set(ids))


@pytest.mark.parametrize("claim", CLAIMS, ids=[c.id for c in CLAIMS])
def test_claim_outcome(claim: Claim) -> None:
    result = verify_claim(claim)
    details = "\n".join(
        f"  [{e.form}] {e.level}: residual {e.residual:.3e} (tol {e.tol:.1e}) {e.error or ''} - {e.description}"
        for e in result.evidence
    )
    assert result.ok, (
        f"{claim.id}: outcome {result.outcome!r}, recorded {claim.expected!r}\n{details}"
    )
    # an outcome is only as good as its evidence: every claim has some
    assert result.evidence, f"{claim.id} has no evidence"
