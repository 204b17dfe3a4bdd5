"""Which public numerical functions of symrb, and which of their option values, the evidence runs.

A wrong option can only be noticed by ``symrb verify`` if some evidence calls it.  This module
lists the *universe*, records which of it the evidence reaches, and reports the rest.

The universe (:func:`universe`) is every function and computing class in the ``__all__`` of the
modules of :data:`MODULES` (the ones the API page documents), and for each its *options*: the
parameters with a finite set of values.  Those are found in the signature (a ``bool`` parameter,
a ``Literal[...]`` annotation) or read from symrb's own dispatch tables (:func:`_tables`: the
methods of ``simulate``, the composition tables of each order, the engine's solvers and orders,
the ``solve_ivp`` methods and flows of ``integrate``, the activations and retractions of the
networks).  A value in effect through a default counts as reached.  Left out, with the reason:

* result and record types (``RigidBodySolution``, ``TrainResult``, ``MVSolveInfo``, ...) and the
  abstract ``Flow``: they hold what the functions computed and compute nothing themselves;
* the random inputs and data sets (``random_so``, ``random_SO``, ``random_lam``,
  ``as_generator``, ``toy_classification``, ``so_rotation_task``, ``digits_task``): they make
  inputs, not results, and no statement of the paper or of a method depends on which inputs;
* the parameter ``progress``: it draws a bar on stderr and changes no number (the tests check
  that it leaves results alone);
* the scenes (TOML input and output, the cache), the command line, the errors and
  ``symrb.testing`` (Hypothesis strategies): no numerics of their own;
* the backend ``"numba"`` of the engine, of the RKMK4 and midpoint flows and of the splitting
  when numba is not installed (it cannot run).

Recording wraps each function object of the universe in every loaded module namespace that
binds it (so ``from x import f`` bindings are caught as well) and, for a class, its ``__init__``;
a wrapper notes the evidence running (:data:`derivations.registry.CURRENT_EVIDENCE`) and the
option values of the call.  Only calls of the universe pay: the evidence of D1, S4, M7 and D9
took 1.97 s plain, 2.02 s recorded this way and 4.91 s under a profile hook restricted to symrb
code (``sys.setprofile``, which sees every Python call).  Nested calls count: the engine reached
through ``simulate`` is reached.  Worker processes of ``verify --jobs N`` are forked with the
wrappers in place and hand back what they noted; where processes are spawned instead (no fork),
run the report with ``--jobs 1``.

``python -m derivations coverage`` prints the report; ``symrb verify --output`` stores it in its
JSON (``"coverage"``), which the claims page and ``tests/test_coverage.py`` read.
"""

from __future__ import annotations

import ast
import functools
import importlib
import inspect
import re
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

from derivations import registry

__all__ = [
    "MODULES",
    "EXCLUDED",
    "Option",
    "Target",
    "universe",
    "Recorder",
    "recording",
    "report",
    "summary_line",
    "unreached",
    "validated",
]

#: The modules whose ``__all__`` holds the public numerical functions (first listing wins the
#: name under which a function is reported).
MODULES = (
    "symrb.rigid_body",
    "symrb.paper",
    "symrb.algebra",
    "symrb.solvers",
    "symrb.engine",
    "symrb.composition",
    "symrb.compose",
    "symrb.base_steps",
    "symrb.exact",
    "symrb.splitting",
    "symrb.continuous",
    "symrb.symmetric",
    "symrb.orbits",
    "symrb.learning",
)

#: Names of those modules left out of the universe (the reasons are in the module docstring).
EXCLUDED = frozenset(
    {"random_so", "random_SO", "random_lam", "as_generator", "toy_classification",
     "so_rotation_task", "digits_task", "Flow"}
)  # fmt: skip

#: Classes that compute (their construction is recorded); every other class is a result type.
COMPUTING_CLASSES = frozenset({"MVStepper", "MVStep", "MidpointStep", "RKMK4Step"})

#: Parameters that are not options of the numerics.
NOT_OPTIONS = frozenset({"progress"})


