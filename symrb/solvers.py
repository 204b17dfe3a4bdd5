r"""The Moser-Veselov equation :math:`U\Lambda - \Lambda U^T = M` on :math:`SO(n)` (the paper,
Sections 2.1 and 2.2).

Given a skew :math:`M` and a positive diagonal :math:`\Lambda`, the discrete rigid body needs the
:math:`U\in SO(n)` with :math:`J_D(U) = U\Lambda - \Lambda U^T = M` *on the branch through the
identity* (:math:`J_D(I) = 0`, and :math:`J_D` is a local diffeomorphism there, claim D8).

**How it is solved** (derived in the book, page "The Moser-Veselov solver").  Put :math:`X = U\Lambda`.  Then :math:`X - X^T = M` and :math:`X^TX = \Lambda^2`.  Writing
:math:`X = S + M/2` with :math:`S` symmetric, the second equation becomes the algebraic Riccati
equation

.. math::

    \tfrac12 M S - \tfrac12 S M - S^2 + \bigl(\Lambda^2 + \tfrac14 M^2\bigr) = 0,

i.e. ``scipy.linalg.solve_continuous_are(a=-M/2, b=I, q=Lambda^2 + M^2/4, r=I)`` (Cardoso and
Leite's reformulation).  Its closed-loop matrix is :math:`-M/2 - S = -X`, so the *stabilizing*
solution is the one with every eigenvalue of :math:`X = U\Lambda` in the open right half-plane.
At :math:`M = 0` it is :math:`S = \Lambda`, :math:`U = I`; it depends continuously on :math:`M`
and is unique when it exists.  This is the branch through the identity.  Other solutions exist
(claim D7): at :math:`M = 0` every diagonal sign matrix commutes with :math:`\Lambda`, so for
n = 3 the identity and the three half-turns about the principal axes all solve the equation in
:math:`SO(3)`, and they continue for small :math:`M`; only the branch through the identity is
returned.  The branch ends where
an eigenvalue of :math:`U\Lambda` reaches the imaginary axis: there the linearisation

.. math::

    \xi \mapsto U\xi\Lambda + \Lambda\xi U^T \quad(\xi\in\mathfrak{so}(n)),

which after :math:`Z = U\xi\Lambda = R/2 + T` becomes the Sylvester equation
:math:`X^TT + TX = (RX - X^TR)/2` for a symmetric :math:`T`, turns singular (eigenvalues
:math:`\mu_i + \mu_j = 0`): the fold.  Past it the branch has no solution.

The Riccati solution is a starting guess (or the previous :math:`U` of a time stepper is); Newton's
method on :math:`U \mapsto U\,\mathrm{cay}(\xi)` with the Sylvester step above polishes it to a
residual :math:`\|J_D(U) - M\|_F \le 10\,\varepsilon\,\|M\|_F`, keeping :math:`U` orthogonal to
rounding.  The branch is checked on the result (:math:`\min\operatorname{Re}\sigma(U\Lambda) > 0`).

Along a ray :math:`t \mapsto tM` the fold is where the Hamiltonian matrix
:math:`\begin{pmatrix}-M/2 & -I\\ -\Lambda^2 - M^2/4 & -M/2\end{pmatrix}` (whose spectrum is
:math:`\sigma(X)\cup\sigma(-X)` on the branch) first has an eigenvalue on the imaginary axis;
:func:`fold_scale` locates it by a scan and bisection.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
from numpy.typing import ArrayLike, NDArray

from . import _validate as v
from ._generated import discrete_rigid_body as _gen
from ._validate import Array
from .errors import InputError, NotConvergedError, OutOfDomainError

__all__ = ["MVSolveInfo", "solve_moser_veselov", "fold_scale"]

_EPS = float(np.finfo(float).eps)
#: Largest n for which the Newton step is solved as one batched dense (n^2 x n^2) system.
_KRON_MAX_N = 8


@dataclass(frozen=True)
class MVSolveInfo:
    r"""What :func:`solve_moser_veselov` did, per item of the batch (arrays of the batch shape).

    Attributes
    ----------
    iterations : ndarray of int
        Newton iterations used after the starting guess.
    residual : ndarray
        :math:`\|U\Lambda - \Lambda U^T - M\|_F`.
    tol : ndarray
        The tolerance the residual met.
    orthogonality : ndarray
        :math:`\|U^TU - I\|_F`.
    margin : ndarray
        :math:`\min\operatorname{Re}\sigma(U\Lambda) > 0`, which tends to 0 at the fold.
    condition : ndarray
        :math:`\kappa = \max_i\lambda_i\,\|L_U^{-1}\|_2`, the condition number of the solution:
        :math:`L_U(\xi) = U\xi\Lambda + \Lambda\xi U^T` is the derivative of :math:`J_D` at
        :math:`U` along :math:`U\xi`, so a change :math:`\delta M` moves :math:`U` by at most
        about :math:`\kappa\|\delta M\|_F/\max_i\lambda_i`.  It is
        :math:`\max\lambda_i/\min_{i\ne j}(\lambda_i+\lambda_j)` at :math:`M = 0` and grows
        without bound at the fold.  Estimated by eight sweeps of the power method (a lower bound,
        typically within a few per cent).  Accuracy stated and tested (tests/test_properties.py):
        :math:`\|U - U_*\|_F \le 10\sqrt{n}\,\varepsilon\,\kappa` for the exact solution
        :math:`U_*` of the rounded data.
    start : str
        ``"riccati"`` (cold start), ``"warm"`` (from ``U0``) or ``"mixed"``.

    Examples
    --------
    >>> import symrb
    >>> M = symrb.hat([0.05, 0.1, 0.15])
    >>> U, info = symrb.solve_moser_veselov(M, [0.7, 1.1, 1.6], return_info=True)
    >>> info.start, bool(info.residual <= info.tol), bool(info.margin > 0)
    ('riccati', True, True)
    >>> print(round(float(info.condition), 2))  # close to 1.6 / (0.7 + 1.1) at M = 0
    0.89
    """

    iterations: NDArray[np.int64]
    residual: Array
    tol: Array
    orthogonality: Array
    margin: Array
    start: str
    condition: Array


# ---------------------------------------------------------------------------------------------
# batched building blocks (no validation: callers pass (b, n, n) and (b, n) float arrays)


def _jd(U: Array, lam: Array) -> Array:
    """J_D(U) = U Lam - Lam U^T for U (b, n, n), lam (b, n): the generated kernel, inputs validated."""
    return _gen.jd(U, lam)


def _fro(a: Array) -> Array:
    return np.sqrt(np.einsum("...ij,...ij->...", a, a))


def _sylvester_sym(X: Array, C: Array) -> Array:
    """Solve X^T T + T X = C for every item (T symmetric when C is and the solution is unique)."""
    b, nn, _ = X.shape
    if nn <= _KRON_MAX_N:
        eye = np.eye(nn)
        # row-major vec: vec(X^T T) = (X^T kron I) vec T, vec(T X) = (I kron X^T) vec T
        K = np.einsum("bki,jl->bijkl", X, eye) + np.einsum("ik,blj->bijkl", eye, X)
        K = K.reshape(b, nn * nn, nn * nn)
        try:
            T = np.linalg.solve(K, C.reshape(b, nn * nn, 1)).reshape(b, nn, nn)
        except np.linalg.LinAlgError:
            # a singular system (exactly at or past the fold): NaN for those items, which the
            # Newton loop treats as a failed step, instead of an exception for the whole batch
            T = np.full_like(C, np.nan)
            for i in range(b):
                try:
                    T[i] = np.linalg.solve(K[i], C[i].reshape(-1)).reshape(nn, nn)
                except np.linalg.LinAlgError:
                    pass
    else:
        T = np.empty_like(C)
        for i in range(b):
            try:
                T[i] = sla.solve_sylvester(X[i].T, X[i], C[i])
            except (np.linalg.LinAlgError, ValueError):
                T[i] = np.nan
    return 0.5 * (T + np.swapaxes(T, -1, -2))


def _times_cayley(U: Array, xi: Array) -> Array:
    """U cay(xi) with cay(xi) = (I - xi/2)^{-1}(I + xi/2) = I + (I - xi/2)^{-1} xi (orthogonal for
    skew xi), computed as U + U (I - xi/2)^{-1} xi so the increment keeps its relative accuracy."""
    eye = np.eye(xi.shape[-1])
    return U + U @ np.linalg.solve(eye - 0.5 * xi, xi)


def _solve_linearised(U: Array, lam: Array, R: Array) -> Array:
    """The skew xi with U xi Lam + Lam xi U^T = R (the derivative of J_D at U along U xi)."""
    X = U * lam[:, None, :]
    Xt = np.swapaxes(X, -1, -2)
    C = 0.5 * (R @ X - Xt @ R)
    T = _sylvester_sym(X, C)
    xi = np.swapaxes(U, -1, -2) @ (0.5 * R + T) / lam[:, None, :]
    return 0.5 * (xi - np.swapaxes(xi, -1, -2))


def _newton_step(U: Array, M: Array, lam: Array, R: Array) -> Array:
    """One Newton step for J_D(U cay(xi)) = M, where R = M - J_D(U) (see the module docstring)."""
    return _times_cayley(U, _solve_linearised(U, lam, R))


def _condition(U: Array, lam: Array, sweeps: int = 8) -> Array:
    """max(lam) ||L_U^{-1}||_2 for L_U(xi) = U xi Lam + Lam xi U^T on so(n), per item.

    The adjoint of L_U in the Frobenius pairing is L_{U^T}, so the power iteration on
    L_{U^T}^{-1} L_U^{-1} (two solves of the Newton step's Sylvester form a sweep) converges to
    ||L_U^{-1}||_2^2 from below.  A fixed start keeps the estimate deterministic.
    """
    b, nn, _ = U.shape
    x = np.broadcast_to(np.triu(np.arange(1.0, nn * nn + 1).reshape(nn, nn) % 7 + 1.0, 1), U.shape)
    x = x - np.swapaxes(x, -1, -2)
    x = x / _fro(x)[:, None, None]
    Ut = np.swapaxes(U, -1, -2)
    growth = np.zeros(b)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        for _ in range(sweeps):
            y = _solve_linearised(Ut, lam, _solve_linearised(U, lam, x))
            growth = _fro(y)
            x = y / growth[:, None, None]
        out = lam.max(axis=-1) * np.sqrt(growth)
    return np.where(np.isfinite(out), out, np.inf)


def _polar(U: Array) -> Array:
    """The orthogonal factor of U (closest orthogonal matrix)."""
    W, _, Vt = np.linalg.svd(U)
    return W @ Vt


def _margin(U: Array, lam: Array) -> Array:
    """min Re of the eigenvalues of U Lam: positive exactly on the branch through the identity."""
    return np.linalg.eigvals(U * lam[:, None, :]).real.min(axis=-1)


def _riccati_guess(M: Array, lam: Array) -> tuple[Array, NDArray[np.bool_]]:
    """U = (S + M/2) Lam^{-1} from the stabilizing Riccati solution S, item by item.

    Returns the guesses and a mask of the items where scipy found no stabilizing solution.
    """
    b, nn, _ = M.shape
    U = np.tile(np.eye(nn), (b, 1, 1))
    failed = np.zeros(b, dtype=bool)
    eye = np.eye(nn)
    for i in range(b):
        Mi = M[i]
        q = np.diag(lam[i] ** 2) + 0.25 * (Mi @ Mi)
        q = 0.5 * (q + q.T)
        try:
            S = sla.solve_continuous_are(-0.5 * Mi, eye, q, eye)
        except (np.linalg.LinAlgError, ValueError):
            failed[i] = True
            continue
        if not np.all(np.isfinite(S)):
            failed[i] = True
            continue
        S = 0.5 * (S + S.T)
        U[i] = (S + 0.5 * Mi) / lam[i][None, :]
    U[~failed] = _polar(U[~failed]) if np.any(~failed) else U[~failed]
    return U, failed


def _rounding_tol(U: Array, lam: Array) -> Array:
    """10 eps ||offdiag(|U| Lam + Lam |U|^T)||_F: the rounding floor of evaluating J_D(U).

    The off-diagonal entries of J_D(U) are differences U_ij lam_j - lam_i U_ji; each is computed
    with an error of about eps (|U_ij| lam_j + lam_i |U_ji|), which exceeds eps ||M|| when the
    terms cancel (a wide spread of lam far from U = I).  The diagonal is exactly zero.
    """
    A = np.abs(U) * lam[:, None, :]
    S = A + lam[:, :, None] * np.abs(np.swapaxes(U, -1, -2))
    S = S - S * np.eye(U.shape[-1])
    return 10.0 * _EPS * _fro(S)


def _newton(
    U: Array, M: Array, lam: Array, tol: Array, maxiter: int, floor: bool = False
) -> tuple[Array, NDArray[np.int64], Array, NDArray[np.bool_], Array]:
    """Newton iterations on every item until ||J_D(U) - M||_F <= tol (per item); with
    ``floor``, tol is raised to the rounding floor :func:`_rounding_tol` of the current U.

    Returns (U, iterations, residual, converged, the tolerance used).
    """
    U = U.copy()
    b = U.shape[0]
    iters = np.zeros(b, dtype=np.int64)
    slow = np.zeros(b, dtype=np.int64)
    R = M - _jd(U, lam)
    res = _fro(R)
    base = tol
    tol = np.maximum(base, _rounding_tol(U, lam)) if floor else base
    active = res > tol
    for _ in range(maxiter):
        if not active.any():
            break
        # the whole batch is stepped (cheap for the small batches of time steppers); only the
        # active items take the new values
        Unew = _newton_step(U, M, lam, R)
        Rnew = M - _jd(Unew, lam)
        rnew = _fro(Rnew)
        ok = active & np.isfinite(rnew)
        if not ok.all():
            ok &= np.isfinite(Unew).all(axis=(-2, -1))
        old = res
        U = np.where(ok[:, None, None], Unew, U)
        R = np.where(ok[:, None, None], Rnew, R)
        res = np.where(ok, rnew, res)
        iters += active
        # an item stops when it meets tol, when a step is not finite, or after four steps in a
        # row that did not halve the residual (rounding floor or divergence)
        slow = np.where(ok & (rnew > 0.5 * old), slow + 1, 0)
        if floor:
            tol = np.maximum(base, _rounding_tol(U, lam))
        active = ok & (res > tol) & (slow < 4)
    return U, iters, res, res <= tol, tol


def _warm_single(
    U: Array, M: Array, lam: Array, tol: float, maxiter: int, floor: bool = False
) -> tuple[Array, int, float, float] | None:
    """Newton from a nearby U for one (n, n) matrix, with 2-D arrays (lower call overhead for time
    steppers).  Returns (U, iterations, residual) when it converges on the branch, else None (the
    caller then falls back to the batched solver with its Riccati start); with ``floor`` the
    tolerance is raised to the rounding floor (:func:`_rounding_tol`), returned last."""
    nn = lam.shape[0]
    eye = np.eye(nn)
    lam_row, lam_col = lam[None, :], lam[:, None]
    R = M - (U * lam_row - lam_col * U.T)
    r = float(np.sqrt(np.vdot(R, R)))
    it = 0
    slow = 0
    base = tol
    if floor:
        tol = max(base, float(_rounding_tol(U[None], lam[None])[0]))
    while r > tol:
        if it >= maxiter or slow >= 4:
            return None
        X = U * lam_row
        C = 0.5 * (R @ X - X.T @ R)
        try:
            if nn <= _KRON_MAX_N:
                Xt = X.T
                K = (Xt[:, None, :, None] * eye[None, :, None, :]) + (
                    eye[:, None, :, None] * Xt[None, :, None, :]
                )
                T = np.linalg.solve(K.reshape(nn * nn, nn * nn), C.reshape(-1)).reshape(nn, nn)
            else:
                T = sla.solve_sylvester(X.T, X, C)
        except (np.linalg.LinAlgError, ValueError):  # singular: at the fold
            return None
        xi = U.T @ (0.5 * R + 0.5 * (T + T.T)) / lam_row
        xi = 0.5 * (xi - xi.T)
        Unew = U + U @ np.linalg.solve(eye - 0.5 * xi, xi)
        Rnew = M - (Unew * lam_row - lam_col * Unew.T)
        rnew = float(np.sqrt(np.vdot(Rnew, Rnew)))
        it += 1
        if not np.isfinite(rnew):
            return None
        slow = slow + 1 if rnew > 0.5 * r else 0
        U, R, r = Unew, Rnew, rnew
        if floor:
            tol = max(base, float(_rounding_tol(U[None], lam[None])[0]))
    # branch certificate: a positive definite symmetric part of X = U Lam puts every eigenvalue of
    # X in the right half-plane (Cholesky is cheap); otherwise look at the eigenvalues
    X = U * lam_row
    try:
        np.linalg.cholesky(0.5 * (X + X.T))
    except np.linalg.LinAlgError:
        if not np.linalg.eigvals(X).real.min() > 0:
            return None
    return U, it, r, tol


# ---------------------------------------------------------------------------------------------
# fold location


def _has_imaginary_eigenvalue(M: Array, lam: Array, s: float, rtol: float) -> bool:
    nn = lam.shape[-1]
    A = s * M
    eye = np.eye(nn)
    H = np.block([[-0.5 * A, -eye], [-(np.diag(lam**2) + 0.25 * (A @ A)), -0.5 * A]])
    ev = np.linalg.eigvals(H)
    # relative to each eigenvalue's own size: with a wide spread of lam the eigenvalues range
    # over many orders of magnitude (+-lam_i at s = 0), and a threshold relative to ||H|| flagged
    # the small ones as imaginary (fold_scale returned 0 for lam = (3e-6, 1e-6, 1e6)).  H is
    # invertible (det X = det Lam > 0 on the branch), so |ev| > 0.
    return bool(np.min(np.abs(ev.real) / np.abs(ev)) <= rtol)


def _fold_scale_one(M: Array, lam: Array, rtol: float = 1e-13) -> float:
    opn = float(np.linalg.norm(M, 2))
    if opn == 0.0:
        return float("inf")
    # ||J_D(U)||_op <= 2 max(lam) for orthogonal U, so no solution exists beyond s_max
    s_max = 2.0 * float(lam.max()) / opn * (1 + 1e-9)
    thresh = 1e-7
    grid = np.linspace(0.0, s_max, 65)[1:]
    lo, hi = 0.0, None
    for s in grid:
        if _has_imaginary_eigenvalue(M, lam, float(s), thresh):
            hi = float(s)
            break
        lo = float(s)
    if hi is None:
        s = s_max
        while hi is None:
            s *= 1.5
            if s > 1e3 * s_max:  # pragma: no cover - no solution can exist there
                raise NotConvergedError(
                    f"fold_scale: no fold found along the ray up to {s:.4g} (||M||_op = "
                    f"{opn:.4g}, lam = {lam}): the eigenvalues lost their accuracy",
                    float("nan"),
                    0,
                )
            if _has_imaginary_eigenvalue(M, lam, s, thresh):
                hi = s
            else:
                lo = s
    while hi - lo > rtol * hi:
        mid = 0.5 * (lo + hi)
        if _has_imaginary_eigenvalue(M, lam, mid, thresh):
            hi = mid
        else:
            lo = mid
    return 0.5 * (lo + hi)


def fold_scale(M: ArrayLike, lam: ArrayLike) -> Array:
    r"""The scale :math:`t^*` at which the ray :math:`t\mapsto tM` meets the fold of :math:`J_D`.

    :math:`J_D(U) = tM` has a solution on the branch through the identity for :math:`0\le t<t^*`
    and none just past :math:`t^*`; so ``M`` itself is solvable when ``fold_scale(M, lam) > 1``,
    and :math:`t^* - 1` is its relative distance to the fold (negative: past it).  For n = 2,
    :math:`t^* = (\lambda_1+\lambda_2)/|M_{12}|`.  ``inf`` for ``M = 0``.

    Computed as the first :math:`t` where the Hamiltonian matrix of the Riccati form (module
    docstring) has an eigenvalue on the imaginary axis: a scan of :math:`(0, t_{\max}]` with
    :math:`t_{\max}\|M\|_{op} = 2\max\lambda` (beyond which :math:`\|J_D(U)\|_{op}\le 2\max\lambda`
    rules out any solution), then bisection to a relative accuracy of about 1e-13.  The
    eigenvalues near the fold lose accuracy in proportion to the spread of :math:`\lambda`, so
    the result is accurate to about :math:`10^{-13} + 10^5\varepsilon\max\lambda/\min\lambda`
    (relative; up to a tenth of that was measured, 2.3e-6 for a spread of :math:`10^6` with a
    nearly equal pair of small moments): closer to the fold than that, whether a momentum is
    inside is not decided by this function (the solver then reports the fold as reached).
    Beyond a spread of about :math:`10^7` the estimate is unreliable (an error of 23 % was
    measured at a spread of :math:`10^8`).

    Parameters
    ----------
    M : array_like, shape (..., n, n)
        Skew-symmetric matrices.
    lam : array_like, shape (..., n)
        The diagonal of :math:`\Lambda`, all entries > 0.

    Returns
    -------
    ndarray, shape (...)
        :math:`t^*` for each item of the broadcast batch.

    Examples
    --------
    For n = 2 the fold is at :math:`(\lambda_1+\lambda_2)/|M_{12}|`:

    >>> import numpy as np
    >>> import symrb
    >>> print(round(float(symrb.fold_scale([[0.0, 1.0], [-1.0, 0.0]], [1.0, 2.0])), 10))
    3.0
    >>> M = symrb.hat([0.5, 1.0, 1.5])
    >>> t = symrb.fold_scale(M, [0.7, 1.1, 1.6])  # M itself is 4.9 % inside the domain
    >>> print(round(float(t), 4))
    1.0488
    >>> U = symrb.solve_moser_veselov(0.999 * t * M, [0.7, 1.1, 1.6])  # just inside: solvable
    >>> symrb.solve_moser_veselov(1.001 * t * M, [0.7, 1.1, 1.6])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    symrb.errors.OutOfDomainError: ... so M is 0.1 % past the fold; ...
    """
    L = v.inertia(lam, positive=True)
    nn = L.shape[-1]
    A = v.bounded(v.skew(M, "M", nn), "M")
    try:
        batch = np.broadcast_shapes(A.shape[:-2], L.shape[:-1])
    except ValueError:
        raise InputError(
            f"the batch axes do not broadcast: M {A.shape}, lam {L.shape}; pass arrays whose "
            "leading axes broadcast (numpy rules)"
        ) from None
    Ab = np.broadcast_to(A, batch + (nn, nn)).reshape(-1, nn, nn)
    Lb = np.broadcast_to(L, batch + (nn,)).reshape(-1, nn)
    out = np.array([_fold_scale_one(Ab[i], Lb[i]) for i in range(Ab.shape[0])])
    return out.reshape(batch)


# ---------------------------------------------------------------------------------------------
# the solver


def _fold_accuracy(lam: Array) -> float:
    """The relative accuracy of fold_scale: 1e-13 + 1e5 eps max(lam)/min(lam) (measured by the
    property suite under its thorough profile: errors up to about 1e4 eps times the spread, with
    a spread of 1e6 and a nearly equal pair of small moments)."""
    return 1e-13 + 1e5 * _EPS * float(lam.max() / lam.min())


def _out_of_domain(M: Array, lam: Array) -> OutOfDomainError:
    t = _fold_scale_one(M, lam)
    past = (1.0 / t - 1.0) * 100.0 if t > 0 else float("inf")
    return OutOfDomainError(
        "U Lam - Lam U^T = M has no solution on the branch through the identity: M is past the "
        f"fold of J_D. ||M||_F = {np.linalg.norm(M):.6g}, ||M||_op = {np.linalg.norm(M, 2):.6g}, "
        f"lam = {np.array2string(lam, precision=6, threshold=12)}; along the ray t*M the fold is at "
        f"t = {t:.10g} (||M||_F = {t * np.linalg.norm(M):.6g} there), so M is {past:.4g} % past "
        f"the fold; scale M by less than {t:.10g} (for a time step h, take h below {t:.10g} h)"
    )


def _damped_newton(
    U: Array, M: Array, lam: Array, base: float, maxiter: int, floor: bool
) -> tuple[Array, int, float, float] | None:
    """Newton with backtracking on one (n, n) item: a step U cay(a xi) is taken with the largest
    a in 1, 1/2, ..., 2^-20 that lowers the residual and keeps U Lam on the branch (margin > 0).

    Returns (U, iterations, residual, tolerance used), or None when it stalls.
    """
    Ub, Mb, lb = U[None], M[None], lam[None]
    R = Mb - _jd(Ub, lb)
    r = float(_fro(R)[0])
    for it in range(4 * maxiter):
        tol = max(base, float(_rounding_tol(Ub, lb)[0])) if floor else base
        if r <= tol:
            return Ub[0], it, r, tol
        with np.errstate(all="ignore"):
            xi = _solve_linearised(Ub, lb, R)
        if not np.all(np.isfinite(xi)):
            return None
        a = 1.0
        while a > 1e-6:
            Un = _times_cayley(Ub, a * xi)
            Rn = Mb - _jd(Un, lb)
            rn = float(_fro(Rn)[0])
            if rn < (1.0 - a / 4.0) * r and _margin(Un, lb)[0] > 0:
                break
            a *= 0.5
        else:
            return None
        Ub, R, r = Un, Rn, rn
    return None


def _continuation(
    M: Array, lam: Array, tol: float, maxiter: int, floor: bool
) -> tuple[Array, int, float, float, float] | None:
    """Damped Newton along t*M from U = I (t = 0) to t = 1, the step in t adapted; one item.

    Returns (U, iterations, residual, margin, tolerance used) on the branch, or None."""
    U = np.eye(M.shape[-1])
    t, dt, total = 0.0, 0.25, 0
    res = tol_used = 0.0
    for _ in range(400):
        if t >= 1.0:
            return U, total, res, float(_margin(U[None], lam[None])[0]), tol_used
        t_new = min(1.0, t + dt)
        got = _damped_newton(U, t_new * M, lam, tol * t_new, maxiter, floor)
        if got is not None:
            U, it, res, tol_used = got
            total += it
            t, dt = t_new, dt * 1.5
        else:
            dt /= 4.0
            if dt < 1e-12:
                return None
    return None


def _solve_batch(
    M: Array,
    lam: Array,
    tol: Array,
    maxiter: int,
    U0: Array | None = None,
    floor: bool = False,
) -> tuple[Array, NDArray[np.int64], Array, Array, str, Array]:
    """Core solver on flat batches (b, n, n), (b, n); raises on failure.  With ``floor`` each
    tolerance is raised to the rounding floor of evaluating J_D at the solution.

    Returns (U, iterations, residual, margin, start, tolerance used).
    """
    b = M.shape[0]
    start = "warm" if U0 is not None else "riccati"
    base = np.asarray(tol, dtype=float)
    tol = base.copy()
    if U0 is not None:
        U, iters, res, conv, tol = _newton(U0, M, lam, tol, maxiter, floor)
        margin = _margin(U, lam)
        bad = ~conv | ~(margin > 0)
    else:
        U = np.empty_like(M)
        iters = np.zeros(b, dtype=np.int64)
        res = np.full(b, np.inf)
        margin = np.full(b, np.nan)
        bad = np.ones(b, dtype=bool)
    if np.any(bad):
        if U0 is not None:
            start = "mixed"
        idx = np.nonzero(bad)[0]
        G, failed = _riccati_guess(M[idx], lam[idx])
        U2, it2, res2, conv2, tol2 = _newton(G, M[idx], lam[idx], base[idx], maxiter, floor)
        m2 = _margin(U2, lam[idx])
        U[idx], iters[idx], res[idx], margin[idx], tol[idx] = U2, it2, res2, m2, tol2
        still = ~conv2 | ~(m2 > 0)
        # the fallback only under the default tolerance: an explicit tol and maxiter are a
        # budget the caller set (NotConvergedError reports on it)
        for j in np.nonzero(still if floor else np.zeros_like(still))[0]:
            # Riccati failed (scipy gives up on badly scaled lam, e.g. spread 1e12) or Newton
            # from its solution did: follow the branch from U = I along t*M instead
            i = idx[j]
            got = _continuation(M[i], lam[i], float(base[i]), maxiter, floor)
            if got is not None:
                U[i], iters[i], res[i], margin[i], tol[i] = got
                still[j] = False
        for j in np.nonzero(still)[0]:
            i = idx[j]
            t = _fold_scale_one(M[i], lam[i])
            if t <= 1.0:
                raise _out_of_domain(M[i], lam[i])
            acc = _fold_accuracy(lam[i])
            spread = float(lam[i].max() / lam[i].min())
            where = (
                f"M is inside the domain (fold at t = {t:.10g} along t*M)"
                if t > 1.0 + acc
                # fold_scale cannot tell the sides apart this close (the thorough profile found
                # an OutOfDomainError saying "-49.84 % past the fold" for an M half way to it)
                else f"M is at the fold as far as fold_scale can tell (t = {t:.10g} along t*M, "
                f"known to a relative {acc:.2g} at this spread of lam)"
            )
            raise NotConvergedError(
                f"solve_moser_veselov: Newton did not reach tol = {tol[i]:.3e} for batch item {i} "
                f"(residual {res[i]:.3e} after {iters[i]} iterations, branch margin "
                f"{margin[i]:.3e}); {where}. "
                + (
                    f"lam spreads over {spread:.3g}: above 1e6 the solver can stall (a known "
                    "limit); a smaller M (a smaller time step) is further from the fold"
                    if spread > 1e6
                    else "a smaller M (a smaller time step) is further from the fold"
                ),
                residual=float(res[i]),
                iterations=int(iters[i]),
            )
    return U, iters, res, margin, start, tol


def solve_moser_veselov(
    M: ArrayLike,
    lam: ArrayLike,
    *,
    tol: float | None = None,
    maxiter: int = 30,
    U0: ArrayLike | None = None,
    return_info: bool = False,
) -> Array | tuple[Array, MVSolveInfo]:
    r"""Solve :math:`U\Lambda - \Lambda U^T = M` for :math:`U\in SO(n)` on the branch through the identity.

    This is the paper's equation for :math:`U_k` in Section 2.1 (:math:`J_D(U_k) = Q_k^TP_k - P_k^TQ_k`, symmetric
    representation) and, with :math:`U = \Omega^T`, its second Moser-Veselov equation (Section 2.2, :math:`M = \Omega^T\Lambda -
    \Lambda\Omega`, Moser-Veselov).  The returned :math:`U` is the unique solution with every
    eigenvalue of :math:`U\Lambda` in the open right half-plane (equal to :math:`I` at
    :math:`M = 0`, continuous in :math:`M`); see the module docstring for the method (Riccati
    start, Sylvester-Newton polish).

    Parameters
    ----------
    M : array_like, shape (..., n, n)
        Skew-symmetric right-hand sides, n >= 2.
    lam : array_like, shape (..., n)
        The diagonal of :math:`\Lambda`, all entries > 0.
    tol : float, optional
        The residual tolerance on :math:`\|U\Lambda-\Lambda U^T-M\|_F`; by default
        :math:`10\,\varepsilon\max(\|M\|_F, \|\mathrm{offdiag}(|U|\Lambda +
        \Lambda|U|^T)\|_F)` for each item: ten times the rounding error of evaluating the
        residual at the solution, which is about :math:`\|M\|_F` unless the terms
        :math:`U_{ij}\lambda_j` and :math:`\lambda_iU_{ji}` cancel (a wide spread of
        :math:`\lambda` far from :math:`U = I`).
    maxiter : int, optional
        The most Newton iterations.
    U0 : array_like, shape (..., n, n), optional
        A starting guess in SO(n), e.g. the previous step's solution; when Newton from it fails
        or lands off the branch, the Riccati start is used instead.
    return_info : bool, optional
        Also return an :class:`MVSolveInfo`.

    Returns
    -------
    U : ndarray, shape (..., n, n)
        The solutions, in SO(n), for the broadcast batch.
    info : MVSolveInfo
        Only with ``return_info=True``.

    Raises
    ------
    InputError
        ``M`` not skew, ``lam`` not positive, shapes that do not match, ``tol < 0``, ``maxiter < 1``.
    OutOfDomainError
        ``M`` is past the fold (no solution on the branch); the message gives
        :math:`\|M\|`, ``lam`` and how far past the fold ``M`` is (see :func:`fold_scale`).
    NotConvergedError
        Newton failed inside the domain (carries the residual and the iteration count).

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> lam = np.array([0.7, 1.1, 1.6])
    >>> M = symrb.hat([0.5, 1.0, 1.5])
    >>> U = symrb.solve_moser_veselov(M, lam)
    >>> bool(np.allclose(U @ np.diag(lam) - np.diag(lam) @ U.T, M))
    True
    >>> bool(np.allclose(U.T @ U, np.eye(3))), round(float(np.linalg.det(U)), 12)
    (True, 1.0)

    Past the fold there is no solution on the branch:

    >>> symrb.solve_moser_veselov(3 * M, lam)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    symrb.errors.OutOfDomainError: U Lam - Lam U^T = M has no solution on the branch ...
    """
    L = v.inertia(lam, positive=True)
    nn = L.shape[-1]
    A = v.bounded(v.skew(M, "M", nn), "M")
    if tol is not None and not v.real_scalar(tol, "tol") >= 0:
        raise InputError(
            f"tol must be a finite number >= 0, got {tol!r}; pass a float >= 0 or None"
        )
    maxiter = v.count(maxiter, "maxiter", 1)
    batch = np.broadcast_shapes(A.shape[:-2], L.shape[:-1])
    G = None
    if U0 is not None:
        G0 = v.orthogonal(U0, "U0", nn)
        batch = np.broadcast_shapes(batch, G0.shape[:-2])
        G = np.broadcast_to(G0, batch + (nn, nn)).reshape(-1, nn, nn).copy()
    Ab = np.broadcast_to(A, batch + (nn, nn)).reshape(-1, nn, nn)
    Ab = 0.5 * (Ab - np.swapaxes(Ab, -1, -2))  # exactly skew
    Lb = np.broadcast_to(L, batch + (nn,)).reshape(-1, nn)
    normM = _fro(Ab)
    tolb = np.full(Ab.shape[0], float(tol)) if tol is not None else 10.0 * _EPS * normM
    try:
        U, iters, res, margin, start, tolb = _solve_batch(
            Ab, Lb, tolb, int(maxiter), G, floor=tol is None
        )
    except (ArithmeticError, np.linalg.LinAlgError) as exc:
        raise OutOfDomainError(
            f"solve_moser_veselov: float64 arithmetic failed ({type(exc).__name__}: {exc}) for "
            f"max ||M||_F = {float(normM.max(initial=0.0)):.4g} against min lam_i = "
            f"{float(Lb.min()):.4g}: M is far past the fold of J_D or the scales overflow; "
            "scale M down (see fold_scale)"
        ) from None
    U = U.reshape(batch + (nn, nn))
    if not return_info:
        return U
    orth = _fro(np.swapaxes(U, -1, -2) @ U - np.eye(nn))
    info = MVSolveInfo(
        iterations=iters.reshape(batch),
        residual=res.reshape(batch),
        tol=tolb.reshape(batch),
        orthogonality=np.asarray(orth).reshape(batch),
        margin=margin.reshape(batch),
        start=start,
        condition=_condition(U.reshape(-1, nn, nn), Lb).reshape(batch),
    )
    return U, info
