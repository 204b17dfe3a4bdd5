"""The diagonal of Lambda in the claims of Section 3: its symbols and its kernel argument."""

from __future__ import annotations

import sympy as sp

from derivations.vocabulary import Arg

ARG_LAM = Arg("lam", "(..., n)", "diagonal of Lambda, lam_i + lam_j > 0")


def lam_symbols(k: int) -> list[sp.Symbol]:
    """The diagonal ``lam1, ..., lamk`` of Lambda as real symbols (fixed-n evidence)."""
    return list(sp.symbols(f"lam1:{k + 1}", real=True))
