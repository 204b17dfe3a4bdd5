"""The paper's maps computed by the engine (symrb.paper on symrb.engine.mv_flow) against a plain
implementation of the paper's equations (Section 2): the symmetric representation
(``discrbopteqns1``, ``Ukdef1``), MV-Algorithm 1 and MV-Algorithm 2, written here step by step
with every :math:`J_D(U) = M` solved by SciPy (``root`` on the exponential coordinates of
:math:`U`, no symrb solver).  n = 3 and 4, one body and a batch, save_every dividing ``steps`` or
not, ``steps`` 0 and 1, a step past the fold, and MV-Algorithm 1 from a :math:`Q_1` off the branch
through the identity (the step-by-step loop runs then)."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import root

import symrb

EPS = float(np.finfo(float).eps)
H = 0.1
LAMS = {3: np.array([0.7, 1.1, 1.6]), 4: np.array([0.6, 0.9, 1.3, 1.7])}
FLOWS = ("symmetric", "rigid body", "mv1", "mv2")


def _skew(x: np.ndarray, n: int) -> np.ndarray:
    X = np.zeros((n, n))
    X[np.triu_indices(n, 1)] = x
    return X - X.T


def _solve_jd(M: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """U in SO(n) near I with U Lambda - Lambda U^T = M: U = expm(X), X skew, by SciPy's root."""
    n = lam.shape[0]
    iu = np.triu_indices(n, 1)
    L = np.diag(lam)

    def F(x: np.ndarray) -> np.ndarray:
        U = expm(_skew(x, n))
        return (U @ L - L @ U.T - M)[iu]

    x0 = (M / (lam[:, None] + lam[None, :]))[iu]  # J^{-1}(M)/... : the linearisation at I
    got = root(F, x0, method="hybr", options={"xtol": 1e-15})
    U = expm(_skew(got.x, n))
    assert np.abs(U @ L - L @ U.T - M).max() <= 1e-14 * max(1.0, np.abs(M).max())
    return U


def _reference_one(flow: str, Q0: np.ndarray, X: np.ndarray, lam: np.ndarray, steps: int):
    """The states k = 0..steps (MV-Algorithm 1: 0..steps+1) of one body, every step saved."""
    L = np.diag(lam)
    if flow in ("symmetric", "rigid body"):
        Q, P = Q0, (Q0 @ X if flow == "symmetric" else Q0 @ (0.5 * X))
        Qs, Ps, Ms = [Q], [P], [Q.T @ P - P.T @ Q]
        for _ in range(steps):
            U = _solve_jd(H * (Q.T @ P - P.T @ Q), lam)  # J_D(U_k) = h (Q_k^T P_k - P_k^T Q_k)
            Q, P = Q @ U, P @ U
            Qs.append(Q), Ps.append(P), Ms.append(Q.T @ P - P.T @ Q)
        return {"Q": np.array(Qs), "P": np.array(Ps), "M": np.array(Ms)}
    if flow == "mv1":
        Qa, Qb = Q0, Q0 @ _solve_jd(H * X, lam)
        Qs = [Qa, Qb]
        for _ in range(steps):
            Om = Qb.T @ Qa  # (MV1) Omega_{k+1} = Q_{k+1}^T Q_k
            M1 = Om.T @ L - L @ Om  # (MV2)
            M2 = Om @ M1 @ Om.T  # (MV3)
            Om2 = _solve_jd(M2, lam).T  # (MV2) for Omega_{k+2}: J_D(Omega^T) = M_{k+2}
            Qa, Qb = Qb, Qb @ Om2.T  # (MV1)
            Qs.append(Qb)
        return {"Q": np.array(Qs)}
    Q, M = Q0, H * X  # mv2
    Qs, Ms = [Q], [M]
    for _ in range(steps):
        Om = _solve_jd(M, lam).T  # (MV2) for Omega_k
        M = Om @ M @ Om.T  # (MV3)
        Q = Q @ _solve_jd(M, lam)  # (MV2) for Omega_{k+1}, (MV1) Q_{k+1} = Q_k Omega_{k+1}^T
        Qs.append(Q), Ms.append(M)
    return {"Q": np.array(Qs), "M": np.array(Ms)}


