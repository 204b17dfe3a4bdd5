r"""Discrete rigid body flows (paper, Section 2): the symmetric representation and Moser-Veselov.

Three maps, each implemented from its own equations and sharing only the solver of
:math:`J_D(U) = U\Lambda - \Lambda U^T = M` (:func:`symrb.solve_moser_veselov`):

* the symmetric representation (eqs. discrbopteqns1, Ukdef1):
  :math:`J_D(U_k) = h\,(Q_k^TP_k - P_k^TQ_k)`, :math:`Q_{k+1} = Q_kU_k`, :math:`P_{k+1} = P_kU_k`;
* MV-Algorithm 1, :math:`(Q_k, Q_{k+1}) \mapsto (Q_{k+1}, Q_{k+2})` (eqs. mv1-mv3);
* MV-Algorithm 2, :math:`(Q_k, M_k) \mapsto (Q_{k+1}, M_{k+1})` (eqs. mv1-mv3).

Time step.  A discrete momentum is :math:`h` times the continuous one.  In the symmetric
representation ``P`` is on the continuous scale (:math:`Q^TP - P^TQ \approx M(t_k)`, so
``P0 = Q0 @ (M0 / 2)`` starts at the body momentum ``M0``) and :math:`h` multiplies it.  The
Moser-Veselov maps take discrete momenta as the paper does, :math:`M^{MV}_{k+1} = hM(t_k)`: with
the paper's indices (:math:`\Omega_k = Q_k^TQ_{k-1}`) the momentum :math:`M_{k+1}` belongs to the
step from :math:`Q_k` (claim D12: :math:`M_{k+1} = Q_k^TP_k - P_k^TQ_k`).  With this scaling each
map is a second-order approximation of the rigid body flow :math:`\dot Q = Q\Omega`,
:math:`\dot M = [M, \Omega]` at step :math:`h` (a symmetric variational integrator; measured in the
book and the tests).

Long runs: each step starts Newton from the previous :math:`U` (it changes by :math:`O(h^2)`), and
only every ``save_every``-th state is kept.  Arrays are batched: ``(..., n, n)``; the time axis of
the outputs comes first.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from . import _validate as v
from ._generated import discrete_rigid_body as _gen
from ._generated import symmetric_rigid_body as _srb
from ._validate import Array
from .errors import InputError
from .solvers import _EPS, _solve_batch, _warm_single

__all__ = [
    "jd_residual",
    "symmetric_step",
    "symmetric_flow",
    "mv_algorithm1",
    "mv_algorithm2",
    "discrete_rigid_body_flow",
]

_MAXITER = 30


def jd_residual(U: ArrayLike, M: ArrayLike, lam: ArrayLike) -> Array:
    r""":math:`U\Lambda - \Lambda U^T - M` (zero when ``U`` solves eq. Ukdef1 / mv2 for ``M``)."""
    L = v.inertia(lam, positive=True)
    nn = L.shape[-1]
    return _gen.jd(v.square(U, "U", nn), L) - v.skew(M, "M", nn)


def _check_steps(steps: int, save_every: int) -> tuple[int, int]:
    if int(steps) != steps or steps < 0:
        raise InputError(f"steps must be an integer >= 0, got {steps!r}")
    if int(save_every) != save_every or save_every < 1:
        raise InputError(f"save_every must be an integer >= 1, got {save_every!r}")
    return int(steps), int(save_every)


def _check_h(h: float) -> float:
    if not (np.isfinite(h) and h > 0):
        raise InputError(f"h must be a finite number > 0, got {h!r}")
    return float(h)


class _Stepper:
    """Solves J_D(U) = M on a flat batch, warm-starting from the previous solution."""

    def __init__(self, lam: Array, batch: tuple[int, ...]) -> None:
        nn = lam.shape[-1]
        self.lam = np.broadcast_to(lam, batch + (nn,)).reshape(-1, nn)
        self.U: Array | None = None
        self.U_prev: Array | None = None
        self.iterations = 0

    def solve(self, M: Array) -> Array:
        Mf = M.reshape(self.lam.shape[0], *M.shape[-2:])
        Mf = 0.5 * (Mf - np.swapaxes(Mf, -1, -2))  # rounding leaves M skew only to ~eps
        tol = 10.0 * _EPS * np.sqrt(np.einsum("bij,bij->b", Mf, Mf))
        if self.U is not None and Mf.shape[0] == 1:
            guess = self.U[0]
            if self.U_prev is not None:
                # U changes smoothly along a run: extrapolate U_k (U_{k-1}^T U_k) (orthogonal)
                guess = guess @ (self.U_prev[0].T @ guess)
                # one Newton-Schulz step back to SO(n), so rounding errors in U^T U - I do not
                # compound from step to step
                guess = guess @ (1.5 * np.eye(guess.shape[-1]) - 0.5 * (guess.T @ guess))
            got = _warm_single(guess, Mf[0], self.lam[0], float(tol[0]), _MAXITER)
            if got is not None:
                self.U_prev = self.U
                self.U = got[0][None]
                self.iterations += got[1]
                return got[0].reshape(M.shape)
        U, it, _res, _margin, _start = _solve_batch(Mf, self.lam, tol, _MAXITER, self.U)
        self.U_prev, self.U = self.U, U
        self.iterations += int(it.sum())
        return U.reshape(M.shape)


def _prepare(
    lam: ArrayLike, *mats: tuple[ArrayLike, str, str]
) -> tuple[Array, list[Array], tuple[int, ...]]:
    L = v.inertia(lam, positive=True)
    nn = L.shape[-1]
    arrays = []
    for x, name, kind in mats:
        if kind == "SO":
            arrays.append(v.orthogonal(x, name, nn))
        elif kind == "skew":
            arrays.append(v.skew(x, name, nn))
        else:
            arrays.append(v.square(x, name, nn))
    batch = np.broadcast_shapes(L.shape[:-1], *[a.shape[:-2] for a in arrays])
    arrays = [np.broadcast_to(a, batch + (nn, nn)).copy() for a in arrays]
    return L, arrays, batch


def symmetric_step(
    Q: ArrayLike, P: ArrayLike, lam: ArrayLike, h: float = 1.0
) -> tuple[Array, Array, Array]:
    r"""One step of the symmetric representation (eqs. discrbopteqns1, Ukdef1).

    Solves :math:`U\Lambda - \Lambda U^T = h(Q^TP - P^TQ)` on the branch through the identity and
    returns :math:`(QU, PU, U)`.

    Parameters
    ----------
    Q : array (..., n, n) in SO(n)
    P : array (..., n, n), the costate (any square matrix; continuous scale, see module docstring)
    lam : array (..., n), positive
    h : time step > 0 (``h = 1`` is the paper's map)
    """
    h = _check_h(h)
    L, (Qa, Pa), batch = _prepare(lam, (Q, "Q", "SO"), (P, "P", "square"))
    U = _Stepper(L, batch).solve(h * _srb.symmetric_momentum(Qa, Pa))
    return Qa @ U, Pa @ U, U


def symmetric_flow(
    Q0: ArrayLike,
    P0: ArrayLike,
    lam: ArrayLike,
    h: float,
    steps: int,
    *,
    save_every: int = 1,
) -> tuple[Array, Array]:
    r"""Iterate the symmetric representation ``steps`` times from :math:`(Q_0, P_0)`.

    Returns ``(Q, P)`` of shape ``(K, ..., n, n)`` with :math:`K = \lfloor steps/save\_every\rfloor + 1`:
    the states :math:`k = 0, s, 2s, \dots` (``s = save_every``).  The body momentum at step k is
    :math:`Q_k^TP_k - P_k^TQ_k` (continuous scale); :func:`discrete_rigid_body_flow` returns it.
    """
    h = _check_h(h)
    steps, save_every = _check_steps(steps, save_every)
    L, (Q, P), batch = _prepare(lam, (Q0, "Q0", "SO"), (P0, "P0", "square"))
    stepper = _Stepper(L, batch)
    Qs, Ps = [Q.copy()], [P.copy()]
    for k in range(1, steps + 1):
        U = stepper.solve(h * _srb.symmetric_momentum(Q, P))
        Q, P = Q @ U, P @ U
        if k % save_every == 0:
            Qs.append(Q)
            Ps.append(P)
    return np.stack(Qs), np.stack(Ps)


def mv_algorithm1(
    Q0: ArrayLike, Q1: ArrayLike, lam: ArrayLike, steps: int, *, save_every: int = 1
) -> Array:
    r"""MV-Algorithm 1: :math:`(Q_k, Q_{k+1}) \mapsto (Q_{k+1}, Q_{k+2})`.

    Each step: :math:`\Omega_{k+1} = Q_{k+1}^TQ_k` (mv1), :math:`M_{k+1} = \Omega_{k+1}^T\Lambda -
    \Lambda\Omega_{k+1}` (mv2), :math:`M_{k+2} = \Omega_{k+1}M_{k+1}\Omega_{k+1}^T` (mv3), solve mv2
    for :math:`\Omega_{k+2}`, then :math:`Q_{k+2} = Q_{k+1}\Omega_{k+2}^T` (mv1).

    Returns the configurations :math:`Q_0, Q_s, Q_{2s}, \dots` up to :math:`Q_{steps+1}`, shape
    ``(K, ..., n, n)``, ``K = floor((steps + 1)/save_every) + 1``.  For step h, start from
    :math:`Q_1 \approx Q(h)`.
    """
    steps, save_every = _check_steps(steps, save_every)
    L, (Qa, Qb), batch = _prepare(lam, (Q0, "Q0", "SO"), (Q1, "Q1", "SO"))
    stepper = _Stepper(L, batch)
    out = [Qa.copy()]
    if save_every == 1:
        out.append(Qb.copy())
    Lb = np.broadcast_to(L, batch + L.shape[-1:])
    for k in range(2, steps + 2):
        Om = np.swapaxes(Qb, -1, -2) @ Qa
        M = _gen.mv_momentum(Om, Lb)
        M_next = _gen.mv_transport(Om, M)
        U = stepper.solve(M_next)  # U = Omega_{k}^T
        Qa, Qb = Qb, Qb @ U
        if k % save_every == 0:
            out.append(Qb)
    return np.stack(out)


def mv_algorithm2(
    Q: ArrayLike, M: ArrayLike, lam: ArrayLike, steps: int, *, save_every: int = 1
) -> tuple[Array, Array]:
    r"""MV-Algorithm 2: :math:`(Q_k, M_k) \mapsto (Q_{k+1}, M_{k+1})` (discrete momenta).

    Each step: solve mv2 :math:`M_k = \Omega_k^T\Lambda - \Lambda\Omega_k` for :math:`\Omega_k`,
    :math:`M_{k+1} = \Omega_kM_k\Omega_k^T` (mv3), solve mv2 for :math:`\Omega_{k+1}`,
    :math:`Q_{k+1} = Q_k\Omega_{k+1}^T` (mv1).  The solution for :math:`\Omega_{k+1}` is the next
    step's :math:`\Omega_k` (same equation), so one solve per step.

    Returns ``(Q, M)`` at :math:`k = 0, s, 2s, \dots`, shape ``(K, ..., n, n)``.  ``M`` is the
    discrete momentum; with the paper's indices :math:`M_k \approx hM(t_{k-1})` (module docstring).
    """
    steps, save_every = _check_steps(steps, save_every)
    L, (Qk, Mk), batch = _prepare(lam, (Q, "Q", "SO"), (M, "M", "skew"))
    stepper = _Stepper(L, batch)
    Qs, Ms = [Qk.copy()], [Mk.copy()]
    Om = np.swapaxes(stepper.solve(Mk), -1, -2)  # Omega_k from mv2
    for k in range(1, steps + 1):
        Mk = _gen.mv_transport(Om, Mk)  # mv3
        Om = np.swapaxes(stepper.solve(Mk), -1, -2)  # Omega_{k+1} from mv2
        Qk = Qk @ np.swapaxes(Om, -1, -2)  # mv1: Q_{k+1} = Q_k Omega_{k+1}^T
        if k % save_every == 0:
            Qs.append(Qk)
            Ms.append(Mk)
    return np.stack(Qs), np.stack(Ms)


def discrete_rigid_body_flow(
    Q0: ArrayLike,
    M0: ArrayLike,
    lam: ArrayLike,
    h: float,
    steps: int,
    *,
    save_every: int = 1,
) -> tuple[Array, Array, Array]:
    r"""The discrete rigid body at step ``h`` from the body momentum ``M0`` (continuous scale).

    Runs :func:`symmetric_flow` from :math:`P_0 = Q_0M_0/2` (so :math:`Q_0^TP_0 - P_0^TQ_0 = M_0`;
    this costate is not orthogonal, but every costate with the same :math:`M_0`, e.g. the one in
    :math:`SO(n)`, :math:`Q_0\exp(\sinh^{-1}(M_0/2))`, gives the same :math:`Q_k`, claim D7)
    and returns ``(t, Q, M)`` with :math:`t_k = kh` and :math:`M_k = Q_k^TP_k - P_k^TQ_k`, a
    second-order approximation of :math:`(Q(t_k), M(t_k))` of :math:`\dot Q = Q\Omega`,
    :math:`\dot M = [M,\Omega]`, :math:`\Omega = J^{-1}(M)`.
    """
    h = _check_h(h)
    steps, save_every = _check_steps(steps, save_every)
    L, (Q, M), batch = _prepare(lam, (Q0, "Q0", "SO"), (M0, "M0", "skew"))
    Qs, Ps = symmetric_flow(Q, Q @ (0.5 * M), L, h, steps, save_every=save_every)
    t = h * save_every * np.arange(Qs.shape[0], dtype=float)
    return t, Qs, np.asarray(_srb.symmetric_momentum(Qs, Ps), dtype=float)
