"""One colour, one marker and one line style per method, for every figure of the book.

A method keeps its look from figure to figure: DOP853 is black with squares on the accuracy page
and wherever else it appears.  SciPy's solvers are dashed, symrb's methods solid and the paper's
own algorithms dash-dotted; the training methods of the learning pages have colours of their own
too.  :func:`method_style` accepts the names under which a method appears in the book: the
benchmark's names (``MV-pre10``), the keys of :data:`symrb.rigid_body.METHODS` with an order
(``("mv", 10)``), and function names (``mv_flow``, ``mv_algorithm2``).  Series that are not
methods (a matrix product as the unit of cost, a goal) have their own entries in
:data:`SERIES_STYLE`, in colours no method has; :func:`series_style` looks a series up in both
tables, which is what the benchmark's figures are given (``BenchResult.figures(style=...)``).
"""

from __future__ import annotations

from typing import Any

from symrb.errors import InputError

_SCIPY = {"ls": "--"}
_SYMRB = {"ls": "-"}
_PAPER = {"ls": "-."}

#: The style of each method by its canonical name: matplotlib keyword arguments.
METHOD_STYLE: dict[str, dict[str, Any]] = {
    # SciPy's solve_ivp (and symrb.integrate, which calls DOP853 on the same field)
    "DOP853": {"color": "#000000", "marker": "s", **_SCIPY},
    "RK45": {"color": "#7f7f7f", "marker": "o", **_SCIPY},
    "RK23": {"color": "#c7c7c7", "marker": "o", **_SCIPY},
    "LSODA": {"color": "#8c564b", "marker": "D", **_SCIPY},
    "Radau": {"color": "#bcbd22", "marker": "P", **_SCIPY},
    "BDF": {"color": "#dbdb8d", "marker": "X", **_SCIPY},
    "integrate": {"color": "#c49c94", "marker": "x", **_SCIPY},
    # symrb's methods
    "MV": {"color": "#1f77b4", "marker": "v", **_SYMRB},
    "MV-fast": {"color": "#17becf", "marker": "^", **_SYMRB},
    "MV-comp2": {"color": "#7b4173", "marker": "<", **_SYMRB},
    "MV-comp4": {"color": "#98df8a", "marker": "<", **_SYMRB},
    "MV-comp6": {"color": "#2ca02c", "marker": ">", **_SYMRB},
    "MV-comp8": {"color": "#0b5d1e", "marker": "p", **_SYMRB},
    "MV-pre4": {"color": "#ffbb78", "marker": "h", **_SYMRB},
    "MV-pre6": {"color": "#ff7f0e", "marker": "H", **_SYMRB},
    "MV-pre8": {"color": "#d62728", "marker": "d", **_SYMRB},
    "MV-pre10": {"color": "#9467bd", "marker": "*", **_SYMRB},
    "RKMK4": {"color": "#e377c2", "marker": "8", **_SYMRB},
    "midpoint": {"color": "#f7b6d2", "marker": "P", **_SYMRB},
    "exact": {"color": "#393b79", "marker": "X", **_SYMRB},
    # symrb.splitting.splitting_flow (planar rotations composed to high order), by order
    "split2": {"color": "#e7ba52", "marker": "1", **_SYMRB},
    "split4": {"color": "#bd9e39", "marker": "2", **_SYMRB},
    "split6": {"color": "#8c6d31", "marker": "3", **_SYMRB},
    "split8": {"color": "#ad494a", "marker": "4", **_SYMRB},
    # the paper's algorithms (symrb.paper)
    "MV-Algorithm 1": {"color": "#aec7e8", "marker": "o", **_PAPER},
    "MV-Algorithm 2": {"color": "#6b6ecf", "marker": "s", **_PAPER},
    "symmetric algorithm": {"color": "#843c39", "marker": "D", **_PAPER},
    # training (symrb.learning): one look for a method on every network it trains
    "gradient descent": {"color": "#637939", "marker": "o", **_SYMRB},
    "extended MSA": {"color": "#a55194", "marker": "s", **_SYMRB},
    "shooting": {"color": "#6baed6", "marker": "D", **_SYMRB},
}

#: Series of the book's figures that are not methods, in colours no method has.
SERIES_STYLE: dict[str, dict[str, Any]] = {
    # a batched n x n matrix product: the unit the cost of a step is measured in
    "matmul": {"color": "#5254a3", "marker": "s", "ls": ":"},
    # a goal drawn as a line
    "goal": {"color": "#999999", "marker": "", "ls": ":"},
}

