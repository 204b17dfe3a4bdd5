"""Method "rkmk4": the Runge-Kutta-Munthe-Kaas method of order 4
(:func:`symrb.compose.rkmk4_rigid_body_flow`)."""

from __future__ import annotations

from ..compose import rkmk4_rigid_body_flow
from ._request import Method, Request, RigidBodySolution


def run(req: Request) -> RigidBodySolution:
    """``rkmk4_rigid_body_flow`` with the request's step."""
    assert req.h is not None and req.steps is not None
    raw = rkmk4_rigid_body_flow(
        req.Q0, req.M0, req.lam, req.h, req.steps, save_every=req.stride, progress=req.progress
    )
    return req.fixed_result(raw, {})


METHOD = Method(
    run,
    fixed_step=True,
    summary="RKMK4, explicit, order 4",
    orders=(4,),
    default_order=4,
    progress=True,
)
