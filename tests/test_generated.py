"""Generated kernels: each is the expression its derivation holds, and the generator stands alone.

* every kernel in ``symrb/_generated`` equals ``sympy.lambdify`` of its source expression on random
  batched data (item by item);
* ``derive --check`` is clean, a hand edit is detected, output does not depend on the hash seed;
* the generator works into an empty ``symrb/_generated`` (byte-identical result), through the
  ``symrb`` script called by its path with a ``PATH`` that has no ``ruff``;
* ``derivations`` imports nothing from ``symrb`` at module level; ``symrb`` never imports SymPy.
"""

from __future__ import annotations

import functools
import hashlib
import importlib
import io
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from sympy.printing.numpy import NumPyPrinter

import symrb
from derivations import printer
from derivations.registry import all_kernels
from derivations.vocabulary import AUXILIARIES, Kernel, n

ROOT = Path(__file__).resolve().parent.parent
KERNELS = all_kernels()


def _shape(spec: str, size: int, batch: tuple[int, ...]) -> tuple[int, ...]:
    dims = [d.strip() for d in spec.strip("()").split(",")]
    assert dims[0] == "...", spec
    return batch + tuple(size if d == "n" else int(d) for d in dims[1:])


def _data(k: Kernel, rng: np.random.Generator, size: int) -> dict[str, np.ndarray]:
    batch = (3,)
    out = {}
    for a in k.args:
        shape = _shape(a.shape, size, batch)
        out[a.name] = (
            rng.uniform(0.4, 1.6, shape) if a.name == "lam" else rng.standard_normal(shape)
        )
    return out


class _LambdifyPrinter(NumPyPrinter):
    """SymPy's NumPy printer for one 2-D item, plus the trace it does not print."""

    def _print_Trace(self, expr: sp.Trace) -> str:
        return f"numpy.trace({self._print(expr.arg)})"

    def _print_ElementwiseApplyFunction(self, expr: sp.Basic) -> str:
        (var,) = expr.function.variables
        body = self._print(expr.function.expr.xreplace({var: sp.Symbol("__arg__")}))
        return "(" + body.replace("__arg__", "(" + self._print(expr.expr) + ")") + ")"


def _lambdify(args: list[sp.Basic], exprs: list[sp.Basic]) -> object:
    printer = _LambdifyPrinter({"fully_qualified_modules": True, "strict": True})
    # SymPy prints Min and Max with functools.reduce
    return sp.lambdify(args, exprs, modules=["numpy", {"functools": functools}], printer=printer)


def _auxiliaries(lam: np.ndarray) -> dict[str, np.ndarray]:
    """W_ij = 1/(lam_i + lam_j) and Lambda = diag(lam), written here from the conventions."""
    return {"W": 1.0 / (lam[:, None] + lam[None, :]), "Lambda": np.diag(lam)}


@pytest.mark.parametrize("kernel", KERNELS, ids=[f"{k.target}.{k.name}" for k in KERNELS])
def test_kernel_equals_lambdify_of_its_source(kernel: Kernel) -> None:
    gen = getattr(importlib.import_module(f"symrb._generated.{kernel.target}"), kernel.name)
    rng = np.random.default_rng(sum(map(ord, kernel.name)))
    if kernel.components:
        size = 3
        data = _data(kernel, rng, size)
        syms = [s for name in sorted(kernel.components) for s in kernel.components[name]]
        fn = _lambdify(syms, list(kernel.outputs.values()))
        got = np.asarray(gen(*[data[a.name] for a in kernel.args]))
        for b in range(3):
            vals = [data[name][b].ravel() for name in sorted(kernel.components)]
            want = np.asarray(fn(*np.concatenate(vals)), dtype=float)
            np.testing.assert_allclose(got[b], want, rtol=1e-12, atol=1e-12)
        return
    if all(a.shape == "(...)" for a in kernel.args):  # scalar arguments (e.g. mv3_cayley_*)
        _check_scalar_kernel(kernel, gen, rng)
        return
    size = 4
    data = _data(kernel, rng, size)
    exprs = list(kernel.outputs.values())
    mats = sorted({m for e in exprs for m in e.atoms(sp.MatrixSymbol)}, key=lambda m: str(m.name))
    fn = _lambdify(mats, exprs)
    got = gen(*[data[a.name] for a in kernel.args])
    if kernel.stack:
        got = [np.asarray(got)[..., i] for i in range(len(exprs))]
    else:
        got = [np.asarray(got)] if len(exprs) == 1 else list(got)
    for b in range(3):
        env = {name: v[b] for name, v in data.items()}
        if "lam" in env:
            env.update(_auxiliaries(env["lam"]))
        want = fn(*[env[str(m.name)] for m in mats])
        for g, w in zip(got, want, strict=True):
            w = np.asarray(w, dtype=float)
            scale = max(1.0, float(np.max(np.abs(w))))
            np.testing.assert_allclose(g[b], w, rtol=0, atol=1e-12 * scale)


