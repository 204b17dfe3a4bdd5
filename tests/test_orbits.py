"""symrb.orbits (S13-S15): batching, validation, invariants, the boundary value problem; and the
demonstrations that the claims' checks can fail (opposite signs, separate controls, wrong
displayed formulas)."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import derivations.claims.section3._orbit_learning as ol
import derivations.claims.section3._orbits as orb
import derivations.claims.section3.s13_adjoint_orbits as s13
import derivations.claims.section3.s14_brockett_toda as s14
import derivations.claims.section3.s15_learning_on_orbits as s15
import derivations.claims.section3.s15_learning_on_orbits.so3 as s15_so3
import symrb
from derivations.claims.section3._display import _Norm
from derivations.claims.section3.s15_learning_on_orbits import _beta
from derivations.symbolic import Pair, Words, eq, trace_residual
from derivations.vocabulary import matrix
from symrb import orbits
from symrb.errors import InputError


def rs(rng, k, size=()):
    a = rng.standard_normal((*size, k, k))
    return (a - np.swapaxes(a, -1, -2)) / 2


def pair(a, b):
    return -0.5 * np.trace(a @ b, axis1=-2, axis2=-1)


def comm(a, b):
    return a @ b - b @ a


# ----------------------------------------------------------------------------- batching


@pytest.mark.parametrize("k", [3, 4, 5])
def test_batch_matches_loop(k):
    rng = np.random.default_rng(k)
    x, p, N = rs(rng, k, (2, 3)), rs(rng, k, (2, 3)), rs(rng, k)
    xd, pd = orbits.orbit_extremal_rhs(x, p, N)
    H = orbits.orbit_hamiltonian(x, p, N)
    V = orbits.brockett_potential(x, N)
    D = orbits.double_bracket_rhs(x, N)
    for i in range(2):
        for j in range(3):
            xi, pi = x[i, j], p[i, j]
            u = comm(pi, xi)
            np.testing.assert_allclose(xd[i, j], comm(xi, u), atol=1e-13)
            np.testing.assert_allclose(pd[i, j], comm(pi, u) - comm(N, comm(N, xi)), atol=1e-13)
            c = comm(xi, N)
            np.testing.assert_allclose(V[i, j], -0.5 * pair(c, c), atol=1e-13)
            np.testing.assert_allclose(H[i, j], 0.5 * pair(u, u) - 0.5 * pair(c, c), atol=1e-12)
            np.testing.assert_allclose(D[i, j], comm(xi, comm(xi, N)), atol=1e-13)


def test_reexported():
    """The orbit entry points at the top level are symrb.orbits' own objects."""
    assert symrb._EXPORTS["orbits"]
    for name in symrb._EXPORTS["orbits"]:
        assert getattr(symrb, name) is getattr(orbits, name)


# ----------------------------------------------------------------------------- validation


def test_rejects_non_skew_and_nan():
    rng = np.random.default_rng(0)
    x, N = rs(rng, 3), rs(rng, 3)
    with pytest.raises(InputError, match="x must be skew"):
        orbits.double_bracket_rhs(x + np.eye(3), N)
    with pytest.raises(InputError, match="N must be skew"):
        orbits.brockett_potential(x, N + np.eye(3))
    with pytest.raises(InputError, match="p must be skew"):
        orbits.orbit_extremal_rhs(x, np.ones((3, 3)), N)
    bad = x.copy()
    bad[0, 1] = np.nan
    with pytest.raises(InputError, match="x must be finite"):
        orbits.orbit_hamiltonian(bad, x, N)
    with pytest.raises(InputError, match="3 x 3"):
        orbits.double_bracket_rhs(rs(rng, 4), N)


