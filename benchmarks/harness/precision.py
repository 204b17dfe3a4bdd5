"""Sections 1 and 2: work-precision diagrams and the long-time invariants of the Moser-Veselov
flow."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from symrb._progress import progress_bar
from symrb._validate import Array
from symrb.continuous import RigidBody, integrate
from symrb.paper import mv_algorithm2
from symrb.rigid_body import casimir_traces, kinetic_energy

from .config import _SCIPY, _STEP_ORDERS, EPS
from .problems import (
    _backend,
    _find,
    _fixed_step_runner,
    _last,
    _NotApplicable,
    _problem,
    _solve_ivp_end,
)
from .timing import _cost_at, fit_slope, time_interleaved

#: What the work-precision errors are measured against (``reference`` of each setting).
REFERENCE = (
    "Gragg-Bulirsch-Stoer extrapolation of order 10 in extended precision "
    "(derivations.reference.rigid_body_extrapolated), macro step 1/32"
)


def _errors(got: tuple[Array, Array], ref: tuple[Array, Array]) -> dict[str, float]:
    eQ = float(np.abs(got[0] - ref[0]).max())
    eM = float(np.abs(got[1] - ref[1]).max())
    return {"error_Q": eQ, "error_M": eM, "error": max(eQ, eM)}


def _reference(lam: Array, Q0: Array, M0: Array, T: float) -> tuple[tuple[Array, Array], float]:
    """(the reference (Q(T), M(T)), an estimate of its own error): Gragg-Bulirsch-Stoer
    extrapolation in extended precision (:func:`derivations.reference.rigid_body_extrapolated`,
    independent of symrb and of every method judged) of order 10 at macro step 1/32; the estimate
    is its largest difference from the same at macro step 1/16 and from order 8 at macro step
    1/64 (higher orders amplify rounding and are not used)."""
    from derivations.reference import rigid_body_extrapolated

    steps = max(1, round(16 * T))
    fine = rigid_body_extrapolated(Q0, M0, lam, T, 2 * steps, stages=5)
    others = (
        rigid_body_extrapolated(Q0, M0, lam, T, steps, stages=5),
        rigid_body_extrapolated(Q0, M0, lam, T, 4 * steps, stages=4),
    )
    est = max(
        float(np.abs(a - b).max()) for other in others for a, b in zip(other, fine, strict=True)
    )
    return (np.asarray(fine[0], dtype=float), np.asarray(fine[1], dtype=float)), est


def _exact_thunk(
    lam: Array, Q0: Array, M0: Array, T: float, mods: dict[str, Any]
) -> Callable[[], tuple[Array, Array]] | None:
    """The exact solution (n = 3) at T as a thunk, or None when it is not available."""
    exact = _find(mods.get("exact"), ["rigid_body_exact"])
    if exact is None or lam.shape[-1] != 3:
        return None

    def exact_go() -> tuple[Array, Array]:
        return _last(exact(Q0, M0, lam, np.array([T])), 3)

    return exact_go


def _configurations(
    lam: Array,
    Q0: Array,
    M0: Array,
    T: float,
    p: dict[str, Any],
    methods: Sequence[str],
    mods: dict[str, Any],
    exact_go: Callable[[], Any] | None,
    out: dict[str, Any],
) -> tuple[dict[str, Callable[[], Any]], dict[str, dict[str, Any]]]:
    """(the thunks timed, by key; what each is: method, rtol or h); a method that is not
    available is recorded in ``out["methods"]``."""
    n = lam.shape[-1]
    configs: dict[str, Callable[[], Any]] = {}
    meta: dict[str, dict[str, Any]] = {}
    for m in methods:
        if m in _SCIPY:
            for r in p["wp_rtols"]:
                configs[f"{m} rtol={r:.0e}"] = _solve_ivp_end(lam, Q0, M0, T, m, r)
                meta[f"{m} rtol={r:.0e}"] = {"method": m, "rtol": r}
        elif m == "integrate":
            for r in p["wp_rtols"]:

                def go(r: float = r) -> tuple[Array, Array]:
                    sol = integrate(
                        RigidBody, (0.0, T), {"Q": Q0, "M": M0}, lam=lam, rtol=r, atol=r
                    )
                    return _last(sol, n)

                configs[f"integrate rtol={r:.0e}"] = go
                meta[f"integrate rtol={r:.0e}"] = {"method": m, "rtol": r}
        elif m in _STEP_ORDERS:
            make = _fixed_step_runner(m, mods)
            if make is None:
                out["methods"][m] = {"available": False}
                continue
            for h in p["wp_h"].get(_STEP_ORDERS[m], ()):
                key = f"{m} h={h:g}"
                configs[key] = make(lam, Q0, M0, T, h)
                meta[key] = {"method": m, "h": T / max(1, round(T / h))}
        elif m == "exact":
            if exact_go is None:
                out["methods"][m] = {"available": False}
                continue
            configs["exact"] = exact_go
            meta["exact"] = {"method": m}
    return configs, meta


def _accuracy(
    configs: dict[str, Callable[[], Any]],
    meta: dict[str, dict[str, Any]],
    ref: tuple[Array, Array],
    out: dict[str, Any],
    notes: list[str],
) -> None:
    """Each configuration's error (its first call) in ``meta``; configurations that fail or do
    not apply are dropped from ``configs`` and recorded in ``out["methods"]``."""
    for key in list(configs):
        try:
            got = configs[key]()
        except _NotApplicable:
            del configs[key]
            out["methods"].setdefault(meta[key]["method"], {"available": False})
            continue
        except Exception as exc:  # noqa: BLE001
            notes.append(
                f"{key} (n = {out['n']}, T = {out['T']}) failed: {type(exc).__name__}: {exc}"
            )
            del configs[key]
            out["methods"].setdefault(meta[key]["method"], {"available": False})
            out["methods"][meta[key]["method"]].setdefault("failures", []).append(str(exc))
            continue
        meta[key].update(_errors(got, ref))


def _method_entry(m: str, rows: list[dict[str, Any]], out: dict[str, Any]) -> dict[str, Any]:
    """A method's points with its fitted order (fixed step) or error-against-work slope."""
    entry: dict[str, Any] = {"available": True, "points": rows}
    if m in _STEP_ORDERS:
        # fit where errors are well above rounding and the reference's own error
        floor = 100 * max(out["reference_error_estimate"], EPS)
        entry["nominal_order"] = _STEP_ORDERS[m]
        entry["order"] = fit_slope([r["h"] for r in rows], [r["error"] for r in rows], floor=floor)
    elif m != "exact":  # adaptive: error against work, err ~ cost^-slope
        entry["error_vs_cpu_slope"] = fit_slope(
            [r["cpu"]["median"] for r in rows], [r["error"] for r in rows], floor=1e-13
        )
    return entry


