"""Verdicts along the learning curve (bench.studies.learning), pinned with synthetic tables whose
checkpoints hold the "contradict" scenario's scores before the "reproduce" scenario's (and the
reverse): the verdict at each checkpoint must be the one the claims' rules give on that table,
and the settling budget the first checkpoint of the final verdict."""

from __future__ import annotations

import re

import numpy as np
import pandas as pd
import pytest

import models
from bench.kit import evaluate_claims
from bench.studies._along import SCORES
from bench.studies.learning import (
    settling,
    settling_table,
    verdicts_along_curve,
)
from tests._markdown import table_rows
from tests._synthetic import synthetic_tables

PROFILE = "smoke"


def test_settling_index():
    assert settling(["not reproduced", "reproduced", "reproduced"]) == 1
    assert settling(["reproduced", "reproduced", "inconclusive"]) == 2
    assert settling(["reproduced", "reproduced"]) == 0
    assert settling(["reproduced"]) == 0
    assert settling(["a", "b", "a", "a"]) == 2


@pytest.fixture(scope="module")
def scenarios():
    return {s: synthetic_tables(PROFILE, scenario=s) for s in ("reproduce", "contradict")}


def _trained(runs):
    return ~runs["model"].map(lambda m: models.spec(m).trivial)


def _checkpoints(scenarios, sequence, drop_experiment=None):
    """Checkpoint tables whose position p holds the trained runs' scores of scenario
    ``sequence[p]`` (steps 5, 10, 20, ...), and their per-time curves."""
    cps, cpc = [], []
    for p, name in enumerate(sequence):
        runs, curves = scenarios[name]
        t = runs[_trained(runs)]
        if drop_experiment is not None:
            t = t[t["experiment"] != drop_experiment]
        step = 5 * 2**p
        frame = t[["config_hash", *SCORES, "status", "train_seconds"]].copy()
        frame["step"], frame["fraction"] = step, step / (5 * 2 ** (len(sequence) - 1))
        cps.append(frame)
        c = curves[curves["config_hash"].isin(t["config_hash"])].copy()
        c["step"] = step
        cpc.append(c[["config_hash", "step", "t", "rel_error", "energy_violation"]])
    return pd.concat(cps, ignore_index=True), pd.concat(cpc, ignore_index=True)


def _hybrid(scenarios, name):
    """What the runs table at a checkpoint holding scenario ``name`` must be (built here with
    pandas): the final table, its trained runs' checkpoint metrics (``SCORES``), status and
    training time taken from scenario ``name``; a run's other columns (e.g. the achieved
    symplectic error) are recorded once, at the end, and stay the final table's."""
    runs, curves = scenarios[name]
    final_runs, final_curves = scenarios["reproduce"]
    out = final_runs.copy()
    src = runs.set_index("config_hash")
    rows = _trained(out)
    for col in (*SCORES, "status", "train_seconds"):
        if col in src.columns:
            out.loc[rows, col] = src.loc[out.loc[rows, "config_hash"], col].to_numpy()
    trivial = out.loc[~rows, "config_hash"]
    curves = pd.concat(
        [
            curves[curves["config_hash"].isin(out.loc[rows, "config_hash"])],
            final_curves[final_curves["config_hash"].isin(trivial)],
        ],
        ignore_index=True,
    )
    return out, curves


def _keyed(verdicts):
    return {v.key: v.verdict for v in verdicts}


@pytest.mark.slow  # keeps make test under 10 min on this CPU
def test_verdict_at_each_checkpoint_is_the_rules_verdict_on_that_table(scenarios):
    runs, curves = scenarios["reproduce"]
    sequence = ("contradict", "reproduce", "reproduce")
    cp, cpc = _checkpoints(scenarios, sequence)
    along = verdicts_along_curve(runs, curves, cp, cpc, PROFILE)
    assert sorted(along["position"].unique()) == [0, 1, 2]
    for p, name in enumerate(sequence):
        want = _keyed(evaluate_claims(*_hybrid(scenarios, name), PROFILE))
        got = dict(along[along["position"] == p][["key", "verdict"]].to_numpy())
        assert got == {k: want[k] for k in got}, p
    # the last checkpoint is the final table: the report's own verdicts
    final = _keyed(evaluate_claims(runs, curves, PROFILE))
    last = dict(along[along["position"] == 2][["key", "verdict"]].to_numpy())
    assert last == {k: final[k] for k in last}
    assert np.allclose(sorted(along["step"].unique()), [5, 10, 20])


