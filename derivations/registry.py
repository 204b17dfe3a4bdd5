"""The claim registry: every statement of the paper that symrb reproduces, stated once.

A claim is declared in a module of its own (derivations/claims/section*/), above its evidence::

    S6 = claim("S6", label="SRBtoRB.prop", title="...", expected="holds", section="3.2",
               statement="If [[srb]] then [[rb]] ...")

    @S6.check(Level.SYMBOLIC_GENERAL_N)
    def s6_momentum_general_n():
        '''$d(Q^T P - P^T Q)/dt - [M, U]$ vanishes on the emitted field (noncommutative, any $n$).'''
        ...

The first paragraph of an evidence function's docstring is its description (a check is described
once): plain words with every formula in ``$...$`` LaTeX (``$p_{k+1}$``, ``$Q^T$``), typeset in the
book's evidence tables and turned into text by ``show``; ``tests/test_registry.py`` rejects ASCII
stand-ins for mathematics outside ``$...$``.  An evidence function returns a non-negative *residual* that is zero (up to ``tol``) exactly
when what it checks is true, at one :class:`Level`.

Formulas shown in the book come from the objects the evidence evaluates: ``[[key]]`` in a claim's
``statement``, ``printed`` or ``corrected`` text is replaced by the LaTeX of the SymPy object
registered with ``claim.formula(key, expr)``, which the evidence reads back with
``claim.formulas[key]``.  Hand-written math in those texts may name objects but not state
relations (a test enforces it), so a displayed sign cannot drift from the checked one.

Evidence is tagged with the *form* it checks: ``"claim"`` (the statement as printed, expected to
hold), ``"printed"`` (the statement as printed, expected to *fail*: an erratum) or ``"corrected"``
(our correction, which must hold).  The outcome of a claim is computed, never typed in:

* ``holds``: every ``claim`` evidence passes;
* ``holds after correction``: every ``printed`` evidence fails and every ``corrected`` one passes;
* ``fails``: some printed-form evidence fails and no correction is registered;
* ``not checkable``: there is no evidence.

Claims live in the modules of the packages :data:`PACKAGES`; the registry discovers every
:class:`Claim` object there, so adding a claim module never edits this file.
"""

from __future__ import annotations

import contextvars
import enum
import importlib
import inspect
import multiprocessing
import pkgutil
import re
import textwrap
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from typing import Any, Literal

from derivations.symbolic import latex
from derivations.vocabulary import CURRENT_CLAIM, KERNELS, Kernel

__all__ = [
    "Level",
    "Evidence",
    "Sentence",
    "SENTENCE_KINDS",
    "Claim",
    "claim",
    "EvidenceResult",
    "ClaimResult",
    "all_claims",
    "all_kernels",
    "get_claim",
    "import_claim_modules",
    "verify",
    "verify_each",
    "verify_claim",
    "kernel_report",
    "CURRENT_EVIDENCE",
    "RECORDER",
    "OUTCOMES",
    "GROUPS",
    "GROUP_TITLES",
    "grouped",
]

OUTCOMES = ("holds", "holds after correction", "fails", "not checkable")
Outcome = Literal["holds", "holds after correction", "fails", "not checkable"]
Form = Literal["claim", "printed", "corrected"]
_FORMS = ("claim", "printed", "corrected")
_PLACEHOLDER = re.compile(r"\[\[([A-Za-z0-9_]+)\]\]")


class Level(enum.StrEnum):
    """Evidence levels, strongest first."""

    SYMBOLIC_GENERAL_N = "symbolic, general n"
    SYMBOLIC_FIXED_N = "symbolic, fixed n"
    EXACT_RATIONAL = "exact rational"
    FLOAT64 = "float64"
    MPMATH = "high precision"

    def __str__(self) -> str:  # pragma: no cover - trivial
        return self.value


