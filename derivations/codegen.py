"""Code emission: one printer, one writer.

A derivation module declares what it emits as a list of :class:`Kernel` objects (function name,
arguments with their shapes, the SymPy expressions of the outputs, a docstring).  The writer turns
a list of kernels into one Python module under ``symrb/_generated/``:

* matrix-level expressions (``MatrixSymbol`` of symbolic size ``n``) are printed with ``@`` for
  products, ``numpy.swapaxes(X, -1, -2)`` for transposes and ``numpy.trace(X, axis1=-2, axis2=-1)``
  for traces, so every kernel broadcasts over leading batch axes;
* the inertia operators enter through *auxiliary* matrices computed from the 1-D diagonal ``lam``
  (``Lam`` = diag(lam), ``W`` with ``W_ij = 1/(lam_i + lam_j)`` so that ``J^{-1}(M) = W o M``);
* component-level expressions (scalars indexed out of arrays) go through :func:`sympy.cse`;
* output is deterministic: fixed order of kernels, sorted temporaries, ``PYTHONHASHSEED``-free
  printing (CSE symbols are numbered in order of appearance), and ``ruff format`` when available.

Every file starts with a header naming the derivation module that wrote it and the command that
regenerates it (``symrb derive``).
"""

from __future__ import annotations

import difflib
import importlib
import pkgutil
import re
import shutil
import subprocess
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import sympy as sp
from sympy.printing.numpy import NumPyPrinter

__all__ = [
    "n",
    "Arg",
    "Kernel",
    "MatrixPrinter",
    "aux",
    "render_module",
    "emit_all",
    "generated_dir",
]

#: The symbolic matrix size used by every matrix-level kernel.
n = sp.Symbol("n", integer=True, positive=True)


def aux(name: str) -> sp.MatrixSymbol:
    """An auxiliary n x n matrix computed inside the kernel from ``lam`` (see ``AUXILIARIES``)."""
    if name not in AUXILIARIES:
        raise KeyError(f"unknown auxiliary {name!r}; known: {sorted(AUXILIARIES)}")
    return sp.MatrixSymbol(name, n, n)


#: How each auxiliary matrix is computed from the 1-D diagonal ``lam`` of Lambda (shape (..., n)).
AUXILIARIES: dict[str, str] = {
    "Lam": "lam[..., :, None] * numpy.eye(lam.shape[-1])",
    "Lam2": "(lam * lam)[..., :, None] * numpy.eye(lam.shape[-1])",
    "W": "1.0 / (lam[..., :, None] + lam[..., None, :])",
}

#: Diagonal auxiliaries and their diagonals: a product with one is printed as a row or column
#: scaling, ``lam[..., :, None] * X`` or ``X * lam[..., None, :]``, never as a dense matmul.
DIAGONAL: dict[str, str] = {"Lam": "lam", "Lam2": "(lam * lam)"}


@dataclass(frozen=True)
class Arg:
    """A kernel argument: its name, its shape as documented (e.g. ``"(..., n, n)"``) and meaning."""

    name: str
    shape: str
    doc: str


@dataclass
class Kernel:
    """A function to emit.

    ``outputs`` maps output names to SymPy expressions (matrix expressions, or scalars in the
    components of the arguments).  One output is returned as is; several are returned as a tuple in
    the given order.  ``stack`` instead stacks scalar outputs along a new last axis.
    ``intermediates`` are named matrix-level temporaries assigned in order before the outputs
    (an output refers to one through a ``MatrixSymbol`` of the same name).
    ``components`` maps an argument name to a SymPy Matrix of scalar symbols standing for its
    entries (``arg[..., i, j]`` or ``arg[..., i]``): such kernels are printed through CSE.
    """

    name: str
    args: Sequence[Arg]
    outputs: dict[str, sp.Basic]
    doc: str
    stack: bool = False
    intermediates: dict[str, sp.Basic] = field(default_factory=dict)
    components: dict[str, sp.Matrix] = field(default_factory=dict)
    source: str = ""


