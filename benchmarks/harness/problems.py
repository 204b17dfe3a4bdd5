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


def _lean3_scalar(lam: Array) -> Callable[[float, Array], Array]:
    """n = 3, 12 unknowns (Q row by row, then m), Euler's equations by hand on Python floats:
    :math:`\\omega_i = m_i / I_i` with :math:`I_1 = \\lambda_2 + \\lambda_3` (and cyclic),
    :math:`\\dot Q = Q\\hat\\omega`, :math:`\\dot m = m \times \\omega`."""
    l1, l2, l3 = (float(x) for x in lam)
    i1, i2, i3 = 1.0 / (l2 + l3), 1.0 / (l1 + l3), 1.0 / (l1 + l2)
    array = np.array

    def f(_t: float, y: Array) -> Array:
        a, b, c, d, e, g, p, q, r, m1, m2, m3 = y.tolist()
        w1, w2, w3 = m1 * i1, m2 * i2, m3 * i3
        return array(
            [b * w3 - c * w2, c * w1 - a * w3, a * w2 - b * w1,
             e * w3 - g * w2, g * w1 - d * w3, d * w2 - e * w1,
             q * w3 - r * w2, r * w1 - p * w3, p * w2 - q * w1,
             m2 * w3 - m3 * w2, m3 * w1 - m1 * w3, m1 * w2 - m2 * w1]
        )  # fmt: skip

    return f


def _lean3_numpy(lam: Array) -> Callable[[float, Array], Array]:
    """n = 3, 12 unknowns, NumPy on views: the columns of :math:`Q\\hat\\omega` and
    :math:`m\times\\omega` written into one new array (no concatenation)."""
    l1, l2, l3 = (float(x) for x in lam)
    inv = np.array([1.0 / (l2 + l3), 1.0 / (l1 + l3), 1.0 / (l1 + l2)])

    def f(_t: float, y: Array) -> Array:
        Q = y[:9].reshape(3, 3)
        m = y[9:]
        w = m * inv
        out = np.empty(12)
        o = out[:9].reshape(3, 3)
        o[:, 0] = Q[:, 1] * w[2] - Q[:, 2] * w[1]
        o[:, 1] = Q[:, 2] * w[0] - Q[:, 0] * w[2]
        o[:, 2] = Q[:, 0] * w[1] - Q[:, 1] * w[0]
        out[9:] = m[[1, 2, 0]] * w[[2, 0, 1]] - m[[2, 0, 1]] * w[[1, 2, 0]]
        return out

    return f


def _lean_n(lam: Array) -> Callable[[float, Array], Array]:
    r"""General n, :math:`2n^2` unknowns (Q, M flat): :math:`\Omega_{ij} = M_{ij} /
    (\lambda_i + \lambda_j)`, :math:`\dot Q = Q\Omega`, :math:`\dot M = M\Omega - \Omega M =
    M\Omega - (M\Omega)^T`, two products written into one new array, no validation."""
    n = lam.shape[-1]
    nn = n * n
    inv = 1.0 / (lam[:, None] + lam[None, :])

    def f(_t: float, y: Array) -> Array:
        Q = y[:nn].reshape(n, n)
        M = y[nn:].reshape(n, n)
        W = M * inv
        out = np.empty(2 * nn)
        np.matmul(Q, W, out=out[:nn].reshape(n, n))
        MW = M @ W
        np.subtract(MW, MW.T, out=out[nn:].reshape(n, n))
        return out

    return f


#: The lean fields a user would write for ``solve_ivp``, by n (3, or any n): the benchmark
#: measures each candidate's cost of one call and keeps the fastest (``lean_field``).
LEAN_VARIANTS: dict[str, Callable[[Array], Callable[[float, Array], Array]]] = {
    "n3 scalar (Python floats)": _lean3_scalar,
    "n3 NumPy views": _lean3_numpy,
    "general n (two matmuls)": _lean_n,
}


def _lean_candidates(n: int) -> list[str]:
    return [k for k in LEAN_VARIANTS if n == 3 or not k.startswith("n3")]


def _to_lean(Q: Array, M: Array, variant: str) -> Array:
    """The initial state of a lean field: n = 3 keeps m = vee(M), else M flat."""
    if variant.startswith("n3"):
        return np.concatenate((Q.ravel(), [M[2, 1], M[0, 2], M[1, 0]]))
    return np.concatenate((Q.ravel(), M.ravel()))


def _from_lean(y: Array, n: int, variant: str) -> tuple[Array, Array]:
    nn = n * n
    if variant.startswith("n3"):
        m1, m2, m3 = y[9:12]
        M = np.array([[0.0, -m3, m2], [m3, 0.0, -m1], [-m2, m1, 0.0]])
        return y[:9].reshape(3, 3), M
    return y[:nn].reshape(n, n), y[nn:].reshape(n, n)


