"""``symrb run`` and ``symrb sweep``: scenes from the command line (see :mod:`symrb.scenes`).

Exit status: 0 done; 1 a run whose integrator stopped early or whose observables are not
finite (nothing is stored); 2 usage, an invalid scene (the message names the key, its line and
the allowed values, whether found while reading, planning or running it), an estimate over the
budget (``--max-seconds``, ``--max-memory``), or a missing optional package; 130 interrupted
(Ctrl-C: "interrupted; k of m points kept", the points finished before it are in the cache);
141 the reader of the output went away (``symrb run S | head -1``).  No error prints a
traceback unless ``SYMRB_TRACEBACK=1`` is set.
"""

from __future__ import annotations

import argparse
import math
import os
import re
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from .errors import InputError

#: the units of --max-memory
_UNITS = {"": 1, "K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}


def _seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"a positive number of seconds, got {text!r}")
    return value


def _bytes(text: str) -> float:
    m = re.fullmatch(r"\s*([0-9.eE+]+)\s*([KMGT]?)(i?B)?\s*", text, flags=re.IGNORECASE)
    try:
        value = float(m.group(1)) * _UNITS[m.group(2).upper()] if m else math.nan
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"a size such as 4G, 512M or 1e9 (bytes), got {text!r}")
    return value


def _cache_help() -> str:
    try:
        from symrb.scenes.store import cache_help
    except ImportError:  # pragma: no cover - no pydantic: main says so
        return "the cache directory"
    return cache_help().replace("%", "%%")


def _parser(cmd: str) -> argparse.ArgumentParser:
    if cmd == "run":
        p = argparse.ArgumentParser(
            prog="symrb run", description="Plan and run a scene (results are cached)."
        )
        p.add_argument("scene", help="the scene, a TOML file")
        p.add_argument("--explain", action="store_true", help="print the plan and stop")
        p.add_argument("--plot", action="store_true",
                       help="save a figure (SCENE.png): the relative drift of the invariants "
                       "on a log axis, the other observables recorded over time")  # fmt: skip
    else:
        p = argparse.ArgumentParser(
            prog="symrb sweep",
            description="Run a scene over a grid: one table (table.csv) plus the arrays.",
        )
        p.add_argument("scene", help="the base scene, a TOML file")
        p.add_argument(
            "--grid",
            action="append",
            required=True,
            metavar="KEY=V1,V2,...",
            help="a dotted key and its values (repeat for a product grid)",
        )
        where = p.add_mutually_exclusive_group()
        where.add_argument("--scheduler", metavar="ADDRESS", help="a dask.distributed scheduler")
        where.add_argument(
            "--local-cluster", type=int, metavar="N", help="start a LocalCluster of N workers"
        )
        p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--out", metavar="DIR", help="write the results (npz + JSON) here")
    p.add_argument("--cache", metavar="DIR", help=_cache_help())
    p.add_argument("--no-cache", action="store_true", help="neither read nor write the cache")
    p.add_argument("--max-seconds", type=_seconds, metavar="S",
                   help="refuse a scene (a grid point) whose estimated run time is over S seconds "
                   "(default 600)")  # fmt: skip
    p.add_argument("--max-memory", type=_bytes, metavar="SIZE",
                   help="refuse a scene whose estimated saved states are over SIZE (4G, 512M; "
                   "default 2G)")  # fmt: skip
    return p


