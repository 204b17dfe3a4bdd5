"""What the three bodies share (``rigid_body``, ``symmetric_rigid_body``, ``mclachlan_scovel``):
the integrators of the symmetric body and of McLachlan-Scovel (``kind``; the rigid body's are in
:mod:`._rigid_body_methods`), their parameters, their initial data, their observables and
:class:`_BodyScene`, the base of their scene models (the states of a run, then the observables
evaluated on them)."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any, ClassVar, Literal

import numpy as np
from pydantic import Field, model_validator

from ... import _validate as v
from ..._validate import Array
from ...algebra import J_inv, pairing, random_lam, random_SO, random_so
from ...continuous import Flow, integrate
from ...errors import InputError
from ...rigid_body import casimir_traces, kinetic_energy, manakov_integrals
from ...symmetric import gl_hamiltonian, multi_sample_control, symmetric_momentum
from ..plan import Plan, SystemPlan, _continuous_save, _est_continuous
from ..schema import Matrix, SceneError, Vector, _Model, _SceneBase, _skew_from

#: the symrb modules of a body's run (their source enters the cache key)
_RB_MODULES = ("continuous", "symmetric", "rigid_body", "algebra", "_validate", "_generated.rigid_body",
               "_results", "scenes.systems._body")  # fmt: skip
#: the modules of the symmetric representation's map (``symmetric_flow``)
_SYMMETRIC_MAP_MODULES = ("paper", "engine", "_compiled", "_stepping", "solvers",
                          "_generated.discrete_rigid_body", "_generated.symmetric_rigid_body",
                          "_progress")  # fmt: skip

#: the components of ``casimirs`` (:func:`symrb.rigid_body.casimir_traces`), for plot legends
CASIMIR_LABELS = (r"$\mathrm{tr}\,M^2$", r"$\mathrm{tr}\,M^4$", r"$\mathrm{tr}\,M^6$")
#: the components of ``manakov`` (:func:`symrb.rigid_body.manakov_integrals`), for plot legends
MANAKOV_LABELS = (
    r"$\mathrm{tr}\,M^2$", r"$3\,\mathrm{tr}(\Lambda^2M^2)$", r"$\mathrm{tr}\,M^4$",
    r"$4\,\mathrm{tr}(\Lambda^4M^2)+2\,\mathrm{tr}(\Lambda^2M\Lambda^2M)$",
    r"$5\,\mathrm{tr}(\Lambda^2M^4)$",
    r"$5\,\mathrm{tr}(\Lambda^6M^2)+5\,\mathrm{tr}(\Lambda^4M\Lambda^2M)$",
)  # fmt: skip


class Continuous(_Model):
    """``symrb.integrate`` (``scipy.integrate.solve_ivp``) with ``method``, ``rtol``, ``atol``."""

    kind: Literal["continuous"]
    method: Literal["DOP853", "RK45", "RK23", "Radau", "BDF", "LSODA"] = "DOP853"
    rtol: float = Field(default=1e-10, gt=0)
    atol: float = Field(default=1e-12, ge=0)


class Discrete(_Model):
    """The symmetric representation of Section 2 (``symrb.discrete_rigid_body_flow`` or
    ``symrb.symmetric_flow``) at step ``h``."""

    kind: Literal["discrete"]
    h: float = Field(gt=0)


class BodyParameters(_Model):
    """A body: ``n``, the diagonal ``lam`` of Lambda (default: ``random_lam(n, seed=seed)``), the
    initial momentum ``M0`` (a 3-vector for n = 3 or an n x n skew matrix; default:
    ``random_so(n, seed=seed)`` scaled to the size ``momentum``, measured by the pairing norm
    :math:`\\sqrt{\\langle M, M\\rangle}`), the attitude ``Q0`` and the number of ``samples``.
    ``op_norm`` instead scales ``M0`` (given or drawn) to that operator norm
    :math:`\\|M_0\\|_{op}` (the largest singular value): ``M0 * (op_norm / ||M0||_2)``."""

    n: int = Field(default=3, ge=2)
    lam: Vector | None = None
    seed: int = Field(default=0, ge=0)
    M0: Vector | Matrix | None = None
    momentum: float = Field(default=1.0, gt=0)
    op_norm: float | None = Field(default=None, gt=0)
    Q0: Literal["identity", "random"] = "identity"
    samples: int = Field(default=1, ge=1)

    def _given(self, keys: Iterable[str]) -> list[str]:
        """The keys among ``keys`` given a value other than their default (so that a scene
        dumped with every default re-validates)."""
        fields = type(self).model_fields
        return sorted(k for k in keys if getattr(self, k) != fields[k].default)

    @model_validator(mode="after")
    def _one_size(self) -> BodyParameters:
        if self.op_norm is not None and self._given(["momentum"]):
            raise InputError("give the size of M0 once: momentum (the pairing norm) or op_norm "
                             "(the operator norm), not both")  # fmt: skip
        return self


def body_rate(p: Any) -> float:
    """The rate |Omega| of a body's parameters ``p``, for the cost estimate: the size of M0 (its
    operator norm, its largest entry times n, or ``momentum``) over the smallest ``lam`` (0.5
    when lam is drawn; a lam that is not positive is refused with the inputs)."""
    if p.op_norm is not None:
        size = float(p.op_norm)
    elif p.M0 is not None:
        size = float(np.abs(np.asarray(p.M0, dtype=float)).max(initial=0.0)) * p.n
    else:
        size = float(p.momentum)
    small = min(p.lam) if p.lam else 0.5
    return size / (small if small > 0 else 0.5)


def body_inputs(p: Any, boundary: bool = False) -> dict[str, Any]:
    """``lam``, ``Q0`` and ``M0`` from a body's parameters ``p``; on the boundary start of the
    symmetric rigid body no momentum is drawn (``M0`` is None)."""
    rng = np.random.default_rng(p.seed)
    n = p.n
    lam = np.asarray(p.lam, dtype=float) if p.lam is not None else random_lam(n, seed=rng)
    lam = v.inertia(lam, "parameters.lam", positive=True)
    if lam.shape != (n,):
        raise SceneError([{"key": "parameters.lam", "line": None, "allowed": None,
                           "message": f"must have n = {n} entries, got shape {lam.shape}"}])  # fmt: skip
    m = p.samples
    batch = (m,) if m > 1 else ()
    M0: Any = None
    if boundary:
        pass
    elif p.M0 is None:
        M0 = random_so(n, batch, seed=rng)
        if p.op_norm is None:
            M0 = M0 * (p.momentum / np.sqrt(pairing(M0, M0)))[..., None, None]
    else:
        M0 = _skew_from(p.M0, n, "parameters.M0")
        M0 = np.broadcast_to(M0, batch + (n, n)).copy()
    if p.op_norm is not None and M0 is not None:
        M0 = M0 * (p.op_norm / np.linalg.norm(M0, 2, axis=(-2, -1)))[..., None, None]
    Q0 = random_SO(n, batch, seed=rng) if p.Q0 == "random" else np.broadcast_to(
        np.eye(n), batch + (n, n)).copy()  # fmt: skip
    return {"lam": lam, "Q0": Q0, "M0": M0}


def _orth_error(Q: Array) -> Array:
    n = Q.shape[-1]
    err: Array = np.abs(np.swapaxes(Q, -1, -2) @ Q - np.eye(n)).max(axis=(-2, -1))
    return err


def _body_observable(name: str, y: Mapping[str, Array], lam: Array) -> Array:
    if name in y:
        return y[name]
    if name == "orthogonality":  # the attitude alone (MV-Algorithm 1 has no momenta)
        return _orth_error(y["Q"])
    M = y["M"] if "M" in y else (
        symmetric_momentum(y["Q"], y["P"]) if "P" in y else np.swapaxes(y["Q"], -1, -2) @ y["B"]
    )  # fmt: skip
    if name == "M":
        return M
    if name == "Omega":
        return J_inv(M, lam)
    if name == "energy":
        return kinetic_energy(M, lam)
    if name == "casimirs":
        return casimir_traces(M)
    if name == "manakov":
        return manakov_integrals(M, lam)
    if name == "lax_spectrum":
        # the Lax matrix M + mu Lambda^2 at mu = i, times i: Hermitian, with a conserved spectrum
        out: Array = np.asarray(np.linalg.eigvalsh(1j * M - np.diag(lam**2)), dtype=float)
        return out
    if name == "P_orthogonality":
        return _orth_error(y["P"])
    if name == "op_norm":  # the largest singular value, a Casimir (S11)
        norm: Array = np.linalg.norm(M, 2, axis=(-2, -1))
        return norm
    if name == "gram_spectrum":  # conserved by the symmetric field on all of gl(n)^2 (S12)
        Q = y["Q"]
        spec: Array = np.asarray(np.linalg.eigvalsh(np.swapaxes(Q, -1, -2) @ Q), dtype=float)
        return spec
    if name == "H":
        return gl_hamiltonian(y["Q"], y["P"], lam)
    if name == "U":
        return multi_sample_control(y["Q"], y["P"], lam)
    raise KeyError(name)  # pragma: no cover - the schema lists the names


def _rot(rotation: Array | None, a: Array) -> Array:
    """R a (a run in a rotated frame), or a itself."""
    return a if rotation is None else rotation @ a


def _rotate_back(states: dict[str, Array], rotation: Array | None) -> dict[str, Array]:
    """R^T X for the attitudes and costates of a run in a rotated frame; the body momentum is
    the run's own (computed from its rotated Q and P first, when it is not a state)."""
    if rotation is None:
        return states
    if "P" in states and "M" not in states:
        states["M"] = symmetric_momentum(states["Q"], states["P"])
    for name in ("Q", "P", "B"):
        if name in states:
            states[name] = rotation.T @ states[name]
    return states