class MatrixPrinter(NumPyPrinter):
    """NumPy printer for batched matrix expressions: ``@``, swapaxes, batched trace, Hadamard."""

    def __init__(self) -> None:
        super().__init__({"fully_qualified_modules": True, "inline": True, "strict": True})

    def _print_MatrixSymbol(self, expr: sp.MatrixSymbol) -> str:
        return str(expr.name)

    def _diag_vector(self, m: sp.Basic) -> str | None:
        """The 1-D diagonal (as code) of a diagonal auxiliary factor, or None."""
        if isinstance(m, sp.MatrixSymbol) and str(m.name) in DIAGONAL:
            return DIAGONAL[str(m.name)]
        if (
            isinstance(m, sp.MatPow)
            and isinstance(m.base, sp.MatrixSymbol)
            and str(m.base.name) in DIAGONAL
            and m.exp.is_Integer
            and m.exp > 0
        ):
            return f"({DIAGONAL[str(m.base.name)]} ** {int(m.exp)})"
        return None

    def _product(self, mats: Sequence[sp.Basic]) -> str:
        """A matrix product; a diagonal factor scales rows or columns instead of a matmul (O(n^2))."""
        diags = [self._diag_vector(m) for m in mats]
        lead = 0
        while lead < len(mats) - 1 and diags[lead] is not None:
            lead += 1
        if lead:
            vec = " * ".join(str(d) for d in diags[:lead])
            vec = vec if lead == 1 else f"({vec})"
            return f"({vec}[..., :, None] * {self._product(mats[lead:])})"
        acc = self.parenthesize(mats[0], 100)
        for m, d in zip(mats[1:], diags[1:], strict=True):
            acc = (
                f"({acc} * {d}[..., None, :])"
                if d is not None
                else f"({acc} @ {self.parenthesize(m, 100)})"
            )
        return acc

    def _print_MatMul(self, expr: sp.MatMul) -> str:
        coeff, mats = expr.as_coeff_matrices()
        body = self._product(mats)
        if coeff == 1:
            return body
        if coeff == -1:
            return f"(-{body})"
        return f"({self._print(coeff)} * {body})"

    def _print_MatAdd(self, expr: sp.MatAdd) -> str:
        terms = [self._print(a) for a in expr.args]
        return "(" + " + ".join(sorted(terms)) + ")"

    def _print_Transpose(self, expr: sp.Transpose) -> str:
        return f"numpy.swapaxes({self._print(expr.arg)}, -1, -2)"

    def _print_Trace(self, expr: sp.Trace) -> str:
        return f"numpy.trace({self._print(expr.arg)}, axis1=-2, axis2=-1)"

    def _print_HadamardProduct(self, expr: sp.HadamardProduct) -> str:
        return "(" + " * ".join(self._print(a) for a in expr.args) + ")"

    def _print_MatPow(self, expr: sp.MatPow) -> str:
        base, exp = expr.args
        if exp.is_Integer and exp > 0:
            b = self._print(base)
            return "(" + " @ ".join([b] * int(exp)) + ")"
        raise NotImplementedError(f"matrix power {expr}")

    def _print_ElementwiseApplyFunction(self, expr) -> str:
        """A scalar function applied entrywise, ``X.applyfunc(f)``: print f's body on the array."""
        lam = expr.function
        (var,) = lam.variables
        hole = sp.Symbol("__entrywise_arg__")
        body = self._print(lam.expr.xreplace({var: hole}))
        return "(" + body.replace(str(hole), f"({self._print(expr.expr)})") + ")"

    def parenthesize(self, item: sp.Basic, level: int, strict: bool = False) -> str:
        s = self._print(item)
        if s.startswith("(") or s.replace("_", "").isalnum() or s.startswith("numpy."):
            return s
        return f"({s})"


def _header(source: str) -> str:
    return (
        f'"""Generated by ``{source}``; do not edit by hand.\n\n'
        "Regenerate with ``symrb derive`` (check with ``symrb derive --check``).\n"
        '"""\n'
        "from __future__ import annotations\n\n"
        "import numpy\n"
    )


def _docstring(k: Kernel) -> str:
    lines = [k.doc.strip(), "", "Parameters", "----------"]
    for a in k.args:
        lines.append(f"{a.name} : array, shape {a.shape}")
        lines.append(f"    {a.doc}")
    lines.append("")
    lines.append("Returns")
    lines.append("-------")
    if k.stack:
        lines.append(f"array, shape (..., {len(k.outputs)}): " + ", ".join(k.outputs))
    else:
        for name in k.outputs:
            lines.append(name)
    body = "\n".join(("    " + ln) if ln else "" for ln in lines)
    return '    r"""' + body.lstrip() + '\n    """\n'


