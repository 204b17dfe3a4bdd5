"""The free rigid body as a scene (``system = "rigid_body"``): the momentum alone
(:class:`RigidBodyMomentum`) or with the attitude, by any method of
:func:`symrb.rigid_body.simulate` (the ``[integrator]`` table is its keyword arguments, see
:mod:`._rigid_body_methods`) or by the paper's algorithms (the symmetric representation,
MV-Algorithms 1 and 2); each integrator planned and run by a function of its own."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any, Literal

import numpy as np

from ... import _validate as v
from ..._generated import rigid_body as _rb
from ..._validate import Array
from ...algebra import _Jinv_weights
from ...composition import composition_coefficients
from ...continuous import Flow
from ...engine import _mv_momentum_flow
from ...errors import InputError
from ...paper import discrete_rigid_body_flow, mv_algorithm1, mv_algorithm2, symmetric_flow
from ...rigid_body import simulate
from ..plan import (
    Plan,
    SystemPlan,
    _continuous_save,
    _est_continuous,
    _fixed_step_cost,
    _fixed_step_plan,
    _fixed_step_save,
    diagnostic_kernels,
)
from ..schema import TimeHorizon, When, _problem, register_system
from . import _rigid_body_methods as rbm
from ._body import (
    _RB_MODULES,
    _SYMMETRIC_MAP_MODULES,
    CASIMIR_LABELS,
    MANAKOV_LABELS,
    BodyParameters,
    _integrate,
    _rot,
    _rotate_back,
    body_inputs,
    body_rate,
)
from ._compare import _Q_ONLY, Compares, _ComparedBody

_MODULES = _RB_MODULES + (
    "scenes.systems._compare",
    "scenes.systems._rigid_body_methods",
    "scenes.systems.rigid_body",
)
#: the modules of the Moser-Veselov engine, and of the paper's MV-Algorithms
_MV_MODULES = (
    "engine",
    "paper",
    "_stepping",
    "solvers",
    "_compiled",
    "_generated.discrete_rigid_body",
)
#: the modules behind the compositions, RKMK4, the midpoint rule and the exact solution
_COMPOSE_MODULES = ("compose", "composition", "base_steps", "engine", "solvers", "_stepping",
                    "_compiled", "_progress", "_generated.discrete_rigid_body")  # fmt: skip
_EXACT_MODULES = ("exact",)
_SPLITTING_MODULES = ("splitting", "composition", "_stepping")
_MV_ALGORITHM_MODULES = (
    "paper",
    "engine",
    "_compiled",
    "_stepping",
    "solvers",
    "_generated.discrete_rigid_body",
    "_progress",
)


class RigidBodyMomentum(Flow):
    r"""The rigid body's momentum alone, :math:`\dot M = [M, \Omega]`, :math:`\Omega = J^{-1}M`.

    The momentum equation does not involve the attitude, so a scene that observes only
    momenta, energies or integrals propagates this flow: n(n - 1)/2... as stored, ``n^2`` numbers
    instead of ``2 n^2`` and two matrix products a step instead of three.  The field is the
    generated ``rigid_body_rhs`` (claim S2) evaluated with an empty attitude of shape (0, n),
    whose product costs nothing.  State ``("M",)``; derived ``Omega``.

    Examples
    --------
    >>> import numpy as np
    >>> import symrb
    >>> from symrb.scenes import RigidBodyMomentum
    >>> lam, M0 = np.array([0.7, 1.1, 1.6]), symrb.hat([0.5, 1.0, 1.5])
    >>> a = symrb.integrate(RigidBodyMomentum, (0, 5), {"M": M0}, lam=lam, t_eval=[5.0])
    >>> b = symrb.integrate(symrb.RigidBody, (0, 5), {"Q": np.eye(3), "M": M0}, lam=lam,
    ...                     t_eval=[5.0])
    >>> bool(np.abs(a.y.M - b.y.M).max() < 1e-9)
    True
    """

    name = "rigid body momentum"
    state = ("M",)

    def rhs(self, y, lam):
        M = y["M"]
        return (_rb.rigid_body_rhs(np.empty((0, M.shape[-1])), M, lam)[1],)

    def check(self, y, lam):
        v.skew(y["M"], "y0['M']")

    def derived(self, y, lam):
        return {"Omega": _Jinv_weights(lam) * y["M"]}


@register_system
class RigidBodyScene(_ComparedBody):
    """The free rigid body (momentum only, or with the attitude: effect ``attitude``).

    The ``[integrator]`` table is the keyword arguments of :func:`symrb.rigid_body.simulate`:
    ``method`` (a key of :data:`symrb.rigid_body.METHODS`, default ``"DOP853"``) and the
    keywords that method takes (``h``, ``order``, ``rtol``, ``atol``, its options), with their
    names, defaults and meanings; the run is one call of ``simulate`` over ``(0, T)`` at the
    observables' times.  Without the effect ``attitude``, a ``solve_ivp`` method and ``"mv"``
    propagate the momentum alone instead (:class:`RigidBodyMomentum`; ``"mv"``: its steps on
    M, at every n).  ``method = "discrete"``, ``"mv_algorithm1"`` and ``"mv_algorithm2"`` run the
    paper's algorithms (:mod:`symrb.paper`; see :mod:`._rigid_body_methods`).

    Examples
    --------
    >>> from symrb.scenes import RigidBodyScene, load_scene, plan_scene
    >>> RigidBodyScene.EFFECTS, sorted(RigidBodyScene.OBSERVABLES)  # doctest: +NORMALIZE_WHITESPACE
    (('attitude',), ['M', 'M_gap', 'Omega', 'Q', 'Q_gap', 'casimirs', 'energy', 'lax_spectrum',
    'manakov', 'orthogonality'])
    >>> scene = load_scene('''
    ... system = "rigid_body"
    ... effects = ["attitude"]
    ... [integrator]
    ... method = "composition"
    ... h = 0.1
    ... order = 6
    ... [horizon]
    ... T = 10.0
    ... [observables]
    ... energy = {every = 10}
    ... ''')
    >>> print(plan_scene(scene).route)  # doctest: +NORMALIZE_WHITESPACE
    symrb.rigid_body.simulate(Q0, M0, lam, (0, T), method='composition', h=0.1, order=6,
    kind=None, step='mv', save_every=...), which calls symrb.compose.composed_rigid_body_flow
    """

    EFFECTS = ("attitude",)
    STATE_OBSERVABLES = ("Q", "M")
    INVARIANTS = {
        "energy": ("energy",),
        "casimirs": CASIMIR_LABELS,
        "manakov": MANAKOV_LABELS,
        "lax_spectrum": (),
    }
    OBSERVABLES = {
        "M": None, "Omega": None, "energy": None, "casimirs": None, "manakov": None,
        "lax_spectrum": None, "Q": "attitude", "orthogonality": "attitude", "M_gap": None,
        "Q_gap": "attitude",
    }  # fmt: skip
    system: Literal["rigid_body"]
    parameters: BodyParameters = BodyParameters()
    integrator: rbm.RigidBodyIntegrator
    horizon: TimeHorizon
    compare: Compares | None = None
    observables: dict[
        Literal[
            "M",
            "Omega",
            "energy",
            "casimirs",
            "manakov",
            "lax_spectrum",
            "Q",
            "orthogonality",
            "M_gap",
            "Q_gap",
        ],  # fmt: skip
        When,
    ]

    def _inputs(self) -> dict[str, Any]:
        """``lam``, ``Q0`` and ``M0``."""
        return body_inputs(self.parameters)

    def _own_plan(self, skipped: list[tuple[str, str]], notes: list[str]) -> SystemPlan:
        if "attitude" not in self.effects:
            skipped.append(("attitude Q", "effect 'attitude' not named: the momentum equation "
                            "M' = [M, Omega] does not involve Q"))  # fmt: skip
        integ = self.integrator
        h = rbm.step(integ)
        if h is None:
            part = _ADAPTIVE_PLANS[type(integ)](self, notes)
        else:
            part = _FIXED_STEP_PLANS[type(integ)](self, skipped, notes, _fixed_step_save(self, h))
        return dataclasses.replace(
            part, kernels=part.kernels + diagnostic_kernels(self.observables)
        )

    def _states(
        self, plan: Plan, x: dict[str, Any], rotation: Array | None
    ) -> tuple[Array, dict[str, Array], str]:
        return _RUNS[type(self.integrator)](self, plan, x, rotation)


# ---------------------------------------------------------------------------------------------
# the plan of each integrator

_Fixed = tuple[int, int, dict[str, tuple[int, ...]]]


def _plan_continuous(sc: RigidBodyScene, notes: list[str]) -> SystemPlan:
    integ: Any = sc.integrator
    p = sc.parameters
    attitude = "attitude" in sc.effects
    rate = body_rate(p)
    t_eval, index = _continuous_save(sc)
    flow = "RigidBody" if attitude else "symrb.scenes.RigidBodyMomentum"
    if not attitude:
        notes.append(
            "solve_ivp's error control sees only M here, so its steps (and M, to the "
            "tolerance) differ from a run that also carries Q"
        )
    if attitude:
        route = _simulate_route(integ, "t_eval")
    else:
        route = (f"symrb.integrate({flow}, method={integ.method!r}, rtol={integ.rtol:g}, "
                 f"atol={integ.atol:g})")  # fmt: skip
    return SystemPlan(
        route=route,
        propagated=("Q", "M") if attitude else ("M",),
        kernels=("rigid_body.rigid_body_rhs",),
        save={"t_eval": [float(t) for t in t_eval]},
        index=index,
        cost=_est_continuous(sc.horizon.T, integ.rtol, rate, (6.0 if attitude else 4.0) * p.n**3),
        modules=_MODULES,
    )


def _plan_mv(
    sc: RigidBodyScene, skipped: list[tuple[str, str]], notes: list[str], fixed: _Fixed
) -> SystemPlan:
    steps = fixed[0]
    integ: Any = sc.integrator
    n = sc.parameters.n
    attitude = "attitude" in sc.effects
    if integ.order != 2 and n != 3:
        raise _problem("integrator.order",
                       f"the preprocessed method (order {integ.order}) needs n = 3, "
                       f"got n = {n}", [2])  # fmt: skip
    kernels: tuple[str, ...] = ("discrete_rigid_body.mv3_cayley_step",) if n == 3 else ()
    if attitude:
        route = _simulate_route(integ, "save_every")
        propagated: tuple[str, ...] = ("Q", "M")
    else:
        route = (f"symrb.engine._mv_momentum_flow(M0, lam, h={integ.h:g}, order={integ.order}): "
                 "the steps of simulate(method='mv') on M alone, M_{k+1} = U_k^T M_k U_k with "
                 "J_D(U_k) = h M_k, which needs no Q")  # fmt: skip
        propagated = ("M",)
        if n == 3:
            notes.append("n = 3: the fused kernel mv3_cayley_step is called with an empty "
                         "attitude, so its Q part does no arithmetic; the NumPy loop (the "
                         "compiled loop carries Q)")  # fmt: skip
    if integ.order != 2:
        kernels += ("discrete_rigid_body.mv3_preprocessed_lam",)
    per = 3e-6 if n == 3 else 8 * 2.0 * n**3 / 1.5e9 + 40e-6
    flops = 60.0 if n == 3 else 16.0 * n**3
    how = " a step (n = 3: one fused kernel call; else ~4 solver sweeps of two n^3 products)"
    cost = _fixed_step_cost(steps, flops, per, how)
    return _fixed_step_plan(fixed, route, propagated, kernels, cost, _MODULES + _MV_MODULES)


#: what ``simulate`` calls for each integrator model
_IMPLEMENTATIONS: dict[type, str] = {
    rbm.SolveIVP: "symrb.integrate(RigidBody, ...)", rbm.MV: "symrb.engine.mv_flow",
    rbm.Composition: "symrb.compose.composed_rigid_body_flow",
    rbm.RKMK4: "symrb.compose.rkmk4_rigid_body_flow",
    rbm.Midpoint: "symrb.compose.midpoint_rigid_body_flow",
    rbm.Exact: "symrb.exact.rigid_body_exact", rbm.Splitting: "symrb.splitting.splitting_flow",
}  # fmt: skip


def _simulate_route(integ: Any, save: str) -> str:
    """``symrb.rigid_body.simulate(...)`` with the integrator table's keywords, and what it
    calls."""
    kw = ", ".join(f"{k}={val!r}" for k, val in rbm.simulate_keywords(integ).items())
    return (f"symrb.rigid_body.simulate(Q0, M0, lam, (0, T), {kw}, {save}=...), which calls "
            f"{_IMPLEMENTATIONS[type(integ)]}")  # fmt: skip


def _needs_n3(sc: RigidBodyScene, what: str) -> None:
    if sc.parameters.n != 3:
        raise _problem("integrator.method", f"{what} needs n = 3, got n = {sc.parameters.n}",
                       [m for m in rbm.METHOD_NAMES if m != "exact"])  # fmt: skip


def _plan_exact(sc: RigidBodyScene, notes: list[str]) -> SystemPlan:
    """The exact solution at the observables' times (n = 3)."""
    _needs_n3(sc, "the exact solution (Jacobi elliptic functions)")
    if "attitude" not in sc.effects:
        notes.append("the exact solution evaluates Q with M: Q is computed, though not recorded")
    t_eval, index = _continuous_save(sc)
    per = 20e-6
    return SystemPlan(
        route=_simulate_route(sc.integrator, "t_eval"),
        propagated=("Q", "M"),
        kernels=(),
        save={"t_eval": [float(t) for t in t_eval]},
        index=index,
        cost={
            "flops": 200.0 * len(t_eval),
            "seconds": 1e-3 + per * len(t_eval),
            "formula": f"{len(t_eval)} times x ~{per * 1e6:.0f} us (elliptic functions) "
            "+ 1 ms of setup",
        },  # fmt: skip
        modules=_MODULES + _EXACT_MODULES,
    )


