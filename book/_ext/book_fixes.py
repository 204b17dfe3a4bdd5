"""Work-arounds for the Jupyter Book 1 / Sphinx 7.4 tool chain, one function each.

``dedupe_inline_scripts``: with Sphinx 7.4, an inline script that an extension adds with
``app.add_js_file(None, body=...)`` after the builder is initialised (sphinx-thebe and
sphinx-togglebutton do so) ends up twice in every page, once with filename ``None`` and once with
``''``. For ``const`` declarations (sphinx-thebe's ``THEBE_JS_URL``) the second copy is a JavaScript
error on every page. This drops the second copy of any script with the same source and attributes.

``declare_parallel_safe``: three extensions Jupyter Book loads do not say whether Sphinx may read
or write pages in parallel, so Sphinx warns (an error under ``-W``) and reads serially, executing
one notebook at a time. Each is safe: sphinx-multitoc-numbering renumbers sections in the main
process after the parallel reads are merged, sphinx-jupyterbook-latex acts only for the LaTeX
builder, and sphinx-mathjax-offline only adds a static directory. This declares them so, which
lets ``tools/build_book.py --jobs N`` execute N pages at a time. An extension not named here that
does not declare itself still makes Sphinx warn and read serially.
"""

from __future__ import annotations

from typing import Any


def dedupe_inline_scripts(
    app: Any, pagename: str, templatename: str, context: dict, doctree: Any
) -> None:
    scripts = context.get("script_files")
    if not scripts:
        return
    seen: set[tuple[str, tuple[tuple[str, str], ...]]] = set()
    kept = []
    for js in scripts:
        attrs = getattr(js, "attributes", {}) or {}
        key = (
            getattr(js, "filename", None) or "",
            tuple(sorted((k, str(v)) for k, v in attrs.items())),
        )
        if key in seen:
            continue
        seen.add(key)
        kept.append(js)
    scripts[:] = kept


#: Extensions loaded by Jupyter Book that are safe to run in parallel but do not declare it.
UNDECLARED_PARALLEL_SAFE = (
    "sphinx_multitoc_numbering",
    "sphinx_jupyterbook_latex",
    "sphinx-mathjax-offline",
)


def declare_parallel_safe(app: Any) -> None:
    for name in UNDECLARED_PARALLEL_SAFE:
        ext = app.extensions.get(name)
        if ext is None:
            continue
        for attr in ("parallel_read_safe", "parallel_write_safe"):
            if getattr(ext, attr, None) is None:
                setattr(ext, attr, True)


def setup(app: Any) -> dict[str, Any]:
    app.connect("html-page-context", dedupe_inline_scripts, priority=900)
    app.connect("builder-inited", declare_parallel_safe)
    return {"version": "0.1", "parallel_read_safe": True, "parallel_write_safe": True}
