r"""Higher order with the same structure: symmetric compositions, RKMK4 and the implicit midpoint rule.

The discrete rigid body of Section 2 (MV-Algorithm 2 at step :math:`h`, see
:func:`symrb.discrete_rigid_body_flow`) is a *symmetric* one-step map of order 2:
:math:`\Phi_{-h} = \Phi_h^{-1}`.  A symmetric composition

.. math::

    \Psi_h = \Phi_{\gamma_s h}\circ\cdots\circ\Phi_{\gamma_2 h}\circ\Phi_{\gamma_1 h},
    \qquad \gamma_{s+1-i} = \gamma_i,

is again symmetric and, for the coefficients of :func:`composition_coefficients`, of order
4, 6 or 8 (Hairer, Lubich and Wanner, *Geometric Numerical Integration*, 2nd ed., Springer 2006,
Section V.3.2).  Every stage is an MV step, so the composition keeps what one step keeps:
:math:`Q` in SO(n), :math:`M_{k+1} = U_k^TM_kU_k` (the spectrum of :math:`M`, hence every
Casimir, conserved to rounding) and the energy (to rounding, each MV step conserves it) and
symplecticity of the map.

The textbook alternatives, with the same result object
(:class:`symrb.DiscreteFlowSolution`):

* RKMK4 (Munthe-Kaas 1998; Hairer, Lubich and Wanner, Section IV.8.2): the classical
  Runge-Kutta method of order 4 applied to :math:`\dot\Theta = \mathrm{dexp}^{-1}_{-\Theta}(\Omega)`
  with :math:`g = \exp\Theta` acting by :math:`(Q, M)\mapsto(Qg, g^TMg)`; order 4, Casimirs and
  orthogonality to rounding, not symmetric, energy drifts at order 4.
* the implicit midpoint rule on the Lie-Poisson equation,
  :math:`M_{k+1} = M_k + h[\bar M, \bar\Omega]`, :math:`\bar M = (M_k + M_{k+1})/2`,
  :math:`\bar\Omega = J^{-1}(\bar M)`, with :math:`Q_{k+1} = Q_k\,\mathrm{cay}(h\bar\Omega)`
  (:math:`\mathrm{cay}(A) = (I - A/2)^{-1}(I + A/2)`, so :math:`Q` stays orthogonal); symmetric,
  order 2, conserves the quadratic invariants (energy and :math:`\mathrm{tr}\,M^2`) but not
  the higher Casimirs (:math:`\mathrm{tr}\,M^4` for :math:`n\ge 5`).

Momenta here are on the continuous scale (the body momentum :math:`M(t_k)`; a base step at
step :math:`h` solves :math:`J_D(U) = hM`).  A *base step* is any object with a method
``step(Q, M, h) -> (Q, M)`` that advances by a real ``h`` of either sign (compositions of order
4 and more take negative substeps); :class:`MVStep` and :class:`MidpointStep` are the symmetric
ones shipped here.
"""

from __future__ import annotations

import contextlib
import functools
import time
from collections.abc import Callable, Sequence
from typing import Any, Protocol, TypeVar

import numpy as np
import scipy.linalg as sla
from numpy.typing import ArrayLike

from . import _validate as v
from ._progress import progress_bar
from ._results import Trajectory
from ._validate import Array
from .discrete import DiscreteFlowSolution
from .engine import MVStepper
from .errors import InputError, NotConvergedError, OutOfDomainError
from .solvers import solve_moser_veselov

__all__ = [
    "composition_coefficients",
    "compose_steps",
    "MVStep",
    "MidpointStep",
    "RKMK4Step",
    "composed_rigid_body_flow",
    "rkmk4_rigid_body_flow",
    "midpoint_rigid_body_flow",
    "benchmark_cost",
]

_EPS = float(np.finfo(float).eps)

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
    >>> from symrb.compose import composition_coefficients
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
    >>> from symrb.compose import compose_steps, composition_coefficients
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


# ---------------------------------------------------------------------------------------------
# base steps


