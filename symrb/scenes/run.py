"""Running a scene: :func:`scene_inputs` (the arrays it starts from), :func:`run_scene` (plan,
run through the system's hook ``_run``, reduce the windowed observables, store)."""

from __future__ import annotations

import os
import re
import time
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from .._validate import Array
from ..errors import InputError
from .parse import load_scene, parse_scene
from .plan import MAX_MEMORY, MAX_SECONDS, Budget, Plan, plan_scene
from .result import SceneResult
from .schema import Scene, SceneError
from .store import SceneStore, _store, _versions, scene_key


def scene_inputs(scene: Scene) -> dict[str, Any]:
    """The arrays a scene starts from (what a hand-written run would pass).

    Parameters
    ----------
    scene : Scene
        A validated scene.

    Returns
    -------
    dict
        For the bodies ``lam``, ``Q0``, ``M0`` (and ``P0`` for the symmetric rigid body, ``B0``
        for McLachlan-Scovel); for the orbits ``x0``, ``N``; for the ResNet ``x0``, ``targets``,
        ``labels``, ``K0``, ``beta0`` (on the digits also ``x_test``, ``labels_test`` and
        ``classes``); the Toda lattice ``a0``, ``b0``, ``L0``; the SO(n) network ``Q0``, ``targets``,
        ``lam``, ``alpha``, ``U0``: each system says in its hook ``_inputs``.

    Examples
    --------
    >>> from symrb.scenes import parse_scene, scene_inputs
    >>> scene = parse_scene({"system": "rigid_body", "parameters": {"n": 4, "seed": 1},
    ...                      "integrator": {"method": "DOP853"}, "horizon": {"T": 1.0},
    ...                      "observables": {"M": "end"}})
    >>> x = scene_inputs(scene)
    >>> x["lam"].shape, x["M0"].shape
    ((4,), (4, 4))
    """
    try:
        x = scene._inputs()
    except SceneError:
        raise
    except InputError as exc:  # a check of symrb's functions: name the scene's key
        raise as_scene_error(exc, scene) from None
    bad = [k for k, a in x.items() if _not_finite(a)]
    if bad:
        raise SceneError([{"key": f"parameters ({bad[0]})", "line": None, "allowed": None,
                           "message": f"the initial {bad[0]} made of the parameters is not "
                           "finite"}])  # fmt: skip
    return x  # type: ignore[no-any-return]


def _not_finite(a: Any) -> bool:
    """Whether an input or a result array holds NaN or infinity (non-numeric arrays: no)."""
    if not isinstance(a, np.ndarray) or a.dtype.kind not in "fc":
        return False
    return not bool(np.isfinite(a).all())


def _keys(data: Any, prefix: str = "") -> list[str]:
    """The dotted keys of a dumped scene, the deepest first."""
    out: list[str] = []
    if isinstance(data, dict):
        for k, val in data.items():
            out += _keys(val, f"{prefix}{k}.") + [f"{prefix}{k}"]
    return out


def as_scene_error(exc: InputError, scene: Any) -> SceneError:
    """A :class:`SceneError` of an :class:`InputError` raised by the functions a scene calls:
    the key is the scene's key the message names (``parameters.lam``, or ``lam`` alone)."""
    if isinstance(exc, SceneError):
        return exc
    msg = str(exc)
    keys = _keys(scene.model_dump(mode="json"))
    key = next((k for k in keys if k in msg), None)
    if key is None:
        key = next((k for k in keys if re.search(rf"\b{re.escape(k.rsplit('.', 1)[-1])}\b", msg)
                    and "." in k), "")  # fmt: skip
    return SceneError([{"key": key, "line": None, "allowed": None, "message": msg}])


def _window_reduce(
    t: Array, values: Array, windows: int, reductions: Sequence[str]
) -> tuple[Array, Array]:
    """Reduce a recorded series per window (see :class:`When`): (window times, values)."""
    a = np.asarray(values)
    blocks = np.array_split(np.arange(a.shape[0]), min(windows, a.shape[0]))
    out = []
    for r in reductions:
        if r == "max_abs":
            b = np.abs(a)
        elif r == "max_abs_change":
            b = np.abs(a - a[0])
        elif r == "max_rel_change":
            b = np.abs(a - a[0]) / np.abs(a[0])
        else:
            b = a
        fn = np.min if r == "min" else np.max
        out.append(np.stack([fn(b[i], axis=0) for i in blocks]))
    ends = np.array([t[i[-1]] for i in blocks])
    return ends, (out[0] if len(out) == 1 else np.stack(out, axis=1))


