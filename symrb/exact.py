r"""The exact free rigid body for n = 3: body momentum by Jacobi elliptic functions, attitude by an
elliptic integral of the third kind (Celledoni, Fassò, Säfström and Zanna, "The exact computation
of the free rigid body motion and its use in splitting methods", SIAM J. Sci. Comput. 30, 2008).

The equations are those of :class:`symrb.RigidBody` for n = 3,

.. math::

    \dot Q = Q\Omega,\qquad \dot M = [M, \Omega],\qquad M = J(\Omega) = \Lambda\Omega + \Omega\Lambda,

which for :math:`m = \operatorname{vee}(M)`, :math:`\omega = \operatorname{vee}(\Omega)` are
Euler's equations :math:`\dot m = m\times\omega`, :math:`\omega_i = m_i/I_i`, with the principal
moments :math:`I_1 = \lambda_2+\lambda_3` (cyclic; :func:`symrb.algebra.inertia_from_lam`).  The spatial
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

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import ellipj, ellipk, elliprf, elliprj

from . import _validate as v
from ._results import Trajectory
from ._validate import Array
from .algebra import _Jinv_weights
from .errors import InputError, OutOfDomainError

__all__ = ["ExactSolution", "rigid_body_exact"]


@dataclass
class ExactSolution:
    r"""Result of :func:`rigid_body_exact` (modelled on :class:`symrb.continuous.FlowSolution`).

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


_EPS = np.zeros((3, 3, 3))
_EPS[0, 1, 2] = _EPS[1, 2, 0] = _EPS[2, 0, 1] = 1.0
_EPS[0, 2, 1] = _EPS[2, 1, 0] = _EPS[1, 0, 2] = -1.0
_SWAP = np.array([-1.0, 1.0, 0.0])


def _hat(w: Array) -> Array:
    """hat(w)_ij = -eps_ijk w_k (no validation; one einsum)."""
    return np.einsum("ijk,...k->...ij", -_EPS, w)


def _rotation_exp(w: Array) -> Array:
    r""":math:`\exp(\hat w)` by Rodrigues' formula, ``w`` of shape (..., 3)."""
    th = np.linalg.norm(w, axis=-1)[..., None, None]
    W = _hat(w)
    a = np.sinc(th / np.pi)  # sin(th) / th
    b = 0.5 * np.sinc(th / (2 * np.pi)) ** 2  # (1 - cos th) / th^2
    return np.eye(3) + a * W + b * (W @ W)


def _turned_frame(m: Array, mu: Array, psi: Array | None = None) -> Array:
    r""":math:`R_z(\psi)B(m)`, where :math:`B` has rows :math:`u, v, m/\mu`,
    :math:`v = (-m_2, m_1, 0)/\rho`, :math:`u = v\times m/\mu = (m_1m_3, m_2m_3, -\rho^2)/(\mu\rho)`,
    :math:`\rho^2 = m_1^2 + m_2^2 > 0`; ``m`` of shape (..., 3), ``mu`` and ``psi`` (...)."""
    rho = np.hypot(m[..., 0], m[..., 1])[..., None]
    mu_ = mu[..., None]
    v = m[..., [1, 0, 2]] * _SWAP / rho
    u = np.concatenate([m[..., :2] * (m[..., 2:] / (mu_ * rho)), -rho / mu_], axis=-1)
    if psi is None:
        return np.stack([u, v, m / mu_], axis=-2)
    c, s = np.cos(psi)[..., None], np.sin(psi)[..., None]
    return np.stack([c * u - s * v, s * u + c * v, m / mu_], axis=-2)


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


#: One body and at most this many times take the scalar path (:func:`_one_body`).
_SCALAR_MAX_TIMES = 8


