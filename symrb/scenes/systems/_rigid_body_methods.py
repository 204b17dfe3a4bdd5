"""The ``[integrator]`` table of a rigid-body scene: the keyword arguments of
:func:`symrb.rigid_body.simulate`, one model per method family, told apart by ``method``.

``method`` is a key of :data:`symrb.rigid_body.METHODS` (default ``"DOP853"``, as in
``simulate``), and the other keys are the keywords that ``simulate`` and that method take, with
their names, defaults and meanings: ``h``, ``order``, ``rtol``, ``atol`` and the method's
options (``condition``, ``backend``, ``kind``, ``step``, ``check``).  The output times
(``t_eval`` or ``save_every``) come from the observables, and ``t_span`` is ``(0, T)``; so
``h`` belongs to the fixed-step methods only (for the ``solve_ivp`` methods and ``"exact"`` it
would only set the output grid, which the observables set), and ``progress`` (a display, not
a choice of the numerics) is not a key.  Three more values of ``method`` run the paper's own
algorithms of :mod:`symrb.paper` (they are not methods of ``simulate``): ``"discrete"``,
``"mv_algorithm1"`` and ``"mv_algorithm2"``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Annotated, Any, Literal, get_args

from pydantic import BeforeValidator, Field

from ...rigid_body import ivp
from ..schema import _Model

#: the default method, as in ``simulate``
DEFAULT_METHOD = "DOP853"


class SolveIVP(_Model):
    """``method`` one of :func:`scipy.integrate.solve_ivp`'s (through :func:`symrb.integrate`),
    with ``rtol``, ``atol`` and ``condition``."""

    method: Literal["DOP853", "RK45", "RK23", "Radau", "BDF", "LSODA"] = "DOP853"
    rtol: float = Field(default=ivp.RTOL, gt=0)
    atol: float = Field(default=ivp.ATOL, ge=0)
    condition: bool = False


class MV(_Model):
    """``method = "mv"``: the Moser-Veselov engine (:func:`symrb.engine.mv_flow`) at step ``h``;
    ``order`` 4-10 (n = 3) the preprocessed method; ``backend`` its ``method``."""

    method: Literal["mv"]
    h: float = Field(gt=0)
    order: Literal[2, 4, 6, 8, 10] = 2
    backend: Literal["auto", "newton", "fixed-point", "numpy", "numba"] = "auto"


class Composition(_Model):
    """``method = "composition"``: a symmetric composition (``order`` 2, 4, 6, 8) of the base
    ``step`` (``"mv"`` or ``"midpoint"``) with the coefficients ``kind``
    (:func:`symrb.composition.composition_coefficients`), at step ``h``."""

    method: Literal["composition"]
    h: float = Field(gt=0)
    order: Literal[2, 4, 6, 8] = 4
    kind: Literal["triple_jump", "suzuki", "yoshida", "kahan_li", "mclachlan"] | None = None
    step: Literal["mv", "midpoint"] = "mv"


class RKMK4(_Model):
    """``method = "rkmk4"``: the Runge-Kutta-Munthe-Kaas method of order 4 at step ``h``."""

    method: Literal["rkmk4"]
    h: float = Field(gt=0)
    order: Literal[4] = 4


class Midpoint(_Model):
    """``method = "midpoint"``: the implicit midpoint rule (order 2) at step ``h``."""

    method: Literal["midpoint"]
    h: float = Field(gt=0)
    order: Literal[2] = 2


class Exact(_Model):
    """``method = "exact"``: the exact solution by Jacobi elliptic functions (n = 3); ``check``
    as in :func:`symrb.exact.rigid_body_exact`."""

    method: Literal["exact"]
    check: bool = True


class Splitting(_Model):
    """``method = "splitting"``: the explicit splitting into planar rotations
    (:func:`symrb.splitting.splitting_flow`), ``order`` 2, 4, 6, 8, at step ``h``; ``backend``
    its ``method``."""

    method: Literal["splitting"]
    h: float = Field(gt=0)
    order: Literal[2, 4, 6, 8] = 4
    backend: Literal["auto", "numpy", "numba"] = "auto"


class Discrete(_Model):
    """``method = "discrete"``, the paper's: the symmetric representation of Section 2
    (``symrb.paper.discrete_rigid_body_flow`` or ``symrb.paper.symmetric_flow``) at step
    ``h``.  ``loop = "reference"`` runs the step-by-step loop of :mod:`symrb.paper`
    (``diagnostics=True``) instead of the engine (``"engine"``, the default; the same map)."""

    method: Literal["discrete"]
    h: float = Field(gt=0)
    loop: Literal["engine", "reference"] = "engine"


class MVAlgorithm2(_Model):
    r"""``method = "mv_algorithm2"``, the paper's MV-Algorithm 2 (``symrb.paper.mv_algorithm2``)
    at step ``h``; its discrete momenta divided by ``h`` are recorded as ``M``.

    ``start = "Q0_M0"`` (the default) starts it from :math:`(Q_0, hM_0)`, read as the pair
    :math:`(Q_0, M_0)`, and records :math:`M_k/h` at :math:`t_k`.  ``start = "Q1_M1"`` follows the
    paper's indices, :math:`M_{k+1} \approx hM(t_k)` (the momentum of the step that leaves
    :math:`Q_k`): the first step is the symmetric algorithm's,
    ``symrb.discrete_rigid_body_flow(Q0, M0, lam, h, 1)``, which gives :math:`Q_1` and
    :math:`M_1 = h(Q_0^TP_0 - P_0^TQ_0)` (claim D12), and MV-Algorithm 2 runs from
    :math:`(Q_1, M_1)`; it records :math:`Q_k` and :math:`M_{k+1}/h` at :math:`t_k`.  Against
    the symmetric algorithm, ``"Q0_M0"`` is one index off.  ``loop = "reference"`` runs the step-by-step loop of :mod:`symrb.paper`
    (``diagnostics=True``) instead of the engine (``"engine"``, the default; the same map)."""

    method: Literal["mv_algorithm2"]
    h: float = Field(gt=0)
    start: Literal["Q0_M0", "Q1_M1"] = "Q0_M0"
    loop: Literal["engine", "reference"] = "engine"


class MVAlgorithm1(_Model):
    r"""``method = "mv_algorithm1"``, the paper's MV-Algorithm 1 (``symrb.paper.mv_algorithm1``)
    at step ``h``, on configurations only: :math:`Q_1` is the first step of the symmetric
    algorithm, ``symrb.discrete_rigid_body_flow(Q0, M0, lam, h, 1)`` (the step with
    :math:`M_1 = h(Q_0^TP_0 - P_0^TQ_0)`, claim D12), then
    :math:`(Q_k, Q_{k+1}) \mapsto (Q_{k+1}, Q_{k+2})`.  It records :math:`Q_k` at :math:`t_k`
    (observables ``Q``, ``orthogonality``, ``Q_gap``; the effect ``attitude``).  ``loop = "reference"`` runs the step-by-step loop of :mod:`symrb.paper`
    (``diagnostics=True``) instead of the engine (``"engine"``, the default; the same map)."""

    method: Literal["mv_algorithm1"]
    h: float = Field(gt=0)
    loop: Literal["engine", "reference"] = "engine"


#: the methods of ``simulate`` a scene runs through it (the others are the paper's algorithms)
SIMULATED = (SolveIVP, MV, Composition, RKMK4, Midpoint, Exact, Splitting)
#: the paper's algorithms (symrb.paper), run as they are
PAPER = (Discrete, MVAlgorithm1, MVAlgorithm2)
#: every value of ``method``: simulate's methods, then the paper's algorithms
METHOD_NAMES = tuple(
    str(name)
    for model in SIMULATED + PAPER
    for name in get_args(model.model_fields["method"].annotation)
)


def _default_method(value: Any) -> Any:
    """A table without ``method`` is simulate's default method (``"DOP853"``)."""
    if isinstance(value, Mapping) and "method" not in value:
        return {**value, "method": DEFAULT_METHOD}
    return value


#: the integrator of a rigid-body scene (and of a rigid-body [compare] run)
RigidBodyIntegrator = Annotated[
    SolveIVP
    | MV
    | Composition
    | RKMK4
    | Midpoint
    | Exact
    | Splitting
    | Discrete
    | MVAlgorithm2
    | MVAlgorithm1,
    Field(discriminator="method"),
    BeforeValidator(_default_method),
]


def simulate_keywords(integ: Any) -> dict[str, Any]:
    """The keyword arguments of ``simulate`` an integrator table stands for (all of its keys)."""
    return dict(integ.model_dump())


def step(integ: Any) -> float | None:
    """The step ``h`` of a fixed-step integrator (None for an adaptive or the exact one)."""
    h = getattr(integ, "h", None)
    return None if h is None else float(h)
