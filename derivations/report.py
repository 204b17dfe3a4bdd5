"""How the book shows a claim: one function, so every page renders claims the same way.

``check("S4")`` runs the registered evidence of a claim (exactly what ``symrb verify S4`` runs),
displays the statement, the printed and corrected forms of an erratum, the note and a table of
the evidence, and raises ``AssertionError`` when the computed outcome differs from the recorded
one, which fails the book build.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from typing import Any

from derivations.registry import ClaimResult, EvidenceResult, get_claim, verify_claim

__all__ = ["plain", "evidence_table", "claim_markdown", "check", "load_results"]


def plain(text: str) -> str:
    """Escape Markdown in plain-text descriptions and notes, leaving ``$...$`` math alone.

    Descriptions are written in ASCII (``u*_k``, ``||M||_op``, ``sum_b[p^b, x^b]``); without
    escaping, ``*``/``_`` become emphasis and ``|`` splits table cells.
    """
    pieces = re.split(r"(\$[^$]+\$)", " ".join(text.split()))
    out = []
    for piece in pieces:
        if piece.startswith("$") and piece.endswith("$") and len(piece) > 1:
            out.append(piece.replace("|", r"\vert "))
        else:
            out.append(re.sub(r"([*_|\\`<>\[\]])", r"\\\1", piece))
    return "".join(out)


def _fmt_residual(e: Mapping[str, Any]) -> str:
    if e.get("error"):
        return "error: " + plain(str(e["error"]))
    return f"{e['residual']:.2e}"


def evidence_table(evidence: Iterable[EvidenceResult | Mapping[str, Any]]) -> str:
    """A Markdown table of evidence results (objects or the dicts of ``verify --json``)."""
    rows = [
        "| form | level | evidence | residual | tol | time |",
        "|---|---|---|---|---|---|",
    ]
    for ev in evidence:
        e = ev.to_dict() if isinstance(ev, EvidenceResult) else ev
        rows.append(
            f"| {e['form']} | {e['level']} | {plain(e['description'])} | {_fmt_residual(e)} "
            f"| {e['tol']:.0e} | {e['seconds']:.3f} s |"
        )
    return "\n".join(rows)


def claim_markdown(result: ClaimResult) -> str:
    """Statement, erratum (printed/corrected), note, outcome and evidence table of a claim."""
    claim = get_claim(result.id)
    parts = [f"**{claim.id}** (`{claim.label}`): {claim.render('statement')}"]
    if claim.printed:
        parts.append(f"*Printed in the paper:* {claim.render('printed')}")
        parts.append(f"*Corrected:* {claim.render('corrected')}")
    if claim.note:
        parts.append(f"*Note:* {plain(claim.note)}")
    parts.append(f"Outcome: **{result.outcome}** (recorded: {claim.expected}).")
    parts.append(evidence_table(result.evidence))
    return "\n\n".join(parts)


def check(cid: str, show: bool = True) -> ClaimResult:
    """Run claim ``cid``'s evidence, display it (in a notebook), and assert the recorded outcome."""
    result = verify_claim(get_claim(cid))
    if show:
        from IPython.display import Markdown, display

        display(Markdown(claim_markdown(result)))
    failing = [
        f"[{e.form}] {e.description}: residual {e.residual:.3e} (tol {e.tol:.0e}) {e.error or ''}"
        for e in result.evidence
        if not e.as_expected
    ]
    assert result.ok, (
        f"{cid}: outcome {result.outcome!r}, recorded {result.expected!r}; " + "; ".join(failing)
    )
    return result


def load_results(build_dir: str = "_build") -> tuple[dict[str, Any], str]:
    """The results of ``symrb verify --output <build_dir>/verify.json`` (written before the book
    build), or of a run here when that file is missing; checked against the registry.

    Returns ``(payload, source)`` with ``payload = {"claims": [...], "kernels": [...]}``.
    """
    import json
    from pathlib import Path

    from derivations.registry import all_claims, kernel_report, verify

    path = Path(build_dir) / "verify.json"
    if path.exists():
        payload = json.loads(path.read_text())
        source = f"`{path.as_posix()}`, written by `symrb verify` before this build"
    else:
        results = verify()
        payload = {"claims": [r.to_dict() for r in results], "kernels": kernel_report()}
        source = "a run of the evidence during this build (no verify.json was found)"
    ids = [r["id"] for r in payload["claims"]]
    registered = [c.id for c in all_claims()]
    assert ids == registered, f"{path} covers {ids}, the registry has {registered}: rerun verify"
    bad = [r["id"] for r in payload["claims"] if not r["ok"]]
    assert not bad, f"computed outcome differs from the record for {bad}"
    return payload, source
