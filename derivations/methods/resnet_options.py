"""M11: the ResNet of Remark 1 as shipped: training, prediction and every activation and layer.

Not a statement of the paper.  Claims D5 and D6 check the layer and adjoint kernels; the coverage
report found that no evidence ran the public trainers ``train`` and ``train_msa``, the classifier
``resnet_predict``, the plain (non-residual) layer, the logistic activation or the sweep reports
(``return_info=True``).  Here every activation and layer runs against a network written in plain
NumPy: its loss differentiated by the complex step (gradients to rounding, independent of any
costate), gradient descent and the extended method of successive approximations written from
their documented definitions, and the condition number of the sweep from its definition.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from itertools import product
from typing import Any

import numpy as np

from derivations.methods.rigid_body_options import _max
from derivations.registry import Level, claim

M11 = claim(
    "M11",
    label="",
    title="The ResNet trainers, the classifier and every layer",
    statement="For either activation (tanh, logistic) and either layer (residual, plain), "
    "`train` is gradient descent on the loss, `train_msa` the extended method of successive "
    "approximations, `resnet_predict` the largest of the last outputs, and the sweeps report "
    "the largest amplification between two layers.",
    expected="holds",
    section="symrb",
    where="`symrb.learning`: `train`, `train_msa`, `resnet_predict`, `costate_sweep` and "
    "`loss_gradients` (options `activation`, `residual`, `return_info`)",
)

_N, _D, _SAMPLES = 3, 3, 4
_STEP = 1e-30  # the complex step


def _sigma(z: Any, activation: str) -> Any:
    return np.tanh(z) if activation == "tanh" else 1 / (1 + np.exp(-z))


def _dsigma(z: np.ndarray, activation: str) -> np.ndarray:
    s = _sigma(z, activation)
    return 1 - s**2 if activation == "tanh" else s * (1 - s)


def _layer(x: Any, K: Any, b: Any, activation: str, residual: bool) -> Any:
    s = _sigma(x @ K.T + b, activation)
    return x + s if residual else s


def _forward(x0: Any, K: Any, b: Any, activation: str, residual: bool) -> list[Any]:
    xs = [x0]
    for k in range(len(K)):
        xs.append(_layer(xs[-1], K[k], b[k], activation, residual))
    return xs


def _loss(x0: Any, y: Any, K: Any, b: Any, act: str, res: bool) -> Any:
    return 0.5 * np.sum((_forward(x0, K, b, act, res)[-1] - y) ** 2)


def _loss_of(x0: Any, y: Any, act: str, res: bool) -> Callable[[np.ndarray], Any]:
    """The loss as a function of the packed weights and biases."""
    return lambda w: _loss(x0, y, *_unpack(w), act, res)


def _complex_grad(f: Callable[[np.ndarray], Any], u: np.ndarray) -> np.ndarray:
    """The gradient of the real-analytic ``f`` at ``u`` by the complex step (to rounding)."""
    g = np.zeros(u.size)
    for i in range(u.size):
        du = np.zeros(u.size, dtype=complex)
        du[i] = _STEP * 1j
        g[i] = f(u.ravel() + du).imag / _STEP
    return g.reshape(u.shape)


def _pack(K: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.concatenate([K.reshape(len(K), -1), b], axis=1)


def _unpack(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    u = u.reshape(_N if u.size == _N * (_D * _D + _D) else 1, _D * _D + _D)
    return u[:, : _D * _D].reshape(-1, _D, _D), u[:, _D * _D :]


def _cases() -> Iterator[tuple[str, bool, np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """(activation, residual, x0, y, K, beta) for both activations and both layers."""
    rng = np.random.default_rng(111)
    for activation, residual in product(("tanh", "logistic"), (True, False)):
        x0, y = rng.standard_normal((2, _SAMPLES, _D))
        K, b = 0.5 * rng.standard_normal((_N, _D, _D)), 0.3 * rng.standard_normal((_N, _D))
        yield activation, residual, x0, y, K, b


@M11.check(Level.FLOAT64, tol=1e-10)
def m11_train_and_predict() -> float:
    """symrb.train (4 steps of lr 0.05) and symrb.learning.resnet_predict (2 classes), for tanh
    and logistic, residual and plain layers (3 layers, 3 states, 4 samples), against gradient
    descent on the loss of a NumPy network differentiated by the complex step and the argmax of
    its last two outputs: max relative difference of the weights, biases and losses (inf when a
    prediction differs)."""
    import symrb

    worst = 0.0
    for act, res, x0, y, K, b in _cases():
        u = _pack(K, b)
        losses = []
        for _ in range(4):
            losses.append(float(_loss(x0, y, *_unpack(u), act, res)))
            u = u - 0.05 * _complex_grad(_loss_of(x0, y, act, res), u)
        losses.append(float(_loss(x0, y, *_unpack(u), act, res)))
        got = symrb.train(x0, y, K, b, steps=4, lr=0.05, activation=act, residual=res)
        Kr, br = _unpack(u)
        for a, w in ((got.K, Kr), (got.beta, br), (got.losses, np.array(losses))):
            worst = _max(worst, float(np.abs(a - w).max() / np.abs(w).max()))
        want = np.argmax(_forward(x0, K, b, act, res)[-1][:, -2:], axis=-1)
        got_classes = symrb.learning.resnet_predict(x0, K, b, 2, activation=act, residual=res)
        if not np.array_equal(got_classes, want):
            return math.inf
    return worst


def _msa_reference(x0: np.ndarray, y: np.ndarray, K: np.ndarray, b: np.ndarray, act: str,
                   res: bool, steps: int, rho: float, inner: int, lr: float) -> tuple:  # fmt: skip
    """The extended MSA as documented: sweeps with the current controls, then per layer
    ``inner`` ascent steps on sum_a <p_(k+1), f(x_k, u)> - rho/2 |x_(k+1) - f(x_k, u)|^2 (states
    and costates fixed; costates p_N = -(x_N - y), p_k = J_k^T p_(k+1)), gradients by the
    complex step."""
    K, b = K.copy(), b.copy()
    losses = []
    for i in range(steps + 1):
        xs = _forward(x0, K, b, act, res)
        losses.append(0.5 * float(np.sum((xs[-1] - y) ** 2)))
        if i == steps:
            break
        ps = [-(xs[-1] - y)]
        for k in reversed(range(_N)):
            sp = _dsigma(xs[k] @ K[k].T + b[k], act) * ps[0]
            ps.insert(0, (ps[0] if res else 0) + sp @ K[k])
        for k in range(_N):

            def h(w: np.ndarray, x: Any = xs[k], x1: Any = xs[k + 1], p1: Any = ps[k + 1]) -> Any:
                Kk, bk = _unpack(w)
                f = _layer(x, Kk[0], bk[0], act, res)
                return np.sum(p1 * f) - rho / 2 * np.sum((x1 - f) ** 2)

            u = _pack(K[k : k + 1], b[k : k + 1])
            for _ in range(inner):
                u = u + lr * _complex_grad(h, u)
            K[k], b[k] = (v[0] for v in _unpack(u))
    return K, b, np.array(losses)


@M11.check(Level.FLOAT64, tol=1e-10)
def m11_train_msa() -> float:
    r"""symrb.learning.train_msa (3 iterations, $\rho = 0.5$, 2 inner steps of 0.05), for tanh and
    logistic, residual and plain layers, against the extended method of successive approximations
    written in NumPy from its documented definition (costates by the adjoint recursion, the ascent
    on the augmented Hamiltonian by the complex step): max relative difference of the weights,
    biases and losses."""
    import symrb

    worst = 0.0
    for act, res, x0, y, K, b in _cases():
        got = symrb.learning.train_msa(x0, y, K, b, steps=3, rho=0.5, inner_steps=2,
                                       inner_lr=0.05, activation=act, residual=res)  # fmt: skip
        Kr, br, lr_ = _msa_reference(x0, y, K, b, act, res, 3, 0.5, 2, 0.05)
        for a, w in ((got.K, Kr), (got.beta, br), (got.losses, lr_)):
            worst = _max(worst, float(np.abs(a - w).max() / np.abs(w).max()))
    return worst


@M11.check(Level.FLOAT64, tol=1e-12)
def m11_sweep_reports() -> float:
    r"""The reports (return_info=True) of symrb.learning.costate_sweep and loss_gradients, for tanh
    and logistic, residual and plain layers: the condition number against its definition $\max_a
    \max_{k \le j} \prod_{i=k}^{j-1} \|J^a_i\|_2$, $J = I + \operatorname{diag}(\sigma'(z)) K$ or
    $\operatorname{diag}(\sigma'(z)) K$, in NumPy; and the costates and gradients returned with it
    against the adjoint recursion and the complex-step gradient of the NumPy loss: max relative
    difference."""
    import symrb

    worst = 0.0
    for act, res, x0, y, K, b in _cases():
        xs = _forward(x0, K, b, act, res)
        norms = np.ones((_N, _SAMPLES))
        for k in range(_N):
            d = _dsigma(xs[k] @ K[k].T + b[k], act)
            for a in range(_SAMPLES):
                J = d[a][:, None] * K[k] + (np.eye(_D) if res else 0)
                norms[k, a] = np.linalg.norm(J, 2)
        kappa = max(1.0, max(float(np.prod(norms[i:j], axis=0).max())
                             for i in range(_N) for j in range(i + 1, _N + 1)))  # fmt: skip
        p, info = symrb.learning.costate_sweep(np.stack(xs), K, b, y, act, res, return_info=True)
        loss, gK, gb, info2 = symrb.learning.loss_gradients(x0, K, b, y, act, res,
                                                            return_info=True)  # fmt: skip
        grad = _complex_grad(_loss_of(x0, y, act, res), _pack(K, b))
        gK_ref, gb_ref = _unpack(grad)
        worst = _max(worst, abs(info.condition / kappa - 1), abs(info2.condition / kappa - 1))
        worst = _max(worst, float(np.abs(p[-1] + (xs[-1] - y)).max()))
        worst = _max(worst, float(np.abs(gK - gK_ref).max() / np.abs(gK_ref).max()))
        worst = _max(worst, float(np.abs(gb - gb_ref).max() / np.abs(gb_ref).max()))
        worst = _max(worst, abs(loss / _loss(x0, y, K, b, act, res) - 1))
    return worst
