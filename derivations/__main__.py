"""``python -m derivations``: the commands of ``symrb`` without going through the package.

    python -m derivations claims [--json]
    python -m derivations show ID [--run]
    python -m derivations verify [IDS ...] [--json] [--output FILE] [--quiet] [--fail-fast]
    python -m derivations derive [--check] [--only TARGET ...] [--target DIR]

The same commands as ``symrb claims|show|verify|derive`` (which call :mod:`derivations.cli`),
usable in a source checkout even when ``symrb/_generated`` is missing or broken.
"""

from __future__ import annotations

import sys

from derivations.cli import main

if __name__ == "__main__":
    sys.exit(main(prog="python -m derivations"))
