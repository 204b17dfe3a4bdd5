"""The command line as a reader meets it: ``symrb --version``, ``--help``, ``claims``, ``show``,
``verify`` and their exit statuses (0 as recorded, 1 a surprise, 2 usage or environment).

Commands are called through ``main([...])`` with captured output; where the environment matters
(no SymPy, no derivations, a fresh interpreter) they run in a subprocess.
"""

from __future__ import annotations

import dataclasses
import importlib.metadata
import json
import os
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
import sympy as sp

import derivations.registry as registry
from derivations import text
from derivations.registry import ClaimResult, EvidenceResult, all_claims, get_claim
from derivations.symbolic import Bracket, Pair
from derivations.vocabulary import W
from symrb import cli as launcher

ROOT = Path(__file__).resolve().parents[1]
CLAIMS = all_claims()
IDS = [c.id for c in CLAIMS]


def _run(code: str, *args: str) -> subprocess.CompletedProcess[str]:
    """``python -c code args`` in the repository, with the repository first on the path."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run(
        [sys.executable, "-c", code, *args], capture_output=True, text=True, cwd=ROOT, env=env
    )


def _call(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = launcher.main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def _too_wide(text: str, width: int = 100) -> list[str]:
    return [line for line in text.splitlines() if len(line) > width]


# ---------------------------------------------------------------------------------------------
# --version and --help


def test_version_is_the_installed_version(capsys: pytest.CaptureFixture[str]) -> None:
    expected = f"symrb {importlib.metadata.version('symrb')}\n"
    for flag in ("--version", "-V"):
        code, out, _ = _call(capsys, flag)
        assert (code, out) == (0, expected)


def test_version_and_help_need_neither_sympy_nor_the_numerics() -> None:
    code = (
        "import sys; sys.modules['sympy'] = None\n"
        "from symrb.cli import main\n"
        "assert main(['--version']) == 0\n"
        "assert main(['--help']) == 0\n"
        "loaded = [m for m in ('numpy', 'scipy', 'symrb.algebra', 'derivations.registry')\n"
        "          if m in sys.modules]\n"
        "assert not loaded, loaded\n"
    )
    proc = _run(code)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("symrb ") and "exit status:" in proc.stdout


def test_python_m_derivations_version() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "derivations", "--version"],
        capture_output=True, text=True, cwd=ROOT,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == f"symrb {importlib.metadata.version('symrb')}\n"


@pytest.mark.parametrize("command", [[], ["claims"], ["show"], ["verify"], ["derive"]])
def test_help_is_plain_text_with_the_exit_status(
    capsys: pytest.CaptureFixture[str], command: list[str]
) -> None:
    code, out, _ = _call(capsys, *command, "--help")
    assert code == 0
    assert "`" not in out, "reST markup in the help"
    assert re.search(r"^exit status:\n  0 .*\n(.*\n)*  1 .*\n(.*\n)*  2 ", out, re.M), out
    assert "pip install -e '.[derive]'" in out
    assert not _too_wide(out)


def test_bad_usage_exits_2(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = _call(capsys)
    assert code == 2 and "usage: symrb" in err and "exit status" in err
    code, _, err = _call(capsys, "frobnicate")
    assert code == 2 and "invalid choice: 'frobnicate'" in err
    code, _, err = _call(capsys, "verify", "--no-such-option")
    assert code == 2 and "unrecognized arguments: --no-such-option" in err


def _commands_section(help_text: str) -> dict[str, str]:
    """The ``commands:`` section of the top-level help: command -> its text (lines joined)."""
    section = help_text.split("\ncommands:\n", 1)[1].split("\n\n", 1)[0]
    entries: dict[str, str] = {}
    name = ""
    for line in section.splitlines():
        if line.startswith("  ") and not line.startswith("   "):
            name = line.split()[0]
            entries[name] = line
        else:
            entries[name] += " " + line.strip()
    return entries


def test_help_lists_every_command(capsys: pytest.CaptureFixture[str]) -> None:
    """One ``commands:`` list names every command ``symrb`` dispatches, the derivations' own
    subcommands included (a new one there must be added to the launcher's table)."""
    from derivations.cli import build_parser

    code, out, _ = _call(capsys, "--help")
    assert code == 0
    listed = _commands_section(out)
    subparsers = build_parser()._subparsers._group_actions[0].choices  # type: ignore[union-attr]
    expected = {"run", "sweep", "bench", *subparsers}
    assert list(listed) == [c[0] for c in launcher.ALL_COMMANDS]
    assert set(listed) == expected, set(listed) ^ expected
    assert not any("not available" in entry for entry in listed.values()), listed
    code, _, err = _call(capsys, "frobnicate")
    assert code == 2 and all(f"'{name}'" in err for name in expected), err


def test_help_marks_the_commands_of_a_source_checkout_when_unavailable() -> None:
    """As from a wheel: no derivations and no benchmarks; their commands are still listed,
    each marked as unavailable here, with why."""
    code = (
        "import sys, importlib.util\n"
        "for m in ('derivations', 'derivations.cli', 'benchmarks'): sys.modules[m] = None\n"
        "from symrb.cli import main; sys.exit(main(['--help']))"
    )
    proc = _run(code)
    assert proc.returncode == 0, proc.stderr
    listed = _commands_section(proc.stdout)
    assert set(listed) == {c[0] for c in launcher.ALL_COMMANDS}
    for name, entry in listed.items():
        assert ("not available here" in entry) == (name not in ("run", "sweep")), entry
    words = " ".join(proc.stdout.split())
    assert "no derivations package next to symrb" in words
    assert "no benchmarks/ next to symrb" in words
    assert not _too_wide(proc.stdout)


@pytest.mark.parametrize("argv", [["claims"], ["show", "S1"], ["verify", "S1"], ["derive"]])
def test_without_sympy_every_command_exits_2_and_says_what_to_install(argv: list[str]) -> None:
    launchers = (
        "from symrb.cli import main; sys.exit(main(sys.argv[1:]))",
        "import runpy; runpy.run_module('derivations', run_name='__main__')",
    )
    for launcher_code in launchers:
        code = "import sys; sys.modules['sympy'] = None; " + launcher_code
        proc = _run(code, *argv)
        assert proc.returncode == 2, proc.stdout + proc.stderr
        assert "pip install -e '.[derive]'" in proc.stderr


def test_without_the_derivations_help_works_and_commands_exit_2() -> None:
    """As from a wheel: ``derivations`` cannot be imported."""
    code = (
        "import sys; sys.modules['derivations'] = None; sys.modules['derivations.cli'] = None\n"
        "from symrb.cli import main; sys.exit(main(sys.argv[1:]))"
    )
    proc = _run(code, "--help")
    assert proc.returncode == 0, proc.stderr
    assert "claims" in proc.stdout and "pip install -e '.[derive]'" in proc.stdout
    for argv in (["claims"], []):
        proc = _run(code, *argv)
        assert proc.returncode == 2, proc.stdout + proc.stderr
        assert "pip install -e '.[derive]'" in proc.stderr


# ---------------------------------------------------------------------------------------------
# claims


def test_claims_lists_every_claim_within_100_columns(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    def no_evidence(*args: Any, **kwargs: Any) -> None:
        raise AssertionError("symrb claims ran evidence")

    monkeypatch.setattr(registry, "_run_evidence", no_evidence)
    code, out, _ = _call(capsys, "claims")
    assert code == 0
    rows = [line for line in out.splitlines() if re.match(r"[DSM]\d+ ", line)]
    assert [r.split()[0] for r in rows] == IDS
    for row, c in zip(rows, CLAIMS, strict=True):
        assert row[5:].startswith(c.expected + " "), row
    assert not _too_wide(out)


@pytest.mark.parametrize("width", [80, 100, 120])
def test_claims_table_wraps_its_cells_and_cuts_nothing(width: int) -> None:
    """Every line fits ``width``; read back column by column, each claim's "in the paper" and
    title cells hold its whole text (word for word, long words broken across lines)."""
    lines = text.claims_lines(CLAIMS, width)
    assert max(map(len, lines)) <= width
    head = lines[0]
    at_where, at_title = head.index("in the paper"), head.index("title")
    cells: dict[str, list[list[str]]] = {}
    current = ""
    for line in lines[2:]:
        if re.match(r"[DSM]\d+ ", line):
            current = line.split()[0]
            cells[current] = [[], []]
        elif not line.startswith(" " * at_where):
            current = ""  # a group heading or a blank line
            continue
        if current:
            cells[current][0].append(line[at_where:at_title].strip())
            cells[current][1].append(line[at_title:].strip())
    assert list(cells) == IDS

    def same(shown: list[str], full: str) -> bool:
        return "".join(shown).replace(" ", "") == full.replace(" ", "")

    for c in CLAIMS:
        where = text.text_of(c.where or f"sec. {c.section}: {c.label}")
        where = where.replace(text._DISPLAY, " ").replace(text._GLUE, " ")
        title = text.claim_text(c, "title").replace(text._GLUE, " ")
        assert same(cells[c.id][0], where), (c.id, cells[c.id][0], where)
        assert same(cells[c.id][1], title), (c.id, cells[c.id][1], title)


def test_claims_json(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = _call(capsys, "claims", "--json")
    assert code == 0
    rows = json.loads(out)
    assert [r["id"] for r in rows] == IDS
    assert [r["expected"] for r in rows] == [c.expected for c in CLAIMS]
    assert [r["erratum"] for r in rows] == [bool(c.printed) for c in CLAIMS]
    assert [r["checks"] for r in rows] == [len(c.evidence) for c in CLAIMS]


# ---------------------------------------------------------------------------------------------
# text of formulas and LaTeX

#: What must not reach a reader: placeholders, LaTeX, control characters, Python powers, SymPy
#: class names printed as calls.
_LEFTOVERS = re.compile(
    r"\[\[[A-Za-z_]\w*\]\]|\$|\\|[\x00-\x02\x1e\x1f]|\*\*"
    r"|\b(Bracket|Pair|GlPair|HadamardProduct|Transpose|Eq|Derivative|Sum|Integral|Subs|Trace"
    r"|Indexed|MatFn|OpNorm|Ddt|Lambda\(|_[A-Z][A-Za-z]+)\("
)


@pytest.mark.parametrize("claim", CLAIMS, ids=IDS)
def test_every_claim_text_renders_as_plain_text(claim: Any) -> None:
    for which in ("title", "statement", "printed", "corrected", "note"):
        if not getattr(claim, which):
            continue
        shown = text.paragraph(text.claim_text(claim, which), width=100)
        bad = _LEFTOVERS.search(re.sub(r"`[^`]*`", "", shown))  # quoted source may hold LaTeX
        assert bad is None, f"{claim.id} {which}: {bad.group()!r} in {shown}"
        assert not _too_wide(shown), f"{claim.id} {which}: {_too_wide(shown)}"
    for key, expr in claim.formulas.items():
        drawn = text.formula_text(expr)
        assert drawn and _LEFTOVERS.search(drawn) is None, f"{claim.id} [[{key}]]: {drawn}"


def _lines(drawn: str) -> list[str]:
    return drawn.splitlines()


def test_formula_text_is_sympys_pretty_printer_with_our_display_objects() -> None:
    n = sp.Symbol("n")
    Q, P, M, X = (sp.MatrixSymbol(s, n, n) for s in "QPMX")
    m_def = sp.Eq(M, Q.T * P - P.T * Q, evaluate=False)
    pretty = sp.pretty(m_def, use_unicode=True, order="none")
    assert _lines(text.formula_text(m_def)) == [line.rstrip() for line in pretty.splitlines()]
    assert text.formula_text(Bracket(M, X)) == "[M, X]"
    assert text.formula_text(Pair(M, X)) == "⟨M, X⟩"
    assert text.formula_text(sp.HadamardProduct(W, M)) == "J⁻¹(M)"
    assert text.formula_text(sp.HadamardProduct(W, Bracket(M, X))) == "J⁻¹([M, X])"
    assert text.formula_text(sp.HadamardProduct(M, X)) == "M∘X"
    assert text.formula_text(Pair(M, Bracket(M, X))) == "⟨M, [M, X]⟩"
    assert _lines(text.formula_text(sp.Transpose(Q * X))) == ["     T", "(Q⋅X)"]
    k, N = sp.symbols("k N", integer=True)
    x = sp.IndexedBase("x")
    total = _lines(text.formula_text(sp.Sum(x[k + 1], (k, 0, N - 1))))
    assert total[0].strip() == "N - 1" and total[-1].strip() == "k = 0"
    assert "x[k + 1]" in total[len(total) // 2]
    y = sp.Symbol("y")
    f = sp.Function("f")(y)
    assert _lines(text.formula_text(sp.Derivative(f, y))) == ["d", "──(f(y))", "dy"]
    assert text.formula_text((Q, P)) == "Q,  P"
    assert text.formula_text(sp.Symbol(r"\hat{H}")) == "Ĥ"  # a name written in LaTeX
    assert text.formula_text(sp.Function(r"\phi")(y)) == "ϕ(y)"


def test_a_tall_formula_is_set_apart_and_a_flat_one_stays_in_the_sentence() -> None:
    k, N = sp.symbols("k N", integer=True)
    x = sp.IndexedBase("x")
    formulas = {"flat": sp.Eq(x[k], 0, evaluate=False), "tall": sp.Sum(x[k], (k, 0, N - 1))}
    raw = "If [[flat]] for every $k\\le N$, then [[tall]]. So it is."
    shown = text.paragraph(text.text_of(raw, formulas), indent="  ", width=60)
    lines = shown.splitlines()
    assert lines[0] == "  If x[k] = 0 for every k ≤ N, then"
    assert lines[-1] == "  So it is."
    assert any(line.startswith("      ") and "x[k]" in line for line in lines[1:-1])
    assert [line for line in lines if line.endswith(".")] == [lines[len(lines) // 2], lines[-1]]
    with pytest.raises(KeyError, match=r"\[\[missing\]\]"):
        text.text_of("[[missing]]", formulas, "S0")


@pytest.mark.parametrize(
    ("latex", "shown"),
    [
        (r"\left\|M\right\|_{\rm op} < 2", "‖M‖_{op} < 2"),
        (r"Q, P\in SO(n)", "Q, P ∈ SO(n)"),
        (r"\mathfrak{so}(n)", "𝔰𝔬(n)"),
        (r"\hat H", "Ĥ"),
        (r"\frac{d}{dt}\left(Q M Q^{T}\right)", "d/dt(Q M Q^T)"),
        (r"p_{k+1}", "p_{k+1}"),
        (r"\partial\phi/\partial Q", "∂ϕ/∂Q"),
        (r"\left\langle x, y \right\rangle", "⟨x, y⟩"),
        (r"0 \le k \le N-1", "0 ≤ k ≤ N-1"),
        (r"\operatorname{tr}(A)", "tr(A)"),
        (r"\tfrac{1}{2} M", "1/2 M"),
        (r"\left.\partial f/\partial x\right|_{K=0}", "∂f/∂x|_{K=0}"),
        (r"\phi = \alpha \sum_k x_k", "ϕ = α ∑_k x_k"),  # the space after a symbol stays
        (r"\sin \theta\, E + \hat H", "sin θ E + Ĥ"),
        (r"|\det P_k - 1|, \dim V", "|det P_k - 1|, dim V"),
        (r"\widehat{G(x)} = \hat b", "(G(x))^∧ = b̂"),
    ],
)
def test_latex_text(latex: str, shown: str) -> None:
    assert text.latex_text(latex) == shown


# ---------------------------------------------------------------------------------------------
# show


def _assert_readable(out: str) -> None:
    assert not _too_wide(out)
    for line in out.splitlines():
        assert _LEFTOVERS.search(line) is None, line


def test_show_an_erratum(capsys: pytest.CaptureFixture[str]) -> None:
    claim = get_claim("S10")
    code, out, _ = _call(capsys, "show", "s10", "--run")
    assert code == 0
    _assert_readable(out)
    assert out.startswith("S10: " + text.claim_text(claim, "title"))
    heads = [line for line in out.splitlines() if line and not line.startswith(" ")]
    for head in ("Statement", "Printed in the paper", "Corrected", "Note", "Evidence"):
        assert head in heads, head
    assert "Run now in" in out
    flat = " ".join(out.split())
    assert " ".join(text.claim_text(claim, "corrected").split()) in flat
    for key in claim.placeholders():  # every displayed formula, line by line
        for line in text.formula_text(claim.formulas[key], 90).splitlines():
            assert line.strip() in out, (key, line)
    assert f"Computed outcome: {claim.expected}, as recorded." in flat
    checks = re.findall(r"^ +\d+\. \[(\w+)\] (.+?), .*?: residual (\S+) (<=|>) tolerance (\S+)",
                        out, re.M)  # fmt: skip
    assert [c[0] for c in checks] == [e.form for e in claim.evidence]
    for (form, _level, _res, rel, _tol), e in zip(checks, claim.evidence, strict=True):
        assert rel == (">" if form == "printed" else "<="), e.name
    assert "symrb verify S10" in out


def test_show_reads_the_recorded_run_when_it_is_current(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    from derivations import report

    result = registry.verify_claim(get_claim("S1"))
    record = result.to_dict()
    float_check = next(i for i, e in enumerate(result.evidence) if e.level == "float64")
    record["evidence"][float_check]["residual"] = 1.234e-15
    path = tmp_path / "verify.json"
    path.write_text(json.dumps({"source_hash": report.source_hash(), "claims": [record]}))
    monkeypatch.setattr(report, "verify_json_path", lambda: path)

    def no_evidence(*args: Any, **kwargs: Any) -> None:
        raise AssertionError("show ran evidence although a current record exists")

    monkeypatch.setattr(registry, "_run_evidence", no_evidence)
    code, out, _ = _call(capsys, "show", "S1")
    assert code == 0
    assert "Recorded in book/_build/verify.json for this code." in out
    tol = result.evidence[float_check].tol
    assert f"residual 1.2e-15 <= tolerance {tol:.0e}: passes" in out

    path.write_text(json.dumps({"source_hash": "another", "claims": [record]}))
    monkeypatch.undo()
    monkeypatch.setattr(report, "verify_json_path", lambda: path)
    code, out, _ = _call(capsys, "show", "S1")
    assert code == 0 and "written for other code" in out and "1.2e-15" not in out


@pytest.mark.parametrize("argv", [["show", "X99"], ["verify", "S1", "X99"]])
def test_unknown_claim_exits_2(capsys: pytest.CaptureFixture[str], argv: list[str]) -> None:
    code, out, err = _call(capsys, *argv)
    assert code == 2
    assert "unknown claim id 'X99'" in err and "S15" in err
    assert "X99" not in out


# ---------------------------------------------------------------------------------------------
# verify


def _table_row(out: str, cid: str) -> str:
    (row,) = [line for line in out.splitlines() if re.match(rf"{cid} +[a-z]", line)]
    return row


def test_verify_progress_and_table(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = _call(capsys, "verify", "S1", "D2", "--jobs", "1")
    assert code == 0
    progress = err.splitlines()
    for i, (cid, outcome) in enumerate((("S1", "holds"), ("D2", "holds after correction"))):
        k = len(get_claim(cid).evidence)
        checks = f"{k} check" + ("s" if k != 1 else "")
        assert re.match(rf"\[{i + 1}/2\] {cid} +{outcome} +\({checks}, .+\)$", progress[i]), (
            progress
        )
    assert not _too_wide(out) and not _too_wide(err)
    s1 = get_claim("S1")
    worst = max((e for e in s1.evidence if e.form != "printed"), key=lambda e: e.tol)
    row = _table_row(out, "S1")
    assert re.match(rf"S1 +holds +yes +{len(s1.evidence)} +\S+ / {worst.tol:.0e} +float64", row)
    d2 = rf"D2 +holds after correction +yes +{len(get_claim('D2').evidence)} +0 \(exact\) +symbolic"
    assert re.match(d2, _table_row(out, "D2"))
    last = out.rstrip().splitlines()[-1]
    assert re.fullmatch(r"2 claims checked in \S+ m?s: every outcome as recorded", last), last


def test_verify_quiet_json_and_output(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    target = tmp_path / "sub" / "verify.json"
    code, out, err = _call(capsys, "verify", "S11", "--quiet", "--json", "--output", str(target))
    assert code == 0 and err == ""
    payload = json.loads(out)
    assert [r["id"] for r in payload["claims"]] == ["S11"]
    assert payload["claims"][0]["outcome"] == get_claim("S11").expected
    assert json.loads(target.read_text())["claims"] == payload["claims"]


def _break(monkeypatch: pytest.MonkeyPatch, cid: str, value: float) -> registry.Evidence:
    """Make the first float64 check of claim ``cid`` return ``value``."""
    claim = get_claim(cid)
    i = next(i for i, e in enumerate(claim.evidence) if e.level == "float64")
    broken = list(claim.evidence)
    broken[i] = dataclasses.replace(broken[i], func=lambda: value)
    monkeypatch.setattr(claim, "evidence", broken)
    return broken[i]


def test_verify_surprise_exits_1_and_names_it(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    ev = _break(monkeypatch, "S1", 0.5)
    code, out, err = _call(capsys, "verify", "S1", "D2", "--jobs", "1")
    assert code == 1
    assert "SURPRISE: recorded holds" in err
    assert re.match(r"S1 +fails +NO ", _table_row(out, "S1"))
    assert re.match(r"D2 +holds after correction +yes ", _table_row(out, "D2"))
    assert "Evidence not as recorded:" in out
    assert f"residual 5.0e-01 > tolerance {ev.tol:.0e}: fails, NOT as expected" in out
    assert "differs from the record for S1" in out
    assert not _too_wide(out)


def test_verify_fail_fast_stops_at_the_first_surprise(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    _break(monkeypatch, "S1", 0.5)
    code, out, err = _call(capsys, "verify", "S1", "S11", "--fail-fast", "--quiet", "--jobs", "1")
    assert code == 1 and err == ""
    assert "S11" not in out


def test_verify_in_two_processes(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """--jobs 2: a progress line per claim as each finishes, the table in the order asked, and a
    broken check in a worker process still makes the run exit 1; --jobs 0 is a usage error."""
    code, out, err = _call(capsys, "verify", "S11", "D2", "S1", "--jobs", "2")
    assert code == 0
    assert sorted(re.findall(r"\] (\S+) ", err)) == ["D2", "S1", "S11"]
    rows = [line.split()[0] for line in out.splitlines() if re.match(r"[DS]\d+ +[a-z]", line)]
    assert rows == ["S11", "D2", "S1"]  # the order asked for, as in a serial run
    _break(monkeypatch, "S1", 0.5)
    code, out, err = _call(capsys, "verify", "S1", "S11", "--jobs", "2")
    assert code == 1 and re.match(r"S1 +fails +NO ", _table_row(out, "S1"))
    code, out, err = _call(capsys, "verify", "S1", "--jobs", "0")
    assert code == 2 and "must be an integer >= 1" in err


def test_verify_table_fits_100_columns_with_every_kind_of_line() -> None:
    long = "x" * 30
    bad = EvidenceResult(
        level="symbolic, general n", description="a long description " * 12, form="printed",
        residual=0.0, tol=0.0, seconds=12.5, name="a_very_long_evidence_function_name_" + long,
    )  # fmt: skip
    crashed = dataclasses.replace(bad, form="corrected", error="ValueError: " + "y" * 150)
    results = [
        ClaimResult(id="D12", label=long, title=long, expected="holds after correction",
                    outcome="fails", evidence=[bad, crashed]),
        ClaimResult(id="S15", label=long, title=long, expected="holds", outcome="holds",
                    evidence=[dataclasses.replace(bad, form="claim", residual=3e-11, tol=1e-9)]),
    ]  # fmt: skip
    unchecked = [{"kernel": "rigid_body." + long, "claims": ["S1", "S2"], "checked_by": []}]
    lines = text.verify_table(results, unchecked)
    assert not [line for line in lines if len(line) > 100]
    shown = "\n".join(lines)
    assert re.search(r"^S15 +holds +yes +1 +3\.0e-11 / 1e-09 +symbolic, general n +12\.5 s$",
                     shown, re.M), shown  # fmt: skip
    assert "D12 [printed] symbolic, general n: residual 0 <= tolerance 0: passes" in shown
    assert "error: ValueError" in shown
    assert "kernel rigid_body." + long + " names claims S1, S2 but no claim evaluated" in shown


def test_verify_table_and_claims_list_set_the_methods_apart() -> None:
    ev = EvidenceResult(level="float64", description="d", form="claim", residual=0.0, tol=1e-12,
                        seconds=0.01)  # fmt: skip
    results = [
        ClaimResult(id=cid, label="l", title="t", expected="holds", outcome="holds", evidence=[ev])
        for cid in ("S1", "M1", "D2")
    ]
    lines = text.verify_table(results, [])
    heads = [lines.index(t) for t in registry.GROUP_TITLES.values()]
    rows = [i for i, line in enumerate(lines) if re.match(r"[DSM]\d+ ", line)]
    ids = [lines[i].split()[0] for i in rows]
    assert ids == ["S1", "D2", "M1"]
    assert heads[0] < rows[0] < rows[1] < heads[1] < rows[2]
    assert text.verify_table(results[:1], [])[2].startswith("S1 ")  # one group: no heading
    paper = [c for c in CLAIMS if c.group == "paper"][:2]
    method = dataclasses.replace(paper[0], id="M1", evidence=[], formulas={})
    listed = text.claims_lines([*paper, method])
    assert listed.index("symrb's own methods") < [r[:2] for r in listed].index("M1")


def test_verify_group_runs_only_that_group(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    ran: list[list[str]] = []

    def record(claims: Any, *args: Any, **kwargs: Any) -> Any:
        ran.append([c.id for c in claims])
        return []

    monkeypatch.setattr("derivations.cli._run", record)
    for argv, group in ((["--paper"], "paper"), (["--group", "method"], "method"), ([], None)):
        code, _, _ = _call(capsys, "verify", "--quiet", *argv)
        assert code == 0 and ran == [[c.id for c in all_claims(group=group)]], (argv, ran)
        ran.clear()
    assert all_claims(group="paper") == CLAIMS[: len(all_claims(group="paper"))]
    code, _, err = _call(capsys, "verify", "--paper", "--group", "method")
    assert code == 2 and "not allowed with" in err


def test_show_lists_the_papers_sentences_with_their_evidence(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    from derivations.registry import Sentence

    claim = get_claim("D10")
    first = claim.evidence[0].name
    monkeypatch.setattr(claim, "sentences", [
        Sentence(r"A covered $M_k = \Omega_k^T \Lambda$.", (first,)),
        Sentence(r"An unchecked $\overline{Q}_0 \in \operatorname{SO}(n)$."),
        Sentence("See [MoVe1991].", (), "prose", "a citation"),
    ])  # fmt: skip
    code, out, _ = _call(capsys, "show", "D10", "--run")
    assert code == 0
    _assert_readable(out)
    tail = out[out.index("\nThe paper's sentences\n") :]
    assert "1 of 2 stating mathematics covered by evidence, 1 UNCOVERED; 1 prose." in tail
    flat = " ".join(tail.split())
    assert f"1. [covered] A covered M_k = Ω_k^T Λ. Checked by evidence 1 ({first})." in flat
    assert "2. [UNCOVERED] An unchecked Q̅_0 ∈ SO(n). No evidence checks this sentence" in flat
    assert "3. [prose] See [MoVe1991]. Why nothing is checked: a citation" in flat
