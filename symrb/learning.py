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
    "SweepInfo",
    "train",
    "TrainResult",
    "toy_classification",
    "so_network_forward",
    "so_network_gradients",
    "so_network_costates",
    "so_extremal_residual",
    "so_procrustes",
    "so_rotation_task",
    "SOTrainResult",
    "train_so_gradient",
    "train_so_msa",
    "train_so_shooting",
    "DigitsTask",
    "digits_task",
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
            f"targets must have the shape of the final states {a.shape}, got {y.shape}; pass one "
            "target per sample"
        )
    return float(0.5 * np.sum((a - y) ** 2))


@dataclass(frozen=True)
class SweepInfo:
    r"""The condition estimate of a forward and costate sweep (``return_info=True`` of
    :func:`costate_sweep`, :func:`loss_gradients`, :func:`so_network_gradients` and
    :func:`so_network_costates`).

    Attributes
    ----------
    condition : float
        :math:`\kappa = \max_a\max_{k\le j}\prod_{i=k}^{j-1}\|J^a_i\|_2 \ge 1`, the largest
        amplification of a perturbation between two layers of the sweep:
        :math:`J^a_i = \partial f/\partial x(x^a_i, u_i)` is the layer's Jacobian at sample a,
        which carries a change of :math:`x^a_i` forward to :math:`x^a_{i+1}` and (transposed) a
        change of :math:`p^a_{i+1}` back to :math:`p^a_i`.  For the residual layer
        :math:`J = I + \operatorname{diag}(\sigma'(z))K`, for the plain one
        :math:`\operatorname{diag}(\sigma'(z))K`, for the SO(n) network (right multiplication
        by :math:`U_i`) :math:`\|U_i\|_2 = 1` up to rounding, so :math:`\kappa \approx 1` there.
    layers : int
        The number N of layers.

    Notes
    -----
    A sweep is an explicit recursion, so it has no residual to report (recomputing
    :math:`p_k - J_k^Tp_{k+1}` in the same arithmetic gives 0): its accuracy is the forward
    error.  Each layer and adjoint step commits a rounding error of about
    :math:`n\varepsilon` relative to the sizes of its terms; errors of the forward pass reach
    :math:`x_N`, hence :math:`p_N = -(x_N - y)`, amplified by at most :math:`\kappa`, and every
    error of a costate reaches :math:`p_0` amplified by at most :math:`\kappa` again (so
    :math:`\kappa^2` in the worst case; rounding errors are not aligned with the most expanding
    direction, and one factor :math:`\kappa` is what is measured).  Stated and tested
    (tests/test_conditions.py, against a 40-digit mpmath sweep): per sample a,
    :math:`\max_k\|p^a_k - p^a_{k,\mathrm{exact}}\| \le 10(N+1)n\varepsilon\kappa s_a`,
    :math:`s_a = \max_k\|x^a_k\| + \max_k\|p^a_k\|`, and for the gradients
    :math:`\max_k\|\delta K_k\|_F, \|\delta\beta_k\| \le 10(N+1)n\varepsilon\kappa\sum_a s_a
    (1 + \max_k\|x^a_k\|)` (measured worst: 0.03 of the bound over 144 random networks).

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> x0, y = np.array([[0.5, -0.5], [1.0, 0.0]]), np.array([[1.0, 0.0], [0.0, 1.0]])
    >>> K, beta = np.full((3, 2, 2), 0.1), np.zeros((3, 2))
    >>> Phi, dK, dbeta, info = symrb.loss_gradients(x0, K, beta, y, return_info=True)
    >>> print(round(info.condition, 3), info.layers)
    1.728 3
    """

    condition: float
    layers: int


