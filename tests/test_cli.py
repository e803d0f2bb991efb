"""The command line: every bad input is one line on stderr, exit code 2, no traceback."""

import os
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from bench._cli import main
from bench.core import REPLICATION_SEEDS

ROOT = Path(__file__).resolve().parents[1]

BAD = [
    (["run", "--system", "chain_pendulum", "--k", "2", "--model", "nod"], "did you mean 'node'"),
    (["run", "--system", "chain_pendulm", "--model", "node"], "unknown system"),
    (["run", "--system", "chain_pendulum", "--k", "0"], "k must be an integer >= 1"),
    (["run", "--system", "chain_pendulum", "--k", "two"], "k must be an integer"),
    (["run", "--system", "chain_pendulum", "--k", "1", "--friction", "-0.4"], "friction"),
    (["run", "--system", "chain_pendulum", "--k", "1", "--friction", "nan"], "friction"),
    (["run", "--system", "chain_pendulum", "--k", "1", "--seed", "-1"], "seed"),
    (
        ["run", "--system", "chain_pendulum", "--k", "1", "--profile", "quik"],
        "did you mean 'quick'",
    ),
    (["run", "--system", "chain_pendulum", "--k", "1", "--set", "widht=3"], "did you mean 'width'"),
    (["run", "--system", "relativistic_particle", "--k", "2"], "relativistic"),
    (["sweep", "no_such_experiment", "--profile", "smoke"], "unknown experiment"),
    (["sweep", "--all", "--executor", "rya"], "did you mean 'ray'"),
    (["sweep", "--all", "--profile", "papr"], "did you mean 'paper'"),
    (["sweep", "--all", "--workers", "x"], "workers must be an integer"),
    (["sweep"], "experiment name or --all"),
    (["frobnicate"], "invalid choice"),
    (["bench", "--papers", "hnn,lnm", "--profile", "smoke"], "did you mean 'lnn'"),
    (["bench", "--papers", ",", "--profile", "smoke"], "--papers needs at least one of"),
    (
        ["campaign", "--profile", "smoke", "--replication"],
        "profile with replication seeds 'smoke'; allowed: quick, paper, paper-core",
    ),
    (
        ["campaign", "--profile", "paper-core", "--claims", "9,99"],
        "unknown claim '99'; allowed: 1,",
    ),
    (["estimate", "--profile", "paper-k", "--claims", "4 99"], "unknown claim '99'; allowed: 1,"),
]


@pytest.mark.parametrize(("argv", "needle"), BAD, ids=[" ".join(a) for a, _ in BAD])
def test_bad_input_one_line_exit_2(argv, needle, capsys, tmp_path):
    code = main(["--results", str(tmp_path), *argv])
    err = capsys.readouterr().err
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    assert needle in lines[0], lines[0]
    assert not (tmp_path / ".rows").exists()  # nothing ran


