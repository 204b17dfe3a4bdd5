"""``python -m derivations``: the commands of ``symrb`` without going through the package.

    python -m derivations claims [--json] [--group paper|method]
    python -m derivations show ID [--run]
    python -m derivations verify [IDS ...] [--group paper|method | --paper] [--json]
                                 [--output FILE] [--quiet] [--fail-fast]
    python -m derivations derive [--check] [--only TARGET ...] [--target DIR]

The same commands as ``symrb claims|show|verify|derive`` (which call :mod:`derivations.cli`),
usable in a source checkout even when ``symrb/_generated`` is missing or broken.  Without SymPy
(or pylatexenc) it says what to install and exits with status 2.
"""

from __future__ import annotations

import sys

try:
    from derivations.cli import main
except ImportError as exc:  # the 'derive' extra is missing
    if exc.name not in ("sympy", "mpmath", "pylatexenc"):
        raise
    print(
        f"python -m derivations needs {exc.name} (the 'derive' extra): "
        "pip install -e '.[derive]' in a clone of the symrb repository",
        file=sys.stderr,
    )
    sys.exit(2)

if __name__ == "__main__":
    sys.exit(main(prog="python -m derivations"))
