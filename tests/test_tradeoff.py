"""The trade-off experiment: Pareto front and 10% rule on synthetic tables, the declaration."""

from __future__ import annotations

import re

import numpy as np
import pandas as pd
import pytest
from _markdown import section, table_rows

from bench.core import _experiments as E
from bench.studies import tradeoff as T


def _brute_front(df, cost, error):
    """Non-dominated rows by the O(n^2) definition (an independent route)."""
    keep = []
    rows = [
        (i, c, e)
        for i, c, e in zip(df.index, df[cost], df[error], strict=True)
        if np.isfinite(c) and np.isfinite(e)
    ]
    for i, c, e in rows:
        dominated = any(
            (c2 <= c and e2 <= e and (c2 < c or e2 < e)) for j, c2, e2 in rows if j != i
        )
        # exact duplicates: keep the first only
        dup_before = any(c2 == c and e2 == e for j, c2, e2 in rows if j < i)
        if not dominated and not dup_before:
            keep.append(i)
    return sorted(keep)


def test_pareto_front_known_table():
    df = pd.DataFrame(
        {
            "name": list("ABCDEFG"),
            "cost": [1.0, 2.0, 3.0, 4.0, 2.0, np.nan, 5.0],
            "rollout_error": [10.0, 5.0, 6.0, 1.0, 5.0, 0.1, 1.0],
        }
    )
    front = T.pareto_front(df, "cost")
    # C is dominated by B, E duplicates B, F has no cost, G costs more than D for the same error
    assert list(front["name"]) == ["A", "B", "D"]
    assert list(front.columns) == list(df.columns)


def test_pareto_front_matches_brute_force_on_random_tables():
    rng = np.random.default_rng(0)
    for _ in range(20):
        n = 30
        # rounded values create ties in cost and in error
        df = pd.DataFrame(
            {
                "c": np.round(rng.lognormal(size=n), 1),
                "e": np.round(rng.lognormal(size=n), 1),
            }
        )
        df.loc[rng.integers(0, n, 3), "e"] = np.nan
        got = sorted(T.pareto_front(df, "c", "e").index)
        assert got == _brute_front(df, "c", "e")


def test_pareto_front_bad_column():
    with pytest.raises(ValueError, match="unknown column"):
        T.pareto_front(pd.DataFrame({"a": [1]}), "cost")


def test_cheapest_within_ten_percent():
    df = pd.DataFrame(
        {
            "system": ["x"] * 4 + ["y"] * 2,
            "k": [2] * 6,
            "rollout_error": [1.0, 1.05, 1.2, 2.0, 0.5, 0.56],
            "cost": [10.0, 3.0, 1.0, 0.5, 4.0, 1.0],
        }
    )
    pick = T.cheapest_within(df, "cost").set_index("system")
    # x: within 10% of 1.0 are 1.0 and 1.05; the cheaper is 1.05 at cost 3
    assert pick.loc["x", "cost"] == 3.0 and pick.loc["x", "rollout_error"] == 1.05
    assert pick.loc["x", "error_ratio"] == pytest.approx(1.05)
    # y: 0.56 is 12% worse than 0.5, so the best itself is the cheapest admissible
    assert pick.loc["y", "cost"] == 4.0 and pick.loc["y", "best_error"] == 0.5
    # tolerance 0: always the best; a huge tolerance: always the cheapest
    assert T.cheapest_within(df, "cost", tolerance=0.0).set_index("system").loc["x", "cost"] == 10
    assert T.cheapest_within(df, "cost", tolerance=10.0).set_index("system").loc["x", "cost"] == 0.5
    with pytest.raises(ValueError, match="tolerance"):
        T.cheapest_within(df, "cost", tolerance=-0.1)


def test_aggregate_seeds_geometric_mean_and_divergence():
    base = E.RunConfig(system="chain_pendulum", k=2, model="node_so").to_dict()
    rows = []
    for seed, err, status in ((0, 1e-2, "ok"), (1, 1e-4, "ok"), (2, np.nan, "diverged")):
        rows.append({**base, "seed": seed, "rollout_error": err, "status": status, "nfe": 4.0})
    agg = T.aggregate_seeds(pd.DataFrame(rows))
    assert len(agg) == 1
    assert agg["rollout_error"].iloc[0] == pytest.approx(1e-3)
    assert agg["n_seeds"].iloc[0] == 2 and agg["diverged"].iloc[0] == 1


