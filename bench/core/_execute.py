"""One run as a pipeline of steps: build -> train -> evaluate -> record.

``execute_run(config)`` never raises (a storage error, which stops a sweep, aside): every
outcome is a row with ``status`` ``ok``, ``diverged`` (training went non-finite at
``diverged_step``) or ``failed`` (``error`` holds the message, the traceback is in the run's
artifact folder). The build, train and evaluate steps are those of the run's observation kind
(:class:`bench.core._observation.Observation`, the registered ones by name); an ensemble's
member is a variant of the train step, for the kinds that say how their runs train as members
(:class:`~bench.core._observation.Member`).
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import Any

import systems

from ._config import RunConfig
from ._errors import storage_error
from ._observation import Member, Observation, observation_kind
from ._record import (
    artifact_dir,
    base_row,
    close_row,
    open_artifacts,
    record_failure,
    save_arrays,
    training_columns,
)

# Member is named here too: the ensembles (bench.core._ensemble) read it as the executor's
__all__ = ["Member", "MemberSteps", "ensemble_member", "execute_run", "run_steps", "steps_of"]


def steps_of(config: RunConfig) -> Observation:
    """The steps of ``config``'s observation kind: the registered kind itself."""
    return observation_kind(config.observation)


@dataclasses.dataclass(frozen=True, eq=False)
class MemberSteps:
    """The steps of an ensemble's member: build and train done by the ensemble (``built`` as
    its kind's build step made it, ``trained`` its ``(model, meta)``), then its kind's evaluate
    step, on the test rollouts the ensemble did where it did them (``rolled``, state runs)."""

    kind: Observation
    built: Any
    trained: tuple
    rolled: Any = None

    def build(self, config: RunConfig, cache_root: Path):
        return self.built

    def train(self, config: RunConfig, built, cache_root: Path, progress: bool):
        return self.trained

    def evaluate(self, config: RunConfig, built, model, meta: dict, cache_root: Path):
        if self.rolled is None:
            return self.kind.evaluate(config, built, model, meta, cache_root)
        from ._evaluate import evaluate_state

        return evaluate_state(config, built, model, meta, cache_root, rolled=self.rolled)


def ensemble_member(steps: Observation, built, trained: tuple, rolled=None) -> MemberSteps:
    """The steps of an ensemble's member of kind ``steps``, built and trained by the ensemble:
    ``built`` as its build step made it, ``trained`` its ``(model, meta)`` (meta as
    :attr:`Member.record` returns it), ``rolled`` its test rollouts when the ensemble did them
    (state runs, :mod:`bench.core._ensemble`)."""
    return MemberSteps(steps, built, trained, rolled)


def run_steps(
    config: RunConfig, steps: Observation | MemberSteps, cache_root=None, progress=False
) -> dict:
    """Build, train and evaluate one run with ``steps``, and record its row (never raises,
    except for a storage error: a full disk stops the sweep, recording nothing)."""
    cache_root = Path(cache_root or systems.cache_root())
    row = base_row(config)
    art = artifact_dir(config.config_hash, cache_root)
    t_start, c_start = time.perf_counter(), time.process_time()
    try:
        open_artifacts(config, art)
        built = steps.build(config, cache_root)
        model, meta = steps.train(config, built, cache_root, progress)
        row.update(training_columns(meta))
        columns, arrays = steps.evaluate(config, built, model, meta, cache_root)
        row.update(columns)
        if arrays:
            save_arrays(art, arrays)
    except Exception as e:  # one run never stops the sweep...
        if storage_error(e):  # ...but a full disk does (bench.core._errors)
            raise
        record_failure(row, art, e)
    return close_row(row, art, t_start, c_start)


def execute_run(config: RunConfig, cache_root=None, progress=False) -> dict:
    """Run one configuration end to end and return its row (never raises).

    The row holds every RunConfig field, ``config_hash``, ``train_hash``, ``status``,
    ``diverged_step``, ``error``, the metrics, the costs, ``curves`` (small per-time curves,
    stored in the row file and expanded into curves.parquet) and, for a trained state run with
    ``eval_checkpoints``, ``checkpoints`` (its learning curve, expanded into
    checkpoints.parquet) with ``checkpoint_seconds``, the time they took.
    """
    return run_steps(config, steps_of(config), cache_root, progress)
