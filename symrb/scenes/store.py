"""The cache of scene results: :func:`scene_key` (a SHA-256 of the canonical scene, of the
source of the symrb modules its plan uses and of the symrb/NumPy/SciPy/Python versions),
:func:`default_cache_dir` (where it lives) and :class:`SceneStore`, a content-addressed store of
:class:`~symrb.scenes.SceneResult` whose entries carry SHA-256 checksums, checked on every read.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import importlib
import io
import json
import os
import platform
import secrets
import shutil
import warnings
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np
import scipy

from .. import __version__
from .._validate import Array
from ..errors import CacheWarning, InputError
from .parse import parse_scene
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


def _module_files(mod: object) -> list[str]:
    """The source files of a module; of a package, every ``.py`` file under it."""
    path = getattr(mod, "__file__", None)
    if not path:
        return []
    if hasattr(mod, "__path__"):
        return sorted(str(p) for p in Path(path).parent.rglob("*.py"))
    return [path]


def _code_digest(modules: Iterable[str]) -> str:
    h = hashlib.sha256()
    for name in sorted(modules):
        mod = importlib.import_module(f"symrb.{name}")
        h.update(name.encode())
        for path in _module_files(mod):
            h.update(_file_digest(path).encode())
    return h.hexdigest()


def scene_key(scene: Scene, plan: Plan | None = None) -> str:
    """The cache key of a scene: SHA-256 of its canonical JSON, of the source of the symrb
    modules it uses and of the symrb, NumPy, SciPy and Python versions."""
    plan = plan or plan_scene(scene)
    payload = {"scene": _canonical(scene), "code": _code_digest(plan.modules),
               "versions": _versions()}  # fmt: skip
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()


def default_cache_dir() -> Path:
    """Where the scene cache lives unless told otherwise.

    Returns
    -------
    Path
        ``$SYMRB_CACHE_DIR`` if set; else ``$XDG_CACHE_HOME/symrb/scenes`` if that variable is
        set; else ``~/.cache/symrb/scenes``.  ``symrb run --help`` prints the directory this
        gives in the current environment.

    Examples
    --------
    >>> from symrb.scenes import SceneStore
    >>> from symrb.scenes.store import default_cache_dir
    >>> SceneStore().root == default_cache_dir()
    True
    """
    env = os.environ.get("SYMRB_CACHE_DIR")
    if env:
        return Path(env).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base).expanduser() / "symrb" / "scenes"


def cache_help() -> str:
    """The ``--cache`` help of ``symrb run`` and ``symrb sweep``: the rule and its outcome here."""
    return ("the cache directory (default: $SYMRB_CACHE_DIR, else $XDG_CACHE_HOME/symrb/scenes, "
            f"else ~/.cache/symrb/scenes; here {default_cache_dir()})")  # fmt: skip


_FILES = ("arrays.npz", "scene.json")
_MANIFEST = "manifest.json"
_FORMAT = 1


class _Damaged(Exception):
    """An entry that fails a check; the message says which."""


def _json_bytes(obj: Any) -> bytes:
    return json.dumps(obj, sort_keys=True, separators=(",", ":")).encode()


def _array_digest(a: Array) -> dict[str, Any]:
    """The dtype, shape and SHA-256 of an array's values (C order, independent of its layout)."""
    a = np.asarray(a)
    h = hashlib.sha256(f"{a.dtype.str}{a.shape}".encode())
    h.update(np.ascontiguousarray(a).tobytes())
    return {"dtype": a.dtype.str, "shape": list(a.shape), "sha256": h.hexdigest()}


def _manifest(key: str, d: Path, result: SceneResult) -> bytes:
    """The manifest of an entry written to ``d``: the SHA-256 and size of each file, the
    checksum of each array as computed (not as read back), and a SHA-256 of all that."""
    files = {}
    for name in _FILES:
        raw = (d / name).read_bytes()
        files[name] = {"size": len(raw), "sha256": hashlib.sha256(raw).hexdigest()}
    arrays = {f"data/{k}": _array_digest(a) for k, a in result.data.items()}
    arrays.update({f"times/{k}": _array_digest(a) for k, a in result.times.items()})
    body = {"format": _FORMAT, "key": key, "files": files, "arrays": arrays}
    return _json_bytes({"body": body, "sha256": hashlib.sha256(_json_bytes(body)).hexdigest()})


