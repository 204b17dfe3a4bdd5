"""The scene reference page: the keys of every system as Markdown tables, and an example scene of
every system and of every form of its ``[integrator]`` table, each parsed by
:func:`symrb.scenes.load_scene` before it is shown.

Everything comes from :func:`symrb.scenes.describe_schema` (the pydantic models) and from the
models' docstrings; the only values typed here are the sample values of keys that have no
default (:data:`SAMPLE`).
"""

from __future__ import annotations

import inspect
import re
from collections.abc import Iterable

from symrb.scenes import When, describe_model, describe_schema, load_scene
from symrb.scenes.reference import SchemaKey
from symrb.scenes.schema import _SYSTEMS

#: a value for each key that has no default (a required number), used by the examples
SAMPLE = {"h": "0.01", "T": "1.0", "steps": "2"}
_FIELDS = ("type", "default", "allowed")


def myst(text: str) -> str:
    """reST of a docstring as MyST Markdown: ````x```` -> `` `x` ``, ``:math:`x``` -> ``$x$``,
    ``:func:`x``` -> ``{func}`x```."""
    text = re.sub(r":math:`([^`]*)`", r"$\1$", text)
    text = re.sub(r":(\w+):`([^`]*)`", r"{py:\1}`\2`", text)
    text = text.replace("{py:mod}", "{py:mod}").replace("``", "`")
    return " ".join(text.split())


def summary(obj: object) -> str:
    """The first paragraph of a docstring, as MyST."""
    return myst((inspect.getdoc(obj) or "").split("\n\n", 1)[0])


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def _code(text: str) -> str:
    return f"`{text}`" if text else ""


def table(keys: Iterable[SchemaKey], first: str = "key") -> str:
    """The keys as a Markdown table: key, type, default (``required`` when there is none) and
    the allowed values."""
    lines = [f"| {first} | type | default | allowed values |", "|---|---|---|---|"]
    for k in keys:
        name = f"{k.table}.{k.key}" if k.table else k.key
        default = "required" if k.required else _code(k.default or "")
        if k.default == "(not set)":
            default = "not set"
        allowed = ", ".join(_code(a) for a in k.allowed)
        lines.append(f"| {_code(name)} | {_cell(k.type)} | {default} | {_cell(allowed)} |")
    return "\n".join(lines)


def _value(k: SchemaKey) -> str:
    if not k.required:
        return k.default or ""
    if k.allowed and len(k.allowed) == 1:
        return k.allowed[0]
    if k.key in SAMPLE:
        return SAMPLE[k.key]
    raise KeyError(f"no sample value for the required key {k.table}.{k.key} of {k.system}")


def _items(keys: Iterable[SchemaKey]) -> list[tuple[str, str]]:
    """(key, TOML value) of the keys: the default, else a sample; a key that is not set by
    default is shown with its first allowed value, or left out when it has no list of them."""
    return [
        (k.key, k.allowed[0] if k.default == "(not set)" else _value(k))
        for k in keys
        if k.default != "(not set)" or k.allowed
    ]


def inline_table(keys: Iterable[SchemaKey]) -> str:
    """A TOML inline table of the keys that have a value (their default, else a sample)."""
    return "{" + ", ".join(f"{key} = {value}" for key, value in _items(keys)) + "}"


def _scene(top: list[tuple[str, str]], tables: dict[str, list[tuple[str, str]]]) -> str:
    """TOML text: the top-level keys, then each table."""
    lines = [f"{key} = {value}" for key, value in top]
    for name, items in tables.items():
        lines += [f"[{name}]"] + [f"{key} = {value}" for key, value in items]
    return "\n".join(lines) + "\n"


def example(system: str, integrator: list[SchemaKey] | None = None) -> str:
    """A scene of ``system`` that parses: its required keys, the keys of one form of its
    ``[integrator]`` table (default the first form) at their defaults (a sample value where
    there is none), the effects the system or that form needs, and the first observable with
    which the scene validates."""
    keys = describe_schema(system)
    model = _SYSTEMS[system]
    if integrator is None:
        first = next(k.variant for k in keys if k.table == "integrator")
        integrator = [k for k in keys if k.table == "integrator" and k.variant == first]
    tables = {
        "integrator": _items(integrator),
        "horizon": _items(k for k in keys if k.table == "horizon"),
    }
    errors = []
    # the effects the system needs, then (when the integrator needs one more) each other effect
    for extra in [None, *model.EFFECTS]:
        for obs, need in model.OBSERVABLES.items():
            effects = [e for e in dict.fromkeys([*model.REQUIRED, extra, need]) if e]
            top = [("system", f'"{system}"')]
            if effects:
                top.append(("effects", "[" + ", ".join(f'"{e}"' for e in effects) + "]"))
            text = _scene(top, {**tables, "observables": [(obs, '"end"')]})
            try:
                load_scene(text)
            except Exception as exc:  # another observable or effect may fit this integrator
                errors.append(f"{obs}: {exc}")
                continue
            return text
    raise ValueError(f"no example of {system} parses:\n" + "\n".join(errors))


