"""How the book shows claims: one module, so every page renders them the same way.

``check("S4")`` displays a claim, the verdict first (:func:`claim_markdown`): its outcome with an
erratum's correction in one line, a summary of its evidence by form (:func:`evidence_summary`),
then its statement, the printed and corrected forms of an erratum, the note, the table of its
evidence (collapsed when long) and, in a collapsed dropdown, the map of the paper's sentences to
that evidence (:func:`sentences_markdown`), from the one run of every claim's evidence that the
build makes (``symrb verify --output book/_build/verify.json``, reused when it was written for the
current code), and raises ``AssertionError`` when the computed outcome differs from the recorded one,
which fails the book build; it also places the label ``claim-s4`` (:func:`anchor_of`) there, the
target of every link to the claim's check (:func:`claim_link`).  :func:`claims_table` and
:func:`claims_summary` are the claims page, one table per claim group (:func:`by_group`: the
paper's claims, then symrb's own methods), with :func:`sentences_summary` counting the sentences of
the paper's statements that evidence covers; :func:`verdict_table` is the book's first page: every
claim of the paper, its outcome and, for an erratum, the correction in one line
(:func:`correction_line`).
"""

from __future__ import annotations

import functools
import hashlib
import json
import re
from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from derivations.registry import (
    GROUPS,
    OUTCOMES,
    ClaimResult,
    EvidenceResult,
    all_claims,
    get_claim,
    grouped,
    kernel_report,
    verify,
)

__all__ = [
    "plain",
    "prose",
    "short_where",
    "breakable",
    "evidence_table",
    "evidence_summary",
    "OPEN_EVIDENCE",
    "FORM_ROWS",
    "claim_markdown",
    "check",
    "load_results",
    "result_from_dict",
    "result_of",
    "by_group",
    "claims_table",
    "claims_summary",
    "sentence_counts",
    "sentences_summary",
    "sentences_markdown",
    "sentences_cell",
    "source_hash",
    "verify_json_path",
    "sentences",
    "summary_of",
    "anchor_of",
    "check_pages",
    "claim_link",
    "correction_line",
    "verdict_table",
]


def plain(text: str) -> str:
    """Escape Markdown in plain-text descriptions and notes, leaving ``$...$`` math alone.

    Descriptions keep their mathematics in ``$...$``; the words around it may still hold
    Markdown characters (``symrb.learning.resnet_forward``, ``lhs - rhs``, ``|``), and without
    escaping ``*``/``_`` become emphasis and ``|`` splits table cells.
    """
    pieces = re.split(r"(\$[^$]+\$)", " ".join(text.split()))
    out = []
    for piece in pieces:
        if piece.startswith("$") and piece.endswith("$") and len(piece) > 1:
            out.append(piece.replace("\\|", r"\Vert ").replace("|", r"\vert "))
        else:
            out.append(re.sub(r"([*_|\\`<>\[\]])", r"\\\1", piece))
    return "".join(out)


def prose(text: str, cell: bool = False) -> str:
    """A claim's ``title``, ``note`` or ``where``, which are Markdown with ``$...$`` math, ready to
    embed in a page: whitespace made single, and with ``cell=True`` (inside a Markdown table) no
    ``|`` left to split the cell (``\\|`` in text; ``\\Vert``/``\\vert`` in math)."""
    text = " ".join(text.split())
    if not cell:
        return text
    out = []
    for piece in re.split(r"(\$[^$]+\$)", text):
        if len(piece) > 1 and piece.startswith("$") and piece.endswith("$"):
            out.append(piece.replace("\\|", r"\Vert ").replace("|", r"\vert "))
        else:
            out.append(re.sub(r"(?<!\\)\|", r"\|", piece))
    return "".join(out)


def _math_pieces(text: str) -> list[tuple[bool, str]]:
    """``text`` cut into ``(is_math, piece)`` pieces at its ``$...$`` formulas."""
    pieces = re.split(r"(\$[^$]+\$)", text)
    return [(p.startswith("$") and p.endswith("$") and len(p) > 1, p) for p in pieces]


