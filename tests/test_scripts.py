"""The set-up and build plumbing of ``tools/`` and ``.ci/run``, run for real on small inputs.

* ``tools/_common.sh``: which Python the scripts use (the active virtual environment, else a
  ``.venv`` they create once and reuse), the clear exits when Python is missing, too old or cannot
  make a virtual environment, the install stamp, and the work-tree fingerprint CI compares;
* ``tools/jupyter``: notebook kernels started through it do not print the TCP warning;
* ``tools/build_book.py``: the log of a book build has no colour codes and no configuration dumps,
  and a failing cell still fails the build with its traceback;
* the book is built in one place only.

Each shell function runs in a copy of ``tools/`` inside a temporary directory, so no test creates
or touches ``.venv`` of the repository.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TOOLS = ROOT / "tools"
# Variables by which the scripts pass state to the scripts they call; a test starts without them.
SCRIPT_STATE = {"VIRTUAL_ENV", "PYTHON", "SYMRB_PYTHON_READY", "SYMRB_INSTALLED", "SYMRB_T0"}
BASE_PYTHON = Path(sys.base_prefix) / "bin" / "python3"
TCP_WARNING = "Kernel is running over TCP without encryption"


def _env(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in SCRIPT_STATE}
    # a script that went wrong must not install into the interpreter running these tests
    env["PIP_REQUIRE_VIRTUALENV"] = "1"
    env.update(extra)
    return env


def _checkout(tmp_path: Path) -> Path:
    """A directory with the repository's tools/ and pyproject.toml: what _common.sh needs."""
    repo = tmp_path / "repo"
    shutil.copytree(TOOLS, repo / "tools", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy2(ROOT / "pyproject.toml", repo / "pyproject.toml")
    return repo


def _sh(
    repo: Path, script: str, python: Path | str, **env: str
) -> subprocess.CompletedProcess[str]:
    """Run ``script`` in bash after sourcing the copy of tools/_common.sh, with PYTHON=python."""
    return subprocess.run(
        ["bash", "-c", f"set -euo pipefail\nsource tools/_common.sh\n{script}"],
        cwd=repo,
        env=_env(PYTHON=str(python), **env),
        capture_output=True,
        text=True,
        timeout=300,
    )


def _fake_python(path: Path, body: str) -> Path:
    """A stand-in interpreter: a bash script that answers some calls and passes the rest on."""
    path.write_text(f'#!/usr/bin/env bash\n{textwrap.dedent(body)}\nexec {BASE_PYTHON} "$@"\n')
    path.chmod(0o755)
    return path


def _venv_with_fake_pip(where: Path) -> Path:
    """A virtual environment whose ``python -m pip`` only records its arguments in pip.log."""
    subprocess.run([str(BASE_PYTHON), "-m", "venv", "--without-pip", str(where)], check=True)
    site = next(where.glob("lib/python3*/site-packages"))
    (site / "pip").mkdir()
    (site / "pip" / "__init__.py").write_text("")
    (site / "pip" / "__main__.py").write_text(
        "import pathlib, sys\n"
        "with open(pathlib.Path(sys.prefix) / 'pip.log', 'a') as log:\n"
        "    print(' '.join(sys.argv[1:]), file=log)\n"
    )
    return where / "bin" / "python"


def _pip_calls(venv: Path) -> list[str]:
    log = venv / "pip.log"
    return log.read_text().splitlines() if log.exists() else []


needs_base_venv = pytest.mark.skipif(
    subprocess.run([str(BASE_PYTHON), "-c", "import ensurepip, venv"]).returncode != 0,
    reason=f"{BASE_PYTHON} cannot create virtual environments (no ensurepip)",
)


def test_active_virtual_environment_is_used(tmp_path: Path) -> None:
    repo = _checkout(tmp_path)
    python = _venv_with_fake_pip(tmp_path / "theirs")
    proc = _sh(repo, 'use_python; echo "PYTHON=$PYTHON"; command -v python', python)
    assert proc.returncode == 0, proc.stderr
    assert f"using the active virtual environment {tmp_path / 'theirs'}" in proc.stdout
    assert f"PYTHON={python}" in proc.stdout
    # tools found on PATH come from that environment first
    assert proc.stdout.strip().splitlines()[-1] == str(python)
    assert not (repo / ".venv").exists()


@needs_base_venv
def test_dot_venv_is_created_once_then_reused(tmp_path: Path) -> None:
    repo = _checkout(tmp_path)
    script = 'use_python; echo "PYTHON=$PYTHON"; "$PYTHON" -c "import sys; print(sys.prefix)"'
    first = _sh(repo, script, BASE_PYTHON)
    assert first.returncode == 0, first.stderr
    assert f"creating .venv with {BASE_PYTHON} -m venv" in first.stdout
    assert f"PYTHON={repo / '.venv' / 'bin' / 'python'}" in first.stdout
    assert first.stdout.strip().splitlines()[-1] == str(repo / ".venv")
    marker = repo / ".venv" / "kept"
    marker.write_text("")
    second = _sh(repo, script, BASE_PYTHON)
    assert second.returncode == 0, second.stderr
    assert "no virtual environment active: using .venv" in second.stdout
    assert "creating" not in second.stdout
    assert marker.exists(), ".venv was made again instead of reused"


def test_stamp_skips_install_until_pyproject_changes(tmp_path: Path) -> None:
    repo = _checkout(tmp_path)
    venv = repo / ".venv"
    _venv_with_fake_pip(venv)
    install = "use_python; install_symrb {}"
    # the base interpreter refuses pip: only the fake pip of .venv may be called
    base = _fake_python(tmp_path / "python3", '[ "$1 $2" != "-m pip" ] || exit 99')

    for extra, runs_pip in [("book", True), ("book", False), ("test", True), ("book", False)]:
        before = len(_pip_calls(venv))
        proc = _sh(repo, install.format(extra), base)
        assert proc.returncode == 0, proc.stderr
        assert "using .venv" in proc.stdout
        assert (len(_pip_calls(venv)) > before) == runs_pip, (extra, proc.stdout)
    assert _pip_calls(venv) == [
        "install -qq --disable-pip-version-check -e .[book]",
        "install -qq --disable-pip-version-check -e .[test]",
    ]
    assert "already installed in .venv" in proc.stdout

    pyproject = repo / "pyproject.toml"
    pyproject.write_text(pyproject.read_text() + "\n# a change\n")
    proc = _sh(repo, install.format("book"), base)
    assert proc.returncode == 0, proc.stderr
    assert _pip_calls(venv)[-1].endswith("-e .[book]") and len(_pip_calls(venv)) == 3


def test_user_venv_is_installed_into_once_per_run(tmp_path: Path) -> None:
    repo = _checkout(tmp_path)
    python = _venv_with_fake_pip(tmp_path / "theirs")
    proc = _sh(repo, "use_python; install_symrb test; install_symrb book", python)
    assert proc.returncode == 0, proc.stderr
    # no stamp in an environment the scripts do not own, but no second install in one run
    assert _pip_calls(tmp_path / "theirs") == ["install -qq --disable-pip-version-check -e .[test]"]
    assert not list((tmp_path / "theirs").glob("*.stamp"))


@pytest.mark.parametrize(
    ("body", "message"),
    [
        (
            'case "$*" in *ensurepip*) echo "No module named ensurepip" >&2; exit 1 ;; esac',
            "cannot create a virtual environment (no venv/ensurepip module); on Debian or "
            "Ubuntu: sudo apt install python3-venv",
        ),
        (
            'case "$*" in *version_info*) exit 1 ;; *python_version*) echo 3.9.2; exit ;; esac',
            "is Python 3.9.2; symrb needs 3.11 or newer",
        ),
    ],
    ids=["no-venv-module", "python-3.9"],
)
def test_unusable_python_exits_2_and_says_why(tmp_path: Path, body: str, message: str) -> None:
    repo = _checkout(tmp_path)
    fake = _fake_python(tmp_path / "python3", body)
    proc = _sh(repo, "use_python; echo reached", fake)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert f"error: {fake} {message}" in proc.stderr
    assert "reached" not in proc.stdout
    assert not (repo / ".venv").exists()


def test_missing_python_exits_2_and_says_why(tmp_path: Path) -> None:
    repo = _checkout(tmp_path)
    proc = _sh(repo, "use_python", "python3-that-does-not-exist")
    assert proc.returncode == 2
    assert "'python3-that-does-not-exist' not found: install Python 3.11 or newer" in proc.stderr


def test_worktree_state_sees_tracked_and_new_files_only(tmp_path: Path) -> None:
    repo = _checkout(tmp_path)
    git = ["git", "-c", "user.name=t", "-c", "user.email=t@example.org"]
    (repo / ".gitignore").write_text("ignored/\n")
    (repo / "tracked.txt").write_text("one\n")
    for cmd in (["init", "-q"], ["add", "."], ["commit", "-q", "-m", "start"]):
        subprocess.run([*git, *cmd], cwd=repo, check=True, capture_output=True)

    def state() -> str:
        proc = _sh(repo, "worktree_state", BASE_PYTHON)
        assert proc.returncode == 0, proc.stderr
        return proc.stdout.strip()

    clean = state()
    (repo / "ignored").mkdir()
    (repo / "ignored" / "build.log").write_text("output\n")
    assert state() == clean, "an ignored file changed the fingerprint"
    (repo / "tracked.txt").write_text("two\n")
    assert state() != clean, "a rewritten tracked file went unnoticed"
    (repo / "tracked.txt").write_text("one\n")
    assert state() == clean
    (repo / "stray.txt").write_text("new\n")
    assert state() != clean, "a new file outside .gitignore went unnoticed"


NOTEBOOK_RUN = textwrap.dedent(
    """
    import nbformat
    from nbclient import NotebookClient

    nb = nbformat.v4.new_notebook()
    nb.cells.append(nbformat.v4.new_code_cell("print(6 * 7)"))
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    NotebookClient(nb, timeout=120, kernel_name="python3").execute()
    print("output:", nb.cells[0].outputs[0]["text"].strip())
    """
)


def test_book_kernel_prints_no_tcp_warning(tmp_path: Path) -> None:
    pytest.importorskip("nbclient")
    stock = subprocess.run(
        [sys.executable, "-c", NOTEBOOK_RUN],
        env=_env(JUPYTER_PATH=""),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert stock.returncode == 0, stock.stderr
    assert "output: 42" in stock.stdout
    # the stock kernel does warn, so the check below can fail
    assert TCP_WARNING in stock.stderr
    ours = subprocess.run(
        [sys.executable, "-c", NOTEBOOK_RUN],
        env=_env(JUPYTER_PATH=str(TOOLS / "jupyter")),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert ours.returncode == 0, ours.stderr
    assert "output: 42" in ours.stdout
    assert TCP_WARNING not in ours.stderr, ours.stderr


PAGE = """\
---
jupytext:
  text_representation:
    extension: .md
    format_name: myst
    format_version: 0.13
kernelspec:
  display_name: Python 3
  language: python
  name: python3
---
# A page

```{{code-cell}} python
{code}
```
"""


def _small_book(where: Path, code: str) -> Path:
    where.mkdir()
    (where / "_config.yml").write_text(
        "title: t\nexecute:\n  execute_notebooks: force\n"
        "sphinx:\n  config:\n    nb_execution_raise_on_error: true\n"
    )
    (where / "_toc.yml").write_text("format: jb-book\nroot: intro\n")
    (where / "intro.md").write_text(PAGE.format(code=code))
    return where


def _build(args: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        args,
        cwd=cwd,
        env=_env(JUPYTER_PATH=str(TOOLS / "jupyter")),
        capture_output=True,
        text=True,
        timeout=600,
    )


def test_book_build_log_is_plain_text(tmp_path: Path) -> None:
    pytest.importorskip("jupyter_book")
    book = _small_book(tmp_path / "good", "print(6 * 7)")
    jupyter_book = Path(sys.executable).parent / "jupyter-book"
    stock = _build([str(jupyter_book), "build", "-W", str(book)], tmp_path)
    assert stock.returncode == 0, stock.stdout + stock.stderr
    # the stock log has what the wrapper removes, so the checks below can fail
    assert "\x1b[" in stock.stdout and "NbParserConfig(" in stock.stdout

    shutil.rmtree(book / "_build")
    ours = _build([sys.executable, str(TOOLS / "build_book.py"), "-W", str(book)], tmp_path)
    log = ours.stdout + ours.stderr
    assert ours.returncode == 0, log
    assert "\x1b" not in log
    assert "ParserConfig(" not in log
    assert TCP_WARNING not in log
    assert "intro.md: Executed notebook" in log  # progress lines stay
    assert "42" in (book / "_build" / "html" / "intro.html").read_text()


def test_book_build_failure_keeps_traceback(tmp_path: Path) -> None:
    pytest.importorskip("jupyter_book")
    book = _small_book(tmp_path / "bad", 'raise ValueError("the page is wrong")')
    proc = _build([sys.executable, str(TOOLS / "build_book.py"), "-W", str(book)], tmp_path)
    log = proc.stdout + proc.stderr
    assert proc.returncode != 0
    assert "CellExecutionError" in log
    assert "ValueError: the page is wrong" in log
    assert "\x1b" not in log


def _commands(path: Path) -> list[str]:
    lines = (line.strip() for line in path.read_text().splitlines())
    return [line for line in lines if line and not line.startswith("#")]


def test_book_is_built_in_one_place() -> None:
    """Only tools/book.sh builds the book; CI runs tools/test.sh once, which calls it once."""
    scripts = [*TOOLS.glob("*.sh"), ROOT / ".ci" / "run"]
    builders = {
        path.name
        for path in scripts
        for cmd in _commands(path)
        if "tools/build_book.py" in cmd or cmd.startswith("jupyter-book build")
    }
    assert builders == {"book.sh"}
    calls = [
        cmd for cmd in _commands(TOOLS / "test.sh") if re.search(r"\bbash tools/book\.sh", cmd)
    ]
    assert len(calls) == 1, calls
    ci = _commands(ROOT / ".ci" / "run")
    assert [cmd for cmd in ci if "tools/test.sh" in cmd] == ["bash tools/test.sh"]
    assert not [cmd for cmd in ci if "book.sh" in cmd]


def test_mutant_spec_applies_to_the_current_code() -> None:
    """Every mutant's text occurs in its file as often as tools/mutants.toml says, so an edit
    that moves a mutated line fails here, not only in the mutation step of the book build."""
    root = Path(__file__).resolve().parents[1]
    run = subprocess.run(
        [sys.executable, str(root / "tools" / "mutate.py"), "--list"],
        capture_output=True,
        text=True,
        cwd=root,
    )
    assert run.returncode == 0, run.stderr