def _read_checked(path: Path, want: dict[str, Any]) -> bytes:
    """The bytes of a file of an entry, their size and SHA-256 as the manifest says."""
    size = path.stat().st_size
    if size != want["size"]:
        raise _Damaged(f"{path.name} has {size} bytes, its manifest says {want['size']}")
    raw = path.read_bytes()
    if len(raw) != size or hashlib.sha256(raw).hexdigest() != want["sha256"]:
        raise _Damaged(f"{path.name} does not match its SHA-256 in the manifest")
    return raw


def _read_manifest(d: Path, key: str) -> dict[str, Any]:
    """The body of an entry's manifest, checked against its own SHA-256 and the key."""
    path = d / _MANIFEST
    if path.stat().st_size > 1 << 22:
        raise _Damaged(f"{_MANIFEST} is too large")
    try:
        doc = json.loads(path.read_bytes())
        body, digest = doc["body"], doc["sha256"]
        ok = hashlib.sha256(_json_bytes(body)).hexdigest() == digest
    except (ValueError, KeyError, TypeError) as exc:
        raise _Damaged(f"{_MANIFEST} is not a manifest ({type(exc).__name__})") from None
    if not ok:
        raise _Damaged(f"{_MANIFEST} does not match its own SHA-256")
    if not isinstance(body, dict):
        raise _Damaged(f"{_MANIFEST} is not a manifest (no table)")
    if body.get("format") != _FORMAT or body.get("key") != key:
        raise _Damaged(f"{_MANIFEST} belongs to key {str(body.get('key'))[:16]}, not this key")
    return body  # type: ignore[no-any-return]