def _attitude_unrecorded(
    sc: RigidBodyScene, skipped: list[tuple[str, str]], notes: list[str], verb: str
) -> None:
    """A ``simulate`` plan without the "attitude" effect: its Q is still propagated with M (the
    last entry of ``skipped``, Q's, is dropped; a note says so)."""
    if "attitude" not in sc.effects:
        skipped.pop()
        notes.append(f"simulate(method={sc.integrator.method!r}) {verb} Q with M: Q is "
                     "propagated, though not recorded")  # fmt: skip


def _plan_composed(
    sc: RigidBodyScene, skipped: list[tuple[str, str]], notes: list[str], fixed: _Fixed
) -> SystemPlan:
    """A composition, RKMK4 or the midpoint rule: ``simulate`` at the step ``h``."""
    integ: Any = sc.integrator
    n = sc.parameters.n
    _attitude_unrecorded(sc, skipped, notes, "steps")
    if isinstance(integ, rbm.Composition):
        try:
            stages = len(composition_coefficients(integ.order, integ.kind))
        except InputError as exc:
            raise _problem("integrator.kind", str(exc), None) from None
        base = 3e-6 if integ.step == "mv" and n == 3 else 8 * 2.0 * n**3 / 1.5e9 + 40e-6
        how = f" ({stages} stages of the {integ.step} step)"
    else:
        stages = 4 if isinstance(integ, rbm.RKMK4) else 1
        base = 10e-6 + 4 * 2.0 * n**3 / 1.5e9
        how = f" ({integ.method})"
    per = stages * base
    cost = _fixed_step_cost(fixed[0], stages * 16.0 * n**3, per, how)
    return _fixed_step_plan(fixed, _simulate_route(integ, "save_every"), ("Q", "M"), (), cost,
                            _MODULES + _COMPOSE_MODULES)  # fmt: skip