@dataclass(frozen=True)
class Evidence:
    """One check of a claim: ``func()`` returns a residual; it passes when ``residual <= tol``."""

    level: Level
    description: str
    func: Callable[[], Any]
    tol: float = 0.0
    form: Form = "claim"
    name: str = ""


#: What a sentence of the paper does: ``"math"`` states mathematics (a definition, a formula, an
#: assertion) and needs evidence; ``"prose"`` states none (motivation, a citation, a pointer to
#: the proof) and says so in ``reason``.
SENTENCE_KINDS = ("math", "prose")


@dataclass(frozen=True)
class Sentence:
    """One sentence of a claim's statement in the paper and the evidence that covers it.

    ``text`` is the sentence as printed (LaTeX, the paper's macros expanded); ``evidence`` the
    names of the evidence functions of the claim that check it.  A ``"math"`` sentence without
    evidence is *uncovered* (shown as such in the book and counted); a ``"prose"`` sentence gives
    in ``reason`` why there is nothing to check.
    """

    text: str
    evidence: tuple[str, ...] = ()
    kind: str = "math"
    reason: str = ""

    @property
    def covered(self) -> bool:
        """True for prose, and for a math sentence with at least one piece of evidence."""
        return self.kind == "prose" or bool(self.evidence)


def _describe(func: Callable[..., Any], description: str | None) -> str:
    if description is not None:
        return " ".join(description.split())
    doc = inspect.getdoc(func)
    if not doc:
        raise ValueError(f"evidence {func.__qualname__} needs a docstring (its description)")
    first = textwrap.dedent(doc).strip().split("\n\n")[0]
    return " ".join(first.split())


