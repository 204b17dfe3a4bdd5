"""Numerics of symrb.learning (claims D5, D6): batching, validation, hard cases, properties."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symrb import learning
from symrb.errors import InputError

KINDS = [(a, r) for a in ("tanh", "logistic") for r in (True, False)]


def _net(seed, N=3, M=4, n=3, scale=0.7):
    rng = np.random.default_rng(seed)
    return (
        rng.standard_normal((M, n)),
        scale * rng.standard_normal((N, n, n)),
        scale * rng.standard_normal((N, n)),
        rng.standard_normal((M, n)),
    )


def _loss(x0, K, b, y, act, res):
    sig = np.tanh if act == "tanh" else (lambda z: 1.0 / (1.0 + np.exp(-z)))
    x = x0
    for Kk, bk in zip(K, b, strict=True):
        x = (x if res else 0.0) + sig(x @ Kk.T + bk)
    return 0.5 * np.sum((x - y) ** 2)


@pytest.mark.parametrize(("act", "res"), KINDS)
def test_batch_matches_per_sample_loop(act, res):
    x0, K, b, y = _net(0)
    states = learning.resnet_forward(x0, K, b, activation=act, residual=res)
    p = learning.costate_sweep(states, K, b, y, activation=act, residual=res)
    loss, gK, gb = learning.loss_gradients(x0, K, b, y, activation=act, residual=res)
    sK, sb, sl = np.zeros_like(gK), np.zeros_like(gb), 0.0
    for a in range(x0.shape[0]):
        sa = learning.resnet_forward(x0[a], K, b, activation=act, residual=res)
        np.testing.assert_allclose(sa, states[:, a], rtol=0, atol=1e-14)
        pa = learning.costate_sweep(sa, K, b, y[a], activation=act, residual=res)
        np.testing.assert_allclose(pa, p[:, a], rtol=0, atol=1e-14)
        la, ka, ba = learning.loss_gradients(x0[a], K, b, y[a], activation=act, residual=res)
        sK, sb, sl = sK + ka, sb + ba, sl + la
    np.testing.assert_allclose(gK, sK, rtol=1e-13, atol=1e-14)
    np.testing.assert_allclose(gb, sb, rtol=1e-13, atol=1e-14)
    assert loss == pytest.approx(sl, rel=1e-14)


@pytest.mark.parametrize("act", ["tanh", "logistic"])
def test_residual_layer_is_a_perturbation_of_the_identity(act):
    """Claim D6: with weights eps K the residual layer's Jacobian in x tends to I, the plain
    layer's to 0 (central differences of one layer)."""
    rng = np.random.default_rng(5)
    K, b, x = rng.standard_normal((1, 3, 3)), rng.standard_normal((1, 3)), rng.standard_normal(3)

    def jacobian(eps, residual, step=1e-6):
        cols = [
            (
                learning.resnet_forward(x + step * e, eps * K, b, act, residual)[-1]
                - learning.resnet_forward(x - step * e, eps * K, b, act, residual)[-1]
            )
            / (2 * step)
            for e in np.eye(3)
        ]
        return np.array(cols).T

    for eps in (1e-2, 1e-4):
        size = eps * np.abs(K).max()  # |dsigma| <= 1: the layer's Jacobian is I (+ or 0) + O(eps)
        assert np.abs(jacobian(eps, True) - np.eye(3)).max() <= 2 * size
        assert np.abs(jacobian(eps, False)).max() <= 2 * size


