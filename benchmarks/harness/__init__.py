r"""Benchmarks of symrb's rigid body integrators, with the speed and accuracy goals of issues 9
and 23.

:func:`run` measures, in one process and one run (``symrb bench`` on the command line, from a
source checkout: the harness is not part of the ``symrb`` wheel):

1. **work-precision** (n = 3, T = 10 and 100): the largest entry of the error in :math:`M(T)` and
   :math:`Q(T)` against a reference, versus process CPU time, for SciPy's ``solve_ivp`` (RK45,
   DOP853, LSODA) on two fields: the lean one a user would write (``problems.LEAN_VARIANTS``: for
   n = 3 Euler's equations by hand on 12 unknowns, for any n two matrix products; the fastest
   variant measured is used and recorded in ``baselines``), under the method's own name, and the
   field built from the generated kernel :func:`symrb._generated.rigid_body.rigid_body_rhs`
   (2 n^2 unknowns) as ``RK45-gen``, ``DOP853-gen``, ``LSODA-gen``; :func:`symrb.integrate`
   (DOP853, to measure its overhead on the generated field), :func:`symrb.discrete_rigid_body_flow` at several steps h, and
   the optional methods found by import (the fast Moser-Veselov engine ``symrb.engine.mv_flow``,
   the compositions and RKMK4/implicit midpoint of ``symrb.compose``, the exact solution
   ``symrb.exact.rigid_body_exact``).  The reference is Gragg-Bulirsch-Stoer extrapolation in
   extended precision (``derivations.reference.rigid_body_extrapolated``, any n, independent of
   symrb), its own error estimated from two macro steps and two orders (a few 1e-16 at T = 100)
   and recorded; the exact solution is judged against it like every other method.  Each
   fixed-step method's order is the slope of :math:`\log(\text{error})` against :math:`\log h`.
2. **long-time invariants**: relative energy and Casimir (:math:`\operatorname{tr}M^2`) errors and
   :math:`\|Q^TQ - I\|` of the Moser-Veselov flow against the step number N (running maxima),
   with the line :math:`\varepsilon\sqrt N` of a random walk of rounding errors and the fitted
   slope of :math:`\log(\text{error})` against :math:`\log N`.
3. **throughput**: body-steps per second of a Moser-Veselov step on batches of 1 to :math:`10^4`
   bodies (n = 3) next to a batched 3x3 matrix product, and a cold start against a warm step.
4. **cost against n**: one step of a single body for n = 3, 5, 10, 20, 50 in units of one
   n x n matrix product.
5. **evidence**: the time of each evidence level of ``symrb verify --json`` (read from a file)
   next to what that level certifies.
6. **step-costs**, 7. **long-horizon**, 8. **cold-start** (issue 23,
   :mod:`~benchmarks.harness.costs`): one whole ``mv_flow`` call, the paper's maps and the
   stages of the compositions against an ``mv_flow`` step, one compiled n = 10 step against its
   flop count; n = 10 to T = 1e4 with the invariants' errors; new processes with numba.

Every goal that compares costs at an error uses measured runs only: for each method the cheapest
run whose error is at most the target (:func:`~benchmarks.harness.timing.cheapest_measured`),
named in the goal's note; no fitted order extends a grid.  A goal not met carries a profile of
one call (cProfile, the top entries by cumulative time) recorded in the run.  ``--json`` keeps
the goals of the run the file held before as ``previous_goals``.

Timing discipline: every configuration is timed once per round and the rounds are interleaved
(drifts of a shared machine hit all configurations alike); a timing repeats its call until it
lasts ``min_time`` (far above the resolution of :func:`time.process_time`); medians are reported
with the min and max over the rounds; the garbage collector is paused while timing; BLAS is pinned
to one thread with ``threadpoolctl`` (without it a warning is recorded).  All times are process
CPU time (:func:`time.process_time`).

The goals are returned as ``{name, measured, target, met, note}``; a goal whose method is not
available, or that needs a long run skipped by ``quick=True``, has ``met = None`` and a note.

The modules: :mod:`~benchmarks.harness.config` (sections, methods, parameters),
:mod:`~benchmarks.harness.timing` (interleaved timing, slopes), :mod:`~benchmarks.harness.problems`
(the bodies and the methods), :mod:`~benchmarks.harness.precision` (sections 1 and 2),
:mod:`~benchmarks.harness.speed` (sections 3 to 5), :mod:`~benchmarks.harness.goals`,
:mod:`~benchmarks.harness.result` and :mod:`~benchmarks.harness.plots`,
:mod:`~benchmarks.harness.runner` (:func:`run`) and :mod:`~benchmarks.harness.cli`.
"""

from .cli import build_parser, main
from .config import SECTIONS
from .result import BenchResult, load
from .runner import run
from .timing import fit_slope, time_interleaved

__all__ = ["SECTIONS", "BenchResult", "run", "load", "time_interleaved", "fit_slope", "main",
           "build_parser"]  # fmt: skip