def integrator_examples(system: str) -> dict[str, str]:
    """form -> its ``[integrator]`` table as one line of TOML (every key of the form), for each
    form; each is parsed in a scene, and its integrator has exactly the keys the form lists."""
    keys = [k for k in describe_schema(system) if k.table == "integrator"]
    out = {}
    for form in dict.fromkeys(k.variant for k in keys):
        mine = [k for k in keys if k.variant == form]
        parsed = load_scene(example(system, mine)).integrator  # type: ignore[attr-defined]
        assert set(type(parsed).model_fields) == {k.key for k in mine}, (form, parsed)
        out[form] = "integrator = " + inline_table(mine)
    return out


def when_table() -> str:
    """The keys of an observable's ``when`` table."""
    return wrap(table(describe_model(When)))


def system_section(system: str) -> str:
    """One system: what it is, its keys, its observables, its integrator forms and examples."""
    keys = describe_schema(system)
    model = _SYSTEMS[system]
    plain = [k for k in keys if k.table not in ("integrator", "observables")]
    obs = [k for k in keys if k.table == "observables"]
    forms = [k for k in keys if k.table == "integrator"]
    out = [f"(scene-key-{system})=", f"## `{system}`", "", summary(model), "", table(plain), ""]
    out += ["Observables (each a `when`, above):", ""]
    out += [", ".join(f"`{k.key}`" + (f" ({k.note})" if k.note else "") for k in obs) + ".", ""]
    out += [f"### `{system}`: the `[integrator]` table", ""]
    examples = integrator_examples(system)
    for form in dict.fromkeys(k.variant for k in forms):
        mine = [k for k in forms if k.variant == form]
        doc = _form_doc(system, form)
        out += [f"**`{form}`**" + (f": {doc}" if doc else ""), ""]
        out += [table(mine), ""]
        out += ["```toml", examples[form], "```", ""]
    out += [f"A whole `{system}` scene:", "", "```toml", example(system).rstrip(), "```", ""]
    return "\n".join(out)


def _form_doc(system: str, form: str) -> str:
    """The docstring summary of the model of one integrator form, without its leading
    ``method = "..."`` (the form's name, shown already)."""
    from symrb.scenes.reference import _variants

    annotation = _SYSTEMS[system].model_fields["integrator"].annotation
    for variant, model in _variants(annotation):
        if variant == form:
            text = summary(model)
            return re.sub(r"^`(method|kind) = \"[^\"]*\"`(, the paper's)?:?\s*", "", text)
    return ""


#: the pages of the scene reference and the systems each lists (every registered system once)
PAGES = {
    "scene_reference": ("rigid_body",),
    "scene_reference_bodies": ("symmetric_rigid_body", "mclachlan_scovel"),
    "scene_reference_orbits": ("double_bracket", "orbit_extremal", "toda"),
    "scene_reference_learning": ("resnet", "so_network"),
}


def page(name: str) -> str:
    """The systems of one page of the scene reference, as MyST (tables wrap their code names:
    the ``symrb-ref`` container).  Fails when a registered system is on no page, or on two."""
    listed = [s for systems in PAGES.values() for s in systems]
    missing = sorted(set(_SYSTEMS) - set(listed))
    assert not missing and len(listed) == len(set(listed)), (
        f"every registered system on exactly one page of the scene reference: {missing or listed}"
    )
    return wrap("\n\n".join(system_section(system) for system in PAGES[name]))


def wrap(body: str) -> str:
    """MyST in the ``symrb-ref`` container, whose tables wrap long code names (the book's CSS)."""
    return f":::{{container}} symrb-ref\n{body}\n:::\n"


def systems_table() -> str:
    """Each system with its page and the first sentence of what it is."""
    lines = ["| system | what it is |", "|---|---|"]
    for systems in PAGES.values():
        for system in systems:
            first = summary(_SYSTEMS[system]).split(". ")[0].rstrip(".") + "."
            lines.append(f"| {{ref}}`{system} <scene-key-{system}>` | {_cell(first)} |")
    return wrap("\n".join(lines))
