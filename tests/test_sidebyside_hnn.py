"""The side-by-side script of the HNN seed's pixel pendulum (bench/sidebyside/hnn_seed.py)
without the seed's code or torch: its one-line error on a bad --seed-code, the mapping of the
seed's PyTorch parameters onto our LatentModel (round trip, and the seed's forward pass written
out in jax on the mapped arrays), the shared batches and windows, and the readers of the seed's
training script."""

from __future__ import annotations

import ast
import types

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import models
from bench.sidebyside import _hnn_seed_torch as T
from bench.sidebyside import hnn_seed as S


@pytest.mark.parametrize("make", [lambda p: p / "absent", lambda p: p])
def test_bad_seed_code_is_one_clear_line(tmp_path, capsys, make):
    (tmp_path / "hnn.py").write_text("")  # a folder with some, not all, of the files
    assert S.main(["--seed-code", str(make(tmp_path)), "--steps", "1"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("error: --seed-code")
    assert "hamiltonian-nn" in err


def test_check_seed_code_names_the_missing_files(tmp_path):
    for f in S.EXPECTED[:-1]:
        (tmp_path / f).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / f).write_text("")
    with pytest.raises(S.SeedCodeError, match="experiment-pixels/train.py"):
        S.check_seed_code(tmp_path)
    (tmp_path / S.EXPECTED[-1]).parent.mkdir(parents=True, exist_ok=True)
    (tmp_path / S.EXPECTED[-1]).write_text("")
    assert S.check_seed_code(tmp_path) == tmp_path


def _latent(name, key=0):
    return models.LatentModel(
        name,
        (2, 4, 4),
        key=jax.random.PRNGKey(key),
        width=8,
        ae_width=8,
        activation="tanh",
        options={"init": "hnn_seed"},
    )


def _random_state(name, seed=0) -> dict:
    """Random parameters in the seed's layout (PyTorch's (out, in) weights)."""
    rng = np.random.default_rng(seed)
    state, _ = S.ours_to_seed(_latent(name))
    return {k: rng.normal(size=v.shape).astype(np.float32) * 0.3 for k, v in state.items()}


@pytest.mark.parametrize("name", ["hnn", "node"])
def test_mapping_round_trip(name):
    m = _latent(name, 0)
    state, extra = S.ours_to_seed(m)
    assert state["autoencoder.linear1.weight"].shape == (8, 32)  # PyTorch's (out, in)
    assert state["autoencoder.linear8.weight"].shape == (32, 8)
    assert state["hnn.differentiable_model.linear3.weight"].shape == (2, 8)  # both models
    assert "hnn.differentiable_model.linear3.bias" not in state  # the seed's has none
    np.testing.assert_array_equal(next(iter(extra.values())), 0.0)  # ours, zero at init
    back = S.seed_to_ours(state, _latent(name, 1))
    for a, b in zip(jax.tree.leaves(m), jax.tree.leaves(back), strict=True):
        np.testing.assert_array_equal(a, b)
    with pytest.raises(ValueError, match="shape"):
        S.seed_to_ours({**state, "autoencoder.linear2.bias": np.zeros(3)}, m)


@pytest.mark.parametrize("name", ["hnn", "node"])
def test_the_seeds_forward_pass_on_the_mapped_parameters(name):
    state = _random_state(name)
    m = S.seed_to_ours(state, _latent(name))

    def lin(n, h, bias=True):  # torch.nn.Linear: h W^T + b
        out = h @ jnp.asarray(state[f"{n}.weight"]).T
        return out + jnp.asarray(state[f"{n}.bias"]) if bias else out

    def stack(first, h):  # MLPAutoencoder.encode / decode
        names = [f"autoencoder.linear{i}" for i in range(first, first + 4)]
        h = jax.nn.relu(lin(names[0], h))
        h = h + jax.nn.relu(lin(names[1], h))
        h = h + jax.nn.relu(lin(names[2], h))
        return lin(names[3], h)

    def mlp(z):  # nn_models.MLP, tanh, no bias on the last layer
        d = "hnn.differentiable_model.linear"
        h = jnp.tanh(lin(f"{d}1", z))
        return lin(f"{d}3", jnp.tanh(lin(f"{d}2", h)), bias=False)

    x = jax.random.uniform(jax.random.PRNGKey(3), (2, 4, 4))
    z = stack(1, x.reshape(-1))
    np.testing.assert_allclose(m.encode(x), z, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(m.decode(z), stack(5, z).reshape(2, 4, 4), rtol=1e-5, atol=1e-6)
    if name == "hnn":  # the solenoidal field of F2 (output 1): dF2 @ M^T = (dF2/dp, -dF2/dq)
        g = jax.grad(lambda v: mlp(v)[1])(z)
        want = jnp.array([g[1], -g[0]])
    else:
        want = mlp(z)
    got = m.dynamics.vector_field(0.0, z, jnp.zeros((0,)))
    np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-6)


def test_the_hnns_unused_first_output_does_not_matter():
    state = _random_state("hnn")
    other = {
        **state,
        "hnn.differentiable_model.linear3.weight": state["hnn.differentiable_model.linear3.weight"]
        * np.array([[5.0], [1.0]], np.float32),
    }
    a, b = S.seed_to_ours(state, _latent("hnn")), S.seed_to_ours(other, _latent("hnn"))
    for x, y in zip(jax.tree.leaves(a), jax.tree.leaves(b), strict=True):
        np.testing.assert_array_equal(x, y)


def test_batches_are_the_runs_and_windows_gather():
    from bench.core import PixelObjective

    frames = np.arange(3 * 7 * 2 * 2, dtype=np.float32).reshape(3, 7, 2, 2)
    cfg = types.SimpleNamespace(batch=4, seed=3, steps_per_call=5, steps=100)
    obj = PixelObjective(chunk=3)
    got = S.batch_stream(obj, frames, cfg, 12)
    stream = obj.batches(frames, cfg)
    want = np.concatenate([stream.take(5) for _ in range(3)])[:12]
    np.testing.assert_array_equal(got, want)
    w = S.all_windows(frames, 3)
    assert len(w) == 3 * 5 and w[:, 1].max() == 4
    np.testing.assert_array_equal(S.gather(frames, np.array([[1, 2]]), 3)[0], frames[1, 2:5])


FAKE_TRAIN = """
def get_args():
    parser = argparse.ArgumentParser()
    parser.add_argument('--input_dim', default=2*4**2, type=int)
    parser.add_argument('--learn_rate', default=1e-3, type=float)
    parser.add_argument('--save_dir', default=THIS_DIR, type=str)
    return parser.parse_args()

def pixelhnn_loss(x, x_next, model, return_scalar=True):
    return x

def train(args):
    torch.manual_seed(args.seed)
    model = build(args)
    optim = torch.optim.Adam(model.parameters(), args.learn_rate, weight_decay=1e-5)
    data = get_dataset(args)
    return model
"""


def test_readers_of_the_training_script():
    tree = ast.parse(FAKE_TRAIN)
    assert T._defaults(tree) == {"input_dim": 32, "learn_rate": 1e-3}  # save_dir: a name
    train = T._function(tree, "train")
    assert len(T._build_statements(train)) == 3  # seed, model, optimiser; not the data
    assert T._weight_decay(train) == 1e-5
    assert T._function(tree, "pixelhnn_loss").name == "pixelhnn_loss"
    with pytest.raises(SystemExit, match="no missing"):
        T._function(tree, "missing")


def test_the_seeds_summary_reads_each_seeds_last_step_against_the_committed_rows(tmp_path):
    """The over-seeds summary (bench.sidebyside.hnn_seed_seeds): the seed curve's last evaluated
    step per seed and model, set beside the committed rows on the seeds both have; the gains,
    their geometric means, the count at the gate and the energy ratio MLP / HNN per side."""
    import pandas as pd

    from bench.sidebyside import hnn_seed_seeds as H

    for s, gain in ((0, 8.0), (1, 2.0)):
        rows = []
        for model, g, e in (("hnn", gain, 1e-3), ("node", 2.0, 4e-2)):
            for step, pm in ((5000, 0.5), (10000, 1.0 / g)):
                rows.append({"model": model, "curve": "seed", "step": step, "pixel_mse": pm,
                             "pixel_mse_static": 1.0, "seed_energy_mse": e})  # fmt: skip
            rows.append({"model": model, "curve": "ours", "step": 10000, "pixel_mse": 9.0,
                         "pixel_mse_static": 1.0, "seed_energy_mse": 1.0})  # fmt: skip
        (tmp_path / f"seed{s}").mkdir()
        pd.DataFrame(rows).to_csv(tmp_path / f"seed{s}" / "curves.csv", index=False)
    (tmp_path / "seedx").mkdir()  # not a seed folder: ignored
    code = H.seed_code_rows(tmp_path)
    assert len(code) == 4 and set(code["step"]) == {10000}
    ours = pd.DataFrame(
        [{"seed": s, "model": m, "pixel_mse": 0.25, "pixel_mse_static": 1.0,
          "seed_energy_mse": 1e-3 if m == "hnn" else 1e-2}
         for s in (0, 1, 2) for m in ("hnn", "node")]
    )  # fmt: skip
    t = H.table(code, ours)
    assert sorted(t["seed"].unique()) == [0, 1]  # seed 2 has no seed-code run
    hnn = t[t["model"] == "hnn"].set_index("seed")
    assert hnn["gain_code"].tolist() == pytest.approx([8.0, 2.0])
    assert hnn["gain_ours"].tolist() == pytest.approx([4.0, 4.0])
    lines = H.markdown(t, 4.0)
    row = {(x.split(" | ")[0][2:], x.split(" | ")[1]): x for x in lines if x.startswith("| ")}
    assert row["HNN", "seed's code"].endswith("| 4.00 | 1 of 2 |")
    assert row["HNN", "committed row"].endswith("| 4.00 | 2 of 2 |")
    assert lines[-1] == (
        "Energy MSE (the seed's metric) MLP / HNN: seed's code 40x, committed row 10x."
    )
    assert H.main(["--root", str(tmp_path / "none")]) == 2
