"""Sphinx extension for the claims and errata pages.

``symrb-errata`` (a MyST directive) expands, when the book is built, into the errata of the
paper.  Without an argument it is the summary table of ``errata.md`` (claim, where in the paper,
what is wrong, the corrected form); with a claim ID (``{symrb-errata} D7``, the whole of
``errata/d07.md``) it is that erratum's page: where the statement is in the paper, a link to the
page showing its check, the printed and the corrected forms side by side as typeset math, what was
found (the claim's note) and a table of its evidence with residual and tolerance.  One erratum,
one page, so that no page of the errata grows past a few screens.  The results are those of the build's one ``symrb verify`` run
(:func:`derivations.report.load_results`); an erratum whose printed-form checks do not all fail,
or whose corrected-form checks do not all pass, stops the build with an error.

A claim's note starts with two sentences the summary reads: what is wrong, then ``Corrected:``
and the corrected form, in one line each (an erratum without them stops the build too).

On every page of the book every table also gets the class ``symrb-stack`` and, in each body
cell, a label naming its column; ``book/_static/symrb.css`` shows the labels and stacks the cells
of a row on narrow screens, so no table needs scrolling sideways on a phone
(``tests/test_book_browser.py`` checks that every table fits its column at 1280 and 400 px).
"""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Mapping, Sequence
from typing import Any

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.errors import ExtensionError
from sphinx.util.docutils import SphinxDirective
from sphinx.util.nodes import nested_parse_with_titles

from derivations.registry import GROUPS, get_claim
from derivations.report import (
    ERRATA,
    SHORT_LEVELS,
    breakable,
    check_pages,
    claim_link,
    load_results,
    plain,
    prose,
    sentences,
    short_where,
    summary_of,
    verify_json_path,
)

__all__ = ["ERRATA", "sentences", "summary_of", "errata_summary", "erratum_page", "errata_page"]

LEVELS = SHORT_LEVELS  # evidence levels as the tables show them, strongest first


def erratum_doc(cid: str) -> str:
    """``errata/d07``: the page of the errata for claim ``cid``."""
    return f"errata/{cid[0].lower()}{int(cid[1:]):02d}"


def _cell(text: str) -> str:
    """Markdown with math for a narrow table cell: formulas cut where a line may break."""
    return prose(breakable(text, limit=12), cell=True)


def _count(n: int, noun: str) -> str:
    return f"{'the' if n == 1 else f'all {n}'} {noun}{'s' * (n != 1)}"


def _capital(text: str) -> str:
    return text[:1].upper() + text[1:]


def levels_of(evidence: Sequence[Mapping[str, Any]]) -> str:
    """``2 symbolic (all n), 1 float64``: how many checks at each level, strongest first."""
    counts = Counter(e["level"] for e in evidence)
    return ", ".join(f"{counts[lv]} {short}" for lv, short in LEVELS.items() if counts[lv])


def fmt_number(x: float) -> str:
    return "0" if x == 0 else f"{x:.1e}"


def verdict(e: Mapping[str, Any]) -> str:
    """What the check found, said so that a failing printed form reads as expected."""
    if e.get("error"):
        return "error"
    passed = e["residual"] <= e["tol"]
    if e["form"] == "printed":
        return "fails, as expected" if not passed else "passes: not an erratum"
    return "passes" if passed else "fails"


def evidence_rows(evidence: Sequence[Mapping[str, Any]]) -> list[str]:
    """A Markdown table of checks: form and level, what is checked, the residual against the
    tolerance, and what that means."""
    rows = [
        "| check | what is checked | residual vs tolerance | result |",
        "|---|---|---|---|",
    ]
    for e in evidence:
        if e.get("error"):
            residual = "error: " + plain(str(e["error"]))
        elif e["tol"] == 0:
            residual = "0 (exact)" if e["residual"] == 0 else f"{fmt_number(e['residual'])} > 0"
        else:
            sign = "≤" if e["residual"] <= e["tol"] else ">"
            residual = f"{fmt_number(e['residual'])} {sign} {fmt_number(e['tol'])}"
        rows.append(
            f"| {e['form']}, {LEVELS.get(e['level'], e['level'])} | {plain(e['description'])} "
            f"| {residual} | {verdict(e)} |"
        )
    return rows


