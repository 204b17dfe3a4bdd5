"""Cost of one Moser-Veselov step of symrb.engine against matrix products timed in the same run.

Ratios (each the median over interleaved repeats, ``time.perf_counter``, BLAS pinned to one
thread with threadpoolctl):

* single body, n = 3, 10, 50: one step of ``mv_flow`` (time of a run / steps) over one
  ``A @ B`` of two n x n arrays (goals: n = 3 <= 3; n = 50 <= 100);
* a batch of 10^4 bodies, n = 3: body-steps/s, and the step time over one batched 3x3 matmul
  ``(10^4, 3, 3) @ (10^4, 3, 3)`` (goals: >= 5e6 body-steps/s and <= 3);
* the cold start (first step, from X0 = (h/2) J^-1(M)) over a warm step of the same batch
  (goal <= 10);
* the long run (``--drift-steps``, default 10^5) of one body, n = 3: relative energy, Casimir
  |m|^2 and orthogonality errors at 10^3, 10^4, 10^5 steps, and the growth exponent between the
  last two (1 = linear drift, 0.5 = random walk).

Usage::

    python benchmarks/step_cost.py [--repeats 7] [--drift-steps 100000] [--profile]

Writes ``benchmarks/results/step_cost.json`` and prints the ratios.  ``--profile`` adds a
cProfile of the single-body n = 3 loop and the batch step (the top entries by own time).
"""

from __future__ import annotations

import argparse
import cProfile
import io
import json
import platform
import pstats
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

import symrb
from symrb import _compiled
from symrb.engine import MVStepper, mv_flow


def _case(n: int, batch: tuple[int, ...] = (), seed: int = 0) -> tuple[np.ndarray, ...]:
    rng = np.random.default_rng(seed)
    lam = rng.uniform(0.5, 2.0, n)
    A = rng.normal(size=batch + (n, n))
    M0 = (A - np.swapaxes(A, -1, -2)) / np.sqrt(n)
    Q0 = np.broadcast_to(np.eye(n), batch + (n, n)).copy()
    return Q0, M0, lam


def _interleaved(fns: dict[str, Callable[[], float]], repeats: int) -> dict[str, float]:
    """Median seconds per unit of each function, repeats interleaved."""
    times: dict[str, list[float]] = {k: [] for k in fns}
    for _ in range(repeats):
        for k, f in fns.items():
            times[k].append(f())
    return {k: float(np.median(v)) for k, v in times.items()}


def _per_call(f: Callable[[], object], number: int) -> Callable[[], float]:
    def run() -> float:
        t = time.perf_counter()
        for _ in range(number):
            f()
        return (time.perf_counter() - t) / number

    return run


def _run(Q0: np.ndarray, M0: np.ndarray, lam: np.ndarray, h: float, method: str) -> Callable:
    def per_step(steps: int) -> float:
        t = time.perf_counter()
        mv_flow(Q0, M0, lam, h, steps, save_every=steps, method=method)
        return time.perf_counter() - t

    return per_step


def single_body(n: int, h: float, repeats: int) -> dict[str, float]:
    Q0, M0, lam = _case(n)
    steps = {3: 4000, 10: 400, 50: 60}[n]
    A, B = np.random.default_rng(1).normal(size=(2, n, n))
    fns: dict[str, Callable[[], float]] = {}
    methods = ["numpy"] + (["numba"] if n == 3 and _compiled.AVAILABLE else [])
    if n != 3:
        methods = ["auto"]
    for meth in methods:
        run = _run(Q0, M0, lam, h, meth)
        run(steps)  # warm up (numba compiles)
        fns[meth] = lambda run=run: run(steps) / steps  # type: ignore[misc]
    fns["matmul"] = _per_call(lambda: A @ B, {3: 20000, 10: 20000, 50: 2000}[n])
    med = _interleaved(fns, repeats)
    sol = mv_flow(Q0, M0, lam, h, steps, save_every=steps, method=methods[0])
    out: dict[str, float] = {"n": n, "matmul_us": med["matmul"] * 1e6}
    for meth in methods:
        out[f"step_us_{meth}"] = med[meth] * 1e6
        out[f"ratio_{meth}"] = med[meth] / med["matmul"]
    out["sweeps_per_step"] = float(sol.iterations.mean())
    return out


