"""One run as a pipeline of steps: build -> train -> evaluate -> record.

``execute_run(config)`` never raises (a storage error, which stops a sweep, aside): every
outcome is a row with ``status`` ``ok``, ``diverged`` (training went non-finite at
``diverged_step``) or ``failed`` (``error`` holds the message, the traceback is in the run's
artifact folder). The observation kinds, state, pixels, frames, measured and controlled, are
variants of the build, train and evaluate steps (:class:`Steps`); an ensemble's member is a
variant of the train step, for the kinds that say how their runs train as members
(:class:`Member`).
"""

from __future__ import annotations

import dataclasses
import functools
import importlib
import time
from collections.abc import Callable
from pathlib import Path

import systems

from ._build import build_run
from ._config import RunConfig
from ._errors import storage_error
from ._evaluate import evaluate_state
from ._fit import objective, train_cached, train_config
from ._record import (
    artifact_dir,
    base_row,
    close_row,
    open_artifacts,
    record_failure,
    save_arrays,
    training_columns,
)


@dataclasses.dataclass(frozen=True)
class Steps:
    """The steps of one kind of run, each a function of plain values:

    - ``build(config, cache_root) -> built``: the run's system, data and untrained model
      (``built``, a tuple whose layout is the kind's own);
    - ``train(config, built, cache_root, progress) -> (model, meta)``: the trained model and
      the training's record (:func:`bench.core._params.cached_training`);
    - ``evaluate(config, built, model, meta, cache_root) -> (columns, arrays)``: the row's
      metric columns (with ``curves``) and the arrays saved as ``curves.npz`` (may be empty).
    """

    build: Callable
    train: Callable
    evaluate: Callable
    member: Member | None = None  # how its runs train as an ensemble's members; None: alone


@dataclasses.dataclass(frozen=True)
class Member:
    """How the runs of one kind train as members of an ensemble (:mod:`bench.core._ensemble`),
    one program for runs that differ only in seed, learning rate or noise:

    - ``train_config(config) -> TrainConfig``: what its train step gives the one training loop
      (members share it up to ``seed`` and ``lr``);
    - ``inputs(config, built) -> (model, dataset, objective)``: what its train step fits;
    - ``record(config, result, cache_root) -> meta``: a member's :class:`bench.TrainResult` as
      its train step's meta (stored in the parameter cache where the kind caches);
    - ``rollouts``: its test rollouts run vmapped over the members
      (:func:`bench.core._ensemble.rollout_members`, state runs), else each member's own.
    """

    train_config: Callable
    inputs: Callable
    record: Callable
    rollouts: bool = False


def _build_state(config: RunConfig, cache_root: Path):
    return build_run(config, cache_root)


def _train_state(config: RunConfig, built, cache_root: Path, progress: bool):
    _, data, _, model = built
    return train_cached(config, model, data, cache_root, progress)


def _build_pixels(config: RunConfig, cache_root: Path):
    from ._pixels import build

    return build(config)


def _train_pixels(config: RunConfig, built, cache_root: Path, progress: bool):
    from ._pixels import train_cached_pixels

    _, data, model = built
    return train_cached_pixels(config, model, data, cache_root, progress)


def _evaluate_pixels(config: RunConfig, built, model, meta: dict, cache_root: Path):
    from ._pixel_eval import evaluate_pixels

    system, data, _ = built
    metrics, curves = evaluate_pixels(config, system, data, model)
    return {**metrics, "curves": curves}, {}


def _build_frames(config: RunConfig, cache_root: Path):
    from ._frames import build

    return build(config)


def _train_frames(config: RunConfig, built, cache_root: Path, progress: bool):
    from ._frames import train_cached_frames

    _, data, model = built
    return train_cached_frames(config, model, data, cache_root, progress)


def _evaluate_frames(config: RunConfig, built, model, meta: dict, cache_root: Path):
    from ._frames import evaluate_frames

    system, data, _ = built
    metrics, curves = evaluate_frames(config, system, data, model)
    return {**metrics, "curves": curves}, {}


def _module_steps(module: str, members: bool = False) -> Steps:
    """The steps of a kind whose module (imported at the first run, it pulls in its own
    libraries) defines ``build(config)``, ``train(config, built, cache_root, progress)`` and
    ``evaluate(config, built, model, meta, cache_root)``; with ``members``, also
    ``train_config``, ``member_inputs`` and ``record``, as :class:`Member` names them."""

    def load():
        return importlib.import_module(f".{module}", __package__)

    member = None
    if members:
        member = Member(
            train_config=lambda *a: load().train_config(*a),
            inputs=lambda *a: load().member_inputs(*a),
            record=lambda *a: load().record(*a),
        )
    return Steps(
        build=lambda config, cache_root: load().build(config),
        train=lambda *a: load().train(*a),
        evaluate=lambda *a: load().evaluate(*a),
        member=member,
    )


def _record_state(config: RunConfig, result, cache_root: Path) -> dict:
    from ._params import store_trained

    return store_trained(config, result, cache_root, train_config(config).checkpoints)


STATE = Steps(
    build=_build_state,
    train=_train_state,
    evaluate=evaluate_state,
    member=Member(
        train_config=train_config,
        inputs=lambda config, built: (built[3], built[1], objective(config)),
        record=_record_state,
        rollouts=True,
    ),
)
PIXELS = Steps(build=_build_pixels, train=_train_pixels, evaluate=_evaluate_pixels)
FRAMES = Steps(build=_build_frames, train=_train_frames, evaluate=_evaluate_frames)
MEASURED = _module_steps("_measured")
CONTROLLED = _module_steps("_controlled", members=True)
# RunConfig.observation -> its steps
OBSERVATIONS = {
    "state": STATE,
    "pixels": PIXELS,
    "frames": FRAMES,
    "measured": MEASURED,
    "controlled": CONTROLLED,
}


def steps_of(config: RunConfig) -> Steps:
    """The steps of ``config``'s observation kind."""
    return OBSERVATIONS.get(config.observation, STATE)  # an unknown one fails validation


def ensemble_member(steps: Steps, built, trained: tuple, rolled=None) -> Steps:
    """``steps`` of an ensemble's member, built and trained by the ensemble: ``built`` as its
    build step made it, ``trained`` its ``(model, meta)`` (meta as :attr:`Member.record`
    returns it), ``rolled`` its test rollouts when the ensemble did them (state runs,
    :mod:`bench.core._ensemble`)."""
    evaluate = steps.evaluate
    if rolled is not None:
        evaluate = functools.partial(evaluate_state, rolled=rolled)
    return dataclasses.replace(
        steps, build=lambda *_: built, train=lambda *_: trained, evaluate=evaluate
    )


def run_steps(config: RunConfig, steps: Steps, cache_root=None, progress=False) -> dict:
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
