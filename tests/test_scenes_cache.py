"""The scene cache checks itself (issue 22): every entry carries SHA-256 checksums of its arrays
and of its metadata, verified when read; a damaged or mismatched entry is reported as a
:class:`~symrb.errors.CacheWarning`, recomputed and replaced; a cache that cannot be written
warns and the result is still returned; the key includes the symrb version; the location shown
by ``--help`` is the one used; entries are created with the permissions the umask allows."""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from scene_helpers import same as _same

from symrb.errors import CacheWarning
from symrb.scenes import SceneStore, parse_scene, run_scene, scene_key, sweep
from symrb.scenes import run as scenes_run
from symrb.scenes import store as scenes_store

ROOT = Path(__file__).resolve().parents[1]

SCENE = {
    "system": "rigid_body",
    "parameters": {"n": 3, "seed": 1},
    "integrator": {"method": "DOP853"},
    "horizon": {"T": 1.0},
    "observables": {"energy": {"points": 4}, "M": "end"},
}

TOML = """\
system = "rigid_body"
[parameters]
n = 3
seed = 1
[integrator]
method = "DOP853"
[horizon]
T = 1.0
[observables]
energy = {points = 4}
M = "end"
"""


def _scene(seed: int = 1):
    return parse_scene({**SCENE, "parameters": {"n": 3, "seed": seed}})


def _run_quiet(sc, cache):
    """run_scene, returning (result, the CacheWarnings it raised)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = run_scene(sc, cache=cache)
    return r, [w for w in caught if issubclass(w.category, CacheWarning)]


def _same_result(a, b) -> None:
    assert sorted(a.data) == sorted(b.data) and sorted(a.times) == sorted(b.times)
    for k in a.data:
        _same(a[k], b[k])
        _same(a.times[k], b.times[k])


def _entry(tmp_path: Path, sc) -> Path:
    return SceneStore(tmp_path).path(scene_key(sc))


def _first_run(tmp_path: Path):
    sc = _scene()
    first, w = _run_quiet(sc, tmp_path)
    assert not first.meta["from_cache"] and not w
    return sc, first


def _recomputed_and_repaired(tmp_path: Path, sc, first, match: str) -> None:
    """The damaged entry is reported, recomputed (the right numbers), and repaired: the next run
    loads it without a warning."""
    again, w = _run_quiet(sc, tmp_path)
    assert not again.meta["from_cache"]
    assert len(w) == 1 and match in str(w[0].message), [str(x.message) for x in w]
    _same_result(first, again)
    third, w = _run_quiet(sc, tmp_path)
    assert third.meta["from_cache"] and not w
    _same_result(first, third)


# ---------------------------------------------------------------------------------------------
# damaged and mismatched entries


def test_truncated_arrays_are_recomputed_and_repaired(tmp_path) -> None:
    sc, first = _first_run(tmp_path)
    npz = _entry(tmp_path, sc) / "arrays.npz"
    npz.write_bytes(npz.read_bytes()[: npz.stat().st_size // 2])
    _recomputed_and_repaired(tmp_path, sc, first, "arrays.npz")


def test_bit_flipped_arrays_are_recomputed_and_repaired(tmp_path) -> None:
    sc, first = _first_run(tmp_path)
    npz = _entry(tmp_path, sc) / "arrays.npz"
    raw = bytearray(npz.read_bytes())
    raw[len(raw) // 3] ^= 0x10
    npz.write_bytes(bytes(raw))
    _recomputed_and_repaired(tmp_path, sc, first, "arrays.npz")


def test_other_valid_arrays_are_not_served(tmp_path) -> None:
    """A valid npz with different numbers (here the energy doubled) fails its checksum."""
    sc, first = _first_run(tmp_path)
    npz = _entry(tmp_path, sc) / "arrays.npz"
    with np.load(npz) as z:
        arrays = {k: z[k] for k in z.files}
    arrays["data/energy"] = 2 * arrays["data/energy"]
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    npz.write_bytes(buf.getvalue())
    _recomputed_and_repaired(tmp_path, sc, first, "arrays.npz")


def test_changed_metadata_is_not_served(tmp_path) -> None:
    """Valid JSON with a different message in scene.json fails the metadata checksum."""
    sc, first = _first_run(tmp_path)
    meta_path = _entry(tmp_path, sc) / "scene.json"
    meta = json.loads(meta_path.read_text())
    meta["meta"]["message"] = "tampered"
    meta_path.write_text(json.dumps(meta))
    _recomputed_and_repaired(tmp_path, sc, first, "scene.json")


def test_entry_of_another_scene_is_not_served(tmp_path) -> None:
    """A whole valid entry copied under another key is another scene's result."""
    sc, first = _first_run(tmp_path)
    other = _scene(seed=2)
    _run_quiet(other, tmp_path)
    src, dst = _entry(tmp_path, other), _entry(tmp_path, sc)
    for name in ("arrays.npz", "scene.json", "manifest.json"):
        (dst / name).write_bytes((src / name).read_bytes())
    _recomputed_and_repaired(tmp_path, sc, first, "key")


def test_existing_entry_is_replaced_not_kept(tmp_path) -> None:
    """``os.replace`` onto an existing (damaged) entry directory fails; the store moves the
    damaged entry aside instead of silently keeping it."""
    sc, first = _first_run(tmp_path)
    entry = _entry(tmp_path, sc)
    (entry / "arrays.npz").write_bytes(b"garbage")
    _recomputed_and_repaired(tmp_path, sc, first, "arrays.npz")
    assert sorted(p.name for p in entry.parent.iterdir()) == [entry.name]  # nothing left over


