"""symrb.engine (Cayley-Newton Moser-Veselov) against independent references.

The reference is symrb.discrete_rigid_body_flow (U-parametrised Newton with a Riccati start, a
different solver of the same map); the orthogonality and conservation checks compare with exact
invariants (Q^T Q = I, the energy and |M| are conserved by the exact discrete map).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import symrb
from symrb import _compiled
from symrb.engine import MVStepper, mv_flow
from symrb.errors import InputError


def _case(n: int, seed: int, scale: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    lam = rng.uniform(0.5, 2.0, n)
    A = rng.normal(size=(n, n))
    M0 = scale * (A - A.T) / np.sqrt(n)
    Q0, _ = np.linalg.qr(rng.normal(size=(n, n)))
    if np.linalg.det(Q0) < 0:
        Q0[:, 0] *= -1
    return Q0, M0, lam


@pytest.mark.parametrize(
    ("n", "method"), [(3, "auto"), (4, "newton"), (4, "fixed-point"), (10, "auto"), (10, "newton")]
)
def test_agrees_with_discrete_rigid_body_flow(n: int, method: str) -> None:
    Q0, M0, lam = _case(n, 7 + n)
    steps = 1000 if n < 10 else 200
    got = mv_flow(Q0, M0, lam, 0.05, steps, save_every=50, method=method)
    ref = symrb.discrete_rigid_body_flow(Q0, M0, lam, 0.05, steps, save_every=50)
    assert got.success and ref.success
    np.testing.assert_array_equal(got.k, ref.k)
    assert np.abs(got.y.Q - ref.y.Q).max() < 2e-12
    assert np.abs(got.y.M - ref.y.M).max() < 2e-12 * max(1.0, np.abs(M0).max())


@settings(max_examples=15, deadline=None)
@given(st.integers(0, 2**16), st.floats(0.01, 0.3), st.floats(0.1, 3.0))
def test_n3_one_step_solves_jd(seed: int, h: float, scale: float) -> None:
    """One step from a cold start: U = Q0^T Q1 solves J_D(U) = h M0 (the reference residual)."""
    Q0, M0, lam = _case(3, seed, scale)
    stepper = MVStepper(lam)
    Q1, M1 = stepper.step(Q0, M0, h)
    U = Q0.T @ Q1
    assert np.abs(U @ np.diag(lam) - np.diag(lam) @ U.T - h * M0).max() < 1e-13
    assert np.abs(M1 - U.T @ M0 @ U).max() < 1e-13


@pytest.mark.parametrize("n", [3, 5])
def test_batch_equals_loop(n: int) -> None:
    Q0, M0, lam = _case(n, 3)
    scales = np.linspace(0.2, 1.5, 6)
    Ms = M0 * scales[:, None, None]
    Qs = np.stack([Q0] * 6)
    batch = mv_flow(Qs, Ms, lam, 0.05, 100, save_every=25)
    for i in range(6):
        one = mv_flow(Q0, Ms[i], lam, 0.05, 100, save_every=25)
        assert np.abs(batch.y.Q[:, i] - one.y.Q).max() < 1e-14
        assert np.abs(batch.y.M[:, i] - one.y.M).max() < 1e-14


@pytest.mark.parametrize("n", [3, 8])
def test_stepper_matches_flow_and_survives_h_changes(n: int) -> None:
    """A composition-like sequence of sub-steps (negative one included, repeated ones that use
    the extrapolated warm start) on one stepper gives the same states as fresh steppers (cold
    starts) for each sub-step."""
    Q, M, lam = _case(n, 11)
    warm = MVStepper(lam)
    Qw, Mw = Q, M
    Qc, Mc = Q, M
    for h in (0.05, -0.03, 0.05, 0.05, 0.05, 0.02, 0.05):
        Qw, Mw = warm.step(Qw, Mw, h)
        Qc, Mc = MVStepper(lam).step(Qc, Mc, h)
    assert np.abs(Qw - Qc).max() < 1e-14 * n
    assert np.abs(Mw - Mc).max() < 1e-14 * n


def test_orthogonality_after_1e4_steps() -> None:
    Q0, M0, lam = _case(3, 5)
    sol = mv_flow(Q0, M0, lam, 0.05, 10_000, save_every=10_000)
    Q = sol.y.Q[-1]
    assert np.abs(Q.T @ Q - np.eye(3)).max() < 2e-14  # random walk, not 1e4 * eps


def test_energy_and_casimir_short_run() -> None:
    """2 * 10^4 steps: energy and |m| stay within a random-walk band (sqrt(k) eps), far below
    linear drift (k eps = 4e-12)."""
    Q0, M0, lam = _case(3, 9)
    sol = mv_flow(Q0, M0, lam, 0.05, 20_000, save_every=1000)
    H = symrb.kinetic_energy(sol.y.M, lam)
    C = np.einsum("kij,kij->k", sol.y.M, sol.y.M)
    assert np.abs(H / H[0] - 1).max() < 2e-13
    assert np.abs(C / C[0] - 1).max() < 2e-13


def test_past_the_fold_ends_run() -> None:
    M = symrb.hat([0.5, 1.0, 1.5])
    lam = np.array([0.7, 1.1, 1.6])
    t = float(symrb.fold_scale(M, lam))
    sol = mv_flow(np.eye(3), M, lam, 1.2 * t, 3)
    assert not sol.success and "failed" in sol.message
    assert sol.k[-1] == 0


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"h": 0.0}, "h must be"),
        ({"h": float("nan")}, "h"),
        ({"steps": -1}, "steps"),
        ({"save_every": 0}, "save_every"),
        ({"lam": [1.0, -1.0, 2.0]}, "lam"),
        ({"M0": np.ones((3, 3))}, "M0 must be skew"),
        ({"Q0": 2 * np.eye(3)}, "Q0"),
        ({"method": "magic"}, "method"),
        ({"lam": [1.0, 2.0]}, "to match lam"),
    ],
)
def test_bad_input(kwargs: dict, match: str) -> None:
    args = {"Q0": np.eye(3), "M0": symrb.hat([0.1, 0.2, 0.3]), "lam": [0.7, 1.1, 1.6],
            "h": 0.1, "steps": 3} | kwargs  # fmt: skip
    with pytest.raises(InputError, match=match):
        mv_flow(**args)


def test_stepper_bad_input() -> None:
    with pytest.raises(InputError, match="batch_shape"):
        MVStepper([0.7, 1.1, 1.6], batch_shape=(2, "x"))  # type: ignore[arg-type]
    with pytest.raises(InputError, match="lam"):
        MVStepper([0.0, 1.1, 1.6])


def test_inputs_not_mutated() -> None:
    Q0, M0, lam = _case(3, 1)
    Qc, Mc, lc = Q0.copy(), M0.copy(), lam.copy()
    MVStepper(lam).step(Q0, M0, 0.1)
    mv_flow(Q0, M0, lam, 0.1, 5)
    assert np.array_equal(Q0, Qc) and np.array_equal(M0, Mc) and np.array_equal(lam, lc)


def test_batch_with_a_lam_per_body() -> None:
    """n = 3, lam of shape (4, 3) (component vectors of lam in the kernels) against
    discrete_rigid_body_flow body by body."""
    Q0, M0, _ = _case(3, 21)
    lams = np.random.default_rng(2).uniform(0.5, 2.0, (4, 3))
    got = mv_flow(np.stack([Q0] * 4), np.stack([M0] * 4), lams, 0.05, 300, save_every=100)
    for i in range(4):
        ref = symrb.discrete_rigid_body_flow(Q0, M0, lams[i], 0.05, 300, save_every=100)
        assert np.abs(got.y.Q[:, i] - ref.y.Q).max() < 1e-12
        assert np.abs(got.y.M[:, i] - ref.y.M).max() < 1e-12


def test_n3_one_newton_step_per_step() -> None:
    """At a fixed h, s = b.x is conserved, so every step after the first is one kernel call."""
    Q0, M0, lam = _case(3, 4)
    sol = mv_flow(Q0, M0, lam, 0.05, 500, save_every=500)
    assert np.all(sol.iterations[1:] == 1)


@pytest.mark.skipif(not _compiled.AVAILABLE, reason="numba not installed")
@pytest.mark.parametrize("batch", [None, 5])
def test_numba_agrees_with_numpy_path_and_reference(batch: int | None) -> None:
    Q0, M0, lam = _case(3, 31)
    if batch:
        Q0 = np.stack([Q0] * batch)
        M0 = M0 * np.linspace(0.3, 1.4, batch)[:, None, None]
    kw = {"save_every": 7}
    fast = mv_flow(Q0, M0, lam, 0.05, 1000, method="numba", **kw)
    slow = mv_flow(Q0, M0, lam, 0.05, 1000, method="numpy", **kw)
    np.testing.assert_array_equal(fast.k, slow.k)
    assert np.abs(fast.y.Q - slow.y.Q).max() < 1e-13
    assert np.abs(fast.y.M - slow.y.M).max() < 1e-13
    # an independent solver: rounding differences grow with the phase (|M| up to 2.6 here)
    ref = symrb.discrete_rigid_body_flow(Q0, M0, lam, 0.05, 1000, **kw)
    assert np.abs(fast.y.Q - ref.y.Q).max() < 1e-11
    assert np.abs(fast.y.M - ref.y.M).max() < 1e-11 * max(1.0, np.abs(M0).max())


@pytest.mark.skipif(not _compiled.AVAILABLE, reason="numba not installed")
def test_numba_past_the_fold_ends_run() -> None:
    M = symrb.hat([0.5, 1.0, 1.5])
    lam = np.array([0.7, 1.1, 1.6])
    t = float(symrb.fold_scale(M, lam))
    sol = mv_flow(np.eye(3), M, lam, 1.2 * t, 3, method="numba")
    assert not sol.success and sol.k[-1] == 0


@pytest.mark.parametrize("n", [3, 4])
def test_numba_method_needs_numba(n: int, monkeypatch: pytest.MonkeyPatch) -> None:
    from symrb import _compiled_n

    monkeypatch.setattr(_compiled, "AVAILABLE", False)
    monkeypatch.setattr(_compiled_n, "AVAILABLE", False)
    Q0, M0, lam = _case(n, 1)
    with pytest.raises(InputError, match="numba"):
        mv_flow(Q0, M0, lam, 0.05, 3, method="numba")
    assert mv_flow(Q0, M0, lam, 0.05, 3).success  # "auto" runs NumPy


# --- the preprocessed method (order > 2, n = 3) ----------------------------------------------


def _exact_end(M0: np.ndarray, lam: np.ndarray, T: float) -> tuple[np.ndarray, np.ndarray]:
    ex = symrb.exact.rigid_body_exact(np.eye(3), M0, lam, [T])
    return ex.y.Q[-1], ex.y.M[-1]


@pytest.mark.parametrize("order", [4, 6, 8, 10])
def test_preprocessed_order_against_exact_solution(order: int) -> None:
    """Error ratio at h and h/2 against the elliptic solution (independent of the engine)."""
    lam = np.array([0.7, 1.1, 1.6])
    M0 = symrb.hat([0.5, 1.0, 1.5])
    Qe, Me = _exact_end(M0, lam, 5.0)
    h = {4: 0.1, 6: 0.2, 8: 0.25, 10: 0.5}[order]
    errs = []
    for hh in (h, h / 2):
        k = round(5.0 / hh)
        sol = mv_flow(np.eye(3), M0, lam, 5.0 / k, k, save_every=k, order=order, method="numpy")
        errs.append(max(np.abs(sol.y.M[-1] - Me).max(), np.abs(sol.y.Q[-1] - Qe).max()))
    assert 1e-13 < errs[1] < errs[0]
    assert abs(np.log2(errs[0] / errs[1]) - order) < 0.3, errs


@pytest.mark.parametrize("batch", [None, 3])
def test_preprocessed_invariants_and_batch(batch: int | None) -> None:
    """|m| is conserved to rounding (the modified map is a rigid body step); a batch with a lam
    per body equals the bodies run one at a time."""
    rng = np.random.default_rng(5)
    lam = rng.uniform(0.5, 2.0, (3, 3)) if batch else np.array([0.7, 1.1, 1.6])
    M0 = (
        np.stack([symrb.hat(rng.normal(size=3)) for _ in range(3)])
        if batch
        else symrb.hat([0.5, 1.0, 1.5])
    )
    sol = mv_flow(np.eye(3), M0, lam, 0.1, 300, save_every=100, order=8, method="numpy")
    norm = np.linalg.norm(sol.y.M, axis=(-2, -1))
    assert np.abs(norm / norm[:1] - 1).max() < 50 * np.finfo(float).eps
    if batch:
        for b in range(3):
            one = mv_flow(np.eye(3), M0[b], lam[b], 0.1, 300, save_every=100, order=8,
                          method="numpy")  # fmt: skip
            assert np.abs(one.y.M - sol.y.M[:, b]).max() < 1e-13
            assert np.abs(one.y.Q - sol.y.Q[:, b]).max() < 1e-13


@pytest.mark.skipif(not _compiled.AVAILABLE, reason="numba not installed")
@pytest.mark.parametrize("batch", [None, 4])
def test_preprocessed_numba_agrees_with_numpy(batch: int | None) -> None:
    rng = np.random.default_rng(9)
    lam = rng.uniform(0.5, 2.0, (batch, 3)) if batch else np.array([0.7, 1.1, 1.6])
    M0 = (
        np.stack([symrb.hat(rng.normal(size=3)) for _ in range(batch)])
        if batch
        else symrb.hat([0.5, 1.0, 1.5])
    )
    a = mv_flow(np.eye(3), M0, lam, 0.1, 500, save_every=50, order=10, method="numpy")
    b = mv_flow(np.eye(3), M0, lam, 0.1, 500, save_every=50, order=10, method="numba")
    assert a.success and b.success
    assert np.abs(a.y.M - b.y.M).max() < 1e-12
    assert np.abs(a.y.Q - b.y.Q).max() < 1e-12
    # and the preprocessing is applied on the compiled path (order 2 differs by far more)
    c = mv_flow(np.eye(3), M0, lam, 0.1, 500, save_every=50, order=2, method="numba")
    assert np.abs(c.y.M - b.y.M).max() > 1e-4


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [({"order": 3}, "order must be one of"), ({"order": True}, "order must be one of")],
)
def test_preprocessed_bad_order(kwargs: dict, match: str) -> None:
    with pytest.raises(InputError, match=match):
        mv_flow(np.eye(3), symrb.hat([0.1, 0.2, 0.3]), [0.7, 1.1, 1.6], 0.1, 2, **kwargs)


def test_preprocessed_needs_n3() -> None:
    Q0, M0, lam = _case(4, 1)
    with pytest.raises(InputError, match=r"needs n = 3, got n = 4.*composed_rigid_body_flow"):
        mv_flow(Q0, M0, lam, 0.1, 2, order=4)


def test_preprocessed_step_too_large_is_an_error() -> None:
    """A step so large that the series makes the modified inertia non-positive ends the run
    with a message naming the order and the way out."""
    sol = mv_flow(np.eye(3), symrb.hat([3.0, 4.0, 5.0]), [0.7, 1.1, 1.6], 2.0, 5, order=10)
    assert not sol.success
    assert "modified Lambda" in sol.message and "smaller h" in sol.message
