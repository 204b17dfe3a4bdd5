"""The sections, the methods and the two parameter sets (full and ``--quick``) of the benchmark."""

from __future__ import annotations

from typing import Any

import numpy as np

#: The sections of :func:`run`, in order.
SECTIONS = (
    "work-precision",
    "long-time",
    "throughput",
    "cost-vs-n",
    "evidence",
    "step-costs",
    "long-horizon",
    "cold-start",
)

EPS = float(np.finfo(float).eps)

#: Symrb step methods (the candidates for "best symrb step method") and their nominal orders.
_STEP_ORDERS = {
    "MV": 2,
    "MV-fast": 2,
    "MV-comp4": 4,
    "MV-comp6": 6,
    "MV-comp8": 8,
    "MV-pre4": 4,
    "MV-pre6": 6,
    "MV-pre8": 8,
    "MV-pre10": 10,
    "RKMK4": 4,
    "midpoint": 2,
    # symrb.splitting.splitting_flow (any n), when the module is importable
    "split2": 2,
    "split4": 4,
    "split6": 6,
    "split8": 8,
}

#: SciPy's methods on the lean field (what a user would write: :data:`problems.LEAN_VARIANTS`).
_SCIPY = ("RK45", "DOP853", "LSODA")
#: The same on symrb's generated field (2 n^2 unknowns, ``problems._plain_field``).
_SCIPY_GEN = tuple(f"{m}-gen" for m in _SCIPY)

ALL_METHODS = (*_SCIPY, *_SCIPY_GEN, "integrate", *_STEP_ORDERS, "exact")

_FULL: dict[str, Any] = {
    "rounds": 5,
    "min_time": 0.02,
    "wp_T": (10.0, 100.0),
    "wp_rtols": tuple(10.0**-k for k in range(3, 14)),
    "wp_h": {
        2: (0.1, 0.05, 0.025, 0.0125),
        4: (0.2, 0.1, 0.05, 0.025),
        6: (0.25, 0.125, 0.0625),
        8: (0.4, 0.2, 0.1),
        10: (0.5, 0.35, 0.25, 0.18, 0.125),
    },
    "wp_n10_T": 100.0,
    "long_steps": 10**6,
    "long_n": (3, 10),
    "long_h": 0.01,
    "batches": (1, 10, 100, 1000, 10000),
    "cold_batch": 10000,
    "cold_budget": 30.0,
    "cost_n": (3, 5, 10, 20, 50),
    "seed": 0,
    # step-costs: the least CPU time of the longer of the two runs whose difference gives a
    # marginal cost per step, and the sizes of the stage costs
    "marginal_time": 0.05,
    "stage_n": (3, 10),
    # long-horizon (n = 10): T, DOP853's tolerances, the symrb runs (method, h), a budget per run
    "lh_T": 1e4,
    "lh_rtols": (1e-10, 1e-11, 1e-12, 1e-13, 1e-14),
    "lh_symrb": (
        ("MV-fast", 0.2),
        ("MV-fast", 0.1),
        ("MV-comp4", 0.4),
        ("split2", 0.2),
        ("split4", 0.4),
        ("MV-comp8", 0.5),
        ("split6", 0.5),
        ("split8", 0.35),
        ("split8", 0.5),
    ),
    "lh_budget": 120.0,
    # long-time: a budget in CPU seconds for each flow's run
    "long_budget": 400.0,
    # cold-start: new processes (the first primes the cache)
    "cold_processes": 4,
}

_QUICK: dict[str, Any] = dict(
    _FULL,
    rounds=3,
    min_time=0.005,
    wp_T=(10.0,),
    wp_rtols=(1e-3, 1e-5, 1e-7, 1e-9, 1e-11, 1e-12),
    wp_h={
        2: (0.1, 0.05, 0.025),
        4: (0.2, 0.1, 0.05),
        6: (0.25, 0.125),
        8: (0.4, 0.2),
        10: (0.5, 0.35, 0.25),
    },
    wp_n10_T=None,
    long_steps=10**4,
    long_n=(3,),
    cold_budget=2.0,
    marginal_time=0.01,
    lh_T=100.0,
    lh_rtols=(1e-10, 1e-12),
    lh_symrb=(("MV-fast", 0.2), ("split4", 0.4)),
    lh_budget=10.0,
    cold_processes=3,
)

_NOT_QUICK = "not measured in --quick (needs a long run)"
