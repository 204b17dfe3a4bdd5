"""symrb.splitting: the schedule covers every plane once, a step follows the vector field, the
NumPy and numba backends agree, the invariants hold to rounding, a batch is its bodies, merging
steps that save nothing changes only rounding, and bad input is refused naming the argument."""

from __future__ import annotations

import numpy as np
import pytest

import symrb
from symrb import splitting
from symrb.errors import InputError
from symrb.rigid_body.invariants import rigid_body_rhs
from symrb.splitting import plane_groups, splitting_flow

numba_only = pytest.mark.skipif(not splitting.AVAILABLE, reason="numba not installed")


def _body(n: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    return symrb.random_SO(n, seed=seed), A - A.T, rng.uniform(0.5, 2.0, n)


@pytest.mark.parametrize("n", [2, 3, 4, 5, 8, 9])
def test_the_groups_hold_every_plane_once_and_are_disjoint(n: int) -> None:
    groups = plane_groups(n)
    planes = [p for g in groups for p in g]
    assert sorted(planes) == [(i, j) for i in range(n) for j in range(i + 1, n)]
    assert len(groups) == (n - 1 if n % 2 == 0 else n)
    for g in groups:
        assert len({k for p in g for k in p}) == 2 * len(g)


@pytest.mark.parametrize("method", ["numpy", pytest.param("numba", marks=numba_only)])
@pytest.mark.parametrize("n", [3, 6])
def test_a_short_step_follows_the_vector_field(n: int, method: str) -> None:
    """(Phi_h(x) - x)/h - f(x) = O(h): the rotation's angle and sign are the field's."""
    Q, M, lam = _body(n, 1)
    dQ, dM = rigid_body_rhs(Q, M, lam)
    gaps = []
    for h in (1e-3, 5e-4):
        sol = splitting_flow(Q, M, lam, h, 1, method=method)
        gaps.append(max(np.abs((sol.y.Q[-1] - Q) / h - dQ).max(),
                        np.abs((sol.y.M[-1] - M) / h - dM).max()))  # fmt: skip
    assert gaps[0] < 1e-2 and 1.8 < gaps[0] / gaps[1] < 2.2


@numba_only
@pytest.mark.parametrize("order", [2, 4, 6, 8])
@pytest.mark.parametrize("n", [3, 5])
def test_numba_agrees_with_numpy(n: int, order: int) -> None:
    Q, M, lam = _body(n, 2)
    a = splitting_flow(Q, M, lam, 0.05, 60, order=order, save_every=7, method="numpy")
    b = splitting_flow(Q, M, lam, 0.05, 60, order=order, save_every=7, method="numba")
    np.testing.assert_array_equal(a.k, b.k)
    np.testing.assert_allclose(a.y.Q, b.y.Q, rtol=0, atol=1e-13)
    np.testing.assert_allclose(a.y.M, b.y.M, rtol=0, atol=1e-13 * np.abs(M).max())


@pytest.mark.parametrize("method", ["numpy", pytest.param("numba", marks=numba_only)])
def test_merging_steps_that_save_nothing_changes_rounding_only(method: str) -> None:
    Q, M, lam = _body(4, 3)
    every = splitting_flow(Q, M, lam, 0.1, 30, order=4, method=method)
    ends = splitting_flow(Q, M, lam, 0.1, 30, order=4, save_every=30, method=method)
    np.testing.assert_allclose(ends.y.Q[-1], every.y.Q[-1], rtol=0, atol=1e-13)
    np.testing.assert_allclose(ends.y.M[-1], every.y.M[-1], rtol=0, atol=1e-12)
    np.testing.assert_array_equal(ends.t, [0.0, 3.0])


@pytest.mark.parametrize("method", ["numpy", pytest.param("numba", marks=numba_only)])
def test_invariants_hold_to_rounding_at_a_large_step(method: str) -> None:
    """Q in SO(n), M skew with its Casimirs; the energy bounded (h |Omega| about 1)."""
    Q, M, lam = _body(5, 4)
    sol = splitting_flow(Q, M, lam, 0.5, 400, order=2, save_every=20, method=method)
    Qs, Ms = sol.y.Q, sol.y.M
    assert np.abs(np.swapaxes(Qs, -1, -2) @ Qs - np.eye(5)).max() < 1e-13
    assert np.abs(Ms + np.swapaxes(Ms, -1, -2)).max() < 1e-13
    c = symrb.casimir_traces(Ms)
    assert np.abs(c - c[0]).max() < 1e-12 * np.abs(c[0]).max()
    E = symrb.kinetic_energy(Ms, lam)
    assert np.abs(E - E[0]).max() < 0.2 * E[0]


def test_a_batch_is_its_bodies() -> None:
    bodies = [_body(4, s) for s in (5, 6, 7)]
    Q, M, lam = (np.stack(x) for x in zip(*bodies, strict=True))
    sol = splitting_flow(Q, M, lam, 0.1, 12, order=4, save_every=4, method="numpy")
    assert sol.y.Q.shape == (4, 3, 4, 4) and sol.success
    for b, (Qb, Mb, lb) in enumerate(bodies):
        one = splitting_flow(Qb, Mb, lb, 0.1, 12, order=4, save_every=4, method="numpy")
        np.testing.assert_allclose(sol.y.Q[:, b], one.y.Q, rtol=0, atol=1e-15)
        np.testing.assert_allclose(sol.y.M[:, b], one.y.M, rtol=0, atol=1e-14)


def test_zero_steps_and_auto() -> None:
    Q, M, lam = _body(3, 8)
    sol = splitting_flow(Q, M, lam, 0.1, 0)
    assert sol.t.tolist() == [0.0] and sol.success and sol.iterations.size == 0
    a = splitting_flow(Q, M, lam, 0.1, 10, method="auto")
    b = splitting_flow(Q, M, lam, 0.1, 10, method="numpy")  # short: auto is NumPy
    np.testing.assert_array_equal(a.y.M, b.y.M)


Q3, M3, LAM3 = np.eye(3), symrb.hat([0.5, 1.0, 1.5]), np.array([0.7, 1.1, 1.6])


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"h": 0.0}, "h must be a finite number > 0"),
        ({"h": np.nan}, "h"),
        ({"steps": -1}, "steps"),
        ({"steps": 2.5}, "steps"),
        ({"save_every": 0}, "save_every"),
        ({"order": 3}, r"order must be one of \(2, 4, 6, 8\)"),
        ({"order": True}, "order must be one of"),
        ({"method": "fortran"}, "method must be one of auto, numpy, numba"),
        ({"Q0": 2 * Q3}, "Q0"),
        ({"M0": M3 + np.eye(3)}, "M0"),
        ({"lam": [0.7, -1.1, 1.6]}, "lam"),
        ({"lam": [0.7, 1.1]}, "lam|M0|Q0"),
        ({"M0": np.stack([M3] * 2), "Q0": np.stack([Q3] * 3)}, "batch axes do not broadcast"),
    ],
)
def test_bad_input_names_the_argument(kwargs: dict, match: str) -> None:
    args = {"Q0": Q3, "M0": M3, "lam": LAM3, "h": 0.1, "steps": 5, **kwargs}
    Q0, M0, lam, h, steps = (args.pop(k) for k in ("Q0", "M0", "lam", "h", "steps"))
    with pytest.raises(InputError, match=match):
        splitting_flow(Q0, M0, lam, h, steps, **args)


def test_numba_missing_is_an_input_error(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(splitting, "AVAILABLE", False)
    with pytest.raises(InputError, match="method 'numba' needs numba"):
        splitting_flow(Q3, M3, LAM3, 0.1, 5, method="numba")
    assert splitting_flow(Q3, M3, LAM3, 0.1, 5).success  # auto falls back to NumPy
