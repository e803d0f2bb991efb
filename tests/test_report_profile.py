"""Which profile ``report`` and ``figures`` show, and failed runs in the figures: ``--profile``
picks a profile, the default names every profile present, a bad name is one line; a diverged
run is counted where the verdicts score it, and Fig. 2's line is claim 1 (c)'s."""

import re

import numpy as np
import pandas as pd
import pytest
from _synthetic import synthetic_tables

from bench._cli import main
from bench._report import make_figures, write_report
from bench.core import chosen_profile, experiment_rows, load_tables, pick_profile
from bench.kit._plot import model_bar_values
from bench.studies.decon.energy import claim_1
from bench.studies.decon.energy._figure import fig2_line, fig_energy


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """smoke rows (energy and second_order, seeds 0-4, one spring HNN diverged) beside fewer
    quick rows (energy, seed 0)."""
    d = tmp_path_factory.mktemp("two_profiles")
    a, ca = synthetic_tables("smoke", experiments=["energy", "second_order"])
    hit = a.index[(a["model"] == "hnn") & (a["system"] == "spring_pendulum")][0]
    a.loc[hit, ["status", "rollout_error", "energy_violation"]] = ["diverged", np.nan, np.nan]
    b, cb = synthetic_tables("quick", experiments=["energy"], seeds=(0,))
    pd.concat([a, b], ignore_index=True).to_parquet(d / "runs.parquet", index=False)
    pd.concat([ca, cb], ignore_index=True).to_parquet(d / "curves.parquet", index=False)
    return d, len(a), len(b)


def test_load_tables_takes_the_profile_named(folder):
    d, n_smoke, n_quick = folder
    assert load_tables(d)[2] == "smoke"  # the most rows, as before
    runs, _, profile = load_tables(d, "quick")
    assert profile == "quick" and set(runs["profile"]) == {"quick"} and len(runs) == n_quick
    with chosen_profile(d, "quick"):
        assert load_tables(d)[2] == "quick"
        assert pick_profile(runs, d) == "quick"
        assert pick_profile(load_tables(d, "smoke")[0], d / "other") == "smoke"


def test_figures_name_every_profile_and_the_one_kept(folder, capsys):
    d, n_smoke, n_quick = folder
    assert main(["--results", str(d), "figures"]) == 0
    (line,) = [x for x in capsys.readouterr().out.splitlines() if x.startswith(f"{d} holds ")]
    held, drawn = re.fullmatch(rf"{re.escape(str(d))} holds (.+): drawing (\S+) .*", line).groups()
    assert _profiles(held) == [("smoke", n_smoke), ("quick", n_quick)] and drawn == "smoke"
    assert "--profile" in line  # the option that picks another


def _profiles(text):
    """``smoke (12 rows), quick (3 rows)`` read back as [(profile, rows)]."""
    return [(p, int(n)) for p, n in re.findall(r"([\w-]+) \((\d+) rows\)", text)]


def test_report_profile_option_judges_the_other_profile(folder, tmp_path):
    d, n_smoke, n_quick = folder
    text = write_report(d, compare=[], profile="quick").read_text()
    header = re.search(r"^- profile: (\S+) \((.*)\)$", text, re.M)
    assert header.group(1) == "quick"  # the profile judged
    assert _profiles(header.group(2)) == [("smoke", n_smoke), ("quick", n_quick)]  # the folder's
    assert int(re.search(r"^- runs: (\d+) runs", text, re.M).group(1)) == n_quick


@pytest.mark.parametrize("verb", ["figures", "report"])
def test_a_profile_not_stored_is_one_line_naming_those_present(folder, verb, capsys):
    d, n_smoke, n_quick = folder
    assert main(["--results", str(d), verb, "--profile", "paper"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: no runs of profile 'paper'"), err
    assert f"smoke ({n_smoke} rows), quick ({n_quick} rows)" in err[0]


def test_a_diverged_run_is_counted_at_the_worst_error(folder):
    d, _, _ = folder
    runs, curves, profile = load_tables(d, "smoke")
    rows = experiment_rows(runs, "second_order", profile)
    bars = model_bar_values(rows).set_index(["system", "variant"])
    hnn = bars.loc[("spring_pendulum", "hnn")]
    assert hnn["n"] == 5 and hnn["n_failed"] == 1
    ok = rows[(rows["model"] == "hnn") & (rows["system"] == "spring_pendulum")]
    finite = ok["rollout_error"].dropna().to_numpy(float)
    assert hnn["mean"] == pytest.approx((finite.sum() + 1.0) / 5)  # scored as error 1
    assert (bars.drop(index=("spring_pendulum", "hnn"))["n_failed"] == 0).all()


def test_every_figure_draws_with_a_diverged_run(folder, tmp_path):
    d, _, _ = folder
    written = {p.name for p in make_figures(d, "smoke")}
    assert {"fig2_energy.png", "fig4_second_order.png"} <= written
    runs, curves, profile = load_tables(d, "smoke")
    assert fig_energy(experiment_rows(runs, "energy", profile), curves, tmp_path)


def test_fig2_line_is_the_rules_theil_sen_slope(folder):
    d, _, _ = folder
    runs, curves, profile = load_tables(d, "smoke")
    rows = experiment_rows(runs, "energy", profile)
    line = fig2_line(rows)
    part = next(p for p in claim_1(rows, curves).parts if p.name.startswith("(c)"))
    assert (line["slope"], line["lo"], line["hi"]) == pytest.approx((part.point, part.lo, part.hi))
    assert set(line["fitted"]["model"]) == {"node", "node_so", "hnn_so"}  # not the plain HNN
