"""A ResNet trained through the costates (Section 2, Remarks 1-2) as a scene (``system =
"resnet"``): ``symrb.train`` or ``symrb.train_msa`` on the toy data or on scikit-learn's
digits."""

from __future__ import annotations

from typing import Annotated, Any, Literal

import numpy as np
from pydantic import Field, model_validator

from ..._validate import Array
from ...learning import (
    costate_sweep,
    digits_task,
    resnet_forward,
    resnet_predict,
    squared_error,
    toy_classification,
    train,
    train_msa,
)
from ..plan import Plan, SystemPlan
from ..schema import TrainingHorizon, When, _invalid, _Model, _problem, _SceneBase, register_system

#: the images of scikit-learn's digits (for the ResNet's cost estimate)
_DIGITS_IMAGES = 1797


class GradientDescent(_Model):
    """``symrb.train``: plain gradient descent with learning rate ``lr``."""

    kind: Literal["gradient_descent"]
    lr: float = Field(default=0.005, gt=0)
    activation: Literal["tanh", "logistic"] = "tanh"
    residual: bool = True


class ExtendedMSA(_Model):
    """``symrb.train_msa``: the extended method of successive approximations, each iteration a
    forward pass, a costate sweep and ``inner_steps`` gradient-ascent steps of size
    ``inner_lr`` per layer on the augmented Hamiltonian with the state penalty ``rho``."""

    kind: Literal["msa"]
    rho: float = Field(default=1.0, ge=0)
    inner_steps: int = Field(default=3, ge=1)
    inner_lr: float = Field(default=0.01, gt=0)
    activation: Literal["tanh", "logistic"] = "tanh"
    residual: bool = True


class NetworkParameters(_Model):
    """The ResNet of Section 2, Remark 1 on the data ``data``: ``"toy"`` (the default),
    ``symrb.learning.toy_classification(samples, seed)`` in the plane (width 2), or ``"digits"``,
    ``symrb.learning.digits_task(features, test_fraction, seed)`` (scikit-learn's digits: width
    ``features + 10``; ``seed`` draws the split, ``test_fraction`` of the images are held out).
    ``layers`` layers, started from zero biases and the weights ``K0_scale`` times standard normal
    numbers drawn from ``numpy.random.default_rng(K0_seed)`` (zero weights when ``K0_scale = 0``,
    the default)."""

    data: Literal["toy", "digits"] = "toy"
    layers: int = Field(default=4, ge=1)
    samples: int = Field(default=200, ge=1)
    seed: int = Field(default=0, ge=0)
    #: the initial weights K are K0_scale times standard normal numbers from K0_seed (zeros when 0)
    K0_scale: float = Field(default=0.0, ge=0)
    K0_seed: int = Field(default=0, ge=0)
    features: int = Field(default=16, ge=1, le=64)
    test_fraction: float = Field(default=0.3, gt=0, lt=1)

    @model_validator(mode="after")
    def _keys_of_the_data(self) -> NetworkParameters:
        own = {"toy": ("samples",), "digits": ("features", "test_fraction")}
        others = [k for data, keys in own.items() if data != self.data for k in keys]
        for key in others:
            if key in self.model_fields_set:
                raise _invalid(
                    (key,), f"{key} is a key of the other data set, not of data = {self.data!r}",
                    [k for k in type(self).model_fields if k not in others],
                )  # fmt: skip
        return self


