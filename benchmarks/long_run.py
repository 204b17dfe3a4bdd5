"""Long-run conservation benchmark of MV-Algorithm 2 (issue: 10^6 steps outside the book).

Runs ``symrb.mv_algorithm2`` for ``--steps`` steps (default 10^6) of the discrete rigid body with
n = 3 (computed by the engine; ``--reference``: the step-by-step loop with its progress bar,
``progress=True``, about 1000 times slower), keeps ``--chunks`` evenly spaced states, and
records how far the Casimirs (spectrum of M), the discrete energy, Manakov's integrals and the
orthogonality of Q have moved.  BLAS is
pinned to one thread (threadpoolctl): on this shared 2-core machine two BLAS threads make small
matrix products hundreds of times slower.

Usage::

    python benchmarks/long_run.py [--steps 1000000] [--n 3] [--h 0.01] [--reference] [--output FILE]

Writes a JSON summary (default ``benchmarks/results/long_run.json``).
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np

import symrb


def drift_summary(Q: np.ndarray, M: np.ndarray, lam: np.ndarray) -> dict[str, list[float]]:
    """Relative drift of the invariants along the saved states (first axis is time)."""
    eig = np.sort(np.abs(np.linalg.eigvals(M).imag), axis=-1)
    casimir = symrb.casimir_traces(M)[..., 0]
    energy = symrb.kinetic_energy(M, lam)
    manakov = symrb.manakov_integrals(M, lam)
    orth = np.abs(np.swapaxes(Q, -1, -2) @ Q - np.eye(Q.shape[-1])).max(axis=(-2, -1))

    def rel(x: np.ndarray) -> np.ndarray:
        x = x.reshape(len(x), -1)
        return np.abs(x - x[0]).max(axis=1) / np.abs(x[0]).max()

    return {
        "spectrum": rel(eig).tolist(),
        "casimir_trM2": rel(casimir).tolist(),
        "energy": rel(energy).tolist(),
        "manakov": rel(manakov).tolist(),
        "orthogonality": orth.tolist(),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=10**6)
    parser.add_argument("--n", type=int, default=3)
    parser.add_argument("--h", type=float, default=0.01)
    parser.add_argument("--chunks", type=int, default=200)
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--reference", action="store_true", help="the step-by-step loop")
    parser.add_argument(
        "--output", default=str(Path(__file__).parent / "results" / "long_run.json")
    )
    args = parser.parse_args()

    from threadpoolctl import threadpool_limits

    rng = np.random.default_rng(args.seed)
    lam = symrb.algebra.random_lam(args.n, seed=rng)
    Q = symrb.random_SO(args.n, seed=rng)
    M = args.h * symrb.random_so(args.n, seed=rng)  # discrete momentum = h * continuous momentum
    per_chunk = max(1, args.steps // args.chunks)
    with threadpool_limits(limits=1):  # compile and load the engine's loop first (not timed)
        warm = time.perf_counter()
        symrb.mv_algorithm2(Q, M, lam, min(args.steps, 30_000), save_every=per_chunk)
        warmup = time.perf_counter() - warm
    start = time.perf_counter()
    with threadpool_limits(limits=1):
        run = symrb.mv_algorithm2(
            Q, M, lam, args.steps, save_every=per_chunk, progress=args.reference
        )
    seconds = time.perf_counter() - start
    if not run.success:
        raise SystemExit(f"the run stopped early: {run.message}")
    saved_k = run.k.tolist()
    drifts = drift_summary(run.y.Q, run.y.M, lam)
    result = {
        "what": "MV-Algorithm 2, discrete rigid body, conservation over a long run",
        "path": "the step-by-step loop" if args.reference else "the engine (symrb.engine.mv_flow)",
        "n": args.n,
        "h": args.h,
        "steps": args.steps,
        "seconds": seconds,
        "warmup_seconds": warmup,
        "microseconds_per_step": 1e6 * seconds / args.steps,
        "newton_iterations_per_step": run.nit / max(1, len(run.iterations)),
        "machine": f"{platform.machine()}, {platform.python_implementation()} {platform.python_version()}",
        "numpy": np.__version__,
        "k": saved_k,
        "max_drift": {key: max(vals) for key, vals in drifts.items()},
        "drift": drifts,
    }
    out = Path(args.output)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"{args.steps} steps in {seconds:.1f} s ({result['microseconds_per_step']:.1f} us/step)")
    for key, val in result["max_drift"].items():
        print(f"  max drift {key:>14}: {val:.2e}")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