def check_erratum(result: Mapping[str, Any], note: str) -> None:
    """Raise :class:`ExtensionError` unless ``result`` is an erratum as its outcome says."""
    cid, evidence = result["id"], result["evidence"]
    printed = [e for e in evidence if e["form"] == "printed"]
    corrected = [e for e in evidence if e["form"] == "corrected"]

    def passes(e: Mapping[str, Any]) -> bool:
        return e.get("error") is None and e["residual"] <= e["tol"]

    if result["outcome"] == "holds after correction":
        if not printed or any(passes(e) for e in printed):
            raise ExtensionError(f"errata: {cid} is not an erratum: a printed-form check passes")
        if not corrected or not all(passes(e) for e in corrected):
            raise ExtensionError(f"errata: {cid}: a corrected-form check fails")
    elif all(passes(e) for e in evidence):
        raise ExtensionError(f"errata: {cid} fails, yet every check passes")
    wrong, fixed = summary_of(note)
    if not wrong or (result["outcome"] == "holds after correction" and not fixed):
        raise ExtensionError(
            f"errata: the note of {cid} must start with what is wrong (one sentence) and then "
            f"'Corrected: ...' (one sentence); it starts {note[:80]!r}"
        )


def errata_summary(results: Sequence[Mapping[str, Any]]) -> list[str]:
    """The summary table of the errata as MyST Markdown lines (the paper's claims only: the checks
    of symrb's own methods have no printed form); each ID links to the erratum's page."""
    results = [r for r in results if GROUPS[r["id"][0]] == "paper"]
    errata = [r for r in results if r["outcome"] in ERRATA]
    lines = [
        f"{len(errata)} of the {len(results)} claims are errata: the paper's statement fails as "
        "printed and a corrected form holds. Each has a page of its own (the claim's ID below "
        "leads there) with where it is in the paper, the printed and corrected forms side by "
        "side, and its checks.",
        "",
        "| claim | where in the paper | what is wrong | corrected form |",
        "|---|---|---|---|",
    ]
    for r in errata:
        claim = get_claim(r["id"])
        check_erratum(r, claim.note)
        wrong, fixed = summary_of(prose(claim.note))
        lines.append(
            f"| {{ref}}`{claim.id} <erratum-{claim.id.lower()}>` "
            f"| {_cell(short_where(claim.where))} | {_cell(wrong)} "
            f"| {_cell(_capital(fixed) or '(none recorded)')} |"
        )
    return lines


#: An inline formula longer than this (characters of TeX, about 300 px typeset) does not fit a
#: card of half the column: the printed and corrected forms are then shown one above the other.
SIDE_BY_SIDE_TEX = 90


def side_by_side(*forms: str) -> str:
    """The columns of the grid of the printed and corrected forms (sphinx-design: phone, tablet,
    laptop, desktop): two on wide screens, unless a formula in a form is too long for half the
    column (:data:`SIDE_BY_SIDE_TEX`)."""
    longest = max((len(m) for f in forms for m in re.findall(r"\$([^$]+)\$", f)), default=0)
    return "1 1 2 2" if longest <= SIDE_BY_SIDE_TEX else "1 1 1 1"


def erratum_page(r: Mapping[str, Any]) -> list[str]:
    """The page of one erratum (a result dict of ``verify --json``) as MyST Markdown lines: its
    title and label, where it is in the paper, the outcome and a link to its check, the claim in
    our words, the printed and corrected forms side by side, what was found and the evidence."""
    claim = get_claim(r["id"])
    check_erratum(r, claim.note)
    labels = ", ".join(f"`{x.strip()}`" for x in claim.label.split(","))
    n_printed = sum(e["form"] == "printed" for e in r["evidence"])
    n_rest = len(r["evidence"]) - n_printed
    if r["outcome"] == "holds after correction":
        outcome = (
            f"{_count(n_printed, 'check')} of the printed form fail{'s' * (n_printed == 1)} "
            f"and {_count(n_rest, 'other check')} pass{'es' * (n_rest == 1)} "
            f"({levels_of(r['evidence'])})"
        )
    else:
        outcome = "some checks fail and no correction is recorded"
    home = check_pages().get(claim.id)
    shown = f" The claim with its check: {claim_link(claim.id, 'on its page')}." if home else ""
    printed = breakable(claim.render("printed") if claim.printed else claim.render("statement"))
    corrected = (
        breakable(claim.render("corrected")) if claim.corrected else "(no correction recorded)"
    )
    return [
        f"(erratum-{claim.id.lower()})=",
        f"# Erratum {claim.id}",  # no math: the title is also the sidebar's and the tab's
        "",
        f"**{claim.id}: {prose(claim.title)}**",
        "",
        f"**Where in the paper.** {prose(claim.where)} (LaTeX labels in the source: {labels}).",
        "",
        f"**Outcome.** *{r['outcome']}*: {outcome}.{shown}",
        "",
        f"**The claim in our words.** {breakable(claim.render('statement'))}",
        "",
        f"::::{{grid}} {side_by_side(printed, corrected)}",
        ":gutter: 2",
        ":class-container: symrb-forms",
        "",
        ":::{grid-item-card} Printed in the paper",
        ":class-card: symrb-printed",
        "",
        printed,
        ":::",
        "",
        ":::{grid-item-card} Corrected",
        ":class-card: symrb-corrected",
        "",
        corrected,
        ":::",
        "::::",
        "",
        f"**What was found.** {prose(claim.note)}",
        "",
        "**Evidence:** each check's residual against its tolerance (a check passes when the "
        "residual is at most the tolerance; a check of the printed form is expected to fail).",
        "",
        *evidence_rows(r["evidence"]),
    ]


