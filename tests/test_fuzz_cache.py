"""Fuzzing the scene cache: Hypothesis damages a stored entry (truncates a file, flips bits,
overwrites bytes, deletes files, stores other valid arrays, edits the metadata or the manifest as
JSON, puts another scene's entry or a file in its place, several of these at once), then runs the
scene again.  Every damage must be detected (one :class:`~symrb.errors.CacheWarning`), the scene
recomputed with the right numbers (bit for bit those of an uncached run), the entry repaired (the
next run loads it, silently), and nothing may raise.

CI's derandomised profile (tests/conftest.py) runs the same examples every time, in about 15 s.
"""

from __future__ import annotations

import io
import json
import shutil
import tempfile
import warnings
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import assume, event, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from scene_helpers import same as _same

from symrb.errors import CacheWarning
from symrb.scenes import SceneStore, parse_scene, run_scene, scene_key

FILES = ("arrays.npz", "scene.json", "manifest.json")

SCENE = parse_scene({
    "system": "rigid_body", "effects": ["attitude"],
    "parameters": {"n": 3, "seed": 5},
    "integrator": {"method": "DOP853"}, "horizon": {"T": 1.0},
    "observables": {"energy": {"points": 4}, "Q": "end", "M": {"points": 2}},
})  # fmt: skip
OTHER = parse_scene({**SCENE.model_dump(mode="json", exclude_unset=True),
                     "parameters": {"n": 3, "seed": 6}})  # fmt: skip
KEY = scene_key(SCENE)
EXPECTED = run_scene(SCENE, cache=False)


@pytest.fixture(scope="module")
def pristine() -> Any:
    """A store holding the entries of SCENE and OTHER, made once and copied per example."""
    with tempfile.TemporaryDirectory() as d:
        for sc in (SCENE, OTHER):
            run_scene(sc, cache=d)
        yield Path(d)


Damage = Callable[[Path], None]  # applied to the entry directory


def _named(fn: Damage, kind: str) -> Damage:
    fn.__name__ = fn.__qualname__ = kind
    return fn


def _truncate(name: str, frac: float) -> Damage:
    def apply(entry: Path) -> None:
        raw = (entry / name).read_bytes()
        (entry / name).write_bytes(raw[: int(frac * len(raw))])

    return _named(apply, f"truncate {name}")


def _flip(name: str, where: float, bit: int) -> Damage:
    def apply(entry: Path) -> None:
        raw = bytearray((entry / name).read_bytes())
        raw[min(int(where * len(raw)), len(raw) - 1)] ^= 1 << bit
        (entry / name).write_bytes(bytes(raw))

    return _named(apply, f"flip a bit of {name}")


def _overwrite(name: str, where: float, data: bytes) -> Damage:
    def apply(entry: Path) -> None:
        raw = bytearray((entry / name).read_bytes())
        i = min(int(where * len(raw)), len(raw) - 1)
        new = raw[:i] + data + raw[i + len(data) :]
        assume(new != raw)
        (entry / name).write_bytes(bytes(new))

    return _named(apply, f"overwrite bytes of {name}")


def _delete(name: str) -> Damage:
    return _named(lambda entry: (entry / name).unlink(), f"delete {name}")


def _npz_arrays(entry: Path) -> dict[str, np.ndarray]:
    with np.load(io.BytesIO((entry / "arrays.npz").read_bytes())) as z:  # no file left open
        return {k: z[k] for k in z.files}


def _write_npz(entry: Path, arrays: dict[str, np.ndarray]) -> None:
    buf = io.BytesIO()
    np.savez(buf, **arrays)  # type: ignore[arg-type]
    (entry / "arrays.npz").write_bytes(buf.getvalue())


@st.composite
def _other_arrays(draw: st.DrawFn) -> Damage:
    """A valid npz: one array replaced by others of the same shape and dtype, or an array
    dropped, added or renamed."""
    names = sorted(EXPECTED_ARRAYS)
    name = draw(st.sampled_from(names))
    how = draw(st.sampled_from(["values", "drop", "add", "rename", "reshape"]))
    old = EXPECTED_ARRAYS[name]
    values = draw(hnp.arrays(old.dtype, old.shape, elements=st.floats(-1e3, 1e3, width=64)))
    if how == "values":
        assume(values.tobytes() != old.tobytes())

    def apply(entry: Path) -> None:
        arrays = _npz_arrays(entry)
        if how == "values":
            arrays[name] = values
        elif how == "drop":
            del arrays[name]
        elif how == "add":
            arrays["data/extra"] = values
        elif how == "rename":
            arrays["data/renamed"] = arrays.pop(name)
        else:
            arrays[name] = old.reshape(-1)
            assume(old.ndim != 1)
        _write_npz(entry, arrays)

    return _named(apply, f"valid npz, an array: {how}")


JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers(-5, 5) | st.floats(-1e3, 1e3) | st.text(max_size=5),
    lambda inner: (
        st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=4), inner, max_size=3)
    ),
    max_leaves=5,
)


