"""Benchmarks of symrb, from a source checkout (not part of the ``symrb`` wheel).

* :mod:`benchmarks.harness`: the harness behind ``symrb bench`` (work-precision, long-time
  invariants, throughput, cost against n, evidence, with the goals of issue 9);
* the scripts ``benchmarks/*.py``: single measurements run by hand
  (``python benchmarks/step_cost.py --help``), their results in ``benchmarks/results/``.
"""
