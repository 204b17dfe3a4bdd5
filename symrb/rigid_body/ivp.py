"""The ``solve_ivp`` methods ("RK45", "DOP853", "Radau", ...): :func:`symrb.integrate` on
:class:`symrb.RigidBody`."""

from __future__ import annotations

from .. import _validate as v
from ..continuous import RigidBody, integrate
from ._request import Method, Request, RigidBodySolution

#: the methods of :func:`scipy.integrate.solve_ivp`
NAMES = ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")
#: the tolerances of :func:`symrb.integrate` when none are given
RTOL, ATOL = 1e-10, 1e-12


def run(req: Request) -> RigidBodySolution:
    """``integrate(RigidBody, ...)`` at the output times of the request (the solver's own steps
    when neither ``t_eval`` nor ``h`` is given)."""
    te = req.grid()
    if te is not None and req.t_eval is None:
        te = te.clip(max=req.t1)  # the last grid time is t1 to rounding: keep it inside t_span
    raw = integrate(
        RigidBody,
        (req.t0, req.t1),
        # validated here so that errors name Q0 and M0 (integrate's names are y0['Q'], y0['M'])
        {"Q": v.orthogonal(req.Q0, "Q0"), "M": v.skew(req.M0, "M0")},
        lam=req.lam,
        method=req.method,
        rtol=RTOL if req.rtol is None else req.rtol,
        atol=ATOL if req.atol is None else req.atol,
        t_eval=te,
        condition=req.options.get("condition", False),
    )
    return RigidBodySolution(
        t=raw.t,
        Q=raw.y["Q"],
        M=raw.y["M"],
        success=raw.success,
        message=raw.message,
        method=req.method,
        stats={"nfev": raw.nfev},
        raw=raw,
    )


METHODS = {
    name: Method(
        run,
        fixed_step=False,
        summary=f"scipy.integrate.solve_ivp, method {name!r} (adaptive, rtol and atol)",
        options=("condition",),
        tolerances=True,
    )
    for name in NAMES
}
