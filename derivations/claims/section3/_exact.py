"""Exact zero tests of symbolic results (claims S5, S8, S12)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import sympy as sp


def count_nonzero(values: Sequence[sp.Expr] | sp.Matrix) -> sp.Integer:
    """How many of the rational functions ``values`` are not identically zero.

    An entry that is non-zero at a random rational point (exact arithmetic) is non-zero; the
    others are decided by ``sp.cancel``."""
    rng = np.random.default_rng(0)
    count = 0
    for v in values:
        e = sp.expand(v)
        if e == 0:
            continue
        point = {
            s: sp.Rational(int(rng.integers(1, 97)), int(rng.integers(1, 89)))
            for s in e.free_symbols
        }
        at = e.xreplace(point)
        if at.is_finite and at != 0:
            count += 1
        elif sp.cancel(sp.together(e)) != 0:
            count += 1
    return sp.Integer(count)
