r"""The symmetric rigid body of Section 3.2, McLachlan-Scovel, the learning version and the
reconstruction :math:`P = Q\exp(\sinh^{-1}(M/2))`.

.. math::

    \dot Q = QU,\quad \dot P = PU,\quad U = J^{-1}(Q^TP - P^TQ)
    \qquad\text{(symmetric rigid body, paper Section 3.2)}

    \dot Q = QJ^{-1}(Q^TB),\quad \dot B = BJ^{-1}(Q^TB)
    \qquad\text{(McLachlan-Scovel, Section 3.2; } B = 2P \text{ when } Q^TP \text{ is skew)}

    \dot Q^a = Q^aU,\quad \dot P^a = P^aU,\quad U = \sum_a J^{-1}((Q^a)^TP^a - (P^a)^TQ^a)
    \qquad\text{(learning version, Section 3.2)}

The vector fields are generated in :mod:`symrb._generated.symmetric_rigid_body` by
the claims S5-S12 of :mod:`derivations.claims.section3`; the functions here validate input and
document the mathematics.  The flows :class:`SymmetricRigidBody`, :class:`McLachlanScovel` and
:class:`MultiSampleSymmetricRigidBody` are :class:`symrb.continuous.Flow` objects naming their
state variables; :func:`symrb.integrate` runs them through :func:`scipy.integrate.solve_ivp`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, overload

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import schur

from . import _validate as v
from ._docs import fill
from ._generated import symmetric_rigid_body as _gen
from ._validate import Array
from .algebra import _Jinv_weights
from .continuous import Flow
from .errors import InputError, OutOfDomainError

__all__ = [
    "symmetric_momentum",
    "symmetric_rigid_body_rhs",
    "mclachlan_scovel_rhs",
    "multi_sample_control",
    "multi_sample_rhs",
    "gl_hamiltonian",
    "P_from_M",
    "PFromMInfo",
    "SymmetricRigidBody",
    "McLachlanScovel",
    "MultiSampleSymmetricRigidBody",
]


def _pair(Q: ArrayLike, P: ArrayLike, qname: str, pname: str, n: int | None = None):
    a = v.square(Q, qname, n)
    b = v.square(P, pname, a.shape[-1])
    return a, b


def symmetric_momentum(Q: ArrayLike, P: ArrayLike) -> Array:
    r"""The body momentum :math:`M = Q^TP - P^TQ` of the symmetric representation (claims S6, S9,
    S11).

    Parameters
    ----------
    Q, P : array_like, shape (..., n, n)
        Square matrices (the attitude and the costate); batch axes broadcast.

    Returns
    -------
    M : ndarray, shape (..., n, n)
        Skew-symmetric.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> print(symrb.symmetric.symmetric_momentum(np.eye(3), symrb.hat([0.1, 0.2, 0.3])))
    [[ 0.  -0.6  0.4]
     [ 0.6  0.  -0.2]
     [-0.4  0.2  0. ]]
    """
    a, b = _pair(Q, P, "Q", "P")
    return _gen.symmetric_momentum(a, b)


@fill
def symmetric_rigid_body_rhs(Q: ArrayLike, P: ArrayLike, lam: ArrayLike) -> tuple[Array, Array]:
    r"""The symmetric rigid body field :math:`(\dot Q, \dot P) = (QU, PU)`,
    :math:`U = J^{-1}(Q^TP - P^TQ)` (claims S5, S6, S12).

    Defined on all of :math:`\mathfrak{gl}(n)\times\mathfrak{gl}(n)`; :math:`SO(n)\times SO(n)` is
    invariant and :math:`M = Q^TP - P^TQ` then follows the rigid body equations.

    Parameters
    ----------
    Q, P : array_like, shape (..., n, n)
        The state (any square matrices); batch axes broadcast.
    %(lam)s

    Returns
    -------
    Qdot, Pdot : ndarray, shape (..., n, n)
        The vector field.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> lam = np.array([0.7, 1.1, 1.6])
    >>> Q, P = np.eye(3), symrb.hat([0.1, 0.2, 0.3])
    >>> Qdot, Pdot = symrb.symmetric.symmetric_rigid_body_rhs(Q, P, lam)
    >>> U = symrb.J_inv(symrb.symmetric.symmetric_momentum(Q, P), lam)
    >>> bool(np.allclose(Qdot, Q @ U) and np.allclose(Pdot, P @ U))
    True
    """
    L = v.inertia(lam)
    a, b = _pair(Q, P, "Q", "P", L.shape[-1])
    return _gen.symmetric_rigid_body_rhs(a, b, L)


@fill
def mclachlan_scovel_rhs(Q: ArrayLike, B: ArrayLike, lam: ArrayLike) -> tuple[Array, Array]:
    r"""The McLachlan-Scovel field :math:`(\dot Q, \dot B) = (QU, BU)`, :math:`U = J^{-1}(Q^TB)`
    (claim S7).

    :math:`J^{-1}` is defined on :math:`\mathfrak{so}(n)`, so :math:`Q^TB` must be skew (this set
    is invariant).  Raises :class:`InputError` otherwise.  For a costate :math:`P` of the
    symmetric rigid body with :math:`Q^TP` skew, the extremal flow is this field for
    :math:`B = 2P` (the paper's McLachlan-Scovel equations with :math:`B = P` runs it at half speed); for any
    :math:`P`, :math:`B = P - QP^TQ` maps the symmetric flow with :math:`Q` orthogonal to it.

    Parameters
    ----------
    Q, B : array_like, shape (..., n, n)
        The state, with :math:`Q^TB` skew-symmetric; batch axes broadcast.
    %(lam)s

    Returns
    -------
    Qdot, Bdot : ndarray, shape (..., n, n)
        The vector field.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> lam = np.array([0.7, 1.1, 1.6])
    >>> Q, P = np.eye(3), symrb.hat([0.1, 0.2, 0.3])  # Q^T P is skew
    >>> a = symrb.symmetric.symmetric_rigid_body_rhs(Q, P, lam)
    >>> b = symrb.symmetric.mclachlan_scovel_rhs(Q, 2 * P, lam)  # the same flow for B = 2P (claim S7)
    >>> bool(np.allclose(a[0], b[0]) and np.allclose(2 * a[1], b[1]))
    True
    """
    L = v.inertia(lam)
    a, b = _pair(Q, B, "Q", "B", L.shape[-1])
    v.skew(np.swapaxes(a, -1, -2) @ b, "Q^T B")
    return _gen.mclachlan_scovel_rhs(a, b, L)


def _samples(Q: ArrayLike, P: ArrayLike, lam: ArrayLike):
    L = v.inertia(lam)
    a, b = _pair(Q, P, "Q", "P", L.shape[-1])
    if a.ndim < 3 or b.ndim < 3:
        raise InputError(
            f"Q and P must have shape (..., m, n, n) with a sample axis m; got {a.shape}, {b.shape}; "
            "pass the samples stacked along axis -3"
        )
    return a, b, L


@fill
def multi_sample_control(Q: ArrayLike, P: ArrayLike, lam: ArrayLike) -> Array:
    r"""The shared optimal control :math:`U = \sum_a J^{-1}((Q^a)^TP^a - (P^a)^TQ^a)` (claim S8).

    Parameters
    ----------
    Q, P : array_like, shape (..., m, n, n)
        The states and costates of the m samples (axis -3 runs over the samples).
    %(lam)s

    Returns
    -------
    U : ndarray, shape (..., n, n)
        The shared control (skew-symmetric).

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> lam = np.array([0.7, 1.1, 1.6])
    >>> Q = np.stack([np.eye(3), np.eye(3)])
    >>> P = np.stack([symrb.hat([0.1, 0, 0]), symrb.hat([0, 0.1, 0])])
    >>> print(symrb.vee(symrb.symmetric.multi_sample_control(Q, P, lam)).round(4))
    [0.0741 0.087  0.    ]
    """
    a, b, L = _samples(Q, P, lam)
    return _shared_control(a, b, L)


def _shared_control(Q: Array, P: Array, lam: Array) -> Array:
    """sum_a J^{-1}(M^a) over axis -3 (no validation: used inside the integrator too)."""
    return _Jinv_weights(lam) * np.sum(_gen.symmetric_momentum(Q, P), axis=-3)


@fill
def multi_sample_rhs(Q: ArrayLike, P: ArrayLike, lam: ArrayLike) -> tuple[Array, Array]:
    r"""The learning flow :math:`\dot Q^a = Q^aU`, :math:`\dot P^a = P^aU` with the shared
    control of :func:`multi_sample_control` (claim S8).

    Parameters
    ----------
    Q, P : array_like, shape (..., m, n, n)
        The states and costates of the m samples (axis -3 runs over the samples).
    %(lam)s

    Returns
    -------
    Qdot, Pdot : ndarray, shape (..., m, n, n)
        The vector field.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> Q = np.stack([np.eye(3), np.eye(3)])
    >>> P = np.stack([symrb.hat([0.1, 0, 0]), symrb.hat([0, 0.1, 0])])
    >>> Qdot, Pdot = symrb.symmetric.multi_sample_rhs(Q, P, [0.7, 1.1, 1.6])
    >>> Qdot.shape
    (2, 3, 3)
    """
    a, b, L = _samples(Q, P, lam)
    U = multi_sample_control(a, b, L)
    return _gen.control_rhs(a, b, U[..., None, :, :])


@fill
def gl_hamiltonian(Q: ArrayLike, P: ArrayLike, lam: ArrayLike) -> Array:
    r"""The Hamiltonian on :math:`\mathfrak{gl}(n)\times\mathfrak{gl}(n)` (paper, Section 3.3;
    claim S12):

    .. math:: H = -\tfrac18\operatorname{tr}[J^{-1}(M)M] = \tfrac14\langle J^{-1}M, M\rangle,
              \qquad M = Q^TP - P^TQ,

    half the rigid body kinetic energy.  Conserved by :func:`symmetric_rigid_body_rhs`.

    Parameters
    ----------
    Q, P : array_like, shape (..., n, n)
        The state (any square matrices); batch axes broadcast.
    %(lam)s

    Returns
    -------
    H : ndarray, shape (...)
        The Hamiltonian.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> lam = np.array([0.7, 1.1, 1.6])
    >>> Q, P = np.eye(3), symrb.hat([0.1, 0.2, 0.3])
    >>> H = symrb.symmetric.gl_hamiltonian(Q, P, lam)
    >>> T = symrb.kinetic_energy(symrb.symmetric.symmetric_momentum(Q, P), lam)
    >>> print(round(float(H), 6), round(float(T / 2), 6))
    0.071095 0.071095
    """
    L = v.inertia(lam)
    a, b = _pair(Q, P, "Q", "P", L.shape[-1])
    return _gen.gl_hamiltonian(a, b, L)


@dataclass(frozen=True)
class PFromMInfo:
    r"""What :func:`P_from_M` did, per item of the batch (arrays of the batch shape).

    Attributes
    ----------
    residual : ndarray
        :math:`\|Q^TP - P^TQ - M\|_F`.
    orthogonality : ndarray
        :math:`\|P^TP - I\|_F`.
    delta : ndarray
        :math:`1 - \|M\|_{op}/2`, the relative distance to the branch point.
    condition : ndarray
        :math:`\kappa = 1/\sqrt{1 - (\|M\|_{op}/2)^2}`, the largest derivative of the
        rotation angles :math:`\arcsin(b/2)` in the eigen-rates :math:`b` of M (about
        :math:`1/\sqrt{2\delta}` near 2).  Accuracy stated and tested: residual and
        orthogonality below :math:`10\,n\,\varepsilon`; the forward error of P below
        :math:`10\,n\,\varepsilon\,\kappa`.

    Examples
    --------
    >>> import symrb
    >>> P, info = symrb.symmetric.P_from_M(np.eye(3), symrb.hat([0.0, 0.0, 1.0]), return_info=True)
    >>> print(round(float(info.condition), 4), float(info.delta))  # 1 / cos(pi / 6)
    1.1547 0.5
    """

    residual: Array
    orthogonality: Array
    delta: Array
    condition: Array


@overload
def P_from_M(Q: ArrayLike, M: ArrayLike, *, return_info: Literal[False] = False) -> Array: ...


@overload
def P_from_M(
    Q: ArrayLike, M: ArrayLike, *, return_info: Literal[True]
) -> tuple[Array, PFromMInfo]: ...


def P_from_M(
    Q: ArrayLike, M: ArrayLike, *, return_info: bool = False
) -> Array | tuple[Array, PFromMInfo]:
    r"""Solve :math:`M = Q^TP - P^TQ` for :math:`P\in SO(n)`: :math:`P = Q\exp(\sinh^{-1}(M/2))`
    (claim S10).

    On skew matrices :math:`\exp(\sinh^{-1}X) = X + (I + X^2)^{1/2}`.  It is evaluated through the
    real Schur form :math:`M = ZTZ^T` (``scipy.linalg.schur``): on a block
    :math:`\begin{pmatrix}0&b\\-b&0\end{pmatrix}` of T, :math:`\sinh^{-1}(\cdot/2)` is
    :math:`\arcsin(b/2)K` with :math:`K = \begin{pmatrix}0&1\\-1&0\end{pmatrix}` (the eigenvalues
    :math:`\pm ib/2` go to :math:`\pm i\arcsin(b/2)`), and the exponential gives the rotation
    block :math:`\begin{pmatrix}c&s\\-s&c\end{pmatrix}`, :math:`s = b/2`, :math:`c = \sqrt{1-s^2}`.
    The eigen-angles :math:`\varphi` of :math:`Q^TP` satisfy :math:`2\sin\varphi = b` with
    :math:`|\varphi| < \pi/2`; the other solutions (angle :math:`\pi - \varphi`) are not returned.

    Parameters
    ----------
    Q : array_like, shape (..., n, n)
        Attitudes, in SO(n).
    M : array_like, shape (..., n, n)
        Skew-symmetric body momenta with :math:`\|M\|_{op} < 2`.

    return_info : bool, optional
        Also return a :class:`PFromMInfo` (residuals and the condition number).

    Returns
    -------
    P : ndarray, shape (..., n, n)
        Costates in SO(n) with :math:`Q^TP - P^TQ = M`.
    info : PFromMInfo
        Only with ``return_info=True``.

    Raises
    ------
    OutOfDomainError
        if some :math:`\|M\|_{op}\ge 2`: at 2 the branch points :math:`\pm i` of
        :math:`\sinh^{-1}` are reached (the solution exists but is not differentiable in M);
        above 2 no solution in SO(n) exists (claim S9).

    Notes
    -----
    Accuracy, measured against a 60-digit reference for
    :math:`\|M\|_{op} = 2(1-\delta)`, n = 3, 4 (two equal planes), 5: the residuals
    :math:`|Q^TP - P^TQ - M|` and :math:`|P^TP - I|` stay below :math:`5\cdot10^{-15}` for every
    :math:`\delta` down to the last float below 2; the forward error of P grows like
    :math:`\epsilon/\sqrt{\delta}` (the problem's own conditioning: :math:`\arcsin'(1) = \infty`):
    about :math:`10^{-12}` at :math:`\delta = 10^{-8}`, :math:`4\cdot10^{-9}` at
    :math:`\delta = 10^{-15}`.  The Schur form is computed per matrix (about 70 microseconds
    each for n = 4).

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> Q, M = np.eye(3), symrb.hat([0.2, 0.4, 0.6])
    >>> P = symrb.symmetric.P_from_M(Q, M)
    >>> bool(np.allclose(symrb.symmetric.symmetric_momentum(Q, P), M) and np.allclose(P.T @ P, np.eye(3)))
    True
    """
    Qa = v.orthogonal(Q, "Q")
    Ma = v.skew(M, "M", Qa.shape[-1])
    norms = np.linalg.norm(Ma, 2, axis=(-2, -1))
    if np.any(norms >= 2.0):
        worst = float(np.max(norms))
        idx = np.unravel_index(int(np.argmax(norms)), norms.shape) if norms.ndim else ()
        where = tuple(int(i) for i in idx)
        raise OutOfDomainError(
            f"P_from_M needs ||M||_op < 2 (at 2 the solution P in SO(n) is not differentiable in "
            f"M, above 2 none exists); got ||M||_op = {worst!r} at batch index {where}; scale M "
            f"by less than {2.0 / worst:.10g}"
        )
    flat = Ma.reshape((-1,) + Ma.shape[-2:])
    A = np.stack([_exp_asinh_half(m) for m in flat]) if flat.shape[0] else np.empty(flat.shape)
    P = Qa @ A.reshape(Ma.shape)
    if not return_info:
        return P
    eye = np.eye(Ma.shape[-1])
    Pt = np.swapaxes(P, -1, -2)
    res = np.linalg.norm(np.swapaxes(Qa, -1, -2) @ P - Pt @ Qa - Ma, axis=(-2, -1))
    orth = np.linalg.norm(Pt @ P - eye, axis=(-2, -1))
    half = norms / 2.0
    cond = 1.0 / np.sqrt((1.0 - half) * (1.0 + half))
    return P, PFromMInfo(residual=res, orthogonality=orth, delta=1.0 - half, condition=cond)


def _exp_asinh_half(M: Array) -> Array:
    """exp(asinh(M/2)) for one real skew M with ||M||_op <= 2, through the real Schur form.

    M = Z T Z^T with T block diagonal, blocks [[0, b], [-b, 0]] (and zeros); on such a block
    asinh(./2) = arcsin(b/2) K with K = [[0, 1], [-1, 0]], and exp(a K) = cos(a) I + sin(a) K, so
    the block of the result is [[c, s], [-s, c]], s = b/2, c = sqrt(1 - s^2).  Every block is
    orthogonal and has skew part exactly the block of M/2, up to rounding, whatever |b| <= 2.
    """
    n = M.shape[-1]
    T, Z = schur(M, output="real")
    A = np.eye(n)
    i = 0
    while i < n:
        if i + 1 < n and T[i + 1, i] != 0.0:
            s = min(max((T[i, i + 1] - T[i + 1, i]) / 4.0, -1.0), 1.0)
            c = np.sqrt(1.0 - s * s)
            A[i : i + 2, i : i + 2] = [[c, s], [-s, c]]
            i += 2
        else:
            i += 1
    return Z @ A @ Z.T


class SymmetricRigidBody(Flow):
    r"""The symmetric rigid body :math:`\dot Q = QU`, :math:`\dot P = PU`,
    :math:`U = J^{-1}(Q^TP - P^TQ)`.

    State ``("Q", "P")`` (any square matrices: the field is defined on
    :math:`\mathfrak{gl}(n)\times\mathfrak{gl}(n)`); derived ``M`` :math:`= Q^TP - P^TQ` and the
    Hamiltonian ``H``.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> lam = np.array([0.7, 1.1, 1.6])
    >>> Q0 = np.eye(3)
    >>> P0 = symrb.symmetric.P_from_M(Q0, symrb.hat([0.5, 1.0, 1.5]))
    >>> sol = symrb.integrate(symrb.SymmetricRigidBody, (0, 10), {"Q": Q0, "P": P0}, lam=lam)
    >>> sorted(sol.y), bool(np.ptp(sol.y.H) < 1e-9)
    (['H', 'M', 'P', 'Q'], True)
    """

    name = "symmetric rigid body"
    state = ("Q", "P")

    def rhs(self, y, lam):
        return _gen.symmetric_rigid_body_rhs(y["Q"], y["P"], lam)

    def derived(self, y, lam):
        return {
            "M": _gen.symmetric_momentum(y["Q"], y["P"]),
            "H": _gen.gl_hamiltonian(y["Q"], y["P"], lam),
        }


class McLachlanScovel(Flow):
    r"""The McLachlan-Scovel equations :math:`\dot Q = QJ^{-1}(Q^TB)`,
    :math:`\dot B = BJ^{-1}(Q^TB)`.

    State ``("Q", "B")`` with Q in SO(n) and :math:`Q^TB` skew; derived ``M`` :math:`= Q^TB`
    (it follows the rigid body equations, claim S7).

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> lam = np.array([0.7, 1.1, 1.6])
    >>> M0 = symrb.hat([0.5, 1.0, 1.5])
    >>> kw = dict(lam=lam, rtol=1e-12, atol=1e-12, t_eval=[0, 5])
    >>> ms = symrb.integrate(symrb.McLachlanScovel, (0, 5), {"Q": np.eye(3), "B": M0}, **kw)
    >>> rb = symrb.integrate(symrb.RigidBody, (0, 5), {"Q": np.eye(3), "M": M0}, **kw)
    >>> bool(np.allclose(ms.y.M, rb.y.M, atol=1e-9))
    True
    """

    name = "McLachlan-Scovel"
    state = ("Q", "B")

    def rhs(self, y, lam):
        return _gen.mclachlan_scovel_rhs(y["Q"], y["B"], lam)

    def check(self, y, lam):
        v.orthogonal(y["Q"], "y0['Q']")
        v.skew(np.swapaxes(y["Q"], -1, -2) @ y["B"], "Q^T B")

    def derived(self, y, lam):
        return {"M": np.swapaxes(y["Q"], -1, -2) @ y["B"]}


class MultiSampleSymmetricRigidBody(Flow):
    r"""The learning flow :math:`\dot Q^a = Q^aU`, :math:`\dot P^a = P^aU`,
    :math:`U = \sum_aJ^{-1}((Q^a)^TP^a - (P^a)^TQ^a)`.

    State ``("Q", "P")`` of shape (..., m, n, n) (m samples, each :math:`Q^a` in SO(n));
    derived ``U`` of shape (..., n, n).

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> Q0 = symrb.random_SO(3, (4,), seed=1)
    >>> P0 = 0.3 * np.random.default_rng(2).standard_normal((4, 3, 3))
    >>> sol = symrb.integrate(symrb.MultiSampleSymmetricRigidBody, (0, 1), {"Q": Q0, "P": P0},
    ...                       lam=[0.7, 1.1, 1.6], t_eval=[0, 0.5, 1])
    >>> sol.y.Q.shape, sol.y.U.shape
    ((3, 4, 3, 3), (3, 3, 3))
    """

    name = "multi-sample symmetric rigid body"
    state = ("Q", "P")
    sample_axes = 1

    def rhs(self, y, lam):
        return _gen.control_rhs(
            y["Q"], y["P"], _shared_control(y["Q"], y["P"], lam)[..., None, :, :]
        )

    def check(self, y, lam):
        v.orthogonal(y["Q"], "y0['Q']")

    def derived(self, y, lam):
        return {"U": _shared_control(y["Q"], y["P"], lam)}
