"""The cache of scene results: :func:`scene_key` (a SHA-256 of the canonical scene, of the
source of the symrb modules its plan uses and of the NumPy/SciPy/Python versions) and
:class:`SceneStore`, a content-addressed store of :class:`~symrb.scenes.SceneResult`."""

from __future__ import annotations

import hashlib
import importlib
import json
import os
import platform
import shutil
import tempfile
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np
import scipy

from .. import __version__
from ..errors import InputError
from .plan import Plan, plan_scene
from .result import SceneResult
from .schema import Scene


def _versions() -> dict[str, str]:
    return {"symrb": __version__, "numpy": np.__version__, "scipy": scipy.__version__,
            "python": platform.python_version()}  # fmt: skip


def _canonical(scene: Any) -> str:
    return json.dumps(scene.model_dump(mode="json"), sort_keys=True, separators=(",", ":"))


_DIGESTS: dict[tuple[str, int, int], str] = {}


def _file_digest(path: str) -> str:
    """SHA-256 of a file, remembered while its modification time and size stay the same."""
    st = os.stat(path)
    key = (path, st.st_mtime_ns, st.st_size)
    if key not in _DIGESTS:
        _DIGESTS[key] = hashlib.sha256(Path(path).read_bytes()).hexdigest()
    return _DIGESTS[key]


def _code_digest(modules: Iterable[str]) -> str:
    h = hashlib.sha256()
    for name in sorted(modules):
        mod = importlib.import_module(f"symrb.{name}")
        path = getattr(mod, "__file__", None)
        h.update(name.encode())
        if path:
            h.update(_file_digest(path).encode())
    return h.hexdigest()


def scene_key(scene: Scene, plan: Plan | None = None) -> str:
    """The cache key of a scene: SHA-256 of its canonical JSON, of the source of the symrb
    modules it uses and of the NumPy/SciPy/Python versions."""
    plan = plan or plan_scene(scene)
    versions = _versions()
    payload = {"scene": _canonical(scene), "code": _code_digest(plan.modules),
               "versions": {k: versions[k] for k in ("numpy", "scipy", "python")}}  # fmt: skip
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()


def _default_cache() -> Path:
    env = os.environ.get("SYMRB_CACHE_DIR")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "symrb" / "scenes"


class SceneStore:
    """A content-addressed store of scene results: ``<root>/<key[:2]>/<key>/`` holding
    ``arrays.npz`` and ``scene.json`` (written to a temporary directory and renamed, so a
    process killed mid-write leaves no partial entry), and ``log.jsonl`` with one line per
    computation (key, process id, seconds).

    Parameters
    ----------
    root : path-like, optional
        The directory; default ``$SYMRB_CACHE_DIR`` or ``~/.cache/symrb/scenes``.

    Examples
    --------
    >>> import tempfile
    >>> from symrb.scenes import SceneStore, parse_scene, run_scene
    >>> store = SceneStore(tempfile.mkdtemp())
    >>> scene = parse_scene({"system": "double_bracket", "integrator": {"kind": "continuous"},
    ...                      "horizon": {"T": 2.0}, "observables": {"pairing": "end"}})
    >>> a = run_scene(scene, cache=store)
    >>> b = run_scene(scene, cache=store)
    >>> a.meta["from_cache"], b.meta["from_cache"], len(store.log())
    (False, True, 1)
    """

    def __init__(self, root: str | os.PathLike[str] | None = None) -> None:
        self.root = Path(root) if root is not None else _default_cache()

    def path(self, key: str) -> Path:
        return self.root / key[:2] / key

    def get(self, key: str, scene: Any = None, plan: Plan | None = None) -> SceneResult | None:
        """The stored result of ``key``, or None (``scene``, ``plan``: see SceneResult.load)."""
        d = self.path(key)
        if not (d / "scene.json").is_file():
            return None
        try:
            return SceneResult.load(d, scene, plan)
        except (OSError, ValueError, KeyError):  # a damaged entry is recomputed
            return None

    def put(self, key: str, result: SceneResult) -> None:
        final = self.path(key)
        final.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{key[:8]}-", dir=final.parent))
        try:
            result.save(tmp)
            try:
                os.replace(tmp, final)
            except OSError:  # another process stored it first: theirs is as good
                shutil.rmtree(tmp, ignore_errors=True)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        line = json.dumps({"key": key, "pid": os.getpid(), "seconds": result.meta["seconds"],
                           "system": result.scene.system})  # fmt: skip
        with open(self.root / "log.jsonl", "a") as f:
            f.write(line + "\n")

    def log(self) -> list[dict[str, Any]]:
        """The computations recorded, oldest first."""
        try:
            text = (self.root / "log.jsonl").read_text()
        except FileNotFoundError:
            return []
        return [json.loads(s) for s in text.splitlines() if s.strip()]


def _store(cache: bool | str | os.PathLike[str] | SceneStore | None) -> SceneStore | None:
    if cache is None or cache is False:
        return None
    if cache is True:
        return SceneStore()
    if isinstance(cache, SceneStore):
        return cache
    if isinstance(cache, str | os.PathLike):
        return SceneStore(cache)
    raise InputError(f"cache must be True, False, a directory or a SceneStore, got {cache!r}")
