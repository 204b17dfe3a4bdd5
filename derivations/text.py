"""Claims as text for a terminal: the formulas a claim registered, and the LaTeX of its prose.

Two renderers, neither written here:

* a registered formula (``[[key]]`` in a claim's texts, ``claim.formulas[key]``) is the SymPy
  object its evidence checked, drawn by SymPy's pretty printer (:func:`formula_text`); the
  subclass :class:`TextPrinter` adds only our display objects (``Bracket`` as ``[A, B]``,
  ``Pair`` as ``⟨a, b⟩``, ``Cross`` as ``u × v``, ``W ∘ X`` as ``J⁻¹(X)``), names written in
  LaTeX (``\\hat{H}``), and, for a display object of a claim module without a rule here, the
  text of its own LaTeX;
* hand-written ``$...$`` LaTeX in prose is read by pylatexenc (:func:`latex_text`), with a few
  macros it does not know (``\\|``, ``\\operatorname``) and spaces around relations.

A formula that the pretty printer draws on one line stays in its sentence; a taller one (a sum,
a fraction) is set apart as a display block, which :func:`paragraph` indents under the text.
"""

from __future__ import annotations

import re
import shutil
import sys
import textwrap
from collections.abc import Sequence
from typing import Any

import sympy as sp
from pylatexenc.latex2text import LatexNodes2Text, MacroTextSpec
from pylatexenc.latex2text import get_default_latex_context_db as _text_context
from pylatexenc.latexwalker import LatexWalker
from pylatexenc.latexwalker import get_default_latex_context_db as _walker_context
from pylatexenc.macrospec import MacroSpec
from sympy.printing.precedence import PRECEDENCE, precedence
from sympy.printing.pretty.pretty import PrettyPrinter
from sympy.printing.pretty.stringpict import prettyForm

from derivations.registry import Claim, ClaimResult, EvidenceResult, grouped
from derivations.symbolic import latex
from derivations.vocabulary import W

__all__ = [
    "WIDTH",
    "TextPrinter",
    "latex_text",
    "formula_text",
    "text_of",
    "claim_text",
    "terminal_width",
    "cell",
    "paragraph",
    "claims_lines",
    "statement_lines",
    "evidence_lines",
    "sentence_lines",
    "seconds_text",
    "verdict",
    "verify_table",
    "progress_line",
]

#: The widest line the commands print (and the cap on wrapped text).
WIDTH = 100

# ---------------------------------------------------------------------------------------------
# hand-written LaTeX: pylatexenc

#: Relations and operators pylatexenc writes without the spaces around them.
_SPACED = {
    "le": "≤", "leq": "≤", "ge": "≥", "geq": "≥", "ne": "≠", "neq": "≠", "in": "∈",
    "notin": "∉", "approx": "≈", "sim": "∼", "equiv": "≡", "to": "→", "rightarrow": "→",
    "mapsto": "↦", "times": "×", "subset": "⊂", "quad": "  ", "qquad": "   ",
}  # fmt: skip
#: Macros pylatexenc does not know, with their arguments.
_ARGUMENTS = {
    "operatorname": "{", "substack": "{", "tfrac": "{{", "dfrac": "{{", "overline": "{",
    "widehat": "{",
}  # fmt: skip
_WALKER = _walker_context().filter_context()
_WALKER.add_context_category(
    "symrb",
    macros=[MacroSpec(name, args) for name, args in _ARGUMENTS.items()],
    prepend=True,
)
_TEXT = _text_context().filter_context()
_TEXT.add_context_category(
    "symrb",
    macros=[
        MacroTextSpec("|", "‖"),
        MacroTextSpec("operatorname", "%(1)s"),
        MacroTextSpec("substack", "%(1)s"),
        MacroTextSpec("tfrac", "%(1)s/%(2)s"),
        MacroTextSpec("dfrac", "%(1)s/%(2)s"),
        MacroTextSpec("overline", "%(1)s\N{COMBINING OVERLINE}"),
        MacroTextSpec("widehat", "(%(1)s)^\N{LOGICAL AND}"),
        MacroTextSpec("det", "det"),
        MacroTextSpec("dim", "dim"),
        *(MacroTextSpec(name, f" {sym} ") for name, sym in _SPACED.items()),
    ],
    prepend=True,
)


