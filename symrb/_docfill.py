"""Docstring parameter blocks written once: :func:`fill_doc` puts a named block where a docstring
has a line ``%(name)s`` (used by :mod:`symrb.learning` and :mod:`symrb.orbits`)."""

from __future__ import annotations

import re
import textwrap
from collections.abc import Callable, Mapping
from typing import TypeVar

_F = TypeVar("_F", bound=Callable[..., object])
#: a docstring line holding only ``%(name)s``: the block ``name`` goes there
_SLOT = re.compile(r"^( *)%\((\w+)\)s$", re.MULTILINE)


def fill_doc(blocks: Mapping[str, str]) -> Callable[[_F], _F]:
    """Decorator: each docstring line ``%(name)s`` becomes ``blocks[name]``, indented like it.

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
    >>> from symrb._docfill import fill_doc
    >>> @fill_doc({"x": "x : float\\n    The input."})
    ... def f(x):
    ...     '''Parameters
    ...     ----------
    ...     %(x)s
    ...     '''
    >>> print(f.__doc__.splitlines()[2:4])
    ['    x : float', '        The input.']
    """

    def fill(obj: _F) -> _F:
        obj.__doc__ = _SLOT.sub(lambda m: textwrap.indent(blocks[m[2]], m[1]), obj.__doc__ or "")
        return obj

    return fill
