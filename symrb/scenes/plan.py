"""The planner: what a scene computes, decided before anything runs.

:func:`plan_scene` does what every system shares (the diagnostics not asked for, the windows,
the records, the modules of the scene machinery); each system contributes its route, state,
kernels, save request and cost through its hook ``_plan`` (a :class:`SystemPlan`).  The helpers
here (:func:`_continuous_save`, :func:`_fixed_step_save`, :func:`_est_continuous`) are shared by
the systems' hooks.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

from .._validate import Array
from .parse import parse_scene
from .schema import Scene, SceneError, TimeHorizon, When, _problem

#: the default limits of a run: ten minutes and 2 GiB of recorded states (``symrb run
#: --max-seconds / --max-memory``, ``run_scene(max_seconds=..., max_memory=...)``)
MAX_SECONDS = 600.0
MAX_MEMORY = 2 * 2**30
#: the least a fixed step or training step costs (a few NumPy calls), for a bound before planning
_LEAST_PER_STEP = 1e-6


@dataclasses.dataclass(frozen=True)
class Budget:
    """The limits a scene's estimated cost must keep: ``seconds`` and ``memory`` (bytes).

    Examples
    --------
    >>> from symrb.scenes.plan import Budget
    >>> Budget().seconds, Budget().memory / 2**30
    (600.0, 2.0)
    """

    seconds: float = MAX_SECONDS
    memory: float = MAX_MEMORY

    def refuse(self, what: str, estimate: float, how: str, key: str = "") -> SceneError:
        """The error of an estimate over the limit ``what`` ("seconds" or "memory")."""
        limit = self.seconds if what == "seconds" else self.memory
        fmt = (lambda x: f"{x:.3g} s") if what == "seconds" else _fmt_bytes
        option = "--max-seconds" if what == "seconds" else "--max-memory"
        return SceneError([{
            "key": key or f"(estimated {'cost' if what == 'seconds' else 'memory'})",
            "line": None, "allowed": None,
            "message": f"the estimate, ~{fmt(estimate)} ({how}), is over the limit of "
                       f"{fmt(limit)}; nothing was run. Raise the limit with {option} "
                       f"(run_scene(max_{what}=...)) or ask for less",
        }])  # fmt: skip

    def check(self, plan: Plan) -> None:
        """Refuse (:class:`SceneError`) a plan whose estimated seconds or memory is over."""
        c = plan.cost
        if not c["seconds"] <= self.seconds:
            raise self.refuse("seconds", c["seconds"], c["formula"])
        if not c.get("bytes", 0.0) <= self.memory:
            raise self.refuse("memory", c["bytes"], c.get("bytes_formula", ""))


#: the modules of the scene machinery a run goes through (their source enters the cache key)
_CORE_MODULES = ("scenes.schema", "scenes.parse", "scenes.plan", "scenes.run")
#: a diagnostic observable -> the generated kernel that evaluates it
DIAGNOSTIC_KERNELS = {
    "energy": "rigid_body.kinetic_energy", "casimirs": "rigid_body.casimir_traces",
    "manakov": "rigid_body.manakov_integrals", "H": "symmetric_rigid_body.gl_hamiltonian",
    "potential": "adjoint_orbits.brockett_potential",
}  # fmt: skip


@dataclasses.dataclass(frozen=True)
class Plan:
    """What a scene computes, decided by :func:`plan_scene`.

    Attributes
    ----------
    system : str
        The scene's system.
    route : str
        The public function(s) called, in words.
    propagated : tuple of str
        The state variables integrated.
    skipped : tuple of (str, str)
        What is not computed, and why.
    kernels : tuple of str
        The generated kernels the run evaluates (``module.function``).
    record : dict
        Observable -> (when, in words; the number of records).
    save : dict
        The save request handed to the integrator: ``{"t_eval": [...]}`` (continuous),
        ``{"steps": N, "save_every": s}`` (fixed step) or ``{"steps": N}`` (training).
    index : dict
        Observable -> indices of its records among the saved states.
    cost : dict
        ``flops`` and ``seconds`` (estimates) and ``formula`` (how they were estimated);
        ``bytes`` (the saved states, an estimate) and ``bytes_formula``.
    notes : tuple of str
        Further remarks (e.g. what changes against a scene with more effects).
    modules : tuple of str
        The symrb modules the run uses (their source enters the cache key).
    windows : dict
        Observable -> (its reductions, the number of windows) for the windowed observables:
        their records are reduced per window and the unreduced series is not kept.
    compare : Plan, tuple of Plan, or None
        The plan of the second run of the ``*_gap`` observables (a tuple for an array of
        ``[[compare]]`` tables, in their order).
    title : str
        The scene's title (a second run's: its ``label``).

    Examples
    --------
    >>> from symrb.scenes import parse_scene, plan_scene
    >>> scene = parse_scene({
    ...     "system": "rigid_body",
    ...     "parameters": {"n": 3, "lam": [0.7, 1.1, 1.6], "M0": [0.5, 1.0, 1.5]},
    ...     "integrator": {"method": "DOP853", "rtol": 1e-8},
    ...     "horizon": {"T": 1.0},
    ...     "observables": {"energy": "end"},
    ... })
    >>> plan = plan_scene(scene)
    >>> plan.propagated
    ('M',)
    """

    system: str
    route: str
    propagated: tuple[str, ...]
    skipped: tuple[tuple[str, str], ...]
    kernels: tuple[str, ...]
    record: dict[str, tuple[str, int]]
    save: dict[str, Any]
    index: dict[str, tuple[int, ...]]
    cost: dict[str, Any]
    notes: tuple[str, ...]
    modules: tuple[str, ...]
    windows: dict[str, tuple[tuple[str, ...], int]] = dataclasses.field(default_factory=dict)
    compare: Plan | tuple[Plan, ...] | None = None
    title: str = ""

    def explain(self) -> str:
        """The plan in words (what ``symrb run --explain`` prints)."""
        out = [f"system      {self.system}", f"route       {self.route}"]
        out.append(f"propagated  {', '.join(self.propagated) or '(nothing)'}")
        for what, why in self.skipped:
            out.append(f"skipped     {what}: {why}")
        out.append(f"kernels     {', '.join(self.kernels)}")
        save = ", ".join(f"{k} = {_brief_list(val)}" for k, val in self.save.items())
        out.append(f"save        {save}")
        for name, (when, count) in self.record.items():
            out.append(f"record      {name}: {when} ({count} record{'s' * (count != 1)})")
        for name, (reds, w) in self.windows.items():
            raw = len(self.index[name])
            out.append(f"reduce      {name}: {raw} records -> {w} windows of ~{raw / w:.3g} "
                       f"({', '.join(reds)}); the {raw} unreduced values are not kept")  # fmt: skip
        if self.compare is not None:
            many = isinstance(self.compare, tuple)
            runs = self.compare if isinstance(self.compare, tuple) else (self.compare,)
            gaps = [n for n in self.record if n.endswith("_gap")]
            what = f"{len(runs)} second runs (one column each)" if many else "a second run"
            out.append(f"compare     {', '.join(gaps)}: the largest entry of |X - X'| against "
                       f"{what} on the same initial data:")  # fmt: skip
            for i, c2 in enumerate(runs):
                if many:
                    out.append(f"  [compare.{i}] {c2.title}".rstrip())
                out += ["  " + line for line in c2.explain().splitlines()]
        c = self.cost
        out.append(
            f"cost        ~{c['flops']:.2g} flops, ~{_fmt_seconds(c['seconds'])} (estimate: "
            f"{c['formula']})"
        )
        if "bytes" in c:
            out.append(f"memory      ~{_fmt_bytes(c['bytes'])} (estimate: {c['bytes_formula']})")
        out += [f"note        {n}" for n in self.notes]
        return "\n".join(out)

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict of the plan."""
        d = dataclasses.asdict(self)
        d["save"] = {k: (list(map(float, val)) if isinstance(val, list | tuple | np.ndarray)
                         else val) for k, val in self.save.items()}  # fmt: skip
        return json.loads(json.dumps(d, default=_json_default))


