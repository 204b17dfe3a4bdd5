"""symrb: numerics for Bloch, Crouch and Ratiu, "Symmetric Discrete Optimal Control and Deep Learning".

The package imports only NumPy and SciPy.  Its kernels in :mod:`symrb._generated` are emitted by
the ``derivations`` of the source tree (SymPy, development time only) and wrapped here by
functions that validate input.  Each submodule lists its public names in ``__all__``; they are
available here too, loaded on first use (so ``import symrb`` is cheap and the ``symrb`` command
works even while the generated kernels are being rewritten).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

#: Public names of each submodule (a test checks this table against the modules' ``__all__``).
_EXPORTS: dict[str, tuple[str, ...]] = {
    "algebra": (
        "hat", "vee", "pairing", "commutator", "skew_part", "J", "J_inv", "J_D",
        "inertia_from_lam", "lam_from_inertia", "random_so", "random_SO", "random_lam",
        "as_generator",
    ),
    "base_steps": ("MVStep", "MidpointStep", "RKMK4Step"),
    "composition": ("composition_coefficients", "compose_steps"),
    "compose": (
        "composed_rigid_body_flow", "rkmk4_rigid_body_flow", "midpoint_rigid_body_flow",
        "benchmark_cost",
    ),
    "continuous": ("Flow", "RigidBody", "Trajectory", "FlowSolution", "integrate"),
    "symmetric": (
        "symmetric_momentum", "symmetric_rigid_body_rhs", "mclachlan_scovel_rhs",
        "multi_sample_control", "multi_sample_rhs", "gl_hamiltonian", "P_from_M", "PFromMInfo",
        "SymmetricRigidBody", "McLachlanScovel", "MultiSampleSymmetricRigidBody",
    ),
    "paper": (
        "jd_residual", "symmetric_step", "symmetric_flow", "mv_algorithm1", "mv_algorithm2",
        "discrete_rigid_body_flow", "DiscreteFlowSolution",
    ),
    "engine": ("MVStepper", "mv_flow"),
    "errors": ("SymrbError", "InputError", "NotConvergedError", "OutOfDomainError"),
    "exact": ("ExactSolution", "rigid_body_exact"),
    "learning": (
        "resnet_forward", "squared_error", "costate_sweep", "loss_gradients", "SweepInfo", "train",
        "TrainResult", "toy_classification", "so_network_forward", "so_network_gradients",
        "so_network_costates", "so_extremal_residual", "so_procrustes", "so_rotation_task",
        "SOTrainResult", "train_so_gradient", "train_so_msa", "train_so_shooting", "DigitsTask",
        "digits_task", "resnet_predict", "train_msa",
    ),
    "orbits": (
        "orbit_extremal_rhs", "orbit_hamiltonian", "brockett_potential", "double_bracket_rhs",
        "double_bracket_flow", "DoubleBracketInfo", "toda_flow", "one_sample_second_term",
        "two_sample_bound", "OrbitBVPResult", "solve_orbit_bvp",
    ),
    "scenes": (
        "SceneError", "When", "RigidBodyScene", "SymmetricRigidBodyScene",
        "McLachlanScovelScene", "DoubleBracketScene", "OrbitExtremalScene", "ResNetScene",
        "TodaScene", "parse_scene", "load_scene", "scene_inputs", "RigidBodyMomentum", "Plan",
        "plan_scene", "SceneResult", "SceneStore", "run_scene", "expand_grid", "SweepResult",
        "sweep", "SONetworkScene",
    ),
    "rigid_body": (
        "rigid_body_rhs", "kinetic_energy", "casimir_traces", "manakov_integrals",
        "euler_rhs_so3", "simulate", "RigidBodySolution",
    ),
    "solvers": ("MVSolveInfo", "solve_moser_veselov", "fold_scale"),
}  # fmt: skip
_WHERE = {name: module for module, names in _EXPORTS.items() for name in names}

__all__ = [name for names in _EXPORTS.values() for name in names]


def __getattr__(name: str) -> Any:
    if name in _EXPORTS:
        return importlib.import_module(f"{__name__}.{name}")
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module 'symrb' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__) | set(_EXPORTS))


if TYPE_CHECKING:  # static type checkers see the eager imports
    from . import (  # noqa: F401
        algebra,
        base_steps,
        compose,
        composition,
        continuous,
        engine,
        errors,
        exact,
        learning,
        orbits,
        paper,
        rigid_body,
        scenes,
        solvers,
        symmetric,
    )
    from .algebra import *  # noqa: F403
    from .base_steps import *  # noqa: F403
    from .compose import *  # noqa: F403
    from .composition import *  # noqa: F403
    from .continuous import *  # noqa: F403
    from .engine import *  # noqa: F403
    from .errors import *  # noqa: F403
    from .exact import *  # noqa: F403
    from .learning import *  # noqa: F403
    from .orbits import *  # noqa: F403
    from .paper import *  # noqa: F403
    from .rigid_body import *  # noqa: F403
    from .scenes import *  # noqa: F403
    from .solvers import *  # noqa: F403
    from .symmetric import *  # noqa: F403
