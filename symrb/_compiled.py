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

A step may be a composition of sub-steps :math:`\gamma_1 h, \dots, \gamma_s h` (the symmetric
compositions of :func:`symrb.compose.composed_rigid_body_flow`; a plain run is
:math:`\gamma = (1)`).  Each sub-step starts from the :math:`s` of the same sub-step of the
previous step (the maps conserve it nearly: :math:`|ds|` stays far below the tolerance, so one
kernel call is the sub-step); the sub-steps of the first step start from
:math:`s = (\gamma_i h)^2\sigma`, :math:`\sigma = s/(\gamma_{i-1}h)^2` of the sub-step before
(:math:`s/h^2` changes only at :math:`O(h^2)` with :math:`h`).

The first root (the cold start with its branch check) is found by the caller on the NumPy path;
this module only continues from a state and an :math:`s` on the branch.

Compilation and its cache: nothing is compiled, and numba is not even imported, until the first
call of :func:`run_mv3`; then the three kernels and the loop are wrapped by
``numba.njit(cache=True)`` as module-level functions (no closures), so a later process loads the
machine code from numba's on-disk cache instead of compiling it (type inference and LLVM, about
a second).  Where numba keeps that cache (``numba.core.caching``, its locator classes, tried in
this order): the directory named by the environment variable ``NUMBA_CACHE_DIR`` if set; else
the ``__pycache__`` directory beside the source file (``symrb/__pycache__`` for the loop,
``symrb/_generated/__pycache__`` for the kernels), used only when numba can create it and write a
temporary file into it; else, e.g. for a read-only installation, numba's user-wide cache
directory (``~/.cache/numba`` on Linux, ``$XDG_CACHE_HOME/numba`` when that is set), in a
subdirectory named after the source directory and a hash of its path.  A read-only install is
never written to; when no directory at all is writable, the functions are compiled in memory
in every process.  The files are an index ``*.nbi`` per function and one ``*.nbc`` per compiled
signature; numba invalidates them when the source file's contents change.

