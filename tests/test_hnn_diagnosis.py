"""The plain-HNN spring diagnosis (``python -m bench diagnose-hnn``): the replay is the
trainer's run, the reference init is the reference's, the frozen flag and the summary."""

from __future__ import annotations

import jax
import numpy as np
import pandas as pd
import pytest
from _markdown import table_rows

import models
from bench.core import build_run, train, train_config
from bench.studies.decon.hnn_diagnosis import _diagnosis as D
from models._mlp import MLP


def test_the_cells_are_the_plain_hnn_spring_runs_of_claims_1_and_3():
    cells = D.cells("paper-core")
    assert [c.seed for c in cells] == [0, 1, 2, 3, 4]
    assert {(c.model, c.system, c.k, c.steps, c.lr) for c in cells} == {
        ("hnn", "spring_pendulum", 2, 8000, 5e-3)
    }
    with pytest.raises(ValueError, match="profile must be one of"):
        D.diagnose("huge", "/nonexistent")
    with pytest.raises(ValueError, match="steps must be an integer >= 1"):
        D.diagnose("smoke", "/nonexistent", steps=0)


@pytest.mark.slow  # a smoke training replayed block by block (~30 s)
def test_replay_is_the_trainers_run_and_says_how_long_it_equals_the_stored_one(tmp_path):
    cfg = D.cells("smoke")[0]
    cache = tmp_path / "cache"
    _, data, _, model = build_run(cfg, cache)
    res = train(model, data, train_config(cfg))
    k = len(res.losses)  # smoke: one block of the run's 20 steps
    pdir = cache / "params" / cfg.train_hash
    pdir.mkdir(parents=True)
    stored = res.losses.copy()
    stored[7] *= 1.01  # a stored run that parts from this one at step 7
    np.save(pdir / "losses.npy", stored)
    rows = pd.DataFrame(D._replay(cfg, "suite", 1, cache))
    # probes before the first step and after the block (rounded up to whole blocks)
    assert list(rows["step"]) == [0, k]
    np.testing.assert_array_equal(rows["loss"], [res.losses[0], res.losses[-1]])
    assert rows["block_loss"].iloc[1] == pytest.approx(np.mean(res.losses))
    assert rows["stored_loss"].iloc[0] == stored[0] and set(rows["same_as_stored"]) == {7}
    # a fresh mass matrix is the identity up to the network's small output
    first = rows.iloc[0]
    assert 0.5 < first["mass_eig_min"] <= first["mass_eig_max"] < 2.0
    # lr_1e-3 starts from the suite's model; reference_init from another; neither reads the
    # stored run (it is the suite's)
    low = pd.DataFrame(D._replay(cfg, "lr_1e-3", 1, cache))
    ref = pd.DataFrame(D._replay(cfg, "reference_init", 1, cache))
    assert low["motion"].iloc[0] == pytest.approx(first["motion"])
    assert low["loss"].iloc[0] == res.losses[0] and low["loss"].iloc[1] != res.losses[-1]
    assert ref["motion"].iloc[0] != pytest.approx(first["motion"])
    assert set(low["lr"]) == {D.LOW_LR} and set(rows["lr"]) == {cfg.lr}
    assert low["stored_loss"].isna().all() and low["same_as_stored"].isna().all()
    with pytest.raises(ValueError, match="variant must be one of"):
        D._replay(cfg, "bogus", 1, cache)


@pytest.mark.slow
def test_diagnose_runs_every_variant_on_its_cores(tmp_path):
    df = D.diagnose("smoke", tmp_path, cache_root=tmp_path / "cache")
    assert (tmp_path / D.FILE).exists() and set(df["variant"]) == set(D.VARIANTS)
    cores = df.groupby("variant")["cores"].first()
    assert cores["suite"] == 1 and cores["reference_init"] == 1


