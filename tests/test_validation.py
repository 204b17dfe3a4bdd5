"""Bad input as a user gives it: complex arrays, the matrix Lambda for lam, a non-orthogonal Q,
non-numbers for scalars.  Each gets an InputError naming the argument, the condition and the
value; integer input keeps working."""

from __future__ import annotations

import re

import numpy as np
import pytest

import symrb
from symrb import InputError

LAM = np.array([0.7, 1.1, 1.6])
M = symrb.hat([0.1, 0.2, 0.3])
Q = symrb.random_SO(3, seed=0)


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda c: symrb.J_inv(c(M), LAM), "M"),
        (lambda c: symrb.J(c(M), LAM), "Omega"),
        (lambda c: symrb.J(M, c(LAM)), "lam"),
        (lambda c: symrb.hat(c(np.array([1.0, 2.0, 3.0]))), "v"),
        (lambda c: symrb.solve_moser_veselov(c(M), LAM), "M"),
        (lambda c: symrb.symmetric.symmetric_momentum(c(Q), Q), "Q"),
        (lambda c: symrb.symmetric.P_from_M(Q, c(M)), "M"),
        (lambda c: symrb.mv_algorithm2(Q, c(M), LAM, 2), "M"),
        (lambda c: symrb.symmetric_flow(c(Q), Q, LAM, 0.1, 2), "Q0"),
        (lambda c: symrb.kinetic_energy(c(M), LAM), "M"),
        (lambda c: symrb.orbits.double_bracket_rhs(c(M), M), "x"),
        (
            lambda c: symrb.learning.resnet_forward(
                c(np.ones(2)), np.zeros((1, 2, 2)), np.zeros((1, 2))
            ),
            "x0",
        ),
        (lambda c: symrb.integrate(symrb.RigidBody, (0, 1), (Q, c(M)), lam=LAM), "y0['M']"),
    ],
)
def test_complex_input_is_rejected_not_cast(call, name: str) -> None:
    """np.asarray(z, dtype=float) would drop the imaginary part with only a warning."""
    with pytest.raises(InputError, match=rf"{re.escape(name)} must be real, got a complex"):
        call(lambda a: a + 0.5j)
    # an imaginary part of exactly zero is still complex input: rejected, with the way out
    with pytest.raises(InputError, match=r"max \|imag\| = 0\); pass .*\.real"):
        call(lambda a: a.astype(complex))


def test_integer_and_list_input_still_works() -> None:
    ints = [[0, -3, 2], [3, 0, -1], [-2, 1, 0]]
    as_float = symrb.J_inv(np.array(ints, dtype=float), np.array([1.0, 2.0, 3.0]))
    np.testing.assert_array_equal(symrb.J_inv(ints, [1, 2, 3]), as_float)
    sol = symrb.symmetric_flow(np.eye(3, dtype=int), np.zeros((3, 3), dtype=int), [1, 2, 3], 1, 2)
    assert sol.success and sol.y.Q.dtype == np.float64
    np.testing.assert_array_equal(symrb.hat([1, 2, 3]), symrb.hat(np.array([1.0, 2.0, 3.0])))


@pytest.mark.parametrize(
    "call",
    [
        lambda lam: symrb.J(M, lam),
        lambda lam: symrb.solve_moser_veselov(M, lam),
        lambda lam: symrb.kinetic_energy(M, lam),
        lambda lam: symrb.mv_algorithm2(Q, 0.1 * M, lam, 2),
        lambda lam: symrb.integrate(symrb.RigidBody, (0, 1), (Q, M), lam=lam),
    ],
)
def test_the_matrix_Lambda_for_lam_is_named_as_such(call) -> None:
    """Before: "lam must be positive ... min lam_i = 0" (the zeros off the diagonal)."""
    with pytest.raises(InputError) as info:
        call(np.diag(LAM))
    msg = str(info.value)
    assert "lam is the 1-D diagonal of Lambda" in msg and "shape (3, 3)" in msg
    assert "np.diag(lam)" in msg and "min lam_i" not in msg


