"""symrb.exact.rigid_body_exact against independent solutions: DOP853 at rtol 1e-13
(symrb.integrate), the ODE residual of the exact curve by finite differences, steady rotations
by the matrix exponential (scipy.linalg.expm), conservation laws; batches, validation,
hypothesis properties."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.linalg import expm

import symrb
from symrb.errors import InputError
from symrb.exact import rigid_body_exact

TIGHT = dict(method="DOP853", rtol=1e-13, atol=1e-13)


def _random_case(seed: int, batch: tuple[int, ...] = ()):
    """lam with positive entries in [0.4, 2], |m| = 1, Q uniform on SO(3)."""
    rng = np.random.default_rng(seed)
    lam = rng.uniform(0.4, 2.0, batch + (3,))
    m = rng.standard_normal(batch + (3,))
    m /= np.linalg.norm(m, axis=-1, keepdims=True)
    Q0 = symrb.random_SO(3, batch, seed=rng)
    return Q0, symrb.hat(m), lam


def _dop853(Q0, M0, lam, t):
    t = np.asarray(t, dtype=float)
    sol = symrb.integrate(
        symrb.RigidBody, (0.0, float(t[-1])), {"Q": Q0, "M": M0}, lam=lam, t_eval=t, **TIGHT
    )
    assert sol.success
    return sol


def _errors(sol, ref, M0):
    """max |M - M_ref| / |M0| and max |Q - Q_ref| over times (per batch item)."""
    scale = np.abs(M0).max(axis=(-2, -1))
    eM = np.abs(sol.y.M - ref.y.M).max(axis=(0, -2, -1)) / scale
    eQ = np.abs(sol.y.Q - ref.y.Q).max(axis=(0, -2, -1))
    return eM, eQ


# ---------------------------------------------------------------------------------------------
# against DOP853 at rtol 1e-13 (an independent integration of the same equations)


def test_against_dop853_both_elliptic_cases() -> None:
    Q0, M0, lam = _random_case(7, (10,))
    t = np.linspace(0.0, 100.0, 41)
    sol = rigid_body_exact(Q0, M0, lam, t)
    ref = _dop853(Q0, M0, lam, t)
    inertia = symrb.algebra.inertia_from_lam(lam)
    # both cases occur: m circles the largest and the smallest principal axis
    assert np.any(sol.axis == np.argmax(inertia, -1))
    assert np.any(sol.axis == np.argmin(inertia, -1))
    assert np.all((sol.k2 > 0) & (sol.k2 < 1)) and np.all(sol.nu > 0)
    eM, eQ = _errors(sol, ref, M0)
    assert eM.max() <= 1e-11, eM
    assert eQ.max() <= 1e-11, eQ


@pytest.mark.parametrize(
    "name, m, lam",
    [
        ("symmetric lam1 = lam2", [0.5, 1.0, 1.5], [0.8, 0.8, 1.5]),
        ("symmetric lam2 = lam3", [0.5, 1.0, 1.5], [0.3, 0.8, 0.8]),
        ("symmetric lam1 = lam3", [0.5, 1.0, 1.5], [0.8, 1.5, 0.8]),
        ("nearly symmetric", [0.5, 1.0, 1.5], [0.8, 0.8 + 1e-9, 1.5]),
        ("symmetric, m nearly in the equal plane", [0.5, 1.0, 1e-6], [0.8, 0.8, 1.5]),
        ("near the largest axis", [1e-7, -2e-7, 1.3], [0.7, 1.1, 1.6]),
        ("near the smallest axis", [1.3, 1e-7, -2e-7], [0.7, 1.1, 1.6]),
        ("negative lam_1 (J still positive)", [0.5, 1.0, 1.5], [-0.2, 1.1, 1.6]),
        ("large momentum", [5.0, -3.0, 2.0], [0.7, 1.1, 1.6]),
    ],
)
def test_against_dop853_special_cases(name, m, lam) -> None:
    Q0 = symrb.random_SO(3, seed=11)
    M0 = symrb.hat(m)
    t = np.linspace(0.0, 20.0, 21)
    sol = rigid_body_exact(Q0, M0, lam, t)
    eM, eQ = _errors(sol, _dop853(Q0, M0, lam, t), M0)
    assert eM <= 1e-11 and eQ <= 1e-11, (name, eM, eQ)


def _separatrix_momentum(lam, s1: float, s3: float) -> np.ndarray:
    """m with mu^2 = 2 E I_2 exactly in exact arithmetic (I = (2.7, 2.3, 1.8) for lam below)."""
    I1, I2, I3 = symrb.algebra.inertia_from_lam(np.asarray(lam))
    a = 0.7
    return np.array([s1 * a, 0.3, s3 * a * np.sqrt((I1 - I2) / I1 * I3 / (I2 - I3))])


@pytest.mark.parametrize("s1, s3", [(1, 1), (-1, 1), (1, -1), (-1, -1)])
def test_separatrix(s1, s3) -> None:
    lam = np.array([0.7, 1.1, 1.6])
    M0 = symrb.hat(_separatrix_momentum(lam, s1, s3))
    Q0 = symrb.random_SO(3, seed=2)
    t = np.linspace(0.0, 20.0, 21)
    sol = rigid_body_exact(Q0, M0, lam, t)
    assert sol.k2 > 1 - 1e-12
    eM, eQ = _errors(sol, _dop853(Q0, M0, lam, t), M0)
    assert eM <= 1e-11 and eQ <= 1e-11


# ---------------------------------------------------------------------------------------------
# steady rotations: M constant and Q = Q0 expm(t Omega0)


@pytest.mark.parametrize(
    "m, lam",
    [
        ([0.0, 0.0, 0.0], [0.7, 1.1, 1.6]),
        ([1.3, 0.0, 0.0], [0.7, 1.1, 1.6]),
        ([0.0, -1.3, 0.0], [0.7, 1.1, 1.6]),  # the saddle (middle axis)
        ([0.0, 0.0, 1.3], [0.7, 1.1, 1.6]),
        ([0.5, 1.0, 1.5], [0.9, 0.9, 0.9]),  # a sphere
        ([0.5, 1.0, 0.0], [0.8, 0.8, 1.5]),  # in the eigenplane of a symmetric body
    ],
)
def test_steady_rotations(m, lam) -> None:
    Q0 = symrb.random_SO(3, seed=4)
    M0 = symrb.hat(m)
    t = np.array([0.0, 0.7, 13.0, -5.0])
    sol = rigid_body_exact(Q0, M0, lam, t)
    Om0 = symrb.J_inv(M0, lam)
    assert np.all(sol.axis == -1) and sol.nu == 0
    np.testing.assert_array_equal(sol.y.M, np.broadcast_to(M0, (4, 3, 3)))
    want = np.stack([Q0 @ expm(s * Om0) for s in t])
    np.testing.assert_allclose(sol.y.Q, want, atol=1e-13, rtol=0)


def test_near_steady_is_continuous() -> None:
    """Momenta 1e-9 off a stable principal axis follow the steady rotation to 1e-8."""
    lam = np.array([0.7, 1.1, 1.6])
    Q0 = symrb.random_SO(3, seed=5)
    t = np.linspace(0.0, 30.0, 7)
    for m in ([1.3, 1e-9, 0.0], [1e-9, 0.0, 1.3], [1e-9, -1e-9, -1.3]):
        near = rigid_body_exact(Q0, symrb.hat(m), lam, t)
        steady = rigid_body_exact(Q0, symrb.hat(np.round(m, 6)), lam, t)
        assert np.all(near.axis >= 0) and np.all(steady.axis == -1)
        np.testing.assert_allclose(near.y.Q, steady.y.Q, atol=1e-8)
        np.testing.assert_allclose(near.y.M, steady.y.M, atol=1e-8)


# ---------------------------------------------------------------------------------------------
# structure: initial data, conservation, batches, times


def test_time_zero_returns_initial_data() -> None:
    Q0, M0, lam = _random_case(3, (6,))
    sol = rigid_body_exact(Q0, M0, lam, 0.0)
    assert sol.t.shape == (1,) and sol.y.Q.shape == (1, 6, 3, 3)
    np.testing.assert_allclose(sol.y.Q[0], Q0, atol=2e-15, rtol=0)
    np.testing.assert_allclose(sol.y.M[0], M0, atol=2e-15, rtol=0)
    np.testing.assert_allclose(sol.y.Omega[0], symrb.J_inv(M0, lam), atol=1e-14, rtol=0)


def test_conservation_over_long_times() -> None:
    """Energy, |m| and the spatial momentum Q m stay at rounding level up to t = 1e4."""
    Q0, M0, lam = _random_case(9, (5,))
    t = np.linspace(0.0, 1e4, 101)
    sol = rigid_body_exact(Q0, M0, lam, t)
    E = symrb.kinetic_energy(sol.y.M, lam)
    c = symrb.casimir_traces(sol.y.M)[..., 0]
    pi = np.einsum("...ij,...j->...i", sol.y.Q, symrb.vee(sol.y.M))
    orth = np.abs(np.swapaxes(sol.y.Q, -1, -2) @ sol.y.Q - np.eye(3)).max()
    assert np.abs(E - E[0]).max() / np.abs(E[0]).max() < 1e-13
    assert np.abs(c - c[0]).max() / np.abs(c[0]).max() < 1e-13
    assert np.abs(pi - pi[0]).max() < 1e-12
    assert orth < 1e-14


def test_batch_equals_loop_and_broadcasts() -> None:
    Q0, M0, lam = _random_case(12, (2, 3))
    lam = lam[0]  # shape (3, 3): a batch of 3 bodies broadcast against (2, 3)
    Qc, Mc, lc = Q0.copy(), M0.copy(), lam.copy()
    t = np.array([0.0, 1.5, 40.0])
    sol = rigid_body_exact(Q0, M0, lam, t)
    assert sol.y.Q.shape == (3, 2, 3, 3, 3) and sol.k2.shape == (2, 3)
    for i in range(2):
        for j in range(3):
            # a batch of one item takes the same (array) route as the batch
            one = rigid_body_exact(Q0[i, j][None], M0[i, j][None], lam[j], t)
            np.testing.assert_allclose(sol.y.Q[:, i, j], one.y.Q[:, 0], atol=1e-15, rtol=0)
            np.testing.assert_allclose(sol.y.M[:, i, j], one.y.M[:, 0], atol=1e-15, rtol=0)
            assert sol.axis[i, j] == one.axis[0]
    assert np.array_equal(Q0, Qc) and np.array_equal(M0, Mc) and np.array_equal(lam, lc)
    single = rigid_body_exact(np.eye(3), M0[0, 0], lam, t)  # Q0 and M0 broadcast against lam
    assert single.y.Q.shape == (3, 3, 3, 3)


@pytest.mark.parametrize("seed", range(40))
def test_scalar_route_equals_array_route(seed: int) -> None:
    """One body and a few times take the float route (_one_body); a batch of one item the
    array route. Both evaluate the same formulas in a different order of operations, so they
    agree to rounding amplified by the phases: |dM|/|M|, |dQ| <= 50 eps (1 + w |t|) with w the
    elliptic rate nu plus the attitude's rate |m|/min I."""
    rng = np.random.default_rng(seed)
    Q0, M0, lam = _random_case(seed)
    M0 = M0 * rng.choice([1e-3, 1.0, 20.0])
    t = rng.uniform(-30, 30, int(rng.integers(1, 5)))
    a = rigid_body_exact(Q0, M0, lam, t)
    b = rigid_body_exact(Q0[None], M0[None], lam, t)
    assert a.y.Q.shape == b.y.Q[:, 0].shape and int(a.axis) == int(b.axis[0])
    rate = (
        float(b.nu[0]) + np.abs(M0).max() * np.sqrt(2) / symrb.algebra.inertia_from_lam(lam).min()
    )
    bound = 50 * np.finfo(float).eps * (1 + rate * np.abs(t).max())
    assert np.abs(a.y.Q - b.y.Q[:, 0]).max() <= bound
    assert np.abs(a.y.M - b.y.M[:, 0]).max() <= bound * np.abs(M0).max()
    np.testing.assert_allclose(float(a.k2), float(b.k2[0]), rtol=1e-13, atol=1e-300)