@register_system
class ResNetScene(_SceneBase):
    """A ResNet trained through the costates (Section 2, Remarks 1-2): by gradient descent
    (``integrator.kind = "gradient_descent"``, ``symrb.train``) or by the extended method of
    successive approximations (``"msa"``, ``symrb.train_msa``), on the toy data in the plane or
    on scikit-learn's digits (``parameters.data``).

    ``accuracy`` is the share of the training samples classified right: on the toy data the
    sign of the second entry of :math:`x_N` against the label, on the digits
    ``symrb.learning.resnet_predict`` with the task's ten classes; ``test_accuracy`` (digits only) the
    same on the held-out images.

    Examples
    --------
    >>> from symrb.scenes import ResNetScene
    >>> ResNetScene.EFFECTS, sorted(ResNetScene.OBSERVABLES)  # doctest: +NORMALIZE_WHITESPACE
    (('terminal_cost', 'costates'), ['K', 'accuracy', 'beta', 'costates', 'loss', 'states',
     'test_accuracy'])
    """

    EFFECTS = ("terminal_cost", "costates")
    RECORD_AXIS = "step"
    STATE_OBSERVABLES = ("states", "K", "beta")
    OBSERVABLES = {
        "states": None, "K": None, "beta": None, "accuracy": None, "test_accuracy": None,
        "loss": "terminal_cost", "costates": "costates",
    }  # fmt: skip
    system: Literal["resnet"]
    parameters: NetworkParameters = NetworkParameters()
    integrator: Annotated[GradientDescent | ExtendedMSA, Field(discriminator="kind")]
    horizon: TrainingHorizon
    observables: dict[
        Literal["states", "K", "beta", "accuracy", "test_accuracy", "loss", "costates"], When
    ]

    @model_validator(mode="after")
    def _held_out_data(self) -> ResNetScene:
        if "test_accuracy" in self.observables and self.parameters.data != "digits":
            raise _invalid(
                ("observables", "test_accuracy"),
                f"the {self.parameters.data} data hold no images out: test_accuracy needs "
                'parameters.data = "digits"',
                [o for o in self.OBSERVABLES if o != "test_accuracy"],
            )  # fmt: skip
        return self

    def _inputs(self) -> dict[str, Any]:
        """``x0``, ``targets``, ``labels``, ``K0``, ``beta0`` (on the digits also ``x_test``,
        ``labels_test`` and ``classes``)."""
        p = self.parameters
        held_out: dict[str, Any] = {}
        if p.data == "digits":
            task = digits_task(p.features, p.test_fraction, seed=p.seed)
            x0, targets, labels = task.x_train, task.y_train, task.labels_train
            held_out = {"x_test": task.x_test, "labels_test": task.labels_test,
                        "classes": task.classes}  # fmt: skip
        else:
            x0, targets, labels = toy_classification(p.samples, seed=p.seed)
        width = x0.shape[-1]
        shape = (p.layers, width, width)
        K0 = (p.K0_scale * np.random.default_rng(p.K0_seed).standard_normal(shape)
              if p.K0_scale > 0 else np.zeros(shape))  # fmt: skip
        return {
            "x0": x0, "targets": targets, "labels": labels,
            "K0": K0, "beta0": np.zeros((p.layers, width)), **held_out,
        }  # fmt: skip

    def _plan(self, skipped: list[tuple[str, str]], notes: list[str]) -> SystemPlan:
        steps = self.horizon.steps
        _check_records(self)
        if steps > 0 and "terminal_cost" not in self.effects:
            raise _problem("horizon.steps", f"{steps} gradient steps need a loss to descend: "
                           "switch on the effect 'terminal_cost' or set steps = 0", [0])  # fmt: skip
        modules: tuple[str, ...] = ("learning", "_validate", "_progress",
                                    "_generated.discrete_control", "scenes.systems.resnet")  # fmt: skip
        p = self.parameters
        if p.data == "digits":  # 1797 images, test_fraction of them held out (digits_task)
            S, width = _DIGITS_IMAGES - round(p.test_fraction * _DIGITS_IMAGES), p.features + 10
            modules += ("algebra",)
            notes.append(f"data: scikit-learn's digits, {p.features} principal components + 10 "
                         f"class entries (width {width}), {S} training images "
                         f"(symrb.learning.digits_task)")  # fmt: skip
        else:
            S, width = p.samples, 2
        route, propagated, cost = _training(self, skipped, S, width)
        integ = self.integrator
        kind = f"{integ.activation}{'' if integ.residual else '_plain'}"
        kernels: tuple[str, ...] = (f"discrete_control.resnet_step_{kind}",)
        if steps > 0 or "costates" in self.effects:
            kernels += (f"discrete_control.resnet_adjoint_{kind}",)
        index: dict[str, tuple[int, ...]] = {}
        for name, when in self.observables.items():
            if name == "loss" and when.every is not None:
                index[name] = tuple(range(0, steps + 1, when.every))
            else:
                index[name] = (steps,)
        return SystemPlan(route=route, propagated=propagated, kernels=kernels,
                          save={"steps": steps}, index=index, cost=cost, modules=modules)  # fmt: skip

    def _run(self, plan: Plan, x: dict[str, Any]) -> tuple[dict[str, Array], dict[str, Array], str]:
        integ: Any = self.integrator
        act, res = integ.activation, integ.residual
        steps = self.horizon.steps
        K, beta = x["K0"], x["beta0"]
        losses = None
        if steps > 0 and isinstance(integ, ExtendedMSA):
            tr = train_msa(x["x0"], x["targets"], K, beta, steps=steps, rho=integ.rho,
                           inner_steps=integ.inner_steps, inner_lr=integ.inner_lr, activation=act,
                           residual=res)  # fmt: skip
            K, beta, losses = tr.K, tr.beta, tr.losses
        elif steps > 0:
            tr = train(x["x0"], x["targets"], K, beta, steps=steps, lr=integ.lr, activation=act,
                       residual=res)  # fmt: skip
            K, beta, losses = tr.K, tr.beta, tr.losses
        kept: list[Array] = []

        def states() -> Array:
            """The trained network's forward pass, run once and only for the observables that
            read it (the digits' accuracy runs its own, on resnet_predict)."""
            if not kept:
                kept.append(resnet_forward(x["x0"], K, beta, act, res))
            return kept[0]

        data: dict[str, Any] = {}
        times: dict[str, Array] = {}
        for name, idx in plan.index.items():
            times[name] = np.asarray(idx, dtype=float)
            if name == "loss":
                data[name] = (losses[list(idx)] if losses is not None else
                              np.array([squared_error(states()[-1], x["targets"])]))  # fmt: skip
            else:
                data[name] = _final(name, x, K, beta, act, res, states)
        return times, data, ""