@dataclass(eq=False)
class Claim:
    """A statement of the paper (see the module docstring for how it is declared).

    ``statement`` is the statement in our words; for an erratum ``printed`` is the form printed in
    the paper and ``corrected`` the form that holds; ``note`` says what was found.  ``label`` is
    the paper's LaTeX label; ``where`` says where a reader of the paper finds the statement
    (section and the numbered item or equation).  ``headline`` states an erratum's correction in
    one line, for the verdict table of the book's first page: its ``[[key]]`` formulas, joined
    by a few words (empty: the table shows the note's ``Corrected:`` sentence).  ``expected`` is
    the outcome recorded for the claim: :func:`verify` reports a mismatch as a failure.
    """

    id: str
    label: str
    title: str
    statement: str
    expected: Outcome
    printed: str | None = None
    corrected: str | None = None
    note: str = ""
    section: str = ""
    where: str = ""
    headline: str = ""
    evidence: list[Evidence] = field(default_factory=list)
    formulas: dict[str, Any] = field(default_factory=dict)
    sentences: list[Sentence] = field(default_factory=list)
    module: str = ""

    def __post_init__(self) -> None:
        if not re.fullmatch(r"[DSM]\d+", self.id):
            raise ValueError(f"claim id must look like D1, S12 or M3, got {self.id!r}")
        if self.expected not in OUTCOMES:
            raise ValueError(
                f"claim {self.id}: expected must be one of {OUTCOMES}, got {self.expected!r}"
            )
        if bool(self.printed) != bool(self.corrected):
            raise ValueError(f"claim {self.id}: give both the printed and the corrected text")
        if self.headline and not self.corrected:
            raise ValueError(f"claim {self.id}: a headline states a correction; give one")

    @property
    def group(self) -> str:
        """``"paper"`` for a statement of the paper, ``"method"`` for a check of symrb's own."""
        return GROUPS[self.id[0]]

    # -- declaration ------------------------------------------------------------------------

    def check(
        self,
        level: Level,
        *,
        tol: float = 0.0,
        form: Form = "claim",
        description: str | None = None,
    ) -> Callable[[Callable[[], Any]], Callable[[], Any]]:
        """Decorator: register the function as a piece of evidence of this claim."""
        if form not in _FORMS:
            raise ValueError(f"claim {self.id}: form must be one of {_FORMS}, got {form!r}")
        if form in ("printed", "corrected") and not self.printed:
            raise ValueError(f"claim {self.id}: {form} evidence needs printed and corrected texts")

        def register(func: Callable[[], Any]) -> Callable[[], Any]:
            self.evidence.append(
                Evidence(
                    level=Level(level),
                    description=_describe(func, description),
                    func=func,
                    tol=float(tol),
                    form=form,
                    name=func.__qualname__,
                )
            )
            return func

        return register

    def formula(self, key: str, expr: Any) -> Any:
        """Register ``expr`` under ``key`` for ``[[key]]`` in this claim's texts; returns it."""
        if key in self.formulas:
            raise ValueError(f"claim {self.id}: formula {key!r} registered twice")
        self.formulas[key] = expr
        return expr

    def sentence(
        self,
        text: str,
        *evidence: Callable[[], Any],
        kind: str = "math",
        reason: str = "",
    ) -> Sentence:
        """Map one sentence of the paper's statement to the evidence functions that check it.

        Call it once per sentence, in the paper's order, after the evidence is declared::

            D7.sentence("The multiplier $\\Sigma$ is $N \\times N$.", d7_multiplier_n_by_n)
            D7.sentence("We now prove the theorem.", kind="prose", reason="points to the proof")

        Each function must be registered evidence of this claim; a prose sentence gives a
        ``reason`` and no evidence.
        """
        if kind not in SENTENCE_KINDS:
            raise ValueError(f"claim {self.id}: kind must be one of {SENTENCE_KINDS}, got {kind!r}")
        known = {ev.func: ev.name for ev in self.evidence}
        names = []
        for func in evidence:
            if func not in known:
                name = getattr(func, "__qualname__", repr(func))
                raise ValueError(f"claim {self.id}: {name} is not evidence of this claim")
            names.append(known[func])
        if kind == "prose" and (names or not reason.strip()):
            raise ValueError(f"claim {self.id}: a prose sentence gives a reason and no evidence")
        item = Sentence(" ".join(text.split()), tuple(names), kind, " ".join(reason.split()))
        self.sentences.append(item)
        return item

    # -- rendering --------------------------------------------------------------------------

    def placeholders(self) -> set[str]:
        texts = [self.statement, self.printed or "", self.corrected or "", self.headline]
        return {m for t in texts for m in _PLACEHOLDER.findall(t)}

    def render(self, which: str = "statement") -> str:
        """The text ``which`` (statement, printed, corrected, headline) with every ``[[key]]`` replaced by
        ``$latex$`` of the registered formula."""
        text = getattr(self, which) or ""

        def sub(m: re.Match[str]) -> str:
            key = m.group(1)
            if key not in self.formulas:
                raise KeyError(f"claim {self.id}: [[{key}]] in its {which} has no formula")
            return "$" + latex(self.formulas[key]) + "$"

        return _PLACEHOLDER.sub(sub, text)


def claim(
    id: str,
    *,
    label: str,
    title: str,
    statement: str,
    expected: Outcome,
    printed: str | None = None,
    corrected: str | None = None,
    note: str = "",
    section: str = "",
    where: str = "",
    headline: str = "",
) -> Claim:
    """Declare a claim in the calling module (see the module docstring)."""
    frame = inspect.currentframe()
    module = frame.f_back.f_globals.get("__name__", "") if frame and frame.f_back else ""
    return Claim(
        id=id,
        label=label,
        title=title,
        statement=statement,
        expected=expected,
        printed=printed,
        corrected=corrected,
        note=" ".join(note.split()),
        section=section,
        where=where,
        headline=headline,
        module=module,
    )


# ---------------------------------------------------------------------------------------------
# results


