"""Numerics of symrb.continuous: batched fields vs per-item loops, validation, P_from_M near its
boundary, the integrate driver, and hypothesis properties."""

from __future__ import annotations

import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import symrb
from symrb.errors import InputError, OutOfDomainError

LAM = np.array([0.6, 0.9, 1.3, 1.9])


def _skew_with_norm(n: int, r: float, seed: int) -> np.ndarray:
    M = symrb.random_so(n, seed=seed)
    return M * (r / np.linalg.norm(M, 2))


# ---------------------------------------------------------------------------------------------
# batched kernels agree with per-item calls, and do not mutate their inputs


@pytest.mark.parametrize(
    "func, second",
    [
        (symrb.symmetric.symmetric_rigid_body_rhs, "P"),
        (symrb.symmetric.gl_hamiltonian, "P"),
        (symrb.symmetric.mclachlan_scovel_rhs, "B"),
    ],
)
def test_batch_matches_loop(func, second) -> None:
    rng = np.random.default_rng(0)
    Q = symrb.random_SO(4, (2, 3), seed=rng)
    if second == "B":
        Y = Q @ symrb.random_so(4, (2, 3), seed=rng)
    else:
        Y = rng.standard_normal((2, 3, 4, 4))
    lam = np.stack([symrb.algebra.random_lam(4, seed=s) for s in range(3)])  # batch (3, 4)
    Qc, Yc, lc = Q.copy(), Y.copy(), lam.copy()
    out = func(Q, Y, lam)
    for i in range(2):
        for j in range(3):
            one = func(Q[i, j], Y[i, j], lam[j])
            if isinstance(out, tuple):
                for a, b in zip(out, one, strict=True):
                    np.testing.assert_allclose(a[i, j], b, rtol=1e-14, atol=1e-14)
            else:
                np.testing.assert_allclose(out[i, j], one, rtol=1e-14, atol=1e-14)
    assert np.array_equal(Q, Qc) and np.array_equal(Y, Yc) and np.array_equal(lam, lc)


def test_fields_against_direct_numpy() -> None:
    rng = np.random.default_rng(1)
    Q, P = rng.standard_normal((2, 4, 4))
    M = Q.T @ P - P.T @ Q
    U = M / (LAM[:, None] + LAM[None, :])
    dQ, dP = symrb.symmetric.symmetric_rigid_body_rhs(Q, P, LAM)
    np.testing.assert_allclose(dQ, Q @ U, atol=1e-14)
    np.testing.assert_allclose(dP, P @ U, atol=1e-14)
    H = symrb.symmetric.gl_hamiltonian(Q, P, LAM)
    np.testing.assert_allclose(H, 0.5 * symrb.kinetic_energy(M, LAM), rtol=1e-13)


def test_multi_sample_control_is_sum_of_single_controls() -> None:
    rng = np.random.default_rng(2)
    Q = symrb.random_SO(4, (5,), seed=rng)
    P = rng.standard_normal((5, 4, 4))
    U = symrb.symmetric.multi_sample_control(Q, P, LAM)
    single = [symrb.J_inv(symrb.symmetric.symmetric_momentum(Q[a], P[a]), LAM) for a in range(5)]
    np.testing.assert_allclose(U, np.sum(single, axis=0), atol=1e-13)
    dQ, dP = symrb.symmetric.multi_sample_rhs(Q, P, LAM)
    np.testing.assert_allclose(dQ, Q @ U, atol=1e-13)
    np.testing.assert_allclose(dP, P @ U, atol=1e-13)
    # one sample: the learning field is the symmetric rigid body field
    d1 = symrb.symmetric.multi_sample_rhs(Q[:1], P[:1], LAM)
    d2 = symrb.symmetric.symmetric_rigid_body_rhs(Q[0], P[0], LAM)
    np.testing.assert_allclose(d1[0][0], d2[0], atol=1e-14)


# ---------------------------------------------------------------------------------------------
# validation


def test_validation_messages() -> None:
    Q = symrb.random_SO(3, seed=0)
    with pytest.raises(InputError, match="lam"):
        symrb.symmetric.symmetric_rigid_body_rhs(Q, Q, [1.0, -1.0, 2.0])
    with pytest.raises(InputError, match="P must be 3 x 3"):
        symrb.symmetric.symmetric_rigid_body_rhs(Q, np.eye(4), [1.0, 1.5, 2.0])
    with pytest.raises(InputError, match="Q\\^T B must be skew"):
        symrb.symmetric.mclachlan_scovel_rhs(Q, Q, [1.0, 1.5, 2.0])
    with pytest.raises(InputError, match="finite"):
        symrb.symmetric.gl_hamiltonian(Q, np.full((3, 3), np.nan), [1.0, 1.5, 2.0])
    with pytest.raises(InputError, match="sample axis"):
        symrb.symmetric.multi_sample_control(Q, Q, [1.0, 1.5, 2.0])
    with pytest.raises(InputError, match="orthogonal"):
        symrb.symmetric.P_from_M(2 * Q, np.zeros((3, 3)))
    with pytest.raises(InputError, match="skew"):
        symrb.symmetric.P_from_M(Q, np.eye(3))


