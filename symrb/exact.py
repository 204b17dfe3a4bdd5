r"""The exact free rigid body for n = 3: body momentum by Jacobi elliptic functions, attitude by an
elliptic integral of the third kind (Celledoni, Fassò, Säfström and Zanna, "The exact computation
of the free rigid body motion and its use in splitting methods", SIAM J. Sci. Comput. 30, 2008).

The equations are those of :class:`symrb.RigidBody` for n = 3,

.. math::

    \dot Q = Q\Omega,\qquad \dot M = [M, \Omega],\qquad M = J(\Omega) = \Lambda\Omega + \Omega\Lambda,

which for :math:`m = \operatorname{vee}(M)`, :math:`\omega = \operatorname{vee}(\Omega)` are
Euler's equations :math:`\dot m = m\times\omega`, :math:`\omega_i = m_i/I_i`, with the principal
moments :math:`I_1 = \lambda_2+\lambda_3` (cyclic; :func:`symrb.inertia_from_lam`).  The spatial
momentum :math:`\pi = Qm` is constant.

**Body momentum.**  With :math:`2E = \sum_i m_i^2/I_i` and :math:`\mu = |m|`, relabel the axes by
a signed permutation :math:`R \in SO(3)` (:math:`m' = Rm`, moments :math:`a = (a_1, a_2, a_3)`)
so that :math:`a_2` is the middle moment and :math:`m'` circles axis 3 (:math:`a_3` is the
largest moment when :math:`\mu^2 > 2Ea_2`, the smallest when :math:`\mu^2 < 2Ea_2`), with
:math:`m'_1(0), m'_3(0) \ge 0`.  Let :math:`\sigma = \operatorname{sign}(a_3 - a_1)` and

.. math::

    d_1 = \mu^2 - 2Ea_1 = \frac{a_2-a_1}{a_2}m_2'^2 + \frac{a_3-a_1}{a_3}m_3'^2,\qquad
    d_3 = 2Ea_3 - \mu^2 = \frac{a_3-a_1}{a_1}m_1'^2 + \frac{a_3-a_2}{a_2}m_2'^2

(sums of terms of one sign, so no cancellation).  Then

.. math::

    m'(t) = \Bigl(\sqrt{\tfrac{a_1|d_3|}{|a_3-a_1|}}\operatorname{cn}\tau,\;
    \sigma\sqrt{\tfrac{a_2|d_3|}{|a_3-a_2|}}\operatorname{sn}\tau,\;
    \sqrt{\tfrac{a_3|d_1|}{|a_3-a_1|}}\operatorname{dn}\tau\Bigr),\qquad
    \tau = \nu t + \tau_0,

    \nu^2 = \frac{|d_1||a_3-a_2|}{a_1a_2a_3},\qquad
    k^2 = \frac{|a_2-a_1||d_3|}{|a_3-a_2||d_1|} \le 1,

with :math:`\tau_0 = F(\varphi_0\,|\,k^2)` from the initial data.

**Attitude.**  Let :math:`B(t) \in SO(3)` be the rotation with rows :math:`u, v, m'/\mu`,
:math:`v = (-m_2', m_1', 0)/\rho`, :math:`u = (m_1'm_3', m_2'm_3', -\rho^2)/(\mu\rho)`,
:math:`\rho^2 = m_1'^2 + m_2'^2` (so :math:`Bm' = \mu e_3`).  Then
:math:`Q(t) = Q_0R^TB(0)^TR_z(\psi(t))B(t)R` with :math:`R_z(\psi) = \exp(\psi\,\hat e_3)` and
:math:`\dot\psi = \mu(2E - m_3'^2/a_3)/\rho^2`, whose integral is

.. math::

    \psi(t) = \frac{\mu t}{a_1} + \gamma\,[Z(\tau) - Z(\tau_0)],\qquad
    \gamma = -\sigma\frac{\mu|a_3-a_1||a_2-a_1|}{a_1^2|a_3-a_2|\,\nu},\qquad
    Z(u) = \int_0^u\frac{\operatorname{sn}^2 s\,ds}{1 - n\operatorname{sn}^2 s},\quad
    n = -\frac{a_3|a_2-a_1|}{a_1|a_3-a_2|},

so that :math:`\Pi(n; \operatorname{am}u\,|\,k^2) = u + nZ(u)`.  On :math:`|u| \le K`,
:math:`Z(u) = \tfrac13\operatorname{sn}^3u\,R_J(\operatorname{cn}^2u, \operatorname{dn}^2u, 1,
1 - n\operatorname{sn}^2u)` (Carlson), and :math:`Z(u + 2K) = Z(u) + 2Z(K)`; the cost does not
grow with :math:`t`.

**Steady rotations.**  When :math:`m(0)` is an eigenvector of the inertia (zero momentum, a sphere,
or :math:`m(0)` on a principal axis or in an eigenspace of a symmetric body) the solution is
:math:`M(t) = M_0`, :math:`Q(t) = Q_0\exp(t\Omega_0)` and is computed so.  The separatrix
(:math:`k^2 = 1`) needs no special case except its saddle (:math:`m` on the middle axis, a steady
rotation); there ``ellipj`` uses :math:`\operatorname{sn} = \tanh`,
:math:`\operatorname{cn} = \operatorname{dn} = \operatorname{sech}`, accurate while
:math:`\nu|t| \lesssim 700`.  Near the separatrix the motion itself is ill-conditioned (the error of
any method grows like :math:`\log(1/(1-k^2))`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import ellipj, ellipk, elliprf, elliprj

from . import _validate as v
from ._results import Trajectory
from ._validate import Array
from .algebra import _Jinv_weights, hat, inertia_from_lam, vee
from .errors import InputError

__all__ = ["ExactSolution", "rigid_body_exact"]


@dataclass
class ExactSolution:
    r"""Result of :func:`rigid_body_exact` (modelled on :class:`symrb.FlowSolution`).

    Attributes
    ----------
    t : ndarray, shape (K,)
        The output times.
    y : Trajectory
        ``Q``, ``M`` and ``Omega`` :math:`= J^{-1}(M)`, each of shape ``(K, ..., 3, 3)``.
    k2 : ndarray, shape (...)
        The parameter :math:`m = k^2` of the Jacobi elliptic functions (0 for a symmetric body,
        1 on the separatrix; 0 for a steady rotation).
    nu : ndarray, shape (...)
        The rate :math:`\nu` of the elliptic argument :math:`\tau = \nu t + \tau_0`; the body
        momentum has period :math:`4K(k^2)/\nu` (0 for a steady rotation).
    axis : ndarray of int, shape (...)
        The principal axis (0, 1, 2, in the order of ``lam``) about which the body momentum
        circles (its component along it never changes sign), or -1 for a steady rotation.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> from symrb.exact import rigid_body_exact
    >>> sol = rigid_body_exact(np.eye(3), symrb.hat([0.5, 1.0, 1.5]), [0.7, 1.1, 1.6], [0, 1, 2])
    >>> sol.t, sol.y.Q.shape, int(sol.axis)
    (array([0., 1., 2.]), (3, 3, 3), 2)
    """

    t: Array
    y: Trajectory
    k2: Array
    nu: Array
    axis: np.ndarray


def _rotation_exp(w: Array) -> Array:
    r""":math:`\exp(\hat w)` by Rodrigues' formula, ``w`` of shape (..., 3)."""
    th = np.linalg.norm(w, axis=-1)[..., None, None]
    W = hat(w)
    a = np.sinc(th / np.pi)  # sin(th) / th
    b = 0.5 * np.sinc(th / (2 * np.pi)) ** 2  # (1 - cos th) / th^2
    return np.eye(3) + a * W + b * (W @ W)


