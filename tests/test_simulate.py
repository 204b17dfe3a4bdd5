"""symrb.rigid_body.simulate: every method and option equals the direct call of its
implementation bit for bit, reaches its order against the exact solution, and refuses what it
does not take with an InputError naming the argument."""

from __future__ import annotations

import numpy as np
import pytest

import symrb
from symrb import _compiled
from symrb.compose import (
    composed_rigid_body_flow,
    midpoint_rigid_body_flow,
    rkmk4_rigid_body_flow,
)
from symrb.composition import _KINDS
from symrb.continuous import RigidBody, integrate
from symrb.engine import mv_flow
from symrb.errors import InputError
from symrb.exact import rigid_body_exact
from symrb.rigid_body import METHODS, RigidBodySolution, simulate
from symrb.rigid_body.entry import _finite
from symrb.rigid_body.ivp import NAMES as IVP
from symrb.splitting import splitting_flow

LAM = np.array([0.7, 1.1, 1.6])
Q0 = symrb.random_SO(3, seed=3)
M0 = symrb.hat([0.5, 1.0, 1.5])
SPAN = (0.0, 2.0)
H = 0.1
STEPS = 20


def _same(sol: RigidBodySolution, t, Q, M) -> None:
    """Bit for bit, and nothing non-finite."""
    assert isinstance(sol, RigidBodySolution)
    np.testing.assert_array_equal(sol.t, t)
    np.testing.assert_array_equal(sol.Q, Q)
    np.testing.assert_array_equal(sol.M, M)
    assert np.isfinite(sol.Q).all() and np.isfinite(sol.M).all()


def _same_raw(sol: RigidBodySolution, raw) -> None:
    _same(sol, raw.t, raw.y["Q"], raw.y["M"])
    assert sol.success == getattr(raw, "success", True)
    assert sol.message == getattr(raw, "message", sol.message)


# ---------------------------------------------------------------------------------------------
# bit for bit against the implementations


@pytest.mark.parametrize("name", IVP)
def test_solve_ivp_methods_are_integrate(name: str) -> None:
    y0 = {"Q": Q0, "M": M0}
    te = [0.0, 0.3, 2.0]
    sol = simulate(Q0, M0, LAM, SPAN, method=name, t_eval=te)
    _same_raw(sol, integrate(RigidBody, SPAN, y0, lam=LAM, method=name, t_eval=te))
    assert sol.stats == {"nfev": sol.raw.nfev} and sol.order is None and sol.method == name
    # the solver's own steps; tolerances passed through
    sol = simulate(Q0, M0, LAM, SPAN, method=name, rtol=1e-6, atol=1e-8)
    _same_raw(sol, integrate(RigidBody, SPAN, y0, lam=LAM, method=name, rtol=1e-6, atol=1e-8))
    # save_every: the grid t0 + k h, the last time t1
    sol = simulate(Q0, M0, LAM, SPAN, method=name, h=H, save_every=5)
    ref = integrate(RigidBody, SPAN, y0, lam=LAM, method=name, t_eval=np.arange(0, 21, 5) * H)
    _same_raw(sol, ref)
    np.testing.assert_array_equal(sol.t, [0.0, 0.5, 1.0, 1.5, 2.0])


def test_solve_ivp_condition_option() -> None:
    sol = simulate(Q0, M0, LAM, SPAN, t_eval=[0, 1, 2], condition=True)
    ref = integrate(RigidBody, SPAN, {"Q": Q0, "M": M0}, lam=LAM, t_eval=[0, 1, 2], condition=True)
    _same_raw(sol, ref)
    np.testing.assert_array_equal(sol.raw.condition, ref.condition)


@pytest.mark.parametrize("order", [2, 4, 6, 8, 10])
@pytest.mark.parametrize("backend", ["auto", "numpy", "numba"])
def test_mv_is_mv_flow(order: int, backend: str) -> None:
    if backend == "numba" and not _compiled.AVAILABLE:
        pytest.skip("numba is not installed")
    sol = simulate(Q0, M0, LAM, SPAN, method="mv", h=H, order=order, backend=backend)
    ref = mv_flow(Q0, M0, LAM, H, STEPS, method=backend, order=order)
    _same_raw(sol, ref)
    assert sol.order == order and sol.stats == {"steps": STEPS, "newton_iterations": ref.nit}
    sol = simulate(Q0, M0, LAM, SPAN, method="mv", h=H, order=order, save_every=7, backend=backend)
    _same_raw(sol, mv_flow(Q0, M0, LAM, H, STEPS, save_every=7, method=backend, order=order))


