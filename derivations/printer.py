"""Code emission: the kernels a claim's evidence checked, printed as batched NumPy functions.

A :class:`Kernel` holds SymPy expressions (matrix expressions in :class:`~sympy.MatrixSymbol` of
symbolic size :data:`n`, or scalars in the components of its arguments).  The same object is
evaluated by a claim's evidence (through :mod:`derivations.symbolic`) and printed here, so what
``symrb`` imports is what the derivations verified (SymForce's ``Codegen.function`` is the model).

Printing rules (every kernel broadcasts over leading batch axes):

* products with ``@``, transposes with ``numpy.swapaxes(X, -1, -2)``, a batched scalar factor
  with ``numpy.expand_dims(c, (-2, -1))`` so that it lines up with the batch axes;
* the inertia operators enter through :data:`AUXILIARIES`: ``Lambda`` is diagonal (a product
  with it scales rows or columns; it is never formed), ``W`` has the entries
  :math:`1/(\\lambda_i+\\lambda_j)` so that :math:`J^{-1}(M) = W\\circ M` (:func:`Jinv`); both are
  defined by a SymPy entry formula from which their code is printed;
* matrix-level common subexpression elimination (:func:`sympy.cse`) after two rewrites: powers
  :math:`X^k` by repeated squaring, and :math:`\\operatorname{tr}(X_1\\cdots X_k)` as
  :math:`\\sum_{ij} A_{ij}B_{ji}` of the two halves of the word (no product for a trace of two
  factors);
* each kernel's docstring states its operation count (per batch item), the claims that checked
  it and the derivation module that defined it;
* output is deterministic and formatted with ``ruff format`` (run through the interpreter running
  this code, so no ``ruff`` on ``PATH`` is needed).
"""

from __future__ import annotations

import difflib
import re
import subprocess
import sys
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import sympy as sp
from sympy.matrices.expressions.applyfunc import ElementwiseApplyFunction
from sympy.printing.numpy import NumPyPrinter
from sympy.printing.precedence import precedence

from derivations.registry import all_kernels
from derivations.vocabulary import _ENTRYWISE, AUXILIARIES, Aux, Kernel, _Entrywise

__all__ = [
    "kernel_source",
    "render_kernel",
    "render_module",
    "collect",
    "emit_all",
    "generated_dir",
]


_LI, _LJ = sp.symbols("lam_i lam_j", real=True)


def _aux_code(aux: Aux) -> str:
    """Code for an auxiliary from its entry formula: lam_i -> lam[..., :, None], lam_j -> ..."""
    expr = aux.entry(_LI, _LJ, sp.Integer(0))
    code = MatrixPrinter().doprint(expr)
    code = re.sub(r"\blam_i\b", "lam[..., :, None]", code)
    return re.sub(r"\blam_j\b", "lam[..., None, :]", code)


def _diag_code(aux: Aux, power: int = 1) -> str:
    assert aux.diagonal is not None
    li = sp.Symbol("lam_i", real=True)
    code = NumPyPrinter({"fully_qualified_modules": True}).doprint(aux.diagonal(li) ** power)
    code = re.sub(r"\blam_i\b", "lam", code)
    return code if code == "lam" else f"({code})"


# ---------------------------------------------------------------------------------------------
# rewrites before CSE


class _Square(sp.MatrixExpr):
    """X @ X (kept as a node so that CSE can share squares of squares)."""

    def __new__(cls, arg: sp.MatrixExpr) -> _Square:
        return super().__new__(cls, arg)

    @property
    def shape(self) -> tuple[sp.Expr, sp.Expr]:
        return self.args[0].shape


class _TracePair(sp.Expr):
    """trace(A B) for two matrix expressions, printed as an einsum (no matrix product)."""

    is_commutative = True

    def __new__(cls, a: sp.MatrixExpr, b: sp.MatrixExpr) -> _TracePair:
        return super().__new__(cls, a, b)


def _is_diag(m: sp.Basic) -> Aux | None:
    if isinstance(m, sp.MatrixSymbol) and str(m.name) in AUXILIARIES:
        aux = AUXILIARIES[str(m.name)]
        return aux if aux.diagonal is not None else None
    if isinstance(m, sp.MatPow) and m.exp.is_Integer and m.exp > 0:
        return _is_diag(m.base)
    return None


