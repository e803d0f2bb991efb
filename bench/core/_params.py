"""The parameter cache, shared by state and pixel runs: ``<cache>/params/<key>/`` holds a
trained model (``model.eqx``), its record (``train.json``: the training's outcome, the sha256 of
``model.eqx``, the fingerprint of the code that trained it), the losses and the checkpoint
snapshots. Runs that differ only in evaluation train once; an entry whose checksum fails, or
that other code trained (``train_hash`` covers the configuration, not the code), is retrained.

The key (:func:`cache_key`) is the configuration's ``train_hash``; a plug-in model's adds the
fingerprint of the plug-in's source (:func:`models.plugin_fingerprint`), which the suite's
code fingerprint does not cover: parameters trained before a plug-in was edited are never
loaded into the edited code."""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from pathlib import Path

import numpy as np

import models
from systems import source_fingerprint

from ._atomic import atomic_write, write_json
from ._config import RunConfig
from ._resume import ResumePoint

# The packages whose source cached parameters and floors depend on (the models, the data's
# physics, training and metrics). A cache entry records their fingerprint and is discarded when
# any of their files changed since.
TRAIN_CODE = ("models", "systems", "bench.core")
RESUME = "resume"  # under an entry: the state of its training while it runs (bench.core._resume)
DATA_TAG = "+data:"  # joins a resume state's code fingerprint to its data's sha256


def code_fingerprint() -> str:
    """:func:`systems.source_fingerprint` of :data:`TRAIN_CODE`."""
    return source_fingerprint(*TRAIN_CODE)


