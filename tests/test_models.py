"""Conformance of every registered model: shapes, dtypes, jit (traced once), vmap, gradients,
args inputs, damped/canonical scenes, the registry's errors and initialisations."""

from __future__ import annotations

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.random as jr
import numpy as np
import pytest
from _model_helpers import (  # noqa: F401
    CHAIN2,
    STRUCTURED,
    TRAINABLE,
    VELOCITY_ONLY,
    G,
    W,
    _apply,
    _scene_for,
    _states,
)

import models
from models import AbstractContinuousModel, Scene


@functools.cache
def _trained_once(name):
    """float32: loss, vmapped outputs and parameter gradients in one jitted program, called
    twice with different values (it must trace once)."""
    model = models.make(name, _scene_for(name), key=jr.PRNGKey(0), width=W)
    traces = []

    @eqx.filter_jit
    def check(model, zs, args):
        traces.append(1)

        def loss(m):
            pred = jax.vmap(lambda z: _apply(m, z, args))(zs)
            return jnp.mean(pred**2) + m.penalty(zs, args), pred

        return eqx.filter_value_and_grad(loss, has_aux=True)(model)

    args = jnp.zeros((0,))
    zs1 = 0.5 * _states(jr.PRNGKey(1), 6, 2)  # float64 inputs: the model must cast them
    zs2 = 0.5 * _states(jr.PRNGKey(2), 6, 2)
    (_, out1), grads = check(model, zs1, args)
    (_, out2), _ = check(model, zs2, args)
    return model, zs1, out1, out2, grads, len(traces)


@functools.cache
def _forward64(name):
    model = models.make(name, _scene_for(name), key=jr.PRNGKey(0), width=W, dtype="float64")
    zs = 0.5 * _states(jr.PRNGKey(1), 6, 2)
    f = eqx.filter_jit(
        lambda m, zs: (_apply(m, zs[0], None), jax.vmap(lambda z: _apply(m, z, None))(zs))
    )
    return model, zs, *f(model, zs.astype(jnp.float32))


@pytest.mark.parametrize("name", TRAINABLE)
def test_conformance_float32_jit_vmap_grad(name):
    model, zs, out, out2, grads, n_traces = _trained_once(name)
    assert out.shape == (6, 4) and out.dtype == jnp.float32
    assert n_traces == 1  # one compile per configuration
    assert not np.allclose(out, out2)  # the second call used its own inputs
    leaves = jax.tree_util.tree_leaves(eqx.filter(grads, eqx.is_inexact_array))
    assert leaves and all(bool(jnp.all(jnp.isfinite(g))) for g in leaves)
    assert sum(float(jnp.sum(jnp.abs(g))) for g in leaves) > 0
    for leaf in jax.tree_util.tree_leaves(eqx.filter(model, eqx.is_inexact_array)):
        assert leaf.dtype == jnp.float32
    if isinstance(model, AbstractContinuousModel) and model.second_order:
        np.testing.assert_array_equal(out[:, :2], zs[:, 2:].astype(jnp.float32))