def _work_precision(
    n: int,
    T: float,
    p: dict[str, Any],
    methods: Sequence[str],
    mods: dict[str, Any],
    notes: list[str],
    log: Callable[[str], None],
) -> dict[str, Any]:
    """One work-precision diagram: every configuration's error and CPU time."""
    lam, Q0, M0 = _problem(n, p["seed"])
    ref, estimate = _reference(lam, Q0, M0, T)
    out: dict[str, Any] = {
        "n": n,
        "T": T,
        "lam": lam.tolist(),
        "reference": REFERENCE,
        "reference_error_estimate": estimate,
        # the same problem solved by SciPy: agreement to DOP853's own error
        "reference_vs_dop853": _errors(_solve_ivp_end(lam, Q0, M0, T, "DOP853", 1e-13)(), ref)[
            "error"
        ],
        "backend": _backend(),
        "methods": {},
    }
    exact_go = _exact_thunk(lam, Q0, M0, T, mods)
    configs, meta = _configurations(lam, Q0, M0, T, p, methods, mods, exact_go, out)
    _accuracy(configs, meta, ref, out, notes)
    log(f"work-precision n = {n}, T = {T:g}: timing {len(configs)} configurations")
    timing = time_interleaved(configs, rounds=p["rounds"], min_time=p["min_time"])
    for key, t in timing.items():
        meta[key]["cpu"] = t
    for m in methods:
        rows = [meta[k] for k in configs if meta[k]["method"] == m]
        if not rows:
            out["methods"].setdefault(m, {"available": False})
            continue
        out["methods"][m] = _method_entry(m, rows, out)
    return out


