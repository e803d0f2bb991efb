"""The claims at every number of links (bench.studies.paper.report._links) on synthetic stored
runs of the paper profile's Fig. 5 cells at k = 1..4, seeds 0-9 (no training)."""

import copy
import dataclasses
import re

import pandas as pd
import pytest
from _markdown import table_rows
from _synthetic import synthetic_tables

from bench import kit as R
from bench.core import expand
from bench.kit import evaluate_claims, seed_span
from bench.studies.decon.coordinates import PAPER_BUDGET_MODELS, claim_4, fig_links
from bench.studies.paper.report import _links as L


@pytest.fixture(scope="module")
def fig5():
    a = synthetic_tables("paper", experiments=("coordinates",))
    b = synthetic_tables("paper", experiments=("coordinates",), seeds=(5, 6, 7, 8, 9), rng=1)
    return (
        pd.concat([a[0], b[0]], ignore_index=True),
        pd.concat([a[1], b[1]], ignore_index=True),
    )


def test_the_selections_split_the_paper_cells_by_k():
    core = {c.config_hash for c in expand("coordinates", "paper-core")}
    links = {c.config_hash for c in expand("coordinates", "paper-k")}
    paper = {c.config_hash: c for c in expand("coordinates", "paper")}
    # together they are the paper profile's cells, the paper's form of NODE+SO included
    assert core | links == set(paper) and not core & links
    assert {c.model for c in paper.values() if c.k == 2} == set(PAPER_BUDGET_MODELS)
    assert {c.k for c in expand("coordinates", "paper-k")} == {1, 3, 4}
    assert {c.k for c in expand("second_order", "paper-k")} == {1, 3, 4}
    assert {c.k for c in expand("symplectic", "paper-k")} == {3, 4}


def test_each_k_and_every_k_pooled_are_judged(fig5):
    runs, curves = fig5
    got = {r.label: r for r in L.readings(runs, curves)}
    assert list(got) == ["k = 1", "k = 2", "k = 3", "k = 4", "k = 1-4"]
    for r in got.values():
        assert r.counts[4][0] == r.counts[4][1] > 0  # every Fig. 5 cell stored
        assert r.judgement.replication_seeds == (5, 6, 7, 8, 9)
    # claims 1 and 3 read the second_order cells too, which this table lacks: pending
    assert got["k = 3"].counts[3][0] < got["k = 3"].counts[3][1]
    # the pooled reading is claim 4's (and claim 1's) only
    assert set(got["k = 1-4"].counts) == {1, 4}
    one = {v.key: v for v in got["k = 3"].judgement.final}
    assert one["4 (geometric-mean error, spring from paper)"].verdict == R.REPRODUCED
    # the per-k reading sees its k only: the edge equals the rule's on that k's rows alone
    k3 = runs[runs["k"] == 3]
    every = evaluate_claims(k3, curves, "paper", claims=(4,), seeds=range(10))
    alone = {v.key: v for v in every}
    key = "4 (MSE, spring from paper)"
    assert one[key].effect == pytest.approx(alone[key].effect)


def test_the_section_names_pending_readings_and_seeds(fig5):
    runs, curves = fig5

    class Ctx:
        pass

    ctx = Ctx()
    ctx.runs, ctx.curves = runs, curves
    text = "\n".join(L.links_section(ctx))
    rows = table_rows(text, "| claim |")
    got = L.readings(runs, curves)
    assert list(rows[0]) == ["claim", "k = 1", "k = 2", "k = 3", "k = 4", "k = 1-4"]
    said = {(row["claim"], r.label): row[r.label] for row in rows for r in got}
    pending, seeds = [], set()
    for r in got:
        for key in {row["claim"] for row in rows}:
            claim = int(key.split()[0])
            n, m = r.counts.get(claim, (0, 0))
            cell = said[key, r.label]
            if m and n < m:  # a reading still waiting for runs says how many are stored
                assert re.fullmatch(r"pending \((\d+) of (\d+) runs\)", cell).groups() == (
                    str(n),
                    str(m),
                ), cell
                pending.append(cell)
            elif cell != "-":  # a judged one: its verdict and the seeds it rests on
                v = next(v for v in r.judgement.final if v.key == key)
                verdict, span = re.fullmatch(r"\*\*(.+?)\*\*.*, seeds (\S+)", cell).groups()
                assert verdict == v.label() and span == seed_span(r.judgement.reading_seeds(key))
                seeds.add(span)
    assert pending and "0-9" in seeds
    # k = 2 alone is paper-core's own reading: no section
    ctx.runs = runs[runs["k"] == 2]
    assert L.links_section(ctx) == []


