"""Ensembles: runs that differ only in seed, learning rate or noise train as one program, the
M-member training of the one training loop (:func:`bench.core._train.drive`: the one step of
their objective mapped over members in one ``lax.scan``; a single run is its one-member case).
Each member keeps its own batches and divergence flags, so member m is the single run of its
config up to float32 round-off. An ensemble is a variant of a run's train step
(:func:`bench.core._execute.ensemble_member`), for the observation kinds that declare how their
runs train as members (:class:`bench.core._execute.Member`: state and controlled runs): a
member's row is the row of its single run, plus ``ensemble_size``, with 1/M of the ensemble's
``train_seconds``, ``compile_seconds`` and ``flops_per_step``. Here: which runs group
(:func:`group_key`, :func:`plan_groups`), their training (:func:`train_ensemble`), their test
rollouts as one program and the execution of a group (:func:`execute_group`).
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path

import systems

from ._config import RunConfig, check_choice
from ._errors import one_line, storage_error
from ._params import cache_key, cached_params_meta, params_dir
from ._train_config import shared_config

MODES = ("auto", "on", "off")
# RunConfig fields that may differ between the members of one ensemble (no shape changes).
ENSEMBLE_FIELDS = ("seed", "lr", "noise")
MAX_SIZE = 20


def enabled(mode: str) -> bool:
    """``on``/``off`` as said; ``auto``: on when jax's default backend is an accelerator."""
    check_choice("ensemble", mode, MODES)
    if mode != "auto":
        return mode == "on"
    import jax

    return jax.default_backend() != "cpu"


# ------------------------------------------------------------------------------ training
def train_ensemble(models: Sequence, datasets: Sequence, configs: Sequence, objective=None):
    """Train ``models[m]`` on ``datasets[m]`` with ``configs[m]`` as one program, each fitting
    ``objective`` (default :data:`bench.core._objective.STATES`, the datasets' chunks of
    states): the M-member training of the one training loop (:func:`bench.core._train.drive`).

    Returns one :class:`bench.TrainResult` per member, each as :func:`bench.train` would
    return it for that member alone (``train_seconds``, ``compile_seconds``,
    ``flops_per_step``: 1/M of the ensemble's). ValueError when the members' configs differ in
    more than seed and lr, or their models or data differ in structure or shape. No progress
    bar and no resume: those are a single run's.
    """
    from ._objective import STATES
    from ._train import drive

    if not (len(models) == len(datasets) == len(configs)):
        raise ValueError("train_ensemble needs as many datasets and configs as models")
    return drive(models, datasets, configs, STATES if objective is None else objective)


# ------------------------------------------------------------------------------ grouping
def _kind(config: RunConfig):
    """How runs of ``config``'s observation kind train as members
    (:class:`bench.core._execute.Member`), or None where they train alone."""
    from ._execute import steps_of

    return steps_of(config).member


def group_key(config: RunConfig) -> str:
    """The fields an ensemble's members share: all but ``ENSEMBLE_FIELDS`` and ``eval_*``, and
    the training configuration their kind gives the one loop, up to seed and learning rate (so
    that a setting derived from the rate, such as a schedule's floor, parts the groups)."""
    d = {
        a: b
        for a, b in config.to_dict().items()
        if a not in ENSEMBLE_FIELDS and not a.startswith("eval_")
    }
    member = _kind(config)
    if member is not None:
        d["train_config"] = repr(shared_config([member.train_config(config)]))
    return json.dumps(d, sort_keys=True, default=str)


def _trivial_names() -> frozenset:
    import models

    return frozenset(models.trivial_models())


def plan_groups(
    configs: Sequence[RunConfig], cache_root=None, max_size: int = MAX_SIZE
) -> list[list[RunConfig]]:
    """Cut pending runs into ensembles (lists of >= 1 run), order kept within each group.

    Runs with one :func:`group_key` form one group (cut into groups of at most ``max_size``).
    Runs whose parameters are cached under ``cache_root``, second runs of one ``train_hash``
    (they differ only in evaluation), trivial predictors (nothing to train), runs of a kind
    that declares no :class:`bench.core._execute.Member` (pixels, frames, measured) and runs
    with fresh states of a ``train_box`` (objectives of their own) come last, alone. Not
    grouped: ``loss`` (a static choice
    of the loss function) and options held by the model (e.g. a regulariser weight inside
    ``model_options``, a static field of the model).
    """
    if isinstance(max_size, bool) or not isinstance(max_size, int) or max_size < 1:
        raise ValueError(f"ensemble size must be an integer >= 1; got {max_size!r}")
    groups: dict[str, list[RunConfig]] = {}
    alone: list[list[RunConfig]] = []
    trains: set[str] = set()
    for c in configs:
        cached = (
            cache_root is not None
            and cached_params_meta(params_dir(cache_root, cache_key(c))) is not None
        )
        # train_box runs fit fresh states of their own (bench.core._box): alone
        own = _kind(c) is None or bool(c.train_box)
        if cached or c.train_hash in trains or c.model in _trivial_names() or own:
            alone.append([c])
            continue
        trains.add(c.train_hash)
        groups.setdefault(group_key(c), []).append(c)
    out = []
    for members in groups.values():
        out.extend(members[i : i + max_size] for i in range(0, len(members), max_size))
    return out + alone