def _final(
    name: str, x: dict[str, Any], K: Array, beta: Array, act: str, res: bool, states: Any
) -> Array:
    """An observable of the final network (``states()``: its forward pass, run once)."""
    if name == "states":
        return states()[None]
    if name == "K":
        return K[None]
    if name == "beta":
        return beta[None]
    if name == "accuracy" and "classes" in x:
        guess = resnet_predict(x["x0"], K, beta, x["classes"], act, res)
        return np.array([np.mean(guess == x["labels"])])
    if name == "accuracy":
        return np.array([np.mean(np.sign(states()[-1][:, 1]) == x["labels"])])
    if name == "test_accuracy":
        guess = resnet_predict(x["x_test"], K, beta, x["classes"], act, res)
        return np.array([np.mean(guess == x["labels_test"])])
    return costate_sweep(states(), K, beta, x["targets"], act, res)[None]


def _check_records(sc: ResNetScene) -> None:
    """Only the final network is kept; the loss is recorded per gradient step."""
    for name, when in sc.observables.items():
        if name != "loss" and not when.end:
            raise _problem(f"observables.{name}", "only the final network is kept: record "
                           f"{name} at the end", ["end"])  # fmt: skip
        if name == "loss" and not (when.end or when.every is not None):
            raise _problem(f"observables.{name}", "the loss is recorded per gradient step",
                           ["end", "every"])  # fmt: skip


def _training(
    sc: ResNetScene, skipped: list[tuple[str, str]], S: int, width: int
) -> tuple[str, tuple[str, ...], dict[str, Any]]:
    """The route, the state and the cost of the training (or of the forward pass alone), on
    ``S`` samples of width ``width``."""
    integ: Any = sc.integrator
    steps, L = sc.horizon.steps, sc.parameters.layers
    flops_ls = 2.0 * width**2 + 16.0 * width  # a layer on one sample (K x, tanh, the sum)
    per = L * S * (4e-7 + 2.6e-9 * (width**2 - 4)) + L * 2e-5
    trained = ("states x_k", "costates p_k", "weights K, beta")
    if steps > 0 and isinstance(integ, ExtendedMSA):
        inner = integ.inner_steps
        route = (f"symrb.train_msa(steps={steps}, rho={integ.rho:g}, inner_steps={inner}, "
                 f"inner_lr={integ.inner_lr:g}, activation={integ.activation!r}): an "
                 f"iteration is a forward pass, a costate sweep and {inner} gradient-ascent "
                 "steps per layer on the augmented Hamiltonian (states and costates "
                 "frozen)")  # fmt: skip
        propagated: tuple[str, ...] = trained
        cost = {"flops": (2 + 2 * inner) * steps * L * S * flops_ls,
                "seconds": (2 + 2 * inner) * steps * per,
                "formula": f"{steps} x (forward + costate sweep + {inner} x (layer + "
                f"adjoint)) of {L} layers x {S} samples"}  # fmt: skip
    elif steps > 0:
        route = (f"symrb.train(steps={steps}, lr={integ.lr:g}, "
                 f"activation={integ.activation!r}): a forward pass and a costate sweep a "
                 "step")  # fmt: skip
        propagated = trained
        cost = {"flops": 2 * steps * L * S * flops_ls, "seconds": 2 * steps * per,
                "formula": f"{steps} x (forward + costate sweep) of {L} layers x {S} "
                "samples"}  # fmt: skip
    else:
        route = "symrb.learning.resnet_forward (no training)"
        propagated = ("states x_k",)
        skipped.append(("costate sweep", "no training steps" if "terminal_cost" in sc.effects
                        else "no terminal cost: nothing to back-propagate"))  # fmt: skip
        cost = {
            "flops": L * S * flops_ls,
            "seconds": per,
            "formula": f"one forward pass of {L} layers x {S} samples",
        }
    if "costates" in sc.effects:
        route += "; symrb.learning.costate_sweep at the end"
    return route, propagated, cost
