"""The shape of the source tree: a one-way import graph, modules and functions of readable size.

The import graph is read from the source (``ast``), imports inside functions included, so a cycle
hidden in a function body is a cycle here too.  Only ``if TYPE_CHECKING:`` blocks are left out
(they never run).  Edges go to first-party modules only: ``symrb``, ``derivations``,
``benchmarks``, ``book`` helpers and ``tools``.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("symrb", "derivations", "benchmarks")
GENERATED = ROOT / "symrb" / "_generated"
MAX_MODULE_LINES = 800
MAX_FUNCTION_LINES = 80


def _sources() -> dict[str, Path]:
    """Module name -> file, for every first-party package under the root."""
    out: dict[str, Path] = {}
    for pkg in PACKAGES:
        base = ROOT / pkg
        if not base.is_dir():
            continue
        for path in sorted(base.rglob("*.py")):
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(parts)] = path
    return out


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(tree: ast.AST) -> Iterator[ast.Import | ast.ImportFrom]:
    """Every import statement, at any depth, outside ``if TYPE_CHECKING:`` blocks."""
    stack = [tree]
    while stack:
        node = stack.pop()
        if isinstance(node, ast.If) and _is_type_checking(node):
            stack.extend(node.orelse)
            continue
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
        stack.extend(ast.iter_child_nodes(node))


def _targets(module: str, path: Path, node: ast.Import | ast.ImportFrom, known: set[str]):
    """The first-party modules an import statement loads."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names if a.name in known]
    if node.level:
        package = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
        package = package[: len(package) - (node.level - 1)]
        base = ".".join(package + ([node.module] if node.module else []))
    else:
        base = node.module or ""
    out = []
    for alias in node.names:
        sub = f"{base}.{alias.name}"
        if sub in known:
            out.append(sub)
        elif base in known:
            out.append(base)
    return out


def import_graph() -> dict[str, set[str]]:
    sources = _sources()
    known = set(sources)
    graph: dict[str, set[str]] = {m: set() for m in sources}
    for module, path in sources.items():
        tree = ast.parse(path.read_text(), filename=str(path))
        for node in _imports(tree):
            graph[module].update(t for t in _targets(module, path, node, known) if t != module)
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_import_graph_is_acyclic() -> None:
    cycles = _cycles(import_graph())
    assert not cycles, "import cycles (imports inside functions count):\n" + "\n".join(
        " <-> ".join(c) for c in cycles
    )


def test_the_cycle_finder_finds_a_cycle_inside_a_function(tmp_path: Path) -> None:
    """The check can fail: a function-level import that closes a loop is reported."""
    a = ast.parse("import b\n")
    b = ast.parse("def f():\n    import a\n")
    graph = {
        "a": {t for n in _imports(a) for t in _targets("a", tmp_path / "a.py", n, {"a", "b"})},
        "b": {t for n in _imports(b) for t in _targets("b", tmp_path / "b.py", n, {"a", "b"})},
    }
    assert _cycles(graph) == [["a", "b"]]


def _hand_written() -> list[Path]:
    return [p for p in _sources().values() if GENERATED not in p.parents]


def _code_lines(node: ast.AST, lines: list[str]) -> int:
    """Lines of code of a function: its span less blank lines, comments and its docstring."""
    start, end = node.lineno, node.end_lineno or node.lineno
    body = getattr(node, "body", [])
    skip: set[int] = set()
    if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
        if isinstance(body[0].value.value, str):
            skip = set(range(body[0].lineno, (body[0].end_lineno or body[0].lineno) + 1))
    count = 0
    for i in range(start, end + 1):
        text = lines[i - 1].strip()
        if i in skip or not text or text.startswith("#"):
            continue
        count += 1
    return count


def test_modules_are_readable_in_size() -> None:
    big = {
        str(p.relative_to(ROOT)): n
        for p in _hand_written()
        if (n := len(p.read_text().splitlines())) > MAX_MODULE_LINES
    }
    assert not big, f"modules over {MAX_MODULE_LINES} lines: {big}"


def test_functions_are_readable_in_size() -> None:
    long = {}
    for path in _hand_written():
        text = path.read_text()
        lines = text.splitlines()
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = _code_lines(node, lines)
                if n > MAX_FUNCTION_LINES:
                    long[f"{path.relative_to(ROOT)}:{node.lineno} {node.name}"] = n
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines of code: {long}"


@pytest.mark.parametrize("pkg", ["symrb", "derivations"])
def test_every_first_party_package_is_scanned(pkg: str) -> None:
    assert any(m == pkg or m.startswith(pkg + ".") for m in _sources())
