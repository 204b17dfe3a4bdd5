"""Extremals of the adjoint-orbit problem of Section 3.5 as a scene (``system =
"orbit_extremal"``): ``symrb.solve_orbit_bvp``, or, for one sample with the corrected sign, the
initial value problem of the double bracket flow (claim S15)."""

from __future__ import annotations

import math
from typing import Any, Literal

import numpy as np
from pydantic import Field

from ... import orbits
from ..._validate import Array
from ...algebra import commutator, pairing
from ..plan import Plan, SystemPlan, _continuous_save, _est_continuous
from ..schema import TimeHorizon, When, _Model, _problem, _SceneBase, register_system
from .double_bracket import OrbitParameters, orbit_inputs

_MODULES = ("orbits", "algebra", "_validate", "_generated.adjoint_orbits",
            "scenes.systems.double_bracket", "scenes.systems.orbit_extremal")  # fmt: skip


class BVP(_Model):
    r"""``symrb.solve_orbit_bvp`` (``scipy.integrate.solve_bvp``) with ``nodes``, ``tol``, the
    endpoint ``costate`` (``"corrected"``: :math:`p_T = -N`; ``"printed"``: the paper's
    :math:`+N`) and the costate guess ``p_guess`` (``"terminal"``: the endpoint value, the
    default of ``solve_orbit_bvp``; ``"zero"``: :math:`p \equiv 0`).  With one sample and the
    corrected sign the extremal is known (:math:`p \equiv -N`, x the double bracket flow; claim
    S15) and the initial value problem is run instead, unless ``one_sample_ivp = false``."""

    kind: Literal["bvp"]
    nodes: int = Field(default=41, ge=3)
    tol: float = Field(default=1e-6, gt=0)
    costate: Literal["corrected", "printed"] = "corrected"
    p_guess: Literal["terminal", "zero"] = "terminal"
    one_sample_ivp: bool = True


@register_system
class OrbitExtremalScene(_SceneBase):
    r"""Extremals of the adjoint-orbit problem with Brockett's potential and the terminal cost
    <x_T, N> (Section 3.5; ``symrb.solve_orbit_bvp``).

    Observables, per record and sample a (norms :math:`\|y\| = \langle y, y\rangle^{1/2}` of
    :func:`symrb.pairing`): ``x``, ``p`` (effect ``costates``), the shared control ``u``;
    ``pairing`` :math:`\langle x^a, N\rangle` (the terminal cost along the extremal);
    ``second_term`` :math:`\|[N, [N, x^a]]\|` (the costate equation's second term);
    ``db_distance`` :math:`\|x^a - x^a_{db}\|` and ``db_second_term``
    :math:`\|[N, [N, x^a_{db}]]\|`, :math:`x^a_{db}` the double bracket flow
    (``symrb.double_bracket_flow``) from :math:`x^a_0` alone: one extra run per sample, made
    only when one of them is asked for (none on the one-sample initial value route, whose state
    is that flow); ``sample_pairings`` :math:`\langle x^a, x^b\rangle` (effect ``samples``;
    conserved by the shared control).

    Examples
    --------
    >>> from symrb.scenes import OrbitExtremalScene
    >>> OrbitExtremalScene.EFFECTS, sorted(OrbitExtremalScene.OBSERVABLES)
    ... # doctest: +NORMALIZE_WHITESPACE
    (('terminal_cost', 'potential', 'samples', 'costates'), ['db_distance', 'db_second_term',
     'p', 'pairing', 'sample_pairings', 'second_term', 'u', 'x'])
    """

    EFFECTS = ("terminal_cost", "potential", "samples", "costates")
    REQUIRED = ("terminal_cost", "potential")
    STATE_OBSERVABLES = ("x", "p")
    OBSERVABLES = {
        "x": None, "u": None, "p": "costates", "pairing": None, "second_term": None,
        "db_distance": None, "db_second_term": None, "sample_pairings": "samples",
    }  # fmt: skip
    system: Literal["orbit_extremal"]
    parameters: OrbitParameters = OrbitParameters()
    integrator: BVP
    horizon: TimeHorizon
    observables: dict[
        Literal["x", "u", "p", "pairing", "second_term", "db_distance", "db_second_term",
                "sample_pairings"],
        When,
    ]  # fmt: skip

    def _inputs(self) -> dict[str, Any]:
        """``x0`` and ``N``."""
        return orbit_inputs(self.parameters)

    def _plan(self, skipped: list[tuple[str, str]], notes: list[str]) -> SystemPlan:
        t_eval, index = _continuous_save(self)
        if _orbit_ivp(self):
            part = _plan_ivp(self, skipped, notes, t_eval, index)
        else:
            part = _plan_bvp(self, skipped, notes, t_eval, index)
        if "samples" not in self.effects:
            skipped.append(("samples", "effect 'samples' not named: one sample"))
        if "costates" not in self.effects:
            skipped.append(("recording p", "effect 'costates' not named"))
        return part

    def _run(self, plan: Plan, x: dict[str, Any]) -> tuple[dict[str, Array], dict[str, Array], str]:
        t_eval = np.asarray(plan.save["t_eval"])
        x0, N = x["x0"], x["N"]
        integ = self.integrator
        failure = ""
        ivp = _orbit_ivp(self)
        if ivp:
            xs = orbits.double_bracket_flow(x0, N, t_eval)[:, None]
            ps = np.broadcast_to(-N, xs.shape).copy()
        else:
            guess = np.zeros_like(N) if integ.p_guess == "zero" else None
            res = orbits.solve_orbit_bvp(x0, N, float(self.horizon.T), costate=integ.costate,
                                         nodes=integ.nodes, tol=integ.tol, p_guess=guess)  # fmt: skip
            if not res.success:
                failure = f"solve_orbit_bvp: {res.message}"
            xs, ps = res.at(t_eval)
        # each sample's own double bracket flow, at the times of the db_* observables (the state
        # itself on the initial value route)
        db_idx = sorted({i for o in ("db_distance", "db_second_term")
                         for i in plan.index.get(o, ())})  # fmt: skip
        xdb: Array | None = None
        if db_idx and ivp:
            xdb = xs[db_idx]
        elif db_idx:
            x0s = x0 if x0.ndim == 3 else x0[None]
            ts = t_eval[db_idx]
            xdb = np.stack([orbits.double_bracket_flow(a, N, ts) for a in x0s], axis=1)
        data = {}
        for name, idx in plan.index.items():
            sel = list(idx)
            own = (
                xdb[np.searchsorted(db_idx, sel)]
                if name.startswith("db_") and xdb is not None
                else None
            )
            data[name] = _observable(name, xs[sel], ps[sel], N, own)
        times = {k: t_eval[list(i)] for k, i in plan.index.items()}
        return times, data, failure