def _plan_splitting(
    sc: RigidBodyScene, skipped: list[tuple[str, str]], notes: list[str], fixed: _Fixed
) -> SystemPlan:
    """The splitting into planar rotations: ``simulate`` at the step ``h``."""
    integ: Any = sc.integrator
    n = sc.parameters.n
    _attitude_unrecorded(sc, skipped, notes, "rotates")
    stages = len(composition_coefficients(integ.order))
    rotations = stages * (n * n - n + 1)  # about 2 n(n - 1)/2 planar rotations a stage
    how = f" ({stages} stages of {n * (n - 1) // 2} planes, each rotated about twice)"
    cost = _fixed_step_cost(fixed[0], rotations * 20.0 * n, rotations * 2e-6, how)
    return _fixed_step_plan(fixed, _simulate_route(integ, "save_every"), ("Q", "M"), (), cost,
                            _MODULES + _SPLITTING_MODULES)  # fmt: skip


def _plan_mv_algorithm(
    sc: RigidBodyScene, skipped: list[tuple[str, str]], notes: list[str], fixed: _Fixed
) -> SystemPlan:
    """MV-Algorithm 1, or MV-Algorithm 2 from (Q0, h M0) or from (Q1, M1)."""
    steps, every, _ = fixed
    integ: Any = sc.integrator
    n = sc.parameters.n
    modules: tuple[str, ...] = _MODULES + _MV_ALGORITHM_MODULES
    first = ("symrb.discrete_rigid_body_flow(Q0, M0, lam, h, 1) for Q_1 and M_1 = "
             "h (Q0^T P0 - P0^T Q0) (the first step, D12), then ")  # fmt: skip
    kernels: tuple[str, ...]
    if isinstance(integ, rbm.MVAlgorithm1):
        route = (first + f"symrb.mv_algorithm1(Q0, Q1, lam, steps - 1) with "
                 f"h={integ.h:g} (the paper's MV-Algorithm 1)")  # fmt: skip
        propagated: tuple[str, ...] = ("Q",)
        skipped.append(("M", "MV-Algorithm 1 carries configurations only"))
        kernels = ("discrete_rigid_body.mv_momentum", "discrete_rigid_body.mv_transport")
    elif integ.start == "Q1_M1":
        more = "steps" if any(o not in _Q_ONLY for o in sc.observables) else "steps - 1"
        route = (first + f"symrb.mv_algorithm2(Q1, M1, lam, {more}) with "
                 f"h={integ.h:g} (the paper's MV-Algorithm 2 and indices; Q_k and "
                 "M_{k+1}/h recorded at t_k)")  # fmt: skip
        propagated = ("Q", "M")
        kernels = ("discrete_rigid_body.mv_transport",)
        if any(o in _Q_ONLY for o in sc.observables) and every > 1:
            notes.append(f"start Q1_M1: the run from Q_1 saves every step (Q_k is "
                         f"its (k - 1)-th), and every {every}-th is kept")  # fmt: skip
    else:
        route = (f"symrb.mv_algorithm2(Q0, h M0, lam, steps) with h={integ.h:g} "
                 "(the paper's MV-Algorithm 2; its discrete momenta divided by "
                 "h)")  # fmt: skip
        propagated = ("Q", "M")
        kernels = ("discrete_rigid_body.mv_transport",)
    if "attitude" not in sc.effects and "Q" in propagated:
        skipped.pop()
        notes.append("MV-Algorithm 2 steps Q_{k+1} = Q_k Omega_{k+1}^T itself, so Q "
                     "is propagated, though not recorded")  # fmt: skip
    if not isinstance(integ, rbm.MVAlgorithm2) or integ.start == "Q1_M1":
        modules += ("_generated.symmetric_rigid_body",)
        kernels += ("symmetric_rigid_body.symmetric_momentum",)
    route += _LOOPS[integ.loop]
    per = (40e-6 if integ.loop == "reference" else 5e-6) + 16.0 * n**3 / 1.5e9
    cost = _fixed_step_cost(steps, 16.0 * n**3, per, " (one solve of J_D(Omega^T) = M a step)")
    return _fixed_step_plan(fixed, route, propagated, kernels, cost, modules)


