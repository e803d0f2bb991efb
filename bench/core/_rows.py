"""The pieces of a run's row and artifacts that every executor shares (``bench.core._execute``
for state runs, ``bench.core._pixels`` for pixel runs): the artifact folder, atomic JSON, the
base row, the test-rollout integrator, and the checks of a cached training."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import systems
from systems._dataset import source_fingerprint

from . import _store
from ._experiments import RunConfig

EVAL_MAX_STEPS = 4096  # adaptive steps per test trajectory (100 points): ~40 per interval


def artifact_dir(config_hash: str, cache_root=None) -> Path:
    """Per-run artifacts: ``<cache>/runs/<config_hash>/``."""
    return Path(cache_root or systems.cache_root()) / "runs" / config_hash


def write_json(path: Path, obj) -> None:
    _store._atomic_write_bytes(path, json.dumps(_store._jsonable(obj), indent=1).encode())


# The packages whose source cached parameters and floors depend on (the models, the data's
# physics, training and metrics). A cache entry records their fingerprint and is discarded when
# any of their files changed since: ``train_hash`` covers the configuration, not the code.
TRAIN_CODE = ("models", "systems", "bench.core")


def code_fingerprint() -> str:
    """:func:`systems._dataset.source_fingerprint` of :data:`TRAIN_CODE`."""
    return source_fingerprint(*TRAIN_CODE)


def sha256_file(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def cached_params_meta(pdir: Path) -> dict | None:
    """The ``train.json`` of the parameters cached in ``pdir``, or None where there are none,
    ``model.eqx`` fails its checksum, or other code trained them (:func:`code_fingerprint`)."""
    pfile, meta_file = Path(pdir) / "model.eqx", Path(pdir) / "train.json"
    try:
        meta = json.loads(meta_file.read_text())
        if meta.get("code") == code_fingerprint() and meta.get("sha256") == sha256_file(pfile):
            return meta
    except (OSError, ValueError):
        pass
    return None


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
