"""Sweeps: execute many runs, skipping the stored ones, and write each row as it arrives.

``sweep(configs, results_dir, ...)`` skips the config hashes already stored, executes the rest
with the local executor (in-process, or a spawn pool whose workers each get cores / workers
XLA threads) or Ray, and writes each row as it arrives (see ``bench.core._store``). One run is
executed by :func:`bench.core._execute.execute_run` (re-exported here). A local sweep whose
``$DECON_DRAIN`` file exists starts no new run and ends once the runs in flight are stored.
"""

from __future__ import annotations

import dataclasses
import os
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import models
import systems

from . import _store
from ._config import RunConfig
from ._env import bound_compiled_programs, cpu_count
from ._errors import StorageError, WorkerDied, one_line, storage_error
from ._evaluate import EVAL_MAX_STEPS, eval_integrator, to_velocity
from ._execute import execute_run
from ._record import artifact_dir, base_row

__all__ = [
    "EVAL_MAX_STEPS",
    "EXECUTORS",
    "artifact_dir",
    "base_row",
    "eval_integrator",
    "execute_run",
    "run_experiments",
    "sweep",
    "to_velocity",
]

EXECUTORS = ("local", "ray")
REBUILD_SECONDS = 20.0  # a sweep rebuilds the tables from the rows at most this often
# A file whose existence drains a local sweep: the runs in flight finish and are stored, no new
# one starts (``make paper-core-drain``, before a machine is handed back).
DRAIN_ENV = "DECON_DRAIN"


def draining() -> bool:
    """Whether ``$DECON_DRAIN`` names a file that exists: start no new run."""
    path = os.environ.get(DRAIN_ENV)
    return bool(path) and Path(path).exists()


def _execute_dict(d: dict, cache_root: str | None = None) -> dict:
    return execute_run(RunConfig.from_dict(d), cache_root=cache_root)


# ---------------------------------------------------------------------------------- sweeps
def _label(c: RunConfig) -> str:
    k = "" if c.k is None else f"-{c.k}"
    f = f" f={c.friction:g}" if c.friction else ""
    return f"{c.system}{k}{f} {c.model} s{c.seed}"


def _schedule(todo: list[RunConfig], order: Callable[[RunConfig], float]) -> list[RunConfig]:
    """The runs longest first by ``order``, with the first run of every cell (runs equal but
    for their seed, which compile the same XLA programs) ahead of the cells' other seeds.

    Seeds of one cell started side by side compile the same programs at the same time, each
    before the other has filled the persistent compilation cache: on a cold cache (a fresh
    clone) the second compile is wasted (4 of the 26 CPU minutes of compilation of quick's
    seeds 0-4 in one measured sweep). Sorting is stable: equal keys keep their order.
    A key that is a tuple (``bench.studies.paper.campaign._campaign.priority``: claim rank, seconds)
    keeps its leading parts first: the rule applies within each of their groups.
    """
    firsts: set[str] = set()
    first = []
    for c in todo:
        cell = dataclasses.replace(c, seed=0).config_hash
        first.append(cell not in firsts)
        firsts.add(cell)

    def key(fc):
        k = order(fc[1])
        group, seconds = (tuple(k[:-1]), k[-1]) if isinstance(k, tuple) else ((), k)
        return (group, fc[0], seconds)

    ranked = sorted(zip(first, todo, strict=True), key=key, reverse=True)
    return [c for _, c in ranked]


def _edited_plugin_runs(results_dir: Path, configs: Sequence[RunConfig]) -> set[str]:
    """config_hash of the stored runs of ``configs`` whose model is a plug-in edited since:
    their row records another fingerprint of the plug-in's source (``plugin_source``, none in
    a row stored without it) than the one this process imported. They are run again (the
    parameter cache keys their training by that source too) and their rows replaced; a note
    on stderr names them. Without plug-in models in ``configs`` no row is read."""
    now = {c.config_hash: models.plugin_fingerprint(c.model) for c in configs}
    now = {h: source for h, source in now.items() if source is not None}
    if not now:
        return set()
    stale = {
        r["config_hash"]: r["model"]
        for r in _store.read_rows(results_dir)
        if r["config_hash"] in now and r.get("plugin_source") != now[r["config_hash"]]
    }
    if stale:
        names = ", ".join(sorted(set(stale.values())))
        print(
            f"{len(stale)} stored run(s) of plug-in model(s) {names} ran other source of the "
            "plug-in than the one loaded now: running them again, their rows replaced",
            file=sys.stderr,
        )
    return set(stale)