@pytest.fixture(scope="module")
def quick_runs():
    return E.expand(T.TRADEOFF, "quick")


def test_declaration_registered_and_drops_invalid(quick_runs):
    assert "tradeoff" in E.available()
    assert len(quick_runs) == len({c.config_hash for c in quick_runs})
    models = {c.model for c in quick_runs}
    assert models == set(T.PROFILE_MODELS["quick"])
    for c in quick_runs:
        if c.model == "node":
            assert "leapfrog" not in (c.eval_integrator, c.train_integrator)
        if c.model == "vin":
            assert (c.eval_integrator, c.eval_substeps) == T.BASE_EVAL
        if c.eval_integrator == "adaptive":
            assert c.eval_substeps == 1
        else:
            assert c.eval_rtol == T.DEFAULT_RTOL
        assert len(T._train_changes(c, "quick")) <= 1
    methods = {c.eval_integrator for c in quick_runs}
    assert {"euler", "rk4", "leapfrog", "implicit_midpoint", "adaptive"} <= methods
    rtols = {c.eval_rtol for c in quick_runs if c.eval_integrator == "adaptive"}
    assert min(rtols) <= 1e-9 and max(rtols) >= 1e-3
    assert {c.width for c in quick_runs} == {64, 128, 256}
    assert {c.system for c in quick_runs} == set(T.PROFILE_SYSTEMS["quick"]) == {"chain_pendulum"}


def test_eval_variants_share_training(quick_runs):
    # Every base-training evaluation of one (system, model, seed) has the same train_hash.
    by_cell = {}
    for c in quick_runs:
        if not T._train_changes(c, "quick"):
            by_cell.setdefault((c.system, c.model, c.seed), set()).add(c.train_hash)
    assert all(len(h) == 1 for h in by_cell.values())
    assert len({c.train_hash for c in quick_runs}) < len(quick_runs) / 2


def test_base_cells_shared_with_paper(quick_runs):
    energy = {c.config_hash for c in E.expand("energy", "quick")}
    shared = {c.model for c in quick_runs if c.config_hash in energy}
    assert shared == {"node", "node_so", "hnn_so"}


def test_include_rejects_two_training_changes():
    d, _ = E.profile_defaults("quick")
    two = E.RunConfig(
        system="chain_pendulum", k=2, model="node_so", **{**d, "width": 64, "steps": 300}
    )
    one = E.RunConfig(system="chain_pendulum", k=2, model="node_so", **{**d, "width": 64})
    assert not T.include(two) and T.include(one)


def _synthetic_store(tmp_path):
    cfgs = E.expand(T.TRADEOFF, "smoke")
    rng = np.random.default_rng(1)
    rows = []
    for c, err in zip(cfgs, rng.lognormal(-3, 1, len(cfgs)), strict=True):
        rows.append(
            {
                **c.to_dict(),
                "system_params": "[]",
                "model_options": "[]",
                "experiment": "tradeoff",
                "profile": "smoke",
                "status": "ok",
                "rollout_error": err,
                "nfe": 10.0 * c.eval_substeps,
                "rollout_seconds_per_traj": 1e-3 * c.eval_substeps,
                "train_seconds": 1.0,
                "config_hash": c.config_hash,
                "train_hash": c.train_hash,
            }
        )
    pd.DataFrame(rows).to_parquet(tmp_path / "runs.parquet")
    return rows


def test_section_and_figure_from_a_store(tmp_path):
    rows = _synthetic_store(tmp_path)
    runs = pd.DataFrame(rows)
    front = T.tradeoff_table(runs)
    assert len(front) and (front.on_front == "yes").any()
    pick = T.cheapest_within(T.aggregate_seeds(runs), "rollout_seconds_per_traj")
    assert len(pick) and (pick["error_ratio"] <= 1.1 + 1e-12).all()
    text = T.tradeoff_section(tmp_path)
    shown = table_rows(section(text, "Pareto front per model"), "|")
    assert [r["config"] for r in shown] == list(front["config"])  # a row per configuration
    assert section(text, "Cheapest configuration within 10% of the best error, by rollout seconds")
    paths = T.tradeoff_figure(tmp_path)
    assert paths and all(p.exists() and p.stat().st_size > 0 for p in paths)


