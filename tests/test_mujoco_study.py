"""The MuJoCo study (claim 16, Fig. 7): its profiles, its verdict rule on synthetic tables built
to pass, to fail and to stay undecided (models that did not learn, a test set that does not
discriminate, the stand-in alone), its report section and figure, and the smoke profile end
to end on the random-control stand-in."""

from __future__ import annotations

import math
import re

import numpy as np
import pandas as pd
import pytest
from _markdown import section, table_rows

import systems
from bench.core import RunConfig, _store, expand, is_supplementary
from bench.kit import policy
from bench.studies.decon import mujoco as X
from bench.studies.decon.mujoco import _rule as R
from bench.studies.decon.mujoco._section import DIFFERENCES
from systems import mujoco_data as D

SEEDS = (0, 1, 2, 3, 4)
SPREAD = np.array([-0.4, 0.4, 0.0, -0.2, 0.2])  # per-seed log offsets, mean 0
INTEGRATOR = {m: i for m, i in X.CELLS if m != R.PAPER_HNN}  # App. C's cells
# test MSE, train MSE and rollout error per model: NODE+SO 5x below NODE, the HNN 4x above
# NODE in test MSE and 6x in train MSE, the constant-velocity predictor 100x above NODE
REPRODUCE = {
    "node": (0.1, 0.05, 0.2),
    "node_so": (0.02, 0.01, 0.1),
    "hnn_force": (0.4, 0.3, 0.4),
    "constant_velocity": (10.0, 5.0, 0.9),
}
# NODE+SO no better than NODE, the HNN best on test and training data
CONTRADICT = {
    "node": (0.1, 0.05, 0.2),
    "node_so": (0.3, 0.2, 0.3),
    "hnn_force": (0.01, 0.005, 0.05),
    "constant_velocity": (10.0, 5.0, 0.9),
}


def _tables(
    values=REPRODUCE, tasks=(X.QUICK_TASK,), data=X.FILE, spread=0.1, frames=False, change=None
):
    """Rows of the mujoco experiment on seeds 0-4 in the store's format (with ``frames``:
    (runs, curves)): each model's (test MSE, train MSE, rollout error) from ``values``, per
    seed times exp(spread * SPREAD) on NODE+SO and the HNN (so the paired log ratios vary);
    ``change`` ({(task, model): values}) overrides cells."""
    c0 = expand(X.EXPERIMENT, "smoke")[0].to_dict()
    rows = []
    for task in tasks:
        dt = systems.MUJOCO_TASKS[task].dt
        for model, integ in INTEGRATOR.items():
            test, train, err = (change or {}).get((task, model), values[model])
            for s in SEEDS:
                jitter = math.exp(spread * SPREAD[s]) if model in ("node_so", "hnn_force") else 1
                c = RunConfig(**{**c0, "system": task, "dt": dt, "model": model, "seed": s,
                                 "train_integrator": integ, "eval_integrator": integ,
                                 "system_params": data,
                                 "model_options": R.MODEL_OPTIONS.get(model, ())})  # fmt: skip
                stand = data == X.STAND_IN
                row = c.to_dict()
                row.update(
                    config_hash=c.config_hash,
                    train_hash=c.train_hash,
                    experiment=X.EXPERIMENT.name,
                    profile="smoke",
                    status="ok",
                    test_mse=test * jitter,
                    train_mse=train * jitter,
                    rollout_error=err * jitter,
                    energy_violation=math.nan,
                    data_source=f"{D.STAND_IN}, 300 steps" if stand else f"file {task}.npz: 200K",
                    data_sha256=("cd" if stand else "ab") * 32,
                    data_points=300 if stand else X.TRANSITIONS,
                    curves={"t": [0.0, dt], "rel_error": [0.0, 0.1]},
                )
                rows.append(_store.jsonable(row))
    runs = _store.rows_frame(rows)
    return (runs, _store.curves_frame(rows)) if frames else runs


