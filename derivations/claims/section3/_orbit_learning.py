"""The computations behind S15's evidence on so(3) that do not read its displayed formulas: the
data and boundary value problem runs of the one- and two-sample checks, the adjoint derivative of
the learning cost against central differences, and the exact so(3) double bracket flow for a
given phase."""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import numpy as np
import sympy as sp

from derivations import reference as ref
from derivations.claims.section3._orbits import np_comm, np_norm2, np_pair, plain
from derivations.symbolic import explicit


@functools.cache
def cost_and_forward() -> tuple[Any, ...]:
    """so(3), two samples, T = 1, u(t) = u0 + t u1: the directional derivative of the cost along
    du(t) = d0 + t d1 by central differences (h = 1e-4, DOP853 rtol 1e-12) and the forward
    trajectory for the adjoint."""
    from scipy.integrate import solve_ivp

    import symrb
    from symrb._generated.adjoint_orbits import orbit_rhs_with_control

    rng = np.random.default_rng(15)
    k, M = 3, 2
    N_, u0, u1, d0, d1 = (ref.random_skew(k, rng, 0.5) for _ in range(5))
    x0 = np.stack([ref.random_skew(k, rng, 0.5) for _ in range(M)])
    opts = {"method": "DOP853", "rtol": 1e-12, "atol": 1e-13}

    def cost(h: float) -> float:
        def f(tt: float, y: np.ndarray) -> np.ndarray:
            xx = y[:-1].reshape(M, k, k)
            uu = u0 + tt * u1 + h * (d0 + tt * d1)
            dx, _ = orbit_rhs_with_control(xx, xx, uu, N_)
            run = 0.5 * np_norm2(uu) - np.sum(symrb.orbits.brockett_potential(xx, N_))
            return np.concatenate([dx.ravel(), [run]])

        s = solve_ivp(f, (0, 1.0), np.concatenate([x0.ravel(), [0.0]]), **opts)
        xT = s.y[:-1, -1].reshape(M, k, k)
        return float(s.y[-1, -1] + np.sum(np_pair(xT, N_)))

    fwd = solve_ivp(
        lambda tt, y: orbit_rhs_with_control(
            y.reshape(M, k, k), y.reshape(M, k, k), u0 + tt * u1, N_
        )[0].ravel(),
        (0, 1.0),
        x0.ravel(),
        dense_output=True,
        **opts,
    )
    h = 1e-4
    return (cost(h) - cost(-h)) / (2 * h), fwd, N_, u0, u1, d0, d1


def endpoint_gradient(pT_expr: sp.MatrixExpr) -> float:
    """Relative difference between the adjoint directional derivative of the cost and central
    differences; the adjoint starts from p^a_T of a displayed endpoint condition (the gradient of
    phi replaced by N), given as ``pT_expr`` in the matrix N, and integrates the emitted costate
    field backwards."""
    from scipy.integrate import solve_ivp

    from symrb._generated.adjoint_orbits import optimal_control, orbit_rhs_with_control

    fd, fwd, N_, u0, u1, d0, d1 = cost_and_forward()
    M, k = 2, 3
    pT = np.array(explicit(pT_expr, {"N": sp.Matrix(N_)}), dtype=float)

    def adjoint(tt: float, y: np.ndarray) -> np.ndarray:
        pp = y[:-1].reshape(M, k, k)
        xx = fwd.sol(tt).reshape(M, k, k)
        uu = u0 + tt * u1
        _, dp = orbit_rhs_with_control(xx, pp, uu, N_)
        integrand = np_pair(uu - optimal_control(xx, pp).sum(axis=0), d0 + tt * d1)
        return np.concatenate([dp.ravel(), [integrand]])

    y_T = np.concatenate([np.broadcast_to(pT, (M, k, k)).ravel(), [0.0]])
    back = solve_ivp(adjoint, (1.0, 0.0), y_T, method="DOP853", rtol=1e-12, atol=1e-13)
    gradient = -back.y[-1, -1]  # integrated from T down to 0
    return abs(gradient - fd) / abs(fd)


def half_angle(tau: sp.Expr) -> tuple[sp.Expr, sp.Expr]:
    """(sin phi, cos phi) from tau = tan(phi / 2)."""
    return 2 * tau / (1 + tau**2), (1 - tau**2) / (1 + tau**2)