@pytest.mark.parametrize("r", [2.0, 2.0 + 1e-12, 3.0])
def test_P_from_M_out_of_domain(r: float) -> None:
    M = _skew_with_norm(4, r, 5)
    Q = symrb.random_SO(4, seed=5)
    with pytest.raises(OutOfDomainError, match=re.escape("||M||_op < 2")):
        symrb.symmetric.P_from_M(Q, M)


def test_P_from_M_batch_reports_offending_index() -> None:
    M = np.stack([_skew_with_norm(3, 1.0, 1), _skew_with_norm(3, 2.5, 2)])
    Q = symrb.random_SO(3, (2,), seed=3)
    with pytest.raises(OutOfDomainError, match=r"batch index \(1,\)"):
        symrb.symmetric.P_from_M(Q, M)


# ---------------------------------------------------------------------------------------------
# P_from_M: accuracy up to the boundary


@pytest.mark.parametrize("delta", [1e-1, 1e-4, 1e-8, 1e-12, 1e-15])
@pytest.mark.parametrize("n", [3, 4, 7])
def test_P_from_M_near_boundary(n: int, delta: float) -> None:
    M = _skew_with_norm(n, 2.0 * (1.0 - delta), 10 + n)
    assert np.linalg.norm(M, 2) < 2.0
    Q = symrb.random_SO(n, seed=n)
    P = symrb.symmetric.P_from_M(Q, M)
    eye = np.eye(n)
    assert np.abs(P.T @ P - eye).max() < 1e-14 * n
    assert abs(np.linalg.det(P) - 1.0) < 1e-13
    np.testing.assert_allclose(symrb.symmetric.symmetric_momentum(Q, P), M, atol=1e-14 * n)


def test_P_from_M_is_the_small_angle_solution() -> None:
    """Eigen-angles phi of Q^T P satisfy 2 sin(phi) = theta with |phi| < pi/2: trace(Q^T P) > 0
    pairwise, and P -> Q as M -> 0."""
    Q = symrb.random_SO(4, seed=1)
    np.testing.assert_allclose(symrb.symmetric.P_from_M(Q, np.zeros((4, 4))), Q, atol=1e-15)
    M = _skew_with_norm(4, 1.9, 2)
    A = Q.T @ symrb.symmetric.P_from_M(Q, M)
    sym = 0.5 * (A + A.T)
    assert np.all(np.linalg.eigvalsh(sym) > 0)  # cos(phi) > 0 on every rotation plane


def test_P_from_M_batch_and_no_mutation() -> None:
    Q = symrb.random_SO(5, (4,), seed=0)
    M = np.stack([_skew_with_norm(5, r, i) for i, r in enumerate([0.1, 0.9, 1.5, 1.999])])
    Qc, Mc = Q.copy(), M.copy()
    P = symrb.symmetric.P_from_M(Q, M)
    for i in range(4):
        np.testing.assert_allclose(P[i], symrb.symmetric.P_from_M(Q[i], M[i]), atol=1e-15)
    assert np.array_equal(Q, Qc) and np.array_equal(M, Mc)


# ---------------------------------------------------------------------------------------------
# integrate


def test_symmetric_flow_reproduces_rigid_body() -> None:
    Q0 = symrb.random_SO(4, seed=11)
    M0 = _skew_with_norm(4, 1.3, 11)
    P0 = symrb.symmetric.P_from_M(Q0, M0)
    ts = np.linspace(0.0, 8.0, 17)
    kw = dict(lam=LAM, rtol=1e-12, atol=1e-12, t_eval=ts)
    a = symrb.integrate(symrb.SymmetricRigidBody, (0.0, 8.0), {"Q": Q0, "P": P0}, **kw)
    b = symrb.integrate(symrb.RigidBody(), (0.0, 8.0), (Q0, M0), **kw)
    assert a.success and b.success and a.nfev > 0
    assert a.y.M.shape == (17, 4, 4) and a.y["Q"].shape == (17, 4, 4)
    np.testing.assert_allclose(a.t, ts)
    np.testing.assert_allclose(a.y.M, b.y.M, atol=1e-9)
    np.testing.assert_allclose(a.y.Q, b.y.Q, atol=1e-9)
    assert np.ptp(a.y.H) < 1e-10
    # the operator norm is conserved (claim S11)
    assert np.ptp(np.linalg.norm(a.y.M, 2, axis=(-2, -1))) < 1e-10