def batch_n3(size: int, h: float, repeats: int) -> dict[str, float]:
    """Marginal step cost (time of 50 steps minus time of 10, over 40: the one-off validation
    and cold start excluded) for the NumPy path and, when installed, the numba path."""
    Q0, M0, lam = _case(3, (size,), seed=2)
    A, B = np.random.default_rng(3).normal(size=(2, size, 3, 3))
    fns: dict[str, Callable[[], float]] = {}
    methods = ["numpy"] + (["numba"] if _compiled.AVAILABLE else [])
    for meth in methods:
        run = _run(Q0, M0, lam, h, meth)
        run(2)
        fns[meth] = lambda run=run: (run(50) - run(10)) / 40  # type: ignore[misc]

    def cold() -> float:
        s = MVStepper(lam, (size,))
        t = time.perf_counter()
        s.step(Q0, M0, h)
        return time.perf_counter() - t

    def warm() -> float:  # the same stepper API, warm
        s = MVStepper(lam, (size,))
        Q1, M1 = s.step(Q0, M0, h)
        t = time.perf_counter()
        s.step(Q1, M1, h)
        return time.perf_counter() - t

    fns |= {"matmul": _per_call(lambda: A @ B, 5), "cold": cold, "warm": warm}
    med = _interleaved(fns, repeats)
    out: dict[str, float] = {"bodies": size, "batched_matmul_ms": med["matmul"] * 1e3}
    for meth in methods:
        out[f"step_ms_{meth}"] = med[meth] * 1e3
        out[f"ratio_to_batched_matmul_{meth}"] = med[meth] / med["matmul"]
        out[f"body_steps_per_s_{meth}"] = size / med[meth]
    out |= {
        "stepper_cold_ms": med["cold"] * 1e3,
        "stepper_warm_ms": med["warm"] * 1e3,
        "cold_over_warm": med["cold"] / med["warm"],
    }
    return out


