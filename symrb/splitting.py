r"""Explicit Lie-Poisson splitting of the free rigid body into planar rotations (any n).

With :math:`J(\Omega) = \Lambda\Omega + \Omega\Lambda` the angular velocity is
:math:`\Omega_{ij} = M_{ij}/(\lambda_i+\lambda_j)` and the energy is a sum over the planes
:math:`i < j`,

.. math::

    H(M) = \tfrac12\langle M, \Omega\rangle = \sum_{i<j} H_{ij}, \qquad
    H_{ij} = \frac{M_{ij}^2}{2(\lambda_i+\lambda_j)},

so the vector field :math:`\dot Q = Q\Omega`, :math:`\dot M = [M, \Omega]` is the sum of the
fields with :math:`\Omega` replaced by its :math:`(i, j)` part
:math:`\Omega^{(ij)} = \Omega_{ij}(E_{ij} - E_{ji})`.  Along that field :math:`M_{ij}` is
constant (:math:`[M, E_{ij} - E_{ji}]_{ij} = M_{ii} - M_{jj} = 0`), hence so is
:math:`\Omega^{(ij)}`, and its flow over a time :math:`\tau` is exact:

.. math::

    R = \exp\bigl(\theta(E_{ij} - E_{ji})\bigr), \quad
    \theta = \frac{\tau M_{ij}}{\lambda_i+\lambda_j}, \qquad
    Q \mapsto QR, \quad M \mapsto R^TMR,

a rotation by :math:`\theta` in the :math:`(i, j)` plane (:math:`R_{ii} = R_{jj} = \cos\theta`,
:math:`R_{ij} = -R_{ji} = \sin\theta`) that changes two columns of :math:`Q` and two rows and
columns of :math:`M`: :math:`O(n)` work (McLachlan, *Explicit Lie-Poisson integration and the
Euler equations*, Phys. Rev. Lett. 71 (1993) 3043; Hairer, Lubich and Wanner, *Geometric
Numerical Integration*, 2nd ed., Section VII.5, for n = 3).  Rotations in disjoint planes
commute, so the planes are taken in :math:`K` groups of disjoint planes (a round-robin schedule:
:math:`K = n - 1` for even n, :math:`K = n` for odd n), each group one exactly solvable flow
:math:`G_k`.  One step of order 2 is the symmetric (Strang) product

.. math:: \Phi_h = G_1(\tfrac h2)\cdots G_{K-1}(\tfrac h2)\,G_K(h)\,G_{K-1}(\tfrac h2)\cdots
    G_1(\tfrac h2),

and the symmetric compositions of :func:`symrb.composition.composition_coefficients` raise it to
order 4, 6 or 8.  Adjacent flows of one group are merged (their angles add), across the stages of
a composition and across steps that save no state.

Every sub-flow is a coadjoint rotation of :math:`M` and a right multiplication of :math:`Q` by a
rotation, so the Casimirs :math:`\operatorname{tr}M^{2k}` and :math:`Q^TQ = I` hold to rounding
whatever ``h``; the map is symplectic and the energy is conserved to the order of the method,
without drift.  The state is updated in increment form (:math:`x + ((\cos\theta - 1)x - \sin\theta
\,y)` with :math:`\cos\theta - 1 = -2\sin^2(\theta/2)`, as in :mod:`symrb.engine`): each rotation
rounds a small increment, and the errors of a long run add up like a random walk (measured:
:math:`|Q^TQ - I|` and the Casimirs within a few :math:`\varepsilon\sqrt N`, 1.5 to 4 times below
the same rotations written as :math:`\cos\theta\,x - \sin\theta\,y`).  ``M`` is kept exactly
skew.

Two backends compute the same map: ``"numpy"``, the reference, vectorised over a batch of bodies
and over the planes of a group; ``"numba"``, a compiled loop over bodies, steps and planes
(needs the optional ``numba``; module-level functions compiled on first use and cached).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ._docs import fill
from ._results import DiscreteFlowSolution, Trajectory
from ._stepping import _check_h, _check_steps, _prepare
from ._validate import Array
from .composition import composition_coefficients
from .errors import InputError

try:  # pragma: no cover - depends on the environment
    import numba

    AVAILABLE = True
except ImportError:  # pragma: no cover
    numba = None  # type: ignore[assignment]
    AVAILABLE = False

__all__ = ["splitting_flow", "SPLITTING_ORDERS"]

#: The orders of :func:`splitting_flow` (2 is the Strang product, 4, 6 and 8 its compositions).
SPLITTING_ORDERS = (2, 4, 6, 8)
_METHODS = ("auto", "numpy", "numba")
#: method="auto" compiles (numba) runs of at least this many plane rotations (steps x bodies x
#: rotations a step): below it loading the compiled loop costs more than the NumPy loop
_NUMBA_MIN_WORK = 5_000


# ---------------------------------------------------------------------------------------------
# the schedule of one step


def plane_groups(n: int) -> list[list[tuple[int, int]]]:
    """The planes ``(i, j)``, ``i < j``, in groups of disjoint planes (round-robin schedule).

    Parameters
    ----------
    n : int
        The dimension, >= 2.

    Returns
    -------
    list of list of tuple of int
        ``n - 1`` groups of ``n / 2`` planes (n even) or ``n`` groups of ``(n - 1) / 2`` planes
        (n odd); every plane exactly once.

    Examples
    --------
    >>> from symrb.splitting import plane_groups
    >>> plane_groups(4)
    [[(0, 3), (1, 2)], [(1, 3), (0, 2)], [(2, 3), (0, 1)]]
    >>> plane_groups(3)
    [[(1, 2)], [(0, 2)], [(0, 1)]]
    """
    m = n if n % 2 == 0 else n + 1  # an odd n plays against a dummy m - 1 = n
    groups = []
    for r in range(m - 1):
        pairs = [(r, m - 1)] + [((r + k) % (m - 1), (r - k) % (m - 1)) for k in range(1, m // 2)]
        groups.append([(min(a, b), max(a, b)) for a, b in pairs if max(a, b) < n])
    return groups


def _schedule(n: int, order: int) -> tuple[list[tuple[int, float]], int]:
    """One step as [(group, fraction of h)], adjacent equal groups merged; and 1 when the step
    begins and ends with the same group and fraction (merged across steps), else 0."""
    K = len(plane_groups(n))
    seq: list[tuple[int, float]] = []
    for g in composition_coefficients(order):
        strang = [(k, 0.5 * g) for k in range(K - 1)] + [(K - 1, float(g))]
        strang += [(k, 0.5 * g) for k in range(K - 2, -1, -1)]
        for k, a in strang:
            if seq and seq[-1][0] == k:
                seq[-1] = (k, seq[-1][1] + a)
            else:
                seq.append((k, a))
    return seq, int(len(seq) > 1)


def _plane_arrays(n: int, order: int) -> tuple[Array, Array, Array, int]:
    """The schedule of one step plane by plane: (pi, pj, fraction of h, planes of the head)."""
    groups = plane_groups(n)
    seq, head = _schedule(n, order)
    pi, pj, a = [], [], []
    for k, frac in seq:
        for i, j in groups[k]:
            pi.append(i)
            pj.append(j)
            a.append(frac)
    g0 = len(groups[seq[0][0]]) if head else 0
    return np.array(pi, np.int64), np.array(pj, np.int64), np.array(a), g0


# ---------------------------------------------------------------------------------------------
# NumPy (the reference)


class _Group:
    """One group of disjoint planes (I, J) for a batch: the weights 1/(lam_i + lam_j) and the
    buffer D of R - I (zero off the planes' entries, which every call overwrites)."""

    def __init__(self, planes: list[tuple[int, int]], n: int, W: Array) -> None:
        self.I = np.array([p[0] for p in planes])
        self.J = np.array([p[1] for p in planes])
        self.rows = n + self.I  # the rows of M_IJ in the stacked state [Q; M]
        self.W = W[:, self.I, self.J]
        self.D = np.zeros(W.shape)

    def rotate(self, X: Array, M: Array, tau: float) -> None:
        """The flow of the planes over the time ``tau``, in place on the stacked state X =
        [Q; M] (B, 2n, n), whose view ``M`` is its momentum: X <- X R, then M <- R^T M, each
        as an increment by D = R - I."""
        theta = (tau * self.W) * X[:, self.rows, self.J]
        half = np.sin(0.5 * theta)
        cm1 = -2.0 * half * half  # cos(theta) - 1
        s = np.sin(theta)
        D, I, J = self.D, self.I, self.J
        D[:, I, I], D[:, J, J], D[:, I, J], D[:, J, I] = cm1, cm1, s, -s
        X += X @ D
        M += np.swapaxes(D, 1, 2) @ M


def _run_numpy(Q: Array, M: Array, W: Array, n: int, order: int, h: float, steps: int,
               save_every: int, Qs: Array, Ms: Array) -> None:  # fmt: skip
    """Steps 1..steps from (Q, M) (B, n, n); saves into Qs, Ms from index 1."""
    groups = [_Group(g, n, W) for g in plane_groups(n)]
    seq, head = _schedule(n, order)
    body = [(groups[g], frac * h) for g, frac in seq[head : len(seq) - head]]
    first, last = groups[seq[0][0]], groups[seq[-1][0]]
    X = np.concatenate([Q, M], axis=1)
    Xm = X[:, n:, :]
    k = 0
    while k < steps:
        block = min(save_every - k % save_every, steps - k)  # steps up to the next saved one
        if head:
            first.rotate(X, Xm, seq[0][1] * h)
        for st in range(block):
            for group, tau in body:
                group.rotate(X, Xm, tau)
            if head:
                frac = seq[-1][1] + (seq[0][1] if st < block - 1 else 0.0)
                last.rotate(X, Xm, frac * h)
        k += block
        Xm[:] = 0.5 * (Xm - np.swapaxes(Xm, 1, 2))  # its rows and columns round differently
        if k % save_every == 0:
            Qs[k // save_every], Ms[k // save_every] = X[:, :n], Xm


# ---------------------------------------------------------------------------------------------
# numba


def _rotate_plane(Q: Any, M: Any, i: int, j: int, theta: float) -> None:  # pragma: no cover
    """One plane of one body, in place: Q R (all rows) and R^T M R, M kept exactly skew."""
    half = np.sin(0.5 * theta)
    cm1 = -2.0 * half * half
    s = np.sin(theta)
    n = Q.shape[0]
    for a in range(n):
        u, v = Q[a, i], Q[a, j]
        Q[a, i] = u + (cm1 * u - s * v)
        Q[a, j] = v + (s * u + cm1 * v)
        if a != i and a != j:  # M_ij is constant, the diagonal zero
            u, v = M[a, i], M[a, j]
            u1 = u + (cm1 * u - s * v)
            v1 = v + (s * u + cm1 * v)
            M[a, i], M[a, j] = u1, v1
            M[i, a], M[j, a] = -u1, -v1


def _run_compiled(Q: Any, M: Any, W: Any, pi: Any, pj: Any, a: Any, g0: int, h: float,
                  steps: int, save_every: int, Qs: Any, Ms: Any) -> None:  # pragma: no cover  # fmt: skip
    """The loop of :func:`_run_numpy`, body by body and plane by plane."""
    L = pi.shape[0]
    for b in range(Q.shape[0]):
        Qb, Mb, Wb = Q[b], M[b], W[b]
        k = 0
        while k < steps:
            block = min(save_every - k % save_every, steps - k)
            for e in range(g0):
                i, j = pi[e], pj[e]
                _rotate_plane(Qb, Mb, i, j, a[e] * h * Mb[i, j] * Wb[i, j])
            for st in range(block):
                for e in range(g0, L - g0):
                    i, j = pi[e], pj[e]
                    _rotate_plane(Qb, Mb, i, j, a[e] * h * Mb[i, j] * Wb[i, j])
                for e in range(L - g0, L):
                    frac = a[e] + (a[e - (L - g0)] if st < block - 1 else 0.0)
                    i, j = pi[e], pj[e]
                    _rotate_plane(Qb, Mb, i, j, frac * h * Mb[i, j] * Wb[i, j])
            k += block
            if k % save_every == 0:
                Qs[k // save_every, b] = Qb
                Ms[k // save_every, b] = Mb


if AVAILABLE:  # compiled on the first call (cache=True: a new process loads them from disk)
    _rotate_plane = numba.njit(cache=True)(_rotate_plane)
    _run_compiled = numba.njit(cache=True)(_run_compiled)


# ---------------------------------------------------------------------------------------------
# the flow


@fill
def splitting_flow(
    Q0: ArrayLike,
    M0: ArrayLike,
    lam: ArrayLike,
    h: float,
    steps: int,
    *,
    order: int = 2,
    save_every: int = 1,
    method: str = "auto",
) -> DiscreteFlowSolution:
    r"""The rigid body by the explicit splitting into planar rotations (module docstring).

    One step of order 2 is the symmetric product of the exact flows of the energy's terms
    :math:`M_{ij}^2/(2(\lambda_i+\lambda_j))`, each a rotation by
    :math:`\theta = \tau M_{ij}/(\lambda_i+\lambda_j)` in the :math:`(i, j)` plane
    (:math:`Q \mapsto QR`, :math:`M \mapsto R^TMR`); orders 4, 6, 8 compose it with the default
    coefficients of :func:`symrb.composition.composition_coefficients`.  Explicit: no equation is
    solved, any ``h`` can be taken, :math:`Q` stays in SO(n) and the Casimirs of :math:`M` stay
    fixed to rounding; the energy error is of the method's order and does not drift.

    Parameters
    ----------
    %(Q0)s
    %(M0)s
    %(lam_positive)s
    %(h)s
    %(steps)s
    order : {2, 4, 6, 8}, optional
        The order: 2 the Strang product (default); 4, 6, 8 its symmetric compositions of 5, 9
        and 17 stages.
    %(save_every)s
    method : {"auto", "numpy", "numba"}, optional
        ``"numpy"``: the reference, vectorised over the batch and over the disjoint planes of a
        group; ``"numba"``: the compiled loop (needs numba; the same map, equal to rounding);
        ``"auto"`` (default): ``"numba"`` when numba is importable and the run has at least
        5000 plane rotations (steps times bodies times rotations a step), else
        ``"numpy"``.

    Returns
    -------
    DiscreteFlowSolution
        ``t`` the times :math:`kh` of the saved states, ``y.Q`` and ``y.M`` of shape
        ``(K, ..., n, n)``; ``iterations`` is empty (nothing is solved).

    Raises
    ------
    InputError
        Invalid arrays (``Q0`` not in SO(n), ``M0`` not skew, ``lam`` not positive, batch axes
        that do not broadcast), ``h``, ``steps``, ``save_every``, an ``order`` or ``method`` not
        listed, or ``method="numba"`` without numba.

    Examples
    --------
    Order 6 at n = 3 against the exact solution, and the invariants after 1000 steps:

    >>> import numpy as np
    >>> import symrb
    >>> from symrb.splitting import splitting_flow
    >>> lam, M0 = np.array([0.7, 1.1, 1.6]), symrb.hat([0.5, 1.0, 1.5])
    >>> sol = splitting_flow(np.eye(3), M0, lam, 0.1, 100, order=6, save_every=100)
    >>> ex = symrb.exact.rigid_body_exact(np.eye(3), M0, lam, [10.0])
    >>> bool(np.abs(sol.y.M[-1] - ex.y.M[-1]).max() < 1e-7)
    True
    >>> sol = splitting_flow(np.eye(3), M0, lam, 0.1, 1000, save_every=1000)
    >>> Q, M = sol.y.Q[-1], sol.y.M[-1]
    >>> bool(np.abs(Q.T @ Q - np.eye(3)).max() < 1e-14)
    True
    >>> bool(abs(np.sum(M * M) - np.sum(M0 * M0)) < 1e-13)
    True

    A batch of bodies (any n):

    >>> lam5 = np.array([1.0, 1.3, 1.7, 2.2, 2.8])
    >>> A = np.triu(np.arange(25.0).reshape(5, 5) / 25, 1)
    >>> splitting_flow(np.eye(5), np.stack([A - A.T] * 4), lam5, 0.05, 10).y.M.shape
    (11, 4, 5, 5)
    """
    h = _check_h(h)
    steps, save_every = _check_steps(steps, save_every)
    if isinstance(order, bool) or order not in SPLITTING_ORDERS:
        raise InputError(f"order must be one of {SPLITTING_ORDERS}, got {order!r}")
    if not isinstance(method, str) or method not in _METHODS:
        raise InputError(f"method must be one of {', '.join(_METHODS)}, got {method!r}")
    if method == "numba" and not AVAILABLE:
        raise InputError("method 'numba' needs numba installed; pass method='numpy' or 'auto'")
    L, (Q, M), batch = _prepare(lam, (Q0, "Q0", "SO"), (M0, "M0", "skew"))
    n = L.shape[-1]
    Qf = np.ascontiguousarray(Q.reshape(-1, n, n))
    Mf = np.ascontiguousarray(M.reshape(-1, n, n))
    Mf = 0.5 * (Mf - np.swapaxes(Mf, 1, 2))
    Lf = np.broadcast_to(L, batch + (n,)).reshape(-1, n)
    W = np.ascontiguousarray(1.0 / (Lf[:, :, None] + Lf[:, None, :]))
    K = steps // save_every
    Qs, Ms = np.empty((K + 1,) + Qf.shape), np.empty((K + 1,) + Mf.shape)
    Qs[0], Ms[0] = Qf, Mf
    pi, pj, a, g0 = _plane_arrays(n, order)
    work = steps * Qf.shape[0] * pi.shape[0]
    use_numba = method == "numba" or (method == "auto" and AVAILABLE and work >= _NUMBA_MIN_WORK)
    if use_numba:
        _run_compiled(Qf, Mf, W, pi, pj, a, g0, h, steps, save_every, Qs, Ms)
    else:
        _run_numpy(Qf, Mf, W, n, order, h, steps, save_every, Qs, Ms)
    k = np.arange(K + 1, dtype=np.int64) * save_every
    ok = bool(np.isfinite(Qs[-1]).all() and np.isfinite(Ms[-1]).all())
    return DiscreteFlowSolution(
        t=k.astype(np.float64) * h,
        k=k,
        y=Trajectory({"Q": Qs.reshape((K + 1,) + Q.shape), "M": Ms.reshape((K + 1,) + M.shape)}),
        iterations=np.zeros(0, dtype=np.int64),
        success=ok,
        status=0 if ok else -1,
        message=f"all {steps} steps taken" + ("" if ok else "; the state is not finite"),
        method=f"splitting into planar rotations, order {order}",
        h=h,
    )
