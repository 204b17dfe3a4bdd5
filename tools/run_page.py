"""Execute one MyST Markdown book page on its own, the way the book build does.

Usage: ``python tools/run_page.py book/section2/01_maximum_principle.md [more pages]``.
Exits non-zero and prints the failing cell's traceback if any cell raises.  Handy while writing a
page: the full ``jupyter-book build`` executes every page.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import nbformat
from myst_nb.core.read import read_myst_markdown_notebook
from nbclient import NotebookClient
from nbclient.exceptions import CellExecutionError


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
    ok = all([run(Path(p)) for p in sys.argv[1:]])
    sys.exit(0 if ok else 1)