def rational_residual(values: sp.Matrix | sp.Expr) -> sp.Integer:
    """The number of entries that are not identically zero as rational functions."""
    items = list(values) if isinstance(values, sp.MatrixBase) else [values]
    return sp.Integer(sum(sp.cancel(sp.together(e)) != 0 for e in items))


ONE_SAMPLE_HORIZONS = (1.0, 2.0, 4.0, 8.0, 16.0)


def one_sample_data() -> tuple[np.ndarray, np.ndarray]:
    """so(3) data of the one-sample checks: ||N|| = 1, ||x_0|| = 0.5, x_0 at the angle 2 from -N
    (decay rate 0.5)."""
    rng = np.random.default_rng(151)
    q = ref.random_rotation(3, rng)
    nu, e = q[:, 2], q[:, 0]
    xi = 0.5 * (np.sin(2.0) * e - np.cos(2.0) * nu)
    return ref.hat(xi), ref.hat(nu)


@functools.cache
def one_sample_runs() -> dict[float, Any]:
    """solve_orbit_bvp for one sample, from the guess p = 0, at each horizon of
    ONE_SAMPLE_HORIZONS."""
    import symrb

    x0, N_ = one_sample_data()
    return {
        Tk: symrb.solve_orbit_bvp(x0, N_, Tk, p_guess=np.zeros((3, 3)))
        for Tk in ONE_SAMPLE_HORIZONS
    }


def second_term_norm(x_: np.ndarray, N_: np.ndarray) -> np.ndarray:
    """||[N, [N, x]]|| in NumPy (the norm of the pairing)."""
    c = np_comm(N_, np_comm(N_, x_))
    return np.sqrt(np_norm2(c))


TWO_SAMPLE_HORIZONS = (2.0, 4.0, 8.0)


def two_sample_data() -> tuple[np.ndarray, np.ndarray]:
    """so(3) data of the two-sample checks: N and two samples x^1_0, x^2_0 (seed 150)."""
    rng = np.random.default_rng(150)
    N_ = ref.random_skew(3, rng, 0.5)
    return np.stack([ref.random_skew(3, rng, 0.5) for _ in range(2)]), N_


@functools.cache
def two_sample_runs() -> dict[float, Any]:
    """solve_orbit_bvp for the two samples at each horizon of TWO_SAMPLE_HORIZONS (collocation
    tolerance 1e-5)."""
    import symrb

    X0, N_ = two_sample_data()
    return {Tk: symrb.solve_orbit_bvp(X0, N_, Tk, tol=1e-5) for Tk in TWO_SAMPLE_HORIZONS}


def numeric(expr: sp.Basic, env: dict[str, np.ndarray]) -> float:
    """A displayed scalar formula evaluated on float64 matrices (explicit on SymPy Floats)."""
    return float(explicit(plain(expr), {k: sp.Matrix(v.tolist()) for k, v in env.items()}))


def exact_so3(
    x0: np.ndarray, N_: np.ndarray, Ts: np.ndarray, tau_fn: Callable[..., Any]
) -> np.ndarray:
    """The exact so(3) double bracket flow at the times Ts from x0 (NumPy, from the displayed
    phase, ``tau_fn(||x_0||, ||N||, tan(phi_0 / 2), T)``): x(T) = r (sin phi_T e - cos phi_T nu/|nu|) in the plane of x0 and N, with e the unit
    vector of x0's component orthogonal to N."""
    xi, nu = ref.vee(x0), ref.vee(N_)
    r, s = np.linalg.norm(xi), np.linalg.norm(nu)
    axis = nu / s
    phi0 = np.arccos(np.clip(-xi @ axis / r, -1.0, 1.0))
    perp = xi + r * np.cos(phi0) * axis
    e = perp / np.linalg.norm(perp)
    tau = tau_fn(r, s, np.tan(phi0 / 2), Ts)
    sin_t, cos_t = 2 * tau / (1 + tau**2), (1 - tau**2) / (1 + tau**2)
    return ref.hat(r * (sin_t[:, None] * e - cos_t[:, None] * axis))
