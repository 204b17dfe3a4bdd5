r"""The SO(n) network of the paper's learning theorem (claim D9): forward sweep, costates,
gradients and the residual of the extremal equations.

Samples :math:`Q^a_0 \in SO(n)` (:math:`a = 1, \dots, M`), layers :math:`Q^a_{k+1} = Q^a_kU_k`
with shared controls :math:`U_k \in SO(n)`, loss :math:`L(U) = \sum_a \tfrac12\|Q^a_N -
T^a\|_F^2 + \alpha\sum_k \operatorname{tr}(\Lambda(I - U_k))`.  Inside, the samples are stacked
by rows, (M, n, n) -> (M n, n): a layer, a costate step and the sum over the samples in the
gradient are then one matrix product each (the generated kernels of claim D9 in
:mod:`symrb._generated.discrete_rigid_body`).  The trainers are in
:mod:`symrb.learning.so_training`.
"""

from __future__ import annotations

from typing import Literal, overload

import numpy as np
from numpy.typing import ArrayLike

from .. import _validate as v
from .._docs import fill_doc
from .._generated import discrete_rigid_body as _gdr
from .._generated import symmetric_rigid_body as _gsr
from .._validate import Array
from ..errors import InputError
from ._common import DOC, SweepInfo, _window_product

__all__ = [
    "so_network_forward",
    "so_network_gradients",
    "so_network_costates",
    "so_extremal_residual",
]


def _so_controls(U: ArrayLike) -> Array:
    UU = v.orthogonal(U, "U")
    if UU.ndim != 3 or UU.shape[0] < 1:
        raise InputError(f"U must have shape (N, n, n) with N >= 1 layers, got {UU.shape}")
    return UU


def _so_samples(Q0: ArrayLike, n: int) -> Array:
    Q = v.orthogonal(Q0, "Q0", n)
    if Q.ndim != 3 or Q.shape[0] < 1:
        raise InputError(f"Q0 must have shape (M, n, n) with M >= 1 samples, got {Q.shape}")
    return Q


def _so_targets(targets: ArrayLike, shape: tuple[int, ...]) -> Array:
    T = v.as_float_array(targets, "targets")
    if T.shape != shape:
        raise InputError(f"targets must have shape (M, n, n) = {shape} like Q0, got {T.shape}")
    return T


def _so_lam(lam: ArrayLike, n: int) -> Array:
    L = v.inertia(lam, "lam", positive=True)
    if L.shape != (n,):
        raise InputError(f"lam must have shape (n,) = ({n},) to match U, got {L.shape}")
    return L


def _so_alpha(alpha: object) -> float:
    a = v.real_scalar(alpha, "alpha")
    if a < 0:
        raise InputError(f"alpha must be >= 0 (the weight of the running cost), got {alpha!r}")
    return a


def _so_forward(Qs0: Array, U: Array) -> Array:
    """All layers on stacked samples: (N + 1, M n, n)."""
    out = np.empty((U.shape[0] + 1, *Qs0.shape))
    out[0] = Qs0
    for k in range(U.shape[0]):
        out[k + 1] = _gdr.so_network_layer(out[k], U[k])
    return out


def _so_loss(QN: Array, Ts: Array, U: Array, lam: Array, alpha: float) -> float:
    run = float(np.sum(lam * (1.0 - np.diagonal(U, axis1=-2, axis2=-1)))) if alpha else 0.0
    return 0.5 * float(np.sum((QN - Ts) ** 2)) + alpha * run


def _so_backward(
    Qs: Array, U: Array, lam: Array, Ts: Array, alpha: float, costates: bool = False
) -> tuple[Array, Array | None]:
    """The costate sweep on stacked samples: the skew gradients G (N, n, n) and, when asked, all
    costates (N + 1, M n, n)."""
    N = U.shape[0]
    P = _gdr.so_network_endpoint(Qs[N], Ts)
    Ps = None
    if costates:
        Ps = np.empty_like(Qs)
        Ps[N] = P
    G = np.empty_like(U)
    lam_alpha = alpha * lam  # the kernel's Lambda is alpha Lambda
    for k in range(N - 1, -1, -1):
        G[k] = _gdr.so_network_gradient(P, Qs[k + 1], U[k], lam_alpha)
        P = _gdr.so_network_costate(P, U[k])
        if Ps is not None:
            Ps[k] = P
    return G, Ps


