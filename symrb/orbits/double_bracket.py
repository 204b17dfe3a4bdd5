r"""The double bracket flow :math:`\dot x = [x, [x, N]]` and the Toda lattice as one (paper,
Section 3.5, claim S14), integrated with ``scipy.integrate.solve_ivp`` (DOP853) on the kernel
generated in :mod:`symrb._generated.adjoint_orbits`."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal, overload

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import OptimizeResult

from .. import _conditioning as _cond
from .. import _validate as v
from .._docs import fill_doc
from .._generated import adjoint_orbits as _gen
from .._ivp import MAX_NFEV, check_budget, solve_ivp_budget
from .._validate import Array
from ..errors import InputError, NotConvergedError
from ._common import DOC, pair_xN

__all__ = ["double_bracket_rhs", "DoubleBracketInfo", "double_bracket_flow", "toda_flow"]


@fill_doc(DOC)
def double_bracket_rhs(x: ArrayLike, N: ArrayLike) -> Array:
    r"""The double bracket vector field :math:`\dot x = [x, [x, N]]`.

    Parameters
    ----------
    %(xN)s

    Returns
    -------
    ndarray, shape (..., n, n)
        :math:`[x, [x, N]]`, of the broadcast shape.

    Examples
    --------
    The field decreases :math:`\langle x, N\rangle` at the rate :math:`\|[x, N]\|^2`:

    >>> import symrb
    >>> x, N = symrb.hat([1.0, 0.5, 0.2]), symrb.hat([0.0, 0.0, 1.0])
    >>> xdot = symrb.orbits.double_bracket_rhs(x, N)
    >>> print(symrb.pairing(xdot, N), -symrb.pairing(*2 * [symrb.commutator(x, N)]))
    -1.25 -1.25
    """
    xx, nn = pair_xN(x, N)
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
    max_nfev: int = ...,
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
    max_nfev: int = ...,
) -> tuple[Array, DoubleBracketInfo]: ...


@fill_doc(DOC)
def double_bracket_flow(
    x0: ArrayLike,
    N: ArrayLike,
    t: ArrayLike,
    rtol: float = 1e-11,
    atol: float = 1e-12,
    *,
    return_info: bool = False,
    max_nfev: int = MAX_NFEV,
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
    %(times)s
    %(tolerances)s
    return_info : bool, optional
        Also return a :class:`~symrb.orbits.DoubleBracketInfo`: the condition number of the flow
        and an error estimate at each output time (costs about four more integrations; none by
        default).
    max_nfev : int, optional
        The budget of each integration: at most this many evaluations of the vector field
        (default 10^6, seconds of work).  A stiff run (a large ``x0`` or ``N``) or a long one
        that needs more raises :class:`~symrb.errors.NotConvergedError` saying where it stopped.

    Returns
    -------
    ndarray, shape (m, n, n)
        x at the times ``t``.
    info : DoubleBracketInfo
        Only with ``return_info=True``.

    Raises
    ------
    NotConvergedError
        If the integrator fails, runs out of its budget ``max_nfev`` or meets a vector field
        that overflows float64.

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
    xx, nn = pair_xN(x0, N, "x0")
    if xx.ndim != 2 or nn.ndim != 2:
        raise InputError(
            f"x0 and N must be single (n, n) matrices, got {xx.shape} and {nn.shape}; pass one "
            "matrix each (loop over a batch)"
        )
    ts = _output_times(t)
    if not isinstance(return_info, bool | np.bool_):
        raise InputError(f"return_info must be True or False, got {return_info!r}; pass a bool")
    max_nfev = check_budget(max_nfev)
    k = xx.shape[-1]
    sol = _db_solve(xx.reshape(1, k * k), nn, ts, rtol, atol, max_nfev)
    if not sol.success:
        raise NotConvergedError(f"double_bracket_flow: {sol.message}", float("nan"), sol.nfev)
    xs = sol.y.T.reshape(-1, k, k)
    if not return_info:
        return xs

    def batch(X0: Array) -> Array:
        run = _db_solve(X0, nn, ts, rtol, atol, max_nfev)
        if not run.success:
            return np.full((ts.size, X0.shape[0], k * k), np.nan)
        return np.asarray(run.y.T.reshape(ts.size, X0.shape[0], k * k))

    def skew(V: Array) -> Array:  # the flow lives on so(n): perturb within it
        W = V.reshape(-1, k, k)
        return np.asarray((W - np.swapaxes(W, -1, -2)).reshape(V.shape))

    kappa = _cond.sensitivity(batch, xx.ravel(), tangent=skew)
    tight = max(rtol / _cond.TIGHTER, 100 * float(np.finfo(float).eps))
    ref = _db_solve(xx.reshape(1, k * k), nn, ts, tight, atol / _cond.TIGHTER, max_nfev)
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


def _db_solve(
    X0: Array, nn: Array, ts: Array, rtol: float, atol: float, max_nfev: int = MAX_NFEV
) -> Any:
    """``solve_ivp`` (DOP853) of the double bracket flow for the batch ``X0`` of shape (b, k k),
    one step-size sequence for the batch, at most ``max_nfev`` evaluations of the field; the
    result's ``y`` has shape (b k k, len(ts))."""
    b, kk = X0.shape
    k = nn.shape[-1]
    if ts[-1] == 0.0:  # t = [0]: solve_ivp returns no output on an empty interval
        return OptimizeResult(y=X0.reshape(-1, 1).copy(), t=ts, success=True, message="t = [0]",
                              nfev=0)  # fmt: skip
    with np.errstate(over="ignore", invalid="ignore"):  # an overflow ends the run (message)
        return solve_ivp_budget(
            lambda _t, y: _gen.double_bracket_rhs(y.reshape(b, k, k), nn).ravel(),
            (0.0, float(ts[-1])),
            X0.ravel(),
            max_nfev=max_nfev,
            t_eval=ts,
            method="DOP853",
            rtol=rtol,
            atol=atol,
        )


@fill_doc(DOC)
def toda_flow(
    a0: ArrayLike,
    b0: ArrayLike,
    t: ArrayLike,
    rtol: float = 1e-11,
    atol: float = 1e-12,
    *,
    max_nfev: int = MAX_NFEV,
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
    %(times)s
    %(tolerances)s
    max_nfev : int, optional
        The budget: at most this many evaluations of the vector field (default 10^6, seconds
        of work).  A stiff run (large entries: the rates grow with them) or a long one
        that needs more raises :class:`~symrb.errors.NotConvergedError` saying where it stopped.

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
        If the integrator fails, runs out of its budget ``max_nfev`` or meets a vector field
        that overflows float64.

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
    max_nfev = check_budget(max_nfev)
    k = a.size
    L0 = np.diag(a) + np.diag(b, 1) + np.diag(b, -1)
    # the field is linear in N: -[L, [L, D]] = [L, [L, -D]], the double bracket solve with -D
    D = -np.diag(np.arange(1.0, k + 1))
    sol = _db_solve(L0.reshape(1, k * k), D, ts, rtol, atol, max_nfev)
    if not sol.success:
        raise NotConvergedError(f"toda_flow: {sol.message}", float("nan"), sol.nfev)
    return np.asarray(sol.y.T.reshape(-1, k, k))
