"""Claim 13 (Fig. 9, App. D.2): the experiment's declarations, and its verdict rule on synthetic
tables built to pass, to fail and to be undecided (no training)."""

from __future__ import annotations

import re

import pandas as pd
import pytest
from _markdown import table_rows
from _synthetic import cell_tables

from bench.core import expand
from bench.studies.decon import rigid_bodies as R

# the paper's picture: SO closes most of the gyroscope's gap; the NODE leads on the other two
REPRODUCE = {
    "gyroscope": {"node": 0.1, "node_so": 0.03, "hnn_so": 0.02},
    "rotor": {"node": 0.02, "node_so": 0.04, "hnn_so": 0.05},
    "magnet_pendulum": {"node": 0.02, "node_so": 0.035, "hnn_so": 0.04},
}
# the HNN far ahead everywhere and SO closing none of it
CONTRADICT = {
    s: {"node": 0.1, "node_so": 0.09, "hnn_so": 0.01}
    for s in ("gyroscope", "rotor", "magnet_pendulum")
}


SHARE = "(a) share of the NODE-HNN difference accounted for by SO"


def _status(v):
    return {p.name: p.status for p in v.parts}


def test_declarations():
    runs = expand(R.RIGID_BODIES, "paper-core")
    assert {(c.system, c.dt) for c in runs} == set(R.DT.items())
    assert {c.model for c in runs} == {"node", "node_so", "hnn_so", "constant_velocity"}
    # the paper's per-run budget and protocol: 800 chunks of 5, 8000 steps, 10 s trajectories
    c = runs[0]
    assert (c.n_train, c.chunk, c.steps, c.width, c.duration, c.test_chunks) == (
        800, 5, 8000, 256, 10.0, 20
    )  # fmt: skip
    assert {c.seed for c in expand(R.RIGID_BODIES, "quick")} == {0, 1, 2, 3, 4}
    # the second learning rate: the three trained models where the NODE leads, paper-core only
    slow = {(c.system, c.model) for c in runs if c.lr == R.STABLE_LR}
    assert slow == {(s, m) for s in R.NODE_LEADS for m in R.MODELS}
    assert {c.lr for c in runs} - {R.STABLE_LR} == {R.PAPER_LR}
    assert {c.lr for c in expand(R.RIGID_BODIES, "quick")} == {R.PAPER_LR}


def test_claim_13_reproduces_on_the_papers_picture():
    v = R.claim_13(cell_tables(R.RIGID_BODIES, REPRODUCE, spread=0.05))
    st = _status(v)
    for system in R.SYSTEMS:  # the NODE's lead on rotor and magnet: SO makes most of it
        assert st[f"{system}: {SHARE}"] == "holds"
    assert st["rotor: (b) NODE leads, log(HNN / NODE)"] == "holds"
    assert st["magnet_pendulum: (b) NODE leads, log(HNN / NODE)"] == "holds"
    assert v.verdict == "reproduced"
    # no difference to account for on the rotor: its (a) is not tested
    same = {**REPRODUCE, "rotor": {"node": 0.02, "node_so": 0.03, "hnn_so": 0.021}}
    st = _status(R.claim_13(cell_tables(R.RIGID_BODIES, same, spread=0.05)))
    assert st[f"rotor: {SHARE}"] == "not tested"


def test_claim_13_is_contradicted_when_so_closes_nothing_and_the_hnn_leads():
    v = R.claim_13(cell_tables(R.RIGID_BODIES, CONTRADICT, spread=0.05))
    st = _status(v)
    assert st[f"gyroscope: {SHARE}"] == "contradicts"
    assert st["rotor: (b) NODE leads, log(HNN / NODE)"] == "contradicts"
    assert v.verdict == "not reproduced"


def test_claim_13_is_undecided_on_noise_few_seeds_or_models_that_did_not_learn():
    noisy = R.claim_13(cell_tables(R.RIGID_BODIES, REPRODUCE, spread=3.0))
    assert noisy.verdict == "inconclusive"
    few = R.claim_13(cell_tables(R.RIGID_BODIES, REPRODUCE, seeds=(0, 1, 2)))
    assert few.verdict == "inconclusive"
    # trivial predictors as good as the models: no model learned, nothing is compared
    flat = R.claim_13(cell_tables(R.RIGID_BODIES, REPRODUCE, trivial_error=0.03))
    assert flat.verdict == "inconclusive"
    assert all(p.status == "not tested" for p in flat.parts if p.role != "condition")
    assert R.claim_13(cell_tables(R.RIGID_BODIES, REPRODUCE).iloc[0:0]).verdict == "inconclusive"


@pytest.mark.parametrize("system", ["rotor", "magnet_pendulum"])
def test_claim_13_b_turns_against_the_claim_on_its_own(system):
    errors = {s: dict(m) for s, m in REPRODUCE.items()}
    errors[system] = {"node": 0.1, "node_so": 0.03, "hnn_so": 0.02}
    v = R.claim_13(cell_tables(R.RIGID_BODIES, errors, spread=0.05))
    assert _status(v)[f"{system}: (b) NODE leads, log(HNN / NODE)"] == "contradicts"
    assert v.verdict == "partly reproduced"


