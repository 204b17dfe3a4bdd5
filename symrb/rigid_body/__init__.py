"""The rigid body: its vector field and invariants, and one entry point to simulate it by any
method (:func:`simulate`, the methods in :data:`METHODS`, one module per method family)."""

from __future__ import annotations

from ._request import RigidBodySolution
from .entry import METHODS as METHODS
from .entry import simulate
from .invariants import (
    casimir_traces,
    euler_rhs_so3,
    kinetic_energy,
    manakov_integrals,
    rigid_body_rhs,
)

__all__ = [
    "rigid_body_rhs",
    "kinetic_energy",
    "casimir_traces",
    "manakov_integrals",
    "euler_rhs_so3",
    "simulate",
    "RigidBodySolution",
]
