"""``python -m derivations``: regenerate or check ``symrb/_generated``, verify the claims.

    python -m derivations derive [--check] [--only TARGET ...]
    python -m derivations verify [IDS ...] [--json] [--output FILE] [--fail-fast]

The same commands as ``symrb derive`` and ``symrb verify`` (which call this module), usable in a
source checkout even when ``symrb/_generated`` is missing or broken.
"""

from __future__ import annotations

import sys

from derivations.cli import main

if __name__ == "__main__":
    sys.exit(main())