# --------------------------------------------------------------------------- evaluation
def rollout_members(configs: Sequence[RunConfig], datasets: Sequence, models: Sequence) -> list:
    """The test rollouts of every member as one program (vmap over members).

    Member m rolls out ``models[m]`` from its own test states ``datasets[m].z_test[:, 0]``
    with the evaluation integrator of ``configs[m]`` (all members must share it). Returns,
    per member, ``(pred, stats, rollout_seconds, eval_compile_seconds)`` as
    :func:`bench.core._evaluate.evaluate_state` takes them (seconds: 1/M of the ensemble's).
    """
    import equinox as eqx
    import jax
    import jax.numpy as jnp

    import models as M

    from ._evaluate import eval_integrator
    from ._train import _member, _stack

    c = configs[0]
    integ = eval_integrator(c)
    if any(eval_integrator(x) != integ or x.random_args != c.random_args for x in configs):
        raise ValueError("ensemble members must share their evaluation settings")
    dtype = jnp.dtype(c.dtype)
    z0s = jnp.stack([jnp.asarray(d.z_test[:, 0], dtype) for d in datasets])
    ts = jnp.stack([jnp.asarray(d.ts_test, dtype) for d in datasets])
    args = None
    if c.random_args:
        args = jnp.stack([jnp.asarray(d.args_test, dtype) for d in datasets])
    parts = [eqx.partition(m, eqx.is_inexact_array) for m in models]
    static = parts[0][1]
    params = _stack([p for p, _ in parts])

    def one(p, z0s, ts, args):
        model = eqx.combine(p, static)
        return M.rollout_batch(model, z0s, ts, args, integ, return_stats=True)

    roll = eqx.filter_jit(jax.vmap(one, in_axes=(0, 0, 0, None if args is None else 0)))
    t0 = time.perf_counter()
    jax.block_until_ready(roll(params, z0s, ts, args))  # compile + first run
    t1 = time.perf_counter()
    pred, stats = jax.block_until_ready(roll(params, z0s, ts, args))
    seconds = time.perf_counter() - t1
    compile_seconds = max(0.0, (t1 - t0) - seconds)
    n = len(models)
    return [(pred[i], _member(stats, i), seconds / n, compile_seconds / n) for i in range(n)]


# ---------------------------------------------------------------------------- execution
def execute_group(configs: Sequence[RunConfig], cache_root=None) -> list[dict]:
    """Train ``configs`` (runs of one :func:`group_key`) as one ensemble, then evaluate each
    member with its kind's steps; one row per run.

    Never raises for a run's failure: when the ensemble cannot be built or trained (a bad
    config, a failed dataset), every member runs alone and records its own outcome; when the
    vmapped test rollouts fail, each member rolls out alone. A storage error (full disk)
    propagates, as in :func:`bench.core._execute.execute_run`.
    """
    from ._execute import ensemble_member, execute_run, run_steps, steps_of

    cache_root = Path(cache_root or systems.cache_root())
    configs = list(configs)
    steps = steps_of(configs[0]) if configs else None
    member = steps.member if steps else None
    built: list = [None] * len(configs)
    trained: list = [None] * len(configs)
    rolled: list = [None] * len(configs)
    c_start, t_start = time.process_time(), time.perf_counter()
    if len(configs) > 1 and member is not None:
        try:
            built = [steps.build(c, cache_root) for c in configs]
            fits = [member.inputs(c, b) for c, b in zip(configs, built, strict=True)]
            if len({objective for _, _, objective in fits}) != 1:
                raise ValueError("ensemble members must fit one objective")
            results = train_ensemble(
                [model for model, _, _ in fits],
                [data for _, data, _ in fits],
                [member.train_config(c) for c in configs],
                fits[0][2],
            )
            trained = [
                (res.model, member.record(c, res, cache_root))
                for c, res in zip(configs, results, strict=True)
            ]
        except Exception as e:
            if storage_error(e):
                raise
            print(
                f"ensemble of {len(configs)} runs fell back to single runs: {one_line(e, 300)}",
                file=sys.stderr,
            )
            trained = [None] * len(configs)
        if trained[0] is not None and member.rollouts:
            try:
                rolled = rollout_members(configs, [d for _, d, _ in fits], [t[0] for t in trained])
            except Exception as e:
                if storage_error(e):
                    raise
                print(
                    f"ensemble rollouts fell back to single ones: {one_line(e, 300)}",
                    file=sys.stderr,
                )
    # training and rollouts, split among the members
    shared = (time.process_time() - c_start) / len(configs)
    shared_wall = (time.perf_counter() - t_start) / len(configs)
    rows = []
    for c, b, t, r in zip(configs, built, trained, rolled, strict=True):
        if t is None:  # trained alone
            row = execute_run(c, cache_root=cache_root)
        else:  # built and trained (and the state runs' test rollouts done) by the ensemble
            row = run_steps(c, ensemble_member(steps, b, t, r), cache_root)
        row["ensemble_size"] = 1 if t is None else len(configs)
        row["cpu_seconds"] = row.get("cpu_seconds", 0.0) + shared
        row["wall_seconds"] = row.get("wall_seconds", 0.0) + shared_wall
        rows.append(row)
    return rows


def _execute_group_dicts(dicts: list[dict], cache_root: str | None = None) -> list[dict]:
    """Ray/pool task: one ensemble from plain dicts."""
    return execute_group([RunConfig.from_dict(d) for d in dicts], cache_root=cache_root)
