"""The rigid body: its vector field and invariants, and one entry point to simulate it by any
method (:func:`simulate`, the methods in :data:`METHODS`, one module per method family)."""

from __future__ import annotations

from ._request import RigidBodySolution
from .invariants import (
    casimir_traces,
    euler_rhs_so3,
    kinetic_energy,
    manakov_integrals,
    rigid_body_rhs,
)
from .simulate import METHODS as METHODS
from .simulate import simulate

__all__ = [
    "rigid_body_rhs",
    "kinetic_energy",
    "casimir_traces",
    "manakov_integrals",
    "euler_rhs_so3",
    "simulate",
    "RigidBodySolution",
]