@dataclass(frozen=True)
class Option:
    """An option of a function: its ``values`` (as text) and how to read the value of a call
    from its bound arguments (defaults applied)."""

    name: str
    values: tuple[str, ...]
    read: Callable[[dict[str, Any]], str]


@dataclass(frozen=True)
class Target:
    """A public numerical function (or computing class) and its options."""

    name: str
    obj: Any
    options: tuple[Option, ...]


def _param(name: str) -> Callable[[dict[str, Any]], str]:
    def read(args: dict[str, Any]) -> str:
        value = args.get(name)
        return repr(bool(value)) if isinstance(value, bool) else str(value)

    return read


def _table_of(kinds: dict[int, tuple[str, ...]], default: dict[int, str]) -> Option:
    """The composition tables: ``order/kind`` for every kind of every order (``kind=None`` is
    the default kind of the order)."""

    def read(args: dict[str, Any]) -> str:
        order = args.get("order")
        kind = args.get("kind")
        return f"{order}/{default.get(order, '?') if kind is None else kind}"  # type: ignore[arg-type]

    values = tuple(f"{o}/{k}" for o, ks in kinds.items() for k in ks)
    return Option("order/kind", values, read)


def _tables() -> dict[str, list[Option]]:
    """The options read from symrb's dispatch tables, by function name."""
    from symrb import _compiled, _compiled_stages
    from symrb.compose import _BACKENDS
    from symrb.composition import _DEFAULT_KIND, _KINDS
    from symrb.engine import _FLOW_METHODS, _SOLVERS, PREPROCESSED_ORDERS
    from symrb.learning.resnet import _ACTIVATIONS
    from symrb.rigid_body.entry import METHODS
    from symrb.rigid_body.ivp import NAMES
    from symrb.splitting import _METHODS as SPLIT_METHODS
    from symrb.splitting import AVAILABLE as SPLIT_NUMBA
    from symrb.splitting import SPLITTING_ORDERS

    flow_methods = tuple(m for m in _FLOW_METHODS if m != "numba" or _compiled.AVAILABLE)
    backends = tuple(m for m in _BACKENDS if m != "numba" or _compiled_stages.AVAILABLE)
    flows = ("RigidBody", "SymmetricRigidBody", "McLachlanScovel", "MultiSampleSymmetricRigidBody")

    def flow_name(args: dict[str, Any]) -> str:
        flow = args.get("flow")
        return flow.__name__ if isinstance(flow, type) else type(flow).__name__

    def step_name(args: dict[str, Any]) -> str:
        step = args.get("step")
        return step if isinstance(step, str) else "object"

    activation = [Option("activation", _ACTIVATIONS, _param("activation"))]
    tables = {
        "symrb.rigid_body.simulate": [Option("method", tuple(METHODS), _param("method"))],
        "symrb.engine.mv_flow": [
            Option("method", flow_methods, _param("method")),
            Option("order", tuple(map(str, PREPROCESSED_ORDERS)), _param("order")),
        ],
        "symrb.engine.MVStepper": [Option("method", _SOLVERS, _param("method"))],
        "symrb.splitting.splitting_flow": [
            Option(
                "method",
                tuple(m for m in SPLIT_METHODS if m != "numba" or SPLIT_NUMBA),
                _param("method"),
            ),  # fmt: skip
            Option("order", tuple(map(str, SPLITTING_ORDERS)), _param("order")),
        ],
        "symrb.composition.composition_coefficients": [_table_of(_KINDS, _DEFAULT_KIND)],
        "symrb.compose.composed_rigid_body_flow": [
            _table_of(_KINDS, _DEFAULT_KIND),
            Option("step", ("mv", "midpoint", "object"), step_name),
        ],
        "symrb.compose.rkmk4_rigid_body_flow": [Option("method", backends, _param("method"))],
        "symrb.compose.midpoint_rigid_body_flow": [Option("method", backends, _param("method"))],
        "symrb.continuous.integrate": [
            Option("method", NAMES, _param("method")),
            Option("flow", flows, flow_name),
        ],
        "symrb.learning.train_so_gradient": [
            Option("retraction", ("cayley", "exp"), _param("retraction"))
        ],
    }
    for name in ("resnet_forward", "costate_sweep", "loss_gradients", "train", "resnet_predict",
                 "train_msa"):  # fmt: skip
        tables[f"symrb.learning.{name}"] = activation
    return tables


