"""Run ``jupyter-book build`` with a log that reads as plain text.

Usage: ``python tools/build_book.py [--jobs N] [jupyter-book build options] book`` (what
``tools/book.sh`` runs). The arguments other than ``--jobs`` go to ``jupyter-book build``
unchanged; this wrapper only

* reads (and so executes) ``N`` pages at a time with Sphinx's parallel build (``--jobs``, default
  ``SYMRB_BOOK_JOBS`` or the number of CPUs this process may use, at most 4). ``jupyter-book build``
  has no such option although the function it calls takes one; ``book/_ext/book_fixes.py``
  declares the Jupyter Book extensions that are silent about it parallel-safe,

* drops the two configuration dumps Sphinx prints at start-up (``myst vX: MdParserConfig(...)``
  and ``myst-nb vX: NbParserConfig(...)``, several hundred characters each), and
* when standard output is not a terminal, or ``NO_COLOR`` is set, switches Sphinx's colours off
  and strips the colour codes jupyter-book adds to its own closing message.

Warnings, errors and tracebacks are printed as before, and the exit status is jupyter-book's.
"""

from __future__ import annotations

import functools
import logging
import os
import re
import sys
from typing import TextIO

# CSI sequences ("ESC [ ... letter"): colours and erase-in-line, the only ones these tools print.
ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")
# Sphinx loggers of the two extensions that dump their configuration at INFO level.
CONFIG_LOGGERS = ("sphinx.myst_parser.sphinx_ext.main", "sphinx.myst_nb.sphinx_ext")
CONFIG_TYPES = {"MdParserConfig", "NbParserConfig"}


class PlainText:
    """A text stream that writes to ``stream`` with ANSI escape sequences removed."""

    def __init__(self, stream: TextIO) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        self._stream.write(ANSI.sub("", text))
        return len(text)

    def __getattr__(self, name: str) -> object:
        return getattr(self._stream, name)


def is_config_dump(record: logging.LogRecord) -> bool:
    """True for the INFO record whose arguments hold a MyST parser configuration object."""
    args = record.args if isinstance(record.args, tuple) else ()
    return record.levelno == logging.INFO and any(
        type(arg).__name__ in CONFIG_TYPES for arg in args
    )


def plain_output() -> bool:
    """Whether to print without colours: ``NO_COLOR`` set, or standard output not a terminal."""
    return bool(os.environ.get("NO_COLOR")) or not sys.stdout.isatty()


def default_jobs() -> int:
    """``SYMRB_BOOK_JOBS`` if set, else the CPUs this process may run on, at most 4."""
    env = os.environ.get("SYMRB_BOOK_JOBS", "").strip()
    if env:
        return parse_jobs(env)
    return max(1, min(4, len(os.sched_getaffinity(0))))


def parse_jobs(text: str) -> int:
    """The number of parallel Sphinx processes in ``text``: a positive integer."""
    if not text.isdigit() or int(text) < 1:
        raise SystemExit(f"build_book.py: --jobs must be a positive integer, got {text!r}")
    return int(text)


def split_jobs(argv: list[str]) -> tuple[int, list[str]]:
    """``(jobs, rest)``: ``--jobs N`` / ``--jobs=N`` taken out of ``argv``."""
    jobs, rest, i = default_jobs(), [], 0
    while i < len(argv):
        arg = argv[i]
        if arg == "--jobs":
            if i + 1 >= len(argv):
                raise SystemExit("build_book.py: --jobs needs a value")
            jobs, i = parse_jobs(argv[i + 1]), i + 2
            continue
        if arg.startswith("--jobs="):
            jobs = parse_jobs(arg.partition("=")[2])
        else:
            rest.append(arg)
        i += 1
    return jobs, rest


def main(argv: list[str]) -> int:
    import jupyter_book.sphinx as jb_sphinx
    from jupyter_book.cli.main import main as jupyter_book
    from sphinx.util import console

    jobs, argv = split_jobs(argv)
    # the CLI imports build_sphinx when it runs and never passes ``jobs``: hand it the number
    jb_sphinx.build_sphinx = functools.partial(jb_sphinx.build_sphinx, jobs=jobs)

    for name in CONFIG_LOGGERS:
        logging.getLogger(name).addFilter(lambda record: not is_config_dump(record))
    if plain_output():
        console.nocolor()
        sys.stdout = PlainText(sys.stdout)  # type: ignore[assignment]
        sys.stderr = PlainText(sys.stderr)  # type: ignore[assignment]
    try:
        jupyter_book.main(["build", *argv], prog_name="jupyter-book", standalone_mode=True)
    except SystemExit as exc:  # click ends every run with SystemExit
        if isinstance(exc.code, str):
            print(exc.code, file=sys.stderr)
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
