"""Fuzz of the public flows and solvers with extreme finite input (issue 22).

Magnitudes from 1e-300 to 1e300, near-singular and widely spread inertias, steps from 1e-300 to
1e300, few steps and small budgets.  Every call must end in one of three ways: a
:mod:`symrb.errors` exception, a result with ``success`` False and a message, or a result with
``success`` True and every number finite (and, where cheap, an invariant kept).  Any other
exception, and a hang, fails.  The counts of the three outcomes are printed at the end of the
module (``pytest -s``); the CI profile of tests/conftest.py makes the examples the same on every
run.
"""

from __future__ import annotations

import dataclasses
from collections import Counter
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import symrb
from symrb.compose import composed_rigid_body_flow, midpoint_rigid_body_flow, rkmk4_rigid_body_flow
from symrb.engine import mv_flow
from symrb.errors import SymrbError
from symrb.exact import rigid_body_exact

OUTCOMES: Counter[str] = Counter()

#: the budget of the adaptive solvers in this file (a hang would be the default's minute)
NFEV = 3000


@pytest.fixture(scope="module", autouse=True)
def _report() -> Iterator[None]:
    yield
    total = sum(OUTCOMES.values())
    print(f"\nfuzz of the flows: {total} calls: " + ", ".join(f"{k} {v}" for k, v in
                                                            sorted(OUTCOMES.items())))  # fmt: skip


# ---------------------------------------------------------------------------------------------
# strategies

magnitudes = st.one_of(
    st.integers(-300, 300).map(lambda e: 10.0**e),
    st.sampled_from([1e-300, 1e-160, 1e-150, 1e150, 1e154, 1e160, 1e300, 1.0]),
    st.floats(1e-3, 1e3),
)