def _integrate(
    sc: Any, plan: Plan, flow: type[Flow], y0: dict[str, Array], lam: Array,
    rotation: Array | None,
) -> tuple[Array, dict[str, Array], str]:  # fmt: skip
    """A continuous run (``symrb.integrate`` with the scene's method and tolerances, at the save
    times of the plan): (times, states, failure or '')."""
    integ = sc.integrator
    kw = dict(lam=lam, method=integ.method, rtol=integ.rtol, atol=integ.atol,
              t_eval=plan.save["t_eval"])  # fmt: skip
    sol = integrate(flow, (0.0, float(sc.horizon.T)), y0, **kw)
    states = {k: sol.y[k] for k in sol.flow.state}
    return sol.t, _rotate_back(states, rotation), "" if sol.success else sol.message


def body_continuous_plan(
    sc: Any, flow: str, kernels: tuple[str, ...], propagated: tuple[str, ...],
    modules: tuple[str, ...],
) -> SystemPlan:  # fmt: skip
    """The plan of ``symrb.integrate`` of a symmetric body's ``flow`` (a name)."""
    integ, p = sc.integrator, sc.parameters
    t_eval, index = _continuous_save(sc)
    return SystemPlan(
        route=f"symrb.integrate({flow}, method={integ.method!r}, rtol={integ.rtol:g})",
        propagated=propagated,
        kernels=kernels,
        save={"t_eval": [float(t) for t in t_eval]},
        index=index,
        cost=_est_continuous(
            sc.horizon.T, integ.rtol, body_rate(p), 10.0 * p.samples * p.n**3
        ),  # fmt: skip
        modules=modules + ("_generated.symmetric_rigid_body",),
    )


