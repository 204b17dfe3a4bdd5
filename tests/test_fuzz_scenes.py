"""A fuzz suite for scene documents (issue 22): Hypothesis writes scene documents, valid and
broken (every key of every system's schema given a value allowed or not, extreme numbers, wrong
types, keys dropped or unknown, TOML syntax errors, bytes that are not text), and runs each
through the ``symrb run`` entry point in-process.  Every example must end in exit 0 with finite
observables, exit 1 (a run that stopped early, with its message; nothing non-finite served as a
success) or exit 2 with a message; never a traceback (any other exception), a hang (an alarm
after 30 s) or non-finite numbers in an accepted run.  The bases are the book's scenes made small
(a short horizon, every observable at the end), so valid examples are quick; the run is given a
budget of 2 s and 64 MiB, so a mutation asking for much is refused by the budget.  Derandomised
under the CI profile (tests/conftest.py); the counts are printed (``pytest -s``)."""

from __future__ import annotations

import contextlib
import io
import json
import math
import signal
import sys
import tempfile
import tomllib
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symrb.cli import main
from symrb.scenes import describe_schema, run_scene

ROOT = Path(__file__).resolve().parents[1]
#: the book's scenes that run in well under a second once made small
BASES = ("double_bracket", "hamiltonian_on_gl", "hamiltonian_on_so", "long_run_near_equal_n3",
         "manakov_drift", "mv_energy", "norm_conservation", "norm_conservation_boundary",
         "orbit_two_samples", "resnet_training", "rigid_body_attitude", "rigid_body_momentum",
         "symmetric_vs_rigid_body", "toda_lattice", "toy_training", "agreement_symmetric")  # fmt: skip
BUDGET = ["--max-seconds", "2", "--max-memory", "64M"]
#: what the examples ended in, by test: exit 0, 1, 2
COUNTS: dict[str, Counter[str]] = {}


def _small(name: str) -> dict[str, Any]:
    """A book scene with a short horizon and every observable at the end."""
    d = tomllib.loads((ROOT / "book" / "scenes" / f"{name}.toml").read_text())
    d.pop("title", None)
    h, step = d["horizon"], d.get("integrator", {}).get("h")
    if "T" in h:
        h["T"] = 4 * step if isinstance(step, float) else 0.5
    else:
        h["steps"] = min(h["steps"], 3)
    d["observables"] = {k: "end" for k in d["observables"]}
    return d


SMALL = {name: _small(name) for name in BASES}
KEYS = [k for k in describe_schema() if k.key != "system"]

EXTREME = st.sampled_from([
    0.0, -0.0, 1.0, -1.0, 0.5, 3, -1, 0, 2, 1e-300, 5e-324, 1e-12, 1e12, 1e13, 1e300, -1e300,
    math.nan, math.inf, -math.inf, 2**63 - 1, -(2**63), 10**9, 5000,
])  # fmt: skip
WRONG = st.sampled_from(["5", "", "abc", "0.05", "end", True, False, [], [1.0, "x"],
                         [[0.0, 1.0], [1.0]], [[1e300]], {}, {"points": 3}, {"bogus": 1},
                         [math.nan, 1.0, 2.0], [1.0, 2.0], [0.0, 0.0, 0.0]])  # fmt: skip