def _with_stable_lr(paper_errors, stable_errors, spread=0.05):
    """Rows at the paper's rate with ``paper_errors`` and, on the systems where the NODE
    leads, the three models at the stable rate with ``stable_errors``."""
    paper = cell_tables(R.RIGID_BODIES, paper_errors, profile="paper-core", spread=spread)
    paper = paper[paper["lr"] == R.PAPER_LR].reset_index(drop=True)
    both = cell_tables(R.RIGID_BODIES, stable_errors, profile="paper-core", spread=spread)
    stable = both[both["lr"] == R.STABLE_LR]
    assert len(stable) == 5 * len(R.NODE_LEADS) * len(R.MODELS)
    return paper, pd.concat([paper, stable], ignore_index=True)


@pytest.mark.parametrize(
    ("stable_errors", "reading"),
    [(REPRODUCE, "reproduced"), (CONTRADICT, "not reproduced")],
)
def test_the_stable_rate_is_a_reading_beside_the_verdict_not_a_part_of_it(stable_errors, reading):
    # at the paper's rate the HNN did not learn where the NODE leads: those parts not tested
    lost = {s: dict(m) for s, m in REPRODUCE.items()}
    for system in R.NODE_LEADS:
        lost[system]["hnn_so"] = 10.0
    paper, rows = _with_stable_lr(lost, stable_errors)
    alone, v = R.claim_13(paper), R.claim_13(rows)
    assert (v.verdict, _status(v)) == (alone.verdict, _status(alone))
    assert _status(v)["rotor: (b) NODE leads, log(HNN / NODE)"] == "not tested"
    assert R.stable_lr_reading(paper) is None
    stable = R.stable_lr_reading(rows)
    assert stable.verdict == reading
    # the stable reading only adds to the detail: its verdict and its parts' statuses
    extra = v.detail.removeprefix(alone.detail)
    assert extra != v.detail and stable.verdict in extra
    assert all(f"{q.name}: {q.status}" in extra for q in stable.parts if q.role != "condition")
    # the stable reading is undecided on noise like any other
    _, noisy = _with_stable_lr(lost, stable_errors, spread=3.0)
    assert R.stable_lr_reading(noisy).verdict == "inconclusive"


def test_figure_draws_every_system_and_model(tmp_path):
    paths = R.fig_rigid_bodies(cell_tables(R.RIGID_BODIES, REPRODUCE), None, tmp_path)
    assert sorted(p.suffix for p in paths) == [".pdf", ".png"]
    assert all(p.stat().st_size > 0 for p in paths)


def test_the_reports_tables_tell_the_two_rates_apart():
    """The experiment's table, its discrimination lines and its missing cells name the learning
    rate, since the experiment's cells differ in it (the other experiments' tables do not)."""
    from bench._tables import _experiment_table, _missing_cells, discrimination_groups

    _, rows = _with_stable_lr(REPRODUCE, CONTRADICT)
    table = table_rows("\n".join(_experiment_table(rows)), "| system |")
    assert list(table[0])[:5] == ["system", "variant", "coordinates", "lr", "seeds"]
    rotor_hnn = [r for r in table if (r["system"], r["variant"]) == ("rotor", "hnn_so")]
    assert sorted(r["lr"] for r in rotor_hnn) == ["0.001", "0.005"]
    # the stable rate's HNN (CONTRADICT: ahead of the NODE) is the rotor's best variant
    rotor = next(d for d in discrimination_groups(rows) if d.group == "system=rotor")
    assert rotor.best == f"hnn_so lr={R.STABLE_LR:g}"
    paper_only = rows[rows["lr"] == R.PAPER_LR]
    (line, _) = _missing_cells(paper_only, "rigid_bodies", "paper-core")
    missing = re.fullmatch(r"No runs for \d+ declared cells \(every seed\): (.*)\.", line)
    cells = missing.group(1).split("; ")  # every missing cell at the stable rate only
    assert f"NODE on rotor lr={R.STABLE_LR:g}" in cells
    assert all(c.endswith(f"lr={R.STABLE_LR:g}") for c in cells), cells
    # a protocol that gives each model its own rate: the rate names no cell
    own = paper_only.assign(lr=paper_only["model"].map({"hnn_so": R.STABLE_LR}).fillna(R.PAPER_LR))
    assert "lr" not in table_rows("\n".join(_experiment_table(own)), "| system |")[0]
    assert all(" lr=" not in d.best for d in discrimination_groups(own))


def test_a_diverged_run_is_scored_and_counted_not_dropped():
    """Every run counts: a diverged HNN run on the gyroscope scores the worst error and is
    counted, so the seed stays in the paired comparison instead of leaving it."""
    runs = cell_tables(R.RIGID_BODIES, REPRODUCE, spread=0.05)
    hit = (runs["system"] == "gyroscope") & (runs["model"] == "hnn_so") & (runs["seed"] == 2)
    assert hit.sum() == 1
    runs.loc[hit, ["status", "rollout_error"]] = ["diverged", float("nan")]
    v = R.claim_13(runs)
    assert v.n_failed == 1, v.detail
    share = next(p for p in v.parts if p.name == f"gyroscope: {SHARE}")
    assert share.n == 5, share.text()
