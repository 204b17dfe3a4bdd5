"""The public docstrings as the API pages render them: numpydoc sections, and an example each.

The API pages (``book/api/``, one per public module) render the docstrings with napoleon's
numpydoc parser, which reads the text after ``name :`` up to the end of the line as the type; a
description written on that line (or a type continued on the next one) lands where the type
belongs.  The examples themselves run as doctests
(``--doctest-modules`` in pyproject.toml).
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
import textwrap
import tomllib
from pathlib import Path

import pytest

import symrb

ROOT = Path(__file__).resolve().parents[1]


def _public_objects() -> dict[str, object]:
    """Every public name of every public module of symrb (``module.name`` -> object), each object
    once, under the module that defines it or its package (the top level re-exports 40 of them)."""
    seen: dict[int, str] = {}
    out: dict[str, object] = {}
    modules = ["symrb"] + sorted(
        m.name
        for m in pkgutil.walk_packages(symrb.__path__, prefix="symrb.")
        if not any(part.startswith("_") for part in m.name.split(".")) and m.name != "symrb.cli"
    )
    for mod_name in modules:
        mod = importlib.import_module(mod_name)
        for name in getattr(mod, "__all__", ()):
            obj = getattr(mod, name)
            if id(obj) not in seen:
                seen[id(obj)] = f"{mod_name}.{name}"
                out[seen[id(obj)]] = obj
    return out


OBJECTS = _public_objects()
PUBLIC = sorted(OBJECTS)
#: the functions and classes (a constant such as ``METHODS`` has no docstring of its own)
CALLABLE = [name for name in PUBLIC if callable(OBJECTS[name])]
#: "name : type" or "name1, name2 : type", the type on the same line
HEADER = re.compile(r"^(?P<names>\*{0,2}\w+(, \*{0,2}\w+)*)( : (?P<type>.+))?$")
#: a type: short, no reST markup, no sentence
MAX_TYPE = 50


def _sections(doc: str) -> dict[str, list[str]]:
    """The numpydoc sections of a docstring: title -> its lines (dedented)."""
    lines = inspect.cleandoc(doc).splitlines()
    out: dict[str, list[str]] = {}
    title = ""
    i = 0
    while i < len(lines):
        if i + 1 < len(lines) and lines[i].strip() and set(lines[i + 1].strip()) == {"-"}:
            title = lines[i].strip()
            out[title] = []
            i += 2
            continue
        if title:
            out[title].append(lines[i])
        i += 1
    return out


def _entries(section: list[str]) -> list[tuple[str, list[str]]]:
    """(header line, description lines) of each entry of a Parameters-like section."""
    entries: list[tuple[str, list[str]]] = []
    for line in section:
        if line and not line[0].isspace():
            entries.append((line, []))
        elif entries and line.strip():
            entries[-1][1].append(line)
    return entries


def _problems(section: list[str], returns: bool = False) -> list[str]:
    """What is wrong with the entries of a section (a Returns entry may be a bare type)."""
    problems = []
    for header, body in _entries(section):
        m = HEADER.match(header)
        if m is None and not returns:
            problems.append(f"{header!r} is not 'name : type'")
            continue
        typ = header if m is None else (m.group("type") or "")
        if len(typ) > MAX_TYPE or "`" in typ or typ.count("(") != typ.count(")"):
            problems.append(f"{header!r}: a description where the type belongs")
        if not body:
            problems.append(f"{header!r} has no indented description below it")
    return problems


def _documented(section: list[str]) -> set[str]:
    names: set[str] = set()
    for header, _body in _entries(section):
        m = HEADER.match(header)
        if m:
            names |= {n.strip().lstrip("*") for n in m.group("names").split(",")}
    return names


@pytest.mark.parametrize("name", CALLABLE)
def test_public_name_has_an_example(name: str) -> None:
    doc = inspect.getdoc(OBJECTS[name]) or ""
    examples = _sections(doc).get("Examples")
    assert examples is not None, f"{name}: no Examples section"
    assert any(line.lstrip().startswith(">>> ") for line in examples), f"{name}: no >>>"


@pytest.mark.parametrize("name", PUBLIC)
def test_parameters_follow_numpydoc(name: str) -> None:
    obj = OBJECTS[name]
    doc = inspect.getdoc(obj) or ""
    sections = _sections(doc)
    problems = []
    for title in ("Parameters", "Returns", "Attributes"):
        if title in sections:
            found = _problems(sections[title], returns=title == "Returns")
            problems += [f"{title}: {p}" for p in found]
    if inspect.isfunction(obj):
        params = [
            p.name
            for p in inspect.signature(obj).parameters.values()
            if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)
        ]
        if params:
            missing = set(params) - _documented(sections.get("Parameters", []))
            if missing:
                problems.append(f"parameters not documented: {sorted(missing)}")
    assert not problems, f"{name}:\n" + "\n".join(problems)


def test_the_checker_catches_a_description_in_the_type() -> None:
    """The two docstrings the issue names, as they were: both are reported."""
    bad = textwrap.dedent(
        """\
        method, rtol, atol, t_eval : as in :func:`scipy.integrate.solve_ivp` (``t_eval=None`` keeps
            the solver's steps)
        U0 : optional starting guess in SO(n) (..., n, n), e.g. the previous step's solution; when
            Newton from it fails or lands off the branch, the Riccati start is used instead
        lam : array_like, shape (..., n)
            The diagonal of Lambda.
        tol : float
        """
    ).splitlines()
    problems = _problems(bad)
    assert len(problems) == 3, problems
    assert "method, rtol" in problems[0] and "U0" in problems[1] and "tol" in problems[2]


def test_doctests_run_with_the_tests() -> None:
    """``python -m pytest`` (as CI runs it) collects the package's docstring examples."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]
    assert "symrb" in config["testpaths"]
    assert "--doctest-modules" in config["addopts"].split()


def test_every_public_module_is_covered() -> None:
    """The names checked reach past the top level: every submodule's public functions count."""
    assert len(PUBLIC) > 100
    assert "symrb.engine.mv_flow" in PUBLIC and "symrb.scenes.plan_scene" in PUBLIC
