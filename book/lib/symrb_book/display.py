"""Small display helpers shared by the book's pages: numbers in typeset math, Markdown tables.

A number printed with ``f"{x:.1e}"`` inside ``$...$`` renders as "3.2e − 16" (TeX reads the
minus as a binary operator); :func:`tex_sci` writes it as :math:`3.2\\times10^{-16}` instead.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence

__all__ = ["tex_sci", "md_table"]


def tex_sci(x: float, digits: int = 1) -> str:
    """``x`` in scientific notation as TeX (no dollar signs), e.g. ``3.2\\times10^{-16}``.

    Parameters
    ----------
    x : float
        The number.
    digits : int
        Digits after the decimal point of the mantissa.

    Returns
    -------
    str
        ``"m\\times10^{e}"``, or just ``"m"`` when the exponent is 0.
    """
    mantissa, exponent = f"{x:.{digits}e}".split("e")
    power = int(exponent)
    return mantissa if power == 0 else rf"{mantissa}\times10^{{{power}}}"


def md_table(header: Sequence[object], rows: Iterable[Sequence[object]]) -> str:
    """A Markdown table; a ``|`` inside a cell (a norm, a message) is escaped (once).

    Parameters
    ----------
    header : sequence
        The column titles.
    rows : iterable of sequences
        The cells, one sequence per row.

    Returns
    -------
    str
        The table as Markdown text.
    """

    def cell(c: object) -> str:
        return re.sub(r"(?<!\\)\|", r"\\|", str(c))

    lines = ["| " + " | ".join(cell(h) for h in header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(cell(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)
