"""The renderers of the claims and errata pages (``derivations.report`` and the book extension
``book/_ext/symrb_claims.py``), on the registered claims and on made-up results."""

from __future__ import annotations

import copy
import importlib.util
import re
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("sphinx")

from derivations.registry import all_claims  # noqa: E402
from derivations.report import _TEX_TOKEN, breakable, prose, short_where  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("symrb_claims", ROOT / "book/_ext/symrb_claims.py")
assert _spec and _spec.loader
ext: Any = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(ext)

CLAIMS = all_claims()
ERRATA = [c for c in CLAIMS if c.expected in ext.ERRATA]
FORMULA = re.compile(r"(?<![$\\])\$([^$]+)\$(?!\$)")


def _texts() -> list[tuple[str, str]]:
    return [
        (f"{c.id}.{which}", c.render(which))
        for c in CLAIMS
        for which in ("statement", "printed", "corrected")
        if getattr(c, which)
    ]


def _normal(tex: str) -> list[str]:
    """The tokens of a formula without spaces, empty groups, sizes and null delimiters: what
    :func:`breakable` may change."""
    tokens = [t for t in _TEX_TOKEN.findall(tex) if t.strip()]
    out: list[str] = []
    skip_dot = False
    for t in tokens:
        if t in (r"\left", r"\right", r"\bigl", r"\bigr", r"\Bigl", r"\Bigr"):
            skip_dot = True
            continue
        if skip_dot and t == ".":
            skip_dot = False
            continue
        skip_dot = False
        if t == "}" and out and out[-1] == "{":
            out.pop()
            continue
        out.append(t)
    return out


def _balanced(tex: str) -> bool:
    depth = 0
    for t in _TEX_TOKEN.findall(tex):
        depth += (t == "{") - (t == "}")
        if depth < 0:
            return False
    return depth == 0 and tex.count(r"\left") == tex.count(r"\right")


@pytest.mark.parametrize(("where", "text"), _texts())
def test_breakable_only_cuts_formulas(where: str, text: str) -> None:
    cut = breakable(text, limit=12)
    pieces = FORMULA.findall(cut)
    assert all(_balanced(p) for p in pieces), f"{where}: a piece is not balanced TeX"
    before = [t for f in FORMULA.findall(text) for t in _normal(f)]
    after = [t for p in pieces for t in _normal(p)]
    assert after == before, f"{where}: cutting changed the formulas"
    assert FORMULA.sub("", cut).split() == FORMULA.sub("", text).split()


def test_breakable_cuts_long_formulas_and_leaves_the_rest() -> None:
    long = r"$V = \sum_{k=0}^{N-1} \left(\langle p_{k+1}, f(x_k, u_k) - x_{k+1}\rangle + \langle \sigma, h(u_k)\rangle - g(x_k, u_k)\right)$"
    cut = breakable(long, limit=12)
    assert len(FORMULA.findall(cut)) >= 4
    assert r"\Bigl(" in cut or r"\bigl(" in cut
    assert breakable("short $x = y$ and $$a = b + c + d + e + f + g + h + i$$", limit=2) == (
        "short $x ={}$ $y$ and $$a = b + c + d + e + f + g + h + i$$"
    )
    assert breakable("$a + b$", limit=24) == "$a + b$"


def test_prose_in_a_table_cell_has_no_bare_pipe() -> None:
    for c in CLAIMS:
        for text in (c.title, c.note, c.where):
            cell = prose(text, cell=True)
            assert not re.search(r"(?<!\\)\|", cell), f"{c.id}: {cell[:80]}"


def test_every_claim_says_where_it_is_in_the_paper() -> None:
    for c in (c for c in CLAIMS if c.group == "paper"):
        assert re.match(r"Section [23](\.\d)?[ ,]", c.where), f"{c.id}: where={c.where!r}"
        short = short_where(c.where)
        section = re.match(r"Section [\d.]+", c.where)
        assert section and short.startswith(section.group() + ","), (c.id, short)
        assert "(" not in FORMULA.sub("", short) and ": " not in FORMULA.sub("", short), short