def _value(text: str) -> Any:
    return tomllib.loads(f"v = {text}")["v"]


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return (
            "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf") if math.isinf(v) else repr(v)
        )
    if isinstance(v, int):
        return str(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return "{" + ", ".join(f"{json.dumps(k)} = {_toml_value(x)}" for k, x in v.items()) + "}"


def to_toml(doc: dict[str, Any]) -> str:
    """A TOML text of ``doc``: scalars first, then one ``[table]`` per table (inner tables
    inline)."""
    top = [f"{json.dumps(k)} = {_toml_value(v)}" for k, v in doc.items() if not isinstance(v, dict)]
    tables = [f"[{json.dumps(k)}]\n" + "\n".join(f"{json.dumps(a)} = {_toml_value(b)}"
                                                 for a, b in v.items())
              for k, v in doc.items() if isinstance(v, dict)]  # fmt: skip
    return "\n".join(top) + "\n" + "\n".join(tables) + "\n"


@st.composite
def documents(draw: st.DrawFn, broken: bool) -> dict[str, Any]:
    """A small book scene; ``broken``: then one to three of its keys set (to a value the schema
    allows, an extreme number or a wrong type), dropped, or an unknown key added."""
    doc = json.loads(json.dumps(SMALL[draw(st.sampled_from(BASES))]))
    if not broken:  # another seed, where the scene has one
        params = doc.get("parameters", {})
        if "seed" in params or any(k.key == "seed" and k.table == "parameters" and
                                   k.system == doc["system"] for k in KEYS):  # fmt: skip
            params["seed"] = draw(st.integers(0, 2**32))
            doc["parameters"] = params
        return doc
    keys = [k for k in KEYS if k.system == doc["system"]]
    for _ in range(draw(st.integers(1, 3))):
        k = draw(st.sampled_from(keys))
        path = [p for p in k.table.split(".") if p] + [k.key]
        choice = draw(st.sampled_from(["allowed", "extreme", "wrong", "drop", "unknown"]))
        if choice == "allowed" and k.allowed:
            val: Any = _value(draw(st.sampled_from(list(k.allowed))))
        elif choice in ("extreme", "allowed"):
            val = draw(EXTREME)
        elif choice == "wrong":
            val = draw(WRONG)
        else:
            val = None
        node = doc
        for p in path[:-1]:
            if not isinstance(node.get(p), dict):
                node[p] = {}
            node = node[p]
        if choice == "drop":
            node.pop(path[-1], None)
        elif choice == "unknown":
            node["bogus_" + path[-1]] = 1
        else:
            node[path[-1]] = val
    return doc


class Hang(BaseException):
    """An example that ran over the alarm."""


def _alarm(signum: int, frame: Any) -> None:
    raise Hang("an example ran over 30 s")


def _run(text: str | bytes, tag: str) -> None:
    """Run one document through ``symrb run`` and check how it ended."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "scene.toml"
        path.write_bytes(text if isinstance(text, bytes) else text.encode())
        out, err = io.StringIO(), io.StringIO()
        old = signal.signal(signal.SIGALRM, _alarm)
        signal.alarm(30)
        try:
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                rc = main(["run", str(path), "--cache", tmp, *BUDGET])
        finally:
            signal.alarm(0)
            signal.signal(signal.SIGALRM, old)
        o, e = out.getvalue(), err.getvalue()
        COUNTS.setdefault(tag, Counter())[f"exit {rc}"] += 1
        assert "Traceback" not in e
        if rc == 2:
            assert e.strip() and "\n\n" not in e.strip(), e
            assert e.startswith(("invalid ", "symrb run: ")), e
        elif rc == 1:
            assert "result      computed" in o and "; ok" not in o, o
        else:
            assert rc == 0, (rc, e)
            r = run_scene(path, cache=tmp, max_seconds=2, max_memory=64 * 2**20)
            assert r.meta["from_cache"] and r.meta["success"]
            for name, a in r.data.items():
                arr = np.asarray(a)
                assert arr.dtype.kind not in "fc" or np.isfinite(arr).all(), name


pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="SIGALRM")


@settings(max_examples=60)
@given(documents(broken=False))
def test_valid_documents_run_to_finite_results(doc) -> None:
    _run(to_toml(doc), "valid")


@settings(max_examples=300)
@given(documents(broken=True))
def test_broken_documents_are_refused_cleanly(doc) -> None:
    _run(to_toml(doc), "broken")


@settings(max_examples=120)
@given(documents(broken=False), st.data())
def test_toml_syntax_errors_and_bytes_are_refused_cleanly(doc, data) -> None:
    """A valid text cut, spliced with characters TOML does not allow, or given bytes that are
    not UTF-8."""
    text = to_toml(doc).encode()
    how = data.draw(st.sampled_from(["cut", "splice", "bytes"]))
    at = data.draw(st.integers(0, len(text)))
    if how == "cut":
        text = text[:at]
    elif how == "splice":
        junk = data.draw(st.sampled_from([b"[", b"]]", b"=", b'"', b"\x00", b"= =", b"{", b"\n[a\n",
                                          b"x = 1\nx = 2\n", b"\xff\xfe"]))  # fmt: skip
        text = text[:at] + junk + text[at:]
    else:
        text = data.draw(st.binary(min_size=1, max_size=64))
    _run(text, "syntax")


def test_counts() -> None:
    """The counts of the tests above (in this process), printed for the report."""
    for tag, c in sorted(COUNTS.items()):
        print(f"fuzz {tag}: {sum(c.values())} examples, {dict(sorted(c.items()))}")
