r"""Optimal control on adjoint orbits and double bracket flows (paper, Section 3.5).

The control system is :math:`\dot x = [x, u]` on an adjoint orbit of :math:`\mathfrak{so}(n)` (skew
matrices; the paper also allows :math:`\mathfrak{su}(n)`), with the cost

.. math::

    \int_0^T \tfrac12\|u\|^2 - V(x)\,dt \;+\; \sum_a \phi(x^a_T),\qquad
    V(x) = -\tfrac12\|[x, n]\|^2,\quad \phi(x) = \langle x, n\rangle,

:math:`\langle a, b\rangle = -\tfrac12\operatorname{tr}(ab)`, :math:`\|a\|^2 = \langle a,a\rangle`.
With :math:`H = \sum_a\langle p^a, [x^a, u]\rangle - \tfrac12\|u\|^2 + \sum_a V(x^a)` the maximum
principle gives (claims S13-S15)

.. math::

    u^* = \sum_b [p^b, x^b],\qquad \dot x^a = [x^a, u^*],\qquad
    \dot p^a = [p^a, u^*] - [n, [n, x^a]],\qquad p^a_T = -\phi_x(x^a_T) = -n.

The paper prints :math:`p^a_T = +\partial\phi/\partial x^a_T` and per-sample controls
:math:`[p^a, x^a]`; both are corrected here (see the errata).  For one sample the extremal is
exactly :math:`p \equiv -n` and the double bracket flow :math:`\dot x = [x, [x, n]]`.

Each vector field calls one kernel generated in :mod:`symrb._generated.adjoint_orbits` by
the claims S13-S15 of :mod:`derivations.claims.section3`.  Here ``N`` is the paper's fixed
element ``n``.

The modules: :mod:`~symrb.orbits.extremal` (the extremal vector field, its
integration from initial data, its Hamiltonian and Brockett's potential), :mod:`~symrb.orbits.double_bracket` (the double bracket flow and the Toda
lattice), :mod:`~symrb.orbits.closed_forms` (the closed forms of S15 on so(3)) and
:mod:`~symrb.orbits.bvp` (the boundary value problem of the learning version).
"""

from __future__ import annotations

from .._package import adopt_classes
from .bvp import OrbitBVPResult, solve_orbit_bvp
from .closed_forms import one_sample_second_term, two_sample_bound
from .double_bracket import DoubleBracketInfo, double_bracket_flow, double_bracket_rhs, toda_flow
from .extremal import (
    brockett_potential,
    orbit_extremal_flow,
    orbit_extremal_rhs,
    orbit_hamiltonian,
)

__all__ = [
    "orbit_extremal_rhs",
    "orbit_extremal_flow",
    "orbit_hamiltonian",
    "brockett_potential",
    "double_bracket_rhs",
    "double_bracket_flow",
    "DoubleBracketInfo",
    "toda_flow",
    "one_sample_second_term",
    "two_sample_bound",
    "OrbitBVPResult",
    "solve_orbit_bvp",
]

adopt_classes(globals(), __all__, __name__)
