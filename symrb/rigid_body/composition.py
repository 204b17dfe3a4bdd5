"""Method "composition": a symmetric composition of a symmetric base step
(:func:`symrb.compose.composed_rigid_body_flow`), order 2, 4, 6 or 8, any n."""

from __future__ import annotations

from ..compose import composed_rigid_body_flow
from ._request import Method, Request, RigidBodySolution


def run(req: Request) -> RigidBodySolution:
    """``composed_rigid_body_flow`` with the request's step; options ``kind`` and ``step``."""
    assert req.h is not None and req.steps is not None and req.order is not None
    raw = composed_rigid_body_flow(
        req.Q0,
        req.M0,
        req.lam,
        req.h,
        req.steps,
        req.order,
        kind=req.options.get("kind"),
        step=req.options.get("step", "mv"),
        save_every=req.stride,
        progress=req.progress,
    )
    return req.fixed_result(raw, {"iterations": raw.nit})


METHOD = Method(
    run,
    fixed_step=True,
    summary=(
        "a symmetric composition of the MV step (or of option step: 'midpoint' or an object); "
        "order 2, 4, 6, 8; option kind: the coefficients (symrb.composition.composition_coefficients)"
    ),
    orders=(2, 4, 6, 8),
    default_order=4,
    options=("kind", "step"),
    progress=True,
)
