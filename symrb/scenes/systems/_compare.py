"""Second runs of a body (``[compare]`` and ``[[compare]]``, for the ``*_gap`` observables):
the model :class:`Compare`, the checks that the runs can be paired, their plans and the gaps;
:class:`_ComparedBody` is the base of the two bodies that take them (the rigid body and the
symmetric rigid body)."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import Discriminator, Field, Tag, field_validator

from ..._validate import Array
from ...algebra import random_SO
from ...errors import InputError
from ..parse import parse_scene
from ..plan import Plan, SystemPlan, plan_scene
from ..schema import Matrix, SceneError, When, _Model
from . import _rigid_body_methods as rbm
from ._body import Continuous, Discrete, _BodyScene


def _integrator_family(value: Any) -> str:
    """``[kind]`` for an integrator of the symmetric rigid body (a table with ``kind``),
    ``[method]`` for one of the rigid body (``simulate``'s keywords)."""
    if isinstance(value, Mapping):
        return "[kind]" if "kind" in value else "[method]"
    return "[kind]" if isinstance(value, Continuous | Discrete) else "[method]"


#: the integrator of a second run: the rigid body's (``method``) or the symmetric body's (``kind``)
CompareIntegrator = Annotated[
    Annotated[rbm.RigidBodyIntegrator, Tag("[method]")]
    | Annotated[Annotated[Continuous | Discrete, Field(discriminator="kind")], Tag("[kind]")],
    Discriminator(_integrator_family),
]


class Compare(_Model):
    r"""A second run on the same parameters (the same initial data), for the ``*_gap``
    observables: ``integrator`` (required; a rigid body's takes ``method`` and ``simulate``'s
    keywords, a symmetric rigid body's ``kind``) and ``system`` (default: the scene's own; the
    rigid body and the symmetric rigid body describe the same motion).

    ``rotation`` (a seed of ``symrb.random_SO(n, seed=rotation)``, or a rotation matrix R) runs
    the second run in a rotated frame: its initial state (every attitude and costate in it:
    :math:`Q_0`, :math:`P_0`, and :math:`Q_1` of MV-Algorithm 1 or of ``start = "Q1_M1"``) is
    multiplied by R on the left, and its attitudes (and costates) are rotated back,
    :math:`R^TQ'`, before the gaps; the body momenta are its own.  The equations are invariant,
    so the gap is the rounding of the algorithm.  ``shift = s`` (fixed steps) compares the
    second run's k-th step with the first run's (k + s)-th: a run started one index off is
    read as if it had started at step s; the second run is s steps shorter and the gaps start
    at step s.  ``label`` names the run in the plan.

    Several second runs: an array of tables ``[[compare]]``; each ``*_gap`` observable then has
    one column per run, in their order (the records that every run can be compared with)."""

    system: Literal["rigid_body", "symmetric_rigid_body"] | None = None
    integrator: CompareIntegrator
    rotation: Annotated[int, Field(ge=0)] | Matrix | None = None
    shift: int = Field(default=0, ge=0)
    label: str = ""

    @field_validator("rotation")
    @classmethod
    def _a_rotation(cls, value: Any) -> Any:
        if isinstance(value, tuple):
            R = np.asarray(value, dtype=float)
            if R.ndim != 2 or R.shape[0] != R.shape[1]:
                raise InputError(f"a rotation is a square matrix, got shape {R.shape}")
            dev = float(np.abs(R.T @ R - np.eye(R.shape[0])).max())
            if dev > 1e-12 or np.linalg.det(R) < 0:
                raise InputError(f"not a rotation: max |R^T R - I| = {dev:.2e}, "
                                 f"det R = {np.linalg.det(R):.3g}")  # fmt: skip
        return value


#: one [compare] table, or an array of tables [[compare]] (one column per run in each gap)
Compares = Annotated[
    Annotated[Compare, Tag("[compare]")] | Annotated[tuple[Compare, ...], Tag("[[compare]]")],
    Discriminator(lambda v: "[[compare]]" if isinstance(v, list | tuple) else "[compare]"),
]


#: observables of the rigid body that need only its attitude (MV-Algorithm 1 has no momenta)
_Q_ONLY = ("Q", "orthogonality", "Q_gap")


def _compares(sc: Any) -> list[Compare]:
    """The scene's second runs, in order (none, one [compare] table, or [[compare]] tables)."""
    cmp = getattr(sc, "compare", None)
    if cmp is None:
        return []
    return list(cmp) if isinstance(cmp, tuple) else [cmp]


def _route_problems(sc: Any, lines: Mapping[tuple[str, ...], int]) -> list[dict[str, Any]]:
    """What the chosen integrators cannot record: observables MV-Algorithm 1 has no momenta
    for, and second runs whose records cannot be paired with the first run's (adaptive against
    fixed steps with ``every``; a shift without fixed steps or between times)."""
    out: list[dict[str, Any]] = []

    def add(key: tuple[str, ...], message: str, allowed: list[Any] | None) -> None:
        line = next((lines[key[:i]] for i in range(len(key), 0, -1) if key[:i] in lines), None)
        out.append({"key": ".".join(key), "line": line, "message": message, "allowed": allowed})

    if isinstance(getattr(sc, "integrator", None), rbm.MVAlgorithm1):
        for name in sc.observables:
            if name not in _Q_ONLY:
                add(("observables", name), "MV-Algorithm 1 steps configurations only "
                    "(Q_k, Q_{k+1}) -> (Q_{k+1}, Q_{k+2}); it has no momentum", list(_Q_ONLY))  # fmt: skip
    cmps = _compares(sc)
    gaps = {name: when for name, when in sc.observables.items() if name.endswith("_gap")}
    mine = rbm.step(sc.integrator)
    fixed = mine is not None
    for i, cmp in enumerate(cmps):
        at = ("compare",) if not isinstance(sc.compare, tuple) else ("compare", str(i))
        theirs, h2 = cmp.integrator, rbm.step(cmp.integrator)
        if isinstance(theirs, rbm.MVAlgorithm1):
            for name in gaps:
                if name != "Q_gap":
                    add(("observables", name), "the second run (MV-Algorithm 1) steps "
                        "configurations only; it has no momentum", ["Q_gap"])  # fmt: skip
        if mine is not None and h2 is not None and h2 != mine:
            add(at + ("integrator", "h"), f"the second run must step as the first, h = "
                f"{mine:g}, got {h2:g}", [mine])  # fmt: skip
        if fixed != (h2 is not None):
            h = mine if h2 is None else h2
            for name, when in gaps.items():
                if when.every is not None:
                    add(("observables", name, "every"),
                        "'every' counts the steps of a fixed-step run, and the other run of the "
                        "comparison (an adaptive integrator) chooses its own steps: record the "
                        f"gap at the end, at times or at points that are multiples of h = {h:g}",
                        ["end", "times", "points"])  # fmt: skip
        if cmp.shift:
            if not fixed or h2 is None:
                add(at + ("shift",), "a shift counts steps: both runs need a fixed step", [0])
                continue
            T, h = float(sc.horizon.T), sc.integrator.h
            if cmp.shift * h >= T * (1 - 1e-12):
                add(at + ("shift",), f"a shift of {cmp.shift} steps of h = {h:g} leaves nothing "
                    f"of T = {T:g} to compare: give fewer than {round(T / h)}", None)  # fmt: skip
            for name, when in gaps.items():
                if when.every is None and not when.end:
                    add(("observables", name), "a shifted comparison pairs steps: record the gap "
                        "at the end or every k steps", ["end", "every"])  # fmt: skip
                elif when.every is not None and cmp.shift % when.every:
                    add(at + ("shift",), f"the shift must be a multiple of observables.{name}'s "
                        f"every = {when.every}, got {cmp.shift}",
                        [when.every * j for j in range(1, 4)])  # fmt: skip
        if isinstance(cmp.rotation, tuple):
            n = sc.parameters.n
            if np.shape(cmp.rotation) != (n, n):
                add(at + ("rotation",), f"a rotation of R^{n} is {n} x {n}, got shape "
                    f"{np.shape(cmp.rotation)}", None)  # fmt: skip
    return out


def _gap_offset(cmp: Compare, when: When) -> int:
    """The first record of a gap observable that the (shifted) second run can be paired with."""
    return cmp.shift // when.every if cmp.shift and when.every is not None else 0


def _compare_scene(sc: Any, cmp: Compare) -> Any:
    """The scene of a second run of the ``*_gap`` observables: the same parameters and horizon
    (``shift`` steps shorter), the integrator (and system) of ``cmp``, recording the compared
    variables at the gap observables' times."""
    system = cmp.system or sc.system
    gaps = {name: when for name, when in sc.observables.items() if name.endswith("_gap")}
    observables = {
        name.removesuffix("_gap"): when.model_dump(exclude={"windows", "reduce"},
                                                   exclude_none=True, exclude_defaults=True)
        for name, when in gaps.items()
    }  # fmt: skip
    horizon = sc.horizon.model_dump()
    if cmp.shift:
        horizon["T"] = float(sc.horizon.T) - cmp.shift * sc.integrator.h
    data = {
        "title": cmp.label or f"second run of {sc.title or sc.system}",
        "system": system,
        "effects": ["attitude"] if system == "rigid_body" and "Q_gap" in gaps else [],
        "parameters": sc.parameters.model_dump(exclude_defaults=True),
        "integrator": cmp.integrator.model_dump(),
        "horizon": horizon,
        "observables": observables,
    }
    return parse_scene(data, source="the [compare] run")


def _compare_error(sc: Any, exc: SceneError, i: int | None = None) -> SceneError:
    """A problem of a second run, keyed as in the scene: ``compare[.i].integrator...`` and the
    gap observables (``observables.M`` of the second run is ``observables.M_gap``)."""
    at = "compare" if i is None or not isinstance(sc.compare, tuple) else f"compare.{i}"
    problems = []
    for q in exc.problems:
        key = q["key"]
        if key.startswith("integrator"):
            key = f"{at}.{key}"
        elif key.startswith("observables."):
            parts = key.split(".")
            parts[1] += "_gap"
            key = ".".join(parts)
        problems.append({**q, "key": key})
    return SceneError(problems, "scene ([compare])")


def _plan_compare(sc: Any, cmp: Compare, i: int) -> Plan:
    try:
        return plan_scene(_compare_scene(sc, cmp))
    except SceneError as exc:
        raise _compare_error(sc, exc, i) from None


def _rotation(sc: Any, cmp: Compare) -> Array | None:
    """The rotation R of a second run in a rotated frame (None without one)."""
    if cmp.rotation is None:
        return None
    if isinstance(cmp.rotation, int):
        return random_SO(sc.parameters.n, seed=cmp.rotation)
    return np.asarray(cmp.rotation, dtype=float)


def _rotated_route(sc: Any, cmp: Compare, c2: Plan) -> str:
    """The route of a second run in a rotated frame: from the rotated state, then rotated back."""
    if (cmp.system or sc.system) == "rigid_body" and isinstance(cmp.integrator, rbm.Discrete):
        return (f"symrb.symmetric_flow(R Q0, R P0, h={cmp.integrator.h:g}) with "
                "P0 = Q0 M0 / 2 (the symmetric algorithm's state, rotated), then "
                "R^T Q")  # fmt: skip
    ci = cmp.integrator
    state = ("(R Q0, R P0)" if (cmp.system or sc.system) != "rigid_body"
             else "(R Q0, R Q1)" if isinstance(ci, rbm.MVAlgorithm1)
             else "(R Q1, M1)" if getattr(ci, "start", "") == "Q1_M1"
             else "(R Q0, M0)")  # fmt: skip
    back = "R^T Q" if "P0" not in state else "R^T Q, R^T P"
    return f"{c2.route}; from the rotated state {state}, then {back}"


def _with_compares(sc: Any, part: SystemPlan, notes: list[str]) -> SystemPlan:
    """The plan of a body with its second runs planned (their modules, their cost, the records
    of the gaps that every run can be paired with); notes on each run appended to ``notes``."""
    cmps = _compares(sc)
    if not cmps:
        return part
    # parse_scene has checked that the runs can be paired (_route_problems)
    plans = tuple(_plan_compare(sc, cmp, i) for i, cmp in enumerate(cmps))
    modules = part.modules
    for i, (cmp, c2) in enumerate(zip(cmps, plans, strict=True)):
        who = ("compare" if len(cmps) == 1 and not isinstance(sc.compare, tuple)
               else f"compare.{i}") + (f" ({cmp.label})" if cmp.label else "")  # fmt: skip
        if cmp.rotation is not None:
            how = (f"R = symrb.random_SO({sc.parameters.n}, seed={cmp.rotation})"
                   if isinstance(cmp.rotation, int) else "R as given")  # fmt: skip
            notes.append(f"{who}: in the frame rotated by {how}")
            if c2.propagated == ("M",):
                notes.append(f"{who}: propagates only M, which the rotation leaves as it "
                             "is")  # fmt: skip
            else:
                route2 = _rotated_route(sc, cmp, c2)
                plans = plans[:i] + (dataclasses.replace(c2, route=route2),) + plans[i + 1 :]
        if cmp.shift:
            notes.append(f"{who}: shifted by {cmp.shift} step{'s' * (cmp.shift > 1)}: its "
                         f"step k is compared "
                         f"with step k + {cmp.shift} of this run; it runs "
                         f"{c2.save['steps']} steps")  # fmt: skip
        modules += c2.modules
    cost = part.cost
    runs = "the second run" if len(plans) == 1 else f"{len(plans)} second runs"
    cost = {"flops": cost["flops"] + sum(c2.cost["flops"] for c2 in plans),
            "seconds": cost["seconds"] + sum(c2.cost["seconds"] for c2 in plans),
            "formula": f"this run ({cost['formula']}) plus {runs}"}  # fmt: skip
    index = dict(part.index)
    for name, when in sc.observables.items():
        skip = max(_gap_offset(cmp, when) for cmp in cmps) if name.endswith("_gap") else 0
        if skip:
            index[name] = index[name][skip:]
            notes.append(f"{name}: recorded from step {skip * (when.every or 0)} on, where "
                         "every second run has a step to compare with")  # fmt: skip
    compare = plans if isinstance(sc.compare, tuple) else plans[0]
    return dataclasses.replace(part, modules=modules, cost=cost, index=index, compare=compare)


def _with_gaps(
    sc: Any, plan: Plan, times: dict[str, Array], data: dict[str, Array], failure: str
) -> tuple[dict[str, Array], dict[str, Array], str]:
    """Run the second runs and replace each ``*_gap`` record by the largest entry of
    |X - X'| (one column per run of an array of ``[[compare]]`` tables)."""
    if plan.compare is None:
        return times, data, failure
    cmps = _compares(sc)
    plans = plan.compare if isinstance(plan.compare, tuple) else (plan.compare,)
    gaps = [k for k in data if k.endswith("_gap")]
    columns: dict[str, list[Array]] = {name: [] for name in gaps}
    for i, (cmp, c2) in enumerate(zip(cmps, plans, strict=True)):
        sc2 = _compare_scene(sc, cmp)
        _, other, failed = sc2._observed(c2, sc2._inputs(), _rotation(sc, cmp))
        if failed and not failure:
            failure = f"the [compare] run{f' compare.{i}' * (len(cmps) > 1)}: {failed}"
        for name in gaps:
            # the first record of the gap is the one every run can be paired with; this
            # run's record j is paired with the first run's record j + (its offset)
            when = sc.observables[name]
            skip = max(_gap_offset(c, when) for c in cmps) - _gap_offset(cmp, when)
            mine, theirs = data[name], other[name.removesuffix("_gap")][skip:]
            k = min(mine.shape[0], theirs.shape[0])
            columns[name].append(np.abs(mine[:k] - theirs[:k]).max(axis=(-2, -1)))
    for name, cols in columns.items():
        k = min(c.shape[0] for c in cols)
        times[name] = times[name][:k]
        data[name] = (np.stack([c[:k] for c in cols], axis=1)
                      if isinstance(plan.compare, tuple) else cols[0])  # fmt: skip
    return times, data, failure


class _ComparedBody(_BodyScene):
    """A body that takes second runs: its own plan (the hook ``_own_plan``) with the second
    runs', its own run with the gaps, and the checks that the runs can be paired."""

    def _own_plan(self, skipped: list[tuple[str, str]], notes: list[str]) -> SystemPlan:
        """The plan of the run itself (without its second runs)."""
        raise NotImplementedError

    def _plan(self, skipped: list[tuple[str, str]], notes: list[str]) -> SystemPlan:
        return _with_compares(self, self._own_plan(skipped, notes), notes)

    def _run(self, plan: Plan, x: dict[str, Any]) -> tuple[dict[str, Array], dict[str, Array], str]:
        times, data, failure = self._observed(plan, x)
        return _with_gaps(self, plan, times, data, failure)

    def _problems(self, lines: Mapping[tuple[str, ...], int]) -> list[dict[str, Any]]:
        return _route_problems(self, lines)