def _inputs(n: int, batch: bool):
    rng = np.random.default_rng(100 + n)
    shape = (2,) if batch else ()
    return symrb.random_SO(n, size=shape, seed=rng), symrb.random_so(n, size=shape, seed=rng)


@functools.cache
def _reference(flow: str, n: int, batch: bool, steps: int):
    Q0, X = _inputs(n, batch)
    lam = LAMS[n]
    if not batch:
        return _reference_one(flow, Q0, X, lam, steps)
    items = [_reference_one(flow, Q0[i], X[i], lam, steps) for i in range(2)]
    return {name: np.stack([it[name] for it in items], axis=1) for name in items[0]}


def _run(flow: str, n: int, batch: bool, steps: int, save_every: int, **kw):
    Q0, X = _inputs(n, batch)
    lam = LAMS[n]
    if flow == "symmetric":
        return symrb.symmetric_flow(Q0, Q0 @ X, lam, H, steps, save_every=save_every, **kw)
    if flow == "rigid body":
        return symrb.discrete_rigid_body_flow(Q0, X, lam, H, steps, save_every=save_every, **kw)
    if flow == "mv1":
        Q1 = Q0 @ np.array(symrb.solve_moser_veselov(H * X, lam))
        return symrb.mv_algorithm1(Q0, Q1, lam, steps, save_every=save_every, **kw)
    return symrb.mv_algorithm2(Q0, H * X, lam, steps, save_every=save_every, **kw)


def _tolerance(flow: str, steps: int) -> float:
    """Rounding of ``steps`` steps: the maps are well conditioned (errors grow like k eps),
    except MV-Algorithm 1, which forms each momentum M = Omega^T Lambda - Lambda Omega from
    Omega = Q_{k+1}^T Q_k (an absolute error eps |Lambda| in a momentum of size h |M|, carried
    into every later Q): a relative error of eps |Lambda| / h a step."""
    k = steps + 2
    return 100 * k * EPS * (1.0 / H if flow == "mv1" else 1.0)


CASES = [(20, 1), (20, 3), (20, 7), (21, 21), (0, 1), (0, 3), (1, 1), (1, 2)]


@pytest.mark.parametrize("batch", [False, True])
@pytest.mark.parametrize("n", [3, 4])
@pytest.mark.parametrize("flow", FLOWS)
def test_engine_path_equals_the_papers_equations(flow, n, batch):
    """The saved steps k, the times and every saved state of the engine path equal the plain
    step-by-step run of the paper's equations (subsampled at save_every) to rounding."""
    for steps, every in CASES:
        ref = _reference(flow, n, batch, steps)
        sol = _run(flow, n, batch, steps, every)
        last = steps + 1 if flow == "mv1" else steps
        k = np.arange(0, last + 1, every)
        assert sol.success and sol.message == f"all {steps} steps taken", sol.message
        assert np.array_equal(sol.k, k), (steps, every, sol.k)
        assert np.array_equal(sol.t, k * (H if flow in ("symmetric", "rigid body") else 1.0))
        assert sorted(sol.y) == sorted(ref), sorted(sol.y)
        tol = _tolerance(flow, steps)
        for name in ref:
            scale = max(1.0, np.abs(ref[name]).max())
            err = np.abs(sol.y[name] - ref[name][k]).max() / scale
            assert err <= tol, (flow, steps, every, name, err, tol)
        # the step-by-step loop of symrb (diagnostics=True) computes the same map
        loop = _run(flow, n, batch, steps, every, diagnostics=True)
        for name in ref:
            scale = max(1.0, np.abs(ref[name]).max())
            assert np.abs(sol.y[name] - loop.y[name]).max() / scale <= tol
        assert sol.iterations.shape[0] >= steps  # one engine step a step (MV: and one more)


