"""The per-call fast paths of the n = 3 engine against the general paths they short-cut.

The reference of each test is the slower general code path of symrb computing the same map
(itself checked against independent references in test_engine.py and test_compose.py): the
one-body validation fast path of ``mv_flow`` against the batch path, the scalar branch check
against the eigenvalue test, the n = 3 composition loop (NumPy and compiled) against the general
composition loop driving ``MVStepper.step`` stage by stage.
"""

from __future__ import annotations

import numpy as np
import pytest

import symrb
from symrb import _compiled, _mv3
from symrb.compose import composed_rigid_body_flow
from symrb.composition import composition_coefficients
from symrb.engine import MVStepper, mv_flow
from symrb.errors import InputError

LAM = np.array([0.7, 1.1, 1.6])
M0 = symrb.hat([0.5, 1.0, 1.5])
needs_numba = pytest.mark.skipif(not _compiled.AVAILABLE, reason="numba not installed")


def _rotation(rng: np.random.Generator) -> np.ndarray:
    Q, R = np.linalg.qr(rng.normal(size=(3, 3)))
    Q = Q * np.sign(np.diag(R))
    return Q if np.linalg.det(Q) > 0 else -Q


class _Plain:
    """MVStepper as a plain base-step object: composed_rigid_body_flow then takes its general
    loop (one ``MVStepper.step`` a stage), the path the n = 3 loop replaces."""

    def __init__(self, lam: np.ndarray, batch: tuple[int, ...] = ()) -> None:
        self.stepper = MVStepper(lam, batch)

    def step(self, Q: np.ndarray, M: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
        return self.stepper.step(Q, M, h)


@pytest.fixture(params=["numpy", "numba"])
def backend(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> str:
    """The n = 3 composition loop on the NumPy kernels (numba hidden) or compiled (always)."""
    if request.param == "numba":
        if not _compiled.AVAILABLE:
            pytest.skip("numba not installed")
        monkeypatch.setattr(_compiled, "MIN_WORK", 0)
    else:
        monkeypatch.setattr(_compiled, "AVAILABLE", False)
    return str(request.param)


# ---------------------------------------------------------------------------------------------
# mv_flow: one body


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("order", [2, 6])
def test_one_body_fast_path_equals_the_batch_path(seed: int, order: int) -> None:
    rng = np.random.default_rng(seed)
    Q0, M = _rotation(rng), symrb.hat(rng.normal(size=3))
    lam = rng.uniform(0.3, 2.0, 3)
    h = 0.2 * float(symrb.fold_scale(M, lam)) if seed % 2 else 0.05
    one = mv_flow(Q0, M, lam, h, 7, save_every=2, order=order)
    ref = mv_flow(Q0[None], M[None], lam, h, 7, save_every=2, order=order)  # validated as arrays
    assert one.success and ref.success and one.message == ref.message
    np.testing.assert_array_equal(one.k, ref.k)
    np.testing.assert_array_equal(one.iterations, ref.iterations)
    np.testing.assert_array_equal(one.y.Q, ref.y.Q[:, 0])
    np.testing.assert_array_equal(one.y.M, ref.y.M[:, 0])


def test_one_body_fast_path_at_and_past_the_fold() -> None:
    t = float(symrb.fold_scale(M0, LAM))
    for scale, ok in ((0.999, True), (1.02, False)):
        one = mv_flow(np.eye(3), M0, LAM, scale * t, 3)
        ref = mv_flow(np.eye(3)[None], M0[None], LAM, scale * t, 3)
        assert one.success is ok and ref.success is ok
        assert one.message == ref.message
        np.testing.assert_array_equal(one.y.M, ref.y.M[:, 0])


def _bad(Q: np.ndarray | None = None, M: np.ndarray | None = None,
         lam: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    return (np.eye(3) if Q is None else Q, M0.copy() if M is None else M,
            LAM.copy() if lam is None else lam)  # fmt: skip


def _with(a: np.ndarray, index: tuple[int, ...], value: float) -> np.ndarray:
    a = a.copy()
    a[index] = value
    return a


@pytest.mark.parametrize(
    "args",
    [
        _bad(M=_with(M0, (0, 1), np.nan)),
        _bad(M=_with(M0, (2, 2), 1e-6)),
        _bad(M=_with(M0, (1, 0), M0[1, 0] + 1e-8)),
        _bad(M=_with(M0, (0, 2), 1e151)),
        _bad(Q=_with(np.eye(3), (1, 1), np.inf)),
        _bad(Q=_with(np.eye(3), (0, 1), 2e-8)),
        _bad(Q=np.diag([1.0, 1.0, -1.0])),
        _bad(lam=np.array([0.7, 0.0, 1.6])),
        _bad(lam=np.array([0.7, -1.0, 1.6])),
        _bad(lam=np.array([0.7, np.nan, 1.6])),
        _bad(lam=np.array([0.7, 1e200, 1.6])),
    ],
)
def test_one_body_bad_input_raises_as_the_checks_do(args: tuple) -> None:
    """(3, 3) float64 input the fast path must not accept: the same error as from lists (which
    take the full checks)."""
    Q, M, lam = args
    with pytest.raises(InputError) as fast:
        mv_flow(Q, M, lam, 0.1, 2)
    with pytest.raises(InputError) as full:
        mv_flow(Q.tolist(), M.tolist(), lam.tolist(), 0.1, 2)
    assert str(fast.value) == str(full.value)


def test_one_body_inside_the_tolerances_is_accepted() -> None:
    """Input inside the checks' tolerances but outside the fast path's own (Q0 off by 5e-9, M0
    skew to 5e-11) runs, as it does through the full checks."""
    Q = _with(np.eye(3), (0, 1), 5e-9)
    M = _with(M0, (1, 0), M0[1, 0] + 5e-11)
    one = mv_flow(Q, M, LAM, 0.1, 3)
    ref = mv_flow(Q.tolist(), M.tolist(), LAM.tolist(), 0.1, 3)
    assert one.success and ref.success
    np.testing.assert_array_equal(one.y.M, ref.y.M)


def test_scalar_branch_check_matches_the_eigenvalue_test() -> None:
    """_mv3._branch3 (Cholesky in scalars) decides as _on_branch (NumPy) on the U of many s,
    on and off the branch through I."""
    rng = np.random.default_rng(11)
    seen = set()
    for _ in range(400):
        lam = tuple(rng.uniform(0.05, 2.0, 3).tolist())
        m = tuple(rng.normal(size=3).tolist())
        h, s = float(rng.uniform(0.05, 3.0)), float(rng.normal() * 10 ** rng.uniform(-3, 1))
        o = _mv3._kernel3(s, h, *m, *lam, *_mv3._I3)
        U = np.eye(3) + np.array(o[5:14]).reshape(3, 3)
        want = bool(_mv3._on_branch(U[None], np.array([lam]))[0])
        assert _mv3._branch3(s, h, m, lam) == want
        seen.add(want)
    assert seen == {True, False}


# ---------------------------------------------------------------------------------------------
# compositions at n = 3


@pytest.mark.parametrize("order", [4, 6, 8])
@pytest.mark.parametrize("batch", [False, True])
def test_composition_loop_agrees_with_the_general_loop(order: int, batch: bool, backend: str
                                                       ) -> None:  # fmt: skip
    rng = np.random.default_rng(order)
    if batch:
        Q0 = np.stack([_rotation(rng) for _ in range(4)])
        M = np.stack([symrb.hat(rng.normal(size=3)) for _ in range(4)])
        lam = rng.uniform(0.3, 2.0, (4, 3))
    else:
        Q0, M, lam = _rotation(rng), symrb.hat(rng.normal(size=3)), LAM
    got = composed_rigid_body_flow(Q0, M, lam, 0.1, 40, order=order, save_every=7)
    shape = (4,) if batch else ()
    ref = composed_rigid_body_flow(Q0, M, lam, 0.1, 40, order=order, save_every=7,
                                   step=_Plain(lam, shape))  # fmt: skip
    assert got.success and ref.success and got.message == ref.message
    assert got.method.startswith("MV-Algorithm 2 composed to order")
    np.testing.assert_array_equal(got.k, ref.k)
    np.testing.assert_allclose(got.t, ref.t, rtol=1e-15)
    np.testing.assert_allclose(got.y.Q, ref.y.Q, rtol=0, atol=1e-13)
    np.testing.assert_allclose(got.y.M, ref.y.M, rtol=0, atol=1e-13 * np.abs(M).max())


def test_composition_past_the_fold_as_the_general_loop(backend: str) -> None:
    """A stage past the fold: the run ends as the general loop ends it (same message, same
    states), whichever loop found the failure."""
    h = 1.0
    got = composed_rigid_body_flow(np.eye(3), M0, LAM, h, 10, order=4, kind="triple_jump")
    ref = composed_rigid_body_flow(np.eye(3), M0, LAM, h, 10, order=4, kind="triple_jump",
                                   step=_Plain(LAM))  # fmt: skip
    assert not got.success and got.message == ref.message and "past the fold" in got.message
    np.testing.assert_array_equal(got.k, ref.k)
    np.testing.assert_array_equal(got.y.M, ref.y.M)


@needs_numba
def test_compiled_stage_failure_falls_back(monkeypatch: pytest.MonkeyPatch) -> None:
    """A Newton failure reported by the compiled loop (forced here at step 3) sends the run to
    the general loop: the result is the general loop's."""
    monkeypatch.setattr(_compiled, "MIN_WORK", 0)
    real = _compiled.run_mv3
    calls = []

    def failing(*args, **kwargs):  # type: ignore[no-untyped-def]
        ms, qs, fail, extra = real(*args, **kwargs)
        calls.append(1)
        fail[:] = 3
        return ms, qs, fail, extra

    monkeypatch.setattr(_compiled, "run_mv3", failing)
    got = composed_rigid_body_flow(np.eye(3), M0, LAM, 0.1, 6, order=6)
    ref = composed_rigid_body_flow(np.eye(3), M0, LAM, 0.1, 6, order=6, step=_Plain(LAM))
    assert calls and got.success and got.message == ref.message
    np.testing.assert_array_equal(got.y.M, ref.y.M)
    np.testing.assert_array_equal(got.y.Q, ref.y.Q)


def test_composition_loop_python_equals_numpy_path() -> None:
    """The loop of _compiled run as plain Python (what numba compiles) against the NumPy
    composition loop, from the same first root: equal to rounding."""
    gammas = composition_coefficients(6)
    h = 0.1
    m = (0.5, 1.0, 1.5)
    lam_c = tuple(LAM.tolist())
    tol = 2e-9 * (sum(lam_c) - max(lam_c))
    h0 = float(gammas[0]) * h
    s, _ = _mv3._solve_s3(_mv3._s_cold(h0, m, lam_c), h0, m, lam_c, tol, check=True)
    ms, qs, fail, _ = _compiled.run_mv3(np.array([s]), h, np.array([m]), LAM[None],
                                        np.eye(3).reshape(1, 9), np.array([tol]), 12, 4,
                                        gammas=gammas, compiled=False)  # fmt: skip
    ref = _mv3._composed3_run(np.eye(3), M0, MVStepper(LAM), h, 12, 4, gammas, False)
    assert ref is not None and not fail.any()
    np.testing.assert_allclose(qs.reshape(-1, 3, 3), ref[1][1:], rtol=0, atol=1e-15)
    np.testing.assert_allclose(_mv3._hat_cols([ms[:, 0, i] for i in range(3)]), ref[2][1:],
                               rtol=0, atol=1e-15)  # fmt: skip


@needs_numba
def test_compiled_loop_equals_its_python_run() -> None:
    """The compiled loop against the same loop run as Python (a batch with a lam per body, four
    sub-steps a step, a cold s = 0): equal to rounding."""
    gammas = composition_coefficients(4)
    rng = np.random.default_rng(5)
    m = rng.normal(size=(3, 3))
    q = np.stack([_rotation(rng).ravel() for _ in range(3)])
    lam = rng.uniform(0.5, 2.0, (3, 3))
    args = (np.full(3, 0.0), 0.05, m, lam, q, np.full(3, 1e-9), 20, 5)
    a = _compiled.run_mv3(*args, gammas=gammas)
    b = _compiled.run_mv3(*args, gammas=gammas, compiled=False)
    for x, y in zip(a, b, strict=True):
        np.testing.assert_allclose(x, y, rtol=0, atol=1e-14)


def test_without_numba(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(_compiled, "AVAILABLE", False)
    with pytest.raises(InputError, match="numba"):
        mv_flow(np.eye(3), M0, LAM, 0.1, 3, method="numba")
    with pytest.raises(RuntimeError, match="numba"):
        _compiled.run_mv3(np.zeros(1), 0.1, np.zeros((1, 3)), np.ones((1, 3)),
                          np.eye(3).reshape(1, 9), np.full(1, 1e-9), 2, 1)  # fmt: skip
    sol = composed_rigid_body_flow(np.eye(3), M0, LAM, 0.1, 3000, order=8)  # over MIN_WORK
    assert sol.success and sol.k[-1] == 3000


def test_result_finite_check_screen() -> None:
    """The screen of first_nonfinite (every entry finite) decides as the row-wise test: a NaN or
    an inf is found at its time index, in whichever state; huge finite entries are finite."""
    from symrb._results import first_nonfinite

    t = np.arange(4.0)
    big = np.full((4, 3, 3), 1e308)
    assert first_nonfinite(t, {"M": big}) is None
    for bad in (np.nan, np.inf, -np.inf):
        M = np.zeros((4, 3, 3))
        M[2, 1, 0] = bad
        assert first_nonfinite(t, {"M": M, "Q": big}) == (2, ["y.M"])
    assert first_nonfinite(np.array([0.0, np.nan]), {"M": np.zeros((2, 3))}) == (1, ["t"])
    assert first_nonfinite(t, {"M": [[0.0], [0.0], [np.nan], [0.0]]}) == (2, ["y.M"])