@pytest.mark.slow  # keeps make test under 10 min on this CPU
def test_settling_budget_finds_where_the_verdict_stops_changing(scenarios):
    runs, curves = scenarios["reproduce"]
    early = _keyed(evaluate_claims(*_hybrid(scenarios, "contradict"), PROFILE))
    final = _keyed(evaluate_claims(runs, curves, PROFILE))
    changed = {k for k in final if early.get(k) != final[k]}
    assert changed, "the scenarios must disagree on some claim for this test to mean anything"
    # contradict, then reproduce twice: the changed verdicts settle at the second checkpoint
    table = settling_table(
        verdicts_along_curve(
            runs,
            curves,
            *_checkpoints(scenarios, ("contradict", "reproduce", "reproduce")),
            PROFILE,
        )
    ).set_index("key")
    for key in changed & set(table.index):
        assert table.loc[key, "settles_at"] == 10 and table.loc[key, "settled"], key
    for key in set(table.index) - changed:
        assert table.loc[key, "settles_at"] == 5, key
    # reproduce twice, then contradict: the changed verdicts change at the last checkpoint
    runs_c, curves_c = _hybrid(scenarios, "contradict")
    seq = ("reproduce", "reproduce", "contradict")
    table = settling_table(
        verdicts_along_curve(runs_c, curves_c, *_checkpoints(scenarios, seq), PROFILE)
    ).set_index("key")
    for key in changed & set(table.index):
        assert table.loc[key, "settles_at"] == 20 and not table.loc[key, "settled"], key


def test_claims_whose_runs_lack_checkpoints_are_left_out(scenarios):
    runs, curves = scenarios["reproduce"]
    cp, cpc = _checkpoints(scenarios, ("reproduce", "reproduce"), drop_experiment="relativistic")
    along = verdicts_along_curve(runs, curves, cp, cpc, PROFILE)
    assert 7 not in set(along["claim"]) and 3 in set(along["claim"])
    empty = verdicts_along_curve(runs, curves, cp.iloc[0:0], cpc.iloc[0:0], PROFILE)
    assert empty.empty


def test_claim_4_is_judged_again_on_the_longer_learning_runs(scenarios):
    from bench.studies.decon.coordinates import claim_4
    from bench.studies.learning import verdicts_along_learning

    runs, curves = scenarios["reproduce"]
    mask = (
        runs["model"].isin(["node_so", "hnn_so"])
        & (runs["system_params"].astype(str) == "[]")
        & (runs["loss"] == "l2")
        & (runs["coordinates"] == "velocity")
    )
    runs = runs.copy()
    runs.loc[mask, "experiment"] = "learning_curves"  # stand-ins for the longer runs
    runs.loc[mask, "steps"] = 2 * runs.loc[mask, "steps"]  # longer than the profile's own
    learn = runs[mask]
    cp, cpc = _checkpoints(scenarios, ("contradict", "reproduce"))
    cp = cp[cp["config_hash"].isin(learn["config_hash"])]
    cpc = cpc[cpc["config_hash"].isin(learn["config_hash"])]
    got = verdicts_along_learning(runs, curves, cp, cpc, PROFILE)
    assert set(got["claim"]) == {4} and sorted(got["position"].unique()) == [0, 1]
    cells = set(zip(learn["system"], learn["system_params"].astype(str), strict=True))
    trivial = runs[~_trained(runs)]
    trivial = trivial[
        [
            (a, b) in cells
            for a, b in zip(trivial["system"], trivial["system_params"].astype(str), strict=True)
        ]
    ]
    for position, name in enumerate(("contradict", "reproduce")):
        s_runs, s_curves = scenarios[name]
        table = pd.concat([s_runs[s_runs["config_hash"].isin(learn["config_hash"])], trivial])
        want = {v.key: v.verdict for v in claim_4(table, s_curves) if v.n_seeds >= 2}
        have = dict(got[got["position"] == position][["key", "verdict"]].to_numpy())
        assert have == want, position
    first = dict(got[got["position"] == 0][["key", "verdict"]].to_numpy())
    last = dict(got[got["position"] == 1][["key", "verdict"]].to_numpy())
    assert first != last  # the scenarios disagree: the test can fail


