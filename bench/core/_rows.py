"""The pieces of a run's row and artifacts that every executor shares (``bench.core._execute``
for state runs, ``bench.core._pixels`` for pixel runs): the artifact folder, atomic JSON, the
base row, and the test-rollout integrator."""

from __future__ import annotations

import json
from pathlib import Path

import systems

from . import _store
from ._experiments import RunConfig

EVAL_MAX_STEPS = 4096  # adaptive steps per test trajectory (100 points): ~40 per interval


def artifact_dir(config_hash: str, cache_root=None) -> Path:
    """Per-run artifacts: ``<cache>/runs/<config_hash>/``."""
    return Path(cache_root or systems.cache_root()) / "runs" / config_hash


def write_json(path: Path, obj) -> None:
    _store._atomic_write_bytes(path, json.dumps(_store._jsonable(obj), indent=1).encode())


def base_row(config: RunConfig) -> dict:
    """The row fields every run has, before any computation."""
    row = config.to_dict()
    row.update(
        config_hash=config.config_hash,
        train_hash=config.train_hash,
        status="failed",
        diverged_step=None,
        error=None,
    )
    return row


def eval_integrator(config: RunConfig):
    """The test-rollout integrator of a run (adaptive: at most EVAL_MAX_STEPS steps)."""
    import models

    return models.Integrator(
        config.eval_integrator,
        substeps=config.eval_substeps,
        rtol=config.eval_rtol,
        max_steps=EVAL_MAX_STEPS,
    )