def test_the_hnn_of_an_older_declaration_is_not_the_claim_s():
    """Rows of the HNN without its floor under M^-1 (stored before it was declared) stay out of
    the verdict: swapped in for the declared HNN, the part they would decide is not judged."""
    runs = _tables(tasks=X.TASKS)
    assert R.claim_16(runs).verdict == "reproduced"
    hnn = runs["model"] == "hnn_force"
    old = runs.copy()
    old.loc[hnn, "model_options"] = "[]"
    assert not R.declared_options(old)[hnn].any() and R.declared_options(old)[~hnn].all()
    v = R.claim_16(old)
    assert v.verdict != "reproduced"
    assert all(p.status == "undecided" for p in v.parts if "HNN" in p.name)
    expected = (("inverse_mass_floor", R.HNN_FLOOR),)
    assert {c.model_options for c in expand(X.EXPERIMENT, "smoke") if c.model == "hnn_force"} == {
        expected
    }


def _statuses(v) -> dict[str, str]:
    return {p.name: p.status for p in v.parts}


# ----------------------------------------------------------------------------- profiles
def test_quick_runs_one_task_and_every_profile_reads_the_files_size(monkeypatch, tmp_path):
    monkeypatch.setenv(D.ENV, str(tmp_path))
    assert not expand(X.EXPERIMENT, "quick")  # no files: no runs
    for task in X.TASKS:  # the include rule asks only whether a task's file is there
        D.data_path(task).touch()
    quick = expand(X.EXPERIMENT, "quick")
    assert {c.system for c in quick} == {X.QUICK_TASK} and len(quick) == (4 + 2) * 5
    code = {(c.model, c.seed) for c in quick if c.lr == R.CODE_LR}
    assert code == {(m, s) for m in ("node", "node_so") for s in SEEDS}  # NODEs at the code's
    assert {c.lr for c in quick} == {R.LR, R.CODE_LR}
    assert {c.seed for c in quick} == set(SEEDS) and {c.steps for c in quick} == {X.QUICK_STEPS}
    core = expand(X.EXPERIMENT, "paper-core")
    assert {c.system for c in core} == set(X.TASKS) and {c.seed for c in core} == set(SEEDS)
    # Fig. 7's setting at paper-core: every model at the code's lr, the paper's HNN there
    # only, with one Euler step; the HNNs there a further reading
    at = {(c.model, c.lr, c.train_substeps, c.eval_substeps) for c in core}
    assert at == {
        *((m, R.LR, 8, 8) for m in R.MODELS),
        *((m, R.CODE_LR, 8, 8) for m in ("node", "node_so", "hnn_force")),
        (R.PAPER_HNN, R.CODE_LR, 1, 1),
    }
    further = {(c.model, c.optimizer) for c in core if is_supplementary(X.EXPERIMENT, c)}
    assert further == {
        ("hnn_force", "adamw"),
        (R.PAPER_HNN, "adamw"),
        *((m, R.PAPER_RULE) for m in R.PAPER_RULE_MODELS),  # Fig. 7's update rule, theirs only
    }
    assert not {c.optimizer for c in quick} - {"adamw"}
    assert all(c.lr == R.CODE_LR for c in core if is_supplementary(X.EXPERIMENT, c))
    for c in (*quick, *core, *expand(X.EXPERIMENT, "paper")):
        assert c.n_generated == X.TRANSITIONS == 200_000
    assert {c.system_params for c in expand(X.EXPERIMENT, "smoke")} == {X.STAND_IN}


def test_the_study_is_registered_with_its_rule_figure_and_section():
    from bench.kit import claim_studies
    from bench.studies import CLAIM_TITLES

    study = next(s for s in claim_studies() if s.claim == 16)
    assert (
        study is X.STUDY
        and study.rule is X.claim_16_readings
        and study.experiments == X.EXPERIMENTS
    )
    assert study.results_figure is X.figure and study.section is X.section
    assert study.title == CLAIM_TITLES[16]


