"""The two-protocol table every claim with a seed's protocol renders: each reading judged on each
seed set, a campaign's reading pending until its declared runs are stored."""

import re

import pandas as pd
import pytest
from _markdown import table_rows

from bench.core import expand, get
from bench.kit import Verdict
from bench.kit._protocols import ROWS, Protocol, by_seed_set, protocol_table

EXPERIMENT = "relativistic_seed"
CELLS = dict.fromkeys(ROWS, "-")


def _rows(profile, seeds, keep=None):
    cfgs = expand(get(EXPERIMENT), profile, seeds=list(seeds))
    cfgs = cfgs if keep is None else cfgs[:keep]
    return pd.DataFrame(
        {"config_hash": [c.config_hash for c in cfgs], "seed": [c.seed for c in cfgs]}
    )


def _reader(seen):
    def read(r):
        seen.append(tuple(sorted(set(r["seed"]))))
        n = r["seed"].nunique()
        return Verdict(7, "t", "reproduced", 1.0, 0.5, 1.5, n, "")

    return read


def _verdict_cell(p):
    line = next(x for x in protocol_table(p, Protocol(CELLS), "-") if x.startswith("| verdict |"))
    return line.split("|")[2].strip()


def test_a_campaign_reading_is_pending_until_its_runs_are_stored():
    declared = len(expand(get(EXPERIMENT), "paper-core", seeds=[0, 1, 2, 3, 4]))
    rows = _rows("paper-core", range(5), keep=3)
    p = Protocol(CELLS, by_seed_set(rows, "paper-core", _reader([]), EXPERIMENT))
    assert _verdict_cell(p) == (
        f"pending (3 of {declared} runs, seeds 0-4); pending (0 of {declared} runs, seeds 5-9)"
    )
    assert p.verdict is None  # no learning gate read off a partial reading
    full = _rows("paper-core", range(5))
    p = Protocol(CELLS, by_seed_set(full, "paper-core", _reader([]), EXPERIMENT))
    assert _verdict_cell(p) == f"reproduced (seeds 0-4); pending (0 of {declared} runs, seeds 5-9)"
    assert p.verdict.verdict == "reproduced"


def test_each_seed_set_is_judged_on_its_own_seeds():
    seen = []
    rows = _rows("quick", range(10))
    p = Protocol(CELLS, by_seed_set(rows, "quick", _reader(seen), EXPERIMENT))
    assert seen == [(0, 1, 2, 3, 4), (5, 6, 7, 8, 9)]
    assert _verdict_cell(p) == "reproduced (seeds 0-4); reproduced (seeds 5-9)"
    # outside a campaign's selection nothing is pending and no replication set is invented
    p = Protocol(CELLS, by_seed_set(_rows("quick", range(5), keep=2), "quick", _reader([])))
    said = re.fullmatch(r"(.+) \(seeds (\S+)\)", _verdict_cell(p))  # one seed set
    assert said.group(1) == "reproduced" and said.group(2) != "5-9"
    assert _verdict_cell(Protocol(CELLS)) == "not run"


def test_the_table_takes_each_readings_rows_in_order():
    ours = Protocol({**CELLS, "data": "a", "loss": "L2"})
    seeds = Protocol({**CELLS, "data": "b", "network": "4 x 500"})
    lines = protocol_table(ours, seeds, "the steps")
    assert lines[1] == "| protocol | ours | the seed's |"
    rows = table_rows("\n".join(lines), "| protocol | ours")
    shown = [(r["protocol"], r["ours"], r["the seed's"]) for r in rows]
    assert shown[0] == ("data", "a", "b") and ("loss", "L2", "-") in shown
    assert shown[len(ROWS)] == ("network", "-", "4 x 500")  # after ours' rows
    assert lines[-1] == "| still differs from the seed's code | - | the steps |"
    with pytest.raises(ValueError, match="missing \\['metric'\\]"):
        protocol_table(Protocol({r: "-" for r in ROWS if r != "metric"}), Protocol({}), "-")
