"""The symmetric rigid body (Q, P) of Section 3.2 as a scene (``system =
"symmetric_rigid_body"``): ``symrb.integrate`` of the symmetric (or, with the effect ``samples``,
the multi-sample) field, or the symmetric representation's map ``symrb.symmetric_flow``."""

from __future__ import annotations

import dataclasses
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import Field, model_validator

from ..._validate import Array
from ...algebra import random_SO
from ...errors import InputError
from ...paper import symmetric_flow
from ...symmetric import (
    MultiSampleSymmetricRigidBody,
    P_from_M,
    SymmetricRigidBody,
    symmetric_momentum,
)
from ..plan import (
    Plan,
    SystemPlan,
    _fixed_step_cost,
    _fixed_step_plan,
    _fixed_step_save,
    diagnostic_kernels,
)
from ..schema import TimeHorizon, When, _problem, register_system
from ._body import (
    _RB_MODULES,
    _SYMMETRIC_MAP_MODULES,
    BodyParameters,
    Continuous,
    Discrete,
    _integrate,
    _rot,
    _rotate_back,
    body_continuous_plan,
    body_inputs,
)
from ._compare import Compares, _ComparedBody

_MODULES = _RB_MODULES + ("scenes.systems._compare", "scenes.systems.symmetric_rigid_body")


class SymmetricBodyParameters(BodyParameters):
    r"""A body for the symmetric rigid body, with ``start``: where :math:`(Q_0, P_0)` comes from.

    ``"momentum"`` (the default): :math:`Q_0` as ``Q0`` says and :math:`P_0 = P(Q_0, M_0)`
    (:func:`symrb.symmetric.P_from_M`), so that :math:`Q_0^TP_0 - P_0^TQ_0 = M_0`. ``"rotations"``:
    :math:`(Q_0, P_0)` = ``random_SO(n, (2,), seed=seed)``, a Haar-random pair in
    :math:`SO(n)^2`. ``"general"``: :math:`(Q_0, P_0)` with standard normal entries from
    ``numpy.random.default_rng(seed)``, a point of :math:`\mathfrak{gl}(n)^2` off
    :math:`SO(n)^2`. The last two take neither ``M0``, ``momentum``, ``op_norm`` nor ``Q0``.
    ``"boundary"``: a start on the set C of claim S11, :math:`\|M_0\|_{op} = 2`:
    :math:`Q_0` as ``Q0`` says (no momentum is drawn before it) and :math:`P_0 = Q_0A`, A the
    rotation by :math:`\pi/2` in the plane of the first two axes and, for n >= 4, by
    :math:`\arccos 0.6` in the plane of the next two; it takes neither ``M0``, ``momentum``
    nor ``op_norm``.  With ``start = "momentum"``, ``op_norm`` must be below 2 (S9: no
    :math:`P_0` in SO(n) beyond)."""

    start: Literal["momentum", "rotations", "general", "boundary"] = "momentum"

    @model_validator(mode="after")
    def _start_alone(self) -> SymmetricBodyParameters:
        if self.start != "momentum":
            keys = {"M0", "momentum", "op_norm", "samples"}
            keys |= set() if self.start == "boundary" else {"Q0"}
            given = self._given(keys)
            if given:
                what = "P0 from Q0" if self.start == "boundary" else "Q0 and P0"
                raise InputError(f"start = {self.start!r} draws {what} itself; remove {given}")
        elif self.op_norm is not None and self.op_norm >= 2:
            raise InputError(f"op_norm = {self.op_norm:g} >= 2 has no costate P0 in SO(n) (claim "
                             "S9): give op_norm < 2, or start = 'boundary' for a start on "
                             "||M||_op = 2")  # fmt: skip
        return self


