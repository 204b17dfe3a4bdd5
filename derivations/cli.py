"""The development commands of a source checkout: ``claims``, ``show``, ``verify`` and ``derive``.

Reached as ``symrb <command>`` or ``python -m derivations <command>``:

* ``claims`` lists the registered claims with their recorded outcomes (no evidence is run);
* ``show ID`` prints one claim for a terminal: where it is in the paper, the statement, the printed
  and corrected forms, the note, then its evidence with residual and tolerance;
* ``verify [IDS]`` runs the evidence, prints a progress line per claim on stderr and a table on
  stdout, and fails when a computed outcome differs from the recorded one;
* ``derive [--check]`` writes (or only compares) ``symrb/_generated``.

Exit status: 0 everything as recorded; 1 a surprise (a computed outcome differs from the record,
a kernel not evaluated by the claims it names, a stale generated file); 2 usage or environment
(bad arguments, an unknown claim, SymPy missing).

This module imports neither SymPy nor the registry at import time, so ``--help`` and ``--version``
work without them; formulas are turned into plain text by :func:`formula_text` and hand-written
LaTeX by :func:`latex_to_text`.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import textwrap
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

__all__ = ["main", "build_parser", "version", "latex_to_text", "formula_text", "claim_text"]

#: The widest line the tables print (and the cap on wrapped text).
WIDTH = 100

_INSTALL = "pip install -e '.[derive]' in a clone of the symrb repository"

EXIT_STATUS = f"""\
exit status:
  0  everything as recorded: every computed outcome equals the recorded one, the generated
     code is what the derivations emit
  1  a surprise: a claim's computed outcome differs from the record, a kernel is not evaluated
     by the claims it names, or a generated file is stale (derive --check)
  2  usage or environment: bad arguments, an unknown claim ID, or SymPy or the derivations
     missing (install them with: {_INSTALL})
