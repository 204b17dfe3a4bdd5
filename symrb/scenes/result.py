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
        """A matplotlib figure: each recorded observable (flattened per record) against time."""
        import matplotlib.pyplot as plt

        names = list(names or self.data)
        fig, axes = plt.subplots(len(names), 1, figsize=(6.4, 2.2 * len(names)), squeeze=False,
                                 sharex=False)  # fmt: skip
        for ax, name in zip(axes[:, 0], names, strict=True):
            t = self.times[name]
            y = np.asarray(self.data[name]).reshape(len(t), -1)
            if np.iscomplexobj(y):
                y = y.imag
            ax.plot(t, y[:, : min(y.shape[1], 12)], ".-" if len(t) < 30 else "-", lw=1)
            ax.set_ylabel(name)
        axes[-1, 0].set_xlabel(type(self.scene).RECORD_AXIS)
        fig.suptitle(self.scene.title or self.scene.system)
        fig.tight_layout()
        return fig
