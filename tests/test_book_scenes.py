"""The book's simulated figures come from scenes: every scene in book/scenes/ is used by a page,
parses and explains its plan, and each page below reads its figure's data from its scene through
``symrb.scenes.run_scene`` (or ``sweep``) instead of computing it with an experiment function."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from symrb.scenes import load_scene, plan_scene

ROOT = Path(__file__).resolve().parents[1]
BOOK = ROOT / "book"
SCENES = sorted((BOOK / "scenes").glob("*.toml"))

#: page -> (the scene its simulated figure uses, or a tuple of the scenes of its figures and
#: tables; the experiment functions it no longer calls)
PAGES: dict[str, tuple[str | tuple[str, ...], tuple[str, ...]]] = {
    "rigid_body_lax.md": ("manakov_drift", ("manakov_drift(",)),
    "section2/02b_residual_layers.md": ("toy_training", ("train_toy_classifier(",)),
    "section2/04_moser_veselov_runs.md": (
        (
            "mv_invariants",
            "agreement_symmetric",
            "agreement_mv1",
            "agreement_discretisation",
            "second_order",
        ),
        ("invariant_drift(", "algorithm_agreement(", "second_order("),
    ),
    "section3/02c_norm_casimir.md": (
        ("norm_conservation", "norm_conservation_boundary"),
        ("norm_conservation(",),
    ),
    "section3/01_optimal_control.md": ("symmetric_vs_rigid_body", ("flow_agreement(",)),
    "scenes.md": ("rigid_body_momentum", ()),
    "section3/03_hamiltonian.md": (
        ("hamiltonian_on_so", "hamiltonian_on_gl"),
        ("hamiltonian_drift(",),
    ),
    "section3/04c_toda_lattice.md": ("toda_lattice", ("toda_lattice(",)),
    "section3/05b_orbit_experiments.md": (
        ("orbit_one_sample", "orbit_two_samples_shared"),
        ("one_sample_learning(", "two_sample_learning("),
    ),
    "hard_cases.md": (
        "long_run_spread1e6_n3",
        ("symrb.engine.mv_flow(np.eye", "symrb.mv_algorithm2(np.eye"),
    ),
    "learning.md": (
        ("so_training_gradient", "so_training_msa", "so_training_shooting"),
        ("train_so_gradient(", "train_so_msa(", "train_so_shooting("),
    ),
    "learning_resnet.md": (
        ("resnet_digits_gd", "resnet_digits_msa"),
        ("learning.train(", "train_msa("),
    ),
}


def _pages() -> dict[str, str]:
    return {str(p.relative_to(BOOK)): p.read_text() for p in BOOK.rglob("*.md")
            if "_build" not in p.parts}  # fmt: skip


@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.name)
def test_every_book_scene_is_used_by_a_page_and_explains_its_plan(path: Path) -> None:
    used = [name for name, text in _pages().items()
            if f"{path.stem}.toml" in text or re.search(rf'run\("{path.stem}"\)', text)]  # fmt: skip
    assert used, f"{path.name} is used by no page of the book"
    text = plan_scene(load_scene(path)).explain()
    assert "propagated" in text and "record" in text and "cost" in text
    assert path.read_text().lstrip().startswith("#"), f"{path.name} needs a comment header"


@pytest.mark.parametrize("page", sorted(PAGES))
def test_page_reads_its_figure_from_its_scene(page: str) -> None:
    names, gone = PAGES[page]
    text = (BOOK / page).read_text()
    cells = re.findall(r"```\{code-cell\}[^\n]*\n(.*?)```", text, flags=re.S)
    code = "\n".join(cells)
    assert re.search(r"\b(scenes\.run_scene|scenes\.sweep|run)\(", code), page
    # every scene is named in a code cell and run there, and its rerun path is in the prose
    for scene in (names,) if isinstance(names, str) else names:
        assert (BOOK / "scenes" / f"{scene}.toml").is_file()
        named = f'"{scene}.toml"' in code or f'run("{scene}")' in code
        assert named, f"{page} does not name book/scenes/{scene}.toml in a code cell"
        assert f"book/scenes/{scene}.toml" in text, f"{page} does not give the rerun command"
    for call in gone:
        assert call not in code, f"{page} still computes its figure with {call[:-1]}"