def _paths(doc: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Every path to a value inside a JSON document."""
    out = [prefix]
    if isinstance(doc, dict):
        for k, v in doc.items():
            out += _paths(v, (*prefix, k))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            out += _paths(v, (*prefix, i))
    return out


@st.composite
def _json_edit(draw: st.DrawFn, name: str) -> Damage:
    """Valid JSON that differs: one value anywhere in the document replaced, or removed."""
    choice = draw(st.integers(0, 10**6))
    value = draw(JSON_VALUES)
    remove = draw(st.booleans())

    def apply(entry: Path) -> None:
        doc = json.loads((entry / name).read_text())
        paths = [p for p in _paths(doc) if p]
        path = paths[choice % len(paths)]
        node = doc
        for part in path[:-1]:
            node = node[part]
        if remove:
            del node[path[-1]]
        else:
            assume(node[path[-1]] != value or type(node[path[-1]]) is not type(value))
            node[path[-1]] = value
        (entry / name).write_text(json.dumps(doc))

    return _named(apply, f"valid JSON, {name} edited")


def _from_other(names: tuple[str, ...]) -> Damage:
    """Files (or all of them) of another scene's valid entry copied in."""

    def apply(entry: Path) -> None:
        src = entry.parent.parent / scene_key(OTHER)[:2] / scene_key(OTHER)
        for name in names:
            shutil.copyfile(src / name, entry / name)

    return _named(apply, f"another scene's {' + '.join(sorted(names))}")


def _replace_by_file(entry: Path) -> None:
    shutil.rmtree(entry)
    entry.write_bytes(b"")


_named(_replace_by_file, "entry directory replaced by a file")


FILE = st.sampled_from(FILES)
FRACTION = st.floats(0.0, 1.0, exclude_max=True)
DAMAGE = st.one_of(
    st.builds(_truncate, FILE, FRACTION),
    st.builds(_flip, FILE, FRACTION, st.integers(0, 7)),
    st.builds(_overwrite, FILE, FRACTION, st.binary(min_size=1, max_size=64)),
    st.builds(_delete, FILE),
    _other_arrays(),
    _json_edit("scene.json"),
    _json_edit("manifest.json"),
    st.builds(_from_other, st.lists(FILE, min_size=1, max_size=3, unique=True).map(tuple)),
    st.just(_replace_by_file),
)

EXPECTED_ARRAYS = {f"data/{k}": a for k, a in EXPECTED.data.items()}
EXPECTED_ARRAYS.update({f"times/{k}": a for k, a in EXPECTED.times.items()})


def _run(root: Path) -> tuple[Any, list[str]]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = run_scene(SCENE, cache=root)
    return r, [str(w.message) for w in caught if issubclass(w.category, CacheWarning)]


def _expected(r: Any) -> None:
    assert sorted(r.data) == sorted(EXPECTED.data)
    for k in EXPECTED.data:
        _same(r[k], EXPECTED[k])
        _same(r.times[k], EXPECTED.times[k])
    assert r.meta["success"] and r.meta["key"] == KEY


@settings(max_examples=100)
@given(damages=st.lists(DAMAGE, min_size=1, max_size=3))
def test_every_damaged_entry_is_detected_recomputed_and_repaired(pristine, damages) -> None:
    with tempfile.TemporaryDirectory() as d:
        root = Path(d) / "c"
        shutil.copytree(pristine, root)
        entry = SceneStore(root).path(KEY)
        before = {n: (entry / n).read_bytes() for n in FILES}
        for damage in damages:
            event(damage.__name__)
            try:
                damage(entry)
            except (OSError, ValueError, KeyError, IndexError, EOFError, zipfile.BadZipFile):
                pass  # it does not apply after an earlier one (the file is gone or unreadable)
        after = {n: (entry / n).read_bytes() if (entry / n).is_file() else None for n in FILES}
        assume(after != before)  # e.g. a file copied from OTHER that is the same
        r, caught = _run(root)
        assert not r.meta["from_cache"] and len(caught) == 1, caught
        assert "damaged" in caught[0]
        _expected(r)
        again, caught = _run(root)
        assert again.meta["from_cache"] and not caught, caught
        _expected(again)
        assert sorted(p.name for p in entry.parent.iterdir()) == [KEY]  # nothing left over


@settings(max_examples=30)
@given(garbage=st.binary(max_size=200), name=FILE)
def test_an_entry_of_garbage_is_recomputed(pristine, garbage, name) -> None:
    """A file of an entry that is anything at all (empty, random bytes)."""
    with tempfile.TemporaryDirectory() as d:
        root = Path(d) / "c"
        shutil.copytree(pristine, root)
        (SceneStore(root).path(KEY) / name).write_bytes(garbage)
        r, caught = _run(root)
        assert not r.meta["from_cache"] and len(caught) == 1, caught
        _expected(r)


@settings(max_examples=40)
@given(name=st.sampled_from(sorted(EXPECTED_ARRAYS)), where=FRACTION,
       how=st.sampled_from(["one ulp", "sign", "value"]), value=st.floats(-1e3, 1e3))  # fmt: skip
def test_other_numbers_in_a_valid_npz_are_never_served(pristine, name, where, how, value) -> None:
    """One entry of one array changed (by one unit in the last place, its sign, or to another
    number) in an npz that is otherwise the stored one: detected, not served."""
    old = EXPECTED_ARRAYS[name]
    new = old.copy().reshape(-1)
    i = min(int(where * new.size), new.size - 1)
    new[i] = {"one ulp": np.nextafter(new[i], np.inf), "sign": -new[i], "value": value}[how]
    assume(new.tobytes() != old.reshape(-1).tobytes())
    with tempfile.TemporaryDirectory() as d:
        root = Path(d) / "c"
        shutil.copytree(pristine, root)
        entry = SceneStore(root).path(KEY)
        arrays = _npz_arrays(entry)
        arrays[name] = new.reshape(old.shape)
        _write_npz(entry, arrays)
        r, caught = _run(root)
        assert not r.meta["from_cache"] and len(caught) == 1, caught
        _expected(r)
