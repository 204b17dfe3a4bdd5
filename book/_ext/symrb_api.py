"""A tiny Sphinx extension for the API reference page.

``.. symrb-api::`` (inside an ``{eval-rst}`` block) expands to one section per public module of the
``symrb`` package, each with ``.. automodule:: <module>`` and ``:members:`` (the package itself gets
its docstring only: the names it re-exports are documented once, in the submodule defining them).  The list of modules is
discovered when the book is built, so a new ``symrb/*.py`` module appears in the reference without
an edit to the book.  Private modules (a name part starting with ``_``, e.g. ``symrb._generated``)
are left out: they are documented through the public functions that wrap them.
"""

from __future__ import annotations

import importlib
import pkgutil

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


class SymrbApi(SphinxDirective):
    has_content = False
    required_arguments = 0
    optional_arguments = 1  # the package name, default symrb

    def run(self) -> list[nodes.Node]:
        package = self.arguments[0] if self.arguments else "symrb"
        lines: list[str] = []
        for name in public_modules(package):
            lines += [f"``{name}``", "=" * (len(name) + 4), "", f".. automodule:: {name}"]
            if name != package:
                lines.append("   :members:")
            lines.append("")
        source = self.get_source_info()[0]
        content = StringList(lines, source=source)
        node = nodes.section()
        node.document = self.state.document
        nested_parse_with_titles(self.state, content, node)
        return node.children


def setup(app):  # Sphinx extension entry point
    app.add_directive("symrb-api", SymrbApi)
    return {"version": "0.1", "parallel_read_safe": True, "parallel_write_safe": True}