# --------------------------------------------------------------------------- the rule
def test_the_paper_s_ordering_is_reproduced_on_every_task():
    runs = _tables(tasks=X.TASKS)
    v = X.claim_16(runs)
    assert v.verdict == "reproduced" and v.key == "16", v.detail
    assert len(v.parts) == 4 * 3 and all(p.status == "holds" for p in v.parts), v.detail
    assert v.effect == pytest.approx(math.log(5.0), abs=1e-9)  # pooled (a): the headline
    assert v.n_seeds == 5 and v.discriminating is True and v.n_failed == 0
    assert R.disagreements(runs) == []  # rollout_error orders every comparison alike
    sources = set(runs["data_source"])  # each task's data named in the detail
    assert len(sources) == len(X.TASKS) and all(src in v.detail for src in sources)


def test_the_opposite_ordering_is_not_reproduced():
    v = X.claim_16(_tables(CONTRADICT))
    assert v.verdict == "not reproduced", v.detail
    assert set(_statuses(v).values()) == {"contradicts"}, v.detail


def test_one_task_where_the_hnn_beats_node_is_partly_reproduced():
    hopper = "HopperFull-v0"
    v = X.claim_16(_tables(tasks=X.TASKS, change={(hopper, "hnn_force"): (0.02, 0.3, 0.05)}))
    s = _statuses(v)
    assert v.verdict == "partly reproduced", v.detail
    assert s[f"{hopper}: (b) log(test MSE HNN / NODE)"] == "contradicts"
    assert s[f"{X.QUICK_TASK}: (b) log(test MSE HNN / NODE)"] == "holds"


def test_a_gain_on_the_margin_is_undecided():
    margin = policy.margin("error", squared=True).value  # 1.5625: a ratio of MSEs
    at = (0.1 / margin, 0.05 / margin, 0.15)
    v = X.claim_16(_tables(spread=1.0, change={(X.QUICK_TASK, "node_so"): at}))
    assert _statuses(v)[f"{X.QUICK_TASK}: (a) log(test MSE NODE / NODE+SO)"] == "undecided"
    assert v.verdict == "inconclusive", v.detail


def test_a_model_that_did_not_learn_leaves_the_parts_it_wins_untested():
    # NODE only 2.5x below the constant-velocity predictor: under the gate (2x squared), so
    # the parts where NODE is the better model, (b) and (c) against NODE, are not tested
    v = X.claim_16(_tables(change={(X.QUICK_TASK, "node"): (4.0, 3.0, 0.8)}))
    s = _statuses(v)
    assert s[f"{X.QUICK_TASK}: (c) log(train MSE HNN / NODE+SO)"] == "holds", v.detail
    against_node = [p for p in v.parts if p.name.rstrip(")").endswith("/ NODE")]
    assert len(against_node) == 2 and all(p.status == "not tested" for p in against_node)
    for p in against_node:  # the reason: NODE's learning gate, closed
        assert [g.label for g in p.gates if g.open is False] == [f"NODE on {X.QUICK_TASK}"]
    assert s[f"{X.QUICK_TASK}: (a) log(test MSE NODE / NODE+SO)"] == "not tested"
    assert v.verdict == "inconclusive", v.detail


def test_an_hnn_that_did_not_learn_is_the_claims_finding_not_a_gap():
    # the HNN 2.5x below the trivial predictor (under the learning gate): (b) and (c) still
    # judged, since the models said to be better learned
    v = X.claim_16(_tables(change={(X.QUICK_TASK, "hnn_force"): (4.0, 3.0, 0.8)}))
    assert v.verdict == "reproduced", v.detail


def test_a_test_set_the_trivial_predictor_wins_is_not_discriminating():
    v = X.claim_16(_tables(change={(X.QUICK_TASK, "constant_velocity"): (1e-3, 1e-3, 0.01)}))
    assert v.verdict == "inconclusive" and v.discriminating is False, v.detail
    assert {p.status for p in v.parts} == {"not tested"}  # the task's parts, void


