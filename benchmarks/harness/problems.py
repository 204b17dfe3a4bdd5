"""The problems timed and the methods that solve them: the test bodies, SciPy's ``solve_ivp`` on a
plain field, symrb's fixed-step flows, and the optional modules found by import."""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

from symrb import _compiled, paper
from symrb._generated import rigid_body as _rb
from symrb._validate import Array
from symrb.algebra import hat, random_lam, random_SO, random_so


def _problem(n: int, seed: int) -> tuple[Array, Array, Array]:
    """(lam, Q0, M0) of the benchmarks: for n = 3 the body of the README, else random."""
    rng = np.random.default_rng(seed)
    Q0 = random_SO(n, seed=rng)
    if n == 3:
        return np.array([0.7, 1.1, 1.6]), Q0, hat([0.5, 1.0, 1.5])
    lam = random_lam(n, seed=rng)
    M0 = random_so(n, seed=rng)
    return lam, Q0, M0 * (2.65 / np.linalg.norm(M0))  # |M0|_F as for n = 3


def _plain_field(lam: Array) -> Callable[[float, Array], Array]:
    """The rigid body field on a flat state (Q, M) for ``solve_ivp``, from the generated kernel,
    with no validation: what a user would write by hand."""
    n = lam.shape[-1]
    nn = n * n

    def f(_t: float, y: Array) -> Array:
        dQ, dM = _rb.rigid_body_rhs(y[:nn].reshape(n, n), y[nn:].reshape(n, n), lam)
        return np.concatenate((dQ.ravel(), dM.ravel()))

    return f


def _solve_ivp_end(lam: Array, Q0: Array, M0: Array, T: float, method: str, rtol: float):
    n = lam.shape[-1]
    y0 = np.concatenate((Q0.ravel(), M0.ravel()))
    f = _plain_field(lam)

    def go() -> tuple[Array, Array]:
        sol = solve_ivp(f, (0.0, T), y0, method=method, rtol=rtol, atol=rtol)
        if not sol.success:
            raise RuntimeError(f"solve_ivp {method} failed: {sol.message}")
        y = sol.y[:, -1]
        return y[: n * n].reshape(n, n), y[n * n :].reshape(n, n)

    return go


def _last(sol: Any, n: int) -> tuple[Array, Array]:
    """The last (Q, M) of a result object (``y.Q``, ``y.M``) or a pair."""
    if hasattr(sol, "y"):
        if getattr(sol, "success", True) is False:
            raise RuntimeError(str(getattr(sol, "message", "the run failed")))
        Q, M = sol.y["Q"], sol.y["M"]
    else:
        Q, M = sol
    return np.asarray(Q).reshape(-1, n, n)[-1], np.asarray(M).reshape(-1, n, n)[-1]


class _NotApplicable(Exception):
    """A method that does not apply to the problem (not a failure)."""


def _backend() -> str:
    """The n = 3 backend of symrb.engine.mv_flow that the benchmark times: the compiled loop when
    numba is importable (``symrb[fast]``), else the NumPy path."""
    return "numba" if _compiled.AVAILABLE else "numpy"


def _optional(module: str) -> tuple[Any, str]:
    """(module or None, why not)."""
    try:
        return importlib.import_module(f"symrb.{module}"), ""
    except Exception as exc:  # noqa: BLE001 - any failure means "not available"
        return None, f"symrb.{module} not importable ({type(exc).__name__}: {exc})"


def _modules(notes: list[str] | None = None) -> dict[str, Any]:
    """symrb's engine, compose and exact modules (None, with a note, for one that fails to
    import: the benchmark then reports its methods as unavailable)."""
    mods: dict[str, Any] = {}
    for mod in ("engine", "compose", "exact"):
        mods[mod], why = _optional(mod)
        if why and notes is not None:
            notes.append(why)
    return mods


def _find(mod: Any, names: Iterable[str]) -> Callable[..., Any] | None:
    for name in names:
        fn = getattr(mod, name, None) if mod is not None else None
        if callable(fn):
            return fn
    return None


def _fixed_step_runner(kind: str, mods: dict[str, Any]) -> Callable[..., Any] | None:
    """A function (lam, Q0, M0, T, h) -> thunk returning (Q(T), M(T)), or None if unavailable."""
    engine, compose = mods.get("engine"), mods.get("compose")
    if kind == "MV":
        fn: Callable[..., Any] | None = paper.discrete_rigid_body_flow
    elif kind == "MV-fast" or kind.startswith("MV-pre"):
        mv = _find(engine, ["mv_flow"])
        if mv is None:
            return None
        order = int(kind[len("MV-pre") :]) if kind.startswith("MV-pre") else 2
        backend = _backend()

        def fn(Q0: Array, M0: Array, lam: Array, h: float, steps: int, **kw: Any) -> Any:
            n = np.shape(lam)[-1]
            if order != 2 and n != 3:
                raise _NotApplicable(f"{kind} is for n = 3")
            method = backend if n == 3 else "auto"
            return mv(Q0, M0, lam, h, steps, order=order, method=method, **kw)
    elif kind.startswith("MV-comp"):
        base = _find(compose, ["composed_rigid_body_flow"])
        if base is None:
            return None
        order = int(kind[len("MV-comp") :])

        def fn(Q0: Array, M0: Array, lam: Array, h: float, steps: int, **kw: Any) -> Any:
            return base(Q0, M0, lam, h, steps, order=order, **kw)

    elif kind == "RKMK4":
        fn = _find(compose, ["rkmk4_rigid_body_flow"])
    elif kind == "midpoint":
        fn = _find(compose, ["midpoint_rigid_body_flow"])
    else:  # pragma: no cover - internal
        raise ValueError(kind)
    if fn is None:
        return None
    flow = fn

    def make(lam: Array, Q0: Array, M0: Array, T: float, h: float):
        steps = max(1, round(T / h))
        hh = T / steps
        n = lam.shape[-1]

        def go() -> tuple[Array, Array]:
            try:
                sol = flow(Q0, M0, lam, hh, steps, save_every=steps)
            except TypeError:
                sol = flow(Q0, M0, lam, hh, steps)
            Q, M = _last(sol, n)
            M0_out = np.asarray(sol.y["M"]).reshape(-1, n, n)[0] if hasattr(sol, "y") else None
            if M0_out is not None and not np.allclose(M0_out, M0) and np.allclose(M0_out, hh * M0):
                M = M / hh  # a flow that returns discrete momenta (h times the continuous one)
            return Q, M

        return go

    return make
