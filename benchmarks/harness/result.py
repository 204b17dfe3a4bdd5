"""The result of a run: measurements, machine, parameters, goals; JSON in and out."""

from __future__ import annotations

import json
import math
import os
import textwrap
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from symrb.errors import InputError

from .plots import Style, _figures, _plot


@dataclass
class BenchResult:
    """The measurements of :func:`run`, with the machine, the parameters and the goals.

    Attributes
    ----------
    machine : dict
        Platform, CPU count, Python, NumPy/SciPy versions, BLAS libraries (threadpoolctl).
    parameters : dict
        The configuration run (grids, steps, rounds, methods, sections).
    measurements : dict
        One entry per section run (see :data:`SECTIONS`).
    goals : list of dict
        ``{name, measured, target, met, note}``; ``met`` is None when not measured.
    notes : list of str
        Warnings recorded during the run (missing optional methods, failures).
    seconds : float
        Wall time of the whole run.
    previous_goals : list of dict
        The goals (``name``, ``measured``, ``met``) of the run that the file written by
        ``symrb bench --json`` held before, so that a page can show each goal before and after.

    Examples
    --------
    >>> from benchmarks.harness import run
    >>> res = run(quick=True, sections=["cost-vs-n"], progress=False,
    ...           config={"cost_n": (3,), "rounds": 1, "min_time": 0.001})
    >>> sorted(res.to_dict())
    ['goals', 'machine', 'measurements', 'notes', 'parameters', 'previous_goals', 'seconds']
    >>> sorted(res.goals[0])
    ['measured', 'met', 'name', 'note', 'target']
    """

    machine: dict[str, Any]
    parameters: dict[str, Any]
    measurements: dict[str, Any] = field(default_factory=dict)
    goals: list[dict[str, Any]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    seconds: float = 0.0
    previous_goals: list[dict[str, Any]] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """The result as JSON-ready data."""
        return _jsonable(
            {
                "machine": self.machine,
                "parameters": self.parameters,
                "measurements": self.measurements,
                "goals": self.goals,
                "notes": self.notes,
                "seconds": self.seconds,
                "previous_goals": self.previous_goals,
            }
        )

    def write_json(self, path: str | os.PathLike[str]) -> Path:
        """Write :meth:`to_dict` to ``path`` (directories created); returns the path."""
        out = Path(path)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(self.to_dict(), indent=1, allow_nan=False) + "\n")
        return out

    def summary(self) -> str:
        """The goals as a plain-text table (100 columns)."""
        lines = [f"{'goal':<62} {'measured':>12} {'target':>12}  met"]
        for g in self.goals:
            m = g["measured"]
            ms = "-" if m is None else (m if isinstance(m, str) else f"{m:.3g}")
            met = {True: "yes", False: "NO", None: "-"}[g["met"]]
            name = textwrap.wrap(g["name"], 62) or [""]
            lines.append(f"{name[0]:<62} {ms:>12} {g['target'][:12]:>12}  {met}")
            lines += [f"  {more}" for more in name[1:]]
            if g["note"]:
                lines += textwrap.wrap(
                    g["note"], 100, initial_indent="    ", subsequent_indent="    "
                )
        return "\n".join(lines)

    def plot(self, directory: str | os.PathLike[str]) -> list[Path]:
        """PNG and SVG diagrams of the sections run (matplotlib, Agg backend); returns the files."""
        return _plot(self.measurements, Path(directory))

    def figures(self, *names: str, style: Style | None = None) -> dict[str, Any]:
        """The diagrams of the sections run as matplotlib figures, by name (``work_precision``,
        ``long_time``, ``throughput``, ``cost_vs_n``; all when no name is given), e.g. to show
        them in a notebook.  ``style(name, **variant)`` gives the keyword arguments of each
        series by its name (a method's or ``matmul``, ``goal``); the book passes its style
        table, so that a method has the same colour in all its figures."""
        return _figures(self.measurements, set(names), style)


def _jsonable(x: Any) -> Any:
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_jsonable(v) for v in x]
    if isinstance(x, set):
        return sorted(_jsonable(v) for v in x)
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def load(path: str | os.PathLike[str]) -> BenchResult:
    """Read a :class:`BenchResult` written by :meth:`BenchResult.write_json` (``--json``).

    Parameters
    ----------
    path : str or path-like
        The JSON file.

    Returns
    -------
    BenchResult

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from benchmarks.harness import load, run
    >>> res = run(quick=True, sections=["cost-vs-n"], progress=False,
    ...           config={"cost_n": (3,), "rounds": 1, "min_time": 0.001})
    >>> with tempfile.TemporaryDirectory() as d:
    ...     f = pathlib.Path(d) / "bench.json"
    ...     _ = res.write_json(f)
    ...     again = load(f)
    >>> again.goals == res.to_dict()["goals"]
    True
    """
    data = json.loads(Path(path).read_text())
    missing = {"machine", "parameters", "measurements", "goals"} - set(data)
    if missing:
        raise InputError(f"path {str(path)!r} is not a symrb bench result: no {sorted(missing)}")
    return BenchResult(
        machine=data["machine"],
        parameters=data["parameters"],
        measurements=data["measurements"],
        goals=data["goals"],
        notes=data.get("notes", []),
        seconds=float(data.get("seconds", 0.0)),
        previous_goals=data.get("previous_goals", []),
    )


def previous_goals(path: str | os.PathLike[str]) -> list[dict[str, Any]]:
    """The goals (name, measured, met) of the bench result at ``path``; [] when there is none."""
    try:
        old = load(path)
    except (OSError, ValueError, InputError, KeyError):
        return []
    if not old.goals:  # an interrupted run's checkpoint: keep what it kept
        return list(old.previous_goals)
    return [{"name": g["name"], "measured": g["measured"], "met": g["met"]} for g in old.goals]
