"""The claim registry: every statement of the paper that symrb reproduces, stated once.

A :class:`Claim` carries our ID (``D1``..``D12``, ``S1``..``S15`` from ``CLAIMS.md``), the paper's
``\\label``, the statement in LaTeX, the outcome we expect, and pieces of :class:`Evidence`.  Each
piece of evidence is a function returning a non-negative *residual* that is zero (up to its
tolerance) exactly when what it checks is true, run at one :class:`Level` (symbolic for general n,
symbolic for fixed n, exact rational, float64, high precision).

Evidence is tagged with the *form* it checks:

``"claim"``
    the statement as printed, which we expect to hold;
``"printed"``
    the statement exactly as printed, which we expect to *fail* (an erratum): its residual must be
    above tolerance, otherwise the erratum is not proven;
``"corrected"``
    our corrected statement, which must hold.

The outcome of a claim is computed, never typed in:

* ``holds``: every ``claim`` evidence passes;
* ``holds after correction``: every ``printed`` evidence fails and every ``corrected`` one passes;
* ``fails``: some printed-form evidence fails and no correction is registered;
* ``not checkable``: there is no evidence.

Claims live in the modules of :mod:`derivations.parts`; each module defines a list ``CLAIMS``.
The registry discovers them, so adding a part never edits this file.
"""

from __future__ import annotations

import enum
import importlib
import pkgutil
import re
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

__all__ = [
    "Level",
    "Evidence",
    "Claim",
    "EvidenceResult",
    "ClaimResult",
    "all_claims",
    "get_claim",
    "verify",
    "verify_claim",
    "OUTCOMES",
]

OUTCOMES = ("holds", "holds after correction", "fails", "not checkable")
Outcome = Literal["holds", "holds after correction", "fails", "not checkable"]
Form = Literal["claim", "printed", "corrected"]


class Level(enum.StrEnum):
    """Evidence levels, strongest first."""

    SYMBOLIC_GENERAL_N = "symbolic, general n"
    SYMBOLIC_FIXED_N = "symbolic, fixed n"
    EXACT_RATIONAL = "exact rational"
    FLOAT64 = "float64"
    MPMATH = "high precision"

    def __str__(self) -> str:  # pragma: no cover - trivial
        return self.value


@dataclass(frozen=True)
class Evidence:
    """One check of a claim.

    Parameters
    ----------
    level:
        How strong the check is (see :class:`Level`).
    description:
        One sentence: what is computed.
    func:
        Called with no arguments; returns the residual (a float >= 0, or anything ``float()``
        accepts, e.g. a SymPy zero).
    tol:
        The check passes when ``residual <= tol``.  Symbolic checks use ``tol=0``.
    form:
        ``"claim"``, ``"printed"`` (expected to fail) or ``"corrected"`` (expected to hold).
    """

    level: Level
    description: str
    func: Callable[[], Any]
    tol: float = 0.0
    form: Form = "claim"


@dataclass(frozen=True)
class Claim:
    """A statement of the paper.

    ``statement`` is the statement in our words (LaTeX allowed).  For an erratum, ``printed`` is the
    form printed in the paper and ``corrected`` the form that holds; ``note`` explains the finding.
    ``expected`` is the outcome recorded for the claim: :func:`verify` reports a mismatch as a
    failure, so a claim whose evidence changes behaviour is noticed.
    """

    id: str
    label: str
    title: str
    statement: str
    expected: Outcome
    evidence: tuple[Evidence, ...] = ()
    printed: str | None = None
    corrected: str | None = None
    note: str = ""
    section: str = ""

    def __post_init__(self) -> None:
        if not re.fullmatch(r"[DS]\d+", self.id):
            raise ValueError(f"claim id must look like D1 or S12, got {self.id!r}")
        if self.expected not in OUTCOMES:
            raise ValueError(
                f"claim {self.id}: expected must be one of {OUTCOMES}, got {self.expected!r}"
            )
        forms = {e.form for e in self.evidence}
        if ("printed" in forms or "corrected" in forms) and not (self.printed and self.corrected):
            raise ValueError(f"claim {self.id}: printed/corrected evidence needs both texts")


