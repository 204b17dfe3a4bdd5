"""Generated kernels: agree with direct NumPy, broadcast over batches, and match their derivations."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import symrb
from derivations import codegen
from symrb._generated import rigid_body as gen

ROOT = Path(__file__).resolve().parent.parent


def _case(rng: np.random.Generator, batch: tuple[int, ...], n: int):
    M = symrb.random_so(n, batch, seed=rng)
    Q = symrb.random_SO(n, batch, seed=rng)
    lam = rng.uniform(0.5, 2.0, batch + (n,))
    return Q, M, lam


@pytest.mark.parametrize("n", [2, 3, 4, 7])
def test_rigid_body_rhs_against_direct_numpy(rng: np.random.Generator, n: int) -> None:
    Q, M, lam = _case(rng, (3, 2), n)
    Qd, Md = gen.rigid_body_rhs(Q, M, lam)
    for idx in np.ndindex(3, 2):
        Om = M[idx] / (lam[idx][:, None] + lam[idx][None, :])
        np.testing.assert_allclose(Qd[idx], Q[idx] @ Om, rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(Md[idx], M[idx] @ Om - Om @ M[idx], rtol=1e-13, atol=1e-13)
        # M = J(Omega) with J as defined in the paper
        L = np.diag(lam[idx])
        np.testing.assert_allclose(L @ Om + Om @ L, M[idx], rtol=1e-13, atol=1e-13)


def test_energy_casimirs_manakov_against_direct_numpy(rng: np.random.Generator) -> None:
    n = 5
    _, M, lam = _case(rng, (4,), n)
    E = gen.kinetic_energy(M, lam)
    C = gen.casimir_traces(M)
    I = gen.manakov_integrals(M, lam)
    assert E.shape == (4,) and C.shape == (4, 3) and I.shape == (4, 6)
    for b in range(4):
        L = np.diag(lam[b])
        A = L @ L
        m = M[b]
        Om = m / (lam[b][:, None] + lam[b][None, :])
        assert E[b] == pytest.approx(-0.25 * np.trace(Om @ m), rel=1e-13)
        assert E[b] == pytest.approx(0.5 * symrb.pairing(Om, m), rel=1e-13)
        mp = np.linalg.matrix_power
        np.testing.assert_allclose(C[b], [np.trace(mp(m, k)) for k in (2, 4, 6)], rtol=1e-12)
        # Manakov's integrals as coefficients of a polynomial in lambda, fitted directly
        lams = np.linspace(-1.0, 1.0, 7)
        for k, j, col in [(2, 0, 0), (3, 1, 1), (4, 0, 2), (4, 2, 3), (5, 1, 4), (5, 3, 5)]:
            vals = [np.trace(mp(m + t * A, k)) for t in lams]
            coeffs = np.polynomial.polynomial.polyfit(lams, vals, k)
            assert I[b, col] == pytest.approx(coeffs[j], rel=1e-8, abs=1e-8 * np.abs(vals).max())


def test_euler_so3_matches_matrix_field(rng: np.random.Generator) -> None:
    m = rng.standard_normal((6, 3))
    lam = rng.uniform(0.5, 2.0, (6, 3))
    M = symrb.hat(m)
    _, Md = gen.rigid_body_rhs(np.broadcast_to(np.eye(3), M.shape), M, lam)
    np.testing.assert_allclose(gen.euler_rhs_so3(m, lam), symrb.vee(Md), rtol=1e-12, atol=1e-14)
    # Euler's form with principal moments I
    I_ = symrb.inertia_from_lam(lam)
    w = m / I_
    np.testing.assert_allclose(gen.euler_rhs_so3(m, lam), np.cross(m, w), rtol=1e-12, atol=1e-14)


def test_kernels_broadcast_lam_against_batch(rng: np.random.Generator) -> None:
    Q, M, _ = _case(rng, (5,), 4)
    lam = np.array([0.7, 1.0, 1.3, 1.9])
    batched = gen.manakov_integrals(M, lam)
    loop = np.stack([gen.manakov_integrals(M[i], lam) for i in range(5)])
    np.testing.assert_allclose(batched, loop, rtol=1e-14)


def test_wrappers_validate_and_do_not_mutate(rng: np.random.Generator) -> None:
    Q, M, lam = _case(rng, (), 4)
    copies = [a.copy() for a in (Q, M, lam)]
    symrb.rigid_body_rhs(Q, M, lam)
    for a, c in zip((Q, M, lam), copies, strict=True):
        np.testing.assert_array_equal(a, c)
    with pytest.raises(symrb.InputError, match="M must be skew"):
        symrb.rigid_body_rhs(Q, M + np.eye(4), lam)
    with pytest.raises(symrb.InputError, match="lam_i \\+ lam_j > 0"):
        symrb.kinetic_energy(M, np.array([1.0, -2.0, 0.5, 0.5]))
    with pytest.raises(symrb.InputError, match="finite"):
        symrb.casimir_traces(np.full((3, 3), np.nan))


def test_derive_check_is_clean() -> None:
    assert codegen.emit_all(check=True, out=sys.stderr) == 0


def test_hand_edit_is_detected(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Copy the generated tree, edit one file by hand: derive --check must fail with a diff."""
    import io
    import shutil

    target = tmp_path / "_generated"
    shutil.copytree(codegen.generated_dir(), target)
    f = target / "rigid_body.py"
    f.write_text(f.read_text().replace("Omega = W * M", "Omega = 2 * W * M"))
    monkeypatch.setattr(codegen, "generated_dir", lambda: target)
    buf = io.StringIO()
    assert codegen.emit_all(check=True, out=buf) == 1
    assert "-    Omega = 2 * W * M" in buf.getvalue()
    # a stale extra file is reported too
    f.write_text(codegen.collect()["rigid_body.py"])
    (target / "orphan.py").write_text("x = 1\n")
    buf = io.StringIO()
    assert codegen.emit_all(check=True, out=buf) == 1 and "stale" in buf.getvalue()


def test_cli_derive_check_exit_code() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "symrb.cli", "derive", "--check"],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_generated_files_have_header() -> None:
    for path in sorted(codegen.generated_dir().glob("*.py")):
        head = path.read_text().splitlines()[0]
        assert "do not edit by hand" in head, path.name


def test_symrb_does_not_import_sympy() -> None:
    code = "import sys, symrb, symrb._generated.rigid_body; assert 'sympy' not in sys.modules, 'sympy imported'"
    subprocess.run([sys.executable, "-c", code], check=True)


def test_generation_does_not_depend_on_hash_seed() -> None:
    """Regenerating under two different PYTHONHASHSEEDs gives byte-identical files."""
    import hashlib
    import os

    code = (
        "import hashlib; from derivations.codegen import collect; f = collect(); "
        "print(hashlib.sha256(''.join(k + f[k] for k in sorted(f)).encode()).hexdigest())"
    )
    digests = set()
    for seed in ("1", "12345"):
        env = dict(os.environ, PYTHONHASHSEED=seed)
        out = subprocess.run(
            [sys.executable, "-c", code],
            env=env,
            capture_output=True,
            text=True,
            cwd=ROOT,
            check=True,
        )
        digests.add(out.stdout.strip())
    assert len(digests) == 1
    committed = {p.name: p.read_text() for p in codegen.generated_dir().glob("*.py")}
    expect = hashlib.sha256(
        "".join(k + committed[k] for k in sorted(committed)).encode()
    ).hexdigest()
    assert digests == {expect}
