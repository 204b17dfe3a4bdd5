r"""Independent references for the float64 and high-precision evidence.

Everything here is written from the paper's definitions with NumPy, SciPy and mpmath only, by a
different route from symrb (which never imports this module, and which this module never
imports), so that evidence comparing a public ``symrb`` function with these catches a wrong
implementation instead of agreeing with it:

* the inertia operator :math:`J(\Omega) = \Lambda\Omega + \Omega\Lambda` as an
  :math:`n^2\times n^2` matrix, inverted by a linear solve (symrb uses the entry weights
  :math:`1/(\lambda_i+\lambda_j)`);
* the rigid body and symmetric rigid body vector fields built on it;
* the exact solution of Euler's equations for n = 3 by Jacobi elliptic functions
  (``scipy.special.ellipj``; Landau and Lifshitz, Mechanics, section 37);
* the discrete symmetric representation and both Moser-Veselov algorithms in 50-digit arithmetic
  (``mpmath``), :math:`J_D(U) = M` solved by Newton's method on the Cayley parameters of
  :math:`U` (``mpmath.findroot``) started from the identity's branch;
* the rigid body for any n by Gragg-Bulirsch-Stoer extrapolation in extended precision
  (``np.longdouble``), the reference of the benchmark's work-precision diagrams;
* the Toda lattice by Symes' QR formula in ``mpmath`` (no differential equation is solved), and
  the extremal equations of the adjoint-orbit problem on :math:`\mathfrak{so}(3)` written with
  cross products and solved by ``mpmath.odefun``.
"""

from __future__ import annotations

from collections.abc import Callable
from fractions import Fraction
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.special import ellipj

Array = NDArray[np.float64]

__all__ = [
    "J_operator",
    "J",
    "J_inv",
    "J_D",
    "hat",
    "vee",
    "rigid_body_field",
    "symmetric_field",
    "pairing",
    "euler_elliptic",
    "random_rotation",
    "random_skew",
    "MPDiscrete",
    "Series",
    "series_eval",
    "rigid_body_taylor",
    "rigid_body_extrapolated",
    "toda_symes",
    "orbit_extremal_so3_mp",
]


def J_operator(lam: Array) -> Array:
    """The matrix of Omega -> Lambda Omega + Omega Lambda on row-major vec(Omega), (n^2, n^2)."""
    L = np.diag(np.asarray(lam, dtype=float))
    eye = np.eye(L.shape[0])
    return np.kron(L, eye) + np.kron(
        eye, L
    )  # vec(L X) = (L kron I) vec X, vec(X L) = (I kron L) vec X


def J(Omega: Array, lam: Array) -> Array:
    """Lambda Omega + Omega Lambda with explicit diagonal matrices (batched over leading axes)."""
    L = np.diag(np.asarray(lam, dtype=float))
    return L @ Omega + Omega @ L


def J_inv(M: Array, lam: Array) -> Array:
    """Solve Lambda Omega + Omega Lambda = M by a dense linear solve (batched over leading axes)."""
    M = np.asarray(M, dtype=float)
    k = M.shape[-1]
    A = J_operator(lam)
    flat = M.reshape(-1, k * k).T
    return np.linalg.solve(A, flat).T.reshape(M.shape)


def J_D(U: Array, lam: Array) -> Array:
    """U Lambda - Lambda U^T with explicit diagonal matrices."""
    L = np.diag(np.asarray(lam, dtype=float))
    return U @ L - L @ np.swapaxes(U, -1, -2)


def pairing(a: Array, b: Array) -> Array:
    """<a, b> = -1/2 trace(a b)."""
    return -0.5 * np.trace(a @ b, axis1=-2, axis2=-1)


def hat(v: Array) -> Array:
    """hat(v) w = v x w (built column by column from the cross product)."""
    v = np.asarray(v, dtype=float)
    cols = [np.cross(v, e) for e in np.eye(3)]
    return np.stack(cols, axis=-1)


def vee(m: Array) -> Array:
    return np.stack([m[..., 2, 1], m[..., 0, 2], m[..., 1, 0]], axis=-1)


