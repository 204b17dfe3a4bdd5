r"""Condition estimates shared by the ODE drivers (:func:`symrb.integrate`,
:func:`symrb.double_bracket_flow`): how much a perturbation of the state is amplified by the flow.

For an ODE :math:`\dot y = f(y)` with flow :math:`\varphi_t`, a perturbation :math:`\delta` of the
state at time 0 (rounding, or a local error of the integrator) moves the state at time t by
:math:`D\varphi_t(y_0)\,\delta` to first order.  The relative condition number

.. math:: \kappa(t) = \max_{\delta}\frac{\|D\varphi_t(y_0)\delta\|/\|y(t)\|}{\|\delta\|/\|y_0\|}

is estimated by internal numerical differentiation (Bock): the trajectory and ``k`` copies
started at :math:`y_0 + \tau\|y_0\|v_j` (random unit directions :math:`v_j`, fixed seed) are
integrated as one batch, with one step-size sequence, so that the differences of the copies are
differences of one smooth numerical map (the discretisation errors cancel to first order instead
of adding noise of size ``rtol / tau``).  A maximum over random directions is a lower bound of
the norm, typically within a factor of a few (of :math:`\sqrt{\dim}` at worst for a matrix of
rank one).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ._validate import Array

#: relative size of the perturbation of the initial state (the nonlinearity error is O(tau),
#: the rounding error O(eps / tau): both about 1e-7 relative to kappa)
TAU = 1e-7
#: the number of random directions
DIRECTIONS = 2
#: the seed of the random directions (the estimate is deterministic)
SEED = 20240208
#: the tolerance factor of the reference run of the error estimate
TIGHTER = 100.0


def _rows(a: Array) -> Array:
    return np.sqrt(np.einsum("ij,ij->i", a, a))


def sensitivity(
    solve: Callable[[Array], Array],
    y0: Array,
    directions: int = DIRECTIONS,
    tau: float = TAU,
    seed: int = SEED,
    tangent: Callable[[Array], Array] | None = None,
) -> Array:
    """The relative condition number :math:`\\kappa(t_i)` at each output time.

    ``solve(Y0)`` integrates the batch ``Y0`` of shape ``(b, d)`` (one row per initial state)
    with one step-size sequence and returns the states at the output times, shape ``(K, b, d)``.
    ``y0`` has shape ``(d,)``.  ``tangent`` maps random directions (rows) into the space the
    state lives in (e.g. skew matrices), when the field is only meant for that space.  Returns
    an array of shape ``(K,)``.
    """
    rng = np.random.default_rng(seed)
    V = rng.standard_normal((directions, y0.size))
    if tangent is not None:
        V = tangent(V)
    V /= _rows(V)[:, None]
    scale = float(np.linalg.norm(y0))
    if scale == 0.0:
        scale = 1.0
    step = tau * scale
    Y = solve(np.concatenate([y0[None], y0[None] + step * V]))
    base = Y[:, 0]
    norm = np.maximum(_rows(base), np.finfo(float).tiny)
    growth = np.stack([_rows(Y[:, j + 1] - base) for j in range(directions)], axis=1) / step
    return np.asarray(growth.max(axis=1) * scale / norm)


def relative_difference(y: Array, ref: Array) -> Array:
    """:math:`\\|y_i - r_i\\|/\\|y_i\\|` row by row (rows: the output times)."""
    return np.asarray(_rows(y - ref) / np.maximum(_rows(y), np.finfo(float).tiny))
