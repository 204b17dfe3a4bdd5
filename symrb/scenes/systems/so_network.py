r"""The SO(n) network of the paper's learning theorem (claim D9) as a scene: ``system =
"so_network"``.

Samples :math:`Q^a_0 \in SO(n)` pass through layers :math:`Q^a_{k+1} = Q^a_kU_k` with shared
controls :math:`U_k \in SO(n)`; the loss is the data term :math:`\sum_a\frac12\|Q^a_N -
T^a\|_F^2` (effect ``terminal_cost``) plus, with the effect ``running_cost``, the penalty
:math:`\alpha\sum_k\operatorname{tr}(\Lambda(I - U_k))` (see :func:`symrb.so_network_gradients`).
The task is :func:`symrb.learning.so_rotation_task`; training starts from :math:`U_k = I` and runs one of
the three trainers of :mod:`symrb.learning`.
"""

from __future__ import annotations

import dataclasses
from typing import Annotated, Any, ClassVar, Literal

import numpy as np
from pydantic import Field, field_validator, model_validator
from pydantic_core.core_schema import ValidationInfo

from ... import learning
from ..._validate import Array
from ...errors import InputError
from ..plan import Plan, SystemPlan, _fmt_seconds
from ..schema import TrainingHorizon, Vector, When, _invalid, _Model, _SceneBase, register_system

__all__ = ["SONetworkScene"]


class SONetworkParameters(_Model):
    r"""The task and the network: ``symrb.learning.so_rotation_task(n, samples, angle, noise, seed)``
    (its defaults), ``layers`` controls :math:`U_k`, started from :math:`U_k = I`; with the
    effect ``running_cost`` its weight ``alpha`` (> 0, default 1) and the diagonal ``lam`` of
    :math:`\Lambda` (positive, n entries; default ``numpy.linspace(1, 2, n)``)."""

    n: int = Field(default=3, ge=2)
    samples: int = Field(default=32, ge=1)
    angle: float = 0.6
    noise: float = Field(default=0.05, ge=0)
    seed: int = Field(default=0, ge=0)
    layers: int = Field(default=4, ge=1)
    lam: Vector | None = None
    alpha: float | None = Field(default=None, gt=0)

    @field_validator("lam")
    @classmethod
    def _lam_of_n(cls, value: Vector | None, info: ValidationInfo) -> Vector | None:
        n = info.data.get("n")
        if value is not None and n is not None and len(value) != n:
            raise InputError(f"lam must have n = {n} entries, got {len(value)}")
        if value is not None and not all(x > 0 for x in value):
            raise InputError(f"lam must be positive, got {list(value)}")
        return value


class SOGradient(_Model):
    """``symrb.train_so_gradient``: Riemannian gradient descent, step ``lr`` (the first trial
    step with ``line_search``, Armijo backtracking), heavy-ball ``momentum`` in [0, 1), the
    ``retraction`` (``"cayley"`` or ``"exp"``); stops when max_k ||G_k||_F <= ``tol``."""

    kind: Literal["gradient"]
    lr: float = Field(default=0.1, gt=0)
    line_search: bool = False
    momentum: float = Field(default=0.0, ge=0, lt=1)
    retraction: Literal["cayley", "exp"] = "cayley"
    tol: float = Field(default=1e-10, gt=0)


class SOMSA(_Model):
    """``symrb.train_so_msa``: the extended method of successive approximations, penalty
    ``rho`` >= 0 (0: the basic MSA), each layer's step a Procrustes problem; stops when
    max_k ||G_k||_F <= ``tol``."""

    kind: Literal["msa"]
    rho: float = Field(default=2.0, ge=0)
    tol: float = Field(default=1e-10, gt=0)


class SOShooting(_Model):
    """``symrb.train_so_shooting``: the extremal equations solved for M_0 by Powell's hybrid
    method to the relative tolerance ``tol``; the horizon's ``steps`` is its budget of
    evaluations (``maxfev``)."""

    kind: Literal["shooting"]
    tol: float = Field(default=1e-12, gt=0)

    @model_validator(mode="before")
    @classmethod
    def _maxfev_is_the_horizon(cls, data: Any) -> Any:
        if isinstance(data, dict) and "maxfev" in data:
            raise _invalid(
                ("maxfev",), "the budget of evaluations is the horizon: set horizon.steps = "
                f"{data['maxfev']!r} instead", ["kind", "tol"],
            )  # fmt: skip
        return data