def test_sample_axes_can_be_2d():
    x0, K, b, y = _net(1, M=6)
    _, gK, gb = learning.loss_gradients(x0, K, b, y)
    _, gK2, gb2 = learning.loss_gradients(x0.reshape(2, 3, 3), K, b, y.reshape(2, 3, 3))
    np.testing.assert_allclose(gK2, gK, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(gb2, gb, rtol=1e-13, atol=1e-15)


@pytest.mark.parametrize(("act", "res"), KINDS)
def test_gradients_match_central_differences(act, res):
    x0, K, b, y = _net(2)
    _, gK, gb = learning.loss_gradients(x0, K, b, y, activation=act, residual=res)
    h = 1e-6
    for idx in [(0, 0, 0), (1, 2, 1), (2, 1, 2)]:
        Kp, Km = K.copy(), K.copy()
        Kp[idx] += h
        Km[idx] -= h
        fd = (_loss(x0, Kp, b, y, act, res) - _loss(x0, Km, b, y, act, res)) / (2 * h)
        assert gK[idx] == pytest.approx(fd, rel=1e-6, abs=1e-8)
    bp, bm = b.copy(), b.copy()
    bp[1, 0] += h
    bm[1, 0] -= h
    fd = (_loss(x0, K, bp, y, act, res) - _loss(x0, K, bm, y, act, res)) / (2 * h)
    assert gb[1, 0] == pytest.approx(fd, rel=1e-6, abs=1e-8)


def test_inputs_not_mutated():
    x0, K, b, y = _net(3)
    copies = [a.copy() for a in (x0, K, b, y)]
    states = learning.resnet_forward(x0, K, b)
    s_copy = states.copy()
    learning.costate_sweep(states, K, b, y)
    learning.loss_gradients(x0, K, b, y)
    learning.train(x0, y, K, b, steps=3, lr=0.01)
    for a, c in zip((x0, K, b, y), copies, strict=True):
        np.testing.assert_array_equal(a, c)
    np.testing.assert_array_equal(states, s_copy)


def test_saturated_activations_stay_finite_without_warnings():
    x0, K, b, y = _net(4)
    K = 1e4 * K  # pre-activations of size ~1e4: tanh and the logistic saturate
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for act, res in KINDS:
            loss, gK, gb = learning.loss_gradients(x0, K, b, y, activation=act, residual=res)
            assert np.isfinite(loss) and np.all(np.isfinite(gK)) and np.all(np.isfinite(gb))


def test_training_decreases_loss():
    x0, y, _c = learning.toy_classification(64, seed=0)
    rng = np.random.default_rng(0)
    K0 = 0.1 * rng.standard_normal((4, 2, 2))
    b0 = np.zeros((4, 2))
    res = learning.train(x0, y, K0, b0, steps=60, lr=0.002)
    assert res.losses.shape == (61,)
    assert res.losses[-1] < 0.8 * res.losses[0]
    assert np.all(np.diff(res.losses) <= 1e-12)  # small steps: monotone descent


def test_training_progress_bar(capsys):
    x0, y, _c = learning.toy_classification(16, seed=1)
    K0, b0 = np.zeros((2, 2, 2)), np.zeros((2, 2))
    quiet = learning.train(x0, y, K0, b0, steps=20, lr=0.01)
    assert capsys.readouterr().err == ""
    shown = learning.train(x0, y, K0, b0, steps=20, lr=0.01, progress=True)
    err = capsys.readouterr().err
    assert "train" in err and "20/20" in err
    np.testing.assert_array_equal(shown.losses, quiet.losses)  # the bar changes nothing else


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (
            lambda: learning.resnet_forward(np.ones(3), np.ones((2, 3, 2)), np.ones((2, 3))),
            "K must",
        ),
        (lambda: learning.resnet_forward(np.ones(3), np.ones((2, 3, 3)), np.ones((3, 3))), "beta"),
        (lambda: learning.resnet_forward(np.ones(2), np.ones((2, 3, 3)), np.ones((2, 3))), "x0"),
        (
            lambda: learning.resnet_forward(
                np.ones(3), np.ones((1, 3, 3)), np.ones((1, 3)), "relu"
            ),
            "activation",
        ),
        (
            lambda: learning.resnet_forward([np.nan, 0, 0], np.ones((1, 3, 3)), np.ones((1, 3))),
            "x0 must be finite",
        ),
        (
            lambda: learning.costate_sweep(np.ones((2, 3)), np.ones((2, 3, 3)), np.ones((2, 3)), 0),
            "states",
        ),
        (
            lambda: learning.loss_gradients(
                np.ones((4, 3)), np.ones((1, 3, 3)), np.ones((1, 3)), np.ones((3, 3))
            ),
            "targets",
        ),
        (
            lambda: learning.train(
                np.ones(3), np.ones(3), np.ones((1, 3, 3)), np.ones((1, 3)), lr=-1
            ),
            "lr",
        ),
        (
            lambda: learning.train(
                np.ones(3), np.ones(3), np.ones((1, 3, 3)), np.ones((1, 3)), steps=1.5
            ),
            "steps",
        ),
        (lambda: learning.toy_classification(0), "num"),
    ],
)
def test_validation_errors(call, match):
    with pytest.raises(InputError, match=match):
        call()


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**31),
    N=st.integers(1, 4),
    n=st.integers(1, 4),
    M=st.integers(1, 5),
    kind=st.sampled_from(KINDS),
)
def test_costates_are_minus_state_gradients(seed, N, n, M, kind):
    """p^a_k = -dPhi/dx^a_k, checked by the complex step on the tail network (independent code)."""
    act, res = kind
    x0, K, b, y = _net(seed, N=N, M=M, n=n)
    states = learning.resnet_forward(x0, K, b, activation=act, residual=res)
    p = learning.costate_sweep(states, K, b, y, activation=act, residual=res)
    rng = np.random.default_rng(seed)
    k = int(rng.integers(0, N + 1))
    a, i = int(rng.integers(0, M)), int(rng.integers(0, n))
    xk = states[k].astype(complex)
    xk[a, i] += 1e-30j
    grad = _loss(xk, K[k:], b[k:], y, act, res).imag / 1e-30
    assert -p[k, a, i] == pytest.approx(grad, rel=1e-10, abs=1e-12)


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**31), kind=st.sampled_from(KINDS))
def test_loss_is_translation_consistent(seed, kind):
    """Phi(u - eps g) < Phi(u) for a small step along the computed gradient g (descent)."""
    act, res = kind
    x0, K, b, y = _net(seed)
    loss, gK, gb = learning.loss_gradients(x0, K, b, y, activation=act, residual=res)
    norm2 = float(np.sum(gK**2) + np.sum(gb**2))
    if norm2 < 1e-12:
        return
    eps = 1e-4 / np.sqrt(norm2)
    new = learning.loss_gradients(x0, K - eps * gK, b - eps * gb, y, activation=act, residual=res)[
        0
    ]
    assert new < loss
    # first-order prediction of the decrease
    assert (loss - new) == pytest.approx(eps * norm2, rel=1e-2)