def _observable(name: str, xs: Array, ps: Array, N: Array, own: Array | None) -> Array:
    """An observable at its records: ``xs``, ``ps`` the state and costate there, ``own`` each
    sample's own double bracket flow there (for the db_* observables)."""
    if name == "x":
        return xs
    if name == "p":
        return ps
    if name == "u":
        return np.sum(commutator(ps, xs), axis=1)
    if name == "pairing":
        return pairing(xs, N)
    if name == "second_term":
        return _second_term(xs, N)
    if name == "sample_pairings":
        return pairing(xs[:, :, None], xs[:, None, :])
    assert own is not None
    return _pairing_norm(xs - own) if name == "db_distance" else _second_term(own, N)


def _orbit_ivp(sc: Any) -> bool:
    """Whether an orbit extremal scene runs as the initial value problem of the double bracket
    flow (one sample, the corrected sign, ``integrator.one_sample_ivp``)."""
    integ = sc.integrator
    return bool(sc.parameters.samples == 1 and integ.costate == "corrected"
                and integ.one_sample_ivp)  # fmt: skip


def _pairing_norm(a: Array) -> Array:
    r""":math:`\|a\| = \langle a, a\rangle^{1/2}` (:func:`symrb.pairing`), over the last two axes."""
    out: Array = np.sqrt(np.maximum(pairing(a, a), 0.0))
    return out


def _second_term(x: Array, N: Array) -> Array:
    r""":math:`\|[N, [N, x]]\|`, the second term of the costate equation (its norm)."""
    return _pairing_norm(commutator(N, commutator(N, x)))


def _db_asked(sc: OrbitExtremalScene) -> list[str]:
    return [o for o in ("db_distance", "db_second_term") if o in sc.observables]


