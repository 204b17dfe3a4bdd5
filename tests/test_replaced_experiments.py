"""Tests of the two replaced experiments that the scene tests compare against
(``tests/replaced_experiments.py``): the agreement of the three discrete rigid-body algorithms,
the conservation of the momentum's operator norm, and the maximum per window both summarise with.
"""

from __future__ import annotations

import numpy as np
import pytest
import replaced_experiments as R

from symrb.errors import InputError

EPS = np.finfo(float).eps


def test_three_algorithms_agree_to_rounding():
    """The symmetric representation, MV-Algorithm 2 and MV-Algorithm 1 give the same Q_k (page
    "The Moser-Veselov equations", which runs 10^4 steps; here 10^3)."""
    steps = 1000
    run = R.algorithm_agreement(steps=steps, windows=10)
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


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: R.algorithm_agreement(lam=(1.0, 2.0)), "lam"),
    ],
)
def test_bad_arguments_are_named(call, match):
    with pytest.raises(InputError, match=match):
        call()


def test_window_max_by_hand() -> None:
    t = np.arange(9.0)
    values = np.array([[1, 7, 2, 0, 3, 4, 9, 1, 5], [0, 0, 0, 0, 0, 0, 0, 0, -1]], dtype=float)
    edges, top = R.window_max(t, values, 3)
    np.testing.assert_array_equal(edges, [0, 8 / 3, 16 / 3, 8])
    # windows [0, 8/3): t = 0, 1, 2;  [8/3, 16/3): t = 3, 4, 5;  [16/3, 8]: t = 6, 7, 8
    np.testing.assert_array_equal(top, [[7, 4, 9], [0, 0, 0]])


def test_window_max_skips_nan_and_empty_windows() -> None:
    edges, top = R.window_max([0.0, 1.0, 10.0], [np.nan, 2.0, 3.0], 4)
    assert edges[-1] == 10.0
    np.testing.assert_array_equal(top, [2.0, np.nan, np.nan, 3.0])


@pytest.mark.parametrize(
    "t, values, windows, word",
    [([0.0, 1.0], [1.0, 2.0], 0, "windows"), ([1.0, 0.0], [1.0, 2.0], 1, "t must"),
     ([0.0, 1.0], [1.0, 2.0, 3.0], 1, "values")],
)  # fmt: skip
def test_window_max_rejects_bad_input(t: list, values: list, windows: int, word: str) -> None:
    with pytest.raises(InputError, match=word):
        R.window_max(t, values, windows)


def test_norm_conservation() -> None:
    run = R.norm_conservation(T=10.0, windows=5)
    np.testing.assert_allclose(run.initial_norms, [0.5, 1.5, 1.99, 2.0], rtol=0, atol=1e-12)
    assert run.deviation.max() < 1e-9  # conserved exactly by the flow; rtol 1e-12
