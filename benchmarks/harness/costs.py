"""Sections 6 to 8 (issue 23): the cost of a step and of a call where users pay it, the
invariants over a long horizon at n = 10, and the cold start of the compiled path.

* **step-costs**: one whole ``mv_flow`` call of one step (n = 3, validation included); the
  marginal cost of a step of ``mv_flow`` (default method), ``mv_algorithm2`` and
  ``symmetric_flow`` (n = 3); the cost per stage of the compositions, RKMK4 and the implicit
  midpoint rule against an ``mv_flow`` step (n = 3 and 10); one compiled step at n = 10 against
  its flop count at this machine's flop rate.
* **long-horizon**: n = 10 to T (1e4 in a full run): the largest relative energy and Casimir errors
  of DOP853 (lean field) at several tolerances and of symrb's methods at a few steps, with their
  CPU times (one run each, a budget per run).
* **cold-start**: new processes that import symrb and make one compiled n = 3 ``mv_flow`` call;
  the first primes numba's cache, the others are timed.

Marginal costs: two runs of K1 < K2 steps, timed interleaved; (t(K2) - t(K1)) / (K2 - K1).  K2
is picked from a probe so that a run lasts about ``marginal_time`` CPU seconds.  Each figure a
goal reads comes with a short profile (the top entries by cumulative time of one call, cProfile)
so that a goal not met says what limits it.
"""

from __future__ import annotations

import cProfile
import math
import os
import pstats
import resource
import subprocess
import sys
import time
from collections.abc import Callable, Iterable
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

from symrb import _compiled, _compiled_n, compose, paper
from symrb._validate import Array
from symrb.rigid_body import casimir_traces, kinetic_energy

from .problems import LEAN_VARIANTS, _find, _pick_lean, _problem, _step_flow, _to_lean
from .timing import time_interleaved

_H = 0.01


def profile_text(fn: Callable[[], Any], top: int = 4) -> str:
    """The ``top`` entries by cumulative time of one call of ``fn`` (cProfile), as one line."""
    pr = cProfile.Profile()
    pr.enable()
    try:
        fn()
    finally:
        pr.disable()
    stats = pstats.Stats(pr).stats  # type: ignore[attr-defined]
    here = str(Path(__file__).parent)
    rows = []
    for (file, line, func), (_cc, nc, _tt, ct, _callers) in stats.items():
        if file.startswith(here) or func in ("<lambda>", "disable") or file == "~":
            continue
        rows.append((ct, f"{func} ({Path(file).name}:{line}) {ct * 1e3:.3g} ms, {nc} calls"))
    rows.sort(key=lambda r: -r[0])
    return "; ".join(r[1] for r in rows[:top])


def _probe(make: Callable[[int], Callable[[], Any]], target: float, k_min: int = 1) -> float:
    """A rough CPU time per step, only used to pick run lengths: runs of 16, 128, ... steps (at
    least ``k_min``; each once, after a warm-up) until one lasts a quarter of ``target``; the
    difference of the last two over their difference in steps, or the last one's mean cost per
    step when that difference is lost in the noise (not positive)."""
    k, prev = max(16, int(k_min)), None
    while True:
        fn = make(k)
        fn()
        t0 = time.process_time()
        fn()
        t = time.process_time() - t0
        if prev is not None and (t >= target / 4 or k >= 10**6):
            diff = (t - prev[1]) / (k - prev[0])
            return diff if diff > 0 else max(t / k, 1e-10)
        prev = (k, t)
        k *= 8