def test_bvp_and_flow_argument_errors():
    rng = np.random.default_rng(1)
    x, N = rs(rng, 3), rs(rng, 3)
    with pytest.raises(InputError, match="T must be a positive"):
        orbits.solve_orbit_bvp(x, N, 0.0)
    with pytest.raises(InputError, match="costate must be"):
        orbits.solve_orbit_bvp(x, N, 1.0, costate="plus")
    with pytest.raises(InputError, match="x0 must have shape"):
        orbits.solve_orbit_bvp(rs(rng, 3, (2, 2)), N, 1.0)
    with pytest.raises(InputError, match="N must be a single"):
        orbits.solve_orbit_bvp(x, rs(rng, 3, (2,)), 1.0)
    with pytest.raises(InputError, match="t must be"):
        orbits.double_bracket_flow(x, N, [0.0, 2.0, 1.0])
    with pytest.raises(InputError, match="continuation"):
        orbits.solve_orbit_bvp(x, N, 1.0, continuation_growth=1.0)


def test_inputs_not_mutated():
    rng = np.random.default_rng(2)
    x, p, N = rs(rng, 3), rs(rng, 3), rs(rng, 3)
    copies = [a.copy() for a in (x, p, N)]
    orbits.orbit_extremal_rhs(x, p, N)
    orbits.double_bracket_flow(x, N, [0.0, 0.5])
    orbits.solve_orbit_bvp(x, N, 0.5)
    for a, c in zip((x, p, N), copies, strict=True):
        np.testing.assert_array_equal(a, c)


# ----------------------------------------------------------------------------- properties

skew_seeds = st.integers(0, 2**32 - 1)


@settings(max_examples=40, deadline=None)
@given(seed=skew_seeds, k=st.integers(3, 6))
def test_double_bracket_decreases_pairing(seed, k):
    """d/dt <x, N> = <[x,[x,N]], N> = -||[x, N]||^2 and the field is tangent to the orbit."""
    rng = np.random.default_rng(seed)
    x, N = rs(rng, k), rs(rng, k)
    d = orbits.double_bracket_rhs(x, N)
    c = comm(x, N)
    assert pair(d, N) == pytest.approx(-pair(c, c), abs=1e-10 * (1 + abs(pair(c, c))))
    # tangent to the orbit: tr(x^j xdot) = 0 for j = 1, 3
    for j in (1, 3):
        xj = np.linalg.matrix_power(x, j)
        assert abs(np.trace(xj @ d)) <= 1e-10 * (1 + np.abs(xj).max() * np.abs(d).max() * k)


@settings(max_examples=40, deadline=None)
@given(seed=skew_seeds, k=st.integers(3, 5))
def test_hamiltonian_constant_along_field(seed, k):
    """dH*/dt along (xdot, pdot) vanishes (central difference, relative to the terms' size)."""
    rng = np.random.default_rng(seed)
    x, p, N = rs(rng, k), rs(rng, k), rs(rng, k)
    xd, pd = orbits.orbit_extremal_rhs(x, p, N)
    h = 1e-5
    dH = (
        orbits.orbit_hamiltonian(x + h * xd, p + h * pd, N)
        - orbits.orbit_hamiltonian(x - h * xd, p - h * pd, N)
    ) / (2 * h)
    scale = 1 + np.abs(xd).max() ** 2 + np.abs(pd).max() ** 2 + np.abs(x).max() ** 4
    assert abs(dH) <= 1e-6 * scale


# ----------------------------------------------------------------------------- the BVP


def test_single_sample_bvp_is_double_bracket_flow():
    rng = np.random.default_rng(3)
    x0, N = rs(rng, 3), rs(rng, 3)
    res = orbits.solve_orbit_bvp(x0, N, 3.0)
    assert res.success, res.message
    assert res.x.shape == (res.t.size, 1, 3, 3) and res.p.shape == res.x.shape
    assert res.u.shape == (res.t.size, 3, 3)
    np.testing.assert_allclose(res.p[:, 0], np.broadcast_to(-N, res.p[:, 0].shape), atol=1e-8)
    ref = orbits.double_bracket_flow(x0, N, res.t)
    assert np.max(np.abs(res.x[:, 0] - ref)) < 1e-5
    # the optimal control is [x, N]
    np.testing.assert_allclose(res.u, comm(res.x[:, 0], N), atol=1e-8)
    xs, ps = res.at([0.0, 3.0])
    np.testing.assert_allclose(xs[0, 0], x0, atol=1e-10)
    np.testing.assert_allclose(ps[1, 0], -N, atol=1e-10)