def short_where(where: str) -> str:
    """``where`` without its parentheses and without what follows its first colon: the section
    and the item, for a table."""
    out: list[str] = []
    depth = 0
    for is_math, piece in _math_pieces(where):
        if is_math:
            if not depth:
                out.append(piece)
            continue
        for ch in piece:
            depth += ch == "("
            if not depth:
                out.append(ch)
            depth -= ch == ")" and depth > 0
    text = " ".join("".join(out).split()).replace(" ,", ",")
    head = []
    for is_math, piece in _math_pieces(text):
        if not is_math and ": " in piece:
            head.append(piece.split(": ", 1)[0])
            break
        head.append(piece)
    return "".join(head).strip()


_TEX_TOKEN = re.compile(r"\\[A-Za-z]+|\\.|\s+|.", re.DOTALL)
_RELATIONS = {
    "=", "<", ">", r"\le", r"\leq", r"\ge", r"\geq", r"\ne", r"\neq", r"\approx", r"\equiv",
    r"\mapsto", r"\to", r"\rightarrow", r"\sim",
}  # fmt: skip
_OPENERS = {"(": ")", "[": "]", r"\langle": r"\rangle", r"\{": r"\}", r"\begin": r"\end"}
_BREAK_AFTER = {",", r"\quad", r"\qquad"}
_UNSEEN = {"{", "}", "_", "^", r"\left", r"\right", r"\limits", r"\,", r"\;", r"\!", r"\quad"}
_TALL = {r"\frac", r"\sum", r"\int", r"\prod"}


def _tex_width(tokens: list[str]) -> int:
    """A rough width of TeX tokens, in symbols (grouping and scripts count nothing)."""
    return sum(1 for t in tokens if t.strip() and t not in _UNSEEN)


def _after(tokens: list[str], i: int) -> int:
    """The index of the first token after ``i`` that is not a space."""
    j = i + 1
    while j < len(tokens) and tokens[j].isspace():
        j += 1
    return j


def _closing_right(tokens: list[str], i: int) -> int:
    """The index of the ``\\right`` closing the ``\\left`` at ``i`` (-1 when there is none)."""
    depth = 0
    for j in range(i, len(tokens)):
        depth += (tokens[j] == r"\left") - (tokens[j] == r"\right")
        if depth == 0:
            return j
    return -1


def _split_tex(tex: str, limit: int) -> list[str]:
    """Cut a formula where a line may break: after a relation, a binary ``+``/``-``, a comma or a
    ``\\quad`` at its top level.  A ``\\left``...``\\right`` pair at the top level
    that is wider than ``limit`` becomes a ``\\bigl``...``\\bigr`` pair (``\\Bigl``...``\\Bigr``
    around fractions, sums and integrals), whose inside may then break too.  An operator that
    ends a piece is followed by ``{}`` so that TeX keeps its spacing."""
    tokens = _TEX_TOKEN.findall(tex)
    pieces: list[list[str]] = [[]]
    stack: list[str] = []  # the token that closes each open group
    last = ""  # the last thing at the top level: "" (nothing), "op", "open" or "x" (an operand)
    i = 0
    while i < len(tokens):
        t = tokens[i]
        if t in (r"\left", r"\right"):
            d = _after(tokens, i)
            if t == r"\left":
                close = _closing_right(tokens, i)
                rd = _after(tokens, close) if close > 0 else len(tokens)
                wide = _tex_width(tokens[i:close]) > limit
                if not stack and rd < len(tokens) and d < close and wide:
                    size = "B" if _TALL & set(tokens[d + 1 : close]) else "b"
                    opening = "" if tokens[d] == "." else f"\\{size}igl{tokens[d]}"
                    closing = "" if tokens[rd] == "." else f"\\{size}igr{tokens[rd]}"
                    tokens = tokens[:i] + tokens[d + 1 : close] + [closing] + tokens[rd + 1 :]
                    pieces[-1].append(opening)
                    last = "open"
                    continue
                stack.append(r"\right")
            elif stack and stack[-1] == r"\right":
                stack.pop()
            pieces[-1].extend(tokens[i : d + 1])
            i = d + 1
            last = last if stack else "x"
            continue
        top = not stack
        if t in _OPENERS:
            stack.append(_OPENERS[t])
        elif t == "{":
            stack.append("}")
        elif stack and t == stack[-1]:
            stack.pop()
        if top and t.strip():
            pieces[-1].append(t)
            operator = (t in _RELATIONS and last) or (t in ("+", "-") and last == "x")
            if operator:
                pieces[-1].append("{}")
            nxt = tokens[_after(tokens, i)] if _after(tokens, i) < len(tokens) else ""
            if operator or (t in _BREAK_AFTER and nxt not in _BREAK_AFTER):
                pieces.append([])
            if t in _RELATIONS or t in ("+", "-", ","):
                last = "op"
            elif t in _OPENERS or t == "{":
                last = "open"
            elif t not in (r"\quad", r"\qquad"):
                last = "x"
        else:
            pieces[-1].append(t)
            if not stack and t.strip():
                last = "x"  # a group just closed at the top level
        i += 1
    out = ["".join(p).strip() for p in pieces]
    return [p for p in out if p]


