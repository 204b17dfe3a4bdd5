"""Reading and validating a scene: :func:`parse_scene`, :func:`load_scene`, and the errors that
name each bad key, its TOML line and the allowed values (:class:`~symrb.scenes.SceneError`)."""

from __future__ import annotations

import os
import re
import tomllib
import typing
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ValidationError

from ..errors import InputError
from .schema import _SCENES, _SYSTEMS, Scene, SceneError, _adapter, _SceneBase

# ---------------------------------------------------------------------------------------------
# errors: pydantic's loc -> key, TOML line, allowed values


def _toml_lines(text: str) -> dict[tuple[str, ...], int]:
    """The 1-based line of every key of a TOML text, by its path (tomllib keeps no positions).

    Table headers ``[a.b]``, array-of-tables headers ``[[a]]`` (indexed), ``key = value`` lines
    with dotted keys, and the keys of single-line inline tables are found.
    """
    out: dict[tuple[str, ...], int] = {}
    table: tuple[str, ...] = ()
    counts: dict[tuple[str, ...], int] = {}

    def split(path: str) -> tuple[str, ...]:
        return tuple(p.strip().strip("\"'") for p in path.split("."))

    key_re = re.compile(
        r"""^\s*((?:[A-Za-z0-9_\-]+|"[^"]*"|'[^']*')(?:\s*\.\s*(?:[A-Za-z0-9_\-]+|"[^"]*"|'[^']*'))*)\s*="""
    )
    for i, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        if line.startswith("[["):
            path = split(line[2 : line.index("]]")])
            idx = counts.get(path, 0)
            counts[path] = idx + 1
            table = path + (str(idx),)
            out.setdefault(path, i)
            out[table] = i
            continue
        if line.startswith("["):
            table = split(line[1 : line.index("]")])
            out[table] = i
            continue
        m = key_re.match(raw)
        if m:
            path = table + split(m.group(1))
            out[path] = i
            rest = raw[m.end() :]
            if "{" in rest:
                for inner in re.finditer(r"([A-Za-z0-9_\-]+)\s*=", rest):
                    out.setdefault(path + (inner.group(1),), i)
    return out


def _allowed(model: Any, loc: Sequence[Any], err: Mapping[str, Any]) -> list[Any] | None:
    """The allowed values (literal choices, or the keys of a model) at ``loc``."""
    ctx = err.get("ctx") or {}
    if "expected" in ctx:
        return re.findall(r"'([^']*)'|(\d+)", str(ctx["expected"])) and [
            a or int(b) for a, b in re.findall(r"'([^']*)'|(\d+)", str(ctx["expected"]))
        ]
    if "expected_tags" in ctx:
        return re.findall(r"'([^']*)'", str(ctx["expected_tags"]))
    if err.get("type") == "extra_forbidden":
        parent = _model_at(model, loc[:-1])
        if parent is None:  # in a member of a union: the raw location names its kind
            raw = [str(x) for x in err.get("loc", ())]
            parent = _model_at(model, raw[1:-1] if raw and raw[0] not in
                               getattr(model, "model_fields", {}) else raw[:-1])  # fmt: skip
        if parent is not None:
            return list(parent.model_fields)
    if err.get("type") == "literal_error" and "expected" in ctx:
        return None
    return None


def _model_at(model: Any, loc: Sequence[Any]) -> Any:
    """The pydantic model class at ``loc`` below ``model`` (None if not a model)."""
    cur: Any = model
    members: list[Any] = []  # the models of a union, until the next part names a kind
    for part in loc:
        if _FAMILY.match(str(part)) or str(part) in ("[compare]", "[[compare]]"):
            continue  # the tag of a union of unions (a family of integrators, one or more runs)
        if members:
            cur = next((m for m in members if str(part) in _tags(m)), None)
            members = []
            continue
        if not (isinstance(cur, type) and issubclass(cur, BaseModel)):
            return None
        if str(part).isdigit():  # an entry of an array of tables
            continue
        field = cur.model_fields.get(str(part))
        if field is None:
            return None
        models = _models_in(field.annotation)
        cur = models[0] if len(models) == 1 else None
        members = models if len(models) > 1 else []
    return cur


def _models_in(ann: Any) -> list[type[BaseModel]]:
    """The pydantic models in an annotation (through unions, Annotated, tuples, dicts)."""
    cands = [ann]
    for _ in range(6):
        nxt: list[Any] = []
        for c in cands:
            args = typing.get_args(c)
            nxt.extend(args if args else [c])
        cands = nxt
    return list(dict.fromkeys(c for c in cands
                              if isinstance(c, type) and issubclass(c, BaseModel)))  # fmt: skip