def test_unchecked_equals_checked() -> None:
    Q0, M0, lam = _random_case(15, (4,))
    t = np.array([0.0, 3.0, 70.0])
    a = rigid_body_exact(Q0, M0, lam, t)
    b = rigid_body_exact(Q0, M0, lam, t, check=False)
    for key in ("Q", "M", "Omega"):
        np.testing.assert_array_equal(a.y[key], b.y[key])
    with pytest.raises(InputError, match="n = 3"):
        rigid_body_exact(np.eye(4), np.zeros((4, 4)), np.ones(4), t, check=False)


def test_negative_and_unsorted_times() -> None:
    """Q(-t) from the exact solution equals DOP853 run backwards."""
    Q0, M0, lam = _random_case(14)
    sol = rigid_body_exact(Q0, M0, lam, [5.0, -10.0, 0.0, -3.0])
    back = symrb.integrate(
        symrb.RigidBody, (0.0, -10.0), {"Q": Q0, "M": M0}, lam=lam, t_eval=[0, -3, -10], **TIGHT
    )
    np.testing.assert_allclose(sol.y.Q[[2, 3, 1]], back.y.Q, atol=1e-11)
    np.testing.assert_allclose(sol.y.M[[2, 3, 1]], back.y.M, atol=1e-11)


# ---------------------------------------------------------------------------------------------
# bad input


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(lam=[0.7, 1.1, 1.6, 2.0]), "n = 3"),
        (dict(Q0=np.eye(4)), "n = 3: Q0 must have shape \\(..., 3, 3\\)"),
        (dict(M0=np.zeros((2, 2))), "M0 must have shape"),
        (dict(Q0=np.diag([1.0, 1.0, -1.0])), "det"),
        (dict(Q0=1.01 * np.eye(3)), "orthogonal"),
        (dict(M0=np.ones((3, 3))), "skew"),
        (dict(lam=[-1.0, -1.0, 1.0]), "lam_i \\+ lam_j > 0"),
        (dict(lam=[0.0, 0.0, 1.0]), "lam_i \\+ lam_j > 0"),
        (dict(lam=np.diag([0.7, 1.1, 1.6])), "diagonal"),
        (dict(t=np.zeros((2, 2))), "1-D"),
        (dict(t=[0.0, np.nan]), "finite"),
        (dict(t=[1j]), "real"),
        (dict(Q0=np.stack([np.eye(3)] * 2), lam=np.ones((3, 3)) + np.eye(3)), "broadcast"),
    ],
)
def test_bad_input(kwargs, match) -> None:
    args = dict(Q0=np.eye(3), M0=symrb.hat([0.5, 1.0, 1.5]), lam=[0.7, 1.1, 1.6], t=[0.0, 1.0])
    args.update(kwargs)
    with pytest.raises(InputError, match=match):
        rigid_body_exact(**args)


