r"""A fast Moser-Veselov step: Newton on the Cayley coordinates, batched, with an n = 3 kernel.

The map is the discrete rigid body of :func:`symrb.discrete_rigid_body_flow` in
:math:`(Q, M)` form (MV-Algorithm 2 with continuous-scale momenta): solve

.. math:: U\Lambda - \Lambda U^T = hM_k, \qquad Q_{k+1} = Q_kU, \qquad M_{k+1} = U^TM_kU

(:math:`U = \Omega_k^T` of the paper's second and third Moser-Veselov equations).  The unknown is
written :math:`U = \operatorname{cay}(X) = (I + X)(I - X)^{-1}` with :math:`X` skew, so every
:math:`U` is orthogonal to rounding whatever the Newton error, and multiplying the equation by
:math:`I - X` on the left and :math:`I + X` on the right turns it into the quadratic equation

.. math:: G(X) = 2J(X) - (I - X)\,B\,(I + X) = 0, \qquad B = hM,\; J(X) = \Lambda X + X\Lambda.

* n = 3: with :math:`X = \hat x`, :math:`G` is :math:`2\,I\circ x - b - b\times x - (b\cdot x)x`
  (:math:`I_1 = \lambda_2+\lambda_3`, cyclic; :math:`b = hm`).  With the scalar
  :math:`s = b\cdot x` this is the linear system :math:`(D_s - \hat b)x = b`,
  :math:`D_s = \operatorname{diag}(2I - s)`, so :math:`x = z(s)/\det(s)` (adjugate) and :math:`s`
  is a root of the quartic :math:`p(s) = s\det(s) - b\cdot z(s)`.  The map conserves
  :math:`s/h^2` (to rounding), so at a fixed ``h`` the previous step's :math:`s` is the root: a
  step is one call of the generated kernel ``mv3_cayley_step`` (one Newton step on :math:`p`,
  whose size is checked, then :math:`x`, :math:`U` and the update :math:`(QU, U^Tm)`); the first
  step, a changed ``h`` or a rejected check iterate ``mv3_cayley_s_newton`` and check the branch.
  Method check M1 checks both kernels symbolically (M2 checks this function's runs).  One body
  runs on Python floats, a batch on structure-of-arrays component vectors.
* general n: Newton's linear equation is the Lyapunov equation
  :math:`P\,dX + dX\,P^T = -G`, :math:`P = 2\Lambda - (I - X)B`, solved on the
  :math:`n(n-1)/2` skew unknowns as one batched dense system (``method="newton"``); or the
  fixed-point iteration :math:`X \leftarrow X - \tfrac12 W\circ G(X)`,
  :math:`W_{ij} = 1/(\lambda_i+\lambda_j)` (two matrix products an iteration, contraction about
  :math:`\|X\|`; ``method="fixed-point"``).  ``"auto"`` uses Newton for n <= 6 and the
  fixed point above, switching to Newton for items where it stalls.

Warm start: each step starts from :math:`X = h\,w` with :math:`w = X/h` of the previous
step (:math:`w \approx \Omega/2`; for n = 3, :math:`s = h^2\sigma` with :math:`\sigma = s/h^2`), so a
caller that changes ``h`` between steps (a composition method's sub-steps) still starts close to
the solution.  The cold start is :math:`X_0 = \tfrac12 W\circ B` (:math:`= \tfrac h2 J^{-1}(M)`;
n = 3: :math:`s_0 = b\cdot x_0`); an item whose Newton iteration
fails (near the fold of :math:`J_D`) is solved by :func:`symrb.solve_moser_veselov` (Riccati start),
which raises :class:`~symrb.errors.OutOfDomainError` past the fold.  Nothing is validated inside
the step loop: :func:`mv_flow` validates once (one n = 3 body of float64 arrays by a few scalar
operations, :mod:`symrb._mv3`, with the branch check of the cold start in scalars too);
:meth:`MVStepper.step` trusts its arguments.

Preprocessing (n = 3, ``mv_flow(..., order=4, 6, 8 or 10)``): Hairer and Vilmart (2006) showed
that one Moser-Veselov step of a body whose inertia is modified as a function of ``h``, of
:math:`|m|^2` and of the energy, :math:`1/\tilde I_i = c/I_i + d`, is the step ``h`` of the
original body's flow to order 4, 6, 8 or 10, in the momentum and the attitude.  The constants
of :math:`c` and :math:`d` are the generated ``mv3_preprocessing_coefficients`` (computed once),
the modified :math:`\tilde\Lambda` of a step the generated ``mv3_preprocessed_lam``; method check M3
checks the composition with exact rational power series in ``h`` against the Taylor series of
the exact flow.  The cost of a step is one more kernel call; the map stays symplectic and
conserves :math:`|m|` exactly (the modified body is a rigid body), the energy to the order.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _compiled, _compiled_n
from . import _validate as v
from ._docs import fill
from ._generated import discrete_rigid_body as _gen
from ._mv3 import (
    _check_modified,
    _columns,
    _first_step_one,
    _hat_cols,
    _max_abs,
    _on_branch,
    _one_body,
    _preprocessing,
    _s_cold,
    _solve_s3,
    _step3,
    _vee_cols,
)
from ._mv3 import _kernel3 as _kernel3
from ._results import STEP_FAILURES, DiscreteFlowSolution, Trajectory, step_failure
from ._stepping import _check_h, _check_steps, _prepare
from ._validate import Array
from .errors import InputError
from .solvers import solve_moser_veselov

__all__ = ["MVStepper", "mv_flow"]

#: The orders of the preprocessed Moser-Veselov method (n = 3), 2 meaning none.
PREPROCESSED_ORDERS = (2, 4, 6, 8, 10)

_EPS = float(np.finfo(float).eps)
#: Newton stops after a step with max |dx| <= this: the error left is about ||x|| dx^2 << eps.
_NEWTON_DX = 1e-9
_MAXITER = 12
_MAXITER_FP = 60
_KRON_MAX_N = 6
_SOLVERS = ("auto", "newton", "fixed-point")
_FLOW_METHODS = _SOLVERS + ("numpy", "numba")
_EYE3 = np.eye(3)
_WH_UNUSED = np.full((1, 3, 3), np.nan)  # MVStepper._one3: n = 3 never uses the fixed point
_NUMBA_MIN_WORK_N = 2_000_000  # n != 3: steps * bodies * n^3 (2000 steps at n = 10, ~0.4 s)
# ---------------------------------------------------------------------------------------------
# general n


def _G(X: Array, B: Array, lam: Array) -> Array:
    """2J(X) - (I - X) B (I + X) for skew X, B (flat batch)."""
    BX = B @ X
    XB = np.swapaxes(BX, -1, -2)  # (B X)^T = X B for skew X, B
    return 2.0 * (lam[:, :, None] * X + X * lam[:, None, :]) - B - BX + XB + X @ BX


class _Kron:
    """Index arrays of the Lyapunov operator P dX + dX P^T on the skew unknowns (i < j)."""

    def __init__(self, n: int) -> None:
        iu, ju = np.triu_indices(n, 1)
        self.n, self.iu, self.ju = n, iu, ju
        r_i, r_j = iu[:, None], ju[:, None]
        c_a, c_b = iu[None, :], ju[None, :]
        self.idx = (r_i, r_j, c_a, c_b)
        self.masks = [
            (r_j == c_b).astype(float),
            (r_j == c_a).astype(float),
            (r_i == c_a).astype(float),
            (r_i == c_b).astype(float),
        ]

    def matrix(self, P: Array) -> Array:
        """The matrix of dX -> P dX + dX P^T on the skew unknowns, batched."""
        r_i, r_j, c_a, c_b = self.idx
        m1, m2, m3, m4 = self.masks
        K: Array = (
            P[:, r_i, c_a] * m1 - P[:, r_i, c_b] * m2 + P[:, r_j, c_b] * m3 - P[:, r_j, c_a] * m4
        )
        return K

    def unpack(self, y: Any) -> Array:
        dX = np.zeros(y.shape[:-1] + (self.n, self.n))
        dX[:, self.iu, self.ju] = y
        dX[:, self.ju, self.iu] = -y
        return dX

    def solve(self, P: Array, C: Array) -> Array:
        """dX skew with P dX + dX P^T = C (C skew), batched."""
        y = np.linalg.solve(self.matrix(P), C[:, self.iu, self.ju][..., None])[..., 0]
        return self.unpack(y)


def _newton_n(
    X: Array, B: Array, lam: Array, kron: _Kron, eye: Array
) -> tuple[Array, int, NDArray[np.bool_]]:
    """Newton with the Lyapunov solve; returns (X, sweeps, converged mask)."""
    conv = np.zeros(X.shape[0], dtype=bool)
    for it in range(1, _MAXITER + 1):
        G = _G(X, B, lam)
        P = 2.0 * lam[:, :, None] * eye - B + X @ B
        dX = kron.solve(P, -G)
        X = X + dX
        err = np.abs(dX).max(axis=(-2, -1))
        conv = err <= _NEWTON_DX
        if conv.all():
            return X, it, conv
        if not np.all(err < 1e3):
            break
    return X, _MAXITER, conv


def _fixed_point_n(
    X: Array, B: Array, lam: Array, Wh: Array
) -> tuple[Array, int, NDArray[np.bool_]]:
    """X <- X - W o G(X) / 2 until the change is at the rounding floor; (X, sweeps, converged)."""
    prev = np.full(X.shape[0], np.inf)
    conv = np.zeros(X.shape[0], dtype=bool)
    for it in range(1, _MAXITER_FP + 1):
        dX = Wh * _G(X, B, lam)
        X = X - dX
        err = np.abs(dX).max(axis=(-2, -1))
        floor = 8.0 * _EPS * np.abs(X).max(axis=(-2, -1))
        # at the rounding floor, or stalled just above it (rounding noise of G)
        conv = (err <= floor) | ((err <= 8.0 * floor) & (err >= 0.9 * prev))
        if conv.all():
            return X, it, conv
        if not np.all(err < 1e3):
            break
        prev = err
    return X, _MAXITER_FP, conv


def _cay(X: Array, eye: Array) -> Array:
    """cay(X) = (I + X)(I - X)^{-1} = I + D (the one formula, :func:`_cay_increment`)."""
    return eye + _cay_increment(X, eye)


def _cay_increment(X: Array, eye: Array) -> Array:
    """D = cay(X) - I = 2 (I - X)^{-1} X, computed as such (small, O(||X||)), so that an update
    Q + QD rounds the O(h) increment rather than a product with an O(1) matrix (Brouwer's law:
    the rounding errors of U = I + D then do not accumulate with a bias)."""
    D: Array = 2.0 * np.asarray(np.linalg.solve(eye - X, X), dtype=np.float64)
    return D


def _cay_inverse(U: Array, eye: Array) -> Array:
    """X = (U - I)(U + I)^{-1}, made exactly skew."""
    X = np.swapaxes(np.linalg.solve(np.swapaxes(U + eye, -1, -2), np.swapaxes(U - eye, -1, -2)),
                    -1, -2)  # fmt: skip
    out: Array = np.asarray(0.5 * (X - np.swapaxes(X, -1, -2)), dtype=np.float64)
    return out


# ---------------------------------------------------------------------------------------------
# the stepper


@fill
class MVStepper:
    r"""One Moser-Veselov step :math:`(Q, M) \mapsto (Q_1, M_1)` with an internal warm start.

    Solves :math:`U\Lambda - \Lambda U^T = hM` for :math:`U = \operatorname{cay}(X)` by Newton
    on :math:`X` (module docstring) and returns :math:`(QU, U^TMU)`: the same map, at the same
    scaling (``M`` the continuous body momentum), as one step of
    :func:`symrb.discrete_rigid_body_flow`.

    Parameters
    ----------
    %(lam_positive)s
    batch_shape : tuple of int, optional
        The batch axes of the states the stepper will be given (broadcast with those of
        ``lam``); ``()`` for one body.
    method : {"auto", "newton", "fixed-point"}, optional
        The solver for n != 3 (n = 3 always uses the generated Newton kernel).

    Notes
    -----
    The warm start is :math:`X = h\,w` with :math:`w = X/h` from the previous call, so a
    composition method may call :meth:`step` with different (even negative) ``h`` on one stepper:
    the guess is then still :math:`O(h^2)` from the solution and Newton only takes an iteration
    or two more; a stepper per distinct sub-step length keeps every warm start at its best.
    :meth:`step` does not validate its arguments (use :func:`mv_flow` or validate once outside
    the loop) and never mutates them.  ``iterations`` holds the Newton sweeps of the last step.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> from symrb.engine import MVStepper
    >>> lam = np.array([0.7, 1.1, 1.6])
    >>> Q, M = np.eye(3), symrb.hat([0.5, 1.0, 1.5])
    >>> stepper = MVStepper(lam)
    >>> Q1, M1 = stepper.step(Q, M, 0.1)
    >>> ref = symrb.discrete_rigid_body_flow(Q, M, lam, 0.1, 1)
    >>> bool(np.abs(Q1 - ref.y.Q[-1]).max() < 1e-14 and np.abs(M1 - ref.y.M[-1]).max() < 1e-14)
    True
    """

    def __init__(
        self, lam: ArrayLike, batch_shape: tuple[int, ...] = (), *, method: str = "auto"
    ) -> None:
        L = v.inertia(lam, positive=True)
        if method not in ("auto", "newton", "fixed-point"):
            raise InputError(f"method must be 'auto', 'newton' or 'fixed-point', got {method!r}")
        try:
            shape = tuple(int(s) for s in batch_shape)
            batch = np.broadcast_shapes(L.shape[:-1], shape)
        except (TypeError, ValueError):
            raise InputError(
                f"batch_shape must be a tuple of ints that broadcasts with lam {L.shape}, "
                f"got {batch_shape!r}"
            ) from None
        n = L.shape[-1]
        self.n, self.batch_shape, self.method = n, batch, method
        self.size = math.prod(batch)
        self.lam = np.ascontiguousarray(np.broadcast_to(L, batch + (n,)).reshape(-1, n))
        self.iterations = 0
        self._w: Any = None  # the warm start, X/h (general n)
        self._w_prev: Any = None  # the one before, when the last two steps had the same h
        self._h_prev: tuple[float | None, float] | None = None  # the h of the last two steps
        self._h_last: float | None = None
        self._eye = np.eye(n)
        self._Wh = 0.5 / (self.lam[:, :, None] + self.lam[:, None, :])
        self._kron = _Kron(n) if 3 < n <= 12 else None  # n = 3 has its own kernels
        self._sigma: Any = None  # n = 3: the warm start s/h^2 (s/h^2 is conserved)
        if n == 3:
            # floats when every body has the same lam (scalar arithmetic in the kernels)
            one = bool(np.all(self.lam == self.lam[:1]))
            lam_c: Any = (
                tuple(float(x) for x in self.lam[0])
                if one
                else tuple(np.ascontiguousarray(self.lam[:, i]) for i in range(3))
            )
            self._lam_c = lam_c
            # Newton on p stops at |ds| <= 1e-9 min_i 2 I_i: the error left, about ds^2 p''/p',
            # is far below rounding (s itself is O(|b|^2 / I))
            tol = 2e-9 * (self.lam.sum(axis=-1) - self.lam.max(axis=-1))
            self._tol: Any = float(tol[0]) if one else tol
            self._tol_max = float(np.min(tol))

    @classmethod
    def _one3(cls, lam: tuple[float, ...]) -> MVStepper:
        """The stepper of one n = 3 body with a validated ``lam`` (floats): what ``__init__``
        builds for it, without the checks (:func:`mv_flow`'s fast path)."""
        self = cls.__new__(cls)
        l1, l2, l3 = lam
        self.n, self.batch_shape, self.method, self.size = 3, (), "auto", 1
        self.lam = np.array([[l1, l2, l3]])
        self.iterations = 0
        self._w = self._w_prev = self._h_prev = self._h_last = self._sigma = None
        self._eye = _EYE3  # read only, as are _Wh and _kron (general n only)
        self._Wh = _WH_UNUSED
        self._kron = None
        self._lam_c = (l1, l2, l3)
        self._tol = self._tol_max = 2e-9 * (l1 + l2 + l3 - max(l1, l2, l3))
        return self

    # n = 3: Python floats for one body, component vectors for a batch --------------------------
    def _step3(self, h: float, m: Any, q: Any, lam: Any = None) -> tuple[Any, ...]:
        """The outputs of mv3_cayley_step, (s, ds, m_next (3), Q_next (9)), at a root s
        (``lam``: a modified Lambda for this step, as components, instead of the stepper's)."""
        lam = self._lam_c if lam is None else lam
        cold = self._sigma is None
        s = _s_cold(h, m, lam) if cold else h * h * self._sigma
        out: Any = None
        if not cold:
            out = _step3(s, h, *m, *lam, *q)
            it = 1
        if cold and type(s) is float and type(q[0]) is float and type(self._tol) is float:
            out, it = _first_step_one(s, h, m, lam, q, self._tol)  # one body with an attitude
        elif out is None or not _max_abs(out[1]) <= self._tol_max:
            s, it = _solve_s3(s, h, m, lam, self._tol, check=True)
            out = _step3(s, h, *m, *lam, *q)
            it += 1
        self._sigma = out[0] / (h * h)
        self.iterations = it
        return out

    # general n ------------------------------------------------------------------------------
    def _X_n(self, B: Array, h: float) -> Array:
        cold = self._w is None
        if cold:
            X0: Array = self._Wh * B
        elif self._w_prev is not None and self._h_prev == (h, h):
            X0 = h * (2.0 * self._w - self._w_prev)  # fixed h: extrapolate the last two steps
        else:
            X0 = h * self._w
        kron = self._kron
        use_newton = self.method == "newton" or (self.method == "auto" and self.n <= _KRON_MAX_N)
        if use_newton and kron is not None:
            X, it, conv = _newton_n(X0, B, self.lam, kron, self._eye)
        else:
            X, it, conv = _fixed_point_n(X0, B, self.lam, self._Wh)
            if not conv.all() and self.method != "fixed-point" and kron is not None:
                idx = np.nonzero(~conv)[0]
                X2, it2, conv2 = _newton_n(X0[idx], B[idx], self.lam[idx], kron, self._eye)
                X[idx], conv[idx] = X2, conv2
                it += it2
        if cold:
            conv &= _on_branch(_cay(X, self._eye), self.lam)
        if not conv.all():
            idx = np.nonzero(~conv)[0]
            U = np.asarray(solve_moser_veselov(B[idx], self.lam[idx]))
            X[idx] = _cay_inverse(U, self._eye)
        self.iterations = it
        self._w_prev = self._w
        self._h_prev = (self._h_last, h)
        self._h_last = h
        self._w = X / h
        return X

    def step(self, Q: ArrayLike, M: ArrayLike, h: float) -> tuple[Array, Array]:
        r"""One step: solve :math:`J_D(U) = hM` and return :math:`(QU, U^TMU)`.

        Parameters
        ----------
        Q : array_like, shape (..., n, n)
            The attitude, in SO(n).
        M : array_like, shape (..., n, n)
            The body momentum (skew, continuous scale).
        h : float
            The (sub-)step, nonzero.

        Returns
        -------
        Q1, M1 : ndarray, shape (..., n, n)

        Raises
        ------
        OutOfDomainError
            When :math:`hM` is past the fold of :math:`J_D` (from the Riccati fallback).
        """
        h = float(h)
        Qa = np.asarray(Q, dtype=float)
        Ma = np.asarray(M, dtype=float)
        n = self.n
        if n == 3 and self.size == 1:
            q = Qa.reshape(9).tolist()
            mm = Ma.reshape(9).tolist()
            out = self._step3(h, (mm[7], mm[2], mm[3]), q)
            m1 = out[2:5]
            M1 = np.array([[0.0, -m1[2], m1[1]], [m1[2], 0.0, -m1[0]], [-m1[1], m1[0], 0.0]])
            return np.array(out[5:]).reshape(Qa.shape), M1.reshape(Ma.shape)
        Qf = Qa.reshape(-1, n, n)
        Mf = Ma.reshape(-1, n, n)
        if n == 3:
            mc = _vee_cols(Mf)
            qc = [Qf[:, i, j].copy() for i in range(3) for j in range(3)]
            out = self._step3(h, mc, qc)
            Q1 = np.stack(out[5:], axis=-1).reshape(Qa.shape)
            return Q1, _hat_cols(list(out[2:5])).reshape(Ma.shape)
        X = self._X_n(h * Mf, h)
        # with U = I + D: QU = Q + QD and, M being skew, U^T M U = M + MD - (MD)^T + D^T(MD):
        # the O(1) state is added to once, to an O(h) increment (what keeps the rounding errors
        # of a long run a random walk, growing like eps sqrt(N), rather than eps N).  The
        # increment is made exactly skew: D^T(MD) is skew only to rounding, and a symmetric part
        # S of M is carried as S + D^T S D (the terms SD + D^T S cancel in the antisymmetrised
        # products), which grows by up to (1 + ||D||^2) a step: from rounding to O(||M||) in
        # 10^4 steps at h ||M|| ~ 0.3 before this was written so
        D = _cay_increment(X, self._eye)
        MD = Mf @ D
        DMD = np.swapaxes(D, -1, -2) @ MD
        dM = (MD - np.swapaxes(MD, -1, -2)) + 0.5 * (DMD - np.swapaxes(DMD, -1, -2))
        return (Qf + Qf @ D).reshape(Qa.shape), (Mf + dM).reshape(Ma.shape)


# ---------------------------------------------------------------------------------------------
# the flow


@fill
def mv_flow(
    Q0: ArrayLike,
    M0: ArrayLike,
    lam: ArrayLike,
    h: float,
    steps: int,
    *,
    save_every: int = 1,
    method: str = "auto",
    order: int = 2,
) -> DiscreteFlowSolution:
    r"""The discrete rigid body at step ``h`` by the Cayley-Newton engine (module docstring).

    The same map and scaling as :func:`symrb.discrete_rigid_body_flow` (agreement to rounding):
    :math:`J_D(U_k) = hM_k`, :math:`Q_{k+1} = Q_kU_k`, :math:`M_{k+1} = U_k^TM_kU_k`, with
    ``M`` the continuous body momentum.  Input is validated once; the loop keeps the state in
    the solver's layout (floats for one body, component vectors for a batch, n = 3) and converts
    only the saved states.

    Parameters
    ----------
    %(Q0)s
    %(M0)s
    %(lam_positive)s
    %(h)s
    %(steps)s
    %(save_every)s
    method : str, optional
        One of ``"auto"``, ``"newton"``, ``"fixed-point"``, ``"numpy"``, ``"numba"``: the solver
        for n != 3 (``"newton"``, ``"fixed-point"``; see :class:`MVStepper`), or the backend:
        ``"numpy"`` the NumPy path (the reference), ``"numba"`` the compiled loop of
        :mod:`symrb._compiled` (n = 3) or :mod:`symrb._compiled_n` (needs numba; results equal
        to rounding), ``"auto"`` compiled when numba is importable and the run has at least
        2 * 10^4 body-steps (n = 3) or steps * bodies * n^3 >= 2 * 10^6, else NumPy.  The
        compiled loops are compiled on their first use in a process and cached on disk by numba
        (``cache=True``), so later processes load them: into the environment variable
        ``NUMBA_CACHE_DIR`` if set, else into the ``__pycache__`` beside each module when numba
        can write there, else (a read-only installation) into numba's user-wide cache
        directory, ``~/.cache/numba`` on Linux (details in :mod:`symrb._compiled`).
    order : {2, 4, 6, 8, 10}, optional
        2: the Moser-Veselov map itself.  4 to 10 (n = 3 only): the preprocessed method of
        Hairer and Vilmart (2006), each step with the modified :math:`\tilde\Lambda(h, m)` of
        the module docstring; an approximation of the continuous flow of that order in both
        :math:`M` and :math:`Q`.

    Returns
    -------
    DiscreteFlowSolution
        ``t`` the times :math:`kh`; ``y.Q`` and ``y.M`` of shape ``(K, ..., n, n)``;
        ``iterations`` the Newton sweeps of each step times the number of bodies (a sweep steps
        the whole batch).  A step past the fold of :math:`J_D` ends the run with ``success``
        False, as in :func:`symrb.discrete_rigid_body_flow`.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> from symrb.engine import mv_flow
    >>> lam = np.array([0.7, 1.1, 1.6])
    >>> M0 = symrb.hat([0.5, 1.0, 1.5])
    >>> sol = mv_flow(np.eye(3), M0, lam, 0.01, 1000, save_every=500)
    >>> ref = symrb.discrete_rigid_body_flow(np.eye(3), M0, lam, 0.01, 1000, save_every=500)
    >>> sol.t
    array([ 0.,  5., 10.])
    >>> bool(np.abs(sol.y.Q - ref.y.Q).max() < 1e-12)
    True

    A batch of bodies steps together (no loop over bodies):

    >>> Ms = M0 * np.linspace(0.5, 1.0, 4)[:, None, None]
    >>> mv_flow(np.eye(3), Ms, lam, 0.01, 10).y.M.shape
    (11, 4, 3, 3)

    Order 10 at a step of 0.1 against the exact solution (:func:`symrb.exact.rigid_body_exact`):

    >>> ex = symrb.exact.rigid_body_exact(np.eye(3), M0, lam, [10.0])
    >>> sol = mv_flow(np.eye(3), M0, lam, 0.1, 100, save_every=100, order=10)
    >>> bool(np.abs(sol.y.M[-1] - ex.y.M[-1]).max() < 1e-11)
    True
    """
    if not (type(h) is float and 0.0 < h < math.inf):  # (the common case: no checks)
        h = _check_h(h)
    if not (type(steps) is int and type(save_every) is int and steps >= 0 and save_every >= 1):
        steps, save_every = _check_steps(steps, save_every)
    if method not in _FLOW_METHODS:
        raise InputError(f"method must be one of {', '.join(_FLOW_METHODS)}, got {method!r}")
    if isinstance(order, bool) or order not in PREPROCESSED_ORDERS:
        raise InputError(f"order must be one of {PREPROCESSED_ORDERS}, got {order!r}")
    Q, M, stepper = _flow_inputs(Q0, M0, lam, method if method in _SOLVERS else "auto")
    n = stepper.n
    if order != 2 and n != 3:
        raise InputError(
            f"order {order} (the preprocessed Moser-Veselov method) needs n = 3, got n = {n}; "
            "for higher order at any n use symrb.compose.composed_rigid_body_flow"
        )
    if method == "numba" and not (_compiled.AVAILABLE if n == 3 else _compiled_n.AVAILABLE):
        raise InputError("method 'numba' needs numba installed (pip install numba)")
    numba_n = n != 3 and (method == "numba" or (method == "auto" and _compiled_n.AVAILABLE
                          and steps * stepper.size * n**3 >= _NUMBA_MIN_WORK_N))  # fmt: skip
    use_numba = n == 3 and (
        method == "numba"
        or (method == "auto" and _compiled.AVAILABLE and steps * stepper.size >= _compiled.MIN_WORK)
    )
    run = _FlowRun(Q, M, stepper, steps, save_every)
    failure = ""
    try:
        if n == 3:
            run.loop3(h, order, use_numba)
            if use_numba and steps > 1 and not run.compiled(h):
                # the NumPy path has the Riccati fallback and the fold diagnosis
                return mv_flow(
                    Q0, M0, lam, h, steps, save_every=save_every, method="numpy", order=order
                )
        elif not run.loop_n(h, numba_n):  # an item failed in the compiled loop
            return mv_flow(Q0, M0, lam, h, steps, save_every=save_every, method="numpy")
    except STEP_FAILURES as exc:
        failure = f"step {run.k} of {steps} failed: {step_failure(exc)}"
        run.k -= 1
        if run.ks[-1] != run.k:  # the state before the failed step
            run.save()
    return run.result(h, order, failure)


def _flow_inputs(Q0: ArrayLike, M0: ArrayLike, lam: ArrayLike, method: str
                 ) -> tuple[Array, Array, MVStepper]:  # fmt: skip
    """:func:`mv_flow`'s validated ``Q0`` (a copy), the skew part of ``M0`` and the stepper;
    one n = 3 body by the scalar fast path (:func:`symrb._mv3._one_body`)."""
    one = _one_body(Q0, M0, lam) if method == "auto" else None  # (n = 3 ignores the solver)
    if one is not None:
        return one[0], one[1], MVStepper._one3(one[2])
    L, (Q, M), batch = _prepare(lam, (Q0, "Q0", "SO"), (M0, "M0", "skew"))
    return Q, 0.5 * (M - np.swapaxes(M, -1, -2)), MVStepper(L, batch, method=method)


def _mv_momentum_flow(M0: ArrayLike, lam: ArrayLike, h: float, steps: int, save_every: int,
                      method: str = "auto", order: int = 2) -> DiscreteFlowSolution:  # fmt: skip
    """:func:`mv_flow` of one body without its attitude: the same steps on M (M bit for bit;
    ``method="numba"`` runs the NumPy loop, the compiled one carries Q), no Q ever stepped
    (``y`` holds M alone): the momentum form :math:`M_{k+1} = U_k^TM_kU_k` needs only the
    :math:`U_k` of :math:`J_D(U_k) = hM_k`."""
    L, (M,), batch = _prepare(lam, (M0, "M0", "skew"))
    if batch:
        raise InputError(f"one body only: M0 of shape (n, n) and lam (n,), got batch {batch}")
    stepper = MVStepper(L, batch, method=method if method in _SOLVERS else "auto")
    run = _FlowRun(None, 0.5 * (M - M.T), stepper, steps, save_every)
    try:
        run.loop3(h, order, False) if run.n == 3 else run.loop_n(h)
        failure = ""
    except STEP_FAILURES as exc:
        failure, run.k = f"step {run.k} of {steps} failed: {step_failure(exc)}", run.k - 1
        if run.ks[-1] != run.k:
            run.save()
    return run.result(h, order, failure)


class _FlowRun:
    """The state of one :func:`mv_flow` run and the states it saved.  For n = 3 the state is
    kept in the kernels' layout: floats (one body) or component vectors (a batch).  ``Q`` None:
    no attitude (one body), Q neither stepped nor saved (its n = 3 components are empty)."""

    def __init__(self, Q: Array | None, M: Array, stepper: MVStepper, steps: int,
                 save_every: int) -> None:  # fmt: skip
        self.attitude = Q is not None
        if Q is None:
            Q = np.empty((0,) + M.shape[-2:])
        self.shapes = (Q.shape, M.shape)
        self.stepper, self.size, self.n = stepper, stepper.size, Q.shape[-1]
        self.steps, self.save_every = steps, save_every
        self.ks: list[int] = [0]
        self.Qs: list[Array] = [Q.copy()] if self.attitude else []
        self.Ms: list[Array] = [M.copy()]
        self.iters = np.full(steps, 1 if self.n == 3 else 0, dtype=np.int64)
        self.k = 0
        self.Qk, self.Mk = Q, M
        self.s: Any = None
        self.coef: tuple[Any, ...] | None = None
        if self.n != 3:
            return
        if self.size == 1 or not self.attitude:  # no attitude: the kernel's Q parts are empty
            self.q: Any = tuple(Q.reshape(9).tolist()) if self.attitude else (np.empty(0),) * 9
            mm = M.reshape(9).tolist()
            self.m: Any = (mm[7], mm[2], mm[3])
        else:
            Mf, Qf = M.reshape(-1, 3, 3), Q.reshape(-1, 3, 3)
            self.m = tuple(_vee_cols(Mf))
            self.q = tuple(Qf[:, i, j].copy() for i in range(3) for j in range(3))

    def save(self) -> None:
        """Keep the current state, at step ``self.k``."""
        self.ks.append(self.k)
        Qshape, Mshape = self.shapes
        if self.n != 3:
            self.Qs += [self.Qk] if self.attitude else []
            self.Ms.append(self.Mk)
        elif self.size == 1 or not self.attitude:
            self.Qs += [np.array(self.q).reshape(Qshape)] if self.attitude else []
            m1, m2, m3 = self.m  # floats: hat(m) directly
            self.Ms.append(
                np.array([[0.0, -m3, m2], [m3, 0.0, -m1], [-m2, m1, 0.0]]).reshape(Mshape)
            )
        else:
            self.Qs.append(np.stack(self.q, axis=-1).reshape(Qshape))
            self.Ms.append(_hat_cols(list(self.m)).reshape(Mshape))

    def loop3(self, h: float, order: int, use_numba: bool) -> None:
        """n = 3 (only the first step when the compiled loop takes the rest).  Fast path: h is
        fixed and s = b.x is conserved by the map, so the previous step's s is the root to
        rounding and one fused kernel call (one Newton step on p, the update) is the whole
        step; |ds| > tol (first step, rounding trouble) takes the stepper's slow path."""
        stepper, size = self.stepper, self.size
        lam_c, tol = stepper._lam_c, stepper._tol_max
        coef = self.coef = _preprocessing(order, lam_c)
        for k in range(1, (min(self.steps, 1) if use_numba else self.steps) + 1):
            self.k = k
            out = None
            m, q = self.m, self.q
            lam_k = lam_c if coef is None else _gen.mv3_preprocessed_lam(h, *m, *lam_c, *coef)
            if self.s is not None:
                out = _step3(self.s, h, *m, *lam_k, *q)
                ds = out[1]
                if not (abs(ds) if size == 1 else np.abs(ds).max()) <= tol:
                    out = None
            if out is None:
                if coef is not None:
                    _check_modified(lam_k, h, order)
                out = stepper._step3(h, m, q, lam_k)
                self.iters[k - 1] = stepper.iterations
            self.s, self.m, self.q = out[0], out[2:5], out[5:]
            if k % self.save_every == 0:
                self.save()
        if size != 1:
            self.iters *= size

    def compiled(self, h: float) -> bool:
        """Steps 2.. by the compiled loop of :mod:`symrb._compiled`; False if an item failed."""
        stepper, size, steps, save_every = self.stepper, self.size, self.steps, self.save_every
        Qshape, Mshape = self.shapes
        self.k = 1
        coef = self.coef
        st, tv = (
            np.broadcast_to(np.asarray(x, dtype=float), (size,)) for x in (self.s, stepper._tol)
        )
        mv, qv = _columns(self.m, size), _columns(self.q, size)
        cv = None if coef is None else _columns(coef, size)
        ms, qs, fail, extra = _compiled.run_mv3(
            st, h, mv, stepper.lam, qv, tv, steps - 1, save_every, k0=1, coef=cv
        )
        if fail.any():
            return False
        self.iters[1:] += extra
        for j, kj in enumerate(range(max(save_every, 2), steps + 1, save_every)):
            self.ks.append(kj)
            self.Qs.append(qs[j].reshape(Qshape))
            self.Ms.append(_hat_cols([ms[j, :, 0], ms[j, :, 1], ms[j, :, 2]]).reshape(Mshape))
        self.k = steps
        return True

    def loop_n(self, h: float, use_numba: bool = False) -> bool:
        """General n: one :meth:`MVStepper.step` a step (``use_numba``: the first, the rest by
        :func:`symrb._compiled_n.continue_mv_n`; False if an item failed there)."""
        for k in range(1, (min(self.steps, 1) if use_numba else self.steps) + 1):
            self.k = k
            self.Qk, self.Mk = self.stepper.step(self.Qk, self.Mk, h)
            self.iters[k - 1] = self.stepper.iterations * self.size
            if k % self.save_every == 0:
                self.save()
        return _compiled_n.continue_mv_n(self, h) if use_numba and self.steps > 1 else True

    def result(self, h: float, order: int, failure: str) -> DiscreteFlowSolution:
        kk = np.array(self.ks, dtype=np.int64)
        k = self.k
        # the saved states have one shape: np.array stacks them (a fifth of np.stack's cost)
        return DiscreteFlowSolution(
            t=np.multiply(kk, h, dtype=np.float64),
            k=kk,
            y=Trajectory(
                {**({"Q": np.array(self.Qs)} if self.attitude else {}), "M": np.array(self.Ms)}
            ),  # fmt: skip
            iterations=self.iters[: max(k, 0)] if failure else self.iters,
            success=not failure,
            status=-1 if failure else 0,
            message=failure or f"all {self.steps} steps taken",
            method="Moser-Veselov, Cayley-Newton engine"
            + (f", preprocessed to order {order}" if order != 2 else ""),
            h=h,
        )