#: how symrb.paper computes the paper's algorithm (``loop`` of the integrator table)
_LOOPS = {
    "engine": "; computed by the engine, one symrb.engine.mv_flow run",
    "reference": "; the step-by-step loop (diagnostics=True), not the engine",
}


def _plan_discrete(
    sc: RigidBodyScene, skipped: list[tuple[str, str]], notes: list[str], fixed: _Fixed
) -> SystemPlan:
    steps = fixed[0]
    integ: Any = sc.integrator
    n = sc.parameters.n
    if "attitude" not in sc.effects:
        skipped.pop()
        notes.append("the symmetric representation's state is (Q, P): Q is "
                     "propagated by the map itself, though not recorded")  # fmt: skip
    per = (60e-6 if integ.loop == "reference" else 5e-6) + 30.0 * n**3 / 1.5e9
    return _fixed_step_plan(
        fixed, f"symrb.discrete_rigid_body_flow(h={integ.h:g})" + _LOOPS[integ.loop], ("Q", "P"),
        ("symmetric_rigid_body.symmetric_momentum",),
        _fixed_step_cost(steps, 30.0 * n**3, per, " (a Newton solve of J_D(U) = hM a step)"),
        _MODULES + _SYMMETRIC_MAP_MODULES,
    )  # fmt: skip


