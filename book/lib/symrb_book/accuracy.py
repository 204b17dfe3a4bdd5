"""The accuracy pages: work-precision panels drawn from a recorded ``symrb bench`` run, and the
look-ups of the guide (the cheapest configuration reaching an error).

Each panel shows at most :data:`MAX_SERIES` methods in the colours of :mod:`symrb_book.style`,
the reference's own estimated error as a grey band on the left, and no point inside the band: an
error below the reference's is drawn at the band's edge with a hollow marker (it says only "at
most the reference's error").
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

from symrb.errors import InputError

from .style import method_style, series_style

#: The width of the book's content column at 1280 px, in CSS pixels.
COLUMN_PX = 680

#: The largest number of methods in one panel.
MAX_SERIES = 6

#: The panels of the accuracy page: the methods the guide names, per setting.
MAIN_PANELS = (
    ((3, 100.0), ("DOP853", "DOP853-gen", "MV-fast", "MV-pre8", "MV-pre10", "exact")),
    ((10, 100.0), ("DOP853", "DOP853-gen", "MV-comp6", "MV-comp8", "RKMK4", "split8")),
)

#: The groups of the appendix: every method of a setting, at most six to a panel (a group none
#: of whose methods ran in a setting is left out).
APPENDIX_GROUPS = (
    ("SciPy, lean field", ("RK45", "DOP853", "LSODA")),
    ("SciPy, generated field", ("RK45-gen", "DOP853-gen", "LSODA-gen", "integrate")),
    ("orders 2 and 4", ("MV", "MV-fast", "midpoint", "MV-comp4", "MV-pre4", "RKMK4")),
    ("orders 6 to 10, exact", ("MV-comp6", "MV-comp8", "MV-pre6", "MV-pre8", "MV-pre10", "exact")),
    ("splitting", ("split2", "split4", "split6", "split8")),
)

#: SciPy's methods: on the lean field under their own name, on the generated one as NAME-gen.
SCIPY = ("RK45", "DOP853", "LSODA")


def lean_recorded(w: dict[str, Any]) -> bool:
    """Whether the setting ``w`` ran SciPy on the lean field (a run before issue 23 did not: its
    ``DOP853`` is the generated field's)."""
    return bool(w.get("baselines", {}).get("variant"))


def label_of(w: dict[str, Any], m: str) -> str:
    """The legend's label of method ``m`` in setting ``w``: SciPy's methods name their field."""
    if m.endswith("-gen"):
        return f"{m[:-4]} (generated field)"
    if m in SCIPY:
        return f"{m} (lean field)" if lean_recorded(w) else f"{m} (generated field)"
    return m


def look_of(w: dict[str, Any], m: str) -> dict[str, Any]:
    """The style of ``m`` in setting ``w``: SciPy's runs on the generated field in their
    method's colour, dotted and hollow (so too an old run's, which had no other field)."""
    if m.endswith("-gen"):
        return method_style(m[:-4], ls=":", mfc="white")
    if m in SCIPY and not lean_recorded(w):
        return method_style(m, ls=":", mfc="white")
    return method_style(m)


def fit_column(fig: Any, width_px: int = COLUMN_PX) -> Any:
    """``fig`` with its dpi lowered so that it is drawn at most ``width_px`` CSS pixels wide: the
    notebook shows a figure at its size in pixels, and the theme narrows a wider image without
    lowering its height (the figure comes out squeezed)."""
    fig.set_dpi(min(fig.dpi, width_px / fig.get_figwidth()))
    return fig


def settings(result: Any) -> list[dict[str, Any]]:
    """The work-precision settings of a bench result (n = 3 first), as recorded."""
    wp = result.measurements["work-precision"]
    return [*wp.get("n3", []), *([wp["n10"]] if wp.get("n10") else [])]


def setting(result: Any, n: int, T: float) -> dict[str, Any]:
    """The work-precision setting ``(n, T)`` of a bench result."""
    for w in settings(result):
        if w["n"] == n and w["T"] == T:
            return w
    raise InputError(f"setting: no work-precision run with n = {n}, T = {T:g}")


def available(w: dict[str, Any], methods: Iterable[str]) -> list[str]:
    """The methods among ``methods`` that ran in the setting ``w``, in the given order."""
    return [m for m in methods if w["methods"].get(m, {}).get("available")]


def cheapest(w: dict[str, Any], error: float, among: Iterable[str] | None = None):
    """(method, point) of the configuration reaching ``error`` at the least median CPU time,
    among ``among`` (every method when None); None if none reaches it."""
    best = None
    names = set(w["methods"]) if among is None else set(among)
    for name, e in w["methods"].items():
        if name not in names or not e.get("available"):
            continue
        for p in e["points"]:
            if p["error"] <= error and (
                best is None or p["cpu"]["median"] < best[1]["cpu"]["median"]
            ):
                best = (name, p)
    return best


def _panel(ax: Any, w: dict[str, Any], methods: Sequence[str], title: str, left: float) -> int:
    """One work-precision panel; returns how many points were drawn at the floor."""
    floor = w["reference_error_estimate"]
    clipped = 0
    for m in methods:
        pts = sorted(w["methods"][m]["points"], key=lambda q: q["error"])
        err = [max(q["error"], floor) for q in pts]
        med = [q["cpu"]["median"] for q in pts]
        bars = [[q["cpu"]["median"] - q["cpu"]["min"] for q in pts],
                [q["cpu"]["max"] - q["cpu"]["median"] for q in pts]]  # fmt: skip
        ax.errorbar(err, med, yerr=bars, ms=6, capsize=2, lw=1.4, label=label_of(w, m),
                    **look_of(w, m))  # fmt: skip
        low = [(e, c) for q, e, c in zip(pts, err, med, strict=True) if q["error"] < floor]
        clipped += len(low)
        if low:
            ax.plot(
                *zip(*low, strict=True), ms=11, **{**look_of(w, m), "ls": "none", "mfc": "white"}
            )
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.axvspan(left, floor, color="0.85", lw=0, label="below the reference's own error")
    ax.set_xlim(left, 1.0)
    ax.set_title(title, fontsize=11)
    ax.grid(True, which="major", alpha=0.3)
    return clipped


def work_precision(result: Any, panels: Sequence[tuple[tuple[int, float], Sequence[str]]],
                   *, ncols: int = 1, titles: Sequence[str] | None = None) -> tuple[Any, int]:  # fmt: skip
    """(figure, points clipped to the floor): one panel per ``((n, T), methods)``, at most
    :data:`MAX_SERIES` methods each, one legend below the panels.

    Raises
    ------
    InputError
        For a panel of more than :data:`MAX_SERIES` methods.
    """
    import matplotlib.pyplot as plt

    nrows = -(-len(panels) // ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(3.9 * ncols + 0.4, 3.1 * nrows + 1.0),
                             squeeze=False, sharex=True)  # fmt: skip
    # sizes set here, not through rc_context (whose exit resets the notebook's backend); a
    # wider figure is drawn smaller (fit_column), so its type is larger
    size = 11 * (1 + 0.2 * max(0, ncols - 2))
    for ax in axes.flat:
        ax.tick_params(labelsize=size - 1)
    for ax in axes[-1]:
        ax.set_xlabel("error of $M(T)$, $Q(T)$", fontsize=size)
    for ax in axes[:, 0]:
        ax.set_ylabel("CPU seconds per run", fontsize=size)
    clipped = 0
    # one error axis for all panels, from below the smallest floor
    left = min(setting(result, n, T)["reference_error_estimate"] for (n, T), _m in panels) / 30
    for i, ((n, T), methods) in enumerate(panels):
        if len(methods) > MAX_SERIES:
            raise InputError(f"work_precision: at most {MAX_SERIES} methods a panel, got {methods}")
        w = setting(result, n, T)
        title = titles[i] if titles else f"n = {n}, T = {T:g}"
        clipped += _panel(axes.flat[i], w, available(w, methods), title, left)
        axes.flat[i].title.set_fontsize(size)
    for ax in list(axes.flat)[len(panels) :]:
        ax.set_visible(False)
    handles: dict[str, Any] = {}
    for ax in axes.flat:
        for h, label in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(label, h)
    fig.legend(handles.values(), handles.keys(), loc="lower center", ncol=4, frameon=False,
               fontsize=size - 1)  # fmt: skip
    rows = -(-len(handles) // 4)
    fig.tight_layout(rect=(0, (0.1 + 0.025 * size * rows) / fig.get_figheight(), 1, 1))
    return fit_column(fig), clipped


def bench_figure(result: Any, name: str) -> Any:
    """The figure ``name`` of a recorded benchmark (``throughput``, ``cost_vs_n``, ``long_time``;
    :meth:`BenchResult.figures`) in the colours of :mod:`symrb_book.style`, fitted to the
    content column."""
    return fit_column(result.figures(name, style=series_style)[name])


def usage(name: str) -> str:
    """How a user asks for the benchmark's method ``name`` (the cell of the guide's table)."""
    if name.startswith("MV-pre"):
        return f'`method="mv", order={name[len("MV-pre") :]}` (`{name}`)'
    if name.startswith("MV-comp"):
        return f'`method="composition", order={name[len("MV-comp") :]}` (`{name}`)'
    if name.startswith("split"):
        return f"`symrb.splitting.splitting_flow(..., order={name[len('split') :]})` (`{name}`)"
    known = {"MV-fast": '`method="mv"`', "MV": "`discrete_rigid_body_flow`",
             "RKMK4": '`method="rkmk4"`', "midpoint": '`method="midpoint"`',
             "DOP853": '`method="DOP853"`'}  # fmt: skip
    return known.get(name, f"`{name}`")


def long_runs(result: Any, flow: str = "mv_flow") -> list[dict[str, Any]]:
    """The long-time runs of ``flow`` (``mv_flow``, ``mv_algorithm2``, ``symmetric_flow``); a
    run recorded before issue 23 is ``mv_flow``'s."""
    return [d for d in result.measurements.get("long-time", [])
            if d.get("flow_key", "mv_flow") == flow]  # fmt: skip


def previous_of(result: Any, name: str) -> dict[str, Any] | None:
    """The goal of the previous run (``result.previous_goals``) matching the goal ``name``: the
    same name, or else the one goal whose name has the same head before ``": "`` (a goal renamed
    since, e.g. with a new target, keeps its setting as its head).

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> r = SimpleNamespace(previous_goals=[{"name": "n = 3, T = 10: faster than DOP853"},
    ...                                     {"name": "exact accurate to 1e-13"}])
    >>> previous_of(r, "n = 3, T = 10: >= 30x faster than DOP853 (lean field)")["name"]
    'n = 3, T = 10: faster than DOP853'
    >>> previous_of(r, "cold start <= 1.5 s") is None
    True
    """
    prev = list(getattr(result, "previous_goals", []) or [])
    same = [g for g in prev if g["name"] == name]
    if same:
        return same[0]
    head = name.split(": ")[0]
    heads = [g for g in prev if ": " in g["name"] and g["name"].split(": ")[0] == head]
    return heads[0] if len(heads) == 1 and ": " in name else None
