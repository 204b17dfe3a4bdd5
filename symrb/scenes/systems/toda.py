r"""The Toda lattice as a scene (``system = "toda"``): claim S14's double bracket flow
:math:`\dot L = -[L, [L, D]]` on a real symmetric tridiagonal :math:`L`, run by
:func:`symrb.toda_flow`."""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from pydantic import Field, ValidationInfo, field_validator, model_validator

from ... import orbits
from ..._validate import Array
from ...errors import InputError, NotConvergedError
from ..plan import Plan, SystemPlan, _continuous_save, _est_continuous
from ..schema import TimeHorizon, When, _Model, _SceneBase, register_system

__all__ = ["TodaScene"]


class TodaParameters(_Model):
    """The Toda matrix L(0): its size ``k`` and either its diagonal ``a`` (k entries) and
    off-diagonal ``b`` (k - 1 entries), or a random draw from ``seed``:
    ``rng = numpy.random.default_rng(seed)``, ``a = rng.standard_normal(k)``, then
    ``b = rng.uniform(0.4, 1.0, k - 1)`` (off-diagonal entries away from 0, so that the lattice
    does not split into blocks)."""

    k: int = Field(default=5, ge=2)
    a: tuple[float, ...] | None = None
    b: tuple[float, ...] | None = None
    seed: int = Field(default=0, ge=0)

    @field_validator("a")
    @classmethod
    def _a_has_k(cls, value: tuple[float, ...] | None, info: ValidationInfo) -> Any:
        k = info.data.get("k")
        if value is not None and k is not None and len(value) != k:
            raise InputError(f"the diagonal needs k = {k} entries, got {len(value)}")
        return value

    @field_validator("b")
    @classmethod
    def _b_has_k_minus_1(cls, value: tuple[float, ...] | None, info: ValidationInfo) -> Any:
        k = info.data.get("k")
        if value is not None and k is not None and len(value) != k - 1:
            raise InputError(f"the off-diagonal needs k - 1 = {k - 1} entries, got {len(value)}")
        return value

    @field_validator("seed")
    @classmethod
    def _seed_draws(cls, value: int, info: ValidationInfo) -> int:
        if info.data.get("a") is not None or info.data.get("b") is not None:
            raise InputError("a and b give L(0): seed draws nothing; remove seed")
        return value

    @model_validator(mode="after")
    def _both_or_neither(self) -> TodaParameters:
        if (self.a is None) != (self.b is None):
            raise InputError("give both a and b (the diagonal and the off-diagonal of L(0)), "
                             "or neither (a random draw from seed)")  # fmt: skip
        return self


class TodaIVP(_Model):
    """``symrb.toda_flow`` (``scipy.integrate.solve_ivp``, DOP853) with ``rtol``, ``atol``."""

    kind: Literal["continuous"]
    rtol: float = Field(default=1e-11, gt=0)
    atol: float = Field(default=1e-12, ge=0)


