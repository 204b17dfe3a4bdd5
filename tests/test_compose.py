"""Tests of symrb.compose: compositions of the MV step, RKMK4 and the implicit midpoint rule.

Independent references: the order conditions of the coefficients are checked by the local error
of a composed Strang splitting of two matrix exponentials in 60-digit arithmetic (mpmath), the
rigid body flows against scipy's DOP853 at rtol = atol = 1e-13 (symrb.integrate), the base step
against symrb.discrete_rigid_body_flow.
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import symrb
from symrb.base_steps import MidpointStep, MVStep, RKMK4Step
from symrb.compose import (
    composed_rigid_body_flow,
    midpoint_rigid_body_flow,
    rkmk4_rigid_body_flow,
)
from symrb.composition import compose_steps, composition_coefficients
from symrb.errors import InputError

LAM = np.array([0.7, 1.1, 1.6])
M0 = symrb.hat([0.5, 1.0, 1.5])
Q0 = np.eye(3)

KINDS = [
    (2, "triple_jump"),
    (4, "triple_jump"),
    (4, "suzuki"),
    (6, "triple_jump"),
    (6, "yoshida"),
    (6, "kahan_li"),
    (8, "triple_jump"),
    (8, "mclachlan"),
    (8, "kahan_li"),
]
STAGES = {
    (2, "triple_jump"): 1,
    (4, "triple_jump"): 3,
    (4, "suzuki"): 5,
    (6, "triple_jump"): 9,
    (6, "yoshida"): 7,
    (6, "kahan_li"): 9,
    (8, "triple_jump"): 27,
    (8, "mclachlan"): 15,
    (8, "kahan_li"): 17,
}


# ---------------------------------------------------------------------------------------------
# coefficients


@pytest.mark.parametrize(("order", "kind"), KINDS)
def test_coefficient_sums(order, kind):
    """sum g = 1, g symmetric, sum g^(2j+1) = 0 for 2j + 1 < order (necessary conditions)."""
    g = composition_coefficients(order, kind)
    assert g.shape == (STAGES[(order, kind)],)
    np.testing.assert_array_equal(g, g[::-1])
    assert abs(g.sum() - 1.0) < 1e-14
    scale = np.abs(g).max()
    for q in range(3, order, 2):
        assert abs(np.sum(g**q)) < 1e-13 * scale**q, (q, np.sum(g**q))


def _mp_expm(A):
    return mpmath.expm(A)


@pytest.mark.parametrize(("order", "kind"), KINDS)
def test_coefficient_order_by_local_error(order, kind):
    """The composed Strang splitting exp(gA/2) exp(gB) exp(gA/2) has local error O(h^(p+1)).

    Computed in 60-digit arithmetic from the float64 coefficients, against exp(s h (A + B)) with
    s = sum(gamma) (so the rounding of sum(gamma) to 1 does not enter); this checks every order
    condition, not only the moments of test_coefficient_sums."""
    mpmath.mp.dps = 60
    rng = np.random.default_rng(7)
    A = mpmath.matrix(rng.standard_normal((3, 3)).tolist()) * mpmath.mpf("0.5")
    B = mpmath.matrix(rng.standard_normal((3, 3)).tolist()) * mpmath.mpf("0.5")
    g = [mpmath.mpf(float(x)) for x in composition_coefficients(order, kind)]

    def local_error(h):
        P = mpmath.eye(3)
        for c in g:
            half = _mp_expm(A * (c * h / 2))
            P = half * _mp_expm(B * (c * h)) * half * P
        exact = _mp_expm((A + B) * (sum(g) * h))
        return mpmath.mnorm(P - exact, 1)

    # h = 0.1 and 0.05: in the asymptotic range, above the floor (about 1e-23) that the float64
    # rounding of the coefficients puts on the order conditions (Sum g^3 = O(1e-17) etc.)
    h = mpmath.mpf("0.1")
    e1, e2 = local_error(h), local_error(h / 2)
    slope = float(mpmath.log(e1 / e2, 2))
    assert abs(slope - (order + 1)) < 0.2, slope


def test_compose_calls_step_with_scaled_h():
    calls = []

    def step(x, h):
        calls.append(h)
        return x + h

    psi = compose_steps(step, [0.25, 0.5, 0.25])
    assert psi(1.0, 2.0) == 3.0
    assert calls == [0.5, 1.0, 0.5]


# ---------------------------------------------------------------------------------------------
# the base step is the step of discrete_rigid_body_flow


def test_mv_step_is_the_discrete_rigid_body_step():
    h, n = 0.1, 5
    ref = symrb.discrete_rigid_body_flow(Q0, M0, LAM, h, n)
    base = MVStep(LAM)
    psi = compose_steps(lambda s, hh: base.step(s[0], s[1], hh), [1.0])
    state = (Q0, M0)
    for k in range(1, n + 1):
        state = psi(state, h)
        np.testing.assert_allclose(state[0], ref.y.Q[k], rtol=0, atol=1e-14)
        np.testing.assert_allclose(state[1], ref.y.M[k], rtol=0, atol=1e-14)
    sol = composed_rigid_body_flow(Q0, M0, LAM, h, n, order=2)
    np.testing.assert_allclose(sol.y.Q, ref.y.Q, rtol=0, atol=1e-14)
    np.testing.assert_allclose(sol.y.M, ref.y.M, rtol=0, atol=1e-14)
    np.testing.assert_allclose(sol.t, ref.t)


def test_iterations_recorded_when_the_base_step_reports_them():
    sol = composed_rigid_body_flow(Q0, M0, LAM, 0.1, 4, order=4, step="midpoint")
    assert sol.iterations.shape == (4 * 5,) and (sol.iterations > 0).all()


def test_pluggable_base_step():
    class Wrapped:
        def __init__(self):
            self.inner = MVStep(LAM)
            self.calls = 0

        def step(self, Q, M, h):
            self.calls += 1
            return self.inner.step(Q, M, h)

    w = Wrapped()
    a = composed_rigid_body_flow(Q0, M0, LAM, 0.1, 4, order=6, step=w)
    b = composed_rigid_body_flow(Q0, M0, LAM, 0.1, 4, order=6, step=MVStep(LAM))
    assert w.calls == 4 * 9
    np.testing.assert_allclose(a.y.Q, b.y.Q, rtol=0, atol=1e-15)
    np.testing.assert_allclose(a.y.M, b.y.M, rtol=0, atol=1e-15)
    assert a.success and b.success
    # the default "mv" is the fast engine (symrb.engine.MVStepper): the same map, to rounding
    c = composed_rigid_body_flow(Q0, M0, LAM, 0.1, 4, order=6)
    np.testing.assert_allclose(c.y.Q, b.y.Q, rtol=0, atol=1e-13)
    np.testing.assert_allclose(c.y.M, b.y.M, rtol=0, atol=1e-13)


# ---------------------------------------------------------------------------------------------
# convergence order against DOP853


@pytest.fixture(scope="module")
def reference():
    sol = symrb.integrate(
        symrb.RigidBody,
        (0.0, 1.0),
        {"Q": Q0, "M": M0},
        lam=LAM,
        method="DOP853",
        rtol=1e-13,
        atol=1e-13,
        t_eval=[1.0],
    )
    return sol.y.Q[-1], sol.y.M[-1]


def _composed(order, kind, step="mv"):
    def run(h, n):
        return composed_rigid_body_flow(
            Q0, M0, LAM, h, n, order, kind=kind, step=step, save_every=n
        )

    return run


def _flow(f):
    def run(h, n):
        return f(Q0, M0, LAM, h, n, save_every=n)

    return run


ORDER_CASES = [
    ("MV", _composed(2, "triple_jump"), (8, 16), 2),
    ("MV triple jump 4", _composed(4, "triple_jump"), (8, 16), 4),
    ("MV Suzuki 4", _composed(4, "suzuki"), (4, 8), 4),
    ("MV triple jump 6", _composed(6, "triple_jump"), (8, 16), 6),
    ("MV Yoshida 6", _composed(6, "yoshida"), (8, 16), 6),
    ("MV Kahan-Li 6", _composed(6, "kahan_li"), (4, 8), 6),
    ("MV triple jump 8", _composed(8, "triple_jump"), (12, 24), 8),
    ("MV McLachlan 8", _composed(8, "mclachlan"), (3, 6), 8),
    ("MV Kahan-Li 8", _composed(8, "kahan_li"), (3, 5), 8),
    ("RKMK4", _flow(rkmk4_rigid_body_flow), (8, 16), 4),
    ("implicit midpoint", _flow(midpoint_rigid_body_flow), (8, 16), 2),
    ("midpoint Suzuki 4", _composed(4, "suzuki", "midpoint"), (8, 16), 4),
]


@pytest.mark.parametrize(
    ("name", "run", "ns", "order"), ORDER_CASES, ids=[c[0] for c in ORDER_CASES]
)
def test_convergence_order(reference, name, run, ns, order):
    """Slope of the error at T = 1 against h, within 0.2 of the order; errors >> 1e-12."""
    Qr, Mr = reference
    errors = []
    for n in ns:
        sol = run(1.0 / n, n)
        assert sol.success, sol.message
        assert sol.t[-1] == pytest.approx(1.0)
        errors.append(max(np.abs(sol.y.Q[-1] - Qr).max(), np.abs(sol.y.M[-1] - Mr).max()))
    assert min(errors) > 3e-12, errors  # well above the reference's error (about 5e-14)
    slope = np.log(errors[0] / errors[1]) / np.log(ns[1] / ns[0])
    assert abs(slope - order) < 0.2, (name, errors, slope)


# ---------------------------------------------------------------------------------------------
# structure


@pytest.fixture(scope="module")
def so4():
    lam = symrb.algebra.random_lam(4, seed=3)
    M = symrb.random_so(4, seed=4)
    M = M / np.abs(M).max()
    Q = symrb.random_SO(4, seed=5)
    return Q, M, lam


def _spectrum(M):
    return np.sort(np.linalg.eigvals(M).imag, axis=-1)


@pytest.mark.parametrize(("order", "kind"), [(4, "triple_jump"), (6, "kahan_li"), (8, "mclachlan")])
def test_mv_compositions_keep_casimirs_energy_and_orthogonality(so4, order, kind):
    Q, M, lam = so4
    sol = composed_rigid_body_flow(Q, M, lam, 0.1, 60, order, kind=kind)
    assert sol.success
    spec = _spectrum(sol.y.M)
    # rounding: 60 steps of up to 17 conjugations M -> U^T M U each (a truncation error of the
    # size of the method's error would be above 1e-6 at h = 0.1)
    assert np.ptp(spec, axis=0).max() < 2e-12 * np.abs(spec).max()
    C = symrb.casimir_traces(sol.y.M)
    assert (np.ptp(C, axis=0) < 2e-12 * np.abs(C).max(axis=0)).all()
    H = symrb.kinetic_energy(sol.y.M, lam)  # the MV map keeps the energy too (measured)
    assert np.ptp(H) < 2e-12 * abs(H[0])
    QtQ = np.swapaxes(sol.y.Q, -1, -2) @ sol.y.Q
    assert np.abs(QtQ - np.eye(4)).max() < 1e-12
    assert (np.linalg.det(sol.y.Q) > 0).all()


def test_rkmk4_keeps_casimirs_and_orthogonality(so4):
    Q, M, lam = so4
    sol = rkmk4_rigid_body_flow(Q, M, lam, 0.1, 60)
    spec = _spectrum(sol.y.M)
    assert np.ptp(spec, axis=0).max() < 2e-12 * np.abs(spec).max()
    H = symrb.kinetic_energy(sol.y.M, lam)
    assert np.ptp(H) > 1e-11 * abs(H[0])  # not conserved (order-4 drift): the tests can fail
    QtQ = np.swapaxes(sol.y.Q, -1, -2) @ sol.y.Q
    assert np.abs(QtQ - np.eye(4)).max() < 1e-12


def test_midpoint_keeps_quadratic_invariants_only():
    """On so(5) the Casimir tr M^4 is quartic: the midpoint rule keeps it only to O(h^2)."""
    lam = symrb.algebra.random_lam(5, seed=3)
    M = symrb.random_so(5, seed=4)
    M = M / np.abs(M).max()
    Q = symrb.random_SO(5, seed=5)
    sol = midpoint_rigid_body_flow(Q, M, lam, 0.1, 60)
    H = symrb.kinetic_energy(sol.y.M, lam)
    C = symrb.casimir_traces(sol.y.M)  # tr M^2, tr M^4
    assert np.ptp(H) < 2e-12 * abs(H[0])
    assert np.ptp(C[:, 0]) < 2e-12 * abs(C[0, 0])
    assert np.ptp(C[:, 1]) > 1e-8 * abs(C[0, 1])
    QtQ = np.swapaxes(sol.y.Q, -1, -2) @ sol.y.Q
    assert np.abs(QtQ - np.eye(5)).max() < 1e-12
    assert (sol.iterations > 0).all() and sol.iterations.size == 60
    mv = composed_rigid_body_flow(Q, M, lam, 0.1, 60, order=4)
    C = symrb.casimir_traces(mv.y.M)
    assert (np.ptp(C, axis=0) < 2e-12 * np.abs(C).max(axis=0)).all()


def _as_state_step(base):
    return lambda s, h: base.step(s[0], s[1], h)


@pytest.mark.parametrize(("order", "kind"), KINDS)
@pytest.mark.parametrize("base", ["mv", "midpoint"])
def test_symmetric_compositions_are_time_reversible(so4, order, kind, base):
    Q, M, lam = so4
    step = MVStep(lam) if base == "mv" else MidpointStep(lam)
    psi = compose_steps(_as_state_step(step), composition_coefficients(order, kind))
    Q1, M1 = psi((Q, M), 0.1)
    Qb, Mb = psi((Q1, M1), -0.1)
    assert np.abs(Q1 - Q).max() > 1e-3  # it moved
    np.testing.assert_allclose(Qb, Q, rtol=0, atol=1e-13)
    np.testing.assert_allclose(Mb, M, rtol=0, atol=1e-13)


def test_rkmk4_is_not_time_reversible(so4):
    """The reversibility test can fail: RKMK4 is not symmetric."""
    Q, M, lam = so4
    step = RKMK4Step(lam)
    Q1, M1 = step.step(Q, M, 0.3)
    Qb, Mb = step.step(Q1, M1, -0.3)
    assert np.abs(Mb - M).max() > 1e-9


@settings(max_examples=15, deadline=None)
@given(
    m=st.lists(st.floats(-1.5, 1.5), min_size=3, max_size=3),
    lam=st.lists(st.floats(0.3, 2.0), min_size=3, max_size=3),
    h=st.floats(0.01, 0.2),
)
def test_reversibility_random(m, lam, h):
    Mm = symrb.hat(m)
    sol = composed_rigid_body_flow(Q0, Mm, lam, h, 2, order=4)
    assert sol.success
    back = composed_rigid_body_flow(sol.y.Q[-1], -sol.y.M[-1], lam, h, 2, order=4)
    # (Q, M) -> (Q, -M) reverses time (a step at h from -M is the step at -h from M), so a
    # symmetric method started from (Q_N, -M_N) returns to (Q_0, -M_0)
    np.testing.assert_allclose(back.y.Q[-1], Q0, rtol=0, atol=1e-13)
    np.testing.assert_allclose(-back.y.M[-1], Mm, rtol=0, atol=1e-13)


def test_batch_matches_single_runs():
    Ms = np.stack([M0, 0.5 * M0, symrb.hat([0.2, -0.3, 0.1])])
    sol = composed_rigid_body_flow(Q0, Ms, LAM, 0.1, 5, order=4)
    assert sol.y.M.shape == (6, 3, 3, 3)
    for i in range(3):
        one = composed_rigid_body_flow(Q0, Ms[i], LAM, 0.1, 5, order=4)
        np.testing.assert_allclose(sol.y.M[:, i], one.y.M, rtol=0, atol=1e-14)
        np.testing.assert_allclose(sol.y.Q[:, i], one.y.Q, rtol=0, atol=1e-14)


def test_fold_ends_the_run():
    sol = composed_rigid_body_flow(Q0, M0, LAM, 1.0, 10, order=4, kind="triple_jump")
    assert not sol.success and sol.status == -1
    assert "past the fold" in sol.message
    assert sol.k.tolist() == [0]


def test_inputs_not_mutated():
    Q, M = Q0.copy(), M0.copy()
    composed_rigid_body_flow(Q, M, LAM, 0.1, 3, order=4)
    rkmk4_rigid_body_flow(Q, M, LAM, 0.1, 3)
    midpoint_rigid_body_flow(Q, M, LAM, 0.1, 3)
    np.testing.assert_array_equal(Q, Q0)
    np.testing.assert_array_equal(M, M0)


# ---------------------------------------------------------------------------------------------
# bad input


@pytest.mark.parametrize(
    ("call", "words"),
    [
        (lambda: composition_coefficients(5), "order"),
        (lambda: composition_coefficients(True), "order"),
        (lambda: composition_coefficients(4.0), "order"),
        (lambda: composition_coefficients(4, "kahan_li"), "kind"),
        (lambda: composition_coefficients(8, "nope"), "kind"),
        (lambda: compose_steps(3, [1.0]), "step"),
        (lambda: compose_steps(lambda x, h: x, []), "gammas"),
        (lambda: compose_steps(lambda x, h: x, [[1.0]]), "gammas"),
        (lambda: compose_steps(lambda x, h: x, [np.nan]), "gammas"),
        (lambda: composed_rigid_body_flow(Q0, M0, LAM, 0.0, 3), "h"),
        (lambda: composed_rigid_body_flow(Q0, M0, LAM, -0.1, 3), "h"),
        (lambda: composed_rigid_body_flow(Q0, M0, LAM, 0.1, -1), "steps"),
        (lambda: composed_rigid_body_flow(Q0, M0, LAM, 0.1, 3, save_every=0), "save_every"),
        (lambda: composed_rigid_body_flow(2 * Q0, M0, LAM, 0.1, 3), "Q0"),
        (lambda: composed_rigid_body_flow(Q0, np.ones((3, 3)), LAM, 0.1, 3), "M0"),
        (lambda: composed_rigid_body_flow(Q0, M0, [-1.0, 1.0, 2.0], 0.1, 3), "lam"),
        (lambda: composed_rigid_body_flow(Q0, M0, LAM, 0.1, 3, order=3), "order"),
        (lambda: composed_rigid_body_flow(Q0, M0, LAM, 0.1, 3, step="rk4"), "step"),
        (lambda: composed_rigid_body_flow(Q0, M0, LAM, 0.1, 3, step=object()), "step"),
        (lambda: composed_rigid_body_flow(Q0, np.zeros((2, 3, 3)), np.ones((3, 3)) + np.eye(3),
                                          0.1, 3), "lam"),
        (lambda: composed_rigid_body_flow(np.stack([Q0] * 2), np.stack([M0] * 3), LAM, 0.1, 1),
         "broadcast"),
        (lambda: rkmk4_rigid_body_flow(Q0, M0, LAM, np.inf, 3), "h"),
        (lambda: midpoint_rigid_body_flow(Q0, M0, LAM, 0.1, 2.5), "steps"),
        (lambda: MidpointStep(LAM, maxiter=0), "maxiter"),
    ],
)  # fmt: skip
def test_bad_input(call, words):
    with pytest.raises(InputError, match=words):
        call()


def test_midpoint_not_converging_ends_the_run():
    sol = midpoint_rigid_body_flow(Q0, 20 * M0, LAM, 2.0, 3)
    assert not sol.success and "did not converge" in sol.message
