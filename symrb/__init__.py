"""symrb: numerics for Bloch, Crouch and Ratiu, "Symmetric Discrete Optimal Control and Deep Learning".

The package imports only NumPy and SciPy.  Its kernels in :mod:`symrb._generated` are emitted by
:mod:`derivations` (SymPy, development time only) and wrapped here by functions that validate input.
"""

from __future__ import annotations

from .algebra import (
    J,
    J_D,
    J_inv,
    commutator,
    hat,
    inertia_from_lam,
    lam_from_inertia,
    pairing,
    random_lam,
    random_SO,
    random_so,
    skew_part,
    vee,
)
from .errors import InputError, NotConvergedError, OutOfDomainError, SymrbError
from .rigid_body import casimir_traces, euler_rhs_so3, kinetic_energy, manakov_integrals, rigid_body_rhs

__version__ = "0.1.0"

__all__ = [
    "J",
    "J_D",
    "J_inv",
    "commutator",
    "hat",
    "inertia_from_lam",
    "lam_from_inertia",
    "pairing",
    "random_lam",
    "random_SO",
    "random_so",
    "skew_part",
    "vee",
    "InputError",
    "NotConvergedError",
    "OutOfDomainError",
    "SymrbError",
    "casimir_traces",
    "euler_rhs_so3",
    "kinetic_energy",
    "manakov_integrals",
    "rigid_body_rhs",
]
