"""Method "midpoint": the implicit midpoint rule on the Lie-Poisson equation
(:func:`symrb.compose.midpoint_rigid_body_flow`)."""

from __future__ import annotations

from ..compose import midpoint_rigid_body_flow
from ._request import Method, Request, RigidBodySolution


def run(req: Request) -> RigidBodySolution:
    """``midpoint_rigid_body_flow`` with the request's step."""
    assert req.h is not None and req.steps is not None
    raw = midpoint_rigid_body_flow(
        req.Q0, req.M0, req.lam, req.h, req.steps, save_every=req.stride, progress=req.progress
    )
    return req.fixed_result(raw, {"iterations": raw.nit})


METHOD = Method(
    run,
    fixed_step=True,
    summary="the implicit midpoint rule, symmetric, order 2",
    orders=(2,),
    default_order=2,
    progress=True,
)