class _ProseText(LatexNodes2Text):
    """pylatexenc's text, with the braces of a script longer than one character kept
    (``p_{k+1}``, not ``p_k+1``)."""

    def group_node_to_text(self, node: Any) -> str:
        contents = str(self._groupnodecontents_to_text(node))
        script = node.pos > 0 and node.parsing_state.s[node.pos - 1] in "_^"
        return "{" + contents + "}" if script and len(contents) > 1 else contents


_TO_TEXT = _ProseText(latex_context=_TEXT, math_mode="text")
_NULL_DELIMITER = re.compile(r"\\(left|right)\s*\.")
#: A macro without arguments followed by a space (``\\phi = 0``, ``\\sin \\theta``): pylatexenc
#: drops that space (``ϕ= 0``, ``sinθ``) unless an empty group ends the macro.  Accents, fonts
#: and fractions take the next token as their argument and are left alone.
_SPACE_AFTER_MACRO = re.compile(
    r"(\\(?!(?:left|right|rm|bf|it|sf|tt|cal|partial|nabla|hat|widehat|dot|ddot|tilde|widetilde|bar|vec|check"
    r"|breve|overline|underline|frac|tfrac|dfrac|sqrt|text|mathrm|mathbf|mathfrak|mathbb|mathcal"
    r"|operatorname|begin|end|substack)\b)[A-Za-z]+)(?= )"
)


def latex_text(tex: str) -> str:
    """Hand-written LaTeX (the inside of ``$...$``) as text: ``\\Lambda`` is ``Λ``, ``\\hat H``
    is ``Ĥ``, ``\\frac{a}{b}`` is ``a/b``, ``\\left\\|M\\right\\|`` is ``‖M‖``; one-character
    scripts lose their braces (``Q^{T}`` is ``Q^T``), longer ones keep them (``p_{k+1}``)."""
    tex = _SPACE_AFTER_MACRO.sub(r"\1{}", _NULL_DELIMITER.sub("", tex))
    walker = LatexWalker(tex, latex_context=_WALKER, tolerant_parsing=True)
    nodes, _pos, _len = walker.get_latex_nodes()
    text = " ".join(_TO_TEXT.nodelist_to_text(nodes).split())
    return re.sub(r"(?<=[(\[⟨]) | (?=[)\]⟩,;])", "", text)


# ---------------------------------------------------------------------------------------------
# registered formulas: SymPy's pretty printer

#: A name written in LaTeX (``\\hat{H}``, ``x^{a}``, ``H_{xx}^*``), which the pretty printer
#: would show verbatim.
_TEX_NAME = re.compile(r"[\\{}^]")


