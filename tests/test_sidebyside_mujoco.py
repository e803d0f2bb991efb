"""The side-by-side script of the paper's MuJoCo code (bench/sidebyside/decon_mujoco.py) without
that code or torch: its one-line errors (a bad --seed-code, bad arguments, no torch), the
mapping of PyTorch state dicts onto our controlled models, the paper's standardisation against
our scene's, and the paper's update rule in optax."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import models
from bench.sidebyside import _mujoco as M
from bench.sidebyside import decon_mujoco as S
from bench.sidebyside._mujoco_ours import epoch_cosine, paper_optimizer

DOF, NU, WIDTH = 3, 2, 8


def _checkout(tmp_path, files=M.EXPECTED):
    for f in files:
        (tmp_path / f).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / f).write_text("")
    return tmp_path


def _one_line_error(capsys, argv) -> str:
    assert S.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("error: "), err
    return err


@pytest.mark.parametrize("make", [lambda p: p / "absent", lambda p: p])
def test_bad_seed_code_is_one_clear_line(tmp_path, capsys, make):
    _checkout(tmp_path, M.EXPECTED[:2])  # a folder with some, not all, of the files
    err = _one_line_error(capsys, ["--seed-code", str(make(tmp_path)), "--steps", "1"])
    assert err.startswith("error: --seed-code") and "decon-hnn" in err


def test_check_paper_code_names_the_missing_files(tmp_path):
    _checkout(tmp_path, M.EXPECTED[:-1])
    with pytest.raises(M.SeedCodeError, match="hamiltonian.py"):
        M.check_paper_code(tmp_path)
    _checkout(tmp_path, M.EXPECTED[-1:])
    assert M.check_paper_code(tmp_path) == tmp_path


@pytest.mark.parametrize(
    "args, word",
    [
        (["--model", "hnn"], "--model"),
        (["--model", ""], "--model"),
        (["--curves", "paper"], "--curves"),
        (["--steps", "-1"], "--steps"),
        (["--log-every", "0"], "--log-every"),
        (["--task", "Nope-v0"], "--task"),
        (["--torch-python", "/nonexistent/python"], "--torch-python"),
    ],
)
def test_argument_errors_are_one_line(tmp_path, capsys, args, word):
    root = _checkout(tmp_path)
    err = _one_line_error(capsys, ["--seed-code", str(root), *args])
    assert word in err


def test_unparsable_argument_exits_through_argparse(tmp_path):
    with pytest.raises(SystemExit) as e:
        S.main(["--seed-code", str(tmp_path), "--steps", "many"])
    assert e.value.code == 2


def _scene(standardised: bool = True):
    st = None
    if standardised:
        rng = np.random.default_rng(3)
        st = models.Standardisation.from_windows(
            rng.normal(size=(20, 3, 2 * DOF)), rng.normal(size=(20, 3, NU)), 0.01
        )
    return models.Scene(dof=DOF, angular=(False,) * DOF, n_controls=NU, standardisation=st)


def _paper_state(name, rng) -> dict:
    """A state dict shaped as the paper's class of ``name`` (nn.Sequential: Linear, Tanh, ...)."""
    n_in = 2 * DOF + NU
    nets = {
        "node": {"net": [n_in, WIDTH, WIDTH, 2 * DOF]},
        "node_so": {"net": [n_in, WIDTH, WIDTH, DOF]},
        "hnn_force_paper": {
            "potential_net": [DOF, WIDTH, WIDTH, 1],
            "mass_net": [DOF, WIDTH, WIDTH, DOF * DOF],
            "force_net": [n_in, WIDTH, WIDTH, DOF],
        },
    }[name]
    state = {}
    for prefix, sizes in nets.items():
        for i, (a, b) in enumerate(zip(sizes[:-1], sizes[1:], strict=True)):
            state[f"{prefix}.{2 * i}.weight"] = rng.normal(size=(b, a))
            state[f"{prefix}.{2 * i}.bias"] = rng.normal(size=b)
    state["input_loc"] = np.zeros(n_in)  # buffers: not parameters, left alone by the mapping
    return state


