"""Interrupted training resumes where it was last saved.

A :class:`ResumePoint` is a folder (the parameter cache's ``params/<train_hash>/resume/``)
where :func:`bench.train` keeps its state at a block boundary every ``every`` seconds of
training: the parameters, the optimiser state, the last parameters with a finite loss, the
checkpoint snapshots taken so far, the losses, and the wall and CPU seconds spent. A later
training of the same configuration by the same code (the cache's code fingerprint; state saved
by other code is ignored, as cached parameters are) starts from there. The batch
stream is not stored: it is replayed (its ``take(k)`` called once per block already trained),
which every objective's stream allows, being a function of its seed and the number of draws.
A resumed training therefore ends with the parameters of the same training run in one go,
bit for bit (a test); a kill between two saves loses the blocks trained since the last one.

The state's files (``state-<step>.eqx``, ``losses-<step>.npy``) are written first and its
record (``resume.json``: step, costs, the files' names and sha256) last, each atomically, and
the previous files are removed after it: a kill at any moment leaves the previous state or the
new one. The folder is removed once the finished training is cached.
"""

from __future__ import annotations

import hashlib
import json
import shutil
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ._atomic import atomic_write, clear_orphans, write_json

RECORD = "resume.json"
EVERY_S = 300.0  # seconds of training between two saves


@dataclass(frozen=True)
class Resumed:
    """A training's saved state: ``done`` steps trained (a whole number of blocks of
    ``block`` steps), ``params``, ``opt_state``, ``good`` (as :func:`bench.train` carries
    them), ``snapshots`` ((step, train_seconds, params) of the checkpoints taken), the losses
    of the ``done`` steps, and the training's wall and CPU seconds until the save."""

    done: int
    block: int
    params: Any
    opt_state: Any
    good: Any
    snapshots: tuple
    losses: np.ndarray
    train_seconds: float
    cpu_seconds: float


class ResumePoint:
    """Where one training keeps its state (``folder``), saved at most every ``every`` seconds
    (default :data:`EVERY_S`; 0: at every block), for the code of fingerprint ``code`` (the
    parameter cache's :func:`bench.core._params.code_fingerprint`): a state saved for other
    code is ignored."""

    def __init__(self, folder, every: float | None = None, code: str = ""):
        every = EVERY_S if every is None else every
        if not (isinstance(every, int | float) and not isinstance(every, bool) and every >= 0):
            raise ValueError(f"ResumePoint.every must be a number of seconds >= 0, got {every!r}")
        self.folder, self.every, self.code = Path(folder), float(every), str(code)
        self._last = time.monotonic()

    def due(self) -> bool:
        """Whether ``every`` seconds have passed since the last save (or since this start)."""
        return time.monotonic() - self._last >= self.every

    def save(self, done, block, params, opt_state, good, snapshots, losses, seconds, cpu):
        """Keep the state after ``done`` steps in blocks of ``block``: ``params``,
        ``opt_state``, ``good`` as :func:`bench.train` carries them, its ``snapshots`` so far
        (:class:`bench.core._train_config.Snapshot`), its ``losses`` (a list of arrays), and
        the wall and CPU seconds spent."""
        import equinox as eqx

        snaps = [eqx.filter(s.model, eqx.is_inexact_array) for s in snapshots]
        losses = np.concatenate(losses) if losses else np.zeros(0)
        # files named by their step: the record (written last) names the pair it belongs to,
        # so a kill before it leaves the previous pair and record intact
        state, loss_file = self.folder / f"state-{done}.eqx", self.folder / f"losses-{done}.npy"
        tree = (params, opt_state, good, snaps)
        atomic_write(state, lambda tmp: eqx.tree_serialise_leaves(tmp, tree))
        atomic_write(loss_file, lambda tmp: np.save(tmp, losses))
        record = {
            "done": int(done),
            "block": int(block),
            "snapshots": [[int(s.step), float(s.train_seconds)] for s in snapshots],
            "n_losses": int(losses.size),
            "train_seconds": float(seconds),
            "cpu_seconds": float(cpu),
            "code": self.code,
            "state": state.name,
            "losses": loss_file.name,
            "sha256": _sha256(state),
            "losses_sha256": _sha256(loss_file),
        }
        write_json(self.folder / RECORD, record)
        for old in (*self.folder.glob("state-*.eqx"), *self.folder.glob("losses-*.npy")):
            if old.name not in (state.name, loss_file.name):
                old.unlink(missing_ok=True)
        self._last = time.monotonic()

    def load(self, params, opt_state, good, block: int) -> Resumed | None:
        """The saved state, shaped like ``params``, ``opt_state`` and ``good`` (a fresh
        training's), or None where there is none, it does not read back, other code saved it,
        or its blocks were not of ``block`` steps."""
        import equinox as eqx

        if self.folder.is_dir():
            clear_orphans(self.folder)  # a save that a kill cut short
        try:
            rec = json.loads((self.folder / RECORD).read_text())
            if rec.get("code") != self.code or rec.get("block") != block:
                return None
            state, loss_file = self.folder / rec["state"], self.folder / rec["losses"]
            if _sha256(state) != rec["sha256"] or _sha256(loss_file) != rec["losses_sha256"]:
                return None
            n = len(rec["snapshots"])
            like = (params, opt_state, good, [params] * n)
            p, o, g, snaps = eqx.tree_deserialise_leaves(state, like=like)
            losses = np.load(loss_file)
        except (OSError, ValueError, KeyError, TypeError, RuntimeError):
            return None
        if losses.size != rec["n_losses"] or rec["done"] % block:
            return None
        return Resumed(
            done=int(rec["done"]),
            block=block,
            params=p,
            opt_state=o,
            good=g,
            snapshots=tuple(
                (int(a), float(b), m) for (a, b), m in zip(rec["snapshots"], snaps, strict=True)
            ),
            losses=losses,
            train_seconds=float(rec["train_seconds"]),
            cpu_seconds=float(rec["cpu_seconds"]),
        )

    def clear(self) -> None:
        """Remove the saved state (the training it belonged to is finished and cached)."""
        shutil.rmtree(self.folder, ignore_errors=True)


def _sha256(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()
