"""Section 2 of the paper: discrete optimal control (D1-D6) and the discrete rigid body (D7-D12)."""