def _literal(annotation: Any) -> tuple[str, ...] | None:
    """The values of a ``Literal[...]`` annotation (given as text), else None."""
    m = re.fullmatch(r"(?:typing\.)?Literal\[(.*)\]", str(annotation))
    if not m:
        return None
    values = ast.literal_eval(f"({m.group(1)},)")
    return tuple(str(v) for v in values)


def _signature_options(obj: Any) -> list[Option]:
    """The bool and Literal parameters of ``obj`` (a class: of its constructor)."""
    out = []
    for p in inspect.signature(obj).parameters.values():
        if p.name in NOT_OPTIONS:
            continue
        values = _literal(p.annotation)
        if values is None and p.annotation in ("bool", bool):
            values = ("True", "False")
        if values is not None:
            out.append(Option(p.name, values, _param(p.name)))
    return out


@functools.cache
def universe() -> tuple[Target, ...]:
    """Every public numerical function of symrb with its options (see the module docstring)."""
    tables = _tables()
    seen: set[int] = set()
    targets = []
    for module_name in MODULES:
        module = importlib.import_module(module_name)
        for name in module.__all__:
            obj = getattr(module, name)
            if name in EXCLUDED or id(obj) in seen or not callable(obj):
                continue
            if inspect.isclass(obj) and name not in COMPUTING_CLASSES:
                continue
            seen.add(id(obj))
            full = f"{module_name}.{name}"
            options = {o.name: o for o in _signature_options(obj)}
            options.update({o.name: o for o in tables.pop(full, [])})
            targets.append(Target(full, obj, tuple(options.values())))
    if tables:
        raise ValueError(f"option tables for functions outside the universe: {sorted(tables)}")
    return tuple(targets)


# ---------------------------------------------------------------------------------------------
# recording


class Recorder:
    """Which evidence reached which target and option value: ``hits[(target, option, value)]``
    is a set of evidence names ``"ID name"`` (``option == value == ""`` for the call itself)."""

    def __init__(self) -> None:
        self.hits: dict[tuple[str, str, str], set[str]] = {}

    def note(self, target: Target, args: tuple[Any, ...], kwargs: dict[str, Any]) -> None:
        evidence = registry.CURRENT_EVIDENCE.get()
        if evidence is None:
            return
        self.hits.setdefault((target.name, "", ""), set()).add(evidence)
        if not target.options:
            return
        try:
            bound = _signature(target.obj).bind(*args, **kwargs)
        except TypeError:  # a wrong call raises in the function itself
            return
        bound.apply_defaults()
        values = dict(bound.arguments)
        values.update(values.pop("options", None) or {})
        for option in target.options:
            key = (target.name, option.name, option.read(values))
            self.hits.setdefault(key, set()).add(evidence)

    def take(self) -> dict[tuple[str, str, str], set[str]]:
        """The hits so far, emptying the record (a worker process hands them back)."""
        hits, self.hits = self.hits, {}
        return hits

    def merge(self, hits: dict[tuple[str, str, str], set[str]]) -> None:
        for key, names in hits.items():
            self.hits.setdefault(key, set()).update(names)


@functools.cache
def _signature(obj: Any) -> inspect.Signature:
    return inspect.signature(obj)


_ORIGINAL = "_coverage_original"


def _our_modules() -> list[Any]:
    return [m for n, m in list(sys.modules.items()) if n.split(".")[0] in ("symrb", "derivations")]


def _wrap(func: Any, target: Target, recorder: Recorder, skip_self: bool) -> Any:
    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        recorder.note(target, args[1:] if skip_self else args, kwargs)
        return func(*args, **kwargs)

    setattr(wrapper, _ORIGINAL, func)
    return wrapper


