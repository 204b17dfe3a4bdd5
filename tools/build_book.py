"""Run ``jupyter-book build`` with a log that reads as plain text.

Usage: ``python tools/build_book.py [jupyter-book build options] book`` (what ``tools/book.sh``
runs). The arguments go to ``jupyter-book build`` unchanged; this wrapper only

* drops the two configuration dumps Sphinx prints at start-up (``myst vX: MdParserConfig(...)``
  and ``myst-nb vX: NbParserConfig(...)``, several hundred characters each), and
* when standard output is not a terminal, or ``NO_COLOR`` is set, switches Sphinx's colours off
  and strips the colour codes jupyter-book adds to its own closing message.

Warnings, errors and tracebacks are printed as before, and the exit status is jupyter-book's.
"""

from __future__ import annotations

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


def main(argv: list[str]) -> int:
    from jupyter_book.cli.main import main as jupyter_book
    from sphinx.util import console

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
