r"""The schema of a scene: what every system shares, and the registry of systems.

:class:`SceneError` (the error of a scene that does not validate), :class:`When` (when an
observable is recorded), the horizons, :class:`_SceneBase` (the fields, checks and hooks every
system shares) and :func:`register_system`, through which each system of
:mod:`symrb.scenes.systems` makes itself known: :func:`~symrb.scenes.parse_scene` validates the
registered models, :func:`~symrb.scenes.plan_scene` and :func:`~symrb.scenes.run_scene` call
their hooks.
"""

from __future__ import annotations

import typing
from collections.abc import Mapping, Sequence
from typing import Annotated, Any, ClassVar, Literal, Union

import numpy as np
from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Field,
    TypeAdapter,
    ValidationError,
    field_validator,
    model_validator,
)
from pydantic_core import InitErrorDetails, PydanticCustomError

from .. import _validate as v
from .._validate import Array
from ..algebra import hat
from ..errors import InputError

# the public names are listed (and re-exported) by symrb.scenes.__all__


class SceneError(InputError):
    """A scene that does not validate; the message names each bad key, its line and what is
    allowed.

    Attributes
    ----------
    problems : list of dict
        One entry per problem: ``key`` (dotted), ``line`` (1-based, or None when the scene does
        not come from a file), ``message`` and ``allowed`` (a list, or None).

    Examples
    --------
    >>> from symrb.scenes import SceneError, load_scene
    >>> text = 'system = "rigid_body"\\n[integrator]\\nmethod = "euler"\\n[horizon]\\nT = 1.0\\n'
    >>> try:
    ...     load_scene(text + '[observables]\\nM = "end"\\n')
    ... except SceneError as exc:
    ...     print(exc.problems[0]["key"], exc.problems[0]["line"], exc.problems[0]["allowed"])
    ... # doctest: +NORMALIZE_WHITESPACE
    integrator.method 3 ['DOP853', 'RK45', 'RK23', 'Radau', 'BDF', 'LSODA', 'mv', 'composition',
    'rkmk4', 'midpoint', 'exact', 'splitting', 'discrete', 'mv_algorithm2', 'mv_algorithm1']
    """

    def __init__(self, problems: list[dict[str, Any]], source: str = "scene") -> None:
        self.problems = problems
        lines = []
        for p in problems:
            where = f" (line {p['line']})" if p.get("line") else ""
            allowed = f"; allowed: {', '.join(map(str, p['allowed']))}" if p.get("allowed") else ""
            lines.append(f"  {p['key'] or '(top level)'}{where}: {p['message']}{allowed}")
        super().__init__(f"invalid {source}:\n" + "\n".join(lines))


# ---------------------------------------------------------------------------------------------
# the schema


#: the largest magnitude of a number in a scene: larger ones overflow the observables (the
#: sixth power of a momentum in ``casimirs``, a square in an energy) or the plan's arithmetic
LARGEST = 1e12


class _Model(BaseModel):
    # no NaN or infinity anywhere (pydantic names the key); strings are not numbers (parse_scene
    # validates in strict mode)
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    @model_validator(mode="after")
    def _not_too_large(self) -> Any:
        for name in type(self).model_fields:
            big = _largest(getattr(self, name))
            if big is not None:
                raise _invalid((name,), f"numbers in a scene lie within +-{LARGEST:g}; got {big:g}")
        return self


def _largest(value: Any) -> float | None:
    """The first float of ``value`` (a float or nested tuples of them) beyond +-LARGEST."""
    if isinstance(value, float):
        return value if abs(value) > LARGEST else None
    if isinstance(value, tuple):
        for x in value:
            big = _largest(x)
            if big is not None:
                return big
    return None


def _invalid(loc: tuple[str, ...], message: str, allowed: Sequence[Any] | None = None) -> Any:
    """A ValidationError to raise in a model validator: pydantic prefixes ``loc`` (relative to
    the model) with the model's own place, so the SceneError names the key and its TOML line;
    ``allowed`` becomes the error's allowed values."""
    ctx = {"expected": ", ".join(repr(a) for a in allowed)} if allowed else None
    err = PydanticCustomError("scene", message, ctx)  # type: ignore[arg-type]
    return ValidationError.from_exception_data(
        "scene", [InitErrorDetails(type=err, loc=loc, input=None)]
    )