@pytest.mark.parametrize("backend", ["auto", "newton", "fixed-point"])
def test_mv_general_n(backend: str) -> None:
    lam = np.array([0.5, 0.9, 1.3, 2.0])
    Q, M = symrb.random_SO(4, seed=1), 0.8 * symrb.random_so(4, seed=2)
    sol = simulate(Q, M, lam, (0, 1), method="mv", h=0.05, backend=backend)
    _same_raw(sol, mv_flow(Q, M, lam, 0.05, 20, method=backend))


@pytest.mark.parametrize(
    ("order", "kind"), [(p, k) for p, kinds in _KINDS.items() for k in (None, *kinds)]
)
def test_composition_is_composed_rigid_body_flow(order: int, kind: str | None) -> None:
    opts = {} if kind is None else {"kind": kind}
    sol = simulate(Q0, M0, LAM, SPAN, method="composition", h=H, order=order, **opts)
    ref = composed_rigid_body_flow(Q0, M0, LAM, H, STEPS, order, kind=kind)
    _same_raw(sol, ref)
    assert sol.order == order and sol.stats == {"steps": STEPS, "iterations": 0}


@pytest.mark.parametrize("order", [2, 4, 6, 8])
@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_splitting_is_splitting_flow(order: int, backend: str) -> None:
    if backend == "numba" and not _compiled.AVAILABLE:
        pytest.skip("numba not installed")
    sol = simulate(Q0, M0, LAM, SPAN, method="splitting", h=H, order=order, save_every=4,
                   backend=backend)  # fmt: skip
    raw = splitting_flow(Q0, M0, LAM, H, STEPS, order=order, save_every=4, method=backend)
    _same_raw(sol, raw)
    assert sol.order == order and sol.method == "splitting" and sol.stats == {"steps": STEPS}
    assert simulate(Q0, M0, LAM, SPAN, method="splitting", h=H).order == 4  # the default


def test_composition_options() -> None:
    sol = simulate(Q0, M0, LAM, SPAN, method="composition", h=H, step="midpoint", save_every=4)
    ref = composed_rigid_body_flow(Q0, M0, LAM, H, STEPS, 4, step="midpoint", save_every=4)
    _same_raw(sol, ref)
    assert sol.order == 4 and sol.stats["iterations"] == ref.nit > 0
    step = symrb.base_steps.MidpointStep(LAM)
    sol = simulate(Q0, M0, LAM, SPAN, method="composition", h=H, order=2, step=step)
    _same_raw(
        sol,
        composed_rigid_body_flow(Q0, M0, LAM, H, STEPS, 2, step=symrb.base_steps.MidpointStep(LAM)),
    )


@pytest.mark.parametrize(
    ("method", "flow"), [("rkmk4", rkmk4_rigid_body_flow), ("midpoint", midpoint_rigid_body_flow)]
)
def test_rkmk4_and_midpoint(method: str, flow) -> None:
    _same_raw(simulate(Q0, M0, LAM, SPAN, method=method, h=H), flow(Q0, M0, LAM, H, STEPS))
    sol = simulate(Q0, M0, LAM, SPAN, method=method, h=H, save_every=3)
    _same_raw(sol, flow(Q0, M0, LAM, H, STEPS, save_every=3))
    assert sol.order == {"rkmk4": 4, "midpoint": 2}[method]


