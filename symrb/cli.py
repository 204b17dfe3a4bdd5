"""The ``symrb`` command: ``claims``, ``show ID``, ``verify [IDS]`` and ``derive [--check]``.

The commands are development tools that run the SymPy derivations of a source checkout
(:mod:`derivations`, not part of the wheel; see ``derivations.cli`` for what each does).  This
launcher imports none of symrb's numerics, so it works while ``symrb/_generated`` is missing;
``symrb --version`` and ``symrb --help`` work without SymPy and without the derivations.

Exit status: 0 everything as recorded; 1 a surprise (a computed outcome differs from the record,
a kernel not evaluated by its claims, a stale generated file); 2 usage or environment (bad
arguments, an unknown claim, SymPy or the derivations missing, with what to install).
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path
from types import ModuleType

COMMANDS = ("claims", "show", "verify", "derive")

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
  derive [--check] regenerate (or only compare) symrb/_generated

{why}

exit status: 0 everything as recorded, 1 a surprise (an outcome differs from the record, a stale
generated file), 2 usage or environment (bad arguments, an unknown claim, SymPy or the
derivations missing)
"""


def version() -> str:
    """The installed version (package metadata, else ``symrb.__version__``)."""
    from importlib import metadata

    try:
        return metadata.version("symrb")
    except metadata.PackageNotFoundError:
        from symrb import __version__

        return __version__


def _derivations_cli() -> ModuleType | None:
    """``derivations.cli`` of the source checkout this package sits in, or ``None`` (a wheel).
    Importing it needs no SymPy."""
    try:
        import derivations.cli as dcli
    except ImportError:
        root = Path(__file__).resolve().parents[1]
        if not (root / "derivations" / "cli.py").is_file():
            return None
        sys.path.insert(0, str(root))
        try:
            import derivations.cli as dcli
        except ImportError:
            return None
    return dcli


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
    if cmd in COMMANDS:
        try:
            import sympy  # noqa: F401
        except ImportError:
            return _exit2(_NEED.format(cmd=cmd) + " (SymPy is not installed)")
    dcli = _derivations_cli()
    if dcli is None:  # an installed wheel: no derivations to run
        need = _NEED.format(cmd=cmd if cmd in COMMANDS else "COMMAND")
        if cmd not in COMMANDS and any(a in ("-h", "--help") for a in args):
            print(_USAGE.format(why=need + "."))
            return 0
        if cmd in COMMANDS:
            return _exit2(need + " (no derivations package next to symrb)")
        return _exit2(_USAGE.format(why=need + "."))
    return int(dcli.main(args, prog="symrb"))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