def test_the_section_says_which_parts_change_with_k(fig5):
    runs, curves = fig5
    got = {r.label: r for r in L.readings(runs, curves)}
    key = "4 (MSE, spring from paper)"
    keys = [(key, 4)]
    k3 = got["k = 3"]
    # two readings that agree: nothing to say
    twin = copy.deepcopy(k3)
    twin.label = "k = 4"
    assert L.disagreements([k3, twin], keys) == []
    # the twin's spring part contradicted (the gap does not vanish there): the line names it
    reading = twin.judgement.reading(key)
    spring = next(p for p in reading.parts if p.name.startswith("spring"))
    was = spring.status
    assert was != "contradicts"
    spring.status = "contradicts"
    twin.judgement.final = [
        dataclasses.replace(v, verdict=R.PARTLY) if v.key == key else v
        for v in twin.judgement.final
    ]
    (line,) = L.disagreements([k3, twin], keys)
    assert line.startswith(f"- claim {key}: k = 3 ")
    assert f"{spring.name}: {was} at k = 3" in line and "contradicts at k = 4" in line
    # a part whose status is the same at both k is not listed
    assert "chain" not in line.split(". ", 1)[1]
    # no part changes, but the twin's replication demoted its verdict: the line says so
    demoted = copy.deepcopy(k3)
    demoted.label = "k = 4"
    own = demoted.judgement.reading(key).label()
    demoted.judgement.final = [
        dataclasses.replace(v, verdict=R.INCONCLUSIVE) if v.key == key else v
        for v in demoted.judgement.final
    ]
    (line,) = L.disagreements([k3, demoted], keys)
    assert line.endswith(
        f"no part changes status; k = 4 reads {own} on its seeds, {R.INCONCLUSIVE} in the end"
    )
    # a reading still pending is left out
    twin.counts = {4: (1, 2)}
    assert L.disagreements([k3, twin], keys) == []
    # the synthetic cells read otherwise at k = 1 than at k = 3: the section carries the line
    (differ,) = L.disagreements([got["k = 1"], k3], keys)
    assert "spring edge" in differ
    text = "\n".join(L.links_section(type("Ctx", (), {"runs": runs, "curves": curves})))
    assert "Where the numbers of links disagree" in text
    # claim 2 names each weight's cell with its k: the part is matched across k without it
    assert L._part_name("node_so_symreg chain_pendulum k=3 w=0.001: gain") == (
        "node_so_symreg chain_pendulum w=0.001: gain"
    )


def test_the_figure_draws_error_against_k(fig5, tmp_path):
    runs, _ = fig5
    runs.to_parquet(tmp_path / "runs.parquet", index=False)
    paths = fig_links(tmp_path)
    assert {p.suffix for p in paths} == {".png", ".pdf"} and all(p.exists() for p in paths)
    # one k only: nothing to draw
    other = tmp_path / "one"
    other.mkdir()
    runs[runs["k"] == 2].to_parquet(other / "runs.parquet", index=False)
    assert fig_links(other) == []


def test_the_figure_compares_the_models_at_each_k_on_the_seeds_they_share(fig5):
    """Mid-campaign, seed 5 at k = 1 lacks HNN+SO on the spring: it waits (every k = 1 point
    rests on seeds 0-4 and 6-9); at k = 2 every seed is complete and stays."""
    from bench.studies.decon.coordinates._links import common_seeds, link_rows

    runs, _ = fig5
    drop = (runs["k"] == 1) & (runs["seed"] == 5) & (runs["model"] == "hnn_so")
    drop &= runs["system"] == "spring_pendulum"
    rows = link_rows(runs[~drop])
    got = common_seeds(rows)
    assert set(rows[rows["k"] == 1]["seed"]) == set(range(10))
    assert set(got[got["k"] == 1]["seed"]) == set(range(10)) - {5}
    assert set(got[got["k"] == 2]["seed"]) == set(rows[rows["k"] == 2]["seed"])
    assert len(common_seeds(link_rows(runs))) == len(link_rows(runs))  # complete: all kept


def _chain_at(runs, k, node_so, hnn_so):
    """``runs`` with the chain's NODE+SO and HNN+SO at ``k`` set to these multiples of the
    constant-velocity predictor's error (rollout error and MSE, per seed)."""
    out = runs.copy()
    chain = (out["system"] == "chain_pendulum") & (out["k"] == k)
    trivial = out[chain & (out["model"] == "constant_velocity")]
    cv = trivial.groupby("seed")[["rollout_error", "mse"]].first()
    for model, factor in (("node_so", node_so), ("hnn_so", hnn_so)):
        rows = chain & (out["model"] == model)
        for col, power in (("rollout_error", 1), ("mse", 2)):
            out.loc[rows, col] = out.loc[rows, "seed"].map(cv[col]).to_numpy() * factor**power
    return out


def _chain_part(runs, curves, key="4 (geometric-mean error, spring from paper)"):
    """Claim 4's chain part over every k of ``runs``, on seeds 0-4."""
    (v,) = [v for v in claim_4(runs[runs["seed"] < 5], curves) if v.key == key]
    return next(p for p in v.parts if p.name.startswith("chain edge"))


