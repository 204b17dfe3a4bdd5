"""Tests of symrb.solvers: the Moser-Veselov equation U Lam - Lam U^T = M on the identity branch."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symrb import (
    InputError,
    NotConvergedError,
    OutOfDomainError,
    fold_scale,
    random_SO,
    random_so,
    solve_moser_veselov,
)
from symrb.algebra import random_lam

EPS = np.finfo(float).eps


def _jd(U, lam):
    return U * lam[..., None, :] - lam[..., :, None] * np.swapaxes(U, -1, -2)


def _check_solution(U, M, lam):
    nn = lam.shape[-1]
    res = np.linalg.norm(_jd(U, lam) - M, axis=(-2, -1))
    assert np.all(res <= 10 * EPS * np.linalg.norm(M, axis=(-2, -1)))
    orth = np.linalg.norm(np.swapaxes(U, -1, -2) @ U - np.eye(nn), axis=(-2, -1))
    assert np.all(orth <= 10 * nn * EPS)
    assert np.allclose(np.linalg.det(U), 1.0, atol=100 * nn * EPS)
    # on the branch through the identity: every eigenvalue of U Lam in the right half-plane
    assert np.all(np.linalg.eigvals(U * lam[..., None, :]).real.min(axis=-1) > 0)


@pytest.mark.parametrize("nn", [2, 3, 4, 5, 8, 13, 21, 34, 50])
def test_random_inside(nn):
    rng = np.random.default_rng(nn)
    lam = random_lam(nn, seed=rng)
    M = random_so(nn, seed=rng)
    t = fold_scale(M, lam)
    for frac in (1e-6, 0.3, 0.9):
        Mf = frac * t * M
        U, info = solve_moser_veselov(Mf, lam, return_info=True)
        _check_solution(U, Mf, lam)
        assert info.residual <= info.tol
        assert info.margin > 0
        assert info.iterations <= 5


@pytest.mark.parametrize("nn", [2, 3, 4, 7, 12])
def test_within_a_tenth_of_a_percent_of_the_fold(nn):
    rng = np.random.default_rng(100 + nn)
    lam = random_lam(nn, seed=rng)
    M = random_so(nn, seed=rng)
    t = fold_scale(M, lam)
    inside = (1 - 1e-3) * t * M
    U = solve_moser_veselov(inside, lam)
    _check_solution(U, inside, lam)
    outside = (1 + 1e-3) * t * M
    with pytest.raises(OutOfDomainError, match="past the fold") as exc:
        solve_moser_veselov(outside, lam)
    msg = str(exc.value)
    assert "||M||_F" in msg and "lam = " in msg and "0.1 % past the fold" in msg


def test_fold_scale_n2_closed_form():
    lam = np.array([0.4, 1.7])
    for m in (0.1, 1.0, 5.0):
        M = np.array([[0.0, -m], [m, 0.0]])
        assert fold_scale(M, lam) == pytest.approx(lam.sum() / m, rel=1e-12)
    assert fold_scale(np.zeros((2, 2)), lam) == np.inf


def test_fold_is_where_the_branch_ends():
    rng = np.random.default_rng(3)
    lam = random_lam(4, seed=rng)
    M = random_so(4, seed=rng)
    t = fold_scale(M, lam)
    margins = [
        solve_moser_veselov(f * t * M, lam, return_info=True)[1].margin for f in (0.9, 0.99, 0.999)
    ]
    # the margin min Re eig(U Lam) closes like sqrt(distance to the fold)
    assert margins[0] > margins[1] > margins[2] > 0
    assert margins[1] / margins[2] == pytest.approx(np.sqrt(10), rel=0.05)


def test_zero_gives_identity():
    lam = np.array([0.5, 1.0, 2.0])
    U, info = solve_moser_veselov(np.zeros((3, 3)), lam, return_info=True)
    assert np.array_equal(U, np.eye(3))
    assert info.residual == 0.0


def test_batch_equals_loop_and_broadcasts():
    rng = np.random.default_rng(4)
    lam = random_lam(5, seed=rng)
    M = random_so(5, size=(3, 2), seed=rng, scale=0.2)
    U = solve_moser_veselov(M, lam)
    assert U.shape == (3, 2, 5, 5)
    for i in range(3):
        for j in range(2):
            assert np.allclose(U[i, j], solve_moser_veselov(M[i, j], lam), atol=1e-14)
    lams = np.stack([lam, 1.5 * lam])
    U2 = solve_moser_veselov(M[0, 0], lams)
    assert U2.shape == (2, 5, 5)
    assert np.allclose(U2[1], solve_moser_veselov(M[0, 0], 1.5 * lam), atol=1e-14)


def test_warm_start_and_wrong_branch_start():
    rng = np.random.default_rng(5)
    lam = random_lam(4, seed=rng)
    M = random_so(4, seed=rng, scale=0.3)
    U = solve_moser_veselov(M, lam)
    Uw, info = solve_moser_veselov(M, lam, U0=U, return_info=True)
    assert info.start == "warm" and np.allclose(Uw, U, atol=1e-14)
    # a start far from the branch: the result is still the branch solution
    far = random_SO(4, seed=rng)
    Uf = solve_moser_veselov(M, lam, U0=far)
    assert np.allclose(Uf, U, atol=1e-12)


def test_not_converged_carries_residual():
    # tol = 0 asks for an exactly zero residual; for n = 3 one Newton step sometimes gets there
    # (all nine entries rounding to 0), for n = 8 (64 entries) it does not
    rng = np.random.default_rng(6)
    lam = random_lam(8, seed=rng)
    M = random_so(8, seed=rng)
    M = 0.5 * fold_scale(M, lam) * M
    with pytest.raises(NotConvergedError) as exc:
        solve_moser_veselov(M, lam, tol=0.0, maxiter=1)
    assert exc.value.iterations >= 1 and exc.value.residual > 0


def test_input_validation_and_no_mutation():
    lam = np.array([0.5, 1.0, 2.0])
    M = random_so(3, seed=0, scale=0.2)
    M0, lam0 = M.copy(), lam.copy()
    solve_moser_veselov(M, lam)
    assert np.array_equal(M, M0) and np.array_equal(lam, lam0)
    with pytest.raises(InputError, match="M must be skew"):
        solve_moser_veselov(M + np.eye(3), lam)
    with pytest.raises(InputError, match="lam must be positive"):
        solve_moser_veselov(M, np.array([0.5, -1.0, 2.0]))
    with pytest.raises(InputError, match="finite"):
        solve_moser_veselov(M * np.nan, lam)
    with pytest.raises(InputError, match="3 x 3"):
        solve_moser_veselov(random_so(4, seed=0), lam)
    with pytest.raises(InputError, match="tol"):
        solve_moser_veselov(M, lam, tol=-1.0)
    with pytest.raises(InputError, match="maxiter"):
        solve_moser_veselov(M, lam, maxiter=0)
    with pytest.raises(InputError, match="U0 must be orthogonal"):
        solve_moser_veselov(M, lam, U0=2 * np.eye(3))


@settings(max_examples=25, deadline=None)
@given(
    nn=st.integers(2, 6),
    seed=st.integers(0, 2**31 - 1),
    frac=st.floats(0.01, 0.99),
    signs=st.lists(st.sampled_from([-1.0, 1.0]), min_size=6, max_size=6),
    c=st.floats(0.1, 10.0),
)
def test_properties(nn, seed, frac, signs, c):
    rng = np.random.default_rng(seed)
    lam = random_lam(nn, seed=rng)
    M = random_so(nn, seed=rng)
    M = frac * fold_scale(M, lam) * M
    U = solve_moser_veselov(M, lam)
    _check_solution(U, M, lam)
    # sign symmetry: D = diag(+-1) commutes with Lambda, so J_D(D U D) = D M D
    D = np.diag(signs[:nn])
    assert np.allclose(solve_moser_veselov(D @ M @ D, lam), D @ U @ D, atol=1e-11)
    # scaling: J_D for c Lambda is c J_D
    assert np.allclose(solve_moser_veselov(c * M, c * lam), U, atol=1e-11)
