"""The ``symrb`` command: ``claims``, ``show ID``, ``verify [IDS]``, ``derive [--check]``,
``bench``, ``run SCENE`` and ``sweep SCENE``.

The first four are development tools that run the SymPy derivations of a source checkout
(:mod:`derivations`, installed with symrb by ``pip install -e '.[derive]'`` but not part of the
wheel; see ``derivations.cli`` for what each does), reached through ``derivations.cli.main``.
This launcher imports none of symrb's numerics for them, so they work while ``symrb/_generated``
is missing; ``symrb --version`` and ``symrb --help`` work without SymPy and without the derivations.
``symrb bench`` times the numerics (``benchmarks.harness``, also of a source checkout only) with
NumPy and SciPy alone, so it is handled here, before the derivations are looked for; so are
``symrb run`` and ``symrb sweep`` (:mod:`symrb.scene_cli`, scenes of :mod:`symrb.scenes`).

Exit status: 0 everything as recorded; 1 a surprise (a computed outcome differs from the record,
a kernel not evaluated by its claims, a stale generated file); 2 usage or environment (bad
arguments, an unknown claim, SymPy or the derivations missing, with what to install).
"""

from __future__ import annotations

import contextlib
import io
import sys
from collections.abc import Callable, Sequence
from importlib import metadata

COMMANDS = ("claims", "show", "verify", "derive")

_BENCH_HELP = """\
numerics command (needs only NumPy and SciPy, no source checkout):
  bench [--quick] [--json PATH] [--plots DIR] [--only SECTION ...]
                   time the integrators against SciPy and report the speed goals
                   (symrb bench --help; exit status 1 only with --strict)
"""

_SCENES_HELP = """\
scene commands (need pydantic; sweeps need pandas, Dask only with --scheduler/--local-cluster):
  run SCENE.toml [--explain] [--plot] [--out DIR] [--no-cache]
                   plan and run a scene (cached); --explain prints the plan only
  sweep SCENE.toml --grid KEY=V1,V2,... [--grid ...] [--scheduler ADDRESS | --local-cluster N]
                   run a grid of scenes; one table (CSV) plus the arrays
"""

_NEED = (
    "symrb {cmd} runs the derivations of a source checkout of symrb and needs its 'derive' extra: "
    "git clone the repository, then pip install -e '.[derive]' in it"
)

_USAGE = """\
usage: symrb [-h] [-V] COMMAND ...

Check the claims of Bloch, Crouch and Ratiu, 'Symmetric Discrete Optimal Control and Deep
Learning' (2024), and derive the kernels of the symrb package.

commands (they need a source checkout of symrb with its 'derive' extra):
  claims           list the claims with their recorded outcomes
  show ID          one claim: statement, printed and corrected forms, evidence
  verify [ID ...]  run the evidence and compare the outcomes with the record
                   (--paper: only the paper's claims, not symrb's own methods)
  derive [--check] regenerate (or only compare) symrb/_generated

{bench}
{scenes}
{why}

exit status: 0 everything as recorded, 1 a surprise (an outcome differs from the record, a stale
generated file), 2 usage or environment (bad arguments, an unknown claim, SymPy or the
derivations missing)
"""


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


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``symrb`` with ``argv`` (default ``sys.argv[1:]``); returns the exit status."""
    args = list(sys.argv[1:] if argv is None else argv)
    if args[:1] in (["--version"], ["-V"]):
        print(f"symrb {version()}")
        return 0
    cmd = next((a for a in args if not a.startswith("-")), "")
    if cmd == "bench":
        i = args.index("bench")
        if any(a not in ("-h", "--help") for a in args[:i]):
            return _exit2(f"usage: symrb bench [options]; got options before 'bench': {args[:i]}")
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
        i = args.index(cmd)
        if any(a not in ("-h", "--help") for a in args[:i]):
            return _exit2(f"usage: symrb {cmd} [options]; got options before {cmd!r}: {args[:i]}")
        from symrb.scene_cli import main as scene_main

        return int(scene_main(cmd, args[i + 1 :]))
    run, missing = _derivations_main()
    if run is None:  # an installed wheel, or no SymPy: no derivations to run
        need = _NEED.format(cmd=cmd if cmd in COMMANDS else "COMMAND")
        if cmd not in COMMANDS and any(a in ("-h", "--help") for a in args):
            print(_USAGE.format(why=need + ".", bench=_BENCH_HELP, scenes=_SCENES_HELP))
            return 0
        if cmd in COMMANDS:
            return _exit2(f"{need} ({missing})")
        return _exit2(_USAGE.format(why=need + ".", bench=_BENCH_HELP, scenes=_SCENES_HELP))
    if not cmd and (not args or any(a in ("-h", "--help") for a in args)):
        return _with_bench_help(run, args)
    return int(run(args, prog="symrb"))


def _with_bench_help(run: Callable[..., int], args: list[str]) -> int:
    """The derivations' top-level help (or usage) with the ``bench`` command added before its
    exit status paragraph."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = int(run(args, prog="symrb"))
    for buf, stream in ((out, sys.stdout), (err, sys.stderr)):
        text = buf.getvalue()
        if text and "exit status:" in text:
            head, sep, tail = text.partition("exit status:")
            text = head + _BENCH_HELP + "\n" + _SCENES_HELP + "\n" + sep + tail
        stream.write(text)
    return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
