"""The side-by-side script of claim 7's relativistic particle
(bench/sidebyside/lnn_relativistic.py) without the seed's code: its one-line errors, the readers
of the seed's notebooks, the maps between the notebooks' states and our models', and our models
with stax parameters computing the notebooks' equations of motion (written out here from the
physics, not taken from the seed's code)."""

from __future__ import annotations

import dataclasses
import json

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.example_libraries import stax

from bench.sidebyside import _relativistic_seed as R
from bench.sidebyside import lnn_relativistic as S


def _fake_checkout(path):
    for f in S.EXPECTED:
        (path / f).parent.mkdir(parents=True, exist_ok=True)
        (path / f).write_text("{}" if f.endswith(".ipynb") else "")
    return path


@pytest.mark.parametrize("make", [lambda p: p / "absent", lambda p: p])
def test_bad_seed_code_is_one_clear_line(tmp_path, capsys, make):
    (tmp_path / "lnn.py").write_text("")  # a folder with some, not all, of the files
    assert S.main(["--seed-code", str(make(tmp_path)), "--steps", "1"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("error: --seed-code")
    assert "lagrangian_nns" in err


@pytest.mark.parametrize(
    "args", [["--models", "lnn,mlp"], ["--curves", "paper"], ["--steps", "-1"], ["--batch", "0"]]
)
def test_bad_options_are_one_clear_line(tmp_path, capsys, args):
    root = _fake_checkout(tmp_path)
    assert S.main(["--seed-code", str(root), *args]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("error: ")


def test_a_notebook_without_the_cells_is_one_clear_error(tmp_path):
    root = _fake_checkout(tmp_path)
    hs = "swish = relu3 = Swish = Relu3 = None\n\n\ndef extended_mlp(args):\n    pass\n"
    (root / "hyperopt" / "HyperparameterSearch.py").write_text(hs)
    nb = {"cells": [{"cell_type": "code", "source": ["lr = 1e-3\n"], "outputs": []}]}
    (root / R.NOTEBOOKS["lnn"][0]).write_text(json.dumps(nb))
    with pytest.raises(S.SeedCodeError, match="defines no"):
        R.load_notebook(root, "lnn")
    (root / R.NOTEBOOKS["lnn"][0]).write_text("not json")
    with pytest.raises(S.SeedCodeError, match="not a notebook"):
        R.load_notebook(root, "lnn")


def test_check_seed_code_names_the_missing_files(tmp_path):
    _fake_checkout(tmp_path)
    (tmp_path / S.EXPECTED[-1]).unlink()
    with pytest.raises(S.SeedCodeError, match="CorrectP"):
        S.check_seed_code(tmp_path)


def test_notebook_readers():
    cell = lambda src, out=(), **kw: {"cell_type": "code", "source": src, "outputs": list(out)}
    nb = {
        "cells": [
            cell("init_params = custom_init(init_params, seed=3)"),
            cell("cstate, cconditionals, ctarget = gen_data_batch(epoch, 64)"),
            cell(
                "loss(get_params(opt_state), cstate, cconditionals, ctarget)",
                [{"data": {"text/plain": "DeviceArray(12.5, dtype=float32)"}}],
            ),
            cell("%matplotlib inline"),
            cell(
                ["for epoch in range(2):\n", "    batch = 256\n", "    print(epoch)\n"],
                [{"text": ["epoch=0 lr=0.1 loss=0.5\n", "epoch=1 lr=0.2 loss=0.25\n"]}],
            ),
        ]
    }
    cells = R._cells(nb)
    assert R.printed_log(nb) == [(0, 0.5), (1, 0.25)]
    assert R.printed_init_loss(nb) == (64, 12.5)
    assert R.loop_batch(cells) == 256
    assert R.custom_init_seed(cells) == 3
    assert R.custom_init_seed(cells[1:]) is None
    assert R.printed_init_loss({"cells": nb["cells"][2:]}) is None
    with pytest.raises(S.SeedCodeError, match="batch"):
        R.loop_batch(cells[:2])


def test_state_maps_carry_the_true_field():
    import systems

    rng = np.random.default_rng(0)
    v = np.tanh(2 * rng.standard_normal((50, 1))) * 0.99
    state = np.concatenate([rng.uniform(-10, 10, (50, 1)), v], 1)
    g = 10 * rng.standard_normal((50, 1))
    system = systems.make("relativistic_particle")
    qddot = np.array(
        [
            system.acceleration_closed_form(0.0, x, jnp.array([y]))
            for x, y in zip(v[:, 0], g[:, 0], strict=True)
        ]
    )
    np.testing.assert_allclose(R.pdot_to_qddot(g, v)[:, 0], qddot, rtol=1e-12)
    p = R.momentum(v)
    np.testing.assert_allclose(np.asarray(system.velocity(0.0, jnp.asarray(p))), v, rtol=1e-9)
    for kind in R.MODELS:
        target = R.seed_targets(kind, state, g)
        z, args, dz = R.to_ours(kind, state, g, target)
        np.testing.assert_allclose(args, g / 10)
        np.testing.assert_allclose(R.seed_form(kind, dz, v), target, rtol=1e-12)
        assert R.weighted_l1(target, target, v) == 0.0
    # the notebooks' weighted L1: the weight 1 + 1 / sqrt(1 - qdot^2), over its sum
    w = 1 + 1 / np.sqrt(1 - v**2)
    err = np.abs(rng.standard_normal((50, 2)))
    want = np.sum(err * w) / np.sum(w)
    assert abs(R.weighted_l1(err, 0 * err, v) - want) < 1e-12
    assert abs(float(R.weighted_l1(jnp.asarray(err), 0 * err, v, jnp)) - want) < 1e-12


def _stax_net(width):
    init, forward = stax.serial(*[stax.Dense(width), stax.Softplus] * 2, stax.Dense(1))
    _, params = init(jax.random.PRNGKey(1), (-1, 3))
    params = jax.tree.map(lambda x: jnp.asarray(x, jnp.float64), params)
    return params, lambda q, x, c: forward(params, jnp.concatenate([q, x, c]))[0]


def _reference(kind, f, q, v, g):
    """The notebooks' equations of motion from the physics: the network f(q, qdot or p, g / 10)
    with q / 10 (not for the HNN on p, which reads raw q and p = qdot (1 - qdot^2)^(-3/2))."""
    c = g / 10
    if kind == "lnn":  # Euler-Lagrange in q / 10
        s = q / 10
        h = jax.hessian(f, 1)(s, v, c)
        rhs = jax.grad(f, 0)(s, v, c) - jax.jacobian(jax.grad(f, 1), 0)(s, v, c) @ v
        return jnp.linalg.pinv(h) @ rhs
    if kind == "hnn_naive":  # Hamilton's equations with qdot as p, in q / 10
        return jnp.concatenate([jax.grad(f, 1)(q / 10, v, c), -jax.grad(f, 0)(q / 10, v, c)])
    p = R.momentum(v)
    pdot = -jax.grad(f, 0)(q, p, c)
    return jnp.concatenate([jax.grad(f, 1)(q, p, c), R.pdot_to_qddot(pdot, v)])


@pytest.mark.parametrize("kind", R.MODELS)
def test_our_model_with_stax_parameters_is_the_notebooks(kind):
    params, f = _stax_net(8)
    config = dataclasses.replace(S.paper_core_config(kind, 0), width=8, depth=2)
    model = S.our_model(config, params, "float64")
    assert S.ours_to_seed(S.net_of(model))[0][0].shape == (3, 8)
    rng = np.random.default_rng(2)
    state = np.concatenate([rng.uniform(-10, 10, (6, 1)), rng.uniform(-0.95, 0.95, (6, 1))], 1)
    g = 10 * rng.standard_normal((6, 1))
    z, args, _ = R.to_ours(kind, state, g, np.zeros((6, 1)))
    field = jax.vmap(lambda zz, a: model.vector_field(0.0, zz, a))(
        jnp.asarray(z), jnp.asarray(args)
    )
    ours = R.seed_form(kind, np.asarray(field), state[:, 1:])
    want = np.stack(
        [
            np.asarray(_reference(kind, f, jnp.asarray(s[:1]), jnp.asarray(s[1:]), jnp.asarray(c)))
            for s, c in zip(state, g, strict=True)
        ]
    )
    np.testing.assert_allclose(ours, want, rtol=1e-9, atol=1e-12)


def test_ours_seed_adam_steps_our_model_by_the_notebooks_optimiser():
    """``ours_seed_adam``: the notebook's ``opt_update``, given the fraction done, steps our
    parameters; at fraction 0 Adam's first step is -lr sign(gradient of the notebook's loss)."""
    import types

    import equinox as eqx
    from jax.example_libraries import optimizers

    from bench.core import train_config
    from bench.sidebyside._relativistic_ours import OursSeedAdam, WeightedSeedBatches, ours_batch

    lr = 3e-2  # not the run's own rate: the step must be the notebook optimiser's
    opt_init, opt_update, get_params = optimizers.adam(lr)
    nb = types.SimpleNamespace(opt_init=opt_init, opt_update=opt_update, get_params=get_params)
    nb.steps = 100
    config = dataclasses.replace(S.paper_core_config("hnn_p", 0), width=8, depth=2)
    tcfg = train_config(config)
    model = S.our_model(config, _stax_net(8)[0], tcfg.dtype)
    rng = np.random.default_rng(3)
    state = np.concatenate([rng.uniform(-10, 10, (16, 1)), rng.uniform(-0.9, 0.9, (16, 1))], 1)
    g = 10 * rng.standard_normal((16, 1))
    batch = (state, g, R.seed_targets("hnn_p", state, g))
    ix = jnp.asarray(ours_batch("hnn_p", batch, tcfg.dtype))
    loss = lambda m: WeightedSeedBatches("hnn_p").loss(m, None, ix, tcfg)
    grads = eqx.filter_grad(loss)(model)
    side = OursSeedAdam("hnn_p", model, tcfg, nb)
    before = eqx.filter(model, eqx.is_inexact_array)
    losses, failed = side.train([batch])
    assert not failed and side.done == 1
    np.testing.assert_allclose(losses, [float(loss(model))], rtol=1e-12)
    after = eqx.filter(side.model, eqx.is_inexact_array)
    moved = jax.tree.map(lambda a, b: np.asarray(a - b), after, before)
    checked = 0
    for d, gr in zip(jax.tree.leaves(moved), jax.tree.leaves(grads), strict=True):
        big = np.abs(np.asarray(gr)) > 1e-6  # H's last bias has none: the field ignores it
        np.testing.assert_allclose(d[big], -lr * np.sign(np.asarray(gr)[big]), rtol=1e-2)
        checked += int(big.sum())
    assert checked > 100
