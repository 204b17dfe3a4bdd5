"""symrb: numerics for Bloch, Crouch and Ratiu, "Symmetric Discrete Optimal Control and Deep Learning".

The package imports only NumPy and SciPy.  Its kernels in :mod:`symrb._generated` are emitted by
:mod:`derivations` (SymPy, development time only) and wrapped here by functions that validate input.
Each submodule lists its public names in ``__all__``; they are re-exported here.
"""

from __future__ import annotations

from . import algebra, continuous, discrete, errors, learning, orbits, rigid_body, solvers
from .algebra import *  # noqa: F403
from .continuous import *  # noqa: F403
from .discrete import *  # noqa: F403
from .errors import *  # noqa: F403
from .learning import *  # noqa: F403
from .orbits import *  # noqa: F403
from .rigid_body import *  # noqa: F403
from .solvers import *  # noqa: F403

__version__ = "0.1.0"

__all__ = [
    *algebra.__all__,
    *continuous.__all__,
    *discrete.__all__,
    *errors.__all__,
    *learning.__all__,
    *orbits.__all__,
    *rigid_body.__all__,
    *solvers.__all__,
]