def test_integrate_batch_matches_single_runs() -> None:
    Q0 = symrb.random_SO(3, (2,), seed=4)
    P0 = symrb.random_SO(3, (2,), seed=5)
    lam = np.array([0.7, 1.1, 1.6])
    kw = dict(lam=lam, rtol=1e-12, atol=1e-12, t_eval=[0.0, 1.0, 2.0])
    batch = symrb.integrate(symrb.SymmetricRigidBody, (0, 2), {"Q": Q0, "P": P0}, **kw)
    assert batch.y.Q.shape == (3, 2, 3, 3) and batch.y.H.shape == (3, 2)
    for i in range(2):
        one = symrb.integrate(symrb.SymmetricRigidBody, (0, 2), {"Q": Q0[i], "P": P0[i]}, **kw)
        np.testing.assert_allclose(batch.y.P[:, i], one.y.P, atol=1e-9)


def test_mclachlan_scovel_matches_symmetric_flow() -> None:
    """B = P - Q P^T Q maps the symmetric flow to McLachlan-Scovel (claim S7)."""
    Q0 = symrb.random_SO(4, seed=21)
    P0 = symrb.symmetric.P_from_M(Q0, _skew_with_norm(4, 1.0, 21))
    B0 = P0 - Q0 @ P0.T @ Q0
    kw = dict(lam=LAM, rtol=1e-12, atol=1e-12, t_eval=np.linspace(0, 5, 6))
    a = symrb.integrate(symrb.SymmetricRigidBody, (0, 5), {"Q": Q0, "P": P0}, **kw)
    b = symrb.integrate(symrb.McLachlanScovel, (0, 5), {"Q": Q0, "B": B0}, **kw)
    np.testing.assert_allclose(b.y.Q, a.y.Q, atol=1e-9)
    np.testing.assert_allclose(b.y.M, a.y.M, atol=1e-9)


def test_costate_with_skew_QTP_is_mclachlan_scovel_for_twice_the_costate() -> None:
    """Claim S7 as corrected: for Q^T P skew the symmetric flow from (Q, P) is the
    McLachlan-Scovel flow from (Q, 2P), not from (Q, P)."""
    Q0 = symrb.random_SO(4, seed=22)
    P0 = Q0 @ _skew_with_norm(4, 0.8, 22)
    kw = dict(lam=LAM, rtol=1e-12, atol=1e-12, t_eval=np.linspace(0, 5, 6))
    a = symrb.integrate(symrb.SymmetricRigidBody, (0, 5), {"Q": Q0, "P": P0}, **kw)
    b = symrb.integrate(symrb.McLachlanScovel, (0, 5), {"Q": Q0, "B": 2 * P0}, **kw)
    c = symrb.integrate(symrb.McLachlanScovel, (0, 5), {"Q": Q0, "B": P0}, **kw)
    np.testing.assert_allclose(b.y.Q, a.y.Q, atol=1e-9)
    np.testing.assert_allclose(b.y.B, 2 * a.y.P, atol=1e-9)
    assert np.abs(c.y.Q - a.y.Q).max() > 1e-2


def test_multi_sample_flow_shapes_and_control() -> None:
    Q0 = symrb.random_SO(3, (4,), seed=8)
    P0 = symrb.random_SO(3, (4,), seed=9)
    lam = np.array([0.7, 1.1, 1.6])
    sol = symrb.integrate(
        symrb.MultiSampleSymmetricRigidBody, (0, 1), {"Q": Q0, "P": P0}, lam=lam, t_eval=[0, 1]
    )
    assert sol.y.Q.shape == (2, 4, 3, 3) and sol.y.U.shape == (2, 3, 3)
    np.testing.assert_allclose(
        sol.y.U[0], symrb.symmetric.multi_sample_control(Q0, P0, lam), atol=1e-14
    )
    # every Q^a stays orthogonal
    eye = np.eye(3)
    assert np.abs(np.swapaxes(sol.y.Q, -1, -2) @ sol.y.Q - eye).max() < 1e-8


