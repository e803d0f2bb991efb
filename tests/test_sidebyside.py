"""The side-by-side script of the LNN seed (bench/sidebyside/lnn_seed.py) without the seed's
code: its one-line error on a bad --seed-code, the stax <-> MLP parameter mapping, the seed's
input embedding and the helpers that read the seed's notebook."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.example_libraries import stax

from bench.sidebyside import _seed as seed_code
from bench.sidebyside import lnn_seed as S
from models import MLP


@pytest.mark.parametrize("make", [lambda p: p / "absent", lambda p: p])
def test_bad_seed_code_is_one_clear_line(tmp_path, capsys, make):
    (tmp_path / "lnn.py").write_text("")  # a folder with some, not all, of the files
    assert S.main(["--seed-code", str(make(tmp_path)), "--steps", "1"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("error: --seed-code")
    assert "lagrangian_nns" in err


def test_check_seed_code_names_the_missing_files(tmp_path):
    for f in S.EXPECTED[:-1]:
        (tmp_path / f).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / f).write_text("")
    with pytest.raises(S.SeedCodeError, match="DoublePendulum.ipynb"):
        S.check_seed_code(tmp_path)
    (tmp_path / S.EXPECTED[-1]).parent.mkdir(parents=True, exist_ok=True)
    (tmp_path / S.EXPECTED[-1]).write_text("{}")
    assert S.check_seed_code(tmp_path) == tmp_path


def test_mapping_round_trip_and_forward():
    mlp = MLP(4, 1, 8, 2, "softplus", "float32", key=jax.random.PRNGKey(0), init="lnn")
    other = MLP(4, 1, 8, 2, "softplus", "float32", key=jax.random.PRNGKey(1), init="lnn")
    params = S.ours_to_seed(mlp)
    assert [len(p) for p in params] == [2, 0, 2, 0, 2]
    back = S.seed_to_ours(params, other)
    for a, b in zip(jax.tree.leaves(mlp), jax.tree.leaves(back), strict=True):
        np.testing.assert_array_equal(a, b)
    # the seed's network (hyperopt's extended_mlp: Dense, Softplus, ..., Dense) on our params
    _, forward = stax.serial(
        stax.Dense(8), stax.Softplus, stax.Dense(8), stax.Softplus, stax.Dense(1)
    )
    x = jax.random.normal(jax.random.PRNGKey(2), (5, 4))
    np.testing.assert_allclose(forward(params, x), jax.vmap(mlp)(x), rtol=1e-6, atol=1e-6)
    with pytest.raises(ValueError):
        S.seed_to_ours(params[:3], other)


def test_seed_features_wrap_angles_like_the_seed():
    import models

    scene = models.Scene(dof=2, angular=(False, False))
    feats = S._seed_features_class()(scene)
    q, v = jnp.array([4.0, -4.0]), jnp.array([1.0, 2.0])
    # raw_lagrangian_eom: q % 2 pi; wrap_coords: (q + pi) % 2 pi - pi
    want = np.concatenate([((np.asarray(q) % (2 * np.pi)) + np.pi) % (2 * np.pi) - np.pi, v])
    np.testing.assert_allclose(feats(q, v, jnp.zeros(0)), want, rtol=1e-6)
    assert feats.size(True) == 4


def test_notebook_readers():
    cells = [
        "lr = 1e-3\ndef loss(p):\n    return p",
        "%matplotlib inline",  # a magic: skipped
        "lr = 1e-5\nfor e in range(3):\n    update_derivative(e, s, b, 1e-6)",
    ]
    found = seed_code._last_definitions(cells, {"lr", "loss"})
    assert found["lr"].value.value == 1e-5 and found["loss"].name == "loss"
    assert seed_code._training_l2reg(cells) == 1e-6
    with pytest.raises(S.SeedCodeError, match="OneCycleLR"):
        seed_code._last_definitions(cells, {"OneCycleLR"})