@dataclass
class EvidenceResult:
    level: str
    description: str
    form: str
    residual: float
    tol: float
    seconds: float
    name: str = ""
    error: str | None = None

    @property
    def passed(self) -> bool:
        """True when the residual is within tolerance (and the evidence ran)."""
        return bool(self.error is None and self.residual <= self.tol)

    @property
    def as_expected(self) -> bool:
        """Printed-form evidence is expected to fail; everything else to pass."""
        if self.error is not None:
            return False
        return (not self.passed) if self.form == "printed" else self.passed

    def to_dict(self) -> dict[str, Any]:
        return {
            "level": self.level,
            "description": self.description,
            "form": self.form,
            "residual": self.residual,
            "tol": self.tol,
            "seconds": self.seconds,
            "passed": self.passed,
            "name": self.name,
            "error": self.error,
        }


@dataclass
class ClaimResult:
    id: str
    label: str
    title: str
    expected: str
    outcome: str
    evidence: list[EvidenceResult] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """True when the computed outcome equals the recorded one."""
        return self.outcome == self.expected

    @property
    def seconds(self) -> float:
        return sum(e.seconds for e in self.evidence)

    def to_dict(self) -> dict[str, Any]:
        return {
            "id": self.id,
            "label": self.label,
            "title": self.title,
            "expected": self.expected,
            "outcome": self.outcome,
            "ok": self.ok,
            "seconds": self.seconds,
            "evidence": [e.to_dict() for e in self.evidence],
        }


# ---------------------------------------------------------------------------------------------
# discovery


#: The packages searched for claims and method checks, in this order.
PACKAGES = ("derivations.claims", "derivations.methods")

#: Claim groups: the paper's statements (D1.., S1..) and checks of symrb's own methods (M1..).
GROUPS = {"D": "paper", "S": "paper", "M": "method"}

#: The heading of each group where claims are listed (terminal tables, the book's claims page).
GROUP_TITLES = {"paper": "The paper's claims", "method": "symrb's own methods"}


def grouped(items: Sequence[Any], id_of: Callable[[Any], str]) -> list[tuple[str, list[Any]]]:
    """``[(title, members), ...]``: ``items`` (claims, results, their dicts) by the group of their
    ID ``id_of(item)``, in the order of :data:`GROUP_TITLES`, groups without members left out."""
    out = [(t, [x for x in items if GROUPS[id_of(x)[0]] == g]) for g, t in GROUP_TITLES.items()]
    return [(title, members) for title, members in out if members]


def _claim_key(cid: str) -> tuple[int, int]:
    return ("DSM".index(cid[0]), int(cid[1:]))


def import_claim_modules() -> list[Any]:
    """Import every module of the claim packages (:data:`PACKAGES`, recursively, sorted by name;
    a package that does not exist is skipped)."""
    modules = []
    for pkg_name in PACKAGES:
        try:
            pkg = importlib.import_module(pkg_name)
        except ModuleNotFoundError as exc:
            if exc.name != pkg_name:
                raise
            continue
        for info in sorted(
            pkgutil.walk_packages(pkg.__path__, prefix=pkg.__name__ + "."), key=lambda m: m.name
        ):
            if any(piece.startswith("_") for piece in info.name.split(".")):
                continue
            modules.append(importlib.import_module(info.name))
    return modules


def all_claims(group: str | None = None) -> list[Claim]:
    """Every registered claim, in the order D1..D12, S1..S15, M1..; with ``group`` (``"paper"``
    or ``"method"``) only that group's."""
    if group is not None and group not in set(GROUPS.values()):
        raise ValueError(f"group must be one of {sorted(set(GROUPS.values()))}, got {group!r}")
    claims: dict[str, Claim] = {}
    for module in import_claim_modules():
        for value in vars(module).values():
            if isinstance(value, Claim) and value.module == module.__name__:
                if value.id in claims and claims[value.id] is not value:
                    raise ValueError(
                        f"claim {value.id} declared twice (again in {module.__name__})"
                    )
                claims[value.id] = value
    ordered = [claims[k] for k in sorted(claims, key=_claim_key)]
    return [c for c in ordered if group is None or c.group == group]