class _SOProblem:
    """A validated SO(n) network problem (samples stacked by rows), shared by the trainers."""

    def __init__(
        self, Q0: ArrayLike, targets: ArrayLike, lam: ArrayLike, alpha: object, n: int
    ) -> None:
        Q = _so_samples(Q0, n)
        self.M, self.n = Q.shape[0], n
        self.Qs0 = Q.reshape(self.M * n, n)
        self.Ts = _so_targets(targets, Q.shape).reshape(self.M * n, n)
        self.lam = _so_lam(lam, n)
        self.alpha = _so_alpha(alpha)

    def loss(self, U: Array) -> float:
        QN = self.Qs0
        for k in range(U.shape[0]):
            QN = _gdr.so_network_layer(QN, U[k])
        return _so_loss(QN, self.Ts, U, self.lam, self.alpha)

    def gradients(self, U: Array) -> tuple[float, Array]:
        """(loss, G) with the least memory: of the layers only Q_1..Q_N are kept (the gradient
        needs Q_{k+1}, not Q_0), Q_N is dropped once used, the loss comes from the endpoint
        costate (||P_N||^2 = ||Q_N - T||^2), and at most two costates are alive at a time."""
        N = U.shape[0]
        layers = np.empty((N - 1, *self.Qs0.shape))
        Q = self.Qs0
        for k in range(N - 1):
            layers[k] = _gdr.so_network_layer(Q, U[k])
            Q = layers[k]
        last: Array | None = _gdr.so_network_layer(Q, U[N - 1])
        P = _gdr.so_network_endpoint(last, self.Ts)
        loss = 0.5 * float(np.vdot(P, P))
        if self.alpha:
            loss += self.alpha * float(np.sum(self.lam * (1.0 - np.diagonal(U, 0, -2, -1))))
        G = np.empty_like(U)
        lam_alpha = self.alpha * self.lam
        for k in range(N - 1, -1, -1):
            Q_next = layers[k] if k < N - 1 else last
            G[k] = _gdr.so_network_gradient(P, Q_next, U[k], lam_alpha)
            last = Q_next = None  # Q_N is not needed any more
            if k:
                P = _gdr.so_network_costate(P, U[k])
        return loss, G


@fill_doc(DOC)
def so_network_forward(Q0: ArrayLike, U: ArrayLike) -> Array:
    r"""All layers :math:`Q^a_k` of the SO(n) network :math:`Q^a_{k+1} = Q^a_k U_k` (claim D9).

    The controls :math:`U_k` are shared by the samples, the samples :math:`Q^a_0` are the
    initial conditions.  Each layer is the generated kernel ``so_network_layer`` applied to the
    samples stacked by rows (one matrix product per layer for all samples).

    Parameters
    ----------
    %(Q0)s
    U : array_like, shape (N, n, n)
        The controls (weights) :math:`U_0, \dots, U_{N-1}`, in SO(n).

    Returns
    -------
    Q : ndarray, shape (N + 1, M, n, n)
        ``Q[k, a]`` is :math:`Q^a_k`.

    Raises
    ------
    InputError
        A shape mismatch, or ``Q0`` or ``U`` not in SO(n) (to 1e-8).

    Examples
    --------
    >>> import numpy as np
    >>> from symrb.learning import so_network_forward
    >>> import symrb
    >>> Q0, U = symrb.random_SO(3, (5,), seed=0), symrb.random_SO(3, (4,), seed=1)
    >>> Q = so_network_forward(Q0, U)
    >>> Q.shape
    (5, 5, 3, 3)
    >>> bool(np.allclose(Q[-1], Q0 @ U[0] @ U[1] @ U[2] @ U[3]))
    True
    """
    UU = _so_controls(U)
    n = UU.shape[-1]
    Q = _so_samples(Q0, n)
    Qs = _so_forward(Q.reshape(-1, n), UU)
    return Qs.reshape(UU.shape[0] + 1, Q.shape[0], n, n)


