"""Open every page of the built book in headless Chromium and check what a reader would see.

Each HTML page of the built book (served from 127.0.0.1 by a local HTTP server) is opened once,
in a window of 1280 x 800 px, then looked at again with the window narrowed to 400 px (a phone).
On every page:

* no request leaves 127.0.0.1 (requests elsewhere are recorded and aborted), and no local
  resource answers with an HTTP error; no uncaught JavaScript error;
* every ``<img>`` has loaded (``naturalWidth > 0``) and has a meaningful ``alt`` text (not empty,
  not a file name such as the hashed ``_images/3f2a...png`` that MyST-NB writes by default, at
  least two words; Sphinx's expand/collapse icons on the module index are controls, not
  pictures, and are left out);
* on pages that load MathJax (Sphinx adds it only to pages with math), typesetting finishes, at
  least one ``mjx-container`` exists, no formula is a MathJax error, and no raw TeX is left in
  the visible text;
* the visible text (code, signatures and typeset math left out) holds no literal HTML tag
  (``<br>``), no Markdown syntax (``**``, ``__``, ``*emphasis*``, backticks, backslash escapes)
  and no Markdown table that failed to render (lines of ``| a | b |`` or ``|---|``), and no
  rendered table has a row of raw pipes or a separator row shown as data;
* no code or output line runs past the column edge;
* evidence tables (a table with a ``residual`` column) hold no ASCII pseudo-TeX outside their
  typeset math (``p_{k+1}``, ``Q^T``, ``d^2H/dy dx``: the patterns of
  ``tests/test_registry.py``);
* the page is at most 10 screens long: ``document.documentElement.scrollHeight / 800 <= 10`` at
  1280 px (but ``genindex-all.html``, Sphinx's whole index on one page beside the index split
  by letter);
* at 1280 px and at 400 px: the page does not scroll sideways; no table, display equation
  (``mjx-container[display]``), figure or image is wider than the content column (the
  ``article``), nor wider than the box it sits in (a table in a wrapper that scrolls sideways is
  too wide: tables must fit; a code block that scrolls in its own box is fine); no text is cut
  off by a box that hides its overflow, and no text lies outside the window.

The errata page must have a summary table listing every erratum, each linking to the erratum's
own page (``errata/d07.html``: its heading is "Erratum D7", with an evidence table); the
errata are the claims whose outcome in
``verify.json`` beside the built book (else the outcome recorded in the registry) is *holds after
correction* or *fails*.  On the claims page and on the landing page (the verdict table), every
claim ID in a table links to the label ``claim-d7`` (``derivations.report.anchor_of``) that the
claim's check places on its page, and that page has an element with that ID.

Playwright drives the system Chromium at ``/usr/bin/chromium`` (``playwright install`` is never
used). Without a built book or without Chromium the test is skipped, except in CI (``CI=true``),
where it fails.  Set ``SYMRB_SCREENSHOT_DIR`` to save a full-page screenshot of every page at
both widths (none is taken otherwise), and ``SYMRB_BOOK_HTML`` to check a book built elsewhere
(default ``book/_build/html``).
"""

from __future__ import annotations

import functools
import http.server
import json
import os
import re
import threading
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any
from urllib.parse import urljoin, urlsplit

import pytest

pytestmark = pytest.mark.browser

ROOT = Path(__file__).resolve().parents[1]
HTML = Path(os.environ.get("SYMRB_BOOK_HTML", ROOT / "book" / "_build" / "html")).resolve()
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
ERRATA_OUTCOMES = ("holds after correction", "fails")
# Every page is looked at in windows of these widths (px): a desktop, then a phone.
WIDTHS = (1280, 400)
# A screen is 800 px high (at 1280 px wide); no page is longer than MAX_SCREENS of them, but
# Sphinx's whole index on one page (the index is also split into a short page per letter).
SCREEN = 800
MAX_SCREENS = 10
LONG_PAGES = {"genindex-all.html"}
# Pages whose tables list claims by ID, each linking to the claim's check.
CLAIM_TABLE_PAGES = ("claims.html", "intro.html")
CLAIM_ID = re.compile(r"[DSM]\d+")