def test_the_section_names_the_machines_and_warns_when_they_differ(tmp_path):
    """Costs are times: the section names the machine that measured them, and says the fronts
    are not comparable where two machines did; a store without the fields says so."""
    rows = _synthetic_store(tmp_path)
    assert _machines(T.tradeoff_section(tmp_path)) == ([], False)  # not recorded
    runs = pd.DataFrame(rows).assign(device="cpu A", cpu_family_model="6/85")
    runs.to_parquet(tmp_path / "runs.parquet")
    one = [("cpu A 6/85", len(runs))]
    assert _machines(T.tradeoff_section(tmp_path)) == (one, False)
    runs.loc[runs.index[:3], "device"] = "cpu B"
    runs.to_parquet(tmp_path / "runs.parquet")
    two = [("cpu A 6/85", len(runs) - 3), ("cpu B 6/85", 3)]
    assert _machines(T.tradeoff_section(tmp_path)) == (two, True)  # and the warning


def _machines(text):
    """The section's machines line read back: each machine with its number of runs, and
    whether a warning follows them."""
    (line,) = [x for x in text.splitlines() if x.startswith("Costs measured on")]
    said, _, warning = line.partition(". ")
    found = re.findall(r"([^:;]+?) \((\d+) runs\)", said)
    return [(m.strip(), int(n)) for m, n in found], bool(warning)


def test_the_figure_leaves_a_cost_the_rows_lack_blank(tmp_path):
    rows = _synthetic_store(tmp_path)
    pd.DataFrame(rows).drop(columns="rollout_seconds_per_traj").to_parquet(
        tmp_path / "runs.parquet"
    )
    paths = T.tradeoff_figure(tmp_path)
    assert paths and all(p.exists() and p.stat().st_size > 0 for p in paths)


def test_table_lists_every_evaluated_method(tmp_path):
    # implicit_midpoint is dominated (slower and worse than rk4x2): it is still listed,
    # marked off the front, and the legend says what each method is
    rows = _synthetic_store(tmp_path)
    runs = pd.DataFrame(rows)
    cont = runs[runs.model == "node_so"]
    runs.loc[cont.index, "rollout_error"] = 0.01
    mid = cont[cont.eval_integrator == "implicit_midpoint"].index
    runs.loc[mid, ["rollout_error", "rollout_seconds_per_traj"]] = [0.5, 1.0]
    table = T.tradeoff_table(runs)
    got = table[table.model == "node_so"]
    assert set(got.config.str.split("x").str[0]) >= {"implicit_midpoint", "rk4"}
    row = got[got.config.str.startswith("implicit_midpoint")].iloc[0]
    assert row.on_front == "no"
    assert (got.on_front == "yes").any()
    from models import DESCRIPTIONS

    legend = dict(re.findall(r"`([^`]+)` = ([^;]+?)(?:;|\.$)", T.methods_legend(runs)))
    assert legend["implicit_midpoint"] == DESCRIPTIONS["implicit_midpoint"]


def test_label_forms():
    df = pd.DataFrame(
        [
            dict(
                eval_integrator="adaptive",
                eval_rtol=1e-9,
                eval_substeps=1,
                width=128,
                steps=5,
                train_integrator="rk4_38",
            ),
            dict(
                eval_integrator="rk4",
                eval_rtol=1e-6,
                eval_substeps=4,
                width=64,
                steps=5,
                train_integrator="euler",
            ),
        ]
    )
    got = list(T.label(df))
    assert got[0].startswith("adaptive@1e-09") and got[1].startswith("rk4x4 train euler")


def test_estimate_counts(quick_runs):
    est = T.estimate("quick")
    assert est["runs"] == len(quick_runs)
    assert 0 < est["trainings"] < est["new_runs"] <= est["runs"]
    assert est["seconds"] > 0


def test_smoke_is_tiny_and_paper_is_full():
    smoke = E.expand(T.TRADEOFF, "smoke")
    assert 0 < len(smoke) <= 10
    paper = E.expand(T.TRADEOFF, "paper")
    rtols = {c.eval_rtol for c in paper if c.eval_integrator == "adaptive"}
    assert rtols == {10.0**-e for e in range(3, 10)}
    subs = {c.eval_substeps for c in paper if c.eval_integrator == "rk4"}
    assert subs == {1, 2, 4, 8}
    assert all(T.include(c) for c in paper)
