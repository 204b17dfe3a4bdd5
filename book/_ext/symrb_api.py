"""A tiny Sphinx extension for the API reference: one page per public module, split when long.

``.. symrb-api-index::`` (inside an ``{eval-rst}`` block, on ``api/index.md``) expands to a table
of every public module of ``symrb``: the module (a link to its page), the first sentence of its
docstring and its public names.  ``.. symrb-api-module:: symrb.engine`` (on ``api/engine.md``)
expands to a summary table of the module's public names (``autosummary``: each name with the
first sentence of its docstring, linked to its entry) and then ``.. automodule::`` with the
members whose home is this module (:func:`home`): a name a package re-exports is documented
once, on the page of the submodule defining it, and the package's table links there.

A module page that would be too long to read (:func:`split_names`: its height estimated from
the docstrings above 7.5 screens of 800 px) gives each of its classes, then its longest other
members, a page of its own, ``api/<module page>/<name>.md``, holding
``.. symrb-api-member:: symrb.scenes.RigidBodyScene``; the summary table links there.  Those pages
are written by ``python book/_ext/symrb_api.py`` (``--check`` lists the stale ones) and reach the
table of contents through one ``glob: api/<module page>/*`` under the module's entry.

The public modules are discovered when the book is built (:func:`public_modules`); private
modules (a name part starting with ``_``, e.g. ``symrb._generated``, ``symrb._validate``) are
left out: they are documented through the public functions that wrap them.  ``tests/test_book_api.py``
checks that every public module has its page, listed in ``_toc.yml``, and no other; that the
member pages on disk are the ones the split asks for; and that every public name is documented
on exactly one page, whatever the split.
"""

from __future__ import annotations

import functools
import importlib
import inspect
import pkgutil
import re
from pathlib import Path
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


# --- splitting: a page a reader finishes -------------------------------------------------------
#
# A page's rendered height is estimated from the docstrings (at 1280x800 in the book's theme; the
# coefficients were fitted to the measured heights of every member of every API page: an entry's
# height is within about 15 % of the estimate).  A module page whose estimate exceeds
# ``TARGET_PX`` gives each of its classes a page of its own, then its longest other members,
# until the rest fits; the summary table at the top of the module page links to every name
# wherever it is documented.  ``TARGET_PX`` is 7.5 screens of 800 px, so that an estimate 15 %
# short still leaves the page under the budget of 10 screens.

SCREEN_PX = 800
TARGET_PX = 6000
#: px per wrapped line of docstring text, per napoleon ``.. attribute::`` entry, per documented
#: member of a class, per line of a member's docstring, per line of signature, per entry
_PX = {"line": 26, "attribute": 100, "member": 8, "member_line": 21, "signature": 29, "entry": 105}
#: px of a page's frame (title, header, footer), of a summary-table row, of a line of a docstring
_PAGE_PX, _ROW_PX = 500, 45
_WRAP = 95  # characters of docstring text on one rendered line


def _napoleon(doc: str, what: str, obj: object, name: str = "") -> list[str]:
    """A docstring as napoleon turns it into reST (``name`` given, an attribute's or constant's
    text is read as ``type: description``, as autodoc has it read)."""
    from sphinx.ext.napoleon import Config, NumpyDocstring

    config = Config(napoleon_use_rtype=False, napoleon_google_docstring=False)
    return str(NumpyDocstring(doc, config, what=what, name=name, obj=obj)).splitlines()


