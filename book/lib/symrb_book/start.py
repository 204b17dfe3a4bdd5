"""The getting-started page: a claim's checks as a short table (the full descriptions are on the
claim's own page and in ``symrb show ID``)."""

from __future__ import annotations

from typing import Any


def evidence_summary(result: Any) -> str:
    """A Markdown table of a claim's checks (a ``ClaimResult`` of ``derivations``): number,
    level, the form checked (``claim``, ``printed`` or ``corrected``), residual, tolerance and
    whether the check came out as the registry records; in the ``symrb-fit`` container, whose
    table fits a phone's column (the book's CSS)."""
    rows = [
        "| check | level | form | residual | tolerance | as recorded |",
        "|---|---|---|---|---|---|",
    ]
    for k, e in enumerate(result.evidence, 1):
        residual = "error" if e.residual is None else f"{e.residual:.1e}"
        rows.append(
            f"| {k} | {e.level} | {e.form} | {residual} | {e.tol:.0e} | "
            f"{'yes' if e.as_expected else 'no'} |"
        )
    return ":::{container} symrb-fit\n" + "\n".join(rows) + "\n:::\n"
