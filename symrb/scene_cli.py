"""``symrb run`` and ``symrb sweep``: scenes from the command line (see :mod:`symrb.scenes`).

Exit status: 0 done; 1 a run whose integrator stopped early; 2 usage, an invalid scene (the
message names the key, its line and the allowed values) or a missing optional package.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from .errors import InputError


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
    return p


def main(cmd: str, argv: Sequence[str]) -> int:
    """Run ``symrb run`` (``cmd = "run"``) or ``symrb sweep`` with ``argv``; the exit status."""
    args = _parser(cmd).parse_args(list(argv))
    try:
        from symrb import scenes
    except ImportError as exc:  # pragma: no cover - depends on the environment
        print(f"symrb {cmd} needs pydantic: pip install pydantic ({exc})", file=sys.stderr)
        return 2
    cache: object = False if args.no_cache else (args.cache or True)
    try:
        scene = scenes.load_scene(Path(args.scene))
        plan = scenes.plan_scene(scene)
    except scenes.SceneError as exc:
        print(exc, file=sys.stderr)
        return 2
    except InputError as exc:
        print(f"symrb {cmd}: {exc}", file=sys.stderr)
        return 2
    if cmd == "run":
        print(plan.explain())
        if args.explain:
            return 0
        result = scenes.run_scene(scene, cache=cache)  # type: ignore[arg-type]
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
    try:
        import tqdm  # noqa: F401

        progress = not args.no_progress
    except ImportError:  # pragma: no cover
        progress = False
    try:
        res = scenes.sweep(
            scene,
            args.grid,
            cache=cache,  # type: ignore[arg-type]
            scheduler=args.scheduler,
            local_cluster=args.local_cluster,
            progress=progress,
        )
    except scenes.SceneError as exc:
        print(exc, file=sys.stderr)
        return 2
    except ImportError as exc:
        print(f"symrb sweep: {exc}", file=sys.stderr)
        return 2
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