def _one_body(
    Qa: Array, Ma: Array, L: Array, tt: Array
) -> tuple[Array, Array, float, float, int] | None:
    """The formulas of :func:`rigid_body_exact` for one body on Python floats (the array code
    costs about 1 us per NumPy call on 3-vectors); None for a steady rotation (the array code
    handles it).  Returns (Q (K, 3, 3), M (K, 3, 3), k2, nu, axis)."""
    lam = [float(x) for x in L]
    inertia = [lam[1] + lam[2], lam[0] + lam[2], lam[0] + lam[1]]
    m0 = [float(Ma[2, 1]), float(Ma[0, 2]), float(Ma[1, 0])]
    order = sorted(range(3), key=inertia.__getitem__)  # stable, as np.argsort(kind="stable")
    b = [inertia[i] for i in order]
    ms = [m0[i] for i in order]
    d2 = ms[0] ** 2 * (b[1] - b[0]) / b[0] - ms[2] ** 2 * (b[2] - b[1]) / b[2]
    largest = d2 < 0 or (d2 == 0 and b[2] - b[1] >= b[1] - b[0])
    perm = order if largest else order[::-1]
    sgn = 1.0 if (perm[1] - perm[0]) % 3 == 1 else -1.0
    s1 = -1.0 if m0[perm[0]] < 0 else 1.0
    s3 = -1.0 if m0[perm[2]] < 0 else 1.0
    rs = (s1, s1 * s3 * sgn, s3)  # R[i, perm[i]] = rs[i]: the signed permutation
    x1, x2, x3 = (rs[i] * m0[perm[i]] for i in range(3))
    a1, a2, a3 = (inertia[i] for i in perm)
    mu = math.sqrt(m0[0] ** 2 + m0[1] ** 2 + m0[2] ** 2)
    d1 = x2**2 * (a2 - a1) / a2 + x3**2 * (a3 - a1) / a3
    d3 = x1**2 * (a3 - a1) / a1 + x2**2 * (a3 - a2) / a2
    if mu == 0 or a1 == a3 or (x1 == 0 and x3 == 0) or d1 == 0 or d3 == 0:
        return None
    sigma = 1.0 if a3 > a1 else -1.0
    h21, h31, h32 = abs(a2 - a1), abs(a3 - a1), abs(a3 - a2)
    d1, d3 = abs(d1), abs(d3)
    c = (
        math.sqrt(a1 * d3 / h31),
        sigma * math.sqrt(a2 * d3 / h32),
        math.sqrt(a3 * d1 / h31),
    )
    nu = math.sqrt(d1 * h32 / (a1 * a2 * a3))
    k2 = min(1.0, h21 * d3 / (h32 * d1))
    n = -a3 * h21 / (a1 * h32)
    gamma = -sigma * mu * h31 * h21 / (a1**2 * h32 * nu)
    y, x = sigma * x2 * math.sqrt(a1 / h31), x1 * math.sqrt(a2 / h32)
    hh = math.hypot(x, y)
    s0, c0 = y / hh, x / hh
    dn0sq = 1.0 - k2 * s0**2
    tau0 = s0 * float(elliprf(c0**2, dn0sq, 1.0))
    Z0 = s0**3 * float(elliprj(c0**2, dn0sq, 1.0, 1.0 - n * s0**2)) / 3.0
    K = min(float(ellipk(k2)), 1e300)
    ZK = min(float(elliprj(0.0, 1.0 - k2, 1.0, 1.0 - n)), 1e300) / 3.0
    R = np.zeros((3, 3))
    for i in range(3):
        R[i, perm[i]] = rs[i]
    mp0 = [c[0] * c0, c[1] * s0, c[2] * math.sqrt(dn0sq)]
    G = Qa @ R.T @ _frame(mp0, mu, 0.0).T
    Ks = len(tt)
    Q = np.empty((Ks, 3, 3))
    M = np.zeros((Ks, 3, 3))
    for i, t in enumerate(tt.tolist()):
        tau = nu * t + tau0
        j4 = round(tau / (4 * K))
        r = tau - 4 * K * j4
        sn, cn, dn, _ = (float(e) for e in ellipj(r, k2))
        j = 2 * j4 + round(r / (2 * K))
        sign = 1.0 - 2.0 * (j % 2)
        Zt = 2 * j * ZK + sign * sn**3 * float(elliprj(cn**2, dn**2, 1.0, 1.0 - n * sn**2)) / 3
        psi = mu * t / a1 + gamma * (Zt - Z0)
        mt = [c[0] * cn, c[1] * sn, c[2] * dn]
        Q[i] = G @ _frame(mt, mu, psi) @ R
        w = [0.0, 0.0, 0.0]  # R^T m'(t)
        for k in range(3):
            w[perm[k]] = rs[k] * mt[k]
        M[i, 2, 1], M[i, 0, 2], M[i, 1, 0] = w
        M[i, 1, 2], M[i, 2, 0], M[i, 0, 1] = -w[0], -w[1], -w[2]
    return Q, M, k2, nu, perm[2]


def _frame(m: list[float], mu: float, psi: float) -> Array:
    """:func:`_turned_frame` for one body on floats."""
    rho = math.hypot(m[0], m[1])
    v = (-m[1] / rho, m[0] / rho, 0.0)
    f = m[2] / (mu * rho)
    u = (m[0] * f, m[1] * f, -rho / mu)
    cp, sp = math.cos(psi), math.sin(psi)
    return np.array(
        [
            [cp * u[0] - sp * v[0], cp * u[1] - sp * v[1], cp * u[2] - sp * v[2]],
            [sp * u[0] + cp * v[0], sp * u[1] + cp * v[1], sp * u[2] + cp * v[2]],
            [m[0] / mu, m[1] / mu, m[2] / mu],
        ]
    )


