r"""Symmetric compositions: the coefficient tables and the composition of a base map.

A symmetric one-step map :math:`\Phi_h` of order 2 (:math:`\Phi_{-h} = \Phi_h^{-1}`, e.g. the
discrete rigid body of Section 2) composed as

.. math::

    \Psi_h = \Phi_{\gamma_s h}\circ\cdots\circ\Phi_{\gamma_2 h}\circ\Phi_{\gamma_1 h},
    \qquad \gamma_{s+1-i} = \gamma_i,

is again symmetric and, for the coefficients of :func:`composition_coefficients`, of order
4, 6 or 8 (Hairer, Lubich and Wanner, *Geometric Numerical Integration*, 2nd ed., Springer 2006,
Section V.3.2).  The rigid body flows built on it are in :mod:`symrb.compose`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

import numpy as np
from numpy.typing import ArrayLike

from . import _validate as v
from ._validate import Array
from .errors import InputError

__all__ = ["composition_coefficients", "compose_steps"]

# ---------------------------------------------------------------------------------------------
# composition coefficients (half of each symmetric sequence, the middle one last)

# Hairer, Lubich, Wanner (2006), Section V.3.2: p6 s7 (Yoshida 1990, solution A), p6 s9 and
# p8 s17 (Kahan and Li 1997, s9odr6a and s17odr8a), p8 s15 (McLachlan 1995).
_HALVES: dict[tuple[int, str], tuple[float, ...]] = {
    (6, "yoshida"): (
        0.78451361047755726381949763,
        0.23557321335935813368479318,
        -1.17767998417887100694641568,
        1.31518632068391121888424973,
    ),
    (6, "kahan_li"): (
        0.39216144400731413927925056,
        0.33259913678935943859974864,
        -0.70624617255763935980996482,
        0.08221359629355080023149045,
        0.79854399093482996339895035,
    ),
    (8, "mclachlan"): (
        0.74167036435061295344822780,
        -0.40910082580003159399730010,
        0.19075471029623837995387626,
        -0.57386247111608226665638773,
        0.29906418130365592384446354,
        0.33462491824529818378495798,
        0.31529309239676659663205666,
        -0.79688793935291635401978884,
    ),
    (8, "kahan_li"): (
        0.13020248308889008087881763,
        0.56116298177510838456196441,
        -0.38947496264484728640807860,
        0.15884190655515560089621075,
        -0.39590389413323757733623154,
        0.18453964097831570709183254,
        0.25837438768632204729397911,
        0.29501172360931029887096624,
        -0.60550853383003451169892108,
    ),
}

_KINDS: dict[int, tuple[str, ...]] = {
    2: ("triple_jump",),
    4: ("triple_jump", "suzuki"),
    6: ("triple_jump", "yoshida", "kahan_li"),
    8: ("triple_jump", "mclachlan", "kahan_li"),
}
_DEFAULT_KIND = {2: "triple_jump", 4: "suzuki", 6: "kahan_li", 8: "kahan_li"}


def _triple_jump(order: int) -> Array:
    g = np.ones(1)
    for p in range(2, order, 2):  # raise the order from p to p + 2
        r = 2.0 ** (1.0 / (p + 1))
        g1 = 1.0 / (2.0 - r)
        g = np.concatenate([g1 * g, -r * g1 * g, g1 * g])
    return g


def composition_coefficients(order: int, kind: str | None = None) -> Array:
    r"""The coefficients :math:`\gamma_1, \dots, \gamma_s` of a symmetric composition.

    For a symmetric one-step map :math:`\Phi_h` of order 2,
    :math:`\Phi_{\gamma_s h}\circ\cdots\circ\Phi_{\gamma_1 h}` has order ``order``.  The
    conditions (Hairer, Lubich and Wanner 2006, Section V.3.2) include
    :math:`\sum\gamma_i = 1`, :math:`\sum\gamma_i^3 = 0` (order 4),
    :math:`\sum\gamma_i^5 = 0` and one more (order 6), :math:`\sum\gamma_i^7 = 0` and three more
    (order 8); the tests check them through the local error of a composed Strang splitting in
    60-digit arithmetic.

    Parameters
    ----------
    order : {2, 4, 6, 8}
        The order of the composition (2 gives the base map, :math:`\gamma = [1]`).
    kind : str, optional
        Which method:

        * ``"triple_jump"`` (any order): Creutz and Gocksch 1989, Suzuki 1990, Yoshida 1990;
          :math:`\gamma_1 = \gamma_3 = 1/(2 - 2^{1/(p+1)})`,
          :math:`\gamma_2 = -2^{1/(p+1)}\gamma_1` raising the order from :math:`p` to
          :math:`p + 2`, applied recursively (3, 9, 27 stages for orders 4, 6, 8);
        * ``"suzuki"`` (order 4, 5 stages): Suzuki 1990, :math:`\gamma_{1,2,4,5} = 1/(4 -
          4^{1/3})`, :math:`\gamma_3 = -4^{1/3}/(4 - 4^{1/3})`; the default for order 4;
        * ``"yoshida"`` (order 6, 7 stages): Yoshida 1990, solution A;
        * ``"kahan_li"`` (order 6, 9 stages; order 8, 17 stages): Kahan and Li 1997,
          s9odr6a and s17odr8a; the default for orders 6 and 8;
        * ``"mclachlan"`` (order 8, 15 stages): McLachlan 1995.

        Orders 6 and 8 are quoted to 26 digits from Hairer, Lubich and Wanner (2006), Section
        V.3.2, eqs. (3.9)-(3.13).

    Returns
    -------
    ndarray, shape (s,)
        The coefficients, symmetric (:math:`\gamma_{s+1-i} = \gamma_i`) and summing to 1.

    Raises
    ------
    InputError
        An order other than 2, 4, 6, 8, or a kind not available at that order.

    Examples
    --------
    >>> import numpy as np
    >>> from symrb.composition import composition_coefficients
    >>> g = composition_coefficients(4, "triple_jump")
    >>> g.round(6)
    array([ 1.351207, -1.702414,  1.351207])
    >>> float(g.sum()), abs(float((g**3).sum())) < 1e-15
    (1.0, True)
    >>> len(composition_coefficients(8))  # Kahan-Li s17odr8a
    17
    """
    if isinstance(order, bool) or not isinstance(order, int | np.integer) or order not in _KINDS:
        raise InputError(f"order must be one of 2, 4, 6, 8, got {order!r}")
    order = int(order)
    if kind is None:
        kind = _DEFAULT_KIND[order]
    if kind not in _KINDS[order]:
        raise InputError(
            f"kind must be one of {list(_KINDS[order])} for order {order}, got {kind!r}"
        )
    if kind == "triple_jump":
        return _triple_jump(order)
    if kind == "suzuki":
        r = 4.0 ** (1.0 / 3.0)
        g1 = 1.0 / (4.0 - r)
        return np.array([g1, g1, -r * g1, g1, g1])
    half = np.array(_HALVES[(order, kind)])
    return np.concatenate([half, half[-2::-1]])


S = TypeVar("S")


def compose_steps(step: Callable[[S, float], S], gammas: ArrayLike) -> Callable[[S, float], S]:
    r"""The composition :math:`\Psi_h = \Phi_{\gamma_s h}\circ\cdots\circ\Phi_{\gamma_1 h}`.

    Parameters
    ----------
    step : callable
        The base map :math:`\Phi_h`, called as ``step(state, h)`` and returning the new state;
        it must accept negative ``h`` when some :math:`\gamma_i < 0`.  For the orders of
        :func:`composition_coefficients` it must be symmetric and of order 2.
    gammas : array_like, shape (s,)
        The coefficients (finite, at least one).

    Returns
    -------
    callable
        :math:`\Psi_h` as ``psi(state, h) -> state``, which calls ``step(state, gamma_i * h)``
        for ``i = 1, ..., s``.

    Examples
    --------
    Composing the exact flow :math:`x\mapsto e^{h}x` of :math:`\dot x = x` gives it back, since the
    coefficients sum to 1:

    >>> import numpy as np
    >>> from symrb.composition import compose_steps, composition_coefficients
    >>> psi = compose_steps(lambda x, h: np.exp(h) * x, composition_coefficients(6))
    >>> bool(np.isclose(psi(1.0, 0.5), np.exp(0.5), rtol=1e-14, atol=0))
    True
    """
    if not callable(step):
        raise InputError(f"step must be callable (state, h) -> state, got {type(step).__name__}")
    g = v.as_float_array(gammas, "gammas")
    if g.ndim != 1 or g.size == 0:
        raise InputError(f"gammas must be a non-empty 1-D array, got shape {g.shape}")
    coeffs = tuple(float(x) for x in g)

    def composed(state: S, h: float) -> S:
        for c in coeffs:
            state = step(state, c * h)
        return state

    return composed
