"""The side-by-side script of the paper's code (bench/sidebyside/decon_hnn.py) without that code
or torch: its one-line error on a bad --seed-code, the mapping of PyTorch state dicts onto our
MLPs (numpy arrays), and the ground-truth helpers on our own chain pendulum."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import models
import systems
from bench.sidebyside import _decon as D
from bench.sidebyside import decon_hnn as S


@pytest.mark.parametrize("make", [lambda p: p / "absent", lambda p: p])
def test_bad_seed_code_is_one_clear_line(tmp_path, capsys, make):
    (tmp_path / "toy_systems.py").write_text("")  # a folder with some, not all, of the files
    assert S.main(["--seed-code", str(make(tmp_path)), "--steps", "1"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("error: --seed-code")
    assert "decon-hnn" in err


def test_check_paper_code_names_the_missing_files(tmp_path):
    for f in D.EXPECTED[:-1]:
        (tmp_path / f).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / f).write_text("")
    with pytest.raises(D.SeedCodeError, match="trainer.py"):
        D.check_paper_code(tmp_path)
    (tmp_path / D.EXPECTED[-1]).parent.mkdir(parents=True, exist_ok=True)
    (tmp_path / D.EXPECTED[-1]).write_text("")
    assert D.check_paper_code(tmp_path) == tmp_path


def _torch_like(prefix, sizes, rng, zero_last_bias=False) -> dict:
    """A state dict shaped as the paper's nn.Sequential(CosSin, FCtanh..., Linear)."""
    state, n = {}, len(sizes) - 1
    for i, (a, b) in enumerate(zip(sizes[:-1], sizes[1:], strict=True)):
        key = f"{prefix}.{i + 1}.0" if i < n - 1 else f"{prefix}.{n}"
        state[f"{key}.weight"] = rng.normal(size=(b, a))
        state[f"{key}.bias"] = (
            np.zeros(b) if (zero_last_bias and i == n - 1) else rng.normal(size=b)
        )
    return state


def test_mapping_round_trip_and_forward():
    rng = np.random.default_rng(0)
    state = _torch_like("dynamics_net", [6, 8, 8, 2], rng)
    ws, bs = D.torch_mlp(state, "dynamics_net")
    assert [w.shape for w in ws] == [(6, 8), (8, 8), (8, 2)]
    back = D.mlp_to_torch(ws, bs, "dynamics_net")
    assert set(back) == set(state)
    for key, v in state.items():
        np.testing.assert_array_equal(back[key], v)
    mlp = models.MLP(6, 2, 8, 2, "tanh", "float64", key=jax.random.PRNGKey(0), init="lnn")
    mlp = D.set_mlp(mlp, ws, bs)
    x = rng.normal(size=(5, 6))
    want = x
    for i in (1, 2):  # the paper's forward pass: x W^T + b, tanh
        want = np.tanh(
            want @ state[f"dynamics_net.{i}.0.weight"].T + state[f"dynamics_net.{i}.0.bias"]
        )
    want = want @ state["dynamics_net.3.weight"].T + state["dynamics_net.3.bias"]
    np.testing.assert_allclose(mlp(jnp.asarray(x)), want, rtol=1e-12)
    with pytest.raises(ValueError):
        D.set_mlp(mlp, ws[:2], bs[:2])


