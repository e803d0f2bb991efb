"""Faults from outside a run: nothing is lost silently.

Damaged row files, unusable results folders, empty results, runs that can never run, a full
disk while a row or a dataset is written, and a sweep killed with SIGKILL. Each fault is
injected for real (files truncated or overwritten, ``ulimit -f`` in a subprocess, SIGKILL);
the runs themselves are faked where the fault is about bookkeeping, not physics.

This module doubles as an experiments module: a sweep subprocess started with
``DECON_EXTRA_EXPERIMENTS=tests.test_faults`` imports it and so knows ``faults_resume``. With
``DECON_TEST_FAKE_RUN=<log file>`` it also swaps the runner's ``execute_run`` for a fake that
sleeps ``DECON_TEST_FAKE_SLEEP`` seconds and logs each execution; the row of the seed
``DECON_TEST_FAKE_PAD_SEED`` carries a large padding field (a row too big for a small disk).
"""

import errno
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import bench.core._runner as runner
from bench._cli import main
from bench.core import (
    Experiment,
    RunConfig,
    StorageError,
    _store,
    check_runnable,
    expand,
    observation_kinds,
    register,
    storage_error,
)

ROOT = Path(__file__).resolve().parents[1]

RESUME = register(
    Experiment(
        name="faults_resume",
        title="test: faults and resume",
        axes={"model": ["node"]},
        fixed={"system": "chain_pendulum", "k": 1},
        profile_overrides={"smoke": {"seeds": list(range(6))}},
    ),
    replace=True,
)


def _fake_row(config) -> dict:
    row = runner.base_row(config)
    row.update(status="ok", rollout_error=0.01 * (config.seed + 1))
    row["curves"] = {"t": [0.0, 0.03], "rel_error": [0.0, 0.01], "energy_violation": [0, 0]}
    if str(config.seed) == os.environ.get("DECON_TEST_FAKE_PAD_SEED"):
        row["pad"] = "x" * 400_000
    return row


def _fake_execute_run(config, cache_root=None, progress=False):
    with open(os.environ["DECON_TEST_FAKE_RUN"], "a") as f:
        f.write(config.config_hash + "\n")
    time.sleep(float(os.environ.get("DECON_TEST_FAKE_SLEEP", "0.7")))
    return _fake_row(config)


if os.environ.get("DECON_TEST_FAKE_RUN"):
    runner.execute_run = _fake_execute_run


def _sweep_cmd(res):
    return [sys.executable, "-m", "bench", "--results", str(res), "sweep", "faults_resume",
            "--profile", "smoke", "--no-progress"]  # fmt: skip


def _env(tmp_path, **extra):
    return {
        **os.environ,
        "DECON_EXTRA_EXPERIMENTS": "tests.test_faults",
        "DECON_TEST_FAKE_RUN": str(tmp_path / "executed.log"),
        "DECON_CACHE": str(tmp_path / "cache"),
        **extra,
    }


def _one_error_line(stderr: str) -> str:
    assert "Traceback" not in stderr, stderr
    lines = [ln for ln in stderr.strip().splitlines() if ln.startswith("error: ")]
    assert len(lines) == 1, stderr
    return lines[0]


@pytest.fixture
def stored(tmp_path):
    """Five fake rows of faults_resume stored in tmp_path/res (configs in expansion order)."""
    configs = expand(RESUME, "smoke")[:5]
    res = tmp_path / "res"
    for c in configs:
        row = _fake_row(c)
        row.update(experiment="faults_resume", profile="smoke")
        _store.write_row(res, row)
    _store.rebuild_tables(res)
    return res, configs


