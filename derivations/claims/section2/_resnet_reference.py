"""An independent NumPy ResNet (forward pass, loss, complex-step derivatives) for D6.

Plain NumPy, no generated code and no symrb: the complex step Im Phi(w + i h e)/h gives
derivatives exact to rounding, the reference for symrb's back-propagation.
"""

from __future__ import annotations

import numpy as np


def _reference_forward(x0, Ks, bs, act: str, residual_layer: bool) -> np.ndarray:
    """Independent plain-NumPy forward pass (complex-safe; no generated code): all states."""
    sig = np.tanh if act == "tanh" else (lambda z: 1.0 / (1.0 + np.exp(-z)))
    states = [x0]
    for K, b in zip(Ks, bs, strict=True):
        y = sig(states[-1] @ K.T + b)
        states.append(states[-1] + y if residual_layer else y)
    return np.stack(states)


def _reference_loss(x0, Ks, bs, targets, act: str, residual_layer: bool):
    return 0.5 * np.sum((_reference_forward(x0, Ks, bs, act, residual_layer)[-1] - targets) ** 2)


def complex_step_gradients(x0, Ks, bs, targets, act: str, residual_layer: bool, h: float = 1e-30):
    """dPhi/dK_k, dPhi/dbeta_k by the complex step Im Phi(w + i h e)/h (exact to round-off)."""
    Ks, bs = np.asarray(Ks, dtype=complex), np.asarray(bs, dtype=complex)
    gK, gb = np.zeros(Ks.shape), np.zeros(bs.shape)
    for arr, out in ((Ks, gK), (bs, gb)):
        for idx in np.ndindex(arr.shape):
            old = arr[idx]
            arr[idx] = old + 1j * h
            out[idx] = _reference_loss(x0, Ks, bs, targets, act, residual_layer).imag / h
            arr[idx] = old
    return gK, gb


def complex_step_state_gradients(states, Ks, bs, targets, act: str, residual_layer: bool,
                                 h: float = 1e-30) -> np.ndarray:  # fmt: skip
    """dPhi/dx^a_k for every layer k and sample a, by the complex step on the tail network."""
    out = np.zeros(states.shape)
    for k in range(len(Ks) + 1):
        for idx in np.ndindex(states.shape[1:]):
            xk = states[k].astype(complex)
            xk[idx] += 1j * h
            out[(k, *idx)] = (
                _reference_loss(xk, Ks[k:], bs[k:], targets, act, residual_layer).imag / h
            )
    return out


def random_network(seed: int, N: int = 4, M: int = 5, dim: int = 3, scale: float = 0.8):
    """(x0, K, beta, targets) with M samples of dimension dim and N layers."""
    rng = np.random.default_rng(seed)
    return (
        rng.standard_normal((M, dim)),
        scale * rng.standard_normal((N, dim, dim)),
        scale * rng.standard_normal((N, dim)),
        rng.standard_normal((M, dim)),
    )