class BaseStep(Protocol):
    """What a base step provides: ``step(Q, M, h) -> (Q, M)`` (continuous-scale momenta)."""

    def step(self, Q: Array, M: Array, h: float) -> tuple[Array, Array]: ...  # pragma: no cover


def _skew(a: Array) -> Array:
    return 0.5 * (a - np.swapaxes(a, -1, -2))


def _lam(lam: ArrayLike) -> Array:
    return np.array(v.inertia(lam, positive=True), dtype=float)


class MVStep:
    r"""One step of MV-Algorithm 2 at step ``h`` (continuous-scale momenta).

    Solves :math:`U\Lambda - \Lambda U^T = hM` on the branch through the identity
    (:func:`symrb.solve_moser_veselov`) and returns :math:`(QU, U^TMU)`, the step of
    :func:`symrb.discrete_rigid_body_flow` (the symmetric representation with
    :math:`P = QM/2`; MV-Algorithm 2 with discrete momentum :math:`hM`).  The map is symmetric:
    from :math:`(QU, U^TMU)` at step :math:`-h` the solution is :math:`U^T`.  Newton starts from
    the last solution found for the same ``h`` (each stage of a composition has its own).

    Parameters
    ----------
    lam : array_like, shape (..., n)
        The diagonal of :math:`\Lambda`, all entries > 0.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> from symrb.compose import MVStep
    >>> lam = [0.7, 1.1, 1.6]
    >>> Q0, M0 = np.eye(3), symrb.hat([0.5, 1.0, 1.5])
    >>> Q1, M1 = MVStep(lam).step(Q0, M0, 0.1)
    >>> ref = symrb.discrete_rigid_body_flow(Q0, M0, lam, 0.1, 1)
    >>> bool(np.allclose(Q1, ref.y.Q[-1], rtol=0, atol=1e-14))
    True
    >>> Qb, Mb = MVStep(lam).step(Q1, M1, -0.1)  # symmetric: -h undoes h
    >>> bool(np.allclose(Mb, M0, rtol=0, atol=1e-14))
    True
    """

    def __init__(self, lam: ArrayLike) -> None:
        self.lam = _lam(lam)
        self._warm: dict[tuple[float, tuple[int, ...]], Array] = {}

    def step(self, Q: Array, M: Array, h: float) -> tuple[Array, Array]:
        """Advance ``(Q, M)`` by ``h`` (any real number); see the class docstring."""
        key = (float(h), np.shape(M))
        U0 = self._warm.get(key)
        U = np.asarray(solve_moser_veselov(h * M, self.lam, U0=U0))
        self._warm[key] = U
        return Q @ U, _skew(np.swapaxes(U, -1, -2) @ M @ U)


def _cayley(A: Array) -> Array:
    eye = np.eye(A.shape[-1])
    return np.asarray(np.linalg.solve(eye - 0.5 * A, eye + 0.5 * A), dtype=np.float64)


