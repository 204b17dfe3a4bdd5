"""The README's "Use the library" example runs and prints what its comments say."""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def _python_blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)


def test_readme_has_a_library_example() -> None:
    text = README.read_text()
    assert "## Use the library" in text
    assert len(_python_blocks()) >= 1


def test_readme_example_runs_and_prints_what_it_says() -> None:
    (block,) = _python_blocks()
    out = io.StringIO()
    namespace: dict[str, object] = {}
    with contextlib.redirect_stdout(out):
        exec(compile(block, str(README), "exec"), namespace)
    printed = out.getvalue().splitlines()
    assert printed[0] == "all 1000 steps taken 10.0"
    # "about 5e-7: second order in h"
    assert 1e-7 < float(printed[1]) < 1e-6