#: the tag of a member of an integrator union of unions (see ``symrb.scenes.systems._compare``)
_FAMILY = re.compile(r"^\[(method|kind)\]$")


def _tags(model: type[BaseModel]) -> tuple[str, ...]:
    """The values of an integrator model's discriminator: its ``kind`` (the literal), or else its
    ``method`` (the rigid body's integrators, whose ``kind`` is an option of a composition)."""
    for name in ("kind", "method"):
        field = model.model_fields.get(name)
        if field is not None and typing.get_origin(field.annotation) is typing.Literal:
            return tuple(str(a) for a in typing.get_args(field.annotation))
    return ()


def _kind_tags() -> set[str]:
    """The ``kind`` (or ``method``) of every integrator of the registered systems (and of their
    second runs)."""
    tags: set[str] = set()
    todo: list[type[BaseModel]] = list(_SCENES)
    seen: set[type[BaseModel]] = set()
    while todo:
        model = todo.pop()
        if model in seen:
            continue
        seen.add(model)
        tags.update(_tags(model))
        for field in model.model_fields.values():
            todo.extend(_models_in(field.annotation))
    return tags


def _clean_loc(loc: Sequence[Any], system: str | None) -> tuple[str, ...]:
    # the members of a union (a reduction or a list of them; a seed or a matrix; one [compare]
    # table or an array of them) are not keys
    out = [str(x) for x in loc if not re.match(r"^(literal|tuple|function-[a-z]+)\[", str(x))
           and str(x) not in ("int", "[compare]", "[[compare]]") and not _FAMILY.match(str(x))]  # fmt: skip
    if out and system is not None and out[0] == system:
        out = out[1:]
    kinds = _kind_tags()
    for i in range(len(out) - 1):
        if out[i] == "integrator" and out[i + 1] in kinds:
            out.pop(i + 1)
            break
    if len(out) > 2 and out[0] == "observables" and out[2] in ("[key]",):
        out = out[:2]
    return tuple(out)


def _from_pydantic(exc: ValidationError, data: Any, text: str | None, source: str) -> SceneError:
    system = data.get("system") if isinstance(data, Mapping) else None
    model = _SYSTEMS.get(system) if isinstance(system, str) else None
    lines = _toml_lines(text) if text is not None else {}
    problems: list[dict[str, Any]] = []
    generic: list[bool] = []  # per problem: only a type error
    for err in exc.errors():
        loc = _clean_loc(err["loc"], system if model is not None else None)
        # a bad key of the observables table: pydantic reports (observables, name, [key])
        if len(err["loc"]) and str(err["loc"][-1]) == "[key]":
            loc = _clean_loc(err["loc"][:-1], system if model is not None else None)
        line = None
        for cut in range(len(loc), 0, -1):
            if loc[:cut] in lines:
                line = lines[loc[:cut]]
                break
        allowed = _allowed(model, loc, err) if model is not None else _allowed(None, loc, err)
        if model is not None and loc[:1] == ("effects",):
            allowed = list(model.EFFECTS)
        if model is not None and loc == ("observables",):
            allowed = list(model.OBSERVABLES)
        if loc == ("system",) or (not loc and err["type"].startswith("union_tag")):
            loc = ("system",)
            line = lines.get(("system",))
            allowed = list(_SYSTEMS)
        msg = str(err["msg"]).removeprefix("Value error, ")
        if err["type"] == "extra_forbidden":
            msg = "unknown key"
        if err["type"] in ("union_tag_invalid", "union_tag_not_found") and loc != ("system",):
            tag = str((err.get("ctx") or {}).get("discriminator", "kind")).strip("'")
            loc = loc + (tag,)
            line = lines.get(loc, line)
            got = (err.get("ctx") or {}).get("tag")
            msg = f"unknown {tag} {got!r}" if got is not None else f"{tag} is required"
        elif err["type"] in ("union_tag_invalid", "union_tag_not_found"):
            got = (err.get("ctx") or {}).get("tag")
            msg = f"unknown system {got!r}" if got is not None else "system is required"
        loc, entry = _split_entry(loc)
        problem = {"key": ".".join(loc), "line": line, "allowed": allowed,
                   "message": entry + _with_input(err, msg)}  # fmt: skip
        # one problem per key: the first member of a union that failed, unless a later one
        # says more than that the value has the wrong type
        same = [i for i, q in enumerate(problems) if q["key"] == problem["key"]]
        if same and generic[same[0]] and not _generic(err):
            problems[same[0]], generic[same[0]] = problem, False
        elif not same:
            problems.append(problem)
            generic.append(_generic(err))
    return SceneError(problems, source)