@dataclasses.dataclass(frozen=True)
class SystemPlan:
    """A system's part of a :class:`Plan` (the hook ``_plan`` of a registered system returns it;
    :func:`plan_scene` adds what is shared: the diagnostics not asked for, the windows, the
    records and the modules of the scene machinery)."""

    route: str
    propagated: tuple[str, ...]
    kernels: tuple[str, ...]
    save: dict[str, Any]
    index: dict[str, tuple[int, ...]]
    cost: dict[str, Any]
    modules: tuple[str, ...]
    #: the plan(s) of the second run(s) of the ``*_gap`` observables (see :class:`Plan`)
    compare: Plan | tuple[Plan, ...] | None = None


def _brief_list(val: Any) -> str:
    if isinstance(val, list | tuple | np.ndarray):
        vals = [float(x) for x in val]
        if len(vals) > 6:
            return f"[{vals[0]:g}, {vals[1]:g}, ..., {vals[-1]:g}] ({len(vals)} times)"
        return "[" + ", ".join(f"{x:g}" for x in vals) + "]"
    return str(val)


def _fmt_seconds(s: float) -> str:
    return f"{s * 1e3:.2g} ms" if s < 1 else f"{s:.2g} s"


def _fmt_bytes(b: float) -> str:
    for unit, size in (("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if b >= size:
            return f"{b / size:.3g} {unit}"
    return f"{b:.0f} bytes"


def _numbers_per_state(sc: Any) -> float:
    """The numbers of one saved state (an estimate: samples x n x n of each state variable)."""
    p = getattr(sc, "parameters", None)
    n = float(getattr(p, "n", 1) or 1)
    return float(getattr(p, "samples", 1) or 1) * n * n


def _steps_asked(sc: Any) -> float | None:
    """The steps a fixed-step or training scene takes (T / h, or horizon.steps); None if adaptive."""
    h = getattr(sc.integrator, "h", None)
    if isinstance(sc.horizon, TimeHorizon):
        return float(sc.horizon.T) / float(h) if isinstance(h, float) and h > 0 else None
    return float(getattr(sc.horizon, "steps", 0))


def _precheck(sc: Any, budget: Budget) -> None:
    """Refuse, before anything is allocated, a scene whose steps or records are over the budget
    (what planning itself would allocate: the save times, the step indices)."""
    steps = _steps_asked(sc)
    if steps is not None and steps * _LEAST_PER_STEP > budget.seconds:
        key = "horizon.T" if isinstance(sc.horizon, TimeHorizon) else "horizon.steps"
        raise budget.refuse("seconds", steps * _LEAST_PER_STEP,
                            f"{steps:.3g} steps of at least {_fmt_seconds(_LEAST_PER_STEP)}", key)  # fmt: skip
    per = 8.0 * (1.0 + _numbers_per_state(sc))
    for name, when in sc.observables.items():
        if when.end:
            records = 1.0
        elif when.points is not None:
            records = float(when.points)
        elif when.times is not None:
            records = float(len(when.times))
        else:
            records = (steps or 0.0) / float(when.every or 1) + 1.0
        if records * per > budget.memory:
            key = f"observables.{name}"
            raise budget.refuse("memory", records * per,
                                f"{records:.3g} records of {_fmt_bytes(per)}", key)  # fmt: skip


def _memory(sc: Any, part: Any) -> tuple[float, str]:
    """The bytes of the saved states of a plan (an estimate) and how it was estimated."""
    save = part.save
    if "t_eval" in save:
        saved = float(len(save["t_eval"]))
    else:
        saved = float(save.get("steps", 0)) / float(save.get("save_every", 1) or 1) + 1.0
    per = 8.0 * len(part.propagated or ("x",)) * _numbers_per_state(sc)
    return saved * per, f"{saved:.3g} saved states of ~{_fmt_bytes(per)}"


def _json_default(o: Any) -> Any:
    if isinstance(o, np.integer):
        return int(o)
    if isinstance(o, np.floating):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, tuple):
        return list(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


#: the images of scikit-learn's digits (for the ResNet's cost estimate)


def _continuous_save(scene: Any) -> tuple[Array, dict[str, tuple[int, ...]]]:
    """The union of the observables' times (t_eval) and each observable's indices into it."""
    T = float(scene.horizon.T)
    per: dict[str, Array] = {}
    for name, when in scene.observables.items():
        if when.every is not None:
            raise _problem(
                f"observables.{name}.every",
                "'every' counts the steps of a fixed-step integrator; this integrator chooses "
                "its own steps",
                ["end", "times", "points"],
            )
        if when.end:
            per[name] = np.array([T])
        elif when.points is not None:
            per[name] = np.linspace(0.0, T, when.points)
        else:
            ts = np.asarray(when.times, dtype=float)
            if ts[0] < 0 or ts[-1] > T:
                raise _problem(
                    f"observables.{name}.times",
                    f"times must lie in [0, T] = [0, {T:g}], got {list(map(float, ts))}",
                )
            per[name] = ts
    t_eval = np.unique(np.concatenate(list(per.values())))
    index = {k: tuple(np.searchsorted(t_eval, ts).tolist()) for k, ts in per.items()}
    return t_eval, index


def _fixed_step_save(scene: Any, h: float) -> tuple[int, int, dict[str, tuple[int, ...]]]:
    """(steps, save_every, indices into the saved states) for a fixed step h."""
    T = float(scene.horizon.T)
    steps = round(T / h)
    if steps < 1 or abs(steps * h - T) > 1e-9 * max(T, 1.0):
        raise _problem("horizon.T", f"T = {T:g} must be a whole number of steps h = {h:g}")
    per: dict[str, Array] = {}
    for name, when in scene.observables.items():
        if when.end:
            ks = np.array([steps])
        elif when.every is not None:
            ks = np.arange(0, steps + 1, when.every)
        else:
            ts = (np.linspace(0.0, T, when.points) if when.points is not None
                  else np.asarray(when.times, dtype=float))  # fmt: skip
            ks = np.rint(ts / h).astype(int)
            bad = np.abs(ks * h - ts) > 1e-9 * max(T, 1.0)
            if np.any(bad) or ks[0] < 0 or ks[-1] > steps:
                key = "points" if when.points is not None else "times"
                raise _problem(
                    f"observables.{name}.{key}",
                    f"with a fixed step h = {h:g} the times must be multiples of h in [0, T]; "
                    f"got {list(map(float, ts[bad] if np.any(bad) else ts))}",
                )
        per[name] = ks
    every = max(int(np.gcd.reduce(np.concatenate([np.asarray(ks, dtype=np.int64)
                                                  for ks in per.values()]))), 1)  # fmt: skip
    index = {name: tuple((np.asarray(ks, dtype=np.int64) // every).tolist())
             for name, ks in per.items()}  # fmt: skip
    return steps, every, index


def _est_continuous(T: float, rtol: float, rate: float, flops_rhs: float) -> dict[str, Any]:
    steps = max(1.0, 0.15 * T * max(rate, 1e-3) * rtol ** (-1.0 / 8.0))
    nfev = 12.0 * steps
    return {
        "flops": nfev * flops_rhs,
        "seconds": nfev * (6e-6 + flops_rhs / 1.5e9),
        "formula": f"~{nfev:.3g} field evaluations (DOP853: 12 per step, ~0.15 T |Omega| "
        "rtol^(-1/8) steps) of the flops of one field, plus 6 us of overhead each",
    }


def _fixed_step_cost(steps: int, flops: float, per: float, how: str = "") -> dict[str, Any]:
    """The cost of ``steps`` fixed steps of ``flops`` and ``per`` seconds each (``how``: the
    estimate of a step, in words)."""
    return {"flops": steps * flops, "seconds": steps * per,
            "formula": f"{steps} steps x ~{_fmt_seconds(per)}{how}"}  # fmt: skip


def _fixed_step_plan(
    fixed: tuple[int, int, dict[str, tuple[int, ...]]], route: str, propagated: tuple[str, ...],
    kernels: tuple[str, ...], cost: dict[str, Any], modules: tuple[str, ...],
) -> SystemPlan:  # fmt: skip
    """The plan of a fixed-step map, ``fixed`` from :func:`_fixed_step_save`."""
    steps, every, index = fixed
    return SystemPlan(route=route, propagated=propagated, kernels=kernels,
                      save={"steps": steps, "save_every": every}, index=index, cost=cost,
                      modules=modules)  # fmt: skip


def diagnostic_kernels(asked: Iterable[str]) -> tuple[str, ...]:
    """The kernels of the diagnostic observables among ``asked``, in the order of their names."""
    return tuple(DIAGNOSTIC_KERNELS[o] for o in sorted(asked) if o in DIAGNOSTIC_KERNELS)


def plan_scene(scene: Scene | Mapping[str, Any], *, budget: Budget | None = None) -> Plan:
    """Plan a scene: the state to propagate, the kernels, the save times and a cost estimate.

    Rules: the attitude is propagated only with the effect ``attitude`` (and by the routes whose
    map needs it); costates are swept only with a terminal cost; only the observables asked for
    are evaluated, each at its own times, from the union of the times handed to the integrator
    (``t_eval`` of ``solve_ivp``, or ``save_every`` of a fixed-step map: the gcd of the steps
    asked for).

    Parameters
    ----------
    scene : Scene or mapping
        The scene (a mapping is validated first).
    budget : Budget, optional
        The limits (default: :data:`MAX_SECONDS`, :data:`MAX_MEMORY`); planning refuses a scene
        whose steps or records alone are over them before it allocates their times.  The plan's
        estimate itself is checked by :meth:`Budget.check` (``run_scene`` does).

    Returns
    -------
    Plan
        What is propagated, what is skipped and why, the save times and the cost estimate.

    Raises
    ------
    SceneError
        Requests the integrator cannot meet (``every`` with an adaptive integrator, times that
        are not multiples of a fixed step, a horizon that is not a whole number of steps), or
        more steps or records than the budget allows.

    Examples
    --------
    >>> from symrb.scenes import parse_scene, plan_scene
    >>> base = {"system": "rigid_body", "parameters": {"n": 10},
    ...         "integrator": {"method": "mv", "h": 0.05}, "horizon": {"T": 100.0}}
    >>> plan = plan_scene({**base, "observables": {"energy": {"every": 100}, "M": "end"}})
    >>> plan.propagated, plan.save
    (('M',), {'steps': 2000, 'save_every': 100})
    >>> plan.index["M"]
    (20,)
    """
    sc: Any = parse_scene(scene)
    obs = sc.observables
    skipped: list[tuple[str, str]] = []
    notes: list[str] = []
    state_names = set(type(sc).STATE_OBSERVABLES)
    not_asked = sorted(o for o in set(type(sc).OBSERVABLES) - set(obs) - state_names
                       if not o.endswith("_gap"))  # fmt: skip
    if not_asked:
        skipped.append((", ".join(not_asked), "not asked for (no diagnostic is evaluated unless "
                        "it is an observable)"))  # fmt: skip
    _precheck(sc, budget or Budget())
    part: SystemPlan = sc._plan(skipped, notes)
    windows = _windows(obs, part.index)
    memory, how = _memory(sc, part)
    record = {name: (obs[name].describe(), windows.get(name, ((), len(part.index[name])))[1])
              for name in obs}  # fmt: skip
    return Plan(
        system=str(sc.system),
        route=part.route,
        propagated=part.propagated,
        skipped=tuple(skipped),
        kernels=part.kernels,
        record=record,
        save=part.save,
        index=part.index,
        cost={**part.cost, "bytes": memory, "bytes_formula": how},
        notes=tuple(notes),
        modules=tuple(dict.fromkeys(_CORE_MODULES + part.modules)),
        windows=windows,
        compare=part.compare,
        title=str(getattr(sc, "title", "")),
    )


def _windows(
    obs: Mapping[str, When], index: Mapping[str, tuple[int, ...]]
) -> dict[str, tuple[tuple[str, ...], int]]:
    """Observable -> (its reductions, the number of windows), for the windowed observables."""
    windows: dict[str, tuple[tuple[str, ...], int]] = {}
    for name, when in obs.items():
        if when.windows is None:
            continue
        if when.windows > len(index[name]):
            raise _problem(f"observables.{name}.windows",
                           f"{when.windows} windows of {len(index[name])} records: give at most "
                           "one window a record")  # fmt: skip
        windows[name] = (when.reductions, when.windows)
    return windows