class TextPrinter(PrettyPrinter):
    """SymPy's pretty printer with the display objects of :mod:`derivations.symbolic`
    (``Bracket``, ``Pair``, ``Cross``, ``J⁻¹(X)`` for ``W ∘ X``) and names written in LaTeX; a
    display object of a claim module is drawn as the text of its own LaTeX."""

    def _print(self, expr: Any, **kwargs: Any) -> Any:
        cls = type(expr)
        if (
            getattr(cls, "_latex", None) is not None
            and not cls.__module__.startswith("sympy")
            and not hasattr(self, "_print_" + cls.__name__)
        ):
            return prettyForm(latex_text(latex(expr)))
        return super()._print(expr, **kwargs)

    def _as_ordered_terms(self, expr: Any, order: str | None = None) -> list[Any]:
        """The terms in the order they were written, numbers last (``N - 1``, not ``-1 + N``)."""
        terms = list(expr.args)
        return [t for t in terms if not t.is_Number] + [t for t in terms if t.is_Number]

    def _print_Symbol(self, e: Any, bold_name: bool = False) -> Any:
        if _TEX_NAME.search(e.name):
            return prettyForm(latex_text(e.name))
        return super()._print_Symbol(e, bold_name)

    _print_MatrixSymbol = _print_Symbol
    _print_RandomSymbol = _print_Symbol

    def _print_Function(self, e: Any, sort: bool = False, func_name: Any = None, **kw: Any) -> Any:
        name = func_name or e.func.__name__
        if _TEX_NAME.search(name):
            name = latex_text(name)
        return super()._print_Function(e, sort=sort, func_name=name, **kw)

    def _print_Max(self, e: Any) -> Any:  # SymPy draws Max and Min with str()
        return prettyForm(*self._print_seq(e.args, "(", ")").left("max"))

    def _print_Min(self, e: Any) -> Any:
        return prettyForm(*self._print_seq(e.args, "(", ")").left("min"))

    def _print_Bracket(self, e: Any) -> Any:
        return self._print_seq(e.args, "[", "]")

    def _print_Pair(self, e: Any) -> Any:
        inner = self._print_seq(e.args, None, None)
        return prettyForm(*prettyForm(*inner.left("⟨")).right("⟩"))

    def _print_Cross(self, e: Any) -> Any:
        a, b = (self._operand(x) for x in e.args)
        return prettyForm(*a.right(" × ", b))

    def _operand(self, x: Any) -> Any:
        """``x`` drawn as a factor of a product (a sum in parentheses)."""
        form = self._print(x)
        return prettyForm(*form.parens()) if precedence(x) < PRECEDENCE["Mul"] else form

    def _print_Indexed(self, e: Any) -> Any:
        indices = self._print_seq(e.indices, "[", "]")
        return prettyForm(*self._print(e.base.label).right(indices))

    def _print_HadamardProduct(self, e: Any) -> Any:
        others = [a for a in e.args if a != W]
        if len(others) != len(e.args) - 1:
            return super()._print_HadamardProduct(e)
        inner = others[0] if len(others) == 1 else sp.HadamardProduct(*others)
        return prettyForm(*prettyForm(*self._print(inner).parens()).left("J⁻¹"))


def _pretty(expr: Any, width: int, suffix: str = "") -> str:
    printer = TextPrinter(
        {"use_unicode": True, "order": "none", "wrap_line": True, "num_columns": width}
    )
    form = printer._print(expr)
    if suffix:
        form = prettyForm(*form.right(suffix))
    return "\n".join(line.rstrip() for line in form.render(**printer._settings).splitlines())


def formula_text(expr: Any, width: int = WIDTH, suffix: str = "") -> str:
    """A registered formula (a SymPy object, or a tuple of them) drawn by :class:`TextPrinter`,
    lines at most ``width`` wide, followed by ``suffix`` (punctuation, on its baseline); the parts
    of a tuple are side by side when each is one line, else one under the other."""
    if not isinstance(expr, tuple | list):
        return _pretty(expr, width, suffix)
    parts = [formula_text(e, width) for e in expr]
    joined = ",  ".join(parts) + suffix
    if all("\n" not in p for p in parts) and len(joined) <= width:
        return joined
    return "\n\n".join([*parts[:-1], formula_text(expr[-1], width, suffix)])


# ---------------------------------------------------------------------------------------------
# a claim's texts

_PLACEHOLDER = re.compile(r"\[\[([A-Za-z0-9_]+)\]\]([.,;:]?)")
_MATH = re.compile(r"(\$[^$]+\$)")
#: Joins the words of a short formula so that wrapping does not split it (see :func:`paragraph`).
_GLUE = "\x1f"
_SHORT = 40
#: Sets a display block apart in the text :func:`text_of` returns (see :func:`paragraph`).
_DISPLAY = "\x1e"
#: How much deeper than its paragraph a display block is indented.
_DISPLAY_INDENT = "    "


def text_of(
    raw: str,
    formulas: dict[str, Any] | None = None,
    owner: str = "",
    glue: bool = False,
    width: int = WIDTH,
) -> str:
    """Text of a text with ``$...$`` math and ``[[key]]`` placeholders for ``formulas``: a
    formula drawn on one line stays in the sentence (with ``glue``, its spaces are
    :data:`_GLUE` when it is at most 40 characters long), a taller one becomes a display block
    (between :data:`_DISPLAY` marks, for :func:`paragraph`)."""

    def glued(text: str) -> str:
        return text.replace(" ", _GLUE) if glue and len(text) <= _SHORT else text

    def formula(m: re.Match[str]) -> str:
        key = m.group(1)
        if formulas is None or key not in formulas:
            raise KeyError(f"claim {owner}: [[{key}]] has no formula")
        text = formula_text(formulas[key], width - len(_DISPLAY_INDENT) - 2, m.group(2))
        return glued(text) if "\n" not in text else f"{_DISPLAY}{text}{_DISPLAY}"

    out = []
    for piece in _MATH.split(raw):
        if len(piece) > 1 and piece.startswith("$") and piece.endswith("$"):
            out.append(glued(latex_text(piece[1:-1])))
        else:
            out.append(_PLACEHOLDER.sub(formula, piece))
    return "".join(out)