def _so_condition(U: Array) -> float:
    """kappa of :class:`SweepInfo` for the SO(n) network: the layer Jacobians are right
    multiplications by U_k (forward) and U_k^T (backward), of norm ||U_k||_2."""
    return _window_product(np.log(np.linalg.norm(U, 2, axis=(-2, -1)))[:, None])


@overload
def so_network_gradients(
    Q0: ArrayLike,
    U: ArrayLike,
    lam: ArrayLike,
    targets: ArrayLike,
    alpha: float = ...,
    *,
    return_info: Literal[False] = False,
) -> tuple[float, Array]: ...


@overload
def so_network_gradients(
    Q0: ArrayLike,
    U: ArrayLike,
    lam: ArrayLike,
    targets: ArrayLike,
    alpha: float = ...,
    *,
    return_info: Literal[True],
) -> tuple[float, Array, SweepInfo]: ...


@fill_doc(DOC)
def so_network_gradients(
    Q0: ArrayLike,
    U: ArrayLike,
    lam: ArrayLike,
    targets: ArrayLike,
    alpha: float = 0.0,
    *,
    return_info: bool = False,
) -> tuple[float, Array] | tuple[float, Array, SweepInfo]:
    r"""Loss and skew gradients of the SO(n) network from the costates of the maximum principle.

    The loss is

    .. math::

        L(U) = \sum_a \tfrac12\|Q^a_N - T^a\|_F^2 + \alpha\sum_k \operatorname{tr}(\Lambda(I - U_k)),

    the paper's learning problem (claim D9) with its running cost :math:`\operatorname{tr}
    (\Lambda U_k)` replaced by :math:`-\alpha\operatorname{tr}(\Lambda U_k)` plus a constant, so
    that for :math:`\alpha > 0` the running cost is :math:`\ge 0` and vanishes at :math:`U_k = I`.
    The costates are those of the proof before the sign flip (D9), :math:`P^a_N =
    -\partial\phi/\partial Q^a_N = -(Q^a_N - T^a)` and :math:`P^a_k = P^a_{k+1}U_k^T` (minus the
    back-propagated gradients, as for the ResNet), and

    .. math::

        G_k = \tfrac12(S_k - S_k^T) + \tfrac\alpha2(\Lambda U_k - U_k^T\Lambda),\qquad
        S_k = \sum_a (P^a_{k+1})^T Q^a_{k+1},

    which satisfies :math:`\frac{d}{dt}L(\dots, U_k e^{t\xi}, \dots)|_{t=0} =
    \operatorname{tr}(G_k^T\xi)` for every skew :math:`\xi`.  Equivalently :math:`G_k =
    \tfrac12 U_k^T(\alpha J_D(U_k) - \sum_a((Q^a_k)^TP^a_k - (P^a_k)^TQ^a_k))U_k`: it vanishes
    exactly when the paper's equation for :math:`U_k` (Ukdef2) holds with :math:`\Lambda \to
    \alpha\Lambda`.  The formulas are the generated kernels checked by claim D9 (exact rational
    evidence against the directional derivative).

    On :math:`SO(n)`, :math:`\tfrac12\|Q - T\|_F^2 = n - \operatorname{tr}(T^TQ)`, so the data
    term is also the alignment loss :math:`-\sum_a\operatorname{tr}((T^a)^TQ^a_N)` up to a
    constant; to classify orientations, take for :math:`T^a` the prototype rotation of the class
    of sample :math:`a`.

    Parameters
    ----------
    %(Q0)s
    %(U)s
    %(lam)s
    targets : array_like, shape (M, n, n)
        The targets :math:`T^a` (in SO(n) for the paper's problem; any matrices work).
    alpha : float, optional
        The weight :math:`\alpha \ge 0` of the running cost.
    return_info : bool, optional
        Also return a :class:`~symrb.learning.SweepInfo` (the condition estimate of the sweeps,
        about 1 for orthogonal controls; not computed by default).

    Returns
    -------
    loss : float
        :math:`L(U)`.
    G : ndarray, shape (N, n, n)
        The skew gradients :math:`G_k`.
    info : SweepInfo
        Only with ``return_info=True``.  Accuracy stated and tested (tests/test_conditions.py,
        against a 40-digit mpmath sweep): :math:`\max_k\|G_k - G_{k,\mathrm{exact}}\|_F \le
        10(N+1)n\varepsilon\kappa B` with
        :math:`B = M\sqrt n\,(\sqrt n + \max_{k,a}\|P^a_k\|_F) + \alpha\max_i\lambda_i`.

    Raises
    ------
    InputError
        Shapes that do not match, ``Q0`` or ``U`` not in SO(n), ``lam`` not positive or
        ``alpha < 0``.

    Examples
    --------
    The gradient agrees with a central difference along :math:`U_0 e^{t\xi}`:

    >>> import numpy as np
    >>> import symrb
    >>> from scipy.linalg import expm
    >>> from symrb.learning import so_network_gradients
    >>> Q0, T = symrb.random_SO(3, (4,), seed=0), symrb.random_SO(3, (4,), seed=1)
    >>> U, lam = symrb.random_SO(3, (2,), seed=2), np.array([1.0, 2.0, 3.0])
    >>> loss, G = so_network_gradients(Q0, U, lam, T, alpha=0.5)
    >>> xi = symrb.hat([0.3, -0.2, 0.5])
    >>> Up, Um = U.copy(), U.copy()
    >>> Up[0], Um[0] = U[0] @ expm(1e-6 * xi), U[0] @ expm(-1e-6 * xi)
    >>> fd = (so_network_gradients(Q0, Up, lam, T, alpha=0.5)[0]
    ...       - so_network_gradients(Q0, Um, lam, T, alpha=0.5)[0]) / 2e-6
    >>> print(round(fd, 6), round(float(np.sum(G[0] * xi)), 6))
    -1.662582 -1.662582
    """
    UU = _so_controls(U)
    prob = _SOProblem(Q0, targets, lam, alpha, UU.shape[-1])
    loss, G = prob.gradients(UU)
    if not return_info:
        return loss, G
    return loss, G, SweepInfo(condition=_so_condition(UU), layers=int(UU.shape[0]))