# TeX that MathJax would have replaced; seen in visible text, it means math did not render.
RAW_TEX = re.compile(
    r"\\\(|\\\)|\\\[|\\\]|\$\$|\\begin\{|\$[^$\n]*[\\^_{}][^$\n]*\$"
    r"|\\(?:frac|partial|left|right|mathrm|mathfrak|operatorname|langle|rangle|lVert|rVert|sum)\b"
)
# Literal HTML tags in visible text: the tag was escaped instead of rendered.
HTML_TAG = re.compile(
    r"</?(?:br|p|div|span|b|i|em|strong|code|sub|sup|a|img|table|thead|tbody|tr|td|th|ul|ol|li"
    r"|hr|pre|details|summary|h[1-6])"
    r"(?:\s+[a-z_:][-\w:.]*(?:\s*=\s*(?:\"[^\"]*\"|'[^']*'|[^\s\"'=<>`]+))?)*\s*/?>",
    re.IGNORECASE,
)
# Markdown syntax left in visible text.
MARKDOWN = {
    # (an API page lists a var-keyword parameter as "**options (Any) - ...", which is no markup)
    "bold or emphasis markers **": re.compile(r"\*\*(?!\w+ \()"),
    "bold or emphasis markers __": re.compile(r"(?<![A-Za-z0-9])__|__(?![A-Za-z0-9])"),
    "emphasis markers *...*": re.compile(
        r"(?<![\w*\\])\*[^\s*][^*\n]{0,80}?(?<![\s\\])\*(?![\w*])"
    ),
    "backticks": re.compile(r"`"),
    "backslash escapes": re.compile(r"\\[*_|`<>\[\]#]"),
}
# A Markdown table that was not rendered: a line of cells, or a separator line.
TABLE_LINE = re.compile(r"\|\s*:?-{3,}:?\s*\||^\s*\|(?:[^|\n]*\|){2,}\s*$", re.MULTILINE)
# Jupyter Book writes index.html as a one-line redirect to the root page.
REDIRECT = re.compile(r'<meta http-equiv="Refresh" content="0; url=([^"]+)"', re.IGNORECASE)
FILE_NAME = re.compile(r"\.(?:png|jpe?g|svg|gif|webp|pdf)$|[0-9a-f]{16,}|/", re.IGNORECASE)

# What a reader sees as text: the page without code, signatures, typeset math and scripts.
VISIBLE_TEXT_JS = """() => {
    const body = document.body.cloneNode(true);
    body.querySelectorAll(
        'pre, code, kbd, samp, script, style, noscript, template, textarea, mjx-container, '
        + '.highlight, .MathJax_Preview, dt.sig, .sig, .headerlink'
    ).forEach(e => e.remove());
    return body.textContent;
}"""

# The rendered tables: for each, its rows (header rows marked), each cell's text (math, code and
# the column labels of stacked tables left out) and the target of its first link.
TABLES_JS = """() => Array.from(document.querySelectorAll('article table')).map(t => {
    const text = cell => {
        const c = cell.cloneNode(true);
        c.querySelectorAll('mjx-container, code, pre, .symrb-cell-label').forEach(e => e.remove());
        return c.textContent.replace(/\\s+/g, ' ').trim();
    };
    return Array.from(t.querySelectorAll('tr')).filter(tr => tr.closest('table') === t).map(tr => ({
        head: !!tr.closest('thead') || Array.from(tr.children).every(c => c.tagName === 'TH'),
        cells: Array.from(tr.children).map(c => {
            const a = c.querySelector('a[href]');
            return {text: text(c), href: a ? a.getAttribute('href') : null};
        }),
    }));
})"""

# What the other tests need to know of a page: its title, how many tables it has, and the IDs
# of the elements links can point to.
FACTS_JS = """() => ({
    h1: (document.querySelector('article h1') || {textContent: ''}).textContent
        .replace(/\\s+/g, ' ').trim(),
    table_count: document.querySelectorAll('article table').length,
    ids: Array.from(document.querySelectorAll('article [id]')).map(e => e.id),
})"""

# Images: where from, alt text, loaded pixels.
# Code and output blocks whose lines run past the column edge (the reader sees them cut off, or
# has to scroll each block sideways): the block's content is wider than the block.
CUT_LINES_JS = """() => Array.from(document.querySelectorAll('article div.highlight pre, article .cell_output pre'))
    .filter(p => p.scrollWidth > p.clientWidth + 1)
    .map(p => {
        const line = p.textContent.split('\\n').reduce((a, b) => (b.length > a.length ? b : a), '');
        return `${p.scrollWidth} px in ${p.clientWidth} px: "${line.trim().slice(0, 60)}"`;
    })"""

