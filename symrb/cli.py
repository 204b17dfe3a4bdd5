"""The ``symrb`` command: ``symrb derive [--check]`` and ``symrb verify [IDS...]``.

Both are development tools that run the SymPy derivations of a source checkout
(:mod:`derivations`, not part of the wheel).  This launcher imports none of symrb's numerics, so
it works even while ``symrb/_generated`` is missing.  Exit status 2 (with what to install) when
SymPy or the derivations are not available; otherwise see ``derivations.cli``.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path

_NEED = (
    "symrb {cmd} runs the derivations of a source checkout of symrb and needs its 'derive' extra: "
    "git clone the repository, then pip install -e '.[derive]' in it"
)


def _derivations_cli(cmd: str):  # type: ignore[no-untyped-def]
    try:
        import sympy  # noqa: F401
    except ImportError:
        sys.exit(_exit2(_NEED.format(cmd=cmd) + " (SymPy is not installed)"))
    try:
        import derivations.cli as dcli
    except ImportError:
        root = Path(__file__).resolve().parents[1]
        if not (root / "derivations" / "__init__.py").is_file():
            sys.exit(_exit2(_NEED.format(cmd=cmd) + " (no derivations package next to symrb)"))
        sys.path.insert(0, str(root))
        import derivations.cli as dcli
    return dcli


def _exit2(message: str) -> int:
    print(message, file=sys.stderr)
    return 2


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    cmd = next((a for a in args if not a.startswith("-")), "")
    if cmd not in ("derive", "verify"):
        print(
            "usage: symrb {derive,verify} ...\n"
            "  symrb derive [--check] [--only TARGET ...]   regenerate or check symrb/_generated\n"
            "  symrb verify [IDS ...] [--json] [--output FILE] [--fail-fast]   check the claims",
            file=sys.stderr,
        )
        return 0 if cmd in ("-h", "--help") or args in (["-h"], ["--help"]) else 2
    return int(_derivations_cli(cmd).main(args))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