@overload
def so_network_costates(
    Q0: ArrayLike, U: ArrayLike, targets: ArrayLike, *, return_info: Literal[False] = False
) -> tuple[Array, Array]: ...


@overload
def so_network_costates(
    Q0: ArrayLike, U: ArrayLike, targets: ArrayLike, *, return_info: Literal[True]
) -> tuple[Array, Array, SweepInfo]: ...


@fill_doc(DOC)
def so_network_costates(
    Q0: ArrayLike, U: ArrayLike, targets: ArrayLike, *, return_info: bool = False
) -> tuple[Array, Array] | tuple[Array, Array, SweepInfo]:
    r"""The layers and the costates of the SO(n) network (the forward and the backward sweep).

    :math:`P^a_N = -(Q^a_N - T^a)`, :math:`P^a_k = P^a_{k+1}U_k^T` (claim D9, the costates of
    the proof before the sign flip; the running cost does not enter them).

    Parameters
    ----------
    %(Q0)s
    %(U)s
    %(T)s
    return_info : bool, optional
        Also return a :class:`~symrb.learning.SweepInfo` (not computed by default).

    Returns
    -------
    Q : ndarray, shape (N + 1, M, n, n)
        The layers :math:`Q^a_k`.
    P : ndarray, shape (N + 1, M, n, n)
        The costates :math:`P^a_k`.
    info : SweepInfo
        Only with ``return_info=True``.  Accuracy stated and tested: per sample,
        :math:`\max_k\|P^a_k - P^a_{k,\mathrm{exact}}\|_F \le 10(N+1)n\varepsilon\kappa
        (\sqrt n + \max_k\|P^a_k\|_F)`.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> from symrb.learning import so_network_costates
    >>> Q0, T, U = symrb.random_SO(3, (2,), seed=0), symrb.random_SO(3, (2,), seed=1), symrb.random_SO(3, (3,), seed=2)
    >>> Q, P = so_network_costates(Q0, U, T)
    >>> bool(np.allclose(P[-1], T - Q[-1])), bool(np.allclose(P[0], P[1] @ U[0].T))
    (True, True)
    """
    UU = _so_controls(U)
    n = UU.shape[-1]
    Q = _so_samples(Q0, n)
    Ts = _so_targets(targets, Q.shape).reshape(-1, n)
    Qs = _so_forward(Q.reshape(-1, n), UU)
    _G, Ps = _so_backward(Qs, UU, np.ones(n), Ts, 0.0, costates=True)
    assert Ps is not None
    shape = (UU.shape[0] + 1, Q.shape[0], n, n)
    if not return_info:
        return Qs.reshape(shape), Ps.reshape(shape)
    info = SweepInfo(condition=_so_condition(UU), layers=int(UU.shape[0]))
    return Qs.reshape(shape), Ps.reshape(shape), info


