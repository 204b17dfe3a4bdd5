"""Issue 22, the scene tool: every mistake in a scene is a usage error (exit 2, one paragraph
naming the key, its line and what is allowed, no traceback) whether found while reading,
planning or running; budgets refuse a scene before any work; a closed pipe and Ctrl-C end
cleanly.  Each case below printed a traceback, hung or was accepted before the fix."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from symrb.cli import main
from symrb.scenes import SceneError, load_scene, plan_scene, run_scene, sweep
from symrb.scenes.plan import Budget

ROOT = Path(__file__).resolve().parents[1]


def _rb(params: str = "", integ: str = 'method = "DOP853"', T: str = "1.0",
        obs: str = 'energy = "end"') -> str:  # fmt: skip
    return (f'system = "rigid_body"\n[parameters]\n{params}\n[integrator]\n{integ}\n'
            f"[horizon]\nT = {T}\n[observables]\n{obs}\n")  # fmt: skip


#: (case, scene text, the key the message must name, its line, a phrase of the message)
CASES = [
    ("lam nan", _rb("lam = [nan, 1.0, 2.0]"), "parameters.lam", 3, "finite"),
    ("lam inf", _rb("lam = [inf, 1.0, 2.0]"), "parameters.lam", 3, "finite"),
    ("lam zero", _rb("lam = [0.0, 1.0, 2.0]"), "parameters.lam", 3, "positive"),
    ("lam negative", _rb("lam = [-1.0, 1.0, 2.0]"), "parameters.lam", 3, "positive"),
    ("lam wrong length", _rb("lam = [1.0, 2.0]"), "parameters.lam", 3, "n = 3 entries"),
    ("M0 nan", _rb("M0 = [nan, 1.0, 2.0]"), "parameters.M0", 3, "finite"),
    ("momentum inf", _rb("momentum = inf"), "parameters.momentum", 3, "finite"),
    ("M0 1e300", _rb("M0 = [1e300, 1.0, 2.0]"), "parameters.M0", 3, "1e+12"),
    ("op_norm 1e300", _rb("op_norm = 1e300"), "parameters.op_norm", 3, "1e+12"),
    (
        "ragged M0",
        _rb("M0 = [[0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 0.0]]"),
        "parameters.M0",
        3,
        "rows of one length",
    ),  # fmt: skip
    ("T inf mv", _rb("", 'method = "mv"\nh = 0.1', "inf"), "horizon.T", 8, "finite"),
    ("h 1e-300", _rb("", 'method = "mv"\nh = 1e-300'), "horizon.T", 8, "--max-seconds"),
    (
        "points 1e9",
        _rb(obs="energy = {points = 1000000000}"),
        "observables.energy",
        9,
        "--max-memory",
    ),  # fmt: skip
    ("n 5000 continuous", _rb("n = 5000"), "(estimated cost)", None, "--max-seconds"),
    ("seed -1", _rb("seed = -1"), "parameters.seed", 3, "greater than or equal to 0"),
    ("T string", _rb(T='"5"'), "horizon.T", 7, "the string '5'"),
    ("h string", _rb("", 'method = "mv"\nh = "0.05"'), "integrator.h", 6, "the string '0.05'"),
    ("n float", _rb("n = 3.5"), "parameters.n", 3, "integer"),
    ("bool as number", _rb("momentum = true"), "parameters.momentum", 3, "number"),
    ("TOML syntax", 'system = "rigid_body"\n[parameters\n', "(top level)", 2, "bad TOML"),
]


def _cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    """symrb in-process: (exit status, stdout, stderr); any exception fails the test."""
    rc = main(list(args))
    out = capsys.readouterr()
    return rc, out.out, out.err


def _assert_usage_error(rc: int, err: str, key: str, line: int | None, phrase: str) -> None:
    assert rc == 2, err
    assert "Traceback" not in err
    assert "\n\n" not in err.strip(), "one paragraph"
    assert key in err and phrase in err, err
    if line is not None:
        assert f"{key} (line {line})" in err, err


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
@pytest.mark.parametrize("explain", [False, True], ids=["run", "explain"])
def test_a_bad_scene_is_a_usage_error(case, explain, tmp_path, capsys) -> None:
    """run and --explain refuse the same scenes, with the same message (exit 2)."""
    name, text, key, line, phrase = case
    path = tmp_path / "s.toml"
    path.write_text(text)
    extra = ["--explain"] if explain else ["--no-cache"]
    rc, out, err = _cli(capsys, "run", str(path), *extra)
    _assert_usage_error(rc, err, key, line, phrase)
    assert "result" not in out  # nothing ran


def test_a_binary_file_is_a_usage_error(tmp_path, capsys) -> None:
    path = tmp_path / "s.toml"
    path.write_bytes(bytes(range(256)) * 4)
    rc, _, err = _cli(capsys, "run", str(path))
    _assert_usage_error(rc, err, "(top level)", 2, "not UTF-8")


def test_a_valid_scene_still_runs(tmp_path, capsys) -> None:
    path = tmp_path / "s.toml"
    path.write_text(_rb("lam = [0.7, 1.1, 1.6]\nM0 = [0.5, 1.0, 1.5]"))
    rc, out, err = _cli(capsys, "run", str(path), "--no-cache")
    assert rc == 0 and "result      computed" in out and "memory      ~" in out, err


@pytest.mark.parametrize(
    "grid, phrase",
    [
        (["horizon.T="], "an empty value"),
        (["horizon.T"], "not of the form KEY=V1,V2"),
        (["horizon.T=1,,2"], "an empty value"),
        (["parameters.seed=0,1", "parameters.seed=2,3"], "on the grid twice"),
        (["horizon.T=abc"], "the string 'abc'"),
        (["parameters.seed=-1,0"], "greater than or equal to 0"),
    ],
)
def test_grid_mistakes_are_usage_errors(grid, phrase, tmp_path, capsys) -> None:
    """A bad grid is refused before any point runs (exit 2, no traceback); a key given twice is
    refused, not one of its lists silently dropped."""
    path = tmp_path / "s.toml"
    path.write_text(_rb())
    args = [a for g in grid for a in ("--grid", g)]
    rc, out, err = _cli(capsys, "sweep", str(path), *args, "--no-progress", "--no-cache")
    assert rc == 2 and "Traceback" not in err and phrase in err, err
    assert out == ""


def test_a_sweep_checks_every_point_before_running_any(tmp_path, capsys) -> None:
    """A grid whose last point is over the budget runs no point at all."""
    path = tmp_path / "s.toml"
    path.write_text(_rb())
    rc, out, err = _cli(capsys, "sweep", str(path), "--grid", "parameters.n=3,4000",
                        "--no-progress", "--cache", str(tmp_path / "c"))  # fmt: skip
    assert rc == 2 and "parameters.n" in err and "--max-seconds" in err, err
    assert not any((tmp_path / "c").rglob("*.npz"))


def test_budgets_can_be_raised(tmp_path, capsys) -> None:
    """The limits are options: --max-seconds / --max-memory (and run_scene's keywords); the
    estimate is in the message."""
    path = tmp_path / "s.toml"
    path.write_text(_rb(obs="energy = {points = 200001}"))
    rc, _, err = _cli(capsys, "run", str(path), "--explain", "--max-memory", "1M")
    assert rc == 2 and "~15.3 MiB" in err and "limit of 1 MiB" in err, err
    rc, out, err = _cli(capsys, "run", str(path), "--explain", "--max-memory", "1G")
    assert rc == 0, err
    rc, _, err = _cli(capsys, "run", str(path), "--explain", "--max-seconds", "1e-9")
    assert rc == 2 and "limit of 1e-09 s" in err, err
    with pytest.raises(SystemExit) as exc:  # argparse's usage error
        main(["run", str(path), "--explain", "--max-memory", "lots"])
    assert exc.value.code == 2 and "a size such as 4G" in capsys.readouterr().err
    scene = load_scene(path)
    with pytest.raises(SceneError, match="over the limit"):
        run_scene(scene, cache=False, max_memory=2**20)
    with pytest.raises(SceneError, match="over the limit"):
        Budget(seconds=1e-9).check(plan_scene(scene))


def test_a_run_with_non_finite_observables_is_a_failure(monkeypatch, tmp_path) -> None:
    """A run whose observables are not finite (an overflow) is not success: its message names
    the observable and the first record, and it is not stored."""
    import symrb.scenes.run as run_module

    real = run_module._execute

    def overflowing(sc, plan):
        times, data, failure = real(sc, plan)
        data["energy"] = np.array([1.0, np.inf, np.inf])
        return times, data, failure

    monkeypatch.setattr(run_module, "_execute", overflowing)
    scene = {**_SCENE, "observables": {"energy": {"points": 3}}}
    r = run_scene(scene, cache=tmp_path)
    assert not r.meta["success"]
    assert r.meta["message"].startswith("observables.energy is not finite from record 1")
    assert not any(tmp_path.rglob("*.npz"))


def test_sweep_function_refuses_a_repeated_key() -> None:
    with pytest.raises(SceneError, match="twice"):
        sweep(_SCENE, ["parameters.seed=0", "parameters.seed=1"], cache=False)


_SCENE = {"system": "rigid_body", "integrator": {"method": "DOP853"}, "horizon": {"T": 1.0},
          "observables": {"energy": "end"}}  # fmt: skip
_ENV = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
_CMD = [sys.executable, "-c", "import sys; from symrb.cli import main; sys.exit(main())"]


def test_a_closed_pipe_prints_no_traceback(tmp_path) -> None:
    """symrb run S | head -1: the reader goes away after one line; no BrokenPipe traceback."""
    path = tmp_path / "s.toml"
    path.write_text(_rb())
    p = subprocess.Popen([*_CMD, "run", str(path), "--no-cache"], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, env=_ENV, cwd=tmp_path)  # fmt: skip
    assert p.stdout is not None and p.stderr is not None
    p.stdout.readline()
    p.stdout.close()  # as head does after its line
    err = p.stderr.read().decode()
    p.wait(timeout=120)
    assert "Traceback" not in err and "BrokenPipe" not in err, err
    assert p.returncode in (0, 141)


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _interrupt(args: list[str], tmp_path: Path, stored: Path | None = None) -> tuple[int, str]:
    """Start symrb, wait until it prints its first line (or logs a first stored result under
    ``stored``), let it work a moment, send SIGINT."""
    # SIGINT as a terminal sends it: a test runner started in the background ignores SIGINT,
    # and a child that inherits that would never see it
    p = subprocess.Popen([*_CMD, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         env=_ENV, cwd=tmp_path, preexec_fn=_default_sigint)  # fmt: skip
    assert p.stdout is not None
    if stored is None:
        p.stdout.readline()
        time.sleep(1.0)
    else:
        deadline = time.monotonic() + 120
        while not (stored / "log.jsonl").is_file() and time.monotonic() < deadline:
            time.sleep(0.05)
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=120)
    return p.returncode, err.decode()


#: a scene of about a second of steps per point (1e4 steps of MV at n = 12)
_SLOW = _rb("n = 12", 'method = "mv"\nh = 0.001', "10.0")


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_ctrl_c_ends_a_run_with_one_line(tmp_path) -> None:
    path = tmp_path / "s.toml"
    # ten times _SLOW: the run must still be going a second after its first line, loaded or not
    path.write_text(_rb("n = 12", 'method = "mv"\nh = 0.001', "100.0"))
    rc, err = _interrupt(["run", str(path), "--no-cache"], tmp_path)
    assert rc == 130 and err.strip() == "interrupted; 0 of 1 point kept", err


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_ctrl_c_ends_a_sweep_with_one_line(tmp_path) -> None:
    """The line counts the points finished (stored in the cache) before Ctrl-C."""
    path = tmp_path / "s.toml"
    path.write_text(_SLOW)
    rc, err = _interrupt(["sweep", str(path), "--grid", "parameters.seed=0,1,2,3,4,5,6,7",
                          "--no-progress", "--cache", str(tmp_path / "c")], tmp_path,
                         stored=tmp_path / "c")  # fmt: skip
    lines = err.strip().splitlines()
    assert rc == 130 and len(lines) == 1 and lines[0].startswith("interrupted; "), err
    kept = int(lines[0].split()[1])
    assert lines[0] == f"interrupted; {kept} of 8 points kept" and 1 <= kept < 8
    assert len(list((tmp_path / "c").rglob("*.npz"))) >= kept
