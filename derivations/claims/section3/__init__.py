"""Section 3 of the paper: the rigid body, the symmetric rigid body and adjoint orbits (S1-S15)."""
