"""The development commands: ``derive`` (write or check ``symrb/_generated``) and ``verify``.

Reached as ``symrb derive`` / ``symrb verify`` or ``python -m derivations derive`` / ``verify``.
Exit status: 0 success; 1 a generated file differs from its derivation (``derive --check``) or a
claim's computed outcome differs from the recorded one (``verify``); 2 bad usage.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any


def _cmd_derive(args: argparse.Namespace) -> int:
    if os.environ.get("PYTHONHASHSEED") != "0":
        # printing must not depend on string hashing: rerun with a fixed seed
        env = dict(os.environ, PYTHONHASHSEED="0")
        argv = [sys.executable, "-m", "derivations", "derive"]
        argv += ["--check"] if args.check else []
        argv += ["--only", *args.only] if args.only else []
        argv += ["--target", str(args.target)] if args.target else []
        return subprocess.run(argv, env=env, check=False).returncode
    from derivations.codegen import emit_all

    try:
        return emit_all(check=args.check, target=args.target, only=args.only)
    except KeyError as exc:
        print(exc.args[0], file=sys.stderr)
        return 2


def _fmt_seconds(s: float) -> str:
    return f"{s:.2f}s" if s >= 0.01 else f"{s * 1000:.1f}ms"


def _progress(claim: Any) -> None:
    print(f"  {claim.id} ...", end="", flush=True, file=sys.stderr)


def _cmd_verify(args: argparse.Namespace) -> int:
    from derivations.registry import kernel_report, verify

    try:
        results = verify(
            args.ids or None,
            progress=_progress if args.progress else None,
            fail_fast=args.fail_fast,
        )
    except KeyError as exc:
        print(exc.args[0], file=sys.stderr)
        return 2
    if args.progress:
        print(file=sys.stderr)
    complete = not args.ids and len(results) == len(_all_ids())
    kernels = kernel_report()
    unchecked = []
    if complete:
        unchecked = [k for k in kernels if set(k["claims"]) - set(k["checked_by"])]
    from derivations.report import source_hash

    payload = {
        "source_hash": source_hash(),
        "claims": [r.to_dict() for r in results],
        "kernels": kernels,
    }
    if args.output:
        Path(args.output).parent.mkdir(parents=True, exist_ok=True)
        Path(args.output).write_text(json.dumps(payload, indent=1) + "\n")
    if args.json:
        print(json.dumps(payload, indent=1))
    else:
        _print_table(results, unchecked)
    ok = all(r.ok for r in results) and not unchecked
    return 0 if ok else 1


def _all_ids() -> list[str]:
    from derivations.registry import all_claims

    return [c.id for c in all_claims()]


def _print_table(results: Sequence[Any], unchecked: Sequence[dict[str, Any]]) -> None:
    header = f"{'ID':<4} {'outcome':<24} {'as recorded':<12} evidence (level: residual / tol, time)"
    print(header)
    print("-" * len(header))
    for r in results:
        print(f"{r.id:<4} {r.outcome:<24} {'yes' if r.ok else 'NO':<12} {len(r.evidence)} checks, "
              f"{_fmt_seconds(r.seconds)}")  # fmt: skip
        for e in r.evidence:
            if e.as_expected and r.ok:
                continue
            form = "" if e.form == "claim" else f" [{e.form}]"
            status = e.error or f"{e.residual:.2e} / {e.tol:.0e}"
            print(f"       unexpected{form} {e.level}: {status}  ({e.name}: {e.description[:80]})")
    for k in unchecked:
        print(
            f"kernel {k['kernel']} names claims {k['claims']} but only {k['checked_by']} "
            "evaluated its expressions"
        )
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


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="symrb", description="Derive symrb's kernels and verify the claims of the paper."
    )
    sub = parser.add_subparsers(dest="command", required=True)
    p_derive = sub.add_parser("derive", help="regenerate symrb/_generated from derivations/")
    p_derive.add_argument("--check", action="store_true", help="only diff; exit 1 on a difference")
    p_derive.add_argument(
        "--only", nargs="+", metavar="TARGET", help="only these generated modules"
    )
    p_derive.add_argument("--target", type=Path, help="write into this directory instead")
    p_derive.set_defaults(func=_cmd_derive)
    p_verify = sub.add_parser("verify", help="check the claims of the paper")
    p_verify.add_argument("ids", nargs="*", help="claim IDs (default: all), e.g. S1 S4 D10")
    p_verify.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p_verify.add_argument("--output", help="also write the JSON to this file")
    p_verify.add_argument("--progress", action="store_true", help="show each claim as it starts")
    p_verify.add_argument(
        "--fail-fast", action="store_true", help="stop at the first claim whose outcome differs"
    )
    p_verify.set_defaults(func=_cmd_verify)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return int(args.func(args))