def _check_scalar_kernel(kernel: Kernel, gen: object, rng: np.random.Generator) -> None:
    """A kernel of scalar arguments: on arrays of 3 items against lambdify item by item, and
    called with Python floats (kernels with ``convert=False`` must accept them) equal to the
    array result."""
    names = [a.name for a in kernel.args]
    # the symbols of the expressions, with their assumptions (a positive one gets positive data)
    syms = {str(x): x for e in kernel.outputs.values() for x in e.free_symbols}
    args = [syms.get(a, sp.Symbol(a, real=True)) for a in names]
    data = {
        a.name: rng.uniform(0.4, 1.6, 3)
        if a.name.startswith("l") or a.is_positive
        else 0.3 * rng.standard_normal(3)
        for a in args
    }
    fn = _lambdify(args, list(kernel.outputs.values()))
    one = len(kernel.outputs) == 1  # one output comes back as an array, not a tuple
    got = np.asarray(gen(*[data[a] for a in names]), dtype=float)  # type: ignore[operator]
    got = got[None] if one else got
    assert np.all(np.isfinite(got)), f"{kernel.name}: the test data leave its domain"
    for b in range(3):
        want = np.asarray(fn(*[data[a][b] for a in names]), dtype=float)
        np.testing.assert_allclose(got[:, b], want, rtol=1e-12, atol=1e-12)
        floats = gen(*[float(data[a][b]) for a in names])  # type: ignore[operator]
        floats = (floats,) if one else floats
        assert all(type(x) is float for x in floats) or kernel.convert
        np.testing.assert_allclose(np.asarray(floats, dtype=float), got[:, b], rtol=0, atol=0)


def test_kernels_are_emitted_once_and_used() -> None:
    """No two kernels share a name, and every kernel is called by some hand-written symrb module."""
    names = [(k.target, k.name) for k in KERNELS]
    assert len(names) == len(set(names))
    sources = "".join(
        p.read_text()
        for p in (ROOT / "symrb").rglob("*.py")
        if "_generated" not in p.parts and p.name != "__init__.py"
    )
    unused = [f"{t}.{name}" for t, name in names if not re.search(rf"\b{name}\b", sources)]
    assert not unused, f"generated but never called from symrb: {unused}"


def test_every_kernel_names_a_claim() -> None:
    for k in KERNELS:
        assert k.claims and all(re.fullmatch(r"[DSM]\d+", c) for c in k.claims), k


def test_derive_check_is_clean() -> None:
    assert printer.emit_all(check=True, out=sys.stderr) == 0


def test_hand_edit_is_detected(tmp_path: Path) -> None:
    """Copy the generated tree, edit one kernel by hand: derive --check must fail with a diff."""
    target = tmp_path / "_generated"
    shutil.copytree(printer.generated_dir(), target)
    f = target / "rigid_body.py"
    text = f.read_text()
    edited = text.replace("W = 1.0 / (", "W = 2.0 / (", 1)
    assert edited != text
    f.write_text(edited)
    buf = io.StringIO()
    assert printer.emit_all(check=True, out=buf, target=target) == 1
    assert "-    W = 2.0 / (" in buf.getvalue()
    f.write_text(text)
    (target / "orphan.py").write_text("x = 1\n")
    buf = io.StringIO()
    assert printer.emit_all(check=True, out=buf, target=target) == 1 and "stale" in buf.getvalue()


def _tracked_copy(dest: Path) -> None:
    files = subprocess.run(
        ["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True
    ).stdout.split(b"\0")
    for raw in filter(None, files):
        src = ROOT / raw.decode()
        if src.is_file():
            (dest / raw.decode()).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest / raw.decode())


def _script(name: str) -> Path:
    path = Path(sys.executable).parent / name
    if not path.exists():
        pytest.skip(f"no {name} script next to {sys.executable}")
    return path