def test_every_erratum_note_says_what_is_wrong_and_the_correction() -> None:
    assert ERRATA
    for c in ERRATA:
        wrong, fixed = ext.summary_of(c.note)
        assert wrong and not wrong.startswith("Corrected"), c.id
        assert fixed, f"{c.id}: no 'Corrected: ...' sentence in the note"


def test_sentences_never_cut_inside_math() -> None:
    assert ext.sentences("It is $a. B$ here. $x$ starts. Corrected: y.") == [
        "It is $a. B$ here.",
        "$x$ starts.",
        "Corrected: y.",
    ]


def _result(outcome: str) -> dict[str, Any]:
    ev = {"level": "exact rational", "description": "d", "seconds": 0.0, "error": None}
    return {
        "id": "S99",
        "outcome": outcome,
        "evidence": [
            {**ev, "form": "printed", "residual": 1.0, "tol": 1e-12},
            {**ev, "form": "corrected", "residual": 0.0, "tol": 1e-12},
        ],
    }


NOTE = "The sign is wrong. Corrected: the sign is right. Details."


def test_an_erratum_passes_the_check() -> None:
    ext.check_erratum(_result("holds after correction"), NOTE)


def test_the_errata_page_refuses_a_statement_that_is_no_longer_an_erratum() -> None:
    r = _result("holds after correction")
    printed_passes = copy.deepcopy(r)
    printed_passes["evidence"][0]["residual"] = 0.0
    with pytest.raises(ext.ExtensionError, match="not an erratum"):
        ext.check_erratum(printed_passes, NOTE)
    corrected_fails = copy.deepcopy(r)
    corrected_fails["evidence"][1]["residual"] = 1.0
    with pytest.raises(ext.ExtensionError, match="corrected-form check fails"):
        ext.check_erratum(corrected_fails, NOTE)
    with pytest.raises(ext.ExtensionError, match="Corrected"):
        ext.check_erratum(r, "The sign is wrong. Nothing else.")


def test_evidence_rows_show_residual_against_tolerance() -> None:
    rows = ext.evidence_rows(_result("holds after correction")["evidence"])
    assert rows[2].endswith("| 1.0e+00 > 1.0e-12 | fails, as expected |")
    assert rows[3].endswith("| 0 ≤ 1.0e-12 | passes |")


# ---------------------------------------------------------------------------------------------
# the sentence map on the claim pages and the claims page


def _with_sentences(monkeypatch: pytest.MonkeyPatch) -> Any:
    """D8 with one sentence of each status (covered, uncovered, prose)."""
    from derivations.registry import Sentence, get_claim

    c = get_claim("D8")
    first = c.evidence[0].name
    monkeypatch.setattr(c, "sentences", [
        Sentence("A covered $J_D(U) = U\\Lambda - \\Lambda U^T$ with $|x|$.", (first,)),
        Sentence("An unchecked $x = 1$."),
        Sentence("See [MoVe1991].", (), "prose", "a citation"),
    ])  # fmt: skip
    return c


def test_sentences_dropdown_marks_the_uncovered(monkeypatch: pytest.MonkeyPatch) -> None:
    from derivations.report import sentences_cell, sentences_markdown, sentences_summary

    _with_sentences(monkeypatch)
    md = sentences_markdown("D8")
    lines = md.splitlines()
    assert lines[0].startswith(":::{dropdown} The paper's sentences: 1 of 2 covered")
    assert "1 UNCOVERED" in lines[0] and ":color: warning" in lines[1] and lines[-1] == ":::"
    rows = [line for line in lines if line.startswith("| ")][1:]
    assert len(rows) == 3 and all(r.count(" | ") == 3 for r in rows)  # no bare | in a cell
    assert rows[0].endswith("| covered | 1 |")
    assert "uncovered" in rows[1] and "no evidence" in rows[1]
    assert "prose" in rows[2] and "a citation" in rows[2]
    assert sentences_cell("D8") == "1/2"
    summary = sentences_summary([{"id": "D8"}])
    assert summary.startswith("3 sentences of the paper's statements: 2 state mathematics, 1 of")
    assert "1 uncovered; 1 prose" in summary