def _read_entry(d: Path, key: str) -> tuple[dict[str, Any], dict[str, Array]]:
    """The metadata and the arrays of the entry ``d`` of ``key``, every byte checked against
    the manifest before it is parsed and every array against its checksum after."""
    body = _read_manifest(d, key)
    raw = {name: _read_checked(d / name, body["files"][name]) for name in _FILES}
    meta = json.loads(raw["scene.json"])
    with np.load(io.BytesIO(raw["arrays.npz"]), allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    if sorted(arrays) != sorted(body["arrays"]):
        raise _Damaged("arrays.npz holds other arrays than its manifest lists")
    for name, a in arrays.items():
        if _array_digest(a) != body["arrays"][name]:
            raise _Damaged(f"array {name} of arrays.npz does not match its checksum")
    if meta["meta"]["key"] != key:
        raise _Damaged(f"scene.json is the result of key {meta['meta']['key'][:16]}")
    return meta, arrays


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        with contextlib.suppress(OSError):
            path.unlink()


class SceneStore:
    """A content-addressed store of scene results: ``<root>/<key[:2]>/<key>/`` holding
    ``arrays.npz``, ``scene.json`` and ``manifest.json`` (the size and SHA-256 of both files,
    the SHA-256 of every array, and a SHA-256 of the manifest itself), and ``log.jsonl`` with
    one line per computation (key, process id, seconds).

    Every read checks the whole entry before anything in it is used; an entry that fails
    (truncated, a bit flipped, other arrays or metadata, another key's entry, a file missing)
    is reported as a :class:`~symrb.errors.CacheWarning`, recomputed and replaced.  An entry is
    written to a temporary directory beside it and renamed into place (a damaged entry already
    there is first moved aside), so a process killed mid-write leaves no partial entry and two
    processes storing the same key leave one good entry.  A store that cannot be written warns
    and the result is returned all the same.  Directories are created with mode ``0o777`` and
    files ``0o666``, less the umask, so a group can share a cache (umask ``002``).

    Parameters
    ----------
    root : path-like, optional
        The directory; default :func:`default_cache_dir` (``$SYMRB_CACHE_DIR``, else
        ``$XDG_CACHE_HOME/symrb/scenes``, else ``~/.cache/symrb/scenes``).

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
        self.root = Path(root).expanduser() if root is not None else default_cache_dir()
        self._unwritable = False

    def path(self, key: str) -> Path:
        return self.root / key[:2] / key

    def _warn(self, message: str) -> None:
        warnings.warn(f"the scene cache {self.root}: {message}", CacheWarning, stacklevel=4)

    def get(self, key: str, scene: Any = None, plan: Plan | None = None) -> SceneResult | None:
        """The stored result of ``key``, or None when there is none or it fails a check (then
        with a :class:`~symrb.errors.CacheWarning`).  ``scene`` and ``plan``, when the caller
        has them, are used instead of validating and planning the stored scene again."""
        d = self.path(key)
        if not os.path.lexists(d):
            return None
        try:
            meta, arrays = _read_entry(d, key)
            if scene is not None and _json_bytes(meta["scene"]) != _canonical(scene).encode():
                raise _Damaged("scene.json holds another scene")
        except (_Damaged, OSError, KeyError, TypeError, ValueError) as exc:
            why = ("a file is missing" if isinstance(exc, FileNotFoundError | NotADirectoryError)
                   else str(exc))  # fmt: skip
            self._warn(f"entry {key[:16]} is damaged or unreadable ({why}); recomputing it")
            return None
        if scene is None:
            scene = parse_scene(meta["scene"])
        data = {k[5:]: a for k, a in arrays.items() if k.startswith("data/")}
        times = {k[6:]: a for k, a in arrays.items() if k.startswith("times/")}
        return SceneResult(scene, plan or plan_scene(scene), times, data, dict(meta["meta"]))

    def put(self, key: str, result: SceneResult) -> bool:
        """Store ``result`` under ``key``, replacing a damaged entry; False, with a
        :class:`~symrb.errors.CacheWarning`, when the store cannot be written."""
        try:
            self._put(key, result)
        except OSError as exc:
            if not self._unwritable:  # once per store: a sweep need not repeat it per point
                self._warn(f"results are not stored ({exc}); they are returned as computed, "
                           "and computed again next time")  # fmt: skip
            self._unwritable = True
            return False
        line = json.dumps({"key": key, "pid": os.getpid(), "seconds": result.meta["seconds"],
                           "system": result.scene.system})  # fmt: skip
        try:
            with open(self.root / "log.jsonl", "a") as f:
                f.write(line + "\n")
        except OSError as exc:
            self._warn(f"log.jsonl is not written ({exc})")
        return True

    def _put(self, key: str, result: SceneResult) -> None:
        final = self.path(key)
        final.parent.mkdir(parents=True, exist_ok=True)  # mode 0o777 less the umask
        tmp = final.parent / f".{key[:8]}-{secrets.token_hex(4)}.tmp"
        os.mkdir(tmp)  # mkdtemp would make it 0o700
        try:
            result.save(tmp)
            (tmp / _MANIFEST).write_bytes(_manifest(key, tmp, result))
            self._swap(tmp, final, key)
        finally:
            if os.path.lexists(tmp):
                _remove(tmp)

    def _swap(self, tmp: Path, final: Path, key: str) -> None:
        """Rename the written entry ``tmp`` to ``final``.  An entry already there is kept if it
        passes its checks (another process stored it first), else moved aside and removed."""
        try:
            os.replace(tmp, final)
            return
        except OSError as exc:
            if exc.errno not in (errno.ENOTEMPTY, errno.EEXIST, errno.ENOTDIR, errno.EISDIR):
                raise
        try:
            _read_entry(final, key)
            return
        except (_Damaged, OSError):
            pass
        trash = final.parent / f".{key[:8]}-{secrets.token_hex(4)}.old"
        try:
            os.replace(final, trash)
        except FileNotFoundError:  # another process moved it aside already
            pass
        try:
            os.replace(tmp, final)
        except OSError:
            if not os.path.lexists(final):  # not that another process put its own there
                raise
        finally:
            if os.path.lexists(trash):
                _remove(trash)

    def log(self) -> list[dict[str, Any]]:
        """The computations recorded, oldest first (a line that is not JSON is skipped, with a
        :class:`~symrb.errors.CacheWarning`)."""
        try:
            text = (self.root / "log.jsonl").read_text(errors="replace")
        except (FileNotFoundError, NotADirectoryError):
            return []
        out, bad = [], 0
        for s in text.splitlines():
            try:
                entry = json.loads(s) if s.strip() else None
            except ValueError:
                entry = None
                bad += 1
            if isinstance(entry, dict):
                out.append(entry)
        if bad:
            warnings.warn(f"the scene cache {self.root}: {bad} line(s) of log.jsonl are not JSON "
                          "and are skipped", CacheWarning, stacklevel=2)  # fmt: skip
        return out


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