#: Other names of the same methods: function names and the keys of symrb.rigid_body.METHODS
#: (with their default order).
ALIASES: dict[str, str] = {
    "mv": "MV-fast",
    "mv_flow": "MV-fast",
    "composition": "MV-comp4",
    "composed_rigid_body_flow": "MV-comp4",
    "rkmk4": "RKMK4",
    "rkmk4_rigid_body_flow": "RKMK4",
    "midpoint_rigid_body_flow": "midpoint",
    "rigid_body_exact": "exact",
    "splitting": "split4",
    "splitting_flow": "split4",
    "discrete_rigid_body_flow": "MV",
    "mv_algorithm1": "MV-Algorithm 1",
    "mv_algorithm2": "MV-Algorithm 2",
    "symmetric_flow": "symmetric algorithm",
    "symmetric_step": "symmetric algorithm",
    "MVStepper.step": "MV-fast",
    # SciPy on symrb's generated field: the same method, drawn dotted with hollow markers
    "DOP853-gen": "DOP853",
    "RK45-gen": "RK45",
    "LSODA-gen": "LSODA",
    "train": "gradient descent",
    "train_so_gradient": "gradient descent",
    "train_msa": "extended MSA",
    "train_so_msa": "extended MSA",
    "train_so_shooting": "shooting",
}

#: The families whose order picks the style: (name, order) -> canonical name.
_BY_ORDER = {"mv": "MV-pre{}", "mv_flow": "MV-pre{}", "composition": "MV-comp{}",
             "composed_rigid_body_flow": "MV-comp{}", "splitting": "split{}",
             "splitting_flow": "split{}"}  # fmt: skip


def canonical(name: str, order: int | None = None) -> str:
    """The canonical name of a method given by any of its names (and its order, for the
    families ``mv``, ``composition`` and ``splitting`` of :data:`symrb.rigid_body.METHODS`).

    Raises
    ------
    InputError
        For a name that has no style.
    """
    if order is not None and name in _BY_ORDER:
        if name in ("mv", "mv_flow") and order == 2:
            return "MV-fast"
        name = _BY_ORDER[name].format(int(order))
    name = ALIASES.get(name, name)
    if name not in METHOD_STYLE:
        raise InputError(
            f"method_style: no style for the method {name!r} (order {order}); add it to "
            "symrb_book.style.METHOD_STYLE"
        )
    return name


def method_style(name: str, order: int | None = None, **overrides: Any) -> dict[str, Any]:
    """The matplotlib keyword arguments (colour, marker, line style) of a method, with the
    keyword arguments ``overrides`` on top.

    Parameters
    ----------
    name : str
        A canonical name (a key of :data:`METHOD_STYLE`), an alias (:data:`ALIASES`) or a key of
        :data:`symrb.rigid_body.METHODS`.
    order : int, optional
        The order, for ``mv`` (2 the Moser-Veselov step, 4-10 preprocessed) and ``composition``.
    **overrides
        Keyword arguments that replace the table's (e.g. ``ls=":"`` for a second view of the
        same method).

    Returns
    -------
    dict
        ``color``, ``marker``, ``ls`` and the overrides.

    Examples
    --------
    >>> method_style("mv_flow") == method_style("MV-fast")
    True
    >>> method_style("mv", order=10)["marker"]
    '*'
    """
    return {**METHOD_STYLE[canonical(name, order)], **overrides}


def series_style(name: str, order: int | None = None, **overrides: Any) -> dict[str, Any]:
    """The matplotlib keyword arguments of a series of a figure: a method's
    (:func:`method_style`) or another series' (:data:`SERIES_STYLE`), with ``overrides`` on top
    (a marker or line style telling two runs of one method apart; never a colour).

    Raises
    ------
    InputError
        For a series in neither table, or an override of the colour.
    """
    if "color" in overrides or "c" in overrides:
        raise InputError(f"series_style: {name!r} keeps the colour of the style table")
    if name in SERIES_STYLE:
        return {**SERIES_STYLE[name], **overrides}
    return method_style(name, order, **overrides)


def series_of(label: str) -> str:
    """The name in the style tables of the series a figure labels ``label``: the label's head
    before ``" ("`` or ``", "`` (``"mv_flow (NumPy path)"`` is ``mv_flow``'s, that is
    ``MV-fast``), looked up in :data:`SERIES_STYLE` and then as a method (:func:`canonical`).

    Raises
    ------
    InputError
        For a label whose head is in neither table.
    """
    head = label.split(" (")[0].split(", ")[0].strip()
    return head if head in SERIES_STYLE else canonical(head)