@contextmanager
def recording() -> Iterator[Recorder]:
    """Record, while the block runs, which targets and option values the evidence reaches
    (in this process and in worker processes forked from it by :func:`registry.verify_each`)."""
    for name in MODULES:  # every binding exists before the namespaces are searched
        importlib.import_module(name)
    recorder = Recorder()
    undo: list[tuple[Any, str, Any]] = []
    modules = _our_modules()
    for target in universe():
        if inspect.isclass(target.obj):
            init = target.obj.__init__
            undo.append((target.obj, "__init__", init))
            setattr(target.obj, "__init__", _wrap(init, target, recorder, skip_self=True))  # noqa: B010
            continue
        wrapper = _wrap(target.obj, target, recorder, skip_self=False)
        for module in modules:
            for attr, value in list(vars(module).items()):
                if value is target.obj:
                    undo.append((module, attr, value))
                    setattr(module, attr, wrapper)
    previous = registry.RECORDER
    registry.RECORDER = recorder
    try:
        yield recorder
    finally:
        registry.RECORDER = previous
        for owner, attr, value in reversed(undo):
            setattr(owner, attr, value)
        for module in _our_modules():  # bindings made while recording (symrb.__getattr__)
            for attr, value in list(vars(module).items()):
                if hasattr(value, _ORIGINAL):
                    setattr(module, attr, getattr(value, _ORIGINAL))


# ---------------------------------------------------------------------------------------------
# the report


def report(recorder: Recorder) -> dict[str, Any]:
    """The coverage report: for every target its evidence and, for every option value, the
    evidence that reached it (an empty list: unreached), and the counts."""
    functions: list[dict[str, Any]] = []
    for t in universe():
        options = [
            {
                "option": o.name,
                "value": v,
                "evidence": sorted(recorder.hits.get((t.name, o.name, v), ())),
            }
            for o in t.options
            for v in o.values
        ]
        evidence = sorted(recorder.hits.get((t.name, "", ""), ()))
        functions.append({"function": t.name, "evidence": evidence, "options": options})
    values = [o for f in functions for o in f["options"]]
    return {
        "functions": functions,
        "summary": {
            "functions": len(functions),
            "functions_reached": sum(bool(f["evidence"]) for f in functions),
            "values": len(values),
            "values_reached": sum(bool(o["evidence"]) for o in values),
        },
    }


def validated(cov: dict[str, Any]) -> dict[str, Any]:
    """``cov`` (a stored report) after checking that it lists exactly the functions and option
    values of the universe now; ``AssertionError`` when it is stale."""
    want = [(t.name, [(o.name, v) for o in t.options for v in o.values]) for t in universe()]
    got = [(f["function"], [(o["option"], o["value"]) for o in f["options"]])
           for f in cov["functions"]]  # fmt: skip
    assert got == want, "the coverage report does not list the functions and options of now"
    return cov


def unreached(cov: dict[str, Any]) -> list[str]:
    """``function`` or ``function option=value`` for everything no evidence reached."""
    out = []
    for f in cov["functions"]:
        if not f["evidence"]:
            out.append(f["function"])
        out += [
            f"{f['function']} {o['option']}={o['value']}" for o in f["options"] if not o["evidence"]
        ]
    return out


def summary_line(cov: dict[str, Any]) -> str:
    """``Evidence reaches 60 of 60 public numerical functions and 90 of 90 of their option
    values.``"""
    s = cov["summary"]
    return (
        f"Evidence reaches {s['functions_reached']} of {s['functions']} public numerical "
        f"functions of symrb and {s['values_reached']} of {s['values']} of their option values."
    )


def table(cov: dict[str, Any]) -> list[str]:
    """The report for a terminal: one line per function and per option value, with the
    evidence that reached it or UNREACHED."""

    def who(names: list[str]) -> str:
        if not names:
            return "UNREACHED"
        return ", ".join(names[:3]) + (f" (+{len(names) - 3})" if len(names) > 3 else "")

    lines = []
    for f in cov["functions"]:
        lines.append(f"{f['function']}: {who(f['evidence'])}")
        lines += [f"    {o['option']}={o['value']}: {who(o['evidence'])}" for o in f["options"]]
    lines.append(summary_line(cov))
    return lines
