"""Experiments shown in the book, one function each.

Each function computes one experiment of a book page and returns a result object with the numbers
the page plots and the tests assert on (so a figure and its check cannot drift apart):

* :mod:`symrb.experiments.discrete`: the discrete rigid body and the Moser-Veselov algorithms
  (Section 2 of the paper);
* :mod:`symrb.experiments.smooth`: the smooth flows and the adjoint-orbit problems (Section 3);
* :mod:`symrb.experiments.accuracy`: what accuracy costs in time.
"""