def _rows(lines: list[str], width: int = _WRAP) -> int:
    return sum(max(1, -(-len(line.strip()) // width)) for line in lines if line.strip())


def _signature_rows(obj: Any) -> int:
    try:
        text = str(inspect.signature(obj))
    except (TypeError, ValueError):
        text = ""
    return max(1, -(-len(text) // 90))


def _attribute_docs(cls: type) -> dict[str, list[str]]:
    """The ``#:`` comments of a class's attributes, its own and its bases' (autodoc shows a
    base's comment on an attribute a subclass assigns again)."""
    from sphinx.pycode import ModuleAnalyzer

    docs: dict[str, list[str]] = {}
    for base in cls.__mro__:
        if base.__module__.split(".")[0] != cls.__module__.split(".")[0]:
            continue
        for (qualname, name), lines in (
            ModuleAnalyzer.for_module(base.__module__).find_attr_docs().items()
        ):
            if qualname == base.__qualname__:
                docs.setdefault(name, list(lines))
    return docs


@functools.cache
def member_px(module: str, name: str) -> int:
    """The estimated rendered height (px) of one documented name: its docstring as napoleon
    turns it into reST, its signature, and for a class its documented methods and attributes."""
    obj = getattr(importlib.import_module(module), name)
    if inspect.isclass(obj) or callable(obj):
        what = "class" if inspect.isclass(obj) else "function"
        lines = _napoleon(inspect.getdoc(obj) or "", what, obj)
        px = _PX["entry"] + _PX["line"] * _rows(lines) + _PX["signature"] * _signature_rows(obj)
        px += _PX["attribute"] * sum(line.lstrip().startswith(".. attribute::") for line in lines)
        if inspect.isclass(obj):
            px += _class_members_px(obj)
        return px
    # a constant: its docstring is its ``#:`` comment, its value is shown
    return _PX["entry"] + _PX["line"] * (2 + -(-len(repr(obj)) // 60))


def _class_members_px(cls: type) -> int:
    attr_docs = _attribute_docs(cls)
    px = 0
    for key, value in vars(cls).items():
        if key.startswith("_") or key == "model_config":
            continue
        if callable(value) or isinstance(value, (property, classmethod, staticmethod)):
            doc = inspect.getdoc(value)
            if doc:
                target = value.fget if isinstance(value, property) else value
                rows = _rows(_napoleon(doc, "method", value)) + _signature_rows(target)
                px += _PX["member"] + _PX["member_line"] * rows
        elif key in attr_docs:
            rows = len(attr_docs[key]) + -(-len(repr(value)) // 90)
            px += _PX["member"] + _PX["member_line"] * rows
    return px


def module_px(module: str, members: list[str]) -> int:
    """The estimated height (px) of a module page documenting ``members``: frame, summary
    table, the module's docstring, the members."""
    mod = importlib.import_module(module)
    rows = _rows(_napoleon(inspect.getdoc(mod) or "", "module", mod))
    return (
        _PAGE_PX
        + _ROW_PX * len(public_names(module))
        + _PX["line"] * rows
        + sum(member_px(module, n) for n in members)
    )


def own_names(module: str) -> list[str]:
    """The public names documented under ``module`` (their :func:`home`), in ``__all__`` order."""
    return [n for n in public_names(module) if home(module, n) == module]


def split_names(module: str) -> list[str]:
    """The names of ``module`` that get a page of their own (in ``__all__`` order): none when
    the module's page fits ``TARGET_PX``; otherwise every class, then the other members from the
    longest down until the rest fits."""
    own = own_names(module)
    if module_px(module, own) <= TARGET_PX:
        return []
    mod = importlib.import_module(module)
    out = {n for n in own if inspect.isclass(getattr(mod, n))}
    rest = sorted((n for n in own if n not in out), key=lambda n: -member_px(module, n))
    while rest and module_px(module, [n for n in own if n not in out]) > TARGET_PX:
        out.add(rest.pop(0))
    return [n for n in own if n in out]


def member_pages(module: str, package: str = "symrb") -> dict[str, str]:
    """The page (under ``api/``, no suffix) of each name of ``module`` with a page of its own:
    ``api/<module page>/<name>``.  Names equal but for case (``random_so``, ``random_SO``) would
    be one file on a case-insensitive disk: the second gets ``-2``."""
    pages: dict[str, str] = {}
    seen: dict[str, int] = {}
    for name in split_names(module):
        count = seen[name.lower()] = seen.get(name.lower(), 0) + 1
        stem = name if count == 1 else f"{name}-{count}"
        pages[name] = f"{page_name(module, package)}/{stem}"
    return pages


def member_stub(module: str, name: str) -> str:
    """The Markdown source of a member's page (``book/api/<module page>/<name>.md``)."""
    return (
        f"# `{name}`\n\n"
        "<!-- written by `python book/_ext/symrb_api.py`: do not edit -->\n\n"
        "```{eval-rst}\n"
        f".. symrb-api-member:: {module}.{name}\n"
        "```\n"
    )


def module_lines(module: str, package: str = "symrb") -> list[str]:
    """The reST a module's page expands to: the summary table of every public name (each linked
    to wherever it is documented), a line on the names with pages of their own, the module's
    docstring and its members without a page of their own."""
    names = public_names(module)
    lines: list[str] = []
    if names:
        lines += [".. autosummary::", "   :nosignatures:", ""]
        lines += [f"   ~{home(module, n)}.{n}" for n in names]
        lines.append("")
    split = split_names(module)
    if split:  # the page would be too long: say which entries have pages of their own
        linked = ", ".join(f":py:obj:`~{module}.{n}`" for n in split)
        lines += [f"On pages of their own (as linked from the table): {linked}.", ""]
    lines.append(f".. automodule:: {module}")
    own = [n for n in own_names(module) if n not in split]
    if own:  # the others are documented on the page of their home or on their own page
        lines.append(f"   :members: {', '.join(own)}")
        lines.append("   :exclude-members: model_config")
    lines.append("")
    return lines


def member_lines(qualified: str, package: str = "symrb") -> list[str]:
    """The reST a member's own page expands to: where it lives, then its entry (a class with
    its members, as on a module page)."""
    module, _, name = qualified.rpartition(".")
    obj = getattr(importlib.import_module(module), name)
    kind = "class" if inspect.isclass(obj) else "function" if callable(obj) else "data"
    lines = [
        f"In :doc:`{module} <../{page_name(module, package)}>` (``from {module} import {name}``).",
        "",
        f".. auto{kind}:: {qualified}",
    ]
    if kind == "class":
        lines += ["   :members:", "   :exclude-members: model_config"]
    return lines + [""]


def documented(package: str = "symrb") -> dict[str, list[str]]:
    """Where each name is documented, read off the reST the pages expand to: qualified name ->
    the pages (``api/...``) whose ``automodule :members:`` or ``auto<kind>`` documents it."""
    where: dict[str, list[str]] = {}
    for module in public_modules(package):
        page = f"api/{page_name(module, package)}"
        for line in module_lines(module, package):
            if line.startswith("   :members: "):
                for name in line.removeprefix("   :members: ").split(", "):
                    where.setdefault(f"{module}.{name}", []).append(page)
        for name, sub in member_pages(module, package).items():
            for line in member_lines(f"{module}.{name}", package):
                if line.startswith(".. auto"):
                    where.setdefault(line.split(":: ")[1], []).append(f"api/{sub}")
    return where


def write_member_pages(book: Path, package: str = "symrb", check: bool = False) -> list[str]:
    """Write every member page under ``book/api/<module page>/`` and delete the stale ones;
    with ``check``, change nothing.  Returns the pages that were (or would be) changed."""
    want = {
        book / "api" / f"{sub}.md": member_stub(module, name)
        for module in public_modules(package)
        for name, sub in member_pages(module, package).items()
    }
    changed = []
    for path in sorted(p for p in (book / "api").glob("*/*.md") if p not in want):
        changed.append(str(path.relative_to(book)))
        if not check:
            path.unlink()
    for path, text in sorted(want.items()):
        if not path.exists() or path.read_text() != text:
            changed.append(str(path.relative_to(book)))
            if not check:
                path.parent.mkdir(exist_ok=True)
                path.write_text(text)
    if not check:
        for folder in (book / "api").iterdir():
            if folder.is_dir() and not any(folder.iterdir()):
                folder.rmdir()
    return changed


def _parse(directive: SphinxDirective, lines: list[str]) -> list[nodes.Node]:
    content = StringList(lines, source=directive.get_source_info()[0])
    node = nodes.section()
    node.document = directive.state.document
    nested_parse_with_titles(directive.state, content, node)
    return node.children


def index_names(module: str) -> str:
    """The "public names" cell of a module in the index: the names documented under it, then
    how many more it re-exports (all of them on its page's table: listing the top-level
    package's forty re-exports here again made the index twice as long)."""
    own = own_names(module)
    again = len(public_names(module)) - len(own)
    text = ", ".join(own)
    if again:
        text += f"{'; ' if own else ''}{again} re-exported"
    return text or "(none)"


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
            names = index_names(module)
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
        return _parse(self, module_lines(self.arguments[0]))


class SymrbApiMember(SphinxDirective):
    """One name with a page of its own (:func:`split_names`): where it lives, then its entry."""

    has_content = False
    required_arguments = 1  # the qualified name, e.g. symrb.scenes.RigidBodyScene

    def run(self) -> list[nodes.Node]:
        return _parse(self, member_lines(self.arguments[0]))


def setup(app: Any) -> dict[str, Any]:  # Sphinx extension entry point
    app.add_directive("symrb-api-index", SymrbApiIndex)
    app.add_directive("symrb-api-module", SymrbApiModule)
    app.add_directive("symrb-api-member", SymrbApiMember)
    return {"version": "0.3", "parallel_read_safe": True, "parallel_write_safe": True}


def main(argv: list[str] | None = None) -> int:
    """``python book/_ext/symrb_api.py [--check]``: write the member pages (``--check``: list
    the pages that are out of date and exit 1 if any)."""
    import sys

    args = sys.argv[1:] if argv is None else argv
    check = "--check" in args
    changed = write_member_pages(Path(__file__).resolve().parents[1], check=check)
    for page in changed:
        print(("out of date: " if check else "wrote or removed: ") + page)
    return 1 if check and changed else 0


if __name__ == "__main__":
    raise SystemExit(main())
