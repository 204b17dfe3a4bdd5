"""symrb.toda_flow: the Toda lattice as the double bracket flow L' = -[L, [L, D]] (claim S14),
against Flaschka's equations for (a, b) and against the double bracket flow x' = [x, [x, N]] of
x = iL, N = iD, each integrated independently here with SciPy."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import symrb
from symrb.errors import InputError

K = 5
RNG = np.random.default_rng(11)
A0, B0 = RNG.standard_normal(K), RNG.uniform(0.3, 1.0, K - 1)
TS = np.linspace(0.0, 3.0, 13)
TIGHT = {"method": "DOP853", "rtol": 1e-12, "atol": 1e-13}


def _band(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.diag(a) + np.diag(b, 1) + np.diag(b, -1)


def test_toda_flow_is_flaschkas_toda_lattice() -> None:
    """a_i' = 2 (b_i^2 - b_{i-1}^2), b_i' = b_i (a_{i+1} - a_i), b_0 = b_k = 0, integrated on
    (a, b) alone: a flow with the other sign, another D or a wrong field differs at O(1)."""

    def flaschka(_t: float, y: np.ndarray) -> np.ndarray:
        a, b = y[:K], y[K:]
        bb = np.concatenate([[0.0], b, [0.0]])
        return np.concatenate([2 * (bb[1:] ** 2 - bb[:-1] ** 2), b * (a[1:] - a[:-1])])

    ref = solve_ivp(flaschka, (0.0, TS[-1]), np.concatenate([A0, B0]), t_eval=TS, **TIGHT)
    L = symrb.toda_flow(A0, B0, TS)
    assert L.shape == (TS.size, K, K)
    np.testing.assert_allclose(np.diagonal(L, axis1=1, axis2=2), ref.y[:K].T, rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.diagonal(L, 1, axis1=1, axis2=2), ref.y[K:].T, rtol=0,
                               atol=1e-9)  # fmt: skip
    np.testing.assert_allclose(np.diagonal(L, -1, axis1=1, axis2=2), ref.y[K:].T, rtol=0,
                               atol=1e-9)  # fmt: skip
    off = np.abs(np.subtract.outer(np.arange(K), np.arange(K))) >= 2
    assert np.abs(L[:, off]).max() < 1e-12  # stays tridiagonal


def test_toda_flow_is_the_double_bracket_flow_of_x_equal_iL() -> None:
    """Claim S14's statement: with x = iL in su(k) and N = iD the double bracket flow
    x' = [x, [x, N]] (integrated here on complex matrices with NumPy) is L(t) = -i x(t)."""
    N = 1j * np.diag(np.arange(1.0, K + 1))

    def field(_t: float, y: np.ndarray) -> np.ndarray:
        x = y.reshape(K, K)
        c = N @ x - x @ N  # [N, x] = -[x, N]
        return (c @ x - x @ c).ravel()  # [x, [x, N]] = [[N, x], x]

    x0 = 1j * _band(A0, B0)
    ref = solve_ivp(field, (0.0, TS[-1]), x0.ravel(), t_eval=TS, **TIGHT)
    L_ref = -1j * ref.y.T.reshape(-1, K, K)
    assert np.abs(L_ref.imag).max() < 1e-12
    np.testing.assert_allclose(symrb.toda_flow(A0, B0, TS), L_ref.real, rtol=0, atol=1e-9)


def test_toda_flow_sorts_the_diagonal_to_the_spectrum() -> None:
    L = symrb.toda_flow(A0, B0, [0.0, 60.0])
    eig = np.linalg.eigvalsh(_band(A0, B0))[::-1]
    np.testing.assert_allclose(np.linalg.eigvalsh(L[-1])[::-1], eig, rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.diagonal(L[-1]), eig, rtol=0, atol=1e-7)  # largest first
    np.testing.assert_array_equal(L[0], _band(A0, B0))


def test_toda_flow_at_time_zero_only_and_tolerances() -> None:
    np.testing.assert_array_equal(symrb.toda_flow(A0, B0, [0.0]), _band(A0, B0)[None])
    loose = symrb.toda_flow(A0, B0, TS, rtol=1e-6, atol=1e-8)
    tight = symrb.toda_flow(A0, B0, TS)
    assert 0 < np.abs(loose - tight).max() < 1e-4  # the tolerances reach solve_ivp
    # atol alone: with rtol tight, an absolute tolerance of 1e-6 moves L (measured ~4e-7)
    loose_atol = symrb.toda_flow(A0, B0, TS, atol=1e-6)
    assert 0 < np.abs(loose_atol - tight).max() < 1e-4


@pytest.mark.parametrize(
    ("a0", "b0", "t", "match"),
    [
        ([1.0], [], [1.0], "k >= 2"),
        (np.ones((2, 2)), [1.0], [1.0], "shape"),
        ([1.0, 2.0, 3.0], [1.0], [1.0], r"\(k - 1,\)"),
        ([1.0, 2.0], [1.0], [1.0, 0.5], "increasing"),
        ([1.0, 2.0], [1.0], [-1.0, 1.0], ">= 0"),
        ([1.0, np.nan], [1.0], [1.0], "finite"),
        ([1.0, 1j], [1.0], [1.0], "real"),
    ],
)
def test_toda_flow_rejects_bad_input(a0, b0, t, match) -> None:
    with pytest.raises(InputError, match=match):
        symrb.toda_flow(a0, b0, t)


def test_toda_flow_does_not_mutate_its_arguments() -> None:
    a0, b0, t = A0.copy(), B0.copy(), TS.copy()
    symrb.toda_flow(a0, b0, t)
    np.testing.assert_array_equal(a0, A0)
    np.testing.assert_array_equal(b0, B0)
    np.testing.assert_array_equal(t, TS)
