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
from symrb.paper import mv_algorithm2, symmetric_flow
from symrb.rigid_body import casimir_traces, kinetic_energy

from .config import _SCIPY, _SCIPY_GEN, _STEP_ORDERS, EPS
from .costs import profile_text
from .problems import (
    GEN_SUFFIX,
    _backend,
    _find,
    _fixed_step_runner,
    _last,
    _NotApplicable,
    _pick_lean,
    _problem,
    _solve_ivp_end,
)
from .timing import cheapest_measured, fit_slope, time_interleaved

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
    available is recorded in ``out["methods"]``.  SciPy's methods run on the lean field named
    in ``out["baselines"]["variant"]``, their ``-gen`` twins on the generated field."""
    n = lam.shape[-1]
    configs: dict[str, Callable[[], Any]] = {}
    meta: dict[str, dict[str, Any]] = {}
    lean = out["baselines"]["variant"]
    for m in methods:
        if m in _SCIPY or m in _SCIPY_GEN:
            base, field = (m[: -len(GEN_SUFFIX)], None) if m in _SCIPY_GEN else (m, lean)
            for r in p["wp_rtols"]:
                configs[f"{m} rtol={r:.0e}"] = _solve_ivp_end(lam, Q0, M0, T, base, r, field)
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
        # fit where errors are well above the reference's own error and the rounding of the run:
        # N = T/h steps leave about eps sqrt(N) (a random walk, Brouwer's law)
        ref_err, T = out["reference_error_estimate"], out["T"]
        fit = [r for r in rows if r["error"] > 100 * max(ref_err, EPS * math.sqrt(T / r["h"]))]
        entry["nominal_order"] = _STEP_ORDERS[m]
        entry["order"] = fit_slope([r["h"] for r in fit], [r["error"] for r in fit])
        entry["order_fit_h"] = [r["h"] for r in fit]
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
        "baselines": _pick_lean(lam, Q0, M0),
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
        keys = [k for k in configs if meta[k]["method"] == m]
        if not keys:
            out["methods"].setdefault(m, {"available": False})
            continue
        out["methods"][m] = _method_entry(m, [meta[k] for k in keys], out)
        # what limits its cheapest run (for the note of a goal not met)
        cheapest = min(keys, key=lambda k: meta[k]["cpu"]["median"])
        out["methods"][m]["profile"] = profile_text(configs[cheapest])
    return out


def _cost_table(wp: dict[str, Any], target: float) -> dict[str, dict[str, Any]]:
    """For each method of a work-precision setting: its cheapest measured run whose error is at
    most ``target`` (``cpu`` None and ``point`` None when no measured run reaches it)."""
    table: dict[str, dict[str, Any]] = {}
    for m, entry in wp["methods"].items():
        if not entry.get("available") or m == "exact":
            continue
        pt = cheapest_measured(entry["points"], target)
        table[m] = {"cpu": None if pt is None else pt["cpu"]["median"], "point": pt}
    return table


#: The flows of the long-time section: mv_flow for every n, the paper's maps for n = 3.
LONG_FLOWS = ("mv_flow", "mv_algorithm2", "symmetric_flow")


def _long_flow(
    which: str, mods: dict[str, Any]
) -> tuple[str, Callable[..., Any], Callable[..., Any]]:
    """(name, start(Q0, M0, h) -> state, run(state, lam, h, chunk, every) -> (Qs, Ms, state)):
    ``mv_flow`` (symrb.paper.mv_algorithm2 when the engine is missing), ``mv_algorithm2``
    (discrete momentum h M), ``symmetric_flow`` (P0 = Q0 M0 / 2; M = Q^T P - P^T Q)."""
    fast = _find(mods.get("engine"), ["mv_flow"])
    if which == "symmetric_flow":

        def run_s(st: Any, lam: Array, h: float, chunk: int, every: int) -> Any:
            sol = symmetric_flow(st[0], st[1], lam, h, chunk, save_every=every)
            _ok(sol)
            Qs, Ps = np.asarray(sol.y["Q"])[1:], np.asarray(sol.y["P"])[1:]
            Ms = np.swapaxes(Qs, -1, -2) @ Ps - np.swapaxes(Ps, -1, -2) @ Qs
            return Qs, Ms, (Qs[-1], Ps[-1])

        return "symrb.paper.symmetric_flow", lambda Q, M, h: (Q, Q @ (M / 2)), run_s
    if which == "mv_flow" and fast is not None:

        def run_f(st: Any, lam: Array, h: float, chunk: int, every: int) -> Any:
            sol = fast(st[0], st[1], lam, h, chunk, save_every=every)
            _ok(sol)
            Qs, Ms = np.asarray(sol.y["Q"])[1:], np.asarray(sol.y["M"])[1:]
            return Qs, Ms, (Qs[-1], Ms[-1])

        return "symrb.engine.mv_flow", lambda Q, M, h: (Q, M), run_f

    def run_a(st: Any, lam: Array, h: float, chunk: int, every: int) -> Any:
        sol = mv_algorithm2(st[0], st[1], lam, chunk, save_every=every)
        _ok(sol)
        Qs, Ms = np.asarray(sol.y["Q"])[1:], np.asarray(sol.y["M"])[1:]
        return Qs, Ms, (Qs[-1], Ms[-1])

    return "symrb.paper.mv_algorithm2", lambda Q, M, h: (Q, h * M), run_a


def _ok(sol: Any) -> None:
    if not sol.success:
        raise RuntimeError(f"the long run stopped: {sol.message}")


def _long_time(
    n: int,
    p: dict[str, Any],
    mods: dict[str, Any],
    progress: bool,
    log: Callable[[str], None],
    which: str = "mv_flow",
) -> dict[str, Any]:
    """Up to ``long_steps`` steps of the flow ``which`` (:data:`LONG_FLOWS`) in chunks, the
    running maxima of the invariants' errors; stops early (``stopped``) when the next chunk
    would pass ``long_budget`` CPU seconds."""
    name, start, run = _long_flow(which, mods)
    lam, Q, M0 = _problem(n, p["seed"] + 1)
    h, total = float(p["long_h"]), int(p["long_steps"])
    state = start(Q, M0.copy(), h)
    M = h * M0 if name.endswith("mv_algorithm2") else M0  # the scale of the flow's momenta
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
    stopped = ""
    log(f"long-time n = {n}: {total} steps of {name}")
    bar = progress_bar(total, f"long run n={n}", progress)
    try:
        for mark in marks:
            chunk = int(mark) - done
            if chunk <= 0:
                continue
            if done >= 100 and cpu + chunk * cpu / done > float(p["long_budget"]):
                stopped = f"stopped at {done} steps: the next chunk would pass the CPU budget"
                break
            every = max(1, chunk // 16)
            t0 = time.process_time()
            Qs, Ms, state = run(state, lam, h, chunk, every)
            cpu += time.process_time() - t0
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
        "steps": done,
        "steps_asked": total,
        "stopped": stopped,
        "flow": name,
        "flow_key": which,
        "cpu_seconds": cpu,
        "cpu_per_step": cpu / max(done, 1),
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