def _plan_ivp(
    sc: OrbitExtremalScene, skipped: list[tuple[str, str]], notes: list[str], t_eval: Array,
    index: dict[str, tuple[int, ...]],
) -> SystemPlan:  # fmt: skip
    """One sample with the corrected sign: the double bracket flow (claim S15)."""
    integ = sc.integrator
    if integ.p_guess != "terminal":
        raise _problem("integrator.p_guess",
                       "one sample with the corrected sign runs as the initial value "
                       "problem of the double bracket flow, which takes no costate "
                       "guess; set integrator.one_sample_ivp = false to solve the BVP "
                       "from this guess", ["terminal"])  # fmt: skip
    skipped.append(("costate sweep (two-point boundary value problem)",
                    "one sample: p = -N along the extremal, an initial value problem "
                    "replaces the BVP (integrator.one_sample_ivp = false solves the "
                    "BVP)"))  # fmt: skip
    unused = sorted({"nodes", "tol"} & integ.model_fields_set)
    if unused:
        notes.append(f"integrator.{', '.join(unused)}: settings of the BVP, not used "
                     "on this route")  # fmt: skip
    db_asked = _db_asked(sc)
    if db_asked:
        notes.append(f"{', '.join(db_asked)}: the state is the double bracket flow "
                     "from x0 itself, so no extra run (db_distance is 0)")  # fmt: skip
    return SystemPlan(
        route="symrb.double_bracket_flow (one sample: the extremal with p_T = -N is "
        "x' = [x, [x, N]] with p = -N constant, claim S15)",
        propagated=("x",),
        kernels=("adjoint_orbits.double_bracket_rhs",),
        save={"t_eval": [float(t) for t in t_eval]},
        index=index,
        cost=_est_continuous(sc.horizon.T, 1e-11, 1.0, 8.0 * sc.parameters.n**3),
        modules=_MODULES,
    )


def _plan_bvp(
    sc: OrbitExtremalScene, skipped: list[tuple[str, str]], notes: list[str], t_eval: Array,
    index: dict[str, tuple[int, ...]],
) -> SystemPlan:  # fmt: skip
    """``symrb.solve_orbit_bvp``, and each sample's own double bracket flow if asked for."""
    integ, m, n = sc.integrator, sc.parameters.samples, sc.parameters.n
    guess = ", p_guess=0" if integ.p_guess == "zero" else ""
    sm = f"{m} sample{'s' * (m > 1)}"
    propagated: tuple[str, ...] = (f"x ({sm})", f"p ({sm})")
    kernels: tuple[str, ...] = ("adjoint_orbits (the extremal field, inside solve_orbit_bvp)",)
    secs = 0.2 * m * max(1.0, math.log(sc.horizon.T) / math.log(1.5) + 1)
    cost = {"flops": secs * 1.5e9, "seconds": secs,
            "formula": "~0.2 s per sample per continuation stage (horizons grow by 1.5 "
            "from 1 to T)"}  # fmt: skip
    if m == 1 and integ.costate == "corrected":
        notes.append("integrator.one_sample_ivp = false: the BVP is solved although "
                     "its solution is known (p = -N, x the double bracket flow; claim "
                     "S15), to check that the solver finds it")  # fmt: skip
    db_asked = _db_asked(sc)
    if db_asked:
        last = max(max(index[o]) for o in db_asked)
        propagated += (f"x_db ({m} own double bracket flow{'s' * (m > 1)})",)
        kernels += ("adjoint_orbits.double_bracket_rhs",)
        notes.append(f"{', '.join(db_asked)}: {m} extra run{'s' * (m > 1)} of "
                     "symrb.double_bracket_flow (default tolerances), from each "
                     f"sample's x0 to t = {t_eval[last]:g}")  # fmt: skip
        db = _est_continuous(float(t_eval[last]), 1e-11, 1.0, 8.0 * n**3)
        cost = {"flops": cost["flops"] + m * db["flops"],
                "seconds": cost["seconds"] + m * db["seconds"],
                "formula": f"{cost['formula']}; plus {m} x ({db['formula']})"}  # fmt: skip
    else:
        skipped.append(("each sample's own double bracket flow", "db_distance, "
                        "db_second_term not asked for"))  # fmt: skip
    return SystemPlan(
        route=f"symrb.solve_orbit_bvp(nodes={integ.nodes}, tol={integ.tol:g}, "
        f"costate={integ.costate!r}{guess}), evaluated at the save times",
        propagated=propagated,
        kernels=kernels,
        save={"t_eval": [float(t) for t in t_eval]},
        index=index,
        cost=cost,
        modules=_MODULES,
    )
