"""Work-arounds for the Jupyter Book 1 / Sphinx 7.4 tool chain, one function each.

``dedupe_inline_scripts``: with Sphinx 7.4, an inline script that an extension adds with
``app.add_js_file(None, body=...)`` after the builder is initialised (sphinx-thebe and
sphinx-togglebutton do so) ends up twice in every page, once with filename ``None`` and once with
``''``. For ``const`` declarations (sphinx-thebe's ``THEBE_JS_URL``) the second copy is a JavaScript
error on every page. This drops the second copy of any script with the same source and attributes.
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


def setup(app: Any) -> dict[str, Any]:
    app.connect("html-page-context", dedupe_inline_scripts, priority=900)
    return {"version": "0.1", "parallel_read_safe": True, "parallel_write_safe": True}