def _exact_input(
    Q0: ArrayLike, M0: ArrayLike, lam: ArrayLike, t: ArrayLike, check: bool
) -> tuple[Array, Array, Array, Array, tuple[int, ...]]:
    """The input of :func:`rigid_body_exact` as float arrays (validated with ``check``), the
    times flattened to 1-D, and the broadcast batch shape."""
    if check:
        L = v.inertia(lam)
        Qa = v.orthogonal(Q0, "Q0")
        Ma = v.bounded(v.skew(M0, "M0"), "M0")
        tt = v.bounded(v.as_float_array(t, "t"), "t")
    else:
        L, Qa, Ma, tt = (np.asarray(x, dtype=float) for x in (lam, Q0, M0, t))
    for name, x, want in (("lam", L, (3,)), ("Q0", Qa, (3, 3)), ("M0", Ma, (3, 3))):
        if x.shape[x.ndim - len(want) :] != want:
            raise InputError(
                f"rigid_body_exact is for n = 3: {name} must have shape (..., "
                f"{', '.join(map(str, want))}), got {x.shape}"
            )
    if tt.ndim > 1:
        raise InputError(f"t must be a scalar or a 1-D array of times, got shape {tt.shape}")
    tt = tt.reshape(-1)
    try:
        batch = np.broadcast_shapes(Qa.shape[:-2], Ma.shape[:-2], L.shape[:-1])
    except ValueError as exc:
        raise InputError(f"Q0, M0 and lam batch shapes do not broadcast: {exc}") from None
    return L, Qa, Ma, tt, batch


def rigid_body_exact(
    Q0: ArrayLike, M0: ArrayLike, lam: ArrayLike, t: ArrayLike, *, check: bool = True
) -> ExactSolution:
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
    check : bool, optional
        Validate the values of the input (default).  ``check=False`` keeps only the conversion to
        float arrays and the shape checks, for inner loops (a splitting method) whose data are
        known to be valid: a ``Q0`` off SO(3) or a ``M0`` that is not skew then gives a wrong
        answer or NaN instead of an error.

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
        not a finite scalar or 1-D array (or ``M0``, ``t`` have entries above 1e150).
    OutOfDomainError
        If the phase :math:`\nu t` of the elliptic functions exceeds 10^15 (its
        rounding alone is then of order 0.1) or the formulas overflow float64 (extreme ``M0``
        against ``lam``).

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
    L, Qa, Ma, tt, batch = _exact_input(Q0, M0, lam, t, check)

    def what() -> str:  # for the messages only: formatting arrays costs a third of a call
        big, last = float(np.abs(Ma).max(initial=0.0)), float(np.abs(tt).max(initial=0.0))
        return f"M0 up to {big:.4g}, lam {L.ravel()[:3]}, t up to {last:.4g}"

    try:
        with np.errstate(all="ignore"):
            sol = _exact(L, Qa, Ma, tt, batch)
    except (ArithmeticError, ValueError) as exc:
        raise OutOfDomainError(
            f"rigid_body_exact: the formulas overflow float64 ({type(exc).__name__}: {exc}) for "
            f"{what()}; rescale M0 and t (M0/c at time c t is the same motion)"
        ) from None
    phase = float(np.max(np.abs(sol.nu), initial=0.0)) * float(np.abs(tt).max(initial=0.0))
    if not phase <= MAX_PHASE:
        raise OutOfDomainError(
            f"rigid_body_exact: the phase nu t = {phase:.4g} of the elliptic functions exceeds "
            f"{MAX_PHASE:g} (its rounding alone is about {phase * 1.1e-16:.2g}) for {what()}; "
            "take shorter times"
        )
    if not all(np.isfinite(x).all() for x in sol.y.values()):
        raise OutOfDomainError(
            f"rigid_body_exact: the solution is not finite in float64 for {what()} (an overflow); "
            "rescale M0 and t (M0/c at time c t is the same motion)"
        )
    return sol


#: The largest phase :math:`\nu t` of the elliptic functions that :func:`rigid_body_exact`
#: evaluates: beyond it the rounding of the phase alone (about 1e-16 of it) exceeds 0.1.
MAX_PHASE = 1e15