def _pick_lean(lam: Array, Q0: Array, M0: Array) -> dict[str, Any]:
    """The lean variants for this n, each checked against the generated field at the initial
    state and timed (median of interleaved rounds of one call): the fastest is used."""
    from .timing import time_interleaved

    n = lam.shape[-1]
    gen = _plain_field(lam)(0.0, np.concatenate((Q0.ravel(), M0.ravel())))
    fns, diffs = {}, {}
    for name in _lean_candidates(n):
        f = LEAN_VARIANTS[name](lam)
        y0 = _to_lean(Q0, M0, name)
        dQ, dM = _from_lean(f(0.0, y0), n, name)
        diffs[name] = float(
            max(np.abs(dQ.ravel() - gen[: n * n]).max(), np.abs(dM.ravel() - gen[n * n :]).max())
        )
        fns[name] = lambda f=f, y0=y0: f(0.0, y0)
    t = time_interleaved(fns, rounds=5, min_time=0.01)
    ok = [k for k in fns if diffs[k] <= 1e-13]
    best = min(ok, key=lambda k: t[k]["median"])
    tgen = time_interleaved(
        {"gen": lambda: _plain_field(lam)(0.0, np.concatenate((Q0.ravel(), M0.ravel())))},
        rounds=3, min_time=0.01,
    )["gen"]  # fmt: skip
    return {
        "variant": best,
        "unknowns": int(_to_lean(Q0, M0, best).size),
        "generated_unknowns": 2 * n * n,
        "per_call": {k: t[k]["median"] for k in fns},
        "generated_per_call": tgen["median"],
        "max_difference_from_generated": diffs,
    }


#: The baselines: a SciPy method's name alone runs on the lean field, ``NAME-gen`` on the
#: generated field of 2 n^2 unknowns.
GEN_SUFFIX = "-gen"


def _solve_ivp_end(
    lam: Array, Q0: Array, M0: Array, T: float, method: str, rtol: float, lean: str | None = None
):
    """A thunk: SciPy's ``method`` to T, on the lean field ``lean`` (a key of
    :data:`LEAN_VARIANTS`) or, when None, the generated field."""
    n = lam.shape[-1]
    if lean is None:
        y0 = np.concatenate((Q0.ravel(), M0.ravel()))
        f = _plain_field(lam)
    else:
        y0 = _to_lean(Q0, M0, lean)
        f = LEAN_VARIANTS[lean](lam)

    def go() -> tuple[Array, Array]:
        sol = solve_ivp(f, (0.0, T), y0, method=method, rtol=rtol, atol=rtol)
        if not sol.success:
            raise RuntimeError(f"solve_ivp {method} failed: {sol.message}")
        y = sol.y[:, -1]
        if lean is None:
            return y[: n * n].reshape(n, n), y[n * n :].reshape(n, n)
        return _from_lean(y, n, lean)

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
    """symrb's engine, compose, exact and splitting modules (None, with a note, for one that
    fails to import: the benchmark then reports its methods as unavailable)."""
    mods: dict[str, Any] = {}
    for mod in ("engine", "compose", "exact", "splitting"):
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


def _step_flow(kind: str, mods: dict[str, Any]) -> Callable[..., Any] | None:
    """The flow ``(Q0, M0, lam, h, steps, save_every=...)`` of a step method, or None."""
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

    elif kind.startswith("split"):
        split = _find(mods.get("splitting"), ["splitting_flow"])
        if split is None:
            return None
        sorder = int(kind[len("split") :])

        def fn(Q0: Array, M0: Array, lam: Array, h: float, steps: int, **kw: Any) -> Any:
            return split(Q0, M0, lam, h, steps, order=sorder, **kw)

    elif kind == "RKMK4":
        fn = _find(compose, ["rkmk4_rigid_body_flow"])
    elif kind == "midpoint":
        fn = _find(compose, ["midpoint_rigid_body_flow"])
    else:  # pragma: no cover - internal
        raise ValueError(kind)
    return fn


def _fixed_step_runner(kind: str, mods: dict[str, Any]) -> Callable[..., Any] | None:
    """A function (lam, Q0, M0, T, h) -> thunk returning (Q(T), M(T)), or None if unavailable."""
    flow = _step_flow(kind, mods)
    if flow is None:
        return None

    def make(lam: Array, Q0: Array, M0: Array, T: float, h: float):
        steps = max(1, round(T / h))
        hh = T / steps
        n = lam.shape[-1]

        scale: list[float] = []  # decided on the first call, so timed calls do not pay for it

        def go() -> tuple[Array, Array]:
            try:
                sol = flow(Q0, M0, lam, hh, steps, save_every=steps)
            except TypeError:
                sol = flow(Q0, M0, lam, hh, steps)
            Q, M = _last(sol, n)
            if not scale:
                out = np.asarray(sol.y["M"]).reshape(-1, n, n)[0] if hasattr(sol, "y") else M0
                # a flow that returns discrete momenta (h times the continuous one)
                discrete = not np.allclose(out, M0) and np.allclose(out, hh * M0)
                scale.append(1.0 / hh if discrete else 1.0)
            return Q, (M if scale[0] == 1.0 else M * scale[0])

        return go

    return make