_PlanFixed = Callable[[RigidBodyScene, list[tuple[str, str]], list[str], _Fixed], SystemPlan]
#: the plan of each fixed-step integrator
_FIXED_STEP_PLANS: dict[type, _PlanFixed] = {
    rbm.MV: _plan_mv, rbm.Composition: _plan_composed, rbm.RKMK4: _plan_composed,
    rbm.Midpoint: _plan_composed, rbm.MVAlgorithm1: _plan_mv_algorithm,
    rbm.MVAlgorithm2: _plan_mv_algorithm, rbm.Discrete: _plan_discrete,
    rbm.Splitting: _plan_splitting,
}  # fmt: skip
_PlanAdaptive = Callable[[RigidBodyScene, list[str]], SystemPlan]
#: the plan of each integrator without steps of its own
_ADAPTIVE_PLANS: dict[type, _PlanAdaptive] = {
    rbm.SolveIVP: _plan_continuous, rbm.Exact: _plan_exact,
}  # fmt: skip


# ---------------------------------------------------------------------------------------------
# the run of each integrator

_Run = tuple[Array, dict[str, Array], str]


def _run_continuous(
    sc: RigidBodyScene, plan: Plan, x: dict[str, Any], rotation: Array | None
) -> _Run:
    """With the attitude: ``simulate``; the momentum alone: ``integrate(RigidBodyMomentum)``."""
    if "Q" in plan.propagated:
        return _run_simulate(sc, plan, x, rotation)
    return _integrate(sc, plan, RigidBodyMomentum, {"M": x["M0"]}, x["lam"], rotation)


