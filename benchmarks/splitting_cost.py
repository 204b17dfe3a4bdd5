"""The explicit splitting (``symrb.splitting.splitting_flow``, compiled) against DOP853 on the
lean field a user would write for SciPy (``Q`` flat, the full ``M``, :math:`\\Omega_{ij} =
M_{ij}/(\\lambda_i+\\lambda_j)`), on the bodies of ``symrb bench`` (``_problem(n, 0)``).

* ``long``: T = 1e4; the cheapest order and step (orders 4, 6, 8, steps from 1 down) whose
  relative energy and Casimir (:math:`\\operatorname{tr}M^{2k}`) errors stay at most 1e-12 over
  200 saved states, against DOP853 at the loosest of rtol = atol = 1e-10 ... 1e-14 that reaches
  the same (errors over 21 states).
* ``short``: T = 100; the cheapest order and step with error at most 1e-8 in (Q, M) at T against
  DOP853 at rtol = atol = 1e-14, against DOP853 at the loosest tolerance that reaches it.

The chosen pair is timed in interleaved repeats (CPU time, BLAS on one thread); the ratio of the
medians is printed with the load average.  Usage::

    python benchmarks/splitting_cost.py [--n 10 3] [--repeats 3]
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp
from threadpoolctl import threadpool_limits

from benchmarks.harness.problems import _problem
from symrb.splitting import splitting_flow

STEPS = (1.0, 0.8, 0.7, 0.6, 0.5, 0.45, 0.4, 0.35, 0.3, 0.25, 0.2, 0.15, 0.1, 0.07, 0.05)
TOLS = (1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13, 1e-14)


def lean_dop853(lam: Any, Q0: Any, M0: Any, T: float, tol: float, t_eval: Any) -> tuple[Any, Any]:
    n = lam.size
    nn = n * n
    W = 1.0 / (lam[:, None] + lam[None, :])

    def f(_t: float, y: Any) -> Any:
        Q, M = y[:nn].reshape(n, n), y[nn:].reshape(n, n)
        Om = M * W
        return np.concatenate(((Q @ Om).ravel(), (M @ Om - Om @ M).ravel()))

    y0 = np.concatenate((Q0.ravel(), M0.ravel()))
    Y = solve_ivp(f, (0, T), y0, method="DOP853", rtol=tol, atol=tol, t_eval=t_eval).y.T
    return Y[:, :nn].reshape(-1, n, n), Y[:, nn:].reshape(-1, n, n)


def split(lam: Any, Q0: Any, M0: Any, T: float, h: float, order: int, saves: int) -> Any:
    N = round(T / h)
    sol = splitting_flow(Q0, M0, lam, T / N, N, order=order, save_every=max(N // saves, 1))
    return sol.y.Q, sol.y.M


def invariant_error(M: Any, lam: Any) -> float:
    E = 0.25 * np.einsum("...ij,...ij->...", M, M / (lam[:, None] + lam[None, :]))
    C = [np.trace(np.linalg.matrix_power(M, 2 * k), axis1=-2, axis2=-1)
         for k in range(1, M.shape[-1] // 2 + 1)]  # fmt: skip
    return float(max(np.abs(x / x[0] - 1).max() for x in [E, *C]))


def cpu(fn: Callable[[], Any]) -> float:
    t = time.process_time()
    fn()
    return time.process_time() - t


def race(a: Callable[[], Any], b: Callable[[], Any], repeats: int) -> tuple[float, float]:
    ta, tb = [], []
    for _ in range(repeats):
        ta.append(cpu(a))
        tb.append(cpu(b))
    return float(np.median(ta)), float(np.median(tb))


def long_run(n: int, repeats: int) -> None:
    lam, Q0, M0 = _problem(n, 0)
    T, te = 1e4, np.linspace(0, 1e4, 21)
    best = []
    for order in (4, 6, 8):
        for h in STEPS:
            took = time.process_time()
            Q, M = split(lam, Q0, M0, T, h, order, 200)
            if invariant_error(M, lam) <= 1e-12:
                best.append((time.process_time() - took, order, h))
                break
    tol = next(
        t for t in TOLS[3:] if invariant_error(lean_dop853(lam, Q0, M0, T, t, te)[1], lam) <= 1e-12
    )
    _, order, h = min(best)
    s, d = race(lambda: split(lam, Q0, M0, T, h, order, 200),
                lambda: lean_dop853(lam, Q0, M0, T, tol, te), repeats)  # fmt: skip
    print(f"n = {n}, T = 1e4, invariants <= 1e-12: splitting order {order} h {h} {s:.3f} s; "
          f"DOP853 rtol {tol:g} {d:.3f} s; DOP853 / splitting {d / s:.2f}")  # fmt: skip


def short_run(n: int, repeats: int) -> None:
    lam, Q0, M0 = _problem(n, 0)
    T = 100.0
    Qr, Mr = lean_dop853(lam, Q0, M0, T, 1e-14, [T])

    def error(QM: Any) -> float:
        return float(max(np.abs(QM[0][-1] - Qr[-1]).max(), np.abs(QM[1][-1] - Mr[-1]).max()))

    best = []
    for order in (4, 6, 8):
        for h in STEPS:
            if error(split(lam, Q0, M0, T, h, order, 1)) <= 1e-8:
                best.append((cpu(lambda: split(lam, Q0, M0, T, h, order, 1)), order, h))  # noqa: B023
                break
    tol = next(t for t in TOLS if error(lean_dop853(lam, Q0, M0, T, t, [T])) <= 1e-8)
    _, order, h = min(best)
    s, d = race(lambda: split(lam, Q0, M0, T, h, order, 1),
                lambda: lean_dop853(lam, Q0, M0, T, tol, [T]), repeats)  # fmt: skip
    print(f"n = {n}, T = 100, error <= 1e-8: splitting order {order} h {h} {s * 1e3:.2f} ms; "
          f"DOP853 rtol {tol:g} {d * 1e3:.2f} ms; DOP853 / splitting {d / s:.2f}")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, nargs="+", default=[10, 3])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    with threadpool_limits(1):
        split(*_problem(3, 0), 1.0, 0.5, 2, 1)  # load the compiled loop
        for n in args.n:
            print(f"load average {os.getloadavg()[0]:.2f}", flush=True)
            short_run(n, 2 * args.repeats + 1)
            long_run(n, args.repeats)


if __name__ == "__main__":
    main()