def test_printed_costate_gives_reverse_flow():
    """With p_T = +N the extremal is p = N and x follows xdot = [x,[x,-N]]: <x_T, N> increases."""
    rng = np.random.default_rng(4)
    x0, N = rs(rng, 3), rs(rng, 3)
    res = orbits.solve_orbit_bvp(x0, N, 2.0, costate="printed")
    assert res.success, res.message
    ref = orbits.double_bracket_flow(x0, -N, res.t)
    assert np.max(np.abs(res.x[:, 0] - ref)) < 1e-5
    good = orbits.solve_orbit_bvp(x0, N, 2.0)
    assert pair(good.x[-1, 0], N) < pair(x0, N) < pair(res.x[-1, 0], N)


def test_critical_point_is_stationary():
    """x0 commuting with N (a critical point of <x, N> on its orbit): x stays at x0."""
    rng = np.random.default_rng(6)
    N = rs(rng, 3)
    res = orbits.solve_orbit_bvp(2.0 * N, N, 5.0)
    assert res.success, res.message
    assert np.max(np.abs(res.x[:, 0] - 2.0 * N)) < 1e-10


def test_degenerate_critical_point_so4_is_reported():
    """so(4), x0 and N in the same Cartan subalgebra: the collocation Jacobian is singular there.
    The solver must then say so (success False), never return a silent wrong answer."""
    N = np.zeros((4, 4))
    N[0, 1], N[1, 0], N[2, 3], N[3, 2] = 1.0, -1.0, 2.0, -2.0
    x0 = 0.5 * N.copy()
    x0[0, 1], x0[1, 0] = 3.0, -3.0
    res = orbits.solve_orbit_bvp(x0, N, 5.0)
    if res.success:
        assert np.max(np.abs(res.x[:, 0] - x0)) < 1e-10
    else:
        assert "singular" in res.message.lower()


def test_two_samples_share_control_and_leave_double_bracket():
    rng = np.random.default_rng(5)
    x0, N = rs(rng, 3, (2,)), rs(rng, 3)
    res = orbits.solve_orbit_bvp(x0, N, 1.0)
    assert res.success, res.message
    u = comm(res.p[:, 0], res.x[:, 0]) + comm(res.p[:, 1], res.x[:, 1])
    np.testing.assert_allclose(res.u, u, atol=1e-12)
    np.testing.assert_allclose(res.x[0], x0, atol=1e-9)
    np.testing.assert_allclose(res.p[-1], np.broadcast_to(-N, (2, 3, 3)), atol=1e-9)
    dev = max(
        np.max(np.abs(res.x[:, a] - orbits.double_bracket_flow(x0[a], N, res.t))) for a in (0, 1)
    )
    assert dev > 1e-2


def test_two_samples_long_horizon():
    """The continuation (first half kept, second half shifted) reaches T = 8 for two samples; the
    shared control conserves <x^1, x^2> and ||x^a||."""
    X0, N = ol.two_sample_data()
    res = orbits.solve_orbit_bvp(X0, N, 8.0, tol=1e-5)
    assert res.success, res.message
    np.testing.assert_allclose(pair(res.x[:, 0], res.x[:, 1]), pair(X0[0], X0[1]), atol=1e-7)
    np.testing.assert_allclose(
        pair(res.x, res.x), np.broadcast_to(pair(X0, X0), (res.t.size, 2)), atol=1e-7
    )