def all_kernels(only: Sequence[str] | None = None) -> list[Kernel]:
    """Every kernel declared by a claim module, by target and definition order (``only``: just
    the kernels of those generated modules)."""
    import_claim_modules()
    kernels = [k for k in KERNELS if not only or k.target in only]
    return sorted(kernels, key=lambda k: (k.target, k.order))


def get_claim(cid: str) -> Claim:
    """The claim with ID ``cid`` (case-insensitive); ``KeyError`` listing the known IDs otherwise."""
    claims = {c.id: c for c in all_claims()}
    key = cid.upper()
    if key not in claims:
        raise KeyError(f"unknown claim id {cid!r}; registered: {', '.join(claims)}")
    return claims[key]


# ---------------------------------------------------------------------------------------------
# running evidence

#: ``"ID name"`` of the evidence running (None outside evidence): what the coverage recorder of
#: :mod:`derivations.coverage` notes against each call it sees.
CURRENT_EVIDENCE: contextvars.ContextVar[str | None] = contextvars.ContextVar(
    "CURRENT_EVIDENCE", default=None
)

#: The coverage recorder while one records (:func:`derivations.coverage.recording`), else None;
#: worker processes forked by :func:`verify_each` hand back what they recorded (``take()``) and
#: this process adds it (``merge(hits)``).
RECORDER: Any = None


def _run_evidence(claim_id: str, ev: Evidence) -> EvidenceResult:
    token = CURRENT_CLAIM.set(claim_id)
    evidence_token = CURRENT_EVIDENCE.set(f"{claim_id} {ev.name}")
    start = time.perf_counter()
    error = None
    try:
        value = ev.func()
        residual = float(abs(complex(value)))
        if residual != residual:  # NaN
            error = "residual is NaN"
            residual = float("inf")
    except Exception as exc:  # an evidence that crashes is reported, not hidden
        error = f"{type(exc).__name__}: {exc}"
        residual = float("inf")
    finally:
        CURRENT_CLAIM.reset(token)
        CURRENT_EVIDENCE.reset(evidence_token)
    return EvidenceResult(
        level=Level(ev.level).value,
        description=ev.description,
        form=ev.form,
        residual=residual,
        tol=ev.tol,
        seconds=time.perf_counter() - start,
        name=ev.name,
        error=error,
    )


def outcome_of(results: Sequence[EvidenceResult]) -> Outcome:
    """Compute the outcome of a claim from its evidence results (see the module docstring)."""
    if not results:
        return "not checkable"
    if any(r.error is not None for r in results):
        return "fails"
    claim_ev = [r for r in results if r.form == "claim"]
    printed = [r for r in results if r.form == "printed"]
    corrected = [r for r in results if r.form == "corrected"]
    if printed or corrected:
        printed_fails = bool(printed) and all(not r.passed for r in printed)
        corrected_holds = bool(corrected) and all(r.passed for r in corrected)
        claim_holds = all(r.passed for r in claim_ev)
        if printed_fails and corrected_holds and claim_holds:
            return "holds after correction"
        if not printed_fails and corrected_holds and claim_holds:
            return "holds"  # the printed form was fine after all
        return "fails"
    return "holds" if all(r.passed for r in claim_ev) else "fails"


def verify_claim(claim: Claim, fail_fast: bool = False) -> ClaimResult:
    """Run every piece of evidence of ``claim`` and compute its outcome.

    With ``fail_fast`` it stops at the first evidence that does not behave as the recorded outcome
    needs (a failing claim or corrected check, a passing printed check); the outcome is then
    computed from the evidence run so far.
    """
    results = []
    for ev in claim.evidence:
        r = _run_evidence(claim.id, ev)
        results.append(r)
        if fail_fast and _contradicts(claim.expected, r):
            break
    return ClaimResult(
        id=claim.id,
        label=claim.label,
        title=claim.title,
        expected=claim.expected,
        outcome=outcome_of(results),
        evidence=results,
    )


