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