def test_extend_guess():
    """_extend keeps the first half of the solution, shifts the second half and holds the middle."""
    calls = []

    def sol(s):
        calls.append(np.array(s))
        return np.stack([s, 2 * s])

    t, y = orbits.bvp._extend(sol, 2.0, 5.0, 11)
    np.testing.assert_allclose(t, np.linspace(0.0, 5.0, 11))
    source = calls[0]
    np.testing.assert_allclose(source[t < 1.0], t[t < 1.0])
    np.testing.assert_allclose(source[t > 4.0], t[t > 4.0] - 3.0)
    np.testing.assert_allclose(source[(t >= 1.0) & (t <= 4.0)], 1.0)
    assert y.shape == (2, 11)


# ----------------------------------------------------------------------------- the checks can fail
# (moved from the claims' evidence: each shows that a wrong sign or formula makes a check fail)


def test_opposite_control_sign_is_not_stationary():
    """dH/du vanishes at the emitted u* = [p, x] but not at [x, p]."""
    ustar = s13.OPTIMAL_CONTROL.outputs["u"]
    assert trace_residual(s13.stationarity(ustar)) == 0
    assert trace_residual(s13.stationarity(-ustar)) > 0


def test_opposite_potential_gradient_fails():
    """The derivative of Brockett's potential is <[N,[N,x]], d>, not <-[N,[N,x]], d>."""
    w = Words()
    dV = orb.directional(s14.BROCKETT_POTENTIAL.outputs["V"], {orb.x: orb.d}, w)
    right = orb.pair_poly(s14.BROCKETT_GRADIENT.rhs, orb.d, w)
    assert trace_residual(dV - right) == 0
    assert trace_residual(dV + right) > 0


def test_wrong_displayed_gradient_fails_the_check(monkeypatch):
    shown = s14.BROCKETT_GRADIENT
    monkeypatch.setattr(s14, "BROCKETT_GRADIENT", eq(shown.lhs, -shown.rhs))
    assert s14.s14_gradient() > 0


def test_separate_controls_change_the_pairing():
    """With two different controls d/dt <x^1, x^2> does not vanish (the shared control is what
    conserves it)."""
    w = Words()
    u2 = matrix("u_2")
    field = s15.ORBIT_RHS_WITH_CONTROL.outputs["xdot"]
    moves = {
        s15._x1: s15.kernel_of_sample(field, 1),
        s15._x2: s15.kernel_of_sample(field, 2, control=u2),
    }
    assert trace_residual(orb.directional(Pair(s15._x1, s15._x2), moves, w)) > 0


def test_printed_endpoint_sign_gives_the_reversed_flow():
    """p = +N also solves the costate equation, but then xdot = [x,[N,x]] = -[x,[x,N]]."""
    w = Words()
    at = {orb.p: orb.N}
    pdot = s14.ORBIT_EXTREMAL_RHS.outputs["pdot"].xreplace(at)
    xdot = s14.ORBIT_EXTREMAL_RHS.outputs["xdot"].xreplace(at)
    db = s14.DOUBLE_BRACKET_RHS.outputs["xdot"]
    assert trace_residual(orb.pair_poly(pdot, orb.d, w)) == 0
    assert trace_residual(orb.pair_poly(xdot + db, orb.d, w)) == 0
    assert trace_residual(orb.pair_poly(xdot - db, orb.d, w)) > 0


def test_printed_equations_fail_and_corrected_pass():
    """The same function judges both forms: the printed per-sample equations are not Hamilton's
    equations of the shared problem, the corrected ones are."""
    assert s15._two_sample_hamilton("printed") > 0
    assert s15._two_sample_hamilton("corrected") == 0


def test_mixed_forms_rescale_the_control():
    """su(2), costate paired by -1/2 tr, ||u||^2 = -kappa(u, u) = -4 tr(u u): u* = [p, x] / 8."""
    assert s13.killing_factor(s13.su_basis(2)) == 4
    assert s13.mixed_form_control_scale() == sp.Rational(1, 8)


