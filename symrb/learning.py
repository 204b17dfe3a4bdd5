r"""Deep learning as discrete optimal control (paper, Section 2, Remarks 1-2; claims D5, D6).

A network of N layers is the control system :math:`x_{k+1} = f(x_k, u_k)` with
:math:`u_k = (K_k, \beta_k)` and one of the layers

.. math::

    f(x, u) = x + \sigma(Kx + \beta) \quad(\text{residual}),\qquad
    f(x, u) = \sigma(Kx + \beta) \quad(\text{plain}),

with :math:`\sigma = \tanh` or the logistic function :math:`(1 + \tanh(z/2))/2 = 1/(1 + e^{-z})`,
applied entrywise.  The residual layer is the ResNet layer :math:`x + h\sigma(Kx + \beta)` of
Benning et al. (2019) with :math:`h = 1`; the paper's Remark 1 gives that name to the plain layer
(claim D6).  The samples :math:`x^a_0` share the controls.  The loss is the terminal cost
:math:`\Phi = \sum_a \phi(x^a_N)`, :math:`\phi(x) = \tfrac12|x - y^a|^2` (running cost g = 0).

Sign conventions (derived in :mod:`derivations.parts.discrete_control`, claims D5 and D6):
the Hamiltonian is :math:`H(p, x, u) = \langle p, f(x, u)\rangle` and the problem a minimisation,
so with the corrected endpoint condition of D5 (the paper's endpoint condition in Section 2 has the
opposite sign, which without a running cost only flips the sign of every costate) the costates are

.. math::

    p^a_N = -\nabla\phi(x^a_N) = -(x^a_N - y^a),\qquad
    p^a_k = \partial_x H(p^a_{k+1}, x^a_k, u_k) = (\partial_x f)^T p^a_{k+1},

and they are *minus* the back-propagated gradients: :math:`p^a_k = -\partial\Phi/\partial x^a_k`.
The weight gradients are :math:`\partial\Phi/\partial u_k = -\sum_a \partial_u H(p^a_{k+1}, x^a_k,
u_k)`, i.e. :math:`\partial\Phi/\partial K_k = -\sum_a (\sigma'(z^a_k)\odot p^a_{k+1})
(x^a_k)^T` and :math:`\partial\Phi/\partial\beta_k = -\sum_a \sigma'(z^a_k)\odot p^a_{k+1}`,
:math:`z^a_k = K_k x^a_k + \beta_k`.

Every layer and adjoint step is a kernel generated in :mod:`symrb._generated.discrete_control`.
Arrays: states have shape ``(N + 1, ..., n)`` (layer first, then any sample axes, then the state);
``K`` has shape ``(N, n, n)`` and ``beta`` ``(N, n)``.  Inputs are never mutated.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from . import _validate as v
from ._generated import discrete_control as _gen
from ._generated import discrete_rigid_body as _gdr
from ._generated import symmetric_rigid_body as _gsr
from ._progress import progress_bar
from ._validate import Array
from .errors import InputError

__all__ = [
    "resnet_forward",
    "squared_error",
    "costate_sweep",
    "loss_gradients",
    "train",
    "TrainResult",
    "toy_classification",
    "so_network_forward",
    "so_network_gradients",
    "so_network_costates",
    "so_extremal_residual",
]

_ACTIVATIONS = ("tanh", "logistic")


#: (activation, residual) -> (layer step, adjoint step), the generated kernels of claim D6
_KERNELS: dict[tuple[str, bool], tuple[Callable, Callable]] = {
    ("tanh", True): (_gen.resnet_step_tanh, _gen.resnet_adjoint_tanh),
    ("tanh", False): (_gen.resnet_step_tanh_plain, _gen.resnet_adjoint_tanh_plain),
    ("logistic", True): (_gen.resnet_step_logistic, _gen.resnet_adjoint_logistic),
    ("logistic", False): (_gen.resnet_step_logistic_plain, _gen.resnet_adjoint_logistic_plain),
}


def _kernels(activation: str, residual: bool) -> tuple[Callable, Callable]:
    if activation not in _ACTIVATIONS:
        raise InputError(f"activation must be one of {_ACTIVATIONS}, got {activation!r}")
    if not isinstance(residual, bool | np.bool_):
        raise InputError(f"residual must be True or False, got {residual!r}")
    return _KERNELS[(activation, bool(residual))]


def _weights(K: ArrayLike, beta: ArrayLike) -> tuple[Array, Array]:
    KK = v.as_float_array(K, "K")
    bb = v.as_float_array(beta, "beta")
    if KK.ndim != 3 or KK.shape[1] != KK.shape[2] or KK.shape[0] < 1:
        raise InputError(f"K must have shape (N, n, n) with N >= 1 layers, got {KK.shape}")
    if bb.shape != KK.shape[:2]:
        raise InputError(f"beta must have shape (N, n) = {KK.shape[:2]} to match K, got {bb.shape}")
    return KK, bb


def _states_like(x: ArrayLike, name: str, n: int) -> Array:
    a = v.as_float_array(x, name)
    if a.ndim < 1 or a.shape[-1] != n:
        raise InputError(f"{name} must have shape (..., n) with n = {n} (from K), got {a.shape}")
    return a


def resnet_forward(
    x0: ArrayLike,
    K: ArrayLike,
    beta: ArrayLike,
    activation: str = "tanh",
    residual: bool = True,
) -> Array:
    r"""All states :math:`x_0, \dots, x_N` of :math:`x_{k+1} = f(x_k, (K_k, \beta_k))`.

    Parameters
    ----------
    x0 : array_like, shape (..., n)
        Initial states, one per sample (any leading sample axes).
    K : array_like, shape (N, n, n)
        Layer weights.
    beta : array_like, shape (N, n)
        Layer biases.
    activation : {"tanh", "logistic"}, optional
        The activation :math:`\sigma`.
    residual : bool, optional
        True for the layer :math:`x + \sigma(Kx + \beta)`, False for :math:`\sigma(Kx + \beta)`.

    Returns
    -------
    states : ndarray, shape (N + 1, ..., n)
        ``states[k]`` is :math:`x_k`.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> x0 = np.array([[0.5, -0.5], [1.0, 0.0]])  # two samples in the plane
    >>> K, beta = np.full((3, 2, 2), 0.1), np.zeros((3, 2))  # three layers
    >>> states = symrb.resnet_forward(x0, K, beta)
    >>> states.shape
    (4, 2, 2)
    >>> print(states[-1].round(4))
    [[ 0.5    -0.5   ]
     [ 1.3619  0.3619]]
    """
    step, _ = _kernels(activation, residual)
    KK, bb = _weights(K, beta)
    x = _states_like(x0, "x0", KK.shape[1])
    out = np.empty((KK.shape[0] + 1, *x.shape))
    out[0] = x
    for k in range(KK.shape[0]):
        out[k + 1] = step(KK[k], bb[k][:, None], out[k][..., None])[..., 0]
    return out


def squared_error(xN: ArrayLike, targets: ArrayLike) -> float:
    r"""The terminal loss :math:`\Phi = \sum_a \tfrac12 |x^a_N - y^a|^2` (summed, not averaged).

    Parameters
    ----------
    xN : array_like, shape (..., n)
        The final states.
    targets : array_like, shape (..., n)
        The targets :math:`y^a`, of the shape of ``xN``.

    Returns
    -------
    float
        The loss.

    Examples
    --------
    >>> import symrb
    >>> print(symrb.squared_error([[1.0, 2.0], [0.0, 0.0]], [[1.0, 0.0], [0.0, 1.0]]))
    2.5
    """
    a = v.as_float_array(xN, "xN")
    y = v.as_float_array(targets, "targets")
    if a.shape != y.shape:
        raise InputError(
            f"targets must have the shape of the final states {a.shape}, got {y.shape}"
        )
    return float(0.5 * np.sum((a - y) ** 2))


def _sweep(
    states: Array, KK: Array, bb: Array, y: Array, activation: str, residual: bool
) -> tuple[Array, Array, Array]:
    _, adjoint = _kernels(activation, residual)
    N = KK.shape[0]
    p = np.empty_like(states)
    p[N] = -(states[N] - y)
    gK = np.empty_like(KK)
    gb = np.empty_like(bb)
    sample_axes = tuple(range(states.ndim - 2))
    for k in range(N - 1, -1, -1):
        p_prev, dK, db = adjoint(KK[k], bb[k][:, None], states[k][..., None], p[k + 1][..., None])
        p[k] = p_prev[..., 0]
        # dPhi/du_k = -sum_a dH/du_k(p^a_{k+1}, x^a_k, u_k)
        gK[k] = -np.sum(dK, axis=sample_axes) if sample_axes else -dK
        gb[k] = -(np.sum(db[..., 0], axis=sample_axes) if sample_axes else db[..., 0])
    return p, gK, gb


def _check_sweep_inputs(states, K, beta, targets):
    KK, bb = _weights(K, beta)
    st = v.as_float_array(states, "states")
    N, n = KK.shape[0], KK.shape[1]
    if st.ndim < 2 or st.shape[0] != N + 1 or st.shape[-1] != n:
        raise InputError(
            f"states must have shape (N + 1, ..., n) = ({N + 1}, ..., {n}) to match K, got {st.shape}"
        )
    y = v.as_float_array(targets, "targets")
    if y.shape != st.shape[1:]:
        raise InputError(f"targets must have shape {st.shape[1:]} (one per sample), got {y.shape}")
    return st, KK, bb, y


def costate_sweep(
    states: ArrayLike,
    K: ArrayLike,
    beta: ArrayLike,
    targets: ArrayLike,
    activation: str = "tanh",
    residual: bool = True,
) -> Array:
    r"""The costates :math:`p^a_k`, shape (N + 1, ..., n), of the squared-error problem.

    :math:`p^a_N = -(x^a_N - y^a)` and :math:`p^a_k = \partial_x H(p^a_{k+1}, x^a_k, u_k)`; they
    equal :math:`-\partial\Phi/\partial x^a_k` (back-propagation with the opposite sign).

    Parameters
    ----------
    states : array_like, shape (N + 1, ..., n)
        The states from :func:`resnet_forward` with the same weights and layer type.
    K : array_like, shape (N, n, n)
        Layer weights.
    beta : array_like, shape (N, n)
        Layer biases.
    targets : array_like, shape (..., n)
        The targets :math:`y^a`.
    activation : {"tanh", "logistic"}, optional
        The activation :math:`\sigma`.
    residual : bool, optional
        True for residual layers, False for plain ones.

    Returns
    -------
    p : ndarray, shape (N + 1, ..., n)
        The costates.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> x0, y = np.array([[0.5, -0.5], [1.0, 0.0]]), np.array([[1.0, 0.0], [0.0, 1.0]])
    >>> K, beta = np.full((3, 2, 2), 0.1), np.zeros((3, 2))
    >>> states = symrb.resnet_forward(x0, K, beta)
    >>> p = symrb.costate_sweep(states, K, beta, y)
    >>> bool(np.allclose(p[-1], y - states[-1]))  # p_N = -(x_N - y)
    True
    """
    st, KK, bb, y = _check_sweep_inputs(states, K, beta, targets)
    return _sweep(st, KK, bb, y, activation, residual)[0]


def loss_gradients(
    x0: ArrayLike,
    K: ArrayLike,
    beta: ArrayLike,
    targets: ArrayLike,
    activation: str = "tanh",
    residual: bool = True,
) -> tuple[float, Array, Array]:
    r"""Loss and weight gradients through the maximum principle.

    The gradients are :math:`\partial\Phi/\partial u_k = -\sum_a \partial_u H(p^a_{k+1}, x^a_k,
    u_k)` (module docstring).

    Parameters
    ----------
    x0 : array_like, shape (..., n)
        Initial states, one per sample.
    K : array_like, shape (N, n, n)
        Layer weights.
    beta : array_like, shape (N, n)
        Layer biases.
    targets : array_like, shape (..., n)
        The targets :math:`y^a`.
    activation : {"tanh", "logistic"}, optional
        The activation :math:`\sigma`.
    residual : bool, optional
        True for residual layers, False for plain ones.

    Returns
    -------
    Phi : float
        The loss :func:`squared_error`.
    dK : ndarray, shape (N, n, n)
        :math:`\partial\Phi/\partial K`.
    dbeta : ndarray, shape (N, n)
        :math:`\partial\Phi/\partial\beta`.

    Examples
    --------
    The gradient agrees with a central difference:

    >>> import numpy as np
    >>> import symrb
    >>> x0, y = np.array([[0.5, -0.5], [1.0, 0.0]]), np.array([[1.0, 0.0], [0.0, 1.0]])
    >>> K, beta = np.full((3, 2, 2), 0.1), np.zeros((3, 2))
    >>> Phi, dK, dbeta = symrb.loss_gradients(x0, K, beta, y)
    >>> E = np.zeros_like(K)
    >>> E[0, 0, 1] = 1e-6
    >>> fd = (symrb.loss_gradients(x0, K + E, beta, y)[0]
    ...       - symrb.loss_gradients(x0, K - E, beta, y)[0]) / 2e-6
    >>> print(round(float(dK[0, 0, 1]), 6), round(fd, 6))
    0.36 0.36
    """
    states = resnet_forward(x0, K, beta, activation, residual)
    st, KK, bb, y = _check_sweep_inputs(states, K, beta, targets)
    _p, gK, gb = _sweep(st, KK, bb, y, activation, residual)
    return squared_error(st[-1], y), gK, gb


@dataclass(frozen=True)
class TrainResult:
    """Outcome of :func:`train`.

    Attributes
    ----------
    K : ndarray, shape (N, n, n)
        The final weights.
    beta : ndarray, shape (N, n)
        The final biases.
    losses : ndarray, shape (steps + 1,)
        The loss before each step and at the end.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> x0, y, _ = symrb.toy_classification(50, seed=0)
    >>> result = symrb.train(x0, y, np.zeros((2, 2, 2)), np.zeros((2, 2)), steps=10, lr=0.01)
    >>> result.K.shape, result.losses.shape
    ((2, 2, 2), (11,))
    """

    K: Array
    beta: Array
    losses: Array


def train(
    x0: ArrayLike,
    targets: ArrayLike,
    K: ArrayLike,
    beta: ArrayLike,
    steps: int = 200,
    lr: float = 0.01,
    activation: str = "tanh",
    residual: bool = True,
    progress: bool = False,
) -> TrainResult:
    r"""Plain gradient descent :math:`u_k \leftarrow u_k - \eta\,\partial\Phi/\partial u_k`.

    The gradients come from :func:`loss_gradients` (costates and :math:`\partial H/\partial u`).
    The initial ``K`` and ``beta`` are copied, never modified.

    Parameters
    ----------
    x0 : array_like, shape (..., n)
        Initial states, one per sample.
    targets : array_like, shape (..., n)
        The targets :math:`y^a`.
    K : array_like, shape (N, n, n)
        Initial layer weights.
    beta : array_like, shape (N, n)
        Initial layer biases.
    steps : int, optional
        The number of gradient steps, >= 0.
    lr : float, optional
        The learning rate :math:`\eta > 0`.
    activation : {"tanh", "logistic"}, optional
        The activation :math:`\sigma`.
    residual : bool, optional
        True for residual layers, False for plain ones.
    progress : bool, optional
        Show a tqdm progress bar (needs the optional package tqdm).

    Returns
    -------
    TrainResult
        The final weights and the losses (``steps + 1`` entries).

    Raises
    ------
    InputError
        Bad arguments, or a loss that became non-finite (``lr`` too large).

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> x0, y, _ = symrb.toy_classification(200, seed=0)
    >>> K, beta = np.zeros((4, 2, 2)), np.zeros((4, 2))
    >>> result = symrb.train(x0, y, K, beta, steps=50, lr=0.005)
    >>> print(result.losses[[0, -1]].round(2))
    [42.47 32.83]
    """
    if isinstance(steps, bool) or not isinstance(steps, int | np.integer) or steps < 0:
        raise InputError(f"steps must be a non-negative integer, got {steps!r}")
    if not v.real_scalar(lr, "lr") > 0:
        raise InputError(f"lr must be a positive finite number, got {lr!r}")
    KK, bb = _weights(K, beta)
    KK, bb = KK.copy(), bb.copy()
    losses = np.empty(int(steps) + 1)
    with progress_bar(int(steps), "train", progress) as bar:
        for i in range(int(steps)):
            loss, gK, gb = loss_gradients(x0, KK, bb, targets, activation, residual)
            if not np.isfinite(loss):
                raise InputError(f"loss became non-finite at step {i} (lr = {lr} too large?)")
            losses[i] = loss
            KK -= lr * gK
            bb -= lr * gb
            bar.step()
    losses[-1] = loss_gradients(x0, KK, bb, targets, activation, residual)[0]
    return TrainResult(K=KK, beta=bb, losses=losses)


def toy_classification(num: int = 200, seed: int | np.random.Generator | None = 0):
    r"""A 2-D toy problem: points uniform in :math:`[-1, 1]^2`, label
    :math:`c = \operatorname{sign}(x_2 - \tfrac12\sin(\pi x_1))`, target :math:`y = (x_1, c)`.

    A residual network must bend the sine boundary flat and push the classes to
    :math:`x_2 = \pm1` (a deformation of the plane, which residual layers can approximate).

    Parameters
    ----------
    num : int, optional
        The number of points, >= 1.
    seed : int, numpy.random.Generator or None, optional
        The random source.

    Returns
    -------
    x0 : ndarray, shape (num, 2)
        The points.
    targets : ndarray, shape (num, 2)
        :math:`(x_1, c)`.
    labels : ndarray, shape (num,)
        The classes :math:`c = \pm 1`.

    Examples
    --------
    >>> import symrb
    >>> x0, targets, labels = symrb.toy_classification(200, seed=0)
    >>> x0.shape, targets.shape, int((labels > 0).sum())
    ((200, 2), (200, 2), 99)
    """
    if isinstance(num, bool) or not isinstance(num, int | np.integer) or num < 1:
        raise InputError(f"num must be a positive integer, got {num!r}")
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    x = rng.uniform(-1.0, 1.0, size=(int(num), 2))
    c = np.where(x[:, 1] - 0.5 * np.sin(np.pi * x[:, 0]) >= 0, 1.0, -1.0)
    targets = np.stack([x[:, 0], c], axis=-1)
    return x, targets, c


# =============================================================================================
# The SO(n) network of the paper's learning theorem (claim D9)
#
# Samples Q^a_0 in SO(n) (a = 1..M), layers Q^a_{k+1} = Q^a_k U_k with shared controls U_k in
# SO(n), loss L(U) = sum_a 1/2 ||Q^a_N - T^a||_F^2 + alpha sum_k tr(Lambda (I - U_k)).  Inside,
# the samples are stacked by rows, (M, n, n) -> (M n, n): a layer, a costate step and the sum
# over the samples in the gradient are then one matrix product each (the generated kernels of
# claim D9 in symrb._generated.discrete_rigid_body).


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

    def gradients(self, U: Array) -> tuple[float, Array, Array]:
        """(loss, G, stacked layers)."""
        Qs = _so_forward(self.Qs0, U)
        G, _ = _so_backward(Qs, U, self.lam, self.Ts, self.alpha)
        return _so_loss(Qs[-1], self.Ts, U, self.lam, self.alpha), G, Qs


def so_network_forward(Q0: ArrayLike, U: ArrayLike) -> Array:
    r"""All layers :math:`Q^a_k` of the SO(n) network :math:`Q^a_{k+1} = Q^a_k U_k` (claim D9).

    The controls :math:`U_k` are shared by the samples, the samples :math:`Q^a_0` are the
    initial conditions.  Each layer is the generated kernel ``so_network_layer`` applied to the
    samples stacked by rows (one matrix product per layer for all samples).

    Parameters
    ----------
    Q0 : array_like, shape (M, n, n)
        The samples :math:`Q^a_0`, in SO(n).
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