def _generic(err: Mapping[str, Any]) -> bool:
    """An error that says only that a value has the wrong type (one member of a union)."""
    return str(err.get("type", "")).endswith("_type")


def _split_entry(loc: tuple[str, ...]) -> tuple[tuple[str, ...], str]:
    """(the key, "entry i: " or "row i, entry j: ") of a location inside an array value."""
    idx: list[str] = []
    while len(loc) > 1 and loc[-1].isdigit():
        idx.insert(0, loc[-1])
        loc = loc[:-1]
    if not idx:
        return loc, ""
    names = ["entry"] if len(idx) == 1 else ["row", "entry"] + ["index"] * (len(idx) - 2)
    return loc, ", ".join(f"{n} {i}" for n, i in zip(names, idx, strict=False)) + ": "


def _with_input(err: Mapping[str, Any], msg: str) -> str:
    """A type error's message with the value given (a string is not a number)."""
    if not _generic(err) or "input" not in err:
        return msg
    got = err["input"]
    if isinstance(got, str) and err["type"] in ("float_type", "int_type", "bool_type"):
        return f"{msg}, got the string {got!r} (a TOML string; write a number without quotes)"
    text = repr(got)
    return f"{msg}, got {text if len(text) <= 60 else text[:57] + '...'}"


def parse_scene(data: Mapping[str, Any] | Scene, *, text: str | None = None,
                source: str = "scene") -> Scene:  # fmt: skip
    """Validate a scene given as a mapping (the parsed TOML, or built in Python).

    Parameters
    ----------
    data : mapping or scene model
        The scene; ``data["system"]`` selects the model (:class:`RigidBodyScene`, ...).  A model
        built in Python is returned as it is, after the checks across its keys (effects of the
        observables, second runs, samples) that a table gets.
    text : str, optional
        The TOML text ``data`` was read from, so errors can name lines.
    source : str, optional
        What to call the scene in error messages (a file name).

    Returns
    -------
    Scene
        A frozen pydantic model with every default filled in.

    Raises
    ------
    SceneError
        Naming each bad key, its line (with ``text``) and the allowed values.

    Examples
    --------
    >>> from symrb.scenes import parse_scene
    >>> scene = parse_scene({"system": "double_bracket", "integrator": {"kind": "continuous"},
    ...                      "horizon": {"T": 5.0}, "observables": {"pairing": {"points": 6}}})
    >>> type(scene).__name__, scene.integrator.rtol
    ('DoubleBracketScene', 1e-11)
    >>> parse_scene({"system": "rigid_body", "integrator": {"method": "DOP853"},
    ...              "horizon": {"T": 1.0}, "observables": {"Q": "end"}})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    symrb.scenes.SceneError: invalid scene:
      observables.Q: needs the effect 'attitude', which is not switched on; allowed: ...
    """
    scene: Any
    if isinstance(data, _SceneBase):  # built in Python: pydantic validated its fields
        scene = data
    elif not isinstance(data, Mapping):
        raise SceneError(
            [{"key": "", "line": None, "message": f"a scene is a table, got {type(data).__name__}",
              "allowed": None}], source)  # fmt: skip
    else:
        try:
            # strict: a string is not a number, nor a boolean an integer; TOML arrays arrive as
            # lists, which strict mode takes only as tuples (the schema's arrays)
            scene = _adapter().validate_python(_tuples(dict(data)), strict=True)
        except ValidationError as exc:
            raise _from_pydantic(exc, data, text, source) from None
    # the checks across keys, for a model built in Python as for a table
    lines = _toml_lines(text) if text is not None else {}
    problems = _cross_key_problems(scene, lines) + scene._problems(lines)
    if problems:
        raise SceneError(problems, source)
    return scene  # type: ignore[no-any-return]


def _tuples(value: Any) -> Any:
    """``value`` with every list (a TOML array) turned into a tuple, through tables."""
    if isinstance(value, list | tuple):
        return tuple(_tuples(x) for x in value)
    if isinstance(value, Mapping):
        return {k: _tuples(x) for k, x in value.items()}
    return value


