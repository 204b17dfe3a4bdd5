"""The compiled loops of symrb._compiled_n and symrb._compiled_stages against the NumPy paths they reproduce.

The NumPy paths (symrb.engine.MVStepper's general-n step, symrb.base_steps.RKMK4Step and
MidpointStep) are the reference: the compiled runs must agree with them to rounding, step for step,
single and batched, and report the same iterations.  The compiled exponential is checked against
scipy.linalg.expm and against closed forms (plane rotations; Rodrigues' formula); the general-n
MV loop also against symrb.discrete_rigid_body_flow (a different solver of the same map).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

import symrb
from symrb import _compiled_n, _compiled_stages, compose
from symrb.base_steps import MVStep
from symrb.compose import (
    composed_rigid_body_flow,
    midpoint_rigid_body_flow,
    rkmk4_rigid_body_flow,
)
from symrb.engine import mv_flow
from symrb.errors import InputError

needs_numba = pytest.mark.skipif(not _compiled_n.AVAILABLE, reason="numba not installed")


def _case(n: int, seed: int, batch: int | None = None, scale: float = 1.0):
    rng = np.random.default_rng(seed)
    lam = rng.uniform(0.5, 2.0, n)
    A = rng.normal(size=(n, n))
    M0 = scale * (A - A.T) / np.sqrt(n)
    Q0, _ = np.linalg.qr(rng.normal(size=(n, n)))
    if np.linalg.det(Q0) < 0:
        Q0[:, 0] *= -1
    if batch:
        M0 = M0 * np.linspace(0.3, 1.3, batch)[:, None, None]
        Q0 = np.stack([Q0] * batch)
        lam = lam * np.linspace(1.0, 1.5, batch)[:, None]  # a batch of lam too
    return Q0, M0, lam


def _agree(a, b, tol=1e-13):
    assert a.success and b.success, (a.message, b.message)
    np.testing.assert_array_equal(a.k, b.k)
    scale = max(1.0, float(np.abs(a.y.M).max()))
    assert np.abs(a.y.Q - b.y.Q).max() < tol
    assert np.abs(a.y.M - b.y.M).max() < tol * scale


# ---------------------------------------------------------------------------------------------
# the exponential


@needs_numba
@pytest.mark.parametrize("n", [2, 3, 5, 10])
@pytest.mark.parametrize(
    ("norm", "skew"),
    [(x, s) for x in (1e-6, 0.01, 0.2, 0.9, 2.0, 5.0, 40.0) for s in (True, False)
     if s or x <= 5.0],
)  # fmt: skip
def test_expm_agrees_with_scipy(n, norm, skew):
    """Each Pade order (the 1-norms pick 3, 5, 7, 9 and 13 with squarings); general matrices
    up to norm 5 (past it, exp of a non-normal matrix is ill-conditioned: both results carry
    errors far above eps |exp(A)|), skew ones (RKMK4's arguments) at every norm."""
    rng = np.random.default_rng(n)
    A = rng.normal(size=(4, n, n))
    A = A - np.swapaxes(A, -1, -2) if skew else A
    A = norm * A / np.abs(A).sum(axis=-2).max(axis=-1)[:, None, None]  # 1-norm = norm
    ref = np.stack([sla.expm(a) for a in A])
    got = _compiled_n.expm(A)
    # scipy's own error grows with the norm (scaling and squaring): the bound is relative to
    # the size of exp(A)
    assert np.abs(got - ref).max() <= 64 * np.finfo(float).eps * max(1.0, norm) * np.abs(ref).max()


@needs_numba
@pytest.mark.parametrize("angle", [1e-8, 0.3, 1.7, 3.0, 25.0])
def test_expm_of_skew_matrices_against_closed_forms(angle):
    c, s = np.cos(angle), np.sin(angle)
    A2 = np.array([[0.0, -angle], [angle, 0.0]])
    assert np.abs(_compiled_n.expm(A2) - np.array([[c, -s], [s, c]])).max() < 1e-15 * max(1, angle)
    axis = np.array([0.48, -0.6, 0.64])  # unit
    K = symrb.hat(axis)
    rodrigues = np.eye(3) + s * K + (1.0 - c) * K @ K
    assert np.abs(_compiled_n.expm(angle * K) - rodrigues).max() < 4e-15 * max(1, angle)


def test_expm_needs_numba(monkeypatch):
    monkeypatch.setattr(_compiled_n, "AVAILABLE", False)
    with pytest.raises(RuntimeError, match="numba"):
        _compiled_n.expm(np.zeros((2, 2)))


# ---------------------------------------------------------------------------------------------
# RKMK4 and the midpoint rule


@needs_numba
@pytest.mark.parametrize("flow", [rkmk4_rigid_body_flow, midpoint_rigid_body_flow])
@pytest.mark.parametrize(
    ("n", "batch"), [(2, None), (3, None), (3, 4), (5, None), (10, None), (10, 3)]
)
def test_stages_agree_with_numpy_path(flow, n, batch):
    Q0, M0, lam = _case(n, 11 + n, batch)
    fast = flow(Q0, M0, lam, 0.05, 120, save_every=7, method="numba")
    slow = flow(Q0, M0, lam, 0.05, 120, save_every=7, method="numpy")
    _agree(fast, slow, 1e-13)
    assert fast.iterations.shape == slow.iterations.shape
    # the midpoint rule stops at |change| <= 4 eps |M|: rounding may move one step's count by one
    assert np.abs(fast.iterations - slow.iterations).max(initial=0) <= 1


@needs_numba
def test_stages_long_run_agree():
    Q0, M0, lam = _case(4, 3)
    for flow in (rkmk4_rigid_body_flow, midpoint_rigid_body_flow):
        fast = flow(Q0, M0, lam, 0.1, 2000, save_every=500, method="numba")
        slow = flow(Q0, M0, lam, 0.1, 2000, save_every=500, method="numpy")
        _agree(fast, slow, 1e-11)  # rounding differences grow with the phase


@needs_numba
def test_midpoint_not_converging_numba_reports_as_numpy():
    Q0, M0, lam = np.eye(3), symrb.hat([0.5, 1.0, 1.5]), np.array([0.7, 1.1, 1.6])
    fast = midpoint_rigid_body_flow(Q0, 20 * M0, lam, 2.0, 3, method="numba")
    slow = midpoint_rigid_body_flow(Q0, 20 * M0, lam, 2.0, 3, method="numpy")
    assert not fast.success and fast.message == slow.message
    np.testing.assert_array_equal(fast.k, slow.k)


@needs_numba
@pytest.mark.parametrize("flow", [rkmk4_rigid_body_flow, midpoint_rigid_body_flow])
def test_auto_compiles_long_runs_only(flow, monkeypatch):
    calls = []
    for name in ("run_rkmk4", "run_midpoint"):
        real = getattr(_compiled_stages, name)
        monkeypatch.setattr(
            _compiled_stages, name, lambda *a, real=real, **k: calls.append(1) or real(*a, **k)
        )
    Q0, M0, lam = _case(3, 1)
    flow(Q0, M0, lam, 0.05, 10)
    assert not calls
    flow(Q0, M0, lam, 0.05, 600, save_every=600)
    assert calls


@pytest.mark.parametrize("flow", [rkmk4_rigid_body_flow, midpoint_rigid_body_flow])
def test_stage_backend_bad_input(flow, monkeypatch):
    Q0, M0, lam = _case(3, 1)
    with pytest.raises(InputError, match="method"):
        flow(Q0, M0, lam, 0.05, 3, method="fast")
    monkeypatch.setattr(_compiled_stages, "AVAILABLE", False)
    with pytest.raises(InputError, match="numba"):
        flow(Q0, M0, lam, 0.05, 3, method="numba")
    assert flow(Q0, M0, lam, 0.05, 600, save_every=600).success  # "auto" runs NumPy


# ---------------------------------------------------------------------------------------------
# the general-n Moser-Veselov loop


@needs_numba
@pytest.mark.parametrize(("n", "batch"), [(2, None), (4, None), (5, 3), (8, None), (10, None),
                                          (10, 3), (14, None)])  # fmt: skip
def test_mv_n_agrees_with_numpy_path_and_reference(n, batch):
    Q0, M0, lam = _case(n, 20 + n, batch)
    fast = mv_flow(Q0, M0, lam, 0.05, 150, save_every=7, method="numba")
    slow = mv_flow(Q0, M0, lam, 0.05, 150, save_every=7, method="numpy")
    _agree(fast, slow, 1e-13)
    np.testing.assert_array_equal(fast.iterations, slow.iterations)
    ref = symrb.discrete_rigid_body_flow(Q0, M0, lam, 0.05, 150, save_every=7)
    _agree(fast, ref, 1e-11)


@needs_numba
def test_mv_n_fixed_point_newton_fallback():
    """n = 8 at 0.8 of the fold: the fixed point does not converge in its 60 sweeps, Newton
    finishes (64 sweeps a step)."""
    Q0, M0, lam = _case(8, 5, 3)
    h = 0.8 * float(np.min(symrb.fold_scale(M0, lam)))
    fast = mv_flow(Q0, M0, lam, h, 40, method="numba")
    slow = mv_flow(Q0, M0, lam, h, 40, method="numpy")
    _agree(fast, slow, 1e-12)
    assert slow.iterations.min() > 3 * 60  # the fallback ran at every step
    np.testing.assert_array_equal(fast.iterations, slow.iterations)


@needs_numba
def test_mv_n_failure_in_the_compiled_loop_redone_on_numpy(monkeypatch):
    Q0, M0, lam = _case(5, 2)
    slow = mv_flow(Q0, M0, lam, 0.05, 30, save_every=4, method="numpy")
    monkeypatch.setattr(_compiled_n, "continue_mv_n", lambda run, h: False)
    fast = mv_flow(Q0, M0, lam, 0.05, 30, save_every=4, method="numba")
    np.testing.assert_array_equal(fast.y.M, slow.y.M)


@needs_numba
def test_mv_n_past_the_fold_ends_run():
    Q0, M0, lam = _case(4, 9)
    t = float(np.min(symrb.fold_scale(M0, lam)))
    fast = mv_flow(Q0, M0, lam, 1.2 * t, 3, method="numba")
    slow = mv_flow(Q0, M0, lam, 1.2 * t, 3, method="numpy")
    assert not fast.success and fast.message == slow.message


@needs_numba
def test_mv_n_auto_compiles_long_runs_only(monkeypatch):
    calls = []
    real = _compiled_n.run_mv_n
    monkeypatch.setattr(_compiled_n, "run_mv_n", lambda *a, **k: calls.append(1) or real(*a, **k))
    Q0, M0, lam = _case(10, 1)
    mv_flow(Q0, M0, lam, 0.05, 20)
    assert not calls
    mv_flow(Q0, M0, lam, 0.05, 2000, save_every=2000)
    assert calls


# ---------------------------------------------------------------------------------------------
# compositions of the general-n Moser-Veselov step


def _spy_composed(monkeypatch, calls, after=None):
    """Count the calls of run_composed_n; ``after`` may alter what it returns."""
    real = _compiled_n.run_composed_n

    def spy(*a, **k):
        calls.append(1)
        out = real(*a, **k)
        return out if after is None else after(*out)

    monkeypatch.setattr(_compiled_n, "run_composed_n", spy)


@needs_numba
@pytest.mark.parametrize("order", [4, 6, 8])
@pytest.mark.parametrize(("n", "batch"), [(2, None), (4, None), (10, None), (5, 3)])
def test_composed_n_agrees_with_numpy_path(order, n, batch, monkeypatch):
    """The compiled composition against the NumPy one (MVStepper per stage) and against the
    composition of MVStep (symrb.solve_moser_veselov); 23 steps saved every 5 (not a divisor),
    and every step (the first one comes from the NumPy stepper)."""
    Q0, M0, lam = _case(n, 40 + n + order, batch)
    args = (Q0, M0, lam, 0.05, 23)
    for every in (5, 1):
        monkeypatch.setattr(compose, "_NUMBA_MIN_WORK_N", 10**18)
        slow = composed_rigid_body_flow(*args, order=order, save_every=every)
        ref = composed_rigid_body_flow(*args, order=order, save_every=every, step=MVStep(lam))
        calls: list[int] = []
        _spy_composed(monkeypatch, calls)
        monkeypatch.setattr(compose, "_NUMBA_MIN_WORK_N", 0)
        fast = composed_rigid_body_flow(*args, order=order, save_every=every)
        assert calls and fast.method == slow.method
        _agree(fast, slow, 1e-13)
        _agree(fast, ref, 1e-12)
        np.testing.assert_array_equal(fast.t, slow.t)
        assert fast.y.Q.shape == slow.y.Q.shape and fast.iterations.shape == (0,)


@needs_numba
@pytest.mark.parametrize("fake", ["fail", "nan"])
def test_composed_n_failure_in_the_compiled_loop_redone_on_numpy(fake, monkeypatch):
    """An item that fails in the compiled loop (or a non-finite state) sends the run to the
    NumPy loop: the result is the NumPy path's, bit for bit."""
    Q0, M0, lam = _case(6, 8, 2)
    monkeypatch.setattr(compose, "_NUMBA_MIN_WORK_N", 10**18)
    slow = composed_rigid_body_flow(Q0, M0, lam, 0.05, 12, order=6, save_every=4)

    def broken(Qs, Ms, fail):
        if fake == "fail":
            fail[1] = 3
        else:
            Ms[-1, 0, 0, 1] = np.nan
        return Qs, Ms, fail

    calls: list[int] = []
    _spy_composed(monkeypatch, calls, broken)
    monkeypatch.setattr(compose, "_NUMBA_MIN_WORK_N", 0)
    fast = composed_rigid_body_flow(Q0, M0, lam, 0.05, 12, order=6, save_every=4)
    assert calls
    np.testing.assert_array_equal(fast.y.M, slow.y.M)
    np.testing.assert_array_equal(fast.y.Q, slow.y.Q)
    assert fast.success and fast.message == slow.message


@needs_numba
def test_composed_n_past_the_fold_reported_as_numpy(monkeypatch):
    """A sub-step past the fold (the triple jump's -1.70 h at h = 0.8 of the fold scale): the
    NumPy loop reports it, whichever backend was chosen."""
    Q0, M0, lam = _case(4, 9)
    h = 0.8 * float(np.min(symrb.fold_scale(M0, lam)))
    monkeypatch.setattr(compose, "_NUMBA_MIN_WORK_N", 0)
    fast = composed_rigid_body_flow(Q0, M0, lam, h, 3, order=4, kind="triple_jump")
    monkeypatch.setattr(compose, "_NUMBA_MIN_WORK_N", 10**18)
    slow = composed_rigid_body_flow(Q0, M0, lam, h, 3, order=4, kind="triple_jump")
    assert not fast.success and fast.message == slow.message
    assert "past the fold" in fast.message
    np.testing.assert_array_equal(fast.k, slow.k)


@needs_numba
def test_composed_n_auto_compiles_long_runs_only(monkeypatch):
    calls: list[int] = []
    _spy_composed(monkeypatch, calls)
    Q0, M0, lam = _case(10, 1)
    composed_rigid_body_flow(Q0, M0, lam, 0.05, 20, order=4)  # 10^5 stage-n^3: NumPy
    assert not calls
    composed_rigid_body_flow(Q0, M0, lam, 0.05, 20, order=4, progress=True)
    assert not calls
    composed_rigid_body_flow(Q0, M0, lam, 0.02, 400, order=4, save_every=400)
    assert calls


def test_composed_n_without_numba_runs_numpy(monkeypatch):
    """numba unavailable: the NumPy loop, whatever the size of the run."""
    Q0, M0, lam = _case(5, 4)
    calls: list[int] = []
    _spy_composed(monkeypatch, calls)
    monkeypatch.setattr(compose, "_NUMBA_MIN_WORK_N", 0)
    monkeypatch.setattr(_compiled_n, "AVAILABLE", False)
    sol = composed_rigid_body_flow(Q0, M0, lam, 0.05, 7, order=4, save_every=3)
    assert sol.success and not calls
    ref = composed_rigid_body_flow(Q0, M0, lam, 0.05, 7, order=4, save_every=3, step=MVStep(lam))
    _agree(sol, ref, 1e-12)
