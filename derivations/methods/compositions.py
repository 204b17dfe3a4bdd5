r"""M4: the orders of symrb's composed and textbook rigid body integrators (not the paper's).

The Moser-Veselov map is symmetric (time-reversible), so its symmetric compositions raise the
order.  Evidence: the observed orders of ``symrb.compose.composed_rigid_body_flow`` (4, 6, 8),
``symrb.compose.rkmk4_rigid_body_flow`` (4) and ``symrb.compose.midpoint_rigid_body_flow`` (2) against the Jacobi
elliptic solution of Euler's equations (:func:`derivations.reference.euler_elliptic`); and the
local order of every coefficient table of ``symrb.composition`` on a Strang splitting of two
matrices in 30-digit arithmetic (mpmath).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from derivations import reference as ref
from derivations.registry import Level, claim

M4 = claim(
    "M4",
    label="",
    title="Orders of the composed and textbook rigid body integrators",
    statement="The Moser-Veselov map is symmetric, so its symmetric compositions of orders 4, 6 "
    "and 8 raise the order; with the Runge-Kutta-Munthe-Kaas method of order 4 and the implicit "
    "midpoint rule of order 2, every observed order against the elliptic solution of Euler's "
    "equations is the nominal one; every composition table (each kind of each order) has its "
    "order on the local error of a splitting, independently of the rigid body; the compiled "
    "loops of the composed flow (batches large enough to take them) keep these orders, and one "
    "composed step of theirs is the composition of its exactly solved Moser-Veselov sub-steps; the matrix exponential of the "
    "compiled RKMK4 is exact to rounding over the range of each of its Pade approximants, and "
    "both of its backends take the textbook method's steps.",
    expected="holds",
    section="symrb",
    where="symrb.compose.composed_rigid_body_flow, symrb.compose.rkmk4_rigid_body_flow and "
    "symrb.compose.midpoint_rigid_body_flow",
)


@M4.check(Level.FLOAT64, tol=0.2)
def m4_compositions_order_against_elliptic() -> float:
    r"""The MV-Algorithm 2 map is symmetric (time-reversible), so its symmetric compositions raise
    the order: symrb.compose.composed_rigid_body_flow (orders 4, 6, 8, the engine's MV step), and
    the textbook alternatives symrb.compose.rkmk4_rigid_body_flow (4) and
    symrb.compose.midpoint_rigid_body_flow (2), these two by their NumPy path and by their
    compiled loop (when numba is installed), $n = 3$, against the Jacobi elliptic solution of
    Euler's equations (reference.euler_elliptic) at $T = 2$: the error in $M$ at steps $h$ and $h/2$
    gives the observed order $\log_2(e(h)/e(h/2))$; largest $|\mathrm{observed} - \mathrm{nominal}|$
    over the methods."""
    import symrb
    from symrb import _compiled_stages

    inertia = np.array([1.0, 1.7, 2.6])
    lam = 0.5 * inertia.sum() - inertia  # I_1 = lam_2 + lam_3 (cyclic)
    T = 2.0
    m = ref.euler_elliptic(inertia, 0.8, 1.1, np.array([0.0, T]))
    M0 = ref.hat(m[0])

    def error(flow: Any, h: float, **kw: Any) -> float:
        sol = flow(np.eye(3), M0, lam, h, round(T / h), save_every=round(T / h), **kw)
        return float(np.abs(ref.vee(sol.y.M[-1]) - m[-1]).max())

    cases = [  # (flow, options, nominal order, step h: errors well above rounding)
        (symrb.compose.composed_rigid_body_flow, {"order": 4}, 4, 0.2),
        (symrb.compose.composed_rigid_body_flow, {"order": 6}, 6, 0.2),
        (symrb.compose.composed_rigid_body_flow, {"order": 8}, 8, 0.25),
    ]
    for backend in ("numpy", "numba") if _compiled_stages.AVAILABLE else ("numpy",):
        cases += [
            (symrb.compose.rkmk4_rigid_body_flow, {"method": backend}, 4, 0.1),
            (symrb.compose.midpoint_rigid_body_flow, {"method": backend}, 2, 0.05),
        ]
    gaps = []
    for flow, kw, p, h in cases:
        observed = np.log2(error(flow, h, **kw) / error(flow, h / 2, **kw))
        gaps.append(abs(observed - p))
    return float(max(gaps))


@M4.check(Level.MPMATH, tol=0.5)
def m4_every_table_local_order() -> float:
    r"""Every composition table of symrb.composition.composition_coefficients (each kind of orders
    2, 4, 6, 8, the non-default ones included), applied to the Strang splitting $\exp(hA/2) \exp(hB)
    \exp(hA/2)$ of two random $3 \times 3$ matrices in 30-digit arithmetic (mpmath): the local error
    against $\exp(h(A + B))$ at steps $h$ and $h/2$ gives the local order $\log_2(e(h)/e(h/2))$,
    which is $p + 1$ for a table of order $p$; $\max |\mathrm{observed} - (p + 1)|$ (one order
    condition broken by a wrong coefficient lowers it by 2 or more)."""
    import mpmath as mp

    from symrb.composition import _KINDS, composition_coefficients

    rng = np.random.default_rng(41)
    with mp.workdps(30):
        A, B = (mp.matrix(rng.standard_normal((3, 3)).tolist()) for _ in range(2))

        def local_error(gammas: np.ndarray, h: Any) -> Any:
            P = mp.eye(3)
            for g in gammas:
                c = mp.mpf(float(g)) * h
                P = mp.expm(c / 2 * A) * mp.expm(c * B) * mp.expm(c / 2 * A) * P
            return mp.mnorm(P - mp.expm(h * (A + B)), 1)

        worst = 0.0
        for order, kinds in _KINDS.items():
            h = mp.mpf({2: 0.05, 4: 0.1, 6: 0.1, 8: 0.2}[order])  # errors far above rounding
            for kind in kinds:
                gammas = composition_coefficients(order, kind)
                observed = mp.log(local_error(gammas, h) / local_error(gammas, h / 2), 2)
                worst = float(np.max([worst, abs(float(observed) - order - 1)]))
    return worst


@M4.check(Level.FLOAT64, tol=0.2)
def m4_compiled_compositions_order() -> float:
    r"""symrb.compose.composed_rigid_body_flow on batches just large enough for its compiled
    loops (numba installed; else the same runs on the NumPy path): at $n = 3$ orders 4, 6, 8
    against the Jacobi elliptic solution (reference.euler_elliptic) at $T = 2$, at $n = 6$ order
    4 against extended-precision extrapolation (reference.rigid_body_extrapolated) at $T = 1$;
    every body of a batch of copies, the error at steps $h$ and $h/2$ gives the observed order
    $\log_2(e(h)/e(h/2))$; largest $|\mathrm{observed} - \mathrm{nominal}|$ (a wrong sub-step
    length in a compiled loop, or in its first step, breaks the order)."""
    from symrb import _compiled, compose
    from symrb.composition import composition_coefficients

    inertia = np.array([1.0, 1.7, 2.6])
    lam = 0.5 * inertia.sum() - inertia  # I_1 = lam_2 + lam_3 (cyclic)
    m = ref.euler_elliptic(inertia, 0.8, 1.1, np.array([0.0, 2.0]))
    gaps = []
    for p, h in ((4, 0.2), (6, 0.2), (8, 0.25)):
        N = round(2.0 / h)  # the batch: MIN_WORK body-stages at the larger step
        B = -(-_compiled.MIN_WORK // (N * composition_coefficients(p).size))
        M0 = np.broadcast_to(ref.hat(m[0]), (B, 3, 3))
        e = []
        for k in (N, 2 * N):
            sol = compose.composed_rigid_body_flow(np.eye(3), M0, lam, 2.0 / k, k, order=p,
                                                   save_every=k)  # fmt: skip
            e.append(float(np.abs(ref.vee(sol.y.M[-1]) - m[-1]).max()))
        gaps.append(abs(np.log2(e[0] / e[1]) - p))
    rng = np.random.default_rng(13)  # the n = 6 body of M13
    lam6 = rng.uniform(0.5, 2.0, 6)
    M6 = ref.random_skew(6, rng, 1.0)
    Q6 = ref.random_rotation(6, rng)
    M6 = 4.0 * M6 / np.linalg.norm(M6, 2)
    Qr, Mr = (x.astype(float) for x in ref.rigid_body_extrapolated(Q6, M6, lam6, 1.0, 20))
    B = -(-compose._NUMBA_MIN_WORK_N // (10 * 5 * 6**3))  # 10 steps of 5 stages at h = 0.1
    e = []
    for k in (10, 20):
        sol = compose.composed_rigid_body_flow(
            np.broadcast_to(Q6, (B, 6, 6)), np.broadcast_to(M6, (B, 6, 6)), lam6, 1.0 / k, k,
            order=4, save_every=k,
        )  # fmt: skip
        e.append(max(float(np.abs(sol.y.Q[-1] - Qr).max()), float(np.abs(sol.y.M[-1] - Mr).max())))
    gaps.append(abs(np.log2(e[0] / e[1]) - 4))
    return float(max(gaps))


@M4.check(Level.FLOAT64, tol=1e-13)
def m4_compiled_composed_step_against_30_digits() -> float:
    r"""One step $h = 0.4$ of symrb.compose.composed_rigid_body_flow (order 4, Suzuki's 5
    sub-steps $\gamma_i h$), $n = 3$, on a batch just large enough for its compiled loop (numba
    installed), against the same 5 Moser-Veselov sub-steps in 30 digits
    (reference.MPDiscrete.solve_jd: $U\Lambda - \Lambda U^T = \gamma_i h M$, $Q \leftarrow QU$,
    $M \leftarrow U^TMU$): max error in $Q$ and $M$ of the first and last body (a sub-step
    taken from its warm start without solving to tolerance is off by $10^{-9}$ here)."""
    from derivations.claims.section2._matrix_formulas import _LAM3
    from symrb import _compiled, compose
    from symrb.composition import composition_coefficients

    rng = np.random.default_rng(1212)
    Q0, M0, h = ref.random_rotation(3, rng), ref.hat(np.array([1.2, -0.7, 0.9])), 0.4
    g = composition_coefficients(4)
    B = -(-_compiled.MIN_WORK // g.size)  # body-stages for the compiled loop in one step
    sol = compose.composed_rigid_body_flow(
        np.broadcast_to(Q0, (B, 3, 3)), np.broadcast_to(M0, (B, 3, 3)), _LAM3, h, 1
    )
    mpd = ref.MPDiscrete(_LAM3, dps=30)
    with mpd.mp.workdps(mpd.dps):
        Q, M = mpd.orthonormal(Q0), mpd.matrix(M0)
        for c in g:
            U = mpd.solve_jd(mpd.mp.mpf(float(c) * h) * M)
            Q, M = Q * U, U.T * M * U
    return max(mpd.distance(x, y[-1][b]) for x, y in ((Q, sol.y.Q), (M, sol.y.M)) for b in (0, -1))


@M4.check(Level.MPMATH, tol=1e-14)
def m4_rkmk4_exponential_against_mpmath() -> float:
    r"""The matrix exponential of the compiled RKMK4 loop (symrb._compiled_n.expm, scaling and
    squaring with the Pade approximants of orders 3 to 13; scipy.linalg.expm, that of the NumPy
    path, without numba) on skew and general $3 \times 3$ and $5 \times 5$ matrices whose 1-norms
    fall in the range of each Pade order and past it (0.01 to 40), against mpmath.expm in 30
    digits: largest error relative to $\max(1, |e^A|)$ (a Pade coefficient wrong in its fourth
    digit gives about $10^{-6}$)."""
    import mpmath as mp

    from symrb import _compiled_n

    if _compiled_n.AVAILABLE:
        expm = _compiled_n.expm
    else:  # pragma: no cover - without numba
        import scipy.linalg

        expm = scipy.linalg.expm
    rng = np.random.default_rng(77)
    worst = 0.0
    for n in (3, 5):
        for norm in (0.01, 0.2, 0.8, 2.0, 4.5, 40.0):
            for skew in (True, False):
                A = rng.standard_normal((n, n))
                A = A - A.T if skew else A
                A = A * (norm / np.abs(A).sum(axis=0).max())
                with mp.workdps(30):
                    E = np.array(mp.expm(mp.matrix(A.tolist())).tolist(), dtype=float)
                err = np.abs(expm(A[None])[0] - E).max() / max(1.0, float(np.abs(E).max()))
                worst = max(worst, float(err))
    return worst


def _rkmk4_textbook(Q: np.ndarray, M: np.ndarray, lam: np.ndarray, h: float) -> tuple[Any, Any]:
    """One step of the Runge-Kutta-Munthe-Kaas method of order 4 (Munthe-Kaas 1999; Hairer,
    Lubich, Wanner IV.8) for Qdot = Q Omega, M = Lambda Omega + Omega Lambda, in the body frame,
    with dexp^{-1} to its second Bernoulli term; plain NumPy and scipy.linalg.expm."""
    import scipy.linalg

    W = 1.0 / (lam[:, None] + lam[None, :])

    def bracket(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return a @ b - b @ a

    def F(th: np.ndarray) -> np.ndarray:  # dexp^{-1}_{-th} of Omega at M(th) = e^{-th} M e^{th}
        g = scipy.linalg.expm(th)
        Mt = g.T @ M @ g
        Om = 0.5 * (Mt - Mt.T) * W
        return Om + bracket(th, Om) / 2.0 + bracket(th, bracket(th, Om)) / 12.0

    k1 = h * F(np.zeros_like(M))
    k2 = h * F(k1 / 2.0)
    k3 = h * F(k2 / 2.0)
    k4 = h * F(k3)
    th = (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0
    g = scipy.linalg.expm(0.5 * (th - th.T))
    return Q @ g, g.T @ M @ g


@M4.check(Level.FLOAT64, tol=1e-13)
def m4_rkmk4_step_against_textbook() -> float:
    r"""Three steps $h = 0.3$ of symrb.compose.rkmk4_rigid_body_flow, by its NumPy path and by
    its compiled loop (when numba is installed), $n = 3$ and $n = 5$, against the textbook
    Runge-Kutta-Munthe-Kaas method of order 4 written here in plain NumPy and
    scipy.linalg.expm: max error in $Q$ and $M$ relative to $\max(1, |M|)$ (the order-4 check
    cannot see a wrong coefficient of $\mathrm{dexp}^{-1}$'s double bracket: for the rigid body
    its effect is of higher order in $h$)."""
    from symrb import _compiled_stages, compose

    rng = np.random.default_rng(44)
    worst = 0.0
    for n in (3, 5):
        lam = rng.uniform(0.5, 2.0, n)
        Q0, M0 = ref.random_rotation(n, rng), ref.random_skew(n, rng, 1.0)
        Q, M = Q0, M0
        Qs, Ms = [Q], [M]
        for _ in range(3):
            Q, M = _rkmk4_textbook(Q, M, lam, 0.3)
            Qs.append(Q)
            Ms.append(M)
        scale = max(1.0, float(np.abs(M0).max()))
        for backend in ("numpy", "numba") if _compiled_stages.AVAILABLE else ("numpy",):
            sol = compose.rkmk4_rigid_body_flow(Q0, M0, lam, 0.3, 3, method=backend)
            err = max(np.abs(sol.y.Q - np.array(Qs)).max(), np.abs(sol.y.M - np.array(Ms)).max())
            worst = max(worst, float(err) / scale)
    return worst
