r"""Optimal control on adjoint orbits and double bracket flows (paper, Section 3.5).

The control system is :math:`\dot x = [x, u]` on an adjoint orbit of :math:`\mathfrak{so}(n)` (skew
matrices; the paper also allows :math:`\mathfrak{su}(n)`), with the cost

.. math::

    \int_0^T \tfrac12\|u\|^2 - V(x)\,dt \;+\; \sum_a \phi(x^a_T),\qquad
    V(x) = -\tfrac12\|[x, n]\|^2,\quad \phi(x) = \langle x, n\rangle,

:math:`\langle a, b\rangle = -\tfrac12\operatorname{tr}(ab)`, :math:`\|a\|^2 = \langle a,a\rangle`.
With :math:`H = \sum_a\langle p^a, [x^a, u]\rangle - \tfrac12\|u\|^2 + \sum_a V(x^a)` the maximum
principle gives (claims S13-S15)

.. math::

    u^* = \sum_b [p^b, x^b],\qquad \dot x^a = [x^a, u^*],\qquad
    \dot p^a = [p^a, u^*] - [n, [n, x^a]],\qquad p^a_T = -\phi_x(x^a_T) = -n.

The paper prints :math:`p^a_T = +\partial\phi/\partial x^a_T` and per-sample controls
:math:`[p^a, x^a]`; both are corrected here (see the errata).  For one sample the extremal is
exactly :math:`p \equiv -n` and the double bracket flow :math:`\dot x = [x, [x, n]]`.

Each vector field calls one kernel generated in :mod:`symrb._generated.adjoint_orbits` by
the claims S13-S15 of :mod:`derivations.claims.section3`.  Here ``N`` is the paper's fixed
element ``n``.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import solve_bvp, solve_ivp
from scipy.optimize import OptimizeResult

from . import _conditioning as _cond
from . import _validate as v
from ._generated import adjoint_orbits as _gen
from ._validate import Array
from .errors import InputError, NotConvergedError

__all__ = [
    "orbit_extremal_rhs",
    "orbit_hamiltonian",
    "brockett_potential",
    "double_bracket_rhs",
    "double_bracket_flow",
    "DoubleBracketInfo",
    "toda_flow",
    "one_sample_second_term",
    "two_sample_bound",
    "OrbitBVPResult",
    "solve_orbit_bvp",
]


def _pair_xN(x: ArrayLike, N: ArrayLike, xname: str = "x") -> tuple[Array, Array]:
    nn = v.skew(N, "N")
    return v.skew(x, xname, nn.shape[-1]), nn


def orbit_extremal_rhs(x: ArrayLike, p: ArrayLike, N: ArrayLike) -> tuple[Array, Array]:
    r"""The extremal vector field of the orbit problem with Brockett's potential (paper, Section 3.4).

    .. math:: \dot x = [x, [p, x]],\qquad \dot p = [p, [p, x]] - [N, [N, x]].

    Parameters
    ----------
    x, p, N : array_like, shape (..., n, n)
        The skew-symmetric state, costate and fixed element (broadcast against each other).

    Returns
    -------
    xdot, pdot : ndarray, shape (..., n, n)
        The vector field, of the broadcast shape.

    Examples
    --------
    With the costate :math:`p = -N` of the one-sample extremal the state follows the double
    bracket flow:

    >>> import numpy as np
    >>> import symrb
    >>> x, N = symrb.hat([1.0, 0.5, 0.2]), symrb.hat([0.0, 0.0, 1.0])
    >>> xdot, pdot = symrb.orbit_extremal_rhs(x, -N, N)
    >>> bool(np.allclose(xdot, symrb.double_bracket_rhs(x, N)))
    True
    """
    xx, nn = _pair_xN(x, N)
    pp = v.skew(p, "p", nn.shape[-1])
    return _gen.orbit_extremal_rhs(xx, pp, nn)


def orbit_hamiltonian(x: ArrayLike, p: ArrayLike, N: ArrayLike) -> Array:
    r"""The optimal Hamiltonian with Brockett's potential, conserved by :func:`orbit_extremal_rhs`.

    .. math:: H^* = -\tfrac12\langle x,[p,[p,x]]\rangle + V(x)
        = \tfrac12\|[p,x]\|^2 - \tfrac12\|[x,N]\|^2.

    Parameters
    ----------
    x, p, N : array_like, shape (..., n, n)
        The skew-symmetric state, costate and fixed element (broadcast against each other).

    Returns
    -------
    ndarray, shape (...)
        The Hamiltonian.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> x, N = symrb.hat([1.0, 0.5, 0.2]), symrb.hat([0.0, 0.0, 1.0])
    >>> print(round(float(symrb.orbit_hamiltonian(x, -N, N)), 6) + 0.0)  # 0 on this extremal
    0.0
    """
    xx, nn = _pair_xN(x, N)
    pp = v.skew(p, "p", nn.shape[-1])
    return _gen.orbit_hamiltonian(xx, pp, nn)


def brockett_potential(x: ArrayLike, N: ArrayLike) -> Array:
    r"""Brockett's potential :math:`V(x) = -\tfrac12\|[x, N]\|^2 = \tfrac12\langle x, [N,[N,x]]\rangle`.

    Parameters
    ----------
    x, N : array_like, shape (..., n, n)
        The skew-symmetric state and fixed element (broadcast against each other).

    Returns
    -------
    ndarray, shape (...)
        The potential.

    Examples
    --------
    >>> import symrb
    >>> x, N = symrb.hat([1.0, 0.5, 0.2]), symrb.hat([0.0, 0.0, 1.0])
    >>> print(symrb.brockett_potential(x, N))  # -|x x n|^2 / 2 for n = 3
    -0.625
    """
    xx, nn = _pair_xN(x, N)
    return _gen.brockett_potential(xx, nn)


def double_bracket_rhs(x: ArrayLike, N: ArrayLike) -> Array:
    r"""The double bracket vector field :math:`\dot x = [x, [x, N]]`.

    Parameters
    ----------
    x, N : array_like, shape (..., n, n)
        The skew-symmetric state and fixed element (broadcast against each other).

    Returns
    -------
    ndarray, shape (..., n, n)
        :math:`[x, [x, N]]`, of the broadcast shape.

    Examples
    --------
    The field decreases :math:`\langle x, N\rangle` at the rate :math:`\|[x, N]\|^2`:

    >>> import symrb
    >>> x, N = symrb.hat([1.0, 0.5, 0.2]), symrb.hat([0.0, 0.0, 1.0])
    >>> xdot = symrb.double_bracket_rhs(x, N)
    >>> print(symrb.pairing(xdot, N), -symrb.pairing(*2 * [symrb.commutator(x, N)]))
    -1.25 -1.25
    """
    xx, nn = _pair_xN(x, N)
    return _gen.double_bracket_rhs(xx, nn)


@dataclass(frozen=True)
class DoubleBracketInfo:
    r"""What :func:`double_bracket_flow` measured (with ``return_info=True``).

    Attributes
    ----------
    condition : ndarray, shape (m,)
        :math:`\kappa(t_i)`, the relative condition number of the flow map from time 0 to each
        output time (the largest relative growth of a skew perturbation of ``x0``; see
        :func:`symrb.integrate`'s Notes for the estimate).
    error_estimate : ndarray, shape (m,)
        :math:`\|x(t_i) - \hat x(t_i)\|_F/\|x(t_i)\|_F` for a run :math:`\hat x` at tolerances
        ``rtol / 100``, ``atol / 100``.
    nfev : int
        The evaluations of the vector field by the returned run.

    Examples
    --------
    >>> import symrb
    >>> x0, N = symrb.hat([1.0, 0.5, 0.2]), symrb.hat([0.0, 0.0, 1.0])
    >>> xs, info = symrb.double_bracket_flow(x0, N, [0, 1, 5], return_info=True)
    >>> print(info.condition.round(2))
    [1.   1.22 0.87]
    """

    condition: Array
    error_estimate: Array
    nfev: int


@overload
def double_bracket_flow(
    x0: ArrayLike,
    N: ArrayLike,
    t: ArrayLike,
    rtol: float = ...,
    atol: float = ...,
    *,
    return_info: Literal[False] = False,
) -> Array: ...


@overload
def double_bracket_flow(
    x0: ArrayLike,
    N: ArrayLike,
    t: ArrayLike,
    rtol: float = ...,
    atol: float = ...,
    *,
    return_info: Literal[True],
) -> tuple[Array, DoubleBracketInfo]: ...


def double_bracket_flow(
    x0: ArrayLike,
    N: ArrayLike,
    t: ArrayLike,
    rtol: float = 1e-11,
    atol: float = 1e-12,
    *,
    return_info: bool = False,
) -> Array | tuple[Array, DoubleBracketInfo]:
    r"""Integrate the double bracket flow :math:`\dot x = [x, [x, N]]` from ``x0``.

    The flow stays on the orbit of ``x0`` and decreases :math:`\langle x, N\rangle` at the rate
    :math:`\|[x, N]\|^2`; it tends to a point commuting with N.  Uses ``scipy.integrate.solve_ivp``
    (DOP853).

    Parameters
    ----------
    x0 : array_like, shape (n, n)
        The skew-symmetric initial point.
    N : array_like, shape (n, n)
        The skew-symmetric fixed element.
    t : array_like, shape (m,)
        Increasing output times, >= 0 (the flow starts at time 0).
    rtol, atol : float, optional
        The tolerances of ``solve_ivp``.
    return_info : bool, optional
        Also return a :class:`DoubleBracketInfo`: the condition number of the flow and an error
        estimate at each output time (costs about four more integrations; none by default).

    Returns
    -------
    ndarray, shape (m, n, n)
        x at the times ``t``.
    info : DoubleBracketInfo
        Only with ``return_info=True``.

    Raises
    ------
    NotConvergedError
        If the integrator fails.

    Notes
    -----
    The equation is the initial value problem :math:`\dot x = [x, [x, N]]`, :math:`x(0) = x_0`.
    A local error of the integrator (about ``rtol`` :math:`\|x\|`) committed at time s reaches
    time t multiplied by the derivative of the flow map, so the relative error at t is about the
    tolerance times the relative condition number :math:`\kappa(t)` (``return_info=True``;
    estimated as in :func:`symrb.integrate`).  Near an equilibrium that is not the minimum (a
    saddle: x commutes with N but is not sorted like it) perturbations grow exponentially until
    the flow leaves it, and so does :math:`\kappa`.  Accuracy stated and tested
    (tests/test_conditions.py, against a run at ``rtol = 1e-13``): the relative error at each
    output time is at most :math:`2\,e(t) + 10\,\tau(t)\,\kappa(t)`, :math:`e(t)` the
    error estimate and :math:`\tau(t)` the tolerance scale; usually it is near
    :math:`(\mathrm{rtol} + \mathrm{atol}/\|x(t)\|_{rms})\,\kappa(t)`, but not within a fixed
    multiple of it (19 times was found at :math:`\kappa = 0.5`: the local errors of all the
    steps add up).

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> x0, N = symrb.hat([1.0, 0.5, 0.2]), symrb.hat([0.0, 0.0, 1.0])
    >>> xs = symrb.double_bracket_flow(x0, N, [0, 1, 5, 20])
    >>> print(symrb.pairing(xs, N).round(4))  # decreasing to -|x0|
    [ 0.2    -0.8442 -1.1357 -1.1358]
    >>> print(symrb.vee(xs[-1]).round(4) + 0.0)  # commutes with N
    [ 0.      0.     -1.1358]
    """
    xx, nn = _pair_xN(x0, N, "x0")
    if xx.ndim != 2 or nn.ndim != 2:
        raise InputError(
            f"x0 and N must be single (n, n) matrices, got {xx.shape} and {nn.shape}; pass one "
            "matrix each (loop over a batch)"
        )
    ts = _output_times(t)
    if not isinstance(return_info, bool | np.bool_):
        raise InputError(f"return_info must be True or False, got {return_info!r}; pass a bool")
    k = xx.shape[-1]
    sol = _db_solve(xx.reshape(1, k * k), nn, ts, rtol, atol)
    if not sol.success:
        raise NotConvergedError(f"double_bracket_flow: {sol.message}", float("nan"), sol.nfev)
    xs = sol.y.T.reshape(-1, k, k)
    if not return_info:
        return xs

    def batch(X0: Array) -> Array:
        run = _db_solve(X0, nn, ts, rtol, atol)
        if not run.success:
            return np.full((ts.size, X0.shape[0], k * k), np.nan)
        return np.asarray(run.y.T.reshape(ts.size, X0.shape[0], k * k))

    def skew(V: Array) -> Array:  # the flow lives on so(n): perturb within it
        W = V.reshape(-1, k, k)
        return np.asarray((W - np.swapaxes(W, -1, -2)).reshape(V.shape))

    kappa = _cond.sensitivity(batch, xx.ravel(), tangent=skew)
    tight = max(rtol / _cond.TIGHTER, 100 * float(np.finfo(float).eps))
    ref = _db_solve(xx.reshape(1, k * k), nn, ts, tight, atol / _cond.TIGHTER)
    err = _cond.relative_difference(sol.y.T, ref.y.T) if ref.success else np.full(ts.size, np.nan)
    return xs, DoubleBracketInfo(condition=kappa, error_estimate=err, nfev=int(sol.nfev))


def _output_times(t: ArrayLike) -> Array:
    """The output times of a flow started at time 0: a non-empty increasing 1-D array >= 0."""
    ts = v.as_float_array(t, "t")
    if ts.ndim != 1 or ts.size == 0 or np.any(np.diff(ts) <= 0) or ts[0] < 0:
        raise InputError(
            f"t must be a non-empty increasing 1-D array of times >= 0, got {ts}; pass sorted "
            "distinct times"
        )
    return ts


def _db_solve(X0: Array, nn: Array, ts: Array, rtol: float, atol: float) -> Any:
    """``solve_ivp`` (DOP853) of the double bracket flow for the batch ``X0`` of shape (b, k k),
    one step-size sequence for the batch; the result's ``y`` has shape (b k k, len(ts))."""
    b, kk = X0.shape
    k = nn.shape[-1]
    if ts[-1] == 0.0:  # t = [0]: solve_ivp returns no output on an empty interval
        return OptimizeResult(y=X0.reshape(-1, 1).copy(), t=ts, success=True, message="t = [0]",
                              nfev=0)  # fmt: skip
    return solve_ivp(
        lambda _t, y: _gen.double_bracket_rhs(y.reshape(b, k, k), nn).ravel(),
        (0.0, float(ts[-1])),
        X0.ravel(),
        t_eval=ts,
        method="DOP853",
        rtol=rtol,
        atol=atol,
    )


def toda_flow(
    a0: ArrayLike, b0: ArrayLike, t: ArrayLike, rtol: float = 1e-11, atol: float = 1e-12
) -> Array:
    r"""The Toda lattice, integrated as the double bracket flow :math:`\dot L = -[L, [L, D]]`.

    :math:`L` is the real symmetric tridiagonal matrix with the diagonal :math:`a` and the
    off-diagonal :math:`b` (Flaschka's variables), :math:`D = \operatorname{diag}(1, \dots, k)`.
    With :math:`x = iL`, :math:`N = iD` this is the double bracket flow
    :math:`\dot x = [x, [x, N]]` on :math:`\mathfrak{su}(k)` (claim S14), and on the band it
    is Flaschka's form of the Toda lattice,

    .. math:: \dot a_i = 2(b_i^2 - b_{i-1}^2),\qquad \dot b_i = b_i(a_{i+1} - a_i)

    (:math:`b_0 = b_k = 0`).  The whole matrix is integrated by the solver of
    :func:`double_bracket_flow` with :math:`N = -D` (the field is linear in N), the generated
    :func:`double_bracket_rhs` and ``scipy.integrate.solve_ivp`` (DOP853); L is real symmetric,
    so :func:`double_bracket_flow` itself, whose states are skew, does not accept it.  The
    entries off the band stay zero, and the spectrum of :math:`L` is kept, up to the integration
    error.  As :math:`t\to\infty` the off-diagonal decays and the diagonal
    tends to the eigenvalues of :math:`L(0)`, sorted in decreasing order.

    Parameters
    ----------
    a0 : array_like, shape (k,)
        The diagonal of :math:`L(0)`, k >= 2.
    b0 : array_like, shape (k - 1,)
        The off-diagonal of :math:`L(0)`.
    t : array_like, shape (m,)
        Increasing output times, >= 0 (the flow starts at time 0).
    rtol, atol : float, optional
        The tolerances of ``solve_ivp``.

    Returns
    -------
    ndarray, shape (m, k, k)
        :math:`L` at the times ``t``.

    Raises
    ------
    InputError
        If ``a0``, ``b0`` are not real 1-D arrays of k >= 2 and k - 1 entries, or ``t`` is not
        increasing and >= 0.
    NotConvergedError
        If the integrator fails.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> a0, b0 = np.array([0.5, -1.0, 0.2]), np.array([0.8, 0.6])
    >>> L = symrb.toda_flow(a0, b0, [0.0, 40.0])
    >>> print(np.diagonal(L[-1]).round(6))  # the eigenvalues of L(0), largest first
    [ 0.940208  0.284592 -1.5248  ]
    >>> print(np.sort(np.linalg.eigvalsh(L[0]))[::-1].round(6))
    [ 0.940208  0.284592 -1.5248  ]
    """
    a = v.as_float_array(a0, "a0")
    b = v.as_float_array(b0, "b0")
    if a.ndim != 1 or a.size < 2 or b.shape != (a.size - 1,):
        raise InputError(
            f"a0 must have shape (k,) with k >= 2 and b0 shape (k - 1,), got {a.shape} and "
            f"{b.shape}; pass the diagonal and the off-diagonal of L(0)"
        )
    ts = _output_times(t)
    k = a.size
    L0 = np.diag(a) + np.diag(b, 1) + np.diag(b, -1)
    # the field is linear in N: -[L, [L, D]] = [L, [L, -D]], the double bracket solve with -D
    sol = _db_solve(L0.reshape(1, k * k), -np.diag(np.arange(1.0, k + 1)), ts, rtol, atol)
    if not sol.success:
        raise NotConvergedError(f"toda_flow: {sol.message}", float("nan"), sol.nfev)
    return np.asarray(sol.y.T.reshape(-1, k, k))


def _pairing_norm(a: Array) -> Array:
    """sqrt(<a, a>) with the pairing of symrb.pairing, over the last two axes."""
    from .algebra import pairing

    return np.asarray(np.sqrt(pairing(a, a)))


def one_sample_second_term(x0: ArrayLike, N: ArrayLike, t: ArrayLike) -> Array:
    r"""The second costate term :math:`\|[N, [N, x(t)]]\|` along the one-sample extremal on
    :math:`\mathfrak{so}(3)`, in closed form (claim S15).

    With the corrected endpoint :math:`p_T = -N` the extremal is the double bracket flow from
    ``x0``, which turns :math:`x` in the plane of :math:`x_0` and :math:`N` towards
    :math:`-N`.  The paper's corrected statement gives

    .. math:: \|[N, [N, x(t)]]\| = \|N\|^2\|x_0\|\sin\varphi_t,\qquad
              \tan\frac{\varphi_t}2 = \tan\frac{\varphi_0}2\,e^{-\|x_0\|\|N\|t},

    :math:`\varphi_0` the angle of :math:`x_0` from :math:`-N`
    (:math:`\cos\varphi_0 = -\langle x_0, N\rangle/(\|x_0\|\|N\|)`), norms and pairing of
    :func:`symrb.pairing`.  The formula is the generated ``one_sample_second_term``, the
    expression that the evidence of S15 checks against the boundary value problem.

    Parameters
    ----------
    x0, N : array_like, shape (3, 3)
        The sample and the fixed element, skew-symmetric and nonzero.
    t : array_like, shape (m,)
        Times >= 0.

    Returns
    -------
    ndarray, shape (m,)
        The second term at the times ``t``; it decays like :math:`e^{-\|x_0\|\|N\|t}`.

    Raises
    ------
    InputError
        If ``x0`` or ``N`` is not a nonzero skew 3 x 3 matrix, or a time is negative.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> x0, N = symrb.hat([0.5, 0.0, 0.0]), symrb.hat([0.0, 0.0, 1.0])  # at the angle pi/2
    >>> print(symrb.one_sample_second_term(x0, N, [0.0, 2.0, 8.0]).round(6))
    [0.5      0.324027 0.018309]
    >>> x = symrb.double_bracket_flow(x0, N, [8.0])[0]
    >>> c = symrb.commutator(N, symrb.commutator(N, x))
    >>> print(np.sqrt(symrb.pairing(c, c)).round(6))
    0.018309
    """
    xx, nn = _pair_xN(x0, N, "x0")
    if xx.shape != (3, 3):
        raise InputError(f"x0 and N must be 3 x 3 (the closed form is on so(3)), got {xx.shape}")
    ts = v.as_float_array(t, "t")
    if ts.ndim != 1 or np.any(ts < 0):
        raise InputError(f"t must be a 1-D array of times >= 0, got {ts}")
    r, s = float(_pairing_norm(xx)), float(_pairing_norm(nn))
    if r == 0.0 or s == 0.0:
        raise InputError(f"x0 and N must be nonzero, got norms {r:g} and {s:g}")
    from .algebra import pairing

    cos0 = float(np.clip(-pairing(xx, nn) / (r * s), -1.0, 1.0))
    return np.asarray(_gen.one_sample_second_term(r, s, np.tan(np.arccos(cos0) / 2), ts))


def two_sample_bound(x0: ArrayLike, N: ArrayLike) -> float:
    r"""The lower bound of the larger second costate term of two samples on
    :math:`\mathfrak{so}(3)` sharing one control (claim S15, corrected).

    .. math:: \max_a\|[N, [N, x^a_T]]\| \ge \|N\|^2\min_a\|x^a_0\|\sin\frac\beta2,\qquad
              \cos\beta = \frac{|\langle x^1_0, x^2_0\rangle|}{\|x^1_0\|\|x^2_0\|},

    at every horizon T (norms and pairing of :func:`symrb.pairing`): unlike one sample, the
    second term does not go to zero.  The formula is the generated ``two_sample_bound``, the
    expression that the evidence of S15 compares with solutions of :func:`solve_orbit_bvp`.

    Parameters
    ----------
    x0 : array_like, shape (2, 3, 3)
        The two samples, skew-symmetric and nonzero.
    N : array_like, shape (3, 3)
        The fixed element, skew-symmetric.

    Returns
    -------
    float
        The bound.

    Raises
    ------
    InputError
        If ``x0`` is not two nonzero skew 3 x 3 matrices or ``N`` not a skew 3 x 3 matrix.

    Examples
    --------
    >>> import symrb
    >>> x0 = [symrb.hat([1.0, 0.0, 0.0]), symrb.hat([0.0, 1.0, 0.0])]  # beta = pi/2
    >>> round(symrb.two_sample_bound(x0, symrb.hat([0.0, 0.0, 2.0])), 6)  # 4 sin(pi/4)
    2.828427
    """
    xx, nn = _pair_xN(x0, N, "x0")
    if xx.shape != (2, 3, 3):
        raise InputError(f"x0 must hold two 3 x 3 samples, shape (2, 3, 3), got {xx.shape}")
    r1, r2 = (float(a) for a in _pairing_norm(xx))
    if r1 == 0.0 or r2 == 0.0:
        raise InputError(f"the samples must be nonzero, got norms {r1:g} and {r2:g}")
    from .algebra import pairing

    # |<x^1, x^2>| <= r_1 r_2 (Cauchy-Schwarz), up to rounding
    p12 = float(np.clip(pairing(xx[0], xx[1]), -r1 * r2, r1 * r2))
    return float(_gen.two_sample_bound(r1, r2, float(_pairing_norm(nn)), p12))


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
        Whether ``solve_bvp`` converged (and the solution is finite).
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
        The factor between successive horizons of the continuation, > 1.
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
    horizons = [float(T)]
    while horizons[0] > continuation_start:
        horizons.insert(0, horizons[0] / continuation_growth)
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
    ok = bool(sol.success) and np.all(np.isfinite(sol.y))
    kappa = _bvp_condition(rhs, sol, half) if condition and ok else None
    return OrbitBVPResult(
        t=sol.x,
        x=x,
        p=p,
        u=u,
        success=bool(ok),
        message=str(sol.message),
        residual=res,
        bc_residual=bcr,
        costate=costate,
        sol=sol,
        condition=kappa,
    )


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
