"""so(n), SO(n) and the inertia operators: properties on random and hypothesis-drawn data."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import symrb

finite = st.floats(-10, 10, allow_nan=False, allow_infinity=False)
vec3 = arrays(np.float64, (3,), elements=finite)


@given(vec3, vec3)
def test_hat_is_cross_and_pairing_is_dot(u: np.ndarray, w: np.ndarray) -> None:
    np.testing.assert_allclose(symrb.hat(u) @ w, np.cross(u, w), atol=1e-12)
    assert symrb.pairing(symrb.hat(u), symrb.hat(w)) == pytest.approx(u @ w, abs=1e-10)
    np.testing.assert_array_equal(symrb.vee(symrb.hat(u)), u)


@given(st.integers(2, 8), st.integers(0, 2**32 - 1))
def test_J_inverse_and_symmetry(n: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    lam = rng.uniform(0.1, 3.0, n)
    a, b = symrb.random_so(n, (2,), seed=rng)
    np.testing.assert_allclose(symrb.J_inv(symrb.J(a, lam), lam), a, rtol=1e-12, atol=1e-12)
    # J is symmetric for the pairing and positive definite
    assert symrb.pairing(symrb.J(a, lam), b) == pytest.approx(
        symrb.pairing(a, symrb.J(b, lam)), rel=1e-10, abs=1e-10
    )
    assert symrb.pairing(a, symrb.J(a, lam)) > 0


def test_J_positive_definite_only_when_pair_sums_positive() -> None:
    lam = np.array([-0.5, 1.0, 2.0])  # lam_1 + lam_j > 0 for all j != 1: still positive definite
    a = symrb.random_so(3, seed=1)
    assert symrb.pairing(a, symrb.J(a, lam)) > 0
    with pytest.raises(symrb.InputError, match=r"min lam_i \+ lam_j = -0.5"):
        symrb.J(a, np.array([-1.5, 1.0, 2.0]))


def test_J_D_derivative_at_identity_is_J(rng: np.random.Generator) -> None:
    from scipy.linalg import expm

    n = 5
    lam = rng.uniform(0.5, 2.0, n)
    Om = symrb.random_so(n, seed=rng)
    eps = 1e-6
    fd = (symrb.algebra.J_D(expm(eps * Om), lam) - symrb.algebra.J_D(expm(-eps * Om), lam)) / (
        2 * eps
    )
    np.testing.assert_allclose(fd, symrb.J(Om, lam), rtol=1e-8, atol=1e-8)


def test_moments_of_inertia_roundtrip(rng: np.random.Generator) -> None:
    lam = rng.uniform(0.5, 2.0, (4, 3))
    I_ = symrb.algebra.inertia_from_lam(lam)
    np.testing.assert_allclose(I_[..., 0], lam[..., 1] + lam[..., 2])
    np.testing.assert_allclose(symrb.algebra.lam_from_inertia(I_), lam)


def test_random_SO_is_special_orthogonal() -> None:
    Q = symrb.random_SO(6, (3, 2), seed=7)
    assert Q.shape == (3, 2, 6, 6)
    np.testing.assert_allclose(
        np.swapaxes(Q, -1, -2) @ Q, np.broadcast_to(np.eye(6), Q.shape), atol=1e-13
    )
    np.testing.assert_allclose(np.linalg.det(Q), 1.0)
    np.testing.assert_array_equal(symrb.random_SO(6, seed=7), symrb.random_SO(6, seed=7))


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: symrb.hat(np.ones(4)), r"v must have shape \(\.\.\., 3\)"),
        (lambda: symrb.vee(np.ones((3, 3))), "m must be skew"),
        (lambda: symrb.J(np.zeros((3, 3)), np.ones(4)), "Omega must be 4 x 4"),
        (lambda: symrb.J_inv(np.ones((2, 3)), np.ones(3)), r"M must have shape \(\.\.\., n, n\)"),
        (lambda: symrb.random_so(1), "n must be >= 2"),
        (lambda: symrb.pairing(np.ones((2, 2)), [[np.inf, 0], [0, 0]]), "eta must be finite"),
    ],
)
def test_clear_errors(call, match: str) -> None:
    with pytest.raises(symrb.InputError, match=match):
        call()