def rigid_body_field(Q: Array, M: Array, lam: Array) -> tuple[Array, Array]:
    """(Q Omega, M Omega - Omega M) with Omega = J^{-1}(M) from the linear solve."""
    Om = J_inv(M, lam)
    return Q @ Om, M @ Om - Om @ M


def symmetric_field(Q: Array, P: Array, lam: Array) -> tuple[Array, Array]:
    """(Q U, P U) with U = J^{-1}(Q^T P - P^T Q) from the linear solve."""
    Qt, Pt = np.swapaxes(Q, -1, -2), np.swapaxes(P, -1, -2)
    U = J_inv(Qt @ P - Pt @ Q, lam)
    return Q @ U, P @ U


def euler_elliptic(inertia: Array, a1: float, a3: float, t: Array) -> Array:
    r"""Exact body angular momentum m(t) of Euler's equations :math:`\dot m = m\times\omega`,
    :math:`\omega_i = m_i/I_i`, for :math:`I_1 < I_2 < I_3` and the initial angular velocity
    :math:`\omega(0) = (a_1, 0, a_3)`, :math:`a_1, a_3 > 0`, on the branch
    :math:`|m|^2 > 2E I_2` (Landau and Lifshitz, section 37):

    .. math::

        \omega_1 = A_1\operatorname{cn}\tau,\quad \omega_2 = -A_2\operatorname{sn}\tau,\quad
        \omega_3 = A_3\operatorname{dn}\tau,\qquad
        \tau = t\sqrt{(I_3-I_2)(|m|^2-2EI_1)/(I_1I_2I_3)}.

    The sign of :math:`\omega_2` is that of :math:`\dot\omega_2(0) = (I_3-I_1)a_1a_3/I_2 > 0`
    with ``sn`` odd, for the convention :math:`\dot m = m\times\omega` (so :math:`-A_2`).
    Returns m at the times ``t``, shape (len(t), 3).
    """
    I1, I2, I3 = (float(x) for x in inertia)
    if not I1 < I2 < I3:
        raise ValueError(f"need I1 < I2 < I3, got {inertia}")
    E2 = I1 * a1**2 + I3 * a3**2  # 2E
    L2 = (I1 * a1) ** 2 + (I3 * a3) ** 2  # |m|^2
    if not L2 > E2 * I2:
        raise ValueError("initial data not on the branch |m|^2 > 2 E I_2")
    A1 = np.sqrt((E2 * I3 - L2) / (I1 * (I3 - I1)))
    A2 = np.sqrt((E2 * I3 - L2) / (I2 * (I3 - I2)))
    A3 = np.sqrt((L2 - E2 * I1) / (I3 * (I3 - I1)))
    k2 = (I2 - I1) * (E2 * I3 - L2) / ((I3 - I2) * (L2 - E2 * I1))
    rate = np.sqrt((I3 - I2) * (L2 - E2 * I1) / (I1 * I2 * I3))
    sn, cn, dn, _ = ellipj(rate * np.asarray(t, dtype=float), k2)
    # the -A2 sn branch: at t = 0 omega_2 = 0 and omega_2 grows when (I1 - I3) a1 a3 / I2 < 0
    sign = -1.0 if (I3 - I1) * a1 * a3 > 0 else 1.0
    w = np.stack([A1 * cn, -sign * A2 * sn, A3 * dn], axis=-1)
    return w * np.array([I1, I2, I3])