def _render_kernel(k: Kernel, printer: MatrixPrinter) -> str:
    argnames = [a.name for a in k.args]
    out = [f"def {k.name}({', '.join(argnames)}):\n", _docstring(k)]
    for name in argnames:
        out.append(f"    {name} = numpy.asarray({name}, dtype=float)\n")
    exprs = list(k.outputs.values())
    body: list[str] = []
    for name, e in k.intermediates.items():
        body.append(f"    {name} = {printer.doprint(e)}\n")
    if k.components:
        # unpack components of arguments into scalars, then CSE
        for argname in sorted(k.components):
            mat = k.components[argname]
            for idx in range(mat.rows):
                for jdx in range(mat.cols):
                    sym = mat[idx, jdx]
                    if not isinstance(sym, sp.Symbol):
                        continue
                    index = f"{idx}, {jdx}" if mat.cols > 1 else f"{idx}"
                    out.append(f"    {sym} = {argname}[..., {index}]\n")
        replacements, reduced = sp.cse(
            exprs, symbols=sp.numbered_symbols("x"), order="canonical", optimizations="basic"
        )
        for sym, sub in replacements:
            body.append(f"    {sym} = {printer.doprint(sub)}\n")
        exprs = reduced
    printed = [printer.doprint(e) for e in exprs]
    if k.stack:
        body.append(
            "    return numpy.stack(numpy.broadcast_arrays(" + ", ".join(printed) + "), axis=-1)\n"
        )
    elif len(printed) == 1:
        body.append(f"    return {printed[0]}\n")
    else:
        body.append("    return (" + ", ".join(printed) + ")\n")
    # auxiliary matrices are computed only when the printed code still refers to them
    text = "".join(body)
    for name in sorted(AUXILIARIES):
        if re.search(rf"\b{name}\b", text):
            out.append(f"    {name} = {AUXILIARIES[name]}\n")
    return "".join(out) + text


def render_module(source: str, kernels: Sequence[Kernel]) -> str:
    """The text of one generated module (deterministic)."""
    printer = MatrixPrinter()
    names = [k.name for k in kernels]
    if len(set(names)) != len(names):
        raise ValueError(f"duplicate kernel names in {source}: {names}")
    text = _header(source)
    text += "\n__all__ = [" + ", ".join(repr(k) for k in names) + "]\n"
    for k in kernels:
        text += "\n\n" + _render_kernel(k, printer)
    return _format(text)


def _format(text: str) -> str:
    """Format with ``ruff format`` (pinned in the ``derive`` extra, so output is reproducible)."""
    ruff = shutil.which("ruff")
    if ruff is None:
        raise RuntimeError(
            "symrb derive needs ruff to format generated code: pip install 'symrb[derive]'"
        )
    proc = subprocess.run(
        [ruff, "format", "--line-length", "100", "--stdin-filename", "generated.py", "-"],
        input=text,
        capture_output=True,
        text=True,
        check=False,
    )
    if proc.returncode != 0:
        raise RuntimeError(f"ruff format failed on generated code:\n{proc.stderr}")
    return proc.stdout


def generated_dir() -> Path:
    """``symrb/_generated`` of the source tree next to this package."""
    return Path(__file__).resolve().parent.parent / "symrb" / "_generated"


INIT_TEXT = (
    '"""Kernels generated by ``derivations`` (see ``derivations/codegen.py``); do not edit by hand.\n\n'
    "Regenerate with ``symrb derive`` (check with ``symrb derive --check``).  Import the\n"
    "hand-written wrappers in :mod:`symrb` instead of these modules: they validate input.\n"
    '"""\n'
)


def collect() -> dict[str, str]:
    """Render every generated file: ``{filename: text}`` from the ``EMITS`` of derivations.parts."""
    from derivations import parts

    files: dict[str, str] = {"__init__.py": INIT_TEXT}
    for info in sorted(pkgutil.iter_modules(parts.__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{parts.__name__}.{info.name}")
        emits = getattr(module, "emit", None)
        if emits is None:
            continue
        target, kernels = emits()
        fname = f"{target}.py"
        if fname in files:
            raise ValueError(f"two derivation modules write {fname}")
        files[fname] = render_module(module.__name__, kernels)
    return files


def emit_all(check: bool = False, out=sys.stdout) -> int:
    """Write (or, with ``check``, diff) every generated file.  Returns a process exit code."""
    target = generated_dir()
    files = collect()
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
    stale = sorted(p.name for p in target.glob("*.py") if p.name not in files)
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