def test_multi_sample_total_momentum_is_a_rigid_body() -> None:
    """Each M^a = Q^aT P^a - P^aT Q^a obeys Mdot^a = [M^a, U], so the total M = sum_a M^a obeys
    the rigid body equation with Omega = U = J^{-1}(M)."""
    lam = np.array([0.7, 1.1, 1.6])
    Q0 = symrb.random_SO(3, (5,), seed=30)
    P0 = 0.3 * np.random.default_rng(31).standard_normal((5, 3, 3))
    ts = np.linspace(0, 4, 9)
    kw = dict(lam=lam, rtol=1e-12, atol=1e-12, t_eval=ts)
    ms = symrb.integrate(symrb.MultiSampleSymmetricRigidBody, (0, 4), (Q0, P0), **kw)
    Mtot = symrb.symmetric.symmetric_momentum(ms.y.Q, ms.y.P).sum(axis=-3)
    rb = symrb.integrate(symrb.RigidBody, (0, 4), (np.eye(3), Mtot[0]), **kw)
    np.testing.assert_allclose(Mtot, rb.y.M, atol=1e-9)
    np.testing.assert_allclose(ms.y.U, rb.y.Omega, atol=1e-9)


def test_mclachlan_scovel_keeps_QTB_skew() -> None:
    """Moved from the evidence of claim S7 (a property of every flow Qdot = QU, Bdot = BU with U
    skew): Q^T B stays skew along symrb's McLachlan-Scovel flow, n = 5, t in [0, 10]."""
    rng = np.random.default_rng(7)
    lam = np.sort(rng.uniform(0.5, 2.0, 5))
    Q0 = symrb.random_SO(5, seed=rng)
    B0 = Q0 @ symrb.random_so(5, seed=rng)
    kw = dict(lam=lam, rtol=1e-12, atol=1e-12, t_eval=np.linspace(0, 10, 21))
    sol = symrb.integrate(symrb.McLachlanScovel, (0, 10), {"Q": Q0, "B": B0}, **kw)
    assert sol.success
    assert np.abs(sol.y.M + np.swapaxes(sol.y.M, -1, -2)).max() < 1e-9
    assert np.abs(np.swapaxes(sol.y.Q, -1, -2) @ sol.y.Q - np.eye(5)).max() < 1e-9


@pytest.mark.parametrize("r", [1.5, 2.0])
def test_operator_norm_conserved_on_rigid_body_flow(r: float) -> None:
    """Moved from the evidence of claim S11 (isospectral flows conserve ||M||_op): inside S and
    on C, n = 4, t in [0, 10]."""
    lam = np.array([0.5, 0.8, 1.4, 2.0])
    M0 = _skew_with_norm(4, r, 12)
    kw = dict(lam=lam, rtol=1e-12, atol=1e-12, t_eval=np.linspace(0, 10, 41))
    sol = symrb.integrate(symrb.RigidBody, (0, 10), {"Q": np.eye(4), "M": M0}, **kw)
    assert np.abs(np.linalg.norm(sol.y.M, 2, axis=(-2, -1)) - r).max() < 1e-9


def test_symmetric_flow_started_on_C_stays_on_C() -> None:
    """Moved from the evidence of claim S11: Q^T P with a rotation by pi/2 gives ||M||_op = 2,
    and the symmetric flow keeps it there (n = 4, t in [0, 10])."""
    lam = np.array([0.5, 0.8, 1.4, 2.0])
    Q0 = symrb.random_SO(4, seed=12)
    A = np.array([[0, -1, 0, 0], [1, 0, 0, 0], [0, 0, 0.6, -0.8], [0, 0, 0.8, 0.6]])
    kw = dict(lam=lam, rtol=1e-12, atol=1e-12, t_eval=np.linspace(0, 10, 41))
    sol = symrb.integrate(symrb.SymmetricRigidBody, (0, 10), {"Q": Q0, "P": Q0 @ A}, **kw)
    assert np.abs(np.linalg.norm(sol.y.M, 2, axis=(-2, -1)) - 2.0).max() < 1e-9


def test_symmetric_flow_keeps_SO_and_conserves_H() -> None:
    """Moved from the evidence of claim S12 (properties of the class of flows): started on
    SO(4) x SO(4), Q and P stay orthogonal and the gl(n) Hamiltonian is conserved, t in [0, 10]."""
    lam = np.array([0.5, 0.8, 1.4, 2.0])
    Q0, P0 = symrb.random_SO(4, (2,), seed=13)
    kw = dict(lam=lam, rtol=1e-12, atol=1e-12, t_eval=np.linspace(0, 10, 41))
    sol = symrb.integrate(symrb.SymmetricRigidBody, (0, 10), {"Q": Q0, "P": P0}, **kw)
    eye = np.eye(4)
    for X in (sol.y.Q, sol.y.P):
        assert np.abs(np.swapaxes(X, -1, -2) @ X - eye).max() < 1e-9
    assert np.abs(sol.y.H / sol.y.H[0] - 1.0).max() < 1e-9


