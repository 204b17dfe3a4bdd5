"""The diagrams of the sections run (matplotlib, imported when a figure is asked for)."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from symrb.errors import InputError

from .config import EPS

#: A style: the matplotlib keyword arguments of a series from its name and the keyword
#: arguments that tell two series of one name apart, e.g. ``style("mv_flow", ls="--")``.
Style = Callable[..., dict[str, Any]]


#: The command line's look of the series that are not methods.
_PLAIN = {"goal": {"color": "gray", "ls": ":"}}


def plain_style(name: str, **variant: Any) -> dict[str, Any]:
    """The style of the command line's figures: the variant, with colours from matplotlib's
    cycle (a goal grey).  The book passes its style table instead
    (``symrb_book.style.series_style``), so that a method has one colour in every figure of the
    book."""
    return {**_PLAIN.get(name, {}), **variant}


def _work_precision_figure(plt: Any, ms: Mapping[str, Any], style: Style | None = None) -> Any:
    """Work-precision: error against CPU time, one panel per problem (None if not run)."""
    wps = list(ms.get("work-precision", {}).get("n3", []))
    if ms.get("work-precision", {}).get("n10"):
        wps.append(ms["work-precision"]["n10"])
    if not wps:
        return None
    # one panel under another, so that each stays legible at a page's width
    fig, axes = plt.subplots(len(wps), 1, figsize=(10, 5.2 * len(wps)), squeeze=False)
    for ax, w in zip(axes[:, 0], wps, strict=True):
        for i, (m, e) in enumerate(w["methods"].items()):
            if not e.get("available"):
                continue
            if style is None:  # SciPy's methods dashed, symrb's solid; twelve colours
                look = {
                    "color": plt.get_cmap("tab20")(i % 20),
                    "marker": "osD^v<>ph*XP"[i % 12],
                    "ls": "--" if m in ("RK45", "DOP853", "LSODA", "integrate") else "-",
                }
            else:
                look = style(m)
            pts = sorted(e["points"], key=lambda q: q["error"])
            # no point below the reference's own error: such errors are drawn at that floor
            err = [max(q["error"], w["reference_error_estimate"]) for q in pts]
            med = [q["cpu"]["median"] for q in pts]
            lo = [q["cpu"]["median"] - q["cpu"]["min"] for q in pts]
            hi = [q["cpu"]["max"] - q["cpu"]["median"] for q in pts]
            ax.errorbar(err, med, yerr=[lo, hi], ms=5, capsize=2, label=m, **look)
        ax.set_xscale("log")
        ax.set_yscale("log")
        floor = w["reference_error_estimate"]
        ax.axvspan(floor / 30, floor, color="0.85", lw=0, label="below the reference's error")
        ax.set_xlabel("error: largest entry of M(T) and Q(T) minus the reference")
        ax.set_ylabel("CPU time per run [s] (median, min-max)")
        ax.set_title(f"work-precision, n = {w['n']}, T = {w['T']:g}")
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=8, ncol=2, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return fig


def _long_time_figure(plt: Any, ms: Mapping[str, Any], style: Style = plain_style) -> Any:
    """The invariants' errors against the step number, one panel per n (None if not run).  Its
    lines are invariants of one method (named in the title), so ``style`` is not used."""
    lts = ms.get("long-time", [])
    if not lts:
        return None
    # one panel per run (n, flow), two to a row, on a shared error axis
    ncols = min(2, len(lts))
    nrows = -(-len(lts) // ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(5.0 * ncols, 4.2 * nrows), squeeze=False,
                             sharey=True)  # fmt: skip
    for ax in list(axes.flat)[len(lts) :]:
        ax.set_visible(False)
    for ax, d in zip(axes.flat, lts, strict=False):
        N = np.asarray(d["N"], dtype=float)
        for key, vals in d["errors"].items():
            s = d["slope"][key]
            lab = f"{key} (slope {s:.2f})" if s is not None else key
            ax.loglog(N, np.maximum(vals, 1e-18), marker=".", label=lab)
        ax.loglog(N, EPS * np.sqrt(N), "k--", label=r"$\varepsilon\sqrt{N}$")
        ax.loglog(N, 10 * EPS * np.sqrt(N), "k:", label=r"$10\,\varepsilon\sqrt{N}$")
        ax.set_xlabel("step number N")
        ax.set_ylabel("largest relative error up to step N")
        ax.set_title(
            f"n = {d['n']}, h = {d['h']:g}, {d['steps']} steps\n({d['flow']})", fontsize=10
        )
        ax.legend(fontsize=8)
    return fig


def _throughput_figure(plt: Any, ms: Mapping[str, Any], style: Style = plain_style) -> Any:
    """Body-steps per second against the batch size (None if not run).  One method (the
    Moser-Veselov step), three ways of calling it: one colour, three markers and line styles."""
    thr = ms.get("throughput")
    if not thr:
        return None
    fig, ax = plt.subplots(figsize=(6.5, 5))
    B = [r["batch"] for r in thr["rows"]]
    steps = [r["step_body_steps_per_s"] for r in thr["rows"]]
    ax.loglog(B, steps, label="MVStepper.step (one call)", **style("MVStepper.step", marker="o"))
    for be, mk, ls in (("numpy", "^", "--"), ("numba", "v", "-.")):
        key = f"flow_{be}_body_steps_per_s"
        if all(key in r for r in thr["rows"]):
            lab = f"mv_flow ({'NumPy path' if be == 'numpy' else 'compiled, numba'})"
            ax.loglog(B, [r[key] for r in thr["rows"]], label=lab,
                      **style("mv_flow", marker=mk, ls=ls))  # fmt: skip
    products = [r["matmul_products_per_s"] for r in thr["rows"]]
    ax.loglog(B, products, label="matmul (np.matmul on (B, 3, 3))",
              **style("matmul", marker="s", ls=":"))  # fmt: skip
    if all("matmul_soa" in r for r in thr["rows"]):
        soa = [r["batch"] / r["matmul_soa"]["median"] for r in thr["rows"]]
        ax.loglog(B, soa, label="matmul (einsum on (3, 3, B), the engine's layout)",
                  **style("matmul", marker="D", ls="-."))  # fmt: skip
    ax.axhline(5e6, label="goal (5e6)", **style("goal"))
    ax.set_xlabel("batch size (bodies)")
    ax.set_ylabel("body-steps (or products) per CPU second")
    ax.set_title("throughput, n = 3")
    ax.legend(fontsize=8)
    return fig


def _cost_vs_n_figure(plt: Any, ms: Mapping[str, Any], style: Style = plain_style) -> Any:
    """The cost of a step against n in matrix products (None if not run)."""
    cost = ms.get("cost-vs-n")
    if not cost:
        return None
    fig, ax = plt.subplots(figsize=(6.5, 5))
    ns = [r["n"] for r in cost["rows"]]
    units = [r["matmul_equivalents"] for r in cost["rows"]]
    ax.loglog(ns, units, label="mv_flow (NumPy path)", **style("mv_flow", marker="^", ls="--"))
    comp = cost.get("compiled_n3")
    if comp:
        ax.loglog([3], [comp["matmul_equivalents"]], ms=9, label="mv_flow (compiled, numba; n = 3)",
                  **style("mv_flow", marker="v", ls="none"))  # fmt: skip
    ax.set_xticks(ns, [str(n) for n in ns])  # the sizes measured, in plain numbers
    ax.xaxis.set_minor_locator(plt.NullLocator())
    ax.set_xlabel("n")
    ax.set_ylabel("CPU time in units of one n x n matmul")
    ax.set_title("per-step cost against n (single body)")
    ax.legend(fontsize=8)
    return fig


#: The figures by name, in the order they are drawn.
_FIGURES: dict[str, Callable[..., Any]] = {
    "work_precision": _work_precision_figure,
    "long_time": _long_time_figure,
    "throughput": _throughput_figure,
    "cost_vs_n": _cost_vs_n_figure,
}


def _figures(
    ms: Mapping[str, Any], names: set[str] | None = None, style: Style | None = None
) -> dict[str, Any]:
    """The figures of the sections in the measurements ``ms`` that are among ``names`` (all when
    ``names`` is empty), by name, drawn with ``style`` (:data:`Style`; default: the command
    line's, :func:`plain_style`, and twelve colours for the work-precision methods)."""
    import matplotlib.pyplot as plt

    unknown = (names or set()) - set(_FIGURES)
    if unknown:
        raise InputError(
            f"figures: names must be among work_precision, long_time, throughput, cost_vs_n; "
            f"got {sorted(unknown)}"
        )
    figs: dict[str, Any] = {}
    for stem, draw in _FIGURES.items():
        if names and stem not in names:
            continue
        fig = draw(plt, ms) if style is None else draw(plt, ms, style)
        if fig is not None:
            fig.tight_layout()
            figs[stem] = fig
    return figs


def _plot(ms: Mapping[str, Any], directory: Path) -> list[Path]:
    """The figures of :func:`_figures` as PNG and SVG files in ``directory`` (Agg backend)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    directory.mkdir(parents=True, exist_ok=True)
    files: list[Path] = []
    for stem, fig in _figures(ms).items():
        for ext in ("png", "svg"):
            path = directory / f"{stem}.{ext}"
            fig.savefig(path, dpi=120)
            files.append(path)
        plt.close(fig)
    return files
