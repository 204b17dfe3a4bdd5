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

Sign conventions (derived in :mod:`derivations.claims.section2`, claims D5 and D6):
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
from typing import Literal, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as v
from .._docs import fill_doc
from .._generated import discrete_control as _gen
from .._progress import progress_bar
from .._validate import Array
from ..errors import InputError
from ._common import DOC, SweepInfo, _positive, _window_product

__all__ = [
    "resnet_forward",
    "squared_error",
    "costate_sweep",
    "loss_gradients",
    "train",
    "TrainResult",
    "resnet_predict",
    "train_msa",
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
        raise InputError(
            f"activation must be one of {_ACTIVATIONS}, got {activation!r}; pass one of them"
        )
    if not isinstance(residual, bool | np.bool_):
        raise InputError(f"residual must be True or False, got {residual!r}; pass a bool")
    return _KERNELS[(activation, bool(residual))]


def _weights(K: ArrayLike, beta: ArrayLike) -> tuple[Array, Array]:
    KK = v.as_float_array(K, "K")
    bb = v.as_float_array(beta, "beta")
    if KK.ndim != 3 or KK.shape[1] != KK.shape[2] or KK.shape[0] < 1:
        raise InputError(
            f"K must have shape (N, n, n) with N >= 1 layers, got {KK.shape}; pass one square "
            "weight matrix per layer"
        )
    if bb.shape != KK.shape[:2]:
        raise InputError(
            f"beta must have shape (N, n) = {KK.shape[:2]} to match K, got {bb.shape}; pass one "
            "bias vector per layer"
        )
    return KK, bb


def _states_like(x: ArrayLike, name: str, n: int) -> Array:
    a = v.as_float_array(x, name)
    if a.ndim < 1 or a.shape[-1] != n:
        raise InputError(
            f"{name} must have shape (..., n) with n = {n} (from K), got {a.shape}; pass states "
            "of the size of K's matrices"
        )
    return a


@fill_doc(DOC)
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
    %(x0)s
    %(K)s
    %(beta)s
    %(activation)s
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
    >>> states = symrb.learning.resnet_forward(x0, K, beta)
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
    >>> print(symrb.learning.squared_error([[1.0, 2.0], [0.0, 0.0]], [[1.0, 0.0], [0.0, 1.0]]))
    2.5
    """
    a = v.as_float_array(xN, "xN")
    y = v.as_float_array(targets, "targets")
    if a.shape != y.shape:
        raise InputError(
            f"targets must have the shape of the final states {a.shape}, got {y.shape}; pass one "
            "target per sample"
        )
    return float(0.5 * np.sum((a - y) ** 2))


def _resnet_condition(
    states: Array, KK: Array, bb: Array, activation: str, residual: bool
) -> float:
    """kappa of :class:`SweepInfo` for the residual network (layer Jacobians per sample)."""
    N, n = KK.shape[0], KK.shape[1]
    x = states[:-1].reshape(N, -1, n)  # (N, samples, n)
    z = np.einsum("kij,kaj->kai", KK, x) + bb[:, None, :]
    if activation == "tanh":
        ds = 1.0 - np.tanh(z) ** 2
    else:
        sig = 0.5 * (1.0 + np.tanh(0.5 * z))
        ds = sig * (1.0 - sig)
    J = ds[..., :, None] * KK[:, None]  # diag(sigma'(z)) K, (N, samples, n, n)
    if residual:
        J = J + np.eye(n)
    with np.errstate(divide="ignore"):
        logs = np.log(np.linalg.norm(J, 2, axis=(-2, -1)))
    return _window_product(logs)


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
            f"states must have shape (N + 1, ..., n) = ({N + 1}, ..., {n}) to match K, got {st.shape}; "
            "pass the output of resnet_forward with the same K"
        )
    y = v.as_float_array(targets, "targets")
    if y.shape != st.shape[1:]:
        raise InputError(
            f"targets must have shape {st.shape[1:]} (one per sample), got {y.shape}; pass one "
            "target per sample"
        )
    return st, KK, bb, y


@overload
def costate_sweep(
    states: ArrayLike,
    K: ArrayLike,
    beta: ArrayLike,
    targets: ArrayLike,
    activation: str = ...,
    residual: bool = ...,
    *,
    return_info: Literal[False] = False,
) -> Array: ...


@overload
def costate_sweep(
    states: ArrayLike,
    K: ArrayLike,
    beta: ArrayLike,
    targets: ArrayLike,
    activation: str = ...,
    residual: bool = ...,
    *,
    return_info: Literal[True],
) -> tuple[Array, SweepInfo]: ...


@fill_doc(DOC)
def costate_sweep(
    states: ArrayLike,
    K: ArrayLike,
    beta: ArrayLike,
    targets: ArrayLike,
    activation: str = "tanh",
    residual: bool = True,
    *,
    return_info: bool = False,
) -> Array | tuple[Array, SweepInfo]:
    r"""The costates :math:`p^a_k`, shape (N + 1, ..., n), of the squared-error problem.

    :math:`p^a_N = -(x^a_N - y^a)` and :math:`p^a_k = \partial_x H(p^a_{k+1}, x^a_k, u_k)`; they
    equal :math:`-\partial\Phi/\partial x^a_k` (back-propagation with the opposite sign).

    Parameters
    ----------
    states : array_like, shape (N + 1, ..., n)
        The states from :func:`resnet_forward` with the same weights and layer type.
    %(K)s
    %(beta)s
    %(y)s
    %(activation)s
    %(residual)s
    return_info : bool, optional
        Also return a :class:`~symrb.learning.SweepInfo` with the condition estimate of the sweep
        (one SVD of each layer's Jacobian per sample; not computed by default).

    Returns
    -------
    p : ndarray, shape (N + 1, ..., n)
        The costates.
    %(info)s

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> x0, y = np.array([[0.5, -0.5], [1.0, 0.0]]), np.array([[1.0, 0.0], [0.0, 1.0]])
    >>> K, beta = np.full((3, 2, 2), 0.1), np.zeros((3, 2))
    >>> states = symrb.learning.resnet_forward(x0, K, beta)
    >>> p = symrb.learning.costate_sweep(states, K, beta, y)
    >>> bool(np.allclose(p[-1], y - states[-1]))  # p_N = -(x_N - y)
    True
    """
    st, KK, bb, y = _check_sweep_inputs(states, K, beta, targets)
    p = _sweep(st, KK, bb, y, activation, residual)[0]
    if not return_info:
        return p
    kappa = _resnet_condition(st, KK, bb, activation, residual)
    return p, SweepInfo(condition=kappa, layers=int(KK.shape[0]))


@overload
def loss_gradients(
    x0: ArrayLike,
    K: ArrayLike,
    beta: ArrayLike,
    targets: ArrayLike,
    activation: str = ...,
    residual: bool = ...,
    *,
    return_info: Literal[False] = False,
) -> tuple[float, Array, Array]: ...


@overload
def loss_gradients(
    x0: ArrayLike,
    K: ArrayLike,
    beta: ArrayLike,
    targets: ArrayLike,
    activation: str = ...,
    residual: bool = ...,
    *,
    return_info: Literal[True],
) -> tuple[float, Array, Array, SweepInfo]: ...


@fill_doc(DOC)
def loss_gradients(
    x0: ArrayLike,
    K: ArrayLike,
    beta: ArrayLike,
    targets: ArrayLike,
    activation: str = "tanh",
    residual: bool = True,
    *,
    return_info: bool = False,
) -> tuple[float, Array, Array] | tuple[float, Array, Array, SweepInfo]:
    r"""Loss and weight gradients through the maximum principle.

    The gradients are :math:`\partial\Phi/\partial u_k = -\sum_a \partial_u H(p^a_{k+1}, x^a_k,
    u_k)` (module docstring).

    Parameters
    ----------
    %(x0)s
    %(K)s
    %(beta)s
    %(y)s
    %(activation)s
    %(residual)s
    return_info : bool, optional
        Also return a :class:`~symrb.learning.SweepInfo` with the condition estimate of the sweeps
        (accuracy stated there; not computed by default).

    Returns
    -------
    Phi : float
        The loss :func:`squared_error`.
    dK : ndarray, shape (N, n, n)
        :math:`\partial\Phi/\partial K`.
    dbeta : ndarray, shape (N, n)
        :math:`\partial\Phi/\partial\beta`.
    %(info)s

    Examples
    --------
    The gradient agrees with a central difference:

    >>> import numpy as np
    >>> import symrb
    >>> x0, y = np.array([[0.5, -0.5], [1.0, 0.0]]), np.array([[1.0, 0.0], [0.0, 1.0]])
    >>> K, beta = np.full((3, 2, 2), 0.1), np.zeros((3, 2))
    >>> Phi, dK, dbeta = symrb.learning.loss_gradients(x0, K, beta, y)
    >>> E = np.zeros_like(K)
    >>> E[0, 0, 1] = 1e-6
    >>> fd = (symrb.learning.loss_gradients(x0, K + E, beta, y)[0]
    ...       - symrb.learning.loss_gradients(x0, K - E, beta, y)[0]) / 2e-6
    >>> print(round(float(dK[0, 0, 1]), 6), round(fd, 6))
    0.36 0.36
    """
    states = resnet_forward(x0, K, beta, activation, residual)
    st, KK, bb, y = _check_sweep_inputs(states, K, beta, targets)
    _p, gK, gb = _sweep(st, KK, bb, y, activation, residual)
    if not return_info:
        return squared_error(st[-1], y), gK, gb
    kappa = _resnet_condition(st, KK, bb, activation, residual)
    return squared_error(st[-1], y), gK, gb, SweepInfo(condition=kappa, layers=int(KK.shape[0]))


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
    >>> x0, y, _ = symrb.learning.toy_classification(50, seed=0)
    >>> result = symrb.train(x0, y, np.zeros((2, 2, 2)), np.zeros((2, 2)), steps=10, lr=0.01)
    >>> result.K.shape, result.losses.shape
    ((2, 2, 2), (11,))
    """

    K: Array
    beta: Array
    losses: Array


@fill_doc(DOC)
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
    %(x0)s
    %(y)s
    %(K0)s
    %(beta0)s
    steps : int, optional
        The number of gradient steps, >= 0.
    lr : float, optional
        The learning rate :math:`\eta > 0`.
    %(activation)s
    %(residual)s
    %(progress)s

    Returns
    -------
    %(TrainResult)s

    Raises
    ------
    InputError
        Bad arguments, or a loss that became non-finite (``lr`` too large).

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> x0, y, _ = symrb.learning.toy_classification(200, seed=0)
    >>> K, beta = np.zeros((4, 2, 2)), np.zeros((4, 2))
    >>> result = symrb.train(x0, y, K, beta, steps=50, lr=0.005)
    >>> print(result.losses[[0, -1]].round(2))
    [42.47 32.83]
    """
    if isinstance(steps, bool) or not isinstance(steps, int | np.integer) or steps < 0:
        raise InputError(f"steps must be a non-negative integer, got {steps!r}; pass an int >= 0")
    if not v.real_scalar(lr, "lr") > 0:
        raise InputError(f"lr must be a positive finite number, got {lr!r}; pass a float > 0")
    KK, bb = _weights(K, beta)
    KK, bb = KK.copy(), bb.copy()
    losses = np.empty(int(steps) + 1)
    with progress_bar(int(steps), "train", progress) as bar:
        for i in range(int(steps)):
            loss, gK, gb = loss_gradients(x0, KK, bb, targets, activation, residual)
            if not np.isfinite(loss):
                raise InputError(
                    f"loss became non-finite at step {i} (lr = {lr} too large?); pass a smaller lr"
                )
            losses[i] = loss
            KK -= lr * gK
            bb -= lr * gb
            bar.step()
    losses[-1] = loss_gradients(x0, KK, bb, targets, activation, residual)[0]
    return TrainResult(K=KK, beta=bb, losses=losses)


@fill_doc(DOC)
def resnet_predict(
    x0: ArrayLike,
    K: ArrayLike,
    beta: ArrayLike,
    classes: int,
    activation: str = "tanh",
    residual: bool = True,
) -> NDArray[np.int64]:
    r"""Class predictions of the network: the index of the largest of the last ``classes``
    entries of :math:`x_N` (:func:`resnet_forward`).

    Parameters
    ----------
    %(x0)s
    %(K)s
    %(beta)s
    classes : int
        The number of classes, 1 to n.
    %(activation)s
    %(residual)s

    Returns
    -------
    ndarray of int, shape (...)
        The predicted classes.

    Examples
    --------
    >>> import numpy as np
    >>> from symrb.learning import resnet_predict
    >>> x0 = np.array([[0.0, 2.0, 1.0], [0.0, -1.0, 3.0]])
    >>> resnet_predict(x0, np.zeros((1, 3, 3)), np.zeros((1, 3)), classes=2)
    array([0, 1])
    """
    states = resnet_forward(x0, K, beta, activation, residual)
    c = v.count(classes, "classes", 1)
    if c > states.shape[-1]:
        raise InputError(f"classes must be at most n = {states.shape[-1]}, got {classes!r}")
    return np.asarray(np.argmax(states[-1][..., -c:], axis=-1), dtype=np.int64)


@fill_doc(DOC)
def train_msa(
    x0: ArrayLike,
    targets: ArrayLike,
    K: ArrayLike,
    beta: ArrayLike,
    steps: int = 100,
    rho: float = 1.0,
    inner_steps: int = 3,
    inner_lr: float = 0.01,
    activation: str = "tanh",
    residual: bool = True,
    progress: bool = False,
) -> TrainResult:
    r"""The extended method of successive approximations for the residual network (Li, Chen, Tai
    and E 2018), with the layer-wise maximisation by a few gradient steps.

    Each iteration runs the forward and the costate sweep (:func:`costate_sweep`) with the
    current controls, then for every layer takes ``inner_steps`` gradient-ascent steps of size
    ``inner_lr`` on

    .. math::

        \tilde H_k(u) = \sum_a\Bigl(\langle p^a_{k+1}, f(x^a_k, u)\rangle
        - \tfrac\rho2|x^a_{k+1} - f(x^a_k, u)|^2\Bigr)

    from the current :math:`u_k`, with the states and costates of the sweeps held fixed.  Its
    gradient is :math:`\sum_a\partial_uH(\tilde p^a, x^a_k, u)` with :math:`\tilde p^a =
    p^a_{k+1} + \rho(x^a_{k+1} - f(x^a_k, u))`, the generated adjoint kernel of claim D6 with a
    modified costate; the first inner step is a gradient-descent step on the loss.  Of the two
    penalties of the extended MSA only the state one is used here (the costate penalty
    :math:`\tfrac\rho2|p^a_k - \partial_xH|^2` needs second derivatives of the layer).

    Parameters
    ----------
    %(x0)s
    %(y)s
    %(K0)s
    %(beta0)s
    steps : int, optional
        The number of MSA iterations, >= 0.
    rho : float, optional
        The penalty :math:`\rho \ge 0`.
    inner_steps : int, optional
        Gradient-ascent steps per layer and iteration, >= 1.
    inner_lr : float, optional
        Their step size, > 0.
    %(activation)s
    %(residual)s
    %(progress)s

    Returns
    -------
    %(TrainResult)s

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> from symrb.learning import train_msa
    >>> x0, y, _ = symrb.learning.toy_classification(200, seed=0)
    >>> K, beta = np.zeros((4, 2, 2)), np.zeros((4, 2))
    >>> result = train_msa(x0, y, K, beta, steps=20, inner_lr=0.001)
    >>> bool(result.losses[-1] < result.losses[0])
    True
    """
    steps = v.count(steps, "steps")
    inner = v.count(inner_steps, "inner_steps", 1)
    lr = _positive(inner_lr, "inner_lr")
    rho = v.real_scalar(rho, "rho")
    if rho < 0:
        raise InputError(f"rho must be >= 0, got {rho!r}")
    step_k, adjoint = _kernels(activation, residual)
    KK, bb = _weights(K, beta)
    KK, bb = KK.copy(), bb.copy()
    losses = np.empty(steps + 1)
    x = _states_like(x0, "x0", KK.shape[1])
    sample_axes = tuple(range(x.ndim - 1))
    with progress_bar(steps, "ResNet extended MSA", progress) as bar:
        for i in range(steps + 1):
            states = resnet_forward(x, KK, bb, activation, residual)
            st, _K, _b, y = _check_sweep_inputs(states, KK, bb, targets)
            if i == 0:
                y0 = y
            loss = squared_error(st[-1], y0)
            if not np.isfinite(loss):
                raise InputError(f"loss became non-finite at iteration {i} (inner_lr too large?)")
            losses[i] = loss
            if i == steps:
                break
            p = _sweep(st, KK, bb, y0, activation, residual)[0]
            for k in range(KK.shape[0]):
                Kk, bk = KK[k].copy(), bb[k].copy()
                xk = st[k][..., None]
                for _ in range(inner):
                    f = step_k(Kk, bk[:, None], xk)
                    pt = p[k + 1][..., None] + rho * (st[k + 1][..., None] - f)
                    _pp, dK, db = adjoint(Kk, bk[:, None], xk, pt)
                    Kk = Kk + lr * (np.sum(dK, axis=sample_axes) if sample_axes else dK)
                    bk = bk + lr * (
                        np.sum(db[..., 0], axis=sample_axes) if sample_axes else db[..., 0]
                    )
                KK[k], bb[k] = Kk, bk
            bar.step()
    return TrainResult(K=KK, beta=bb, losses=losses)
