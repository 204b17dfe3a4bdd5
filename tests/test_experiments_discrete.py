"""Tests of symrb.experiments.discrete: the experiments the rigid-body and Section 2 pages plot.

Each test calls the function its page calls (with smaller sizes where the page's run is long) and
judges the numbers against a reference stated here: a closed form, a theoretical order, a bound of
float64 arithmetic, or an independent integrator, never against a spread that the experiment
computes itself.
"""

from __future__ import annotations

import numpy as np
import pytest

from symrb import InputError
from symrb.experiments import discrete as X

EPS = np.finfo(float).eps


def test_manakov_drift_stays_at_the_integrator_tolerance():
    run = X.manakov_drift(t_end=10.0, samples=201, windows=10)
    # DOP853 at rtol = atol = 1e-12 over t <= 10: a relative drift of 1e-9 would be a thousand
    # times the tolerance
    assert run.max_drift.max() < 1e-9 and run.max_energy_drift < 1e-9
    assert run.window_casimirs.max() < 1e-9
    # M_12 is not conserved: it changes by order one over the same run
    assert run.m12_range > 0.1
    # the summary per window keeps the largest value of the raw series, and covers the run
    assert run.window_integrals.max() == run.drift.max()
    assert run.window_energy.max() == run.energy_drift.max()
    assert run.window_t[-1] == run.t[-1] and run.window_t.shape == (10,)
    assert run.labels == ("(2,0)", "(3,1)", "(4,0)", "(4,2)", "(5,1)", "(5,3)")


def test_manakov_drift_sees_a_loose_integrator():
    """The same measurement with a tolerance of 1e-4 shows a drift far above 1e-9: the bound
    above is met because the integrals are conserved, not because the measure is blind."""
    assert X.manakov_drift(t_end=10.0, samples=201, rtol=1e-4).max_drift.max() > 1e-7


def test_time_step_scaling_is_second_order_with_the_predicted_term():
    run = X.time_step_scaling()
    assert np.all(np.abs(run.order - 2) < 0.01)
    # J_D(exp(h Om)) - h J(Om) = h^2/2 (Om^2 Lam - Lam Om^2) + O(h^3): the leading term, written
    # with an explicit diagonal matrix
    L = np.diag(run.lam)
    O2 = run.Omega @ run.Omega
    c2 = np.linalg.norm(O2 @ L - L @ O2) / 2
    assert run.error[-1] / run.h[-1] ** 2 == pytest.approx(c2, rel=1e-3)
    assert run.leading == pytest.approx(c2, rel=1e-12)


def test_layer_jacobian_residual_tends_to_identity_plain_to_zero():
    run = X.layer_jacobian()
    small = run.scale <= 1e-2
    # residual layer: dF/dx - I = diag(tanh') eps K_1, linear in eps (slope 1 on log-log axes)
    slope = np.polyfit(np.log(run.scale[small]), np.log(run.residual_gap[small]), 1)[0]
    assert slope == pytest.approx(1.0, abs=0.01)
    assert run.residual_gap[0] < 1e-3
    # plain layer: dF/dx = diag(tanh') eps K_1 -> 0, so dF/dx - I -> -I, of max entry 1
    assert run.plain_gap[small] == pytest.approx(1.0, abs=0.02)


def test_toy_training_learns_the_classes():
    run = X.train_toy_classifier()
    assert run.losses[-1] < 0.2 * run.losses[0]
    assert run.accuracy > 0.95  # chance is 0.5
    assert run.window_min.min() == run.losses.min() and run.window_max.max() == run.losses.max()
    assert run.window_step[-1] == run.losses.shape[0] - 1


def test_trace_maximum_reaches_the_closed_form_value():
    run = X.trace_maximum()
    s = np.linalg.svd(run.A, compute_uv=False)
    # max over SO(n) of tr(AU): the sum of the singular values, the smallest taken with the sign
    # of det A (von Neumann's trace inequality)
    best = s[:-1].sum() + np.sign(np.linalg.det(run.A)) * s[-1]
    assert run.value_search == pytest.approx(best, rel=1e-10)
    assert run.value_closed == pytest.approx(best, rel=1e-12)
    for U in (run.U_search, run.U_closed):
        assert np.abs(U.T @ U - np.eye(U.shape[0])).max() < 1e-12
        assert np.linalg.det(U) == pytest.approx(1.0, abs=1e-12)
    assert run.asymmetry < 1e-6  # AU symmetric at a critical point