@st.composite
def momenta(draw: st.DrawFn, n: int = 3) -> np.ndarray:
    """A skew matrix of a random direction scaled to an extreme magnitude."""
    v = np.array(draw(st.lists(st.floats(-1, 1), min_size=n * (n - 1) // 2,
                               max_size=n * (n - 1) // 2)))  # fmt: skip
    A = np.zeros((n, n))
    A[np.triu_indices(n, 1)] = v
    return draw(magnitudes) * (A - A.T)


@st.composite
def inertias(draw: st.DrawFn, n: int = 3) -> np.ndarray:
    """Positive moments: ordinary, near-singular (one or two tiny), widely spread or scaled to
    an extreme magnitude."""
    kind = draw(st.sampled_from(["plain", "tiny", "spread", "scaled"]))
    lam = np.array(draw(st.lists(st.floats(0.5, 2.0), min_size=n, max_size=n)))
    if kind == "tiny":
        lam[: draw(st.integers(1, 2))] *= draw(magnitudes.filter(lambda x: x < 1))
    elif kind == "spread":
        lam[0] /= draw(magnitudes)
        lam[-1] *= draw(magnitudes)
    elif kind == "scaled":
        lam = lam * draw(magnitudes)
    return lam


attitudes = st.integers(0, 2**16).map(lambda seed: symrb.random_SO(3, seed=seed))
steps = st.integers(0, 4)


# ---------------------------------------------------------------------------------------------
# the check


def _numbers(x: Any, skip: frozenset[str] = frozenset()) -> Iterator[tuple[str, np.ndarray]]:
    """Every float array, float and nested container of a result, by name."""
    if isinstance(x, dict):
        for k, val in x.items():
            yield from ((f"{k}.{n}" if n else str(k), a) for n, a in _numbers(val))
    elif dataclasses.is_dataclass(x) and not isinstance(x, type):
        for f in dataclasses.fields(x):
            if f.name not in skip and f.name not in ("flow", "raw"):
                yield from ((f"{f.name}.{n}" if n else f.name, a)
                            for n, a in _numbers(getattr(x, f.name)))  # fmt: skip
    elif isinstance(x, tuple | list):
        for i, val in enumerate(x):
            yield from ((f"[{i}]{n}", a) for n, a in _numbers(val))
    elif isinstance(x, np.ndarray | float | np.floating):
        a = np.asarray(x)
        if a.dtype.kind == "f":
            yield "", a


def outcome(call: Callable[[], Any], invariant: Callable[[Any], float] | None = None) -> None:
    """Run ``call``: a symrb error, a failure with a message, or a finite success."""
    try:
        with np.errstate(all="ignore"):
            out = call()
    except SymrbError as exc:
        assert str(exc), "a symrb error without a message"
        OUTCOMES["symrb error"] += 1
        return
    sol = out
    if hasattr(sol, "success"):
        if not sol.success:
            assert sol.message, "success=False without a message"
            OUTCOMES["success=False"] += 1
            return
        # condition is NaN by design unless diagnostics=True
        bad = [name for name, a in _numbers(sol, frozenset({"condition"}))
               if not np.isfinite(a).all()]  # fmt: skip
        assert not bad, f"success=True with non-finite {bad}: {sol.message}"
        if getattr(sol, "raw", None) is not None:
            bad = [n for n, a in _numbers(sol.raw, frozenset({"condition"}))
                   if not np.isfinite(a).all()]  # fmt: skip
            assert not bad, f"success=True with non-finite raw {bad}"
    else:
        bad = [name for name, a in _numbers(sol) if not np.isfinite(a).all()]
        assert not bad, f"returned non-finite {bad}"
    if invariant is not None:
        assert invariant(out) <= 1e-8, f"invariant off by {invariant(out):.3g}"
    OUTCOMES["finite result"] += 1


def casimir_drift(M: np.ndarray) -> float:
    """The relative change of tr M^2 along a run (absolute below 1e-300: subnormal squares)."""
    c = np.einsum("...ij,...ji->...", M, M)
    return float(np.max(np.abs(c - c[0])) / (np.max(np.abs(c[0])) + 1e-300))


# ---------------------------------------------------------------------------------------------
# the properties


@given(Q=attitudes, M=momenta(), lam=inertias(), h=magnitudes, k=steps, halve=st.booleans())
def test_paper_flows(Q, M, lam, h, k, halve) -> None:
    outcome(lambda: symrb.discrete_rigid_body_flow(Q, M, lam, h, k, halve=halve),
            lambda s: casimir_drift(s.y.M))  # fmt: skip
    outcome(lambda: symrb.symmetric_flow(Q, Q @ M, lam, h, k))
    outcome(lambda: symrb.mv_algorithm2(Q, h * M, lam, k), lambda s: casimir_drift(s.y.M))
    outcome(lambda: symrb.mv_algorithm1(Q, symrb.random_SO(3, seed=1), lam, k))


@given(Q=attitudes, M=momenta(), lam=inertias(), h=magnitudes, k=steps,
       order=st.sampled_from([2, 4, 10]))  # fmt: skip
def test_engine_and_compositions(Q, M, lam, h, k, order) -> None:
    outcome(lambda: mv_flow(Q, M, lam, h, k, order=order), lambda s: casimir_drift(s.y.M))
    outcome(lambda: composed_rigid_body_flow(Q, M, lam, h, k, order=min(order, 8)),
            lambda s: casimir_drift(s.y.M))  # fmt: skip
    outcome(lambda: rkmk4_rigid_body_flow(Q, M, lam, h, k))
    outcome(lambda: midpoint_rigid_body_flow(Q, M, lam, h, k))


@given(M=momenta(n=4), lam=inertias(n=4), h=magnitudes, k=steps)
def test_engine_general_n(M, lam, h, k) -> None:
    outcome(lambda: mv_flow(np.eye(4), M, lam, h, k), lambda s: casimir_drift(s.y.M))


@given(Q=attitudes, M=momenta(), lam=inertias(), T=magnitudes,
       method=st.sampled_from(["mv", "composition", "rkmk4", "midpoint"]))  # fmt: skip
def test_simulate_fixed_step(Q, M, lam, T, method) -> None:
    outcome(lambda: symrb.simulate(Q, M, lam, (0.0, T), method=method, h=T / 3))


@given(Q=attitudes, M=momenta(), lam=inertias(), T=magnitudes,
       method=st.sampled_from(["DOP853", "RK45", "Radau"]))  # fmt: skip
def test_integrate(Q, M, lam, T, method) -> None:
    outcome(lambda: symrb.integrate(symrb.RigidBody, (0.0, T), {"Q": Q, "M": M}, lam=lam,
                                    method=method, max_nfev=NFEV))  # fmt: skip
    outcome(lambda: symrb.integrate(symrb.SymmetricRigidBody, (0.0, T), {"Q": Q, "P": Q @ M},
                                    lam=lam, max_nfev=NFEV))  # fmt: skip


@given(Q=attitudes, M=momenta(), lam=inertias(), T=magnitudes)
def test_exact(Q, M, lam, T) -> None:
    outcome(lambda: rigid_body_exact(Q, M, lam, [0.0, T]), lambda s: casimir_drift(s.y.M))


@given(M=momenta(), lam=inertias())
def test_solvers(M, lam) -> None:
    outcome(lambda: symrb.solve_moser_veselov(M, lam))
    # fold_scale is inf for M = 0 (documented): every other value must be finite
    outcome(lambda: np.where(np.isposinf(symrb.fold_scale(M, lam)), 1.0, symrb.fold_scale(M, lam)))


@given(a=st.lists(st.floats(-1, 1), min_size=3, max_size=3), b=st.lists(st.floats(-1, 1),
       min_size=2, max_size=2), scale=magnitudes, T=magnitudes)  # fmt: skip
def test_orbit_flows(a, b, scale, T) -> None:
    x0, N = scale * symrb.hat(a), symrb.hat([0.0, 0.0, 1.0])
    outcome(lambda: symrb.toda_flow(scale * np.array(a), scale * np.array(b), [0.0, T],
                                    max_nfev=NFEV))  # fmt: skip
    outcome(lambda: symrb.double_bracket_flow(x0, N, [0.0, T], max_nfev=NFEV))
    outcome(lambda: symrb.orbits.orbit_extremal_flow(x0, -N, N, [0.0, T], max_nfev=NFEV))


@settings(max_examples=12)  # a boundary value solve costs up to a second
@given(a=st.lists(st.floats(-1, 1), min_size=3, max_size=3), scale=magnitudes, T=magnitudes)
def test_orbit_bvp(a, scale, T) -> None:
    outcome(lambda: symrb.solve_orbit_bvp(scale * symrb.hat(a), symrb.hat([0.0, 0.0, 1.0]), T,
                                          nodes=11))  # fmt: skip


# ---------------------------------------------------------------------------------------------
# the cases of issue 22, each of which failed before the fix


BIG = symrb.hat([0.3, -0.2, 0.5])
LAM = [0.7, 1.1, 1.6]


@pytest.mark.parametrize(
    "call",
    [
        lambda: symrb.discrete_rigid_body_flow(np.eye(3), 1e160 * BIG, LAM, 0.1, 10),
        lambda: symrb.symmetric_flow(np.eye(3), 1e160 * BIG, LAM, 0.1, 10),
        lambda: symrb.mv_algorithm2(np.eye(3), 1e155 * BIG, LAM, 10),
        lambda: rkmk4_rigid_body_flow(np.eye(3), 1e160 * BIG, LAM, 0.1, 10),
        lambda: mv_flow(np.eye(3), 1e300 * BIG, LAM, 0.1, 10),
        lambda: composed_rigid_body_flow(np.eye(3), 1e300 * BIG, LAM, 0.1, 10),
        lambda: rigid_body_exact(np.eye(3), 1e300 * BIG, LAM, [1.0]),
        lambda: symrb.fold_scale(BIG, 1e300 * np.array(LAM)),
    ],
    ids=["drb", "symmetric", "mv2", "rkmk4", "mv_flow", "composed", "exact", "fold_scale"],
)
def test_issue22_overflow_is_an_input_error(call: Callable[[], Any]) -> None:
    with pytest.raises(symrb.InputError, match="magnitude <= 1e\\+150"):
        call()


@pytest.mark.parametrize(
    "call",
    [
        lambda n: symrb.toda_flow([0.5, -1.0, 0.2], [0.8e300, 0.6e300], [0.0, 1.0], max_nfev=n),
        lambda n: symrb.toda_flow([0.5, -1.0, 0.2], [0.8, 0.6], [0.0, 1e300], max_nfev=n),
        lambda n: symrb.toda_flow([0.5, -1.0, 0.2], [0.8e10, 0.6e10], [0.0, 1.0], max_nfev=n),
        lambda n: symrb.double_bracket_flow(1e300 * BIG, BIG, [0.0, 1.0], max_nfev=n),
        lambda n: symrb.double_bracket_flow(BIG, BIG, [0.0, 1e300], max_nfev=n),
    ],
    ids=["toda-b", "toda-t", "toda-stiff", "db-x", "db-t"],
)
def test_issue22_hangs_end_with_a_message(call: Callable[[int], Any]) -> None:
    with pytest.raises(symrb.NotConvergedError, match="budget of max_nfev = 500|not finite"):
        call(500)


def test_halving_is_bounded() -> None:
    """A step 1e7 times past the fold with halve=True took up to 2^30 substeps (a hang); now at
    most 2^12, then the step fails with the fold diagnosis."""
    sol = symrb.discrete_rigid_body_flow(np.eye(3), BIG, LAM, 1e7, 1, halve=True)
    assert sol.success is False and sol.failed_step == 1 and "past the fold" in sol.message


def test_orbit_bvp_continuation_is_bounded() -> None:
    """T = 1e300 meant about 1700 boundary value solves; now refused before the first."""
    with pytest.raises(symrb.InputError, match="more than 100"):
        symrb.solve_orbit_bvp(1e-300 * BIG, BIG, 1e300)


def test_budget_of_integrate_is_reported() -> None:
    sol = symrb.integrate(symrb.RigidBody, (0, 1e6), {"Q": np.eye(3), "M": 1e10 * BIG},
                          lam=LAM, max_nfev=500)  # fmt: skip
    assert sol.success is False and "budget of max_nfev = 500" in sol.message


def test_a_non_finite_state_is_never_a_success() -> None:
    """The result types themselves: a state that overflowed marks the run failed, cut there."""
    from symrb._results import DiscreteFlowSolution, Trajectory

    Q = np.stack([np.eye(3)] * 3)
    Q[2, 0, 0] = np.inf
    sol = DiscreteFlowSolution(
        t=np.arange(3.0), k=np.arange(3), y=Trajectory(Q=Q), iterations=np.zeros(2, int),
        success=True, status=0, message="all 2 steps taken", method="test",
        residual=np.array([0.0, np.inf]), tol=np.ones(2),
    )  # fmt: skip
    assert (sol.success, sol.status, sol.failed_step, sol.y.Q.shape) == (False, -1, 2, (2, 3, 3))
    assert "y.Q not finite from step 2" in sol.message and "residual of solve 1" in sol.message