def sha256_file(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def params_dir(cache_root, train_hash: str) -> Path:
    """``<cache_root>/params/<train_hash>/`` (``train_hash``: a :func:`cache_key`)."""
    return Path(cache_root) / "params" / train_hash


def cache_key(config: RunConfig) -> str:
    """The key of ``config``'s parameters in the cache: its ``train_hash`` for a built-in
    model; ``<train_hash>-<fingerprint>`` for a plug-in model, the fingerprint that of the
    plug-in's source as this process imported it (:func:`models.plugin_fingerprint`), so that
    an edited plug-in trains anew and its earlier parameters stay under their own key."""
    source = models.plugin_fingerprint(config.model)
    return config.train_hash if source is None else f"{config.train_hash}-{source}"


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


def _load_snapshots(pdir: Path, meta: dict, checkpoints: tuple, like, final) -> tuple:
    """The cached snapshots of a training whose checkpoints were ``checkpoints`` (ValueError,
    so that the run retrains, when they were others or their file is damaged)."""
    import equinox as eqx

    from ._train_config import Snapshot

    if not checkpoints:
        return ()
    if meta.get("checkpoints") != list(checkpoints):
        raise ValueError("the cached training kept other checkpoints")
    kept = meta.get("snapshots") or []
    inner = [s for s in kept if s[0] < meta["steps_done"] or meta["status"] != "ok"]
    models = []
    if inner:
        sfile = pdir / "snapshots.eqx"
        if meta.get("snapshots_sha256") != sha256_file(sfile):
            raise ValueError("the cached snapshots are damaged")
        models = eqx.tree_deserialise_leaves(sfile, like=[like] * len(inner))
    out = [Snapshot(int(a), float(b), m) for (a, b), m in zip(inner, models, strict=True)]
    if len(kept) > len(inner):  # the last snapshot is the final model
        out.append(Snapshot(int(kept[-1][0]), float(kept[-1][1]), final))
    return tuple(out)


# the stretches of a training trace whose medians loss_rise compares
RISE_STRETCHES = 50
# a run whose loss_rise is above this ended a decade above its best: a finite blow-up (the
# median of a stretch of batch losses of a run that trains moves well under 2x between
# neighbouring stretches, and a cosine schedule ends at the lowest rate)
BLOW_UP_RISE = 10.0


def loss_rise(losses) -> float | None:
    """How far training ended above its best: the median loss of the last of
    :data:`RISE_STRETCHES` equal stretches of the trace (fewer for a shorter one) over the lowest
    such median. About 1 where the loss ends at its best; orders of magnitude above 1 where
    training blew up and the loss stayed finite, which the ``diverged`` status (a non-finite
    loss) does not see. Non-finite losses are left out; None with fewer than 2 finite ones."""
    x = np.asarray(losses, dtype=np.float64)
    x = x[np.isfinite(x)]
    if x.size < 2:
        return None
    medians = np.array([np.median(s) for s in np.array_split(x, min(RISE_STRETCHES, x.size))])
    best = float(medians.min())
    if best <= 0.0:  # a loss that reached 0 exactly: any rise is infinite, none is 1
        return 1.0 if medians[-1] <= 0.0 else float("inf")
    return float(medians[-1] / best)


def result_meta(res) -> dict:
    """A :class:`bench.TrainResult`'s outcome and costs as the row's training fields
    (``final_loss``: the last finite loss, None without one; ``loss_rise``: :func:`loss_rise`)."""
    losses = np.asarray(res.losses, dtype=np.float64)
    return {
        "status": res.status,
        "diverged_step": res.diverged_step,
        "train_seconds": float(res.train_seconds),
        "compile_seconds": float(res.compile_seconds),
        "steps_done": int(res.steps_done),
        "flops_per_step": float(res.flops_per_step),
        "final_loss": float(losses[np.isfinite(losses)][-1]) if np.isfinite(losses).any() else None,
        "loss_rise": loss_rise(losses),
        "resumed_step": int(getattr(res, "resumed_step", 0)),
        "resumed_cpu_seconds": float(getattr(res, "resumed_cpu_seconds", 0.0)),
    }


def store_trained(config: RunConfig, res, cache_root: Path, checkpoints: tuple = ()) -> dict:
    """Write a :class:`bench.TrainResult` (trained keeping ``checkpoints``) to
    ``params/<key>/`` (:func:`cache_key`); return its meta, as :func:`cached_training` returns
    it."""
    import equinox as eqx

    pdir = params_dir(cache_root, cache_key(config))
    losses = np.asarray(res.losses, dtype=np.float64)
    meta = {**result_meta(res), "code": code_fingerprint()}
    atomic_write(pdir / "model.eqx", lambda tmp: eqx.tree_serialise_leaves(tmp, res.model))
    meta["sha256"] = sha256_file(pdir / "model.eqx")
    snaps = tuple(getattr(res, "snapshots", ()))
    meta["checkpoints"] = list(checkpoints)
    meta["snapshots"] = [[s.step, float(s.train_seconds)] for s in snaps]
    inner = [s for s in snaps if s.step < res.steps_done or res.status != "ok"]
    if inner:  # the final model is model.eqx already
        models = [s.model for s in inner]
        atomic_write(pdir / "snapshots.eqx", lambda tmp: eqx.tree_serialise_leaves(tmp, models))
        meta["snapshots_sha256"] = sha256_file(pdir / "snapshots.eqx")
    write_json(pdir / "train.json", meta)
    atomic_write(pdir / "losses.npy", lambda tmp: np.save(tmp, losses))
    meta["train_cached"] = False
    meta["_snapshots"] = snaps
    return meta


def cached_training(
    config: RunConfig, like, cache_root: Path, fit: Callable, checkpoints: tuple = ()
) -> tuple:
    """``(model, meta)``: the parameters cached under :func:`cache_key` (with the snapshots
    of ``checkpoints``; ``like`` gives their structure) where they hold, else those of
    ``fit(resume)`` (a :class:`bench.TrainResult`; ``resume``, the entry's
    :class:`bench.core._resume.ResumePoint`, goes to :func:`bench.train`, so that a killed
    training goes on from its last saved state), stored. ``meta["train_cached"]`` says which;
    ``meta["_snapshots"]`` holds the checkpoint snapshots."""
    import equinox as eqx

    pdir = params_dir(cache_root, cache_key(config))
    meta = cached_params_meta(pdir)
    if meta is not None:
        try:
            loaded = eqx.tree_deserialise_leaves(pdir / "model.eqx", like=like)
            meta["_snapshots"] = _load_snapshots(pdir, meta, checkpoints, like, loaded)
            meta["train_cached"] = True
            return loaded, meta
        except Exception:  # a corrupt cache entry, or one without these checkpoints: retrain
            pass
    resume = resume_point(config, cache_root)
    res = fit(resume)
    meta = store_trained(config, res, cache_root, checkpoints)
    resume.clear()
    return res.model, meta


def resume_point(config: RunConfig, cache_root: Path, data: str = "") -> ResumePoint:
    """Where the training of ``config`` keeps its state while it runs
    (``params/<key>/resume/``, :func:`cache_key`), for this code and, where the configuration
    does not name its data, for the data of sha256 ``data``: a state saved for other code or
    data is ignored."""
    code = code_fingerprint() + (f"{DATA_TAG}{data}" if data else "")
    return ResumePoint(params_dir(cache_root, cache_key(config)) / RESUME, code=code)


def saved_by_this_code(saved: str) -> bool:
    """Whether a state saved with ``code`` ``saved`` (:func:`resume_point`) was saved by the
    code that runs now, whatever data it names."""
    return str(saved).partition(DATA_TAG)[0] == code_fingerprint()


def resumable_training(config: RunConfig, cache_root: Path, fit: Callable, data: str = ""):
    """``fit(resume)`` (a :class:`bench.TrainResult`) for a training that is not cached: a
    killed one goes on from its last saved state (:func:`resume_point`), and the state is
    removed once it ends."""
    resume = resume_point(config, cache_root, data)
    res = fit(resume)
    resume.clear()
    return res