def test_generate_into_empty_directory_by_script_without_ruff_on_path(tmp_path: Path) -> None:
    """Delete symrb/_generated in a copy of the tree, run the ``symrb`` script by its path with a
    PATH that lacks ruff: the regenerated files equal the committed ones byte for byte."""
    copy = tmp_path / "tree"
    _tracked_copy(copy)
    gen = copy / "symrb" / "_generated"
    committed = {p.name: p.read_bytes() for p in gen.glob("*.py")}
    shutil.rmtree(gen)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONHASHSEED",)}
    env["PATH"] = "/usr/bin:/bin"
    env["PYTHONPATH"] = str(copy)
    assert shutil.which("ruff", path=env["PATH"]) is None
    proc = subprocess.run(
        [str(_script("symrb")), "derive"], cwd=copy, env=env, capture_output=True, text=True
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    regenerated = {p.name: p.read_bytes() for p in gen.glob("*.py")}
    assert regenerated == committed


def test_generation_does_not_depend_on_hash_seed() -> None:
    code = (
        "import hashlib; from derivations.printer import collect; f = collect(); "
        "print(hashlib.sha256(''.join(k + f[k] for k in sorted(f)).encode()).hexdigest())"
    )
    digests = set()
    for seed in ("1", "12345"):
        env = dict(os.environ, PYTHONHASHSEED=seed)
        out = subprocess.run(
            [sys.executable, "-c", code], env=env, capture_output=True, text=True, cwd=ROOT,
            check=True,
        )  # fmt: skip
        digests.add(out.stdout.strip())
    committed = {p.name: p.read_text() for p in printer.generated_dir().glob("*.py")}
    expect = hashlib.sha256(
        "".join(k + committed[k] for k in sorted(committed)).encode()
    ).hexdigest()
    assert digests == {expect}


def test_generated_files_have_header() -> None:
    for path in sorted(printer.generated_dir().glob("*.py")):
        head = path.read_text().splitlines()[0]
        assert "do not edit by hand" in head, path.name
        if path.name != "__init__.py":
            assert "Total ops per batch item" in path.read_text(), path.name


def test_derivations_import_nothing_from_symrb_at_module_level() -> None:
    """Import every part and render every kernel with ``symrb`` unimportable."""
    code = (
        "import sys; sys.modules['symrb'] = None\n"
        "from derivations.registry import all_claims\n"
        "from derivations.printer import collect\n"
        "assert len(all_claims('paper')) == 27\n"
        "files = collect()\n"
        "print(len(files))\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
        env=dict(os.environ, PYTHONHASHSEED="0"),
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-3000:]


def test_symrb_does_not_import_sympy() -> None:
    code = (
        "import sys, symrb, importlib, pkgutil, symrb._generated as g\n"
        "[importlib.import_module('symrb._generated.' + m.name) for m in pkgutil.iter_modules(g.__path__)]\n"
        "[getattr(symrb, name) for name in symrb.__all__]\n"
        "assert 'sympy' not in sys.modules, 'sympy imported'\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_cli_without_sympy_exits_2_and_says_what_to_install() -> None:
    code = "import sys; sys.modules['sympy'] = None; from symrb.cli import main; sys.exit(main(sys.argv[1:]))"
    for cmd in (["verify"], ["derive", "--check"]):
        proc = subprocess.run(
            [sys.executable, "-c", code, *cmd], capture_output=True, text=True, cwd=ROOT
        )
        assert proc.returncode == 2, proc.stderr
        assert "pip install -e '.[derive]'" in proc.stderr


def test_exports_table_matches_the_modules() -> None:
    """Every top-level name is a public name of the submodule the table says; at most 40."""
    assert len(symrb.__all__) == len(set(symrb.__all__)) <= 40
    for module, names in symrb._EXPORTS.items():
        public = importlib.import_module(f"symrb.{module}").__all__
        assert set(names) <= set(public), (module, sorted(set(names) - set(public)))
        for name in names:
            assert getattr(symrb, name) is getattr(importlib.import_module(f"symrb.{module}"), name)
    for module in symrb._SUBMODULES:
        assert getattr(symrb, module) is importlib.import_module(f"symrb.{module}")


def test_auxiliaries_print_their_entry_formula() -> None:
    """The code printed for W equals W's entry formula evaluated in NumPy."""
    lam = np.array([[0.5, 1.25, 2.0], [1.0, 3.0, 0.25]])
    code = printer._aux_code(AUXILIARIES["W"])
    got = eval(code, {"numpy": np, "lam": lam})  # noqa: S307 - our own printed code
    li, lj = sp.symbols("li lj")
    entry = sp.lambdify([li, lj], AUXILIARIES["W"].entry(li, lj, sp.Integer(0)))
    np.testing.assert_allclose(got, entry(lam[:, :, None], lam[:, None, :]), rtol=1e-15)
    assert n.is_integer