def _cost_table(wp: dict[str, Any], target: float) -> dict[str, dict[str, Any]]:
    table = {}
    for m, entry in wp["methods"].items():
        if not entry.get("available") or m == "exact":
            continue
        pts = entry["points"]
        cost, how = _cost_at(
            [r["error"] for r in pts], [r["cpu"]["median"] for r in pts], target, entry.get("order")
        )
        table[m] = {"cpu": cost, "how": how}
    return table


def _mv_flow_function(mods: dict[str, Any]) -> tuple[Callable[..., Any], str, bool]:
    """(flow(Q, M, lam, h, steps, save_every), name, takes continuous momenta)."""
    fast = _find(mods.get("engine"), ["mv_flow"])
    if fast is not None:
        return fast, "symrb.engine.mv_flow", True

    def slow(Q: Array, M: Array, lam: Array, _h: float, steps: int, *, save_every: int) -> Any:
        return mv_algorithm2(Q, M, lam, steps, save_every=save_every)

    return slow, "symrb.mv_algorithm2", False


def _long_time(
    n: int, p: dict[str, Any], mods: dict[str, Any], progress: bool, log: Callable[[str], None]
) -> dict[str, Any]:
    flow, name, continuous = _mv_flow_function(mods)
    lam, Q, M0 = _problem(n, p["seed"] + 1)
    h, total = float(p["long_h"]), int(p["long_steps"])
    M = M0.copy() if continuous else h * M0
    H0 = float(kinetic_energy(M, lam))
    C0 = float(casimir_traces(M)[0])
    marks = np.unique(np.round(np.logspace(0, math.log10(total), 8 * int(math.log10(total)) + 1)))
    marks = marks.astype(np.int64)
    Ns: list[int] = []
    energy: list[float] = []
    casimir: list[float] = []
    orth: list[float] = []
    run_max = [0.0, 0.0, 0.0]
    done = 0
    cpu = 0.0
    log(f"long-time n = {n}: {total} steps of {name}")
    bar = progress_bar(total, f"long run n={n}", progress)
    try:
        for mark in marks:
            chunk = int(mark) - done
            if chunk <= 0:
                continue
            every = max(1, chunk // 16)
            t0 = time.process_time()
            sol = flow(Q, M, lam, h, chunk, save_every=every)
            cpu += time.process_time() - t0
            if not sol.success:
                raise RuntimeError(f"the long run stopped at step {done}: {sol.message}")
            Qs = np.asarray(sol.y["Q"])[1:]
            Ms = np.asarray(sol.y["M"])[1:]
            eH = np.abs(kinetic_energy(Ms, lam) - H0) / abs(H0)
            eC = np.abs(casimir_traces(Ms)[..., 0] - C0) / abs(C0)
            eO = np.abs(np.swapaxes(Qs, -1, -2) @ Qs - np.eye(n)).max(axis=(-2, -1))
            run_max = [
                max(run_max[0], eH.max()),
                max(run_max[1], eC.max()),
                max(run_max[2], eO.max()),
            ]
            done = int(mark)
            Ns.append(done)
            energy.append(float(run_max[0]))
            casimir.append(float(run_max[1]))
            orth.append(float(run_max[2]))
            Q, M = Qs[-1], Ms[-1]
            if bar.bar is not None:
                bar.bar.update(chunk)
    finally:
        bar.close()
    Na = np.asarray(Ns, dtype=float)
    series = {"energy": energy, "casimir": casimir, "orthogonality": orth}
    fit_from = Na >= min(100.0, Na[-1] / 10)
    out: dict[str, Any] = {
        "n": n,
        "h": h,
        "steps": total,
        "flow": name,
        "cpu_seconds": cpu,
        "cpu_per_step": cpu / total,
        "N": Ns,
        "errors": series,
        "eps_sqrt_N": (EPS * np.sqrt(Na)).tolist(),
        "slope": {},
        "max_ratio_to_eps_sqrt_N": {},
    }
    for key, vals in series.items():
        va = np.asarray(vals)
        out["slope"][key] = fit_slope(Na[fit_from], va[fit_from], floor=0.0)
        out["max_ratio_to_eps_sqrt_N"][key] = float(np.max(va / (EPS * np.sqrt(Na))))
    return out