def test_too_few_seeds_is_inconclusive():
    runs = _tables()
    v = X.claim_16(runs[runs["seed"] < 3])
    assert v.verdict == "inconclusive" and v.n_seeds == 3, v.detail


def test_failed_runs_score_the_worst_value_and_are_counted():
    runs = _tables()
    hnn = runs["model"] == "hnn_force"
    runs.loc[hnn, "status"] = "diverged"
    runs.loc[hnn, "test_mse"] = math.nan
    v = X.claim_16(runs)
    assert v.n_failed == 5
    # scored at the task's worst value (>= 1): a diverged HNN loses to NODE, not skipped
    assert _statuses(v)[f"{X.QUICK_TASK}: (b) log(test MSE HNN / NODE)"] == "holds"


def test_a_rollout_error_that_orders_the_other_way_is_named():
    runs = _tables(change={(X.QUICK_TASK, "node_so"): (0.02, 0.01, 0.5)})
    v = X.claim_16(runs)
    assert v.verdict == "reproduced", v.detail  # the verdict reads the paper's metric
    off = R.disagreements(runs)
    assert [x.split(":")[0] for x in off] == [f"{X.QUICK_TASK} (a) NODE / NODE+SO"]
    assert all(x in v.detail for x in off)  # and the detail names it


def test_the_stand_in_alone_gives_no_signed_verdict():
    stand = _tables(data=X.STAND_IN)
    v = X.claim_16(stand)
    assert v.verdict == "inconclusive" and v.variant == X.NOT_JUDGED, v.detail
    assert v.key == "16 (not judged: stand-in data)"
    assert [p.status for p in v.parts] == ["undecided"]
    check = R.judge(stand)  # the pipeline check: the rule on the stand-in, shown in the detail
    assert check.verdict == "reproduced" and v.detail.endswith(f"({check.detail})")
    # no runs at all: the claim's own key (the runs are not made yet), not the stand-in's
    empty = X.claim_16(_tables().iloc[0:0])
    assert empty.key == "16" and empty.n_seeds == 0
    assert [(p.status, p.note) for p in empty.parts] == [("undecided", "no runs")]


def test_the_task_files_are_judged_and_the_stand_in_left_out():

    runs = pd.concat([_tables(), _tables(CONTRADICT, data=X.STAND_IN)], ignore_index=True)
    v = X.claim_16(runs)
    assert v.verdict == "reproduced" and v.key == "16", v.detail
    left_out = re.search(r"(\d+) stand-in rows left out", v.detail).group(1)
    assert int(left_out) == (R.data_kind(runs) == "stand-in").sum() == 20


# ------------------------------------------------------------------ section and figure
@pytest.mark.parametrize("data", [X.FILE, X.STAND_IN], ids=["file", "stand-in"])
def test_the_section_and_figure_show_fig_7_s_numbers(tmp_path, data):
    runs, curves = _tables(tasks=X.TASKS, data=data, spread=0.0, frames=True)
    runs.to_parquet(tmp_path / "runs.parquet", index=False)
    curves.to_parquet(tmp_path / "curves.parquet", index=False)
    text = section(X.section(tmp_path), X.TITLE)
    table = {(r["task"], r["model"]): r for r in table_rows(text, "| task | model")}
    cheetah = table["HalfCheetahFull-v0", "NODE+SO"]
    assert (cheetah["seeds"], cheetah["test MSE"], cheetah["train MSE"]) == (
        "5",
        "0.02 ± 0",
        "0.01 ± 0",
    )
    assert cheetah["rollout error (geometric mean)"] == "0.1"
    trivial = table["HopperFull-v0", "constant velocity"]
    assert (trivial["seeds"], trivial["test MSE"], trivial["train MSE"]) == ("5", "10 ± 0", "5 ± 0")
    assert _bullets(text, "What differs from the paper:") == list(DIFFERENCES)
    v = X.claim_16(runs)
    assert _verdict_line(text) == (v.verdict, v.variant)
    data_lines = dict(x.split(": ", 1) for x in _bullets(text, "Data:"))
    for task in X.TASKS:  # each task's source and the transitions read from it
        source, read = data_lines[task].split("; ")[:2]
        rows = runs[runs["system"] == task]
        assert source == rows["data_source"].iloc[0]
        assert read == f"{int(rows['data_points'].iloc[0])} transitions read"
    if data == X.FILE:
        assert v.variant == "" and set(R.data_kind(runs)) == {"file"}
    else:
        assert v.variant == X.NOT_JUDGED and set(R.data_kind(runs)) == {"stand-in"}
    paths = X.figure(tmp_path)
    assert {p.suffix for p in paths} == {".png", ".pdf"} and all(p.stat().st_size for p in paths)
    assert paths[0].name == f"{X.STEM}.png"


