"""Sections 3 and 4: throughput on batches of bodies and the cost of a step against n, both in
units of a matrix product; section 5: the time of each evidence level of ``symrb verify``."""

from __future__ import annotations

import json
import math
import os
import time
import warnings
from collections.abc import Callable, Mapping
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from symrb._generated import discrete_rigid_body as _gen
from symrb._stepping import _Stepper
from symrb._validate import Array
from symrb.algebra import random_so

from .problems import _backend, _find, _problem
from .timing import time_interleaved


def _stepper(
    lam: Array, Q: Array, M0: Array, h: float, mods: dict[str, Any], warm: bool = True
) -> tuple[Callable[[], None], str]:
    """(a thunk advancing one step of a batch in place, its name).  Uses ``symrb.engine``'s
    ``MVStepper`` when available, else the warm-started solver loop of ``mv_algorithm2``.  With
    ``warm`` the slow path's first solve on a batch starts from one body's solution."""
    engine = mods.get("engine")
    cls = getattr(engine, "MVStepper", None) if engine is not None else None
    batch = Q.shape[:-2]
    if cls is not None:
        try:
            st = cls(lam, batch)
            state = [Q.copy(), M0.copy()]

            def fast() -> None:
                state[0], state[1] = st.step(state[0], state[1], h)

            return fast, "symrb.engine.MVStepper.step"
        except Exception as exc:  # noqa: BLE001
            warnings.warn(f"symrb.engine.MVStepper unusable: {exc}", stacklevel=2)
    st2 = _Stepper(lam, batch)
    Mk = h * M0
    if warm and batch:
        # a warm step is what is timed: start the batch's Newton from the solution of its first
        # body (the bodies are close), not from one Riccati solve per body
        first = _Stepper(lam, ())
        st2.U = np.broadcast_to(first.solve(Mk.reshape(-1, *Mk.shape[-2:])[0]), Mk.shape)
        st2.U = st2.U.reshape(-1, *Mk.shape[-2:]).copy()
    Om = np.swapaxes(st2.solve(Mk), -1, -2)
    s2 = [Q.copy(), Mk, Om]

    def slow() -> None:
        Qk, Mk, Om = s2
        Mn = _gen.mv_transport(Om, Mk)
        Om = np.swapaxes(st2.solve(Mn), -1, -2)
        s2[0], s2[1], s2[2] = Qk @ np.swapaxes(Om, -1, -2), Mn, Om

    return slow, "MV-Algorithm 2 step (symrb.paper solver, warm started)"


def _batch_problem(n: int, batch: int, seed: int) -> tuple[Array, Array, Array]:
    lam, Q0, M0 = _problem(n, seed)
    rng = np.random.default_rng(seed + 7)
    dM = random_so(n, (batch,), scale=0.05, seed=rng)
    return lam, np.broadcast_to(Q0, (batch, n, n)).copy(), M0 + dM


#: The step counts of two runs of a flow whose time difference gives the marginal cost of a step
#: (the one-off validation, set-up and cold start cancel).
_MARGINAL_K = (4, 24)


def _flow_thunk(
    mv: Callable[..., Any], Q: Array, M: Array, lam: Array, h: float, K: int, method: str
) -> Callable[[], Any]:
    return lambda: mv(Q, M, lam, h, K, save_every=K, method=method)


def _throughput_scale(backend: str, batch: int) -> int:
    """The factor on _MARGINAL_K for a batch: the runs take well above the one-off cost."""
    return max(1, math.ceil((5e4 if backend == "numba" else 5e2) / batch))


def _marginal(t: Mapping[str, Any], pattern: str, scale: int = 1) -> float:
    """(median time at the larger K - at the smaller K) / (difference in steps)."""
    k1, k2 = (k * scale for k in _MARGINAL_K)
    lo = t[pattern.format(K=k1)]["median"]
    hi = t[pattern.format(K=k2)]["median"]
    return float((hi - lo) / (k2 - k1))


def _matmul_thunk(A1: Array, A2: Array, out: Array | None) -> Callable[[], Any]:
    if out is None:
        return lambda: A1 @ A2
    return lambda: np.matmul(A1, A2, out=out)


