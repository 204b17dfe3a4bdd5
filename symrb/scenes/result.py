"""The outcome of a scene run: :class:`SceneResult` (the arrays, the scene, the plan, the
versions), written to and read from a directory (``arrays.npz`` and ``scene.json``)."""

from __future__ import annotations

import dataclasses
import json
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .._validate import Array
from ..errors import InputError
from .parse import parse_scene
from .plan import Plan, _json_default, plan_scene


@dataclasses.dataclass
class SceneResult:
    """The outcome of :func:`run_scene`.

    Attributes
    ----------
    scene : Scene
        The scene that was run.
    plan : Plan
        Its plan.
    times : dict of ndarray
        Observable -> the times (training steps for the ResNet) of its records.
    data : dict of ndarray
        Observable -> its records, the record axis first.
    meta : dict
        ``key`` (the cache key), ``versions``, ``seconds`` (compute time of the first run),
        ``from_cache``, ``success`` and ``message``.

    Examples
    --------
    >>> from symrb.scenes import parse_scene, run_scene
    >>> scene = parse_scene({"system": "rigid_body", "integrator": {"method": "DOP853"},
    ...                      "horizon": {"T": 10.0}, "observables": {"energy": {"points": 3}}})
    >>> r = run_scene(scene, cache=False)
    >>> r.times["energy"], r["energy"].shape
    (array([ 0.,  5., 10.]), (3,))
    """

    scene: Any
    plan: Plan
    times: dict[str, Array]
    data: dict[str, Array]
    meta: dict[str, Any]

    def __getitem__(self, name: str) -> Array:
        try:
            return self.data[name]
        except KeyError:
            raise KeyError(f"scene recorded {list(self.data)}, not {name!r}") from None

    def metadata(self) -> dict[str, Any]:
        """The JSON side of the result: the scene, the plan, the versions and ``meta``."""
        return {"scene": self.scene.model_dump(mode="json"), "plan": self.plan.to_dict(),
                "meta": self.meta}  # fmt: skip

    def save(self, directory: str | os.PathLike[str]) -> Path:
        """Write ``arrays.npz`` and ``scene.json`` into ``directory`` (created); returns it."""
        d = Path(directory)
        d.mkdir(parents=True, exist_ok=True)
        arrays = {f"data/{k}": a for k, a in self.data.items()}
        arrays.update({f"times/{k}": a for k, a in self.times.items()})
        np.savez(d / "arrays.npz", **arrays)  # type: ignore[arg-type]
        (d / "scene.json").write_text(json.dumps(self.metadata(), indent=1,
                                                 default=_json_default) + "\n")  # fmt: skip
        return d

    @classmethod
    def load(
        cls, directory: str | os.PathLike[str], scene: Any = None, plan: Plan | None = None
    ) -> SceneResult:
        """Read a result written by :meth:`save` (``scene`` and ``plan``, when the caller has
        them, are used instead of validating and planning the stored scene again)."""
        d = Path(directory)
        meta = json.loads((d / "scene.json").read_text())
        if scene is None:
            scene = parse_scene(meta["scene"])
        with np.load(d / "arrays.npz") as z:
            data = {k[5:]: z[k] for k in z.files if k.startswith("data/")}
            times = {k[6:]: z[k] for k in z.files if k.startswith("times/")}
        return cls(scene, plan or plan_scene(scene), times, data, dict(meta["meta"]))

    def plot(self, names: Sequence[str] | None = None) -> Any:
        """A matplotlib figure of the observables recorded as time series (those recorded at
        one time only are left out).

        The invariants of the system (``INVARIANTS`` of its scene class: energy, Casimirs,
        Manakov's integrals, spectra) share the first panel as their relative drift
        :math:`|I(t) - I(0)| / |I(0)|` per component (the absolute drift where
        :math:`I(0) = 0`), on a log axis with a legend naming each; an invariant reduced per
        window by ``max_rel_change`` is that drift already and is drawn as recorded.  Each
        other observable gets a panel of its own, its components against the record axis.
        """
        import matplotlib.pyplot as plt

        invariants = type(self.scene).INVARIANTS
        series = [k for k in (names or self.data) if len(self.times[k]) > 1]
        drifts = [k for k in series if k in invariants and self._drift_kind(k)]
        others = [k for k in series if k not in drifts]
        panels = len(others) + bool(drifts)
        if not panels:
            raise InputError(f"no observable of {list(names or self.data)} has a time series "
                             "to plot (each was recorded at one time only)")  # fmt: skip
        fig, axes = plt.subplots(panels, 1, figsize=(8.4, 2.8 * panels + 0.6), squeeze=False)
        axis = type(self.scene).RECORD_AXIS
        if drifts:
            self._plot_drift(axes[0, 0], drifts, invariants)
        for ax, name in zip(axes[int(bool(drifts)) :, 0], others, strict=True):
            t = self.times[name]
            y = np.asarray(self.data[name]).reshape(len(t), -1)
            y = y.imag if np.iscomplexobj(y) else y
            shown = min(y.shape[1], 12)
            ax.plot(t, y[:, :shown], ".-" if len(t) < 30 else "-", lw=1)
            more = f" (first {shown} of {y.shape[1]} entries)" if y.shape[1] > shown else ""
            ax.set_ylabel(name)
            ax.set_title(f"{name}{more}", fontsize=9, loc="left")
        for ax in axes[:, 0]:
            ax.set_xlabel(axis)
        fig.suptitle(self.scene.title or self.scene.system)
        fig.tight_layout()
        return fig

    def _drift_kind(self, name: str) -> str:
        """How an invariant's records give its relative drift: "series" (unreduced), "windowed"
        (reduced by max_rel_change alone) or "" (reduced otherwise: not a drift)."""
        reductions = self.scene.observables[name].reductions
        if not reductions:
            return "series"
        return "windowed" if reductions == ("max_rel_change",) else ""

    def _plot_drift(self, ax: Any, names: Sequence[str], invariants: dict[str, Any]) -> None:
        """The relative drift of the invariants ``names`` on ``ax`` (log axis, legend)."""
        exact: list[str] = []
        for name in names:
            t = self.times[name]
            y = np.asarray(self.data[name]).reshape(len(t), -1)
            labels = list(invariants[name]) or [f"{name} {j + 1}" for j in range(y.shape[1])]
            if len(labels) != y.shape[1]:
                labels = [f"{name} {j + 1}" for j in range(y.shape[1])]
            windowed = self._drift_kind(name) == "windowed"
            if windowed:
                drift = np.abs(y)
            else:
                scale = np.abs(y[0])
                drift = np.abs(y - y[0]) / np.where(scale > 0, scale, 1.0)
                labels = [lab + (" (absolute: 0 at t = 0)" if s == 0 else "")
                          for lab, s in zip(labels, scale, strict=True)]  # fmt: skip
            for j, label in enumerate(labels):
                d = np.where(drift[:, j] > 0, drift[:, j], np.nan)
                if np.all(np.isnan(d[1:])):
                    exact.append(label)
                    continue
                prefix = "" if label.startswith(name) or label == name else f"{name}: "
                suffix = " (largest per window)" if windowed else ""
                ax.plot(t, d, ".-" if len(t) < 30 else "-", lw=1, label=prefix + label + suffix)
        ax.set_yscale("log")
        ax.set_ylabel("$|I(t) - I(0)|\\,/\\,|I(0)|$")
        ax.set_title("relative drift of the invariants" + (
            f"; exactly conserved (not drawn): {', '.join(exact)}" if exact else ""),
            fontsize=9, loc="left")  # fmt: skip
        if ax.get_lines():
            ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