@register_system
class SymmetricRigidBodyScene(_ComparedBody):
    """The symmetric rigid body (Q, P) of Section 3.2; effect ``samples`` for the learning
    version (m samples sharing the control).

    Examples
    --------
    >>> from symrb.scenes import SymmetricRigidBodyScene
    >>> SymmetricRigidBodyScene.EFFECTS, sorted(SymmetricRigidBodyScene.OBSERVABLES)
    ... # doctest: +NORMALIZE_WHITESPACE
    (('samples',), ['H', 'M', 'M_gap', 'P', 'P_orthogonality', 'Q', 'Q_gap', 'U', 'energy',
     'gram_spectrum', 'op_norm', 'orthogonality'])
    """

    EFFECTS = ("samples",)
    SINGLE_SAMPLE = False
    STATE_OBSERVABLES = ("Q", "P", "M")
    INVARIANTS = {"energy": ("energy",)}
    OBSERVABLES = {
        "Q": None, "P": None, "M": None, "H": None, "energy": None, "orthogonality": None,
        "P_orthogonality": None, "gram_spectrum": None, "op_norm": None, "U": "samples",
        "M_gap": None, "Q_gap": None,
    }  # fmt: skip
    system: Literal["symmetric_rigid_body"]
    parameters: SymmetricBodyParameters = SymmetricBodyParameters()
    integrator: Annotated[Continuous | Discrete, Field(discriminator="kind")]
    horizon: TimeHorizon
    compare: Compares | None = None
    observables: dict[
        Literal[
            "Q", "P", "M", "H", "energy", "orthogonality", "P_orthogonality", "gram_spectrum",
            "op_norm", "U", "M_gap", "Q_gap",
        ],
        When,
    ]  # fmt: skip

    def _inputs(self) -> dict[str, Any]:
        """``lam``, ``Q0``, ``M0`` and ``P0`` (see :class:`SymmetricBodyParameters`)."""
        p = self.parameters
        start = p.start
        out = body_inputs(p, boundary=start == "boundary")
        Q0, M0, n = out["Q0"], out["M0"], p.n
        if start == "momentum":
            out["P0"] = P_from_M(Q0, M0)
        elif start == "boundary":
            out["P0"] = Q0 @ _boundary_rotation(n)
            out["M0"] = symmetric_momentum(Q0, out["P0"])
        else:
            pair = (random_SO(n, (2,), seed=p.seed) if start == "rotations"
                    else np.random.default_rng(p.seed).standard_normal((2, n, n)))  # fmt: skip
            out["Q0"], out["P0"] = pair[0], pair[1]
            out["M0"] = symmetric_momentum(pair[0], pair[1])
        return out

    def _own_plan(self, skipped: list[tuple[str, str]], notes: list[str]) -> SystemPlan:
        integ: Any = self.integrator
        p = self.parameters
        samples = "samples" in self.effects
        if isinstance(integ, Discrete):
            steps, every, index = _fixed_step_save(self, integ.h)
            if samples:
                raise _problem("integrator.kind", "the learning version (effect 'samples') has "
                               "no discrete map here", ["continuous"])  # fmt: skip
            per = 60e-6 + 30.0 * p.n**3 / 1.5e9
            part = _fixed_step_plan(
                (steps, every, index), f"symrb.symmetric_flow(h={integ.h:g})", ("Q", "P"),
                ("symmetric_rigid_body.symmetric_momentum",),
                _fixed_step_cost(steps, 30.0 * p.n**3, per), _MODULES + _SYMMETRIC_MAP_MODULES,
            )  # fmt: skip
        elif samples:
            part = body_continuous_plan(self, "MultiSampleSymmetricRigidBody", (
                "symmetric_rigid_body.control_rhs", "symmetric_rigid_body.symmetric_momentum"),
                ("Q", "P"), _MODULES)  # fmt: skip
        else:
            part = body_continuous_plan(self, "SymmetricRigidBody",
                                        ("symmetric_rigid_body.symmetric_rigid_body_rhs",),
                                        ("Q", "P"), _MODULES)  # fmt: skip
        if samples:
            propagated = tuple(f"{s} ({p.samples} samples)" for s in part.propagated)
            part = dataclasses.replace(part, propagated=propagated)
        else:
            skipped.append(("samples", "effect 'samples' not named: one body"))
        # the energy's kernel last: the symmetric field's own kernels come first
        extra = diagnostic_kernels(self.observables)
        if "energy" in self.observables:
            extra = tuple(k for k in extra if k != "rigid_body.kinetic_energy")
            extra += ("rigid_body.kinetic_energy",)
        return dataclasses.replace(part, kernels=part.kernels + extra)

    def _states(
        self, plan: Plan, x: dict[str, Any], rotation: Array | None
    ) -> tuple[Array, dict[str, Array], str]:
        integ: Any = self.integrator
        Q0, P0 = _rot(rotation, x["Q0"]), _rot(rotation, x["P0"])
        if isinstance(integ, Continuous):
            flow = (MultiSampleSymmetricRigidBody if "samples" in self.effects
                    else SymmetricRigidBody)  # fmt: skip
            return _integrate(self, plan, flow, {"Q": Q0, "P": P0}, x["lam"], rotation)
        steps, every = plan.save["steps"], plan.save["save_every"]
        dsol = symmetric_flow(Q0, P0, x["lam"], integ.h, steps, save_every=every)
        states = _rotate_back({k: dsol.y[k] for k in ("Q", "P", "M")}, rotation)
        return dsol.t, states, "" if dsol.success else dsol.message


def _boundary_rotation(n: int) -> Array:
    """A = Q0^T P0 of ``start = "boundary"``: the rotation by pi/2 in the plane of the first
    two axes (so ||A - A^T||_op = 2, the set C of claim S11) and, for n >= 4, by arccos 0.6 in
    the plane of the next two."""
    A = np.eye(n)
    A[:2, :2] = [[0.0, -1.0], [1.0, 0.0]]
    if n >= 4:
        A[2:4, 2:4] = [[0.6, -0.8], [0.8, 0.6]]
    return A
