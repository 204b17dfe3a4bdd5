"""The hard-cases page's demonstrations of the scene tool: what ``symrb run`` says about a
mistaken scene file, and the cache: damage one stored number, run again."""

from __future__ import annotations

import contextlib
import io
import tempfile
import warnings
from pathlib import Path
from typing import Any

import numpy as np


def nudge_stored_number(entry: Path, name: str) -> None:
    """Move the first entry of the stored array ``name`` of a cache entry by one unit in the
    last place, writing back an npz that is valid in every other respect."""
    with np.load(entry / "arrays.npz") as z:
        arrays = {k: z[k] for k in z.files}
    a = arrays[name].copy()
    a.flat[0] = np.nextafter(a.flat[0], np.inf)
    arrays[name] = a
    buf = io.BytesIO()
    np.savez(buf, **arrays)  # type: ignore[arg-type]
    (entry / "arrays.npz").write_bytes(buf.getvalue())


def run_noting_warnings(run: Any, *args: Any, **kwargs: Any) -> tuple[Any, list[str]]:
    """``run(*args, **kwargs)`` and the messages of the symrb warnings it gave, each without the
    directory that the cache names first."""
    from symrb.errors import SymrbWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = run(*args, **kwargs)
    return result, [str(w.message).split(": ", 1)[-1] for w in caught
                    if issubclass(w.category, SymrbWarning)]  # fmt: skip


def run_cli(document: str) -> tuple[int, str]:
    """``symrb run`` (in this process, without the cache) on the scene file ``document``: its
    exit status and what it printed to standard error, with the file's temporary directory left
    out."""
    from symrb import scene_cli

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "scene.toml"
        path.write_text(document)
        err = io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            status = scene_cli.main("run", [str(path), "--no-cache"])
    return status, err.getvalue().replace(tmp + "/", "")