def test_integrate_validation() -> None:
    Q = symrb.random_SO(3, seed=0)
    lam = [0.7, 1.1, 1.6]
    with pytest.raises(InputError, match="missing \\['P'\\]"):
        symrb.integrate(symrb.SymmetricRigidBody, (0, 1), {"Q": Q}, lam=lam)
    with pytest.raises(InputError, match="unexpected \\['M'\\]"):
        symrb.integrate(symrb.SymmetricRigidBody, (0, 1), {"Q": Q, "P": Q, "M": Q}, lam=lam)
    with pytest.raises(InputError, match=r"y0\['M'\] must be skew"):
        symrb.integrate(symrb.RigidBody, (0, 1), (Q, Q), lam=lam)
    with pytest.raises(InputError, match="t_span"):
        symrb.integrate(symrb.RigidBody, (0, 1, 2), (Q, np.zeros((3, 3))), lam=lam)
    with pytest.raises(InputError, match="rtol"):
        symrb.integrate(symrb.RigidBody, (0, 1), (Q, np.zeros((3, 3))), lam=lam, rtol=0)
    with pytest.raises(InputError, match="flow must be a Flow"):
        symrb.integrate("rigid body", (0, 1), (Q, np.zeros((3, 3))), lam=lam)
    with pytest.raises(InputError, match="integrate"):
        symrb.integrate(symrb.RigidBody, (0, 1), (Q, np.zeros((3, 3))), lam=lam, method="nope")
    with pytest.raises(InputError, match="sample axis"):
        symrb.integrate(symrb.MultiSampleSymmetricRigidBody, (0, 1), (Q, Q), lam=lam)


def test_integrate_reports_failure_without_raising() -> None:
    """A solver failure comes back as success=False with the solver's message, not as NaNs."""
    Q = symrb.random_SO(3, seed=0)
    P = 1e160 * symrb.random_SO(3, seed=1)  # P U overflows to inf
    sol = symrb.integrate(symrb.SymmetricRigidBody, (0, 1), {"Q": Q, "P": P}, lam=[0.7, 1.1, 1.6])
    assert sol.success is False and sol.status == -1
    assert "overflowed" in sol.message


# ---------------------------------------------------------------------------------------------
# hypothesis


@settings(max_examples=40, deadline=None)
@given(
    n=st.integers(2, 6),
    r=st.floats(0.0, 1.999999),
    seed=st.integers(0, 2**32 - 1),
)
def test_P_from_M_property(n: int, r: float, seed: int) -> None:
    M = _skew_with_norm(n, r, seed) if r > 0 else np.zeros((n, n))
    Q = symrb.random_SO(n, seed=seed)
    P = symrb.symmetric.P_from_M(Q, M)
    np.testing.assert_allclose(Q.T @ P - P.T @ Q, M, atol=1e-13)
    np.testing.assert_allclose(P.T @ P, np.eye(n), atol=1e-13)


@settings(max_examples=30, deadline=None)
@given(n=st.integers(2, 6), seed=st.integers(0, 2**32 - 1))
def test_momentum_of_rotations_bounded(n: int, seed: int) -> None:
    """Claim S9 on random pairs: ||Q^T P - P^T Q||_op <= 2 for Q, P in SO(n)."""
    rng = np.random.default_rng(seed)
    Q, P = symrb.random_SO(n, (2,), seed=rng)
    assert np.linalg.norm(symrb.symmetric.symmetric_momentum(Q, P), 2) <= 2.0 + 1e-12


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), scale=st.floats(0.1, 3.0))
def test_hamiltonian_is_invariant_under_rotation(seed: int, scale: float) -> None:
    """H(Q, P) depends only on M = Q^T P - P^T Q: H(RQ, RP) = H(Q, P) for R in SO(n)."""
    rng = np.random.default_rng(seed)
    Q, R = symrb.random_SO(4, (2,), seed=rng)
    P = scale * rng.standard_normal((4, 4))
    np.testing.assert_allclose(
        symrb.symmetric.gl_hamiltonian(R @ Q, R @ P, LAM),
        symrb.symmetric.gl_hamiltonian(Q, P, LAM),
        rtol=1e-12,
        atol=1e-14,
    )
