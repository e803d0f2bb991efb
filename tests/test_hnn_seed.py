"""Claim 10 (the HNN seed's tasks): its declarations, and its verdict rule on
synthetic tables built to pass, to fail and to be undecided (no training), plus the table
beside the seed's numbers and the figure from a synthetic results folder."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from _markdown import table_rows

from bench.core import _store, expand
from bench.kit import policy
from bench.studies.hnn_seed import tasks as H

SEEDS = (0, 1, 2, 3, 4)
SPREAD = np.array([-0.4, 0.4, 0.0, -0.2, 0.2])  # mean 0, sd 0.32: t half-width 0.30 at n = 5


def _tables(
    energy_ratio: float, loss_ratio: float, spread: float = 0.0, two_body_loss: float = 0.1
) -> pd.DataFrame:
    """Rows of the three experiments at smoke on seeds 0-4: the MLP's energy MSE
    ``energy_ratio`` x the HNN's and the HNN's test loss ``loss_ratio`` x the MLP's
    (``two_body_loss`` on the two-body, where the seed's HNN fits 10x better), per seed times
    exp(spread * SPREAD); NODE+SO between; trivial predictors far worse."""
    rows = []
    for exp in H.EXPERIMENTS:
        for c0 in expand(exp, "smoke"):
            for s in SEEDS:
                c = type(c0)(**{**c0.to_dict(), "seed": s})
                jitter = math.exp(spread * SPREAD[s])
                e_hnn, l_mlp = 1e-4, 1e-3
                fit = two_body_loss if c.system == "two_body" else loss_ratio
                energy, loss, err = {
                    ("node", "momentum"): (e_hnn * energy_ratio * jitter, l_mlp, 0.05),
                    ("hnn", "momentum"): (e_hnn, l_mlp * fit * jitter, 0.04),
                    ("node_so", "velocity"): (e_hnn * 3, l_mlp, 0.03),
                    ("constant_velocity", "velocity"): (10.0, math.nan, 0.8),
                }[(c.model, c.coordinates)]
                row = c.to_dict()
                momentum = c.coordinates == "momentum"
                row.update(
                    config_hash=c.config_hash,
                    train_hash=c.train_hash,
                    experiment=exp.name,
                    profile="smoke",
                    status="ok",
                    energy_mse=energy,
                    derivative_mse_test=loss,
                    derivative_mse_train=loss,
                    rollout_error=err / 2 if momentum else err,
                    rollout_error_velocity=err if momentum else math.nan,
                    curves={"t": [0.1], "rel_error": [err], "energy_violation": [0.1]},
                )
                rows.append(_store.jsonable(row))
    return _store.rows_frame(rows)


def _parts(v):
    return {p.name.split(":")[0] + ":" + p.name.split(":")[1].split()[0]: p.status for p in v.parts}


def _by_system(v):
    """``{"(a) two_body": status, ...}``: each part's status by its letter and system."""
    return {p.name.split(":")[0]: p.status for p in v.parts}


def test_declarations_follow_the_seed():
    for exp in H.EXPERIMENTS:
        cfgs = expand(exp, "paper")
        assert {(c.model, c.coordinates) for c in cfgs} == set(H.CELLS)
        assert all(c.train_target == "derivative" and c.width == 200 for c in cfgs)
        assert {c.seed for c in cfgs} == set(SEEDS)
    spring = expand(H.EXPERIMENTS[0], "paper")[0]
    # 25 training trajectories of 30 points on [0, 3] s, noise 0.1, 2000 full-batch steps
    assert (spring.n_train, spring.chunk, spring.noise, spring.steps, spring.batch) == (
        25,
        30,
        0.1,
        2000,
        25,
    )
    assert spring.dt * (spring.chunk - 1) == pytest.approx(3.0)
    two = expand(H.EXPERIMENTS[2], "paper")[0]
    assert (two.n_train, two.chunk, two.steps, two.noise) == (800, 50, 10000, 0.0)


def test_several_orders_of_magnitude_at_similar_loss_are_reproduced():
    v = H.claim_10(_tables(energy_ratio=1000.0, loss_ratio=1.0, spread=0.1))
    assert v.verdict == "reproduced", v.detail
    assert len(v.parts) == 6 and all(p.status == "holds" for p in v.parts)
    assert v.effect == pytest.approx(math.log(1000.0), rel=1e-6)
    # "tied on loss" is a condition on the mass-spring and the pendulum; on the two-body the
    # seed states the HNN's fit edge, "about an order of magnitude", a finding at sqrt(10)
    roles = {p.name.split(":")[0]: p.role for p in v.parts if p.name.startswith("(b)")}
    assert roles["(b) mass_spring"] == roles["(b) pendulum"] == "condition"
    fit = next(p for p in v.parts if p.name.startswith("(b) two_body"))
    assert fit.role != "condition" and fit.kind == "greater"
    assert fit.margin_value == pytest.approx(10**0.5) and H.TWO_BODY_FIT.source in fit.margin
    # the two-body margin is the seed's stated number, the others the policy's energy margin
    two = next(p for p in v.parts if p.name.startswith("(a) two_body"))
    assert two.margin_value == H.TWO_BODY_ENERGY.value == 100.0
    assert H.TWO_BODY_ENERGY.source in two.margin  # the margin names where the seed states it
    # the Deconstructing view (NODE+SO) reported beside, not a part of the verdict
    assert "Deconstructing view" in v.detail and not any("NODE+SO" in p.name for p in v.parts)


def test_equal_energy_error_is_not_reproduced():
    v = H.claim_10(_tables(energy_ratio=1.0, loss_ratio=1.0, spread=0.1, two_body_loss=1.0))
    assert v.verdict == "not reproduced", v.detail
    assert {p.status for p in v.parts if p.name.startswith("(a)")} == {"contradicts"}
    # the two-body HNN fitting 10x better, as the seed's did, holds alone: the headline fails
    v = H.claim_10(_tables(energy_ratio=1.0, loss_ratio=1.0, spread=0.1))
    assert v.verdict.startswith("partly reproduced") and _by_system(v)["(b) two_body"] == "holds"
    assert "headline contradicted" in v.label(), v.label()


def test_an_energy_edge_with_a_worse_fit_is_judged():
    # "at similar loss" can only confound: the HNN fits 30x worse, so its fit cannot explain
    # its energy advantage, and the comparison is judged (the condition is shown, and holds)
    v = H.claim_10(_tables(energy_ratio=1000.0, loss_ratio=30.0, spread=0.1))
    assert v.verdict == "reproduced", v.detail
    assert {p.status for p in v.parts if p.name.startswith("(b)")} == {"holds"}
    assert {p.status for p in v.parts if p.name.startswith("(a)")} == {"holds"}


def test_an_energy_edge_bought_with_a_better_fit_is_not_tested():
    # the HNN fits 30x better where the seed says "tied": fit could explain its energy
    # advantage, so (a) is not tested there; the two-body, where the seed says the HNN fits
    # better, is judged
    v = H.claim_10(_tables(energy_ratio=1000.0, loss_ratio=1 / 30.0, spread=0.1))
    assert v.verdict == "inconclusive", v.detail
    got = _by_system(v)
    assert got["(b) mass_spring"] == got["(b) pendulum"] == "contradicts"
    assert got["(a) mass_spring"] == got["(a) pendulum"] == "not tested"
    assert got["(a) two_body"] == got["(b) two_body"] == "holds"


def test_a_two_body_hnn_that_fits_no_better_contradicts_the_seeds_fit_statement():
    # the seed's two-body HNN fits about 10x better: tied here, that finding fails while the
    # energy edge is still judged (never gated by the fit); 3x better is undecided at sqrt(10)
    tied = H.claim_10(_tables(energy_ratio=1000.0, loss_ratio=1.0, spread=0.1, two_body_loss=1))
    got = _by_system(tied)
    assert got["(b) two_body"] == "contradicts" and got["(a) two_body"] == "holds"
    assert tied.verdict == "partly reproduced", tied.detail
    near = H.claim_10(_tables(energy_ratio=1000.0, loss_ratio=1.0, spread=1.0, two_body_loss=1 / 3))
    assert _by_system(near)["(b) two_body"] == "undecided", near.detail


def test_a_ratio_on_the_margin_is_undecided():
    # at the policy's energy-MSE margin: undecided where the seed says "dramatically", far
    # short of the two-body's stated 100x
    margin = policy.margin("energy", squared=True).value
    v = H.claim_10(_tables(energy_ratio=margin, loss_ratio=1.0, spread=1.0))
    got = {p.name.split(":")[0]: p.status for p in v.parts if p.name.startswith("(a)")}
    assert got == {
        "(a) mass_spring": "undecided",
        "(a) pendulum": "undecided",
        "(a) two_body": "contradicts",
    }, v.detail


def test_fewer_than_five_seeds_or_no_runs_are_inconclusive():
    r = _tables(energy_ratio=100.0, loss_ratio=1.0)
    assert H.claim_10(r[r["seed"] < 3]).verdict == "inconclusive"
    assert H.claim_10(r.iloc[0:0]).verdict == "inconclusive"
    # rollout-trained rows of these systems are not the seed's protocol: left out
    assert H.claim_10(r.assign(train_target="rollout")).verdict == "inconclusive"


def test_section_and_figure_from_a_results_folder(tmp_path):
    r = _tables(energy_ratio=100.0, loss_ratio=1.0)
    r.to_parquet(tmp_path / "runs.parquet", index=False)
    rows = {row["task"]: row for row in table_rows(H.section(tmp_path), "| task | seeds")}
    assert list(rows) == list(H.SYSTEMS)
    for system in H.SYSTEMS:
        # the seed's numbers and ours, side by side (ours: 1e-2 MLP / 1e-4 HNN / 3e-4 NODE+SO)
        mlp, hnn = H.SEED_NUMBERS[system]["energy_mse"]
        assert rows[system]["energy MSE MLP / HNN (seed)"] == f"{mlp:.3g} / {hnn:.3g}"
        ours = rows[system]["energy MSE MLP / HNN / NODE+SO (ours)"].split(" / ")
        assert [float(x) for x in ours] == [0.01, 0.0001, 0.0003]
    paths = H.figure(tmp_path)
    assert {p.suffix for p in paths} == {".png", ".pdf"} and all(
        p.stat().st_size > 1000 for p in paths
    )