#: observables recorded once, for the final controls
_END_ONLY = ("U", "Q", "costates", "extremal_residual", "iterations", "converged")
#: the four generated kernels of a forward and a backward sweep (claim D9)
_SWEEP_KERNELS = (
    "discrete_rigid_body.so_network_layer",
    "discrete_rigid_body.so_network_endpoint",
    "discrete_rigid_body.so_network_gradient",
    "discrete_rigid_body.so_network_costate",
)


@register_system
class SONetworkScene(_SceneBase):
    r"""The SO(n) network of the learning theorem (claim D9) trained on
    :func:`symrb.learning.so_rotation_task` from :math:`U_k = I`.

    Effects: ``terminal_cost`` (required: the data term, the loss the trainers descend),
    ``running_cost`` (the control penalty :math:`\alpha\sum_k\operatorname{tr}(\Lambda(I -
    U_k))`; without it :math:`\alpha = 0` and only the product of the controls is determined;
    shooting needs it, as it inverts :math:`J_D` with the inertia :math:`\alpha\Lambda`) and
    ``costates`` (record the final costates).

    Integrators (``integrator.kind``): ``"gradient"`` (:func:`symrb.train_so_gradient`),
    ``"msa"`` (:func:`symrb.train_so_msa`) and ``"shooting"`` (:func:`symrb.train_so_shooting`).
    The horizon's ``steps`` is the budget: the most iterations of gradient descent and the MSA
    (both stop earlier once :math:`\max_k\|G_k\|_F \le` ``tol``), and the most evaluations of
    the shooting function (its ``maxfev``).

    Observables, each recorded only when asked for:

    - ``loss``, ``residual`` (:math:`\max_k\|G_k\|_F`): per iteration (shooting: per
      evaluation), ``{every = k}`` (the iterations 0, k, 2k, ... that were done; windows
      allowed) or ``"end"`` (the final iterate).  The trainers evaluate both at every iteration
      anyway (the stopping test).
    - ``U`` (the final controls, shape (N, n, n)), ``Q`` (their layers
      :func:`symrb.learning.so_network_forward`, (N + 1, M, n, n)), ``costates``
      (:func:`symrb.learning.so_network_costates`, (N + 1, M, n, n); effect ``costates``),
      ``extremal_residual`` (:func:`symrb.learning.so_extremal_residual`: :math:`r_k`, (N,)),
      ``iterations`` (the iterations done; shooting: the evaluations) and ``converged`` (1 if the
      trainer's stopping test was met, else 0): at the end only.

    A run that spends its budget without converging is not a failure: it is stored, and
    ``converged`` says so.

    Examples
    --------
    >>> from symrb.scenes import SONetworkScene, load_scene, run_scene
    >>> SONetworkScene.EFFECTS
    ('terminal_cost', 'running_cost', 'costates')
    >>> scene = load_scene('''
    ... system = "so_network"
    ... effects = ["terminal_cost", "running_cost"]
    ... [parameters]
    ... n = 3
    ... samples = 8
    ... [integrator]
    ... kind = "msa"
    ... [horizon]
    ... steps = 500
    ... [observables]
    ... loss = "end"
    ... converged = "end"
    ... ''')
    >>> r = run_scene(scene, cache=False)
    >>> int(r["converged"][0]), bool(r.times["loss"][0] < 500)
    (1, True)
    """

    EFFECTS = ("terminal_cost", "running_cost", "costates")
    REQUIRED = ("terminal_cost",)
    RECORD_AXIS = "iteration"
    OBSERVABLES = {
        "loss": "terminal_cost", "residual": None, "U": None, "Q": None, "costates": "costates",
        "extremal_residual": None, "iterations": None, "converged": None,
    }  # fmt: skip
    # what the trainers return anyway, and Q, which has an entry of its own among the skipped
    # (extremal_residual costs sweeps of its own and is reported as not asked for)
    STATE_OBSERVABLES: ClassVar[tuple[str, ...]] = (
        "U", "loss", "residual", "iterations", "converged", "costates", "Q",
    )  # fmt: skip
    system: Literal["so_network"]
    parameters: SONetworkParameters = SONetworkParameters()
    integrator: Annotated[SOGradient | SOMSA | SOShooting, Field(discriminator="kind")]
    horizon: TrainingHorizon
    observables: dict[
        Literal[
            "loss", "residual", "U", "Q", "costates", "extremal_residual", "iterations",
            "converged",
        ],
        When,
    ]  # fmt: skip

    @model_validator(mode="after")
    def _consistent(self) -> SONetworkScene:
        running = "running_cost" in self.effects
        for key in ("alpha", "lam"):
            if not running and key in self.parameters.model_fields_set:
                raise _invalid(
                    ("parameters", key), f"{key} belongs to the running cost alpha tr(Lambda "
                    "(I - U_k)), which is off: add 'running_cost' to the effects",
                    [k for k in SONetworkParameters.model_fields if k not in ("alpha", "lam")],
                )  # fmt: skip
        if isinstance(self.integrator, SOShooting):
            if not running:
                raise _invalid(
                    ("integrator", "kind"), "shooting solves alpha J_D(U_k) = M_k for the "
                    "controls: it needs the effect 'running_cost' (alpha > 0)",
                    ["gradient", "msa"],
                )  # fmt: skip
            if self.horizon.steps < 1:
                raise _invalid(
                    ("horizon", "steps"), "shooting needs a budget of at least one evaluation"
                )  # fmt: skip
        for name, when in self.observables.items():
            if name in _END_ONLY and not when.end:
                raise _invalid(
                    ("observables", name), f"only the final controls are kept: record {name} "
                    "at the end", ["end"],
                )  # fmt: skip
            if name not in _END_ONLY and not (when.end or when.every is not None):
                raise _invalid(
                    ("observables", name), f"{name} is recorded per iteration: give every (or "
                    "end), not times or points", ["end", "every"],
                )  # fmt: skip
        return self

    @property
    def alpha(self) -> float:
        """The weight of the running cost (0 without the effect ``running_cost``)."""
        if "running_cost" not in self.effects:
            return 0.0
        return 1.0 if self.parameters.alpha is None else self.parameters.alpha

    def _inputs(self) -> dict[str, Any]:
        """``Q0``, ``targets`` (the task), ``lam``, ``alpha`` and the start ``U0`` (identities)."""
        p = self.parameters
        Q0, targets = learning.so_rotation_task(p.n, samples=p.samples, angle=p.angle, noise=p.noise,
                                       seed=p.seed)  # fmt: skip
        lam = np.asarray(p.lam, dtype=float) if p.lam is not None else np.linspace(1.0, 2.0, p.n)
        return {"Q0": Q0, "targets": targets, "lam": lam, "alpha": self.alpha,
                "U0": np.tile(np.eye(p.n), (p.layers, 1, 1))}  # fmt: skip

    def _plan(self, skipped: list[tuple[str, str]], notes: list[str]) -> SystemPlan:
        steps = self.horizon.steps
        asked = set(self.observables)
        t = _trainer(self, notes)
        kernels, modules = t.kernels, t.modules
        if "extremal_residual" in asked:
            kernels += ("symmetric_rigid_body.symmetric_momentum", "discrete_rigid_body.jd")
            modules += ("_generated.symmetric_rigid_body",)
        _notes_and_skips(self, skipped, notes, t.what)
        budget = max(steps, 1)
        index: dict[str, tuple[int, ...]] = {}
        for name, when in self.observables.items():
            every = when.every
            index[name] = tuple(range(0, steps + 1, every)) if every is not None else (steps,)
        cost = {
            "flops": budget * t.flops,
            "seconds": budget * (t.seconds + t.flops / 1.5e9),
            "formula": f"at most {budget} {t.what}s x (~{t.flops:.2g} flops + "
            f"~{_fmt_seconds(t.seconds)} of kernel calls); it stops at tol, usually much "
            "earlier",
        }
        return SystemPlan(
            route=f"{t.route}: each {t.what} is {t.per}",
            propagated=t.propagated,
            kernels=tuple(dict.fromkeys(kernels)),
            save={"steps": steps},
            index=index,
            cost=cost,
            modules=tuple(dict.fromkeys(modules)),
        )

    def _run(self, plan: Plan, x: dict[str, Any]) -> tuple[dict[str, Array], dict[str, Array], str]:
        integ, steps = self.integrator, self.horizon.steps
        Q0, T, lam, alpha = x["Q0"], x["targets"], x["lam"], x["alpha"]
        if isinstance(integ, SOGradient):
            res = learning.train_so_gradient(
                Q0, T, x["U0"], lam, alpha=alpha, steps=steps, lr=integ.lr,
                retraction=integ.retraction, line_search=integ.line_search,
                momentum=integ.momentum, tol=integ.tol,
            )  # fmt: skip
        elif isinstance(integ, SOMSA):
            res = learning.train_so_msa(Q0, T, x["U0"], lam, alpha=alpha, steps=steps,
                                        rho=integ.rho, tol=integ.tol)  # fmt: skip
        else:
            res = learning.train_so_shooting(Q0, T, lam, alpha, self.parameters.layers,
                                             tol=integ.tol, maxfev=steps)  # fmt: skip
        last = res.iterations
        sweeps: dict[str, Array] = {}

        def layers_and_costates() -> tuple[Array, Array]:
            if not sweeps:
                sweeps["Q"], sweeps["P"] = learning.so_network_costates(Q0, res.U, T)
            return sweeps["Q"], sweeps["P"]

        times: dict[str, Array] = {}
        data: dict[str, Array] = {}
        for name, when in self.observables.items():
            its = np.arange(0, last + 1, when.every) if when.every is not None else np.array([last])
            times[name] = its.astype(float)
            if name == "loss":
                data[name] = res.losses[its]
            elif name == "residual":
                data[name] = res.residuals[its]
            elif name == "U":
                data[name] = res.U[None]
            elif name == "Q":
                Q = layers_and_costates()[0] if "costates" in self.observables else (
                    learning.so_network_forward(Q0, res.U))  # fmt: skip
                data[name] = Q[None]
            elif name == "costates":
                data[name] = layers_and_costates()[1][None]
            elif name == "extremal_residual":
                data[name] = learning.so_extremal_residual(Q0, res.U, lam, T, alpha)[None]
            elif name == "iterations":
                data[name] = np.array([res.iterations])
            else:
                data[name] = np.array([int(res.converged)])
        return times, data, ""