class MidpointStep:
    r"""One step of the implicit midpoint rule for the rigid body (continuous-scale momenta).

    .. math::

        \bar M = M_k + \tfrac h2[\bar M, \bar\Omega],\quad \bar\Omega = J^{-1}(\bar M),\qquad
        M_{k+1} = 2\bar M - M_k,\quad Q_{k+1} = Q_k\,\mathrm{cay}(h\bar\Omega),

    with :math:`J^{-1}(M)_{ij} = M_{ij}/(\lambda_i + \lambda_j)` and
    :math:`\mathrm{cay}(A) = (I - A/2)^{-1}(I + A/2)`.  The first equation is solved by fixed
    point iteration (it contracts for :math:`|h|\,\|\bar\Omega\|` small) to
    :math:`\|\cdot\| \le 4\varepsilon\|M_k\|`.  Symmetric and of order 2.

    Parameters
    ----------
    lam : array_like, shape (..., n)
        The diagonal of :math:`\Lambda`, all entries > 0.
    maxiter : int, optional
        The most fixed-point iterations; more raise :class:`symrb.errors.NotConvergedError`.

    Attributes
    ----------
    last_iterations : int
        The fixed-point iterations of the last step.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> from symrb.compose import MidpointStep
    >>> lam = np.array([0.7, 1.1, 1.6])
    >>> M0 = symrb.hat([0.5, 1.0, 1.5])
    >>> Q1, M1 = MidpointStep(lam).step(np.eye(3), M0, 0.1)
    >>> H = symrb.kinetic_energy(np.stack([M0, M1]), lam)  # a quadratic invariant: conserved
    >>> bool(abs(H[1] - H[0]) < 1e-14)
    True
    """

    def __init__(self, lam: ArrayLike, maxiter: int = 100) -> None:
        self.lam = _lam(lam)
        self.W = 1.0 / (self.lam[..., :, None] + self.lam[..., None, :])
        self.maxiter = v.count(maxiter, "maxiter", 1)
        self.last_iterations = 0

    def step(self, Q: Array, M: Array, h: float) -> tuple[Array, Array]:
        """Advance ``(Q, M)`` by ``h`` (any real number); see the class docstring."""
        tol = 4.0 * _EPS * max(float(np.max(np.abs(M), initial=0.0)), 1e-300)
        Mb = M
        it = 0
        while True:
            Om = Mb * self.W
            with np.errstate(over="ignore", invalid="ignore"):
                new = M + 0.5 * h * (Mb @ Om - Om @ Mb)
                diff = float(np.max(np.abs(new - Mb), initial=0.0))
            Mb = new
            it += 1
            if diff <= tol:
                break
            if it >= self.maxiter or not np.isfinite(diff):
                raise NotConvergedError(
                    f"implicit midpoint: the fixed point iteration did not converge in {it} "
                    f"iterations (last change {diff:.3e}, h = {h!r}); take a smaller h",
                    diff,
                    it,
                )
        self.last_iterations = it
        Om = Mb * self.W
        return Q @ _cayley(h * Om), _skew(2.0 * Mb - M)


