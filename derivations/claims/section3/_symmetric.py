"""The symmetric representation of Sections 3.2-3.3 (claims S5-S12): its matrix symbols, kernel
arguments and the momentum map every kernel of ``symrb/_generated/symmetric_rigid_body.py`` is
built on."""

from __future__ import annotations

from derivations.vocabulary import Arg, matrix

Q, P, B, U = matrix("Q"), matrix("P"), matrix("B"), matrix("U")
M, Om = matrix("M"), matrix("Omega")
Qdot, Pdot, Bdot, Mdot = matrix("Qdot"), matrix("Pdot"), matrix("Bdot"), matrix("Mdot")
ARG_Q = Arg("Q", "(..., n, n)", "configuration (SO(n) is invariant; any square matrix accepted)")
ARG_P = Arg("P", "(..., n, n)", "costate")
ARG_B = Arg("B", "(..., n, n)", "McLachlan-Scovel costate, Q^T B skew")
ARG_U = Arg("U", "(..., n, n)", "control, skew")

#: The momentum map of the symmetric representation; every kernel of S5-S12 is built on this object.
MOMENTUM = Q.T * P - P.T * Q