def main(cmd: str, argv: Sequence[str]) -> int:
    """Run ``symrb run`` (``cmd = "run"``) or ``symrb sweep`` with ``argv``; the exit status."""
    args = _parser(cmd).parse_args(list(argv))
    try:
        from symrb import scenes
    except ImportError as exc:  # pragma: no cover - depends on the environment
        print(f"symrb {cmd} needs pydantic: pip install pydantic ({exc})", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # Ctrl-C while importing
        print(f"interrupted; 0 of 1 point{'s' * (cmd == 'sweep')} kept", file=sys.stderr)
        return 130
    try:
        return _run(args) if cmd == "run" else _sweep(args)
    except KeyboardInterrupt as exc:
        kept, total = getattr(exc, "kept", 0), getattr(exc, "total", 1)
        print(f"interrupted; {kept} of {total} point{'s' * (total != 1)} kept", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the reader went away (| head): no more output, no traceback
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 141
    except scenes.SceneError as exc:
        print(_with_lines(exc, args.scene), file=sys.stderr)
        return 2
    except (InputError, ImportError, OSError) as exc:
        print(f"symrb {cmd}: {exc}", file=sys.stderr)
        return 2
    except (ArithmeticError, ValueError, MemoryError, RecursionError) as exc:
        # a numerical failure the checks of the scene did not foresee: still a message
        if os.environ.get("SYMRB_TRACEBACK"):
            raise
        print(f"symrb {cmd}: the run of {args.scene} failed: {type(exc).__name__}: {exc}. The "
              "scene's numbers are beyond what its integrator handles; try smaller initial "
              "data, step or horizon (SYMRB_TRACEBACK=1 shows where)", file=sys.stderr)  # fmt: skip
        return 2


def _with_lines(exc: Any, path: str) -> str:
    """The message of a SceneError found after reading (no lines, no file name) with both."""
    from symrb.scenes import SceneError
    from symrb.scenes.parse import _toml_lines

    if all(p.get("line") for p in exc.problems) and not str(exc).startswith("invalid scene:"):
        return str(exc)
    try:
        lines = _toml_lines(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return str(exc)
    problems = []
    for p in exc.problems:
        parts, line = tuple(str(p["key"]).split(".")), p.get("line")
        for cut in range(len(parts), 0, -1):
            line = line or lines.get(parts[:cut])
        problems.append({**p, "line": line})
    source = str(exc).split(":", 1)[0].removeprefix("invalid ")
    return str(SceneError(problems, Path(path).name if source == "scene" else source))


def _budget(args: argparse.Namespace) -> dict[str, float]:
    from symrb.scenes.plan import MAX_MEMORY, MAX_SECONDS

    return {"max_seconds": args.max_seconds or MAX_SECONDS,
            "max_memory": args.max_memory or MAX_MEMORY}  # fmt: skip


def _run(args: argparse.Namespace) -> int:
    """``symrb run``: check everything a run checks (the scene, its plan, its budget, its
    initial data), print the plan, and unless ``--explain`` run it."""
    from symrb import scenes
    from symrb.scenes.plan import Budget

    cache: object = False if args.no_cache else (args.cache or True)
    budget = _budget(args)
    scene = scenes.load_scene(Path(args.scene))
    plan = scenes.plan_scene(scene, budget=Budget(budget["max_seconds"], budget["max_memory"]))
    Budget(budget["max_seconds"], budget["max_memory"]).check(plan)
    scenes.scene_inputs(scene)
    print(plan.explain())
    if args.explain:
        return 0
    result = scenes.run_scene(scene, cache=cache, **budget)  # type: ignore[arg-type]
    m = result.meta
    how = "loaded from the cache" if m["from_cache"] else f"computed in {m['seconds']:.3g} s"
    print(f"result      {how}; key {m['key'][:16]}; {m['message']}")
    for name, a in result.data.items():
        print(f"  {name:14s} shape {tuple(a.shape)}")
    out = Path(args.out) if args.out else None
    if out is not None:
        print(f"written     {result.save(out)}")
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        target = (out or Path(".")) / (Path(args.scene).stem + ".png")
        target.parent.mkdir(parents=True, exist_ok=True)
        result.plot().savefig(target, dpi=120)
        print(f"figure      {target}")
    return 0 if m["success"] else 1


def _sweep(args: argparse.Namespace) -> int:
    """``symrb sweep``: every grid point checked before the first runs, then run."""
    from symrb import scenes

    cache: object = False if args.no_cache else (args.cache or True)
    try:
        import tqdm  # noqa: F401

        progress = not args.no_progress
    except ImportError:  # pragma: no cover
        progress = False
    scene = scenes.load_scene(Path(args.scene))
    budget = _budget(args)
    res = scenes.sweep(scene, args.grid, cache=cache,  # type: ignore[arg-type]
                       scheduler=args.scheduler, local_cluster=args.local_cluster,
                       progress=progress, max_seconds=budget["max_seconds"],
                       max_memory=budget["max_memory"])  # fmt: skip
    import pandas as pd

    with pd.option_context("display.width", 120, "display.max_columns", 20):
        print(res.table.to_string(index=False))
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        res.table.to_csv(out / "table.csv", index=False)
        for r in res.results:
            r.save(out / r.meta["key"][:16])
        print(f"written     {out / 'table.csv'} and {len(res.results)} result directories")
    return 0 if all(r.meta["success"] for r in res.results) else 1
