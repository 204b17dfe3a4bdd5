r"""M2: the Moser-Veselov engine ``symrb.engine.mv_flow`` (symrb's own; not a paper claim).

The engine runs the Moser-Veselov map with the fused n = 3 Cayley step (M1) and a general-n
solver with an increment update.  Evidence: the 50-digit run of the symmetric representation
(:mod:`derivations.claims.section2._reference_run`), the defining equations with
:func:`derivations.reference.J_D`, and long runs held to rounding.
"""

from __future__ import annotations

import numpy as np

from derivations import reference as ref
from derivations.claims.section2._matrix_formulas import _LAM3
from derivations.claims.section2._reference_run import _H, _STEPS, _mp_run
from derivations.registry import Level, claim

M2 = claim(
    "M2",
    label="",
    title="The Moser-Veselov engine",
    statement="symrb.engine.mv_flow runs the Moser-Veselov map: its attitudes and momenta agree "
    "with a 50-digit run of the symmetric representation, satisfy the defining equations for "
    "$n=5$ and $n=8$, keep the momentum skew, and keep the energy, the Casimir and orthogonality "
    "within rounding over long runs; the scalar $s$ that the engine carries from step to step is "
    "conserved by the map; it refuses an attitude that is not a rotation (to $10^{-8}$) and a "
    "momentum that is not skew, for one body as for a batch.",
    expected="holds",
    section="symrb",
    where="symrb.engine.mv_flow (the fused n = 3 step of M1 and the general-n solver)",
)


@M2.check(Level.FLOAT64, tol=1e-12)
def m2_cayley_s_conserved() -> float:
    r"""The scalar $s_k = h\, m_k \cdot x_k$ ($x_k$ the Cayley vector of $U_k = Q_k^T Q_{k+1}$)
    along 2000 steps of symrb.discrete_rigid_body_flow ($U$-parametrised solver, $n = 3$, $h =
    0.05$) is constant: $\max |s_k/s_0 - 1|$ (what lets symrb.engine take one Newton step on $p$ a
    step)."""
    import symrb

    M0 = ref.hat(np.array([0.9, -0.5, 0.7]))
    sol = symrb.discrete_rigid_body_flow(np.eye(3), M0, _LAM3, 0.05, 2000)
    Q, M = sol.y.Q, sol.y.M[:-1]
    U = np.swapaxes(Q[:-1], -1, -2) @ Q[1:]
    x = np.stack([U[:, 2, 1] - U[:, 1, 2], U[:, 0, 2] - U[:, 2, 0], U[:, 1, 0] - U[:, 0, 1]], -1)
    x /= 1.0 + np.trace(U, axis1=-2, axis2=-1)[:, None]
    s = 0.05 * np.einsum("ki,ki->k", np.stack([M[:, 2, 1], M[:, 0, 2], M[:, 1, 0]], -1), x)
    return float(np.abs(s / s[0] - 1).max())


@M2.check(Level.FLOAT64, tol=1e-13)
def m2_engine_against_50_digits() -> float:
    """symrb.engine.mv_flow (Cayley-Newton, the emitted $n = 3$ kernels) from $(Q_0, M_0)$ at $h =
    0.1$, 12 steps, single body and a batch of 2 copies, against the $Q_k$ and continuous momenta of
    the 50-digit reference run of the symmetric representation: max absolute error."""
    from symrb import engine

    run = _mp_run()
    one = engine.mv_flow(run["Q0"], run["M0"], _LAM3, _H, _STEPS)
    two = engine.mv_flow(np.stack([run["Q0"]] * 2), np.stack([run["M0"]] * 2), _LAM3, _H, _STEPS)
    errs = [
        np.abs(one.y.Q - run["Qf"]).max(),
        np.abs(one.y.M - run["Mcf"]).max(),
        np.abs(two.y.Q - run["Qf"][:, None]).max(),
        np.abs(two.y.M - run["Mcf"][:, None]).max(),
    ]
    return float(np.max(errs))