def breakable(text: str, limit: int = 24) -> str:
    """``text`` with every ``$...$`` formula wider than ``limit`` symbols cut into several
    formulas separated by spaces, where a line may break (MathJax 3 never breaks a formula, so a
    long one would be cut off or scroll in a narrow column).  Display math is left alone."""

    def cut(m: re.Match[str]) -> str:
        tex = m.group(1)
        if _tex_width(_TEX_TOKEN.findall(tex)) <= limit:
            return m.group(0)
        return " ".join(f"${piece}$" for piece in _split_tex(tex, limit))

    return re.sub(r"(?<![$\\])\$([^$]+)\$(?!\$)", cut, text)


def evidence_table(evidence: Iterable[EvidenceResult | Mapping[str, Any]]) -> str:
    """A Markdown table of evidence results (objects or the dicts of ``verify --json``): number,
    form and level, what is checked and the residual against the tolerance (typeset).  Four
    columns, and long formulas in the descriptions cut where a line may break
    (:func:`breakable`), so that it fits the content column inside a dropdown (the time a
    claim's checks take is on the claims page, by level on the evidence page)."""
    rows = [
        "| # | form, level | what is checked | residual vs tolerance |",
        "|---|---|---|---|",
    ]
    for k, ev in enumerate(evidence, 1):
        e = ev.to_dict() if isinstance(ev, EvidenceResult) else ev
        level = SHORT_LEVELS.get(e["level"], e["level"])
        what = breakable(plain(e["description"]))
        rows.append(f"| {k} | {e['form']}, {level} | {what} | {_against(e)} |")
    return "\n".join(rows)


#: A claim with at most this many checks shows its evidence table open under the verdict; a
#: longer one is collapsed (its summary by form stays in view, so the page stays short).
OPEN_EVIDENCE = 5

#: The rows of the verdict's summary: each form of evidence, what it checks and what it must do.
FORM_ROWS = {
    "claim": ("the statement as printed", "pass"),
    "printed": ("the erratum as printed (must fail)", "fail"),
    "corrected": ("the correction", "pass"),
}


def _ratio(e: EvidenceResult | Mapping[str, Any]) -> tuple[float, float]:
    """How close a check (a result or its dict) came to its tolerance: residual over tolerance
    (an exact check, tol 0, is 0 when it holds and infinite when not), then the residual; an
    error is infinitely far."""
    d = e.to_dict() if isinstance(e, EvidenceResult) else e
    residual, tol = d["residual"], d["tol"]
    if d.get("error") is not None or residual is None or residual != residual:
        return float("inf"), float("inf")
    if tol:
        return residual / tol, residual
    return (0.0 if residual == 0 else float("inf")), residual


def _tex_number(x: float) -> str:
    """``x`` as typeset math: ``8.1\\times10^{-16}``, ``10^{-13}``, ``3`` (a number in a table
    cell neither breaks at its exponent's minus nor reads as ``e-16``)."""
    if (x == 0 or 0.01 <= abs(x) < 100) and "e" not in f"{x:.2g}":
        return f"{x:.2g}"
    mantissa, exponent = f"{x:.1e}".split("e")
    power = f"10^{{{int(exponent)}}}"
    return power if mantissa == "1.0" else f"{mantissa}\\times{power}"