def test_reference_biases_are_pytorch_defaults_except_the_mass_output():
    scene = models.Scene(dof=2, angular=(False, False), n_args=0, damped=False, canonical=False)
    model = models.make("hnn", scene, key=jax.random.PRNGKey(0), width=16, depth=2)
    new = D.reference_biases(model, jax.random.PRNGKey(1))
    mlps = lambda tree: [  # noqa: E731
        x for x in jax.tree.leaves(tree, is_leaf=lambda x: isinstance(x, MLP)) if isinstance(x, MLP)
    ]
    for old_mlp, new_mlp, zero_last in [
        *[
            (a, b, False)
            for a, b in zip(mlps(model.hamiltonian_part), mlps(new.hamiltonian_part), strict=True)
        ],
        *[(a, b, True) for a, b in zip(mlps(model.mass), mlps(new.mass), strict=True)],
    ]:
        for w0, w1 in zip(old_mlp.weights, new_mlp.weights, strict=True):
            np.testing.assert_array_equal(w0, w1)
        for i, (w, b) in enumerate(zip(new_mlp.weights, new_mlp.biases, strict=True)):
            lim = 1 / np.sqrt(w.shape[0])
            if zero_last and i == len(new_mlp.biases) - 1:
                assert not np.any(np.asarray(b))
            else:
                b = np.asarray(b)
                assert np.all(np.abs(b) <= lim) and np.all(b != 0)
                assert b.size == 1 or np.std(b) > lim / 4  # spread over the interval
    assert mlps(model.hamiltonian_part) and mlps(model.mass)


def _table(last_ratio: dict) -> pd.DataFrame:
    """Two probes per (seed, variant): step 0 at loss 0.1 and step 300 whose block mean is
    ``last_ratio`` x 0.1."""
    rows = []
    for (seed, variant), ratio in last_ratio.items():
        for step in (0, 300):
            loss = 0.1 if step == 0 else 0.1 * ratio
            rows.append(
                {
                    "seed": seed,
                    "variant": variant,
                    "lr": 1e-3 if variant == "lr_1e-3" else 5e-3,
                    "cores": 1,
                    "step": step,
                    "loss": loss,
                    "block_loss": loss,
                    "stored_loss": np.nan,
                    "mass_eig_min": 1.0,
                    "mass_eig_max": 1.0 if step == 0 else (240.0 if ratio > 0.5 else 12.0),
                    "motion": 0.01 if step == 0 else 0.6,
                    "dq_error": 0.5,
                    "same_as_stored": 300 if variant == "suite" else np.nan,
                    "config_hash": f"h{seed}",
                }
            )
    return pd.DataFrame(rows)


def test_summary_flags_stalled_runs_and_shows_the_stored_run():
    df = _table({(0, "suite"): 0.1, (1, "suite"): 0.95, (1, "lr_1e-3"): 0.3})
    runs = pd.DataFrame(
        [{"config_hash": "h1", "status": "ok", "final_loss": 0.102, "rollout_error": 0.38}]
    )
    rows = table_rows(D.summary(df, runs), "| seed | variant")
    got = {
        (r["seed"], r["variant"]): (
            r["stalled"],
            r["replay = stored run (steps)"],
            r["stored run: status, final loss, rollout error"],
        )
        for r in rows
    }
    assert got == {
        ("0", "suite"): ("no", "300", "-"),  # no stored row for h0
        ("1", "suite"): ("**yes**", "300", "ok, 0.102, 0.38"),
        ("1", "lr_1e-3"): ("no", "-", "-"),  # the stored run is the suite's only
    }
    one = next(r for r in rows if (r["seed"], r["variant"]) == ("1", "suite"))
    assert one["largest eig M"] == "1 -> 240"
    assert D.stalled_counts(df) == {"suite": (1, 2), "lr_1e-3": (0, 1)}
    # the variants in their declared order, seed by seed
    assert [r["variant"] for r in rows if r["seed"] == "1"] == ["suite", "lr_1e-3"]
    # on the threshold: not stalled; NaN: not stalled
    assert D.stalled([0.51, 0.5, np.nan], 1.0).tolist() == [True, False, False]


def test_section_says_how_to_make_the_table_where_there_is_none(tmp_path):
    assert "python -m bench diagnose-hnn" in D.section(tmp_path)  # the command is the contract
    with pytest.raises(LookupError):
        table_rows(D.section(tmp_path), "| seed | variant")
    _table({(0, "suite"): 0.9}).to_csv(tmp_path / D.FILE, index=False)
    (row,) = table_rows(D.section(tmp_path), "| seed | variant")
    assert [row[k] for k in ("seed", "variant", "lr", "cores", "steps")] == [
        "0",
        "suite",
        "0.005",
        "1",
        "300",
    ]
    assert row["loss: first step -> last block"] == "0.1 -> 0.09"