@M2.check(Level.FLOAT64, tol=1e-12)
def m2_engine_general_n_equations() -> float:
    r"""symrb.engine.mv_flow at $n = 5$ and $n = 8$ (the general-$n$ solver and its increment
    update, not the $n = 3$ kernels; by the NumPy path and, when numba is installed, by the
    compiled loop of each), 40 steps of $h = 0.05$: with $U_k = Q_k^T Q_{k+1}$ from the
    returned attitudes, the defining equations $J_D(U_k) = h M_k$ (reference.J_D, explicit
    $\Lambda$) and $M_{k+1} = U_k^T M_k U_k$, and $U_k^T U_k = I$: max residual relative to $\max(1,
    |h M_k|)$. Then 3000 steps at $n = 5$ with $h \|M\|_{\mathrm{op}} = 0.5$: $\max |M + M^T|$ (an
    exactly skew update gives 0), and the relative drift of $\operatorname{tr} M^T M$ in units of
    $10 \varepsilon \sqrt{N}$, scaled so that one unit is 1e-12 (the tolerance)."""
    from symrb import _compiled_n, engine

    worst = 0.0
    methods = ("numpy", "numba") if _compiled_n.AVAILABLE else ("numpy",)
    for dim, method in [(d, m) for d in (5, 8) for m in methods]:
        rng = np.random.default_rng(50 + dim)
        lam = rng.uniform(0.5, 2.0, dim)
        Q0 = ref.random_rotation(dim, rng)
        M0 = ref.random_skew(dim, rng, 1.0)
        h = 0.05
        sol = engine.mv_flow(Q0, M0, lam, h, 40, method=method)
        Q, M = sol.y.Q, sol.y.M
        U = np.swapaxes(Q[:-1], -1, -2) @ Q[1:]
        scale = max(1.0, float(np.abs(h * M).max()))
        r1 = np.abs(ref.J_D(U, lam) - h * M[:-1]).max() / scale
        r2 = np.abs(np.swapaxes(U, -1, -2) @ M[:-1] @ U - M[1:]).max() / max(1.0, np.abs(M).max())
        r3 = np.abs(np.swapaxes(U, -1, -2) @ U - np.eye(dim)).max()
        worst = max(worst, float(r1), float(r2), float(r3))
    # a long run with a large step (h ||M||_op = 0.5, 3000 steps): M stays skew-symmetric (an
    # update skew only to rounding let a symmetric part grow like (1 + ||D||^2)^k, to 6e-2 here)
    # and tr M^2 drifts by no more than rounding does in 3000 steps
    rng = np.random.default_rng(55)
    lam = rng.uniform(0.5, 2.0, 5)
    M0 = ref.random_skew(5, rng, 1.0)
    M0 = M0 / np.linalg.norm(M0, 2)
    for method in methods:
        M = engine.mv_flow(np.eye(5), M0, lam, 0.5, 3000, save_every=3000, method=method).y.M
        sym = np.abs(M + np.swapaxes(M, -1, -2)).max()
        casimir = np.einsum("kij,kij->k", M, M)
        drift = abs(casimir[-1] / casimir[0] - 1.0) / (10.0 * np.sqrt(3000.0))  # in units of
        worst = max(worst, float(sym), float(drift) * 1e-12 / np.finfo(float).eps)  # 10 eps √N
    return worst


@M2.check(Level.FLOAT64, tol=1.0)
def m2_engine_n3_long_run_rounding() -> float:
    r"""symrb.engine.mv_flow, $n = 3$ (the fused kernel; the compiled loop too when numba is
    installed), $\lambda = (10^{-3}, 1, 10^3)$, $h M_0$ a tenth of the way or so to the fold, $2
    \cdot 10^4$ steps: the largest relative energy and $\operatorname{tr} M^2$ errors and $\max |Q^T
    Q - I|$, in units of $10 \varepsilon \sqrt{N}$ (the long-time goal; the kernel's update written
    as $U^T m$ gave 17)."""
    from symrb import _compiled, engine

    lam = np.array([1e-3, 1.0, 1e3])
    rng = np.random.default_rng(2)
    M0 = ref.random_skew(3, rng, 1.0)
    M0 = M0 * (0.5 * lam.min() / np.linalg.norm(M0, 2))
    N = 20_000
    worst = 0.0
    for method in ("numpy", "numba") if _compiled.AVAILABLE else ("numpy",):
        sol = engine.mv_flow(np.eye(3), M0, lam, 1.0, N, save_every=100, method=method)
        M, Q = sol.y.M, sol.y.Q
        m = np.stack([M[:, 2, 1], M[:, 0, 2], M[:, 1, 0]], axis=-1)
        inertia = lam.sum() - lam  # I_1 = lam_2 + lam_3 (cyclic)
        H = 0.5 * (m**2 / inertia).sum(axis=-1)
        C = (m**2).sum(axis=-1)
        orth = np.abs(np.swapaxes(Q, -1, -2) @ Q - np.eye(3)).max(axis=(-2, -1))
        err = np.maximum.reduce([np.abs(H / H[0] - 1), np.abs(C / C[0] - 1), orth])
        k = np.maximum(sol.k, 100)
        worst = max(worst, float((err / (10 * np.finfo(float).eps * np.sqrt(k))).max()))
    return worst


@M2.check(Level.FLOAT64, tol=0.0)
def m2_engine_accepts_only_states() -> float:
    r"""symrb.engine.mv_flow, $n = 3$, one body given as float64 arrays (its fast path of the
    input checks) and the same bodies as a batch of two: an attitude $Q_0 = R(I + \epsilon S)$
    ($R$ a rotation, $S$ symmetric, $\epsilon = 10^{-12}, 10^{-7}, 10^{-5}, 10^{-3}$), a reflection,
    and a momentum with a symmetric part $10^{-4}$; the number of runs accepted or refused
    (InputError) against the documented rule computed with plain NumPy ($\max|Q_0^TQ_0 - I| \le
    10^{-8}$ and $\det Q_0 > 0$; $M_0$ skew to rounding)."""
    from symrb import engine
    from symrb.errors import InputError

    rng = np.random.default_rng(23)
    R = ref.random_rotation(3, rng)
    S = rng.standard_normal((3, 3))
    S = S + S.T
    M = ref.random_skew(3, rng, 1.0)
    cases = [(R @ (np.eye(3) + e * S), M) for e in (1e-12, 1e-7, 1e-5, 1e-3)]
    cases += [(R @ np.diag([1.0, 1.0, -1.0]), M), (R, M + 1e-4 * S)]
    wrong = 0
    for Q0, M0 in cases:
        want = bool(np.abs(Q0.T @ Q0 - np.eye(3)).max() <= 1e-8 and np.linalg.det(Q0) > 0)
        want = want and bool(np.abs(M0 + M0.T).max() <= 1e-12)
        for q, m in ((Q0, M0), (np.stack([Q0, R]), np.stack([M0, M]))):
            try:
                engine.mv_flow(q, m, _LAM3, 0.1, 2)
                got = True
            except InputError:
                got = False
            wrong += int(got != want)
    return float(wrong)