def test_a_failing_square_lam_gets_a_hint_and_a_batch_of_diagonals_still_works() -> None:
    full = np.array([[1.0, 0.2, 0.1], [0.2, -2.0, 0.3], [0.1, 0.3, 1.5]])  # not a valid batch
    with pytest.raises(
        InputError, match=r"min lam_i \+ lam_j = -1.8.*got the square shape \(3, 3\)"
    ):
        symrb.J(M, full)
    batch = np.array([[0.7, 1.1, 1.6], [1.0, 2.0, 3.0], [0.5, 0.6, 0.7]])  # three diagonals
    out = symrb.J(M, batch)
    assert out.shape == (3, 3, 3)
    np.testing.assert_allclose(out[1], symrb.J(M, batch[1]))
    with pytest.raises(InputError, match=r"lam is the 1-D diagonal .* got shape \(3, 1\)"):
        symrb.J(M, LAM[:, None])


@pytest.mark.parametrize("flow", [symrb.RigidBody, symrb.McLachlanScovel])
def test_integrate_rejects_a_non_orthogonal_attitude(flow) -> None:
    y0 = dict(zip(flow.state, (1.01 * Q, Q @ M), strict=True))
    with pytest.raises(InputError, match=r"y0\['Q'\] must be orthogonal; max \|.*\| = 2\.0"):
        symrb.integrate(flow, (0, 1), y0, lam=LAM)
    reflection = np.diag([1.0, 1.0, -1.0])
    y0 = dict(zip(flow.state, (reflection, reflection @ M), strict=True))
    with pytest.raises(InputError, match=r"y0\['Q'\] must have det \+1"):
        symrb.integrate(flow, (0, 1), y0, lam=LAM)


def test_integrate_multi_sample_rejects_a_non_orthogonal_sample_but_symmetric_flow_allows_gl() -> (
    None
):
    Qa = symrb.random_SO(3, (2,), seed=1)
    Qa[1] *= 1.1
    with pytest.raises(InputError, match=r"y0\['Q'\] must be orthogonal"):
        symrb.integrate(symrb.MultiSampleSymmetricRigidBody, (0, 1), (Qa, Qa), lam=LAM)
    # the symmetric rigid body is defined on gl(n) x gl(n) (claim S12): any Q is accepted
    sol = symrb.integrate(symrb.SymmetricRigidBody, (0, 1), (1.1 * Q, 0.2 * Q), lam=LAM)
    assert sol.success


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (
            lambda: symrb.symmetric_flow(Q, Q, LAM, 0.1 + 0j, 2),
            "h must be a real number, got complex",
        ),
        (lambda: symrb.symmetric_flow(Q, Q, LAM, "0.1", 2), "h must be a real number, got str"),
        (lambda: symrb.symmetric_flow(Q, Q, LAM, np.nan, 2), "h must be finite"),
        (lambda: symrb.mv_algorithm2(Q, M, LAM, 2.5), "steps must be an integer >= 0, got 2.5"),
        (lambda: symrb.mv_algorithm2(Q, M, LAM, True), "steps must be an integer >= 0, got True"),
        (lambda: symrb.solve_moser_veselov(M, LAM, tol=1j), "tol must be a real number"),
        (lambda: symrb.solve_moser_veselov(M, LAM, maxiter=0), "maxiter must be an integer >= 1"),
        (lambda: symrb.solve_orbit_bvp(M, M, 1j), "T must be a real number"),
        (lambda: symrb.symmetric_flow(Q, Q, LAM, 0.1, 2, save_every=2.0), None),
    ],
)
def test_scalars(call, match) -> None:
    if match is None:  # an integral float is accepted as a count
        assert call().success
        return
    with pytest.raises(InputError, match=match):
        call()


def test_string_arrays_are_not_parsed_as_numbers() -> None:
    with pytest.raises(InputError, match="lam must be a real array of numbers, got dtype <U3"):
        symrb.J(M, ["0.7", "1.1", "1.6"])
