"""The API reference of the book (``book/api/``): one page per public module of symrb, each in
``book/_toc.yml``, no page for an internal module, and each page's members documented once; a
module page estimated too long to read gives its classes and longest functions pages of their
own (``book/api/<module page>/<name>.md``), and every public name is still documented on exactly
one page.

The public modules are found by the same function the book's Sphinx extension uses
(``book/_ext/symrb_api.py``), whose rules this test also checks against the modules themselves.
"""

from __future__ import annotations

import importlib
import inspect
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BOOK = ROOT / "book"
sys.path.insert(0, str(BOOK / "_ext"))

import symrb_api  # noqa: E402

INTERNAL = ("_generated", "_docs", "_package", "_compiled", "_validate", "_results", "_progress")


def _toc_files() -> list[str]:
    return re.findall(r"file: (api/[\w.-]+)", (BOOK / "_toc.yml").read_text())


def _toc_globs() -> dict[str, str]:
    """``glob: api/<page>/*`` entries of the toc -> the file entry they are a section of."""
    lines = (BOOK / "_toc.yml").read_text().splitlines()
    out = {}
    for i, line in enumerate(lines):
        match = re.match(r"(\s*)- glob: (api/[\w.-]+)/\*$", line)
        if not match:
            continue
        indent = len(match.group(1))
        parent = next(  # the nearest entry above, 4 columns to the left (its `sections:` between)
            re.match(r"\s*- file: (api/[\w.-]+)$", up).group(1)
            for up in reversed(lines[:i])
            if re.match(r"\s*- file: ", up) and len(up) - len(up.lstrip()) == indent - 4
        )
        out[match.group(2)] = parent
    return out


def test_every_public_module_has_its_page_in_the_toc():
    modules = symrb_api.public_modules()
    pages = {f"api/{symrb_api.page_name(m)}" for m in modules} | {"api/index"}
    on_disk = {f"api/{p.stem}" for p in (BOOK / "api").glob("*.md")}
    assert on_disk == pages, (sorted(on_disk - pages), sorted(pages - on_disk))
    assert sorted(_toc_files()) == sorted(pages)
    for m in modules:
        text = (BOOK / "api" / f"{symrb_api.page_name(m)}.md").read_text()
        assert f".. symrb-api-module:: {m}\n" in text, m


def test_internal_modules_are_left_out():
    modules = symrb_api.public_modules()
    assert "symrb.engine" in modules and "symrb.scenes.systems.rigid_body" in modules
    for name in INTERNAL:
        assert importlib.import_module(f"symrb.{name}")
        assert not any(name in m.split(".") for m in modules), name
    assert not any(p.name.startswith("_") for p in (BOOK / "api").glob("*.md"))


def test_a_name_is_documented_on_exactly_one_page():
    """A re-exported name is documented where it is defined; its package's table links there."""
    homes: dict[str, str] = {}
    for m in symrb_api.public_modules():
        for name in symrb_api.public_names(m):
            where = symrb_api.home(m, name)
            assert where in symrb_api.public_modules(), (m, name, where)
            obj = getattr(importlib.import_module(m), name)
            assert getattr(importlib.import_module(where), name) is obj, (m, name, where)
            homes.setdefault(f"{id(obj)}:{name}", where)
            assert homes[f"{id(obj)}:{name}"] == where, (m, name)
    assert symrb_api.home("symrb", "simulate") == "symrb.rigid_body.entry"
    assert symrb_api.home("symrb.scenes", "RigidBodyScene") == "symrb.scenes"
    assert symrb_api.home("symrb.rigid_body", "RigidBodySolution") == "symrb.rigid_body"


def test_purpose_is_the_first_sentence():
    assert symrb_api.purpose("symrb.errors") == "Exceptions raised by symrb."
    assert symrb_api.purpose("symrb.algebra") == (
        "The Lie algebra so(n), the group SO(n) and the inertia operators of the paper."
    )  # SO(n) kept: no space before its parenthesis
    assert symrb_api.purpose("symrb.scenes.sweeps") == (
        "Sweeps: :func:`expand_grid` and :func:`sweep`."
    )  # the remarks in parentheses left for the module's page
    exact = symrb_api.purpose("symrb.exact")
    assert exact.endswith("an elliptic integral of the third kind."), exact


def test_member_pages_are_the_ones_the_split_asks_for():
    """The pages under ``api/<module page>/`` are exactly those ``split_names`` asks for, with
    the stub ``python book/_ext/symrb_api.py`` writes, and each folder is globbed in the toc
    under its module's entry."""
    stale = symrb_api.write_member_pages(BOOK, check=True)
    assert not stale, f"run python book/_ext/symrb_api.py: {stale}"
    folders = {}
    for m in symrb_api.public_modules():
        pages = symrb_api.member_pages(m)
        assert set(pages) == set(symrb_api.split_names(m)), m
        if pages:
            folders[f"api/{symrb_api.page_name(m)}"] = f"api/{symrb_api.page_name(m)}"
    assert _toc_globs() == folders
    on_disk = [
        p.relative_to(BOOK / "api").with_suffix("").as_posix()
        for p in (BOOK / "api").glob("*/*.md")
    ]
    # one file per page on a case-insensitive disk too (random_so, random_SO)
    assert len({p.lower() for p in on_disk}) == len(on_disk)


def test_names_equal_but_for_case_get_two_files(monkeypatch):
    monkeypatch.setattr(symrb_api, "split_names", lambda module: ["random_so", "random_SO"])
    pages = symrb_api.member_pages("symrb.algebra")
    assert pages == {"random_so": "algebra/random_so", "random_SO": "algebra/random_SO-2"}