def claim_text(claim: Claim, which: str = "statement", glue: bool = False) -> str:
    """A claim's text ``which`` (statement, printed, corrected, note, title) for a terminal (see
    :func:`text_of`)."""
    raw = " ".join((getattr(claim, which) or "").split())
    return text_of(raw, claim.formulas, claim.id, glue)


# ---------------------------------------------------------------------------------------------
# laying text out


def terminal_width() -> int:
    """The terminal width when stdout is one (at most :data:`WIDTH`), else :data:`WIDTH`."""
    if sys.stdout.isatty():
        return max(60, min(WIDTH, shutil.get_terminal_size((WIDTH, 24)).columns))
    return WIDTH


def paragraph(text: str, indent: str = "  ", width: int | None = None) -> str:
    """``text`` wrapped and indented; words joined by :data:`_GLUE` stay on one line, and a
    display block of :func:`text_of` is set on lines of its own, indented deeper."""
    width = width or terminal_width()
    out: list[str] = []
    for k, piece in enumerate(text.split(_DISPLAY)):
        if k % 2:
            deeper = indent + _DISPLAY_INDENT
            out.append("\n".join((deeper + line).rstrip() for line in piece.splitlines()))
            continue
        piece = piece.strip()
        if piece:
            out.append(
                textwrap.fill(
                    piece,
                    width=width,
                    initial_indent=indent,
                    subsequent_indent=indent,
                    break_on_hyphens=False,
                    break_long_words=False,
                ).replace(_GLUE, " ")
            )
    return "\n".join(out)


def _id(item: Claim | ClaimResult) -> str:
    return item.id


def cell(text: str, width: int) -> list[str]:
    """``text`` (one line of :func:`text_of`) wrapped into lines of at most ``width`` characters:
    nothing is cut, a word longer than the cell is broken across lines."""
    text = " ".join(text.replace(_DISPLAY, " ").split())
    lines = textwrap.wrap(text, width=max(width, 1), break_on_hyphens=False)
    return [line.replace(_GLUE, " ") for line in lines] or [""]


