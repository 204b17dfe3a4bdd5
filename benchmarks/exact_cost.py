"""Cost and accuracy of the exact rigid body propagator (``symrb.exact.rigid_body_exact``) against
DOP853 (``symrb.integrate(symrb.RigidBody, ..., method="DOP853")``) at rtol = atol = 1e-12.

``check=False`` (no value validation, for inner loops) is timed as well.

Issue goal: the exact propagator at least 100x faster than DOP853 at rtol 1e-12, accurate to
1e-13.  For each final time T (default 10 and 100) one evaluation of the exact solution at T and
one DOP853 run from 0 to T are timed in interleaved repeats (CPU time, ``time.process_time``; each
sample loops a call until it has taken at least ``--min-sample`` seconds) with BLAS pinned to one
thread (threadpoolctl); the ratio of the medians is reported with the spread of the samples.

Accuracy: the exact solution and DOP853 at T are compared with a 25-digit Taylor integration of
the same equations (``mpmath.odefun``) at T <= ``--mp-horizon`` (default 10; it takes seconds per
unit of time), and with each other at every T.

Usage::

    python benchmarks/exact_cost.py [--T 10 100] [--repeats 7] [--output FILE]

Writes a JSON summary (default ``benchmarks/results/exact_cost.json``).
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

import symrb
from symrb.exact import rigid_body_exact

LAM = np.array([0.7, 1.1, 1.6])
M0 = symrb.hat([0.5, 1.0, 1.5])


def _sample(call: Callable[[], object], min_seconds: float) -> float:
    """CPU seconds per call, looping until ``min_seconds`` have passed."""
    count, start = 0, time.process_time()
    while True:
        call()
        count += 1
        used = time.process_time() - start
        if used >= min_seconds:
            return used / count


def mp_reference(Q0: np.ndarray, M0: np.ndarray, lam: np.ndarray, T: float, dps: int = 25):
    """Q(T), M(T) from mpmath's Taylor-series ODE solver in ``dps`` digits (independent of symrb's
    formulas: only the vector field Qdot = Q Omega, mdot = m x omega, omega_i = m_i / I_i)."""
    import mpmath as mp

    mp.mp.dps = dps
    inertia = [mp.mpf(float(x)) for x in symrb.algebra.inertia_from_lam(lam)]

    def f(_t, y):
        m = y[9:]
        w = [m[i] / inertia[i] for i in range(3)]
        Q = [[y[3 * i + j] for j in range(3)] for i in range(3)]
        W = [[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]]
        dQ = [sum(Q[i][k] * W[k][j] for k in range(3)) for i in range(3) for j in range(3)]
        dm = [m[1] * w[2] - m[2] * w[1], m[2] * w[0] - m[0] * w[2], m[0] * w[1] - m[1] * w[0]]
        return dQ + dm

    y0 = [mp.mpf(float(x)) for x in np.ravel(Q0)] + [mp.mpf(float(x)) for x in symrb.vee(M0)]
    yT = mp.odefun(f, 0, y0)(T)
    QT = np.array([float(x) for x in yT[:9]]).reshape(3, 3)
    return QT, symrb.hat(np.array([float(x) for x in yT[9:]]))


def measure(
    Ts: tuple[float, ...] = (10.0, 100.0),
    repeats: int = 7,
    rtol: float = 1e-12,
    min_sample: float = 0.05,
    mp_horizon: float = 10.0,
    seed: int = 1,
) -> dict:
    """Time one exact evaluation at T and one DOP853 run to T (interleaved repeats, CPU time) and
    compare both with each other and, for T <= ``mp_horizon``, with :func:`mp_reference`."""
    from threadpoolctl import threadpool_limits

    Q0 = symrb.random_SO(3, seed=seed)
    rows = []
    with threadpool_limits(limits=1):
        for T in Ts:

            def exact(T: float = T):
                return rigid_body_exact(Q0, M0, LAM, [T])

            def exact_unchecked(T: float = T):
                return rigid_body_exact(Q0, M0, LAM, [T], check=False)

            def dop(T: float = T):
                return symrb.integrate(
                    symrb.RigidBody, (0.0, T), {"Q": Q0, "M": M0}, lam=LAM,
                    method="DOP853", rtol=rtol, atol=rtol, t_eval=[T],
                )  # fmt: skip

            ex_t, un_t, dop_t = [], [], []
            for _ in range(repeats):
                ex_t.append(_sample(exact, min_sample))
                un_t.append(_sample(exact_unchecked, min_sample))
                dop_t.append(_sample(dop, min_sample))
            e, d = exact(), dop()
            row = {
                "T": T,
                "exact_seconds_median": float(np.median(ex_t)),
                "exact_seconds_range": [float(min(ex_t)), float(max(ex_t))],
                "dop853_seconds_median": float(np.median(dop_t)),
                "dop853_seconds_range": [float(min(dop_t)), float(max(dop_t))],
                "dop853_nfev": d.nfev,
                "exact_unchecked_seconds_median": float(np.median(un_t)),
                "ratio_median": float(np.median(dop_t) / np.median(ex_t)),
                "ratio_unchecked_median": float(np.median(dop_t) / np.median(un_t)),
                "exact_vs_dop853_Q": float(np.abs(e.y.Q[-1] - d.y.Q[-1]).max()),
                "exact_vs_dop853_M": float(np.abs(e.y.M[-1] - d.y.M[-1]).max()),
            }
            if T <= mp_horizon:
                Qr, Mr = mp_reference(Q0, M0, LAM, T)
                row["exact_error_Q"] = float(np.abs(e.y.Q[-1] - Qr).max())
                row["exact_error_M"] = float(np.abs(e.y.M[-1] - Mr).max())
                row["dop853_error_Q"] = float(np.abs(d.y.Q[-1] - Qr).max())
                row["dop853_error_M"] = float(np.abs(d.y.M[-1] - Mr).max())
            rows.append(row)
    return {
        "what": "exact n = 3 rigid body (symrb.exact) vs DOP853, one evaluation at time T",
        "clock": "time.process_time (CPU seconds), BLAS pinned to 1 thread",
        "rtol": rtol,
        "lam": LAM.tolist(),
        "m0": symrb.vee(M0).tolist(),
        "repeats": repeats,
        "machine": f"{platform.machine()}, {platform.python_implementation()} "
        f"{platform.python_version()}",
        "numpy": np.__version__,
        "rows": rows,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--T", type=float, nargs="+", default=[10.0, 100.0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--rtol", type=float, default=1e-12)
    parser.add_argument("--min-sample", type=float, default=0.05)
    parser.add_argument("--mp-horizon", type=float, default=10.0)
    parser.add_argument(
        "--output", default=str(Path(__file__).parent / "results" / "exact_cost.json")
    )
    args = parser.parse_args()
    result = measure(tuple(args.T), args.repeats, args.rtol, args.min_sample, args.mp_horizon)
    out = Path(args.output)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=1) + "\n")
    for r in result["rows"]:
        line = (
            f"T = {r['T']:g}: exact {1e6 * r['exact_seconds_median']:.0f} us, DOP853 "
            f"{1e3 * r['dop853_seconds_median']:.1f} ms ({r['dop853_nfev']} evaluations), "
            f"ratio {r['ratio_median']:.0f} (check=False: {1e6 * r['exact_unchecked_seconds_median']:.0f} us, "
            f"ratio {r['ratio_unchecked_median']:.0f}); |exact - DOP853| Q {r['exact_vs_dop853_Q']:.1e}"
        )
        if "exact_error_Q" in r:
            line += (
                f"; vs 25-digit reference: exact Q {r['exact_error_Q']:.1e} M "
                f"{r['exact_error_M']:.1e}, DOP853 Q {r['dop853_error_Q']:.1e} M "
                f"{r['dop853_error_M']:.1e}"
            )
        print(line)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