@pytest.mark.parametrize("name", TRAINABLE)
def test_conformance_float64_and_vmap_matches_unbatched(name):
    model, zs, single, outs = _forward64(name)
    assert outs.shape == (6, 4) and outs.dtype == jnp.float64 and single.dtype == jnp.float64
    for leaf in jax.tree_util.tree_leaves(eqx.filter(model, eqx.is_inexact_array)):
        assert leaf.dtype == jnp.float64
    np.testing.assert_allclose(outs[0], single, rtol=1e-12, atol=1e-12)
    if isinstance(model, AbstractContinuousModel) and model.second_order:
        # dq/dt = qdot exactly, and the field's second half is acceleration(q, v)
        zs32 = zs.astype(jnp.float32).astype(jnp.float64)
        np.testing.assert_array_equal(outs[:, :2], zs32[:, 2:])
        acc = model.acceleration(zs32[0, :2], zs32[0, 2:], None)
        np.testing.assert_allclose(acc, single[2:], rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("name", TRAINABLE)
def test_conformance_integrator_coordinates_carry_the_same_flow(name):
    """Every continuous model's rollout coordinates y = encode(z) carry its field:
    decode(encode(z)) = z and internal_field(t, encode(z)) = D encode(z) vector_field(t, z)
    (float64, one jvp; identity maps pass trivially), so that a rollout in y is the flow of
    vector_field."""
    model = _forward64(name)[0]
    if not isinstance(model, AbstractContinuousModel):
        pytest.skip("a discrete model has no vector field")
    zs = 0.5 * _states(jr.PRNGKey(3), 4, 2)
    for z in zs:
        y = model.encode(z, None)
        np.testing.assert_allclose(model.decode(y, None), z, rtol=1e-10, atol=1e-12)
        pushed = jax.jvp(
            lambda z_: model.encode(z_, None), (z,), (model.vector_field(0.0, z, None),)
        )[1]
        np.testing.assert_allclose(
            model.internal_field(0.0, y, None), pushed, rtol=1e-9, atol=1e-11
        )


@functools.cache
def _variant(name):
    """A damped scene with one args input, mixed coordinates, canonical where allowed."""
    scene = Scene(
        dof=2,
        angular=(True, False),
        n_args=1,
        damped=True,
        canonical=name not in VELOCITY_ONLY,
    )
    model = models.make(name, scene, key=jr.PRNGKey(3), width=W, dtype="float64")
    f = eqx.filter_jit(jax.vmap(_apply, in_axes=(None, 0, None)))
    zs = 0.5 * _states(jr.PRNGKey(4), 5, 2)
    return model, f(model, zs, jnp.array([1.0])), f(model, zs, jnp.array([2.0]))


@pytest.mark.parametrize("name", TRAINABLE)
def test_variant_scene_uses_args_and_dissipation(name):
    model, out1, out2 = _variant(name)
    assert out1.shape == (5, 4) and bool(jnp.all(jnp.isfinite(out1)))
    assert float(jnp.max(jnp.abs(out1 - out2))) > 1e-8  # args are inputs
    if name in STRUCTURED:  # spec(name).takes_dissipation: a damped scene adds the term
        assert model.dissipation is not None
    else:
        assert getattr(model, "dissipation", None) is None
    plain = models.make(
        name, _variant(name)[0].scene, key=jr.PRNGKey(3), width=W, dissipation=False
    )
    assert getattr(plain, "dissipation", None) is None


def test_spec_agrees_with_the_built_models():
    # models.spec reads the capabilities off the classes; a built model must show each of them.
    for name in models.available():
        s = models.spec(name)
        model = models.make(name, _scene_for(name), key=jr.PRNGKey(0), width=W)
        assert s.continuous == isinstance(model, AbstractContinuousModel), name
        assert s.discrete == isinstance(model, models.AbstractDiscreteModel), name
        assert s.trivial == isinstance(model, models.AbstractTrivialModel), name
        assert s.second_order == bool(getattr(model, "second_order", False)), name
        assert set(s.coordinates) == set(models.coordinates(name)), name
        assert s.default_activation in ("tanh", "softplus")
    assert [n for n in models.available() if models.spec(n).trivial] == models.trivial_models()
    hnn, lnn, vin, node = (models.spec(n) for n in ("hnn", "lnn", "vin", "node"))
    assert hnn.hamiltonian and lnn.lagrangian and vin.lagrangian and node.structure is None
    assert vin.discrete and not vin.continuous
    assert hnn.options == ("init", "inverse_mass", "momentum_map")
    with pytest.raises(ValueError, match="unknown model 'nope'"):
        models.spec("nope")


def test_registry_and_errors():
    assert models.available() == [
        "node",
        "node_so",
        "node_so_pq",
        "hnn",
        "hnn_so",
        "mixture_hnn",
        "node_symreg",
        "node_so_symreg",
        "lnn",
        "vin",
        "vin_implicit",
        "resnet",
        "hnn_force",
        "hnn_force_paper",
        "constant_velocity",
        "at_rest",
    ]
    assert models.trivial_models() == ["constant_velocity", "at_rest"]
    assert models.coordinates("node_so_symreg") == ("momentum",)
    assert models.coordinates("lnn") == ("velocity",)
    key = jr.PRNGKey(0)
    with pytest.raises(ValueError, match="hnn_so"):
        models.make("hnn_s0", CHAIN2, key=key)
    with pytest.raises(ValueError, match="weight"):
        models.make("node_symreg", CHAIN2, key=key, wieght=1.0)
    with pytest.raises(ValueError, match="allowed: \\[\\]"):
        models.make("node_so", CHAIN2, key=key, weight=1.0)
    with pytest.raises(ValueError, match="solve"):
        models.make("lnn", CHAIN2, key=key, solve="qr")
    for bad in (
        {"width": 0},
        {"depth": 1.5},
        {"activation": "sin"},
        {"dtype": "float16"},
        {"dissipation": "yes"},
    ):
        with pytest.raises(ValueError):
            models.make("node", CHAIN2, key=key, **bad)
    with pytest.raises(ValueError, match="velocity"):
        models.make("lnn", Scene(dof=1, angular=(False,), canonical=True), key=key)
    with pytest.raises(ValueError, match="momentum"):
        models.make("node_so_symreg", CHAIN2, key=key)
    with pytest.raises(ValueError, match="momentum_map"):
        models.make("hnn", CHAIN2, key=key, momentum_map="no")
    with pytest.raises(ValueError):
        Scene(dof=2, angular=(True,))


def test_parameter_count_and_inits():
    node = models.make("node", CHAIN2, key=jr.PRNGKey(0), width=32, depth=3)
    n_in = 2 * 2 + 2  # (cos q, sin q) for two angles, then qdot
    assert models.n_parameters(node) == (n_in + 1) * 32 + 2 * (32 + 1) * 32 + (32 + 1) * 4
    w = node.net.weights[1]
    np.testing.assert_allclose(w.T @ w, 0.25 * np.eye(32), atol=1e-5)  # orthogonal, gain 0.5
    lnn = models.make("lnn", CHAIN2, key=jr.PRNGKey(0), width=64)
    assert lnn.net.activation == "softplus"
    stds = [float(jnp.std(x)) for x in lnn.net.weights]  # LNN seed appendix B, eq. 3
    np.testing.assert_allclose(stds[:2], [2.2 / 8, 0.58 / 8], rtol=0.1)
    assert 5 < stds[2] < 11  # output layer sigma = sqrt(64) = 8 (64 samples)


def test_hnn_learning_the_inverse_mass_is_still_a_hamiltonian_flow():
    """``hnn`` with ``inverse_mass``: M(q) is the inverse of the network's L L^T + 1e-4 I, the
    learned H is conserved along the field (dH/dt = grad H . F = 0 up to rounding), and the
    rollout coordinates carry the same flow (as the conformance test checks for defaults)."""
    scene = _scene_for("hnn")
    model = models.make(
        "hnn", scene, key=jr.PRNGKey(5), width=W, dtype="float64", inverse_mass=True
    )
    assert "inverse_mass" in models.spec("hnn").options
    for z in 0.5 * _states(jr.PRNGKey(6), 3, 2):
        q = z[:2]
        minv = model.mass.inverse.matrix(q, None)
        c = model.mass.factor(q, None)
        np.testing.assert_allclose(c @ c.T @ minv, np.eye(2), atol=1e-10)
        assert minv[0, 0] >= 1e-4
        f = model.vector_field(0.0, z, None)
        dh = jax.grad(lambda z_: model.hamiltonian(z_, None))(z) @ f
        assert abs(float(dh)) < 1e-9 * (1 + float(jnp.linalg.norm(f))), dh
        y = model.encode(z, None)
        np.testing.assert_allclose(model.decode(y, None), z, rtol=1e-10, atol=1e-12)
        pushed = jax.jvp(lambda z_: model.encode(z_, None), (z,), (f,))[1]
        np.testing.assert_allclose(
            model.internal_field(0.0, y, None), pushed, rtol=1e-9, atol=1e-11
        )


def test_the_paper_init_is_pytorch_bias_over_the_orthogonal_draw():
    """``init="paper"``: the orthogonal weights of the default (the same draw) and PyTorch's
    default biases U(+-1/sqrt(fan_in)) on every layer, but a mass network's last (zero, as the
    paper's code builds it); node_so_pq starts so by default, hnn_so on request."""
    key = jr.PRNGKey(3)
    a = models.MLP(6, 4, 256, 2, "tanh", "float64", key=key)
    b = models.MLP(6, 4, 256, 2, "tanh", "float64", key=key, init="paper")
    for wa, wb in zip(a.weights, b.weights, strict=True):
        np.testing.assert_array_equal(wa, wb)
    assert all(not np.any(x) for x in a.biases)
    for fan_in, bias in zip((6, 256, 256), b.biases, strict=True):
        lim = 1 / np.sqrt(fan_in)
        assert np.all(np.abs(bias) <= lim) and np.std(bias) > 0.4 * lim  # U(-l, l): std l/sqrt 3
    pq = models.make("node_so_pq", CHAIN2, key=key, width=W)
    assert np.any(pq.inner.net.biases[0]) and np.any(pq.inner.net.biases[-1])
    assert not np.any(pq.inner.inverse_mass.net.biases[-1])
    assert np.any(pq.inner.inverse_mass.net.biases[0])
    plain = models.make("node_so_pq", CHAIN2, key=key, width=W, init="orthogonal")
    assert not any(np.any(x) for x in plain.inner.net.biases)
    so = models.make("hnn_so", CHAIN2, key=key, width=W, init="paper").hamiltonian_part
    assert np.any(so.potential.biases[0]) and np.any(so.potential.biases[-1])
    assert np.any(so.inverse_mass.net.biases[0]) and not np.any(so.inverse_mass.net.biases[-1])
    default = models.make("hnn_so", CHAIN2, key=key, width=W).hamiltonian_part
    assert not any(np.any(x) for x in default.potential.biases)
    for wa, wb in zip(default.potential.weights, so.potential.weights, strict=True):
        np.testing.assert_array_equal(wa, wb)