def _problem(key: str, message: str, allowed: list[Any] | None = None) -> SceneError:
    """A SceneError of one problem (``key`` dotted, no line): a request the plan cannot meet."""
    return SceneError([{"key": key, "line": None, "message": message, "allowed": allowed}])


def _skew_from(value: Any, n: int, name: str) -> Array:
    """A skew matrix from a scene's key: a 3-vector (n = 3, through hat) or an n x n matrix."""
    a = np.asarray(value, dtype=float)
    if a.shape == (3,) and n == 3:
        return hat(a)
    return v.skew(a, name, n)


Reduction = Literal["max", "min", "max_abs", "max_abs_change", "max_rel_change"]
#: what each reduction keeps of a window, entry by entry; x_0 is the first record
REDUCTIONS: dict[str, str] = {
    "max": "the largest x",
    "min": "the smallest x",
    "max_abs": "the largest |x|",
    "max_abs_change": "the largest |x - x_0|",
    "max_rel_change": "the largest |x - x_0| / |x_0|",
}


class When(_Model):
    r"""When to record an observable: exactly one of ``end``, ``every``, ``times``, ``points``;
    optionally reduced per window (``windows`` with ``reduce``).

    In TOML: ``"end"`` (the final state only), ``{every = k}`` (every k-th step of a fixed-step
    integrator or training step), ``{times = [t1, t2, ...]}`` (chosen times in ``[0, T]``) or
    ``{points = K}`` (K equally spaced times from 0 to T).

    A windowed reduction, ``{points = 1001, windows = 25, reduce = "max_rel_change"}``, splits
    the records (the first one included) into ``windows`` consecutive blocks of nearly equal
    size (as ``numpy.array_split``) and keeps, per block and per entry of the observable, one
    value: the largest ``x`` (``"max"``), the smallest (``"min"``), the largest :math:`|x|`
    (``"max_abs"``), the largest :math:`|x - x_0|` (``"max_abs_change"``) or
    :math:`|x - x_0|/|x_0|` (``"max_rel_change"``), :math:`x_0` being the first record.  The
    time of a window is that of its last record.  A list of reductions,
    ``reduce = ["min", "max"]``, keeps each, stacked on axis 1 in the order given.  The
    unreduced series is not kept.

    Examples
    --------
    >>> from symrb.scenes import When
    >>> When.model_validate("end")
    When(end=True, every=None, times=None, points=None, windows=None, reduce=None)
    >>> When.model_validate({"points": 3}).describe()
    '3 equally spaced times in [0, T]'
    >>> When.model_validate({"every": 1, "windows": 20, "reduce": "max_abs_change"}).describe()
    'every 1 steps, reduced to the largest |x - x_0| over each of 20 windows'
    """

    end: bool = False
    every: int | None = Field(default=None, ge=1)
    times: tuple[float, ...] | None = None
    points: int | None = Field(default=None, ge=2)
    windows: int | None = Field(default=None, ge=1)
    reduce: Reduction | tuple[Reduction, ...] | None = None

    @model_validator(mode="before")
    @classmethod
    def _from_string(cls, data: Any) -> Any:
        if isinstance(data, str):
            if data != "end":
                raise InputError(
                    f"a string 'when' must be \"end\", got {data!r}; or a table "
                    "{every = k}, {times = [...]}, {points = K}"
                )
            return {"end": True}
        return data

    @model_validator(mode="after")
    def _exactly_one(self) -> When:
        given = [k for k in ("every", "times", "points") if getattr(self, k) is not None]
        given += ["end"] if self.end else []
        if len(given) != 1:
            raise InputError(
                f"give exactly one of end, every, times, points; got {given or 'none'}"
            )
        if self.times is not None and (
            not self.times or any(b <= a for a, b in zip(self.times, self.times[1:], strict=False))
        ):
            raise InputError(f"times must be a non-empty increasing list, got {list(self.times)}")
        if (self.windows is None) != (self.reduce is None):
            has, lacks = ("windows", "reduce") if self.reduce is None else ("reduce", "windows")
            raise InputError(
                f"{has} needs {lacks}: a windowed reduction gives both, e.g. "
                '{points = 1001, windows = 25, reduce = "max_abs_change"}'
            )
        if self.windows is not None and self.end:
            raise InputError("a windowed reduction needs a series: give every, times or points, "
                             "not end")  # fmt: skip
        if isinstance(self.reduce, tuple) and (
            not self.reduce or len(set(self.reduce)) != len(self.reduce)
        ):
            raise InputError(f"reduce must list distinct reductions, got {list(self.reduce)}")
        return self

    @property
    def reductions(self) -> tuple[str, ...]:
        """The reductions asked for, as a tuple (empty without a windowed reduction)."""
        if self.reduce is None:
            return ()
        return (self.reduce,) if isinstance(self.reduce, str) else tuple(self.reduce)

    def describe(self) -> str:
        """The request in words."""
        if self.end:
            return "at the end"
        if self.every is not None:
            what = f"every {self.every} steps"
        elif self.points is not None:
            what = f"{self.points} equally spaced times in [0, T]"
        else:
            what = f"at t = {list(self.times or ())}"
        if self.windows is not None:
            red = " and ".join(REDUCTIONS[r] for r in self.reductions)
            what += f", reduced to {red} over each of {self.windows} windows"
        return what


