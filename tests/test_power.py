"""The engine's power (bench.kit._power): a small simulation on synthetic parts."""

import math

import numpy as np
import pytest
from _markdown import table_rows

from bench.kit import _power as P
from bench.kit import at_most, greater, margin, verdict

ERR = margin("error")  # 1.25x: log margin 0.223
rng = np.random.default_rng(0)


def _values(mean, sd=0.2, n=5):
    x = rng.normal(0, 1, n)
    return mean + sd * (x - x.mean()) / x.std(ddof=1)  # exactly mean and sd


def test_the_spread_is_recovered_from_the_interval():
    part = greater("p", _values(1.0, 0.3), ERR)
    assert P.spread(part) == pytest.approx(0.3, rel=1e-9)


def test_a_clear_effect_signs_at_five_seeds_and_a_reversed_one_contradicts():
    holds, contra = P.sign_rates(greater("p", _values(1.5), ERR), 5, sims=400)
    assert holds > 0.95 and contra == 0
    holds, contra = P.sign_rates(greater("p", _values(-1.0), ERR), 5, sims=400)
    assert contra > 0.95 and holds == 0


def test_an_undecided_part_names_the_seeds_that_would_decide_it():
    # an edge of 1.6x with a wide spread: undecided at five seeds, signed with more
    part = greater("p", _values(math.log(1.6), 0.5), ERR)
    assert part.status == "undecided"
    need = P.seeds_to_decide(part, sims=300)
    assert need is not None and 5 < need < P.MAX_SEEDS
    assert max(P.sign_rates(part, need, sims=1000, seed=1)) >= 0.75
    assert max(P.sign_rates(part, max(need // 2, 2), sims=1000, seed=1)) < 0.8


def test_an_effect_on_the_margin_is_never_decided():
    part = at_most("p", _values(math.log(1.25), 0.3), ERR)
    assert part.status == "undecided"
    assert P.seeds_to_decide(part, sims=200) is None


def test_the_table_and_the_reports_lines():
    parts = [
        greater("a clear", _values(1.5), ERR),
        greater("b undecided", _values(math.log(1.6), 0.5), ERR),
    ]
    v = verdict(99, "synthetic", parts, parts[0], 5, "edge")
    table = P.power_table([v], sims=200)
    assert list(table["part"]) == ["a clear", "b undecided"]
    assert table.loc[0, "holds_5"] > 0.9 and math.isnan(table.loc[0, "seeds_to_decide"])
    assert table.loc[1, "seeds_to_decide"] > 5
    shown = table_rows("\n".join(P.power_lines(table)), "| claim | part")
    assert [(r["claim"], r["part"]) for r in shown] == [("99", "b undecided")]  # undecided only
    assert shown[0]["seeds to decide"] == str(int(table.loc[1, "seeds_to_decide"]))


def test_the_command_writes_the_table(tmp_path, monkeypatch):
    """`python -m bench power` on a folder of synthetic runs writes power.csv."""
    import pandas as pd
    from _synthetic import synthetic_tables

    from bench._cli import main

    runs, _ = synthetic_tables("quick", experiments=("second_order",))
    runs.to_parquet(tmp_path / "runs.parquet", index=False)
    assert main(["--results", str(tmp_path), "power", "--simulations", "50"]) == 0
    table = pd.read_csv(tmp_path / "power.csv")
    assert {"claim", "part", "holds_5", "seeds_to_decide"} <= set(table.columns) and len(table)
