"""Determinism: the same configuration run twice in one environment gives identical numbers.

Every metric, the per-time curves and the predicted trajectory of a smoke run must match bit
for bit between two executions with fresh caches (data regenerated, model retrained, nothing
reused from disk); only wall-clock timings may differ. The fast test runs both in this process;
the slow one in two fresh processes through the CLI, as a user would.
"""

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

from bench import execute_run
from bench.core import RunConfig, profile_defaults

ROOT = Path(__file__).resolve().parents[1]


def _config(model: str = "node_so") -> RunConfig:
    base, _ = profile_defaults("smoke")
    return RunConfig(**dict(base, system="chain_pendulum", k=1, model=model, seed=0))


def _numbers(row: dict) -> dict:
    """Everything but wall-clock timings, as canonical JSON values (NaN compared equal)."""
    # the row file's checksum covers its timings too: not a number of the run
    keep = {k: v for k, v in row.items() if "seconds" not in k and k != "_row_sha256"}
    if isinstance(keep.get("checkpoints"), dict):  # a learning curve's own timings
        keep["checkpoints"] = {k: v for k, v in keep["checkpoints"].items() if "seconds" not in k}
    return json.loads(json.dumps(keep, default=str).replace("NaN", "null"))


def _assert_identical(a: dict, b: dict) -> None:
    assert a["status"] == b["status"] == "ok", (a.get("error"), b.get("error"))
    assert math.isfinite(a["rollout_error"]) and a["rollout_error"] > 0
    na, nb = _numbers(a), _numbers(b)
    assert na.keys() == nb.keys()
    differ = [k for k in na if na[k] != nb[k]]
    assert not differ, {k: (na[k], nb[k]) for k in differ if k != "curves"} or "curves differ"


def test_same_config_twice_in_process_is_bit_identical(tmp_path):
    config = _config()
    a = execute_run(config, cache_root=tmp_path / "a")
    b = execute_run(config, cache_root=tmp_path / "b")
    assert not a["train_cached"] and not b["train_cached"]  # both trained from scratch
    _assert_identical(a, b)


@pytest.mark.slow
def test_same_config_twice_in_fresh_processes_is_bit_identical(tmp_path):
    rows = []
    for name in ("a", "b"):
        env = {**os.environ, "DECON_CACHE": str(tmp_path / f"cache_{name}")}
        out = subprocess.run(
            [sys.executable, "-m", "bench", "--results", str(tmp_path / name), "run",
             "--system", "chain_pendulum", "--k", "1", "--model", "node_so", "--profile", "smoke"],
            cwd=ROOT, env=env, capture_output=True, text=True, timeout=600,
        )  # fmt: skip
        assert out.returncode == 0, out.stderr
        (path,) = (tmp_path / name / ".rows").glob("*.json")
        rows.append(json.loads(path.read_text()))
    assert rows[0]["config_hash"] == _config().config_hash
    _assert_identical(*rows)
