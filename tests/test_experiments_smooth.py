"""The experiments of the Section 3 pages (symrb.experiments.smooth), asserted on as the pages
show them.  Each tolerance is stated against a reference: an exact value (a conserved quantity,
zero for two descriptions of one motion), a closed form, or the integrator's tolerance."""

from __future__ import annotations

import numpy as np
import pytest

from symrb.errors import InputError
from symrb.experiments import smooth

EPS = np.finfo(float).eps


def test_window_max_by_hand() -> None:
    t = np.arange(9.0)
    values = np.array([[1, 7, 2, 0, 3, 4, 9, 1, 5], [0, 0, 0, 0, 0, 0, 0, 0, -1]], dtype=float)
    edges, top = smooth.window_max(t, values, 3)
    np.testing.assert_array_equal(edges, [0, 8 / 3, 16 / 3, 8])
    # windows [0, 8/3): t = 0, 1, 2;  [8/3, 16/3): t = 3, 4, 5;  [16/3, 8]: t = 6, 7, 8
    np.testing.assert_array_equal(top, [[7, 4, 9], [0, 0, 0]])


def test_window_max_skips_nan_and_empty_windows() -> None:
    edges, top = smooth.window_max([0.0, 1.0, 10.0], [np.nan, 2.0, 3.0], 4)
    assert edges[-1] == 10.0
    np.testing.assert_array_equal(top, [2.0, np.nan, np.nan, 3.0])


@pytest.mark.parametrize(
    "t, values, windows, word",
    [([0.0, 1.0], [1.0, 2.0], 0, "windows"), ([1.0, 0.0], [1.0, 2.0], 1, "t must"),
     ([0.0, 1.0], [1.0, 2.0, 3.0], 1, "values")],
)  # fmt: skip
def test_window_max_rejects_bad_input(t: list, values: list, windows: int, word: str) -> None:
    with pytest.raises(InputError, match=word):
        smooth.window_max(t, values, windows)


def test_flow_agreement_follows_the_tolerance() -> None:
    run = smooth.flow_agreement(T=10.0, samples=101, windows=5)
    worst = run.difference.max(axis=1)
    # the two flows describe one motion: the difference is integration error, which the global
    # error of DOP853 keeps within a modest multiple of the tolerance on [0, 10]
    assert np.all(worst <= 100 * run.tolerances), worst / run.tolerances
    assert np.all(worst[1:] < worst[:-1] / 100)  # tolerances 1000 times apart
    np.testing.assert_array_equal(np.nanmax(run.difference_max, axis=1), worst)
    assert np.all(run.nfev_symmetric > 0) and np.all(np.diff(run.nfev_symmetric) > 0)


def test_mclachlan_scovel_map() -> None:
    run = smooth.mclachlan_scovel_map(T=10.0, samples=51)
    assert run.skew_defect.max() < 1e-12  # Q^T B stays skew: exactly, up to rounding
    assert run.gap.max() < 1e-9  # rtol 1e-12 over t <= 10


def test_shared_control_is_the_rigid_body_velocity() -> None:
    run = smooth.shared_control(T=5.0)
    assert run.gap.max() < 1e-9


def test_momentum_norms_bound_and_distribution() -> None:
    run = smooth.momentum_norms(count=4000)
    assert run.norms.max() <= 2 + 1e-12
    # n = 3: Q^T P is a Haar rotation, its angle has the density (1 - cos a)/pi on [0, pi] and
    # ||M||_op = 2 |sin a|, of mean 4/pi and variance 2 - 16/pi^2
    n3 = run.norms[run.sizes.index(3)]
    mean, sd = 4 / np.pi, np.sqrt(2 - 16 / np.pi**2)
    assert abs(n3.mean() - mean) < 4 * sd / np.sqrt(n3.size)
    assert n3.max() > 1.99  # the bound 2 is approached


def test_rotation_angles_are_arcsin() -> None:
    theta = np.linspace(0.0, 3.0, 61)
    run = smooth.rotation_angles(theta)
    np.testing.assert_array_equal(run.refused, theta >= 2)
    inside = theta < 2
    np.testing.assert_allclose(
        run.angle[inside], np.arcsin(theta[inside] / 2), rtol=0, atol=4 * EPS
    )
    assert np.all(np.isnan(run.angle[~inside]))
    with pytest.raises(InputError, match="theta"):
        smooth.rotation_angles([-1.0])


