"""Cost of the fixed-n symbolic checks against n: where SymPy's cost explodes.

The fixed-n checks of the claim registry run at one n (3 or 4).  This script runs the bodies of
three of them at n = 2, 3, ... with the same derivation helpers (``derivations.symbolic.explicit``
on the emitted kernels and the displayed formulas), timing each n (process CPU time), until one
run exceeds ``--budget`` seconds or n reaches ``--max-n``:

* ``S2 J symmetric``: <J a, b> = <a, J b> for symbolic skew a, b (claim S2, registry n = 4);
* ``S2 emitted field``: the emitted rigid body field at Q = I against the displayed J(Omega) = M
  and Mdot = [M, Omega] (claim S2, registry n = 4; the general-Q part is left out);
* ``S4 integrals conserved``: d/dt of the emitted Manakov integrals of degree <= 4 vanishes along
  the emitted field (claim S4, registry n = 4).

Usage: ``python benchmarks/symbolic_cost.py [--budget 20] [--max-n 8] [--json PATH]``; the JSON
(default ``benchmarks/results/symbolic_cost.json``) holds the times, the residuals (all must be
0) and, per check, the growth factor of the time from one n to the next.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from collections.abc import Callable
from pathlib import Path

import sympy as sp

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from derivations.claims.section3 import s02_rigid_body_equations as rb  # noqa: E402
from derivations.claims.section3 import s04_manakov_integrals as s4  # noqa: E402
from derivations.claims.section3._inertia import lam_symbols  # noqa: E402
from derivations.symbolic import explicit, lhs_minus_rhs, residual, skew_matrix  # noqa: E402


def j_symmetric(n: int) -> sp.Expr:
    lam, a, b = lam_symbols(n), skew_matrix("a", n), skew_matrix("b", n)
    eq = rb.S2.formulas["J_symmetric"]
    return residual(explicit(lhs_minus_rhs(eq), {"a": a, "b": b}, lam))


def emitted_field(n: int) -> sp.Expr:
    lam, Ms = lam_symbols(n), skew_matrix("m", n)
    env = {"Q": sp.eye(n), "M": Ms}
    Omega = explicit(rb.RIGID_BODY_RHS["Qdot"], env, lam)
    Mdot = explicit(rb.RIGID_BODY_RHS["Mdot"], env, lam)
    r = residual(sp.simplify(rb.J_explicit(Omega, lam) - Ms))
    return r + residual(sp.simplify(Mdot - explicit(rb.MDOT.rhs, {"M": Ms, "Omega": Omega})))


def integrals_conserved(n: int) -> sp.Expr:
    return s4.conservation(lam_symbols(n), skew_matrix("m", n), 4)


CHECKS: dict[str, tuple[Callable[[int], sp.Expr], int]] = {
    "S2 J symmetric": (j_symmetric, 4),
    "S2 emitted field": (emitted_field, 4),
    "S4 integrals conserved": (integrals_conserved, 4),
}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--budget", type=float, default=20.0, help="stop a check after a run this long")
    ap.add_argument("--max-n", type=int, default=8)
    ap.add_argument("--json", default=str(ROOT / "benchmarks/results/symbolic_cost.json"))
    args = ap.parse_args(argv)
    out: dict[str, object] = {
        "sympy": sp.__version__,
        "python": platform.python_version(),
        "budget_seconds": args.budget,
        "checks": {},
    }
    for name, (fn, registry_n) in CHECKS.items():
        rows = []
        for n in range(2, args.max_n + 1):
            t0 = time.process_time()
            r = fn(n)
            dt = time.process_time() - t0
            rows.append({"n": n, "seconds": dt, "residual": str(r)})
            print(f"{name:<26} n = {n:2d}: {dt:8.2f} s  residual {r}", flush=True)
            if r != 0:
                raise SystemExit(f"{name} at n = {n}: residual {r} != 0")
            if dt > args.budget:
                break
        pairs = zip(rows[:-1], rows[1:], strict=True)
        growth = [b["seconds"] / a["seconds"] for a, b in pairs if a["seconds"] > 0]
        out["checks"][name] = {  # type: ignore[index]
            "registry_n": registry_n,
            "runs": rows,
            "growth": growth,
            "largest_n_under_budget": max(
                (r["n"] for r in rows if r["seconds"] <= args.budget), default=None
            ),
        }
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    Path(args.json).write_text(json.dumps(out, indent=1) + "\n")
    print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
