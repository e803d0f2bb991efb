"""A configuration's path from the CLI to its stored row passes through each step once.

The profiler counts, per ``bench`` module, the calls that enter it from another ``bench``
module while ``python -m bench run`` trains and stores one smoke run. The pipeline's steps
(CLI, runner, executor, build, train, evaluate) are each entered at most twice, the train step
three times when the parameter cache misses (the cache calls back the training it wraps); the
modules
that are libraries of small functions (metrics, the run configuration's properties, atomic
writes, tables) are called, not passed through, and are not bounded here.
"""

import collections
import sys

from bench._cli import main

STEPS = (
    "bench._cli",
    "bench.core._runner",
    "bench.core._execute",
    "bench.core._build",
    "bench.core._fit",
    "bench.core._evaluate",
)


def _entries(argv):
    counts = collections.Counter()

    def profile(frame, event, arg):
        if event != "call" or frame.f_code.co_name == "<module>":
            return
        mod = frame.f_globals.get("__name__", "")
        caller = frame.f_back.f_globals.get("__name__", "") if frame.f_back else ""
        if mod.startswith("bench") and caller.startswith("bench") and caller != mod:
            counts[mod] += 1

    sys.setprofile(profile)
    try:
        rc = main(argv)
    finally:
        sys.setprofile(None)
    return rc, counts


def test_a_run_enters_each_pipeline_step_at_most_twice(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("DECON_CACHE", str(tmp_path / "cache"))  # a cold cache: the worst case
    argv = ["--results", str(tmp_path), "run", "--system", "chain_pendulum", "--k", "1"]
    argv += ["--model", "node_so", "--profile", "smoke", "--steps", "4"]
    rc, counts = _entries(argv)
    assert rc == 0 and "config_hash" in capsys.readouterr().out
    assert all(counts[m] >= 1 for m in STEPS[1:]), counts  # the profiler saw the path
    bound = {m: 3 if m == "bench.core._fit" else 2 for m in STEPS}
    over = {m: counts[m] for m in STEPS if counts[m] > bound[m]}
    assert not over, f"pipeline steps entered more often than {bound}: {over}"
