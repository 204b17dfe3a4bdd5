"""Execute one MyST Markdown book page on its own, the way the book build does.

Usage: ``python tools/run_page.py book/section2/01_maximum_principle.md [more pages]``.
Exits non-zero and prints the failing cell's traceback if any cell raises.  Handy while writing a
page: the full ``jupyter-book build`` executes every page.  As in the book build
(``tools/_common.sh``), the kernels find the book's own code, ``book/lib/symrb_book``, through
``PYTHONPATH``.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import nbformat
from myst_nb.core.read import read_myst_markdown_notebook
from nbclient import NotebookClient
from nbclient.exceptions import CellExecutionError

BOOK_LIB = Path(__file__).resolve().parents[1] / "book" / "lib"


def run(path: Path) -> bool:
    nb = read_myst_markdown_notebook(path.read_text())
    nb = nbformat.from_dict(nb) if not isinstance(nb, nbformat.NotebookNode) else nb
    client = NotebookClient(
        nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(path.parent)}}
    )
    start = time.perf_counter()
    try:
        client.execute()
    except CellExecutionError as exc:
        print(f"FAILED {path} after {time.perf_counter() - start:.1f}s\n{exc}")
        return False
    ncells = sum(1 for c in nb.cells if c.cell_type == "code")
    print(f"ok {path}: {ncells} code cells in {time.perf_counter() - start:.1f}s")
    return True


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    os.environ["PYTHONPATH"] = os.pathsep.join(
        [str(BOOK_LIB), *filter(None, os.environ.get("PYTHONPATH", "").split(os.pathsep))]
    )
    ok = all([run(Path(p)) for p in sys.argv[1:]])
    sys.exit(0 if ok else 1)