def _documented_once(package: str = "symrb") -> None:
    """Every public object is documented on exactly one page: read off the reST the module and
    member pages expand to (their ``:members:`` lists and ``.. auto<kind>::`` lines)."""
    where = symrb_api.documented(package)
    twice = {name: pages for name, pages in where.items() if len(pages) != 1}
    assert not twice, twice
    expected = {
        f"{m}.{n}" for m in symrb_api.public_modules(package) for n in symrb_api.own_names(m)
    }
    assert set(where) == expected, (sorted(expected - set(where)), sorted(set(where) - expected))
    for m in symrb_api.public_modules(package):
        for n in symrb_api.public_names(m):  # the summary table links every name to its home
            assert f"   ~{symrb_api.home(m, n)}.{n}" in symrb_api.module_lines(m, package)


@pytest.mark.parametrize("target", [0, 4000, None, 10**9])
def test_every_name_is_documented_once_whatever_the_split(target, monkeypatch):
    """At the book's target and at three others (everything split, some, nothing)."""
    if target is not None:
        monkeypatch.setattr(symrb_api, "TARGET_PX", target)
    _documented_once()
    split = {m: symrb_api.split_names(m) for m in symrb_api.public_modules()}
    if target == 0:  # every module with members of its own splits them all
        assert all(split[m] == symrb_api.own_names(m) for m in split)
    if target == 10**9:
        assert not any(split.values())


def test_the_split_keeps_every_page_within_the_budget():
    """Every module page (what stays on it) and every member page is estimated within
    ``TARGET_PX``; a split module gives every class a page; a short module stays whole."""
    for m in symrb_api.public_modules():
        split = symrb_api.split_names(m)
        stay = [n for n in symrb_api.own_names(m) if n not in split]
        assert symrb_api.module_px(m, stay) <= symrb_api.TARGET_PX, m
        for n in split:
            assert symrb_api._PAGE_PX + symrb_api.member_px(m, n) <= symrb_api.TARGET_PX, (m, n)
        if split:
            mod = importlib.import_module(m)
            assert all(n in split for n in stay + split if inspect.isclass(getattr(mod, n))), m
    scenes = symrb_api.split_names("symrb.scenes")
    assert {"RigidBodyScene", "SceneResult", "Plan"} <= set(scenes)
    assert symrb_api.split_names("symrb.errors") == []


def test_the_estimate_follows_the_length_of_a_docstring():
    """The estimate grows with the docstring: a long function over a one-line one, a class with
    an Attributes section over a bare one (the split relies on the order)."""
    px = symrb_api.member_px
    assert px("symrb.rigid_body.entry", "simulate") > 3 * px("symrb.cli", "version")
    assert px("symrb.paper", "DiscreteFlowSolution") > 2 * px("symrb.errors", "SymrbError")
    assert px("symrb.scenes", "RigidBodyScene") > px("symrb.scenes", "SweepResult")


def test_member_pages_expand_to_their_entry():
    """A member page says where the name lives and documents it with the directive of its kind."""
    lines = symrb_api.member_lines("symrb.scenes.RigidBodyScene")
    assert lines[0].startswith("In :doc:`symrb.scenes <../scenes>`")
    assert ".. autoclass:: symrb.scenes.RigidBodyScene" in lines and "   :members:" in lines
    assert ".. autofunction:: symrb.algebra.J_D" in symrb_api.member_lines("symrb.algebra.J_D")
    stub = symrb_api.member_stub("symrb.scenes", "RigidBodyScene")
    assert ".. symrb-api-member:: symrb.scenes.RigidBodyScene\n" in stub
    split = symrb_api.split_names("symrb.algebra")  # some functions split, the others stay
    module = symrb_api.module_lines("symrb.algebra")
    members = next(line for line in module if line.startswith("   :members: "))
    stay = members.removeprefix("   :members: ").split(", ")
    assert split and stay and not set(stay) & set(split)
    assert sorted(stay + split) == sorted(symrb_api.own_names("symrb.algebra"))


def test_attribute_comments_are_not_read_as_type_and_text():
    """Napoleon reads a ``#:`` comment with a colon as ``type: description``: "(empty: numbered)"
    showed as a type "... (empty" and a text "numbered) ...".  No documented comment has one."""
    from sphinx.pycode import ModuleAnalyzer

    found = []
    for m in symrb_api.public_modules():
        mod = importlib.import_module(m)
        own = symrb_api.own_names(m)
        comments = {
            (m, k): v
            for (cls, k), v in ModuleAnalyzer.for_module(m).find_attr_docs().items()
            if not cls and k in own  # a documented constant
        }
        for n in own:
            if inspect.isclass(getattr(mod, n)):
                docs = symrb_api._attribute_docs(getattr(mod, n))
                comments.update(
                    {(f"{m}.{n}", k): v for k, v in docs.items() if not k.startswith("_")}
                )
        for where, lines in comments.items():
            out = symrb_api._napoleon("\n".join(lines), "attribute", None, f"{where[0]}.{where[1]}")
            if any(line.lstrip().startswith(":type:") for line in out):
                found.append((where, lines[0]))
    assert not found, found


def test_the_index_lists_the_names_documented_on_each_page():
    """Each row names what its page documents and counts the re-exports (their homes' rows name
    them): the top-level package's forty names are not listed twice."""
    for m in symrb_api.public_modules():
        own, cell = symrb_api.own_names(m), symrb_api.index_names(m)
        again = len(symrb_api.public_names(m)) - len(own)
        assert cell.startswith(", ".join(own)), m
        assert cell.endswith(f"{again} re-exported" if again else ", ".join(own) or "(none)"), m
    assert symrb_api.index_names("symrb").endswith(" re-exported")
    assert "simulate" in symrb_api.index_names("symrb.rigid_body.entry")