def test_bad_input_subprocess_has_no_traceback(tmp_path):
    out = subprocess.run(
        [sys.executable, "-m", "bench", "--results", str(tmp_path), "run", "--system",
         "chain_pendulum", "--k", "2", "--model", "nod"],
        cwd=ROOT, capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert out.returncode == 2
    assert "Traceback" not in out.stderr
    last = out.stderr.strip().splitlines()[-1]
    assert last.startswith("error: ") and "unknown model 'nod'; allowed: node" in last, last


def test_help_on_every_verb(capsys):
    for verb in ("list", "run", "sweep", "figures", "report", "perf", "bench"):
        with pytest.raises(SystemExit) as e:
            main([verb, "--help"])
        assert e.value.code == 0
        assert "usage:" in capsys.readouterr().out


def test_list(capsys):
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    for word in ("chain_pendulum", "node_so", "smoke", "quick", "paper"):
        assert word in out


@pytest.mark.slow  # a real run: data, training and evaluation compiles (30-130 s here)
def test_run_prints_metrics_and_adds_row(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("DECON_CACHE", str(tmp_path / "cache"))
    argv = ["--results", str(tmp_path / "res"), "run", "--system", "chain_pendulum", "--k", "1",
            "--model", "node_so", "--seed", "0", "--profile", "smoke", "--steps", "10"]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "rollout_error" in out and "status: ok" in out
    df = pd.read_parquet(tmp_path / "res" / "runs.parquet")
    assert len(df) == 1 and df.loc[0, "experiment"] == "adhoc" and df.loc[0, "model"] == "node_so"
    # Running it again adds nothing and shows the stored row.
    assert main(argv) == 0
    assert "already stored" in capsys.readouterr().out
    assert len(pd.read_parquet(tmp_path / "res" / "runs.parquet")) == 1


# report and figures on a folder without runs: tests/test_faults.py


def test_env_pins_cores_and_compilation_cache():
    # XLA sizes its thread pools from the affinity mask: setup_process(1) must shrink it and
    # turn on the persistent compilation cache, in jax's settings too (jax is imported by then:
    # `import bench` loads the studies but changes nothing in the process).
    code = (
        "import os, jax, bench, bench.core._env as e; "
        "assert 'JAX_COMPILATION_CACHE_DIR' not in os.environ; n = e.setup_process(1); "
        "assert jax.config.jax_enable_x64, 'setup_process did not turn 64-bit mode on'; "
        "assert jax.config.jax_default_matmul_precision == 'float32', 'matmuls not float32'; "
        "print(n, len(os.sched_getaffinity(0)), os.environ['JAX_COMPILATION_CACHE_DIR'], "
        "jax.config.jax_compilation_cache_dir)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120,
        env={k: v for k, v in os.environ.items() if not k.startswith("JAX_COMPILATION")},
    )  # fmt: skip
    n, mask, cache, in_jax = out.stdout.split()
    assert (n, mask) == ("1", "1"), out.stderr
    assert in_jax == cache, "jax was not told where the cache is"
    assert cache.endswith(os.path.join("decon-bench", "jax"))


IMPORTS_CHANGE_NOTHING = """
import sys, warnings, jax, matplotlib, numpy as np
backend = dict.__getitem__(matplotlib.rcParams, "backend")  # unresolved: no backend chosen yet
import systems, models, bench
assert not jax.config.jax_enable_x64, "an import turned jax's 64-bit mode on"
assert jax.config.jax_default_matmul_precision is None, "an import set the matmul precision"
assert dict.__getitem__(matplotlib.rcParams, "backend") == backend, "an import set a backend"
assert "matplotlib.pyplot" not in sys.modules, "an import loaded pyplot"
warnings.simplefilter("ignore")  # making a system without 64-bit mode warns of float32 arrays
s = systems.make("chain_pendulum", k=1)
config = systems.DatasetConfig(system="pendulum", n_generated=2, n_train=2, n_test=1)
for compute in (lambda: s.simulate(np.array([0.1, 0.0]), np.arange(3) * 0.1),
                lambda: systems.make_dataset(config, cache_dir=sys.argv[1])):
    try:
        compute()
    except ValueError as e:
        print(e)
    else:
        raise AssertionError("ground truth was computed without 64-bit mode")
systems.enable_x64()
try:
    s.simulate(np.array([0.1, 0.0]), np.arange(3) * 0.1)
except ValueError as e:
    print(e)
print(systems.make("chain_pendulum", k=1).simulate(np.array([0.1, 0.0]), np.arange(3) * 0.1).dtype)
"""


def test_imports_change_no_process_setting(tmp_path):
    """`import systems, models, bench` leaves jax's 64-bit mode off and matplotlib's backend
    unchosen; ground truth without 64-bit mode (or from a system made without it) is a one-line
    error naming the fix, and the same computation runs in float64 once it is on."""
    out = subprocess.run(
        [sys.executable, "-c", IMPORTS_CHANGE_NOTHING, str(tmp_path)], cwd=ROOT,
        capture_output=True, text=True, timeout=300,
        env={k: v for k, v in os.environ.items() if k not in ("JAX_ENABLE_X64", "MPLBACKEND")},
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    *errors, dtype = out.stdout.splitlines()
    assert len(errors) == 3 and dtype == "float64", out.stdout
    for e in errors[:2]:
        assert "systems.enable_x64()" in e and 'jax.config.update("jax_enable_x64", True)' in e
    assert "made while jax's 64-bit mode was off" in errors[2]
    assert not list(tmp_path.iterdir()), "a dataset was cached without 64-bit mode"


def test_estimate_of_a_campaign_prints_its_three_phases(capsys, tmp_path):
    """paper-core's status: the replication seeds of the signed verdicts (none in an empty
    folder), its own seeds, then the replication seeds of the other claims."""
    assert main(["--results", str(tmp_path), "estimate", "--profile", "paper-core"]) == 0
    lines = capsys.readouterr().out.splitlines()
    titles = [x for x in lines if x.startswith("paper-core")]  # one plan per phase
    seeds = REPLICATION_SEEDS["paper"]
    assert len(titles) == 3, titles
    assert titles[0].endswith("signed verdicts (none): no runs")
    assert all(str(s) in titles[2] for s in seeds) and "replication" not in titles[1]
    assert sum(x.split()[:1] == ["total"] for x in lines) == 2
    # then the further readings that wait, each named where its experiment names it
    head = lines.index(
        "further readings still waiting (each joins its claim once stored on a seed set):"
    )
    waiting = {x.split(":")[0].strip(): x for x in lines[head + 1 :]}
    assert "the paper's HNN: 0 of 15 on seeds 0-4" in waiting["claim 16"]
    assert "claim 5" in waiting and "seeds 5-9" not in waiting["claim 5"]  # none of it stored


def test_bench_papers_selects_the_declared_experiments():
    """``bench --papers`` runs the experiments that declare those papers, and all by default."""
    from argparse import Namespace

    from bench._cli import _sweep_names
    from bench.core import PAPERS, available, get

    seeds = _sweep_names(Namespace(verb="bench", papers="hnn,lnn,vin"))
    paper = _sweep_names(Namespace(verb="bench", papers="deconstructing"))
    assert {"vin", "relativistic_seed", "pixel_pendulum_hnn_seed"} <= set(seeds)
    assert {"energy", "rigid_bodies"} <= set(paper) and not set(seeds) & set(paper)
    assert {get(n).paper for n in seeds} == {"hnn", "lnn", "vin"}
    assert sorted(seeds + paper) == sorted(_sweep_names(Namespace(verb="bench", papers=None)))
    assert sorted(seeds + paper) == available() and set(PAPERS) == {"deconstructing"} | {
        "hnn",
        "lnn",
        "vin",
    }


def test_estimate_in_a_given_order_prints_each_seed_set_in_that_order(capsys, tmp_path):
    """make paper-k's status: its claims one at a time in the order given, the profile's
    seeds then the replication seeds, each table's rows in that order."""
    args = ["--results", str(tmp_path), "estimate", "--profile", "paper-k", "--claims"]
    assert main([*args, "3 4"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert any(x.startswith("order: claims 3, 4, one at a time") for x in lines), lines
    rows = [x.split()[0] for x in lines if x.split()[:1] in (["3"], ["4"])]
    assert rows == ["3", "4", "3", "4"], lines
    assert sum(x.startswith("paper-k, replication seeds") for x in lines) == 1