@pytest.mark.parametrize("name", list(M.PAPER_CLASSES))
def test_mapping_round_trip_and_forward(name):
    rng = np.random.default_rng(0)
    state = _paper_state(name, rng)
    model = models.make(name, _scene(), key=jax.random.PRNGKey(1), width=WIDTH, dtype="float64")
    mapped = M.with_paper_weights(name, model, state)
    back = M.model_to_torch(name, mapped)
    mapped_keys = {k for k in state if k.split(".")[0] in dict(M.NETWORKS[name])}
    assert set(back) == mapped_keys
    for key in mapped_keys:
        np.testing.assert_array_equal(back[key], state[key])
    for prefix, attr in M.NETWORKS[name]:  # the paper's forward: x W^T + b, tanh
        mlp = getattr(mapped, attr)
        x = rng.normal(size=(4, mlp.weights[0].shape[0]))
        want = x
        for i in (0, 2):
            want = np.tanh(want @ state[f"{prefix}.{i}.weight"].T + state[f"{prefix}.{i}.bias"])
        want = want @ state[f"{prefix}.4.weight"].T + state[f"{prefix}.4.bias"]
        np.testing.assert_allclose(jax.vmap(mlp)(jnp.asarray(x)), want, rtol=1e-12)


def test_mapping_refuses_other_shapes():
    rng = np.random.default_rng(2)
    state = _paper_state("node_so", rng)  # dof outputs: node needs 2 dof
    model = models.make("node", _scene(), key=jax.random.PRNGKey(0), width=WIDTH)
    with pytest.raises(ValueError, match="shapes"):
        M.with_paper_weights("node", model, state)
    with pytest.raises(KeyError):
        M.torch_mlp(state, "force_net")


def test_gradient_rows_of_the_same_gradient_are_zero_and_name_the_unused_network():
    rng = np.random.default_rng(4)
    name = "hnn_force_paper"
    state = _paper_state(name, rng)
    model = models.make(name, _scene(), key=jax.random.PRNGKey(0), width=WIDTH, dtype="float64")
    grads = M.with_paper_weights(name, model, state)  # a pytree of the gradient's shape
    rows = M.gradient_rows(name, grads, state)
    assert len(rows) == 2 * 3 * 2 + 1
    assert all(r[-1] == 0.0 for r in rows[:-1])
    assert rows[-1][0] == "mass_net" and rows[-1][-1] > 0  # its norm, ours 0


@pytest.mark.parametrize("name", list(M.PAPER_CLASSES))
def test_paper_statistics_are_our_scene_s(name):
    rng = np.random.default_rng(5)
    z, u, dt = rng.normal(size=(30, 3, 2 * DOF)), rng.normal(size=(30, 3, NU)), 0.02
    st = models.Standardisation.from_windows(z, u, dt)
    scene = models.Scene(dof=DOF, angular=(False,) * DOF, n_controls=NU, standardisation=st)
    model = models.make(name, scene, key=jax.random.PRNGKey(0), width=WIDTH)
    scale = np.maximum(z.reshape(-1, 2 * DOF).std(0), 1e-6)
    theirs = M.paper_statistics(z, u, dt, name)
    ours = M.our_statistics(model, scale, name)
    assert set(theirs) == set(ours)
    for key in ours:
        np.testing.assert_allclose(theirs[key], ours[key], rtol=1e-12, atol=1e-12)


def test_held_schedule_and_late():
    np.testing.assert_array_equal(M.held_schedule(2, 3), [0, 0, 0, 1, 1, 1])
    assert M.late([4.0, 1.0, 4.0], [10, 20, 30], 30) == pytest.approx(2.0)
    assert M.late([4.0, 9.0], [1, 2], 30) == pytest.approx(9.0)  # none in the second half
    assert np.isnan(M.late([1.0, np.nan], [20, 30], 30))


def test_paper_optimizer_is_clipped_adam_with_an_l2_term_and_an_epoch_cosine():
    import types

    tcfg = types.SimpleNamespace(lr=5e-3, clip=1.0, weight_decay=0.1)
    opt = paper_optimizer(tcfg, steps_per_epoch=2, epochs=4)
    params = {"w": jnp.array([1.0, -2.0])}
    g = {"w": jnp.array([30.0, 40.0])}  # norm 50: clipped to (0.6, 0.8)
    upd, _ = opt.update(g, opt.init(params), params)
    # Adam's first step is -lr sign(g + decay w): the L2 term added after the clip
    np.testing.assert_allclose(upd["w"], -5e-3 * np.sign([0.6 + 0.1, 0.8 - 0.2]), rtol=1e-6)
    g = {"w": jnp.array([0.01, 0.01])}  # under the clip: the decay term dominates
    upd, _ = opt.update(g, opt.init(params), params)
    np.testing.assert_allclose(upd["w"], -5e-3 * np.sign([0.01 + 0.1, 0.01 - 0.2]), rtol=1e-6)
    sched = epoch_cosine(5e-3, 2, 4)
    lrs = [float(sched(s)) for s in range(8)]
    want = [
        1e-6 + (5e-3 - 1e-6) * (1 + np.cos(np.pi * e / 4)) / 2 for e in (0, 0, 1, 1, 2, 2, 3, 3)
    ]
    np.testing.assert_allclose(lrs, want, rtol=1e-6)
