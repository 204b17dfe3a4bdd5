"""Tests of symrb.paper: symmetric representation, MV-Algorithms 1 and 2, time-step scaling.

The long-run agreement of the three maps and their order of accuracy are experiments of the book
(symrb.experiments.discrete), tested once in tests/test_experiments_discrete.py.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from symrb import (
    InputError,
    discrete_rigid_body_flow,
    mv_algorithm1,
    mv_algorithm2,
    random_SO,
    random_so,
    solve_moser_veselov,
    symmetric_flow,
)
from symrb.paper import DiscreteFlowSolution, jd_residual, symmetric_step
from symrb.rigid_body import rigid_body_rhs

EPS = np.finfo(float).eps
LAM3 = np.array([0.7, 1.1, 1.6])


def _start(seed=0, scale=0.05, nn=3):
    rng = np.random.default_rng(seed)
    return random_SO(nn, seed=rng), random_so(nn, seed=rng, scale=scale), rng


def test_mv_algorithm2_conserves_the_spectrum():
    """mv3 is a conjugation, so the spectrum of M_k along MV-Algorithm 2 stays that of M_1 (n = 4,
    1000 steps).  Every orthogonal update has this property, so it is a test of the implementation
    class, not evidence for claim D10 (which compares with a 50-digit reference)."""
    rng = np.random.default_rng(10)
    lam = np.array([0.6, 0.9, 1.3, 1.7])
    M1 = random_so(4, seed=rng, scale=0.05)
    MB = mv_algorithm2(random_SO(4, seed=rng), M1, lam, 1000).y.M
    ev0 = np.sort(np.linalg.eigvals(M1).imag)
    evs = np.sort(np.linalg.eigvals(MB).imag, axis=-1)
    assert np.max(np.abs(evs - ev0)) <= 1e-12 * np.max(np.abs(ev0))


def _reference(Q0, M0, lam, T):
    nn = lam.shape[0]

    def f(_t, y):
        Q, M = y[: nn * nn].reshape(nn, nn), y[nn * nn :].reshape(nn, nn)
        dQ, dM = rigid_body_rhs(Q, M, lam)
        return np.concatenate([dQ.ravel(), dM.ravel()])

    y0 = np.concatenate([Q0.ravel(), M0.ravel()])
    sol = solve_ivp(f, (0, T), y0, method="DOP853", rtol=1e-13, atol=1e-13)
    return sol.y[: nn * nn, -1].reshape(nn, nn), sol.y[nn * nn :, -1].reshape(nn, nn)


def test_mv2_momentum_scaling():
    """M^{MV}_{k+1} = h M(t_k): MV-Algorithm 2 started at (Q_1, h M(0)) tracks h M(t_k) to O(h^2)."""
    rng = np.random.default_rng(4)
    M0, Q0 = random_so(3, seed=rng, scale=0.5), random_SO(3, seed=rng)
    h, T = 0.01, 1.0
    N = round(T / h)
    U0 = solve_moser_veselov(h * M0, LAM3)
    Ms = mv_algorithm2(Q0 @ U0, h * M0, LAM3, N - 1).y.M
    _QT, MT = _reference(Q0, M0, LAM3, (N - 1) * h)
    assert np.abs(Ms[-1] / h - MT).max() < 20 * h**2 * np.abs(M0).max()


def test_batch_equals_loop():
    rng = np.random.default_rng(5)
    Q0 = random_SO(3, size=(2,), seed=rng)
    M0 = random_so(3, size=(2,), seed=rng, scale=0.3)
    sol = discrete_rigid_body_flow(Q0, M0, LAM3, 0.1, 20, save_every=5)
    Q, M = sol.y.Q, sol.y.M
    assert Q.shape == (5, 2, 3, 3) and M.shape == (5, 2, 3, 3) and sol.t.shape == (5,)
    for i in range(2):
        one = discrete_rigid_body_flow(Q0[i], M0[i], LAM3, 0.1, 20, save_every=5)
        assert np.allclose(Q[:, i], one.y.Q, atol=1e-13)
        assert np.allclose(M[:, i], one.y.M, atol=1e-13)
    mv2 = mv_algorithm2(Q0, 0.1 * M0, LAM3, 10)
    for i in range(2):
        one = mv_algorithm2(Q0[i], 0.1 * M0[i], LAM3, 10)
        assert np.allclose(mv2.y.Q[:, i], one.y.Q, atol=1e-13)
        assert np.allclose(mv2.y.M[:, i], one.y.M, atol=1e-13)


def test_save_every_subsamples_the_full_run():
    Q0, M, _ = _start(6)
    full = symmetric_flow(Q0, Q0 @ M, LAM3, 1.0, 12)
    sub = symmetric_flow(Q0, Q0 @ M, LAM3, 1.0, 12, save_every=4)
    assert sub.y.Q.shape == (4, 3, 3)
    assert np.array_equal(sub.k, [0, 4, 8, 12]) and np.array_equal(sub.t, [0.0, 4.0, 8.0, 12.0])
    assert np.array_equal(sub.y.Q, full.y.Q[::4]) and np.array_equal(sub.y.P, full.y.P[::4])
    assert np.array_equal(sub.iterations, full.iterations)  # every step is counted
    QA = mv_algorithm1(Q0, full.y.Q[1], LAM3, 11, save_every=3)
    QA1 = mv_algorithm1(Q0, full.y.Q[1], LAM3, 11)
    assert np.array_equal(QA.y.Q, QA1.y.Q[::3]) and np.array_equal(QA.k, [0, 3, 6, 9, 12])
    assert np.array_equal(QA1.k, np.arange(13)) and np.array_equal(QA1.t, np.arange(13.0))


def test_symmetric_step_matches_definition():
    Q0, M, _ = _start(7, scale=0.2)
    P0 = random_so(3, seed=1) + Q0  # any costate
    Q1, P1, U = symmetric_step(Q0, P0, LAM3, 0.5)
    target = 0.5 * (Q0.T @ P0 - P0.T @ Q0)
    assert np.linalg.norm(jd_residual(U, target, LAM3)) <= 10 * EPS * np.linalg.norm(target)
    assert np.allclose(Q1, Q0 @ U, atol=0) and np.allclose(P1, P0 @ U, atol=0)


def test_validation_and_no_mutation():
    Q0, M, _ = _start(8)
    P0 = Q0 @ M
    copies = [Q0.copy(), P0.copy(), LAM3.copy()]
    symmetric_flow(Q0, P0, LAM3, 0.1, 3)
    mv_algorithm2(Q0, M, LAM3, 3)
    assert all(np.array_equal(a, b) for a, b in zip(copies, [Q0, P0, LAM3], strict=True))
    with pytest.raises(InputError, match="h must be"):
        symmetric_flow(Q0, P0, LAM3, 0.0, 3)
    with pytest.raises(InputError, match="steps must be"):
        symmetric_flow(Q0, P0, LAM3, 0.1, -1)
    with pytest.raises(InputError, match="save_every must be"):
        mv_algorithm2(Q0, M, LAM3, 3, save_every=0)
    with pytest.raises(InputError, match="save_every must be"):
        mv_algorithm2(Q0, M, LAM3, 3, save_every=True)
    with pytest.raises(InputError, match="Q0 must be orthogonal"):
        symmetric_flow(2 * Q0, P0, LAM3, 0.1, 3)
    with pytest.raises(InputError, match="M must be skew"):
        mv_algorithm2(Q0, M + np.eye(3), LAM3, 3)
    with pytest.raises(InputError, match="lam must be positive"):
        mv_algorithm1(Q0, Q0, -LAM3, 3)


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), scale=st.floats(0.01, 0.5), h=st.floats(0.01, 0.5))
def test_symmetric_step_properties(seed, scale, h):
    rng = np.random.default_rng(seed)
    Q0 = random_SO(4, seed=rng)
    P0 = rng.standard_normal((4, 4)) * scale
    Q1, P1, U = symmetric_step(Q0, P0, np.array([0.6, 0.9, 1.3, 1.7]), h)
    # Q stays in SO(n), and the momentum is transported: M_1 = U^T M_0 U (claim D8)
    assert np.abs(Q1.T @ Q1 - np.eye(4)).max() < 1e-14
    M0 = Q0.T @ P0 - P0.T @ Q0
    M1 = Q1.T @ P1 - P1.T @ Q1
    assert np.allclose(M1, U.T @ M0 @ U, atol=1e-13 * (1 + np.abs(M0).max()))


def test_result_object_names_the_states_and_counts_newton_iterations():
    Q0, M, _ = _start(9, scale=0.2)
    sym = symmetric_flow(Q0, Q0 @ M, LAM3, 0.5, 6, save_every=3)
    assert isinstance(sym, DiscreteFlowSolution)
    assert sym.success and sym.status == 0 and sym.message == "all 6 steps taken"
    assert sorted(sym.y) == ["M", "P", "Q"] and sym.h == 0.5
    assert np.array_equal(sym.t, [0.0, 1.5, 3.0])
    # one solve per step; the first starts from the Riccati solution (which may already meet the
    # tolerance), the others from an extrapolation that Newton has to polish
    assert sym.iterations.shape == (6,) and np.all(sym.iterations[1:] >= 1)
    assert sym.nit == sym.iterations.sum()
    np.testing.assert_allclose(
        sym.y.M, np.swapaxes(sym.y.Q, -1, -2) @ sym.y.P - np.swapaxes(sym.y.P, -1, -2) @ sym.y.Q
    )
    mv2 = mv_algorithm2(Q0, 0.1 * M, LAM3, 4)
    assert mv2.h is None and np.array_equal(mv2.t, np.arange(5.0))
    assert sorted(mv2.y) == ["M", "Q"] and mv2.iterations.shape == (5,)  # one more solve
    assert sorted(mv_algorithm1(Q0, mv2.y.Q[1], LAM3, 4).y) == ["Q"]


def test_a_solve_past_the_fold_stops_the_run_with_a_message():
    Q0, M, _ = _start(10, scale=0.2)
    # 10 M is far past the fold of J_D: the first step fails
    sol = symmetric_flow(Q0, Q0 @ (10 * M), LAM3, 1.0, 5)
    assert not sol.success and sol.status == -1
    assert "step 1 of 5 failed" in sol.message and "past the fold" in sol.message
    assert np.array_equal(sol.k, [0]) and sol.iterations.shape == (0,)
    mv2 = mv_algorithm2(Q0, 10 * M, LAM3, 5)
    assert not mv2.success and "step 1 of 5 failed" in mv2.message


def _failing_engine(monkeypatch, fail_at):
    """symrb.paper's engine (mv_flow) with a run of more than ``fail_at`` steps failing at step
    ``fail_at`` as mv_flow reports a failure: the states saved before it, then the state before
    the failed step, the iterations of the steps taken, the message "step k of N failed: ..."."""
    import dataclasses

    import symrb.paper as paper

    real = paper.mv_flow

    def fake(Q0, M0, lam, h, steps, *, save_every=1, **kw):
        if steps <= fail_at:  # the single solves around the run
            return real(Q0, M0, lam, h, steps, save_every=save_every, **kw)
        done = real(Q0, M0, lam, h, fail_at - 1, save_every=1, **kw)
        keep = (done.k % save_every == 0) | (done.k == fail_at - 1)
        return dataclasses.replace(
            done,
            t=done.t[keep],
            k=done.k[keep],
            y=type(done.y)({name: x[keep] for name, x in done.y.items()}),
            success=False,
            status=-1,
            message=f"step {fail_at} of {steps} failed: no solution (test)",
        )

    monkeypatch.setattr(paper, "mv_flow", fake)


@pytest.mark.parametrize("path", ["reference", "engine"])
@pytest.mark.parametrize("flow", ["symmetric", "mv1", "mv2"])
def test_a_failure_mid_run_keeps_the_states_reached(monkeypatch, flow, path):
    """The fourth solve raises: the run returns the states up to the last completed step (appended
    when save_every would have skipped it), the iterations of the solves done, and the reason.
    The reference loop (diagnostics=True) reports it; on the engine path (mv_flow failing at the
    engine step of that solve) the reference loop redoes the run, so the report is the same."""
    import symrb._stepping as dm
    from symrb.errors import OutOfDomainError

    original = dm._Stepper.solve
    calls = {"n": 0}

    def failing(self, M):
        calls["n"] += 1
        if calls["n"] == 4:
            raise OutOfDomainError("no solution (test)")
        return original(self, M)

    diag = path == "reference"
    monkeypatch.setattr(dm._Stepper, "solve", failing)
    if not diag:  # the engine fails too: the reference loop redoes the run and reports it
        _failing_engine(monkeypatch, {"symmetric": 4, "mv1": 5, "mv2": 3}[flow])
    Q0, M, _ = _start(11, scale=0.2)
    if flow == "symmetric":
        sol = symmetric_flow(Q0, Q0 @ M, LAM3, 0.5, 10, save_every=2, diagnostics=diag)
        last = 3  # steps 1-3 done, step 4 failed
    elif flow == "mv1":
        Q1 = Q0 @ solve_moser_veselov(0.1 * M, LAM3)
        sol = mv_algorithm1(Q0, Q1, LAM3, 10, save_every=2, diagnostics=diag)
        last = 4  # Q_2, Q_3, Q_4 computed (steps 1-3), step 4 (Q_5) failed
    else:
        sol = mv_algorithm2(Q0, 0.1 * M, LAM3, 10, save_every=2, diagnostics=diag)
        last = 2  # the first solve and steps 1, 2; step 3 failed
    assert not sol.success and sol.status == -1
    assert "failed: no solution (test)" in sol.message
    assert sol.k[-1] == last and sol.y.Q.shape[0] == len(sol.k)
    assert sol.failed_step == (last if flow == "mv1" else last + 1)
    assert f"step {sol.failed_step} of 10 failed" in sol.message
    assert sol.iterations.shape == (3,)
    # the fold diagnosis of the failed step's momentum (inside the fold here)
    assert sol.fold is not None and sol.fold > 1 and "inside the fold" in sol.message


def test_progress_bar(capsys, monkeypatch):
    Q0, M, _ = _start(12)
    sol = mv_algorithm2(Q0, M, LAM3, 50, save_every=50, progress=True)
    err = capsys.readouterr().err
    assert sol.success and "MV-Algorithm 2" in err and "50/50" in err
    mv_algorithm2(Q0, M, LAM3, 50, save_every=50)
    assert capsys.readouterr().err == ""
    monkeypatch.setitem(__import__("sys").modules, "tqdm", None)  # tqdm not installed
    with pytest.raises(ImportError, match=r"pip install 'symrb\[progress\]'"):
        symmetric_flow(Q0, Q0 @ M, LAM3, 0.1, 5, progress=True)
    with pytest.raises(InputError, match="progress must be True or False"):
        symmetric_flow(Q0, Q0 @ M, LAM3, 0.1, 5, progress="yes")
