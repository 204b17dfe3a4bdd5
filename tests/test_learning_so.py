"""The SO(n) network of claim D9 (symrb.learning): gradients from costates against central
differences along U_k exp(t xi) and against PyTorch autograd (an independent reverse mode, for the
SO(n) network and the ResNet), batching, validation."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.linalg import expm
from scipy.stats import special_ortho_group

from symrb import learning
from symrb.errors import InputError


def _rot(n, size, rng):
    return special_ortho_group.rvs(n, size=size, random_state=rng).reshape(size, n, n)


def _small_rot(n, size, rng, scale=0.5):
    out = []
    for _ in range(size):
        a = scale * rng.standard_normal((n, n))
        out.append(expm(a - a.T))
    return np.array(out)


def _problem(seed, n=3, N=3, M=4):
    rng = np.random.default_rng(seed)
    return (
        _rot(n, M, rng),
        _small_rot(n, N, rng),
        rng.uniform(0.5, 2.0, n),
        _rot(n, M, rng),
    )


def _loss_direct(Q0, U, lam, T, alpha):
    """The loss written out sample by sample (no costates, no kernels)."""
    total = 0.0
    for Q, Tg in zip(Q0, T, strict=True):
        for Uk in U:
            Q = Q @ Uk
        total += 0.5 * np.sum((Q - Tg) ** 2)
    return total + alpha * sum(np.trace(np.diag(lam) @ (np.eye(len(lam)) - Uk)) for Uk in U)


def _basis(n):
    for i in range(n):
        for j in range(i + 1, n):
            xi = np.zeros((n, n))
            xi[i, j], xi[j, i] = 1.0, -1.0
            yield xi


@pytest.mark.parametrize("alpha", [0.0, 0.7])
def test_gradient_matches_central_difference_along_exp(alpha):
    Q0, U, lam, T = _problem(1, n=4, N=3, M=5)
    loss, G = learning.so_network_gradients(Q0, U, lam, T, alpha=alpha)
    assert loss == pytest.approx(_loss_direct(Q0, U, lam, T, alpha), rel=1e-13)
    np.testing.assert_allclose(G, -np.swapaxes(G, 1, 2), atol=1e-14)
    h = 1e-5
    for k in range(U.shape[0]):
        for xi in _basis(4):
            up, um = U.copy(), U.copy()
            up[k], um[k] = U[k] @ expm(h * xi), U[k] @ expm(-h * xi)
            fd = (_loss_direct(Q0, up, lam, T, alpha) - _loss_direct(Q0, um, lam, T, alpha)) / (
                2 * h
            )
            assert fd == pytest.approx(np.sum(G[k] * xi), abs=1e-8 * np.abs(G).max())


def test_gradient_sign_is_checked():
    """A descent step along -G lowers the loss (a gradient of the wrong sign would raise it)."""
    Q0, U, lam, T = _problem(2)
    loss, G = learning.so_network_gradients(Q0, U, lam, T, alpha=0.3)
    U2 = np.array([Uk @ expm(-1e-3 * Gk) for Uk, Gk in zip(U, G, strict=True)])
    assert learning.so_network_gradients(Q0, U2, lam, T, alpha=0.3)[0] < loss


def test_forward_and_costates_batch_match_per_sample():
    Q0, U, lam, T = _problem(3)
    Q, P = learning.so_network_costates(Q0, U, T)
    assert Q.shape == P.shape == (4, 4, 3, 3)
    for a in range(4):
        q = Q0[a]
        for k in range(3):
            q = q @ U[k]
            np.testing.assert_allclose(Q[k + 1, a], q, atol=1e-14)
        np.testing.assert_allclose(P[3, a], T[a] - q, atol=1e-14)
        for k in range(2, -1, -1):
            np.testing.assert_allclose(P[k, a], P[k + 1, a] @ U[k].T, atol=1e-13)
    np.testing.assert_allclose(learning.so_network_forward(Q0, U), Q, atol=0)


def test_extremal_residual_is_twice_the_gradient_norm():
    Q0, U, lam, T = _problem(4)
    r = learning.so_extremal_residual(Q0, U, lam, T, alpha=0.4)
    G = learning.so_network_gradients(Q0, U, lam, T, alpha=0.4)[1]
    np.testing.assert_allclose(r, 2 * np.linalg.norm(G, axis=(1, 2)), rtol=1e-12)


def test_inputs_not_mutated():
    Q0, U, lam, T = _problem(5)
    copies = [a.copy() for a in (Q0, U, lam, T)]
    learning.so_network_gradients(Q0, U, lam, T, alpha=0.5)
    learning.so_network_costates(Q0, U, T)
    for a, c in zip((Q0, U, lam, T), copies, strict=True):
        np.testing.assert_array_equal(a, c)


@pytest.mark.parametrize(
    ("change", "match"),
    [
        (lambda a: {**a, "U": a["U"] * 1.1}, "U must be orthogonal"),
        (lambda a: {**a, "U": a["U"][0]}, r"U must have shape \(N, n, n\)"),
        (lambda a: {**a, "Q0": a["Q0"] * 1.1}, "Q0 must be orthogonal"),
        (lambda a: {**a, "Q0": -a["Q0"]}, "Q0 must have det"),
        (lambda a: {**a, "targets": a["targets"][:2]}, "targets must have shape"),
        (lambda a: {**a, "lam": a["lam"][:2]}, "lam must"),
        (lambda a: {**a, "lam": -a["lam"]}, "lam must be positive"),
        (lambda a: {**a, "alpha": -1.0}, "alpha must be >= 0"),
        (lambda a: {**a, "alpha": "x"}, "alpha must be a real number"),
    ],
)
def test_validation(change, match):
    Q0, U, lam, T = _problem(6)
    args = change({"Q0": Q0, "U": U, "lam": lam, "targets": T, "alpha": 0.5})
    with pytest.raises(InputError, match=match):
        learning.so_network_gradients(**args)


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    n=st.integers(2, 6),
    N=st.integers(1, 5),
    M=st.integers(1, 7),
    alpha=st.floats(0.0, 2.0),
)
def test_gradient_directional_derivative_random_sizes(seed, n, N, M, alpha):
    """d/dt L(U_k exp(t xi)) = tr(G_k^T xi) for a random skew xi, by a 4-point difference."""
    Q0, U, lam, T = _problem(seed, n=n, N=N, M=M)
    rng = np.random.default_rng(seed + 1)
    _loss, G = learning.so_network_gradients(Q0, U, lam, T, alpha=alpha)
    k = int(rng.integers(N))
    a = rng.standard_normal((n, n))
    xi = a - a.T

    def f(t):
        Ut = U.copy()
        Ut[k] = U[k] @ expm(t * xi)
        return _loss_direct(Q0, Ut, lam, T, alpha)

    h = 1e-3
    fd = (8 * (f(h) - f(-h)) - (f(2 * h) - f(-2 * h))) / (12 * h)
    scale = max(1.0, float(np.abs(G).max() * np.abs(xi).max()))
    assert fd == pytest.approx(np.sum(G[k] * xi), abs=1e-7 * scale)


# ---------------------------------------------------------------------------------------------
# PyTorch autograd as an independent reverse mode


def _torch():
    torch = pytest.importorskip("torch")
    torch.set_default_dtype(torch.float64)
    return torch


def _torch_so_grad(torch, Q0, U, lam, T, alpha):
    """Euclidean gradient dL/dU by autograd, then its component along U_k so(n): the directional
    derivative along U_k xi is tr((dL/dU_k)^T U_k xi), so G_k = skew(U_k^T dL/dU_k)."""
    Ut = torch.tensor(U, requires_grad=True)
    Q = torch.tensor(Q0)
    for k in range(U.shape[0]):
        Q = Q @ Ut[k]
    L = torch.tensor(np.diag(lam))
    eye = torch.eye(U.shape[-1])
    loss = 0.5 * ((Q - torch.tensor(T)) ** 2).sum()
    loss = loss + alpha * sum(torch.trace(L @ (eye - Ut[k])) for k in range(U.shape[0]))
    loss.backward()
    A = np.swapaxes(U, 1, 2) @ Ut.grad.numpy()
    return float(loss.detach()), 0.5 * (A - np.swapaxes(A, 1, 2))


@settings(max_examples=20, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    n=st.integers(2, 7),
    N=st.integers(1, 6),
    M=st.integers(1, 9),
    alpha=st.floats(0.0, 2.0),
)
def test_so_gradients_equal_torch_autograd(seed, n, N, M, alpha):
    torch = _torch()
    Q0, U, lam, T = _problem(seed, n=n, N=N, M=M)
    loss, G = learning.so_network_gradients(Q0, U, lam, T, alpha=alpha)
    tloss, tG = _torch_so_grad(torch, Q0, U, lam, T, alpha)
    assert loss == pytest.approx(tloss, rel=1e-12)
    assert np.abs(G - tG).max() <= 1e-10 * np.abs(tG).max()


@settings(max_examples=20, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    n=st.integers(1, 6),
    N=st.integers(1, 6),
    M=st.integers(1, 9),
    act=st.sampled_from(["tanh", "logistic"]),
    res=st.booleans(),
)
def test_resnet_gradients_equal_torch_autograd(seed, n, N, M, act, res):
    torch = _torch()
    rng = np.random.default_rng(seed)
    x0, y = rng.standard_normal((M, n)), rng.standard_normal((M, n))
    K, b = 0.7 * rng.standard_normal((N, n, n)), 0.7 * rng.standard_normal((N, n))
    loss, dK, db = learning.loss_gradients(x0, K, b, y, activation=act, residual=res)
    Kt, bt = torch.tensor(K, requires_grad=True), torch.tensor(b, requires_grad=True)
    x = torch.tensor(x0)
    sig = torch.tanh if act == "tanh" else torch.sigmoid
    for k in range(N):
        z = sig(x @ Kt[k].T + bt[k])
        x = x + z if res else z
    tloss = 0.5 * ((x - torch.tensor(y)) ** 2).sum()
    tloss.backward()
    assert loss == pytest.approx(float(tloss.detach()), rel=1e-12)
    for mine, theirs in ((dK, Kt.grad.numpy()), (db, bt.grad.numpy())):
        assert np.abs(mine - theirs).max() <= 1e-10 * max(np.abs(theirs).max(), 1e-300)


# ---------------------------------------------------------------------------------------------
# training three ways


def _task():
    Q0, T = learning.so_rotation_task(3, samples=8, seed=0)
    return Q0, T, np.array([1.0, 2.0, 3.0]), 1.0, np.tile(np.eye(3), (3, 1, 1))


@pytest.fixture(scope="module")
def trained():
    Q0, T, lam, alpha, U0 = _task()
    return {
        "gradient": learning.train_so_gradient(
            Q0, T, U0, lam, alpha=alpha, steps=2000, line_search=True, tol=1e-10
        ),
        "momentum": learning.train_so_gradient(
            Q0,
            T,
            U0,
            lam,
            alpha=alpha,
            steps=2000,
            lr=0.05,
            momentum=0.8,
            retraction="exp",
            tol=1e-10,
        ),
        "msa": learning.train_so_msa(Q0, T, U0, lam, alpha=alpha, steps=2000, tol=1e-10),
        "shooting": learning.train_so_shooting(Q0, T, lam, alpha, 3, tol=1e-13),
    }


@pytest.mark.parametrize("method", ["gradient", "momentum", "msa", "shooting"])
def test_each_method_converges_and_lowers_the_loss(trained, method):
    res = trained[method]
    assert res.converged
    assert res.losses[-1] < 0.1 * res.losses[0]
    assert res.losses.shape == res.residuals.shape == (res.iterations + 1,)
    assert res.residual == res.residuals[-1] <= 1e-9
    np.testing.assert_allclose(
        np.swapaxes(res.U, 1, 2) @ res.U, np.tile(np.eye(3), (3, 1, 1)), atol=1e-12
    )


def test_descent_methods_decrease_monotonically(trained):
    for method in ("gradient", "msa"):
        losses = trained[method].losses
        assert np.all(np.diff(losses) <= 1e-12 * losses[0]), method


def test_three_methods_agree_at_convergence(trained):
    ref = trained["shooting"]
    for method in ("gradient", "momentum", "msa"):
        res = trained[method]
        assert res.losses[-1] == pytest.approx(ref.losses[-1], rel=1e-12)
        np.testing.assert_allclose(res.U, ref.U, atol=1e-8)


@pytest.mark.parametrize("method", ["gradient", "msa", "shooting"])
def test_extremal_equations_hold_at_convergence(trained, method):
    """alpha J_D(U_k) = sum_a ((Q^a_k)^T P^a_k - (P^a_k)^T Q^a_k), P^a_N = -(Q^a_N - T^a), at
    every layer, to the solver's tolerance (the residual is twice the gradient norm)."""
    Q0, T, lam, alpha, _ = _task()
    res = trained[method]
    r = learning.so_extremal_residual(Q0, res.U, lam, T, alpha)
    assert r.max() <= 2 * res.residual + 1e-14  # two routes to the same quantity
    assert r.max() <= 2e-9
    # a check that can fail: the start (U = I) is far from extremal
    assert learning.so_extremal_residual(Q0, _task()[4], lam, T, alpha).min() > 1e-2


