"""How the book shows a claim: one function, so every page renders claims the same way.

``check("S4")`` displays a claim's statement, the printed and corrected forms of an erratum, the
note and a table of its evidence, from the one run of every claim's evidence that the build makes
(``symrb verify --output book/_build/verify.json``, reused when it was written for the current
code), and raises ``AssertionError`` when the computed outcome differs from the recorded one,
which fails the book build.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Iterable, Mapping
from typing import Any

from derivations.registry import ClaimResult, EvidenceResult, get_claim

__all__ = [
    "plain",
    "evidence_table",
    "claim_markdown",
    "check",
    "load_results",
    "result_of",
    "source_hash",
    "verify_json_path",
]


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


def source_hash() -> str:
    """SHA-256 of every Python file of ``derivations`` and ``symrb`` (paths and contents): the
    code a verify run checked.  Results recorded with another hash are stale."""
    import hashlib
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent
    h = hashlib.sha256()
    for package in ("derivations", "symrb"):
        for path in sorted((root / package).rglob("*.py")):
            h.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes())
    return h.hexdigest()


def verify_json_path() -> Any:
    """Where the book build writes ``symrb verify --output``: ``book/_build/verify.json``."""
    from pathlib import Path

    return Path(__file__).resolve().parent.parent / "book" / "_build" / "verify.json"


@functools.cache
def _run_all() -> dict[str, Any]:
    from derivations.registry import kernel_report, verify

    results = verify()
    return {
        "source_hash": source_hash(),
        "claims": [r.to_dict() for r in results],
        "kernels": kernel_report(),
    }


def load_results() -> tuple[dict[str, Any], str]:
    """Every claim's results, computed once: read from ``book/_build/verify.json`` when that file
    was written for the current code (same :func:`source_hash`), else by running the evidence
    here (once per process).  Checked against the registry; asserts that every outcome is as
    recorded.

    Returns ``(payload, source)`` with ``payload = {"claims": [...], "kernels": [...], ...}``
    and ``source`` saying where the results come from.
    """
    import json

    from derivations.registry import all_claims

    path = verify_json_path()
    payload = json.loads(path.read_text()) if path.exists() else None
    if payload is not None and payload.get("source_hash") == source_hash():
        source = "`book/_build/verify.json`, written by `symrb verify` for this code"
    else:
        payload = _run_all()
        source = "a run of the evidence in this process (no current verify.json was found)"
    ids = [r["id"] for r in payload["claims"]]
    registered = [c.id for c in all_claims()]
    assert ids == registered, f"results cover {ids}, the registry has {registered}"
    bad = [r["id"] for r in payload["claims"] if not r["ok"]]
    assert not bad, f"computed outcome differs from the record for {bad}"
    return payload, source


def result_of(cid: str) -> ClaimResult:
    """The recorded run of claim ``cid`` (see :func:`load_results`) as a :class:`ClaimResult`."""
    payload, _source = load_results()
    (r,) = [r for r in payload["claims"] if r["id"] == cid.upper()]
    fields = ("level", "description", "form", "residual", "tol", "seconds", "name", "error")
    evidence = [EvidenceResult(**{k: e.get(k) for k in fields}) for e in r["evidence"]]
    return ClaimResult(
        id=r["id"], label=r["label"], title=r["title"], expected=r["expected"],
        outcome=r["outcome"], evidence=evidence,
    )  # fmt: skip


def check(cid: str, show: bool = True) -> ClaimResult:
    """Show claim ``cid`` (statement, printed and corrected forms, note, evidence) from the run of
    :func:`load_results` and assert its recorded outcome (which fails the book build)."""
    result = result_of(cid)
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