def so_network_gradients(
    Q0: ArrayLike,
    U: ArrayLike,
    lam: ArrayLike,
    targets: ArrayLike,
    alpha: float = 0.0,
) -> tuple[float, Array]:
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

    Parameters
    ----------
    Q0 : array_like, shape (M, n, n)
        The samples :math:`Q^a_0`, in SO(n).
    U : array_like, shape (N, n, n)
        The controls, in SO(n).
    lam : array_like, shape (n,)
        The diagonal of :math:`\Lambda`, positive.
    targets : array_like, shape (M, n, n)
        The targets :math:`T^a` (in SO(n) for the paper's problem; any matrices work).
    alpha : float, optional
        The weight :math:`\alpha \ge 0` of the running cost.

    Returns
    -------
    loss : float
        :math:`L(U)`.
    G : ndarray, shape (N, n, n)
        The skew gradients :math:`G_k`.

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
    loss, G, _ = prob.gradients(UU)
    return loss, G


def so_network_costates(Q0: ArrayLike, U: ArrayLike, targets: ArrayLike) -> tuple[Array, Array]:
    r"""The layers and the costates of the SO(n) network (the forward and the backward sweep).

    :math:`P^a_N = -(Q^a_N - T^a)`, :math:`P^a_k = P^a_{k+1}U_k^T` (claim D9, the costates of
    the proof before the sign flip; the running cost does not enter them).

    Parameters
    ----------
    Q0 : array_like, shape (M, n, n)
        The samples, in SO(n).
    U : array_like, shape (N, n, n)
        The controls, in SO(n).
    targets : array_like, shape (M, n, n)
        The targets :math:`T^a`.

    Returns
    -------
    Q : ndarray, shape (N + 1, M, n, n)
        The layers :math:`Q^a_k`.
    P : ndarray, shape (N + 1, M, n, n)
        The costates :math:`P^a_k`.

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
    return Qs.reshape(shape), Ps.reshape(shape)


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
    Q0 : array_like, shape (M, n, n)
        The samples, in SO(n).
    U : array_like, shape (N, n, n)
        The controls, in SO(n).
    lam : array_like, shape (n,)
        The diagonal of :math:`\Lambda`, positive.
    targets : array_like, shape (M, n, n)
        The targets.
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
