"""Mutation check: do small wrong edits to the shipped numerics make ``symrb verify`` fail?

Each mutant in ``tools/mutants.toml`` replaces one exact piece of text in one file (a sign, a
transpose, a coefficient, a weight, a branch, a recorded outcome).  For every mutant this script

1. copies the tracked files of the repository into a fresh temporary directory,
2. applies the replacement there (the text must occur exactly as often as the spec says),
3. runs ``symrb derive`` in the copy when the mutant edits the generator (``derivations/``), as a
   developer would after editing it,
4. runs ``symrb verify --fail-fast`` in the copy (``PYTHONPATH`` points at the copy),

and calls the mutant *killed* when verify exits non-zero.  A mutant marked ``equivalent`` (with
the reason) changes speed, not results; it is run and reported but does not count in the kill
ratio.  The repository itself is never modified.

Usage::

    python tools/mutate.py                 # every mutant, 2 at a time
    python tools/mutate.py --subset ci     # the fixed small subset that CI runs
    python tools/mutate.py --only jinv-weights cayley-factor
    python tools/mutate.py --list
    python tools/mutate.py --json book/_build/mutation.json

Exit status: 0 when every result-changing mutant is killed, 1 otherwise, 2 on a stale spec.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "tools" / "mutants.toml"


@dataclass(frozen=True)
class Mutant:
    id: str
    file: str
    old: str
    new: str
    what: str
    count: int = 1
    ci: bool = False
    equivalent: str = ""


@dataclass
class Outcome:
    id: str
    what: str
    file: str
    equivalent: str
    killed: bool
    status: str
    seconds: float
    detail: str


def load(path: Path = SPEC) -> tuple[list[str], list[Mutant]]:
    data = tomllib.loads(path.read_text())
    mutants = [Mutant(**m) for m in data["mutant"]]
    ids = [m.id for m in mutants]
    dup = {i for i in ids if ids.count(i) > 1}
    if dup:
        raise SystemExit(f"duplicate mutant ids in {path}: {sorted(dup)}")
    return list(data["verify"]), mutants


def check_spec(mutants: list[Mutant]) -> list[str]:
    """Every mutant's text must occur exactly ``count`` times in its file (else the spec is stale)."""
    problems = []
    for m in mutants:
        path = ROOT / m.file
        if not path.exists():
            problems.append(f"{m.id}: {m.file} does not exist")
            continue
        found = path.read_text().count(m.old)
        if found != m.count:
            problems.append(f"{m.id}: text occurs {found} times in {m.file}, spec says {m.count}")
        if m.old == m.new:
            problems.append(f"{m.id}: old and new text are the same")
    return problems


def _tracked_copy(dest: Path) -> None:
    files = subprocess.run(
        ["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True
    ).stdout.split(b"\0")
    for raw in files:
        if not raw:
            continue
        rel = raw.decode()
        src = ROOT / rel
        if not src.is_file():  # deleted in the work tree
            continue
        target = dest / rel
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(src, target)
    # uncommitted edits of tracked files are part of what is checked: copy2 took the work tree


def _env(copy: Path) -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(copy) + os.pathsep + env.get("PYTHONPATH", "")
    env["PYTHONHASHSEED"] = "0"
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        env[var] = "1"
    return env


def _last_lines(text: str, k: int = 3) -> str:
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    return " | ".join(lines[-k:])[-400:]


def run_one(m: Mutant, verify_args: list[str], timeout: float) -> Outcome:
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix=f"symrb-mutant-{m.id}-") as tmp:
        copy = Path(tmp)
        _tracked_copy(copy)
        path = copy / m.file
        text = path.read_text()
        path.write_text(text.replace(m.old, m.new))
        env = _env(copy)
        py = [sys.executable, "-m", "symrb.cli"]
        if m.file.startswith("derivations/"):
            gen = subprocess.run(
                [*py, "derive"], cwd=copy, env=env, capture_output=True, text=True, timeout=timeout
            )
            if gen.returncode != 0:
                return Outcome(
                    m.id, m.what, m.file, m.equivalent, True, "killed by derive",
                    time.perf_counter() - start, _last_lines(gen.stdout + gen.stderr),
                )  # fmt: skip
        try:
            proc = subprocess.run(
                [*py, *verify_args],
                cwd=copy,
                env=env,
                capture_output=True,
                text=True,
                timeout=timeout,
            )
        except subprocess.TimeoutExpired:
            return Outcome(
                m.id, m.what, m.file, m.equivalent, True, "killed (timeout)",
                time.perf_counter() - start, f"verify did not finish in {timeout:.0f} s",
            )  # fmt: skip
    killed = proc.returncode != 0
    status = f"killed (exit {proc.returncode})" if killed else "SURVIVED"
    return Outcome(
        m.id,
        m.what,
        m.file,
        m.equivalent,
        killed,
        status,
        time.perf_counter() - start,
        _last_lines(proc.stdout + proc.stderr),
    )


