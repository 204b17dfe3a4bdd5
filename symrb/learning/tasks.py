r"""Data sets for the networks: a 2-D toy classification for the residual network, a rotation
to learn for the SO(n) network, and scikit-learn's handwritten digits (the residual network of
Remark 1 on real data)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import expm

from .. import _validate as v
from .._docs import fill_doc
from .._validate import Array
from ..algebra import as_generator, random_SO
from ..errors import InputError
from ._common import DOC

__all__ = ["toy_classification", "so_rotation_task", "DigitsTask", "digits_task"]


@fill_doc(DOC)
def toy_classification(num: int = 200, seed: int | np.random.Generator | None = 0):
    r"""A 2-D toy problem: points uniform in :math:`[-1, 1]^2`, label
    :math:`c = \operatorname{sign}(x_2 - \tfrac12\sin(\pi x_1))`, target :math:`y = (x_1, c)`.

    A residual network must bend the sine boundary flat and push the classes to
    :math:`x_2 = \pm1` (a deformation of the plane, which residual layers can approximate).

    Parameters
    ----------
    num : int, optional
        The number of points, >= 1.
    %(seed)s

    Returns
    -------
    x0 : ndarray, shape (num, 2)
        The points.
    targets : ndarray, shape (num, 2)
        :math:`(x_1, c)`.
    labels : ndarray, shape (num,)
        The classes :math:`c = \pm 1`.

    Examples
    --------
    >>> import symrb
    >>> x0, targets, labels = symrb.learning.toy_classification(200, seed=0)
    >>> x0.shape, targets.shape, int((labels > 0).sum())
    ((200, 2), (200, 2), 99)
    """
    if isinstance(num, bool) or not isinstance(num, int | np.integer) or num < 1:
        raise InputError(f"num must be a positive integer, got {num!r}; pass an int >= 1")
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    x = rng.uniform(-1.0, 1.0, size=(int(num), 2))
    c = np.where(x[:, 1] - 0.5 * np.sin(np.pi * x[:, 0]) >= 0, 1.0, -1.0)
    targets = np.stack([x[:, 0], c], axis=-1)
    return x, targets, c


@fill_doc(DOC)
def so_rotation_task(
    n: int = 3,
    samples: int = 32,
    angle: float = 0.6,
    noise: float = 0.05,
    seed: int | np.random.Generator | None = 0,
) -> tuple[Array, Array]:
    r"""A task for the SO(n) network: learn one rotation from noisy examples.

    Samples :math:`Q^a_0` Haar-random in SO(n); targets :math:`T^a = Q^a_0 R E^a` with one fixed
    rotation :math:`R = e^{\theta\hat\omega}` (angle ``angle``, a random axis-like skew unit
    :math:`\hat\omega`) and small random rotations :math:`E^a = e^{\epsilon\eta^a}` (noise).
    For small angles and a positive running cost the loss has one minimiser near the controls
    whose product is :math:`R`.

    Parameters
    ----------
    n : int, optional
        The matrix size, >= 2.
    samples : int, optional
        The number M of samples, >= 1.
    angle : float, optional
        The rotation angle :math:`\theta` of :math:`R`.
    noise : float, optional
        The size :math:`\epsilon \ge 0` of the perturbations.
    %(seed)s

    Returns
    -------
    Q0 : ndarray, shape (samples, n, n)
        The samples.
    targets : ndarray, shape (samples, n, n)
        The targets, in SO(n).

    Examples
    --------
    >>> from symrb.learning import so_rotation_task
    >>> Q0, T = so_rotation_task(4, samples=10, seed=1)
    >>> Q0.shape, T.shape
    ((10, 4, 4), (10, 4, 4))
    """
    n = v.count(n, "n", 2)
    samples = v.count(samples, "samples", 1)
    angle = v.real_scalar(angle, "angle")
    noise = v.real_scalar(noise, "noise")
    if noise < 0:
        raise InputError(f"noise must be >= 0, got {noise!r}")
    rng = as_generator(seed)
    Q0 = random_SO(n, (samples,), seed=rng)
    w = rng.standard_normal((n, n))
    w = w - w.T
    R = expm(angle * w / np.linalg.norm(w, 2))
    eta = rng.standard_normal((samples, n, n))
    E = expm(noise * (eta - np.swapaxes(eta, 1, 2)) / 2)
    return Q0, Q0 @ R @ E


@dataclass(frozen=True)
class DigitsTask:
    """The digits classification task of :func:`digits_task`.

    Attributes
    ----------
    x_train, x_test : ndarray, shape (M, n)
        Initial states: ``features`` principal components, then ``classes`` zeros.
    y_train : ndarray, shape (M, n)
        Targets: the same components, then the one-hot code of the class.
    labels_train, labels_test : ndarray of int, shape (M,)
        The digits 0-9.
    classes : int
        The number of classes (the last ``classes`` entries of a state are read out).

    Examples
    --------
    >>> from symrb.learning import digits_task
    >>> task = digits_task(features=8)  # doctest: +SKIP
    >>> task.x_train.shape[1], task.classes  # doctest: +SKIP
    (18, 10)
    """

    x_train: Array
    y_train: Array
    labels_train: NDArray[np.int64]
    x_test: Array
    labels_test: NDArray[np.int64]
    classes: int


def digits_task(
    features: int = 16, test_fraction: float = 0.3, seed: int | np.random.Generator | None = 0
) -> DigitsTask:
    r"""scikit-learn's handwritten digits (1797 8x8 images shipped with the package, no download)
    as a task for the residual network.

    The pixels are centred and projected on their first ``features`` principal components (of
    the training set, scaled to unit variance on average); a state is those components followed
    by ten zeros, its target the same components followed by the one-hot code of the digit, so
    the network has to write the class into the last ten entries while keeping the rest.  The
    predicted class is the largest of the last ten entries of :math:`x_N`
    (:func:`~symrb.learning.resnet.resnet_predict`).

    Parameters
    ----------
    features : int, optional
        The number of principal components, 1 to 64.
    test_fraction : float, optional
        The share of the images held out for testing, in (0, 1).
    seed : int, numpy.random.Generator or None, optional
        The random source of the split.

    Returns
    -------
    DigitsTask
        The training and test states, the training targets and the labels.

    Raises
    ------
    ImportError
        scikit-learn is not installed (``pip install scikit-learn``).

    Examples
    --------
    >>> from symrb.learning import digits_task
    >>> task = digits_task(features=8)  # doctest: +SKIP
    >>> task.x_train.shape, task.x_test.shape  # doctest: +SKIP
    ((1258, 18), (539, 18))
    """
    try:
        from sklearn.datasets import load_digits
    except ImportError:  # pragma: no cover - depends on the environment
        raise ImportError(
            "digits_task needs the optional package scikit-learn: pip install scikit-learn"
        ) from None
    features = v.count(features, "features", 1)
    if features > 64:
        raise InputError(f"features must be at most 64 (8x8 pixels), got {features}")
    frac = v.real_scalar(test_fraction, "test_fraction")
    if not 0 < frac < 1:
        raise InputError(f"test_fraction must be in (0, 1), got {test_fraction!r}")
    data = load_digits()
    X, labels = np.asarray(data.data, dtype=float), np.asarray(data.target, dtype=np.int64)
    order = as_generator(seed).permutation(len(labels))
    n_test = int(round(frac * len(labels)))
    test, train = order[:n_test], order[n_test:]
    mean = X[train].mean(axis=0)
    _u, s, vt = np.linalg.svd(X[train] - mean, full_matrices=False)
    scale = float(np.sqrt(np.mean(s[:features] ** 2) / len(train)))
    classes = 10

    def states(idx: NDArray[np.int64]) -> Array:
        comps = (X[idx] - mean) @ vt[:features].T / scale
        return np.concatenate([comps, np.zeros((len(idx), classes))], axis=1)

    x_train = states(train)
    y_train = x_train.copy()
    y_train[np.arange(len(train)), features + labels[train]] = 1.0
    return DigitsTask(
        x_train=x_train,
        y_train=y_train,
        labels_train=labels[train],
        x_test=states(test),
        labels_test=labels[test],
        classes=classes,
    )