class RKMK4Step:
    r"""One step of RKMK4, the Runge-Kutta-Munthe-Kaas method of order 4 for the rigid body.

    The flow is :math:`(Q(t), M(t)) = (Q_0g, g^TM_0g)` with :math:`\dot g = g\,\Omega`,
    :math:`\Omega = J^{-1}(g^TM_0g)`.  With :math:`g = \exp\Theta`,
    :math:`\dot\Theta = \mathrm{dexp}^{-1}_{-\Theta}(\Omega) \approx \Omega + \tfrac12[\Theta,
    \Omega] + \tfrac1{12}[\Theta, [\Theta, \Omega]]` (the series truncated after the terms
    order 4 needs; Hairer, Lubich and Wanner 2006, Section IV.8.2), and the classical
    Runge-Kutta method of order 4 is applied to :math:`\Theta` from :math:`\Theta(0) = 0`:

    .. math::

        k_i = hF(\Theta_i),\ \Theta_1 = 0,\ \Theta_2 = k_1/2,\ \Theta_3 = k_2/2,\ \Theta_4 = k_3,
        \qquad \Theta = (k_1 + 2k_2 + 2k_3 + k_4)/6,

    :math:`F(\Theta) = \mathrm{dexp}^{-1}_{-\Theta}(J^{-1}(e^{-\Theta}M_0e^{\Theta}))`, and
    :math:`(Q_1, M_1) = (Q_0e^\Theta, e^{-\Theta}M_0e^\Theta)` with
    :func:`scipy.linalg.expm`.  Orthogonality and the spectrum of :math:`M` are kept to
    rounding; the method is explicit, of order 4 and not symmetric.

    Parameters
    ----------
    lam : array_like, shape (..., n)
        The diagonal of :math:`\Lambda`, all entries > 0.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> from symrb.compose import RKMK4Step
    >>> M0 = symrb.hat([0.5, 1.0, 1.5])
    >>> Q1, M1 = RKMK4Step([0.7, 1.1, 1.6]).step(np.eye(3), M0, 0.1)
    >>> bool(np.allclose(Q1.T @ Q1, np.eye(3), rtol=0, atol=1e-15))
    True
    """

    def __init__(self, lam: ArrayLike) -> None:
        self.lam = _lam(lam)
        self.W = 1.0 / (self.lam[..., :, None] + self.lam[..., None, :])
        self.last_iterations = 0

    def _F(self, theta: Array, M0: Array) -> Array:
        g = sla.expm(theta)
        gt = np.swapaxes(g, -1, -2)
        Om = _skew(gt @ M0 @ g) * self.W
        c = theta @ Om - Om @ theta
        return Om + 0.5 * c + (theta @ c - c @ theta) / 12.0

    def step(self, Q: Array, M: Array, h: float) -> tuple[Array, Array]:
        """Advance ``(Q, M)`` by ``h`` (any real number); see the class docstring."""
        k1 = h * (M * self.W)  # F(0) = J^{-1}(M)
        k2 = h * self._F(0.5 * k1, M)
        k3 = h * self._F(0.5 * k2, M)
        k4 = h * self._F(k3, M)
        g = sla.expm(_skew((k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0))
        gt = np.swapaxes(g, -1, -2)
        return Q @ g, _skew(gt @ M @ g)


# ---------------------------------------------------------------------------------------------
# flows


def _prepare(
    Q0: ArrayLike, M0: ArrayLike, lam: ArrayLike, h: float, steps: int, save_every: int
) -> tuple[Array, Array, Array, float, int, int]:
    L = _lam(lam)
    nn = L.shape[-1]
    Q = v.orthogonal(Q0, "Q0", nn)
    M = v.skew(M0, "M0", nn)
    hv = v.real_scalar(h, "h")
    if not hv > 0:
        raise InputError(f"h must be a finite number > 0, got {h!r}")
    steps = v.count(steps, "steps", 0)
    save_every = v.count(save_every, "save_every", 1)
    try:
        batch = np.broadcast_shapes(Q.shape[:-2], M.shape[:-2], L.shape[:-1])
    except ValueError:
        raise InputError(
            f"the batch axes do not broadcast: lam {L.shape}, Q0 {Q.shape}, M0 {M.shape}"
        ) from None
    Q = np.broadcast_to(Q, batch + (nn, nn)).copy()
    M = _skew(np.broadcast_to(M, batch + (nn, nn)).copy())
    return Q, M, L, hv, steps, save_every


def _run(
    advance: Callable[[Array, Array], tuple[Array, Array]],
    counter: _Counter | None,
    Q: Array,
    M: Array,
    h: float,
    steps: int,
    save_every: int,
    method: str,
    progress: bool,
) -> DiscreteFlowSolution:
    """The loop shared by the flows: save every ``save_every``-th state, stop on a failed step."""
    ks, Qs, Ms, its = [0], [Q.copy()], [M.copy()], []
    bar = progress_bar(steps, method, progress)
    failure = ""
    k = 0
    try:
        for k in range(1, steps + 1):
            Q, M = advance(Q, M)
            if counter is not None:
                its.extend(counter.pop())
            if k % save_every == 0:
                ks.append(k)
                Qs.append(Q)
                Ms.append(M)
            bar.step()
    except (OutOfDomainError, NotConvergedError) as exc:
        failure = f"step {k} of {steps} failed: {exc}"
        if ks[-1] != k - 1:
            ks.append(k - 1)
            Qs.append(Q)
            Ms.append(M)
    bar.close()
    kk = np.asarray(ks, dtype=np.int64)
    return DiscreteFlowSolution(
        t=kk.astype(float) * h,
        k=kk,
        y=Trajectory(Q=np.stack(Qs), M=np.stack(Ms)),
        iterations=np.asarray(its, dtype=np.int64),
        success=not failure,
        status=-1 if failure else 0,
        message=failure or f"all {steps} steps taken",
        method=method,
        h=h,
    )


class _Counter:
    """Collects ``last_iterations`` of a base step after each call (when it has one)."""

    def __init__(self, base: Any) -> None:
        self.base = base
        self.items: list[int] = []

    def wrap(self, state: tuple[Array, Array], h: float) -> tuple[Array, Array]:
        out = self.base.step(state[0], state[1], h)
        n = getattr(self.base, "last_iterations", None)
        if n is not None:
            self.items.append(int(n))
        return out

    def pop(self) -> list[int]:
        got, self.items = self.items, []
        return got


def composed_rigid_body_flow(
    Q0: ArrayLike,
    M0: ArrayLike,
    lam: ArrayLike,
    h: float,
    steps: int,
    order: int = 4,
    *,
    kind: str | None = None,
    step: str | BaseStep = "mv",
    save_every: int = 1,
    progress: bool = False,
) -> DiscreteFlowSolution:
    r"""The rigid body by a symmetric composition of a symmetric base step.

    Each step is :math:`\Phi_{\gamma_s h}\circ\cdots\circ\Phi_{\gamma_1 h}` with the
    coefficients :func:`composition_coefficients` ``(order, kind)`` and the base step
    :math:`\Phi` (by default one MV-Algorithm 2 step of :class:`symrb.engine.MVStepper`),
    approximating :math:`\dot Q = Q\Omega`, :math:`\dot M = [M, \Omega]`,
    :math:`\Omega = J^{-1}(M)` to order ``order``.

    Parameters
    ----------
    Q0 : array_like, shape (..., n, n)
        The initial attitude, in SO(n).
    M0 : array_like, shape (..., n, n)
        The initial body momentum (skew-symmetric, continuous scale).
    lam : array_like, shape (..., n)
        The diagonal of :math:`\Lambda`, all entries > 0.
    h : float
        The time step, > 0.
    steps : int
        The number of (composed) steps, >= 0.
    order : {2, 4, 6, 8}, optional
        The order of the composition (2: the base step alone).
    kind : str, optional
        The coefficients (see :func:`composition_coefficients`; by default Suzuki's 5 stages at
        order 4 and Kahan-Li at orders 6 and 8).
    step : {"mv", "midpoint"} or object, optional
        The base step: ``"mv"`` (:class:`symrb.engine.MVStepper`, the fast Moser-Veselov step;
        :class:`MVStep` is the same map through :func:`symrb.solve_moser_veselov`),
        ``"midpoint"`` (:class:`MidpointStep`), or any
        object with a method ``step(Q, M, h) -> (Q, M)`` that is symmetric and of order 2 (e.g.
        a faster engine); its ``last_iterations`` attribute, if any, is recorded.
    save_every : int, optional
        Keep the states :math:`k = 0, s, 2s, \dots` (``s = save_every``).
    progress : bool, optional
        Show a tqdm progress bar (needs the optional package tqdm).

    Returns
    -------
    DiscreteFlowSolution
        ``t`` the times :math:`kh`; ``y.Q`` and ``y.M`` of shape ``(K, ..., n, n)``;
        ``iterations`` the solver iterations of each stage when the base step reports them in
        an attribute ``last_iterations`` (:class:`MidpointStep` does, :class:`MVStep` does not).
        A failed stage (e.g. past the fold of :math:`J_D` at a large :math:`|\gamma_i| h`)
        ends the run with ``success`` False.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> from symrb.compose import composed_rigid_body_flow
    >>> lam = np.array([0.7, 1.1, 1.6])
    >>> M0 = symrb.hat([0.5, 1.0, 1.5])
    >>> exact = symrb.integrate(symrb.RigidBody, (0, 1), {"Q": np.eye(3), "M": M0}, lam=lam,
    ...                         rtol=1e-13, atol=1e-13, t_eval=[1.0]).y.M[-1]
    >>> def error(h):
    ...     sol = composed_rigid_body_flow(np.eye(3), M0, lam, h, round(1 / h), order=4)
    ...     return np.abs(sol.y.M[-1] - exact).max()
    >>> print(round(float(np.log2(error(0.1) / error(0.05)))))  # fourth order
    4
    """
    Q, M, L, hv, steps, save_every = _prepare(Q0, M0, lam, h, steps, save_every)
    gammas = composition_coefficients(order, kind)
    if isinstance(step, str):
        if step == "mv":  # the fast engine (Cayley-parametrised Newton, warm started)
            base: Any = MVStepper(L, np.broadcast_shapes(Q.shape[:-2], M.shape[:-2]))
            name = "MV-Algorithm 2"
        elif step == "midpoint":
            base = MidpointStep(L)
            name = "implicit midpoint"
        else:
            raise InputError(f'step must be "mv", "midpoint" or an object, got {step!r}')
    elif callable(getattr(step, "step", None)):
        base = step
        name = type(step).__name__
    else:
        raise InputError(
            f"step must be 'mv', 'midpoint' or an object with a method step(Q, M, h), got "
            f"{type(step).__name__}"
        )
    counter = _Counter(base)
    psi = compose_steps(counter.wrap, gammas)
    kind_name = kind or _DEFAULT_KIND[int(order)]
    method = f"{name} composed to order {int(order)} ({kind_name}, {gammas.size} stages)"
    return _run(
        lambda q, m: psi((q, m), hv), counter, Q, M, hv, steps, save_every, method, progress
    )


def rkmk4_rigid_body_flow(
    Q0: ArrayLike,
    M0: ArrayLike,
    lam: ArrayLike,
    h: float,
    steps: int,
    *,
    save_every: int = 1,
    progress: bool = False,
) -> DiscreteFlowSolution:
    r"""The rigid body by RKMK4 (:class:`RKMK4Step`), order 4, explicit.

    Parameters
    ----------
    Q0, M0, lam, h, steps, save_every, progress
        As in :func:`composed_rigid_body_flow`.

    Returns
    -------
    DiscreteFlowSolution
        ``t`` the times :math:`kh`; ``y.Q`` and ``y.M``; no iterations (explicit).

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> from symrb.compose import rkmk4_rigid_body_flow
    >>> M0 = symrb.hat([0.5, 1.0, 1.5])
    >>> sol = rkmk4_rigid_body_flow(np.eye(3), M0, [0.7, 1.1, 1.6], 0.1, 100, save_every=50)
    >>> sol.t
    array([ 0.,  5., 10.])
    >>> c = symrb.casimir_traces(sol.y.M)[:, 0]  # tr M^2: conserved to rounding
    >>> bool(np.ptp(c) < 1e-13)
    True
    """
    Q, M, L, hv, steps, save_every = _prepare(Q0, M0, lam, h, steps, save_every)
    base = RKMK4Step(L)
    return _run(
        lambda q, m: base.step(q, m, hv), None, Q, M, hv, steps, save_every, "RKMK4", progress
    )


def midpoint_rigid_body_flow(
    Q0: ArrayLike,
    M0: ArrayLike,
    lam: ArrayLike,
    h: float,
    steps: int,
    *,
    save_every: int = 1,
    progress: bool = False,
) -> DiscreteFlowSolution:
    r"""The rigid body by the implicit midpoint rule (:class:`MidpointStep`), order 2, symmetric.

    Parameters
    ----------
    Q0, M0, lam, h, steps, save_every, progress
        As in :func:`composed_rigid_body_flow`.

    Returns
    -------
    DiscreteFlowSolution
        ``t`` the times :math:`kh`; ``y.Q`` and ``y.M``; ``iterations`` the fixed-point
        iterations of each step.  A step whose iteration does not converge ends the run with
        ``success`` False.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> from symrb.compose import midpoint_rigid_body_flow
    >>> lam = [0.7, 1.1, 1.6]
    >>> M0 = symrb.hat([0.5, 1.0, 1.5])
    >>> sol = midpoint_rigid_body_flow(np.eye(3), M0, lam, 0.1, 100, save_every=100)
    >>> H = symrb.kinetic_energy(sol.y.M, lam)  # a quadratic invariant: conserved
    >>> bool(np.ptp(H) < 1e-13), sol.message
    (True, 'all 100 steps taken')
    """
    Q, M, L, hv, steps, save_every = _prepare(Q0, M0, lam, h, steps, save_every)
    counter = _Counter(MidpointStep(L))
    return _run(
        lambda q, m: counter.wrap((q, m), hv),
        counter,
        Q,
        M,
        hv,
        steps,
        save_every,
        "implicit midpoint",
        progress,
    )


# ---------------------------------------------------------------------------------------------
# benchmark (not a test: it reports process-time ratios measured in one run)


def _methods() -> dict[str, tuple[int, Callable[..., DiscreteFlowSolution]]]:
    def comp(order: int, kind: str, step: str = "mv") -> Callable[..., DiscreteFlowSolution]:
        def run(Q0: Array, M0: Array, lam: Array, h: float, n: int) -> DiscreteFlowSolution:
            return composed_rigid_body_flow(
                Q0, M0, lam, h, n, order, kind=kind, step=step, save_every=max(n, 1)
            )

        return run

    def other(flow: Callable[..., DiscreteFlowSolution]) -> Callable[..., DiscreteFlowSolution]:
        def run(Q0: Array, M0: Array, lam: Array, h: float, n: int) -> DiscreteFlowSolution:
            return flow(Q0, M0, lam, h, n, save_every=max(n, 1))

        return run

    return {
        "MV (order 2)": (2, comp(2, "triple_jump")),
        "MV triple jump 4": (4, comp(4, "triple_jump")),
        "MV Suzuki 4": (4, comp(4, "suzuki")),
        "MV Yoshida 6": (6, comp(6, "yoshida")),
        "MV Kahan-Li 6": (6, comp(6, "kahan_li")),
        "MV McLachlan 8": (8, comp(8, "mclachlan")),
        "MV Kahan-Li 8": (8, comp(8, "kahan_li")),
        "RKMK4": (4, other(rkmk4_rigid_body_flow)),
        "implicit midpoint": (2, other(midpoint_rigid_body_flow)),
        "midpoint Suzuki 4": (4, comp(4, "suzuki", "midpoint")),
    }


def benchmark_cost(
    T: float = 10.0,
    target: float = 1e-8,
    *,
    lam: ArrayLike = (0.7, 1.1, 1.6),
    m0: ArrayLike = (0.5, 1.0, 1.5),
    repeats: int = 5,
    methods: Sequence[str] | None = None,
) -> dict[str, dict[str, float]]:
    r"""Process time to reach a given error at time ``T``, for each method and for DOP853.

    The rigid body on SO(3) from :math:`Q_0 = I`, :math:`M_0 = \hat m_0` is integrated to
    ``T``; the error is the largest entry of :math:`|Q - Q_{ref}|` and :math:`|M - M_{ref}|`
    against DOP853 at ``rtol = atol = 1e-13`` (:func:`symrb.integrate`).  For each method the
    smallest number of steps found with error :math:`\le` ``target`` (from the error at a coarse
    step and the order, then in 5% increments) is timed; DOP853 (through
    :func:`symrb.integrate`) is timed at the largest ``rtol = atol`` in the sequence
    :math:`10^{-k/4}` that reaches ``target``.  Times are medians of ``repeats`` interleaved
    runs of :func:`time.process_time`, with BLAS limited to one thread when threadpoolctl is
    installed.  For reports, never for tests (timings depend on the machine).

    Parameters
    ----------
    T : float, optional
        The final time.
    target : float, optional
        The error to reach.
    lam : array_like, shape (3,), optional
        The diagonal of :math:`\Lambda`.
    m0 : array_like, shape (3,), optional
        The initial body momentum as a vector (:func:`symrb.hat`).
    repeats : int, optional
        Timed runs of each method (interleaved), >= 1.
    methods : sequence of str, optional
        A subset of the method names (all by default; see the keys of the result).

    Returns
    -------
    dict
        For each method name (and ``"DOP853"``): ``steps`` (or the number of right-hand side
        evaluations for DOP853), ``h`` (or ``rtol``), ``error``, ``seconds`` (median process
        time) and ``ratio`` (seconds over DOP853's seconds).

    Examples
    --------
    >>> from symrb.compose import benchmark_cost
    >>> out = benchmark_cost(T=1.0, target=1e-6, repeats=1, methods=["RKMK4"])
    >>> sorted(out), out["RKMK4"]["error"] <= 1e-6
    (['DOP853', 'RKMK4'], True)
    """
    from .algebra import hat
    from .continuous import RigidBody, integrate

    Tv = v.real_scalar(T, "T")
    if not Tv > 0:
        raise InputError(f"T must be a finite number > 0, got {T!r}")
    tgt = v.real_scalar(target, "target")
    if not tgt > 0:
        raise InputError(f"target must be a finite number > 0, got {target!r}")
    repeats = v.count(repeats, "repeats", 1)
    table = _methods()
    names = list(table) if methods is None else list(methods)
    unknown = [m for m in names if m not in table]
    if unknown:
        raise InputError(f"methods must be among {list(table)}, got unknown {unknown}")
    L = _lam(lam)
    Q0, M0 = np.eye(3), hat(m0)

    try:
        from threadpoolctl import threadpool_limits

        limit: Any = threadpool_limits(1)
    except ImportError:  # pragma: no cover - optional
        limit = contextlib.nullcontext()
    with limit:
        ref = integrate(
            RigidBody, (0.0, Tv), {"Q": Q0, "M": M0}, lam=L, rtol=1e-13, atol=1e-13, t_eval=[Tv]
        )
        Qr, Mr = ref.y["Q"][-1], ref.y["M"][-1]

        def error(Q: Array, M: Array) -> float:
            return float(max(np.abs(Q - Qr).max(), np.abs(M - Mr).max()))

        runs: dict[str, Callable[[], Any]] = {}
        out: dict[str, dict[str, float]] = {}
        for name in names:
            order, fn = table[name]

            def err_at(n: int, fn: Callable[..., DiscreteFlowSolution] = fn) -> float:
                sol = fn(Q0, M0, L, Tv / n, n)
                return error(sol.y["Q"][-1], sol.y["M"][-1]) if sol.success else np.inf

            n = max(4, int(np.ceil(4 * Tv)))
            e = err_at(n)
            while not np.isfinite(e):
                n *= 2
                e = err_at(n)
            n = max(1, int(np.ceil(n * (e / tgt) ** (1.0 / order) * 0.97)))
            e = err_at(n)
            while e > tgt:
                n = int(np.ceil(n * 1.05))
                e = err_at(n)
            out[name] = {"steps": float(n), "h": Tv / n, "error": e}
            runs[name] = functools.partial(fn, Q0, M0, L, Tv / n, n)

        k = 16
        while True:
            tol = 10.0 ** (-k / 4)
            sol = integrate(
                RigidBody, (0.0, Tv), {"Q": Q0, "M": M0}, lam=L, rtol=tol, atol=tol, t_eval=[Tv]
            )
            e = error(sol.y["Q"][-1], sol.y["M"][-1])
            if e <= tgt or k >= 52:
                break
            k += 1
        out["DOP853"] = {"steps": float(sol.nfev), "h": tol, "error": e}
        runs["DOP853"] = functools.partial(
            integrate,
            RigidBody,
            (0.0, Tv),
            {"Q": Q0, "M": M0},
            lam=L,
            rtol=tol,
            atol=tol,
            t_eval=[Tv],
        )

        times: dict[str, list[float]] = {name: [] for name in runs}
        for _ in range(repeats):
            for name, run in runs.items():
                t0 = time.process_time()
                run()
                times[name].append(time.process_time() - t0)
    base = float(np.median(times["DOP853"]))
    for name, ts in times.items():
        out[name]["seconds"] = float(np.median(ts))
        out[name]["ratio"] = out[name]["seconds"] / base if base > 0 else np.inf
    return out
