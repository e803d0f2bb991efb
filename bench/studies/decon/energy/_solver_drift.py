"""The solver's own energy drift on the TRUE system, for claim 1's footnote: "The energy
violation is considerably larger than merely the numerical error associated with the solver"
(Gruver et al. 2022, footnote 1).

For a stored run, :func:`solver_drift` rolls the system's true vector field out with the run's
evaluation integrator (method, substeps, tolerance), time step, horizon, dtype and test initial
states (its dataset's), and scores the rollout with the run's own energy-violation metric
(as ``bench.core._evaluate`` scores a run: the geometric mean over t >= 1 and trajectories of
|H(zhat) - H(z)| / (|H(zhat)| + |H(z)|) against the float64 ground truth). It is the part of a
run's ``energy_violation`` that no model can remove: the solver's truncation and the dtype's
round-off. Nothing is trained. The value depends only on the run's cell and seed (the dataset,
the integrator, the dtype), not on the model: it is computed once per distinct (dataset,
evaluation settings), kept in memory and in ``<cache>/solver_drift/<key>.json`` (discarded when
the code that computes it changes).

The test states are the dataset's; where the full dataset is not cached, the test part alone is
made (``n_generated = n_train = 1``: the test trajectories, their windows and their keys do not
depend on the training part; the ground truth of 200 trajectories instead of 1000). A row whose
table already carries ``solver_energy_violation`` keeps it (a table that stores it, and the
synthetic tables of the tests).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from pathlib import Path

import equinox as eqx
import numpy as np
import pandas as pd

import models

COLUMN = "solver_energy_violation"
_MEMO: dict[str, float] = {}


def _key(config) -> str:
    """The cache key of a run's solver drift: its dataset and evaluation settings."""
    what = {
        "dataset": config.dataset_config().hash(),
        "eval": [config.eval_integrator, config.eval_substeps, config.eval_rtol],
        "dtype": config.dtype,
        "coordinates": config.coordinates,
        "random_args": config.random_args,
    }
    return hashlib.sha256(json.dumps(what, sort_keys=True).encode()).hexdigest()[:32]


def _test_set(config, cache_root: Path):
    """The run's dataset where it is cached (the very test states the run was scored on), else
    its test part alone (the same test trajectories: module docstring)."""
    import systems

    dcfg = config.dataset_config()
    if systems.dataset_path(dcfg, cache_root).exists():
        return systems.make_dataset(dcfg, cache_root)
    small = dataclasses.replace(dcfg, n_generated=1, n_train=1)
    return systems.make_dataset(small, cache_root)


class TrueField(models.AbstractContinuousModel):
    """The system's true vector field as a continuous model in (q, qdot), so that
    ``models.rollout`` and the run's integrator advance it exactly as they advance a learned
    one."""

    scene: models.Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    system: object

    def vector_field(self, t, z, args):
        a = None if args is None or args.shape[-1] == 0 else args
        return self.system.vector_field(t, z, a)


def compute(config, cache_root: Path | None = None) -> float:
    """The solver's energy drift of run ``config`` (module docstring); NaN for a run in
    canonical (q, p) coordinates or one not observed as states (pixels, controlled tasks).
    The rollout and the score are the run's evaluation's (``bench.core._evaluate``): the test
    states in the run's dtype, ``models.rollout_batch`` with :func:`eval_integrator`, and the
    geometric mean over t >= 1 of :func:`bench.metrics.energy_violation_curve`."""
    import jax.numpy as jnp

    import systems

    from ....core import energies, energy_violation_curve, eval_integrator, geometric_mean

    if config.coordinates != "velocity" or config.observation != "state":
        return math.nan
    systems.enable_x64()
    root = Path(cache_root) if cache_root is not None else systems.cache_root()
    system = systems.make(config.system, **config.system_kwargs())
    data = _test_set(config, root)
    scene = models.Scene(
        dof=system.dof,
        angular=tuple(system.angular),
        n_args=system.n_args if config.random_args else 0,
        damped=config.friction > 0,
    )
    dtype = jnp.dtype(config.dtype)
    z0s = jnp.asarray(data.z_test[:, 0], dtype=dtype)
    ts = jnp.asarray(data.ts_test, dtype=dtype)
    args = jnp.asarray(data.args_test, dtype=dtype) if config.random_args else None
    integ = eval_integrator(config)
    roll = eqx.filter_jit(lambda m, z0s, ts, args: models.rollout_batch(m, z0s, ts, args, integ))
    zhat = np.asarray(roll(TrueField(scene, config.dtype, system), z0s, ts, args), np.float64)
    h_args = data.args_test if config.random_args else None
    h_true = energies(system, data.z_test, h_args, config.coordinates)
    h_pred = energies(system, zhat, h_args, config.coordinates)
    return float(geometric_mean(energy_violation_curve(h_pred, h_true)[..., 1:]))


def _cached(config, cache_root: Path | None) -> float:
    import systems

    from ....core import code_fingerprint, write_json

    key = _key(config)
    if key in _MEMO:
        return _MEMO[key]
    root = Path(cache_root) if cache_root is not None else systems.cache_root()
    path = root / "solver_drift" / f"{key}.json"
    own = hashlib.sha256(Path(__file__).read_bytes()).hexdigest()[:16]
    code = f"{code_fingerprint()}-{own}"  # the trainer's code and this module's
    try:
        stored = json.loads(path.read_text())
        if stored["code"] == code:
            _MEMO[key] = float(stored["value"])
            return _MEMO[key]
    except (OSError, ValueError, KeyError, TypeError):
        pass
    value = compute(config, root)
    write_json(path, {"value": value, "code": code})
    _MEMO[key] = value
    return value


