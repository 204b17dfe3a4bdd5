"""Method "mv": the Moser-Veselov map by the Cayley-Newton engine (:func:`symrb.engine.mv_flow`),
order 2, or 4 to 10 preprocessed (n = 3)."""

from __future__ import annotations

from ..engine import PREPROCESSED_ORDERS, mv_flow
from ._request import Method, Request, RigidBodySolution


def run(req: Request) -> RigidBodySolution:
    """``mv_flow`` with the request's step; option ``backend`` is its ``method``."""
    assert req.h is not None and req.steps is not None and req.order is not None
    raw = mv_flow(
        req.Q0,
        req.M0,
        req.lam,
        req.h,
        req.steps,
        save_every=req.stride,
        method=req.options.get("backend", "auto"),
        order=req.order,
    )
    return req.fixed_result(raw, {"newton_iterations": raw.nit})


METHOD = Method(
    run,
    fixed_step=True,
    summary=(
        "the discrete rigid body (MV-Algorithm 2 at step h), Cayley-Newton engine; order 2, or "
        "4-10 preprocessed (n = 3); option backend: 'auto', 'newton', 'fixed-point', 'numpy', "
        "'numba'"
    ),
    orders=PREPROCESSED_ORDERS,
    default_order=2,
    options=("backend",),
)
