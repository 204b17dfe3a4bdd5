r"""Base steps of the rigid body (continuous-scale momenta): MV-Algorithm 2 at step ``h``, the
implicit midpoint rule and RKMK4.

A *base step* is any object with a method ``step(Q, M, h) -> (Q, M)`` that advances by a real
``h`` of either sign (compositions of order 4 and more take negative substeps); :class:`MVStep`
and :class:`MidpointStep` are symmetric and of order 2, :class:`RKMK4Step` is explicit, of
order 4 and not symmetric.  The flows built on them are in :mod:`symrb.compose`.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
import scipy.linalg as sla
from numpy.typing import ArrayLike

from . import _validate as v
from ._docs import fill
from ._validate import Array
from .errors import NotConvergedError
from .solvers import solve_moser_veselov

__all__ = ["MVStep", "MidpointStep", "RKMK4Step"]

_EPS = float(np.finfo(float).eps)


# ---------------------------------------------------------------------------------------------
# base steps


class BaseStep(Protocol):
    """What a base step provides: ``step(Q, M, h) -> (Q, M)`` (continuous-scale momenta)."""

    def step(self, Q: Array, M: Array, h: float) -> tuple[Array, Array]: ...  # pragma: no cover


def _skew(a: Array) -> Array:
    return 0.5 * (a - np.swapaxes(a, -1, -2))


def _lam(lam: ArrayLike) -> Array:
    return np.array(v.inertia(lam, positive=True), dtype=float)


@fill
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
    %(lam_positive)s

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> from symrb.base_steps import MVStep
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


@fill
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
    %(lam_positive)s
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
    >>> from symrb.base_steps import MidpointStep
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


@fill
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
    %(lam_positive)s

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> from symrb.base_steps import RKMK4Step
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