@fill_doc(DOC)
def so_extremal_residual(
    Q0: ArrayLike, U: ArrayLike, lam: ArrayLike, targets: ArrayLike, alpha: float
) -> Array:
    r"""How far the controls are from the extremal equations of claim D9, layer by layer.

    The paper's equation for :math:`U_k` (Ukdef2) for the loss of :func:`so_network_gradients`
    reads :math:`\alpha J_D(U_k) = \sum_a((Q^a_k)^TP^a_k - (P^a_k)^TQ^a_k)` with the costates of
    :func:`so_network_costates` (:math:`J_D(U) = U\Lambda - \Lambda U^T`); this returns
    :math:`r_k = \|\alpha J_D(U_k) - \sum_a((Q^a_k)^TP^a_k - (P^a_k)^TQ^a_k)\|_F`, which equals
    :math:`2\|G_k\|_F` (the gradient).  The momentum is the generated kernel
    ``symmetric_momentum`` on the samples stacked by rows (which sums it over the samples).

    Parameters
    ----------
    %(Q0)s
    %(U)s
    %(lam)s
    %(T)s
    alpha : float
        The weight of the running cost, >= 0.

    Returns
    -------
    r : ndarray, shape (N,)
        The residuals :math:`r_k`.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> from symrb.learning import so_extremal_residual, so_network_gradients
    >>> Q0, T, U = symrb.random_SO(3, (2,), seed=0), symrb.random_SO(3, (2,), seed=1), symrb.random_SO(3, (3,), seed=2)
    >>> lam = np.array([1.0, 2.0, 3.0])
    >>> r = so_extremal_residual(Q0, U, lam, T, alpha=0.5)
    >>> G = so_network_gradients(Q0, U, lam, T, alpha=0.5)[1]
    >>> bool(np.allclose(r, 2 * np.linalg.norm(G, axis=(1, 2))))
    True
    """
    UU = _so_controls(U)
    prob = _SOProblem(Q0, targets, lam, alpha, UU.shape[-1])
    return _so_extremal(prob, UU)


def _so_extremal(prob: _SOProblem, U: Array) -> Array:
    Qs = _so_forward(prob.Qs0, U)
    _G, Ps = _so_backward(Qs, U, prob.lam, prob.Ts, prob.alpha, costates=True)
    assert Ps is not None
    out = np.empty(U.shape[0])
    for k in range(U.shape[0]):
        R = _gsr.symmetric_momentum(Qs[k], Ps[k])
        out[k] = np.linalg.norm(prob.alpha * _gdr.jd(U[k], prob.lam) - R)
    return out