def _frame(m: Array) -> Array:
    r"""The rotation :math:`B` with rows :math:`u, v, m/|m|` (needs :math:`m_1^2 + m_2^2 > 0`)."""
    m1, m2, m3 = m[..., 0], m[..., 1], m[..., 2]
    mu = np.linalg.norm(m, axis=-1)
    rho = np.hypot(m1, m2)
    zero = np.zeros_like(m1)
    u = np.stack([m1 * m3 / rho, m2 * m3 / rho, -rho], axis=-1) / mu[..., None]
    vv = np.stack([-m2 / rho, m1 / rho, zero], axis=-1)
    return np.stack([u, vv, m / mu[..., None]], axis=-2)


def _working_frame(inertia: Array, m: Array) -> tuple[Array, Array, np.ndarray]:
    """The signed permutation R (det +1), the moments a in the new order and the axis circled."""
    order = np.argsort(inertia, axis=-1, kind="stable")
    b = np.take_along_axis(inertia, order, axis=-1)
    ms = np.take_along_axis(m, order, axis=-1)
    # d2 = 2 E b2 - mu^2: negative when m circles the largest axis, positive for the smallest
    d2 = (
        ms[..., 0] ** 2 * (b[..., 1] - b[..., 0]) / b[..., 0]
        - ms[..., 2] ** 2 * (b[..., 2] - b[..., 1]) / b[..., 2]
    )
    largest = (d2 < 0) | ((d2 == 0) & (b[..., 2] - b[..., 1] >= b[..., 1] - b[..., 0]))
    perm = np.where(largest[..., None], order, order[..., ::-1])
    even = (perm[..., 1] - perm[..., 0]) % 3 == 1
    P = np.eye(3)[perm]  # rows e_{perm_i}: (P m)_i = m_{perm_i}
    P[..., 1, :] *= np.where(even, 1.0, -1.0)[..., None]
    mp = np.einsum("...ij,...j->...i", P, m)
    s1 = np.where(mp[..., 0] < 0, -1.0, 1.0)
    s3 = np.where(mp[..., 2] < 0, -1.0, 1.0)
    R = np.stack([s1, s1 * s3, s3], axis=-1)[..., :, None] * P
    a = np.take_along_axis(inertia, perm, axis=-1)
    return R, a, perm[..., 2]