def _against(e: Mapping[str, Any], one_line: bool = False) -> str:
    """``$8.1\\times10^{-16}$ $\\le 10^{-13}$``: a check's residual against its tolerance, typeset
    (``exact (0)`` for a zero residual at tolerance 0, the message for an error).  Two formulas,
    so that a narrow column may break the line before the sign (never inside a number); one
    with ``one_line``, which keeps a column of a wide table from narrowing below it."""
    if e.get("error"):
        return "error: " + plain(str(e["error"]))
    residual, tol = e["residual"], e["tol"]
    join = " " if one_line else "$ $"
    if tol == 0:
        return "exact (0)" if residual == 0 else f"${_tex_number(residual)}{join}> 0$"
    sign = r"\le" if residual <= tol else ">"
    return f"${_tex_number(residual)}{join}{sign} {_tex_number(tol)}$"


def _call(k: int, e: EvidenceResult) -> str:
    """``#19: $8.1\\times10^{-16}$ $\\le 10^{-13}$``: check ``k`` (its number in the evidence
    table) against its tolerance."""
    return f"#{k}: error" if e.error is not None else f"#{k}: {_against(e.to_dict())}"


def evidence_summary(evidence: Sequence[EvidenceResult]) -> str:
    """The verdict's evidence in a few lines: a Markdown table with one row per form of evidence
    (the statement as printed, the printed form of an erratum, the correction), the number of
    checks by level, whether they pass or fail as they must, and the decisive check: of those
    that must pass the closest to its tolerance, of those that must fail the closest to passing,
    by its number in the full evidence table; a check not as it must be is named in bold."""
    rows = [
        "| checks of | checks by level | result | closest call (# in the table) |",
        "|---|---|---|---|",
    ]
    numbered = list(enumerate(evidence, 1))
    for form, (what, must) in FORM_ROWS.items():
        mine = [(k, e) for k, e in numbered if e.form == form]
        if not mine:
            continue
        levels = _levels_cell([{"level": e.level} for _k, e in mine])
        wrong = [k for k, e in mine if not e.as_expected]
        verb = "pass" if must == "pass" else "fail"
        if wrong:
            result = (
                f"**{len(wrong)} of {len(mine)} do not {verb}: #{', #'.join(map(str, wrong))}**"
            )
        else:
            result = {1: f"it {verb}{'es' if verb == 'pass' else 's'}", 2: f"both {verb}"}.get(
                len(mine), f"all {len(mine)} {verb}"
            )
        if must == "pass":
            k, e = max(mine, key=lambda ke: _ratio(ke[1]))
        else:
            k, e = min(mine, key=lambda ke: _ratio(ke[1]))
        rows.append(f"| {what} | {levels} | {result} | {_call(k, e)} |")
    return "\n".join(rows)


def _verdict(result: ClaimResult) -> str:
    """``**Verdict on D7: holds after correction.** **Corrected:** ...``: the outcome (for an
    erratum a link to its page of the errata, and its correction in one line) and the recorded
    outcome when they differ."""
    outcome = _outcome_cell({"id": result.id, "outcome": result.outcome,
                             "expected": result.expected})  # fmt: skip
    text = f"**Verdict on {result.id}: {outcome}.**"
    fixed = correction_line(result.id)
    if fixed:
        text += f" **Corrected:** {breakable(fixed)}."
    return text


def claim_markdown(result: ClaimResult) -> str:
    """A claim as the book shows it, the verdict first: the verdict (with an erratum's correction
    in one line), the evidence summary by form (:func:`evidence_summary`), then where the claim is
    in the paper and its statement, the printed and corrected forms, the note,
    the full evidence table (collapsed for more than :data:`OPEN_EVIDENCE` checks) and the
    map of the paper's sentences (:func:`sentences_markdown`)."""
    claim = get_claim(result.id)
    pieces = [prose(short_where(claim.where))] if claim.where else []
    if claim.label:  # a method check of symrb's own has no label in the paper
        pieces.append(f"LaTeX label `{claim.label}`")
    head = f"**{claim.id}** ({'; '.join(pieces)})" if pieces else f"**{claim.id}**"
    parts = [_verdict(result), evidence_summary(result.evidence)]
    parts.append(f"{head}: {breakable(claim.render('statement'))}")
    if claim.printed:
        parts.append(f"*Printed in the paper:* {breakable(claim.render('printed'))}")
        parts.append(f"*Corrected:* {breakable(claim.render('corrected'))}")
    if claim.note:
        parts.append(f"*Note:* {prose(claim.note)}")
    n = len(result.evidence)
    if n:
        counts = Counter(e.form for e in result.evidence)
        by_form = ", ".join(f"{counts[f]} of {FORM_ROWS[f][0]}" for f in FORM_ROWS if counts[f])
        title = f"The evidence: {n} check{'s' * (n != 1)} ({by_form}), each with its residual"
        open_ = [":open:"] if n <= OPEN_EVIDENCE else []
        parts.append("\n".join([f":::{{dropdown}} {title}", *open_, "",
                                evidence_table(result.evidence), ":::"]))  # fmt: skip
    if claim.sentences:
        parts.append(sentences_markdown(claim.id))
    return "\n\n".join(parts)


