"""The code printer against SymPy's own evaluation, on random matrix-expression trees.

Hypothesis builds expressions from matrix symbols, the auxiliaries Lambda (diagonal) and W, sums,
products, transposes, Hadamard products, powers, traces and scalar coefficients (numbers, batched
traces, and sums of them, which need parentheses and batch alignment).  Each expression is printed
by :func:`derivations.printer.render_kernel` exactly as a kernel would be, run on batched NumPy
arrays, and compared item by item with SymPy evaluating the same expression on explicit matrices.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from derivations import printer
from derivations.vocabulary import AUXILIARIES, Arg, Kernel, Lam, W, matrix, n

SIZE = 3
BATCH = 2
A, B, C = matrix("A"), matrix("B"), matrix("C")
ARGS = [Arg(x, "(..., n, n)", "test matrix") for x in "ABC"] + [Arg("lam", "(..., n)", "diag")]

leaves = st.sampled_from([A, B, C, Lam, W])


def _scalar(children: st.SearchStrategy[sp.MatrixExpr]) -> st.SearchStrategy[sp.Expr]:
    numbers = st.sampled_from(
        [sp.Integer(2), sp.Integer(-1), sp.Rational(1, 3), sp.Rational(-5, 4)]
    )
    traces = children.map(sp.Trace)
    return st.one_of(
        numbers,
        traces,
        st.tuples(numbers, traces).map(lambda t: t[0] + t[1]),  # a sum as a coefficient
        st.tuples(traces, traces).map(lambda t: t[0] * t[1]),
    )


def _extend(children: st.SearchStrategy[sp.MatrixExpr]) -> st.SearchStrategy[sp.MatrixExpr]:
    return st.one_of(
        st.tuples(children, children).map(lambda t: t[0] + t[1]),
        st.tuples(children, children).map(lambda t: t[0] - t[1]),
        st.tuples(children, children).map(lambda t: t[0] * t[1]),
        st.tuples(children, children, children).map(lambda t: t[0] * t[1] * t[2]),
        children.map(lambda x: x.T),
        st.tuples(children, children).map(lambda t: sp.HadamardProduct(t[0], t[1])),
        st.tuples(children, st.integers(2, 4)).map(lambda t: sp.MatPow(t[0], t[1])),
        st.tuples(_scalar(children), children).map(lambda t: t[0] * t[1]),
    )


matrix_exprs = st.recursive(leaves, _extend, max_leaves=7)
scalar_exprs = st.one_of(matrix_exprs.map(sp.Trace), st.tuples(matrix_exprs, matrix_exprs).map(
    lambda t: sp.Rational(1, 2) * sp.Trace(t[0]) - sp.Trace(t[1]) * sp.Trace(t[0])
))  # fmt: skip


def _compile(outputs: dict[str, sp.Basic]) -> object:
    k = Kernel(
        name="k", target="printer_test", args=ARGS, outputs=outputs, doc="Test kernel.",
        claims=("S1",), register=False,
    )  # fmt: skip
    namespace: dict[str, object] = {"numpy": np}
    exec(printer.render_kernel(k), namespace)  # noqa: S102 - our own printed code
    return namespace["k"]


def _sympy_value(expr: sp.Basic, values: dict[str, np.ndarray], lam: np.ndarray) -> np.ndarray:
    """SymPy's own evaluation: substitute explicit matrices, doit, evaluate numerically."""
    rep: dict[sp.Basic, sp.Basic] = {
        matrix(name): sp.ImmutableMatrix(values[name]) for name in ("A", "B", "C")
    }
    lam_s = [sp.Float(x, 30) for x in lam]
    for name, aux in AUXILIARIES.items():
        rep[matrix(name)] = aux.explicit(lam_s)
    out = expr.xreplace(rep).xreplace({n: SIZE})
    # entrywise through SymPy's own explicit forms (doit leaves e.g. HadamardPower unevaluated)
    out = out.replace(
        lambda e: isinstance(e, sp.Trace), lambda e: sp.Matrix(e.arg.as_explicit()).trace()
    )
    if isinstance(out, sp.MatrixBase | sp.MatrixExpr):
        return np.array(sp.Matrix(out.as_explicit()).evalf(20), dtype=float)
    return np.array(sp.N(out, 20), dtype=float)


def _data(seed: int) -> tuple[dict[str, np.ndarray], np.ndarray]:
    rng = np.random.default_rng(seed)
    values = {name: rng.uniform(-1.0, 1.0, (BATCH, SIZE, SIZE)) for name in "ABC"}
    lam = rng.uniform(0.5, 1.5, (BATCH, SIZE))
    return values, lam


def _check(expr: sp.Basic, seed: int) -> None:
    fn = _compile({"out": expr})
    values, lam = _data(seed)
    got = np.asarray(fn(values["A"], values["B"], values["C"], lam))
    for b in range(BATCH):
        want = _sympy_value(expr, {k: v[b] for k, v in values.items()}, lam[b])
        scale = max(1.0, float(np.max(np.abs(want))))
        np.testing.assert_allclose(got[b], want, rtol=0, atol=1e-11 * scale, err_msg=str(expr))


@settings(max_examples=60, deadline=None)
@given(matrix_exprs, st.integers(0, 2**16))
def test_printed_matrix_expressions_match_sympy(expr: sp.MatrixExpr, seed: int) -> None:
    _check(expr, seed)


@settings(max_examples=40, deadline=None)
@given(scalar_exprs, st.integers(0, 2**16))
def test_printed_scalar_expressions_match_sympy(expr: sp.Expr, seed: int) -> None:
    _check(expr, seed)


@pytest.mark.parametrize(
    "expr",
    [
        sp.MatMul(sp.Trace(A) + sp.Trace(B), B, C),  # a sum as a coefficient: parentheses
        sp.Trace(A) * B,  # a batched scalar times a matrix: batch alignment
        (sp.Trace(A * B) - 2) * (A + B.T),
        Lam * A * Lam**2 - A.T * Lam,  # diagonal scalings on both sides
        sp.HadamardProduct(W, A * B - B * A),
        sp.MatPow(A, 6) + sp.MatPow(A, 4),
    ],
    ids=[
        "sum-coefficient",
        "batched-scalar",
        "scalar-difference",
        "diagonals",
        "hadamard",
        "powers",
    ],
)
def test_printer_regressions(expr: sp.MatrixExpr) -> None:
    _check(expr, 7)


def test_repeated_products_are_shared() -> None:
    """tr M^2, tr M^4, tr M^6 need two matrix products (M^2 and M^3), not nine."""
    M = matrix("A")
    k = Kernel(
        name="k", target="printer_test", args=ARGS,
        outputs={f"t{p}": sp.Trace(sp.MatPow(M, p)) for p in (2, 4, 6)},
        doc="Test kernel.", claims=("S1",), stack=True, register=False,
    )  # fmt: skip
    text = printer.render_kernel(k)
    assert text.count(" @ ") == 2, text
    assert "Total ops per batch item: 2 matrix products" in text
