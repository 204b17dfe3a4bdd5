"""The scene file format as data: every key of every system, read from the models themselves.

:func:`describe_schema` lists the keys of each registered system (its top-level keys and the
keys of its ``[parameters]``, ``[integrator]``, ``[horizon]``, ``[observables]`` and
``[compare]`` tables), one :class:`SchemaKey` each, with the type, the default and the allowed
values as the pydantic models declare them; :func:`describe_model` does the same for one model
(such as :class:`~symrb.scenes.When`, the value of every observable).  Nothing here is typed
twice: a key added to a model appears in the listing by itself.
"""

from __future__ import annotations

import dataclasses
import types
import typing
from typing import Any, Literal, Union

import annotated_types
from pydantic import BaseModel

from ..errors import InputError
from .schema import _SYSTEMS, system_name

# the public names are listed (and re-exported) by symrb.scenes.__all__

#: the tables of a scene, in the order a scene file gives them
TABLES = ("", "parameters", "integrator", "horizon", "observables", "compare")
_BOUNDS = (
    (annotated_types.Gt, "gt", ">"),
    (annotated_types.Ge, "ge", ">="),
    (annotated_types.Lt, "lt", "<"),
    (annotated_types.Le, "le", "<="),
)


@dataclasses.dataclass(frozen=True)
class SchemaKey:
    """One key of a scene file.

    Attributes
    ----------
    system : str
        The system (``"rigid_body"``, ...), or ``""`` for a key of a shared model.
    table : str
        The TOML table holding the key: ``""`` (top level), ``"parameters"``, ``"integrator"``,
        ``"horizon"``, ``"observables"`` or ``"compare"``.
    variant : str
        For a table with several forms, the key and value that choose this one (such as
        ``method = "mv"``); else ``""``.
    key : str
        The key's name.
    type : str
        Its type in words, with its bounds (``"float > 0"``).
    default : str or None
        The default as TOML text, ``"(not set)"`` when leaving it out means "derived" or
        "none"; None when the key is required.
    allowed : tuple of str
        The allowed values of a key with a fixed list of them, as TOML text; else empty.
    note : str
        What else to know (the effect an observable needs); often empty.

    Examples
    --------
    >>> from symrb.scenes import describe_schema
    >>> key = next(k for k in describe_schema("rigid_body") if k.key == "order"
    ...            and k.variant == 'method = "mv"')
    >>> key.type, key.default, key.allowed
    ('integer', '2', ('2', '4', '6', '8', '10'))
    """

    system: str
    table: str
    variant: str
    key: str
    type: str
    default: str | None
    allowed: tuple[str, ...] = ()
    note: str = ""

    @property
    def required(self) -> bool:
        """True when a scene must give the key."""
        return self.default is None