@dataclass
class EvidenceResult:
    level: str
    description: str
    form: str
    residual: float
    tol: float
    seconds: float
    error: str | None = None

    @property
    def passed(self) -> bool:
        """True when the residual is within tolerance (and the evidence ran)."""
        return bool(self.error is None and self.residual <= self.tol)

    @property
    def as_expected(self) -> bool:
        """Printed-form evidence is expected to fail; everything else to pass."""
        if self.error is not None:
            return False
        return (not self.passed) if self.form == "printed" else self.passed

    def to_dict(self) -> dict[str, Any]:
        return {
            "level": self.level,
            "description": self.description,
            "form": self.form,
            "residual": self.residual,
            "tol": self.tol,
            "seconds": self.seconds,
            "passed": self.passed,
            "error": self.error,
        }


@dataclass
class ClaimResult:
    id: str
    label: str
    title: str
    expected: str
    outcome: str
    evidence: list[EvidenceResult] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """True when the computed outcome equals the recorded one."""
        return self.outcome == self.expected

    @property
    def seconds(self) -> float:
        return sum(e.seconds for e in self.evidence)

    def to_dict(self) -> dict[str, Any]:
        return {
            "id": self.id,
            "label": self.label,
            "title": self.title,
            "expected": self.expected,
            "outcome": self.outcome,
            "ok": self.ok,
            "seconds": self.seconds,
            "evidence": [e.to_dict() for e in self.evidence],
        }


def _claim_key(cid: str) -> tuple[int, int]:
    return (0 if cid[0] == "D" else 1, int(cid[1:]))


def all_claims() -> list[Claim]:
    """Every registered claim, in the order D1..D12, S1..S15 (discovered from derivations.parts)."""
    from derivations import parts

    claims: dict[str, Claim] = {}
    for info in sorted(pkgutil.iter_modules(parts.__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{parts.__name__}.{info.name}")
        for claim in getattr(module, "CLAIMS", ()):
            if claim.id in claims:
                raise ValueError(f"claim {claim.id} registered twice (again in {module.__name__})")
            claims[claim.id] = claim
    return [claims[k] for k in sorted(claims, key=_claim_key)]


def get_claim(cid: str) -> Claim:
    """The claim with ID ``cid`` (case-insensitive); ``KeyError`` listing the known IDs otherwise."""
    claims = {c.id: c for c in all_claims()}
    key = cid.upper()
    if key not in claims:
        raise KeyError(f"unknown claim id {cid!r}; registered: {', '.join(claims)}")
    return claims[key]


def _run_evidence(ev: Evidence) -> EvidenceResult:
    start = time.perf_counter()
    error = None
    try:
        value = ev.func()
        residual = float(abs(complex(value)))
        if residual != residual:  # NaN
            error = "residual is NaN"
            residual = float("inf")
    except Exception as exc:  # an evidence that crashes is reported, not hidden
        error = f"{type(exc).__name__}: {exc}"
        residual = float("inf")
    seconds = time.perf_counter() - start
    return EvidenceResult(
        level=Level(ev.level).value,
        description=ev.description,
        form=ev.form,
        residual=residual,
        tol=ev.tol,
        seconds=seconds,
        error=error,
    )


def outcome_of(results: Sequence[EvidenceResult]) -> Outcome:
    """Compute the outcome of a claim from its evidence results (see the module docstring)."""
    if not results:
        return "not checkable"
    if any(r.error is not None for r in results):
        return "fails"
    claim_ev = [r for r in results if r.form == "claim"]
    printed = [r for r in results if r.form == "printed"]
    corrected = [r for r in results if r.form == "corrected"]
    if printed or corrected:
        printed_fails = bool(printed) and all(not r.passed for r in printed)
        corrected_holds = bool(corrected) and all(r.passed for r in corrected)
        claim_holds = all(r.passed for r in claim_ev)
        if printed_fails and corrected_holds and claim_holds:
            return "holds after correction"
        if not printed_fails and corrected_holds and claim_holds:
            return "holds"  # the printed form was fine after all
        return "fails"
    return "holds" if all(r.passed for r in claim_ev) else "fails"


def verify_claim(claim: Claim) -> ClaimResult:
    """Run every piece of evidence of ``claim`` and compute its outcome."""
    results = [_run_evidence(ev) for ev in claim.evidence]
    return ClaimResult(
        id=claim.id,
        label=claim.label,
        title=claim.title,
        expected=claim.expected,
        outcome=outcome_of(results),
        evidence=results,
    )


def verify(ids: Iterable[str] | None = None, progress: bool = False) -> list[ClaimResult]:
    """Verify the claims with the given IDs (all when ``None``), in registry order."""
    claims = all_claims() if ids is None else [get_claim(i) for i in ids]
    out = []
    for claim in claims:
        if progress:
            print(f"  verifying {claim.id} ...", flush=True)
        out.append(verify_claim(claim))
    return out