@pytest.mark.parametrize(
    "change",
    [
        lambda b: b.subs(_beta / 2, _beta),  # sin(beta): too strong
        lambda b: b.subs(_beta / 2, _beta / 3),  # sin(beta/3): true, but not the sharp bound
    ],
)
def test_wrong_bound_fails_the_check(monkeypatch, change):
    bound = s15.BOUND
    monkeypatch.setattr(s15_so3, "BOUND", sp.Ge(bound.lhs, change(bound.rhs)))
    assert s15_so3.s15_bound_so3() > 0


def test_wrong_decay_rate_fails_the_check(monkeypatch):
    phase = s15.PHASE
    faster = phase.rhs.subs(_Norm(orb.N), 2 * _Norm(orb.N))
    monkeypatch.setattr(s15_so3, "PHASE", eq(phase.lhs, faster))
    assert s15_so3.s15_decay_exact_so3() > 0


def test_one_sample_second_term_decreases_with_T():
    """The closed form ||[N,[N,x_T]]|| at T = 1, 2, 4, 8, 16 decreases to 0, the last ratio close
    to exp(-||x_0|| ||N|| 8)."""
    x0, N = ol.one_sample_data()
    decay = symrb.orbits.one_sample_second_term(x0, N, ol.ONE_SAMPLE_HORIZONS)
    assert np.all(np.diff(decay) < 0) and decay[-1] < 1e-3
    assert decay[-1] / decay[-2] == pytest.approx(np.exp(-0.5 * 8), rel=0.02)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_one_sample_second_term_is_the_norm_along_the_double_bracket_flow(seed):
    # the closed form against ||[N, [N, x(t)]]|| of a numerical double bracket flow from the
    # same x0 (catches an angle measured from +N, or a wrong rate)
    rng = np.random.default_rng(seed)
    x0, N = symrb.random_so(3, seed=rng), symrb.random_so(3, seed=rng)
    t = np.array([0.0, 0.5, 2.0, 6.0])
    x = orbits.double_bracket_flow(x0, N, t, rtol=1e-12, atol=1e-14)
    c = symrb.commutator(N, symrb.commutator(N, x))
    flow = np.sqrt(symrb.pairing(c, c))
    scale = symrb.pairing(N, N) * np.sqrt(symrb.pairing(x0, x0))
    np.testing.assert_allclose(orbits.one_sample_second_term(x0, N, t), flow,
                               atol=1e-8 * scale)  # fmt: skip


def test_two_sample_bound_and_the_errors():
    # samples of norms 2 and 0.5 at the angle beta: the bound is ||N||^2 0.5 sin(beta / 2)
    beta = 1.1
    x0 = [symrb.hat([2.0, 0.0, 0.0]), symrb.hat([0.5 * np.cos(beta), 0.5 * np.sin(beta), 0.0])]
    got = orbits.two_sample_bound(x0, symrb.hat([0.3, -1.2, 1.6]))  # ||N||^2 = 4.09
    assert got == pytest.approx(4.09 * 0.5 * np.sin(beta / 2), rel=1e-14)
    with pytest.raises(symrb.InputError, match="two 3 x 3 samples"):
        orbits.two_sample_bound(x0[0], symrb.hat([0.0, 0.0, 1.0]))
    with pytest.raises(symrb.InputError, match="nonzero"):
        orbits.two_sample_bound([x0[0], np.zeros((3, 3))], symrb.hat([0.0, 0.0, 1.0]))
    with pytest.raises(symrb.InputError, match="so\\(3\\)"):
        orbits.one_sample_second_term(symrb.random_so(4, seed=1), symrb.random_so(4, seed=2), [1])
    with pytest.raises(symrb.InputError, match="times >= 0"):
        orbits.one_sample_second_term(x0[0], symrb.hat([0.0, 0.0, 1.0]), [-1.0])