def _bullets(text, label):
    """The bullet list after the line ``label`` (e.g. "Data:")."""
    lines = text.splitlines()
    out = []
    for x in lines[lines.index(label) + 1 :]:
        if x.startswith("- "):
            out.append(x[2:])
        elif out:
            break
    return out


def _verdict_line(text):
    """The section's verdict and its variant
    (``Verdict (at lr 0.0002): **inconclusive** (not judged...).``)."""
    m = re.search(r"^Verdict \(at lr [\d.e-]+\): \*\*(.+?)\*\*(?: \((.+)\))?\.$", text, re.M)
    return m.group(1), m.group(2) or ""


def test_no_runs_give_a_section_without_a_table_and_no_figure(tmp_path):
    text = section(X.section(tmp_path), X.TITLE)
    assert text is not None and X.figure(tmp_path) == []
    with pytest.raises(LookupError):  # no table of models
        table_rows(text, "| task | model")


# --------------------------------------------------------------------------- end to end
@pytest.mark.slow
def test_the_smoke_profile_runs_and_reports_on_the_stand_in(tmp_path):
    from bench.core import load_runs, sweep

    sweep(expand(X.EXPERIMENT, "smoke"), tmp_path / "res", experiment=X.EXPERIMENT.name,
          profile="smoke", progress=False, cache_root=tmp_path / "cache")  # fmt: skip
    runs = load_runs(tmp_path / "res")
    assert (runs["status"] == "ok").all(), runs[["model", "error"]]
    v = X.claim_16(runs)
    assert v.variant == X.NOT_JUDGED and R.judge(runs).verdict in v.detail, v.detail
    assert _verdict_line(X.section(tmp_path / "res")) == (v.verdict, X.NOT_JUDGED)
    assert len(X.figure(tmp_path / "res")) == 2


def test_without_our_hnn_at_the_code_lr_its_parts_wait_and_a_is_judged_there():
    """NODE and NODE+SO at the reference code's learning rate (Fig. 7's) and our HNN not yet
    there (a further reading still running): the verdict is read at the code's lr, (a) judged
    with the App. C trivial predictor as gate, the HNN's parts (b) and (c) *not tested* as
    waiting (never as a model that did not learn), App. C's verdict named beside it."""
    runs = _tables()
    base = X.claim_16(runs)
    assert base.verdict == "reproduced"
    node = runs[runs["model"].isin(["node", "node_so"])].copy()
    node["lr"] = R.CODE_LR
    # at the code's lr the order flips: NODE+SO 4x worse than NODE
    node.loc[node["model"] == "node_so", "test_mse"] *= 40
    both = pd.concat([runs, node], ignore_index=True)
    v = X.claim_16(both)
    got = _statuses(v)
    assert {k: s for k, s in got.items() if "(a)" in k} == {
        k: "contradicts" for k in got if "(a)" in k
    }
    hnn = [p for p in v.parts if "HNN" in p.name]
    assert hnn and all(p.status == "not tested" and "HNN waits" in p.note for p in hnn)
    assert v.verdict == "not reproduced", v.detail
    assert f"judged at the reference code's lr {R.CODE_LR:g}" in v.detail
    assert f"at App. C's {R.LR:g}, not judged: reproduced" in v.detail
    assert not [g for p in hnn for g in p.gates if g.kind == "learning" and g.open is False]
    # the parts equal the code's-lr reading of (a) alone
    (a,) = R.code_lr_parts(both)
    assert a.status == "contradicts" and a.n == len(SEEDS)
    assert not R.code_lr_parts(runs)
    assert (R.verdict_lr(both), R.verdict_lr(runs)) == (R.CODE_LR, R.LR)


