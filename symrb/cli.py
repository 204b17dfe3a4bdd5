"""The ``symrb`` command line: ``symrb derive [--check]`` and ``symrb verify [IDS...] [--json]``.

Both commands are development tools: they import :mod:`derivations`, which needs SymPy
(``pip install 'symrb[derive]'``).  Importing :mod:`symrb` itself never imports SymPy.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path


def _need_derivations() -> None:
    try:
        import sympy  # noqa: F401
    except ImportError:  # pragma: no cover - depends on the environment
        sys.exit("symrb derive/verify need SymPy: pip install 'symrb[derive]'")


def _cmd_derive(args: argparse.Namespace) -> int:
    _need_derivations()
    if os.environ.get("PYTHONHASHSEED") != "0":
        # SymPy's printing order must not depend on string hashing: rerun with a fixed seed.
        env = dict(os.environ, PYTHONHASHSEED="0")
        argv = [sys.executable, "-m", "symrb.cli", "derive"] + (["--check"] if args.check else [])
        return subprocess.run(argv, env=env, check=False).returncode
    from derivations.codegen import emit_all

    return emit_all(check=args.check)


def _fmt_seconds(s: float) -> str:
    return f"{s:.2f}s" if s >= 0.01 else f"{s * 1000:.1f}ms"


def _cmd_verify(args: argparse.Namespace) -> int:
    _need_derivations()
    from derivations.registry import verify

    try:
        results = verify(args.ids or None, progress=not args.json and args.progress)
    except KeyError as exc:
        print(exc.args[0], file=sys.stderr)
        return 2
    payload = [r.to_dict() for r in results]
    if args.output:
        Path(args.output).parent.mkdir(parents=True, exist_ok=True)
        Path(args.output).write_text(json.dumps(payload, indent=1) + "\n")
    if args.json:
        print(json.dumps(payload, indent=1))
    else:
        header = (
            f"{'ID':<4} {'label':<28} {'outcome':<24} {'ok':<3} evidence (level: residual, time)"
        )
        print(header)
        print("-" * len(header))
        for r in results:
            ev = "; ".join(
                f"{e.level}{'' if e.form == 'claim' else ' [' + e.form + ']'}: "
                f"{e.residual:.1e} {_fmt_seconds(e.seconds)}"
                + (f" ERROR {e.error}" if e.error else "")
                for e in r.evidence
            )
            print(f"{r.id:<4} {r.label[:28]:<28} {r.outcome:<24} {'ok' if r.ok else 'NO':<3} {ev}")
        bad = [r.id for r in results if not r.ok]
        total = sum(r.seconds for r in results)
        print(
            f"\n{len(results)} claims checked in {total:.1f}s; "
            + (
                "all outcomes as recorded"
                if not bad
                else f"outcome differs from the record: {', '.join(bad)}"
            )
        )
    return 0 if all(r.ok for r in results) else 1


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="symrb", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    p_derive = sub.add_parser("derive", help="regenerate symrb/_generated from derivations/")
    p_derive.add_argument(
        "--check", action="store_true", help="only diff; exit 1 if anything would change"
    )
    p_derive.set_defaults(func=_cmd_derive)
    p_verify = sub.add_parser("verify", help="check the claims of the paper")
    p_verify.add_argument("ids", nargs="*", help="claim IDs (default: all), e.g. S1 S4 D10")
    p_verify.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p_verify.add_argument("--output", help="also write the JSON to this file")
    p_verify.add_argument("--progress", action="store_true", help="print each claim as it starts")
    p_verify.set_defaults(func=_cmd_verify)
    args = parser.parse_args(argv)
    return int(args.func(args))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
