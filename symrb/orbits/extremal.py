r"""The extremal vector field of the orbit problem with Brockett's potential, its Hamiltonian and
the potential (paper, Sections 3.4-3.5; the fields are the kernels generated in
:mod:`symrb._generated.adjoint_orbits`)."""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from .. import _validate as v
from .._docs import fill_doc
from .._generated import adjoint_orbits as _gen
from .._ivp import MAX_NFEV, check_budget, solve_ivp_budget
from .._validate import Array
from ..errors import InputError, NotConvergedError
from ._common import DOC, pair_xN, symmetric
from .double_bracket import _output_times

__all__ = ["orbit_extremal_rhs", "orbit_hamiltonian", "brockett_potential", "orbit_extremal_flow"]


@fill_doc(DOC)
def orbit_extremal_rhs(x: ArrayLike, p: ArrayLike, N: ArrayLike) -> tuple[Array, Array]:
    r"""The extremal vector field of the orbit problem with Brockett's potential (paper, Section 3.4).

    .. math:: \dot x = [x, [p, x]],\qquad \dot p = [p, [p, x]] - [N, [N, x]].

    Parameters
    ----------
    %(xpN)s

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
    >>> xdot, pdot = symrb.orbits.orbit_extremal_rhs(x, -N, N)
    >>> bool(np.allclose(xdot, symrb.orbits.double_bracket_rhs(x, N)))
    True
    """
    xx, nn = pair_xN(x, N)
    pp = v.skew(p, "p", nn.shape[-1])
    return _gen.orbit_extremal_rhs(xx, pp, nn)


@fill_doc(DOC)
def orbit_hamiltonian(x: ArrayLike, p: ArrayLike, N: ArrayLike) -> Array:
    r"""The optimal Hamiltonian with Brockett's potential, conserved by :func:`orbit_extremal_rhs`.

    .. math:: H^* = -\tfrac12\langle x,[p,[p,x]]\rangle + V(x)
        = \tfrac12\|[p,x]\|^2 - \tfrac12\|[x,N]\|^2.

    Parameters
    ----------
    %(xpN)s

    Returns
    -------
    ndarray, shape (...)
        The Hamiltonian.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> x, N = symrb.hat([1.0, 0.5, 0.2]), symrb.hat([0.0, 0.0, 1.0])
    >>> print(round(float(symrb.orbits.orbit_hamiltonian(x, -N, N)), 6) + 0.0)  # 0 on this extremal
    0.0
    """
    xx, nn = pair_xN(x, N)
    pp = v.skew(p, "p", nn.shape[-1])
    return _gen.orbit_hamiltonian(xx, pp, nn)


@fill_doc(DOC)
def brockett_potential(x: ArrayLike, N: ArrayLike) -> Array:
    r"""Brockett's potential :math:`V(x) = -\tfrac12\|[x, N]\|^2 = \tfrac12\langle x, [N,[N,x]]\rangle`.

    Parameters
    ----------
    %(xN)s

    Returns
    -------
    ndarray, shape (...)
        The potential.

    Examples
    --------
    >>> import symrb
    >>> x, N = symrb.hat([1.0, 0.5, 0.2]), symrb.hat([0.0, 0.0, 1.0])
    >>> print(symrb.orbits.brockett_potential(x, N))  # -|x x n|^2 / 2 for n = 3
    -0.625
    """
    xx, nn = pair_xN(x, N)
    return _gen.brockett_potential(xx, nn)


#: the sign of the field on the matrices passed: +1 on so(n); -1 on i Sym(n), where (x, p, N)
#: = i (L, P, D) and the field, homogeneous of degree 3, gives i Ldot = i^3 F(L, P, D)
_ALGEBRAS = {"so": 1.0, "isym": -1.0}