def claims_lines(claims: Sequence[Claim], width: int = WIDTH) -> list[str]:
    """The claims as a table: ID, recorded outcome, where it is in the paper, title; the last
    two cells wrap onto further lines, so no line is wider than ``width`` and no text is cut;
    a heading above each group when there is more than one."""
    lead = 4 + 1 + 22 + 2  # the ID and outcome columns and their gaps
    rest = max(width - lead - 2, 20)
    where_w = max(12, rest * 2 // 3)
    title_w = rest - where_w
    head = f"{'ID':<4} {'recorded outcome':<22}  {'in the paper':<{where_w}}  title"
    lines = [head, "-" * width]
    groups = grouped(claims, _id)
    for title, members in groups:
        if len(groups) > 1:
            lines += ["", title]
        for c in members:
            where = cell(text_of(c.where or f"sec. {c.section}: {c.label}"), where_w)
            name = cell(claim_text(c, "title"), title_w)
            for k in range(max(len(where), len(name))):
                first = f"{c.id:<4} {c.expected:<22}  " if k == 0 else " " * lead
                left = where[k] if k < len(where) else ""
                right = name[k] if k < len(name) else ""
                lines.append(f"{first}{left:<{where_w}}  {right}".rstrip())
    return lines


def statement_lines(claim: Claim, width: int) -> list[str]:
    """Title, where in the paper, recorded outcome, statement, printed/corrected forms, note."""
    out: list[str] = []
    title = f"{claim.id}: {claim_text(claim, 'title')}"
    out += textwrap.wrap(title, width=width, subsequent_indent="    ")
    out.append("=" * min(width, len(title)))
    where = claim.where or f"section {claim.section}, LaTeX label {claim.label}"
    out.append(paragraph(f"In the paper: {text_of(where)}", indent="", width=width))
    out.append(f"Recorded outcome: {claim.expected}")
    sections = [("Statement", "statement")]
    if claim.printed:
        sections += [("Printed in the paper", "printed"), ("Corrected", "corrected")]
    if claim.note:
        sections.append(("Note", "note"))
    for heading, which in sections:
        out += ["", heading, paragraph(claim_text(claim, which, glue=True), width=width)]
    return out


def evidence_lines(result: ClaimResult, source: str, width: int) -> list[str]:
    """The evidence of a claim for ``show``: where the results come from (``source``), the
    computed outcome, then each check with its verdict and description."""
    agreement = "as recorded" if result.ok else f"NOT as recorded ({result.expected})"
    out = ["", "Evidence", paragraph(source[:1].upper() + source[1:] + ".", width=width)]
    out.append(f"  Computed outcome: {result.outcome}, {agreement}.")
    for k, e in enumerate(result.evidence, 1):
        head = f"  {k:>2}. [{e.form}] {e.level}, {seconds_text(e.seconds)}: {verdict(e)}"
        out += textwrap.wrap(head, width=width, subsequent_indent="      ")
        out.append(paragraph(text_of(e.description), indent="      ", width=width))
    return out


def sentence_lines(claim: Claim, width: int) -> list[str]:
    """The sentences of the claim's statement in the paper for ``show``, each with its status
    (covered, UNCOVERED, prose) and the evidence that checks it (or, for prose, why there is
    nothing to check); nothing when the claim maps no sentences."""
    if not claim.sentences:
        return []
    math = [s for s in claim.sentences if s.kind == "math"]
    covered = sum(bool(s.evidence) for s in math)
    out = ["", "The paper's sentences"]
    head = f"{covered} of {len(math)} stating mathematics covered by evidence"
    if covered < len(math):
        head += f", {len(math) - covered} UNCOVERED"
    out.append(paragraph(f"{head}; {len(claim.sentences) - len(math)} prose.", width=width))
    number = {ev.name: k for k, ev in enumerate(claim.evidence, 1)}
    for k, s in enumerate(claim.sentences, 1):
        status = s.kind if s.kind == "prose" else ("covered" if s.evidence else "UNCOVERED")
        out.append(f"  {k:>2}. [{status}]")
        out.append(paragraph(text_of(s.text), indent="      ", width=width))
        if s.kind == "prose":
            why = f"Why nothing is checked: {text_of(s.reason)}"
            out.append(paragraph(why, indent="      ", width=width))
        elif s.evidence:
            names = ", ".join(f"{number[n]} ({n})" for n in s.evidence)
            out.append(paragraph(f"Checked by evidence {names}.", indent="      ", width=width))
        else:
            out.append("      No evidence checks this sentence yet.")
    return out


def seconds_text(s: float) -> str:
    """A duration for people: ``1.4 s``, ``18 ms``, ``<1 ms``."""
    if s >= 0.1:
        return f"{s:.1f} s"
    return f"{s * 1000:.0f} ms" if s >= 0.0005 else "<1 ms"


def _ratio(e: EvidenceResult) -> float:
    """residual / tolerance of an evidence result (``inf`` for an error or any residual above a
    zero tolerance, 0 for an exact zero)."""
    if e.error is not None:
        return float("inf")
    if e.tol == 0:
        return 0.0 if e.residual == 0 else float("inf")
    return float(e.residual / e.tol)


def _num(x: float, digits: int) -> str:
    return "0" if x == 0 else f"{x:.{digits}e}"


def _residual_tol(e: EvidenceResult) -> str:
    """``residual / tol`` of an evidence result; ``0 (exact)`` for an exact zero."""
    if e.error is not None:
        return "error"
    if e.tol == 0 and e.residual == 0:
        return "0 (exact)"
    return f"{_num(e.residual, 1)} / {_num(e.tol, 0)}"


def verdict(e: EvidenceResult) -> str:
    """What an evidence result says, with its residual compared with its tolerance."""
    if e.error is not None:
        return f"error: {e.error}"
    rel, what = ("<=", "passes") if e.passed else (">", "fails")
    why = "as expected" if e.as_expected else "NOT as expected"
    if e.form == "printed":
        why += " of a printed form" if e.as_expected else ": a printed form should fail"
    return f"residual {_num(e.residual, 1)} {rel} tolerance {_num(e.tol, 0)}: {what}, {why}"


_COLUMNS = (("ID", 4), ("computed outcome", 22), ("as recorded", 11), ("checks", 6),
            ("closest call", 15), ("level", 19), ("time", 7))  # fmt: skip


def _row(cells: Sequence[str]) -> str:
    parts = []
    for (name, w), cell in zip(_COLUMNS, cells, strict=True):
        parts.append(f"{cell:>{w}}" if name in ("checks", "time") else f"{cell:<{w}}")
    return "  ".join(parts).rstrip()


def _result_row(r: ClaimResult) -> str:
    """A claim's row: the closest call is the check that must pass (claim and corrected forms)
    with the largest residual / tolerance."""
    must = [e for e in r.evidence if e.form != "printed"]
    e = max(must, key=_ratio) if must else None
    return _row([
        r.id, r.outcome, "yes" if r.ok else "NO", str(len(r.evidence)),
        "-" if e is None else _residual_tol(e), "-" if e is None else e.level,
        seconds_text(r.seconds),
    ])  # fmt: skip


def _surprise_lines(
    results: Sequence[ClaimResult], unchecked: Sequence[dict[str, Any]]
) -> list[str]:
    """The evidence that did not behave as recorded and the kernels not evaluated by their
    claims."""
    lines: list[str] = []
    surprises = [(r, e) for r in results for e in r.evidence if not e.as_expected]
    if surprises:
        lines += ["", "Evidence not as recorded:"]
        for r, e in surprises:
            head = f"{r.id} [{e.form}] {e.level}: {verdict(e)}"
            lines += textwrap.wrap(head, width=WIDTH, subsequent_indent="    ")
            lines += textwrap.wrap(
                f"{e.name}: {text_of(e.description)}", width=WIDTH,
                initial_indent="    ", subsequent_indent="    ",
            )  # fmt: skip
    for k in unchecked:
        by = ", ".join(k["checked_by"])
        text = f"kernel {k['kernel']} names claims {', '.join(k['claims'])} but " + (
            f"only {by} evaluated its expressions" if by else "no claim evaluated its expressions"
        )
        lines += [""] + textwrap.wrap(text, width=WIDTH, subsequent_indent="    ")
    return lines


def verify_table(
    results: Sequence[ClaimResult], unchecked: Sequence[dict[str, Any]], prog: str = "symrb"
) -> list[str]:
    """The lines ``symrb verify`` prints: a table (at most :data:`WIDTH` columns; a heading
    above each claim group when there is more than one), the evidence that did not behave as
    recorded, kernels not evaluated by their claims, a summary."""
    lines = [_row([name for name, _w in _COLUMNS])]
    lines.append("-" * len(lines[0]))
    groups = grouped(results, _id)
    for title, members in groups:
        if len(groups) > 1:
            lines += ["", title]
        lines += [_result_row(r) for r in members]
    lines.append(
        "closest call: the largest residual / tolerance among the checks that must pass "
        "(symbolic and"
    )
    lines.append(f"exact checks must give 0); '{prog} show ID' lists every check of a claim.")
    lines += _surprise_lines(results, unchecked)
    bad = [r.id for r in results if not r.ok]
    total = sum(r.seconds for r in results)
    noun = "claim" if len(results) == 1 else "claims"
    summary = f"{len(results)} {noun} checked in {seconds_text(total)}: "
    if bad:
        summary += f"the computed outcome differs from the record for {', '.join(bad)}"
    elif unchecked:
        summary += "every outcome as recorded, but some kernels were not evaluated"
    else:
        summary += "every outcome as recorded"
    lines += ["", summary]
    return lines


def progress_line(i: int, total: int, r: ClaimResult, seconds: float) -> str:
    w = len(str(total))
    mark = "" if r.ok else f"  SURPRISE: recorded {r.expected}"
    checks = f"{len(r.evidence)} check" + ("" if len(r.evidence) == 1 else "s")
    return (
        f"[{i:>{w}}/{total}] {r.id:<4} {r.outcome:<22}  ({checks}, {seconds_text(seconds)}){mark}"
    )
