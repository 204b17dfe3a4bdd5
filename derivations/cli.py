"""The development commands of a source checkout: ``claims``, ``show``, ``verify`` and ``derive``.

Reached as ``symrb <command>`` or ``python -m derivations <command>``:

* ``claims`` lists the registered claims with their recorded outcomes (no evidence is run): the
  paper's claims, then the checks of symrb's own methods;
* ``show ID`` prints one claim for a terminal: where it is in the paper, the statement, the printed
  and corrected forms, the note, then its evidence with residual and tolerance;
* ``verify [IDS] [--group paper|method]`` runs the evidence, prints a progress line per claim on
  stderr and a table on stdout (one block per group), and fails when a computed outcome differs
  from the recorded one;
* ``derive [--check]`` writes (or only compares) ``symrb/_generated``;
* ``coverage`` runs every claim's evidence and lists which public numerical functions of symrb
  and which of their option values it reached (:mod:`derivations.coverage`); exit 1 when
  anything is unreached.  ``verify --output`` stores the same report in its JSON.

Exit status: 0 everything as recorded; 1 a surprise (a computed outcome differs from the record,
a kernel not evaluated by the claims it names, a stale generated file); 2 usage or environment
(bad arguments, an unknown claim).  Importing this module needs SymPy (the launchers
``symrb`` and ``python -m derivations`` say what to install when it is missing); the text of
claims comes from :mod:`derivations.text`.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import textwrap
import time
from collections.abc import Callable, Sequence
from importlib import metadata
from pathlib import Path
from typing import Any

from derivations import coverage, report
from derivations.printer import emit_all
from derivations.registry import (
    GROUP_TITLES,
    Claim,
    ClaimResult,
    all_claims,
    get_claim,
    kernel_report,
    verify_claim,
    verify_each,
)
from derivations.text import (
    WIDTH,
    claim_text,
    claims_lines,
    evidence_lines,
    progress_line,
    seconds_text,
    sentence_lines,
    statement_lines,
    terminal_width,
    verify_table,
)

__all__ = ["main", "build_parser", "version", "INSTALL"]

#: How to get what the commands need.
INSTALL = "pip install -e '.[derive]' in a clone of the symrb repository"

EXIT_STATUS = f"""\
exit status:
  0  everything as recorded: every computed outcome equals the recorded one, the generated
     code is what the derivations emit
  1  a surprise: a claim's computed outcome differs from the record, a kernel is not evaluated
     by the claims it names, or a generated file is stale (derive --check)
  2  usage or environment: bad arguments, an unknown claim ID, or SymPy or the derivations
     missing (install them with: {INSTALL})