def _run_mv(sc: RigidBodyScene, plan: Plan, x: dict[str, Any], rotation: Array | None) -> _Run:
    """``simulate(method="mv")``; without the attitude, the same steps on M alone."""
    if "Q" in plan.propagated:
        return _run_simulate(sc, plan, x, rotation)
    integ: Any = sc.integrator
    sol = _mv_momentum_flow(x["M0"], x["lam"], integ.h, plan.save["steps"],
                            plan.save["save_every"], integ.backend, integ.order)  # fmt: skip
    return sol.t, {"M": sol.y.M}, "" if sol.success else sol.message


def _run_simulate(
    sc: RigidBodyScene, plan: Plan, x: dict[str, Any], rotation: Array | None
) -> _Run:
    """One call of ``simulate`` with the integrator table's keywords, over (0, T), at the
    output times of the plan (``t_eval``, or ``save_every`` of a fixed step)."""
    save = ({"t_eval": plan.save["t_eval"]} if "t_eval" in plan.save
            else {"save_every": plan.save["save_every"]})  # fmt: skip
    sol = simulate(_rot(rotation, x["Q0"]), x["M0"], x["lam"], (0.0, float(sc.horizon.T)),
                   **rbm.simulate_keywords(sc.integrator), **save)  # fmt: skip
    keep = ("Q", "M") if "attitude" in sc.effects else ("M",)
    states = _rotate_back({k: getattr(sol, k) for k in keep}, rotation)
    return sol.t, states, "" if sol.success else sol.message


def _run_mv_algorithm2(
    sc: RigidBodyScene, plan: Plan, x: dict[str, Any], rotation: Array | None
) -> _Run:
    integ: Any = sc.integrator
    if integ.start == "Q1_M1":
        return _mv_from_first_step(sc, plan, x, rotation)
    steps, every = plan.save["steps"], plan.save["save_every"]
    dsol = mv_algorithm2(_rot(rotation, x["Q0"]), integ.h * x["M0"], x["lam"], steps,
                         save_every=every, diagnostics=integ.loop == "reference")  # fmt: skip
    keep = ("Q",) if "attitude" in sc.effects else ()
    states = {k: dsol.y[k] for k in keep}
    states["M"] = dsol.y.M / integ.h
    return (np.asarray(dsol.k, dtype=float) * integ.h, _rotate_back(states, rotation),
            "" if dsol.success else dsol.message)  # fmt: skip


