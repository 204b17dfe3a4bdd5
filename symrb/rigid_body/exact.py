"""Method "exact": the exact solution by Jacobi elliptic functions
(:func:`symrb.exact.rigid_body_exact`, n = 3)."""

from __future__ import annotations

from ..errors import InputError
from ..exact import rigid_body_exact
from ._request import Method, Request, RigidBodySolution


def run(req: Request) -> RigidBodySolution:
    """``rigid_body_exact`` at the output times of the request (``t_eval`` or the grid of h)."""
    te = req.grid()
    if te is None:
        raise InputError(
            "method 'exact' has no steps of its own: pass t_eval, or h (and save_every) for the "
            "output grid t0 + k h"
        )
    # the solution is from Q0, M0 at time 0: evaluate it at t - t0
    raw = rigid_body_exact(
        req.Q0, req.M0, req.lam, te - req.t0, check=req.options.get("check", True)
    )
    return RigidBodySolution(
        t=req.t0 + raw.t,
        Q=raw.y["Q"],
        M=raw.y["M"],
        success=True,
        message=f"exact solution at {raw.t.size} times",
        method=req.method,
        raw=raw,
    )


METHOD = Method(
    run,
    fixed_step=False,
    summary="the exact solution (Jacobi elliptic functions), n = 3; option check (bool)",
    options=("check",),
)