"""


def version() -> str:
    """The installed version of symrb (its package metadata)."""
    try:
        return metadata.version("symrb")
    except metadata.PackageNotFoundError:
        return "unknown (symrb is not installed)"


# ---------------------------------------------------------------------------------------------
# claims


def _cmd_claims(args: argparse.Namespace) -> int:
    claims = all_claims(group=args.group)
    if args.json:
        rows = [
            {
                "id": c.id, "group": c.group, "title": c.title,
                "title_text": claim_text(c, "title"), "label": c.label, "section": c.section,
                "where": c.where, "expected": c.expected, "erratum": bool(c.printed),
                "checks": len(c.evidence),
            }
            for c in claims
        ]  # fmt: skip
        print(json.dumps(rows, indent=1))
        return 0
    for line in claims_lines(claims, terminal_width()):
        print(line)
    methods = sum(c.group == "method" for c in claims)
    count = f"{len(claims) - methods} claims" + (
        f" and {methods} checks of symrb's own methods" if methods else ""
    )
    tail = (
        f"{count}, with the outcomes recorded in the registry; '{args.prog} show ID' "
        f"explains one, '{args.prog} verify' checks them."
    )
    print("\n" + textwrap.fill(tail, width=terminal_width()))
    return 0


# ---------------------------------------------------------------------------------------------
# show


def _recorded(cid: str) -> tuple[ClaimResult | None, str]:
    """The result of claim ``cid`` from ``book/_build/verify.json`` when that file was written
    for the current code, with a phrase saying so; ``(None, why not)`` otherwise."""
    path = report.verify_json_path()
    if not path.is_file():
        return None, "no book/_build/verify.json"
    try:
        payload = json.loads(path.read_text())
    except (OSError, ValueError):
        return None, "book/_build/verify.json is unreadable"
    if payload.get("source_hash") != report.source_hash():
        return None, "book/_build/verify.json was written for other code"
    match = [r for r in payload.get("claims", []) if r.get("id") == cid]
    if not match:
        return None, f"book/_build/verify.json has no result for {cid}"
    return report.result_from_dict(match[0]), "recorded in book/_build/verify.json for this code"


def _cmd_show(args: argparse.Namespace) -> int:
    try:
        claim = get_claim(args.id)
    except KeyError as exc:
        print(textwrap.fill(exc.args[0], width=WIDTH), file=sys.stderr)
        return 2
    width = terminal_width()
    out = statement_lines(claim, width)
    result, source = (None, "") if args.run else _recorded(claim.id)
    if result is None:
        why = "asked with --run" if args.run else source
        start = time.perf_counter()
        result = verify_claim(claim)
        source = f"run now in {seconds_text(time.perf_counter() - start)}: {why}"
    out += evidence_lines(result, source, width)
    out += sentence_lines(claim, width)
    out += ["", f"Rerun its evidence with: {args.prog} verify {claim.id}"]
    print("\n".join(out))
    return 0 if result.ok else 1


# ---------------------------------------------------------------------------------------------
# verify


def _run(
    claims: Sequence[Claim], fail_fast: bool, report: Callable[[str, bool], None], jobs: int = 1
) -> list[ClaimResult]:
    """Verify ``claims`` (in ``jobs`` processes), reporting each result as it comes
    (``report(line, final)``); stop after the first surprise with ``fail_fast``.  The results
    are returned in the order of ``claims``."""
    total = len(claims)
    order = {c.id: i for i, c in enumerate(claims)}
    if jobs == 1 and claims:
        report(f"[{1:>{len(str(total))}}/{total}] {claims[0].id:<4} running ...", False)
    results: list[ClaimResult] = []
    last = time.perf_counter()
    for r in verify_each(claims, jobs=jobs, fail_fast=fail_fast):
        now = time.perf_counter()
        results.append(r)
        report(progress_line(len(results), total, r, now - last if jobs == 1 else r.seconds), True)
        last = now
        if jobs == 1 and len(results) < total and not (fail_fast and not r.ok):
            nxt = claims[len(results)].id
            report(f"[{len(results) + 1:>{len(str(total))}}/{total}] {nxt:<4} running ...", False)
    return sorted(results, key=lambda r: order[r.id])


def _claims(ids: Sequence[str], group: str | None) -> list[Claim]:
    """The claims with these IDs (all of ``group``, or all, when empty; duplicates dropped);
    ``KeyError`` for an unknown one."""
    if not ids:
        return all_claims(group=group)
    seen: dict[str, Claim] = {}
    for cid in ids:
        c = get_claim(cid)
        seen.setdefault(c.id, c)
    return list(seen.values())


def _reporter(quiet: bool) -> Callable[[str, bool], None]:
    """Prints progress lines on stderr; on a terminal a running line is overwritten by the next,
    starting with ``loading the claims ...``."""
    live = not quiet and sys.stderr.isatty()
    loading = "loading the claims ..."
    if live:
        print(loading, end="\r", file=sys.stderr, flush=True)
    shown = [len(loading) if live else 0]  # length of the line a carriage return left open

    def report(line: str, final: bool) -> None:
        if quiet or (not final and not live):
            return
        pad = " " * max(0, shown[0] - len(line))
        print(line + pad, end="\n" if final else "\r", file=sys.stderr, flush=True)
        shown[0] = 0 if final else len(line)

    return report


def _cmd_verify(args: argparse.Namespace) -> int:
    progress = _reporter(args.quiet)
    try:
        claims = _claims(args.ids, args.group)
    except KeyError as exc:
        print(textwrap.fill(exc.args[0], width=WIDTH), file=sys.stderr)
        return 2
    with coverage.recording() as recorder:
        results = _run(claims, args.fail_fast, progress, jobs=args.jobs)
    complete = not args.ids and len(results) == len(all_claims())
    kernels = kernel_report()
    unchecked = []
    if complete:
        unchecked = [k for k in kernels if set(k["claims"]) - set(k["checked_by"])]
    payload = {
        "source_hash": report.source_hash(),
        "claims": [r.to_dict() for r in results],
        "kernels": kernels,
        "coverage": coverage.report(recorder),
    }
    if args.output:
        Path(args.output).parent.mkdir(parents=True, exist_ok=True)
        Path(args.output).write_text(json.dumps(payload, indent=1) + "\n")
        if not args.quiet:
            print(f"wrote {args.output}", file=sys.stderr)
    if args.json:
        print(json.dumps(payload, indent=1))
    else:
        print("\n".join(verify_table(results, unchecked, args.prog)))
    ok = all(r.ok for r in results) and not unchecked
    return 0 if ok else 1


# ---------------------------------------------------------------------------------------------
# coverage


def _cmd_coverage(args: argparse.Namespace) -> int:
    progress = _reporter(args.quiet)
    with coverage.recording() as recorder:
        results = _run(all_claims(), False, progress, jobs=args.jobs)
    cov = coverage.report(recorder)
    if args.json:
        print(json.dumps(cov, indent=1))
    elif args.unreached:
        print("\n".join([*coverage.unreached(cov), coverage.summary_line(cov)]))
    else:
        print("\n".join(coverage.table(cov)))
    return 0 if all(r.ok for r in results) and not coverage.unreached(cov) else 1


# ---------------------------------------------------------------------------------------------
# derive


def _cmd_derive(args: argparse.Namespace) -> int:
    if os.environ.get("PYTHONHASHSEED") != "0":
        # printing must not depend on string hashing: rerun with a fixed seed
        env = dict(os.environ, PYTHONHASHSEED="0")
        argv = [sys.executable, "-m", "derivations", "derive"]
        argv += ["--check"] if args.check else []
        argv += ["--only", *args.only] if args.only else []
        argv += ["--target", str(args.target)] if args.target else []
        return subprocess.run(argv, env=env, check=False).returncode
    try:
        return emit_all(check=args.check, target=args.target, only=args.only)
    except KeyError as exc:
        print(exc.args[0], file=sys.stderr)
        return 2


# ---------------------------------------------------------------------------------------------
# the parser

_FMT = argparse.RawDescriptionHelpFormatter
_GROUP_HELP = "only the paper's claims (paper) or only the checks of symrb's own methods (method)"


def _add_claims(sub: Any) -> None:
    p = sub.add_parser(
        "claims", formatter_class=_FMT, epilog=EXIT_STATUS,
        help="list the claims with their recorded outcomes",
        description="List every claim of the paper, then the checks of symrb's own methods: ID,\n"
        "where it is in the paper, the recorded outcome and the title.  No evidence is run.",
    )  # fmt: skip
    p.add_argument("--json", action="store_true", help="print JSON instead of a list")
    p.add_argument("--group", choices=tuple(GROUP_TITLES), help=_GROUP_HELP)
    p.set_defaults(func=_cmd_claims)


def _add_show(sub: Any) -> None:
    p = sub.add_parser(
        "show", formatter_class=_FMT, epilog=EXIT_STATUS,
        help="one claim: statement, printed and corrected forms, evidence",
        description="Show one claim: where it is in the paper, its statement, the printed and\n"
        "corrected forms of an erratum, the note, and every check of its evidence with\n"
        "residual and tolerance (from book/_build/verify.json when it was written for\n"
        "this code, else run now).",
    )  # fmt: skip
    p.add_argument("id", metavar="ID", help="a claim ID such as S10 or D7 (see: claims)")
    p.add_argument("--run", action="store_true", help="run the evidence even if recorded")
    p.set_defaults(func=_cmd_show)


def _add_verify(sub: Any) -> None:
    p = sub.add_parser(
        "verify", formatter_class=_FMT, epilog=EXIT_STATUS,
        help="run the evidence and compare the outcomes with the record",
        description="Run the evidence of the claims (all by default: the paper's, then symrb's\n"
        "own methods), print a progress line per claim on stderr and a table on stdout, and\n"
        "fail when a computed outcome differs from the recorded one.",
    )  # fmt: skip
    p.add_argument(
        "ids", nargs="*", metavar="ID",
        help="claim IDs, e.g. S1 D10 (default: all, or all of the group asked for)",
    )  # fmt: skip
    which = p.add_mutually_exclusive_group()
    which.add_argument("--group", choices=tuple(GROUP_TITLES), help=_GROUP_HELP)
    which.add_argument(
        "--paper", dest="group", action="store_const", const="paper",
        help="only the paper's claims (the same as --group paper)",
    )  # fmt: skip
    p.add_argument("--json", action="store_true", help="print JSON instead of the table")
    p.add_argument("--output", metavar="FILE", help="also write the JSON to FILE")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    p.add_argument(
        "--fail-fast", action="store_true", help="stop at the first claim whose outcome differs"
    )
    p.add_argument(
        "-j", "--jobs", type=_jobs, default=_default_jobs(), metavar="N",
        help=f"claims run in N worker processes (default here: {_default_jobs()}, the CPUs this "
        "process may use; 1 runs them in this process, in order)",
    )  # fmt: skip
    p.set_defaults(func=_cmd_verify)


def _default_jobs() -> int:
    """The CPUs this process may use (its affinity where the platform tells)."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)