def _execute(sc: Any, plan: Plan) -> tuple[dict[str, Array], dict[str, Array], str]:
    """Run a planned scene: (times per observable, data per observable, failure message), the
    windowed observables reduced."""
    times, data, failure = sc._run(plan, scene_inputs(sc))
    for name, (reductions, windows) in plan.windows.items():
        if data[name].shape[0] == 0:  # pragma: no cover - a run that failed at once
            continue
        times[name], data[name] = _window_reduce(times[name], data[name], windows, reductions)
    return times, data, failure


def run_scene(
    scene: Scene | Mapping[str, Any] | str | os.PathLike[str],
    *,
    cache: bool | str | os.PathLike[str] | SceneStore | None = True,
    max_seconds: float = MAX_SECONDS,
    max_memory: float = MAX_MEMORY,
) -> SceneResult:
    """Plan and run a scene, or load its result from the cache.

    Parameters
    ----------
    scene : Scene, mapping, or path
        The scene (a path or TOML text is read with :func:`load_scene`).
    cache : bool, path or SceneStore, optional
        ``True`` (default): the store at :func:`~symrb.scenes.store.default_cache_dir`
        (``$SYMRB_CACHE_DIR``, else ``$XDG_CACHE_HOME/symrb/scenes``, else
        ``~/.cache/symrb/scenes``); a directory or a :class:`SceneStore`; ``False``: compute and
        store nothing.  An entry that fails its checksums, or a cache that cannot be written,
        gives a :class:`~symrb.errors.CacheWarning` and the result is computed.
    max_seconds, max_memory : float, optional
        The budget: a scene whose estimated seconds or bytes of saved states
        (``plan.cost``) are over it is refused before anything is computed (default ten
        minutes and 2 GiB).

    Returns
    -------
    SceneResult
        ``meta["from_cache"]`` tells whether anything was computed.  A run whose integrator
        stopped early, or whose observables are not finite, has ``meta["success"]`` False (and
        ``meta["message"]`` says why) and is not stored.

    Raises
    ------
    SceneError
        An invalid scene, initial data its functions refuse (naming the key), or an estimate
        over the budget.

    Examples
    --------
    >>> from symrb.scenes import run_scene
    >>> r = run_scene({"system": "resnet", "effects": ["terminal_cost"],
    ...                "integrator": {"kind": "gradient_descent"}, "horizon": {"steps": 20},
    ...                "observables": {"loss": {"every": 10}}}, cache=False)
    >>> r.times["loss"], bool(r["loss"][-1] < r["loss"][0])
    (array([ 0., 10., 20.]), True)
    """
    if isinstance(scene, str | os.PathLike):
        sc: Any = load_scene(scene)
    else:
        sc = parse_scene(scene)
    budget = Budget(float(max_seconds), float(max_memory))
    plan = plan_scene(sc, budget=budget)
    budget.check(plan)
    store = _store(cache)
    key = scene_key(sc, plan)
    if store is not None:
        hit = store.get(key, sc, plan)
        if hit is not None:
            hit.meta["from_cache"] = True
            return hit
    start = time.perf_counter()
    try:
        times, data, failure = _execute(sc, plan)
    except InputError as exc:
        raise as_scene_error(exc, sc) from None
    seconds = time.perf_counter() - start
    bad = [name for name, a in data.items() if _not_finite(np.asarray(a))]
    if bad and not failure:
        a = np.asarray(data[bad[0]])
        first = int(np.argmax(~np.isfinite(a.reshape(a.shape[0], -1)).all(axis=1)))
        failure = (f"observables.{bad[0]} is not finite from record {first} on (an overflow: "
                   "smaller initial data, a smaller step or a shorter horizon)")  # fmt: skip
    meta = {"key": key, "versions": _versions(), "seconds": seconds, "from_cache": False,
            "success": not failure, "message": failure or "ok"}  # fmt: skip
    result = SceneResult(sc, plan, times, data, meta)
    if store is not None and not failure:
        store.put(key, result)
    return result