IMAGES_JS = """() => Array.from(document.images).map(i => ({
    src: i.getAttribute('src') || '', alt: i.getAttribute('alt'), width: i.naturalWidth,
    control: i.classList.contains('toggler')
}))"""

# What a reader at this window width cannot see: text that lies outside the window, or outside
# an ancestor box that hides its overflow (so no scrolling reveals it); tables, display
# equations, figures and images wider than the content column (the article without its padding)
# or than the box they sit in (so they are cut, or scroll sideways); how far the page itself
# scrolls sideways, and how long it is.
LAYOUT_JS = """() => {
    const W = document.documentElement.clientWidth;
    // the content column (the search page has no article: its main part)
    const article = document.querySelector('article') || document.querySelector('main')
        || document.body;
    const clipped = [], outside = [], wide = [], scrolled = [];
    const describe = (el, text) =>
        `${el.tagName.toLowerCase()}${el.className ? '.' + String(el.className).split(' ')[0] : ''}`
        + `: "${text.trim().slice(0, 60)}"`;
    const hiders = new Map();  // element -> [its nearest ancestor that does not show overflow, style]
    const hider = start => {
        if (!hiders.has(start)) {
            let found = [null, null];
            for (let a = start; a && a !== document.documentElement; a = a.parentElement) {
                const s = getComputedStyle(a);
                if (s.overflowX !== 'visible' || s.overflowY !== 'visible') { found = [a, s]; break; }
            }
            hiders.set(start, found);
        }
        return hiders.get(start);
    };
    const units = [];
    const walker = document.createTreeWalker(article, NodeFilter.SHOW_TEXT);
    for (let n = walker.nextNode(); n; n = walker.nextNode()) {
        if (!n.textContent.trim() || n.parentElement.closest('mjx-container, script, style')) continue;
        const r = document.createRange();
        r.selectNodeContents(n);
        const el = n.parentElement;
        units.push([el, el, n.textContent, Array.from(r.getClientRects())]);
    }
    const tex = m => {  // the TeX of a typeset formula, to say which one is cut off
        const item = window.MathJax && MathJax.startup && MathJax.startup.document
            ? Array.from(MathJax.startup.document.math).find(i => i.typesetRoot === m) : null;
        return item ? '$' + item.math + '$' : 'a formula';
    };
    article.querySelectorAll('mjx-container').forEach(m => units.push(
        [m, m.parentElement, tex(m), [m.getBoundingClientRect()]]));
    for (const [el, from, text, rects] of units) {
        const s = getComputedStyle(el);
        if (s.visibility === 'hidden' || s.display === 'none') continue;
        for (const rect of rects) {
            if (rect.width === 0 || rect.height === 0) continue;
            const [box, bs] = hider(from);
            if (box) {
                const b = box.getBoundingClientRect();
                const scrolls = /auto|scroll/.test(bs.overflowX);
                const cutX = rect.left < b.left - 1 || rect.right > b.right + 1;
                const cutY = rect.top < b.top - 1 || rect.bottom > b.bottom + 1;
                if ((cutX && !scrolls) || (cutY && !/auto|scroll/.test(bs.overflowY))) {
                    clipped.push(describe(el, text));
                    break;
                }
                if (scrolls && (b.left < -1 || b.right > W + 1)) {
                    outside.push(describe(el, text));
                    break;
                }
                if (scrolls) continue;
            }
            if (rect.left < -1 || rect.right > W + 1) {
                outside.push(describe(el, text));
                break;
            }
        }
    }
    // the content column: the article's box without its padding
    const a = article.getBoundingClientRect(), as = getComputedStyle(article);
    const left = a.left + parseFloat(as.paddingLeft), right = a.right - parseFloat(as.paddingRight);
    const kinds = [
        ['table', t => { const c = t.querySelector('th, td'); return c ? c.textContent : ''; }],
        ['mjx-container[display]', tex],
        ['figure', f => { const c = f.querySelector('figcaption, img'); return c ? (c.alt || c.textContent) : ''; }],
        ['img', i => i.alt || i.getAttribute('src') || ''],
    ];
    for (const [selector, name] of kinds) {
        article.querySelectorAll(selector).forEach(el => {
            if (el.classList.contains('symrb-math-scroll')) {  // too long even at 60 %: own box
                const r = el.getBoundingClientRect();
                if (r.left >= left - 1 && r.right <= right + 1) {
                    scrolled.push(`"${String(name(el)).trim().slice(0, 50)}": `
                        + `${el.scrollWidth} px in its ${el.clientWidth} px box`);
                    return;
                }
            }
            const rects = [el.getBoundingClientRect()];
            const inner = el.querySelector(':scope > mjx-math');  // a formula wider than its line
            if (inner) rects.push(inner.getBoundingClientRect());
            if (rects[0].width === 0 || rects[0].height === 0) return;  // not shown
            const l = Math.min(...rects.map(r => r.left)), r = Math.max(...rects.map(r => r.right));
            const holder = el.parentElement;
            const holderWidth = holder ? holder.clientWidth : Infinity;
            const width = Math.max(r - l, el.scrollWidth);
            if (l < left - 1 || r > right + 1 || el.scrollWidth > el.clientWidth + 1
                    || (selector === 'table' && width > holderWidth + 1)) {
                wide.push(`${selector.replace(/\\[.*/, '')} "${String(name(el)).trim().slice(0, 50)}": `
                    + `${Math.round(width)} px in a ${Math.round(right - left)} px column`
                    + (selector === 'table' ? ` (its box ${holderWidth} px)` : ''));
            }
        });
    }
    article.querySelectorAll('mjx-container.symrb-math-scroll:not([display])').forEach(el =>
        scrolled.push(`"${tex(el).trim().slice(0, 50)}": ${el.scrollWidth} px in its `
            + `${el.clientWidth} px box (inline)`));
    return {
        window: W,
        page: document.documentElement.scrollWidth,
        height: document.documentElement.scrollHeight,
        clipped: clipped.slice(0, 10),
        outside: outside.slice(0, 10),
        wide: wide,
        scrolled: scrolled,
    };
}"""


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