def _exact(L: Array, Qa: Array, Ma: Array, tt: Array, batch: tuple[int, ...]) -> ExactSolution:
    """The formulas of :func:`rigid_body_exact` on validated input."""
    if batch == () and len(tt) <= _SCALAR_MAX_TIMES:
        one = _one_body(Qa, Ma, L, tt)
        if one is not None:
            Q1, M1, k2_, nu_, ax = one
            y1 = Trajectory(Q=Q1, M=M1, Omega=_Jinv_weights(L) * M1)
            return ExactSolution(t=tt, y=y1, k2=np.array(k2_), nu=np.array(nu_), axis=np.array(ax))
    Qa = np.broadcast_to(Qa, batch + (3, 3))
    Ma = np.broadcast_to(Ma, batch + (3, 3))
    L = np.broadcast_to(L, batch + (3,))

    inertia = L.sum(axis=-1, keepdims=True) - L  # I_1 = lam_2 + lam_3 (inertia_from_lam)
    m0 = Ma[..., [2, 0, 1], [1, 2, 0]]  # vee(M0)
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
    any_steady = bool(steady.any())
    if any_steady:  # dummy values keep the formulas finite there (the results are replaced)
        ok = ~steady
        a1, a2, a3 = np.where(ok, a1, 1.0), np.where(ok, a2, 2.0), np.where(ok, a3, 3.0)
        d1, d3, mu = np.where(ok, d1, 1.0), np.where(ok, d3, 1.0), np.where(ok, mu, 1.0)
        x1, x2 = np.where(ok, x1, 1.0), np.where(ok, x2, 0.0)

    sigma = np.sign(a3 - a1)
    h21, h31, h32 = np.abs(a2 - a1), np.abs(a3 - a1), np.abs(a3 - a2)
    d1, d3 = np.abs(d1), np.abs(d3)
    c1 = np.sqrt(a1 * d3 / h31)
    c2 = sigma * np.sqrt(a2 * d3 / h32)
    c3 = np.sqrt(a3 * d1 / h31)
    nu = np.sqrt(d1 * h32 / (a1 * a2 * a3))
    k2 = np.minimum(1.0, h21 * d3 / (h32 * d1))
    n = -a3 * h21 / (a1 * h32)
    gamma = -sigma * mu * h31 * h21 / (a1**2 * h32 * nu)

    # the initial phase: sn(tau0) = s0, cn(tau0) = c0 >= 0, tau0 = F(asin s0 | k2)
    y, x = sigma * x2 * np.sqrt(a1 / h31), x1 * np.sqrt(a2 / h32)
    h = np.hypot(x, y)
    s0, c0 = y / h, x / h
    dn0sq = 1.0 - k2 * s0**2
    tau0 = s0 * elliprf(c0**2, dn0sq, 1.0)
    Z0 = s0**3 * elliprj(c0**2, dn0sq, 1.0, 1.0 - n * s0**2) / 3.0

    T = tt.reshape((-1,) + (1,) * len(batch))
    tau = nu * T + tau0
    # reduce tau modulo the period 4K (scipy's dn loses digits like eps * tau otherwise); on the
    # separatrix K and Z(K) are infinite and j = 0 (the caps avoid 0 * inf)
    K = np.minimum(ellipk(k2), 1e300)
    j4 = np.round(tau / (4 * K))
    r = tau - 4 * K * j4
    sn, cn, dn, _ = ellipj(r, k2)
    j = 2 * j4 + np.round(r / (2 * K))  # tau = 2 K j + (a remainder in [-K, K])
    ZK = np.minimum(elliprj(0.0, 1.0 - k2, 1.0, 1.0 - n), 1e300) / 3.0
    sign = 1.0 - 2.0 * (j % 2)
    Zt = 2 * j * ZK + sign * sn**3 * elliprj(cn**2, dn**2, 1.0, 1.0 - n * sn**2) / 3.0
    psi = mu * T / a1 + gamma * (Zt - Z0)

    # Q(t) = Q0 R^T B(0)^T R_z(psi) B(t) R, M(t) = hat(R^T m'(t)) (working-frame m')
    c = np.stack([c1, c2, c3], axis=-1)
    mt = c * np.stack([cn, sn, dn], axis=-1)
    mp0 = c * np.stack([c0, s0, np.sqrt(dn0sq)], axis=-1)
    Rt = np.swapaxes(R, -1, -2)
    G = Qa @ Rt @ np.swapaxes(_turned_frame(mp0, mu), -1, -2)
    Q = G @ _turned_frame(mt, mu, psi) @ R
    M = _hat(np.einsum("...ij,...j->...i", Rt, mt))
    if any_steady:  # M constant, Q = Q0 exp(t Omega0)
        Qs = Qa @ _rotation_exp(T[..., None] * (m0 / inertia))
        st = steady[..., None, None]
        Q = np.where(st, Qs, Q)
        M = np.where(st, Ma, M)
        k2, nu, axis = np.where(ok, k2, 0.0), np.where(ok, nu, 0.0), np.where(ok, axis, -1)
    y_out = Trajectory(Q=Q, M=M, Omega=_Jinv_weights(L) * M)
    return ExactSolution(t=tt, y=y_out, k2=k2, nu=nu, axis=axis)
