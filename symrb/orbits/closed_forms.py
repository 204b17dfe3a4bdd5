r"""The closed forms of claim S15 on :math:`\mathfrak{so}(3)`: the second costate term along the
one-sample extremal and the lower bound for two samples (the generated kernels of
:mod:`symrb._generated.adjoint_orbits`, validated and documented)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .. import _validate as v
from .._generated import adjoint_orbits as _gen
from .._validate import Array
from ..algebra import pairing
from ..errors import InputError
from ._common import pair_xN

__all__ = ["one_sample_second_term", "two_sample_bound"]


def _pairing_norm(a: Array) -> Array:
    """sqrt(<a, a>) with the pairing of symrb.pairing, over the last two axes."""
    return np.asarray(np.sqrt(pairing(a, a)))


def one_sample_second_term(x0: ArrayLike, N: ArrayLike, t: ArrayLike) -> Array:
    r"""The second costate term :math:`\|[N, [N, x(t)]]\|` along the one-sample extremal on
    :math:`\mathfrak{so}(3)`, in closed form (claim S15).

    With the corrected endpoint :math:`p_T = -N` the extremal is the double bracket flow from
    ``x0``, which turns :math:`x` in the plane of :math:`x_0` and :math:`N` towards
    :math:`-N`.  The paper's corrected statement gives

    .. math:: \|[N, [N, x(t)]]\| = \|N\|^2\|x_0\|\sin\varphi_t,\qquad
              \tan\frac{\varphi_t}2 = \tan\frac{\varphi_0}2\,e^{-\|x_0\|\|N\|t},

    :math:`\varphi_0` the angle of :math:`x_0` from :math:`-N`
    (:math:`\cos\varphi_0 = -\langle x_0, N\rangle/(\|x_0\|\|N\|)`), norms and pairing of
    :func:`symrb.pairing`.  The formula is the generated ``one_sample_second_term``, the
    expression that the evidence of S15 checks against the boundary value problem.

    Parameters
    ----------
    x0, N : array_like, shape (3, 3)
        The sample and the fixed element, skew-symmetric and nonzero.
    t : array_like, shape (m,)
        Times >= 0.

    Returns
    -------
    ndarray, shape (m,)
        The second term at the times ``t``; it decays like :math:`e^{-\|x_0\|\|N\|t}`.

    Raises
    ------
    InputError
        If ``x0`` or ``N`` is not a nonzero skew 3 x 3 matrix, or a time is negative.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> x0, N = symrb.hat([0.5, 0.0, 0.0]), symrb.hat([0.0, 0.0, 1.0])  # at the angle pi/2
    >>> print(symrb.orbits.one_sample_second_term(x0, N, [0.0, 2.0, 8.0]).round(6))
    [0.5      0.324027 0.018309]
    >>> x = symrb.double_bracket_flow(x0, N, [8.0])[0]
    >>> c = symrb.commutator(N, symrb.commutator(N, x))
    >>> print(np.sqrt(symrb.pairing(c, c)).round(6))
    0.018309
    """
    xx, nn = pair_xN(x0, N, "x0")
    if xx.shape != (3, 3):
        raise InputError(f"x0 and N must be 3 x 3 (the closed form is on so(3)), got {xx.shape}")
    ts = v.as_float_array(t, "t")
    if ts.ndim != 1 or np.any(ts < 0):
        raise InputError(f"t must be a 1-D array of times >= 0, got {ts}")
    r, s = float(_pairing_norm(xx)), float(_pairing_norm(nn))
    if r == 0.0 or s == 0.0:
        raise InputError(f"x0 and N must be nonzero, got norms {r:g} and {s:g}")
    cos0 = float(np.clip(-pairing(xx, nn) / (r * s), -1.0, 1.0))
    return np.asarray(_gen.one_sample_second_term(r, s, np.tan(np.arccos(cos0) / 2), ts))


def two_sample_bound(x0: ArrayLike, N: ArrayLike) -> float:
    r"""The lower bound of the larger second costate term of two samples on
    :math:`\mathfrak{so}(3)` sharing one control (claim S15, corrected).

    .. math:: \max_a\|[N, [N, x^a_T]]\| \ge \|N\|^2\min_a\|x^a_0\|\sin\frac\beta2,\qquad
              \cos\beta = \frac{|\langle x^1_0, x^2_0\rangle|}{\|x^1_0\|\|x^2_0\|},

    at every horizon T (norms and pairing of :func:`symrb.pairing`): unlike one sample, the
    second term does not go to zero.  The formula is the generated ``two_sample_bound``, the
    expression that the evidence of S15 compares with solutions of
    :func:`~symrb.orbits.bvp.solve_orbit_bvp`.

    Parameters
    ----------
    x0 : array_like, shape (2, 3, 3)
        The two samples, skew-symmetric and nonzero.
    N : array_like, shape (3, 3)
        The fixed element, skew-symmetric.

    Returns
    -------
    float
        The bound.

    Raises
    ------
    InputError
        If ``x0`` is not two nonzero skew 3 x 3 matrices or ``N`` not a skew 3 x 3 matrix.

    Examples
    --------
    >>> import symrb
    >>> x0 = [symrb.hat([1.0, 0.0, 0.0]), symrb.hat([0.0, 1.0, 0.0])]  # beta = pi/2
    >>> round(symrb.orbits.two_sample_bound(x0, symrb.hat([0.0, 0.0, 2.0])), 6)  # 4 sin(pi/4)
    2.828427
    """
    xx, nn = pair_xN(x0, N, "x0")
    if xx.shape != (2, 3, 3):
        raise InputError(f"x0 must hold two 3 x 3 samples, shape (2, 3, 3), got {xx.shape}")
    r1, r2 = (float(a) for a in _pairing_norm(xx))
    if r1 == 0.0 or r2 == 0.0:
        raise InputError(f"the samples must be nonzero, got norms {r1:g} and {r2:g}")
    # |<x^1, x^2>| <= r_1 r_2 (Cauchy-Schwarz), up to rounding
    p12 = float(np.clip(pairing(xx[0], xx[1]), -r1 * r2, r1 * r2))
    return float(_gen.two_sample_bound(r1, r2, float(_pairing_norm(nn)), p12))