def _toml(value: Any) -> str:
    """A value as TOML text."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, tuple | list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return repr(value)


def _literals(annotation: Any) -> tuple[Any, ...]:
    """The values of the Literals in a type (inside Optional, a union or a list), else ()."""
    if typing.get_origin(annotation) is Literal:
        return typing.get_args(annotation)
    found: list[Any] = []
    for arg in typing.get_args(annotation):
        if arg is not Ellipsis and arg is not type(None):
            found += [a for a in _literals(arg) if a not in found]
    return tuple(found)


def _is_union(annotation: Any) -> bool:
    return typing.get_origin(annotation) in (Union, types.UnionType)


def _type_name(annotation: Any) -> str:
    """A type in words: integer, float, string, boolean, list of floats, matrix, ..."""
    origin, args = typing.get_origin(annotation), typing.get_args(annotation)
    if origin is typing.Annotated:
        return _type_name(args[0])
    if _is_union(annotation):
        names = [_type_name(a) for a in args if a is not type(None)]
        return " or ".join(dict.fromkeys(names))
    if origin is Literal:
        kinds = {type(a) for a in args}
        return _type_name(kinds.pop()) if len(kinds) == 1 else "value"
    if origin is tuple:
        inner = _type_name(args[0])
        if inner == "list of floats":
            return "matrix (list of lists of floats)"
        if inner.startswith("matrix"):
            return "list of matrices"
        return f"list of {inner}s"
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return "table"
    return {bool: "boolean", int: "integer", float: "float", str: "string"}.get(
        annotation, getattr(annotation, "__name__", str(annotation))
    )


def _bounds(metadata: list[Any]) -> str:
    found = [
        f"{sign} {getattr(m, attr)}"
        for m in metadata
        for kind, attr, sign in _BOUNDS
        if isinstance(m, kind)
    ]
    return " " + " and ".join(found) if found else ""


def describe_model(
    model: type[BaseModel], system: str = "", table: str = "", variant: str = ""
) -> list[SchemaKey]:
    """The keys of one scene model, in the order it declares them.

    Parameters
    ----------
    model : pydantic model class
        A model of :mod:`symrb.scenes` (such as :class:`~symrb.scenes.When`, or a system's
        parameters).
    system, table, variant : str
        Copied into each :class:`SchemaKey` (where the model sits in a scene).

    Returns
    -------
    list of SchemaKey
        One per field of ``model``.

    Examples
    --------
    >>> from symrb.scenes import When, describe_model
    >>> [(k.key, k.type) for k in describe_model(When)][:3]
    [('end', 'boolean'), ('every', 'integer >= 1'), ('times', 'list of floats')]
    """
    if not (isinstance(model, type) and issubclass(model, BaseModel)):
        raise InputError(f"model must be a pydantic model class, got {model!r}")
    rows = []
    for key, field in model.model_fields.items():
        if field.is_required():
            default = None
        elif field.default is None:
            default = "(not set)"
        else:
            default = _toml(field.default)
        rows.append(
            SchemaKey(
                system=system,
                table=table,
                variant=variant,
                key=key,
                type=_type_name(field.annotation) + _bounds(field.metadata),
                default=default,
                allowed=tuple(_toml(a) for a in _literals(field.annotation)),
            )
        )
    return rows


def _variants(annotation: Any) -> list[tuple[str, type[BaseModel]]]:
    """The forms of a table: (``key = "value"`` choosing it, model) for a discriminated union,
    else [("", model)]; nested unions (the compared run's integrator) are flattened."""
    if typing.get_origin(annotation) is typing.Annotated or _is_union(annotation):
        out = []
        for arg in typing.get_args(annotation):
            if (
                isinstance(arg, type)
                or typing.get_origin(arg) in (typing.Annotated, Union)
                or (_is_union(arg))
            ):
                out += _variants(arg)
        return out
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        fields = annotation.model_fields
        for tag in ("method", "kind"):  # the key that alone chooses this form
            values = _literals(fields[tag].annotation) if tag in fields else ()
            if len(values) == 1 and fields[tag].is_required():
                return [(f"{tag} = {_toml(values[0])}", annotation)]
        for tag in ("method", "kind"):  # a form chosen by one of several values
            values = _literals(fields[tag].annotation) if tag in fields else ()
            if values:
                return [(f"{tag} = " + ", ".join(_toml(v) for v in values), annotation)]
        return [("", annotation)]
    return []


def describe_schema(system: str | None = None) -> list[SchemaKey]:
    """Every key of every registered scene system (or of one), read from its model.

    The top-level keys (``system``, ``title``, ``effects``), then the keys of each table:
    ``[parameters]``, ``[integrator]`` (one :attr:`SchemaKey.variant` per method or kind, the
    key that chooses it first), ``[horizon]``, ``[observables]`` (one key per observable, of
    type ``when``: a :class:`~symrb.scenes.When`; its note names the effect it needs) and
    ``[compare]`` (the systems that have it; its ``integrator`` is a table of the same forms
    as ``[integrator]``).

    Parameters
    ----------
    system : str, optional
        A registered system name (``system = ...`` in a scene); default every system, in the
        order they were registered.

    Returns
    -------
    list of SchemaKey
        The keys, system by system, table by table.

    Raises
    ------
    InputError
        ``system`` is not a registered system.

    Examples
    --------
    >>> from symrb.scenes import describe_schema
    >>> keys = describe_schema("toda")
    >>> [k.key for k in keys if k.table == "parameters"]
    ['k', 'a', 'b', 'seed']
    >>> next(k for k in keys if k.key == "k").type
    'integer >= 2'
    """
    if system is not None and system not in _SYSTEMS:
        raise InputError(f"system must be one of {sorted(_SYSTEMS)}, got {system!r}")
    models = [_SYSTEMS[system]] if system is not None else list(_SYSTEMS.values())
    rows: list[SchemaKey] = []
    for model in models:
        name = system_name(model)
        fields = model.model_fields
        top = [k for k in describe_model(model, name) if k.key in ("system", "title", "effects")]
        top.sort(key=lambda k: ("system", "title", "effects").index(k.key))
        rows += [
            dataclasses.replace(k, allowed=(_toml(name),), default=None)
            if k.key == "system"
            else dataclasses.replace(k, allowed=tuple(_toml(e) for e in model.EFFECTS))
            if k.key == "effects"
            else k
            for k in top
        ]
        for table in ("parameters", "integrator", "horizon"):
            for variant, sub in _variants(fields[table].annotation):
                rows += describe_model(sub, name, table, variant)
        for obs, effect in model.OBSERVABLES.items():
            note = f"needs the effect {_toml(effect)}" if effect else ""
            rows.append(SchemaKey(name, "observables", "", obs, "when", "(not set)", (), note))
        if "compare" in fields:
            for k in describe_model(_compare_model(fields["compare"].annotation), name, "compare"):
                if k.key == "integrator":
                    k = dataclasses.replace(k, type="table (as [integrator])", allowed=())
                rows.append(k)
    return rows


def _compare_model(annotation: Any) -> type[BaseModel]:
    """The model of one ``[compare]`` table inside its optional, tagged union."""
    for arg in typing.get_args(annotation):
        if isinstance(arg, type) and issubclass(arg, BaseModel):
            return arg
        found = _compare_model(arg) if typing.get_args(arg) else None
        if found is not None:
            return found
    return None  # type: ignore[return-value]