def test_double_bracket_flow_at_time_zero_only_returns_x0():
    # solve_ivp gives no output on the empty interval [0, 0]; the flow returns x0 itself
    x0, N = symrb.random_so(4, seed=11), symrb.random_so(4, seed=12)
    xs = orbits.double_bracket_flow(x0, N, [0.0])
    assert xs.shape == (1, 4, 4)
    np.testing.assert_array_equal(xs[0], x0)
    xs, info = orbits.double_bracket_flow(x0, N, [0.0], return_info=True)
    np.testing.assert_array_equal(xs[0], x0)
    assert info.nfev == 0 and abs(info.condition[0] - 1.0) < 1e-8  # the identity map


# ----------------------------------------------------------------------------- orbit_extremal_flow
# (S14: the Toda lattice through the coupled (x, p) extremal)


def test_extremal_flow_only_the_derived_costate_gives_toda():
    """The sensitivity of s14_optimal_flow_is_toda: from the same L_0 the costates p(0) = 0,
    -1.1 N and +N (against Symes at +t) leave Toda at O(1); -N stays on it."""
    ts = np.linspace(0.0, 2.0, 9)
    good = s14.toda_through_extremal(4, -1.0, ts)
    assert max(good.values()) < 1e-8
    for scale in (0.0, -1.1):
        bad = s14.toda_through_extremal(4, scale, ts)
        assert bad["symes"] > 0.1, (scale, bad)
    L0, D = s14.toda_start(4, 4), np.diag([1.0, 2.0, 3.0, 4.0])
    L, _ = orbits.orbit_extremal_flow(L0, D, D, ts, algebra="isym")
    assert np.abs(L - s14.ref.toda_symes(L0, ts)).max() > 0.1  # +N is Toda backwards


def test_extremal_flow_leaves_toda_at_the_predicted_rate():
    """The extremal p = -N is unstable in (x, p): the distance of p from -N grows like e^{r t}
    with r = (lambda_max - lambda_min)(d_max - d_min) near the sorted limit (the Notes of
    orbit_extremal_flow; 9.80 for the k = 3 data of S14)."""
    L0, D = s14.toda_start(3, 3), np.diag([1.0, 2.0, 3.0])
    lam = np.linalg.eigvalsh(L0)
    rate = (lam[-1] - lam[0]) * 2.0
    ts = np.array([2.0, 3.0])
    _, P = orbits.orbit_extremal_flow(L0, -D, D, ts, algebra="isym")
    drift = np.abs(P + D).max(axis=(1, 2))
    measured = np.log(drift[1] / drift[0]) / (ts[1] - ts[0])
    assert abs(measured - rate) < 0.05 * rate, (measured, rate)


def test_extremal_flow_so_matches_the_field_and_conserves_H():
    """On so(4) the run agrees with a plain solve_ivp of orbit_extremal_rhs, conserves H* and the
    spectrum of x; p0 = -N reproduces double_bracket_flow."""
    from scipy.integrate import solve_ivp

    rng = np.random.default_rng(7)
    x0, p0, N = rs(rng, 4), rs(rng, 4) * 0.3, rs(rng, 4)
    ts = np.linspace(0.0, 1.0, 5)
    xs, ps = orbits.orbit_extremal_flow(x0, p0, N, ts)

    def f(_t, y):
        a, b = orbits.orbit_extremal_rhs(y[:16].reshape(4, 4), y[16:].reshape(4, 4), N)
        return np.concatenate([a.ravel(), b.ravel()])

    sol = solve_ivp(f, (0, 1), np.concatenate([x0.ravel(), p0.ravel()]), t_eval=ts,
                    method="DOP853", rtol=1e-12, atol=1e-13)  # fmt: skip
    np.testing.assert_allclose(xs, sol.y[:16].T.reshape(-1, 4, 4), atol=1e-9)
    np.testing.assert_allclose(ps, sol.y[16:].T.reshape(-1, 4, 4), atol=1e-9)
    H = orbits.orbit_hamiltonian(xs, ps, N)
    assert np.ptp(H) < 1e-9
    ev = np.linalg.eigvals(xs).imag
    assert np.abs(np.sort(ev, axis=1) - np.sort(ev[0])).max() < 1e-9
    xd, pd = orbits.orbit_extremal_flow(x0, -N, N, ts)
    np.testing.assert_allclose(xd, orbits.double_bracket_flow(x0, N, ts), atol=1e-9)
    np.testing.assert_allclose(pd, np.broadcast_to(-N, pd.shape), atol=1e-12)


