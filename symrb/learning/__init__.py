r"""Deep learning as discrete optimal control (paper, Section 2, Remarks 1-2, and the learning
theorem; claims D5, D6 and D9).

The modules: :mod:`~symrb.learning.resnet` (the residual network of Remark 1: forward sweep,
costate sweep, gradients, gradient descent and the extended method of successive
approximations), :mod:`~symrb.learning.so_network` (the SO(n) network of the learning theorem:
forward sweep, costates, gradients, the residual of the extremal equations),
:mod:`~symrb.learning.so_training` (its three trainers) and :mod:`~symrb.learning.tasks` (the
data sets).  Every name is importable from :mod:`symrb.learning`.
"""

from __future__ import annotations

from .._package import adopt_classes
from ._common import SweepInfo
from .resnet import (
    TrainResult,
    costate_sweep,
    loss_gradients,
    resnet_forward,
    resnet_predict,
    squared_error,
    train,
    train_msa,
)
from .so_network import (
    so_extremal_residual,
    so_network_costates,
    so_network_forward,
    so_network_gradients,
)
from .so_training import (
    SOTrainResult,
    so_procrustes,
    train_so_gradient,
    train_so_msa,
    train_so_shooting,
)
from .tasks import DigitsTask, digits_task, so_rotation_task, toy_classification

__all__ = [
    "resnet_forward",
    "squared_error",
    "costate_sweep",
    "loss_gradients",
    "SweepInfo",
    "train",
    "TrainResult",
    "toy_classification",
    "so_network_forward",
    "so_network_gradients",
    "so_network_costates",
    "so_extremal_residual",
    "so_procrustes",
    "so_rotation_task",
    "SOTrainResult",
    "train_so_gradient",
    "train_so_msa",
    "train_so_shooting",
    "DigitsTask",
    "digits_task",
    "resnet_predict",
    "train_msa",
]

adopt_classes(globals(), __all__, __name__)