def test_mass_network_maps_onto_our_cholesky_factor():
    rng = np.random.default_rng(1)
    state = _torch_like("mass_net", [4, 8, 8, 4], rng, zero_last_bias=True)
    ws, bs = D.torch_mlp(state, "mass_net", mass=True, dof=2)
    assert ws[-1].shape == (8, 3)
    np.testing.assert_allclose(bs[-1], [-D.SHIFT, 0.0, -D.SHIFT])  # the diagonal's shift
    back = D.mlp_to_torch(ws, bs, "mass_net", mass=True)
    idx, _ = D.mass_rows(2)
    np.testing.assert_allclose(back["mass_net.3.weight"][idx], state["mass_net.3.weight"][idx])
    assert not back["mass_net.3.weight"][2].any()  # the unused output A[1, 0]
    scene = models.Scene(dof=2, angular=(True, True))
    feats = models.Features(scene)
    inv = models._mass.CholeskyNet(
        feats, 8, 2, "tanh", "float64", key=jax.random.PRNGKey(0), jitter=D.PAPER_MINV_EPS
    )
    inv = eqx.tree_at(lambda m: m.net, inv, D.set_mlp(inv.net, ws, bs))
    q = rng.normal(size=(6, 2))
    ours = jax.jit(jax.vmap(lambda qq: inv.matrix(qq, jnp.zeros(0))))(jnp.asarray(q))
    x = np.concatenate([np.cos(q), np.sin(q)], axis=1)
    np.testing.assert_allclose(ours, D.paper_minv(state, "mass_net", x), rtol=1e-12)


@pytest.mark.parametrize("name", ["node_so", "hnn"])
def test_build_mapped_places_every_network_and_compares_gradients(name):
    """The paper's parameters land in the networks :func:`network` names (our arrays, through
    the state dict and back), and the gradient comparison of a pytree with its own state dict
    (the mass bias unshifted, as gradients are) is zero."""
    scene = models.Scene(dof=2, angular=(True, True))
    config = type("C", (), {"width": 8, "depth": 2, "activation": None})()
    model = D.build_mapped(name, scene, config, "float64", None, jax.random.PRNGKey(3))
    state, grads = {}, {}
    for prefix, mass in D.NETWORKS[name]:
        net = D.network(name, model, prefix)
        ws, bs = [np.asarray(w) for w in net.weights], [np.asarray(b) for b in net.biases]
        state.update(D.mlp_to_torch(ws, bs, prefix, mass))
        g = D.mlp_to_torch(ws, bs, prefix, mass)
        if mass:
            idx, _ = D.mass_rows(2)
            g[f"{prefix}.3.bias"][idx] = bs[-1]
        grads.update(g)
    again = D.build_mapped(name, scene, config, "float64", state, jax.random.PRNGKey(4))
    for a, b in zip(jax.tree.leaves(model), jax.tree.leaves(again), strict=True):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-15)
    rows = D.gradient_rows(name, model, grads, 2)
    assert len(rows) == 12 and max(r[-1] for r in rows) < 1e-15


