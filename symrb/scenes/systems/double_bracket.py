"""The double bracket flow x' = [x, [x, N]] of Section 3.5 as a scene (``system =
"double_bracket"``), by ``symrb.double_bracket_flow``; the parameters and the initial data of
an adjoint orbit, shared with the orbit extremals (:mod:`.orbit_extremal`)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, ClassVar, Literal

import numpy as np
from pydantic import Field, ValidationInfo, field_validator

from ... import _validate as v
from ... import orbits
from ..._validate import Array
from ...algebra import pairing, random_so
from ...errors import InputError
from ...rigid_body import casimir_traces
from ..plan import Plan, SystemPlan, _continuous_save, _est_continuous, diagnostic_kernels
from ..schema import (
    Matrix,
    TimeHorizon,
    Vector,
    When,
    _Model,
    _SceneBase,
    _skew_from,
    register_system,
)


class OrbitParameters(_Model):
    """An adjoint orbit of so(n): ``x0`` (3-vector or matrix; with samples, a list of them) and
    the fixed element ``N``; default random from ``seed`` (``symrb.random_so`` with entries of
    standard deviation ``scale``, N drawn first)."""

    n: int = Field(default=3, ge=2)
    seed: int = Field(default=0, ge=0)
    x0: Vector | Matrix | tuple[Matrix, ...] | None = None
    N: Vector | Matrix | None = None
    samples: int = Field(default=1, ge=1)
    scale: float = Field(default=1.0, gt=0)

    @field_validator("scale")
    @classmethod
    def _scale_draws(cls, value: float, info: ValidationInfo) -> float:
        if info.data.get("x0") is not None and info.data.get("N") is not None:
            raise InputError("x0 and N are given: scale draws nothing; remove scale")
        return value


class DoubleBracketIVP(_Model):
    """``symrb.double_bracket_flow`` (DOP853) with ``rtol``, ``atol``."""

    kind: Literal["continuous"]
    rtol: float = Field(default=1e-11, gt=0)
    atol: float = Field(default=1e-12, ge=0)


def orbit_inputs(p: OrbitParameters) -> dict[str, Any]:
    """``x0`` and ``N`` of an orbit's parameters (drawn from ``seed``, N first, when not given)."""
    rng = np.random.default_rng(p.seed)
    n = p.n
    N = (_skew_from(p.N, n, "parameters.N") if p.N is not None
         else random_so(n, scale=p.scale, seed=rng))  # fmt: skip
    m = p.samples
    if p.x0 is None:
        x0 = random_so(n, (m,) if m > 1 else (), scale=p.scale, seed=rng)
    else:
        x0 = np.asarray(p.x0, dtype=float)
        x0 = _skew_from(x0, n, "parameters.x0") if x0.ndim < 3 else v.skew(x0, "x0", n)
    return {"x0": x0, "N": N}


@register_system
class DoubleBracketScene(_SceneBase):
    """The double bracket flow x' = [x, [x, N]] of Section 3.5.

    Examples
    --------
    >>> from symrb.scenes import DoubleBracketScene
    >>> DoubleBracketScene.EFFECTS, sorted(DoubleBracketScene.OBSERVABLES)
    ((), ['casimirs', 'pairing', 'potential', 'x'])
    """

    SINGLE_SAMPLE: ClassVar[bool] = True
    STATE_OBSERVABLES = ("x",)
    OBSERVABLES = {"x": None, "potential": None, "pairing": None, "casimirs": None}
    INVARIANTS = {"casimirs": (r"$\mathrm{tr}\,x^2$", r"$\mathrm{tr}\,x^4$", r"$\mathrm{tr}\,x^6$")}
    system: Literal["double_bracket"]
    parameters: OrbitParameters = OrbitParameters()
    integrator: DoubleBracketIVP
    horizon: TimeHorizon
    observables: dict[Literal["x", "potential", "pairing", "casimirs"], When]

    def _inputs(self) -> dict[str, Any]:
        """``x0`` and ``N``."""
        return orbit_inputs(self.parameters)

    def _plan(self, skipped: list[tuple[str, str]], notes: list[str]) -> SystemPlan:
        integ = self.integrator
        t_eval, index = _continuous_save(self)
        return SystemPlan(
            route=f"symrb.double_bracket_flow(rtol={integ.rtol:g}, atol={integ.atol:g})",
            propagated=("x",),
            kernels=("adjoint_orbits.double_bracket_rhs",) + diagnostic_kernels(self.observables),
            save={"t_eval": [float(t) for t in t_eval]},
            index=index,
            cost=_est_continuous(self.horizon.T, integ.rtol, 1.0, 8.0 * self.parameters.n**3),
            modules=(
                "orbits",
                "algebra",
                "_validate",
                "_generated.adjoint_orbits",
                "_generated.rigid_body",
                "scenes.systems.double_bracket",
            ),  # fmt: skip
        )

    def _run(self, plan: Plan, x: dict[str, Any]) -> tuple[dict[str, Array], dict[str, Array], str]:
        t_eval = np.asarray(plan.save["t_eval"])
        x0, N = x["x0"], x["N"]
        integ = self.integrator
        xs = orbits.double_bracket_flow(x0, N, t_eval, rtol=integ.rtol, atol=integ.atol)
        fns: dict[str, Callable[[Array], Array]] = {
            "x": lambda a: a, "potential": lambda a: orbits.brockett_potential(a, N),
            "pairing": lambda a: pairing(a, N), "casimirs": casimir_traces,
        }  # fmt: skip
        times = {k: t_eval[list(i)] for k, i in plan.index.items()}
        data = {name: fns[name](xs[list(idx)]) for name, idx in plan.index.items()}
        return times, data, ""