def test_a_k_where_the_models_did_not_learn_is_left_out_of_the_pool(fig5):
    """Pooled over k, claim 4's chain edge reads only the k where NODE+SO and HNN+SO both
    learned: at k = 4 they barely beat constant velocity (under the 2x gate) and NODE+SO is
    ahead, yet the pooled edge is the one of k = 1-3 alone, and the part says so."""
    runs, curves = fig5
    k4 = _chain_at(runs, 4, node_so=0.8, hnn_so=0.9)
    part = _chain_part(k4, curves)
    assert part.n == 5
    is_k4 = (runs["system"] == "chain_pendulum") & (runs["k"] == 4)
    without = runs[~(is_k4 & runs["model"].isin(["node_so", "hnn_so"]))]
    alone = _chain_part(without, curves)
    assert part.status == alone.status == "holds"
    assert part.point == pytest.approx(alone.point) and part.lo == pytest.approx(alone.lo)
    assert "pooled over k = 1-3" in part.note and "at k = 4 did not learn" in part.note
    assert "left out" not in alone.note
    # the report's section names it
    text = "\n".join(L.links_section(type("Ctx", (), {"runs": k4, "curves": curves})))
    (line,) = [
        x
        for x in text.splitlines()
        if "claim 4 (geometric-mean error, spring from paper)" in x and "pooled over" in x
    ]
    assert line.startswith("- chain edge log(NODE+SO/HNN+SO), claim 4 (")
    assert "pooled over k = 1-3" in line and "at k = 4 did not learn" in line
    # where the models learn at no k, the part is not tested, whatever its edge
    none = k4
    for k in (1, 2, 3):
        none = _chain_at(none, k, node_so=0.8, hnn_so=0.9)
    gone = _chain_part(none, curves)
    assert gone.status == "not tested" and "did not learn" in gone.note


def test_learning_gates_over_every_k():
    """kit.learned_at_each_k: one k gives each model's own gate; several k keep the k where
    every gated model learned, and one gate, closed where none is kept."""
    rows = []
    for k, factor in ((1, 0.01), (2, 0.9)):  # the model learns at k = 1 only
        for s in range(5):
            rows += [
                {"k": k, "seed": s, "model": "constant_velocity", "rollout_error": 1.0},
                {"k": k, "seed": s, "model": "node_so", "rollout_error": factor},
            ]
    rows = pd.DataFrame(rows).assign(status="ok")
    cells = lambda r: [(r, {"model": "node_so"}, "node_so")]  # noqa: E731
    one = R.learned_at_each_k(cells(rows[rows["k"] == 1]))
    assert one.kept == (1.0,) and [g.open for g in one.gates] == [True] and not one.note
    bad = R.learned_at_each_k(cells(rows[rows["k"] == 2]))
    assert bad.kept == () and [g.open for g in bad.gates] == [False]
    both = R.learned_at_each_k(cells(rows))
    assert both.kept == (1.0,) and [g.open for g in both.gates] == [True]
    assert "pooled over k = 1" in both.note and "node_so at k = 2 did not learn" in both.note
    worse = rows.assign(rollout_error=lambda d: d["rollout_error"].where(d["k"] == 2, 0.9))
    (gate,) = R.learned_at_each_k(cells(worse)).gates
    assert gate.open is False and "at k = 1 did not learn" in gate.text


def test_claim_1_fits_only_the_k_where_every_fig2_model_learned():
    """Claim 1 (a) and (d) over every k: a k where a gated model (HNN+SO, gated by both) did
    not learn on one system is left out of the fit, named in the note, and the fit equals
    the one without that k."""
    from bench.studies.decon.energy import claim_1

    runs, curves = synthetic_tables("paper", experiments=("energy",))
    assert set(runs["k"]) == {1, 2, 3, 4}
    at = (runs["system"] == "chain_pendulum") & (runs["k"] == 4)
    cv = runs[at & (runs["model"] == "constant_velocity")].set_index("seed")["rollout_error"]
    bad = runs.copy()
    hnn = at & (bad["model"] == "hnn_so")
    bad.loc[hnn, "rollout_error"] = bad.loc[hnn, "seed"].map(cv).to_numpy()
    fig2 = ["node", "node_so", "hnn_so"]
    without = runs[~((runs["k"] == 4) & runs["model"].isin(fig2))]
    got, want = claim_1(bad, curves), claim_1(without, curves)
    for name in ("(a)", "(d)"):
        a = next(p for p in got.parts if p.name.startswith(name))
        b = next(p for p in want.parts if p.name.startswith(name))
        assert a.status == b.status != "not tested", (a.status, a.note)
        assert a.point == pytest.approx(b.point), name
        assert "pooled over k = 1-3" in a.note and "left out" not in b.note
        assert "HNN+SO on chain_pendulum at k = 4 did not learn" in a.note
