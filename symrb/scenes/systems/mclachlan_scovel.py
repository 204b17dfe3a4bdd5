"""The McLachlan-Scovel equations (Q, B) of Section 3.2 as a scene (``system =
"mclachlan_scovel"``), from B0 = Q0 M0, by ``symrb.integrate``."""

from __future__ import annotations

import dataclasses
from typing import Any, Literal

from ..._validate import Array
from ...symmetric import McLachlanScovel
from ..plan import Plan, SystemPlan, diagnostic_kernels
from ..schema import TimeHorizon, When, register_system
from ._body import (
    _RB_MODULES,
    BodyParameters,
    Continuous,
    _BodyScene,
    _integrate,
    _rot,
    body_continuous_plan,
    body_inputs,
)

_MODULES = _RB_MODULES + ("scenes.systems.mclachlan_scovel",)


@register_system
class McLachlanScovelScene(_BodyScene):
    """The McLachlan-Scovel equations (Q, B) of Section 3.2, from B0 = Q0 M0.

    Examples
    --------
    >>> from symrb.scenes import McLachlanScovelScene
    >>> McLachlanScovelScene.EFFECTS, sorted(McLachlanScovelScene.OBSERVABLES)
    ((), ['B', 'M', 'Q', 'energy', 'orthogonality'])
    """

    OBSERVABLES = {"Q": None, "B": None, "M": None, "energy": None, "orthogonality": None}
    INVARIANTS = {"energy": ("energy",)}
    STATE_OBSERVABLES = ("Q", "B", "M")
    system: Literal["mclachlan_scovel"]
    parameters: BodyParameters = BodyParameters()
    integrator: Continuous
    horizon: TimeHorizon
    observables: dict[Literal["Q", "B", "M", "energy", "orthogonality"], When]

    def _inputs(self) -> dict[str, Any]:
        """``lam``, ``Q0``, ``M0`` and ``B0 = Q0 M0``."""
        out = body_inputs(self.parameters)
        out["B0"] = out["Q0"] @ out["M0"]
        return out

    def _plan(self, skipped: list[tuple[str, str]], notes: list[str]) -> SystemPlan:
        part = body_continuous_plan(self, "McLachlanScovel",
                                    ("symmetric_rigid_body.mclachlan_scovel_rhs",), ("Q", "B"),
                                    _MODULES)  # fmt: skip
        return dataclasses.replace(
            part, kernels=part.kernels + diagnostic_kernels(self.observables)
        )

    def _states(
        self, plan: Plan, x: dict[str, Any], rotation: Array | None
    ) -> tuple[Array, dict[str, Array], str]:
        y0 = {"Q": _rot(rotation, x["Q0"]), "B": _rot(rotation, x["B0"])}
        return _integrate(self, plan, McLachlanScovel, y0, x["lam"], rotation)