@pytest.mark.parametrize("n", [3, 4])
@pytest.mark.parametrize("flow", ["symmetric", "rigid body", "mv2"])
def test_a_step_past_the_fold_fails_as_the_reference_loop_says(flow, n):
    """Past the fold of J_D (the first step; the fold scale is constant along a run, so a run
    inside it at the start stays inside): success False, the same message, step, fold scale and
    h_max as the step-by-step loop, and the states reached.  (MV-Algorithm 1 on the engine path
    starts from M_1 = J_D(Q_0^T Q_1) with Q_0^T Q_1 on the branch: inside the fold; its failure
    bookkeeping is tested in tests/test_discrete.py with a failing engine.)"""
    Q0, X = _inputs(n, False)
    lam = LAMS[n]
    X = X * 1.3 * symrb.fold_scale(H * X, lam)  # h X is 30 % past the fold
    if flow == "mv2":
        runs = [symrb.mv_algorithm2(Q0, H * X, lam, 5, diagnostics=d) for d in (False, True)]
    elif flow == "symmetric":
        runs = [symrb.symmetric_flow(Q0, Q0 @ X, lam, H, 5, diagnostics=d) for d in (False, True)]
    else:
        runs = [
            symrb.discrete_rigid_body_flow(Q0, X, lam, H, 5, diagnostics=d) for d in (False, True)
        ]
    eng, ref = runs
    assert not ref.success  # the case is past the fold
    assert not eng.success and eng.status == -1
    assert eng.failed_step == ref.failed_step and np.array_equal(eng.k, ref.k)
    assert eng.fold == pytest.approx(ref.fold, rel=1e-12)
    assert (eng.h_max is None) == (ref.h_max is None)
    if ref.h_max is not None:
        assert eng.h_max == pytest.approx(ref.h_max, rel=1e-12)
    # the same words, numbers to their printed digits (the fold scale of the same momentum)
    assert eng.message == ref.message, (eng.message, ref.message)
    for name in ref.y:
        assert np.abs(eng.y[name] - ref.y[name]).max() <= 1e-13


def test_mv_algorithm1_off_the_branch_runs_the_reference_loop():
    """Q_0^T Q_1 not on the branch through the identity (a rotation by nearly pi): the engine
    would recompute another Q_1, so the step-by-step loop runs (same result as diagnostics=True)."""
    lam = LAMS[3]
    Q0 = np.eye(3)
    Q1 = expm(_skew(np.array([0.0, 0.0, 3.0]), 3))
    a = symrb.mv_algorithm1(Q0, Q1, lam, 6, save_every=2)
    b = symrb.mv_algorithm1(Q0, Q1, lam, 6, save_every=2, diagnostics=True)
    assert np.array_equal(a.y.Q, b.y.Q) and np.array_equal(a.k, b.k)
    assert np.array_equal(a.y.Q[0], Q0)
    ref = _reference_one_mv1_from(Q0, Q1, lam, 6)
    assert np.abs(a.y.Q - ref[::2]).max() <= 1e-12


def _reference_one_mv1_from(Q0: np.ndarray, Q1: np.ndarray, lam: np.ndarray, steps: int):
    L = np.diag(lam)
    Qa, Qb, Qs = Q0, Q1, [Q0, Q1]
    for _ in range(steps):
        Om = Qb.T @ Qa
        M2 = Om @ (Om.T @ L - L @ Om) @ Om.T
        Qa, Qb = Qb, Qb @ _solve_jd(M2, lam)
        Qs.append(Qb)
    return np.array(Qs)


def test_a_run_the_engine_cannot_take_is_the_reference_loops():
    """The engine's scalar n = 3 arithmetic overflows for h = 1e-160 and lam up to 1e77 (found by
    tests/test_fuzz_flows.py), where the step-by-step loop's matrix solve succeeds: the engine's
    failure must not be the answer, the reference loop redoes the run."""
    Q0 = symrb.random_SO(3, seed=0)
    M = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1e-160], [0.0, -1e-160, 0.0]])
    lam = np.array([1.0, 1.0, 1e77])
    assert not symrb.engine.mv_flow(Q0, M, lam, 1e-160, 1).success  # the engine alone fails
    got = symrb.discrete_rigid_body_flow(Q0, M, lam, 1e-160, 1)
    ref = symrb.discrete_rigid_body_flow(Q0, M, lam, 1e-160, 1, diagnostics=True)
    assert got.success and ref.success
    for name in ref.y:
        assert np.array_equal(got.y[name], ref.y[name])