def sweep(
    configs: Sequence[RunConfig],
    results_dir="results",
    *,
    experiment: str | Mapping[str, str] = "adhoc",
    profile: str = "custom",
    executor: str = "local",
    workers: int | None = 1,
    address: str | None = None,
    progress: bool = True,
    cache_root=None,
    ensemble: str = "auto",
    ensemble_max: int = 20,
    order: Callable[[RunConfig], float] | None = None,
) -> list[dict]:
    """Execute the runs of ``configs`` not yet in ``results_dir``; return the new rows.

    ``workers``: local processes (1 = in-process; None = one per core). Each finished row is
    written atomically as it arrives and the tables are rebuilt, so a killed sweep resumes.

    Before anything is written, every run to execute is checked by
    :func:`bench.core._runnable.check_runnable` (ValueError for a run the models cannot run,
    e.g. leapfrog on a first-order model; the configurations checked themselves when built).
    A write that fails for want of space or permission (in a run or when storing its row)
    stops the sweep with :class:`bench.core._errors.StorageError`; the rows stored so far are
    whole and the next sweep resumes. A damaged row file counts as not done (see
    :func:`bench.core._store.scan_rows`): its run is executed again, as is a stored run of a
    plug-in model whose source changed since (:func:`_edited_plugin_runs`).

    ``ensemble`` (``auto``, ``on``, ``off``; ``auto``: on when jax's default backend is an
    accelerator): train runs that differ only in seed, lr or noise as ensembles of at most
    ``ensemble_max`` members, one per task (see ``bench.core._ensemble``).

    ``experiment``: the name every new row is tagged with, or a mapping config_hash -> name
    (several experiments swept as one, :func:`run_experiments`). ``order``: an estimate of a
    run's seconds; the runs then start longest first, so that the workers finish together,
    one run of every cell before the cell's other seeds (:func:`_schedule`).
    """
    from ._config import check_choice
    from ._runnable import check_runnable

    if isinstance(experiment, Mapping):
        tags, label = dict(experiment), "sweep"
    else:
        tags, label = {}, experiment

    check_choice("executor", executor, EXECUTORS)
    existed = Path(results_dir).is_dir()
    # ValueError: a file, under a file, not writable; a missing folder is made further down
    results_dir = _store.check_results_dir(results_dir, create=False)
    cache_root = Path(cache_root or systems.cache_root()).resolve()
    done = _store.done_hashes(results_dir) - _edited_plugin_runs(results_dir, configs)
    todo, seen = [], set()
    for c in configs:
        if c.config_hash not in done and c.config_hash not in seen:
            seen.add(c.config_hash)
            todo.append(c)
    for c in todo:  # before anything is written, the results folder included
        try:
            check_runnable(c)
        except ValueError as e:
            raise ValueError(f"run {_label(c)} ({c.config_hash}): {e}") from None
    if not existed:
        _store.check_results_dir(results_dir)
    for d in (results_dir, results_dir / _store.ROWS):  # a killed sweep's half-written files
        _store.clear_orphans(d)
    if order is not None:
        todo = _schedule(todo, order)
    if todo:
        _store.check_results_dir(cache_root, what="cache folder ($DECON_CACHE)")
    new_rows: list[dict] = []
    if not todo:
        if progress:
            print(f"{label}: all {len(configs)} runs already stored", file=sys.stderr)
        _store.rebuild_tables(results_dir)
        return new_rows

    if draining():
        print(f"{label}: draining (${DRAIN_ENV} exists): no run started", file=sys.stderr)
        return new_rows

    from tqdm.auto import tqdm

    bar = tqdm(total=len(todo), desc=f"{label} [{profile}]", unit="run", disable=not progress)

    last_rebuild = [time.perf_counter()]

    def finish(row: dict) -> None:
        row.setdefault("ensemble_size", 1)
        row["experiment"] = tags.get(row["config_hash"], label)
        row["profile"] = profile
        _store.write_row(results_dir, row)
        # the rows are the truth; the tables are rebuilt from them at most every
        # REBUILD_SECONDS while the sweep goes on (reading every row each time is quadratic),
        # and once at its end
        if time.perf_counter() - last_rebuild[0] > REBUILD_SECONDS:
            _store.rebuild_tables(results_dir)
            last_rebuild[0] = time.perf_counter()
        new_rows.append(row)
        bar.update(1)
        bar.set_postfix_str(f"last: {row['model']} {row['status']}")

    # ---- ensembles (bench.core._ensemble): groups of runs trained as one program
    from . import _ensemble

    groups = [[c] for c in todo]
    if _ensemble.enabled(ensemble):
        groups = _ensemble.plan_groups(todo, cache_root, ensemble_max)
    # ----
    cores = cpu_count()
    try:
        if executor == "ray":
            _sweep_ray(groups, finish, cache_root, address, cores)
        else:
            workers = cores if workers is None else max(1, int(workers))
            workers = min(workers, len(groups))
            if workers == 1:
                for g in groups:
                    if draining():
                        break
                    bar.set_postfix_str(_label(g[0]) + (f" +{len(g) - 1}" if len(g) > 1 else ""))
                    if len(g) == 1:
                        finish(execute_run(g[0], cache_root=cache_root, progress=False))
                    else:
                        for row in _ensemble.execute_group(g, cache_root=cache_root):
                            finish(row)
                    bound_compiled_programs()
            else:
                _sweep_pool(groups, finish, cache_root, workers, cores)
        _store.rebuild_tables(results_dir)
    except Exception as e:
        if new_rows:  # the tables show every stored row however the sweep ends (best effort)
            try:
                _store.rebuild_tables(results_dir)
            except Exception:  # noqa: BLE001 - the rows are the truth; the next sweep rebuilds
                pass
        err = storage_error(e)
        if err is None:
            raise
        where = f" {err.filename}" if err.filename else ""
        raise StorageError(
            f"could not write{where}: {err.strerror or err} (disk full or a file-size limit?); "
            f"{label} stopped after {len(new_rows)} new of {len(todo)} runs; the rows "
            f"stored in {results_dir} are whole: run it again to resume"
        ) from e
    finally:
        bar.close()
    return new_rows


