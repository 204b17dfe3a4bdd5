r"""The maximum principle's two-point boundary value problem of the learning version on adjoint
orbits (paper, Section 3.5, claim S15), solved with ``scipy.integrate.solve_bvp``, and the
conditioning constant of the problem at a solution."""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import solve_bvp, solve_ivp

from .. import _validate as v
from .._generated import adjoint_orbits as _gen
from .._validate import Array
from ..errors import InputError

__all__ = ["OrbitBVPResult", "solve_orbit_bvp"]


@dataclass(frozen=True)
class OrbitBVPResult:
    r"""Solution of the two-point boundary value problem of :func:`solve_orbit_bvp`.

    Attributes
    ----------
    t : ndarray, shape (m,)
        The collocation mesh.
    x, p : ndarray, shape (m, M, n, n)
        The states and costates of the M samples on the mesh.
    u : ndarray, shape (m, n, n)
        The shared optimal control.
    success : bool
        Whether ``solve_bvp`` converged and the solution, the control and the residuals are
        finite.
    message : str
        ``solve_bvp``'s message.
    residual : float
        The largest relative collocation residual reported by ``solve_bvp``.
    bc_residual : float
        The largest boundary condition mismatch.
    costate : str
        ``"corrected"`` or ``"printed"`` (the endpoint condition imposed).
    sol : object
        ``solve_bvp``'s result; :meth:`at` evaluates the solution at any time.
    condition : float or None
        With ``condition=True`` (and success): :math:`\kappa = \max(\kappa_1, \kappa_2)`, the
        conditioning constants of the boundary value problem linearised about the solution
        (see :func:`solve_orbit_bvp`'s Notes): a change :math:`\delta` of the boundary values
        and a defect :math:`r(t)` of the equations move the solution by at most about
        :math:`\kappa(\|\delta\| + \int_0^T\|r\|\,dt)`.  None otherwise.

    Examples
    --------
    >>> import symrb
    >>> x0, N = symrb.hat([1.0, 0.5, 0.2]), symrb.hat([0.0, 0.0, 1.0])
    >>> res = symrb.solve_orbit_bvp(x0, N, 2.0)
    >>> x, p = res.at([0.0, 1.0, 2.0])
    >>> res.success, x.shape
    (True, (3, 1, 3, 3))
    """

    t: Array
    x: Array
    p: Array
    u: Array
    success: bool
    message: str
    residual: float
    bc_residual: float
    costate: str
    sol: Any
    condition: float | None = None

    def at(self, t: ArrayLike) -> tuple[Array, Array]:
        """(x, p) at the times ``t`` (1-D), shapes (len(t), M, n, n), from the collocation spline."""
        ts = np.atleast_1d(v.as_float_array(t, "t"))
        M, k = self.x.shape[1], self.x.shape[-1]
        return _unpack(self.sol.sol(ts), M, k)