Examples
--------
>>> from symrb import _compiled
>>> isinstance(_compiled.AVAILABLE, bool)
True
"""

from __future__ import annotations

import importlib.util
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ._generated import discrete_rigid_body as _gen
from ._validate import Array

#: True when numba can be imported (it is imported on the first compiled call only).
AVAILABLE = importlib.util.find_spec("numba") is not None

__all__ = ["AVAILABLE", "run_mv3"]

_MAXITER = 12
#: ``method="auto"`` compiles n = 3 runs of at least this many body-steps (sub-steps count)
MIN_WORK = 20_000

# The kernels the loop calls, by these global names: the plain Python functions until
# :func:`_jit` replaces them by their compiled versions (the loop itself runs as plain Python
# too, slowly: what the tests without numba use).
_step: Any = _gen.mv3_cayley_step
_snewton: Any = _gen.mv3_cayley_s_newton
_prelam: Any = _gen.mv3_preprocessed_lam
_loop: Any = None  # the compiled _mv3_loop, made by _jit


def _jit() -> Any:
    """The compiled loop (compiled, or loaded from numba's cache, on the first call)."""
    global _step, _snewton, _prelam, _loop
    if _loop is None:
        import numba

        try:
            jit = numba.njit(cache=True)
            kernels = [jit(f) for f in (_gen.mv3_cayley_step, _gen.mv3_cayley_s_newton,
                                        _gen.mv3_preprocessed_lam, _mv3_loop)]  # fmt: skip
        except RuntimeError:  # numba found no writable cache directory: compile in memory
            kernels = [numba.njit(f) for f in (_gen.mv3_cayley_step, _gen.mv3_cayley_s_newton,
                                               _gen.mv3_preprocessed_lam, _mv3_loop)]  # fmt: skip
        _step, _snewton, _prelam, _loop = kernels
    return _loop


def _mv3_loop(s0, h, gammas, m0, lam, q0, tol, steps, k0, save_every, ms, qs, fail, extra, pre, cf):  # type: ignore[no-untyped-def]  # noqa: E501
    """The steps of each body (module docstring); writes ``ms``, ``qs``, ``fail``, ``extra``."""
    ng = gammas.shape[0]
    sg = np.zeros(ng)  # the s of each sub-step length, from the previous step
    for b in range(m0.shape[0]):
        s = s0[b]
        sigma = 0.0
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
            for g in range(ng):
                hs = h * gammas[g]
                if k > 1:  # the map conserves s at a fixed h: the last s of this sub-step
                    s = sg[g]
                elif g > 0:  # the first step: s/h^2 is nearly conserved as h changes
                    s = hs * hs * sigma
                if pre:  # the preprocessed method: this step's modified Lambda
                    l1, l2, l3 = _prelam(
                        hs, m1, m2, m3, L1, L2, L3, c[0], c[1], c[2], c[3], c[4], c[5], c[6],
                        c[7], c[8], c[9], c[10], c[11], c[12], c[13], c[14], c[15], c[16], c[17],
                        c[18], c[19], c[20], c[21], c[22], c[23], c[24], c[25], c[26], c[27],
                    )  # fmt: skip
                o = _step(
                    s, hs, m1, m2, m3, l1, l2, l3, q11, q12, q13, q21, q22, q23, q31, q32, q33
                )
                if not abs(o[1]) <= tol[b]:
                    ok = False
                    for _ in range(_MAXITER):
                        s, ds = _snewton(s, hs, m1, m2, m3, l1, l2, l3)
                        extra[k - 1] += 1
                        if abs(ds) <= tol[b]:
                            ok = True
                            break
                    if not ok:
                        fail[b] = k
                        break
                    o = _step(
                        s, hs, m1, m2, m3, l1, l2, l3, q11, q12, q13, q21, q22, q23, q31, q32, q33
                    )
                s = o[0]  # the kernel returns increments: the state is rounded once a step
                sigma = s / (hs * hs)
                sg[g] = s
                m1, m2, m3 = m1 + o[2], m2 + o[3], m3 + o[4]
                q11, q12, q13 = q11 + o[5], q12 + o[6], q13 + o[7]
                q21, q22, q23 = q21 + o[8], q22 + o[9], q23 + o[10]
                q31, q32, q33 = q31 + o[11], q32 + o[12], q33 + o[13]
            if fail[b]:
                break
            if (k0 + k) % save_every == 0:
                ms[j, b, 0], ms[j, b, 1], ms[j, b, 2] = m1, m2, m3
                qs[j, b, 0], qs[j, b, 1], qs[j, b, 2] = q11, q12, q13
                qs[j, b, 3], qs[j, b, 4], qs[j, b, 5] = q21, q22, q23
                qs[j, b, 6], qs[j, b, 7], qs[j, b, 8] = q31, q32, q33
                j += 1
    return 0


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
    *,
    gammas: Array | None = None,
    compiled: bool = True,
) -> tuple[Array, Array, NDArray[np.int64], NDArray[np.int64]]:
    r"""Continue ``steps`` steps of n = 3 bodies from a state on the branch (compiled loop).

    Parameters
    ----------
    s : ndarray, shape (B,)
        The scalar :math:`s = b\cdot x` of the first (sub-)step, a root of :math:`p` at
        ``gammas[0] * h`` (or a good start for Newton).
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
    gammas : ndarray, shape (S,), optional
        A step is the sub-steps ``gammas[0] * h``, ..., ``gammas[-1] * h`` in turn (a
        composition method); by default the one step ``h``.
    compiled : bool, optional
        False runs the same loop as plain Python (slow; for checking the loop without numba).

    Returns
    -------
    ms : ndarray, shape (K, B, 3)
    qs : ndarray, shape (K, B, 9)
        The saved states (K the number of saved steps; NaN after a failure).
    fail : ndarray of int, shape (B,)
        0, or the step whose Newton iteration failed (that body's saves stop before it).
    extra : ndarray of int, shape (steps,)
        The Newton steps taken at each step besides one a sub-step (summed over the bodies).

    Raises
    ------
    RuntimeError
        Without numba (and ``compiled`` True).

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
    if compiled and not AVAILABLE:
        raise RuntimeError("numba is not installed (pip install numba)")
    loop = _jit() if compiled else _mv3_loop
    B = m.shape[0]
    K = (k0 + steps) // save_every - k0 // save_every
    ms = np.full((K, B, 3), np.nan)
    qs = np.full((K, B, 9), np.nan)
    fail = np.zeros(B, dtype=np.int64)
    extra = np.zeros(steps, dtype=np.int64)
    pre = coef is not None
    cf = np.ascontiguousarray(coef, dtype=float) if pre else np.zeros((B, 28))
    gv = np.ones(1) if gammas is None else np.ascontiguousarray(gammas, dtype=float)
    loop(
        np.ascontiguousarray(s, dtype=float),
        float(h),
        gv,
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