def _configs(runs: pd.DataFrame) -> list:
    """Each row's run configuration (None where a row does not parse into one)."""
    from ....core import RunConfig, field_names

    names = [c for c in runs.columns if c in field_names()]
    out = []
    for _, row in runs.iterrows():
        try:
            out.append(RunConfig.from_dict({k: row[k] for k in names}))
        except Exception:  # noqa: BLE001 - a row that is not a run has no drift
            out.append(None)
    return out


def same_cells(runs: pd.DataFrame, of: pd.DataFrame) -> pd.DataFrame:
    """The rows of ``runs`` whose solver drift is that of a row of ``of`` (the same dataset
    and evaluation settings): the NODEs beside the HNN, with no drift of their own to compute."""
    keys = {_key(c) for c in _configs(of) if c is not None}
    mine = [c is not None and _key(c) in keys for c in _configs(runs)]
    return runs[np.asarray(mine, dtype=bool)] if len(runs) else runs


def solver_drift(runs: pd.DataFrame, cache_root: Path | None = None) -> pd.Series:
    """Per row of ``runs``, the solver's energy drift on the true system of its cell and seed
    (:data:`COLUMN` where the table has it, else computed: :func:`compute`, cached); NaN where
    it cannot be had (a row that does not parse into a run, or fails to compute)."""
    out = pd.Series(np.nan, index=runs.index, name=COLUMN, dtype=float)
    if COLUMN in runs:
        out[:] = pd.to_numeric(runs[COLUMN], errors="coerce").to_numpy(float)
    missing = runs[out.isna()]
    for i, config in zip(missing.index, _configs(missing), strict=True):
        try:
            out[i] = math.nan if config is None else _cached(config, cache_root)
        except Exception:  # noqa: BLE001 - a value that cannot be had leaves the part untested
            out[i] = math.nan
    return out


def footnote_part(runs: pd.DataFrame, fig2: pd.DataFrame, hnns: tuple[str, ...], nodes=()):
    """Claim 1 (d), footnote 1: per seed, ``log(energy violation of the HNN / the solver's
    drift on the true system)`` of the same cell and seed, the weaker (smaller) over the
    systems, a *greater* part at the energy margin ("considerably larger"). ``runs``: the
    Fig. 2 runs with ``_ev`` (the scored energy violation: failed runs at the worst);
    ``fig2``: the same cells with the trivial predictors, for the learning gates (the HNN
    learned on every system; over several k, the k where it did: ``learned_at_each_k``);
    ``nodes``: models whose ratio the note reports, not judged."""
    from ....kit import MODEL_LABELS, gated, greater, learned_at_each_k, policy, undecided

    name = "(d) HNN+SO energy violation over the solver's own drift on the true system, log"
    hnn_rows = runs[runs["model"].isin(hnns)]
    if not len(hnn_rows):
        return None
    node_rows = runs[runs["model"].isin(nodes)]
    if len(node_rows) and COLUMN not in runs:  # the NODEs of the HNN's cells only
        node_rows = same_cells(node_rows, hnn_rows)
    own = pd.concat([hnn_rows, node_rows])
    drift = solver_drift(own)
    ratio = np.log(pd.to_numeric(own["_ev"], errors="coerce") / drift)
    ok = np.isfinite(ratio)
    is_hnn = own["model"].isin(hnns)
    if not (ok & is_hnn).any():
        return undecided(name, "no solver drift could be computed for the HNN's cells")
    # the HNN learned on every system; over several k, only the k where it did
    lg = learned_at_each_k(
        [
            (g, {"model": m}, f"{MODEL_LABELS.get(m, m)} on {system}")
            for system, g in fig2.groupby("system")
            for m in hnns
            if (g["model"] == m).any()
        ]
    )
    h = own[ok & is_hnn]
    if lg.kept:
        h = h[h["k"].isin(lg.kept)]
    per = ratio[h.index].groupby([h["seed"], h["system"]]).mean().unstack("system")
    per = per.dropna()  # the seeds that have every system
    notes = []
    for system in sorted(h["system"].unique()):
        g = own[ok & (own["system"] == system)]
        d = float(np.exp(np.log(drift[g.index]).mean()))
        r = {
            m: float(np.exp(ratio[gm.index].mean()))
            for m, gm in g.groupby("model")
            if m in (*hnns, *nodes)
        }
        ratios = ", ".join(f"{MODEL_LABELS.get(m, m)} {v:.3g}x" for m, v in r.items())
        notes.append(f"{system}: solver drift {d:.3g}; violation / drift {ratios}")
    part = greater(
        f"{name} (weaker system)",
        per.min(axis=1).to_numpy(),
        policy.margin("energy"),
        "; ".join([*notes, *([lg.note] if lg.note else [])])
        + ("; the NODEs' ratios reported, not judged" if nodes else ""),
    )
    return gated(part, *lg.gates)
