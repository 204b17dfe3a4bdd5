"""symrb: numerics for Bloch, Crouch and Ratiu, "Symmetric Discrete Optimal Control and Deep Learning".

The package imports only NumPy and SciPy.  Its kernels in :mod:`symrb._generated` are emitted by
the ``derivations`` of the source tree (SymPy, development time only) and wrapped by functions that
validate input.  The top level holds the entry points (:data:`_EXPORTS`, 40 names, loaded on
first use so that ``import symrb`` is cheap); everything else is imported from the submodule that
defines it, e.g. ``symrb.engine.mv_flow`` or ``symrb.scenes.plan_scene``.  ``ARCHITECTURE.md``
in the source tree maps the submodules.

>>> import numpy as np, symrb
>>> sol = symrb.simulate(np.eye(3), symrb.hat([0.3, -0.2, 0.5]), [0.7, 1.1, 1.6], (0.0, 1.0),
...                      method="mv", h=0.01)
>>> sol.success, sol.Q.shape
(True, (101, 3, 3))
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

#: The top-level names and the submodule defining each (a test checks that each is in that
#: module's ``__all__``).
_EXPORTS: dict[str, tuple[str, ...]] = {
    "rigid_body": (
        "simulate", "RigidBodySolution", "kinetic_energy", "casimir_traces", "manakov_integrals",
    ),
    "paper": ("symmetric_flow", "mv_algorithm1", "mv_algorithm2", "discrete_rigid_body_flow"),
    "algebra": ("hat", "vee", "pairing", "commutator", "J", "J_inv", "random_so", "random_SO"),
    "continuous": ("integrate", "RigidBody"),
    "symmetric": ("SymmetricRigidBody", "McLachlanScovel", "MultiSampleSymmetricRigidBody"),
    "solvers": ("solve_moser_veselov", "fold_scale"),
    "orbits": ("double_bracket_flow", "toda_flow", "solve_orbit_bvp"),
    "learning": (
        "train", "train_msa", "so_network_gradients", "train_so_gradient", "train_so_msa",
        "train_so_shooting",
    ),
    "scenes": ("load_scene", "run_scene", "sweep"),
    "errors": ("SymrbError", "InputError", "NotConvergedError", "OutOfDomainError"),
}  # fmt: skip
_WHERE = {name: module for module, names in _EXPORTS.items() for name in names}

__all__ = [name for names in _EXPORTS.values() for name in names]

#: The public submodules, reachable as attributes (``symrb.engine``) without an explicit import.
_SUBMODULES = frozenset(
    {"algebra", "base_steps", "compose", "composition", "continuous", "engine", "errors", "exact",
     "learning", "orbits", "paper", "rigid_body", "scenes", "solvers", "symmetric", "testing"}
)  # fmt: skip


def __getattr__(name: str) -> Any:
    if name in _SUBMODULES:
        return importlib.import_module(f"{__name__}.{name}")
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module 'symrb' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__) | _SUBMODULES)


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
        testing,
    )
    from .algebra import J, J_inv, commutator, hat, pairing, random_SO, random_so, vee
    from .continuous import RigidBody, integrate
    from .errors import InputError, NotConvergedError, OutOfDomainError, SymrbError
    from .learning import (
        so_network_gradients,
        train,
        train_msa,
        train_so_gradient,
        train_so_msa,
        train_so_shooting,
    )
    from .orbits import double_bracket_flow, solve_orbit_bvp, toda_flow
    from .paper import discrete_rigid_body_flow, mv_algorithm1, mv_algorithm2, symmetric_flow
    from .rigid_body import (
        RigidBodySolution,
        casimir_traces,
        kinetic_energy,
        manakov_integrals,
        simulate,
    )
    from .scenes import load_scene, run_scene, sweep
    from .solvers import fold_scale, solve_moser_veselov
    from .symmetric import McLachlanScovel, MultiSampleSymmetricRigidBody, SymmetricRigidBody