def rigid_body_exact(Q0: ArrayLike, M0: ArrayLike, lam: ArrayLike, t: ArrayLike) -> ExactSolution:
    r"""The exact solution :math:`Q(t), M(t)` of the rigid body :math:`\dot Q = Q\Omega`,
    :math:`\dot M = [M,\Omega]`, :math:`M = J(\Omega)`, for n = 3.

    The body momentum is given by Jacobi elliptic functions and the attitude by an elliptic
    integral of the third kind (formulas in :mod:`symrb.exact`; Celledoni, Fassò, Säfström and
    Zanna 2008), evaluated with :func:`scipy.special.ellipj`, :func:`~scipy.special.ellipk`,
    :func:`~scipy.special.elliprf` and :func:`~scipy.special.elliprj`.  The cost of each time is
    the same for every :math:`t` (no time stepping).

    Parameters
    ----------
    Q0 : array_like, shape (..., 3, 3)
        The initial attitude, in SO(3).
    M0 : array_like, shape (..., 3, 3)
        The initial body momentum, skew-symmetric.
    lam : array_like, shape (..., 3)
        The diagonal of :math:`\Lambda`, with :math:`\lambda_i+\lambda_j>0` for :math:`i\ne j`
        (positive principal moments :math:`I_1 = \lambda_2+\lambda_3`, cyclic).  Batch axes of
        ``Q0``, ``M0`` and ``lam`` broadcast.
    t : array_like, shape (K,) or scalar
        The times (any real values, in any order; a scalar is read as one time).

    Returns
    -------
    ExactSolution
        ``t`` of shape (K,); ``y.Q``, ``y.M``, ``y.Omega`` of shape ``(K, ..., 3, 3)``; the
        elliptic parameter ``k2``, the rate ``nu`` and the ``axis`` circled, per batch item.

    Raises
    ------
    InputError
        If n != 3, ``Q0`` is not in SO(3), ``M0`` is not skew-symmetric, ``lam`` has a
        non-positive :math:`\lambda_i+\lambda_j`, the batch shapes do not broadcast, or ``t`` is
        not a finite scalar or 1-D array.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> from symrb.exact import rigid_body_exact
    >>> lam = np.array([0.7, 1.1, 1.6])
    >>> M0 = symrb.hat([0.5, 1.0, 1.5])
    >>> sol = rigid_body_exact(np.eye(3), M0, lam, np.linspace(0, 100, 5))
    >>> ref = symrb.integrate(symrb.RigidBody, (0, 100), {"Q": np.eye(3), "M": M0}, lam=lam,
    ...                       rtol=1e-13, atol=1e-13, t_eval=sol.t)
    >>> bool(np.abs(sol.y.Q - ref.y.Q).max() < 1e-9 and np.abs(sol.y.M - ref.y.M).max() < 1e-9)
    True
    >>> float(np.ptp(symrb.kinetic_energy(sol.y.M, lam))) < 1e-14
    True
    """
    L = v.inertia(lam)
    if L.shape[-1] != 3:
        raise InputError(
            f"rigid_body_exact is for n = 3: lam must have shape (..., 3), got {L.shape}"
        )
    Qa = v.orthogonal(Q0, "Q0", 3)
    Ma = v.skew(M0, "M0", 3)
    tt = v.as_float_array(t, "t")
    if tt.ndim > 1:
        raise InputError(f"t must be a scalar or a 1-D array of times, got shape {tt.shape}")
    tt = np.atleast_1d(tt)
    try:
        batch = np.broadcast_shapes(Qa.shape[:-2], Ma.shape[:-2], L.shape[:-1])
    except ValueError as exc:
        raise InputError(f"Q0, M0 and lam batch shapes do not broadcast: {exc}") from None
    Qa = np.broadcast_to(Qa, batch + (3, 3))
    Ma = np.broadcast_to(Ma, batch + (3, 3))
    L = np.broadcast_to(L, batch + (3,))

    inertia = inertia_from_lam(L)
    m0 = vee(Ma)
    R, a, axis = _working_frame(inertia, m0)
    mp = np.einsum("...ij,...j->...i", R, m0)
    a1, a2, a3 = a[..., 0], a[..., 1], a[..., 2]
    x1, x2, x3 = mp[..., 0], mp[..., 1], mp[..., 2]
    mu = np.linalg.norm(m0, axis=-1)
    d1 = x2**2 * (a2 - a1) / a2 + x3**2 * (a3 - a1) / a3
    d3 = x1**2 * (a3 - a1) / a1 + x2**2 * (a3 - a2) / a2
    # steady rotations: m0 an eigenvector of the inertia (m0 = 0, a sphere, m0 on the middle
    # axis (the saddle), or d1 = 0 or d3 = 0: m0 in the eigenspace of a1 or a3)
    steady = (mu == 0) | (a1 == a3) | ((x1 == 0) & (x3 == 0)) | (d1 == 0) | (d3 == 0)
    ok = ~steady

    # dummy values on the steady items keep the formulas finite there (their results are replaced)
    def safe(x: Array, fill: float = 1.0) -> Array:
        return np.where(ok, x, fill)

    a1s, a2s, a3s = safe(a1, 1.0), safe(a2, 2.0), safe(a3, 3.0)
    d1s, d3s, mus = np.abs(safe(d1)), np.abs(safe(d3)), safe(mu)
    sigma = np.sign(a3s - a1s)
    h21, h31, h32 = np.abs(a2s - a1s), np.abs(a3s - a1s), np.abs(a3s - a2s)
    c1 = np.sqrt(a1s * d3s / h31)
    c2 = np.sqrt(a2s * d3s / h32)
    c3 = np.sqrt(a3s * d1s / h31)
    nu = np.sqrt(d1s * h32 / (a1s * a2s * a3s))
    k2 = np.minimum(1.0, h21 * d3s / (h32 * d1s))
    n = -a3s * h21 / (a1s * h32)
    gamma = -sigma * mus * h31 * h21 / (a1s**2 * h32 * nu)

    # the initial phase: sn(tau0) = s0, cn(tau0) = c0 >= 0, tau0 = F(asin s0 | k2)
    y, x = sigma * safe(x2, 0.0) * np.sqrt(a1s / h31), safe(x1) * np.sqrt(a2s / h32)
    h = np.hypot(x, y)
    s0, c0 = y / h, x / h
    dn0sq = 1.0 - k2 * s0**2
    tau0 = s0 * elliprf(c0**2, dn0sq, 1.0)
    Z0 = s0**3 * elliprj(c0**2, dn0sq, 1.0, 1.0 - n * s0**2) / 3.0

    T = tt.reshape((-1,) + (1,) * len(batch))
    tau = nu * T + tau0
    K = ellipk(k2)
    # reduce tau modulo the period 4K (scipy's dn loses digits like eps * tau otherwise); on the
    # separatrix K = inf and nothing is reduced
    j4 = np.round(tau / (4 * K))
    with np.errstate(invalid="ignore"):  # 0 * inf on the separatrix, not selected
        r = np.where(j4 == 0, tau, tau - 4 * K * j4)
    sn, cn, dn, _ = ellipj(r, k2)
    j = 2 * j4 + np.round(r / (2 * K))  # tau = 2 K j + (a remainder in [-K, K])
    ZK = elliprj(0.0, 1.0 - k2, 1.0, 1.0 - n) / 3.0
    with np.errstate(invalid="ignore"):  # 0 * inf on the separatrix, not selected
        periods = np.where(j == 0, 0.0, 2 * j * ZK)
    Zt = (
        periods
        + np.where(j % 2 == 0, 1.0, -1.0)
        * sn**3
        * elliprj(cn**2, dn**2, 1.0, 1.0 - n * sn**2)
        / 3.0
    )
    psi = mus * T / a1s + gamma * (Zt - Z0)

    mt = np.stack([c1 * cn, sigma * c2 * sn, c3 * dn], axis=-1)  # (K, ..., 3) working frame
    mp0 = np.stack([c1 * c0, sigma * c2 * s0, c3 * np.sqrt(dn0sq)], axis=-1)
    cpsi, spsi = np.cos(psi), np.sin(psi)
    zero, one = np.zeros_like(psi), np.ones_like(psi)
    Rz = np.stack(
        [
            np.stack([cpsi, -spsi, zero], axis=-1),
            np.stack([spsi, cpsi, zero], axis=-1),
            np.stack([zero, zero, one], axis=-1),
        ],
        axis=-2,
    )
    Rt = np.swapaxes(R, -1, -2)
    G = Qa @ Rt @ np.swapaxes(_frame(mp0), -1, -2)
    Q = G @ Rz @ _frame(mt) @ R
    m = np.einsum("...ji,...j->...i", R, mt)  # R^T m'

    # steady rotations: M constant, Q = Q0 exp(t Omega0)
    w0 = m0 / inertia
    Qs = Qa @ _rotation_exp(T[..., None] * w0)
    st = np.broadcast_to(steady, Q.shape[:-2])
    Q = np.where(st[..., None, None], Qs, Q)
    M = np.where(st[..., None, None], Ma, hat(m))
    y_out = Trajectory(Q=Q, M=M, Omega=_Jinv_weights(L) * M)
    return ExactSolution(
        t=tt,
        y=y_out,
        k2=np.where(ok, k2, 0.0),
        nu=np.where(ok, nu, 0.0),
        axis=np.where(ok, axis, -1),
    )