def test_a_fully_covered_map_is_not_a_warning() -> None:
    from derivations.registry import get_claim
    from derivations.report import sentences_markdown

    c = next(c for c in CLAIMS if c.sentences and all(s.covered for s in c.sentences))
    md = sentences_markdown(c.id)
    assert "UNCOVERED" not in md and ":color: warning" not in md
    assert md.count("\n| ") == len(get_claim(c.id).sentences) + 1


def test_claims_table_has_a_sentences_column_for_the_paper_only(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from derivations.report import claims_table

    _with_sentences(monkeypatch)
    ev = {"form": "claim", "level": "float64", "residual": 0.0, "tol": 1e-12}
    row = {"title": "t", "outcome": "holds", "expected": "holds", "seconds": 0.1, "evidence": [ev]}
    paper = claims_table([{**row, "id": "D8"}]).splitlines()
    assert "| sentences |" in paper[0] and "| 1/2 |" in paper[2]
    assert len({line.count("|") for line in paper}) == 1
    method = claims_table([{**row, "id": "M1"}]).splitlines()
    assert "sentences" not in method[0] and len({line.count("|") for line in method}) == 1


# ---------------------------------------------------------------------------------------------
# the verdict: every claim ID in the generated tables links to the label where its check is shown

PAPER = [c for c in CLAIMS if c.group == "paper"]
_REF = re.compile(r"^\{ref\}`([DSM]\d+) <([a-z0-9-]+)>`$")


def _results() -> list[dict[str, Any]]:
    """Results shaped like ``verify --json`` for every registered claim, with its recorded
    outcome (printed-form checks failing, the others passing)."""
    out = []
    for c in CLAIMS:
        evidence = [
            {
                "form": e.form,
                "level": str(e.level),
                "description": e.description,
                "residual": 1.0 if e.form == "printed" else 0.0,
                "tol": e.tol,
                "seconds": 0.01,
                "error": None,
            }
            for e in c.evidence
        ]
        out.append({
            "id": c.id, "label": c.label, "title": c.title, "expected": c.expected,
            "outcome": c.expected, "ok": True, "seconds": 0.01, "evidence": evidence,
        })  # fmt: skip
    return out


def _rows(table: str) -> list[list[str]]:
    """The body cells of a Markdown table."""
    lines = [line for line in table.splitlines() if line.startswith("|")][2:]
    return [[cell.strip() for cell in re.split(r"(?<!\\)\|", line)[1:-1]] for line in lines]


def _anchors_shown() -> set[str]:
    """The labels that ``check()`` places on the pages of the book (one per claim it shows)."""
    from derivations import report

    return {report.anchor_of(cid) for cid in report.check_pages()}


def test_check_places_the_label_its_links_point_to(monkeypatch: pytest.MonkeyPatch) -> None:
    from IPython import display as ipd

    from derivations import report
    from derivations.registry import ClaimResult

    shown: list[str] = []
    monkeypatch.setattr(ipd, "display", lambda md: shown.append(md.data))
    fake = ClaimResult(id="D4", label="", title="", expected="holds", outcome="holds")
    monkeypatch.setattr(report, "result_of", lambda cid: fake)
    monkeypatch.setattr(report, "claim_markdown", lambda result: "**D4**")
    report.check("D4")
    report.check("D4", anchor=False)
    assert shown == ["(claim-d4)=\n\n**D4**", "**D4**"]


def test_every_claim_is_checked_on_exactly_one_page() -> None:
    """The paper's claims and symrb's method checks alike: each has one page showing its check."""
    from derivations.registry import all_claims
    from derivations.report import check_pages

    pages = check_pages()
    assert [c.id for c in PAPER if c.id not in pages] == []
    assert [c.id for c in all_claims() if c.id not in pages] == []
    for cid, doc in pages.items():
        assert (ROOT / "book" / f"{doc}.md").is_file(), (cid, doc)
        assert doc != "intro", f"{cid}: the landing page shows no check (its label is elsewhere)"


def test_a_claim_anchored_on_two_pages_is_refused(tmp_path: Path, monkeypatch: Any) -> None:
    from derivations import report

    for name in ("a.md", "b.md"):
        (tmp_path / name).write_text('check("D4");\n')
    (tmp_path / "c.md").write_text('check("D4", anchor=False);\n')
    monkeypatch.setattr(report, "book_dir", lambda: tmp_path)
    report.check_pages.cache_clear()
    try:
        with pytest.raises(ValueError, match="anchored on a and on b"):
            report.check_pages()
        (tmp_path / "b.md").unlink()
        assert report.check_pages() == {"D4": "a"}
    finally:
        report.check_pages.cache_clear()


@pytest.mark.parametrize("group", ["paper", "method"])
def test_every_claim_id_in_the_claims_tables_links_to_its_check(group: str) -> None:
    from derivations.report import check_pages, claims_table

    anchors = _anchors_shown()
    results = [r for r in _results() if ext.GROUPS[r["id"][0]] == group]
    rows = _rows(claims_table(results))
    assert [r[0].split()[0].removeprefix("{ref}`") for r in rows] == [r["id"] for r in results]
    for row, r in zip(rows, results, strict=True):
        m = _REF.match(row[0])
        assert r["id"] in check_pages(), f"{r['id']}: no page of the book shows its check"
        assert m and m.group(1) == r["id"], f"{r['id']} does not link: {row[0]}"
        assert m.group(2) in anchors, f"{r['id']} links to {m.group(2)}, never placed"


def test_the_landing_table_has_every_claim_each_linked_to_its_check() -> None:
    from derivations.report import verdict_table

    anchors = _anchors_shown()
    rows = _rows(verdict_table(_results()))
    assert len(rows) == len(PAPER) == 27
    errata_pages = {p.stem for p in (ROOT / "book/errata").glob("*.md")}
    for row, c in zip(rows, PAPER, strict=True):
        m = _REF.match(row[0])
        assert m and m.group(1) == c.id and m.group(2) in anchors, row[0]
        if c.expected in ext.ERRATA:
            assert f"<erratum-{c.id.lower()}>" in row[2], f"{c.id}: outcome not linked: {row[2]}"
            assert ext.erratum_doc(c.id).removeprefix("errata/") in errata_pages, c.id
            assert row[3], f"{c.id}: no corrected form"
        else:
            assert row[2] == "holds" and row[3] == "", (c.id, row[2:])


def test_the_correction_in_one_line_comes_from_registered_formulas() -> None:
    from derivations.report import correction_line

    for c in ERRATA:
        line = correction_line(c.id)
        assert "\n" not in line and "[[" not in line and line.count("$") >= 2, (c.id, line)
        assert c.headline, f"{c.id}: give a headline (its correction in one line)"
        words = FORMULA.sub("", c.headline).split()
        assert len(words) <= 8, f"{c.id}: the headline is a sentence, not a line: {c.headline}"
        width = sum(len(_normal(f)) for f in FORMULA.findall(line))
        assert width <= 130, f"{c.id}: the correction is {width} TeX tokens wide"
    assert all(correction_line(c.id) == "" for c in PAPER if c not in ERRATA)


def test_every_erratum_has_its_page_and_its_label() -> None:
    pages = sorted((ROOT / "book/errata").glob("*.md"))
    assert [f"errata/{p.stem}" for p in pages] == sorted(ext.erratum_doc(c.id) for c in ERRATA)
    results = {r["id"]: r for r in _results()}
    for c in ERRATA:
        text = (ROOT / "book" / f"{ext.erratum_doc(c.id)}.md").read_text()
        assert re.search(rf"^```{{symrb-errata}} {c.id}$", text, re.M), c.id
        lines = ext.errata_page(list(results.values()), c.id)
        assert lines[0] == f"(erratum-{c.id.lower()})=" and lines[1] == f"# Erratum {c.id}"
    summary = _rows("\n".join(ext.errata_page(list(results.values()), None)))
    assert [r[0] for r in summary] == [f"{{ref}}`{c.id} <erratum-{c.id.lower()}>`" for c in ERRATA]
    with pytest.raises(ext.ExtensionError, match="not an erratum"):
        ext.errata_page(list(results.values()), "D4")


# ---------------------------------------------------------------------------------------------
# a claim's display: the verdict and the evidence by form first, the full table collapsed when long


def _claim_result(cid: str, residuals: dict[str, float] | None = None) -> Any:
    """Claim ``cid``'s result with its recorded outcome (printed-form checks failing), or with
    the residuals ``{evidence name: residual}`` given."""
    from derivations.registry import ClaimResult, EvidenceResult, get_claim

    c = get_claim(cid)
    residuals = residuals or {}
    evidence = [
        EvidenceResult(
            level=str(e.level),
            description=e.description,
            form=e.form,
            residual=residuals.get(e.name, 1.0 if e.form == "printed" else 0.0),
            tol=e.tol,
            seconds=0.01,
            name=e.name,
        )  # fmt: skip
        for e in c.evidence
    ]
    return ClaimResult(id=c.id, label=c.label, title=c.title, expected=c.expected,
                       outcome=c.expected, evidence=evidence)  # fmt: skip


def test_a_claim_opens_with_its_verdict_and_its_evidence_by_form() -> None:
    from derivations.report import OPEN_EVIDENCE, claim_markdown, correction_line

    for c in CLAIMS:
        md = claim_markdown(_claim_result(c.id))
        first = md.split("\n\n")[0]
        assert first.startswith(f"**Verdict on {c.id}: ") and c.expected in first, (c.id, first)
        if c.corrected:
            assert f"**Corrected:** {breakable(correction_line(c.id))}" in first, c.id
        summary = _rows(md.split("\n\n")[1])
        forms = {e.form for e in c.evidence}
        assert len(summary) == len(forms) and all(len(r) == 4 for r in summary), c.id
        assert md.split("\n\n")[2].startswith(f"**{c.id}**"), c.id  # then the statement
        n = len(c.evidence)
        dropdown = re.search(
            r"^:::\{dropdown\} The evidence: (\d+) checks?.*\n(:open:\n)?", md, re.M
        )
        assert dropdown and int(dropdown.group(1)) == n, c.id
        assert bool(dropdown.group(2)) == (n <= OPEN_EVIDENCE), c.id
        assert md.count("\n| ") - md.count("\n| #") >= n  # every check keeps its row


def test_the_evidence_summary_names_the_decisive_and_the_wrong_checks() -> None:
    from derivations.report import evidence_summary

    c = next(c for c in ERRATA if {"claim", "printed", "corrected"} <= {e.form for e in c.evidence})
    result = _claim_result(c.id)
    rows = {r[0]: r for r in _rows(evidence_summary(result.evidence))}
    assert set(rows) == {"the statement as printed", "the erratum as printed (must fail)",
                         "the correction"}  # fmt: skip
    n_printed = sum(e.form == "printed" for e in c.evidence)
    assert rows["the erratum as printed (must fail)"][2] in (f"all {n_printed} fail", "both fail",
                                                       "it fails")  # fmt: skip
    assert "**" not in "".join(r[2] for r in rows.values())
    # a printed-form check that passes and a corrected one that fails are named, in bold
    first_printed = next(k for k, e in enumerate(c.evidence, 1) if e.form == "printed")
    first_corrected = next(k for k, e in enumerate(c.evidence, 1) if e.form == "corrected")
    worst = {c.evidence[first_printed - 1].name: 0.0, c.evidence[first_corrected - 1].name: 5.0}
    rows = {r[0]: r for r in _rows(evidence_summary(_claim_result(c.id, worst).evidence))}
    assert rows["the erratum as printed (must fail)"][2].startswith("**1 of")
    assert f"#{first_printed}**" in rows["the erratum as printed (must fail)"][2]
    assert (
        rows["the correction"][2] == f"**1 of {sum(e.form == 'corrected' for e in c.evidence)}"
        f" do not pass: #{first_corrected}**"
    )
    # the closest call of the correction is now the failing check, of the printed form the pass
    assert rows["the correction"][3].startswith(f"#{first_corrected}: $5$ $>")
    assert rows["the erratum as printed (must fail)"][3].startswith(f"#{first_printed}: ")