def source_hash() -> str:
    """SHA-256 of every Python file of ``derivations`` and ``symrb`` (paths and contents): the
    code a verify run checked.  Results recorded with another hash are stale."""
    root = Path(__file__).resolve().parent.parent
    h = hashlib.sha256()
    for package in ("derivations", "symrb"):
        for path in sorted((root / package).rglob("*.py")):
            h.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes())
    return h.hexdigest()


def verify_json_path() -> Path:
    """Where the book build writes ``symrb verify --output``: ``book/_build/verify.json``."""
    return Path(__file__).resolve().parent.parent / "book" / "_build" / "verify.json"


@functools.cache
def _run_all() -> dict[str, Any]:
    from derivations import coverage

    with coverage.recording() as recorder:
        results = verify()
    return {
        "source_hash": source_hash(),
        "claims": [r.to_dict() for r in results],
        "kernels": kernel_report(),
        "coverage": coverage.report(recorder),
    }


def load_results() -> tuple[dict[str, Any], str]:
    """Every claim's results, computed once: read from ``book/_build/verify.json`` when that file
    was written for the current code (same :func:`source_hash`), else by running the evidence
    here (once per process).  Checked against the registry; asserts that every outcome is as
    recorded.

    Returns ``(payload, source)`` with ``payload = {"claims": [...], "kernels": [...], ...}``
    and ``source`` saying where the results come from.
    """
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
    return result_from_dict(r)


def result_from_dict(r: Mapping[str, Any]) -> ClaimResult:
    """A :class:`ClaimResult` from its dict in ``verify --json`` (``ClaimResult.to_dict``)."""
    fields = ("level", "description", "form", "residual", "tol", "seconds", "name", "error")
    evidence = [EvidenceResult(**{k: e.get(k) for k in fields}) for e in r["evidence"]]
    return ClaimResult(
        id=r["id"], label=r["label"], title=r["title"], expected=r["expected"],
        outcome=r["outcome"], evidence=evidence,
    )  # fmt: skip


def check(cid: str, show: bool = True, anchor: bool = True) -> ClaimResult:
    """Show claim ``cid`` (statement, printed and corrected forms, note, evidence) from the run of
    :func:`load_results` and assert its recorded outcome (which fails the book build).

    With ``anchor`` (the default) the display starts with the label :func:`anchor_of` that the
    claims and verdict tables link to; a claim is shown so on exactly one page of the book (its
    home, :func:`check_pages`), so pass ``anchor=False`` to show it a second time elsewhere.
    """
    result = result_of(cid)
    if show:
        from IPython.display import Markdown, display

        label = f"({anchor_of(cid)})=\n\n" if anchor else ""
        display(Markdown(label + claim_markdown(result)))
    failing = [
        f"[{e.form}] {e.description}: residual {e.residual:.3e} (tol {e.tol:.0e}) {e.error or ''}"
        for e in result.evidence
        if not e.as_expected
    ]
    assert result.ok, (
        f"{cid}: outcome {result.outcome!r}, recorded {result.expected!r}; " + "; ".join(failing)
    )
    return result


# ---------------------------------------------------------------------------------------------
# the claims page: one table per group (the paper's claims, symrb's own methods)

#: Evidence levels as the tables show them, strongest first.
SHORT_LEVELS = {
    "symbolic, general n": "symbolic (all n)",
    "symbolic, fixed n": "symbolic (fixed n)",
    "exact rational": "exact rational",
    "float64": "float64",
    "high precision": "high precision",
}


