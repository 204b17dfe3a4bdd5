"""The systems of the scenes, one module each; importing one registers its scene model.

Each module defines its model (a subclass of :class:`~symrb.scenes.schema._SceneBase` with its
parameters and integrators) and the hooks ``_inputs``, ``_plan`` and ``_run``; what several
systems share lives beside them (``_body``: the three bodies; ``_compare``: second runs of a
body).
"""

from __future__ import annotations

# the order of registration (the order of the systems in error messages): not alphabetical
# isort: off
from .rigid_body import RigidBodyMomentum, RigidBodyScene
from .symmetric_rigid_body import SymmetricRigidBodyScene
from .mclachlan_scovel import McLachlanScovelScene
from .double_bracket import DoubleBracketScene
from .orbit_extremal import OrbitExtremalScene
from .resnet import ResNetScene
from .so_network import SONetworkScene
from .toda import TodaScene

# isort: on

__all__ = [
    "RigidBodyScene",
    "SymmetricRigidBodyScene",
    "McLachlanScovelScene",
    "DoubleBracketScene",
    "OrbitExtremalScene",
    "ResNetScene",
    "SONetworkScene",
    "TodaScene",
    "RigidBodyMomentum",
]