def test_three_algorithms_agree_to_rounding():
    """The symmetric representation, MV-Algorithm 2 and MV-Algorithm 1 give the same Q_k (page
    "The Moser-Veselov equations", which runs 10^4 steps; here 10^3)."""
    steps = 1000
    run = X.algorithm_agreement(steps=steps, windows=10)
    # the O(h^2) error of the discrete flow at h = 1 against an independent integrator: this is
    # the size of the error a wrong index or a wrong transpose would make
    assert 1e-4 < run.discretisation_error < 1e-2
    assert run.wrong_index_gap.max() > 0.1 * run.discretisation_error
    # symmetric vs MV-Algorithm 2: rounding only, at most ten float64 units per step
    assert run.gap_sym_mv2.max() < 10 * steps * EPS
    assert run.gap_momentum.max() < 10 * steps * EPS
    # MV-Algorithm 1 loses digits each step (it differences nearly equal matrices), but stays
    # five orders of magnitude below the discretisation error
    assert run.gap_mv1_mv2.max() < 1e-5 * run.discretisation_error
    assert run.gap_mv1_mv2.max() > run.gap_sym_mv2.max()
    assert run.largest()["sym_mv2"] == run.gap_sym_mv2.max()
    assert run.k.shape == (steps,) and run.window_k[-1] == steps


def test_mv_algorithm2_invariants_drift_by_rounding_only():
    steps = 5000
    run = X.invariant_drift(steps=steps, save_every=10, windows=10)
    # less than one float64 rounding unit per step, for every invariant
    assert max(run.max_drift.values()) < steps * EPS
    assert run.k[-1] == steps and run.window_k[-1] == steps
    for key, series in run.drift.items():
        assert series[0] == 0 or key == "orthogonality"
        assert run.window[key].max() == series[1:].max()


def test_discrete_flow_is_second_order():
    run = X.second_order()
    # halving h divides the error of a second-order method by 2^2
    assert np.all(np.abs(run.ratio_Q - 4) < 0.1) and np.all(np.abs(run.ratio_M - 4) < 0.1)
    assert run.error_M[0] > 1e-4  # the errors are discretisation errors, far above rounding


def test_solver_accuracy_meets_its_documented_tolerance():
    run = X.solver_accuracy(sizes=(2, 3, 5, 8, 20))
    # the solver's tolerance: ||J_D(U) - M||_F <= 10 eps ||M||_F
    assert run.residual.max() <= 10
    assert np.all(run.orthogonality <= 10 * run.n)
    assert np.all(np.abs(run.det_error) < 100 * run.n * EPS)
    assert np.all(run.margin > 0)
    for nn in np.unique(run.n):
        margins = run.margin[run.n == nn]
        assert margins[-1] < margins[0]  # the margin closes towards the fold


def test_fold_approach_has_the_square_root_law():
    run = X.fold_approach()
    # at a fold the branch closes like the square root of the distance
    assert run.exponent == pytest.approx(0.5, abs=0.02)
    near = run.distance < 1e-5
    slope = np.polyfit(np.log(run.distance[near]), np.log(run.sigma_min[near]), 1)[0]
    assert slope == pytest.approx(0.5, abs=0.02)
    assert run.residual.max() <= 10 and run.iterations.max() <= 4
    assert "past the fold" in run.past_fold


def test_solver_cost_records_cpu_time_per_repeat():
    run = X.solver_cost(sizes=(3, 50), repeats=3, inner=2)
    assert run.cold_ms.shape == run.warm_ms.shape == (2, 3)
    assert np.all(run.cold_ms > 0) and np.all(run.warm_ms > 0)
    assert np.all(run.cold_ms.min(axis=1) <= run.cold_median)
    assert np.all(run.cold_median <= run.cold_ms.max(axis=1))
    assert run.cold_median[1] > run.cold_median[0]  # an O(n^3) solve: n = 50 costs more
    assert run.pinned  # threadpoolctl comes with the test extra


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: X.manakov_drift(t_end=-1.0), "t_end"),
        (lambda: X.manakov_drift(samples=1), "samples"),
        (lambda: X.time_step_scaling(halvings=1), "halvings"),
        (lambda: X.layer_jacobian(scales=[0.0, 1.0]), "scales"),
        (lambda: X.train_toy_classifier(lr=0.0), "lr"),
        (lambda: X.algorithm_agreement(lam=(1.0, 2.0)), "lam"),
        (lambda: X.second_order(hs=(0.3, 0.1), T=1.0), "divide"),
        (lambda: X.solver_accuracy(fractions=(1.5,)), "fractions"),
        (lambda: X.fold_approach(distances=[0.5]), "distances"),
        (lambda: X.solver_cost(repeats=0), "repeats"),
    ],
)
def test_bad_arguments_are_named(call, match):
    with pytest.raises(InputError, match=match):
        call()
