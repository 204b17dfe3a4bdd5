"""Tests of the book's own code (``book/lib/symrb_book``): the computations of the conventions,
Section 2 and Section 3 pages that are not scenes.

Each test calls the function its page calls (with smaller sizes where the page's run is long) and
judges the numbers against a reference stated here: a closed form, a theoretical order, a bound of
float64 arithmetic, an exact value (a conserved quantity, zero for two descriptions of one
motion), or the integrator's tolerance, never against a spread that the experiment computes
itself.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from symrb_book import discrete, smooth

from symrb import InputError

EPS = np.finfo(float).eps


def test_time_step_scaling_is_second_order_with_the_predicted_term():
    run = discrete.time_step_scaling()
    assert np.all(np.abs(run.order - 2) < 0.01)
    # J_D(exp(h Om)) - h J(Om) = h^2/2 (Om^2 Lam - Lam Om^2) + O(h^3): the leading term, written
    # with an explicit diagonal matrix
    L = np.diag(run.lam)
    O2 = run.Omega @ run.Omega
    c2 = np.linalg.norm(O2 @ L - L @ O2) / 2
    assert run.error[-1] / run.h[-1] ** 2 == pytest.approx(c2, rel=1e-3)
    assert run.leading == pytest.approx(c2, rel=1e-12)


def test_layer_jacobian_residual_tends_to_identity_plain_to_zero():
    run = discrete.layer_jacobian()
    small = run.scale <= 1e-2
    # residual layer: dF/dx - I = diag(tanh') eps K_1, linear in eps (slope 1 on log-log axes)
    slope = np.polyfit(np.log(run.scale[small]), np.log(run.residual_gap[small]), 1)[0]
    assert slope == pytest.approx(1.0, abs=0.01)
    assert run.residual_gap[0] < 1e-3
    # plain layer: dF/dx = diag(tanh') eps K_1 -> 0, so dF/dx - I -> -I, of max entry 1
    assert run.plain_gap[small] == pytest.approx(1.0, abs=0.02)


def test_trace_maximum_reaches_the_closed_form_value():
    run = discrete.trace_maximum()
    s = np.linalg.svd(run.A, compute_uv=False)
    # max over SO(n) of tr(AU): the sum of the singular values, the smallest taken with the sign
    # of det A (von Neumann's trace inequality)
    best = s[:-1].sum() + np.sign(np.linalg.det(run.A)) * s[-1]
    assert run.value_search == pytest.approx(best, rel=1e-10)
    assert run.value_closed == pytest.approx(best, rel=1e-12)
    for U in (run.U_search, run.U_closed):
        assert np.abs(U.T @ U - np.eye(U.shape[0])).max() < 1e-12
        assert np.linalg.det(U) == pytest.approx(1.0, abs=1e-12)
    assert run.asymmetry < 1e-6  # AU symmetric at a critical point


def test_solver_accuracy_meets_its_documented_tolerance():
    run = discrete.solver_accuracy(sizes=(2, 3, 5, 8, 20))
    # the solver's tolerance: ||J_D(U) - M||_F <= 10 eps ||M||_F
    assert run.residual.max() <= 10
    assert np.all(run.orthogonality <= 10 * run.n)
    assert np.all(np.abs(run.det_error) < 100 * run.n * EPS)
    assert np.all(run.margin > 0)
    for nn in np.unique(run.n):
        margins = run.margin[run.n == nn]
        assert margins[-1] < margins[0]  # the margin closes towards the fold


def test_fold_approach_has_the_square_root_law():
    run = discrete.fold_approach()
    # at a fold the branch closes like the square root of the distance
    assert run.exponent == pytest.approx(0.5, abs=0.02)
    near = run.distance < 1e-5
    slope = np.polyfit(np.log(run.distance[near]), np.log(run.sigma_min[near]), 1)[0]
    assert slope == pytest.approx(0.5, abs=0.02)
    assert run.residual.max() <= 10 and run.iterations.max() <= 4
    assert "past the fold" in run.past_fold


def test_solver_cost_records_cpu_time_per_repeat():
    run = discrete.solver_cost(sizes=(3, 50), repeats=3, inner=2)
    assert run.cold_ms.shape == run.warm_ms.shape == (2, 3)
    assert np.all(run.cold_ms > 0) and np.all(run.warm_ms > 0)
    assert np.all(run.cold_ms.min(axis=1) <= run.cold_median)
    assert np.all(run.cold_median <= run.cold_ms.max(axis=1))
    assert run.cold_median[1] > run.cold_median[0]  # an O(n^3) solve: n = 50 costs more
    assert run.pinned  # threadpoolctl comes with the test extra


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: discrete.time_step_scaling(halvings=1), "halvings"),
        (lambda: discrete.layer_jacobian(scales=[0.0, 1.0]), "scales"),
        (lambda: discrete.solver_accuracy(fractions=(1.5,)), "fractions"),
        (lambda: discrete.fold_approach(distances=[0.5]), "distances"),
        (lambda: discrete.solver_cost(repeats=0), "repeats"),
    ],
)
def test_bad_arguments_are_named(call, match):
    with pytest.raises(InputError, match=match):
        call()


def test_mclachlan_scovel_map() -> None:
    run = smooth.mclachlan_scovel_map(T=10.0, samples=51)
    assert run.skew_defect.max() < 1e-12  # Q^T B stays skew: exactly, up to rounding
    assert run.gap.max() < 1e-9  # rtol 1e-12 over t <= 10


def test_shared_control_is_the_rigid_body_velocity() -> None:
    run = smooth.shared_control(T=5.0)
    assert run.gap.max() < 1e-9


def test_momentum_norms_bound_and_distribution() -> None:
    run = smooth.momentum_norms(count=4000)
    assert run.norms.max() <= 2 + 1e-12
    # n = 3: Q^T P is a Haar rotation, its angle has the density (1 - cos a)/pi on [0, pi] and
    # ||M||_op = 2 |sin a|, of mean 4/pi and variance 2 - 16/pi^2
    n3 = run.norms[run.sizes.index(3)]
    mean, sd = 4 / np.pi, np.sqrt(2 - 16 / np.pi**2)
    assert abs(n3.mean() - mean) < 4 * sd / np.sqrt(n3.size)
    assert n3.max() > 1.99  # the bound 2 is approached


def test_rotation_angles_are_arcsin() -> None:
    theta = np.linspace(0.0, 3.0, 61)
    run = smooth.rotation_angles(theta)
    np.testing.assert_array_equal(run.refused, theta >= 2)
    inside = theta < 2
    np.testing.assert_allclose(
        run.angle[inside], np.arcsin(theta[inside] / 2), rtol=0, atol=4 * EPS
    )
    assert np.all(np.isnan(run.angle[~inside]))
    with pytest.raises(InputError, match="theta"):
        smooth.rotation_angles([-1.0])


def test_boundary_accuracy_is_as_conditioned() -> None:
    run = smooth.boundary_accuracy([1e-1, 1e-4, 1e-8, 1e-12, 1e-15], n=5)
    assert run.residual.max() < 5e-15 and run.orthogonality.max() < 5e-15
    # the forward error is set by the conditioning of the problem, eps / sqrt(delta)
    assert np.all(run.forward_error <= 10 * run.eps_over_sqrt_delta), run.forward_error
    assert run.forward_error[-1] > 100 * run.forward_error[0]  # and does grow near the boundary


# ---------------------------------------------------------------------------------------------
# the scene reference (book/lib/symrb_book/scene_reference.py)


def test_scene_reference_examples_parse_and_show_every_integrator_key():
    from symrb_book import scene_reference as ref

    from symrb.scenes import describe_schema, load_scene

    for system in ref.PAGES["scene_reference"] + ref.PAGES["scene_reference_learning"]:
        load_scene(ref.example(system))
        forms = ref.integrator_examples(system)
        variants = {k.variant for k in describe_schema(system) if k.table == "integrator"}
        assert set(forms) == variants
        for form, line in forms.items():
            keys = [k for k in describe_schema(system) if k.variant == form]
            shown = [k.key for k in keys if k.default != "(not set)" or k.allowed]
            assert all(f"{key} = " in line for key in shown), (form, line)


def test_scene_reference_pages_list_every_system_once(monkeypatch):
    from symrb_book import scene_reference as ref

    text = ref.page("scene_reference_bodies")
    assert "## `symmetric_rigid_body`" in text and "## `mclachlan_scovel`" in text
    monkeypatch.setitem(ref.PAGES, "scene_reference_orbits", ("double_bracket", "orbit_extremal"))
    with pytest.raises(AssertionError, match="exactly one page"):
        ref.page("scene_reference")  # toda is on no page
    monkeypatch.setitem(ref.PAGES, "scene_reference_orbits", ("double_bracket", "toda", "toda"))
    with pytest.raises(AssertionError, match="exactly one page"):
        ref.page("scene_reference")


def test_scene_reference_table_marks_required_keys_and_escapes_pipes():
    from symrb_book import scene_reference as ref

    from symrb.scenes import describe_schema

    rows = ref.table(k for k in describe_schema("rigid_body") if k.variant == 'method = "mv"')
    assert "| `integrator.h` | float > 0 | required |  |" in rows
    assert "| `integrator.order` | integer | `2` | `2`, `4`, `6`, `8`, `10` |" in rows
    assert ref.myst(":func:`symrb.simulate` at ``h``, :math:`x^2`") == (
        "{py:func}`symrb.simulate` at `h`, $x^2$"
    )


def test_evidence_summary_shows_each_check_and_whether_it_is_as_recorded():
    from types import SimpleNamespace

    from symrb_book.start import evidence_summary

    checks = [
        SimpleNamespace(level="float64", form="claim", residual=3e-15, tol=1e-12, as_expected=True),
        SimpleNamespace(
            level="float64", form="printed", residual=None, tol=1e-12, as_expected=False
        ),  # fmt: skip
    ]
    text = evidence_summary(SimpleNamespace(evidence=checks))
    assert "| 1 | float64 | claim | 3.0e-15 | 1e-12 | yes |" in text
    assert "| 2 | float64 | printed | error | 1e-12 | no |" in text


# one style per method, in every figure


def test_method_styles_have_distinct_colours():
    from matplotlib.colors import to_rgb
    from symrb_book.style import METHOD_STYLE, SERIES_STYLE

    table = {**METHOD_STYLE, **SERIES_STYLE}
    rgb = {name: np.array(to_rgb(s["color"])) for name, s in table.items()}
    names = list(rgb)
    for i, a in enumerate(names):
        for b in names[i + 1 :]:
            # no two methods (or other series) share a colour, nor come within 0.1 in RGB
            assert np.linalg.norm(rgb[a] - rgb[b]) > 0.1, (a, b)


def test_every_method_of_symrb_the_benchmark_and_the_paper_has_a_style():
    from symrb_book.style import canonical, method_style

    from benchmarks.harness.config import ALL_METHODS
    from symrb.rigid_body import METHODS

    for name, method in METHODS.items():
        for order in method.orders or (None,):
            style = method_style(name, order)
            assert {"color", "marker", "ls"} <= set(style), name
    for name in (*ALL_METHODS, "mv_algorithm1", "mv_algorithm2", "symmetric_flow",
                 "discrete_rigid_body_flow"):  # fmt: skip
        canonical(name)
    # one method, one look, under each of its names
    assert method_style("mv", 10) == method_style("MV-pre10")
    assert method_style("mv") == method_style("mv_flow") == method_style("MV-fast")
    assert method_style("composition", 6) == method_style("MV-comp6")
    assert method_style("discrete_rigid_body_flow") == method_style("MV")
    with pytest.raises(InputError, match="no style"):
        method_style("Euler")


def test_work_precision_panels_use_the_style_and_stay_above_the_floor():
    import matplotlib

    matplotlib.use("Agg")
    from pathlib import Path

    import matplotlib.pyplot as plt
    from matplotlib.colors import to_hex
    from symrb_book import accuracy
    from symrb_book.style import METHOD_STYLE, series_of

    from benchmarks.harness import load

    full = load(Path(__file__).resolve().parents[1] / "benchmarks" / "results" / "bench.json")
    # as the pages draw them: a group none of whose methods ran in a setting is left out
    panels = [((w["n"], w["T"]), group) for w in accuracy.settings(full)
              for _, group in accuracy.APPENDIX_GROUPS
              if accuracy.available(w, group)] + list(accuracy.MAIN_PANELS)  # fmt: skip
    for ncols, chosen in ((3, panels[:-2]), (2, panels[-2:])):
        fig, clipped = accuracy.work_precision(full, chosen, ncols=ncols)
        assert clipped == 0
        assert len(fig.legends) == 1  # one legend, below the panels
        for ax, ((n, T), _group) in zip(fig.axes, chosen, strict=False):
            assert ax.get_legend() is None
            floor = accuracy.setting(full, n, T)["reference_error_estimate"]
            # errorbar: data line; a label names its method ("DOP853 (lean field)" is DOP853's)
            series = {c.get_label(): c.lines[0] for c in ax.containers}
            assert 0 < len(series) <= accuracy.MAX_SERIES
            for label, line in series.items():
                name = series_of(label)
                assert to_hex(line.get_color()) == to_hex(METHOD_STYLE[name]["color"]), label
                assert line.get_marker() == METHOD_STYLE[name]["marker"], label
                # SciPy on the generated field: dotted and hollow; everything else as the table
                gen = label.endswith("(generated field)")
                assert line.get_linestyle() == (
                    ":" if gen else {"--": "--", "-": "-"}[METHOD_STYLE[name]["ls"]]
                )
                assert min(line.get_xdata()) >= floor  # nothing below the reference's error
        plt.close(fig)
    with pytest.raises(InputError, match="at most 6"):
        accuracy.work_precision(full, [((3, 10.0), tuple(METHOD_STYLE)[:7])])


#: Words that make a plotted series a method's.
_METHOD_WORDS = ("DOP853", "RK45", "LSODA", "Radau", "BDF", "mv_flow", "mv_algorithm", "MV-",
                 "RKMK4", "rkmk4", "symmetric vs", "gradient descent", "MSA", "shooting")  # fmt: skip


def test_book_figures_of_methods_take_their_style_from_the_table():
    """A code cell of a book page that labels a plotted series with a method's name draws it
    with ``symrb_book.style`` (``method_style``, or the accuracy module that uses it)."""
    import re
    from pathlib import Path

    book = Path(__file__).resolve().parents[1] / "book"
    checked = []
    for page in sorted(book.rglob("*.md")):
        if "_build" in page.parts:
            continue
        cells = re.findall(r"```\{code-cell\}.*?\n(.*?)```", page.read_text(), flags=re.S)
        for cell in cells:
            labels = re.findall(r"label=([^,)\n]*(?:\n[^,)\n]*)?)", cell)
            if any(word in label for label in labels for word in _METHOD_WORDS) or any(
                label.strip() == "method" for label in labels
            ):
                assert "method_style(" in cell, (page.name, cell[:200])
                checked.append(page.name)
            if "work_precision(" in cell:
                checked.append(page.name)
    assert {"hard_cases.md", "04_moser_veselov_runs.md", "accuracy.md"} <= set(checked), checked


class _Run(dict):
    """A scene result as the learning figures read it: records by name, their times."""

    def __init__(self, **records):
        super().__init__((k, np.asarray(v, dtype=float)) for k, v in records.items())
        self.times = {k: np.arange(len(v), dtype=float) for k, v in self.items()}


def _book_figures():
    """Every figure of the book that draws methods (by the functions its pages call), by name,
    on the recorded benchmarks and on made-up training runs."""
    import json

    from symrb_book import accuracy, learning

    from benchmarks.harness import load

    results = Path(__file__).resolve().parents[1] / "benchmarks" / "results"
    full = load(results / "bench.json")
    training = json.loads((results / "learning.json").read_text())["training"]
    run = _Run(loss=[3.0, 2.0, 1.5], residual=[1.0, 1e-3, 1e-9])
    so_runs = {"gradient descent": run, "extended MSA": run, "shooting": run}
    return {
        "throughput": accuracy.bench_figure(full, "throughput"),
        "cost_vs_n": accuracy.bench_figure(full, "cost_vs_n"),
        "so training": learning.so_training_figure(so_runs, {"shooting": "extremals"}, 1.0),
        "resnet loss": learning.loss_figure(dict(list(so_runs.items())[:2]), {}, "t"),
        "training time": learning.training_time_figure(training),
    }


def test_every_figure_draws_each_method_in_the_colour_of_the_style_table():
    """Each labelled line and bar of a figure of the book that draws methods is named by the
    style table (its label's head, :func:`series_of`) and drawn in that name's colour: a method
    looks the same in every figure."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import to_hex
    from symrb_book.style import METHOD_STYLE, SERIES_STYLE, series_of

    table = {**METHOD_STYLE, **SERIES_STYLE}
    wrong, seen = [], set()
    for name, fig in _book_figures().items():
        for ax in fig.axes:
            artists = [(line.get_label(), line.get_color()) for line in ax.get_lines()]
            artists += [(c.get_label(), p.get_facecolor()) for c in ax.containers for p in c]
            for label, colour in artists:
                if label.startswith("_"):
                    continue  # unlabelled: not a series
                key = series_of(label)
                seen.add(key)
                if to_hex(colour) != to_hex(table[key]["color"]):
                    wrong.append(f"{name}: {label!r} in {to_hex(colour)}, {key} is "
                                 f"{table[key]['color']}")  # fmt: skip
        plt.close(fig)
    assert not wrong, "\n".join(wrong)
    assert {"MV-fast", "matmul", "gradient descent", "extended MSA", "shooting"} <= seen


def test_series_styles_keep_their_colour():
    from symrb_book.style import SERIES_STYLE, series_of, series_style

    assert series_style("matmul", marker="o") == {**SERIES_STYLE["matmul"], "marker": "o"}
    assert series_style("mv_flow", ls=":")["color"] == series_style("MV-fast")["color"]
    assert series_of("mv_flow (NumPy path)") == series_of("MVStepper.step (one call)") == "MV-fast"
    assert series_of("gradient descent (Cayley, Armijo)") == "gradient descent"
    with pytest.raises(InputError, match="keeps the colour"):
        series_style("matmul", color="red")
    with pytest.raises(InputError, match="no style"):
        series_of("Euler (forward)")


def test_tex_sci_writes_powers_of_ten_that_typeset_as_one_number() -> None:
    from symrb_book.display import tex_sci

    assert tex_sci(3.2e-16) == r"3.2\times10^{-16}"
    assert tex_sci(-1.25e7, 2) == r"-1.25\times10^{7}"
    assert tex_sci(4.0) == "4.0"  # no factor 10^0
    assert "e" not in tex_sci(9.99e-300).replace("times", "")  # never the e-notation of Python


def test_md_table_escapes_each_pipe_once() -> None:
    from symrb_book.display import md_table

    text = md_table(["a", "b"], [("|x|", r"already \| escaped")])
    assert text.splitlines() == ["| a | b |", "|---|---|", r"| \|x\| | already \| escaped |"]


def test_page_titles_have_no_math() -> None:
    """A page's title is shown in the sidebar of every page, also on pages that load no MathJax,
    where math in it stays raw TeX (the browser test caught it on 25 pages): titles are words."""
    book = Path(__file__).resolve().parents[1] / "book"
    titled = []
    for page in book.rglob("*.md"):
        if "_build" in page.parts:
            continue
        in_code = False
        for line in page.read_text().splitlines():
            if line.startswith("```"):
                in_code = not in_code
            elif not in_code and line.startswith("# ") and "$" in line:
                titled.append((page.relative_to(book), line))
    assert not titled, titled