class _BodyScene(_SceneBase):
    """The base of the bodies' scene models: a run gives the states (the hook ``_states``), on
    which each observable is evaluated at its own records."""

    SINGLE_SAMPLE: ClassVar[bool] = True

    def _states(
        self, plan: Plan, x: dict[str, Any], rotation: Array | None
    ) -> tuple[Array, dict[str, Array], str]:
        """(times of the saved states, the saved states by name, a failure message or ''); with
        a ``rotation`` R, the run starts from its initial state rotated by R and its attitudes
        (and costates) are rotated back (see :class:`~symrb.scenes.systems._compare.Compare`)."""
        raise NotImplementedError

    def _observed(
        self, plan: Plan, x: dict[str, Any], rotation: Array | None = None
    ) -> tuple[dict[str, Array], dict[str, Array], str]:
        """Run and evaluate the observables: (times, data per observable, failure or '')."""
        t, states, failure = self._states(plan, x, rotation)
        times, data = {}, {}
        for name, idx in plan.index.items():
            keep = [i for i in idx if i < t.shape[0]]  # a failed run stops early
            # all records: the integrator's arrays as they are (a copy can change the memory
            # layout, and with it the last bit of a reduction such as einsum)
            whole = keep == list(range(t.shape[0]))
            y = states if whole else {k: a[keep] for k, a in states.items()}
            times[name] = t[keep]
            data[name] = np.asarray(_body_observable(name.removesuffix("_gap"), y, x["lam"]))
        del states
        return times, data, failure

    def _run(self, plan: Plan, x: dict[str, Any]) -> tuple[dict[str, Array], dict[str, Array], str]:
        return self._observed(plan, x)
