"""M7: the one entry point ``symrb.rigid_body.simulate`` and every method and option it takes.

Not a statement of the paper: symrb's ``simulate(Q0, M0, lam, t_span, method=...)`` dispatches to
the solve_ivp methods, the Moser-Veselov engine (orders 2-10), the symmetric compositions of
every kind, RKMK4, the implicit midpoint rule and the exact solution.  A wrong dispatch (an order
or a composition kind not passed on, the discrete momentum scale mixed up, ``t_eval`` or
``save_every`` read off the grid, tolerances ignored) changes the accuracy or the times of the
result; these checks hold every combination against a 20-digit Taylor integration of the rigid
body (mpmath, :func:`derivations.reference.rigid_body_mp`), independent of symrb: the error at the final time for the solve_ivp methods and the exact solution, and the
observed order of each fixed-step method from two step sizes.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable

import numpy as np

from derivations import reference as ref
from derivations.registry import Level, claim

M7 = claim(
    "M7",
    label="",
    title="One entry point for every rigid-body method",
    statement="`symrb.rigid_body.simulate` runs each method it offers at the accuracy that method "
    "has: the solve_ivp methods to their tolerances, the exact solution to rounding, and every "
    "fixed-step method (the Moser-Veselov engine at orders 2 to 10, each symmetric composition "
    "of each order and kind, with either base step, RKMK4, the implicit midpoint rule and the "
    "splitting into planar rotations) at its order; `t_eval` and `save_every` return the states "
    "at the times they name.",
    expected="holds",
    section="symrb",
    where="`symrb.rigid_body.simulate` (`symrb/rigid_body/entry.py`) and its adapters, the entry "
    "point of the README and of the rigid-body scenes",
)

_LAM = np.array([0.7, 1.1, 1.6])
_M0 = np.array([0.5, 1.0, 1.5])
_T = 1.0


@functools.cache
def _reference() -> tuple[np.ndarray, Callable[[float], tuple[np.ndarray, np.ndarray]]]:
    """The start attitude and the 20-digit reference solution from it (a function of t)."""
    Q0 = ref.random_rotation(3, np.random.default_rng(7))
    return Q0, ref.rigid_body_mp(_LAM.sum() - _LAM, Q0, _M0, 20)


def _error(sol: object, times: np.ndarray) -> float:
    """Largest |Q - Q_ref| and |m - m_ref| / |m_0| over ``times`` (the solution's rows)."""
    _, at = _reference()
    worst = 0.0
    for row, t in enumerate(times):
        Qr, mr = at(float(t))
        eQ = np.abs(sol.Q[row] - Qr).max()  # type: ignore[attr-defined]
        eM = np.abs(ref.vee(sol.M[row]) - mr).max() / np.linalg.norm(_M0)  # type: ignore[attr-defined]
        worst = max(worst, float(eQ), float(eM))
    return worst


def _fixed_step_cases() -> list[tuple[str, int, dict[str, str]]]:
    """(method, order, options) for every fixed-step method, order, mv backend ("numba" where
    numba is installed, as with the test and book extras) and composition kind and step."""
    from symrb.composition import _KINDS
    from symrb.engine import PREPROCESSED_ORDERS

    cases: list[tuple[str, int, dict[str, str]]] = [("mv", p, {}) for p in PREPROCESSED_ORDERS]
    from symrb import _compiled

    backends = ["auto", "newton", "fixed-point", "numpy"] + ["numba"] * _compiled.AVAILABLE
    cases += [("mv", 2, {"backend": b}) for b in backends]
    for order, kinds in _KINDS.items():
        for kind in kinds:
            cases.append(("composition", order, {"kind": kind}))
        cases.append(("composition", order, {"kind": kinds[-1], "step": "midpoint"}))
    cases += [("rkmk4", 4, {}), ("midpoint", 2, {})]
    cases += [("splitting", p, {}) for p in (2, 4, 6, 8)]
    cases += [("splitting", 4, {"backend": b}) for b in ["numpy"] + ["numba"] * _compiled.AVAILABLE]
    return cases


#: nominal orders of the methods whose order is not a parameter (the literature's)
_FIXED_ORDER = {"rkmk4": 4, "midpoint": 2}


def _h_for(order: int, options: dict[str, str]) -> float:
    """A step where the method's error at T = 1 is in its asymptotic range and above rounding,
    at h and at h/2 (measured here: about 1e-4 ... 1e-12); the triple jumps of order 6 and 8
    have large error constants and take smaller steps."""
    if options.get("kind") == "triple_jump" and order >= 6:
        return {6: 0.1, 8: 0.0625}[order]
    return {2: 0.05, 4: 0.1, 6: 0.2, 8: 0.25, 10: 0.5}[order]


@M7.check(Level.MPMATH, tol=0.3)
def m7_fixed_step_orders() -> float:
    r"""Every fixed-step method of simulate (mv at orders 2-10 and its backends, every composition
    kind of orders 2-8 with the MV and the midpoint base step, RKMK4, midpoint, the splitting at
    orders 2-8 and its backends): the order observed from the errors at $T = 1$ with steps $h$
    and $h/2$ against the 20-digit reference; the largest distance of the observed order from the
    nominal one (an order or a base step not passed on, or the momentum scale mixed up, moves it
    by 2 or more); inf when two compositions of one order (another kind or base step) give the
    same result (a kind or a step not passed on)."""
    from symrb.rigid_body import simulate

    Q0, _ = _reference()
    worst = 0.0
    finals: dict[int, list[np.ndarray]] = {}
    for method, order, options in _fixed_step_cases():
        nominal = _FIXED_ORDER.get(method, order)
        h = _h_for(nominal, options)
        kw = {"order": order} if method in ("mv", "composition", "splitting") else {}
        errors = []
        for step in (h, h / 2):
            sol = simulate(Q0, ref.hat(_M0), _LAM, (0.0, _T), method=method, h=step,
                           t_eval=[_T], **kw, **options)  # fmt: skip
            errors.append(_error(sol, np.array([_T])))
        observed = math.log2(errors[0] / errors[1])
        worst = max(worst, abs(observed - nominal))
        if method == "composition":
            finals.setdefault(order, []).append(sol.M[-1])
    for group in finals.values():  # kinds and steps of one order share it: one ignored shows here
        if any(np.array_equal(a, b) for i, a in enumerate(group) for b in group[i + 1 :]):
            return math.inf
    return worst


@M7.check(Level.MPMATH, tol=1e-7)
def m7_solve_ivp_and_exact() -> float:
    """Every solve_ivp method of simulate at rtol 1e-10, atol 1e-12 (DOP853 also with the option
    condition=True) and the exact solution (with its option check on and off), at $T = 1$ against
    the 20-digit reference: max error; and the tolerances are passed on (RK45 at rtol 1e-4 is at
    least 100 times less accurate than at 1e-10, else the check fails)."""
    from symrb.rigid_body import simulate
    from symrb.rigid_body.ivp import NAMES

    Q0, _ = _reference()
    worst = 0.0
    runs = [(m, {"rtol": 1e-10, "atol": 1e-12}) for m in NAMES]
    runs += [("DOP853", {"rtol": 1e-10, "atol": 1e-12, "condition": True})]
    runs += [("exact", {}), ("exact", {"check": False})]
    for method, kw in runs:
        sol = simulate(Q0, ref.hat(_M0), _LAM, (0.0, _T), method=method, t_eval=[_T], **kw)
        worst = max(worst, _error(sol, np.array([_T])))
    loose = simulate(Q0, ref.hat(_M0), _LAM, (0.0, _T), method="RK45", t_eval=[_T],
                     rtol=1e-4, atol=1e-6)  # fmt: skip
    tight = simulate(Q0, ref.hat(_M0), _LAM, (0.0, _T), method="RK45", t_eval=[_T],
                     rtol=1e-10, atol=1e-12)  # fmt: skip
    if not _error(loose, np.array([_T])) > 100 * _error(tight, np.array([_T])):
        return math.inf
    return worst


#: what the times check asks of each method: its settings and the accuracy it has there
_SAMPLED = (
    ("mv", {"h": 0.01}, 1e-4),
    ("DOP853", {"rtol": 1e-10}, 1e-8),
    ("exact", {}, 1e-12),
)


@M7.check(Level.MPMATH, tol=1.0)
def m7_times_kept() -> float:
    r"""t_eval and save_every: for mv ($h = 0.01$, error about 1e-5), DOP853 (rtol 1e-10) and exact,
    from $t_0 = 0$ and from $t_0 = 2$, the returned times are the ones asked for (t_eval at $t_0 +
    0.3, 0.5, 1.0$; save_every 25: $t_0 + 0, 0.25, \dots, 1$) and the states there agree with the
    20-digit reference to the method's accuracy (1e-4, 1e-8, 1e-12; a state one step of 0.01 off is
    1e-2 away): max error over that accuracy (inf when a time differs)."""
    from symrb.rigid_body import simulate

    Q0, _ = _reference()
    asks = [
        ({"t_eval": [0.3, 0.5, 1.0]}, np.array([0.3, 0.5, 1.0])),
        ({"save_every": 25, "h": 0.01}, np.linspace(0.0, 1.0, 5)),
    ]
    worst = 0.0
    for method, extra, accuracy in _SAMPLED:
        for t0 in (0.0, 2.0):  # the flow is autonomous: from t0 the state at t is the one at t - t0
            for ask, times in asks:
                shifted = {k: (np.asarray(x) + t0 if k == "t_eval" else x) for k, x in ask.items()}
                sol = simulate(Q0, ref.hat(_M0), _LAM, (t0, t0 + _T), method=method,
                               **{**extra, **shifted})  # fmt: skip
                if sol.t.shape != times.shape or np.abs(sol.t - t0 - times).max() > 1e-12:
                    return math.inf
                worst = max(worst, _error(sol, times) / accuracy)
    return worst