#: The two batched 3x3 products of the throughput section, by their key in a row.
MATMULS = {
    "matmul": "np.matmul(A, B, out=C) on (batch, 3, 3) arrays",
    "matmul_soa": "np.einsum('ikb,kjb->ijb', A, B) on (3, 3, batch) arrays (the engine's layout)",
}


def _throughput(p: dict[str, Any], mods: dict[str, Any], log: Callable[[str], None]):
    h = 0.01
    fns: dict[str, Callable[[], Any]] = {}
    name = ""
    for B in p["batches"]:
        lam, Q, M = _batch_problem(3, B, p["seed"])
        fns[f"step B={B}"], name = _stepper(lam, Q, M, h, mods)
        A1 = np.asarray(np.random.default_rng(B).standard_normal((B, 3, 3)))
        A2 = np.asarray(np.random.default_rng(B + 1).standard_normal((B, 3, 3)))
        C = np.empty_like(A1)
        fns[f"matmul B={B}"] = _matmul_thunk(A1, A2, C)
        # the same products in the layout of the engine's batch: components first, (3, 3, B)
        S1, S2 = (
            np.ascontiguousarray(A1.transpose(1, 2, 0)),
            np.ascontiguousarray(A2.transpose(1, 2, 0)),
        )
        fns[f"soa B={B}"] = partial(np.einsum, "ikb,kjb->ijb", S1, S2)
    mv = _find(mods.get("engine"), ["mv_flow"])
    backends = ("numpy", "numba") if _backend() == "numba" else ("numpy",)
    if mv is not None:
        for B in p["batches"]:
            lam, Q, M = _batch_problem(3, B, p["seed"])
            for be in backends:
                # enough steps that the difference of the two runs is far above the one-off
                # cost and its noise: about 2e3 body-steps a step of K for NumPy, 2e5 compiled
                scale = _throughput_scale(be, B)
                for K in _MARGINAL_K:
                    k = K * scale
                    fns[f"flow {be} K={k} B={B}"] = _flow_thunk(mv, Q, M, lam, h, k, be)
    log(f"throughput: batches {list(p['batches'])}")
    t = time_interleaved(fns, rounds=p["rounds"], min_time=p["min_time"])
    rows = []
    for B in p["batches"]:
        ts, tm, tsoa = t[f"step B={B}"], t[f"matmul B={B}"], t[f"soa B={B}"]
        row: dict[str, Any] = {
            "batch": B,
            "step": ts,
            "matmul": tm,
            "matmul_soa": tsoa,
            "step_body_steps_per_s": B / ts["median"],
            "matmul_products_per_s": B / tm["median"],
            "step_over_matmul": ts["median"] / tm["median"],
        }
        if mv is not None:
            for be in backends:
                per = _marginal(t, f"flow {be} K={{K}} B={B}", _throughput_scale(be, B))
                row[f"flow_{be}_per_step"] = per
                row[f"flow_{be}_body_steps_per_s"] = B / per
                row[f"flow_{be}_over_matmul"] = per / tm["median"]
                row[f"flow_{be}_over_matmul_soa"] = per / tsoa["median"]
        rows.append(row)

    # cold start (a fresh stepper and its first step) against a warm step, same batch; the batch
    # is cut down (recorded) when a cold start of ``cold_batch`` bodies would exceed the budget
    def cold_run(B: int) -> tuple[float, Callable[[], None]]:
        lam, Q, M = _batch_problem(3, B, p["seed"])
        t0 = time.process_time()
        step, _n = _stepper(lam, Q, M, h, mods, warm=False)
        step()
        return time.process_time() - t0, step

    probe, _s = cold_run(10)
    budget = float(p["cold_budget"])
    Bc = int(p["cold_batch"])
    while Bc > 10 and probe / 10 * Bc > budget:
        Bc //= 10
    colds = []
    for _ in range(max(1, min(3, p["rounds"]))):
        c, step = cold_run(Bc)
        colds.append(c)
        if sum(colds) > budget:
            break
    warm = time_interleaved({"warm": step}, rounds=p["rounds"], min_time=p["min_time"])["warm"]
    cold = {"median": float(np.median(colds)), "min": min(colds), "max": max(colds)}
    return {
        "n": 3,
        "h": h,
        "matmul": MATMULS,
        "stepper": name,
        "rows": rows,
        "cold_start": {
            "batch": Bc,
            "cold": cold,
            "warm": warm,
            "ratio": cold["median"] / warm["median"],
        },
    }