def test_exact_is_rigid_body_exact() -> None:
    te = [0.0, 0.7, 2.0]
    _same_raw(simulate(Q0, M0, LAM, SPAN, method="exact", t_eval=te), _exact(te))
    sol = simulate(Q0, M0, LAM, SPAN, method="exact", h=H, save_every=4, check=False)
    _same_raw(sol, rigid_body_exact(Q0, M0, LAM, np.arange(0, 21, 4) * H, check=False))
    sol = simulate(Q0, M0, LAM, SPAN, method="exact", h=0.5)  # every h
    np.testing.assert_array_equal(sol.t, [0.0, 0.5, 1.0, 1.5, 2.0])


def _exact(t):
    return rigid_body_exact(Q0, M0, LAM, t)


@pytest.mark.parametrize("method", ["mv", "composition", "rkmk4", "midpoint"])
def test_fixed_step_t_eval_keeps_the_grid_steps(method: str) -> None:
    """t_eval on the grid: the states of the direct run at those steps, at the grid times."""
    te = [0.0, 0.4, 1.2, 2.0]  # steps 0, 4, 12, 20: the run keeps every 4th
    sol = simulate(Q0, M0, LAM, SPAN, method=method, h=H, t_eval=te)
    ref = simulate(Q0, M0, LAM, SPAN, method=method, h=H, save_every=4)
    rows = [0, 1, 3, 5]
    _same(sol, ref.t[rows], ref.Q[rows], ref.M[rows])
    np.testing.assert_allclose(sol.t, te, rtol=0, atol=1e-15)


def test_a_start_time_shifts_the_times_only() -> None:
    for method in ("mv", "rkmk4", "exact", "DOP853"):
        a = simulate(Q0, M0, LAM, (0.0, 1.0), method=method, h=0.25)
        b = simulate(Q0, M0, LAM, (3.0, 4.0), method=method, h=0.25)
        np.testing.assert_array_equal(b.t, 3.0 + a.t)
        tol = 1e-12 if method in ("exact", "DOP853") else 0.0  # rounding of t - t0 only
        np.testing.assert_allclose(b.Q, a.Q, rtol=0, atol=tol)
        np.testing.assert_allclose(b.M, a.M, rtol=0, atol=tol)


def test_fixed_step_t_eval_at_the_start_only() -> None:
    sol = simulate(Q0, M0, LAM, SPAN, method="mv", h=H, t_eval=[0.0])
    _same(sol, [0.0], Q0[None], M0[None])
    assert sol.raw.k.tolist() == [0, STEPS]  # one run of all steps, keeping only the ends


def test_errors_name_the_arrays() -> None:
    for method, h in (("DOP853", None), ("mv", H), ("composition", H), ("exact", H)):
        with pytest.raises(InputError, match="Q0"):
            simulate(2 * Q0, M0, LAM, SPAN, method=method, h=h)
        with pytest.raises(InputError, match="M0"):
            simulate(Q0, M0 + np.eye(3), LAM, SPAN, method=method, h=h)


def test_every_method_is_tested_here() -> None:
    assert set(METHODS) == {*IVP, "mv", "composition", "rkmk4", "midpoint", "exact", "splitting"}


# ---------------------------------------------------------------------------------------------
# independent: against the exact solution, errors at the method's order


def _error(method: str, h: float, order: int | None = None, T: float = 2.0) -> float:
    sol = simulate(Q0, M0, LAM, (0.0, T), method=method, h=h, order=order, t_eval=[T])
    ex = _exact([T])
    return float(max(np.abs(sol.Q[-1] - ex.y.Q[-1]).max(), np.abs(sol.M[-1] - ex.y.M[-1]).max()))


@pytest.mark.parametrize(
    ("method", "order", "h"),
    [("mv", 2, 0.1), ("mv", 4, 0.1), ("mv", 6, 0.25), ("mv", 8, 0.4), ("mv", 10, 0.5),
     ("composition", 2, 0.1), ("composition", 4, 0.1), ("composition", 6, 0.25),
     ("composition", 8, 0.4), ("rkmk4", None, 0.1), ("midpoint", None, 0.1),
     ("splitting", 2, 0.05), ("splitting", 4, 0.1), ("splitting", 6, 0.2),
     ("splitting", 8, 0.4)],
)  # fmt: skip
def test_errors_at_the_methods_order(method: str, order: int | None, h: float) -> None:
    p = order or METHODS[method].default_order
    assert p is not None
    ratio = _error(method, h, order) / _error(method, h / 2, order)
    assert 2 ** (p - 0.6) < ratio < 2 ** (p + 0.6), (method, p, np.log2(ratio))