def _rectangular(rows: tuple[tuple[float, ...], ...]) -> tuple[tuple[float, ...], ...]:
    lengths = sorted({len(r) for r in rows})
    if len(lengths) > 1:
        raise InputError(f"a matrix has rows of one length; got rows of lengths {lengths}")
    return rows


Matrix = Annotated[tuple[tuple[float, ...], ...], AfterValidator(_rectangular)]
Vector = tuple[float, ...]


class TimeHorizon(_Model):
    """The final time ``T`` (> 0)."""

    T: float = Field(gt=0)


class TrainingHorizon(_Model):
    """The number of gradient steps (>= 0)."""

    steps: int = Field(ge=0)


# running_cost: a cost on the controls summed over the steps (the SO(n) network's
# alpha tr(Lambda (I - U_k))); potential is a cost on the state (Brockett's potential)
_ALL_EFFECTS = ("attitude", "samples", "terminal_cost", "potential", "running_cost", "costates")
Effect = Literal["attitude", "samples", "terminal_cost", "potential", "running_cost", "costates"]


class _SceneBase(_Model):
    """Fields shared by every scene; a system subclasses it, fixes ``system`` and the allowed
    values, implements the hooks and is registered with :func:`register_system`.

    The hooks: ``_inputs()`` (the arrays the scene starts from, :func:`scene_inputs`),
    ``_plan(skipped, notes)`` (the system's part of the plan, a
    :class:`~symrb.scenes.plan.SystemPlan`; it appends to ``skipped`` and ``notes``),
    ``_run(plan, x)`` (run the plan from the inputs ``x``: the times and data per observable
    and a failure message or '') and, optionally, ``_problems(lines)`` (the checks across keys
    that only this system has, as :class:`SceneError` problems).
    """

    #: the effects this system can switch on
    EFFECTS: ClassVar[tuple[str, ...]] = ()
    #: effects the system's only route needs
    REQUIRED: ClassVar[tuple[str, ...]] = ()
    #: observable -> the effect it needs (or None)
    OBSERVABLES: ClassVar[dict[str, str | None]] = {}

    #: conserved observables -> the names of their components (an empty tuple numbers them),
    #: drawn as relative drift by :meth:`~symrb.scenes.result.SceneResult.plot`
    INVARIANTS: ClassVar[dict[str, tuple[str, ...]]] = {}
    #: observables that are state variables, not diagnostics; never listed as not asked for
    STATE_OBSERVABLES: ClassVar[tuple[str, ...]] = ()
    #: the label of the record axis in plots ("t", or "step" for training)
    RECORD_AXIS: ClassVar[str] = "t"
    #: a system of one sample (``parameters.samples > 1`` is an error)
    SINGLE_SAMPLE: ClassVar[bool] = False

    title: str = ""
    effects: tuple[Effect, ...] = ()

    def _inputs(self) -> dict[str, Any]:
        """The arrays the scene starts from (see :func:`scene_inputs`)."""
        raise NotImplementedError

    def _plan(self, skipped: list[tuple[str, str]], notes: list[str]) -> Any:
        """The system's part of the plan (a SystemPlan); append to ``skipped`` and ``notes``."""
        raise NotImplementedError

    def _run(self, plan: Any, x: dict[str, Any]) -> tuple[dict[str, Array], dict[str, Array], str]:
        """Run the plan from the inputs ``x``: (times and data per observable, failure or '')."""
        raise NotImplementedError

    def _problems(self, lines: Mapping[tuple[str, ...], int]) -> list[dict[str, Any]]:
        """The system's own checks across keys (``lines``: the TOML line of each key)."""
        return []

    @field_validator("effects")
    @classmethod
    def _effects_allowed(cls, value: tuple[str, ...]) -> tuple[str, ...]:
        bad = [e for e in value if e not in cls.EFFECTS]
        if bad:
            raise InputError(
                f"effects {bad} do not apply to this system; allowed: {list(cls.EFFECTS) or 'none'}"
            )
        missing = [e for e in cls.REQUIRED if e not in value]
        if missing:
            raise InputError(f"this system needs the effects {missing} (its only route has them)")
        if len(set(value)) != len(value):
            raise InputError(f"effects named twice: {list(value)}")
        return tuple(sorted(value))

    @field_validator("observables", check_fields=False)
    @classmethod
    def _observables_allowed(cls, value: dict[str, When]) -> dict[str, When]:
        if not value:
            raise InputError(f"ask for at least one observable; allowed: {list(cls.OBSERVABLES)}")
        return dict(sorted(value.items()))