def _cost_vs_n(p: dict[str, Any], mods: dict[str, Any], log: Callable[[str], None]):
    h = 0.01
    fns: dict[str, Callable[[], Any]] = {}
    name = ""
    mv = _find(mods.get("engine"), ["mv_flow"])
    scale = {n: max(1, 400 // n**2) for n in p["cost_n"]}  # more steps where a step is cheap
    for n in p["cost_n"]:
        lam, Q0, M0 = _problem(n, p["seed"])
        if mv is not None:
            name = "symrb.engine.mv_flow (NumPy path), marginal cost of a step"
            for K in _MARGINAL_K:
                k = K * scale[n]
                fns[f"flow K={k} n={n}"] = _flow_thunk(mv, Q0, M0, lam, h, k, "numpy")
                if n == 3 and _backend() == "numba":
                    fns[f"numba K={k * 100} n=3"] = _flow_thunk(
                        mv, Q0, M0, lam, h, 100 * k, "numba"
                    )
        else:
            fns[f"step n={n}"], name = _stepper(lam, Q0, M0, h, mods)
        rng = np.random.default_rng(n)
        A1, A2 = rng.standard_normal((n, n)), rng.standard_normal((n, n))
        fns[f"matmul n={n}"] = _matmul_thunk(A1, A2, None)
    log(f"cost against n: {list(p['cost_n'])}")
    t = time_interleaved(fns, rounds=p["rounds"], min_time=p["min_time"])
    rows = []
    compiled = None
    for n in p["cost_n"]:
        tm = t[f"matmul n={n}"]
        if mv is not None:
            per = _marginal(t, f"flow K={{K}} n={n}", scale[n])
            step: dict[str, Any] = {
                "median": per,
                "how": "marginal: (t(K2) - t(K1)) / (K2 - K1)",
            }
        else:
            step = t[f"step n={n}"]
        rows.append(
            {
                "n": n,
                "step": step,
                "matmul": tm,
                "matmul_equivalents": step["median"] / tm["median"],
            }
        )
        if n == 3 and mv is not None and _backend() == "numba":
            per = _marginal(t, "numba K={K} n=3", 100 * scale[3])
            compiled = {"per_step": per, "matmul": tm, "matmul_equivalents": per / tm["median"]}
    return {"h": h, "stepper": name, "rows": rows, "compiled_n3": compiled}


_CERTIFIES = {
    "symbolic, general n": "an identity for every n (SymPy, noncommutative symbols)",
    "symbolic, fixed n": "an identity for the stated n (SymPy, explicit matrices)",
    "exact rational": "an identity on sample rational data (exact arithmetic)",
    "high precision": "agreement with an independent high-precision (mpmath) computation",
    "float64": "agreement to rounding with an independent route on random float data",
}


def _evidence(path: str | os.PathLike[str]) -> dict[str, Any]:
    data = json.loads(Path(path).read_text())
    levels: dict[str, dict[str, Any]] = {}
    for claim in data.get("claims", []):
        for e in claim.get("evidence", []):
            lv = str(e.get("level"))
            row = levels.setdefault(lv, {"checks": 0, "seconds": [], "claims": set(), "passed": 0})
            row["checks"] += 1
            row["seconds"].append(float(e.get("seconds") or 0.0))
            row["claims"].add(str(claim.get("id")))
            row["passed"] += str(e.get("passed")) == "True" or e.get("passed") is True
    out = {}
    for lv, row in sorted(levels.items(), key=lambda kv: -sum(kv[1]["seconds"])):
        s = row["seconds"]
        out[lv] = {
            "checks": row["checks"],
            "passed": int(row["passed"]),
            "claims": sorted(row["claims"]),
            "total_seconds": float(sum(s)),
            "median_seconds": float(np.median(s)),
            "max_seconds": float(max(s)),
            "certifies": _CERTIFIES.get(lv, "see symrb show ID"),
        }
    return {"source": Path(path).name, "levels": out, "timer": "as recorded by symrb verify"}
