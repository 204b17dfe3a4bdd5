"""The figures of the learning pages: the training curves of the SO(n) network and of the residual
network, and the training time to a fixed loss of the learning benchmark.

Each method is drawn in its colour of :mod:`symrb_book.style` and labelled with its name first
(``"gradient descent (Cayley, Armijo)"``), the name :func:`symrb_book.style.series_of` reads back.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from .style import series_style


def so_training_figure(runs: Mapping[str, Any], labels: Mapping[str, str], loss_star: float) -> Any:
    """Two semilog panels against the iteration: the loss above its optimum ``loss_star`` and the
    first-order optimality residual, one curve per method.

    Parameters
    ----------
    runs : mapping
        ``{method: run}``: a scene result per training method (``"gradient descent"``,
        ``"extended MSA"``, ``"shooting"``) with the records ``loss`` and ``residual``.
    labels : mapping
        ``{method: detail}``: the words after the method's name in the legend.
    loss_star : float
        The optimal loss.
    """
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6))
    for method, run in runs.items():
        label = f"{method} ({labels[method]})" if labels.get(method) else method
        loss = np.maximum(np.asarray(run["loss"]) - loss_star, 1e-16)
        look = series_style(method, marker=".", ms=3)
        axes[0].semilogy(run.times["loss"], loss, label=label, **look)
        axes[1].semilogy(run.times["residual"], run["residual"], label=label, **look)
    axes[0].set(xlabel="iteration (shooting: evaluation)", ylabel="$L - L^*$",
                title="loss above the optimum")  # fmt: skip
    axes[1].set(xlabel="iteration (shooting: evaluation)", ylabel="$\\max_k \\|G_k\\|_F$",
                title="first-order optimality residual")  # fmt: skip
    axes[1].legend(fontsize=8)
    fig.tight_layout()
    return fig


def loss_figure(runs: Mapping[str, Any], labels: Mapping[str, str], title: str) -> Any:
    """The training loss against the iteration on a log axis, one curve per method.

    Parameters
    ----------
    runs : mapping
        ``{method: run}``: a scene result per training method with the record ``loss``.
    labels : mapping
        ``{method: detail}``: the words after the method's name in the legend.
    title : str
        The panel's title.
    """
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.4))
    for method, run in runs.items():
        label = f"{method} ({labels[method]})" if labels.get(method) else method
        ax.plot(run.times["loss"], run["loss"], label=label, **series_style(method, marker=""))
    ax.set(xlabel="iteration", ylabel="training loss (sum over samples)", yscale="log",
           title=title)  # fmt: skip
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


#: The training method of each run of the learning benchmark, by the start of its name.
BENCH_METHODS = {"gradient_descent": "gradient descent", "msa": "extended MSA"}


def bench_method(key: str) -> str:
    """The training method of the learning benchmark's run ``key`` (``msa_rho_3.0``: the
    extended MSA)."""
    for prefix, method in BENCH_METHODS.items():
        if key.startswith(prefix):
            return method
    raise KeyError(f"bench_method: no training method for the run {key!r}")


def training_time_figure(training: Mapping[str, Any]) -> Any:
    """Horizontal bars on a log axis: the median time to the target loss of each run of the
    learning benchmark (``training`` its ``"training"`` record), with the iterations it took,
    one colour per training method."""
    import matplotlib.pyplot as plt
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    names = list(training["seconds_median"])
    fig, ax = plt.subplots(figsize=(7, 3.2))
    for method in dict.fromkeys(bench_method(k) for k in names):
        mine = [i for i, k in enumerate(names) if bench_method(k) == method]
        colour = series_style(method)["color"]
        ax.barh(mine, [training["seconds_median"][names[i]] * 1e3 for i in mine], label=method,
                color=colour)  # fmt: skip
    ax.set_yticks(range(len(names)), names)
    for i, k in enumerate(names):
        ax.text(training["seconds_median"][k] * 1e3, i, f"  {training['iterations_to_target'][k]} it.",
                va="center", fontsize=8)  # fmt: skip
    ax.set(xscale="log", xlabel="ms to the target loss (median)",
           title="training time to a fixed loss")  # fmt: skip
    ax.xaxis.set_major_locator(LogLocator(subs=(1, 2, 5)))  # 20, 50, 100, ... ms, in plain numbers
    ax.xaxis.set_major_formatter(FuncFormatter(lambda x, _pos: f"{x:g}"))
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlim(right=ax.get_xlim()[1] * 2)  # room for the counts of iterations
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    return fig
