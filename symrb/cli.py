"""The ``symrb`` command: ``claims``, ``show ID``, ``verify [IDS]``, ``derive [--check]``,
``bench``, ``run SCENE`` and ``sweep SCENE``.

The first four are development tools that run the SymPy derivations of a source checkout
(:mod:`derivations`, installed with symrb by ``pip install -e '.[derive]'`` but not part of the
wheel; see ``derivations.cli`` for what each does), reached through ``derivations.cli.main``.
This launcher imports none of symrb's numerics for them, so they work while ``symrb/_generated``
is missing; ``symrb --version`` and ``symrb --help`` work without SymPy and without the derivations.
The top-level help is written here (:func:`help_text`): one list of every command
(:data:`ALL_COMMANDS`), each one that cannot run here marked, with why.
``symrb bench`` times the numerics (``benchmarks.harness``, also of a source checkout only) with
NumPy and SciPy alone, so it is handled here, before the derivations are looked for; so are
``symrb run`` and ``symrb sweep`` (:mod:`symrb.scene_cli`, scenes of :mod:`symrb.scenes`).

Exit status: 0 everything as recorded; 1 a surprise (a computed outcome differs from the record,
a kernel not evaluated by its claims, a stale generated file); 2 usage or environment (bad
arguments, an unknown claim, SymPy or the derivations missing, with what to install).
"""

from __future__ import annotations

import functools
import sys
import textwrap
import warnings
from collections.abc import Callable, Sequence
from importlib import metadata
from pathlib import Path
from typing import Any

COMMANDS = ("claims", "show", "verify", "derive", "coverage")
"""The commands of :mod:`derivations.cli` (a source checkout with the 'derive' extra)."""

_INSTALL_DERIVE = "git clone the repository, then pip install -e '.[derive]' in it"

#: Every command of ``symrb``: (name, its arguments in the help, what it does, what it needs:
#: "scenes" (pydantic), "bench" (the harness of a source checkout), "derive" (the derivations
#: of a source checkout)). The top-level help lists exactly these, in this order.
ALL_COMMANDS: tuple[tuple[str, str, str, str], ...] = (
    ("run", "SCENE.toml", "plan and run a scene (cached); --explain prints the plan only, "
     "--plot draws the relative drift of the invariants", "scenes"),
    ("sweep", "SCENE.toml --grid KEY=V1,V2,...", "run a grid of scenes; one table (CSV) plus "
     "the arrays; --scheduler ADDRESS or --local-cluster N run it on Dask", "scenes"),
    ("bench", "[--quick]", "time the integrators against SciPy and report the speed goals",
     "bench"),
    ("claims", "", "list the claims with their recorded outcomes", "derive"),
    ("show", "ID", "one claim: statement, printed and corrected forms, evidence", "derive"),
    ("verify", "[ID ...]", "run the evidence and compare the outcomes with the record "
     "(--paper: the paper's claims only)", "derive"),
    ("derive", "[--check]", "regenerate (or only compare) symrb/_generated", "derive"),
    ("coverage", "", "which public functions and option values of symrb the evidence reaches",
     "derive"),
)  # fmt: skip

_NEED = (
    "symrb {cmd} runs the derivations of a source checkout of symrb and needs its 'derive' extra: "
    + _INSTALL_DERIVE
)

_DESCRIPTION = """\
Check the claims of Bloch, Crouch and Ratiu, 'Symmetric Discrete Optimal Control and Deep
Learning' (2024), run scenes of the rigid body and its relatives, and time the integrators."""

_NOTES = """\
  run and sweep need pydantic (sweep also pandas; Dask only with --scheduler/--local-cluster).
  bench, claims, show, verify, derive and coverage exist only in a source checkout of symrb
  (not in the wheel): {install}
  ('.[bench]' for bench)."""

_EPILOG = """\
'symrb COMMAND --help' gives the options of one command.

examples:
  symrb run book/scenes/mv_invariants.toml --plot   a scene and its invariants' drift
  symrb claims                                       the claims and their recorded outcomes
  symrb show S10                                     one claim: statement, erratum, evidence
  symrb verify --paper                               run the evidence of the paper's claims

exit status:
  0  done, everything as recorded
  1  a surprise: a claim's computed outcome differs from the record or a generated file is
     stale (derive --check), a scene's integrator stopped early, a speed goal missed (bench
     --strict)
  2  usage or environment: bad arguments, an unknown claim ID, an invalid scene, or a package
     missing (for the derivations: pip install -e '.[derive]' in a clone of the repository)
"""

_USAGE_LINE = "usage: symrb [-h] [-V] COMMAND ..."


def version() -> str:
    """The installed version (package metadata, else ``symrb.__version__``)."""
    try:
        return metadata.version("symrb")
    except metadata.PackageNotFoundError:
        from symrb import __version__

        return __version__


#: What a failed import of the derivations may miss: then they cannot run here (a wheel, or a
#: checkout without its 'derive' extra); any other import error is a bug and is raised.
_OPTIONAL = ("derivations", "derivations.cli", "sympy", "mpmath", "pylatexenc")