def drift_seeds(seeds: int, steps: int, h: float) -> dict[str, object]:
    """``seeds`` bodies (random lam per body, one batch) for ``steps`` steps: the RMS over the
    seeds of the largest relative energy, Casimir and orthogonality errors up to N = 10^2, ...,
    and the growth exponent: the least-squares slope of log RMS against log N."""
    rng = np.random.default_rng(40)
    lam = rng.uniform(0.5, 2.0, (seeds, 3))
    A = rng.normal(size=(seeds, 3, 3))
    M0 = (A - np.swapaxes(A, -1, -2)) / np.sqrt(3)
    Q0 = np.broadcast_to(np.eye(3), (seeds, 3, 3)).copy()
    marks = [10**e for e in range(2, 9) if 10**e <= steps]
    save = marks[0]
    t = time.perf_counter()
    sol = mv_flow(Q0, M0, lam, h, steps, save_every=save)
    wall = time.perf_counter() - t
    M, Q = sol.y.M, sol.y.Q  # (K, seeds, 3, 3)
    H = symrb.kinetic_energy(M, lam[None])
    C = np.einsum("ksij,ksij->ks", M, M)
    orth = np.abs(np.swapaxes(Q, -1, -2) @ Q - np.eye(3)).max(axis=(-2, -1))
    out: dict[str, object] = {"seeds": seeds, "steps": steps, "h": h, "seconds": wall,
                              "marks": marks}  # fmt: skip
    for key, err in (("energy_rel", np.abs(H / H[0] - 1)), ("casimir_rel", np.abs(C / C[0] - 1)),
                     ("orthogonality", orth)):  # fmt: skip
        upto = np.array([err[: m // save + 1].max(axis=0) for m in marks])  # (marks, seeds)
        rms = np.sqrt(np.mean(upto**2, axis=1))
        out[key + "_rms"] = rms.tolist()
        if len(marks) >= 2 and np.all(rms > 0):
            out[key + "_growth_exponent"] = float(np.polyfit(np.log(marks), np.log(rms), 1)[0])
    return out


def drift(steps: int, h: float) -> dict[str, object]:
    Q0, M0, lam = _case(3, seed=4)
    marks = [m for m in (10**3, 10**4, 10**5, 10**6) if m <= steps]
    save = marks[0]
    t = time.perf_counter()
    sol = mv_flow(Q0, M0, lam, h, steps, save_every=save)
    wall = time.perf_counter() - t
    H = symrb.kinetic_energy(sol.y.M, lam)
    C = np.einsum("kij,kij->k", sol.y.M, sol.y.M)
    Q = sol.y.Q
    orth = np.abs(np.swapaxes(Q, -1, -2) @ Q - np.eye(3)).max(axis=(-2, -1))

    def upto(x: np.ndarray) -> list[float]:  # max over the states up to each mark
        return [float(np.max(x[: m // save + 1])) for m in marks]

    out: dict[str, object] = {
        "steps": steps,
        "h": h,
        "seconds": wall,
        "marks": marks,
        "energy_rel": upto(np.abs(H / H[0] - 1)),
        "casimir_rel": upto(np.abs(C / C[0] - 1)),
        "orthogonality": upto(orth),
    }
    if len(marks) >= 2:
        for key in ("energy_rel", "casimir_rel", "orthogonality"):
            a, b = out[key][-2], out[key][-1]  # type: ignore[index]
            out[key + "_growth_exponent"] = float(
                np.log(max(b, 1e-300) / max(a, 1e-300)) / np.log(marks[-1] / marks[-2])
            )
    return out


def profile(size: int, h: float) -> dict[str, str]:
    out = {}
    Q0, M0, lam = _case(3)
    Qb, Mb, _ = _case(3, (size,), seed=2)
    for name, code in (
        ("single_n3", lambda: mv_flow(Q0, M0, lam, h, 4000, save_every=4000)),
        ("batch_n3", lambda: mv_flow(Qb, Mb, lam, h, 20, save_every=20)),
    ):
        pr = cProfile.Profile()
        pr.enable()
        code()
        pr.disable()
        buf = io.StringIO()
        pstats.Stats(pr, stream=buf).strip_dirs().sort_stats("tottime").print_stats(8)
        out[name] = buf.getvalue()
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--h", type=float, default=0.05)
    ap.add_argument("--batch", type=int, default=10_000)
    ap.add_argument("--sizes", type=int, nargs="*", default=[3, 10, 50])
    ap.add_argument("--drift-steps", type=int, default=100_000)
    ap.add_argument("--drift-seeds", type=int, default=0, help="multi-seed drift run (e.g. 8)")
    ap.add_argument("--profile", action="store_true")
    ap.add_argument(
        "--output", type=Path, default=Path(__file__).parent / "results" / "step_cost.json"
    )
    args = ap.parse_args()
    with threadpool_limits(1):
        res: dict[str, object] = {
            "machine": platform.platform(),
            "numpy": np.__version__,
            "numba": _compiled.numba.__version__ if _compiled.AVAILABLE else None,
            "timer": "time.perf_counter, median of interleaved repeats",
            "single": [single_body(n, args.h, args.repeats) for n in args.sizes],
            "batch": batch_n3(args.batch, args.h, args.repeats),
        }
        if args.drift_steps and not args.drift_seeds:
            res["drift"] = drift(args.drift_steps, args.h)
        if args.drift_seeds:
            res["drift_seeds"] = drift_seeds(args.drift_seeds, args.drift_steps, args.h)
        if args.profile:
            res["profile"] = profile(args.batch, args.h)
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps(res, indent=2) + "\n")
    for row in res["single"]:  # type: ignore[union-attr]
        cells = ", ".join(
            f"{k[8:]} {row[k]:.2f} us = {row['ratio_' + k[8:]]:.2f} matmul"
            for k in row
            if k.startswith("step_us_")
        )
        print(f"single n={row['n']:>2}: matmul {row['matmul_us']:.2f} us; {cells}; "
              f"sweeps/step {row['sweeps_per_step']:.2f}")  # fmt: skip
    b: dict = res["batch"]  # type: ignore[assignment]
    for k in b:
        if k.startswith("step_ms_"):
            meth = k[8:]
            print(
                f"batch {b['bodies']} n=3 {meth}: step {b[k]:.3f} ms, batched matmul "
                f"{b['batched_matmul_ms']:.3f} ms, ratio {b['ratio_to_batched_matmul_' + meth]:.2f}"
                f", {b['body_steps_per_s_' + meth]:.3g} body-steps/s"
            )
    print(f"stepper cold {b['stepper_cold_ms']:.3f} ms / warm {b['stepper_warm_ms']:.3f} ms = "
          f"{b['cold_over_warm']:.2f}")  # fmt: skip
    for key in ("drift", "drift_seeds"):
        if key in res:
            print(f"{key}:", json.dumps(res[key]))
    if "profile" in res:
        for name, text in res["profile"].items():  # type: ignore[union-attr]
            print(f"--- profile {name}\n{text}")


if __name__ == "__main__":
    main()