def by_group(results: Sequence[Mapping[str, Any]]) -> list[tuple[str, list[Any]]]:
    """``[(title, results), ...]``: the results (dicts of ``verify --json``) of each claim group
    that has any, in the order of :data:`~derivations.registry.GROUP_TITLES`."""
    return grouped(results, lambda r: str(r["id"]))


def _seconds_cell(s: float) -> str:
    return f"{s:.2f}\N{NO-BREAK SPACE}s" if s >= 0.01 else f"{s * 1000:.1f}\N{NO-BREAK SPACE}ms"


def _levels_cell(evidence: Sequence[Mapping[str, Any]]) -> str:
    """How many checks at each level, strongest first, on one line."""
    counts = Counter(e["level"] for e in evidence)
    return ", ".join(f"{counts[lv]} {short}" for lv, short in SHORT_LEVELS.items() if counts[lv])


#: The levels whose checks involve no rounding.
EXACT_LEVELS = ("symbolic, general n", "symbolic, fixed n", "exact rational")


def _checks_cell(evidence: Sequence[Mapping[str, Any]]) -> str:
    """``21 checks, 14 without rounding``: how many checks, and how many are symbolic or in
    exact rational arithmetic (the levels are on the claim's page)."""
    exact = sum(e["level"] in EXACT_LEVELS for e in evidence)
    n = len(evidence)
    return f"{n} check{'s' * (n != 1)}, {exact} without rounding"


def _margin_cell(evidence: Sequence[Mapping[str, Any]]) -> str:
    """The closest call: the largest residual/tolerance among checks that must pass, typeset
    (``$1.1\\times10^{-15} \\le 10^{-13}$``, one formula: it holds the column at its width)."""
    worst = max((e for e in evidence if e["form"] != "printed"), key=_ratio)
    if worst["tol"] == 0:
        return "exact\N{NO-BREAK SPACE}(0)"
    return _against(worst, one_line=True)


def _where_cell(cid: str) -> str:
    """Where claim ``cid`` is: for a claim of the paper its section (the item is on the claim's
    page), for a method check the symrb function it backs."""
    text = get_claim(cid).where
    if not text:
        return "(not recorded)"
    section = re.match(r"Section [\d.]+", text)
    if GROUPS[cid[0]] == "paper" and section:
        return section.group()
    return prose(short_where(text), cell=True)


def _outcome_cell(r: Mapping[str, Any]) -> str:
    """The outcome; for an erratum, a link to its page of the errata."""
    outcome = str(r["outcome"])
    if outcome in ERRATA:
        outcome = f"{{ref}}`{outcome} <erratum-{r['id'].lower()}>`"
    if r["outcome"] != r["expected"]:
        outcome += f" (recorded {r['expected']})"
    return outcome


def claims_table(results: Sequence[Mapping[str, Any]]) -> str:
    """The Markdown table of the claims page for ``results`` (dicts of ``verify --json``): ID
    (a link to the claim's check, :func:`claim_link`), title with its section of the paper (for
    a method check: the symrb function it backs), outcome (an erratum's links to its page of the
    errata), for the paper's claims the sentences covered (:func:`sentences_cell`), and the
    evidence: how many checks and how many without rounding, the closest call and the time
    (the checks by level are on the claim's page)."""
    paper = all(GROUPS[r["id"][0]] == "paper" for r in results)
    where = "section of the paper" if paper else "what it backs in symrb"
    sentences = " sentences |" if paper else ""
    rows = [
        f"| ID | claim ({where}) | outcome |{sentences} evidence: checks; closest call "
        "(residual ≤ tolerance); time |",
        "|---|---|---|---|" + "---|" * paper,
    ]
    for r in results:
        covered = f" {sentences_cell(r['id'])} |" if paper else ""
        rows.append(
            f"| {claim_link(r['id'])} | {prose(r['title'], cell=True)} ({_where_cell(r['id'])}) "
            f"| {_outcome_cell(r)} |{covered} {_checks_cell(r['evidence'])}; closest "
            f"{_margin_cell(r['evidence'])}; {_seconds_cell(r['seconds'])} |"
        )
    return "\n".join(rows)


