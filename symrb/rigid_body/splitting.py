"""Method "splitting": the explicit splitting into planar rotations
(:func:`symrb.splitting.splitting_flow`), order 2, 4, 6 or 8, any n."""

from __future__ import annotations

from ..splitting import SPLITTING_ORDERS, splitting_flow
from ._request import Method, Request, RigidBodySolution


def run(req: Request) -> RigidBodySolution:
    """``splitting_flow`` with the request's step; option ``backend`` is its ``method``."""
    assert req.h is not None and req.steps is not None and req.order is not None
    raw = splitting_flow(
        req.Q0,
        req.M0,
        req.lam,
        req.h,
        req.steps,
        order=req.order,
        save_every=req.stride,
        method=req.options.get("backend", "auto"),
    )
    return req.fixed_result(raw, {})


METHOD = Method(
    run,
    fixed_step=True,
    summary=(
        "explicit Lie-Poisson splitting into exact planar rotations (McLachlan 1993), any n; "
        "order 2, 4, 6, 8; Q in SO(n) and the Casimirs to rounding; option backend: 'auto', "
        "'numpy', 'numba'"
    ),
    orders=SPLITTING_ORDERS,
    default_order=4,
    options=("backend",),
)