# ---------------------------------------------------------------------------------------------
# the registry

#: every registered scene model, in the order of registration
_SCENES: list[type[_SceneBase]] = []
#: system name -> its scene model
_SYSTEMS: dict[str, type[_SceneBase]] = {}
#: a scene, that is any registered model (every one is a _SceneBase)
Scene = _SceneBase
_ADAPTERS: dict[tuple[type[_SceneBase], ...], TypeAdapter[Any]] = {}
_HOOKS = ("_inputs", "_plan", "_run")


def system_name(cls: type[_SceneBase]) -> str:
    """The literal ``system`` of a scene model."""
    return str(typing.get_args(cls.model_fields["system"].annotation)[0])


def register_system(cls: type[_SceneBase]) -> type[_SceneBase]:
    """Register a scene model (a class decorator).

    The model fixes ``system`` to one literal name and implements the hooks of
    :class:`_SceneBase` (``_inputs``, ``_plan``, ``_run``); :func:`parse_scene` then validates
    it, and :func:`plan_scene` and :func:`run_scene` call its hooks.

    Raises
    ------
    InputError
        Another model registered under the same system name, or a hook not implemented.
    """
    name = system_name(cls)
    if name in _SYSTEMS and _SYSTEMS[name] is not cls:
        raise InputError(f"system {name!r} is registered already (by "
                         f"{_SYSTEMS[name].__name__}); give {cls.__name__} another name")  # fmt: skip
    missing = [h for h in _HOOKS if getattr(cls, h) is getattr(_SceneBase, h)]
    if missing:
        raise InputError(f"system {name!r} ({cls.__name__}) must implement the hooks {missing}")
    if cls not in _SCENES:
        _SCENES.append(cls)
    _SYSTEMS[name] = cls
    return cls


def _adapter() -> TypeAdapter[Any]:
    """The discriminated union of every registered scene model (built once per registry)."""
    key = tuple(_SCENES)
    if key not in _ADAPTERS:
        union: Any = Union[key]  # type: ignore[valid-type]  # noqa: UP007 - runtime tuple
        _ADAPTERS[key] = TypeAdapter(Annotated[union, Field(discriminator="system")])
    return _ADAPTERS[key]