def marginal_costs(
    makes: dict[str, Callable[[int], Callable[[], Any]]],
    p: dict[str, Any],
    k_min: dict[str, int] | None = None,
) -> dict[str, dict[str, Any]]:
    """The marginal CPU cost of a step of each run ``makes[name](K)``: ``per_step``, ``K``
    (K1, K2; K2 from a probe so that a run lasts about ``marginal_time``), ``reliable`` (the
    difference of the two runs exceeds the spread of either over the rounds).  ``k_min[name]``:
    the fewest steps of a run of that name (a flow that changes its backend with the run's
    length, e.g. compiled from a threshold on, is timed above the threshold only)."""
    target = float(p["marginal_time"])
    lo = {name: max(1, int((k_min or {}).get(name, 1))) for name in makes}
    per = {name: _probe(make, target, lo[name]) for name, make in makes.items()}
    k2 = {
        name: int(min(max(24, 6 * lo[name], math.ceil(target / c)), 10**7))
        for name, c in per.items()
    }
    fns = {}
    for name, make in makes.items():
        fns[f"{name} K1"] = make(max(lo[name], k2[name] // 6))
        fns[f"{name} K2"] = make(k2[name])
    t = time_interleaved(fns, rounds=p["rounds"], min_time=p["min_time"])
    out = {}
    for name in makes:
        k1 = max(lo[name], k2[name] // 6)
        a, b = t[f"{name} K1"], t[f"{name} K2"]
        # reliable: the difference of the two runs exceeds the spread of either over the rounds
        spread = max(a["max"] - a["min"], b["max"] - b["min"])
        out[name] = {"per_step": (b["median"] - a["median"]) / (k2[name] - k1),
                     "K": [k1, k2[name]], "run_K2": b,
                     "reliable": bool(b["median"] - a["median"] > spread)}  # fmt: skip
    return out


def mv_long_run_method(mv: Callable[..., Any], lam: Array, Q0: Array, M0: Array) -> str:
    """The method ``mv_flow`` uses for a long run at this n, pinned so that the two runs of a
    marginal cost never straddle its automatic switch: ``"numba"`` when numba is installed and
    ``mv_flow`` accepts it at this n, else ``"numpy"`` (n = 3) or ``"auto"``."""
    n = lam.shape[-1]
    if _compiled.AVAILABLE:
        try:
            mv(Q0, M0, lam, _H, 2, method="numba")
            return "numba"
        except Exception:  # noqa: BLE001 - not accepted at this n
            pass
    return "numpy" if n == 3 else "auto"


def _paper_makes(mods: dict[str, Any]) -> dict[str, Callable[[int], Callable[[], Any]]]:
    """n = 3 runs of K steps of mv_flow (the method of its long runs, pinned:
    :func:`mv_long_run_method`), mv_algorithm2 (discrete momentum h M0, the paper's h = 1
    convention) and symmetric_flow (P0 = Q0 M0 / 2)."""
    lam, Q0, M0 = _problem(3, 0)
    makes: dict[str, Callable[[int], Callable[[], Any]]] = {}
    mv = _find(mods.get("engine"), ["mv_flow"])
    if mv is not None:
        how = mv_long_run_method(mv, lam, Q0, M0)
        makes["mv_flow"] = lambda K: lambda: mv(Q0, M0, lam, _H, K, save_every=K, method=how)
    Md, P0 = _H * M0, Q0 @ (M0 / 2)
    makes["mv_algorithm2"] = lambda K: lambda: paper.mv_algorithm2(Q0, Md, lam, K, save_every=K)
    makes["symmetric_flow"] = lambda K: (
        lambda: paper.symmetric_flow(Q0, P0, lam, _H, K, save_every=K)
    )
    return makes


def _run_of(flow: Callable[..., Any], Q0: Array, M0: Array, lam: Array, K: int):
    """A thunk: ``flow`` for K steps of h = 0.01, keeping the last state only."""
    return lambda: flow(Q0, M0, lam, _H, K, save_every=K)


def _stages(kind: str) -> int:
    """The MV (or base) steps of one step of ``kind``: the composition's coefficients, 4 for
    RKMK4, 1 for the midpoint rule."""
    if kind.startswith("MV-comp"):
        from symrb.composition import composition_coefficients

        return len(composition_coefficients(int(kind[len("MV-comp") :])))
    return 4 if kind == "RKMK4" else 1


def _compiled_from(n: int, kinds: Iterable[str]) -> dict[str, int]:
    """The fewest steps (one body) from which each flow of ``kinds`` runs its compiled loop with
    method "auto" (numba installed): the thresholds of symrb.compose and symrb._compiled, so a
    marginal cost never mixes the NumPy and the compiled path."""
    if not (_compiled.AVAILABLE and _compiled_n.AVAILABLE):
        return {}
    out = {}
    for kind in kinds:
        if kind.startswith("MV-comp"):
            work = _compiled.MIN_WORK if n == 3 else compose._NUMBA_MIN_WORK_N / n**3
            out[kind] = math.ceil(work / _stages(kind))
        elif kind in ("RKMK4", "midpoint"):
            out[kind] = compose._NUMBA_MIN_STEPS
    return out


def _stage_costs(n: int, p: dict[str, Any], mods: dict[str, Any]) -> dict[str, Any]:
    """The cost per stage of the compositions, RKMK4 and midpoint against an mv_flow step."""
    lam, Q0, M0 = _problem(n, p["seed"])
    mv = _find(mods.get("engine"), ["mv_flow"])
    makes: dict[str, Callable[[int], Callable[[], Any]]] = {}
    how = None
    if mv is not None:
        how = mv_long_run_method(mv, lam, Q0, M0)
        makes["mv_flow"] = lambda K: lambda: mv(Q0, M0, lam, _H, K, save_every=K, method=how)
    missing = []
    for kind in ("MV-comp4", "MV-comp6", "MV-comp8", "RKMK4", "midpoint"):
        flow = _step_flow(kind, mods)
        if flow is None:
            missing.append(kind)
            continue
        makes[kind] = partial(_run_of, flow, Q0, M0, lam)
    got = marginal_costs(makes, p, _compiled_from(n, makes))
    out: dict[str, Any] = {"n": n, "h": _H, "unavailable": missing, "methods": {},
                           "mv_flow_method": how}  # fmt: skip
    base = got.get("mv_flow", {}).get("per_step")
    out["mv_flow_per_step"] = base
    for kind in makes:
        if kind == "mv_flow":
            continue
        st = _stages(kind)
        per = got[kind]["per_step"]
        out["methods"][kind] = {
            "per_step": per,
            "stages": st,
            "per_stage": per / st,
            "over_mv_flow_step": None if not base else per / st / base,
            "reliable": got[kind]["reliable"] and got.get("mv_flow", {}).get("reliable", False),
            "K": got[kind]["K"],
            "profile": profile_text(makes[kind](50)),
        }
    return out


def mv_step_flops(n: int, iterations: float) -> float:
    r"""Flops of one Moser-Veselov step by the fixed point of ``symrb.engine`` at size n with
    ``iterations`` sweeps: each sweep two n x n products (:math:`BX`, :math:`X(BX)`, 4n^3) and
    about 12 n^2 entrywise operations; then the Cayley increment :math:`2(I - X)^{-1}X` (LU
    :math:`\tfrac23 n^3` and n solves, :math:`2n^3`), :math:`Q + QD` (:math:`2n^3`) and
    :math:`U^TMU` (:math:`4n^3`), and about 6 n^2 more.

    Examples
    --------
    >>> from benchmarks.harness.costs import mv_step_flops
    >>> round(mv_step_flops(10, 8))
    50867
    """
    n3, n2 = float(n) ** 3, float(n) ** 2
    return iterations * (4 * n3 + 12 * n2) + (2 / 3 + 2 + 2 + 4) * n3 + 6 * n2


def _n10_compiled(p: dict[str, Any], mods: dict[str, Any]) -> dict[str, Any]:
    """One compiled step at n = 10 (``mv_flow(method="numba")``) against its flop count at this
    machine's flop rate (a batch of 1000 10x10 products, ``np.matmul`` with ``out``)."""
    n = 10
    lam, Q0, M0 = _problem(n, p["seed"])
    mv = _find(mods.get("engine"), ["mv_flow"])
    out: dict[str, Any] = {"n": n, "available": False}
    if mv is None or not _compiled.AVAILABLE:
        out["why"] = "numba not installed" if mv is not None else "symrb.engine missing"
        return out
    try:
        sol = mv(Q0, M0, lam, _H, 200, save_every=200, method="numba")
    except Exception as exc:  # noqa: BLE001 - not accepted at n = 10: unavailable
        out["why"] = f"mv_flow(method='numba') at n = 10: {type(exc).__name__}: {exc}"
        return out
    its = np.asarray(getattr(sol, "iterations", []), dtype=float)
    iters = float(its.sum() / 200) if its.size else 0.0
    source = "mv_flow(method='numba')"
    if not iters > 0:  # the compiled run reports no sweeps: count those of the NumPy fixed point
        ref = mv(Q0, M0, lam, _H, 200, save_every=200, method="fixed-point")
        iters = float(np.sum(ref.iterations) / 200)
        source = "mv_flow(method='fixed-point'), the compiled run reporting none"
    got = marginal_costs({"numba": lambda K: lambda: mv(Q0, M0, lam, _H, K, save_every=K,
                                                        method="numba")}, p)  # fmt: skip
    rng = np.random.default_rng(1)
    A1, A2 = rng.standard_normal((2, 1000, n, n))
    C = np.empty_like(A1)
    t = time_interleaved(
        {"batched": lambda: np.matmul(A1, A2, out=C), "one": lambda: A1[0] @ A2[0]},
        rounds=p["rounds"], min_time=p["min_time"],
    )  # fmt: skip
    rate = 1000 * 2 * n**3 / t["batched"]["median"]
    flops = mv_step_flops(n, iters)
    per = got["numba"]["per_step"]
    out.update(
        available=True,
        per_step=per,
        iterations_per_step=iters,
        iterations_from=source,
        flops=flops,
        flop_rate=rate,
        matmul_one=t["one"]["median"],
        flop_time=flops / rate,
        ratio=per / (flops / rate),
        profile=profile_text(lambda: mv(Q0, M0, lam, _H, 2000, save_every=2000, method="numba")),
    )
    return out


def _step_costs(p: dict[str, Any], mods: dict[str, Any], log: Callable[[str], None]):
    log("step costs: one mv_flow call, the paper's maps, stages, n = 10 compiled step")
    out: dict[str, Any] = {"h": _H}
    mv = _find(mods.get("engine"), ["mv_flow"])
    if mv is not None:
        lam, Q0, M0 = _problem(3, 0)
        one = lambda: mv(Q0, M0, lam, _H, 1)  # noqa: E731
        t = time_interleaved({"one": one}, rounds=p["rounds"], min_time=p["min_time"])
        out["one_call"] = {
            "cpu": t["one"],
            "profile": profile_text(one),
            "what": "mv_flow(Q0, M0, lam, 0.01, 1), n = 3, default method",
        }
    makes = _paper_makes(mods)
    # each at run lengths long enough for its own marginal cost, and the paper's maps (which run
    # mv_flow with its default method) from the length where mv_flow compiles its loop on, as
    # mv_flow itself is timed on its compiled loop; beside it, whole runs of the same length (the
    # paper map's longer run) for all three
    long = {name: _compiled.MIN_WORK for name in makes if name != "mv_flow"}
    got = marginal_costs(makes, p, long if _compiled.AVAILABLE else None)
    out["paper"] = {
        name: dict(g, profile=profile_text(makes[name](200))) for name, g in got.items()
    }
    K = got["mv_algorithm2"]["K"][1]
    same = time_interleaved({k: make(K) for k, make in makes.items()}, rounds=p["rounds"],
                            min_time=p["min_time"])  # fmt: skip
    out["paper_same_length"] = {"K": K, **{k: v["median"] for k, v in same.items()}}
    if mv is not None:
        lam3, Q3, M3 = _problem(3, 0)
        out["paper"]["mv_flow"]["method"] = mv_long_run_method(mv, lam3, Q3, M3)
    out["stages"] = {str(n): _stage_costs(n, p, mods) for n in p["stage_n"]}
    out["n10_compiled"] = _n10_compiled(p, mods)
    return out


def _invariant_errors(Ms: Array, lam: Array, M0: Array) -> tuple[float, float]:
    """The largest relative errors of the energy and of the Casimirs over the states ``Ms``."""
    H0 = float(kinetic_energy(M0, lam))
    C0 = casimir_traces(M0)
    eH = float(np.max(np.abs(kinetic_energy(Ms, lam) - H0)) / abs(H0))
    eC = float(np.max(np.abs(casimir_traces(Ms) - C0) / np.abs(C0)))
    return eH, eC


def _timed(fn: Callable[[], Any]) -> tuple[Any, float]:
    t0 = time.process_time()
    got = fn()
    return got, time.process_time() - t0


def _lh_dop853(lam: Array, Q0: Array, M0: Array, T: float, rtol: float, lean: str):
    n = lam.shape[-1]
    y0 = _to_lean(Q0, M0, lean)
    f = LEAN_VARIANTS[lean](lam)

    def go() -> Array:
        sol = solve_ivp(f, (0.0, T), y0, method="DOP853", rtol=rtol, atol=rtol,
                        t_eval=np.linspace(0.0, T, 101))  # fmt: skip
        return sol.y[n * n :].T.reshape(-1, n, n)

    return go


def _lh_symrb(flow: Callable[..., Any], lam: Array, Q0: Array, M0: Array, T: float, h: float):
    steps = max(1, round(T / h))

    def go(frac: int = 1) -> Array:
        k = max(1, steps // frac)
        sol = flow(Q0, M0, lam, T / steps, k, save_every=max(1, k // 100))
        if getattr(sol, "success", True) is False:
            raise RuntimeError(str(sol.message))
        return np.asarray(sol.y["M"]).reshape(-1, lam.shape[-1], lam.shape[-1])

    return go, steps


def _long_horizon(p: dict[str, Any], mods: dict[str, Any], log: Callable[[str], None]):
    """n = 10 to T: invariant errors and CPU time of DOP853 at each rtol and of symrb's runs."""
    n, T, budget = 10, float(p["lh_T"]), float(p["lh_budget"])
    lam, Q0, M0 = _problem(n, p["seed"])
    lean = _pick_lean(lam, Q0, M0)["variant"]
    log(f"long horizon n = {n}, T = {T:g}")
    runs: list[dict[str, Any]] = []
    for rtol in p["lh_rtols"]:
        probe, c = _timed(_lh_dop853(lam, Q0, M0, T / 100, rtol, lean))
        if 100 * c > budget:
            runs.append({"method": "DOP853", "rtol": rtol, "skipped": f"about {100 * c:.0f} s"})
            continue
        Ms, cpu = _timed(_lh_dop853(lam, Q0, M0, T, rtol, lean))
        eH, eC = _invariant_errors(Ms, lam, M0)
        runs.append({"method": "DOP853", "rtol": rtol, "cpu": cpu, "energy": eH, "casimir": eC})
    for kind, h in p["lh_symrb"]:
        flow = _step_flow(kind, mods)
        if flow is None:
            runs.append({"method": kind, "h": h, "skipped": "not available"})
            continue
        go, steps = _lh_symrb(flow, lam, Q0, M0, T, h)
        try:
            _probe_M, c = _timed(partial(go, 100))
            if 100 * c > budget:
                runs.append({"method": kind, "h": h, "skipped": f"about {100 * c:.0f} s"})
                continue
            Ms, cpu = _timed(go)
        except Exception as exc:  # noqa: BLE001 - a failed run is recorded, not fatal
            runs.append({"method": kind, "h": h, "skipped": f"{type(exc).__name__}: {exc}"})
            continue
        eH, eC = _invariant_errors(Ms, lam, M0)
        runs.append({"method": kind, "h": T / steps, "steps": steps, "cpu": cpu, "energy": eH,
                     "casimir": eC, "profile": profile_text(partial(go, 100))})  # fmt: skip
    return {"n": n, "T": T, "lean_field": lean, "budget_per_run": budget, "runs": runs,
            "timer": "process CPU time of one run"}  # fmt: skip


_COLD = (
    "import numpy as np\n"
    "import symrb\n"
    "from symrb.engine import mv_flow\n"
    "mv_flow(np.eye(3), symrb.hat([0.5, 1.0, 1.5]), np.array([0.7, 1.1, 1.6]), 0.01, 100,"
    " method='numba')\n"  # (steps 2.. are the compiled loop's: one step would not load it)
)


def _cold_start(p: dict[str, Any], log: Callable[[str], None]) -> dict[str, Any]:
    """New processes running :data:`_COLD`: child CPU time and wall time of each."""
    if not _compiled.AVAILABLE:
        return {"available": False, "why": "numba not installed"}
    log("cold start: new processes")
    import symrb

    root = str(Path(symrb.__file__).resolve().parent.parent)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([root, os.environ.get("PYTHONPATH", "")]))
    cpu, wall = [], []
    for _ in range(int(p["cold_processes"])):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", _COLD], check=True, env=env, capture_output=True)
        wall.append(time.perf_counter() - t0)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu.append(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)
    return {
        "available": True,
        "code": _COLD,
        "first": {"cpu": cpu[0], "wall": wall[0]},
        "cpu": cpu[1:],
        "wall": wall[1:],
        "median_cpu": float(np.median(cpu[1:])),
        "median_wall": float(np.median(wall[1:])),
    }
