"""The record step of a run: its row (the configuration, ``config_hash``, ``train_hash``, the
outcome, the training's and evaluation's columns, costs and provenance) and its artifact folder
``<cache>/runs/<config_hash>/`` (``config.json``, ``metrics.json``, ``curves.npz`` and, for a
failure, ``traceback.txt``)."""

from __future__ import annotations

import time
import traceback
from pathlib import Path

import numpy as np

import models
import systems

from ._atomic import atomic_write, write_json
from ._config import RunConfig
from ._errors import one_line
from ._provenance import provenance

# Row fields of the nested tables (curves.parquet, checkpoints.parquet), not in metrics.json.
NESTED = ("curves", "checkpoints")


def artifact_dir(config_hash: str, cache_root=None) -> Path:
    """Per-run artifacts: ``<cache>/runs/<config_hash>/``."""
    return Path(cache_root or systems.cache_root()) / "runs" / config_hash


def base_row(config: RunConfig) -> dict:
    """The row fields every run has, before any computation; a plug-in model's row also
    records the fingerprint of the plug-in's source (``plugin_source``,
    :func:`models.plugin_fingerprint`), which its ``config_hash`` does not cover."""
    row = config.to_dict()
    row.update(
        config_hash=config.config_hash,
        train_hash=config.train_hash,
        status="failed",
        diverged_step=None,
        error=None,
    )
    source = models.plugin_fingerprint(config.model)
    if source is not None:  # built-in rows keep their columns
        row["plugin_source"] = source
    return row


def _nan_if_none(x) -> float:
    return float("nan") if x is None else float(x)


def training_columns(meta: dict) -> dict:
    """The row columns of a train step's ``meta`` (:func:`bench.core._params.cached_training`)."""
    return dict(
        status=meta["status"],
        diverged_step=meta.get("diverged_step"),
        train_seconds=meta["train_seconds"],
        compile_seconds=meta["compile_seconds"],
        steps_done=meta.get("steps_done"),
        final_loss=meta.get("final_loss"),
        loss_rise=meta.get("loss_rise"),
        flops_per_step=_nan_if_none(meta.get("flops_per_step")),
        train_cached=meta["train_cached"],
        resumed_step=meta.get("resumed_step") or 0,
        # the interrupted part's CPU time belongs to this run only where this run trained
        resumed_cpu_seconds=0.0 if meta["train_cached"] else meta.get("resumed_cpu_seconds", 0.0),
    )


def open_artifacts(config: RunConfig, art: Path) -> None:
    """Start a run's artifact folder: its ``config.json``, no traceback of an earlier try."""
    art.mkdir(parents=True, exist_ok=True)
    write_json(art / "config.json", config.to_dict())
    (art / "traceback.txt").unlink(missing_ok=True)


def save_arrays(art: Path, arrays: dict) -> None:
    """The full per-trajectory curves of an evaluation, as ``curves.npz``."""
    atomic_write(art / "curves.npz", lambda tmp: np.savez_compressed(tmp, **arrays))


def record_failure(row: dict, art: Path, error: Exception) -> None:
    """Mark ``row`` failed with the error's message; its traceback goes to the artifacts."""
    row["status"] = "failed"
    row["error"] = one_line(error, 500)
    (art / "traceback.txt").write_text(traceback.format_exc())


def close_row(row: dict, art: Path, t_start: float, c_start: float) -> dict:
    """Add the costs and provenance to ``row``, write ``metrics.json``; return the row."""
    row["wall_seconds"] = time.perf_counter() - t_start
    # every thread of the process, plus an interrupted training's CPU time until its last save
    cpu = time.process_time() - c_start
    row["cpu_seconds"] = cpu + float(row.get("resumed_cpu_seconds") or 0.0)
    row.update(provenance())  # versions, device and commit: bench.core._provenance
    write_json(art / "metrics.json", {a: b for a, b in row.items() if a not in NESTED})
    return row