def errata_page(results: Sequence[Mapping[str, Any]], cid: str | None) -> list[str]:
    """The lines of ``{symrb-errata}`` (the summary, ``cid`` None) or ``{symrb-errata} cid``."""
    if cid is None:
        return errata_summary(results)
    match = [r for r in results if r["id"] == cid.upper()]
    if not match or match[0]["outcome"] not in ERRATA:
        raise ExtensionError(f"errata: {cid} is not an erratum of the paper")
    return erratum_page(match[0])


class SymrbErrata(SphinxDirective):
    """``symrb-errata [ID]``: the summary table, or the page of erratum ID (see the module)."""

    has_content = False
    optional_arguments = 1

    def run(self) -> list[nodes.Node]:
        self.env.note_dependency(str(verify_json_path()))
        payload, _source = load_results()
        lines = errata_page(payload["claims"], self.arguments[0] if self.arguments else None)
        content = StringList(lines, source=self.get_source_info()[0])
        holder = nodes.section()
        holder.document = self.state.document
        nested_parse_with_titles(self.state, content, holder)
        return holder.children


#: A body cell with more characters than this gets the class ``symrb-long``: the CSS lets its
#: long words (a dotted code name) break anywhere, so that they never widen the table, while
#: the short cells (a form, a number) keep their words whole.
LONG_CELL = 60


def _label(head: nodes.Node) -> nodes.inline:
    """The label ``header: `` of a cell in the column headed by ``head`` (a copy of the header's
    text and math, so that a formula in a header is typeset in the label too)."""
    label = nodes.inline("", "", classes=["symrb-cell-label"])
    for child in head.children:
        if isinstance(child, nodes.paragraph):
            label.extend(c.deepcopy() for c in child.children)
        else:
            label += nodes.Text(child.astext())
    label += nodes.Text(": ")
    return label


def label_table_cells(app: Any, doctree: nodes.document) -> None:
    """Give every table of the page the classes ``symrb-stack`` and ``symrb-page-<page>``, every
    body cell a label with its column's header, which the CSS shows when the cells are stacked,
    and every long cell the class ``symrb-long`` (tables written in Markdown, printed by a cell as
    Markdown, or made by a directive such as autosummary; a table a cell prints as HTML, such as
    a pandas table, is not seen here)."""
    page = "symrb-page-" + app.env.docname.replace("/", "-")
    for table in doctree.findall(nodes.table):
        table["classes"] += ["symrb-stack", page]
        head = next(iter(table.findall(nodes.thead)), None)
        heads = list(next(iter(head.findall(nodes.row))).children) if head is not None else []
        for body in table.findall(nodes.tbody):
            for row in body.findall(nodes.row):
                for k, entry in enumerate(row.children):
                    if len(entry.astext()) > LONG_CELL:
                        entry["classes"].append("symrb-long")
                    if k >= len(heads):
                        continue
                    first = entry.children[0] if entry.children else None
                    if isinstance(first, nodes.paragraph):
                        first.insert(0, _label(heads[k]))
                    else:
                        entry.insert(0, nodes.paragraph("", "", _label(heads[k])))


def setup(app: Any) -> dict[str, Any]:
    app.add_directive("symrb-errata", SymrbErrata)
    app.connect("doctree-read", label_table_cells)
    return {"version": "0.2", "parallel_read_safe": True, "parallel_write_safe": True}