def worker_pool(workers: int):
    """A pool of ``workers`` spawned processes, each pinned to its own share of the cores (an
    affinity mask, which sizes XLA's thread pools) in its initializer, before it imports jax:
    no oversubscription. The sweep's pool, and the stability study's; use it with
    :func:`imap_unordered`. A ``concurrent.futures`` pool, not ``multiprocessing.Pool``: when a
    worker dies, ``multiprocessing.Pool`` replaces it and waits forever for the lost task (a
    campaign would hang at nice 19, unseen), where this one raises."""
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    ctx = mp.get_context("spawn")
    available = sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else []
    share = max(1, len(available) // workers) if available else 1
    slots = ctx.Queue()
    for i in range(workers):
        slots.put(available[i * share : (i + 1) * share] or None)
    return ProcessPoolExecutor(workers, mp_context=ctx, initializer=_pin_worker, initargs=(slots,))


def imap_unordered(pool, fn, jobs):
    """``fn(job)`` for every job on ``pool`` (:func:`worker_pool`), started in the order given,
    yielded as they finish. A worker that dies raises :class:`WorkerDied` (one line) instead of
    leaving the caller waiting; the jobs not started are cancelled."""
    from concurrent.futures import as_completed
    from concurrent.futures.process import BrokenProcessPool

    futures = [pool.submit(fn, job) for job in jobs]
    done = 0
    try:
        for f in as_completed(futures):
            result = f.result()
            done += 1
            yield result
    except BrokenProcessPool:
        _stop(pool, futures)
        raise WorkerDied(
            f"a worker process died (killed by the OS: out of memory? or a crash in native "
            f"code) after {done} of {len(futures)} jobs finished; what finished is stored: "
            "run it again to resume"
        ) from None
    except BaseException:  # a failed write, an interrupt, the caller stopping: stop at once
        _stop(pool, futures)
        raise


def _stop(pool, futures) -> None:
    """Cancel the jobs not started and end the workers, as ``multiprocessing.Pool``'s exit did
    (``ProcessPoolExecutor`` would otherwise finish the runs in flight first)."""
    for f in futures:
        f.cancel()
    processes = getattr(pool, "_processes", None) or {}  # private, but stable since 3.2
    for p in list(processes.values()):
        p.terminate()
    pool.shutdown(wait=False, cancel_futures=True)


def _sweep_pool(groups, finish, cache_root, workers, cores):
    jobs = [([c.to_dict() for c in g], str(cache_root)) for g in groups]
    with worker_pool(workers) as pool:
        for rows in imap_unordered(pool, _star_execute, jobs):
            for row in rows:
                finish(row)


def _pin_worker(slots) -> None:
    """A pool worker's initializer: its own cores, then the compilation cache."""
    from ._env import setup_process

    cores = slots.get()
    setup_process(cores=cores or None)
    if cores:
        os.environ["OMP_NUM_THREADS"] = str(len(cores))


def _star_execute(job):
    from ._env import configure_compilation_cache, configure_numerics

    configure_compilation_cache()  # a Ray worker has no initializer; idempotent in the pool's
    configure_numerics()
    dicts, cache_root, *plugins = job  # plugins: models.plugin_modules() of a Ray driver
    if plugins and plugins[0]:
        _load_plugins(plugins[0])
    if draining():  # the sweep is being drained: this job ends without running
        return []
    if len(dicts) == 1:
        rows = [_execute_dict(dicts[0], cache_root)]
    else:
        from ._ensemble import _execute_group_dicts

        rows = _execute_group_dicts(dicts, cache_root)
    bound_compiled_programs()  # a worker runs many runs: keep its memory maps bounded
    return rows


def _load_plugins(plugins: Mapping[str, Sequence[str]]) -> None:
    """Load the driver's plug-in models in this worker (a Ray worker, started by the raylet,
    imported none of them): put the folders they were imported from on ``sys.path``, then
    import the modules (:func:`models.load_plugins`, once each per process)."""
    for folder in (f for fs in plugins.values() for f in fs):
        if folder not in sys.path:
            sys.path.append(folder)
    models.load_plugins(",".join(plugins))


def _sweep_ray(groups, finish, cache_root, address, cores):
    from ._ray_head import auth_ready

    # a local instance is hosted by a spawned helper where Ray's authentication mode can be set
    # before ray is imported here; else ray.init() starts it (forking this process)
    hosted = not address and auth_ready(fresh="ray" not in sys.modules)
    try:
        import ray
    except ImportError as e:  # pragma: no cover
        raise ValueError("the ray executor needs the 'ray' extra: pip install -e '.[ray]'") from e
    # The plug-in models the configs may name: each task loads them (_star_execute), whether
    # or not this process started Ray; the workers' environment names them too.
    plugins = models.plugin_modules({c.model for g in groups for c in g})
    folders = [str(Path(__file__).resolve().parents[2])]  # this checkout, installed or not
    folders += [f for fs in plugins.values() for f in fs]
    env = {
        "OMP_NUM_THREADS": "1",
        "DECON_CACHE": str(cache_root),
        # Workers start elsewhere: let them import this checkout and the plug-ins.
        "PYTHONPATH": os.pathsep.join(
            dict.fromkeys(p for p in (*folders, os.environ.get("PYTHONPATH")) if p)
        ),
        models.MODULES_ENV: ",".join(plugins),
    }
    started, head = False, None
    if not ray.is_initialized():
        if hosted:  # a local instance, its processes not forked from this one (JAX's)
            from ._ray_head import LocalHead

            head = LocalHead(cores)
            address = head.address
        try:
            ray.init(
                address=address,
                runtime_env={"env_vars": env},
                log_to_driver=False,
                **({} if address else {"num_cpus": cores, "include_dashboard": False}),
            )
        except BaseException:
            if head is not None:
                head.stop()
            raise
        started = True
    try:
        # one task per ensemble (a single run is an ensemble of 1); a GPU per task on GPUs
        gpus = 1 if ray.cluster_resources().get("GPU", 0) >= 1 else 0
        remote = ray.remote(num_cpus=1, num_gpus=gpus)(_star_execute)
        pending = {
            remote.remote(([c.to_dict() for c in g], str(cache_root), plugins)): g for g in groups
        }
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            g = pending.pop(ready[0])
            try:
                rows = ray.get(ready[0])
            except Exception as e:  # a worker that died: record, keep going
                if storage_error(e):  # a full disk: stop (sweep raises StorageError)
                    raise
                rows = []
                for c in g:
                    row = base_row(c)
                    row["error"] = one_line(e, 500)
                    rows.append(row)
            for row in rows:
                finish(row)
    finally:
        if started:
            ray.shutdown()
        if head is not None:
            head.stop()


def run_experiments(
    names: Sequence[str],
    profile: str,
    results_dir="results",
    seeds: Sequence[int] | None = None,
    models: Sequence[str] | None = None,
    where=None,
    **kw,
) -> dict[str, list[dict]]:
    """Sweep the named experiments under ``profile`` as ONE sweep (one pool of workers, runs
    of every experiment interleaved, longest first with ``order``); a run that several
    experiments declare is tagged with the first of them. ``seeds`` replaces the profile's
    seeds (a replication); ``models`` the experiments' trained models (``expand``); ``where``
    (a predicate on a RunConfig) keeps only the runs it accepts. Returns the new rows per
    experiment."""
    from ._experiments import expand

    configs, tags = [], {}
    for n in names:
        for c in expand(n, profile, seeds=seeds, models=models):
            if where is not None and not where(c):
                continue
            if c.config_hash not in tags:
                tags[c.config_hash] = n
                configs.append(c)
    rows = sweep(configs, results_dir, experiment=tags, profile=profile, **kw)
    return {n: [r for r in rows if r["experiment"] == n] for n in names}