def _at_code_lr(runs, values, models=("node", "node_so", "hnn_force")):
    """Copies of ``runs``' rows of ``models`` trained at the code's lr, with ``values``' test
    and train MSE (the paper's HNN: ``hnn_force``'s copied, renamed)."""
    out = []
    for m in models:
        src = "hnn_force" if m == R.PAPER_HNN else m
        rows = runs[runs["model"] == src].copy()
        test, train, _ = values[src]
        rows = rows.assign(lr=R.CODE_LR, model=m, test_mse=test, train_mse=train)
        if m == R.PAPER_HNN:
            rows = rows.assign(model_options="[]", train_substeps=1, eval_substeps=1)
        rows["test_mse"] *= np.exp(0.1 * SPREAD[rows["seed"].to_numpy()])
        out.append(rows)
    return pd.concat([runs, *out], ignore_index=True)


def test_the_verdict_is_judged_at_fig_7_s_lr_once_every_model_ran_there():
    """Where the HNN ran at the code's lr (Fig. 7's), the verdict is read there and App. C's
    reading is named beside it; the paper's HNN, where it ran, is read in the HNN's place as a
    verdict of its own."""
    runs = _tables()
    assert X.claim_16(runs).verdict == "reproduced"
    both = _at_code_lr(runs, CONTRADICT)
    v = X.claim_16(both)
    assert v.verdict == "not reproduced", v.detail
    assert f"judged at the reference code's lr {R.CODE_LR:g}" in v.detail
    assert f"at App. C's {R.LR:g}, not judged: reproduced" in v.detail
    assert [w.key for w in X.claim_16_readings(both)] == ["16"]
    # the paper's HNN, 10x worse than NODE in test and training: its reading reproduces
    worse = {**CONTRADICT, "hnn_force": (1.0, 0.5, 0.5)}
    paper = _at_code_lr(both, worse, models=(R.PAPER_HNN,))
    got = {w.key: w for w in X.claim_16_readings(paper)}
    assert list(got) == ["16", "16 (the paper's HNN)"]
    assert got["16"].verdict == "not reproduced"
    hnn = {k: s for k, s in _statuses(got["16 (the paper's HNN)"]).items() if "HNN" in k}
    assert hnn and set(hnn.values()) == {"holds"}, hnn
    # without our HNN at the code's lr, (a) is judged there and the HNN's parts wait
    ours = (paper["model"] == "hnn_force") & (paper["lr"] == R.CODE_LR)
    waits = X.claim_16(paper[~ours])
    assert {p.status for p in waits.parts if "HNN" in p.name} == {"not tested"}
    assert {p.name: p.status for p in waits.parts if "(a)" in p.name} == {
        p.name: p.status for p in v.parts if "(a)" in p.name
    }


def test_the_figure_shows_the_verdicts_learning_rate_with_both_hnns():
    """Fig. 7's figure at the rate the verdict reads: at the code's once NODE and NODE+SO ran
    there, the paper's HNN beside them (ours not yet there), constant velocity from App. C's
    rows; App. C's rows otherwise."""
    from bench.studies.decon.mujoco._section import figure_rows

    runs = _tables()
    data, kind, lr = figure_rows(runs)
    assert (kind, lr) == ("file", R.LR) and set(data["lr"]) == {R.LR}
    paper = _at_code_lr(runs, CONTRADICT, models=("node", "node_so", R.PAPER_HNN))
    data, kind, lr = figure_rows(paper)
    assert (kind, lr) == ("file", R.CODE_LR)
    by_model = dict(zip(data["model"], data["lr"], strict=False))
    assert set(by_model) == {"node", "node_so", R.PAPER_HNN, "constant_velocity"}
    assert {by_model[m] for m in ("node", "node_so", R.PAPER_HNN)} == {R.CODE_LR}