def test_damaged_log_line_is_skipped(tmp_path) -> None:
    sc, _ = _first_run(tmp_path)
    with open(tmp_path / "log.jsonl", "a") as f:
        f.write('{"key": "abc", "pid\n')
    with pytest.warns(CacheWarning, match="log.jsonl"):
        log = SceneStore(tmp_path).log()
    assert [e["key"] for e in log] == [scene_key(sc)]


# ---------------------------------------------------------------------------------------------
# caches that cannot be written


def test_read_only_cache_warns_and_returns_the_result(tmp_path, monkeypatch) -> None:
    root = tmp_path / "ro"
    root.mkdir()
    root.chmod(0o555)
    if os.geteuid() == 0:  # root writes anyway: refuse every directory made under the cache
        real = os.mkdir

        def refuse(path, *args, **kwargs):
            if str(path).startswith(str(root)):
                raise PermissionError(13, "Permission denied", str(path))
            return real(path, *args, **kwargs)

        monkeypatch.setattr(os, "mkdir", refuse)
    sc = _scene()
    try:
        r, w = _run_quiet(sc, root)
    finally:
        root.chmod(0o755)
    assert not r.meta["from_cache"] and r.meta["success"]
    assert len(w) == 1 and "not stored" in str(w[0].message)
    _same_result(r, run_scene(sc, cache=False))


def test_cache_path_that_is_a_file(tmp_path) -> None:
    path = tmp_path / "cache"
    path.write_text("not a directory")
    sc = _scene()
    r, w = _run_quiet(sc, path)
    assert not r.meta["from_cache"] and w and "not stored" in str(w[-1].message)
    _same_result(r, run_scene(sc, cache=False))
    assert path.read_text() == "not a directory"


def test_unwritable_cache_warns_once_per_sweep(tmp_path) -> None:
    path = tmp_path / "cache"
    path.write_text("")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = sweep(SCENE, {"parameters.seed": [1, 2, 3]}, cache=path)
    assert len(res.results) == 3 and all(r.meta["success"] for r in res.results)
    assert [issubclass(w.category, CacheWarning) for w in caught] == [True]


def _cli(*args: str, env: dict | None = None) -> subprocess.CompletedProcess:
    code = "import sys; from symrb.cli import main; sys.exit(main())"
    clean = {k: v for k, v in os.environ.items()
             if k not in ("SYMRB_CACHE_DIR", "XDG_CACHE_HOME")}  # fmt: skip
    return subprocess.run(
        [sys.executable, "-c", code, *args], capture_output=True, text=True, cwd=ROOT,
        env={**clean, **(env or {})}, timeout=300,
    )  # fmt: skip


def test_unwritable_home_still_writes_out(tmp_path) -> None:
    """HOME is a file: the default cache cannot be made; the run warns, succeeds and writes
    ``--out``."""
    home = tmp_path / "home"
    home.write_text("")
    scene = tmp_path / "s.toml"
    scene.write_text(TOML)
    out = _cli("run", str(scene), "--out", str(tmp_path / "out"), env={"HOME": str(home)})
    assert out.returncode == 0, out.stderr
    assert "not stored" in out.stderr and "Traceback" not in out.stderr
    assert (tmp_path / "out" / "arrays.npz").is_file()


# ---------------------------------------------------------------------------------------------
# the key, the location, the permissions


def test_key_includes_the_symrb_version(monkeypatch) -> None:
    sc = _scene()
    key = scene_key(sc)
    monkeypatch.setattr(scenes_store, "__version__", "0.0.0+other")
    assert scene_key(sc) != key


@pytest.mark.parametrize("var", ["SYMRB_CACHE_DIR", "XDG_CACHE_HOME", "HOME"])
def test_help_names_the_directory_used(tmp_path, var) -> None:
    env = {var: str(tmp_path / "base")}
    expected = {"SYMRB_CACHE_DIR": tmp_path / "base",
                "XDG_CACHE_HOME": tmp_path / "base" / "symrb" / "scenes",
                "HOME": tmp_path / "base" / ".cache" / "symrb" / "scenes"}[var]  # fmt: skip
    helped = _cli("run", "--help", env={**env, "COLUMNS": "2000"})  # no wrapping at "-"
    assert helped.returncode == 0
    assert str(expected) in " ".join(helped.stdout.split())
    scene = tmp_path / "s.toml"
    scene.write_text(TOML)
    ran = _cli("run", str(scene), env=env)
    assert ran.returncode == 0, ran.stderr
    assert (expected / "log.jsonl").is_file()


@pytest.mark.parametrize("umask", [0o022, 0o002])
def test_entries_follow_the_umask(tmp_path, umask) -> None:
    old = os.umask(umask)
    try:
        sc = _scene()
        run_scene(sc, cache=tmp_path / "c")
    finally:
        os.umask(old)
    entry = _entry(tmp_path / "c", sc)
    for d in (entry, entry.parent):
        assert d.stat().st_mode & 0o777 == 0o777 & ~umask, oct(d.stat().st_mode)
    for f in entry.iterdir():
        assert f.stat().st_mode & 0o777 == 0o666 & ~umask, (f, oct(f.stat().st_mode))


def test_stored_result_is_checked_every_time_it_is_read(tmp_path, monkeypatch) -> None:
    """Damage between two loads is caught on the second: nothing is remembered as verified."""
    sc, first = _first_run(tmp_path)
    again, w = _run_quiet(sc, tmp_path)
    assert again.meta["from_cache"] and not w
    calls = []
    real = scenes_run._execute
    monkeypatch.setattr(scenes_run, "_execute", lambda s, p: calls.append(1) or real(s, p))
    (_entry(tmp_path, sc) / "arrays.npz").write_bytes(b"")
    _recomputed_and_repaired(tmp_path, sc, first, "arrays.npz")
    assert calls == [1]