@functools.cache
def _iu(k: int) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Row and column indices of the strict upper triangle of a k x k matrix (read-only)."""
    i, j = np.triu_indices(k, 1)
    i.flags.writeable = j.flags.writeable = False
    return i, j


def _pack(x: Array, p: Array) -> Array:
    """(m, M, k, k) skew x, p -> (2 M k(k-1)/2, m) upper-triangle coordinates."""
    i, j = _iu(x.shape[-1])
    m = x.shape[0]
    return np.concatenate([x[..., i, j].reshape(m, -1), p[..., i, j].reshape(m, -1)], axis=1).T


def _y_half(M: int, k: int) -> int:
    """The number of packed coordinates of the states (the costates follow them)."""
    return M * k * (k - 1) // 2


def _unpack(y: Array, M: int, k: int) -> tuple[Array, Array]:
    i, j = _iu(k)
    d = len(i)
    m = y.shape[1]
    yy = y.T.reshape(m, 2, M, d)
    out = np.zeros((2, m, M, k, k))
    out[..., i, j] = np.moveaxis(yy, 1, 0)
    out[..., j, i] = -np.moveaxis(yy, 1, 0)
    return out[0], out[1]


def _extend(
    sol: Callable[[Array], Array], T_old: float, T_new: float, nodes: int
) -> tuple[Array, Array]:
    """The initial guess on [0, T_new] from a solution ``sol`` on [0, T_old], T_new > T_old.

    The first half of ``sol`` as is, its second half shifted to end at T_new, its midpoint value
    in between, on ``nodes`` equally spaced times (``solve_bvp`` refines the layers itself:
    keeping the previous mesh makes it refine far more).
    """
    t = np.linspace(0.0, T_new, nodes)
    half = 0.5 * T_old
    source = np.where(t < half, t, np.maximum(t - (T_new - T_old), half))
    return t, sol(source)


def solve_orbit_bvp(
    x0: ArrayLike,
    N: ArrayLike,
    T: float,
    *,
    costate: Literal["corrected", "printed"] = "corrected",
    nodes: int = 41,
    tol: float = 1e-6,
    max_nodes: int = 20000,
    p_guess: ArrayLike | None = None,
    continuation_start: float = 1.0,
    continuation_growth: float = 1.5,
    condition: bool = False,
) -> OrbitBVPResult:
    r"""Solve the maximum principle's two-point boundary value problem of the learning version (S15).

    Samples :math:`x^a` (``x0`` of shape (n, n) for one sample or (M, n, n)) share the control
    :math:`u^* = \sum_b [p^b, x^b]`;

    .. math::

        \dot x^a = [x^a, u^*],\quad \dot p^a = [p^a, u^*] - [N, [N, x^a]],\quad
        x^a(0) = x^a_0,\quad p^a(T) = \mp N,

    for :math:`V = \sum_a -\tfrac12\|[x^a, N]\|^2` and :math:`\phi(x) = \langle x, N\rangle`.
    ``costate="corrected"`` imposes :math:`p^a_T = -\phi_x = -N` (what the maximum principle with
    :math:`H = \langle p, f\rangle - L` gives); ``"printed"`` imposes the paper's
    :math:`p^a_T = +\partial\phi/\partial x^a_T = N`.

    Solved with ``scipy.integrate.solve_bvp`` on the upper-triangle coordinates of the skew
    matrices, from the initial guess :math:`x \equiv x_0`, :math:`p \equiv` ``p_guess`` (by
    default the terminal value :math:`p_T`; the guess p = 0 gives a singular collocation Jacobian
    when x0 commutes with N).  For ``T > continuation_start`` the horizon is grown geometrically
    (factor ``continuation_growth``) from below ``continuation_start`` to ``T``: Newton's method
    from a constant guess does not converge on long horizons.  The guess on a longer horizon keeps
    the first half of the previous solution, shifts its second half to end at the new horizon and
    holds its midpoint value in between (an optimal trajectory on a long horizon stays near a
    steady state between an initial and a terminal layer); stretching the previous solution in
    time instead widens both layers, and for two samples fails beyond T = 5 or so.  Does not raise
    when the solver fails: check ``success`` and ``residual``.

    Parameters
    ----------
    x0 : array_like, shape (n, n) or (M, n, n)
        The skew-symmetric initial states (one sample, or M).
    N : array_like, shape (n, n)
        The skew-symmetric fixed element.
    T : float
        The horizon, > 0.
    costate : {"corrected", "printed"}, optional
        The endpoint condition: :math:`p^a_T = -N` (corrected) or the paper's :math:`+N`.
    nodes : int, optional
        The number of initial mesh nodes, >= 3.
    tol : float, optional
        ``solve_bvp``'s tolerance.
    max_nodes : int, optional
        ``solve_bvp``'s largest mesh.
    p_guess : array_like, shape (n, n), optional
        A constant initial guess for the costates (default: the terminal value).
    continuation_start : float, optional
        The horizon below which no continuation is needed, > 0.
    continuation_growth : float, optional
        The factor between successive horizons of the continuation, > 1.  At most 100
        horizons (boundary value solves) are taken: a ``T`` further from
        ``continuation_start`` than ``continuation_growth**100`` is refused (InputError).
    condition : bool, optional
        Also compute the conditioning constant of the problem at the solution
        (``OrbitBVPResult.condition``; see Notes); costs one integration of the linearised
        equations for the fundamental matrix.  Not computed by default.

    Returns
    -------
    OrbitBVPResult
        The solution on the collocation mesh, with ``success`` and the residuals.

    Notes
    -----
    The equations are :math:`\dot y = f(y)` for the packed state and costates
    :math:`y = (x, p)` (:math:`D` coordinates: the strict upper triangles) with the separated
    boundary conditions :math:`B_ay(0) + B_by(T) = \beta` (:math:`B_a` picks the states,
    :math:`B_b` the costates).  ``solve_bvp`` returns a cubic spline S whose defect
    :math:`r = S' - f(S)` satisfies ``residual`` :math:`= \max` of its root mean square,
    relative to :math:`1 + |f|`, over each mesh interval :math:`\le` ``tol``.  For the
    fundamental matrix :math:`\dot\Phi = A(t)\Phi`, :math:`\Phi(0) = I` of the linearisation
    :math:`A = \partial f/\partial y` along S and :math:`Q = B_a + B_b\Phi(T)`, the error of S
    is bounded by (Ascher, Mattheij and Russell, *Numerical Solution of Boundary Value Problems
    for ODEs*, 1995, Section 3.2)

    .. math::

        \max_t\|S(t) - y(t)\| \lesssim \kappa_1\|\delta\| + \kappa_2\int_0^T\|r\|\,dt,\qquad
        \kappa_1 = \max_t\|\Phi(t)Q^{-1}\|_2,\quad \kappa_2 = \max_{t,s}\|G(t, s)\|_2,

    with :math:`\delta` the boundary mismatch (``bc_residual``) and the Green's function
    :math:`G(t,s) = \Phi(t)Q^{-1}B_a\Phi(s)^{-1}` for :math:`s < t`,
    :math:`-\Phi(t)Q^{-1}B_b\Phi(T)\Phi(s)^{-1}` for :math:`s > t`.  ``condition=True``
    reports :math:`\kappa = \max(\kappa_1, \kappa_2)` on at most 101 times :math:`t_i` of the
    final mesh, computed stably by multiple shooting: with the transition matrices
    :math:`\Phi_i` of the linearisation over :math:`[t_i, t_{i+1}]` (A by central differences of
    f along the spline, ``solve_ivp`` DOP853 at ``rtol = 1e-8``), the matrix S of the linear
    system :math:`z_{i+1} - \Phi_iz_i = r_i`, :math:`B_az_0 + B_bz_{m-1} = \beta` has the
    blocks :math:`G(t_i, t_{j+1})` and :math:`\Phi(t_i)Q^{-1}` in its inverse, and
    :math:`\kappa` is the largest 2-norm of a :math:`D\times D` block of :math:`S^{-1}`: the
    conditioning of the problem's (multiple-shooting) Newton matrix at the solution, which the
    collocation Newton matrix of ``solve_bvp`` approximates.  NaN when S is singular to working
    precision.

    Accuracy stated and tested (tests/test_conditions.py, against a solve at ``tol = 1e-10``):
    :math:`\max_t\|S(t) - y(t)\|_2 \le \kappa\,(\mathrm{bc\_residual} +
    T\,\mathrm{residual}\,(1 + \max_t\|f\|_\infty))`.

    Examples
    --------
    For one sample the corrected extremal is the double bracket flow:

    >>> import numpy as np
    >>> import symrb
    >>> x0, N = symrb.hat([1.0, 0.5, 0.2]), symrb.hat([0.0, 0.0, 1.0])
    >>> res = symrb.solve_orbit_bvp(x0, N, 2.0)
    >>> res.success, res.x.shape[1:]
    (True, (1, 3, 3))
    >>> flow = symrb.double_bracket_flow(x0, N, res.t)
    >>> bool(np.abs(res.x[:, 0] - flow).max() < 1e-6)
    True

    The conditioning constant bounds the error by the residuals:

    >>> res = symrb.solve_orbit_bvp(x0, N, 2.0, condition=True)
    >>> print(round(res.condition, 2))
    1.35
    """
    nn, xs0 = _bvp_samples(x0, N)
    _check_bvp_options(T, costate, nodes, continuation_start, continuation_growth)
    M, k = xs0.shape[0], nn.shape[-1]
    sign = -1.0 if costate == "corrected" else 1.0
    pT = sign * nn

    def rhs(_t, y):
        x, p = _unpack(y, M, k)
        u = _gen.optimal_control(x, p).sum(axis=1)
        dx, dp = _gen.orbit_rhs_with_control(x, p, u[:, None], nn)
        return _pack(dx, dp)

    # the boundary values packed: x^a(0) = x^a_0 (the states, first half), p^a(T) = p_T
    half = _y_half(M, k)
    boundary = _pack(xs0[None], np.broadcast_to(pT, (1, M, k, k)))[:, 0]

    def bc(ya, yb):
        return np.concatenate([ya[:half] - boundary[:half], yb[half:] - boundary[half:]])

    # continuation in the horizon: solve on [0, T_j] for T_j = T0, growth * T0, ..., T, each
    # solution extended (see _extend) to the initial guess of the next
    horizons = _horizons(float(T), continuation_start, continuation_growth)
    s = np.linspace(0.0, 1.0, int(nodes))
    xg = np.broadcast_to(xs0, (len(s), M, k, k))
    if p_guess is None:
        pg = np.broadcast_to(pT, xg.shape)
    else:
        pg = np.broadcast_to(v.skew(p_guess, "p_guess", k), xg.shape)
    t, y = s * horizons[0], _pack(xg, pg)
    for j, Tj in enumerate(horizons):
        sol = solve_bvp(rhs, bc, t, y, tol=tol, max_nodes=int(max_nodes))
        if not sol.success or j + 1 == len(horizons):
            break
        t, y = _extend(sol.sol, Tj, horizons[j + 1], int(nodes))
    x, p = _unpack(sol.y, M, k)
    u = _gen.optimal_control(x, p).sum(axis=1)
    bcr = float(np.max(np.abs(bc(sol.y[:, 0], sol.y[:, -1]))))
    res = float(np.max(sol.rms_residuals)) if sol.rms_residuals is not None else float("inf")
    finite = all(np.isfinite(a).all() for a in (sol.x, sol.y, u, res, bcr))
    ok = bool(sol.success) and finite
    kappa = _bvp_condition(rhs, sol, half) if condition and ok else None
    note = "" if finite else "; but the solution or its residual is not finite (an overflow)"
    return OrbitBVPResult(
        t=sol.x,
        x=x,
        p=p,
        u=u,
        success=bool(ok),
        message=str(sol.message) + note,
        residual=res,
        bc_residual=bcr,
        costate=costate,
        sol=sol,
        condition=kappa,
    )


def _bvp_samples(x0: ArrayLike, N: ArrayLike) -> tuple[Array, Array]:
    """N, shape (n, n), and the samples, shape (M, n, n), of :func:`solve_orbit_bvp`."""
    nn = v.skew(N, "N")
    if nn.ndim != 2:
        raise InputError(
            f"N must be a single (n, n) skew matrix, got shape {nn.shape}; pass one matrix"
        )
    k = nn.shape[-1]
    xx = v.skew(x0, "x0", k)
    if xx.ndim not in (2, 3):
        raise InputError(
            f"x0 must have shape (n, n) or (M, n, n), got {xx.shape}; pass the samples stacked "
            "along one axis"
        )
    xs0 = xx[None] if xx.ndim == 2 else xx
    M = xs0.shape[0]
    if M < 1:
        raise InputError("x0 must hold at least one sample, got 0; pass at least one")
    return nn, xs0


def _check_bvp_options(
    T: float, costate: str, nodes: int, continuation_start: float, continuation_growth: float
) -> None:
    """Raise InputError for a bad horizon, endpoint condition, continuation or mesh size."""
    if not v.real_scalar(T, "T") > 0:
        raise InputError(f"T must be a positive finite time, got {T!r}; pass a float > 0")
    if costate not in ("corrected", "printed"):
        raise InputError(
            f"costate must be 'corrected' or 'printed', got {costate!r}; pass one of them"
        )
    if not (continuation_start > 0 and continuation_growth > 1):
        raise InputError(
            "continuation_start must be > 0 and continuation_growth > 1, got "
            f"{continuation_start!r} and {continuation_growth!r}; pass values in those ranges"
        )
    if int(nodes) < 3:
        raise InputError(f"nodes must be >= 3, got {nodes}; pass an int >= 3")
    count = math.log(max(T / continuation_start, 1.0)) / math.log(continuation_growth)
    if not count <= MAX_HORIZONS:
        raise InputError(
            f"the continuation from continuation_start = {continuation_start!r} to T = {T!r} at "
            f"continuation_growth = {continuation_growth!r} takes {count:.4g} boundary value "
            f"solves, more than {MAX_HORIZONS}; pass a larger continuation_start or "
            "continuation_growth (or a shorter T)"
        )


#: The most horizons (boundary value solves) the continuation of :func:`solve_orbit_bvp` takes.
MAX_HORIZONS = 100


def _horizons(T: float, start: float, growth: float) -> list[float]:
    """The horizons of the continuation: T / growth^j, ..., T / growth, T, the first <= start."""
    horizons = [T]
    while horizons[0] > start:
        horizons.insert(0, horizons[0] / growth)
    return horizons


def _jacobian(rhs: Callable[[float, Array], Array], t: float, y: Array) -> Array:
    """A = df/dy at y by central differences (the columns of f evaluated at once)."""
    D = y.size
    step = 1e-6 * np.maximum(1.0, np.abs(y))
    E = np.diag(step)
    cols = np.concatenate([y[:, None] + E, y[:, None] - E], axis=1)
    F = rhs(t, cols)
    return np.asarray((F[:, :D] - F[:, D:]) / (2 * step))


def _bvp_condition(rhs: Callable[[float, Array], Array], sol: Any, half: int) -> float:
    """The conditioning constant of the separated BVP y' = f(y), y_x(0), y_p(T) given,
    linearised along the spline ``sol.sol``, by multiple shooting (see :func:`solve_orbit_bvp`'s
    Notes): the largest block norm of the inverse of the multiple-shooting matrix."""
    t_mesh = sol.x
    D = sol.y.shape[0]
    idx = np.unique(np.round(np.linspace(0, t_mesh.size - 1, min(t_mesh.size, 101))).astype(int))
    ts = t_mesh[idx]
    m = ts.size

    def var(t: float, phi: Array) -> Array:
        A = _jacobian(rhs, t, sol.sol(t))
        return np.asarray((A @ phi.reshape(D, D)).ravel())

    # rows i = 0..m-2: z_{i+1} - Phi_i z_i (Phi_i the transition matrix over [t_i, t_{i+1}]);
    # the last D rows: the boundary conditions B_a z_0 + B_b z_{m-1}
    S = np.zeros((m * D, m * D))
    eye = np.eye(D)
    for i in range(m - 1):
        run = solve_ivp(
            var, (ts[i], ts[i + 1]), eye.ravel(), method="DOP853", rtol=1e-8, atol=1e-12
        )
        if not run.success or not np.all(np.isfinite(run.y)):
            return float("nan")
        S[i * D : (i + 1) * D, i * D : (i + 1) * D] = -run.y[:, -1].reshape(D, D)
        S[i * D : (i + 1) * D, (i + 1) * D : (i + 2) * D] = eye
    S[(m - 1) * D : (m - 1) * D + half, :half] = eye[:half, :half]
    S[(m - 1) * D + half :, (m - 1) * D + half : m * D] = eye[half:, half:]
    if np.linalg.cond(S) > 1e-2 / float(np.finfo(float).eps):
        return float("nan")
    blocks = np.linalg.inv(S).reshape(m, D, m, D).transpose(0, 2, 1, 3)
    return float(np.max(np.linalg.norm(blocks, 2, axis=(-2, -1))))