def random_rotation(k: int, rng: np.random.Generator) -> Array:
    """A rotation from the QR factorisation of a Gaussian matrix (det fixed to +1)."""
    q, r = np.linalg.qr(rng.standard_normal((k, k)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


def so_orthonormal_basis(k: int) -> list[np.ndarray]:
    """(E_ij - E_ji)/sqrt(2), i < j: an orthonormal basis of so(k) for the Frobenius inner
    product."""
    out = []
    for i in range(k):
        for j in range(i + 1, k):
            E = np.zeros((k, k))
            E[i, j], E[j, i] = 1 / np.sqrt(2), -1 / np.sqrt(2)
            out.append(E)
    return out


def random_skew(k: int, rng: np.random.Generator, scale: float = 1.0) -> Array:
    a = rng.standard_normal((k, k)) * scale
    return a - a.T


class MPDiscrete:
    """The discrete maps of Section 2 in ``dps``-digit arithmetic, for n = 3 (mpmath).

    ``solve_jd(M)`` returns the U in SO(3) with U Lambda - Lambda U^T = M on the branch through
    the identity: Newton on the Cayley parameters a of U = (I - A)^{-1}(I + A), A = hat(a),
    continued in float64 from M = 0 (U = I) along t M, t = 1/4, 1/2, 3/4, 1 (scipy.optimize.root),
    then polished in ``dps`` digits (mpmath.findroot).
    """

    def __init__(self, lam: Array, dps: int = 50) -> None:
        import mpmath as mp

        self.mp = mp
        self.dps = dps
        with mp.workdps(dps):
            self.L = mp.diag([mp.mpf(float(x)) for x in lam])
            self.eye = mp.eye(3)

    def _skew(self, a: object, b: object, c: object) -> object:
        mp = self.mp
        return mp.matrix([[0, -c, b], [c, 0, -a], [-b, a, 0]])

    def cayley(self, x: list[object]) -> object:
        mp = self.mp
        A = self._skew(*x)
        return mp.inverse(self.eye - A) * (self.eye + A)

    def solve_jd(self, M: object) -> object:
        mp = self.mp
        with mp.workdps(self.dps):
            Mf = np.array(M.tolist(), dtype=float)
            x = self._float_branch(Mf)

            def F(a: object, b: object, c: object) -> list[object]:
                U = self.cayley([a, b, c])
                R = U * self.L - self.L * U.T - M
                return [R[2, 1], R[0, 2], R[1, 0]]

            def Jac(a: object, b: object, c: object) -> object:
                # dU = (I - A)^{-1} dA (U + I) for U = (I - A)^{-1}(I + A), A = hat(a, b, c)
                A = self._skew(a, b, c)
                inv = mp.inverse(self.eye - A)
                U = inv * (self.eye + A)
                cols = []
                for e in ((1, 0, 0), (0, 1, 0), (0, 0, 1)):
                    dU = inv * self._skew(*e) * (U + self.eye)
                    dR = dU * self.L - self.L * dU.T
                    cols.append([dR[2, 1], dR[0, 2], dR[1, 0]])
                return mp.matrix(cols).T

            x0 = [mp.mpf(float(v)) for v in x]
            tol = mp.mpf(10) ** (-self.dps + 8)
            x = list(mp.findroot(F, x0, J=Jac, solver="mdnewton", tol=tol))
            return self.cayley(x)

    def _float_branch(self, M: Array) -> Array:
        """Cayley parameters of the branch solution in float64: Newton (scipy.optimize.root) on
        t M for t = 1/4, 1/2, 3/4, 1, starting from U = I at t = 0."""
        from scipy.optimize import root

        lam = np.array([float(self.L[i, i]) for i in range(3)])

        def residual(x: Array, t: float) -> Array:
            A = hat(x)
            U = np.linalg.solve(np.eye(3) - A, np.eye(3) + A)
            R = U * lam[None, :] - lam[:, None] * U.T - t * M
            return np.array([R[2, 1], R[0, 2], R[1, 0]])

        x = np.zeros(3)
        for t in (0.25, 0.5, 0.75, 1.0):
            sol = root(residual, x, args=(t,), method="hybr", options={"xtol": 1e-14})
            x = sol.x
        return x

    def matrix(self, a: Array) -> object:
        return self.mp.matrix(np.asarray(a, dtype=float).tolist())

    def orthonormal(self, Q: Array) -> object:
        """Q re-orthogonalised in high precision (QR with positive diagonal)."""
        mp = self.mp
        with mp.workdps(self.dps):
            q, r = mp.qr(self.matrix(Q))
            return q * mp.diag([mp.sign(r[i, i]) for i in range(3)])

    def symmetric(self, Q0: object, P0: object, h: float, steps: int) -> tuple[list, list]:
        """Q_k, P_k of the symmetric representation: J_D(U_k) = h (Q_k^T P_k - P_k^T Q_k)."""
        mp = self.mp
        with mp.workdps(self.dps):
            Q, P = Q0, P0
            Qs, Ps = [Q], [P]
            for _ in range(steps):
                U = self.solve_jd(mp.mpf(h) * (Q.T * P - P.T * Q))
                Q, P = Q * U, P * U
                Qs.append(Q)
                Ps.append(P)
            return Qs, Ps

    def mv2(self, Q1: object, M1: object, steps: int) -> tuple[list, list]:
        """MV-Algorithm 2 from (Q_1, M_1): returns Q_1.. and M_1.. (steps + 1 of each)."""
        mp = self.mp
        with mp.workdps(self.dps):
            Qk, Mk = Q1, M1
            Om = self.solve_jd(Mk).T  # mv2: M_k = Om_k^T L - L Om_k, i.e. J_D(Om_k^T) = M_k
            Qs, Ms = [Qk], [Mk]
            for _ in range(steps):
                Mk = Om * Mk * Om.T  # mv3
                Om = self.solve_jd(Mk).T  # mv2 for Om_{k+1}
                Qk = Qk * Om.T  # mv1: Om_{k+1} = Q_{k+1}^T Q_k
                Qs.append(Qk)
                Ms.append(Mk)
            return Qs, Ms

    def mv1(self, Q0: object, Q1: object, steps: int) -> list:
        """MV-Algorithm 1 from (Q_0, Q_1): returns Q_0, Q_1, ..., Q_{steps+1}."""
        with self.mp.workdps(self.dps):
            Qa, Qb = Q0, Q1
            out = [Qa, Qb]
            for _ in range(steps):
                Om = Qb.T * Qa  # mv1
                Mk = Om.T * self.L - self.L * Om  # mv2
                Mk = Om * Mk * Om.T  # mv3
                Om = self.solve_jd(Mk).T  # mv2 for the next Omega
                Qa, Qb = Qb, Qb * Om.T  # mv1
                out.append(Qb)
            return out

    def distance(self, a: object, b: Array) -> float:
        """max |a - b| entrywise, a in high precision, b float64 (NaN in b gives NaN)."""
        with self.mp.workdps(self.dps):
            d = a - self.matrix(b)
            return float(np.max([float(abs(d[i, j])) for i in range(3) for j in range(3)]))


# ---------------------------------------------------------------------------------------------
# truncated power series with exact rational coefficients


class Series:
    """A power series :math:`\\sum_{k<N} a_k h^k` truncated after ``N`` terms, with
    :class:`fractions.Fraction` coefficients; ``+ - * /`` and integer powers (the inverse needs
    :math:`a_0 \\ne 0`)."""

    __slots__ = ("c",)

    def __init__(self, coeffs: list[Fraction]) -> None:
        self.c = coeffs

    @classmethod
    def const(cls, value: Any, N: int) -> Series:
        return cls([Fraction(value)] + [Fraction(0)] * (N - 1))

    @classmethod
    def var(cls, N: int) -> Series:
        return cls([Fraction(0), Fraction(1)] + [Fraction(0)] * (N - 2))

    def _lift(self, other: Any) -> Series:
        return other if isinstance(other, Series) else Series.const(other, len(self.c))

    def __add__(self, other: Any) -> Series:
        o = self._lift(other)
        return Series([a + b for a, b in zip(self.c, o.c, strict=True)])

    __radd__ = __add__

    def __neg__(self) -> Series:
        return Series([-a for a in self.c])

    def __sub__(self, other: Any) -> Series:
        return self + (-self._lift(other))

    def __rsub__(self, other: Any) -> Series:
        return self._lift(other) - self

    def __mul__(self, other: Any) -> Series:
        o, N = self._lift(other), len(self.c)
        out = [Fraction(0)] * N
        for i, a in enumerate(self.c):
            if a:
                for j in range(N - i):
                    if o.c[j]:
                        out[i + j] += a * o.c[j]
        return Series(out)

    __rmul__ = __mul__

    def inverse(self) -> Series:
        a, N = self.c, len(self.c)
        if a[0] == 0:
            raise ZeroDivisionError("series with a zero constant term has no inverse")
        inv = [Fraction(0)] * N
        inv[0] = 1 / a[0]
        for k in range(1, N):
            inv[k] = -sum((a[j] * inv[k - j] for j in range(1, k + 1)), Fraction(0)) / a[0]
        return Series(inv)

    def __truediv__(self, other: Any) -> Series:
        return self * self._lift(other).inverse()

    def __rtruediv__(self, other: Any) -> Series:
        return self._lift(other) * self.inverse()

    def __pow__(self, k: int) -> Series:
        if k < 0:
            return self.inverse() ** (-k)
        out, base = Series.const(1, len(self.c)), self
        while k:
            if k & 1:
                out = out * base
            base, k = base * base, k >> 1
        return out

    def integral(self) -> Series:
        """The antiderivative vanishing at 0 (truncated)."""
        return Series([Fraction(0)] + [a / (k + 1) for k, a in enumerate(self.c[:-1])])


def series_eval(expr: Any, values: dict[Any, Any], N: int) -> Series:
    """Evaluate a SymPy expression built from ``+``, ``*`` and integer powers of symbols and
    rational numbers on :class:`Series` (``values``: symbol -> Series or number), memoised on
    the expression's subtrees (shared subexpressions are evaluated once)."""
    import sympy as sp

    memo: dict[Any, Series] = {}

    def go(e: Any) -> Series:
        if e in memo:
            return memo[e]
        if e in values:
            v = values[e]
            r = v if isinstance(v, Series) else Series.const(v, N)
        elif e.is_Rational:
            r = Series.const(Fraction(int(e.p), int(e.q)), N)
        elif isinstance(e, sp.Add):
            r = go(e.args[0])
            for a in e.args[1:]:
                r = r + go(a)
        elif isinstance(e, sp.Mul):
            r = go(e.args[0])
            for a in e.args[1:]:
                r = r * go(a)
        elif isinstance(e, sp.Pow) and e.exp.is_Integer:
            r = go(e.base) ** int(e.exp)
        else:
            raise TypeError(f"series_eval: unsupported node {type(e).__name__}: {e}")
        memo[e] = r
        return r

    return go(expr)


def rigid_body_taylor(
    inertia: list[Fraction], m0: list[Fraction], N: int
) -> tuple[list[Series], list[list[Series]]]:
    r"""The Taylor series in :math:`t` of the free rigid body from :math:`m(0) = m_0`,
    :math:`Q(0) = I`: :math:`\dot m = m\times\omega`, :math:`\dot Q = Q\hat\omega`,
    :math:`\omega_i = m_i/I_i`, by Picard iteration (``N`` iterations fix ``N`` coefficients).
    Returns (m as 3 series, Q as 3 x 3 series)."""
    m = [Series.const(x, N) for x in m0]
    Q = [[Series.const(int(i == j), N) for j in range(3)] for i in range(3)]
    for _ in range(N):
        w = [m[i] * Fraction(1) / Fraction(inertia[i]) for i in range(3)]
        dm = [m[1] * w[2] - m[2] * w[1], m[2] * w[0] - m[0] * w[2], m[0] * w[1] - m[1] * w[0]]
        W = [[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]]
        dQ = [[sum((Q[i][k] * W[k][j] for k in range(3) if k != j), Series.const(0, N))
               for j in range(3)] for i in range(3)]  # fmt: skip
        m = [Series.const(m0[i], N) + dm[i].integral() for i in range(3)]
        Q = [[Series.const(int(i == j), N) + dQ[i][j].integral() for j in range(3)]
             for i in range(3)]  # fmt: skip
    return m, Q


def rigid_body_mp(
    inertia: Array, Q0: Array, m0: Array, dps: int = 20
) -> Callable[[float], tuple[Array, Array]]:
    r"""The free rigid body :math:`\dot Q = Q\hat\omega`, :math:`\dot m = m\times\omega`,
    :math:`\omega_i = m_i/I_i` from :math:`(Q_0, m_0)`, by mpmath's Taylor-series solver
    (``mpmath.odefun``) in ``dps`` digits: a function of :math:`t \ge 0` returning
    :math:`(Q(t), m(t))` as float arrays (the series are kept, so many times cost little)."""
    import mpmath

    with mpmath.workdps(dps):
        inv = [1 / mpmath.mpf(float(x)) for x in inertia]

        def field(_t: Any, y: list[Any]) -> list[Any]:
            m = y[9:]
            w = [m[i] * inv[i] for i in range(3)]
            W = [[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]]
            Qd = [sum(y[3 * i + k] * W[k][j] for k in range(3)) for i in range(3) for j in range(3)]
            md = [m[1] * w[2] - m[2] * w[1], m[2] * w[0] - m[0] * w[2], m[0] * w[1] - m[1] * w[0]]
            return Qd + md

        y0 = [mpmath.mpf(float(x)) for x in np.concatenate([np.ravel(Q0), m0])]
        solution = mpmath.odefun(field, 0, y0)

    def at(t: float) -> tuple[Array, Array]:
        with mpmath.workdps(dps):
            y = np.array([float(x) for x in solution(t)])
        return y[:9].reshape(3, 3), y[9:]

    return at


def toda_symes(L0: Array, t: Array, dps: int = 60) -> Array:
    r"""The Toda lattice :math:`\dot L = [B, L]`, :math:`B = L_+ - L_-` (strictly upper minus
    strictly lower part of L), from the real symmetric :math:`L_0`, by Symes' QR formula:
    :math:`\exp(tL_0) = Q(t)R(t)` with Q orthogonal and R upper triangular with a positive
    diagonal, :math:`L(t) = Q(t)^T L_0 Q(t)`, in ``dps``-digit arithmetic (mpmath's ``expm`` and
    Householder ``qr``); any real t, negative too.  Returns L at the times ``t``, shape (m, k, k).

    Why it is Toda: differentiating :math:`L_0 e^{tL_0} = e^{tL_0}L_0` gives :math:`L = Q^T\dot Q +
    \dot R R^{-1}`, a skew plus an upper triangular matrix, so :math:`Q^T\dot Q = L_- - L_-^T =
    -B` and :math:`\dot L = [L, Q^T\dot Q] = [B, L]`.  ``dps`` must cover the spread
    :math:`e^{|t|(\lambda_{max} - \lambda_{min})}` of the columns of the exponential."""
    import mpmath

    L0 = np.asarray(L0, dtype=float)
    k = L0.shape[0]
    out = []
    with mpmath.workdps(dps):
        A = mpmath.matrix(L0.tolist())
        for tt in np.atleast_1d(t):
            Q, R = mpmath.qr(mpmath.expm(mpmath.mpf(float(tt)) * A))
            for j in range(k):  # the factorisation with a positive diagonal of R is unique
                if R[j, j] < 0:
                    for i in range(k):
                        Q[i, j] = -Q[i, j]
            L = Q.T * A * Q
            out.append([[float(L[i, j]) for j in range(k)] for i in range(k)])
    return np.array(out)


def orbit_extremal_so3_mp(
    x0: Array, p0: Array, N: Array, dps: int = 25
) -> Callable[[float], tuple[Array, Array]]:
    r"""The extremal equations :math:`\dot x = [x, [p, x]]`, :math:`\dot p = [p, [p, x]] -
    [N, [N, x]]` on :math:`\mathfrak{so}(3)`, written for the vectors :math:`\xi, \pi, \nu`
    of x, p, N with :math:`[\hat a, \hat b] = \widehat{a\times b}`:
    :math:`\dot\xi = \xi\times(\pi\times\xi)`, :math:`\dot\pi = \pi\times(\pi\times\xi)
    - \nu\times(\nu\times\xi)`, solved by mpmath's Taylor-series solver (``odefun``) in
    ``dps`` digits.  Returns a function of :math:`t \ge 0` giving :math:`(x(t), p(t))` as float
    3 x 3 skew matrices."""
    import mpmath

    def cross(a: list[Any], b: list[Any]) -> list[Any]:
        return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]

    with mpmath.workdps(dps):
        nu = [mpmath.mpf(float(c)) for c in vee(np.asarray(N, dtype=float))]

        def field(_t: Any, y: list[Any]) -> list[Any]:
            xi, pi = y[:3], y[3:]
            c = cross(pi, xi)
            nnx = cross(nu, cross(nu, xi))
            return cross(xi, c) + [a - b for a, b in zip(cross(pi, c), nnx, strict=True)]

        start = np.concatenate([vee(np.asarray(x0, dtype=float)), vee(np.asarray(p0, dtype=float))])
        solution = mpmath.odefun(field, 0, [mpmath.mpf(float(c)) for c in start])

    def at(t: float) -> tuple[Array, Array]:
        with mpmath.workdps(dps):
            y = np.array([float(c) for c in solution(t)])
        return hat(y[:3]), hat(y[3:])

    return at


def rigid_body_extrapolated(
    Q0: Array, M0: Array, lam: Array, T: float, macro_steps: int, stages: int = 8
) -> tuple[NDArray[np.longdouble], NDArray[np.longdouble]]:
    r"""The free rigid body :math:`\dot Q = Q\Omega`, :math:`\dot M = M\Omega - \Omega M`,
    :math:`\Lambda\Omega + \Omega\Lambda = M`, any n, from :math:`(Q_0, M_0)` to time ``T``, by
    Gragg-Bulirsch-Stoer extrapolation in extended precision (``np.longdouble``, 64-bit mantissa
    on x86-64): ``macro_steps`` equal steps, each the explicit midpoint rule with 2, 4, ...,
    ``2 * stages`` substeps extrapolated to zero step by Aitken-Neville (order ``2 * stages``;
    Hairer, Norsett and Wanner, *Solving ODEs I*, II.9).  Nothing of symrb and no float64 solver
    is used; :math:`\Omega` is :math:`M_{ij}/(\lambda_i+\lambda_j)`, and each evaluation checks
    that it solves :math:`\Lambda\Omega + \Omega\Lambda = M` to rounding.  Its error is estimated
    by comparing two values of ``macro_steps``.  Returns :math:`(Q(T), M(T))` in extended
    precision."""
    ld = np.longdouble
    lamd = np.asarray(lam, dtype=ld)
    L = np.diag(lamd)
    weight = 1 / (lamd[:, None] + lamd[None, :])
    eps = float(np.finfo(ld).eps)

    def field(Q: Any, M: Any) -> tuple[Any, Any]:
        Om = M * weight
        residual = np.abs(L @ Om + Om @ L - M).max()
        if residual > 64 * eps * (1 + np.abs(M).max()):
            raise ArithmeticError(f"rigid_body_extrapolated: J(Omega) - M = {residual}")
        return Q @ Om, M @ Om - Om @ M

    y = (np.asarray(Q0, dtype=ld), np.asarray(M0, dtype=ld))
    H = ld(T) / macro_steps
    for _ in range(macro_steps):
        table: list[list[tuple[Any, Any]]] = []
        f0 = field(*y)
        for j in range(1, stages + 1):
            n_sub = 2 * j
            h = H / n_sub
            prev = y
            cur = (y[0] + h * f0[0], y[1] + h * f0[1])
            for _m in range(1, n_sub):
                f = field(*cur)
                prev, cur = cur, (prev[0] + 2 * h * f[0], prev[1] + 2 * h * f[1])
            row = [cur]
            for k in range(1, j):
                ratio = ld(n_sub) ** 2 / ld(2 * (j - k)) ** 2 - 1
                a, b = row[k - 1], table[-1][k - 1]
                row.append((a[0] + (a[0] - b[0]) / ratio, a[1] + (a[1] - b[1]) / ratio))
            table.append(row)
        y = table[-1][-1]
    return y