def _git(*args: str) -> str:
    proc = subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True, check=False)
    return proc.stdout.strip()


def summarise(outcomes: list[Outcome]) -> dict[str, object]:
    counted = [o for o in outcomes if not o.equivalent]
    killed = [o for o in counted if o.killed]
    return {
        "mutants": len(outcomes),
        "result_changing": len(counted),
        "killed": len(killed),
        "equivalent": len(outcomes) - len(counted),
        "survivors": [o.id for o in counted if not o.killed],
        "kill_ratio": (len(killed) / len(counted)) if counted else 1.0,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subset", choices=["all", "ci"], default="all")
    ap.add_argument("--only", nargs="+", metavar="ID", help="run only these mutants")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds per verify run")
    ap.add_argument("--json", type=Path, help="write the results as JSON to this file")
    ap.add_argument("--list", action="store_true", help="list the mutants and exit")
    args = ap.parse_args(argv)

    verify_args, mutants = load()
    problems = check_spec(mutants)
    if problems:
        print("stale mutant spec (tools/mutants.toml):", *problems, sep="\n  ", file=sys.stderr)
        return 2
    if args.only:
        unknown = sorted(set(args.only) - {m.id for m in mutants})
        if unknown:
            print(f"unknown mutant ids: {unknown}", file=sys.stderr)
            return 2
        mutants = [m for m in mutants if m.id in args.only]
    elif args.subset == "ci":
        mutants = [m for m in mutants if m.ci]
    if args.list:
        for m in mutants:
            tag = " [equivalent: " + m.equivalent + "]" if m.equivalent else ""
            print(f"{m.id:<28} {m.file:<44} {m.what}{tag}")
        return 0

    print(
        f"{len(mutants)} mutants, {args.jobs} at a time; each runs: symrb {' '.join(verify_args)}"
    )
    start = time.perf_counter()
    outcomes: list[Outcome] = []
    with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        futures = [pool.submit(run_one, m, verify_args, args.timeout) for m in mutants]
        for fut in futures:
            o = fut.result()
            outcomes.append(o)
            eq = " (equivalent)" if o.equivalent else ""
            print(f"  {o.id:<28} {o.status:<22} {o.seconds:6.1f} s{eq}  {o.what}", flush=True)
            if not o.killed and not o.equivalent:
                print(f"      last output: {o.detail}", flush=True)
    summary = summarise(outcomes)
    summary["seconds"] = round(time.perf_counter() - start, 1)
    summary["subset"] = "only" if args.only else args.subset
    print(
        f"\nkilled {summary['killed']} of {summary['result_changing']} result-changing mutants "
        f"({100 * float(summary['kill_ratio']):.0f} %), {summary['equivalent']} equivalent, "
        f"in {summary['seconds']} s"
    )
    if summary["survivors"]:
        print("survivors: " + ", ".join(summary["survivors"]))  # type: ignore[arg-type]
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        payload = {
            "commit": _git("rev-parse", "--short", "HEAD"),
            "uncommitted_changes": bool(_git("status", "--porcelain", "--untracked-files=no")),
            "verify": verify_args,
            "summary": summary,
            "outcomes": [asdict(o) for o in outcomes],
        }
        args.json.write_text(json.dumps(payload, indent=1) + "\n")
    return 0 if not summary["survivors"] else 1


if __name__ == "__main__":
    sys.exit(main())