def _jobs(text: str) -> int:
    """``--jobs``: an integer >= 1 (argparse reports anything else as a usage error)."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be an integer >= 1, got {text!r}")
    return value


def _add_derive(sub: Any) -> None:
    p = sub.add_parser(
        "derive", formatter_class=_FMT, epilog=EXIT_STATUS,
        help="regenerate (or with --check compare) symrb/_generated",
        description="Print the kernels of the derivations as NumPy code into symrb/_generated\n"
        "(the only writer of that directory), or with --check only compare.",
    )  # fmt: skip
    p.add_argument("--check", action="store_true", help="only compare; exit 1 on a difference")
    p.add_argument("--only", nargs="+", metavar="TARGET", help="only these generated modules")
    p.add_argument("--target", type=Path, help="write into this directory instead")
    p.set_defaults(func=_cmd_derive)


def _add_coverage(sub: Any) -> None:
    p = sub.add_parser(
        "coverage", formatter_class=_FMT, epilog=EXIT_STATUS,
        help="which public functions and option values of symrb the evidence reaches",
        description="Run every claim's evidence with a recorder on and list each public\n"
        "numerical function of symrb and each value of its options with the evidence that\n"
        "reached it, or UNREACHED (exit 1 when anything is unreached).",
    )  # fmt: skip
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    p.add_argument("--unreached", action="store_true", help="list only what is unreached")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    p.add_argument(
        "-j", "--jobs", type=_jobs, default=1, metavar="N",
        help="claims run in N worker processes (default 1: in this process, in order)",
    )  # fmt: skip
    p.set_defaults(func=_cmd_coverage)


def build_parser(prog: str = "symrb") -> argparse.ArgumentParser:
    """The argument parser of the four commands (plain-text help with the exit status)."""
    parser = argparse.ArgumentParser(
        prog=prog,
        formatter_class=_FMT,
        description=(
            "Check the claims of Bloch, Crouch and Ratiu, 'Symmetric Discrete Optimal Control\n"
            "and Deep Learning' (2024), and derive the kernels of the symrb package.  The\n"
            "commands run the SymPy derivations of a source checkout of symrb."
        ),
        epilog=(
            "examples:\n"
            f"  {prog} claims                 list the claims and their recorded outcomes\n"
            f"  {prog} show S10               one claim: statement, erratum, evidence\n"
            f"  {prog} verify S1 S4 D10       run the evidence of some claims\n"
            f"  {prog} verify --paper         run the evidence of the paper's claims only\n"
            f"  {prog} derive --check         is symrb/_generated what the derivations emit?\n\n"
            + EXIT_STATUS
        ),
    )
    parser.add_argument("-V", "--version", action="version", version=f"symrb {version()}")
    parser.set_defaults(prog=prog)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND", title="commands")
    for add in (_add_claims, _add_show, _add_verify, _add_derive, _add_coverage):
        add(sub)
    return parser


def main(argv: Sequence[str] | None = None, prog: str = "symrb") -> int:
    """Run a command; returns the exit status (argparse's usage errors give 2, help 0)."""
    parser = build_parser(prog)
    if not list(sys.argv[1:] if argv is None else argv):
        parser.print_help(sys.stderr)
        return 2
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:
        return int(exc.code or 0) if not isinstance(exc.code, str) else 2
    try:
        return int(args.func(args))
    except BrokenPipeError:  # `symrb claims | head`: the reader closed the pipe, not an error
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # no second error when Python flushes at exit
        return 0
