r"""Shared numpydoc fragments, defined once and substituted into docstrings.

A line of a docstring that holds only ``%(name)s`` is replaced by the fragment ``name``,
indented as that line (in the manner of SciPy's private ``doccer``).  Other ``%`` signs are left
alone, so LaTeX and format strings in the text need no escaping.
"""

from __future__ import annotations

import re
import textwrap
from collections.abc import Callable, Mapping
from typing import TypeVar

F = TypeVar("F", bound=Callable[..., object])

_LINE = re.compile(r"^(?P<indent>[ \t]*)%\((?P<name>\w+)\)s[ \t]*$", re.M)

#: the fragments, each a numpydoc entry ``name : type`` and its indented description
FRAGMENTS: dict[str, str] = {
    "Q0": "Q0 : array_like, shape (..., n, n)\n    The initial attitude, in SO(n).",
    "M0": (
        "M0 : array_like, shape (..., n, n)\n"
        "    The initial body momentum (skew-symmetric, continuous scale)."
    ),
    "lam": (
        "lam : array_like, shape (..., n)\n"
        "    The diagonal of :math:`\\Lambda`, with :math:`\\lambda_i+\\lambda_j>0` for "
        ":math:`i \\ne j`."
    ),
    "lam_positive": (
        "lam : array_like, shape (..., n)\n    The diagonal of :math:`\\Lambda`, all entries > 0."
    ),
    "h": "h : float\n    The time step, > 0.",
    "steps": "steps : int\n    The number of steps, >= 0.",
    "save_every": (
        "save_every : int, optional\n"
        "    Keep the states :math:`k = 0, s, 2s, \\dots` (``s = save_every``)."
    ),
    "progress": (
        "progress : bool, optional\n    Show a tqdm progress bar (needs the optional package tqdm)."
    ),
    "halve": (
        "halve : bool, optional\n"
        "    When a step has no solution on the branch (:math:`h` times the momentum past the "
        "fold of\n"
        "    :math:`J_D`) or Newton fails, take it as :math:`2^j` steps of :math:`h/2^j` with the\n"
        "    smallest such :math:`j \\le 12` (for the continuous-time use, where :math:`h` is "
        "only a\n"
        "    resolution); ``halvings`` and ``message`` say which steps were halved.  Without it "
        "such\n"
        "    a step ends the run (``failed_step``, ``fold`` and ``h_max`` say where, how far "
        "past the\n"
        "    fold and the largest step that works)."
    ),
    "diagnostics": (
        "diagnostics : bool, optional\n"
        "    Also estimate the solver's condition number at every solve (``condition``; costs "
        "about\n"
        "    sixteen Sylvester solves a step)."
    ),
}


def fill_doc(blocks: Mapping[str, str]) -> Callable[[F], F]:
    """Decorator: each docstring line ``%(name)s`` becomes ``blocks[name]``, indented like it
    (KeyError for an unknown name, so a typo fails at import).

    Parameters
    ----------
    blocks : mapping of str to str
        The blocks by name, unindented (a numpydoc entry: the header line, then its indented
        description).

    Returns
    -------
    callable
        The decorator; it returns the object it decorates, its ``__doc__`` filled in.

    Examples
    --------
    >>> from symrb._docs import fill_doc
    >>> @fill_doc({"x": "x : float\\n    The input."})
    ... def f(x):
    ...     '''Parameters
    ...     ----------
    ...     %(x)s
    ...     '''
    >>> print(f.__doc__.splitlines()[2:4])
    ['    x : float', '        The input.']
    """

    def fill_one(obj: F) -> F:
        if obj.__doc__:
            obj.__doc__ = _LINE.sub(
                lambda m: textwrap.indent(blocks[m["name"]], m["indent"]), obj.__doc__
            )
        return obj

    return fill_one


#: :func:`fill_doc` with the rigid-body fragments :data:`FRAGMENTS`
fill = fill_doc(FRAGMENTS)