# ---------------------------------------------------------------------------------------------
# hypothesis: the exact curve solves the ODE (finite differences) and matches DOP853


def _ode_residual(Q0, M0, lam, t0: float) -> float:
    """Largest |dX/dt - f(X)| at t0 with dX/dt from the 6th-order central difference, relative to
    the size of the field."""
    h = 1e-2
    w = np.array([-1, 9, -45, 0, 45, -9, 1]) / (60 * h)
    s = rigid_body_exact(Q0, M0, lam, t0 + h * np.arange(-3, 4))
    dQ = np.tensordot(w, s.y.Q, axes=1)
    dM = np.tensordot(w, s.y.M, axes=1)
    Q, M, Om = s.y.Q[3], s.y.M[3], s.y.Omega[3]
    scale = np.abs(Om).max() * max(1.0, np.abs(M).max())
    return float(max(np.abs(dQ - Q @ Om).max(), np.abs(dM - (M @ Om - Om @ M)).max()) / scale)


moments = st.floats(0.3, 2.5)
components = st.floats(-2.0, 2.0)


@given(
    lam=st.tuples(moments, moments, moments),
    m=st.tuples(components, components, components).filter(lambda m: np.linalg.norm(m) > 0.05),
    seed=st.integers(0, 2**16),
    t0=st.floats(-200.0, 200.0),
)
def test_hypothesis_solves_the_ode(lam, m, seed, t0) -> None:
    Q0 = symrb.random_SO(3, seed=seed)
    assert _ode_residual(Q0, symrb.hat(m), np.array(lam), t0) < 1e-7


@settings(max_examples=10)
@given(
    lam=st.tuples(moments, moments, moments),
    m=st.tuples(components, components, components).filter(lambda m: np.linalg.norm(m) > 0.05),
    seed=st.integers(0, 2**16),
)
def test_hypothesis_against_dop853(lam, m, seed) -> None:
    Q0, M0, lamv = symrb.random_SO(3, seed=seed), symrb.hat(m), np.array(lam)
    t = np.linspace(0.0, 10.0, 6)
    sol = rigid_body_exact(Q0, M0, lamv, t)
    ref = _dop853(Q0, M0, lamv, t)
    # the reference's own error grows with the angle turned, |Omega| t
    turns = 1.0 + 10.0 * np.abs(sol.y.Omega).max()
    eM, eQ = _errors(sol, ref, M0)
    assert eM <= 1e-11 * turns and eQ <= 1e-11 * turns, (eM, eQ, turns)
