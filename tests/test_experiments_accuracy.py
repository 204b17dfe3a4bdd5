"""The work-precision experiment of the accuracy page (symrb.experiments.accuracy).

Accuracy is asserted against known properties of the methods (the Moser-Veselov flow is second
order and isospectral; explicit Runge-Kutta methods are neither); speed only where the work
itself differs fourfold, and through a fake clock that shows what is measured."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from symrb.errors import InputError
from symrb.experiments import accuracy


@pytest.fixture(scope="module")
def small() -> accuracy.WorkPrecision:
    return accuracy.work_precision(
        steps=(0.1, 0.05, 0.025, 0.0125),
        tolerances=(1e-4, 1e-8),
        T=5.0,
        repeats=5,
        min_seconds=0.01,
    )


def test_runs_and_their_order(small: accuracy.WorkPrecision) -> None:
    assert [r.method for r in small.runs] == ["Moser-Veselov"] * 4 + ["RK45"] * 2 + ["DOP853"] * 2
    assert [r.setting for r in small.series("RK45")] == ["rtol = 1e-04", "rtol = 1e-08"]
    assert [r.work for r in small.series("Moser-Veselov")] == [50, 100, 200, 400]
    for run in small.runs:
        assert run.cpu_seconds.shape == (5,) and np.all(run.cpu_seconds > 0)
        low, high = run.spread
        assert low <= run.median <= high


def test_discrete_flow_is_second_order_and_isospectral(small: accuracy.WorkPrecision) -> None:
    # Moser-Veselov is second order in h (Hairer and Vilmart 2006): error ratio 4 per halving
    assert 1.9 < small.order < 2.1, small.order
    mv = small.series("Moser-Veselov")
    errors = np.array([r.error for r in mv])
    np.testing.assert_allclose(errors[:-1] / errors[1:], 4.0, rtol=0.05)
    # M_{k+1} = U_k^T M_k U_k: the spectrum is kept up to rounding, at every step size
    assert max(r.casimir_drift for r in mv) < 1e-12
    # an explicit Runge-Kutta method at a loose tolerance does not keep it
    assert small.series("RK45")[0].casimir_drift > 1e-9


def test_errors_follow_the_tolerance(small: accuracy.WorkPrecision) -> None:
    for method in ("RK45", "DOP853"):
        loose, tight = small.series(method)
        assert tight.error < loose.error / 100
        assert tight.error < 1e-6  # rtol 1e-8 over t <= 5
        assert tight.work > loose.work


def test_cost_grows_with_the_work(small: accuracy.WorkPrecision) -> None:
    # medians of interleaved rounds: four times the steps must cost more CPU time, even on a
    # loaded machine (a single wall-clock timing per run did not manage this)
    medians = [r.median for r in small.series("Moser-Veselov")]
    assert medians[2] > medians[0] and medians[3] > medians[1], medians


def test_cheapest(small: accuracy.WorkPrecision) -> None:
    best = small.cheapest("DOP853", 1e-3)
    assert best is not None and best.error <= 1e-3
    assert best.median == min(r.median for r in small.series("DOP853") if r.error <= 1e-3)
    assert small.cheapest("Moser-Veselov", 1e-12) is None


def test_times_are_process_cpu_time(monkeypatch: pytest.MonkeyPatch) -> None:
    # a fake CPU clock that advances by 1 s per reading: every timing is exactly 1 s per call,
    # whatever the wall clock does, so the timings come from time.process_time
    ticks = itertools.count()
    monkeypatch.setattr(accuracy.time, "process_time", lambda: float(next(ticks)))
    wp = accuracy.work_precision(
        steps=(0.1, 0.05), tolerances=(1e-4,), methods=("DOP853",), T=1.0, repeats=3
    )
    for run in wp.runs:
        np.testing.assert_array_equal(run.cpu_seconds, [1.0, 1.0, 1.0])


@pytest.mark.parametrize(
    "kwargs, word",
    [({"steps": (0.1,)}, "steps"), ({"tolerances": (2.0,)}, "tolerances"),
     ({"T": -1.0}, "T must"), ({"repeats": 0}, "repeats"), ({"min_seconds": -1}, "min_seconds")],
)  # fmt: skip
def test_bad_input(kwargs: dict, word: str) -> None:
    with pytest.raises(InputError, match=word):
        accuracy.work_precision(**kwargs)