def _under_paper_rule(runs, values):
    """``runs`` with the paper's three models at the code's lr under the reference's update
    rule, ``values``' test and train MSE (the paper's HNN takes ``hnn_force``'s)."""
    rule = _at_code_lr(runs, values, models=R.PAPER_RULE_MODELS).iloc[len(runs) :].copy()
    hnn = (rule["model"] == R.PAPER_HNN).to_numpy()
    spread = np.exp(SPREAD[rule["seed"].to_numpy()[hnn]])  # the HNN's seeds far apart
    for metric in ("test_mse", "train_mse"):
        rule.loc[hnn, metric] = rule.loc[hnn, metric].to_numpy() * spread
    return pd.concat([runs, rule.assign(optimizer=R.PAPER_RULE)], ignore_index=True)


MARGIN = policy.margin("error", squared=True).value  # 1.5625 for a ratio of MSEs; loss's too


@pytest.mark.parametrize(
    ("values", "hnn_status", "key_verdict"),
    [
        # the paper's HNN 10x worse than NODE, NODE+SO 5x better: Fig. 7's ordering
        ({**REPRODUCE, "hnn_force": (1.0, 0.5, 0.5)}, "holds", "reproduced"),
        ({**CONTRADICT}, "contradicts", "not reproduced"),
        # the HNN worse than NODE by the margin itself, its seeds far apart: (b) undecided
        ({**REPRODUCE, "hnn_force": (0.1 * MARGIN, 0.05 * MARGIN, 0.2)}, "undecided", "inconc"),
    ],
)
def test_the_paper_s_update_rule_is_a_reading_of_its_own(values, hnn_status, key_verdict):
    """The paper's models at the code's lr under its update rule (Adam with the decay as an
    L2 term, after clipping) are read as a verdict of their own, gated on App. C's
    constant-velocity rows; they never enter the other readings."""
    runs = _tables()
    both = _under_paper_rule(runs, values)
    assert X.claim_16(both) == X.claim_16(runs)  # App. C's rows still decide the verdict
    got = {w.key: w for w in X.claim_16_readings(both)}
    assert list(got) == ["16", "16 (the paper's models and update rule)"]
    rule = got["16 (the paper's models and update rule)"]
    (b,) = [s for k, s in _statuses(rule).items() if "(b)" in k]
    assert b == hnn_status, _statuses(rule)
    assert rule.verdict.startswith(key_verdict), (rule.verdict, rule.detail)
    # under AdamW at the code's lr too: each rule read on its own rows
    code = _at_code_lr(runs, CONTRADICT, models=("node", "node_so", "hnn_force", R.PAPER_HNN))
    adamw = _under_paper_rule(code, values)
    got = {w.key: w for w in X.claim_16_readings(adamw)}
    assert got["16 (the paper's models and update rule)"] == rule
    assert got["16"].verdict == "not reproduced"


def test_models_worse_than_holding_the_velocity_on_their_training_data_are_named():
    """A trained model whose training MSE is above the constant-velocity predictor's fits its
    own training data worse than holding the velocity (a finite loss, so not flagged
    diverged): the section names its seeds; models below the predictor are not named."""
    from bench.studies.decon.mujoco._section import worse_than_trivial_in_training

    runs = _tables()
    assert worse_than_trivial_in_training(runs) == []
    hnn = runs["model"] == "hnn_force"
    runs.loc[hnn & (runs["seed"] == 3), "train_mse"] = 1e10
    runs.loc[hnn & (runs["seed"] == 1), "train_mse"] = 6.0
    (line,) = worse_than_trivial_in_training(runs)
    assert line == f"HNN on {X.QUICK_TASK}, seed 1 (6), 3 (1e+10) (the predictor: 5)"
