"""A tiny Sphinx extension for the API reference: one page per public module.

``.. symrb-api-index::`` (inside an ``{eval-rst}`` block, on ``api/index.md``) expands to a table
of every public module of ``symrb``: the module (a link to its page), the first sentence of its
docstring and its public names.  ``.. symrb-api-module:: symrb.engine`` (on ``api/engine.md``)
expands to a summary table of the module's public names (``autosummary``: each name with the
first sentence of its docstring, linked to its entry) and then ``.. automodule::`` with the
members whose home is this module (:func:`home`): a name a package re-exports is documented
once, on the page of the submodule defining it, and the package's table links there.

The public modules are discovered when the book is built (:func:`public_modules`); private
modules (a name part starting with ``_``, e.g. ``symrb._generated``, ``symrb._validate``) are
left out: they are documented through the public functions that wrap them.  ``tests/test_book_api.py``
checks that every public module has its page, listed in ``_toc.yml``, and no other.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
from typing import Any

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.util.docutils import SphinxDirective
from sphinx.util.nodes import nested_parse_with_titles


def public_modules(package: str = "symrb") -> list[str]:
    """The package and its public submodules, sorted (the package itself first)."""
    pkg = importlib.import_module(package)
    names = [package]
    for info in pkgutil.walk_packages(pkg.__path__, prefix=package + "."):
        if any(part.startswith("_") for part in info.name.split(".")):
            continue
        names.append(info.name)
    return [names[0]] + sorted(names[1:])


def page_name(module: str, package: str = "symrb") -> str:
    """The page of a module under ``api/``: ``symrb`` -> ``symrb``, ``symrb.scenes.plan`` ->
    ``scenes-plan`` (dots in a file name would read as a suffix)."""
    if module == package:
        return package
    return module.removeprefix(package + ".").replace(".", "-")


def public_names(module: str) -> list[str]:
    """A module's public names: its ``__all__``, else the functions and classes it defines whose
    names do not start with an underscore (the members ``automodule`` documents)."""
    mod = importlib.import_module(module)
    names = getattr(mod, "__all__", None)
    if names is not None:
        return list(names)
    return [
        name
        for name, obj in vars(mod).items()
        if not name.startswith("_")
        and (inspect.isfunction(obj) or inspect.isclass(obj))
        and obj.__module__ == module
    ]


def home(module: str, name: str) -> str:
    """The module where ``module.name`` is documented: for a function or class the module its
    ``__module__`` names (a re-exported function is documented in the submodule defining it, an
    adopted class in its package); for a constant the deepest public module listing the same
    object in its ``__all__``; a private home falls back to ``module``."""
    obj = getattr(importlib.import_module(module), name)
    if inspect.isfunction(obj) or inspect.isclass(obj):
        where = obj.__module__
    else:
        where = max(
            (
                m
                for m in public_modules(module.split(".")[0])
                if m.startswith(module)
                and name in getattr(importlib.import_module(m), "__all__", ())
                and getattr(importlib.import_module(m), name) is obj
            ),
            key=len,
            default=module,
        )
    if any(part.startswith("_") for part in where.split(".")):
        # defined in a private module: documented where a public module first lists it,
        # a subpackage before the top-level package (whose page lists names, no members)
        listing = [
            m
            for m in public_modules(module.split(".")[0])
            if name in getattr(importlib.import_module(m), "__all__", ())
            and getattr(importlib.import_module(m), name) is obj
        ]
        deeper = [m for m in listing if "." in m]
        where = min(deeper or listing or [module], key=len)
    return where


def purpose(module: str) -> str:
    """The first sentence of a module's docstring (reST, one line), without its remarks in
    parentheses (the module's page has them)."""
    doc = inspect.getdoc(importlib.import_module(module)) or ""
    first = " ".join(doc.split("\n\n", 1)[0].split())
    match = re.search(r"(?<![.:e]\.g)\.(\s|$)", first)
    first = first[: match.start() + 1] if match else first
    if first.count("(") > first.count(")"):  # a period inside a remark ("SIAM J.") ended it
        first = first[: first.rindex(" (")] + "."
    text = _REMARK.sub("", first)
    return text if len(text.split()) >= 4 else first


#: a remark in parentheses after a space (not the argument of SO(n)); code spans and one level of
#: nested parentheses inside it are allowed
_REMARK = re.compile(r" \((?:[^()`]|`[^`]*`|\([^()]*\))*\)")


def _parse(directive: SphinxDirective, lines: list[str]) -> list[nodes.Node]:
    content = StringList(lines, source=directive.get_source_info()[0])
    node = nodes.section()
    node.document = directive.state.document
    nested_parse_with_titles(directive.state, content, node)
    return node.children


class SymrbApiIndex(SphinxDirective):
    """The table of the public modules: module (linked), purpose, public names."""

    has_content = False
    optional_arguments = 1  # the package name, default symrb

    def run(self) -> list[nodes.Node]:
        package = self.arguments[0] if self.arguments else "symrb"
        lines = [
            ".. list-table::",
            "   :header-rows: 1",
            "   :widths: 25 47 28",
            "   :class: symrb-api-index",
            "",
            "   * - module",
            "     - what it is",
            "     - public names",
        ]
        for module in public_modules(package):
            names = ", ".join(public_names(module)) or "(none)"
            lines += [
                f"   * - :doc:`{module} <{page_name(module, package)}>`",
                f"     - {purpose(module)}",
                f"     - {names}",
            ]
        return _parse(self, lines)


class SymrbApiModule(SphinxDirective):
    """One module: a summary table of its public names, then its docstring and members."""

    has_content = False
    required_arguments = 1  # the module

    def run(self) -> list[nodes.Node]:
        module = self.arguments[0]
        names = public_names(module)
        lines: list[str] = []
        if names:
            lines += [".. autosummary::", "   :nosignatures:", ""]
            lines += [f"   ~{home(module, n)}.{n}" for n in names]
            lines.append("")
        lines.append(f".. automodule:: {module}")
        own = [n for n in names if home(module, n) == module]
        if own:  # the others are documented on the page of their home
            lines.append(f"   :members: {', '.join(own)}")
            lines.append("   :exclude-members: model_config")
        lines.append("")
        return _parse(self, lines)


def setup(app: Any) -> dict[str, Any]:  # Sphinx extension entry point
    app.add_directive("symrb-api-index", SymrbApiIndex)
    app.add_directive("symrb-api-module", SymrbApiModule)
    return {"version": "0.2", "parallel_read_safe": True, "parallel_write_safe": True}