def _window_product(log_norms: Array) -> float:
    """max over samples and windows k <= j of prod_{i=k}^{j-1} ||J_i|| (the empty window: 1),
    from log_norms of shape (N, samples): Kadane's maximum subarray sum on the logarithms."""
    best = np.zeros(log_norms.shape[1:])
    cur = np.zeros(log_norms.shape[1:])
    for row in log_norms:
        cur = np.maximum(0.0, cur + row)
        best = np.maximum(best, cur)
    return float(np.exp(np.max(best, initial=0.0)))


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
    return_info : bool, optional
        Also return a :class:`SweepInfo` with the condition estimate of the sweep (one SVD of
        each layer's Jacobian per sample; not computed by default).

    Returns
    -------
    p : ndarray, shape (N + 1, ..., n)
        The costates.
    info : SweepInfo
        Only with ``return_info=True``.

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
    return_info : bool, optional
        Also return a :class:`SweepInfo` with the condition estimate of the sweeps (accuracy
        stated there; not computed by default).

    Returns
    -------
    Phi : float
        The loss :func:`squared_error`.
    dK : ndarray, shape (N, n, n)
        :math:`\partial\Phi/\partial K`.
    dbeta : ndarray, shape (N, n)
        :math:`\partial\Phi/\partial\beta`.
    info : SweepInfo
        Only with ``return_info=True``.

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
        raise InputError(f"num must be a positive integer, got {num!r}; pass an int >= 1")
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
    return_info : bool, optional
        Also return a :class:`SweepInfo` (the condition estimate of the sweeps, about 1 for
        orthogonal controls; not computed by default).

    Returns
    -------
    loss : float
        :math:`L(U)`.
    G : ndarray, shape (N, n, n)
        The skew gradients :math:`G_k`.
    info : SweepInfo
        Only with ``return_info=True``.  Accuracy stated and tested (tests/test_conditions.py,
        against a 40-digit mpmath sweep): :math:`\max_k\|G_k - G_{k,\mathrm{exact}}\|_F \le
        10(N+1)n\varepsilon\kappa(M\sqrt n\,(\sqrt n + \max_{k,a}\|P^a_k\|_F) +
        \alpha\max_i\lambda_i)`.

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


def so_network_costates(
    Q0: ArrayLike, U: ArrayLike, targets: ArrayLike, *, return_info: bool = False
) -> tuple[Array, Array] | tuple[Array, Array, SweepInfo]:
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
    return_info : bool, optional
        Also return a :class:`SweepInfo` (not computed by default).

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


# ---------------------------------------------------------------------------------------------
# training the SO(n) network three ways


@dataclass(frozen=True)
class SOTrainResult:
    r"""Outcome of :func:`train_so_gradient`, :func:`train_so_msa` and :func:`train_so_shooting`.

    Attributes
    ----------
    U : ndarray, shape (N, n, n)
        The final controls, in SO(n).
    losses : ndarray, shape (iterations + 1,)
        The loss before each iteration and at the end.
    residuals : ndarray, shape (iterations + 1,)
        The first-order optimality residual :math:`\max_k\|G_k\|_F` (the Riemannian gradient,
        :func:`so_network_gradients`) at the same points.
    iterations : int
        The number of iterations done.
    residual : float
        The final first-order residual, ``residuals[-1]``.
    converged : bool
        Whether the method's stopping test was met (shooting: the root finder's test, or the
        shooting residual at the rounding floor of the sweep, :math:`10(N+1)n\varepsilon
        (1 + \|x\|)`).
    method : str
        ``"gradient"``, ``"msa"`` or ``"shooting"``.
    M0 : ndarray, shape (n, n), or None
        :func:`train_so_shooting`: the momentum :math:`M_0` found.  None for the other methods.
    shooting_residual : float or None
        :func:`train_so_shooting`: :math:`\|F(M_0)\|_2`, the residual of the shooting equation.
        None for the other methods.
    condition : float or None
        :func:`train_so_shooting` with ``condition=True``: :math:`1/\sigma_{\min}(\partial
        F/\partial M_0)`, which bounds :math:`\|M_0 - M_0^*\|` by :math:`\kappa` times
        ``shooting_residual`` to first order.  None otherwise.

    Examples
    --------
    >>> import numpy as np
    >>> from symrb.learning import so_rotation_task, train_so_gradient
    >>> Q0, T = so_rotation_task(3, samples=8, seed=0)
    >>> res = train_so_gradient(Q0, T, np.tile(np.eye(3), (2, 1, 1)), [1.0, 2.0, 3.0], alpha=0.1,
    ...                         steps=20, lr=0.05)
    >>> res.losses.shape, res.iterations, res.method
    ((21,), 20, 'gradient')
    """

    U: Array
    losses: Array
    residuals: Array
    iterations: int
    residual: float
    converged: bool
    method: str
    M0: Array | None = None
    shooting_residual: float | None = None
    condition: float | None = None


def _grad_norm(G: Array) -> float:
    return float(np.max(np.linalg.norm(G, axis=(-2, -1))))


def _retract(U: Array, step: Array, retraction: str) -> Array:
    """U_k R(step_k) with R the Cayley map (I - A/2)^-1 (I + A/2) or the exponential."""
    if retraction == "exp":
        from scipy.linalg import expm

        return np.asarray(U @ expm(step))
    eye = np.eye(U.shape[-1])
    return np.asarray(U @ np.linalg.solve(eye - 0.5 * step, eye + 0.5 * step))


def _so_start(U0: ArrayLike, Q0: ArrayLike, targets: ArrayLike, lam: ArrayLike, alpha: object):
    UU = _so_controls(U0).copy()
    return UU, _SOProblem(Q0, targets, lam, alpha, UU.shape[-1])


def _positive(x: object, name: str) -> float:
    val = v.real_scalar(x, name)
    if not val > 0:
        raise InputError(f"{name} must be > 0, got {x!r}")
    return val


def train_so_gradient(
    Q0: ArrayLike,
    targets: ArrayLike,
    U0: ArrayLike,
    lam: ArrayLike,
    alpha: float = 0.0,
    steps: int = 500,
    lr: float = 0.1,
    retraction: str = "cayley",
    line_search: bool = False,
    momentum: float = 0.0,
    tol: float = 1e-10,
    progress: bool = False,
) -> SOTrainResult:
    r"""Riemannian gradient descent on :math:`SO(n)^N` for the loss of :func:`so_network_gradients`.

    Each step runs the forward and the costate sweep, then :math:`U_k \leftarrow U_k R(-t\,d_k)`
    with :math:`R` the Cayley map :math:`(I - A/2)^{-1}(I + A/2)` or the exponential, the
    direction :math:`d_k = G_k` (or with heavy-ball momentum :math:`d \leftarrow G + \mu d`, in
    the body frame), and :math:`t` = ``lr`` or, with ``line_search``, the Armijo step
    (backtracking from twice the last accepted step until the loss drops by at least
    :math:`10^{-4}\,t\,\langle G, d\rangle`).  Stops when :math:`\max_k\|G_k\|_F \le` ``tol``.

    Parameters
    ----------
    Q0 : array_like, shape (M, n, n)
        The samples, in SO(n).
    targets : array_like, shape (M, n, n)
        The targets :math:`T^a`.
    U0 : array_like, shape (N, n, n)
        The initial controls, in SO(n) (copied, never modified).
    lam : array_like, shape (n,)
        The diagonal of :math:`\Lambda`, positive.
    alpha : float, optional
        The weight of the running cost, >= 0.
    steps : int, optional
        The most iterations.
    lr : float, optional
        The step (the first trial step with ``line_search``), > 0.
    retraction : {"cayley", "exp"}, optional
        The retraction.
    line_search : bool, optional
        Armijo backtracking instead of a fixed step.
    momentum : float, optional
        The heavy-ball coefficient :math:`0 \le \mu < 1`.
    tol : float, optional
        The stopping tolerance on the first-order residual.
    progress : bool, optional
        Show a progress bar (tqdm).

    Returns
    -------
    SOTrainResult
        The final controls, the losses and residuals before each step, the iterations.

    Raises
    ------
    InputError
        Bad arguments, or a loss that became non-finite.

    Examples
    --------
    >>> import numpy as np
    >>> from symrb.learning import so_rotation_task, train_so_gradient
    >>> Q0, T = so_rotation_task(3, samples=8, seed=0)
    >>> U0 = np.tile(np.eye(3), (3, 1, 1))
    >>> res = train_so_gradient(Q0, T, U0, [1.0, 2.0, 3.0], alpha=1.0, steps=500,
    ...                         line_search=True, tol=1e-9)
    >>> bool(res.converged), bool(res.losses[-1] < res.losses[0])
    (True, True)
    """
    U, prob = _so_start(U0, Q0, targets, lam, alpha)
    steps = v.count(steps, "steps")
    lr = _positive(lr, "lr")
    tol = _positive(tol, "tol")
    mu = v.real_scalar(momentum, "momentum")
    if not 0 <= mu < 1:
        raise InputError(f"momentum must be in [0, 1), got {momentum!r}")
    if retraction not in ("cayley", "exp"):
        raise InputError(f"retraction must be 'cayley' or 'exp', got {retraction!r}")
    if not isinstance(line_search, bool | np.bool_):
        raise InputError(f"line_search must be True or False, got {line_search!r}")
    losses, residuals = [], []
    d = np.zeros_like(U)
    t = lr
    converged = False
    it = 0
    with progress_bar(steps, "SO(n) gradient descent", progress) as bar:
        loss, G = prob.gradients(U)
        while True:
            if not np.isfinite(loss):
                raise InputError(f"loss became non-finite at iteration {it} (lr = {lr} too large?)")
            losses.append(loss)
            residuals.append(_grad_norm(G))
            if residuals[-1] <= tol:
                converged = True
                break
            if it == steps:
                break
            d = G + mu * d
            slope = float(np.sum(G * d))
            if slope <= 0:  # momentum turned uphill: restart it
                d, slope = G.copy(), float(np.sum(G * G))
            if line_search:
                t = min(2 * t, 1e3 * lr)
                while True:
                    trial = _retract(U, -t * d, retraction)
                    new = prob.loss(trial)
                    if new <= loss - 1e-4 * t * slope or t < 1e-14:
                        break
                    t *= 0.5
                U = trial
            else:
                U = _retract(U, -lr * d, retraction)
            loss, G = prob.gradients(U)
            it += 1
            bar.step()
    return SOTrainResult(
        U=U,
        losses=np.array(losses),
        residuals=np.array(residuals),
        iterations=it,
        residual=residuals[-1],
        converged=converged,
        method="gradient",
    )


def so_procrustes(A: ArrayLike) -> Array:
    r"""The rotation maximising :math:`\operatorname{tr}(AU)` over :math:`U \in SO(n)`.

    With the singular value decomposition :math:`A = XSY^T` (``scipy.linalg.svd``), the maximiser
    is :math:`U = Y D X^T`, :math:`D = \operatorname{diag}(1, \dots, 1, \det(YX^T))` (the special
    orthogonal Procrustes problem; the determinant fix flips the direction of the smallest
    singular value when :math:`YX^T` is a reflection).  Unique when the smallest singular value
    is simple and, for :math:`\det(YX^T) = -1`, positive.

    Parameters
    ----------
    A : array_like, shape (..., n, n)
        The matrices.

    Returns
    -------
    U : ndarray, shape (..., n, n)
        The maximisers, in SO(n).

    Examples
    --------
    >>> import numpy as np
    >>> from symrb.learning import so_procrustes
    >>> A = np.diag([3.0, -2.0, -1.0])  # the best rotation turns the last two axes
    >>> print(so_procrustes(A).round(12) + 0.0)
    [[ 1.  0.  0.]
     [ 0. -1.  0.]
     [ 0.  0. -1.]]
    """
    from scipy.linalg import svd

    a = v.square(A, "A")
    flat = a.reshape(-1, a.shape[-1], a.shape[-1])
    out = np.empty_like(flat)
    for i, Ai in enumerate(flat):
        X, _s, Yt = svd(Ai)
        D = np.ones(a.shape[-1])
        D[-1] = np.sign(np.linalg.det(Yt.T @ X.T))
        out[i] = (Yt.T * D) @ X.T
    return out.reshape(a.shape)


def train_so_msa(
    Q0: ArrayLike,
    targets: ArrayLike,
    U0: ArrayLike,
    lam: ArrayLike,
    alpha: float = 0.0,
    steps: int = 200,
    rho: float = 2.0,
    tol: float = 1e-10,
    progress: bool = False,
) -> SOTrainResult:
    r"""The extended method of successive approximations (Li, Chen, Tai and E 2018) on SO(n).

    Each iteration runs the forward and the costate sweep with the current controls, then sets
    every :math:`U_k` to the maximiser over :math:`SO(n)` of the augmented Hamiltonian

    .. math::

        \tilde H_k(U) = \sum_a\Bigl(\langle P^a_{k+1}, Q^a_kU\rangle
        - \tfrac\rho2\|Q^a_{k+1} - Q^a_kU\|_F^2 - \tfrac\rho2\|P^a_k - P^a_{k+1}U^T\|_F^2\Bigr)
        - \alpha\operatorname{tr}(\Lambda(I - U)),

    which for orthogonal :math:`Q^a_k` and :math:`U` is :math:`\operatorname{tr}(A_kU)` plus a
    constant with

    .. math::

        A_k = \sum_a\bigl((P^a_{k+1})^TQ^a_k + \rho((Q^a_{k+1})^TQ^a_k + (P^a_{k+1})^TP^a_k)
        \bigr) + \alpha\Lambda,

    so the layer-wise maximisation is the special orthogonal Procrustes problem, solved exactly
    by :func:`so_procrustes`.  :math:`\rho = 0` is the basic MSA (which may oscillate); the
    :math:`\rho` terms keep the step close to the current controls.  Stops when
    :math:`\max_k\|G_k\|_F \le` ``tol``.

    Parameters
    ----------
    Q0 : array_like, shape (M, n, n)
        The samples, in SO(n).
    targets : array_like, shape (M, n, n)
        The targets.
    U0 : array_like, shape (N, n, n)
        The initial controls, in SO(n).
    lam : array_like, shape (n,)
        The diagonal of :math:`\Lambda`, positive.
    alpha : float, optional
        The weight of the running cost, >= 0.
    steps : int, optional
        The most iterations.
    rho : float, optional
        The penalty :math:`\rho \ge 0` of the extended MSA.
    tol : float, optional
        The stopping tolerance on the first-order residual.
    progress : bool, optional
        Show a progress bar (tqdm).

    Returns
    -------
    SOTrainResult
        The final controls, the losses and residuals before each iteration, the iterations.

    Examples
    --------
    >>> import numpy as np
    >>> from symrb.learning import so_rotation_task, train_so_msa
    >>> Q0, T = so_rotation_task(3, samples=8, seed=0)
    >>> res = train_so_msa(Q0, T, np.tile(np.eye(3), (3, 1, 1)), [1.0, 2.0, 3.0], alpha=1.0,
    ...                    steps=500, tol=1e-9)
    >>> bool(res.converged), bool(res.losses[-1] < res.losses[0])
    (True, True)
    """
    U, prob = _so_start(U0, Q0, targets, lam, alpha)
    steps = v.count(steps, "steps")
    rho = v.real_scalar(rho, "rho")
    if rho < 0:
        raise InputError(f"rho must be >= 0, got {rho!r}")
    tol = _positive(tol, "tol")
    losses, residuals = [], []
    converged = False
    it = 0
    aL = prob.alpha * np.diag(prob.lam)
    with progress_bar(steps, "SO(n) extended MSA", progress) as bar:
        while True:
            Qs = _so_forward(prob.Qs0, U)
            G, Ps = _so_backward(Qs, U, prob.lam, prob.Ts, prob.alpha, costates=True)
            assert Ps is not None
            loss = _so_loss(Qs[-1], prob.Ts, U, prob.lam, prob.alpha)
            if not np.isfinite(loss):
                raise InputError(f"loss became non-finite at iteration {it}")
            losses.append(loss)
            residuals.append(_grad_norm(G))
            if residuals[-1] <= tol:
                converged = True
                break
            if it == steps:
                break
            A = np.empty_like(U)
            for k in range(U.shape[0]):
                A[k] = Ps[k + 1].T @ Qs[k] + aL
                if rho:
                    A[k] += rho * (Qs[k + 1].T @ Qs[k] + Ps[k + 1].T @ Ps[k])
            U = so_procrustes(A)
            it += 1
            bar.step()
    return SOTrainResult(
        U=U,
        losses=np.array(losses),
        residuals=np.array(residuals),
        iterations=it,
        residual=residuals[-1],
        converged=converged,
        method="msa",
    )


def _skew_from_upper(x: Array, n: int) -> Array:
    iu = np.triu_indices(n, 1)
    S = np.zeros((n, n))
    S[iu] = x
    return S - S.T


def train_so_shooting(
    Q0: ArrayLike,
    targets: ArrayLike,
    lam: ArrayLike,
    alpha: float,
    layers: int,
    M0: ArrayLike | None = None,
    tol: float = 1e-12,
    maxfev: int = 400,
    progress: bool = False,
    condition: bool = False,
) -> SOTrainResult:
    r"""The extremal equations of claim D9 as a two-point boundary value problem, by shooting.

    The extremals of the loss of :func:`so_network_gradients` (:math:`\alpha > 0`) satisfy the
    discrete system

    .. math::

        Q^a_{k+1} = Q^a_kU_k,\quad P^a_{k+1} = P^a_kU_k,\quad
        \alpha J_D(U_k) = M_k := \sum_a\bigl((Q^a_k)^TP^a_k - (P^a_k)^TQ^a_k\bigr),

    with :math:`Q^a_0` given and :math:`P^a_N = -(Q^a_N - T^a)`.  The momentum is transported,
    :math:`M_{k+1} = U_k^TM_kU_k` (claim D8), so the controls are a discrete rigid body
    (Moser-Veselov) trajectory of inertia :math:`\alpha\Lambda` and are fixed by the single
    unknown :math:`M_0 \in \mathfrak{so}(n)`: :math:`U_k` solves :math:`J_D(U_k) = M_k/\alpha`
    on the branch through the identity (:func:`symrb.solve_moser_veselov`).  Shooting solves
    :math:`F(M_0) = \sum_a((Q^a_0)^TP^a_0 - (P^a_0)^TQ^a_0) - M_0 = 0` (the costates from the
    backward sweep of the controls of :math:`M_0`) with ``scipy.optimize.root`` (Powell's hybrid
    method) from ``M0`` (default 0, all :math:`U_k = I`).

    Parameters
    ----------
    Q0 : array_like, shape (M, n, n)
        The samples, in SO(n).
    targets : array_like, shape (M, n, n)
        The targets.
    lam : array_like, shape (n,)
        The diagonal of :math:`\Lambda`, positive.
    alpha : float
        The weight of the running cost, > 0.
    layers : int
        The number of layers :math:`N \ge 1`.
    M0 : array_like, shape (n, n), optional
        The initial guess of :math:`M_0` (skew).
    tol : float, optional
        The relative tolerance of the root finder on :math:`M_0` (``xtol``).
    maxfev : int, optional
        The most evaluations of :math:`F`.
    progress : bool, optional
        Show a progress bar (tqdm) over the evaluations.
    condition : bool, optional
        Also compute the condition number of the shooting equation at the solution
        (``SOTrainResult.condition``: :math:`\kappa = 1/\sigma_{\min}(\partial F/\partial
        M_0)` by central differences, :math:`n(n-1)` more evaluations of F).  Not computed by
        default.

    Returns
    -------
    SOTrainResult
        ``losses`` and ``residuals`` at every evaluation of :math:`F`; ``iterations`` is the
        number of evaluations; ``M0`` the returned :math:`M_0` and ``shooting_residual``
        :math:`\|F(M_0)\|_2` (on the strict upper triangle).

    Notes
    -----
    The equation solved is :math:`F(M_0) = 0` on :math:`\mathfrak{so}(n)` (coordinates: the
    strict upper triangle).  To first order :math:`M_0 - M_0^* = (\partial F/\partial M_0)^{-1}
    F(M_0)`, so :math:`\|M_0 - M_0^*\| \le \kappa\|F(M_0)\|` with
    :math:`\kappa = 1/\sigma_{\min}(\partial F/\partial M_0)` (dimensionless: F and
    :math:`M_0` are both momenta), and rounding in evaluating F (about
    :math:`(N+1)Mn\varepsilon` times the size of its terms) bounds how small
    ``shooting_residual`` can get.  Stated and tested (tests/test_conditions.py, against a
    solve from another starting guess): two solutions differ by at most
    :math:`10\kappa(\|F_1\| + \|F_2\| + 2(N+1)Mn\varepsilon\sqrt n\,(\sqrt n +
    \max_a\|P^a_0\|_F))`.

    Raises
    ------
    InputError
        Bad arguments.

    Examples
    --------
    >>> import numpy as np
    >>> from symrb.learning import so_rotation_task, train_so_shooting
    >>> Q0, T = so_rotation_task(3, samples=8, seed=0)
    >>> res = train_so_shooting(Q0, T, [1.0, 2.0, 3.0], alpha=1.0, layers=3)
    >>> bool(res.converged), bool(res.residual < 1e-9)
    (True, True)
    >>> res = train_so_shooting(Q0, T, [1.0, 2.0, 3.0], alpha=1.0, layers=3, condition=True)
    >>> bool(res.shooting_residual < 1e-13), round(res.condition, 3)
    (True, 0.095)
    """
    from scipy.optimize import root

    from .errors import OutOfDomainError
    from .solvers import solve_moser_veselov

    N = v.count(layers, "layers", 1)
    Q = v.orthogonal(Q0, "Q0")
    if Q.ndim != 3:
        raise InputError(f"Q0 must have shape (M, n, n), got {Q.shape}")
    n = Q.shape[-1]
    prob = _SOProblem(Q, targets, lam, alpha, n)
    if not prob.alpha > 0:
        raise InputError(f"alpha must be > 0 for shooting (J_D is inverted), got {alpha!r}")
    tol = _positive(tol, "tol")
    maxfev = v.count(maxfev, "maxfev", 1)
    iu = np.triu_indices(n, 1)
    x0 = np.zeros(len(iu[0]))
    if M0 is not None:
        x0 = v.skew(M0, "M0", n)[iu].copy()
    lam_a = prob.alpha * prob.lam
    losses: list[float] = []
    residuals: list[float] = []
    last: dict[str, Array] = {}

    def controls(x: Array) -> Array:
        M = _skew_from_upper(x, n)
        U = np.empty((N, n, n))
        guess: Array | None = None
        for k in range(N):
            U[k] = np.asarray(solve_moser_veselov(M, lam_a, U0=guess))
            guess = U[k]
            M = U[k].T @ M @ U[k]
        return U

    if not isinstance(condition, bool | np.bool_):
        raise InputError(f"condition must be True or False, got {condition!r}; pass a bool")

    def shoot(x: Array) -> tuple[Array, Array, Array] | None:
        """(F(x), U, G), or None beyond the fold of J_D."""
        try:
            U = controls(x)
        except OutOfDomainError:
            return None
        Qs = _so_forward(prob.Qs0, U)
        G, Ps = _so_backward(Qs, U, prob.lam, prob.Ts, prob.alpha, costates=True)
        assert Ps is not None
        last["Qs"] = Qs
        R = _gsr.symmetric_momentum(Qs[0], Ps[0])
        return np.asarray(R[iu] - x), U, G

    with progress_bar(maxfev, "SO(n) shooting", progress) as bar:

        def F(x: Array) -> Array:
            out = shoot(x)
            if out is None:  # beyond the fold of J_D: push the root finder back
                return -10.0 * (1.0 + np.abs(x)) * np.sign(x + (x == 0))
            Fx, U, G = out
            losses.append(_so_loss(last["Qs"][-1], prob.Ts, U, prob.lam, prob.alpha))
            residuals.append(_grad_norm(G))
            last["U"] = U
            last["F"] = Fx
            bar.step()
            return Fx

        sol = root(F, x0, method="hybr", options={"xtol": tol, "maxfev": maxfev})
        F(sol.x)  # the reported controls are those of the returned M_0
    kappa = _shooting_condition(shoot, sol.x) if condition else None
    shooting_residual = float(np.linalg.norm(last["F"])) if "F" in last else float("inf")
    # hybr reports "not making good progress" once F is at rounding level and xtol cannot be
    # met (the thorough profile found converged = False with |F| = 5.6e-16): F at the rounding
    # floor of the sweep, 10 (N + 1) n eps (1 + |x|), counts as converged
    layers_n = 0 if last.get("U") is None else int(np.shape(last["U"])[0])
    floor = (
        10.0
        * (layers_n + 1)
        * n
        * float(np.finfo(float).eps)
        * (1.0 + float(np.linalg.norm(sol.x)))
    )
    converged = bool(sol.success) or shooting_residual <= floor
    return SOTrainResult(
        U=last["U"],
        losses=np.array(losses),
        residuals=np.array(residuals),
        iterations=len(losses) - 1,
        residual=residuals[-1],
        converged=converged,
        method="shooting",
        M0=_skew_from_upper(sol.x, n),
        shooting_residual=shooting_residual,
        condition=kappa,
    )


def _shooting_condition(
    shoot: Callable[[Array], tuple[Array, Array, Array] | None], x: Array
) -> float:
    """1 / the smallest singular value of dF/dm at m = x (central differences, relative step
    1e-6; the nonlinearity error is O(1e-12) relative, the rounding error O(eps / 1e-6)); NaN
    when a difference crosses the fold of J_D."""
    d = x.size
    step = 1e-6 * max(1.0, float(np.linalg.norm(x)))
    J = np.empty((d, d))
    for j in range(d):
        e = np.zeros(d)
        e[j] = step
        plus, minus = shoot(x + e), shoot(x - e)
        if plus is None or minus is None:
            return float("nan")
        J[:, j] = (plus[0] - minus[0]) / (2 * step)
    smallest = float(np.linalg.svd(J, compute_uv=False)[-1])
    return 1.0 / smallest if smallest > 0 else float("inf")


def so_rotation_task(
    n: int = 3,
    samples: int = 32,
    angle: float = 0.6,
    noise: float = 0.05,
    seed: int | np.random.Generator | None = 0,
) -> tuple[Array, Array]:
    r"""A task for the SO(n) network: learn one rotation from noisy examples.

    Samples :math:`Q^a_0` Haar-random in SO(n); targets :math:`T^a = Q^a_0 R E^a` with one fixed
    rotation :math:`R = e^{\theta\hat\omega}` (angle ``angle``, a random axis-like skew unit
    :math:`\hat\omega`) and small random rotations :math:`E^a = e^{\epsilon\eta^a}` (noise).
    For small angles and a positive running cost the loss has one minimiser near the controls
    whose product is :math:`R`.

    Parameters
    ----------
    n : int, optional
        The matrix size, >= 2.
    samples : int, optional
        The number M of samples, >= 1.
    angle : float, optional
        The rotation angle :math:`\theta` of :math:`R`.
    noise : float, optional
        The size :math:`\epsilon \ge 0` of the perturbations.
    seed : int, numpy.random.Generator or None, optional
        The random source.

    Returns
    -------
    Q0 : ndarray, shape (samples, n, n)
        The samples.
    targets : ndarray, shape (samples, n, n)
        The targets, in SO(n).

    Examples
    --------
    >>> from symrb.learning import so_rotation_task
    >>> Q0, T = so_rotation_task(4, samples=10, seed=1)
    >>> Q0.shape, T.shape
    ((10, 4, 4), (10, 4, 4))
    """
    from scipy.linalg import expm

    from .algebra import as_generator, random_SO

    n = v.count(n, "n", 2)
    samples = v.count(samples, "samples", 1)
    angle = v.real_scalar(angle, "angle")
    noise = v.real_scalar(noise, "noise")
    if noise < 0:
        raise InputError(f"noise must be >= 0, got {noise!r}")
    rng = as_generator(seed)
    Q0 = random_SO(n, (samples,), seed=rng)
    w = rng.standard_normal((n, n))
    w = w - w.T
    R = expm(angle * w / np.linalg.norm(w, 2))
    eta = rng.standard_normal((samples, n, n))
    E = expm(noise * (eta - np.swapaxes(eta, 1, 2)) / 2)
    return Q0, Q0 @ R @ E


# ---------------------------------------------------------------------------------------------
# the residual network of Remark 1 on real data: scikit-learn's handwritten digits


@dataclass(frozen=True)
class DigitsTask:
    """The digits classification task of :func:`digits_task`.

    Attributes
    ----------
    x_train, x_test : ndarray, shape (M, n)
        Initial states: ``features`` principal components, then ``classes`` zeros.
    y_train : ndarray, shape (M, n)
        Targets: the same components, then the one-hot code of the class.
    labels_train, labels_test : ndarray of int, shape (M,)
        The digits 0-9.
    classes : int
        The number of classes (the last ``classes`` entries of a state are read out).

    Examples
    --------
    >>> from symrb.learning import digits_task
    >>> task = digits_task(features=8)  # doctest: +SKIP
    >>> task.x_train.shape[1], task.classes  # doctest: +SKIP
    (18, 10)
    """

    x_train: Array
    y_train: Array
    labels_train: NDArray[np.int64]
    x_test: Array
    labels_test: NDArray[np.int64]
    classes: int


def digits_task(
    features: int = 16, test_fraction: float = 0.3, seed: int | np.random.Generator | None = 0
) -> DigitsTask:
    r"""scikit-learn's handwritten digits (1797 8x8 images shipped with the package, no download)
    as a task for the residual network.

    The pixels are centred and projected on their first ``features`` principal components (of
    the training set, scaled to unit variance on average); a state is those components followed
    by ten zeros, its target the same components followed by the one-hot code of the digit, so
    the network has to write the class into the last ten entries while keeping the rest.  The
    predicted class is the largest of the last ten entries of :math:`x_N`
    (:func:`resnet_predict`).

    Parameters
    ----------
    features : int, optional
        The number of principal components, 1 to 64.
    test_fraction : float, optional
        The share of the images held out for testing, in (0, 1).
    seed : int, numpy.random.Generator or None, optional
        The random source of the split.

    Returns
    -------
    DigitsTask
        The training and test states, the training targets and the labels.

    Raises
    ------
    ImportError
        scikit-learn is not installed (``pip install scikit-learn``).

    Examples
    --------
    >>> from symrb.learning import digits_task
    >>> task = digits_task(features=8)  # doctest: +SKIP
    >>> task.x_train.shape, task.x_test.shape  # doctest: +SKIP
    ((1258, 18), (539, 18))
    """
    try:
        from sklearn.datasets import load_digits
    except ImportError:  # pragma: no cover - depends on the environment
        raise ImportError(
            "digits_task needs the optional package scikit-learn: pip install scikit-learn"
        ) from None
    from .algebra import as_generator

    features = v.count(features, "features", 1)
    if features > 64:
        raise InputError(f"features must be at most 64 (8x8 pixels), got {features}")
    frac = v.real_scalar(test_fraction, "test_fraction")
    if not 0 < frac < 1:
        raise InputError(f"test_fraction must be in (0, 1), got {test_fraction!r}")
    data = load_digits()
    X, labels = np.asarray(data.data, dtype=float), np.asarray(data.target, dtype=np.int64)
    order = as_generator(seed).permutation(len(labels))
    n_test = int(round(frac * len(labels)))
    test, train = order[:n_test], order[n_test:]
    mean = X[train].mean(axis=0)
    _u, s, vt = np.linalg.svd(X[train] - mean, full_matrices=False)
    scale = float(np.sqrt(np.mean(s[:features] ** 2) / len(train)))
    classes = 10

    def states(idx: NDArray[np.int64]) -> Array:
        comps = (X[idx] - mean) @ vt[:features].T / scale
        return np.concatenate([comps, np.zeros((len(idx), classes))], axis=1)

    x_train = states(train)
    y_train = x_train.copy()
    y_train[np.arange(len(train)), features + labels[train]] = 1.0
    return DigitsTask(
        x_train=x_train,
        y_train=y_train,
        labels_train=labels[train],
        x_test=states(test),
        labels_test=labels[test],
        classes=classes,
    )


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
    x0 : array_like, shape (..., n)
        Initial states.
    K : array_like, shape (N, n, n)
        Layer weights.
    beta : array_like, shape (N, n)
        Layer biases.
    classes : int
        The number of classes, 1 to n.
    activation : {"tanh", "logistic"}, optional
        The activation.
    residual : bool, optional
        Residual or plain layers.

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
    x0 : array_like, shape (..., n)
        Initial states, one per sample.
    targets : array_like, shape (..., n)
        The targets :math:`y^a`.
    K : array_like, shape (N, n, n)
        Initial layer weights (copied, never modified).
    beta : array_like, shape (N, n)
        Initial layer biases.
    steps : int, optional
        The number of MSA iterations, >= 0.
    rho : float, optional
        The penalty :math:`\rho \ge 0`.
    inner_steps : int, optional
        Gradient-ascent steps per layer and iteration, >= 1.
    inner_lr : float, optional
        Their step size, > 0.
    activation : {"tanh", "logistic"}, optional
        The activation.
    residual : bool, optional
        Residual or plain layers.
    progress : bool, optional
        Show a progress bar (tqdm).

    Returns
    -------
    TrainResult
        The final weights and the losses (``steps + 1`` entries).

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> from symrb.learning import train_msa
    >>> x0, y, _ = symrb.toy_classification(200, seed=0)
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