def _power(base: sp.MatrixExpr, k: int) -> sp.MatrixExpr:
    """X^k by repeated squaring: X^6 = (X^2)^2 X^2."""
    if k == 1:
        return base
    factors = []
    sq = base
    while k:
        if k & 1:
            factors.append(sq)
        k >>= 1
        if k:
            sq = _Square(sq)
    return factors[0] if len(factors) == 1 else sp.MatMul(*reversed(factors))


def _word(expr: sp.Basic) -> tuple[sp.Expr, list[sp.Basic]]:
    """A product as (scalar coefficient, list of letters): powers of dense factors spelled out,
    powers of diagonal auxiliaries kept whole."""
    coeff, mats = (
        expr.as_coeff_matrices() if isinstance(expr, sp.MatMul) else (sp.Integer(1), [expr])
    )
    word: list[sp.Basic] = []
    for m in mats:
        if isinstance(m, sp.MatPow) and _is_diag(m.base) is None and m.exp.is_Integer and m.exp > 0:
            word.extend([m.base] * int(m.exp))
        else:
            word.append(m)
    return coeff, word


def _halves(word: list[sp.Basic]) -> tuple[list[sp.Basic], list[sp.Basic]]:
    """Cut a trace word after the ceil(d/2)-th of its d dense letters, so that tr(A M A M) is
    tr(X X) with X = A M and tr(M^6) is tr(M^3 M^3); diagonal letters stay with the letter after
    them."""
    dense = [i for i, m in enumerate(word) if _is_diag(m) is None]
    if len(dense) < 2:
        return word, []
    cut = dense[(len(dense) + 1) // 2 - 1] + 1
    return word[:cut], word[cut:]


def _rewrite(expr: sp.Basic) -> sp.Basic:
    """Powers by repeated squaring, traces of products as trace pairs, opaque entrywise nodes."""
    if isinstance(expr, ElementwiseApplyFunction):
        name = next((k for k, v in _ENTRYWISE.items() if v == expr.function), None)
        if name is None:
            raise ValueError(f"entrywise function {expr.function} was not made with entrywise()")
        return _Entrywise(name, _rewrite(expr.expr))
    if isinstance(expr, sp.MatPow):
        base = _rewrite(expr.base)
        if _is_diag(expr.base) is not None:
            return sp.MatPow(base, expr.exp)
        if not (expr.exp.is_Integer and expr.exp > 0):
            raise NotImplementedError(f"matrix power {expr}")
        return _power(base, int(expr.exp))
    if isinstance(expr, sp.Trace):
        coeff, word = _word(expr.arg)
        left, right = _halves(word)
        if not right:
            return _rewrite(coeff) * sp.Trace(_rewrite(sp.MatMul(*left).doit()))
        a, b = (_rewrite(sp.MatMul(*half).doit()) for half in (left, right))
        return _rewrite(coeff) * _TracePair(a, b)
    if not expr.args:
        return expr
    new = [_rewrite(a) for a in expr.args]
    if all(x is y for x, y in zip(new, expr.args, strict=True)):
        return expr
    return expr.func(*new)


def _cheap(e: sp.Basic) -> bool:
    """Temporaries not worth a name: views, diagonal powers, negations of a symbol."""
    if isinstance(e, sp.Transpose) and isinstance(e.arg, sp.MatrixSymbol):
        return True
    if _is_diag(e) is not None:
        return True
    if isinstance(e, sp.MatMul):
        coeff, mats = e.as_coeff_matrices()
        return coeff.is_Number and len(mats) == 1 and isinstance(mats[0], sp.MatrixSymbol)
    return False


def _cse(exprs: list[sp.Basic]) -> tuple[list[tuple[sp.Symbol, sp.Basic]], list[sp.Basic]]:
    """sympy.cse on the rewritten expressions, then cheap temporaries substituted back."""
    rewritten = [_rewrite(e) for e in exprs]
    reps, reduced = sp.cse(rewritten, symbols=sp.numbered_symbols("t"), order="none")
    keep: list[tuple[sp.Symbol, sp.Basic]] = []
    inline: dict[sp.Basic, sp.Basic] = {}
    for sym, sub in reps:
        sub = sub.xreplace(inline)
        if _cheap(sub):
            inline[sym] = sub
        else:
            keep.append((sym, sub))
    reduced = [r.xreplace(inline) for r in reduced]
    # renumber the kept temporaries t0, t1, ... in order
    renum = {}
    for idx, (sym, _sub) in enumerate(keep):
        new = (
            sp.MatrixSymbol(f"t{idx}", *sym.shape)
            if isinstance(sym, sp.MatrixSymbol)
            else sp.Symbol(f"t{idx}")
        )
        renum[sym] = new
    keep = [(renum[s], e.xreplace(renum)) for s, e in keep]
    reduced = [r.xreplace(renum) for r in reduced]
    return keep, reduced


# ---------------------------------------------------------------------------------------------
# the printer


def _is_matrix(e: sp.Basic) -> bool:
    return isinstance(e, sp.MatrixExpr)


class MatrixPrinter(NumPyPrinter):
    """NumPy printer for batched matrix expressions (see the module docstring)."""

    def __init__(self, like: str = "") -> None:
        super().__init__({"fully_qualified_modules": True, "inline": True, "strict": True})
        self.like = (
            like  # an (..., n, n) argument that zero and identity matrices take the shape of
        )

    # atoms
    def _print_ZeroMatrix(self, expr: sp.ZeroMatrix) -> str:
        if not self.like:
            raise NotImplementedError(
                "a zero matrix needs a matrix argument to take its shape from"
            )
        return f"numpy.zeros_like({self.like})"

    def _print_Identity(self, expr: sp.Identity) -> str:
        if not self.like:
            raise NotImplementedError("an identity matrix needs a matrix argument for its shape")
        return f"numpy.broadcast_to(numpy.eye({self.like}.shape[-1]), {self.like}.shape)"

    def _print_MatrixSymbol(self, expr: sp.MatrixSymbol) -> str:
        name = str(expr.name)
        if name in AUXILIARIES and AUXILIARIES[name].diagonal is not None:
            aux = AUXILIARIES[name]
            return f"({_diag_code(aux)}[..., :, None] * numpy.eye(lam.shape[-1]))"
        return name

    def _print_Symbol(self, expr: sp.Symbol) -> str:
        return str(expr.name)

    def _print_Min(self, expr: sp.Min) -> str:
        return self._nested("numpy.minimum", expr.args)

    def _print_Max(self, expr: sp.Max) -> str:
        return self._nested("numpy.maximum", expr.args)

    def _nested(self, fn: str, args: Sequence[sp.Basic]) -> str:
        """``fn(a, fn(b, c))``, elementwise over broadcast arguments (no functools import)."""
        first, *rest = sorted(args, key=sp.default_sort_key)
        inner = self._print(rest[0]) if len(rest) == 1 else self._nested(fn, rest)
        return f"{fn}({self._print(first)}, {inner})"

    def _print_Rational(self, expr: sp.Rational) -> str:
        return f"({expr.p} / {expr.q})"

    def _print_Half(self, expr: sp.Rational) -> str:
        return "0.5"

    # matrix operations
    def _factor(self, m: sp.Basic) -> str:
        s = self._print(m)
        return s if _atomic(s) else f"({s})"

    def _product(self, mats: Sequence[sp.Basic]) -> str:
        """A product; diagonal factors scale rows (leading) or columns (trailing), O(n^2)."""
        diags = [_is_diag(m) for m in mats]
        lead = 0
        while lead < len(mats) - 1 and diags[lead] is not None:
            lead += 1
        if lead:
            vec = " * ".join(self._diag(m) for m in mats[:lead])
            vec = vec if lead == 1 else f"({vec})"
            return f"({vec}[..., :, None] * {self._factor_product(mats[lead:])})"
        acc = self._factor(mats[0])
        for m, d in zip(mats[1:], diags[1:], strict=True):
            acc = (
                f"({acc} * {self._diag(m)}[..., None, :])"
                if d is not None
                else f"({acc} @ {self._factor(m)})"
            )
        return acc

    def _factor_product(self, mats: Sequence[sp.Basic]) -> str:
        s = self._product(mats) if len(mats) > 1 else self._factor(mats[0])
        return s

    def _diag(self, m: sp.Basic) -> str:
        aux = _is_diag(m)
        assert aux is not None
        power = int(m.exp) if isinstance(m, sp.MatPow) else 1
        return _diag_code(aux, power)

    def _print_MatMul(self, expr: sp.MatMul) -> str:
        coeff, mats = expr.as_coeff_matrices()
        if not mats:
            return self._print(coeff)
        body = self._product(mats)
        if coeff == 1:
            return body
        if coeff == -1:
            return f"(-{body})"
        if coeff.is_Number:
            return f"({self._print(coeff)} * {body})"
        # a batched scalar (a trace, a component): align it with the batch axes
        return f"(numpy.expand_dims({self._print(coeff)}, (-2, -1)) * {body})"

    def _print_MatAdd(self, expr: sp.MatAdd) -> str:
        plus, minus = [], []
        for a in expr.args:
            if isinstance(a, sp.MatMul) and a.as_coeff_matrices()[0].is_negative:
                minus.append(self._print(-a))
            else:
                plus.append(self._print(a))
        plus.sort()
        minus.sort()
        text = " + ".join(plus) if plus else ""
        for m in minus:
            text = f"{text} - {self._factor_str(m)}" if text else f"-{self._factor_str(m)}"
        return f"({text})"

    @staticmethod
    def _factor_str(s: str) -> str:
        return s if _atomic(s) else f"({s})"

    def _print_Transpose(self, expr: sp.Transpose) -> str:
        return f"numpy.swapaxes({self._print(expr.arg)}, -1, -2)"

    def _print_Trace(self, expr: sp.Trace) -> str:
        arg = expr.arg
        aux = _is_diag(arg)
        if aux is not None:
            return f"numpy.sum({self._diag(arg)}, axis=-1)"
        return f"numpy.trace({self._print(arg)}, axis1=-2, axis2=-1)"

    def _print__TracePair(self, expr: _TracePair) -> str:
        a, b = expr.args
        if _is_diag(a) is not None:
            return f'numpy.einsum("...i,...ii->...", {self._diag(a)}, {self._print(b)})'
        if _is_diag(b) is not None:
            return f'numpy.einsum("...i,...ii->...", {self._diag(b)}, {self._print(a)})'
        return f'numpy.einsum("...ij,...ji->...", {self._print(a)}, {self._print(b)})'

    def _print__Square(self, expr: _Square) -> str:
        f = self._factor(expr.args[0])
        return f"({f} @ {f})"

    def _print_HadamardProduct(self, expr: sp.HadamardProduct) -> str:
        return "(" + " * ".join(sorted(self._factor(a) for a in expr.args)) + ")"

    def _print_HadamardPower(self, expr: sp.HadamardPower) -> str:
        return f"({self._factor(expr.base)} ** {self._print(expr.exp)})"

    def _print_MatPow(self, expr: sp.MatPow) -> str:
        aux = _is_diag(expr.base)
        if aux is not None:
            return f"({self._diag(expr)}[..., :, None] * numpy.eye(lam.shape[-1]))"
        raise NotImplementedError(f"matrix power {expr} (rewrite with _power first)")

    def _print__Entrywise(self, expr: _Entrywise) -> str:
        fn = _ENTRYWISE[str(expr.args[0])]
        (var,) = fn.variables
        hole = sp.Symbol("__entrywise_arg__")
        body = self._print(fn.expr.xreplace({var: hole}))
        arg = self._print(expr.args[1])
        bare = arg[1:-1] if _balanced_outer(arg) else arg
        # as the only argument of a call the argument needs no parentheses of its own
        body = body.replace(f"({hole})", f"({bare})")
        return "(" + body.replace(str(hole), self._factor(expr.args[1])) + ")"

    def _print_Pow(self, expr: sp.Pow, rational: bool = False) -> str:
        if expr.exp == -1:
            return f"1.0 / {self.parenthesize(expr.base, precedence(expr), strict=True)}"
        if expr.exp.is_Integer and 3 <= int(expr.exp) <= _MAX_PRODUCT_POWER:
            # a product, not ``**``: Python floats (C pow), NumPy arrays (its own, vectorised
            # pow) and numba (LLVM) round x**3 differently, while x * x * x is the same IEEE
            # products in all three, so a scalar kernel gives the same bits however it is called
            base = self._factor_str(self._print(expr.base))
            return "(" + " * ".join([base] * int(expr.exp)) + ")"
        return super()._print_Pow(expr, rational=rational)


#: integer powers x**3 .. x**8 of a scalar are printed as products (see _print_Pow)
_MAX_PRODUCT_POWER = 8


def _atomic(s: str) -> bool:
    """True when the printed text needs no parentheses as an operand."""
    if re.fullmatch(r"[A-Za-z_][A-Za-z_0-9]*", s) or re.fullmatch(r"\d+(\.\d*)?", s):
        return True
    if s.startswith("(") and _balanced_outer(s):
        return True
    if re.fullmatch(r"numpy\.[a-z_]+\(.*\)", s, flags=re.S) and _balanced_outer(s[s.index("(") :]):
        return True
    return False


def _balanced_outer(s: str) -> bool:
    """Does the opening parenthesis at s[0] close at the very end of s?"""
    if not s.startswith("(") or not s.endswith(")"):
        return False
    depth = 0
    for i, ch in enumerate(s):
        depth += ch == "("
        depth -= ch == ")"
        if depth == 0 and i != len(s) - 1:
            return False
    return depth == 0


# ---------------------------------------------------------------------------------------------
# operation counts


def _count(expr: sp.Basic, acc: dict[str, int]) -> None:
    if isinstance(expr, sp.MatMul):
        coeff, mats = expr.as_coeff_matrices()
        dense = [m for m in mats if _is_diag(m) is None]
        acc["products"] += max(len(dense) - 1, 0)
        acc["elementwise"] += len(mats) - len(dense) + (0 if coeff in (1, -1) else 1)
        for m in mats:
            _count(m, acc)
        if not coeff.is_Number:
            _count(coeff, acc)
        return
    if isinstance(expr, _Square):
        acc["products"] += 1
    elif isinstance(expr, (sp.MatAdd, sp.HadamardProduct)):
        acc["elementwise"] += len(expr.args) - 1
    elif isinstance(expr, sp.HadamardPower):
        acc["elementwise"] += 1
    elif isinstance(expr, _Entrywise):
        acc["elementwise"] += 1
    elif isinstance(expr, (sp.Trace, _TracePair)):
        acc["traces"] += 1
    elif isinstance(expr, (sp.Add, sp.Mul, sp.Pow)) and not isinstance(expr, sp.MatrixExpr):
        acc["scalar"] += sp.count_ops(expr.func(*[sp.Dummy() for _ in expr.args]))
    for a in expr.args:
        if isinstance(a, sp.Basic):
            _count(a, acc)


def op_count(temps: Iterable[tuple[sp.Basic, sp.Basic]], outputs: Iterable[sp.Basic]) -> str:
    acc = {"products": 0, "elementwise": 0, "traces": 0, "scalar": 0}
    for _s, e in temps:
        _count(e, acc)
    for e in outputs:
        _count(e, acc)
    parts = []
    if acc["products"]:
        parts.append(f"{acc['products']} matrix product{'s' * (acc['products'] != 1)} (n^3)")
    if acc["elementwise"]:
        parts.append(f"{acc['elementwise']} elementwise (n^2)")
    if acc["traces"]:
        parts.append(f"{acc['traces']} trace{'s' * (acc['traces'] != 1)} (n^2)")
    if acc["scalar"]:
        parts.append(f"{acc['scalar']} scalar")
    return ", ".join(parts) if parts else "none"


# ---------------------------------------------------------------------------------------------
# rendering


def _docstring(k: Kernel, ops: str) -> str:
    summary, _, rest = k.doc.strip().partition("\n\n")
    lines = [" ".join(summary.split())]
    if rest.strip():
        lines += ["", *[ln.rstrip() for ln in rest.strip().splitlines()]]
    lines += ["", "Parameters", "----------"]
    for a in k.args:
        lines.append(f"{a.name} : array, shape {a.shape}")
        lines.append(f"    {a.doc}")
    lines += ["", "Returns", "-------"]
    if k.stack:
        lines.append(f"array, shape (..., {len(k.outputs)})")
        lines.append("    " + ", ".join(k.outputs) + ", stacked along the last axis")
    else:
        for name in k.outputs:
            lines.append(f"{name} : array")
    lines += [
        "",
        "Notes",
        "-----",
        f"Checked by claim{'s' * (len(k.claims) != 1)} {', '.join(k.claims)} "
        f"(``symrb verify {' '.join(k.claims)}``);",
        f"expressions from ``{k.source}``.",
        "",
        f"Total ops per batch item: {ops}.",
    ]
    body = "\n".join(("    " + ln) if ln else "" for ln in lines)
    return '    r"""' + body.lstrip() + '\n    """\n'


def _component_code(k: Kernel, printer: MatrixPrinter) -> tuple[list[str], list[str], str]:
    out = []
    for argname in sorted(k.components):
        mat = k.components[argname]
        for idx in range(mat.rows):
            for jdx in range(mat.cols):
                sym = mat[idx, jdx]
                if not isinstance(sym, sp.Symbol):
                    continue
                index = f"{idx}, {jdx}" if mat.cols > 1 else f"{idx}"
                out.append(f"    {sym} = {argname}[..., {index}]\n")
    reps, reduced = sp.cse(
        list(k.outputs.values()),
        symbols=sp.numbered_symbols("x"),
        order="canonical",
        optimizations="basic",
    )
    body = [f"    {sym} = {printer.doprint(sub)}\n" for sym, sub in reps]
    printed = [printer.doprint(e) for e in reduced]
    ops = sum(sp.count_ops(e) for _s, e in reps) + sum(sp.count_ops(e) for e in reduced)
    return out + body, printed, f"{ops} scalar"


def render_kernel(k: Kernel) -> str:
    """The text of one generated function."""
    like = next((a.name for a in k.args if a.shape.endswith("n, n)")), "")
    printer = MatrixPrinter(like)
    argnames = [a.name for a in k.args]
    head = [f"def {k.name}({', '.join(argnames)}):\n"]
    conv = [f"    {name} = numpy.asarray({name}, dtype=float)\n" for name in argnames]
    if not k.convert:
        conv = []
    if k.components:
        body, printed, ops = _component_code(k, printer)
    else:
        temps, reduced = _cse(list(k.outputs.values()))
        body = [f"    {sym} = {printer.doprint(sub)}\n" for sym, sub in temps]
        printed = [printer.doprint(e) for e in reduced]
        ops = op_count(temps, reduced)
    if k.stack:
        body.append(
            "    return numpy.stack(numpy.broadcast_arrays(" + ", ".join(printed) + "), axis=-1)\n"
        )
    elif len(printed) == 1:
        body.append(f"    return {printed[0]}\n")
    else:
        body.append("    return (" + ", ".join(printed) + ")\n")
    text = "".join(body)
    aux_lines = [
        f"    {name} = {_aux_code(aux)}\n"
        for name, aux in sorted(AUXILIARIES.items())
        if aux.diagonal is None and re.search(rf"\b{name}\b", text)
    ]
    return "".join(head) + _docstring(k, ops) + "".join(conv) + "".join(aux_lines) + text


def kernel_source(kernels: Sequence[Kernel]) -> str:
    """The module docstring naming the derivation modules that define the kernels."""
    sources = sorted({k.source for k in kernels})
    return ", ".join(f"``{s}``" for s in sources)


def _header(kernels: Sequence[Kernel]) -> str:
    return (
        f'"""Generated from {kernel_source(kernels)}; do not edit by hand.\n\n'
        "Every function here is the expression that the evidence of the claims named in its\n"
        "docstring evaluated.  Regenerate with ``python -m derivations derive`` (or ``symrb\n"
        "derive``); ``--check`` only compares.\n"
        '"""\n\n'
        "from __future__ import annotations\n\n"
        "import numpy\n"
    )


def render_module(kernels: Sequence[Kernel]) -> str:
    """The text of one generated module (deterministic), formatted with ruff."""
    names = [k.name for k in kernels]
    if len(set(names)) != len(names):
        raise ValueError(f"duplicate kernel names: {names}")
    text = _header(kernels)
    text += "\n__all__ = [" + ", ".join(repr(k) for k in names) + "]\n"
    for k in kernels:
        text += "\n\n" + render_kernel(k)
    return _format(text)


def _format(text: str) -> str:
    """``ruff format`` through this interpreter (pinned in the ``derive`` extra: reproducible)."""
    try:
        import ruff  # noqa: F401
    except ImportError:
        raise RuntimeError(
            "generating code needs ruff in this Python environment: pip install -e '.[derive]'"
        ) from None
    proc = subprocess.run(
        [sys.executable, "-m", "ruff", "format", "--line-length", "100", "--stdin-filename",
         "generated.py", "-"],
        input=text,
        capture_output=True,
        text=True,
        check=False,
    )  # fmt: skip
    if proc.returncode != 0:
        raise RuntimeError(f"ruff format failed on generated code:\n{proc.stderr}")
    return proc.stdout


def generated_dir() -> Path:
    """``symrb/_generated`` of the source tree next to this package."""
    return Path(__file__).resolve().parent.parent / "symrb" / "_generated"


INIT_TEXT = (
    '"""Kernels generated by ``derivations`` (see ``derivations/printer.py``); do not edit by hand.\n\n'
    "Regenerate with ``python -m derivations derive`` (or ``symrb derive``).  Import the\n"
    "hand-written wrappers in :mod:`symrb` instead of these modules: they validate input.\n"
    '"""\n'
)


def collect(only: Sequence[str] | None = None) -> dict[str, str]:
    """Render the generated files: ``{filename: text}`` (``only``: just these target modules)."""
    files: dict[str, str] = {} if only else {"__init__.py": INIT_TEXT}
    by_target: dict[str, list[Kernel]] = {}
    for k in all_kernels(only):
        by_target.setdefault(k.target, []).append(k)
    unknown = sorted(set(only or ()) - set(by_target))
    if unknown:
        raise KeyError(f"no kernels go to {unknown}; targets: {sorted(by_target)}")
    for target, kernels in sorted(by_target.items()):
        if only and target not in only:
            continue
        files[f"{target}.py"] = render_module(kernels)
    return files


def emit_all(
    check: bool = False,
    out: Any = sys.stdout,
    target: Path | None = None,
    only: Sequence[str] | None = None,
) -> int:
    """Write (or, with ``check``, diff) the generated files into ``target`` (default
    ``symrb/_generated``, created when missing).  Returns a process exit code."""
    target = generated_dir() if target is None else target
    files = collect(only)
    changed = 0
    for fname in sorted(files):
        path = target / fname
        new = files[fname]
        old = path.read_text() if path.exists() else ""
        if old == new:
            continue
        changed += 1
        if check:
            diff = difflib.unified_diff(
                old.splitlines(keepends=True),
                new.splitlines(keepends=True),
                fromfile=f"committed/{fname}",
                tofile=f"regenerated/{fname}",
            )
            out.writelines(diff)
        else:
            target.mkdir(parents=True, exist_ok=True)
            path.write_text(new)
            print(f"wrote symrb/_generated/{fname}", file=out)
    stale = (
        sorted(p.name for p in target.glob("*.py") if p.name not in files)
        if target.exists() and not only
        else []
    )
    for name in stale:
        changed += 1
        if check:
            print(
                f"stale generated file symrb/_generated/{name} (no derivation writes it)", file=out
            )
        else:
            (target / name).unlink()
            print(f"removed stale symrb/_generated/{name}", file=out)
    if check:
        if changed:
            print(
                f"derive --check: {changed} generated file(s) differ from their derivations",
                file=out,
            )
            return 1
        print(f"derive --check: {len(files)} generated files match their derivations", file=out)
    return 0