@fill_doc(DOC)
def orbit_extremal_flow(
    x0: ArrayLike,
    p0: ArrayLike,
    N: ArrayLike,
    t: ArrayLike,
    rtol: float = 1e-11,
    atol: float = 1e-12,
    *,
    algebra: Literal["so", "isym"] = "so",
    max_nfev: int = MAX_NFEV,
) -> tuple[Array, Array]:
    r"""Integrate the extremal equations with Brockett's potential from :math:`(x_0, p_0)`.

    .. math:: \dot x = [x, [p, x]],\qquad \dot p = [p, [p, x]] - [N, [N, x]]

    (paper, Section 3.4, eq. ``opb``; the field is :func:`orbit_extremal_rhs`), as an initial
    value problem, by ``scipy.integrate.solve_ivp`` (DOP853).

    Parameters
    ----------
    x0, p0, N : array_like, shape (n, n)
        The initial state, the initial costate and the fixed element: skew-symmetric with
        ``algebra="so"``; real symmetric with ``algebra="isym"``.
    %(times)s
    %(tolerances)s
    algebra : {"so", "isym"}, optional
        ``"so"``: the matrices are elements of :math:`\mathfrak{so}(n)`.  ``"isym"``: a real
        symmetric :math:`L` stands for :math:`iL`, a skew-Hermitian matrix of
        :math:`\mathfrak{u}(n)` (of :math:`\mathfrak{su}(n)` when traceless), the setting of
        the Toda lattice; the field keeps :math:`i\,\mathrm{Sym}(n)` and on the symmetric
        matrices :math:`(L, P, D)` it reads :math:`\dot L = -[L, [P, L]]`,
        :math:`\dot P = -[P, [P, L]] + [D, [D, L]]`.
    max_nfev : int, optional
        The budget: at most this many evaluations of the vector field (default 10^6, seconds
        of work); a run that needs more raises :class:`~symrb.errors.NotConvergedError`.

    Returns
    -------
    x, p : ndarray, shape (m, n, n)
        The state and the costate at the times ``t`` (symmetric ``L``, ``P`` with
        ``algebra="isym"``).

    Raises
    ------
    InputError
        If the matrices are not single square matrices of one size, skew (``"so"``) or symmetric
        (``"isym"``), ``algebra`` is not one of those, ``t`` is not increasing and >= 0, or the
        tolerances are not positive.
    NotConvergedError
        If the integrator fails (e.g. the solution blows up or overflows float64) or runs out
        of its budget ``max_nfev``.

    Notes
    -----
    With :math:`p_0 = -N` the costate stays :math:`-N` exactly (:math:`[p,[p,x]] = [N,[N,x]]`
    for every x) and x follows the double bracket flow :math:`\dot x = [x, [x, N]]`; with
    :math:`x_0 = iL_0`, :math:`L_0` tridiagonal, and :math:`N = iD`,
    :math:`D = \operatorname{diag}(1, \dots, n)`, that is the Toda lattice (claim S14;
    :func:`toda_flow`).  This solution is unstable as one of the extremal system: near the
    sorted limit a perturbation of :math:`p` grows like :math:`e^{rt}`, r up to
    :math:`(\lambda_{max} - \lambda_{min})(d_{max} - d_{min})` (the eigenvalues of
    :math:`L_0` and of :math:`D`), the rate at which the double bracket flow contracts.  The
    rounding and truncation errors grow at that rate too, so a long run leaves the double
    bracket flow: integrate that flow itself (:func:`double_bracket_flow`, :func:`toda_flow`)
    for long times.

    Examples
    --------
    The Toda lattice through the optimal flow: :math:`p_0 = -D` stays, and the off-diagonal of
    :math:`L` decays (:func:`toda_flow` integrates the same Toda flow directly):

    >>> import numpy as np
    >>> import symrb
    >>> L0 = np.array([[0.5, 0.8, 0.0], [0.8, -1.0, 0.6], [0.0, 0.6, 0.2]])
    >>> D = np.diag([1.0, 2.0, 3.0])
    >>> L, P = symrb.orbits.orbit_extremal_flow(L0, -D, D, [0.0, 2.0], algebra="isym")
    >>> print(np.abs(P[-1] + D).max() < 1e-12, np.abs(L[-1] - symrb.toda_flow(
    ...     [0.5, -1.0, 0.2], [0.8, 0.6], [0.0, 2.0])[-1]).max() < 1e-9)
    True True
    """
    if not isinstance(algebra, str) or algebra not in _ALGEBRAS:
        raise InputError(f"algebra must be 'so' or 'isym', got {algebra!r}; pass one of them")
    if algebra == "so":
        xx, nn = pair_xN(x0, N, "x0")
        pp = v.skew(p0, "p0", nn.shape[-1])
    else:
        nn = symmetric(N, "N")
        xx, pp = (symmetric(a, name, nn.shape[-1]) for a, name in ((x0, "x0"), (p0, "p0")))
    if any(a.ndim != 2 for a in (xx, pp, nn)):
        raise InputError(
            f"x0, p0 and N must be single (n, n) matrices, got {xx.shape}, {pp.shape} and "
            f"{nn.shape}; pass one matrix each (loop over a batch)"
        )
    ts = _output_times(t)
    if not (v.real_scalar(rtol, "rtol") > 0 and v.real_scalar(atol, "atol") >= 0):
        raise InputError(
            f"need rtol > 0 and atol >= 0, got rtol={rtol}, atol={atol}; pass values in those "
            "ranges"
        )
    max_nfev = check_budget(max_nfev)
    k, sign = nn.shape[-1], _ALGEBRAS[algebra]
    y0 = np.concatenate([xx.ravel(), pp.ravel()])
    if ts[-1] == 0.0:  # t = [0]: solve_ivp returns no output on an empty interval
        return xx[None].copy(), pp[None].copy()

    def field(_t: float, y: Array) -> Array:
        xdot, pdot = _gen.orbit_extremal_rhs(y[: k * k].reshape(k, k), y[k * k :].reshape(k, k), nn)
        return sign * np.concatenate([xdot.ravel(), pdot.ravel()])

    with np.errstate(over="ignore", invalid="ignore"):  # a blow-up is reported below
        sol = solve_ivp_budget(field, (0.0, float(ts[-1])), y0, max_nfev=max_nfev, t_eval=ts,
                               method="DOP853", rtol=rtol, atol=atol)  # fmt: skip
    if not sol.success or not np.all(np.isfinite(sol.y)):
        raise NotConvergedError(f"orbit_extremal_flow: {sol.message}", float("nan"), sol.nfev)
    ys = sol.y.T
    return ys[:, : k * k].reshape(-1, k, k), ys[:, k * k :].reshape(-1, k, k)