def _derivations_main() -> tuple[Callable[..., int] | None, str]:
    """``derivations.cli.main`` (installed with symrb in an editable checkout), or ``None`` and
    what is missing (no derivations next to symrb, as in a wheel, or SymPy not installed)."""
    try:
        from derivations.cli import main as derivations_main
    except ImportError as exc:
        if exc.name not in _OPTIONAL:
            raise
        if exc.name.startswith("derivations"):
            return None, "no derivations package next to symrb"
        return None, f"{'SymPy' if exc.name == 'sympy' else exc.name} is not installed"
    return derivations_main, ""


def _exit2(message: str) -> int:
    print(message, file=sys.stderr)
    return 2


def _missing(need: str) -> str:
    """Why the commands needing ``need`` cannot run here ("" when they can), found without
    importing anything (``symrb --help`` loads neither SymPy nor the numerics)."""
    from importlib.util import find_spec

    if need == "bench":
        spec = find_spec("benchmarks")
        where = spec.submodule_search_locations if spec is not None else None
        if not where or not any((Path(d) / "harness").is_dir() for d in where):
            return "no benchmarks/ next to symrb"
        return ""
    if need == "derive":
        if find_spec("derivations") is None:
            return "no derivations package next to symrb"
        for name in ("sympy", "mpmath", "pylatexenc"):
            if find_spec(name) is None:
                return f"{'SymPy' if name == 'sympy' else name} is not installed"
        return ""
    return "" if find_spec("pydantic") is not None else "pydantic is not installed"


def help_text() -> str:
    """The top-level help: every command with what it does, each one that cannot run here
    marked with why, the notes on what each needs, examples and the exit status."""
    missing = {need: _missing(need) for need in ("scenes", "bench", "derive")}
    lines = [_USAGE_LINE, "", _DESCRIPTION, "", "commands:"]
    for name, arguments, does, need in ALL_COMMANDS:
        head = f"  {name} {arguments}".rstrip()
        words = does + (" [not available here, see below]" if missing[need] else "")
        body = textwrap.wrap(words, width=98 - 21)
        if len(head) > 19:
            lines += [head]
        else:
            lines += [f"{head:<21}{body.pop(0)}"]
        lines += [" " * 21 + b for b in body]
    lines += ["", _NOTES.format(install=_INSTALL_DERIVE)]
    for need, why in missing.items():
        if why:
            names = ", ".join(c[0] for c in ALL_COMMANDS if c[3] == need)
            lines += textwrap.wrap(f"Not available here: {names} ({why}).", width=96,
                                   initial_indent="  ", subsequent_indent="  ")  # fmt: skip
    lines += ["", _EPILOG]
    return "\n".join(lines)


def _show_warning(prog: str, message: Warning | str, category: type[Warning], *rest: Any,
                  **kwargs: Any) -> None:  # fmt: skip
    """Print a warning as ``PROG: warning: message`` (symrb's own) or as Python would."""
    from symrb.errors import SymrbWarning

    if issubclass(category, SymrbWarning):
        print(f"{prog}: warning: {message}", file=sys.stderr)
    else:
        print(warnings.formatwarning(message, category, *rest[:2]), end="", file=sys.stderr)


def _usage_error(message: str) -> int:
    return _exit2(f"{_USAGE_LINE}\nsymrb: error: {message}")


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``symrb`` with ``argv`` (default ``sys.argv[1:]``); returns the exit status."""
    args = list(sys.argv[1:] if argv is None else argv)
    if args[:1] in (["--version"], ["-V"]):
        print(f"symrb {version()}")
        return 0
    cmd = next((a for a in args if not a.startswith("-")), "")
    if not cmd:
        if any(a in ("-h", "--help") for a in args):
            print(help_text())
            return 0
        if not args:
            print(help_text(), file=sys.stderr)
            return 2
        return _usage_error(f"unrecognized arguments: {' '.join(args)}")
    if cmd not in {c[0] for c in ALL_COMMANDS}:
        choices = ", ".join(repr(c[0]) for c in ALL_COMMANDS)
        return _usage_error(f"argument COMMAND: invalid choice: {cmd!r} (choose from {choices})")
    i = args.index(cmd)
    if cmd in ("bench", "run", "sweep") and any(a not in ("-h", "--help") for a in args[:i]):
        return _exit2(f"usage: symrb {cmd} [options]; got options before {cmd!r}: {args[:i]}")
    if cmd == "bench":
        try:  # the harness of a source checkout (benchmarks/), not part of the wheel
            from benchmarks.harness import main as bench_main
        except ModuleNotFoundError as exc:
            if exc.name not in ("benchmarks", "benchmarks.harness"):
                raise
            return _exit2(
                "symrb bench runs the benchmark harness of a source checkout of symrb "
                "(benchmarks/, not part of the wheel): git clone the repository, then "
                "pip install -e '.[bench]' in it"
            )
        return int(bench_main(args[i + 1 :], prog="symrb bench"))
    if cmd in ("run", "sweep"):
        from symrb.scene_cli import main as scene_main

        with warnings.catch_warnings():  # symrb's warnings as one line each, not a source line
            warnings.showwarning = functools.partial(_show_warning, f"symrb {cmd}")
            return int(scene_main(cmd, args[i + 1 :]))
    run, missing = _derivations_main()
    if run is None:  # an installed wheel, or no SymPy: no derivations to run
        return _exit2(f"{_NEED.format(cmd=cmd)} ({missing})")
    return int(run(args, prog="symrb"))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
