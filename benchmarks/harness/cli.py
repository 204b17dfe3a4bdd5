"""The command line ``symrb bench``."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

from symrb.errors import InputError

from .config import SECTIONS
from .runner import run

_EXIT = """\
exit status:
  0 the benchmarks ran (goals not met are reported, not failures, unless --strict)
  1 with --strict: a measured goal was not met
  2 usage or environment (bad arguments, an unreadable --verify-json, matplotlib missing for
    --plots)
"""


def build_parser(prog: str = "symrb bench") -> argparse.ArgumentParser:
    """The parser of ``symrb bench``."""
    parser = argparse.ArgumentParser(
        prog=prog,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description=(
            "Time symrb's rigid body integrators against SciPy (work-precision, long-time\n"
            "invariants, throughput, cost against n, evidence, step costs, long horizon, cold\n"
            "start) and report the goals of issues 9 and 23.\n"
            "Needs only NumPy and SciPy (threadpoolctl pins BLAS to one thread; tqdm shows\n"
            "progress; matplotlib draws --plots)."
        ),
        epilog=_EXIT,
    )
    parser.add_argument("--quick", action="store_true", help="a short run (about 30 s)")
    parser.add_argument("--json", metavar="PATH", help="write the results as JSON to PATH")
    parser.add_argument("--plots", metavar="DIR", help="write PNG and SVG diagrams into DIR")
    parser.add_argument(
        "--only", nargs="+", metavar="SECTION", help=f"only these sections: {', '.join(SECTIONS)}"
    )
    parser.add_argument("--methods", nargs="+", metavar="NAME", help="only these methods")
    parser.add_argument("--verify-json", metavar="PATH", help="symrb verify --json output")
    parser.add_argument("--no-progress", action="store_true", help="no progress output")
    parser.add_argument("--strict", action="store_true", help="exit 1 when a goal is not met")
    return parser


def main(argv: Sequence[str] | None = None, prog: str = "symrb bench") -> int:
    """Run ``symrb bench`` with ``argv``; returns the exit status (0, 1 or 2, see ``--help``).

    Parameters
    ----------
    argv : sequence of str, optional
        The arguments after ``bench`` (default ``sys.argv[1:]``).
    prog : str, optional
        The program name shown in the usage.

    Returns
    -------
    int
        0 the benchmarks ran, 1 with ``--strict`` a measured goal was not met, 2 bad usage or
        environment.

    Examples
    --------
    >>> from benchmarks.harness import main
    >>> main(["--only", "no-such-section"])  # the reason goes to stderr
    2
    """
    parser = build_parser(prog)
    try:
        args = parser.parse_args(list(sys.argv[1:] if argv is None else argv))
    except SystemExit as exc:
        return int(exc.code or 0) if not isinstance(exc.code, str) else 2
    if args.plots:
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            print(f"{prog} --plots needs matplotlib: pip install matplotlib", file=sys.stderr)
            return 2
    if args.verify_json and not Path(args.verify_json).is_file():
        print(f"{prog}: --verify-json {args.verify_json}: no such file", file=sys.stderr)
        return 2
    try:
        res = run(
            quick=args.quick,
            methods=args.methods,
            progress=not args.no_progress,
            sections=args.only,
            verify_json=args.verify_json,
            checkpoint=args.json,
        )
    except InputError as exc:
        print(f"{prog}: {exc}", file=sys.stderr)
        return 2
    except (OSError, json.JSONDecodeError) as exc:
        print(f"{prog}: {exc}", file=sys.stderr)
        return 2
    print(res.summary())
    for note in res.notes:
        print(f"note: {note}")
    if args.json:
        print(f"wrote {res.write_json(args.json)}")
    if args.plots:
        for f in res.plot(args.plots):
            print(f"wrote {f}")
    unmet = [g for g in res.goals if g["met"] is False]
    return 1 if args.strict and unmet else 0