@register_system
class TodaScene(_SceneBase):
    r"""The Toda lattice (claim S14): the double bracket flow :math:`\dot L = -[L, [L, D]]`,
    :math:`D = \operatorname{diag}(1, \dots, k)`, from a symmetric tridiagonal :math:`L(0)`
    (:func:`symrb.toda_flow`).

    Observables: ``L`` (the matrix), ``a`` (its diagonal), ``b`` (its off-diagonal
    :math:`L_{i,i+1}`), ``spectrum`` (the eigenvalues of :math:`L(t)`,
    ``numpy.linalg.eigvalsh``, largest first: kept by the flow) and ``off_band`` (the largest
    :math:`|L_{ij}|` with :math:`|i - j| \ge 2`: zero for the exact flow, which keeps :math:`L`
    tridiagonal).  :func:`~symrb.scenes.scene_inputs` gives ``a0``, ``b0`` and ``L0``.

    Examples
    --------
    >>> import numpy as np
    >>> from symrb.scenes import TodaScene, run_scene
    >>> TodaScene.EFFECTS, sorted(TodaScene.OBSERVABLES)
    ((), ['L', 'a', 'b', 'off_band', 'spectrum'])
    >>> r = run_scene({"system": "toda", "parameters": {"k": 3, "seed": 1},
    ...                "integrator": {"kind": "continuous"}, "horizon": {"T": 40.0},
    ...                "observables": {"a": "end", "spectrum": {"points": 2}}}, cache=False)
    >>> bool(np.abs(r["a"][-1] - r["spectrum"][0]).max() < 1e-6)  # sorted to the spectrum
    True
    """

    STATE_OBSERVABLES = ("L", "a", "b")
    OBSERVABLES = {"L": None, "a": None, "b": None, "spectrum": None, "off_band": None}
    INVARIANTS = {"spectrum": ()}
    system: Literal["toda"]
    parameters: TodaParameters = TodaParameters()
    integrator: TodaIVP
    horizon: TimeHorizon
    observables: dict[Literal["L", "a", "b", "spectrum", "off_band"], When]

    def _inputs(self) -> dict[str, Any]:
        """``a0``, ``b0`` (the band of L(0)) and ``L0``."""
        p = self.parameters
        if p.a is not None and p.b is not None:
            a0, b0 = np.array(p.a, dtype=float), np.array(p.b, dtype=float)
        else:
            rng = np.random.default_rng(p.seed)
            a0 = rng.standard_normal(p.k)
            b0 = rng.uniform(0.4, 1.0, p.k - 1)
        return {"a0": a0, "b0": b0, "L0": np.diag(a0) + np.diag(b0, 1) + np.diag(b0, -1)}

    def _plan(self, skipped: list[tuple[str, str]], notes: list[str]) -> SystemPlan:
        integ = self.integrator
        t_eval, index = _continuous_save(self)
        k = self.parameters.k
        return SystemPlan(
            route=f"symrb.toda_flow(rtol={integ.rtol:g}, atol={integ.atol:g}): the double "
            f"bracket flow L' = -[L, [L, D]], D = diag(1, ..., {k}), on the whole {k} x {k} "
            "matrix",
            propagated=("L",),
            kernels=("adjoint_orbits.double_bracket_rhs",),
            save={"t_eval": [float(t) for t in t_eval]},
            index=index,
            cost=_est_continuous(self.horizon.T, integ.rtol, 1.0, 8.0 * k**3),
            modules=("scenes.systems.toda", "orbits", "_validate", "_generated.adjoint_orbits"),
        )

    def _run(self, plan: Plan, x: dict[str, Any]) -> tuple[dict[str, Array], dict[str, Array], str]:
        t_eval = np.asarray(plan.save["t_eval"])
        integ = self.integrator
        failure = ""
        try:
            Ls = orbits.toda_flow(x["a0"], x["b0"], t_eval, rtol=integ.rtol, atol=integ.atol)
        except NotConvergedError as exc:
            failure, t_eval = str(exc), t_eval[:0]
            Ls = np.empty((0,) + x["L0"].shape)
        times, data = {}, {}
        for name, idx in plan.index.items():
            keep = [i for i in idx if i < t_eval.shape[0]]
            times[name] = t_eval[keep]
            data[name] = _observable(name, Ls[keep])
        return times, data, failure


def _observable(name: str, L: Array) -> Array:
    """An observable of the Toda scene from the matrices L, shape (records, k, k)."""
    if name == "L":
        return L
    if name == "a":
        return np.diagonal(L, axis1=-2, axis2=-1).copy()
    if name == "b":
        return np.diagonal(L, 1, axis1=-2, axis2=-1).copy()
    if name == "spectrum":
        return np.asarray(np.linalg.eigvalsh(L)[..., ::-1], dtype=float)
    k = L.shape[-1]
    i, j = np.indices((k, k))
    off = np.abs(i - j) >= 2
    if not off.any():  # k = 2: nothing off the band
        return np.zeros(L.shape[0])
    return np.asarray(np.abs(L[:, off]).max(axis=-1), dtype=float)