"""


def version() -> str:
    """The installed version of symrb (its package metadata, else ``symrb.__version__``)."""
    from importlib import metadata

    try:
        return metadata.version("symrb")
    except metadata.PackageNotFoundError:
        try:
            import symrb

            return str(symrb.__version__)
        except ImportError:
            return "unknown (symrb is not installed)"


# ---------------------------------------------------------------------------------------------
# plain text of LaTeX and of SymPy formulas

_SYMBOLS = {
    "langle": "<\1", "rangle": "\2>", "|": "||", "Vert": "||", "lVert": "||", "rVert": "||",
    "vert": "|", "lvert": "|", "rvert": "|", "le": " <= ", "leq": " <= ", "ge": " >= ",
    "geq": " >= ", "ne": " != ", "neq": " != ", "approx": " ~ ", "sim": " ~ ", "in": " in ",
    "notin": " not in ", "subset": " subset ", "times": " x ", "circ": " o ", "cdot": " . ",
    "wedge": " ^ ", "to": " -> ", "rightarrow": " -> ", "mapsto": " |-> ", "pm": "+-",
    "mp": "-+", "infty": "inf", "dots": "...", "ldots": "...", "cdots": "...", "quad": "\0",
    "qquad": "\0", ",": " ", ";": " ", ":": " ", " ": " ", "!": "", "limits": "",
    "nolimits": "", "displaystyle": "", "rm": "", "bf": "", "it": "", "partial": "d",
    "nabla": "grad", "prime": "'", "ast": "*", "star": "*", "{": "{", "}": "}", "_": "_",
    "%": "%", "$": "$", "&": "&", "#": "#", "\\": "; ", "ell": "l",
}  # fmt: skip
_ACCENTS = {
    "dot": "dot", "ddot": "ddot", "hat": "hat", "widehat": "hat", "tilde": "tilde",
    "widetilde": "tilde", "bar": "bar", "overline": "bar", "check": "check", "vec": "",
}  # fmt: skip
_FONTS = {
    "mathfrak", "mathbb", "mathrm", "mathbf", "mathcal", "mathit", "mathsf", "mathscr",
    "operatorname", "text", "textrm", "textit", "textbf", "textsf", "boldsymbol", "mbox",
}  # fmt: skip
_FRACTIONS = {"frac", "tfrac", "dfrac"}
_SIMPLE_SCRIPT = re.compile(r"-?[A-Za-z0-9*']+|[A-Za-z]+\^[A-Za-z0-9*']+")


class _Latex:
    """A small recursive reader of the LaTeX the claims use (see :func:`latex_to_text`)."""

    def __init__(self, text: str, strict: bool = True) -> None:
        self.s = text
        self.i = 0
        self.strict = strict

    def _skip_spaces(self) -> None:
        while self.i < len(self.s) and self.s[self.i].isspace():
            self.i += 1

    def _command(self) -> str:
        """The name of the command at ``self.i`` (which is just after a backslash)."""
        start = self.i
        if self.i < len(self.s) and self.s[self.i].isalpha():
            while self.i < len(self.s) and self.s[self.i].isalpha():
                self.i += 1
        else:
            self.i += 1
        return self.s[start : self.i]

    def argument(self) -> str:
        """The next argument (a brace group or one token) as plain text."""
        self._skip_spaces()
        if self.i >= len(self.s):
            return ""
        if self.s[self.i] == "{":
            depth, start = 0, self.i
            while self.i < len(self.s):
                ch = self.s[self.i]
                if ch == "\\":
                    self.i += 2
                    continue
                depth += ch == "{"
                depth -= ch == "}"
                self.i += 1
                if depth == 0:
                    break
            return _Latex(self.s[start + 1 : self.i - 1], self.strict).text().strip()
        if self.s[self.i] == "\\":
            self.i += 1
            return self._convert_command(self._command())
        self.i += 1
        return self.s[self.i - 1]

    def _convert_command(self, name: str) -> str:
        if name in _FRACTIONS:
            num, den = self.argument(), self.argument()
            return f"{_wrap(num)}/{_wrap(den)}"
        if name == "sqrt":
            if self.s.startswith("[", self.i):
                self.i = self.s.index("]", self.i) + 1
            return f"sqrt({self.argument()})"
        if name in _ACCENTS:
            return self.argument() + _ACCENTS[name]
        if name in _FONTS:
            return self.argument()
        if name == "substack":
            return self.argument().replace("; ", ", ")
        if name in ("begin", "end"):
            self.argument()  # the environment: a matrix, whose brackets are \left[ \right]
            return ""
        if name in ("left", "right", "big", "Big", "bigl", "bigr", "Bigl", "Bigr"):
            self._skip_spaces()
            if self.s.startswith(".", self.i):
                self.i += 1
            return ""
        if name == "partial":
            self._skip_spaces()
            return "d"
        if name in _SYMBOLS:
            return _SYMBOLS[name]
        return name

    def _script(self) -> str:
        """The argument of ``_`` or ``^``: a brace group, a command, or a signed character (the
        texts mix LaTeX with printed text such as ``X^-1``)."""
        self._skip_spaces()
        bare = r"[-+]?[A-Za-z0-9*']" + ("" if self.strict else "+")
        m = re.compile(bare).match(self.s, self.i)
        if m and not self.s.startswith("{", self.i):
            self.i = m.end()
            return m.group()
        return self.argument()

    def text(self) -> str:
        out: list[str] = []

        partial = [-1]  # where in ``out`` the last \\partial went

        def glued() -> bool:
            """Whether the output so far ends in a letter or digit (not a \\partial's d)."""
            last = len(out) - 1
            return last != partial[0] and bool(out) and out[-1][-1:].isalnum()

        while self.i < len(self.s):
            ch = self.s[self.i]
            if ch == "\\":
                self.i += 1
                name = self._command()
                word = self._convert_command(name)
                if name.isalpha() and name != "partial" and word[:1].isalpha() and glued():
                    out.append(" ")  # U_k\Lambda is U_k Lambda, \sum_a\phi is sum_a phi
                out.append(word)
                if name == "partial":
                    partial[0] = len(out) - 1
            elif ch in "_^":
                self.i += 1
                arg = self._script()
                if _SIMPLE_SCRIPT.fullmatch(arg):
                    out.append(ch + arg)
                elif ch == "_":
                    out.append("_{" + arg + "}")
                else:
                    out.append("^(" + arg + ")")
                if self.strict and self.i < len(self.s) and self.s[self.i].isalnum():
                    out.append(" ")  # Q^TB is Q^T B
            elif ch in "{}":
                self.i += 1
            elif ch == "&":
                self.i += 1
                out.append(", ")
            elif ch == "~":
                self.i += 1
                out.append(" ")
            else:
                self.i += 1
                out.append(ch)
        return "".join(out)


def _wrap(text: str) -> str:
    """``text`` in parentheses unless it is a single word or number."""
    return text if re.fullmatch(r"[\w.']+(\^[\w']+)?", text) else f"({text})"


def _tidy(text: str) -> str:
    """One space between words, none inside brackets or before a comma; a quad (``\\0``, kept
    apart until here) is two spaces; no space inside angle brackets (marked ``\\1``, ``\\2``)."""
    text = re.sub(r"\s+", " ", text)
    text = re.sub(r"(?<=[(\[]) | (?=[)\],;])", "", text)
    text = re.sub(r" ?\0[ \0]*", "  ", text)
    text = re.sub("\x01 ?| ?\x02", "", text)
    return text.strip()


def latex_to_text(latex: str, strict: bool = True) -> str:
    """Hand-written or printed LaTeX as plain text for a terminal.

    Greek letters are spelled out (``\\Lambda`` is ``Lambda``), accents follow their letter
    (``\\hat{H}`` is ``Hhat``, ``\\dot{x}`` is ``xdot``), ``\\frac{a}{b}`` is ``a/b``,
    ``\\left\\langle a, b\\right\\rangle`` is ``<a, b>``, ``\\|M\\|_{\\rm op}`` is ``||M||_op``;
    one-token scripts lose their braces (``Q^{T}`` is ``Q^T``), longer subscripts keep them
    (``p_{k+1}``) and longer superscripts get parentheses (``(I + X^2)^(1/2)``).  With
    ``strict=False`` (for names printed by SymPy, such as ``delta_Omega``) a bare script may be
    longer than one character.
    """
    return _tidy(_Latex(latex, strict).text())


def _text_printer() -> Any:
    """A StrPrinter that writes the paper's notation (built on first use: SymPy is imported)."""
    import sympy as sp
    from sympy.matrices.expressions.applyfunc import ElementwiseApplyFunction
    from sympy.printing.precedence import PRECEDENCE, precedence
    from sympy.printing.str import StrPrinter

    from derivations.vocabulary import W

    class TextPrinter(StrPrinter):
        """``Bracket(a, b)`` as ``[a, b]``, ``Pair(a, b)`` as ``<a, b>``, ``W o X`` as ``J^-1(X)``,
        transposes as ``X^T``, equations with ``=``; display objects of the parts without a
        rule here print through their own ``_latex`` (with this printer for their arguments),
        and :func:`latex_to_text` turns what remains of LaTeX into text."""

        def _print(self, expr: Any, **kwargs: Any) -> str:
            if isinstance(expr, sp.Indexed):  # before Indexed._sympystr
                return self._print_Indexed(expr)
            cls = type(expr)
            own = getattr(cls, "_latex", None)
            if (
                own is not None
                and not cls.__module__.startswith("sympy")
                and not hasattr(self, "_print_" + cls.__name__)
            ):
                return str(own(expr, self))
            return str(super()._print(expr, **kwargs))

        def _atom(self, expr: Any) -> str:
            text = self._print(expr)
            atoms = (sp.Symbol, sp.MatrixSymbol, sp.Number, sp.Indexed, sp.Function)
            simple = isinstance(expr, (*atoms, ElementwiseApplyFunction))
            return text if simple or re.fullmatch(r"[\w\\{}^']+", text) else f"({text})"

        def _as_ordered_terms(self, expr: Any, order: str | None = None) -> list[Any]:
            """The terms in the order they were written, numbers last (N - 1, not -1 + N)."""
            terms = list(expr.args)
            return [t for t in terms if not t.is_Number] + [t for t in terms if t.is_Number]

        def _print_Max(self, expr: Any) -> str:
            return f"max({', '.join(self._print(a) for a in expr.args)})"

        def _print_Min(self, expr: Any) -> str:
            return f"min({', '.join(self._print(a) for a in expr.args)})"

        def _print_Relational(self, expr: Any) -> str:
            ops = {"==": "=", "!=": "!="}
            op = ops.get(expr.rel_op, expr.rel_op)
            return f"{self._print(expr.lhs)} {op} {self._print(expr.rhs)}"

        def _print_tuple(self, expr: Any) -> str:
            return ",  ".join(self._print(e) for e in expr)

        _print_Tuple = _print_tuple

        def _print_Bracket(self, expr: Any) -> str:
            a, b = expr.args
            return f"[{self._print(a)}, {self._print(b)}]"

        def _print_Pair(self, expr: Any) -> str:
            a, b = expr.args
            return f"<{self._print(a)}, {self._print(b)}>"

        def _print_Cross(self, expr: Any) -> str:
            a, b = expr.args
            return f"{self._atom(a)} x {self._atom(b)}"

        def _print_HadamardProduct(self, expr: Any) -> str:
            others = [a for a in expr.args if a != W]
            if len(others) == len(expr.args) - 1:
                inner = others[0] if len(others) == 1 else sp.HadamardProduct(*others)
                return f"J^{{-1}}({self._print(inner)})"
            return " o ".join(self._atom(a) for a in expr.args)

        def _print_Transpose(self, expr: Any) -> str:
            return f"{self._atom(expr.arg)}^T"

        def _print_MatMul(self, expr: Any) -> str:
            coeff, mats = expr.as_coeff_mmul()
            factors = list(mats.args) if isinstance(mats, sp.MatMul) else [mats]
            body = " ".join(self.parenthesize(f, PRECEDENCE["Mul"]) for f in factors)
            if coeff == 1:
                return body
            if coeff == -1:
                return "-" + body
            if coeff.is_Rational and coeff.q != 1:
                sign = "-" if coeff < 0 else ""
                return f"{sign}({abs(coeff.p)}/{coeff.q}) {body}"
            return f"{self.parenthesize(coeff, PRECEDENCE['Mul'])} {body}"

        def _print_Pow(self, expr: Any, rational: bool = False) -> str:
            return str(super()._print_Pow(expr, rational=rational)).replace("**", "^")

        def _print_MatPow(self, expr: Any) -> str:
            return f"{self._atom(expr.base)}^{self._atom(expr.exp)}"

        def _print_Trace(self, expr: Any) -> str:
            return f"tr({self._print(expr.arg)})"

        def _print_Determinant(self, expr: Any) -> str:
            return f"det({self._print(expr.arg)})"

        def _print_Identity(self, expr: Any) -> str:
            return "I"

        def _print_ZeroMatrix(self, expr: Any) -> str:
            return "0"

        def _print_Abs(self, expr: Any) -> str:
            return f"|{self._print(expr.args[0])}|"

        def _print_MatrixBase(self, expr: Any) -> str:
            rows = ("[" + ", ".join(self._print(x) for x in expr.row(i)) + "]" for i in
                    range(expr.rows))  # fmt: skip
            return "[" + ", ".join(rows) + "]"

        def _print_Indexed(self, expr: Any) -> str:
            base = self._print(expr.base.label)
            idx = [self._print(i).replace(" ", "") for i in expr.indices]
            sub = [i if len(i) == 1 else "{" + i + "}" for i in idx]
            if len(sub) == 2:
                return f"{base}^{sub[0]}_{sub[1]}"
            return f"{base}_{sub[0]}" if len(sub) == 1 else f"{base}[{', '.join(idx)}]"

        def _print_Derivative(self, expr: Any) -> str:
            order = sum(int(c) for _v, c in expr.variable_count)
            dvars = " ".join(
                f"d{self._print(v)}" + (f"^{c}" if c != 1 else "") for v, c in expr.variable_count
            )
            top = "d" if order == 1 else f"d^{order}"
            return f"{top}/{dvars} {self._atom(expr.expr)}"

        def _print_Subs(self, expr: Any) -> str:
            body, old, new = expr.args
            at = ", ".join(
                f"{self._print(o)} = {self._print(n)}" for o, n in zip(old, new, strict=True)
            )
            return f"({self._print(body)})|_{{{at}}}"

        def _limits(self, limits: Any, sep: str = ", ") -> str:
            parts = []
            for lim in limits:
                if len(lim) == 3:
                    var, lo, hi = (self._print(x).replace(" ", "") for x in lim)
                    parts.append(f"{var}={lo}..{hi}")
                else:
                    parts.append(self._print(lim[0]))
            return sep.join(parts)

        def _print_Sum(self, expr: Any) -> str:
            body = self.parenthesize(expr.function, PRECEDENCE["Mul"])
            return f"sum_{{{self._limits(expr.limits)}}} {body}"

        def _print_Integral(self, expr: Any) -> str:
            body = self.parenthesize(expr.function, PRECEDENCE["Mul"])
            pieces = []
            for lim in expr.limits:
                if len(lim) == 3:
                    pieces.append(f"int_{{{self._print(lim[1])}..{self._print(lim[2])}}}")
                else:
                    pieces.append("int")
            dvars = " ".join(f"d{self._print(lim[0])}" for lim in expr.limits)
            return f"{' '.join(pieces)} {body} {dvars}"

        def _print_ElementwiseApplyFunction(self, expr: Any) -> str:
            (var,) = expr.function.variables
            hole = sp.Symbol("ARGUMENT")
            body = self._print(expr.function.expr.xreplace({var: hole}))
            return body.replace("ARGUMENT", self._print(expr.expr))

        def parenthesize(self, item: Any, level: int, strict: bool = False) -> str:
            text = self._print(item)
            if precedence(item) < level or (strict and precedence(item) == level):
                return f"({text})"
            return text

    return TextPrinter({"order": "none"})


def formula_text(expr: Any) -> str:
    """A registered formula (a SymPy object, or a tuple of them) as one line of plain text."""
    if isinstance(expr, tuple | list):
        return ",  ".join(formula_text(e) for e in expr)
    return latex_to_text(_text_printer().doprint(expr), strict=False)


_PLACEHOLDER = re.compile(r"\[\[([A-Za-z0-9_]+)\]\]")
_MATH = re.compile(r"(\$[^$]+\$)")


#: Joins the words of a short formula so that wrapping does not split it (see :func:`_paragraph`).
_GLUE = "\x1f"
_SHORT = 40


def claim_text(claim: Any, which: str = "statement", glue: bool = False) -> str:
    """A claim's text ``which`` (statement, printed, corrected, note, title) as plain text:
    ``[[key]]`` becomes :func:`formula_text` of the registered formula and ``$...$`` becomes
    :func:`latex_to_text` of its content.  With ``glue`` the spaces of formulas up to 40
    characters long are :data:`_GLUE`, for :func:`_paragraph`."""
    raw = " ".join((getattr(claim, which) or "").split())
    return text_of(raw, claim.formulas, claim.id, glue)


def text_of(
    raw: str, formulas: dict[str, Any] | None = None, owner: str = "", glue: bool = False
) -> str:
    """Plain text of a text with ``$...$`` math and ``[[key]]`` placeholders for ``formulas``."""

    def glued(text: str) -> str:
        return text.replace(" ", _GLUE) if glue and len(text) <= _SHORT else text

    def formula(m: re.Match[str]) -> str:
        key = m.group(1)
        if formulas is None or key not in formulas:
            raise KeyError(f"claim {owner}: [[{key}]] has no formula")
        return glued(formula_text(formulas[key]))

    out = []
    for piece in _MATH.split(raw):
        if len(piece) > 1 and piece.startswith("$") and piece.endswith("$"):
            out.append(glued(latex_to_text(piece[1:-1])))
        else:
            out.append(_PLACEHOLDER.sub(formula, piece))
    return "".join(out)


# ---------------------------------------------------------------------------------------------
# shared helpers


def _width() -> int:
    """The terminal width when stdout is one (at most :data:`WIDTH`), else :data:`WIDTH`."""
    if sys.stdout.isatty():
        return max(60, min(WIDTH, shutil.get_terminal_size((WIDTH, 24)).columns))
    return WIDTH


def _fit(text: str, width: int) -> str:
    """``text`` cut to ``width`` characters, with ``...`` when it was longer."""
    return text if len(text) <= width else text[: max(width - 3, 0)].rstrip() + "..."


def _paragraph(text: str, indent: str = "  ", width: int | None = None) -> str:
    """``text`` wrapped and indented; words joined by :data:`_GLUE` stay on one line."""
    return textwrap.fill(
        text, width=width or _width(), initial_indent=indent, subsequent_indent=indent,
        break_on_hyphens=False, break_long_words=False,
    ).replace(_GLUE, " ")  # fmt: skip


def _seconds(s: float) -> str:
    """A duration for people: ``1.4 s``, ``18 ms``, ``<1 ms``."""
    if s >= 0.1:
        return f"{s:.1f} s"
    return f"{s * 1000:.0f} ms" if s >= 0.0005 else "<1 ms"


def _no_sympy(command: str) -> str | None:
    """Why ``command`` cannot run here (SymPy missing), or ``None``."""
    try:
        import sympy  # noqa: F401
    except ImportError:
        return f"{command} needs SymPy and the derivations of a source checkout: {_INSTALL}"
    return None


def _claims(ids: Sequence[str]) -> list[Any]:
    """The claims with these IDs (all when empty, duplicates dropped); ``KeyError`` for an
    unknown one."""
    from derivations.registry import all_claims, get_claim

    if not ids:
        return all_claims()
    seen: dict[str, Any] = {}
    for cid in ids:
        c = get_claim(cid)
        seen.setdefault(c.id, c)
    return list(seen.values())


def _ratio(e: Any) -> float:
    """residual / tolerance of an evidence result (``inf`` for an error or any residual above a
    zero tolerance, 0 for an exact zero)."""
    if e.error is not None:
        return float("inf")
    if e.tol == 0:
        return 0.0 if e.residual == 0 else float("inf")
    return float(e.residual / e.tol)


def _num(x: float, digits: int) -> str:
    return "0" if x == 0 else f"{x:.{digits}e}"


def _residual_tol(e: Any) -> str:
    """``residual / tol`` of an evidence result; ``0 (exact)`` for an exact zero."""
    if e.error is not None:
        return "error"
    if e.tol == 0 and e.residual == 0:
        return "0 (exact)"
    return f"{_num(e.residual, 1)} / {_num(e.tol, 0)}"


def _verdict(e: Any) -> str:
    """What an evidence result says, with its residual compared with its tolerance."""
    if e.error is not None:
        return f"error: {e.error}"
    rel, what = ("<=", "passes") if e.passed else (">", "fails")
    why = "as expected" if e.as_expected else "NOT as expected"
    if e.form == "printed":
        why += " of a printed form" if e.as_expected else ": a printed form should fail"
    return f"residual {_num(e.residual, 1)} {rel} tolerance {_num(e.tol, 0)}: {what}, {why}"


# ---------------------------------------------------------------------------------------------
# derive


def _cmd_derive(args: argparse.Namespace) -> int:
    if os.environ.get("PYTHONHASHSEED") != "0":
        # printing must not depend on string hashing: rerun with a fixed seed
        env = dict(os.environ, PYTHONHASHSEED="0")
        argv = [sys.executable, "-m", "derivations", "derive"]
        argv += ["--check"] if args.check else []
        argv += ["--only", *args.only] if args.only else []
        argv += ["--target", str(args.target)] if args.target else []
        return subprocess.run(argv, env=env, check=False).returncode
    from derivations.printer import emit_all

    try:
        return emit_all(check=args.check, target=args.target, only=args.only)
    except KeyError as exc:
        print(exc.args[0], file=sys.stderr)
        return 2


# ---------------------------------------------------------------------------------------------
# claims


def _cmd_claims(args: argparse.Namespace) -> int:
    from derivations.registry import all_claims

    claims = all_claims()
    if args.json:
        rows = [
            {
                "id": c.id, "title": c.title, "title_text": claim_text(c, "title"),
                "label": c.label, "section": c.section, "where": c.where,
                "expected": c.expected, "erratum": bool(c.printed), "checks": len(c.evidence),
            }
            for c in claims
        ]  # fmt: skip
        print(json.dumps(rows, indent=1))
        return 0
    for line in claims_lines(claims, _width()):
        print(line)
    tail = (
        f"{len(claims)} claims, with the outcomes recorded in the registry; '{args.prog} show ID' "
        f"explains one, '{args.prog} verify' checks them."
    )
    print("\n" + textwrap.fill(tail, width=_width()))
    return 0


def claims_lines(claims: Sequence[Any], width: int = WIDTH) -> list[str]:
    """One line per claim: ID, where it is in the paper, recorded outcome, title; at most
    ``width`` characters."""
    where_w = 22
    head = f"{'ID':<4} {'recorded outcome':<22}  {'in the paper':<{where_w}}  title"
    lines = [head, "-" * min(width, len(head) + 30)]
    for c in claims:
        where = c.where or f"sec. {c.section}: {c.label}"
        line = (
            f"{c.id:<4} {c.expected:<22}  {_fit(text_of(where), where_w):<{where_w}}  "
            f"{claim_text(c, 'title')}"
        )
        lines.append(_fit(line, width))
    return lines


# ---------------------------------------------------------------------------------------------
# show


def _recorded(cid: str) -> tuple[Any | None, str]:
    """The result of claim ``cid`` from ``book/_build/verify.json`` when that file was written
    for the current code, with a phrase saying so; ``(None, why not)`` otherwise."""
    from derivations.registry import ClaimResult, EvidenceResult
    from derivations.report import source_hash, verify_json_path

    path = verify_json_path()
    if not path.is_file():
        return None, "no book/_build/verify.json"
    try:
        payload = json.loads(path.read_text())
    except (OSError, ValueError):
        return None, "book/_build/verify.json is unreadable"
    if payload.get("source_hash") != source_hash():
        return None, "book/_build/verify.json was written for other code"
    match = [r for r in payload.get("claims", []) if r.get("id") == cid]
    if not match:
        return None, f"book/_build/verify.json has no result for {cid}"
    r = match[0]
    fields = ("level", "description", "form", "residual", "tol", "seconds", "name", "error")
    evidence = [EvidenceResult(**{k: e.get(k) for k in fields}) for e in r["evidence"]]
    result = ClaimResult(
        id=r["id"], label=r["label"], title=r["title"], expected=r["expected"],
        outcome=r["outcome"], evidence=evidence,
    )  # fmt: skip
    return result, "recorded in book/_build/verify.json for this code"


def _cmd_show(args: argparse.Namespace) -> int:
    from derivations.registry import get_claim, verify_claim

    try:
        claim = get_claim(args.id)
    except KeyError as exc:
        print(textwrap.fill(exc.args[0], width=WIDTH), file=sys.stderr)
        return 2
    width = _width()
    out: list[str] = []
    title = f"{claim.id}: {claim_text(claim, 'title')}"
    out += textwrap.wrap(title, width=width, subsequent_indent="    ")
    out.append("=" * min(width, len(title)))
    where = claim.where or f"section {claim.section}, LaTeX label {claim.label}"
    out.append(_paragraph(f"In the paper: {text_of(where)}", indent="", width=width))
    out.append(f"Recorded outcome: {claim.expected}")
    sections = [("Statement", "statement")]
    if claim.printed:
        sections += [("Printed in the paper", "printed"), ("Corrected", "corrected")]
    if claim.note:
        sections.append(("Note", "note"))
    for heading, which in sections:
        out += ["", heading, _paragraph(claim_text(claim, which, glue=True), width=width)]

    result, source = (None, "") if args.run else _recorded(claim.id)
    if result is None:
        why = "asked with --run" if args.run else source
        start = time.perf_counter()
        result = verify_claim(claim)
        source = f"run now in {_seconds(time.perf_counter() - start)}: {why}"
    verdict = "as recorded" if result.ok else f"NOT as recorded ({claim.expected})"
    out += ["", "Evidence", _paragraph(source[:1].upper() + source[1:] + ".", width=width)]
    out.append(f"  Computed outcome: {result.outcome}, {verdict}.")
    for k, e in enumerate(result.evidence, 1):
        head = f"  {k:>2}. [{e.form}] {e.level}, {_seconds(e.seconds)}: {_verdict(e)}"
        out += textwrap.wrap(head, width=width, subsequent_indent="      ")
        out.append(_paragraph(text_of(e.description), indent="      ", width=width))
    out += ["", f"Rerun its evidence with: {args.prog} verify {claim.id}"]
    print("\n".join(out))
    return 0 if result.ok else 1


# ---------------------------------------------------------------------------------------------
# verify


def _closest_call(r: Any) -> Any | None:
    """The evidence that must pass (claim and corrected forms) with the largest
    residual / tolerance, or ``None`` when there is none."""
    must = [e for e in r.evidence if e.form != "printed"]
    return max(must, key=_ratio) if must else None


_COLUMNS = (("ID", 4), ("computed outcome", 22), ("as recorded", 11), ("checks", 6),
            ("closest call", 15), ("level", 19), ("time", 7))  # fmt: skip


def _row(cells: Sequence[str]) -> str:
    parts = []
    for (name, w), cell in zip(_COLUMNS, cells, strict=True):
        parts.append(f"{cell:>{w}}" if name in ("checks", "time") else f"{cell:<{w}}")
    return "  ".join(parts).rstrip()


def verify_table(
    results: Sequence[Any], unchecked: Sequence[dict[str, Any]], prog: str = "symrb"
) -> list[str]:
    """The lines ``symrb verify`` prints: a table (at most :data:`WIDTH` columns), the evidence
    that did not behave as recorded, kernels not evaluated by their claims, a summary."""
    lines = [_row([name for name, _w in _COLUMNS])]
    lines.append("-" * len(lines[0]))
    for r in results:
        e = _closest_call(r)
        lines.append(
            _row([
                r.id, r.outcome, "yes" if r.ok else "NO", str(len(r.evidence)),
                "-" if e is None else _residual_tol(e), "-" if e is None else e.level,
                _seconds(r.seconds),
            ])
        )  # fmt: skip
    lines.append(
        "closest call: the largest residual / tolerance among the checks that must pass "
        "(symbolic and"
    )
    lines.append(f"exact checks must give 0); '{prog} show ID' lists every check of a claim.")
    surprises = [(r, e) for r in results for e in r.evidence if not e.as_expected]
    if surprises:
        lines += ["", "Evidence not as recorded:"]
        for r, e in surprises:
            head = f"{r.id} [{e.form}] {e.level}: {_verdict(e)}"
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
    bad = [r.id for r in results if not r.ok]
    total = sum(r.seconds for r in results)
    noun = "claim" if len(results) == 1 else "claims"
    summary = f"{len(results)} {noun} checked in {_seconds(total)}: "
    if bad:
        summary += f"the computed outcome differs from the record for {', '.join(bad)}"
    elif unchecked:
        summary += "every outcome as recorded, but some kernels were not evaluated"
    else:
        summary += "every outcome as recorded"
    lines += ["", summary]
    return lines


def _progress_line(i: int, total: int, r: Any, seconds: float) -> str:
    w = len(str(total))
    mark = "" if r.ok else f"  SURPRISE: recorded {r.expected}"
    checks = f"{len(r.evidence)} check" + ("" if len(r.evidence) == 1 else "s")
    return f"[{i:>{w}}/{total}] {r.id:<4} {r.outcome:<22}  ({checks}, {_seconds(seconds)}){mark}"


def _run(
    claims: Sequence[Any], fail_fast: bool, report: Callable[[str, bool], None]
) -> Iterator[Any]:
    """Verify ``claims`` in order, reporting each (``report(line, final)``); stop after the first
    surprise with ``fail_fast``."""
    from derivations.registry import verify_claim

    total = len(claims)
    for i, c in enumerate(claims, 1):
        report(f"[{i:>{len(str(total))}}/{total}] {c.id:<4} running ...", False)
        start = time.perf_counter()
        r = verify_claim(c, fail_fast=fail_fast)
        report(_progress_line(i, total, r, time.perf_counter() - start), True)
        yield r
        if fail_fast and not r.ok:
            return


def _cmd_verify(args: argparse.Namespace) -> int:
    from derivations.registry import all_claims, kernel_report
    from derivations.report import source_hash

    live = not args.quiet and sys.stderr.isatty()
    loading = "loading the claims ..."
    if live:  # on a terminal, a line that the progress lines overwrite
        print(loading, end="\r", file=sys.stderr, flush=True)
    try:
        claims = _claims(args.ids)
    except KeyError as exc:
        print(textwrap.fill(exc.args[0], width=WIDTH), file=sys.stderr)
        return 2
    shown = [len(loading) if live else 0]  # length of the line a carriage return left open

    def report(line: str, final: bool) -> None:
        if args.quiet or (not final and not live):
            return
        pad = " " * max(0, shown[0] - len(line))
        print(line + pad, end="\n" if final else "\r", file=sys.stderr, flush=True)
        shown[0] = 0 if final else len(line)

    results = list(_run(claims, args.fail_fast, report))
    complete = not args.ids and len(results) == len(all_claims())
    kernels = kernel_report()
    unchecked = []
    if complete:
        unchecked = [k for k in kernels if set(k["claims"]) - set(k["checked_by"])]
    payload = {
        "source_hash": source_hash(),
        "claims": [r.to_dict() for r in results],
        "kernels": kernels,
    }
    if args.output:
        Path(args.output).parent.mkdir(parents=True, exist_ok=True)
        Path(args.output).write_text(json.dumps(payload, indent=1) + "\n")
        if not args.quiet:
            print(f"wrote {args.output}", file=sys.stderr)
    if args.json:
        print(json.dumps(payload, indent=1))
    else:
        print("\n".join(verify_table(results, unchecked, args.prog)))
    ok = all(r.ok for r in results) and not unchecked
    return 0 if ok else 1


# ---------------------------------------------------------------------------------------------
# the parser


def build_parser(prog: str = "symrb") -> argparse.ArgumentParser:
    """The argument parser of the four commands (plain-text help with the exit status)."""
    fmt = argparse.RawDescriptionHelpFormatter
    parser = argparse.ArgumentParser(
        prog=prog,
        formatter_class=fmt,
        description=(
            "Check the claims of Bloch, Crouch and Ratiu, 'Symmetric Discrete Optimal Control\n"
            "and Deep Learning' (2024), and derive the kernels of the symrb package.  The\n"
            "commands run the SymPy derivations of a source checkout of symrb."
        ),
        epilog=(
            "examples:\n"
            f"  {prog} claims                 list the claims and their recorded outcomes\n"
            f"  {prog} show S10               one claim: statement, erratum, evidence\n"
            f"  {prog} verify S1 S4 D10       run the evidence of some claims\n"
            f"  {prog} derive --check         is symrb/_generated what the derivations emit?\n\n"
            + EXIT_STATUS
        ),
    )
    parser.add_argument("-V", "--version", action="version", version=f"symrb {version()}")
    parser.set_defaults(prog=prog)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND", title="commands")

    p = sub.add_parser(
        "claims", formatter_class=fmt, epilog=EXIT_STATUS,
        help="list the claims with their recorded outcomes",
        description="List every claim of the paper: ID, where it is in the paper, the recorded\n"
        "outcome and the title.  No evidence is run.",
    )  # fmt: skip
    p.add_argument("--json", action="store_true", help="print JSON instead of a list")
    p.set_defaults(func=_cmd_claims)

    p = sub.add_parser(
        "show", formatter_class=fmt, epilog=EXIT_STATUS,
        help="one claim: statement, printed and corrected forms, evidence",
        description="Show one claim: where it is in the paper, its statement, the printed and\n"
        "corrected forms of an erratum, the note, and every check of its evidence with\n"
        "residual and tolerance (from book/_build/verify.json when it was written for\n"
        "this code, else run now).",
    )  # fmt: skip
    p.add_argument("id", metavar="ID", help="a claim ID such as S10 or D7 (see: claims)")
    p.add_argument("--run", action="store_true", help="run the evidence even if recorded")
    p.set_defaults(func=_cmd_show)

    p = sub.add_parser(
        "verify", formatter_class=fmt, epilog=EXIT_STATUS,
        help="run the evidence and compare the outcomes with the record",
        description="Run the evidence of the claims (all by default), print a progress line per\n"
        "claim on stderr and a table on stdout, and fail when a computed outcome differs\n"
        "from the recorded one.",
    )  # fmt: skip
    p.add_argument("ids", nargs="*", metavar="ID", help="claim IDs (default: all), e.g. S1 D10")
    p.add_argument("--json", action="store_true", help="print JSON instead of the table")
    p.add_argument("--output", metavar="FILE", help="also write the JSON to FILE")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    p.add_argument(
        "--fail-fast", action="store_true", help="stop at the first claim whose outcome differs"
    )
    p.set_defaults(func=_cmd_verify)

    p = sub.add_parser(
        "derive", formatter_class=fmt, epilog=EXIT_STATUS,
        help="regenerate (or with --check compare) symrb/_generated",
        description="Print the kernels of the derivations as NumPy code into symrb/_generated\n"
        "(the only writer of that directory), or with --check only compare.",
    )  # fmt: skip
    p.add_argument("--check", action="store_true", help="only compare; exit 1 on a difference")
    p.add_argument("--only", nargs="+", metavar="TARGET", help="only these generated modules")
    p.add_argument("--target", type=Path, help="write into this directory instead")
    p.set_defaults(func=_cmd_derive)
    return parser


def main(argv: Sequence[str] | None = None, prog: str = "symrb") -> int:
    """Run a command; returns the exit status (argparse's usage errors give 2, help 0)."""
    parser = build_parser(prog)
    if not list(sys.argv[1:] if argv is None else argv):
        parser.print_help(sys.stderr)
        return 2
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:
        return int(exc.code or 0) if not isinstance(exc.code, str) else 2
    why = _no_sympy(f"{prog} {args.command}")
    if why is not None:
        print(why, file=sys.stderr)
        return 2
    try:
        return int(args.func(args))
    except BrokenPipeError:  # `symrb claims | head`: the reader closed the pipe, not an error
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # no second error when Python flushes at exit
        return 0