def test_dop853_against_the_exact_solution() -> None:
    te = np.linspace(0, 2, 5)
    sol = simulate(Q0, M0, LAM, SPAN, t_eval=te, rtol=1e-12, atol=1e-12)
    ex = _exact(te)
    assert np.abs(sol.Q - ex.y.Q).max() < 1e-10 and np.abs(sol.M - ex.y.M).max() < 1e-10


# ---------------------------------------------------------------------------------------------
# failures and errors


def test_a_run_past_the_fold_stops_with_finite_states() -> None:
    for method in ("mv", "composition"):
        sol = simulate(Q0, 30 * M0, LAM, (0, 10), method=method, h=0.5)
        assert not sol.success and "failed" in sol.message
        assert np.isfinite(sol.Q).all() and np.isfinite(sol.M).all()
        assert sol.t.size == sol.Q.shape[0] == sol.M.shape[0] < 21


def test_non_finite_states_are_cut() -> None:
    Q = np.stack([np.eye(3)] * 3)
    M = np.stack([M0, M0, M0 * np.nan])
    raw = type("Raw", (), {"t": np.arange(3.0)})()
    sol = _finite(RigidBodySolution(np.arange(3.0), Q, M, True, "ok", "mv", raw=raw))
    assert not sol.success and sol.t.tolist() == [0.0, 1.0] and "not finite" in sol.message


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"method": "euler"}, r"method must be one of \['RK45'.*'exact', 'splitting'\]"),
        ({"method": "mv"}, "h: method 'mv' is a fixed-step method"),
        ({"method": "rkmk4", "h": 0.3}, "does not divide t_span"),
        ({"method": "mv", "h": 0.1, "t_eval": [0.05]}, "t_eval must be on the step grid"),
        ({"method": "mv", "h": 0.1, "kind": "suzuki"}, r"takes no option \['kind'\]"),
        ({"method": "rkmk4", "h": 0.1, "backend": "numba"}, "it takes none"),
        ({"method": "mv", "h": 0.1, "order": 3}, r"order must be one of \(2, 4, 6, 8, 10\)"),
        ({"method": "composition", "h": 0.1, "order": 10}, "order must be one of"),
        ({"method": "splitting", "h": 0.1, "order": 3}, r"order must be one of \(2, 4, 6, 8\)"),
        ({"method": "splitting", "h": 0.1, "backend": "fortran"}, "method must be one of"),
        ({"method": "splitting", "h": 0.1, "kind": "suzuki"}, r"its options are \['backend'\]"),
        ({"method": "splitting", "h": 0.1, "rtol": 1e-6}, "rtol, atol: method 'splitting'"),
        ({"method": "DOP853", "order": 4}, "has no order"),
        ({"method": "mv", "h": 0.1, "rtol": 1e-6}, "rtol, atol: method 'mv'"),
        ({"method": "mv", "h": 0.1, "progress": True}, "has no progress bar"),
        ({"method": "DOP853", "save_every": 2}, "save_every needs h"),
        ({"method": "mv", "h": 0.1, "save_every": 2, "t_eval": [0.0]}, "not both"),
        ({"method": "mv", "h": 0.1, "save_every": 0}, "save_every must be an integer >= 1"),
        ({"method": "mv", "h": -0.1}, "h must be a finite number > 0"),
        ({"method": "exact"}, "method 'exact' has no steps of its own"),
        ({"t_eval": [1.0, 0.5]}, "t_eval must be a non-empty increasing"),
        ({"t_eval": [3.0]}, "t_eval must lie in t_span"),
    ],
)
def test_errors_name_the_argument(kwargs: dict, match: str) -> None:
    with pytest.raises(InputError, match=match):
        simulate(Q0, M0, LAM, SPAN, **kwargs)


def test_bad_t_span() -> None:
    with pytest.raises(InputError, match="t_span must be"):
        simulate(Q0, M0, LAM, (1.0, 1.0))