def test_paper_budget_note_takes_the_curves_cells_only_and_names_each_folder():
    from bench.studies.learning import _paper_budget_note

    def row(model, folder, err, **kw):
        base = {"system": "chain_pendulum", "k": 2, "loss": "l2", "friction": 0.0,
                "noise": 0.0, "coordinates": "velocity", "system_params": "()",
                "status": "ok", "steps": 8000, "n_train": 800}  # fmt: skip
        return {**base, "model": model, "_folder": folder, "rollout_error": err, **kw}

    ref = pd.DataFrame(
        [
            row("hnn_so", "paper_gpu", 0.01),
            row("hnn_so", "paper_gpu", 0.04),
            row("hnn_so", "paper", 0.02),
            # the damped campaign's HNN+SO shares system, k and model: not the curves' cell
            row("hnn_so", "paper", 10.0, friction=0.4),
            row("hnn_so", "paper", 10.0, noise=0.01),
            row("node_so", "paper", 10.0, system="spring_pendulum"),
        ]
    )
    note = _paper_budget_note(ref, "chain_pendulum", "()")
    said = re.findall(r"(\S+) (\S+) \((\d+) steps, n_train (\d+), n=(\d+), `([^`]+)`\)", note)
    assert said == [  # per model and folder: geometric mean, steps, n_train, runs, folder
        ("HNN+SO", "0.02", "8000", "800", "1", "paper"),
        ("HNN+SO", "0.02", "8000", "800", "2", "paper_gpu"),
    ], note
    assert _paper_budget_note(ref.iloc[0:0], "chain_pendulum", "()") == ""


def test_a_claim_whose_runs_train_for_different_budgets_settles_at_a_fraction():
    """Claim 7 reads two protocols whose runs train for different numbers of steps: its rows
    have no one step per checkpoint, so its settling budget is a fraction of its runs'
    training; the columns keep the other claims' steps."""
    from bench.studies.learning import _settling_lines

    rows = []
    for key, claim, steps, verdicts in (
        ("1", 1, [100.0, 300.0], ["inconclusive", "inconclusive"]),
        ("7", 7, [np.nan, np.nan], ["inconclusive", "reproduced"]),
        ("7 (rollout loss)", 7, [np.nan, np.nan], ["partly reproduced"] * 2),
    ):
        for position, (step, verdict) in enumerate(zip(steps, verdicts, strict=True)):
            rows.append(
                {
                    "key": key,
                    "claim": claim,
                    "position": position,
                    "fraction": 2.0 ** (position - 1),
                    "step": step,
                    "verdict": verdict,
                    "effect": 0.0,
                }
            )
    along = pd.DataFrame(rows)
    settled = settling_table(along).set_index("key")
    assert settled.loc["1", "settles_at"] == 100.0  # the other claims keep their steps
    for key, fraction in (("7", 1.0), ("7 (rollout loss)", 0.5)):
        assert np.isnan(settled.loc[key, "settles_at"])
        assert settled.loc[key, "settles_fraction"] == fraction
    shown = {r["claim"]: r for r in table_rows("\n".join(_settling_lines(along)), "| claim")}
    assert list(shown["1"])[1:3] == ["verdict at 1/2 (100 steps)", "verdict at 1 (300 steps)"]
    for key, fraction in (("7", "1"), ("7 (rollout loss)", "1/2")):
        cells = list(shown[key].values())
        assert cells[1:3] == settled.loc[key, "verdicts"]
        assert cells[3].split(" of its runs' training")[0] == fraction, cells[3]