def claims_summary(results: Sequence[Mapping[str, Any]]) -> str:
    """``27 claims (20 holds, 7 holds after correction); every computed outcome equals the
    recorded one. 180 checks ran in 40.0 s`` (``method checks`` for the methods group)."""
    counts = Counter(r["outcome"] for r in results)
    summary = ", ".join(f"{counts[o]} {o}" for o in OUTCOMES if counts[o])
    total = sum(r["seconds"] for r in results)
    nchecks = sum(len(r["evidence"]) for r in results)
    paper = all(GROUPS[r["id"][0]] == "paper" for r in results)
    return (
        f"{len(results)} {'claims' if paper else 'method checks'} ({summary}); every computed "
        f"outcome equals the recorded one. {nchecks} checks ran in {total:.1f} s"
    )


# ---------------------------------------------------------------------------------------------
# the verdict: every claim's check is linked from the tables; an erratum's correction in one line

#: The outcomes listed in the errata.
ERRATA = ("holds after correction", "fails")

_MATH = re.compile(r"(\$[^$]+\$)")
_CHECK_CALL = re.compile(r"""\bcheck\(\s*["']([DSM]\d+)["']\s*(,[^)]*)?\)""")


def sentences(text: str) -> list[str]:
    """The sentences of ``text``: cut after ``.``, ``!`` or ``?`` followed by a space and a
    capital letter, a digit, a bracket, a quote or a formula, never inside ``$...$``."""
    masked = "".join(p[0] + "x" * (len(p) - 1) if m else p for m, p in _math_pieces(text))
    cuts = [m.end() for m in re.finditer(r"(?<=[.!?])\s+(?=[A-Z0-9(\[`'$])", masked)]
    bounds = [0, *cuts, len(text)]
    return [
        text[a:b].strip() for a, b in zip(bounds, bounds[1:], strict=False) if text[a:b].strip()
    ]


def summary_of(note: str) -> tuple[str, str]:
    """What is wrong (the note's first sentence) and the corrected form (its sentence starting
    with ``Corrected:``, without that word); empty strings when the note lacks them."""
    parts = sentences(note)
    wrong = parts[0] if parts and not parts[0].startswith("Corrected:") else ""
    fixed = next(
        (p.removeprefix("Corrected:").strip() for p in parts if p.startswith("Corrected:")), ""
    )
    return wrong, fixed


def anchor_of(cid: str) -> str:
    """``claim-d7``: the label :func:`check` places where claim ``cid``'s check is shown."""
    return f"claim-{cid.lower()}"


def book_dir() -> Path:
    """The book's sources, ``book/`` beside ``derivations/``."""
    return verify_json_path().parent.parent


@functools.cache
def check_pages() -> dict[str, str]:
    """``{"D7": "section2/03_discrete_rigid_body", ...}``: the page of the book that shows each
    claim's check, found as the one ``check("D7")`` call (without ``anchor=False``) in the
    pages' sources.  A claim checked with an anchor on two pages is an error (its label would
    be defined twice)."""
    pages: dict[str, str] = {}
    root = book_dir()
    for path in sorted(root.rglob("*.md")):
        if "_build" in path.parts:
            continue
        doc = path.relative_to(root).with_suffix("").as_posix()
        for m in _CHECK_CALL.finditer(path.read_text(encoding="utf-8")):
            if re.search(r"anchor\s*=\s*False", m.group(2) or ""):
                continue
            cid = m.group(1)
            if cid in pages and pages[cid] != doc:
                raise ValueError(f"check({cid!r}) is anchored on {pages[cid]} and on {doc}")
            pages[cid] = doc
    return pages


def claim_link(cid: str, text: str | None = None) -> str:
    """MyST for a link to where claim ``cid``'s check is shown (``text``, default the ID); the
    plain text when no page of the book shows it."""
    text = text or cid
    if cid not in check_pages():
        return text
    return f"{{ref}}`{text} <{anchor_of(cid)}>`"


def correction_line(cid: str) -> str:
    """An erratum's correction in one line: its ``headline`` (registered formulas and a few
    words), else the ``Corrected:`` sentence of its note; ``""`` for a claim that holds."""
    claim = get_claim(cid)
    if not claim.corrected:
        return ""
    if claim.headline:
        return claim.render("headline")
    return summary_of(prose(claim.note))[1]