def test_cartesian_to_angular_recovers_our_chain_field():
    """The bobs' Cartesian velocities and accelerations of our own chain (its forward
    kinematics differentiated twice along the motion), mapped back to angles, are our field;
    and the field comparison of our field with itself is zero."""
    system = systems.make("chain_pendulum", k=2)
    rng = np.random.default_rng(0)
    states = rng.normal(size=(16, 4))
    field = systems.derivatives(system, states)
    q, v, a = states[:, :2], states[:, 2:], field[:, 2:]
    lengths = np.asarray(system.lengths)
    c, s = np.cos(q), np.sin(q)
    # x_i = sum_{j <= i} l_j sin q_j, y_i = -sum_{j <= i} l_j cos q_j
    vel = np.cumsum(lengths * np.stack([c * v, s * v], axis=-1).transpose(2, 0, 1), axis=-1)
    acc = np.stack([c * a - s * v**2, s * a + c * v**2], axis=-1).transpose(2, 0, 1)
    acc = np.cumsum(lengths * acc, axis=-1)
    vel, acc = vel.transpose(1, 2, 0), acc.transpose(1, 2, 0)  # (N, k, 2)
    qdot, qddot = D.cartesian_to_angular(q, vel, acc, lengths)
    np.testing.assert_allclose(qdot, v, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(qddot, a, rtol=1e-12, atol=1e-12)
    energy = np.asarray(jax.vmap(system.energy)(jnp.asarray(states)))
    d = D.field_difference(system, states, v, a, energy)
    assert d == {"qdot": 0.0, "qddot": 0.0, "energy": 0.0}
    d = D.field_difference(system, states, v, a * (1 + 1e-3))
    assert d["qddot"] == pytest.approx(1e-3, rel=1e-6)


def test_wrapped_difference_ignores_whole_turns():
    a = np.array([[np.pi - 0.1, 0.0, 1.0, 2.0]])
    b = np.array([[-np.pi + 0.1, 2 * np.pi, 1.0, 2.5]])
    np.testing.assert_allclose(D.wrapped_difference(a, b, 2), [[-0.2, 0.0, 0.0, -0.5]], atol=1e-12)


def test_bad_options_and_interpreter_are_one_line(tmp_path, capsys):
    for f in D.EXPECTED:
        (tmp_path / f).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / f).write_text("")
    assert S.main(["--seed-code", str(tmp_path), "--model", "lnn"]) == 2
    assert S.main(["--seed-code", str(tmp_path), "--k", "5"]) == 2
    assert S.main(["--seed-code", str(tmp_path), "--torch-python", str(tmp_path / "nopython")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3 and err[0].startswith("error: --model") and "--torch-python" in err[2]
    assert "--k of 1, 2, 3, 4" in err[1]


def test_the_cell_at_each_number_of_links_is_the_suite_form():
    for k in (1, 2, 3, 4):
        for model in ("node_so", "hnn", "hnn_so"):
            c = S.run_config(model, 3, k)
            assert (c.system, c.k, c.model, c.seed, c.model_options) == (
                "chain_pendulum",
                k,
                model,
                3,
                (),
            )


def test_late_and_the_paper_metric():
    rows = [{"curve": "c", "step": s, "x": v} for s, v in ((0, 9.0), (3, 1.0), (4, 4.0))]
    assert S.late(rows, "c", "x", 4) == pytest.approx(2.0)  # steps 3, 4 of 4: sqrt(1 x 4)
    assert S.late(rows[:1], "c", "x", 4) == pytest.approx(9.0)  # none late: the last
    true = np.ones((2, 3, 4))
    pred = true.copy()
    pred[:, 1:] *= 1.1  # t = 0 exact: err 0 there, clamped at 1e-7 only with t0
    e = 0.1 / 2.1
    assert S.paper_metric(pred, true) == pytest.approx(e)
    assert S.paper_metric(pred, true, t0=True) == pytest.approx((1e-7 * e * e) ** (1 / 3))


def test_learning_sets_the_papers_trained_model_beside_ours_and_the_stored_runs(monkeypatch):
    """(l): constant velocity over each final prediction (constant velocity itself: 1x, does
    not learn; a prediction a tenth as far off: learns), the stored runs' ratio on the cell,
    and the verdict between the paper's code and ours."""
    from types import SimpleNamespace

    import pandas as pd

    from bench.sidebyside._learn import constant_velocity

    rng = np.random.default_rng(0)
    ts = np.linspace(0.0, 1.0, 11)
    z = rng.normal(size=(6, 11, 4))
    cv = constant_velocity(z, ts)
    close = z + 0.1 * (cv - z)
    rows = [("constant_velocity", s, 0.4) for s in range(3)] + [
        ("node_so", s, 0.1) for s in range(3)
    ]
    runs = pd.DataFrame(rows, columns=["model", "seed", "rollout_error"])
    runs["system"], runs["k"], runs["status"], runs["model_options"] = (
        "chain_pendulum",
        2,
        "ok",
        "[]",
    )
    monkeypatch.setattr("bench.load_runs", lambda _: runs)
    recorded = []
    a = SimpleNamespace(k=2, steps=10, results="unused")
    system = SimpleNamespace(angular=(True, True, False, False))
    lines = S.learning(
        "node_so", system, a, z, ts, {"paper": cv, "suite": close}, lambda *r: recorded.append(r)
    )
    assert (
        "paper 1x (does not learn)" in lines[0]
        and "our stored runs (3 seeds): 4x (learns)" in lines[0]
    )
    assert "suite " in lines[0] and lines[0].split("suite ")[1].split("x")[0] != "1"
    assert lines[1] == (
        "verdict: DIFFER: node_so on chain_pendulum k = 2: ours learns it "
        "(gate 2x constant velocity)"
    )
    assert [r[0] for r in recorded] == ["l", "l", "l"]