def test_extremal_flow_argument_errors():
    rng = np.random.default_rng(3)
    x, p, N = rs(rng, 3), rs(rng, 3), rs(rng, 3)
    S = x @ x  # symmetric
    with pytest.raises(InputError, match="algebra must be"):
        orbits.orbit_extremal_flow(x, p, N, [0.0, 1.0], algebra="su")
    with pytest.raises(InputError, match="p0 must be skew"):
        orbits.orbit_extremal_flow(x, S, N, [0.0, 1.0])
    with pytest.raises(InputError, match="x0 must be symmetric"):
        orbits.orbit_extremal_flow(x, S, S, [0.0, 1.0], algebra="isym")
    with pytest.raises(InputError, match="single"):
        orbits.orbit_extremal_flow(rs(rng, 3, (2,)), p, N, [0.0, 1.0])
    with pytest.raises(InputError, match="t must be"):
        orbits.orbit_extremal_flow(x, p, N, [1.0, 0.5])
    with pytest.raises(InputError, match="rtol > 0"):
        orbits.orbit_extremal_flow(x, p, N, [0.0, 1.0], rtol=0.0)
    with pytest.raises(InputError, match="complex"):
        orbits.orbit_extremal_flow(1j * S, 1j * S, 1j * S, [0.0, 1.0], algebra="isym")
    xs, ps = orbits.orbit_extremal_flow(x, p, N, [0.0])
    assert xs.shape == ps.shape == (1, 3, 3) and np.array_equal(xs[0], x)


@pytest.mark.parametrize(
    ("name", "wrong"),
    [("P_TODA", lambda f: eq(f.lhs, -f.rhs)), ("TODA_B", lambda f: eq(f.lhs, -f.rhs))],
)
def test_toda_every_k_can_fail(monkeypatch, name, wrong):
    """s14_toda_every_k fails for the costate p = +N (Toda backwards) and for a wrong sign of the
    displayed b-equation."""
    assert s14.s14_toda_every_k() == 0
    monkeypatch.setattr(s14, name, wrong(getattr(s14, name)))
    assert s14.s14_toda_every_k() > 0


def test_constant_costate_check_can_fail(monkeypatch):
    """s14_constant_costate_gives_toda fails when a displayed costate is not a root (p = -2N) or
    the reversed field has the wrong sign."""
    monkeypatch.setattr(s14, "P_TODA", eq(orb.p, -2 * orb.N))
    assert s14.s14_constant_costate_gives_toda() > 0
    monkeypatch.undo()
    shown = s14.DOUBLE_BRACKET_REVERSED
    monkeypatch.setattr(s14, "DOUBLE_BRACKET_REVERSED", eq(shown.lhs, s14.DOUBLE_BRACKET.rhs))
    assert s14.s14_constant_costate_gives_toda() > 0


def test_toda_is_optimal_can_fail(monkeypatch):
    """s14_toda_is_optimal fails for the square with the opposite cross term and for the
    minimising control [N, x]."""
    assert s14.s14_toda_is_optimal() == 0
    sq = s14.SQUARE
    monkeypatch.setattr(s14, "SQUARE", eq(sq.lhs, sq.rhs + 2 * sp.Add.make_args(sq.rhs)[-1]))
    assert s14.s14_toda_is_optimal() > 0
    monkeypatch.undo()
    monkeypatch.setattr(s14, "U_MIN", eq(orb.u, -s14.U_MIN.rhs))
    assert s14.s14_toda_is_optimal() > 0
