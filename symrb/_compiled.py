r"""Optional compiled n = 3 Moser-Veselov loop: the generated kernels under numba.

``numba`` is not a run-time dependency: :data:`AVAILABLE` is False without it and
:func:`symrb.engine.mv_flow` then runs its NumPy path (the reference).  With it, the generated
scalar kernels ``mv3_cayley_step`` and ``mv3_cayley_s_newton`` (method check M1) are compiled as they
are (``numba.njit`` of the emitted Python functions, no fast-math, so the arithmetic is the
NumPy path's, operation for operation) and called from a compiled loop over the steps of each
body of a batch.  A step is the NumPy fast path's: one ``mv3_cayley_step`` at the previous
step's :math:`s` (conserved by the map), accepted when :math:`|ds| \le` tol; otherwise Newton on
:math:`p` by ``mv3_cayley_s_newton`` until :math:`|ds| \le` tol.  A body whose Newton iteration
fails is reported (its step index) and the caller redoes the run on the NumPy path, which has
the Riccati fallback and the fold diagnosis.

The first step (the cold start with its branch check) is taken by the caller on the NumPy path;
this module only continues from a state and an :math:`s` on the branch.

Examples
--------
>>> from symrb import _compiled
>>> isinstance(_compiled.AVAILABLE, bool)
True
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ._generated import discrete_rigid_body as _gen
from ._validate import Array

try:  # pragma: no cover - depends on the environment
    import numba

    AVAILABLE = True
except ImportError:  # pragma: no cover
    numba = None  # type: ignore[assignment]
    AVAILABLE = False

__all__ = ["AVAILABLE", "run_mv3"]

_MAXITER = 12
_loop: Callable[..., Any] | None = None


def _build() -> Callable[..., Any]:
    step = numba.njit(cache=True)(_gen.mv3_cayley_step)
    snewton = numba.njit(cache=True)(_gen.mv3_cayley_s_newton)
    prelam = numba.njit(cache=True)(_gen.mv3_preprocessed_lam)

    @numba.njit(cache=True)
    def loop(s0, h, m0, lam, q0, tol, steps, k0, save_every, ms, qs, fail, extra, pre, cf):  # type: ignore[no-untyped-def]  # noqa: E501
        for b in range(m0.shape[0]):
            s = s0[b]
            m1, m2, m3 = m0[b, 0], m0[b, 1], m0[b, 2]
            L1, L2, L3 = lam[b, 0], lam[b, 1], lam[b, 2]
            l1, l2, l3 = L1, L2, L3
            c = cf[b]
            q = q0[b]
            q11, q12, q13, q21, q22, q23, q31, q32, q33 = (
                q[0], q[1], q[2], q[3], q[4], q[5], q[6], q[7], q[8]
            )  # fmt: skip
            j = 0
            for k in range(1, steps + 1):
                if pre:  # the preprocessed method: this step's modified Lambda
                    l1, l2, l3 = prelam(
                        h, m1, m2, m3, L1, L2, L3, c[0], c[1], c[2], c[3], c[4], c[5], c[6],
                        c[7], c[8], c[9], c[10], c[11], c[12], c[13], c[14], c[15], c[16], c[17],
                        c[18], c[19], c[20], c[21], c[22], c[23], c[24], c[25], c[26], c[27],
                    )  # fmt: skip
                o = step(s, h, m1, m2, m3, l1, l2, l3, q11, q12, q13, q21, q22, q23, q31, q32, q33)
                if not abs(o[1]) <= tol[b]:
                    ok = False
                    for _ in range(_MAXITER):
                        s, ds = snewton(s, h, m1, m2, m3, l1, l2, l3)
                        extra[k - 1] += 1
                        if abs(ds) <= tol[b]:
                            ok = True
                            break
                    if not ok:
                        fail[b] = k
                        break
                    o = step(
                        s, h, m1, m2, m3, l1, l2, l3, q11, q12, q13, q21, q22, q23, q31, q32, q33
                    )
                s = o[0]  # the kernel returns increments: the state is rounded once a step
                m1, m2, m3 = m1 + o[2], m2 + o[3], m3 + o[4]
                q11, q12, q13 = q11 + o[5], q12 + o[6], q13 + o[7]
                q21, q22, q23 = q21 + o[8], q22 + o[9], q23 + o[10]
                q31, q32, q33 = q31 + o[11], q32 + o[12], q33 + o[13]
                if (k0 + k) % save_every == 0:
                    ms[j, b, 0], ms[j, b, 1], ms[j, b, 2] = m1, m2, m3
                    qs[j, b, 0], qs[j, b, 1], qs[j, b, 2] = q11, q12, q13
                    qs[j, b, 3], qs[j, b, 4], qs[j, b, 5] = q21, q22, q23
                    qs[j, b, 6], qs[j, b, 7], qs[j, b, 8] = q31, q32, q33
                    j += 1
        return 0

    return loop  # type: ignore[no-any-return]


def run_mv3(
    s: Array,
    h: float,
    m: Array,
    lam: Array,
    q: Array,
    tol: Array,
    steps: int,
    save_every: int,
    k0: int = 0,
    coef: Array | None = None,
) -> tuple[Array, Array, NDArray[np.int64], NDArray[np.int64]]:
    r"""Continue ``steps`` steps of n = 3 bodies from a state on the branch (compiled loop).

    Parameters
    ----------
    s : ndarray, shape (B,)
        The scalar :math:`s = b\cdot x` of the last step (a root of :math:`p`).
    h : float
        The step.
    m : ndarray, shape (B, 3)
        The body momenta (vectors).
    lam : ndarray, shape (B, 3)
        The diagonals of :math:`\Lambda`.
    q : ndarray, shape (B, 9)
        The attitudes, row-major.
    tol : ndarray, shape (B,)
        The Newton tolerance on :math:`|ds|`.
    steps, save_every, k0 : int
        Steps to take, numbered k0 + 1, ..., k0 + steps; the states after the steps whose number
        is a multiple of ``save_every`` are saved.
    coef : ndarray, shape (B, 28), optional
        The constants of ``mv3_preprocessed_lam`` (preprocessed method): each step then uses
        the modified Lambda of the current momentum.

    Returns
    -------
    ms : ndarray, shape (K, B, 3)
    qs : ndarray, shape (K, B, 9)
        The saved states (K the number of saved steps; NaN after a failure).
    fail : ndarray of int, shape (B,)
        0, or the step whose Newton iteration failed (that body's saves stop before it).
    extra : ndarray of int, shape (steps,)
        The Newton steps taken at each step besides its one (summed over the bodies).

    Raises
    ------
    RuntimeError
        Without numba.

    Examples
    --------
    >>> import numpy as np
    >>> from symrb import _compiled
    >>> if _compiled.AVAILABLE:
    ...     ms, qs, fail, extra = _compiled.run_mv3(np.zeros(1), 0.1, np.zeros((1, 3)),
    ...         np.ones((1, 3)), np.eye(3).reshape(1, 9), np.full(1, 1e-9), 4, 2)
    ...     print(ms.shape, qs.shape, int(fail[0]))
    ... else:
    ...     print((2, 1, 3), (2, 1, 9), 0)
    (2, 1, 3) (2, 1, 9) 0
    """
    global _loop
    if not AVAILABLE:
        raise RuntimeError("numba is not installed (pip install numba)")
    if _loop is None:
        _loop = _build()
    B = m.shape[0]
    K = (k0 + steps) // save_every - k0 // save_every
    ms = np.full((K, B, 3), np.nan)
    qs = np.full((K, B, 9), np.nan)
    fail = np.zeros(B, dtype=np.int64)
    extra = np.zeros(steps, dtype=np.int64)
    pre = coef is not None
    cf = np.ascontiguousarray(coef, dtype=float) if pre else np.zeros((B, 28))
    _loop(
        np.ascontiguousarray(s, dtype=float),
        float(h),
        np.ascontiguousarray(m, dtype=float),
        np.ascontiguousarray(lam, dtype=float),
        np.ascontiguousarray(q, dtype=float),
        np.ascontiguousarray(tol, dtype=float),
        int(steps),
        int(k0),
        int(save_every),
        ms,
        qs,
        fail,
        extra,
        pre,
        cf,
    )
    return ms, qs, fail, extra