@dataclasses.dataclass(frozen=True)
class _Trainer:
    """A trainer's part of the plan: its call, one iteration (or evaluation) in words, and the
    estimated flops and seconds of one."""

    route: str
    per: str
    what: str
    flops: float
    seconds: float
    propagated: tuple[str, ...]
    kernels: tuple[str, ...]
    modules: tuple[str, ...]


def _trainer(sc: SONetworkScene, notes: list[str]) -> _Trainer:
    """The plan of the scene's trainer (gradient descent, the MSA or shooting)."""
    p, integ, steps = sc.parameters, sc.integrator, sc.horizon.steps
    n, N, M = p.n, p.layers, p.samples
    layer = 2.0 * M * n**3  # one layer, costate step or sample sum on the stacked samples
    call = 5e-6  # the overhead of a kernel call
    sweep = f"a forward sweep over the {N} layers and a backward costate sweep"
    flops = 3 * N * layer
    seconds = 3 * N * call
    kernels: tuple[str, ...] = _SWEEP_KERNELS
    modules: tuple[str, ...] = (
        "scenes.systems.so_network", "learning", "algebra", "_validate", "_progress",
        "_generated.discrete_rigid_body",
    )  # fmt: skip
    propagated: tuple[str, ...] = (
        f"layers Q^a_k ({M} samples x {N + 1} layers, stacked by rows)",
        "costates P^a_k (backward sweep)", f"controls U_k ({N} in SO({n}))",
    )  # fmt: skip
    if isinstance(integ, SOGradient):
        route = (f"symrb.train_so_gradient(steps={steps}, lr={integ.lr:g}, "
                 f"line_search={integ.line_search}, momentum={integ.momentum:g}, "
                 f"retraction={integ.retraction!r}, tol={integ.tol:g}) "
                 "from U_k = I")  # fmt: skip
        per = f"{sweep} (the gradients G_k), then U_k {integ.retraction}(-t G_k)"
        flops += N * 10.0 * n**3
        seconds += N * 2 * call
        if integ.line_search:
            per += " with Armijo backtracking (a forward sweep per trial step, ~1.5)"
            flops += 1.5 * N * layer
            seconds += 1.5 * N * call
        what = "iteration"
    elif isinstance(integ, SOMSA):
        route = (f"symrb.train_so_msa(steps={steps}, rho={integ.rho:g}, tol={integ.tol:g}) "
                 "from U_k = I")  # fmt: skip
        per = (f"{sweep} keeping all {N + 1} costates, then per layer the Procrustes "
               "problem max tr(A_k U) over SO(n): one SVD (so_procrustes)")  # fmt: skip
        flops += N * ((3 if integ.rho else 1) * layer + 30.0 * n**3)
        seconds += N * 1e-4
        what = "iteration"
    else:
        d = n * (n - 1) // 2
        route = (f"symrb.train_so_shooting(layers={N}, tol={integ.tol:g}, maxfev={steps}) "
                 f"from M_0 = 0 (U_k = I)")  # fmt: skip
        per = (f"{N} Moser-Veselov solves alpha J_D(U_k) = M_k, M_(k+1) = U_k^T M_k U_k, "
               f"then {sweep} and the momentum of the costates at k = 0")  # fmt: skip
        propagated = (f"momentum M_0 (n(n-1)/2 = {d} unknowns)", *propagated)
        kernels = kernels + ("discrete_rigid_body.jd", "symmetric_rigid_body.symmetric_momentum")
        modules += ("solvers", "errors", "_generated.symmetric_rigid_body")
        flops += N * 60.0 * n**3
        seconds += N * 8e-4
        what = "evaluation"
        notes.append(f"shooting's records count evaluations of F(M_0) on the {d} unknowns "
                     "(hybr's finite-difference Jacobian included), not iterations; "
                     f"horizon.steps = {steps} is its maxfev")  # fmt: skip
    return _Trainer(route, per, what, flops, seconds, propagated, kernels, modules)