def _errata_ids() -> list[str]:
    """The errata of the built book: from the ``verify.json`` the build read, else the registry."""
    results = HTML.parent / "verify.json"
    if results.is_file():
        claims = json.loads(results.read_text())["claims"]
        return [r["id"] for r in claims if r["outcome"] in ERRATA_OUTCOMES]
    from derivations.registry import all_claims

    return [c.id for c in all_claims() if c.expected in ERRATA_OUTCOMES]


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, format: str, *args: Any) -> None:
        pass


@pytest.fixture(scope="module")
def server() -> Iterator[str]:
    if not PAGES:
        _skip_or_fail(f"the book is not built ({HTML} has no index.html): run bash tools/book.sh")
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


# The book's script that fits display equations to the column (book/_static/symrb-math-fit.js)
# marks <html data-symrb-math-fit="W"> when it is done for window width W.
MATH_FIT_DONE = """() => !document.querySelector('script[src*="symrb-math-fit"]')
    || document.documentElement.dataset.symrbMathFit === String(window.innerWidth)"""


def _wait_for_math_fit(tab: Any) -> None:
    tab.wait_for_function(MATH_FIT_DONE, timeout=30_000)


def _open(browser: Any, server: str, page: str, width: int = 1280) -> tuple[Any, Any, dict]:
    """Open ``page`` in a new context of the given window width, wait until its images and math
    are done, and return ``(context, tab, record)`` with the requests and errors seen."""
    record: dict[str, list[str]] = {"requests": [], "outside": [], "http": [], "js": []}
    context = browser.new_context(
        viewport={"width": width, "height": SCREEN}, service_workers="block"
    )

    def route(r: Any) -> None:
        url = r.request.url
        record["requests"].append(url)
        parts = urlsplit(url)
        if parts.scheme in {"data", "blob", "about"} or parts.hostname in LOCAL_HOSTS:
            r.continue_()
        else:
            record["outside"].append(url)
            r.abort()

    context.route("**/*", route)
    tab = context.new_page()
    tab.on("pageerror", lambda exc: record["js"].append(str(exc)))
    tab.on(
        "response",
        lambda resp: (
            record["http"].append(f"{resp.status} {resp.url}") if resp.status >= 400 else None
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
        has_mathjax = tab.evaluate(
            "() => Array.from(document.scripts).some(s => /mathjax/i.test(s.src))"
        )
        if has_mathjax:
            tab.wait_for_function(
                "() => window.MathJax && MathJax.startup && MathJax.startup.promise", timeout=60_000
            )
            tab.evaluate("() => MathJax.startup.promise")
        _wait_for_math_fit(tab)
    except BaseException:
        context.close()
        raise
    record["mathjax"] = [str(has_mathjax)] if has_mathjax else []
    return context, tab, record


def _text_defects(visible: str) -> list[str]:
    """Leftover TeX, HTML tags, Markdown syntax and unrendered tables in the visible text."""
    found = []
    for name, pattern in [("raw TeX", RAW_TEX), ("literal HTML tags", HTML_TAG)]:
        hits = sorted({m.group(0) for m in pattern.finditer(visible)})
        if hits:
            found.append(f"{name}: {hits[:8]}")
    for name, pattern in MARKDOWN.items():
        hits = sorted({_context(visible, m) for m in pattern.finditer(visible)})
        if hits:
            found.append(f"Markdown {name}: {hits[:5]}")
    rows = sorted({m.group(0).strip()[:80] for m in TABLE_LINE.finditer(visible)})
    if rows:
        found.append(f"Markdown table shown as text: {rows[:5]}")
    return found


def _context(text: str, m: re.Match[str], width: int = 30) -> str:
    return " ".join(text[max(0, m.start() - width) : m.end() + width].split())


def _table_defects(rows: list[list[str]]) -> list[str]:
    """Rendered table rows made of raw pipes, or a Markdown separator row shown as data."""
    bad = []
    for cells in rows:
        joined = " ‖ ".join(cells)
        pipes = [c for c in cells if re.search(r"(^|\s)\|(\s|$)", c)]
        separator = cells and all(re.fullmatch(r"[|:\- ]*-{3,}[|:\- ]*", c) for c in cells if c)
        if pipes or (separator and any(cells)):
            bad.append(joined[:120])
    return bad


def _image_defects(images: list[dict]) -> list[str]:
    bad = []
    for img in images:
        alt = (img["alt"] or "").strip()
        name = img["src"].rsplit("/", 1)[-1]
        if not img["width"]:
            bad.append(f"{name}: no pixels loaded (naturalWidth 0)")
        if img["control"]:
            continue  # Sphinx's expand/collapse icon on the module index, not a picture
        if not alt:
            bad.append(f"{name}: no alt text")
        elif FILE_NAME.search(alt) or len(alt.split()) < 2:
            bad.append(f"{name}: alt text is not a description: {alt[:60]!r}")
    return bad


def _body_rows(tables: list[list[dict]]) -> Iterator[list[dict]]:
    """The cells of every row that is not a header row, of every table."""
    for table in tables:
        for row in table:
            if not row["head"]:
                yield row["cells"]


def _evidence_defects(tables: list[list[dict]]) -> list[str]:
    """ASCII pseudo-TeX (``p_{k+1}``, ``Q^T``) outside typeset math in the cells of the evidence
    tables: the tables with a column whose header starts with "residual"."""
    from test_registry import _pseudo_tex

    found = []
    for table in tables:
        heads = [c["text"].lower() for row in table if row["head"] for c in row["cells"]]
        if not any(h.startswith("residual") for h in heads):
            continue
        for row in table:
            if not row["head"]:
                found += [f"{hit!r} in {c['text'][:60]!r}" for c in row["cells"]
                          for hit in _pseudo_tex(c["text"])]  # fmt: skip
    return found


def _page_problems(seen: dict[str, Any]) -> list[str]:
    """What :func:`test_page` reports of the findings of :func:`_look`."""
    record = seen["record"]
    problems = []
    if not record["requests"]:
        problems.append("no request recorded")
    if record["outside"]:
        problems.append(f"requests left 127.0.0.1: {record['outside']}")
    if record["http"]:
        problems.append(f"HTTP errors: {record['http']}")
    if record["js"]:
        problems.append(f"JavaScript errors: {record['js']}")
    if record["mathjax"] and seen["mjx_count"] == 0:
        problems.append("MathJax is loaded but typeset nothing")
    if seen["math_errors"]:
        problems.append(f"MathJax could not typeset: {seen['math_errors'][:5]}")
    problems += [f"image {d}" for d in _image_defects(seen["images"])]
    problems += _text_defects(seen["visible"])
    rows = [[c["text"] for c in row["cells"]] for table in seen["tables"] for row in table]
    problems += [f"table row of raw pipes: {r}" for r in _table_defects(rows)]
    problems += [f"code or output line cut at the column edge: {c}" for c in seen["cut"][:5]]
    ascii_math = _evidence_defects(seen["tables"])
    if ascii_math:
        problems.append(f"ASCII math in evidence tables ({len(ascii_math)}): {ascii_math[:5]}")
    return problems


def _layout_problems(layout: dict[str, Any]) -> list[str]:
    """What a reader cannot see whole, from the findings of :data:`LAYOUT_JS`.  A display
    equation too long for the column at 60 % of its size scrolls in its own box; that is allowed
    on a phone, never at desktop width (:data:`WIDTHS`\\[0]), where it must fit."""
    problems = []
    if layout["window"] >= WIDTHS[0] - 20:  # the window's width less the scroll bar
        problems += [f"equation scrolls in its box: {e}" for e in layout.get("scrolled", [])]
    if layout["page"] > layout["window"] + 1:
        problems.append(
            f"the page scrolls sideways: {layout['page']} px in a {layout['window']} px window"
        )
    problems += [f"text cut off by its box: {c}" for c in layout["clipped"]]
    problems += [f"text outside the window: {c}" for c in layout["outside"]]
    problems += [f"wider than the column: {w}" for w in layout["wide"]]
    return problems


def _look(browser: Any, server: str, page: str) -> dict[str, Any]:
    """Open ``page`` at the first of :data:`WIDTHS`, read what the tests ask of it, then narrow
    the same tab to each other width and measure the layout again (screenshots only when
    ``SYMRB_SCREENSHOT_DIR`` is set).  Returns the findings, not the page."""
    context, tab, record = _open(browser, server, page, width=WIDTHS[0])
    try:
        seen = {
            "record": record,
            "images": tab.evaluate(IMAGES_JS),
            "visible": tab.evaluate(VISIBLE_TEXT_JS),
            "tables": tab.evaluate(TABLES_JS),
            "cut": tab.evaluate(CUT_LINES_JS),
            "mjx_count": tab.locator("mjx-container").count(),
            "math_errors": tab.evaluate(
                "() => Array.from(document.querySelectorAll('mjx-merror'))"
                ".map(e => e.getAttribute('data-mjx-error') || e.textContent)"
            ),
            **tab.evaluate(FACTS_JS),
        }
        shots = os.environ.get("SYMRB_SCREENSHOT_DIR")
        layouts = {}
        for width in WIDTHS:
            if width != WIDTHS[0]:
                tab.set_viewport_size({"width": width, "height": SCREEN})
                _wait_for_math_fit(tab)
            layouts[width] = tab.evaluate(LAYOUT_JS)
            if shots:
                name = page.replace("/", "__").removesuffix(".html") + f"_{width}px.png"
                (Path(shots) / name).parent.mkdir(parents=True, exist_ok=True)
                tab.screenshot(path=str(Path(shots) / name), full_page=True)
    finally:
        context.close()
    seen["problems"] = _page_problems(seen)
    del seen["visible"]  # the largest finding, needed only for the problems
    seen["height"] = layouts[WIDTHS[0]]["height"]
    seen["layout"] = {width: _layout_problems(layout) for width, layout in layouts.items()}
    return seen


@pytest.fixture(scope="module")
def look(server: str, browser: Any) -> Callable[[str], dict[str, Any]]:
    """``look(page)``: the findings of :func:`_look`, each page opened once for all the tests."""
    seen: dict[str, dict[str, Any] | Exception] = {}

    def get(page: str) -> dict[str, Any]:
        if page not in seen:
            try:
                seen[page] = _look(browser, server, page)
            except Exception as exc:  # a page that did not open is not opened again
                seen[page] = exc
        found = seen[page]
        if isinstance(found, Exception):
            raise found
        return found

    return get


@pytest.mark.parametrize(
    ("text", "defect"),
    [
        ("checks<br>of the printed form", "literal HTML tags"),
        ('see <span class="x">here</span>', "literal HTML tags"),
        ("evidence marked *printed* fails", "emphasis markers"),
        ("a **bold** claim", "**"),
        ("the `symrb` package", "backticks"),
        (r"u\*\_k and \|M\|", "backslash escapes"),
        ("| claim | outcome |\n|---|---|\n| S1 | holds |", "Markdown table"),
        (r"the pairing \langle p, x \rangle", "raw TeX"),
        ("$\\|M\\|_{op} < 2$ was not typeset", "raw TeX"),
    ],
)
def test_text_checks_see_what_issue_8_found(text: str, defect: str) -> None:
    found = _text_defects(f"Some prose. {text} More prose.")
    assert any(defect in f for f in found), found


def test_text_checks_pass_plain_prose() -> None:
    prose = (
        "The pairing <p, f> and u*_k, H*_xx in ASCII; |x|^2 and ||M||_op < 2; a * b; "
        "the map x |-> y; costs 2.1e+00 > 1e-12, as expected."
    )
    assert _text_defects(prose) == []


def test_table_checks_see_a_row_of_raw_pipes() -> None:
    assert _table_defects([["| a | b |", ""], ["1", "2"]])
    assert _table_defects([["---", ":---:"]])
    assert not _table_defects([["D1", "|x| + |y| <= 1"], ["S9", "holds"]])


def test_image_checks_see_hashed_names_and_missing_pixels() -> None:
    hashed = "../_images/" + "0123456789abcdef" * 4 + ".png"
    images = [
        {"src": hashed, "alt": hashed, "width": 640, "control": False},
        {"src": "a.png", "alt": "", "width": 640, "control": False},
        {"src": "b.png", "alt": "Bar chart of seconds per claim", "width": 0, "control": False},
        {"src": "c.png", "alt": "Bar chart of seconds per claim", "width": 640, "control": False},
    ]
    found = _image_defects(images)
    assert len(found) == 3 and not any(f.startswith("c.png") for f in found), found


def test_evidence_check_sees_ascii_math_only_in_evidence_tables() -> None:
    def table(head: list[str], *rows: list[str]) -> list[dict]:
        cells = [[{"text": t, "href": None} for t in r] for r in (head, *rows)]
        return [{"head": k == 0, "cells": c} for k, c in enumerate(cells)]

    head = ["check", "what is checked", "residual vs tolerance", "result"]
    found = _evidence_defects(
        [table(head, ["claim, float64", "p_{k+1} against Q^T P", "1e-16 ≤ 1e-12", "passes"])]
    )
    assert len(found) == 2, found
    assert not _evidence_defects(
        [
            table(head, ["claim, float64", "the costate against SymPy", "0 (exact)", "passes"]),
            table(["key", "meaning"], ["p_{k+1}", "not an evidence table"]),
        ]
    )


# A page with one of each thing the layout check must see, and things it must pass: a table in
# a wrapper that scrolls, a formula and a picture wider than the column, text cut off by a box
# that hides its overflow; a code block that scrolls in its own box, a table that fits.
LAYOUT_SAMPLE = """<html><body style="margin: 0"><article style="padding: 0 10px">
<div style="overflow-x: auto"><table><tr><td>wide table</td><td><div style="width: 600px">.</div>
</td></tr></table></div>
<mjx-container display="true" style="display: block"><mjx-math
  style="display: inline-block; width: 700px">x</mjx-math></mjx-container>
<img alt="wide picture" width="700" height="10"
  src="data:image/gif;base64,R0lGODlhAQABAIAAAAAAAP///yH5BAEAAAAALAAAAAABAAEAAAIBRAA7">
<div style="overflow: hidden; width: 100px; white-space: nowrap">cut words run on and on and on</div>
<pre style="overflow: auto">fine code that is much longer than the column of a phone, and scrolls</pre>
<table><tr><td>fine table</td></tr></table>
<mjx-container display="true" class="symrb-math-scroll" style="display: block; overflow-x: auto">
  <mjx-math style="display: inline-block; width: 1700px">y</mjx-math></mjx-container>
</article></body></html>"""


def _sample_layout(browser: Any, width: int) -> list[str]:
    """The layout problems of :data:`LAYOUT_SAMPLE` in a window ``width`` px wide."""
    context = browser.new_context(viewport={"width": width, "height": SCREEN})
    try:
        tab = context.new_page()
        tab.set_content(LAYOUT_SAMPLE)
        return _layout_problems(tab.evaluate(LAYOUT_JS))
    finally:
        context.close()


def test_layout_check_sees_what_does_not_fit(browser: Any) -> None:
    found = "\n".join(_sample_layout(browser, 400))
    for seen in ('table "wide table"', 'mjx-container "a formula"', 'img "wide picture"',
                 "cut off by its box: div", "scrolls sideways"):  # fmt: skip
        assert seen in found, found
    assert "fine" not in found, found
    # the long equation that scrolls in its own box (symrb-math-fit.js) passes on a phone only
    assert "scrolls in its box" not in found, found
    wide = _sample_layout(browser, WIDTHS[0])
    assert any("equation scrolls in its box" in w for w in wide), wide


def test_book_has_pages() -> None:
    if not PAGES:
        _skip_or_fail("the book is not built: run bash tools/book.sh")
    for page in (
        "index.html",
        "intro.html",
        "conventions.html",
        "claims.html",
        "errata.html",
        "getting_started.html",
        "scene_reference.html",
        "api/index.html",
        "api/engine.html",
        "api/scenes.html",
    ):
        assert page in PAGES, f"{page} is missing from the built book"


@pytest.mark.parametrize("page", PAGES or ["(book not built)"])
def test_page(page: str, look: Callable[[str], dict[str, Any]]) -> None:
    problems = look(page)["problems"]
    assert not problems, f"{page}:\n  " + "\n  ".join(problems)


@pytest.mark.parametrize("page", [p for p in PAGES if p not in LONG_PAGES] or ["(not built)"])
def test_page_height(page: str, look: Callable[[str], dict[str, Any]]) -> None:
    height = look(page)["height"]
    assert height / SCREEN <= MAX_SCREENS, (
        f"{page} is {height / SCREEN:.1f} screens long ({height} px at {WIDTHS[0]} px wide; "
        f"at most {MAX_SCREENS} screens of {SCREEN} px)"
    )


@pytest.mark.parametrize("width", WIDTHS)
@pytest.mark.parametrize("page", PAGES or ["(book not built)"])
def test_layout(page: str, width: int, look: Callable[[str], dict[str, Any]]) -> None:
    problems = look(page)["layout"][width]
    assert not problems, f"{page} at {width} px:\n  " + "\n  ".join(problems)


def test_errata_page_has_a_summary_and_one_page_per_erratum(
    look: Callable[[str], dict[str, Any]],
) -> None:
    errata = _errata_ids()
    assert errata, "no erratum found in the results: nothing to check"
    summary = look("errata.html")["tables"]
    rows = [next((c for c in cells if c["href"]), None) for cells in _body_rows(summary)]
    listed = [r["text"] if r else "" for r in rows]
    assert listed == errata, f"the summary lists {listed}, the errata are {errata}"
    for r in rows:
        assert r is not None
        page, _, anchor = r["href"].partition("#")
        assert page.startswith("errata/") and anchor, f"{r['text']} links to {r['href']}"
        found = look(page)
        assert found["h1"].startswith(f"Erratum {r['text']}"), f"{page}: heading {found['h1']!r}"
        assert anchor in found["ids"] and found["table_count"], (
            f"{page}: no #{anchor} or no evidence table"
        )


@pytest.mark.parametrize("page", CLAIM_TABLE_PAGES)
def test_claim_ids_link_to_their_checks(page: str, look: Callable[[str], dict[str, Any]]) -> None:
    """Every claim ID in the tables of ``page`` links to the label ``claim-d7`` that the claim's
    check places on its page (``derivations.report.check``), and that page has it."""
    from derivations.registry import all_claims
    from derivations.report import anchor_of

    if page not in PAGES:
        _skip_or_fail(f"{page} is not built")
    ids = {c.id for c in all_claims()}
    cells = [c for cells in _body_rows(look(page)["tables"]) for c in cells if c["text"] in ids]
    assert cells, f"{page}: no claim ID in its tables"
    problems = []
    for cell in cells:
        cid, href = cell["text"], cell["href"]
        url = urlsplit(urljoin(f"http://book/{page}", href or ""))
        target = url.path.lstrip("/")
        if not href:
            problems.append(f"{cid} links nowhere")
        elif url.fragment != anchor_of(cid):
            problems.append(f"{cid} links to {href}, not to its check (#{anchor_of(cid)})")
        elif target not in PAGES or url.fragment not in look(target)["ids"]:
            problems.append(f"{cid} links to {href}: no such element on {target}")
    assert not problems, f"{page}: {len(problems)} of {len(cells)} claim IDs:\n  " + "\n  ".join(
        problems
    )