def test_boundary_accuracy_is_as_conditioned() -> None:
    run = smooth.boundary_accuracy([1e-1, 1e-4, 1e-8, 1e-12, 1e-15], n=5)
    assert run.residual.max() < 5e-15 and run.orthogonality.max() < 5e-15
    # the forward error is set by the conditioning of the problem, eps / sqrt(delta)
    assert np.all(run.forward_error <= 10 * run.eps_over_sqrt_delta), run.forward_error
    assert run.forward_error[-1] > 100 * run.forward_error[0]  # and does grow near the boundary


def test_norm_conservation() -> None:
    run = smooth.norm_conservation(T=10.0, windows=5)
    np.testing.assert_allclose(run.initial_norms, [0.5, 1.5, 1.99, 2.0], rtol=0, atol=1e-12)
    assert run.deviation.max() < 1e-9  # conserved exactly by the flow; rtol 1e-12


def test_hamiltonian_drift() -> None:
    run = smooth.hamiltonian_drift(T=20.0, windows=4)
    assert set(run.series) == {"orthogonality", "H on SO", "H on gl", "spectrum on gl"}
    for name, series in run.series.items():
        assert series[0] == 0.0 or name == "orthogonality"  # drifts start at 0
        assert series.max() < 1e-9, name  # all conserved exactly by the flow; rtol 1e-12
        np.testing.assert_array_equal(np.nanmax(run.series_max[name]), series.max())


def test_toda_lattice_sorts_to_the_spectrum() -> None:
    run = smooth.toda_lattice(T=12.0)  # as on the page
    assert run.spectrum_drift < 1e-8  # isospectral (rtol 1e-10)
    assert run.off_band < 1e-8  # stays tridiagonal, up to the integration error
    assert np.all(np.diff(run.eigenvalues) < 0)
    # the off-diagonal decays like exp(-(gap of the spectrum) t): at t = 30 the diagonal is the
    # spectrum, sorted in decreasing order
    late = smooth.toda_lattice(T=30.0)
    np.testing.assert_allclose(late.a[-1], late.eigenvalues, rtol=0, atol=1e-9)
    assert np.abs(late.b[-1]).max() < 1e-5 < np.abs(late.b[0]).min()


def test_one_sample_learning_against_the_closed_form() -> None:
    run = smooth.one_sample_learning(T=8.0)
    r, phi0, rate = 0.5, 2.0, 0.5  # the defaults: ||x0|| = 0.5, angle 2 from -N, ||N|| = 1
    phi = 2 * np.arctan(np.tan(phi0 / 2) * np.exp(-rate * run.t))
    psi = 2 * np.arctan(np.tan((np.pi - phi0) / 2) * np.exp(-rate * run.t))
    # corrected p_T = -N: the double bracket flow, <x, N> = -r cos(phi) decreases
    np.testing.assert_allclose(run.cost_corrected, -r * np.cos(phi), rtol=0, atol=1e-6)
    np.testing.assert_allclose(run.second_corrected, r * np.sin(phi), rtol=0, atol=1e-6)
    np.testing.assert_allclose(run.second_exact, r * np.sin(phi), rtol=0, atol=1e-15)
    # printed p_T = +N: the reversed flow, x turns towards +N, <x, N> = r cos(psi) increases
    np.testing.assert_allclose(run.cost_printed, r * np.cos(psi), rtol=0, atol=1e-6)
    assert run.costate_deviation < 1e-8 and run.flow_deviation < 1e-6
    assert run.rate == rate


def test_two_sample_learning_stays_above_the_bound() -> None:
    run = smooth.two_sample_learning(T=8.0)
    larger = run.second_shared.max(axis=0)
    assert np.all(larger > run.bound)  # for every t, not only at T
    assert run.pairing_drift < 1e-6  # conserved by the shared control (BVP tolerance 1e-5)
    assert run.deviation.max() > 0.5  # neither sample follows its own double bracket flow ...
    assert run.second_own[:, -1].max() < 1e-5 < run.bound  # ... which would reach zero
