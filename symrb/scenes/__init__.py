r"""Scenes: declared experiments that compute only what they ask for.

A *scene* declares an experiment: the system, the effects switched on (an effect not named is
not computed), the parameters, the integrator, the horizon, and the observables with the times
at which to record them.  It is written in TOML (:func:`load_scene`) or built in Python
(:func:`parse_scene`, or a model such as :class:`RigidBodyScene`), and validated by pydantic
models; an error names the key, its line in the file and the allowed values
(:class:`SceneError`, an :class:`~symrb.errors.InputError`).

>>> from symrb.scenes import load_scene, plan_scene
>>> scene = load_scene('''
... system = "rigid_body"
... [parameters]
... n = 10
... [integrator]
... method = "DOP853"
... [horizon]
... T = 100.0
... [observables]
... energy = {points = 11}
... ''')
>>> plan = plan_scene(scene)
>>> plan.propagated
('M',)

:func:`plan_scene` decides from the observables and the effects what state to propagate (no
attitude when only momenta or energies are observed, no costate sweep without a terminal cost, no
diagnostic that is not asked for), which public functions and generated kernels to call, and the
times at which to save (as diffrax's ``SaveAt``: the union of the observables' times, each
observable evaluated only at its own; a windowed observable reduced per window as
:class:`When` describes, its unreduced series not kept; the ``*_gap`` observables compared with
the second run of a ``[compare]`` table, or with each run of an array of ``[[compare]]`` tables,
one column each; a second run may run in a rotated frame, or be compared some steps later).  :meth:`Plan.explain` prints the plan with what is skipped
and why, and an estimated cost.  :func:`run_scene` runs a scene and returns a
:class:`SceneResult` (arrays, the scene, the plan, the versions), cached on disk by a SHA-256 of
the canonical scene and of the source of the symrb modules it uses, so a rerun that changes
nothing recomputes nothing.  :func:`sweep` runs a grid of scenes, in-process or on a Dask
cluster (``dask.distributed``, imported only there), and returns one pandas table plus the
results.

Where each stage lives: ``schema`` (what every system shares: :class:`SceneError`,
:class:`When`, the base model with its hooks, :func:`register_system`), ``parse``
(:func:`parse_scene`, :func:`load_scene`, the errors with their TOML lines), ``plan``
(:class:`Plan`, :func:`plan_scene`), ``run`` (:func:`scene_inputs`, :func:`run_scene`),
``result`` (:class:`SceneResult`), ``reference`` (:func:`describe_schema`: every key of every
system, as the scene reference in the book lists them), ``store`` (:func:`scene_key`, :class:`SceneStore`), ``sweeps``
(:func:`expand_grid`, :func:`sweep`), and ``systems/``, one module per system with its model and
its hooks ``_inputs``, ``_plan``, ``_run`` (a new system is a new module there).

The systems (``system = ...``) and what each offers:

=====================  ==============================  =============================================
system                 effects                         observables
=====================  ==============================  =============================================
rigid_body             attitude                        M, Q, Omega, energy, casimirs, manakov,
                                                       lax_spectrum, orthogonality, M_gap, Q_gap
symmetric_rigid_body   samples                         Q, P, M, H, energy, orthogonality,
                                                       P_orthogonality, gram_spectrum, op_norm,
                                                       U, M_gap, Q_gap
mclachlan_scovel       (none)                          Q, B, M, energy, orthogonality
double_bracket         (none)                          x, potential, pairing, casimirs
orbit_extremal         terminal_cost, potential,       x, p, u, pairing, second_term, db_distance,
                       samples, costates               db_second_term, sample_pairings
resnet                 terminal_cost, costates         loss, accuracy, test_accuracy, states, K,
                                                       beta, costates
so_network             terminal_cost, running_cost,    loss, residual, U, Q, costates,
                       costates                        extremal_residual, iterations, converged
toda                   (none)                          L, a, b, spectrum, off_band
=====================  ==============================  =============================================
"""

from __future__ import annotations

from .._package import adopt_classes

try:
    import pydantic  # noqa: F401 - the schema's models; checked first for a clear message
except ImportError as exc:  # pragma: no cover - exercised in the clean-venv wheel test
    raise ImportError(
        "symrb.scenes needs pydantic, which comes with the scenes extra: "
        "pip install 'symrb[scenes]' (or pip install pydantic)"
    ) from exc

from .parse import load_scene, parse_scene
from .plan import Plan, plan_scene
from .reference import SchemaKey, describe_model, describe_schema
from .result import SceneResult
from .run import run_scene, scene_inputs
from .schema import Scene as Scene
from .schema import SceneError, When
from .schema import register_system as register_system
from .store import SceneStore
from .store import scene_key as scene_key
from .sweeps import SweepResult, expand_grid, sweep
from .systems import (
    DoubleBracketScene,
    McLachlanScovelScene,
    OrbitExtremalScene,
    ResNetScene,
    RigidBodyMomentum,
    RigidBodyScene,
    SONetworkScene,
    SymmetricRigidBodyScene,
    TodaScene,
)

__all__ = [
    "SceneError",
    "When",
    "RigidBodyScene",
    "SymmetricRigidBodyScene",
    "McLachlanScovelScene",
    "DoubleBracketScene",
    "OrbitExtremalScene",
    "ResNetScene",
    "TodaScene",
    "parse_scene",
    "load_scene",
    "scene_inputs",
    "RigidBodyMomentum",
    "Plan",
    "plan_scene",
    "SceneResult",
    "SceneStore",
    "run_scene",
    "expand_grid",
    "SweepResult",
    "sweep",
    "SONetworkScene",
    "describe_schema",
    "describe_model",
    "SchemaKey",
]

adopt_classes(globals(), __all__, __name__)