def _contradicts(expected: str, r: EvidenceResult) -> bool:
    if r.error is not None:
        return True
    if r.form == "printed":
        return r.passed if expected == "holds after correction" else False
    return not r.passed


def _verify_by_id(cid: str, fail_fast: bool) -> tuple[ClaimResult, list[tuple[str, str]], Any]:
    """Run in a worker process: the result, the kernels whose expressions the claim read and
    what the coverage recorder (inherited from the parent, if any) noted for it."""
    if RECORDER is not None:
        RECORDER.take()  # drop what the parent had recorded before the fork
    result = verify_claim(get_claim(cid), fail_fast=fail_fast)
    read = [(k.target, k.name) for k in KERNELS if cid in k.checked_by]
    return result, read, RECORDER.take() if RECORDER is not None else None


def _pool_context() -> Any:
    """Worker processes forked from this one where the platform can (no second import of the
    claim modules), spawned elsewhere."""
    methods = multiprocessing.get_all_start_methods()
    return multiprocessing.get_context("fork" if "fork" in methods else "spawn")


def verify_each(
    claims: Sequence[Claim], *, jobs: int = 1, fail_fast: bool = False
) -> Iterator[ClaimResult]:
    """Verify ``claims``, yielding each result when it is ready.

    With ``jobs == 1`` the claims run here, in order.  With more, they run in that many worker
    processes and the results come in the order they finish; which kernels each claim's evidence
    read is carried back, so :func:`kernel_report` is the same as after a serial run.  With
    ``fail_fast`` no further claim is started after the first result that differs from its
    record (one that is already running still finishes).
    """
    if jobs < 1:
        raise ValueError(f"jobs must be an integer >= 1, got {jobs!r}")
    if jobs == 1 or len(claims) <= 1:
        for c in claims:
            result = verify_claim(c, fail_fast=fail_fast)
            yield result
            if fail_fast and not result.ok:
                return
        return
    by_key = {(k.target, k.name): k for k in KERNELS}
    workers = min(jobs, len(claims))
    with ProcessPoolExecutor(max_workers=workers, mp_context=_pool_context()) as pool:
        futures = [pool.submit(_verify_by_id, c.id, fail_fast) for c in claims]
        try:
            for future in as_completed(futures):
                result, read, hits = future.result()
                for key in read:
                    by_key[key].checked_by.add(result.id)
                if hits and RECORDER is not None:
                    RECORDER.merge(hits)
                yield result
                if fail_fast and not result.ok:
                    return
        finally:
            for future in futures:
                future.cancel()


def verify(
    ids: Iterable[str] | None = None,
    progress: Callable[[ClaimResult], None] | None = None,
    fail_fast: bool = False,
    jobs: int = 1,
) -> list[ClaimResult]:
    """Verify the claims with the given IDs (all when ``None``); the results in registry order.
    ``progress`` is called with each result as it comes (see :func:`verify_each`)."""
    claims = all_claims() if ids is None else [get_claim(i) for i in ids]
    order = {c.id: i for i, c in enumerate(claims)}
    out = []
    for result in verify_each(claims, jobs=jobs, fail_fast=fail_fast):
        if progress is not None:
            progress(result)
        out.append(result)
    return sorted(out, key=lambda r: order[r.id])


def kernel_report() -> list[dict[str, Any]]:
    """For every emitted kernel: its module, the claims it names and the claims whose evidence
    read its expressions in this process (run :func:`verify` first)."""
    return [
        {
            "kernel": f"{k.target}.{k.name}",
            "source": k.source,
            "claims": list(k.claims),
            "checked_by": sorted(k.checked_by, key=_claim_key),
        }
        for k in all_kernels()
    ]