def _run_discrete(
    sc: RigidBodyScene, plan: Plan, x: dict[str, Any], rotation: Array | None
) -> _Run:
    integ: Any = sc.integrator
    steps, every = plan.save["steps"], plan.save["save_every"]
    lam, diag = x["lam"], integ.loop == "reference"
    if rotation is None:
        dsol = discrete_rigid_body_flow(x["Q0"], x["M0"], lam, integ.h, steps,
                                        save_every=every, diagnostics=diag)  # fmt: skip
    else:  # the state (Q0, P0) of the symmetric algorithm, rotated: P0 as the flow sets it
        P0 = discrete_rigid_body_flow(x["Q0"], x["M0"], lam, integ.h, 1).y.P[0]
        dsol = symmetric_flow(_rot(rotation, x["Q0"]), _rot(rotation, P0), lam, integ.h, steps,
                              save_every=every, diagnostics=diag)  # fmt: skip
    keep = ("Q", "M") if "attitude" in sc.effects else ("M",)
    states = _rotate_back({k: dsol.y[k] for k in keep}, rotation)
    return dsol.t, states, "" if dsol.success else dsol.message


def _mv_from_first_step(sc: Any, plan: Plan, x: dict[str, Any], rotation: Array | None) -> _Run:
    """MV-Algorithm 1 from (Q_0, Q_1), or MV-Algorithm 2 from (Q_1, M_1) (``start = "Q1_M1"``),
    Q_1 and M_1 from the symmetric algorithm's first step; Q_k and M_{k+1}/h at t_k."""
    integ, lam, h = sc.integrator, x["lam"], sc.integrator.h
    steps, every = plan.save["steps"], plan.save["save_every"]
    diag = integ.loop == "reference"
    first = discrete_rigid_body_flow(x["Q0"], x["M0"], lam, h, 1, diagnostics=diag)
    if not first.success:
        empty = np.zeros((0,) + x["Q0"].shape)
        return np.zeros(0), {"Q": empty, "M": empty}, first.message
    Q1, M1 = first.y.Q[1], h * first.y.M[0]
    if isinstance(integ, rbm.MVAlgorithm1):
        dsol = mv_algorithm1(_rot(rotation, x["Q0"]), _rot(rotation, Q1), lam, steps - 1,
                             save_every=every, diagnostics=diag)  # fmt: skip
        return (np.asarray(dsol.k, dtype=float) * h, _rotate_back({"Q": dsol.y.Q}, rotation),
                "" if dsol.success else dsol.message)  # fmt: skip
    need_Q = any(o.removesuffix("_gap") in ("Q", "orthogonality") for o in plan.index)
    need_M = any(o.removesuffix("_gap") not in ("Q", "orthogonality") for o in plan.index)
    # Q_k is the (k - 1)-th state of the run from Q_1: with Q asked for every e > 1 steps the
    # run saves every step; M_{k+1}, its k-th momentum, is saved at the steps asked for
    save = every if every == 1 or not need_Q else 1
    dsol = mv_algorithm2(_rot(rotation, Q1), M1, lam, steps if need_M else steps - 1,
                         save_every=save, diagnostics=diag)  # fmt: skip
    states: dict[str, Array] = {}
    if need_Q:
        Qs = np.concatenate([_rot(rotation, x["Q0"])[None], dsol.y.Q])[: steps + 1]
        states["Q"] = Qs[::every] if save == 1 else Qs
    if need_M:
        Ms = dsol.y.M / h
        states["M"] = Ms[::every] if save != every else Ms
    count = min(len(a) for a in states.values())
    states = {k: a[:count] for k, a in states.items()}
    times = (np.arange(count) * every).astype(float) * h
    return times, _rotate_back(states, rotation), "" if dsol.success else dsol.message


_RunFn = Callable[[RigidBodyScene, Plan, dict[str, Any], Array | None], _Run]
#: the run of each integrator
_RUNS: dict[type, _RunFn] = {
    rbm.SolveIVP: _run_continuous, rbm.MV: _run_mv, rbm.Composition: _run_simulate,
    rbm.RKMK4: _run_simulate, rbm.Midpoint: _run_simulate, rbm.Exact: _run_simulate,
    rbm.MVAlgorithm1: _mv_from_first_step, rbm.MVAlgorithm2: _run_mv_algorithm2,
    rbm.Discrete: _run_discrete, rbm.Splitting: _run_simulate,
}  # fmt: skip