def _cross_key_problems(scene: Any, lines: Mapping[tuple[str, ...], int]) -> list[dict[str, Any]]:
    """The checks across keys every system shares: the effects of the observables, a second run
    exactly when a ``*_gap`` observable asks for one, and the samples."""
    problems = []
    for name in scene.observables:
        need = type(scene).OBSERVABLES.get(name)
        if need is not None and need not in scene.effects:
            problems.append({
                "key": f"observables.{name}",
                "line": lines.get(("observables", name)) or lines.get(("observables",)),
                "message": f"needs the effect {need!r}, which is not switched on",
                "allowed": [o for o, e in type(scene).OBSERVABLES.items()
                            if e is None or e in scene.effects],
            })  # fmt: skip
    compare = getattr(scene, "compare", None)
    gaps = [name for name in scene.observables if name.endswith("_gap")]
    if gaps and compare is None:
        problems.append({
            "key": f"observables.{gaps[0]}",
            "line": lines.get(("observables", gaps[0])) or lines.get(("observables",)),
            "message": "needs a second run to compare with: add a [compare] table with its "
                       "integrator", "allowed": None,
        })  # fmt: skip
    if compare is not None and not gaps:
        problems.append({
            "key": "compare", "line": lines.get(("compare",)),
            "message": "a second run is used only by the *_gap observables; ask for one or drop "
                       "[compare]", "allowed": [o for o in type(scene).OBSERVABLES
                                                if o.endswith("_gap")],
        })  # fmt: skip
    params = getattr(scene, "parameters", None)
    single = type(scene).SINGLE_SAMPLE
    samples = getattr(params, "samples", 1) if params is not None else 1
    # checked for one-sample systems and those with the effect; a network's samples are its data
    if (
        (single or "samples" in type(scene).EFFECTS)
        and samples > 1
        and ("samples" not in scene.effects)
    ):
        message = ("this system has a single sample" if single
                   else "samples > 1 needs the effect 'samples'")  # fmt: skip
        problems.append({
            "key": "parameters.samples", "line": lines.get(("parameters", "samples")),
            "message": f"{message}, got {samples}", "allowed": [1],
        })  # fmt: skip
    return problems


def load_scene(path_or_text: str | os.PathLike[str]) -> Scene:
    """Read a scene from a TOML file (or a TOML text) and validate it (:func:`parse_scene`).

    Parameters
    ----------
    path_or_text : str or path-like
        A path to a ``.toml`` file, or the TOML text itself (a string with a newline).

    Returns
    -------
    Scene
        The validated scene (one of the ``*Scene`` models, chosen by ``system``).

    Raises
    ------
    SceneError
        Bad TOML (with the parser's line) or a scene that does not validate.

    Examples
    --------
    >>> from symrb.scenes import load_scene
    >>> load_scene('system = "resnet"\\n[integrator]\\nkind = "sgd"')  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    symrb.scenes.SceneError: invalid scene:
      integrator.kind (line 3): unknown kind 'sgd'; allowed: gradient_descent, msa
      horizon: Field required
      observables: Field required; allowed: states, K, beta, accuracy, test_accuracy, loss, costates
    """
    if isinstance(path_or_text, os.PathLike) or "\n" not in str(path_or_text):
        path = Path(path_or_text)
        try:
            st = os.stat(path)
            key = (str(path.resolve()), st.st_mtime_ns, st.st_size)
            if key in _LOADED:  # validated before, and unchanged since (scenes are frozen)
                return _LOADED[key]
            text = path.read_text(encoding="utf-8")
        except OSError as exc:
            raise InputError(f"scene file {str(path)!r} cannot be read: {exc}") from None
        except UnicodeDecodeError as exc:
            raise SceneError([{"key": "", "line": text_line(path.read_bytes(), exc.start),
                               "message": f"not a TOML text (not UTF-8 at byte {exc.start})",
                               "allowed": None}], path.name) from None  # fmt: skip
        source = path.name
        scene = _load_text(text, source)
        _LOADED[key] = scene
        return scene
    return _load_text(str(path_or_text), "scene")


def text_line(data: bytes, offset: int) -> int:
    """The 1-based line of byte ``offset`` of ``data``."""
    return data[:offset].count(b"\n") + 1


#: scene files validated in this process, by (path, modification time, size)
_LOADED: dict[tuple[str, int, int], Any] = {}


def _load_text(text: str, source: str) -> Scene:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"line (\d+)", str(exc))
        raise SceneError(
            [{"key": "", "line": int(m.group(1)) if m else None, "message": f"bad TOML: {exc}",
              "allowed": None}], source) from None  # fmt: skip
    return parse_scene(data, text=text, source=source)
