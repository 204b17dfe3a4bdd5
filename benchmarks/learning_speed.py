"""Speed of the SO(n) network's loss gradient (symrb's costate sweep against torch.autograd) and
training time to a fixed loss (extended MSA against gradient descent).

* Gradient: n = 8, N = 32 layers, M = 1024 samples, alpha = 0.1.  symrb's
  ``so_network_gradients`` (validation, forward sweep, costate sweep, skew gradients) against
  PyTorch autograd on the same network (float64 forward ``Q @ U_k``, ``loss.backward()``, then
  the skew part of ``U_k^T dL/dU_k``, the same G_k) in the same run: interleaved repeats,
  medians of ``time.perf_counter``, BLAS pinned to one thread (threadpoolctl) and
  ``torch.set_num_threads(1)``.  The gradients are compared (largest relative difference).
* Memory: the peak traced by ``tracemalloc`` during one symrb call (NumPy reports its
  allocations to tracemalloc); for torch, whose CPU allocator tracemalloc does not see, the
  bytes of the tensors autograd saves for the backward pass (``saved_tensors_hooks``, counted
  once per storage) plus the parameters' gradient, and the peak of the running sum of the
  operators' net allocations recorded by ``torch.profiler`` (``profile_memory=True``).
* Training to a fixed loss: the rotation task ``so_rotation_task(4, samples=64)``, N = 4,
  alpha = 1, from U = I; the target loss is L* + 1e-6 (L0 - L*), L* from the shooting solver.
  Each method is run once to find how many iterations reach the target, then timed
  (interleaved repeats, medians) for that many iterations.

Usage::

    PYTHONPATH=. python benchmarks/learning_speed.py [--repeats 15]

Writes ``benchmarks/results/learning.json`` (no machine paths) and prints the ratios.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
import tracemalloc
from collections.abc import Callable
from pathlib import Path

import numpy as np
from scipy.linalg import expm
from threadpoolctl import threadpool_info, threadpool_limits

import symrb
from symrb import learning

OUT = Path(__file__).resolve().parent / "results" / "learning.json"


def _network(n: int, N: int, M: int, seed: int = 0) -> tuple[np.ndarray, ...]:
    rng = np.random.default_rng(seed)
    Q0 = symrb.random_SO(n, (M,), seed=rng)
    T = symrb.random_SO(n, (M,), seed=rng)
    A = 0.2 * rng.standard_normal((N, n, n))
    U = np.array([expm(a - a.T) for a in A])
    lam = rng.uniform(0.5, 2.0, n)
    return Q0, U, lam, T


def _torch_gradient(
    torch: object, Q0: np.ndarray, U: np.ndarray, lam: np.ndarray, T: np.ndarray, alpha: float
) -> Callable[[], tuple[float, np.ndarray]]:
    tq, tT, tL = (torch.from_numpy(a) for a in (Q0, T, np.diag(lam)))  # type: ignore[attr-defined]
    eye = torch.eye(U.shape[-1], dtype=torch.float64)  # type: ignore[attr-defined]

    def run() -> tuple[float, np.ndarray]:
        Ut = torch.tensor(U, requires_grad=True)  # type: ignore[attr-defined]
        Q = tq
        for k in range(U.shape[0]):
            Q = Q @ Ut[k]
        loss = 0.5 * ((Q - tT) ** 2).sum() + alpha * torch.einsum(  # type: ignore[attr-defined]
            "ij,kji->", tL, eye - Ut
        )
        loss.backward()
        A = np.swapaxes(U, 1, 2) @ Ut.grad.numpy()
        return float(loss.detach()), 0.5 * (A - np.swapaxes(A, 1, 2))

    return run


def _torch_saved_bytes(torch: object, run: Callable[[], object]) -> int:
    seen: dict[tuple[int, int], int] = {}

    def pack(t: object) -> object:
        key = (t.untyped_storage().data_ptr(), t.untyped_storage().nbytes())  # type: ignore[attr-defined]
        seen[key] = key[1]
        return t

    with torch.autograd.graph.saved_tensors_hooks(pack, lambda t: t):  # type: ignore[attr-defined]
        run()
    return int(sum(seen.values()))


def _torch_profiler_peak(torch: object, run: Callable[[], object]) -> int:
    """Peak of torch's CPU allocator during ``run``: the running sum of the memory each
    profiled operator allocated net of what it freed (``profile_memory=True``), in start order."""
    from torch.profiler import ProfilerActivity, profile

    with profile(activities=[ProfilerActivity.CPU], profile_memory=True) as prof:
        run()
    events = sorted((e.time_range.start, e.self_cpu_memory_usage) for e in prof.events())
    return int(np.max(np.cumsum([m for _t, m in events])))


def _peak(fn: Callable[[], object]) -> int:
    tracemalloc.start()
    tracemalloc.reset_peak()
    fn()
    _cur, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return int(peak)


def _interleaved(fns: dict[str, Callable[[], object]], repeats: int) -> dict[str, list[float]]:
    times: dict[str, list[float]] = {k: [] for k in fns}
    for _ in range(repeats):
        for k, f in fns.items():
            t0 = time.perf_counter()
            f()
            times[k].append(time.perf_counter() - t0)
    return times


def gradient_case(repeats: int) -> dict[str, object]:
    import torch

    torch.set_num_threads(1)
    n, N, M, alpha = 8, 32, 1024, 0.1
    Q0, U, lam, T = _network(n, N, M)
    mine = lambda: learning.so_network_gradients(Q0, U, lam, T, alpha=alpha)  # noqa: E731
    theirs = _torch_gradient(torch, Q0, U, lam, T, alpha)
    loss, G = mine()
    tloss, tG = theirs()
    for f in (mine, theirs):  # warm-up
        f()
    times = _interleaved({"symrb": mine, "torch": theirs}, repeats)
    med = {k: float(np.median(v)) for k, v in times.items()}
    saved = _torch_saved_bytes(torch, theirs)
    grad_bytes = U.nbytes
    return {
        "n": n,
        "layers": N,
        "samples": M,
        "alpha": alpha,
        "repeats": repeats,
        "seconds_median": med,
        "seconds_all": {k: [round(x, 6) for x in v] for k, v in times.items()},
        "ratio_symrb_over_torch": med["symrb"] / med["torch"],
        "loss_relative_difference": abs(loss - tloss) / abs(tloss),
        "gradient_max_relative_difference": float(np.abs(G - tG).max() / np.abs(tG).max()),
        "memory_bytes": {
            "symrb_tracemalloc_peak": _peak(mine),
            "torch_saved_tensors": saved,
            "torch_saved_tensors_plus_gradient": saved + grad_bytes,
            "torch_profiler_peak": _torch_profiler_peak(torch, theirs),
            "torch_tracemalloc_peak_python_side": _peak(theirs),
            "layers_array": (N + 1) * M * n * n * 8,
        },
        "memory_method": "symrb: tracemalloc peak during one call (NumPy allocations are "
        "traced). torch: bytes of the tensors saved for backward (saved_tensors_hooks, each "
        "storage once) plus the gradient of U, and the peak of the running sum of the memory "
        "the profiled operators allocated net of frees (torch.profiler, profile_memory=True); "
        "tracemalloc does not see torch's CPU allocator, its peak (Python side only) is listed "
        "for completeness.",
    }


def training_case(repeats: int) -> dict[str, object]:
    n, N, M, alpha = 4, 4, 64, 1.0
    Q0, T = learning.so_rotation_task(n, samples=M, seed=3)
    lam = np.linspace(1.0, 2.0, n)
    U0 = np.tile(np.eye(n), (N, 1, 1))
    star = learning.train_so_shooting(Q0, T, lam, alpha, N, tol=1e-13)
    L0 = learning.so_network_gradients(Q0, U0, lam, T, alpha=alpha)[0]
    target = star.losses[-1] + 1e-6 * (L0 - star.losses[-1])
    runs: dict[str, Callable[[int], learning.SOTrainResult]] = {
        "gradient_descent_armijo": lambda s: learning.train_so_gradient(
            Q0, T, U0, lam, alpha=alpha, steps=s, line_search=True, lr=0.05, tol=1e-300
        ),
    }
    for lr in (0.002, 0.005, 0.01):
        runs[f"gradient_descent_lr_{lr}"] = lambda s, lr=lr: learning.train_so_gradient(
            Q0, T, U0, lam, alpha=alpha, steps=s, lr=lr, tol=1e-300
        )
    for rho in (1.5, 2.0, 3.0, 4.0, 6.0):
        runs[f"msa_rho_{rho}"] = lambda s, rho=rho: learning.train_so_msa(
            Q0, T, U0, lam, alpha=alpha, steps=s, rho=rho, tol=1e-300
        )
    needed: dict[str, int | None] = {}
    for k, run in runs.items():
        res = run(3000)
        hit = np.nonzero(res.losses <= target)[0]
        needed[k] = int(hit[0]) if len(hit) else None
    fns = {k: (lambda r=run, s=needed[k]: r(s)) for k, run in runs.items() if needed[k]}
    times = _interleaved(fns, repeats)
    med = {k: float(np.median(v)) for k, v in times.items()}
    best_gd = min((k for k in med if k.startswith("gradient")), key=med.__getitem__)
    best_msa = min((k for k in med if k.startswith("msa")), key=med.__getitem__)
    return {
        "task": f"so_rotation_task(n={n}, samples={M}, seed=3), N = {N}, alpha = {alpha}, "
        "lam = linspace(1, 2, n), from U = I",
        "loss_start": L0,
        "loss_optimal_shooting": float(star.losses[-1]),
        "loss_target": float(target),
        "iterations_to_target": needed,
        "note": "None: the target was not reached in 3000 iterations (the fixed step or the "
        "MSA penalty too small: the iteration oscillates or diverges)",
        "seconds_median": med,
        "fastest_gradient_descent": best_gd,
        "fastest_msa": best_msa,
        "ratio_fastest_msa_over_fastest_gradient_descent": med[best_msa] / med[best_gd],
        "seconds_per_iteration": {k: med[k] / needed[k] for k in med if needed[k]},
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--output", type=Path, default=OUT)
    args = ap.parse_args()
    import torch

    with threadpool_limits(limits=1):
        blas = sorted({Path(i.get("filepath", "")).name for i in threadpool_info()})
        res = {
            "machine": f"{platform.machine()}, {platform.python_implementation()} "
            f"{platform.python_version()}",
            "numpy": np.__version__,
            "torch": torch.__version__,
            "blas_libraries": blas,
            "blas_threads": 1,
            "torch_threads": 1,
            "gradient": gradient_case(args.repeats),
            "training": training_case(max(3, args.repeats // 3)),
        }
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps(res, indent=1) + "\n")
    g, t = res["gradient"], res["training"]
    print(
        f"gradient n=8 N=32 M=1024: symrb {g['seconds_median']['symrb'] * 1e3:.1f} ms, torch "
        f"{g['seconds_median']['torch'] * 1e3:.1f} ms, ratio {g['ratio_symrb_over_torch']:.2f}; "
        f"max rel. gradient difference {g['gradient_max_relative_difference']:.1e}"
    )
    print("memory:", json.dumps(g["memory_bytes"]))
    print("training, iterations to target:", json.dumps(t["iterations_to_target"]))
    print(
        f"training time to target: {t['fastest_msa']} over {t['fastest_gradient_descent']} = "
        f"{t['ratio_fastest_msa_over_fastest_gradient_descent']:.2f}"
    )


if __name__ == "__main__":
    main()