# ---------------------------------------------------------------------------------------------
# extended MSA for the residual network; scikit-learn's digits


def test_msa_first_inner_step_is_a_gradient_step():
    """One inner step from the current weights: the state penalty has zero gradient there, so the
    update is u - lr dPhi/du (the costates are minus the gradients)."""
    x0, y, _ = learning.toy_classification(60, seed=1)
    rng = np.random.default_rng(0)
    K, b = 0.3 * rng.standard_normal((3, 2, 2)), 0.3 * rng.standard_normal((3, 2))
    msa = learning.train_msa(x0, y, K, b, steps=1, rho=5.0, inner_steps=1, inner_lr=1e-3)
    gd = learning.train(x0, y, K, b, steps=1, lr=1e-3)
    np.testing.assert_allclose(msa.K, gd.K, atol=1e-14)
    np.testing.assert_allclose(msa.beta, gd.beta, atol=1e-14)


def test_msa_lowers_the_loss_and_penalty_acts():
    x0, y, _ = learning.toy_classification(200, seed=0)
    K, b = np.zeros((4, 2, 2)), np.zeros((4, 2))
    res = learning.train_msa(x0, y, K, b, steps=30, inner_lr=0.001, inner_steps=3)
    assert res.losses[-1] < 0.9 * res.losses[0]
    other = learning.train_msa(x0, y, K, b, steps=30, rho=0.0, inner_lr=0.001, inner_steps=3)
    assert not np.allclose(res.K, other.K)  # rho enters the update
    np.testing.assert_array_equal(K, 0.0)  # inputs not mutated


def test_msa_validation():
    x0, y, _ = learning.toy_classification(10, seed=0)
    K, b = np.zeros((2, 2, 2)), np.zeros((2, 2))
    with pytest.raises(InputError, match="rho must be >= 0"):
        learning.train_msa(x0, y, K, b, rho=-1.0)
    with pytest.raises(InputError, match="inner_steps must be an integer >= 1"):
        learning.train_msa(x0, y, K, b, inner_steps=0)
    with pytest.raises(InputError, match="inner_lr must be > 0"):
        learning.train_msa(x0, y, K, b, inner_lr=0.0)


def test_resnet_predict_reads_the_last_entries():
    x0 = np.array([[5.0, 0.0, 1.0, 2.0], [5.0, 0.0, 3.0, -1.0]])
    K, b = np.zeros((1, 4, 4)), np.zeros((1, 4))
    np.testing.assert_array_equal(learning.resnet_predict(x0, K, b, classes=2), [1, 0])
    with pytest.raises(InputError, match="classes must be at most"):
        learning.resnet_predict(x0, K, b, classes=5)


def test_digits_gradient_descent_learns():
    pytest.importorskip("sklearn")
    task = learning.digits_task(features=12, seed=0)
    assert task.x_train.shape[1] == 22 and task.classes == 10
    assert len(task.labels_train) + len(task.labels_test) == 1797
    np.testing.assert_array_equal(task.x_train[:, 12:], 0.0)
    np.testing.assert_array_equal(task.y_train[:, 12:].sum(axis=1), 1.0)
    n = task.x_train.shape[1]
    K, b = np.zeros((3, n, n)), np.zeros((3, n))
    res = learning.train(task.x_train, task.y_train, K, b, steps=100, lr=5e-4)
    acc = np.mean(learning.resnet_predict(task.x_test, res.K, res.beta, 10) == task.labels_test)
    assert res.losses[-1] < 0.7 * res.losses[0]
    assert acc > 0.8  # chance is 0.1
