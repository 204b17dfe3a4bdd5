"""Sphinx extension for the claims and errata pages.

``symrb-errata`` (a MyST directive without arguments) expands, when the book is built, into the
errata of the paper: a summary table (claim, where in the paper, what is wrong, the corrected
form, the evidence) and then one section per erratum, so that the page's contents panel lists
them.  Each section has where the statement is in the paper, the printed and the corrected forms
side by side as typeset math, what was found (the claim's note) and a table of its evidence with
residual and tolerance.  The results are those of the build's one ``symrb verify`` run
(:func:`derivations.report.load_results`); an erratum whose printed-form checks do not all fail,
or whose corrected-form checks do not all pass, stops the build with an error.

A claim's note starts with two sentences the summary reads: what is wrong, then ``Corrected:``
and the corrected form, in one line each (an erratum without them stops the build too).

On the claims and errata pages every table also gets the class ``symrb-stack`` and, in each
body cell, a label naming its column; ``book/_static/symrb.css`` shows the labels and stacks the
cells of a row on narrow screens, so no table needs scrolling sideways on a phone.
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
    SHORT_LEVELS,
    breakable,
    load_results,
    plain,
    prose,
    short_where,
    verify_json_path,
)

ERRATA = ("holds after correction", "fails")
STACKED_PAGES = {"claims", "errata"}
LEVELS = SHORT_LEVELS  # evidence levels as the tables show them, strongest first
_MATH = re.compile(r"(\$[^$]+\$)")


def _outside_math(text: str) -> list[tuple[bool, str]]:
    """``text`` cut into (is_math, piece) pieces at ``$...$``."""
    return [(p.startswith("$") and p.endswith("$") and len(p) > 1, p) for p in _MATH.split(text)]


def sentences(text: str) -> list[str]:
    """The sentences of ``text``: cut after ``.``, ``!`` or ``?`` followed by a space and a
    capital letter, a digit, a bracket, a quote or a formula, never inside ``$...$``."""
    masked = "".join(p[0] + "x" * (len(p) - 1) if m else p for m, p in _outside_math(text))
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


def errata_markdown(results: Sequence[Mapping[str, Any]]) -> list[str]:
    """The summary table and one section per erratum, as MyST Markdown lines (the paper's claims
    only: the checks of symrb's own methods have no printed form)."""
    results = [r for r in results if GROUPS[r["id"][0]] == "paper"]
    errata = [r for r in results if r["outcome"] in ERRATA]
    lines = [
        "## Summary",
        "",
        f"{len(errata)} of the {len(results)} claims are errata: the paper's statement fails as "
        "printed and a corrected form holds. Each has its own section below, with where it is "
        "in the paper, the printed and corrected forms side by side, and its checks.",
        "",
        ":::{container} full-width",
        "| claim | where in the paper | what is wrong | corrected form | evidence levels |",
        "|---|---|---|---|---|",
    ]
    for r in errata:
        claim = get_claim(r["id"])
        check_erratum(r, claim.note)
        wrong, fixed = summary_of(prose(claim.note))
        evidence = ", ".join(
            LEVELS[lv] for lv in LEVELS if lv in {e["level"] for e in r["evidence"]}
        )
        lines.append(
            f"| {{ref}}`{claim.id} <erratum-{claim.id.lower()}>` | {_cell(short_where(claim.where))} "
            f"| {_cell(wrong)} | {_cell(_capital(fixed) or '(none recorded)')} | {evidence} |"
        )
    lines.append(":::")
    for r in errata:
        claim = get_claim(r["id"])
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
        lines += [
            "",
            f"(erratum-{claim.id.lower()})=",
            f"## {claim.id}: {prose(claim.title)}",
            "",
            f"**Where in the paper.** {prose(claim.where)} (LaTeX labels in the source: {labels}).",
            "",
            f"**Outcome.** *{r['outcome']}*: {outcome}.",
            "",
            f"**The claim in our words.** {breakable(claim.render('statement'))}",
            "",
            "::::{grid} 1 1 2 2",
            ":gutter: 2",
            ":class-container: symrb-forms",
            "",
            ":::{grid-item-card} Printed in the paper",
            ":class-card: symrb-printed",
            "",
            breakable(claim.render("printed") if claim.printed else claim.render("statement")),
            ":::",
            "",
            ":::{grid-item-card} Corrected",
            ":class-card: symrb-corrected",
            "",
            breakable(claim.render("corrected")) if claim.corrected else "(no correction recorded)",
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
    return lines


class SymrbErrata(SphinxDirective):
    """``symrb-errata``: the summary table and one section per erratum (see the module)."""

    has_content = False

    def run(self) -> list[nodes.Node]:
        self.env.note_dependency(str(verify_json_path()))
        payload, _source = load_results()
        lines = errata_markdown(payload["claims"])
        content = StringList(lines, source=self.get_source_info()[0])
        holder = nodes.section()
        holder.document = self.state.document
        nested_parse_with_titles(self.state, content, holder)
        return holder.children


def label_table_cells(app: Any, doctree: nodes.document) -> None:
    """On the claims and errata pages, give every table the class ``symrb-stack`` and every body
    cell a label with its column's header, which the CSS shows when the cells are stacked."""
    if app.env.docname not in STACKED_PAGES:
        return
    for table in doctree.findall(nodes.table):
        table["classes"].append("symrb-stack")
        head = next(iter(table.findall(nodes.thead)), None)
        if head is None:
            continue
        headers = [entry.astext().strip() for entry in next(iter(head.findall(nodes.row)))]
        for body in table.findall(nodes.tbody):
            for row in body.findall(nodes.row):
                for header, entry in zip(headers, row.children, strict=False):
                    label = nodes.inline(text=f"{header}: ", classes=["symrb-cell-label"])
                    first = entry.children[0] if entry.children else None
                    if isinstance(first, nodes.paragraph):
                        first.insert(0, label)
                    else:
                        entry.insert(0, nodes.paragraph("", "", label))


def setup(app: Any) -> dict[str, Any]:
    app.add_directive("symrb-errata", SymrbErrata)
    app.connect("doctree-read", label_table_cells)
    return {"version": "0.2", "parallel_read_safe": True, "parallel_write_safe": True}