# ---------------------------------------------------------------------- damaged row files
def test_damaged_row_files_named_set_aside_and_rerun(stored, monkeypatch):
    res, configs = stored
    rows_dir = res / _store.ROWS
    paths = [rows_dir / f"{c.config_hash}.json" for c in configs]
    good = paths[4].read_text()
    paths[0].write_text(good[: len(good) // 2])  # truncated (a full disk, a broken copy)
    paths[1].write_text("<<<<<<< HEAD\n" + good + "\n=======\n")  # a merge conflict
    paths[2].write_text(json.dumps({"config_hash": configs[2].config_hash, "foo": 1}))
    edited = json.loads(paths[3].read_text())
    edited["rollout_error"] = 1e-9  # valid JSON, wrong content: the checksum says so
    paths[3].write_text(json.dumps(edited))
    damaged = {p.name: p.read_bytes() for p in paths[:4]}
    partial = rows_dir / ".tmp-partial.json"  # a row being written (or left by a kill)
    partial.write_text(good[:10])

    with pytest.warns(_store.DamagedRowWarning) as caught:
        done = _store.done_hashes(res)
    assert done == {configs[4].config_hash}
    messages = " ".join(str(w.message) for w in caught)
    for p in paths[:4]:
        assert str(p) in messages
    for needle in ("not JSON", "status", "checksum"):
        assert needle in messages
    # Moved aside, byte for byte, never deleted.
    aside = rows_dir / _store.DAMAGED
    assert {p.name: p.read_bytes() for p in aside.glob("*.json")} == damaged
    assert sorted(p.name for p in _store.unread_rows(res)) == sorted(damaged)
    assert partial.exists() and str(partial) not in messages  # a temporary is not a row

    # The next sweep reruns exactly the four runs whose rows were lost.
    executed = []
    monkeypatch.setattr(
        runner, "execute_run", lambda c, **kw: executed.append(c.config_hash) or _fake_row(c)
    )
    new = runner.sweep(configs, res, experiment="faults_resume", profile="smoke", progress=False)
    assert sorted(executed) == sorted(c.config_hash for c in configs[:4]) and len(new) == 4
    df = pd.read_csv(res / "runs.csv")
    assert sorted(df["config_hash"]) == sorted(c.config_hash for c in configs)
    assert _store.unread_rows(res) == []  # rerun: nothing missing any more
    assert len(list(aside.glob("*.json"))) == 4  # and the damaged files are still kept


def test_report_and_figures_say_how_many_rows_they_could_not_read(stored, monkeypatch, capsys):
    import bench._report

    res, configs = stored
    seen = []
    monkeypatch.setattr(
        bench._report, "write_report", lambda d, *a, **kw: seen.append(len(_store.load_runs(d)))
    )
    monkeypatch.setattr(
        bench._report, "make_figures", lambda d, *a, **kw: seen.append(len(_store.load_runs(d)))
    )
    (res / _store.ROWS / f"{configs[0].config_hash}.json").write_text("{")
    (res / _store.ROWS / f"{configs[1].config_hash}.json").write_text("")
    for verb in ("report", "figures"):
        assert main(["--results", str(res), verb]) == 0
        err = capsys.readouterr().err
        assert (
            f"warning: 2 stored row file(s) could not be read and are left out of the {verb}" in err
        )
    assert seen == [3, 3]


# ------------------------------------------------------------------- unusable results folder
def test_unusable_results_folder_one_line_exit_2(tmp_path, capsys):
    afile = tmp_path / "afile"
    afile.write_text("not a folder")
    cases = [
        (afile, "is a file"),
        (afile / "sub", f"is under {afile}, which is a file"),
        (Path("/proc/decon-bench-results"), "cannot be created"),  # even root cannot
    ]
    for path, needle in cases:
        for argv in (["sweep", "--all", "--profile", "smoke"], ["report"], ["figures"]):
            if argv[0] != "sweep" and "created" in needle:
                continue  # report/figures do not create the folder: it has no runs
            code = main(["--results", str(path), *argv])
            line = _one_error_line(capsys.readouterr().err)
            assert code == 2 and str(path) in line and needle in line, (argv, line)
    assert afile.read_text() == "not a folder"
    # The Python API says the same, and checks the cache folder before any run.
    with pytest.raises(ValueError, match=f"results folder {afile} is a file"):
        runner.sweep(expand(RESUME, "smoke"), afile, progress=False)
    with pytest.raises(ValueError, match=r"cache folder \(\$DECON_CACHE\) .* is under"):
        runner.sweep(expand(RESUME, "smoke"), tmp_path / "res", cache_root=afile / "c")
    assert not list((tmp_path / "res").glob(f"{_store.ROWS}/*"))


@pytest.mark.skipif(os.geteuid() == 0, reason="root ignores permissions (see the slow variant)")
def test_unwritable_results_folder_in_process(tmp_path, capsys):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        code = main(["--results", str(ro), "sweep", "--all", "--profile", "smoke", "--no-progress"])
    finally:
        ro.chmod(0o755)
    line = _one_error_line(capsys.readouterr().err)
    assert code == 2 and line == f"error: results folder {ro} is not writable: Permission denied"
    assert list(ro.iterdir()) == []


@pytest.mark.slow  # a sweep in a subprocess (as root, without the permission override)
def test_unwritable_results_folder_subprocess(tmp_path):
    """A folder without write permission. Root ignores permissions, so as root the command
    runs without the CAP_DAC_OVERRIDE capability (``setpriv``), which makes it obey them."""
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    cmd = [sys.executable, "-m", "bench", "--results", str(ro), "sweep", "--all",
           "--profile", "smoke", "--no-progress"]  # fmt: skip
    if os.geteuid() == 0:
        if shutil.which("setpriv") is None:
            pytest.skip("root without setpriv: cannot drop the permission override")
        cmd = ["setpriv", "--bounding-set=-dac_override,-dac_read_search", *cmd]
    try:
        out = subprocess.run(cmd, cwd=ROOT, env=_env(tmp_path), capture_output=True, text=True,
                             timeout=120)  # fmt: skip
    finally:
        ro.chmod(0o755)
    line = _one_error_line(out.stderr)
    assert out.returncode == 2, out.stderr
    assert line == f"error: results folder {ro} is not writable: Permission denied"
    assert list(ro.iterdir()) == []


# ------------------------------------------------------------------------------ empty results
def test_empty_results_report_and_figures_exit_nonzero(tmp_path, capsys):
    (tmp_path / "with_empty_rows" / _store.ROWS).mkdir(parents=True)
    (tmp_path / "empty").mkdir()
    for folder in ("missing", "empty", "with_empty_rows"):
        res = tmp_path / folder
        for verb, what in (("report", "report"), ("figures", "draw")):
            code = main(["--results", str(res), verb])
            line = _one_error_line(capsys.readouterr().err)
            assert code == 1
            assert line.startswith(f"error: no runs stored in {res} for any profile (smoke, ")
            assert f"nothing to {what}" in line
        assert not (res / "REPORT.md").exists() and not (res / "figures").exists()
    assert not (tmp_path / "missing").exists()


# ----------------------------------------------------------------- runs that can never run
IMPOSSIBLE = [
    (["--model", "node", "--integrator", "leapfrog"], "allowed for 'node': "),
    (["--model", "node", "--set", "eval_integrator=leapfrog"], "eval_integrator 'leapfrog'"),
    (["--model", "lnn", "--coordinates", "momentum"], "needs velocity coordinates"),
    (["--model", "vin", "--coordinates", "momentum"], "needs velocity coordinates"),
    (["--model", "lnn", "--set", 'model_options={"nope": 1}'], "allowed: ['eps'"),
    (["--set", "test_chunks=100"], "exceeds the 334 points"),
    (["--set", "chunk=1"], "chunk must be in [2, 334]"),
]


@pytest.mark.parametrize(("extra", "needle"), IMPOSSIBLE, ids=[" ".join(a) for a, _ in IMPOSSIBLE])
def test_run_that_can_never_run_rejected_before_training(extra, needle, tmp_path, capsys):
    argv = ["--results", str(tmp_path / "res"), "run", "--system", "chain_pendulum", "--k", "1",
            "--profile", "smoke", *extra]  # fmt: skip
    code = main(argv)
    line = _one_error_line(capsys.readouterr().err)
    assert code == 2 and needle in line, line
    assert not (tmp_path / "res").exists()  # nothing ran, nothing was recorded


def test_integrator_rule_follows_model_capabilities(tmp_path):
    base = dict(system="chain_pendulum", k=1, n_generated=8, n_train=4, n_test=2, test_chunks=2)
    with pytest.raises(ValueError, match="allowed for 'node': ") as e:
        check_runnable(RunConfig(model="node", train_integrator="leapfrog", **base))
    allowed = str(e.value).split("allowed for 'node': ")[1].split(", ")
    assert "leapfrog" not in allowed and "rk4_38" in allowed
    # Second-order models take leapfrog; discrete models ignore the integrator.
    for model in ("node_so", "vin"):
        check_runnable(RunConfig(model=model, train_integrator="leapfrog", **base))
    # hnn_so takes leapfrog in both coordinates: second order in (q, qdot), and in (q, p) the
    # generalised Stormer-Verlet of its Hamiltonian; the explicit kick needs a second-order model.
    check_runnable(RunConfig(model="hnn_so", eval_integrator="leapfrog", **base))
    check_runnable(
        RunConfig(model="hnn_so", eval_integrator="leapfrog", coordinates="momentum", **base)
    )
    with pytest.raises(ValueError, match="eval_integrator 'leapfrog_explicit' cannot run"):
        check_runnable(RunConfig(model="node", eval_integrator="leapfrog_explicit", **base))
    # The Python API refuses before anything runs.
    bad = RunConfig(model="node", eval_integrator="leapfrog", **base)
    with pytest.raises(ValueError, match="leapfrog"):
        runner.sweep([bad], tmp_path / "res", progress=False, cache_root=tmp_path / "cache")
    assert not (tmp_path / "res" / _store.ROWS).exists()


@pytest.mark.slow  # ~100 distinct (model, scene, integrator) traces: about a minute
def test_every_experiment_run_is_runnable():
    from bench.core import available

    for profile in ("smoke", "quick", "paper"):
        for name in available():
            for c in expand(name, profile):
                check_runnable(c)


# ---------------------------------------------------------------------------- a full disk
def _limited(cmd, kib):
    """``cmd`` under ``ulimit -f kib`` (file size limit, in KiB), SIGXFSZ ignored."""
    return ["bash", "-c", f"trap '' XFSZ; ulimit -f {kib} && exec \"$@\"", "limited", *cmd]


@pytest.mark.slow  # a sweep in a subprocess under a file-size limit
def test_full_disk_while_a_row_is_written_stops_and_resumes(tmp_path, monkeypatch):
    res = tmp_path / "res"
    env = _env(tmp_path, DECON_TEST_FAKE_SLEEP="0", DECON_TEST_FAKE_PAD_SEED="3")
    out = subprocess.run(_limited(_sweep_cmd(res), 128), cwd=ROOT, env=env, capture_output=True,
                         text=True, timeout=120)  # fmt: skip
    line = _one_error_line(out.stderr)
    assert out.returncode == 1, out.stderr
    assert "could not write" in line and "File too large" in line and "run it again" in line
    configs = expand(RESUME, "smoke")
    rows_dir = res / _store.ROWS
    stored = {p.stem for p in rows_dir.glob("*.json")}
    assert stored == {c.config_hash for c in configs[:3]}  # seeds 0-2; seed 3's row did not fit
    assert not list(rows_dir.glob(".tmp*")) and not list(res.glob(".tmp*"))  # no partial file
    assert len(pd.read_csv(res / "runs.csv")) == 3
    executed = (tmp_path / "executed.log").read_text().split()
    assert executed == [c.config_hash for c in configs[:4]]
    # Room again: the next sweep resumes with the runs not stored.
    monkeypatch.setattr(runner, "execute_run", lambda c, **kw: _fake_row(c))
    new = runner.sweep(configs, res, experiment="faults_resume", profile="smoke", progress=False)
    assert [r["seed"] for r in new] == [3, 4, 5]
    df = pd.read_parquet(res / "runs.parquet")
    assert sorted(df["config_hash"]) == sorted(c.config_hash for c in configs)


def test_full_disk_while_a_dataset_is_written(tmp_path):
    import systems
    from systems import _dataset

    cfg = systems.DatasetConfig(system="chain_pendulum", system_params={"k": 1}, n_generated=4,
                                n_train=4, n_test=2, test_chunks=2)  # fmt: skip
    rng = np.random.default_rng(0)
    arrays = {
        "ts_train": np.arange(5) * 0.03,
        "z_train": rng.normal(size=(4000, 5, 2)),  # 320 kB: more than the limit below
        "args_train": np.zeros((4000, 2)),
        "ts_test": np.arange(10) * 0.03,
        "z_test": rng.normal(size=(2, 10, 2)),
        "args_test": np.zeros((2, 2)),
    }
    np.savez(tmp_path / "arrays.npz", **arrays)
    path = tmp_path / "cache" / "datasets" / f"{cfg.hash()}.npz"
    code = (
        "import sys, errno, numpy as np, systems; from systems import _dataset as d\n"
        "cfg = systems.DatasetConfig(system='chain_pendulum', system_params={'k': 1},"
        " n_generated=4, n_train=4, n_test=2, test_chunks=2)\n"
        f"a = dict(np.load({str(tmp_path / 'arrays.npz')!r}))\n"
        f"try:\n    d._save(__import__('pathlib').Path({str(path)!r}), cfg, a)\n"
        "except OSError as e:\n    print('errno', errno.errorcode[e.errno]); sys.exit(3)\n"
    )
    out = subprocess.run(_limited([sys.executable, "-c", code], 128), cwd=ROOT,
                         capture_output=True, text=True, timeout=120)  # fmt: skip
    assert out.returncode == 3 and "errno EFBIG" in out.stdout, out.stdout + out.stderr
    assert list(path.parent.iterdir()) == []  # no partial cache file, no temporary left
    # A damaged cache file is never trusted: truncated, or with arrays that disagree with
    # their checksum, it does not load (make_dataset then generates the data again).
    _dataset._save(path, cfg, arrays)
    assert _dataset._load(path, cfg) is not None
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    assert _dataset._load(path, cfg) is None
    bad = dict(arrays)
    with np.load(tmp_path / "arrays.npz") as f:
        np.savez(path, checksum=np.array(_dataset._checksum(bad)),
                 config=np.array(cfg.canonical_json()),
                 **{**{k: f[k] for k in f.files}, "z_test": arrays["z_test"] + 1})  # fmt: skip
    assert _dataset._load(path, cfg) is None


def test_full_disk_in_a_run_stops_the_sweep_not_recorded_as_failed(tmp_path, monkeypatch):
    configs = expand(RESUME, "smoke")[:3]
    res = tmp_path / "res"

    def build(self, config, cache_root):  # the state runs' build step
        if config.seed == 1:
            raise OSError(errno.ENOSPC, "No space left on device", str(cache_root / "x.npz"))
        raise RuntimeError("a bug in this run")  # an ordinary failure: recorded, not fatal

    monkeypatch.setattr(type(observation_kinds()["state"]), "build", build)
    with pytest.raises(StorageError, match="No space left on device.*after 1 new of 3 runs"):
        runner.sweep(configs, res, progress=False, cache_root=tmp_path / "cache")
    rows = _store.read_rows(res)
    assert [(r["seed"], r["status"]) for r in rows] == [(0, "failed")]
    assert storage_error(RuntimeError("ray: OSError: [Errno 28] No space left")).errno == 28
    assert storage_error(RuntimeError("[Errno 2] missing")) is None
    # Resume: the run that met the full disk was not recorded, so it runs now.
    monkeypatch.setattr(runner, "execute_run", lambda c, **kw: _fake_row(c))
    new = runner.sweep(configs, res, progress=False, cache_root=tmp_path / "cache")
    assert [r["seed"] for r in new] == [1, 2]


@pytest.mark.slow  # a real smoke run: data, training and evaluation compiles
def test_full_disk_real_sweep_dataset_then_resume(tmp_path):
    """A real sweep under a 2 KiB file-size limit: the dataset cache does not fit; the sweep
    stops with one line and leaves no cache file; without the limit it runs to the end."""
    res = tmp_path / "res"
    env = {**os.environ, "DECON_CACHE": str(tmp_path / "cache"), "DECON_JAX_CACHE": "0"}
    argv = [sys.executable, "-m", "bench", "--results", str(res), "run", "--system",
            "chain_pendulum", "--k", "1", "--model", "node", "--profile", "smoke"]  # fmt: skip
    out = subprocess.run(_limited(argv, 2), cwd=ROOT, env=env, capture_output=True, text=True,
                         timeout=300)  # fmt: skip
    line = _one_error_line(out.stderr)
    assert out.returncode == 1 and "File too large" in line, out.stderr
    assert f"could not write {tmp_path / 'cache' / 'datasets'}" in line
    assert not list(res.glob(f"{_store.ROWS}/*.json"))
    assert not list((tmp_path / "cache" / "datasets").glob("*"))
    out = subprocess.run(argv, cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert len(_store.read_rows(res)) == 1 and "status: ok" in out.stdout


# ------------------------------------------------------------------------- kill and resume
def test_orphan_temporaries_of_dead_writers_are_cleared(tmp_path):
    """A kill mid-write leaves ``.tmp-<pid>-*``; the next sweep removes a dead writer's only."""
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    rows = tmp_path / _store.ROWS
    rows.mkdir(parents=True)
    orphan = rows / f".tmp-{dead.pid}-abc.json"
    live = rows / f".tmp-{os.getpid()}-def.json"
    unnamed = rows / ".tmp-ghi.json"
    for p in (orphan, live, unnamed):
        p.write_text("{")
    assert _store.clear_orphans(rows) == [orphan]
    assert not orphan.exists() and live.exists() and unnamed.exists()
    # this process's own temporaries carry its pid
    assert _store.tmp_prefix() == f".tmp-{os.getpid()}-"


def test_a_sweep_run_again_stores_only_the_missing_rows(tmp_path, monkeypatch):
    """In-process, through the CLI: three rows stored, the sweep run again executes the other
    three and stores each run once."""
    configs = expand(RESUME, "smoke")
    res = tmp_path / "results"
    executed = []

    def fake(config, **kw):
        executed.append(config.config_hash)
        return _fake_row(config)

    monkeypatch.setattr(runner, "execute_run", fake)
    runner.sweep(configs[:3], res, experiment="faults_resume", profile="smoke", progress=False)
    argv = ["--results", str(res), "sweep", "faults_resume", "--profile", "smoke", "--no-progress"]
    assert main(argv) == 0
    assert executed == [c.config_hash for c in configs]  # each run once
    df = pd.read_parquet(res / "runs.parquet")
    assert sorted(df["config_hash"]) == sorted(c.config_hash for c in configs)
    assert (df["status"] == "ok").all()


@pytest.mark.slow  # two sweeps in subprocesses, one killed
def test_resume_after_kill(tmp_path):
    """SIGKILL in the middle of a sweep: the next sweep stores exactly the missing rows."""
    log = tmp_path / "executed.log"
    res = tmp_path / "results"
    env = _env(tmp_path, DECON_TEST_FAKE_SLEEP="0.4")
    proc = subprocess.Popen(
        _sweep_cmd(res), cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE
    )
    rows_dir = res / _store.ROWS
    deadline = time.time() + 60
    while time.time() < deadline and len(list(rows_dir.glob("*.json"))) < 2:
        time.sleep(0.05)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    # pathlib's glob matches dotfiles: a kill during a row's write leaves a .tmp-*.json
    killed_rows = {p.stem for p in rows_dir.glob("*.json") if not p.name.startswith(".")}
    assert 1 <= len(killed_rows) < 6, "kill landed outside the sweep"
    out = subprocess.run(
        _sweep_cmd(res), cwd=ROOT, env=env, capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 0, out.stderr
    expected = {c.config_hash for c in expand(RESUME, "smoke")}
    df = pd.read_parquet(res / "runs.parquet")
    assert len(df) == 6 and set(df["config_hash"]) == expected and (df["status"] == "ok").all()
    executed = log.read_text().split()
    # Rows stored before the kill were not executed again; at most the run in flight was.
    assert all(executed.count(h) == 1 for h in killed_rows)
    assert len(executed) <= 6 + 1
    assert not list(rows_dir.glob(".tmp*"))
    assert _store.unread_rows(res) == []  # and no row was left damaged


def test_a_row_rewritten_under_its_hash_marks_every_table_stale(stored, monkeypatch, capsys):
    """A rerun that replaces a row (same config_hash, new numbers) leaves the hash sets equal;
    the row files' digest recorded at the last rebuild tells the tables are stale, and the
    report rebuilds them with the new numbers (the curves too)."""
    import bench._report

    res, configs = stored
    monkeypatch.setattr(bench._report, "write_report", lambda d, *a, **kw: None)
    assert _store.stale_tables(res) == []
    row = _fake_row(configs[0])
    row.update(experiment="faults_resume", profile="smoke", rollout_error=0.5)
    row["curves"]["rel_error"] = [0.0, 0.5]
    _store.write_row(res, row)
    stale = dict(_store.stale_tables(res))
    assert set(stale) == set(_store.TABLES)
    assert stale["curves.parquet"].startswith("built from other row files")
    assert main(["--results", str(res), "report"]) == 0
    assert "warning: rebuilt from the row files: runs.parquet (built from other row" in (
        capsys.readouterr().err
    )
    runs = pd.read_parquet(res / "runs.parquet").set_index("config_hash")
    assert runs.loc[configs[0].config_hash, "rollout_error"] == 0.5
    curves = pd.read_parquet(res / "curves.parquet")
    assert curves["rel_error"].max() == 0.5
    assert _store.stale_tables(res) == []


def test_a_folder_without_a_recorded_digest_is_checked_by_its_runs(stored):
    """Folders built before digests were recorded (no ``rows_digest`` in bench_meta.json) are
    not all flagged: the hash-set check still runs."""
    res, configs = stored
    meta = json.loads((res / _store.META).read_text())
    del meta["rows_digest"]
    (res / _store.META).write_text(json.dumps(meta))
    assert _store.stale_tables(res) == []
    (res / _store.ROWS / f"{configs[0].config_hash}.json").unlink()
    assert [n for n, _ in _store.stale_tables(res)] == ["runs.parquet", "runs.csv"]


@pytest.mark.parametrize("verb", ["report", "figures"])
def test_report_and_figures_rebuild_a_damaged_runs_table_and_name_it(
    stored, monkeypatch, capsys, verb
):
    """A truncated runs.parquet (and a runs.csv of other runs) is named and rebuilt from the
    row files, the truth; a second call finds nothing to rebuild."""
    import bench._report

    res, configs = stored
    monkeypatch.setattr(bench._report, "write_report", lambda d, *a, **kw: None)
    monkeypatch.setattr(bench._report, "make_figures", lambda d, *a, **kw: None)
    _store.rebuild_tables(res)
    assert _store.stale_tables(res) == []
    data = (res / "runs.parquet").read_bytes()
    (res / "runs.parquet").write_bytes(data[: len(data) // 2])
    pd.read_csv(res / "runs.csv").iloc[1:].to_csv(res / "runs.csv", index=False)
    assert main(["--results", str(res), verb]) == 0
    err = capsys.readouterr().err
    assert "warning: rebuilt from the row files: runs.parquet (unreadable" in err
    assert "runs.csv (other runs than the row files)" in err and "curves" not in err
    df = pd.read_parquet(res / "runs.parquet")
    assert sorted(df["config_hash"]) == sorted(c.config_hash for c in configs)
    assert _store.stale_tables(res) == []
    assert main(["--results", str(res), verb]) == 0  # nothing to rebuild the second time
    assert "rebuilt" not in capsys.readouterr().err


def test_a_temporary_left_by_a_kill_is_not_a_row(stored):
    """A kill between a row's temporary write and its rename leaves ``.rows/.tmp-*.json``:
    neither the staleness check nor the digest counts it as a row."""
    res, _ = stored
    assert _store.stale_tables(res) == []
    (res / _store.ROWS / ".tmp-abc123.json").write_text('{"config_hash": "half')
    assert _store.stale_tables(res) == []
