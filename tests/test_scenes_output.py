"""What ``symrb run --plot`` draws and what a sweep table holds: the invariants as relative drift
on a log axis with a legend naming each, and a ``*_drift`` column only for an observable recorded
as a time series."""

from __future__ import annotations

import numpy as np
import pytest

import symrb
from symrb.scenes import parse_scene, run_scene, scene_inputs, sweep

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")

SCENE = {
    "system": "rigid_body",
    "parameters": {"n": 4, "seed": 2},
    "integrator": {"method": "DOP853", "rtol": 1e-8, "atol": 1e-10},
    "horizon": {"T": 4.0},
    "observables": {
        "energy": {"points": 9},
        "casimirs": {"points": 9},
        "manakov": {"points": 9, "windows": 4, "reduce": "max_rel_change"},
        "Omega": {"points": 5},
        "M": "end",
    },
}


def test_plot_draws_the_relative_drift_of_each_invariant() -> None:
    """The first panel: one line per component of energy and Casimirs, equal to
    |I(t) - I(0)| / |I(0)| of a hand-written evaluation on the recorded M (plain NumPy traces),
    the windowed Manakov drifts as recorded; log axis, labelled axes, every line in the legend.
    M, recorded at the end only, is not drawn; Omega, no invariant, has a panel of its own."""
    scene = parse_scene({**SCENE, "observables": {**SCENE["observables"], "M": {"points": 9}}})
    r = run_scene(scene, cache=False)
    M, lam = r["M"], scene_inputs(scene)["lam"]
    Om = M * (1.0 / (lam[:, None] + lam[None, :]))  # Omega_ij = M_ij / (lam_i + lam_j)
    energy = -0.25 * np.einsum("kij,kji->k", M, Om)
    traces = np.stack([np.trace(np.linalg.matrix_power(M, p), axis1=1, axis2=2)
                       for p in (2, 4, 6)], axis=1)  # fmt: skip
    fig = run_scene(parse_scene(SCENE), cache=False).plot()
    drift_ax, *others = fig.axes
    assert drift_ax.get_yscale() == "log"
    assert drift_ax.get_xlabel() == "t" and "I(0)" in drift_ax.get_ylabel()
    lines = {ln.get_label(): ln for ln in drift_ax.get_lines()}
    legend = [t.get_text() for t in drift_ax.get_legend().get_texts()]
    assert sorted(legend) == sorted(lines) and len(lines) == 1 + 3 + 6
    assert lines["energy"].get_ydata()[0] != lines["energy"].get_ydata()[0]  # 0 at t = 0: NaN
    expected = {"energy": energy[:, None], "casimirs": traces}
    for name, values in expected.items():
        rel = np.abs(values - values[0]) / np.abs(values[0])
        mine = [ln for label, ln in lines.items() if label.startswith(name)]
        assert len(mine) == values.shape[1]
        for j, ln in enumerate(mine):
            np.testing.assert_allclose(ln.get_ydata()[1:], rel[1:, j], rtol=1e-6, atol=1e-15)
    windowed = [ln for label, ln in lines.items() if "per window" in label]
    assert len(windowed) == 6
    for j, ln in enumerate(windowed):
        np.testing.assert_array_equal(ln.get_xdata(), r.times["manakov"])
        np.testing.assert_array_equal(ln.get_ydata(), np.abs(r["manakov"][:, j]))
    assert len(others) == 1 and others[0].get_ylabel() == "Omega"
    assert others[0].get_xlabel() == "t"


def test_plot_of_nothing_but_end_values_is_an_input_error() -> None:
    scene = parse_scene({**SCENE, "observables": {"M": "end", "energy": "end"}})
    with pytest.raises(symrb.InputError, match="time series"):
        run_scene(scene, cache=False).plot()


def test_sweep_drift_columns_only_for_time_series() -> None:
    """energy recorded at the end only, or reduced per window: its value, no drift column;
    recorded at 9 times: a drift column, its largest change from the first record."""
    grid = ["parameters.seed=1,2"]
    for when in ("end", {"points": 9, "windows": 3, "reduce": "max_rel_change"}):
        scene = parse_scene({**SCENE, "observables": {"energy": when}})
        out = sweep(scene, grid, cache=False, progress=False)
        assert "energy" in out.table and "energy_drift" not in out.table, (when, list(out.table))
    out = sweep(parse_scene({**SCENE, "observables": {"energy": {"points": 9}}}), grid,
                cache=False, progress=False)  # fmt: skip
    for row, r in zip(out.table.itertuples(), out.results, strict=True):
        assert row.energy_drift == np.max(np.abs(r["energy"] - r["energy"][0])) > 0