def _notes_and_skips(
    sc: SONetworkScene, skipped: list[tuple[str, str]], notes: list[str], what: str
) -> None:
    """What the plan says about the stopping test, the sweeps at the end and what is skipped."""
    integ, steps, asked = sc.integrator, sc.horizon.steps, set(sc.observables)
    if not isinstance(integ, SOShooting):
        notes.append(f"stops once max_k ||G_k||_F <= tol = {integ.tol:g}: the records are "
                     f"those of the iterations done, at most {steps} + 1")  # fmt: skip
    notes.append(f"the trainer evaluates the loss and max_k ||G_k||_F at every {what} (its "
                 "stopping test); only the records asked for are kept")  # fmt: skip
    extra = []
    if "extremal_residual" in asked:
        extra.append("extremal_residual: a forward and a costate sweep and N momenta")
    if "costates" in asked:
        extra.append("costates (and Q): a forward and a costate sweep")
    elif "Q" in asked:
        extra.append("Q: a forward sweep")
    if extra:
        notes.append("at the final controls, " + "; ".join(extra))
    if not {"Q", "costates"} & asked:
        skipped.append(("Q (the final layers)", "not asked for: no forward sweep at the end"))
    if "running_cost" not in sc.effects:
        skipped.append(("running cost alpha tr(Lambda (I - U_k))", "effect 'running_cost' "
                        "not named: alpha = 0, the loss is the data term alone and fixes "
                        "only the product U_0 ... U_(N-1)"))  # fmt: skip
    if "costates" not in asked:
        keep = ("at most two alive" if isinstance(integ, SOGradient)
                else "all N + 1 inside, for the step")  # fmt: skip
        why = ("effect 'costates' not named" if "costates" not in sc.effects
               else "not asked for")  # fmt: skip
        skipped.append(("recording the costates P^a_k", f"{why}: the trainer's sweeps run "
                        f"(they give G_k; {keep}), no costate leaves it"))  # fmt: skip