def test_msa_without_penalty_does_not_converge_here():
    """rho = 0 (the basic MSA) oscillates on this task: the penalty is what makes it converge."""
    Q0, T, lam, alpha, U0 = _task()
    res = learning.train_so_msa(Q0, T, U0, lam, alpha=alpha, rho=0.0, steps=200)
    assert not res.converged
    assert res.losses[-1] > 10 * learning.train_so_msa(Q0, T, U0, lam, alpha=alpha).losses[-1]


def test_procrustes_against_grid_so2():
    rng = np.random.default_rng(0)
    theta = np.linspace(0, 2 * np.pi, 200001)
    grid = np.stack([np.cos(theta), -np.sin(theta), np.sin(theta), np.cos(theta)], -1)
    grid = grid.reshape(-1, 2, 2)
    for _ in range(20):
        A = rng.standard_normal((2, 2))
        U = learning.so_procrustes(A)
        best = np.einsum("ij,gji->g", A, grid).max()
        val = np.trace(A @ U)
        assert np.linalg.det(U) == pytest.approx(1.0)
        assert best <= val + 1e-12
        assert val - best <= 1e-9 * np.abs(A).max()


def test_procrustes_against_dense_sample_so3():
    rng = np.random.default_rng(1)
    q = rng.standard_normal((400000, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    w, x, y, z = q.T
    R = np.stack(
        [
            1 - 2 * (y * y + z * z),
            2 * (x * y - z * w),
            2 * (x * z + y * w),
            2 * (x * y + z * w),
            1 - 2 * (x * x + z * z),
            2 * (y * z - x * w),
            2 * (x * z - y * w),
            2 * (y * z + x * w),
            1 - 2 * (x * x + y * y),
        ],
        -1,
    ).reshape(-1, 3, 3)
    for _ in range(5):
        A = rng.standard_normal((3, 3))
        if np.linalg.det(A) > 0 and rng.random() < 0.5:
            A[:, 0] *= -1  # reflections too: the determinant fix must act
        U = learning.so_procrustes(A)
        vals = np.einsum("ij,gji->g", A, R)
        val = np.trace(A @ U)
        assert np.linalg.det(U) == pytest.approx(1.0)
        assert vals.max() <= val + 1e-12
        assert val - vals.max() <= 2e-3 * np.abs(A).sum()  # the sample's resolution
        # the best sample lies next to the maximiser
        assert np.linalg.norm(R[np.argmax(vals)] - U) < 0.15


def test_procrustes_batched_and_not_mutating():
    A = np.random.default_rng(2).standard_normal((4, 2, 3, 3))
    A0 = A.copy()
    U = learning.so_procrustes(A)
    assert U.shape == A.shape
    np.testing.assert_array_equal(A, A0)
    np.testing.assert_allclose(U[1, 1], learning.so_procrustes(A[1, 1]), atol=0)


def test_training_progress_bars(capsys):
    pytest.importorskip("tqdm")
    Q0, T, lam, alpha, U0 = _task()
    learning.train_so_gradient(Q0, T, U0, lam, alpha=alpha, steps=3, progress=True)
    learning.train_so_msa(Q0, T, U0, lam, alpha=alpha, steps=3, progress=True)
    learning.train_so_shooting(Q0, T, lam, alpha, 3, maxfev=5, progress=True)
    err = capsys.readouterr().err
    for desc in ("gradient descent", "extended MSA", "shooting"):
        assert desc in err


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda a: learning.train_so_gradient(*a, lr=0.0), "lr must be > 0"),
        (lambda a: learning.train_so_gradient(*a, momentum=1.0), "momentum must be in"),
        (lambda a: learning.train_so_gradient(*a, retraction="qr"), "retraction must be"),
        (lambda a: learning.train_so_gradient(*a, steps=-1), "steps must be an integer"),
        (lambda a: learning.train_so_msa(*a, rho=-1.0), "rho must be >= 0"),
        (lambda a: learning.train_so_shooting(a[0], a[1], a[3], 0.0, 3), "alpha must be > 0"),
        (lambda a: learning.train_so_shooting(a[0], a[1], a[3], 1.0, 0), "layers must be"),
    ],
)
def test_training_validation(call, match):
    Q0, T, lam, _alpha, U0 = _task()
    with pytest.raises(InputError, match=match):
        call((Q0, T, U0, lam))
