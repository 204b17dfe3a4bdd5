"""Build the wheel, install it into a clean virtual environment, and import symrb there.

Checks that the wheel holds ``symrb`` only (no ``derivations``, no ``benchmarks``), that the package works from it
with only its declared run-time dependencies (NumPy and SciPy, fetched by pip from the package
index), that neither importing symrb, nor calling it, nor importing every generated kernel module
pulls in SymPy, and that ``symrb derive`` / ``symrb verify`` / ``symrb bench`` there exit with
status 2 and say what to install.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
import textwrap
import zipfile
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]

SNIPPET = textwrap.dedent(
    """
    import importlib
    import pathlib
    import pkgutil
    import sys

    import numpy as np

    import symrb
    import symrb._generated
    from symrb import algebra

    here = pathlib.Path(symrb.__file__).resolve()
    assert "site-packages" in here.parts, f"symrb imported from {here}, not from the wheel"

    lam = np.array([0.5, 1.0, 2.0])
    M = algebra.J(algebra.hat(np.array([1.0, 2.0, 3.0])), lam)
    assert np.allclose(algebra.J_inv(M, lam), algebra.hat(np.array([1.0, 2.0, 3.0])))

    # run generated kernels through their wrappers, on a batch
    Ms = symrb.random_so(3, (4,), scale=0.1, seed=1)
    Qs = symrb.random_SO(3, (4,), seed=2)
    Qdot, Mdot = symrb.rigid_body.rigid_body_rhs(Qs, Ms, lam)
    assert Mdot.shape == (4, 3, 3) and np.allclose(Mdot, -np.swapaxes(Mdot, -1, -2))
    assert symrb.manakov_integrals(Ms, lam).shape == (4, 6)
    U = symrb.solve_moser_veselov(Ms, lam)
    assert np.allclose(symrb.algebra.J_D(U, lam), Ms)
    P = symrb.symmetric.P_from_M(Qs, Ms)
    assert np.allclose(np.swapaxes(Qs, -1, -2) @ P - np.swapaxes(P, -1, -2) @ Qs, Ms)

    public = [
        m.name
        for m in pkgutil.walk_packages(symrb.__path__, prefix="symrb.")
        if not any(part.startswith("_") for part in m.name.split("."))
    ]
    for name in public:
        # modules of an extra (hypothesis, pydantic) say which extra when it is missing
        extra = {"symrb.testing": "symrb[test]", "symrb.scenes": "symrb[scenes]"}.get(name)
        if extra is not None:
            try:
                importlib.import_module(name)
            except ImportError as exc:
                assert extra in str(exc), exc
            continue
        importlib.import_module(name)
    generated = sorted(m.name for m in pkgutil.iter_modules(symrb._generated.__path__))
    assert generated, "no generated kernel modules in the wheel"
    for name in generated:
        importlib.import_module(f"symrb._generated.{name}")

    assert "sympy" not in sys.modules, "symrb imported SymPy"
    print("public:", ", ".join(public))
    print("generated:", ", ".join(generated))
    """
)


def _run(cmd: list[str], **kwargs: object) -> subprocess.CompletedProcess[str]:
    proc = subprocess.run(cmd, capture_output=True, text=True, **kwargs)  # type: ignore[call-overload]
    assert proc.returncode == 0, (
        f"{' '.join(map(str, cmd))} failed ({proc.returncode})\n"
        f"--- stdout\n{proc.stdout[-4000:]}\n--- stderr\n{proc.stderr[-4000:]}"
    )
    return proc


@pytest.mark.timeout(900)
def test_wheel_in_clean_venv(tmp_path: Path) -> None:
    if importlib.util.find_spec("build") is None:
        pytest.skip("the 'build' package is missing: pip install -e '.[test]'")
    dist = tmp_path / "dist"
    # an isolated build: pip fetches the build backend named in pyproject.toml
    cmd = [sys.executable, "-m", "build", "--wheel", "--outdir", str(dist), str(ROOT)]
    _run(cmd, cwd=ROOT)
    wheels = sorted(dist.glob("symrb-*.whl"))
    assert len(wheels) == 1, f"expected one wheel, got {wheels}"
    names = zipfile.ZipFile(wheels[0]).namelist()
    tops = {name.split("/")[0] for name in names if not name.split("/")[0].endswith(".dist-info")}
    assert tops == {"symrb"}, f"the wheel holds more than symrb: {sorted(tops)}"

    venv = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", str(venv)])
    py = venv / ("Scripts/python.exe" if os.name == "nt" else "bin/python")
    env = {
        k: v for k, v in os.environ.items() if k not in {"PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV"}
    }
    _run(
        [str(py), "-m", "pip", "install", "--quiet", "--disable-pip-version-check", str(wheels[0])],
        env=env,
        cwd=tmp_path,
    )
    proc = _run([str(py), "-c", SNIPPET], env=env, cwd=tmp_path)
    print(proc.stdout)
    missing = subprocess.run(
        [str(py), "-c", "import sympy"], capture_output=True, text=True, env=env, cwd=tmp_path
    )
    assert missing.returncode != 0, (
        "SymPy is installed in the clean venv: it must not be a dependency"
    )
    script = py.parent / "symrb"
    for cmd in (["verify"], ["derive", "--check"]):
        proc = subprocess.run(
            [str(script), *cmd], capture_output=True, text=True, env=env, cwd=tmp_path
        )
        assert proc.returncode == 2, proc.stdout + proc.stderr
        assert "pip install -e '.[derive]'" in proc.stderr
    # the bench harness (benchmarks/) is not in the wheel either
    proc = subprocess.run(
        [str(script), "bench", "--quick"], capture_output=True, text=True, env=env, cwd=tmp_path
    )
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert "source checkout" in proc.stderr