def verdict_table(results: Sequence[Mapping[str, Any]]) -> str:
    """The Markdown table of the book's first page: for each claim of the paper in ``results``
    (dicts of ``verify --json``), its ID linked to its check, its title, the computed outcome
    (an erratum's linked to its page of the errata) and the correction in one line."""
    rows = [
        "| claim | what the paper states | outcome | corrected form |",
        "|---|---|---|---|",
    ]
    for r in results:
        if GROUPS[r["id"][0]] != "paper":
            continue
        fixed = prose(breakable(correction_line(r["id"]), limit=20), cell=True)
        rows.append(
            f"| {claim_link(r['id'])} | {prose(r['title'], cell=True)} | {_outcome_cell(r)} "
            f"| {fixed} |"
        )
    return "\n".join(rows)


# ---------------------------------------------------------------------------------------------
# the sentence map: every sentence of a claim's statement in the paper and the evidence checking it


def _sentences(cids: Iterable[str]) -> list[Any]:
    return [s for cid in cids for s in get_claim(cid).sentences]


def sentence_counts(cids: Iterable[str]) -> dict[str, int]:
    """How many sentences the claims ``cids`` map: ``sentences``, ``math`` (state mathematics),
    ``covered`` (math with evidence), ``uncovered`` (math without) and ``prose``."""
    sentences = _sentences(cids)
    math = [s for s in sentences if s.kind == "math"]
    covered = sum(bool(s.evidence) for s in math)
    return {
        "sentences": len(sentences),
        "math": len(math),
        "covered": covered,
        "uncovered": len(math) - covered,
        "prose": len(sentences) - len(math),
    }


def sentences_summary(results: Sequence[Mapping[str, Any]]) -> str:
    """``120 sentences of the paper's statements: 100 state mathematics, 98 of them covered by
    evidence, 2 uncovered; 20 prose.`` for the claims of ``results``, naming any claim whose
    sentences are not mapped yet."""
    ids = [str(r["id"]) for r in results]
    c = sentence_counts(ids)
    text = (
        f"{c['sentences']} sentences of the paper's statements: {c['math']} state mathematics, "
        f"{c['covered']} of them covered by evidence, {c['uncovered']} uncovered; "
        f"{c['prose']} prose (motivation, citations, pointers to a proof: nothing to check)."
    )
    unmapped = [cid for cid in ids if not get_claim(cid).sentences]
    if unmapped:
        text += f" Not yet mapped sentence by sentence: {', '.join(unmapped)}."
    return text


def sentences_cell(cid: str) -> str:
    """``4/5``: the sentences of claim ``cid`` that state mathematics and have evidence, of all
    that state mathematics (``(not mapped)`` before its sentences are mapped)."""
    c = sentence_counts([cid])
    if not c["sentences"]:
        return "(not mapped)"
    return f"{c['covered']}/{c['math']}"


def sentences_markdown(cid: str) -> str:
    """A collapsed MyST dropdown with the map of claim ``cid``'s sentences in the paper: each
    sentence (math typeset), whether evidence covers it, and the checks that do (their numbers
    in the evidence table above it, so the table fits the column); an uncovered sentence is marked and the dropdown turns
    to the warning colour."""
    claim = get_claim(cid)
    number = {ev.name: k for k, ev in enumerate(claim.evidence, 1)}
    c = sentence_counts([cid])
    title = f"The paper's sentences: {c['covered']} of {c['math']} covered by evidence"
    if c["uncovered"]:
        title += f", {c['uncovered']} UNCOVERED"
    if c["prose"]:
        title += f"; {c['prose']} prose"
    rows = [
        f":::{{dropdown}} {title}",
        *([":color: warning"] if c["uncovered"] else []),
        "",
        "| # | sentence of the paper | status | checked by (# in the evidence table) |",
        "|---|---|---|---|",
    ]
    for k, s in enumerate(claim.sentences, 1):
        if s.kind == "prose":
            status, by = "prose", plain(s.reason)
        elif s.evidence:
            status = "covered"
            by = ", ".join(str(number[n]) for n in s.evidence)
        else:
            status, by = "**⚠ uncovered**", "**no evidence yet**"
        text = prose(breakable(s.text, limit=30), cell=True)
        rows.append(f"| {k} | {text} | {status} | {by} |")
    rows.append(":::")
    return "\n".join(rows)
