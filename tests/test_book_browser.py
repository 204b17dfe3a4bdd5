"""Open every page of the built book in headless Chromium and check what a reader would see.

For each HTML page of ``book/_build/html`` (served from 127.0.0.1 by a local HTTP server):

* no request leaves 127.0.0.1 (requests elsewhere are recorded and aborted), and no local
  resource answers with an HTTP error;
* every ``<img>`` has loaded (``naturalWidth > 0``);
* on pages that load MathJax (Sphinx adds it only to pages with math), typesetting finishes, at
  least one ``mjx-container`` exists, and no raw TeX delimiter is left in the visible text;
* no uncaught JavaScript error.

Playwright drives the system Chromium at ``/usr/bin/chromium`` (``playwright install`` is never
used). Without a built book or without Chromium the test is skipped, except in CI (``CI=true``),
where it fails.  Set ``SYMRB_SCREENSHOT_DIR`` to save a full-page screenshot of every page.
"""

from __future__ import annotations

import functools
import http.server
import os
import re
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import pytest

pytestmark = pytest.mark.browser

ROOT = Path(__file__).resolve().parents[1]
HTML = ROOT / "book" / "_build" / "html"
CHROMIUM = Path("/usr/bin/chromium")
LAUNCH_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
LOCAL_HOSTS = {"127.0.0.1"}
# TeX delimiters that MathJax would have replaced; seen in visible text, they mean math did not render.
RAW_TEX = re.compile(r"\\\(|\\\)|\\\[|\\\]|\$\$|\\begin\{")
# Jupyter Book writes index.html as a one-line redirect to the root page.
REDIRECT = re.compile(r'<meta http-equiv="Refresh" content="0; url=([^"]+)"', re.IGNORECASE)


def _in_ci() -> bool:
    return os.environ.get("CI", "").strip().lower() in {"1", "true", "yes"}


def _skip_or_fail(reason: str) -> None:
    if _in_ci():
        pytest.fail(f"{reason} (CI=true, so this is a failure, not a skip)")
    pytest.skip(reason)


def _pages() -> list[str]:
    if not (HTML / "index.html").is_file():
        return []
    skip = {"_static", "_sources", "_images", "_sphinx_design_static"}
    return sorted(
        p.relative_to(HTML).as_posix()
        for p in HTML.rglob("*.html")
        if not skip.intersection(p.relative_to(HTML).parts)
    )


PAGES = _pages()


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, format: str, *args: Any) -> None:
        pass


@pytest.fixture(scope="module")
def server() -> Iterator[str]:
    if not PAGES:
        _skip_or_fail(
            f"the book is not built ({HTML.relative_to(ROOT)} has no index.html): run bash tools/book.sh"
        )
    handler = functools.partial(_QuietHandler, directory=str(HTML))
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{httpd.server_address[1]}"
    finally:
        httpd.shutdown()
        httpd.server_close()
        thread.join(timeout=5)


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    if not CHROMIUM.exists():
        _skip_or_fail(f"{CHROMIUM} is missing: apt-get install chromium")
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        _skip_or_fail("playwright is not installed: pip install -e '.[test]'")
    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=str(CHROMIUM), args=LAUNCH_ARGS, headless=True)
        try:
            yield b
        finally:
            b.close()


def test_book_has_pages() -> None:
    if not PAGES:
        _skip_or_fail("the book is not built: run bash tools/book.sh")
    for page in (
        "index.html",
        "intro.html",
        "conventions.html",
        "claims.html",
        "errata.html",
        "api.html",
    ):
        assert page in PAGES, f"{page} is missing from the built book"


@pytest.mark.parametrize("page", PAGES or ["(book not built)"])
def test_page(page: str, server: str, browser: Any, tmp_path: Path) -> None:
    requests: list[str] = []
    outside: list[str] = []
    http_errors: list[str] = []
    js_errors: list[str] = []

    context = browser.new_context(viewport={"width": 1280, "height": 900}, service_workers="block")

    def route(r: Any) -> None:
        url = r.request.url
        requests.append(url)
        parts = urlsplit(url)
        if parts.scheme in {"data", "blob", "about"} or parts.hostname in LOCAL_HOSTS:
            r.continue_()
        else:
            outside.append(url)
            r.abort()

    context.route("**/*", route)
    tab = context.new_page()
    tab.on("pageerror", lambda exc: js_errors.append(str(exc)))
    tab.on(
        "response",
        lambda resp: (
            http_errors.append(f"{resp.status} {resp.url}") if resp.status >= 400 else None
        ),
    )
    try:
        redirect = REDIRECT.search(
            (HTML / page).read_text(encoding="utf-8", errors="replace")[:2000]
        )
        if redirect:  # follow it, and check the page it leads to
            target = redirect.group(1)
            assert (HTML / page).parent.joinpath(target).is_file(), (
                f"{page} redirects to missing {target}"
            )
            with tab.expect_navigation(url=f"**/{target}", wait_until="load", timeout=60_000):
                tab.goto(f"{server}/{page}", wait_until="commit", timeout=60_000)
        else:
            tab.goto(f"{server}/{page}", wait_until="load", timeout=60_000)

        # images: make lazy ones load, then wait until every image has finished (or failed) loading
        tab.evaluate(
            "() => document.querySelectorAll('img').forEach(i => { i.loading = 'eager'; })"
        )
        tab.wait_for_function(
            "() => Array.from(document.images).every(i => i.complete)", timeout=30_000
        )
        broken = tab.evaluate(
            "() => Array.from(document.images).filter(i => !(i.naturalWidth > 0)).map(i => i.src)"
        )

        has_mathjax = tab.evaluate(
            "() => Array.from(document.scripts).some(s => /mathjax/i.test(s.src))"
        )
        mjx_count = 0
        raw_tex: list[str] = []
        if has_mathjax:
            tab.wait_for_function(
                "() => window.MathJax && MathJax.startup && MathJax.startup.promise", timeout=60_000
            )
            tab.evaluate("() => MathJax.startup.promise")
            mjx_count = tab.locator("mjx-container").count()
            visible = tab.evaluate(
                """() => {
                    const body = document.body.cloneNode(true);
                    body.querySelectorAll(
                        'pre, code, script, style, textarea, mjx-container, .highlight, .MathJax_Preview'
                    ).forEach(e => e.remove());
                    return body.textContent;
                }"""
            )
            raw_tex = [m.group(0) for m in RAW_TEX.finditer(visible)]

        shots = os.environ.get("SYMRB_SCREENSHOT_DIR")
        if shots:
            target = Path(shots) / (page.replace("/", "__").removesuffix(".html") + ".png")
            target.parent.mkdir(parents=True, exist_ok=True)
            tab.screenshot(path=str(target), full_page=True)
    finally:
        context.close()

    assert requests, f"{page}: no request recorded"
    assert not outside, f"{page}: requests left 127.0.0.1: {outside}"
    assert not http_errors, f"{page}: HTTP errors: {http_errors}"
    assert not broken, f"{page}: images that did not load: {broken}"
    assert not js_errors, f"{page}: JavaScript errors: {js_errors}"
    if has_mathjax:
        assert mjx_count > 0, f"{page}: MathJax is loaded but typeset nothing"
        assert not raw_tex, f"{page}: raw TeX left in the visible text: {raw_tex[:10]}"
