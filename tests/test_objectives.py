"""The training loop's variants against independent computations: fresh states from a box and
their targets (the system's field, computed apart), the learning-rate schedules' closed forms,
PyTorch-style Adam with L2 weight decay written out by hand, and the run fields that select
them (validated, and out of the hashes at their defaults)."""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np
import optax
import pytest

import models
import systems
from bench.core import (
    BoxObjective,
    BoxStates,
    RunConfig,
    TrainConfig,
    lr_schedule,
    optimizer,
    train,
)

BOX = (0.0, 2 * math.pi, -10.0, 10.0)


def _pendulum():
    return systems.make("chain_pendulum", k=2)


def test_box_states_are_uniform_in_the_box_with_the_true_field():
    system = _pendulum()
    out = BoxStates(system, BOX, batch=256, seed=3, dtype="float64").take(4)
    assert out.shape == (4, 256, 2, 4)
    z, dz = out[..., 0, :].reshape(-1, 4), out[..., 1, :].reshape(-1, 4)
    assert z[:, :2].min() >= 0 and z[:, :2].max() < 2 * math.pi
    assert z[:, 2:].min() >= -10 and z[:, 2:].max() < 10
    # uniform: means and variances of U(a, b) within 5 standard errors (n = 1024)
    for cols, (a, b) in ((slice(0, 2), BOX[:2]), (slice(2, 4), BOX[2:])):
        x = z[:, cols].ravel()
        se = (b - a) / math.sqrt(12 * len(x))
        assert abs(x.mean() - (a + b) / 2) < 5 * se
        assert x.var() == pytest.approx((b - a) ** 2 / 12, rel=0.15)
    # the targets: the system's field at those states, by systems.derivatives
    np.testing.assert_allclose(dz, systems.derivatives(system, z), rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(dz[:, :2], z[:, 2:])  # dq/dt = qdot
    # fresh draws every call; the same seed, the same draws
    again = BoxStates(system, BOX, batch=256, seed=3, dtype="float64")
    first = again.take(4)
    np.testing.assert_array_equal(first, out)
    assert not np.allclose(again.take(4), first)


def test_box_training_fits_the_field_of_a_box():
    """A NODE+SO trained on fresh box states learns the pendulum's accelerations there."""
    system = systems.make("chain_pendulum", k=1)
    scene = models.Scene(dof=1, angular=(True,))
    import jax

    model = models.make("node_so", scene, key=jax.random.PRNGKey(0), width=32, depth=2)
    box = (0.0, 2 * math.pi, -2.0, 2.0)
    objective = BoxObjective("chain_pendulum", (("k", 1),), box)
    cfg = TrainConfig(steps=1500, batch=64, lr=1e-2, target="derivative", seed=0)
    res = train(model, None, cfg, objective=objective)
    assert res.status == "ok" and res.steps_done == 1500
    test = BoxStates(system, box, batch=512, seed=99, dtype="float32").take(1)[0]
    z, dz = jnp.asarray(test[:, 0]), test[:, 1]
    pred = np.asarray(jax.vmap(lambda s: res.model.vector_field(0.0, s, jnp.zeros(0)))(z))
    err = np.mean((pred[:, 1] - dz[:, 1]) ** 2) / np.var(dz[:, 1])
    assert err < 0.05, err  # 95% of the acceleration's variance explained
    assert res.losses[-100:].mean() < 0.2 * res.losses[:100].mean()


def test_schedules_closed_forms():
    n, lr = 1000, 1e-3
    one = lr_schedule(TrainConfig(steps=n, lr=lr, schedule="onecycle"))
    # the notebook's OneCycleLR: u = 0.2 + 0.8 s / N, lr/1e4 + (lr - lr/1e4)(1 - cos 2 pi u)/2
    for s in (0, 100, 375, 700, 1000):
        u = 0.2 + 0.8 * s / n
        want = lr / 1e4 + (lr - lr / 1e4) * (1 - math.cos(2 * math.pi * u)) / 2
        assert float(one(jnp.asarray(s))) == pytest.approx(want, rel=1e-6)
    assert float(one(jnp.asarray(375))) == pytest.approx(lr)  # the peak at 3/8 of the steps
    const = lr_schedule(TrainConfig(steps=n, lr=lr, schedule="constant"))
    assert [float(const(jnp.asarray(s))) for s in (0, 999)] == [lr, lr]
    cos = lr_schedule(TrainConfig(steps=n, lr=lr, lr_floor=0.01))
    assert float(cos(jnp.asarray(n // 2))) == pytest.approx(lr * (1 + 0.01) / 2, rel=1e-6)


def test_adam_l2_is_adam_on_the_gradient_plus_decay():
    """Two steps of ``adam_l2`` against Adam written out (PyTorch's Adam(weight_decay=w))."""
    lr, w, b1, b2, eps = 1e-2, 0.1, 0.9, 0.999, 1e-8
    cfg = TrainConfig(steps=10, lr=lr, weight_decay=w, optimizer="adam_l2", schedule="constant")
    opt = optimizer(cfg)
    theta = jnp.array([1.0, -2.0, 0.5])
    grads = [jnp.array([0.3, 0.1, -0.2]), jnp.array([-0.1, 0.4, 0.05])]
    state = opt.init(theta)
    p, m, v = np.asarray(theta, float), np.zeros(3), np.zeros(3)
    for t, g in enumerate(grads, start=1):
        updates, state = opt.update(g, state, theta)
        theta = optax.apply_updates(theta, updates)
        gg = np.asarray(g, float) + w * p
        m, v = b1 * m + (1 - b1) * gg, b2 * v + (1 - b2) * gg**2
        p = p - lr * (m / (1 - b1**t)) / (np.sqrt(v / (1 - b2**t)) + eps)
        np.testing.assert_allclose(np.asarray(theta), p, rtol=1e-5)
    # no clipping: a huge gradient moves Adam by about lr, whatever its norm
    big = optimizer(TrainConfig(steps=10, lr=lr, weight_decay=0.0, optimizer="adam_l2"))
    u, _ = big.update(jnp.array([1e6, 0.0, 0.0]), big.init(theta), theta)
    assert abs(float(u[0])) == pytest.approx(lr, rel=1e-3)


def test_adam_l2_clip_clips_the_gradient_before_the_l2_term():
    """``adam_l2_clip`` against PyTorch's ``clip_grad_norm_(1)`` then ``Adam(weight_decay=w)``
    written out: the gradient's norm is clipped, the decay then added unclipped."""
    lr, w, b1, b2, eps, clip = 1e-2, 0.5, 0.9, 0.999, 1e-8, 1.0
    cfg = TrainConfig(
        steps=10, lr=lr, weight_decay=w, optimizer="adam_l2_clip", schedule="constant", clip=clip
    )
    opt = optimizer(cfg)
    theta = jnp.array([1.0, -2.0, 0.5])
    grads = [jnp.array([3.0, 4.0, 0.0]), jnp.array([0.1, -0.2, 0.05])]  # the first norm 5
    state = opt.init(theta)
    p, m, v = np.asarray(theta, float), np.zeros(3), np.zeros(3)
    for t, g in enumerate(grads, start=1):
        updates, state = opt.update(g, state, theta)
        theta = optax.apply_updates(theta, updates)
        g = np.asarray(g, float)
        gg = g * min(1.0, clip / np.linalg.norm(g)) + w * p
        m, v = b1 * m + (1 - b1) * gg, b2 * v + (1 - b2) * gg**2
        p = p - lr * (m / (1 - b1**t)) / (np.sqrt(v / (1 - b2**t)) + eps)
        np.testing.assert_allclose(np.asarray(theta), p, rtol=1e-5)
    # unclipped, the first step (Adam's is about -lr sign) turns the other way in the second
    # component: 4 - 0.5 * 2 > 0, where 0.8 - 0.5 * 2 < 0
    theta0 = jnp.array([1.0, -2.0, 0.5])
    for name, sign in (("adam_l2_clip", 1.0), ("adam_l2", -1.0)):
        o = optimizer(TrainConfig(steps=10, lr=lr, weight_decay=w, optimizer=name, clip=clip))
        u, _ = o.update(grads[0], o.init(theta0), theta0)
        assert float(u[1]) == pytest.approx(sign * lr, rel=1e-3)


def test_run_fields_are_validated_and_out_of_the_hash_at_their_defaults():
    base = RunConfig(system="chain_pendulum", k=2)
    same = RunConfig(
        system="chain_pendulum",
        k=2,
        optimizer="adamw",
        lr_schedule="cosine",
        weight_decay=None,
        train_box=(),
    )
    assert base.config_hash == same.config_hash
    box = RunConfig(system="chain_pendulum", k=2, train_target="derivative", train_box=list(BOX))
    assert box.train_box == BOX and box.config_hash != base.config_hash
    assert RunConfig.from_dict({**box.to_dict(), "train_box": "[0, 1, -1, 1]"}).train_box == (
        0.0,
        1.0,
        -1.0,
        1.0,
    )
    bad = [
        (dict(optimizer="sgd"), "optimizer"),
        (dict(lr_schedule="step"), "lr_schedule"),
        (dict(weight_decay=-1.0), "weight_decay"),
        (dict(train_box=(0.0, 1.0)), "train_box"),
        (dict(train_box=(1.0, 0.0, -1.0, 1.0), train_target="derivative"), "q_low < q_high"),
        (dict(train_box=BOX), "train_target 'derivative'"),
        (dict(train_box=BOX, train_target="derivative", noise=0.1), "noise"),
    ]
    for kw, needle in bad:
        with pytest.raises(ValueError, match=needle):
            RunConfig(system="chain_pendulum", k=2, **kw)
    with pytest.raises(ValueError, match="optimizer .* allowed adamw, adam_l2, adam_l2_clip"):
        TrainConfig(optimizer="sgd")
    with pytest.raises(ValueError, match="schedule .* allowed cosine, onecycle, constant"):
        TrainConfig(schedule="step")
