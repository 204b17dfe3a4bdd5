"""The API reference of the book (``book/api/``): one page per public module of symrb, each in
``book/_toc.yml``, no page for an internal module, and each page's members documented once.

The public modules are found by the same function the book's Sphinx extension uses
(``book/_ext/symrb_api.py``), whose rules this test also checks against the modules themselves.
"""

from __future__ import annotations

import importlib
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BOOK = ROOT / "book"
sys.path.insert(0, str(BOOK / "_ext"))

import symrb_api  # noqa: E402

INTERNAL = ("_generated", "_docs", "_package", "_compiled", "_validate", "_results", "_progress")


def _toc_files() -> list[str]:
    return re.findall(r"file: (api/[\w.-]+)", (BOOK / "_toc.yml").read_text())


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
