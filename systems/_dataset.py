"""Training and test sets of ground-truth trajectories, cached on disk.

Protocol (Gruver et al. 2022, as the paper's public code generates its data, with its defects
fixed: every trajectory on the same uniform time grid, test windows anywhere, independent keys):

- every trajectory is simulated on ts = arange(n) * dt with n = round(duration / dt) + 1
  (334 points for 10 s at dt = 0.03);
- training: ``n_generated`` initial states are drawn and the first ``n_train`` are kept
  (only those are simulated; the others would be discarded, so the data are the same); from each
  one random chunk of ``chunk`` consecutive points, starting anywhere, ts_train = arange(chunk)*dt;
- test: ``n_test`` trajectories simulated from initial states drawn with an independent key
  (train and test keys are ``fold_in(PRNGKey(seed), 0 / 1)``), and from each one random window
  of ``test_chunks * chunk`` points starting anywhere (not only at t = 0);
- optional Gaussian observation noise of std ``noise`` on the training set only, after the
  optional conversion to canonical coordinates z = (q, p) (``coordinates="momentum"``);
- ``random_args``: per-trajectory system parameters from ``system.sample_args`` (stored in
  ``args_*`` either way; the default parameters otherwise).

Cache: ``<cache_dir>/datasets/<config.hash()>.npz``; the npz holds the arrays, the canonical
config JSON, a sha256 of the arrays and the :func:`source_fingerprint` of the ``systems``
package that generated them. It is written through the one atomic write (a temporary file
moved into place); a file that does not load, or whose checksum, config or code disagrees (the
physics was edited since: any change to a file of ``systems/``), is rebuilt.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import importlib.util
import json
import math
import numbers
import os
import warnings
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from ._atomic import atomic_write
from ._base import MAX_STEPS
from ._coordinates import to_momentum
from ._precision import require_x64
from ._registry import make

FORMAT_VERSION = 1
COORDINATES = ("velocity", "momentum")
_ARRAYS = ("ts_train", "z_train", "args_train", "ts_test", "z_test", "args_test")


@dataclasses.dataclass(frozen=True)
class DatasetConfig:
    """What a dataset is made of; the same config always yields the same data."""

    system: str
    system_params: tuple[tuple[str, object], ...] = ()
    n_generated: int = 1000
    n_train: int = 800
    chunk: int = 5
    dt: float = 0.03
    duration: float = 10.0
    n_test: int = 200
    test_chunks: int = 20
    noise: float = 0.0
    coordinates: str = "velocity"
    random_args: bool = False
    seed: int = 0

    def __post_init__(self):
        params = self.system_params
        if isinstance(params, dict):
            params = params.items()
        try:
            params = tuple(sorted((str(k), v) for k, v in params))
        except (TypeError, ValueError) as e:
            raise ValueError(
                f"system_params must be (name, value) pairs; got {self.system_params!r}"
            ) from e
        object.__setattr__(self, "system_params", params)
        for field in ("n_generated", "n_train", "chunk", "n_test", "test_chunks"):
            _check_int(field, getattr(self, field), 1)
        _check_int("seed", self.seed, 0)
        for field in ("dt", "duration"):
            value = getattr(self, field)
            if not _is_real(value) or not value > 0:
                raise ValueError(f"{field} must be a finite number > 0; got {value!r}")
        if not _is_real(self.noise) or self.noise < 0:
            raise ValueError(f"noise must be a finite number >= 0; got {self.noise!r}")
        if self.coordinates not in COORDINATES:
            raise ValueError(f"coordinates must be one of {COORDINATES}; got {self.coordinates!r}")
        if not isinstance(self.random_args, bool):
            raise ValueError(f"random_args must be True or False; got {self.random_args!r}")
        if self.n_train > self.n_generated:
            raise ValueError(
                f"n_train ({self.n_train}) must be <= n_generated ({self.n_generated})"
            )
        n = self.n_points
        if self.chunk < 2 or self.chunk > n:
            raise ValueError(f"chunk must be in [2, {n}] (points per trajectory); got {self.chunk}")
        if self.test_chunks * self.chunk > n:
            raise ValueError(
                f"test_chunks * chunk = {self.test_chunks * self.chunk} points exceeds the "
                f"{n} points of a {self.duration} s trajectory at dt={self.dt}"
            )
        with warnings.catch_warnings():  # only the parameters are checked: float32 is moot
            warnings.filterwarnings("ignore", "Explicitly requested dtype", UserWarning)
            make(self.system, **dict(self.system_params))  # ValueError for a bad system

    @property
    def n_points(self) -> int:
        """Points per simulated trajectory: round(duration / dt) + 1."""
        return int(round(self.duration / self.dt)) + 1

    def canonical_json(self) -> str:
        return json.dumps(
            {"format": FORMAT_VERSION, "config": dataclasses.asdict(self)},
            sort_keys=True,
            separators=(",", ":"),
            default=str,
        )

    def hash(self) -> str:
        """sha256 of the canonical JSON of the config and the cache format version."""
        return hashlib.sha256(self.canonical_json().encode()).hexdigest()


@functools.cache
def source_fingerprint(*packages: str) -> str:
    """A short sha256 of the Python source of the importable ``packages`` (``"systems"``,
    ``"bench.core"``): their ``.py`` files by relative path and bytes. Caches store it beside
    what the code computed and discard an entry written by other code, since their keys (the
    configuration's hash) do not cover the code."""
    h = hashlib.sha256()
    for name in packages:
        spec = importlib.util.find_spec(name)
        if spec is None:
            raise ValueError(f"no importable package {name!r} to fingerprint")
        for root in map(Path, spec.submodule_search_locations or [spec.origin]):
            files = sorted(root.rglob("*.py")) if root.is_dir() else [root]
            for f in files:
                rel = f.relative_to(root) if root.is_dir() else f.name
                h.update(f"{name}/{rel}\0".encode())
                h.update(f.read_bytes())
    return h.hexdigest()[:16]


def _is_real(x) -> bool:
    return isinstance(x, numbers.Real) and not isinstance(x, bool) and math.isfinite(x)


def _check_int(name, value, low):
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < low:
        raise ValueError(f"{name} must be an integer >= {low}; got {value!r}")


@dataclasses.dataclass(frozen=True)
class Dataset:
    """Train chunks and test windows as numpy float64 arrays.

    ts_train (C,), z_train (N, C, 2d), args_train (N, P);
    ts_test (T,), z_test (M, T, 2d), args_test (M, P); angular: which q are angles.
    """

    config: DatasetConfig
    ts_train: np.ndarray
    z_train: np.ndarray
    args_train: np.ndarray
    ts_test: np.ndarray
    z_test: np.ndarray
    args_test: np.ndarray
    angular: tuple[bool, ...]


def cache_root() -> Path:
    """The suite's git-ignored cache root, the one definition (bench's caches live under it
    too): ``$DECON_CACHE``, or ``./.cache/decon-bench``."""
    return Path(os.environ.get("DECON_CACHE") or Path(".cache") / "decon-bench")


def dataset_path(config: DatasetConfig, cache_dir=None) -> Path:
    """The file of ``config``'s dataset in the cache ``cache_dir`` (default :func:`cache_root`),
    whether or not it has been made."""
    root = Path(cache_dir if cache_dir is not None else cache_root())
    return root / "datasets" / f"{config.hash()}.npz"


def make_dataset(config: DatasetConfig, cache_dir=None) -> Dataset:
    """Load the dataset of ``config`` from the cache (:func:`dataset_path`), or generate and
    cache it."""
    if not isinstance(config, DatasetConfig):
        raise ValueError(f"config must be a DatasetConfig; got {type(config).__name__}")
    require_x64("make_dataset")
    system = make(config.system, **dict(config.system_params))
    path = dataset_path(config, cache_dir)
    arrays = _load(path, config)
    if arrays is None:
        arrays = _generate(system, config)
        _save(path, config, arrays)
    return Dataset(config=config, angular=tuple(system.angular), **arrays)


def _simulate(system, z0s, ts, args):
    """Ground truth; a seam for tests (which check that a cache hit never simulates)."""
    return np.asarray(system.simulate_batch(z0s, ts, args))


def _windows(traj, key, length):
    n, points, _ = traj.shape
    starts = np.asarray(jax.random.randint(key, (n,), 0, points - length + 1))
    idx = starts[:, None] + np.arange(length)[None]
    return np.take_along_axis(traj, idx[:, :, None], axis=1)


def _generate(system, config: DatasetConfig) -> dict[str, np.ndarray]:
    root = jax.random.PRNGKey(config.seed)
    k_train, k_test = jax.random.fold_in(root, 0), jax.random.fold_in(root, 1)

    # Draw all n_generated initial states so that the kept ones do not depend on n_train.
    k_init, k_args, k_start, k_noise = jax.random.split(k_train, 4)
    z0_train = system.sample_initial(k_init, config.n_generated)[: config.n_train]
    k_init_test, k_args_test, k_start_test = jax.random.split(k_test, 3)
    z0_test = system.sample_initial(k_init_test, config.n_test)
    if config.random_args:
        args_train = system.sample_args(k_args, config.n_generated)[: config.n_train]
        args_test = system.sample_args(k_args_test, config.n_test)
    else:
        args_train = jnp.broadcast_to(system.default_args(), (config.n_train, system.n_args))
        args_test = jnp.broadcast_to(system.default_args(), (config.n_test, system.n_args))
    args_train = np.asarray(args_train, dtype=np.float64)
    args_test = np.asarray(args_test, dtype=np.float64)

    # One batch (one compile) for train and test; the keys above keep them independent.
    ts = np.arange(config.n_points) * config.dt
    traj = _simulate(
        system,
        jnp.concatenate([z0_train, z0_test]),
        ts,
        np.concatenate([args_train, args_test]),
    )
    bad = np.flatnonzero(~np.isfinite(traj).all(axis=(1, 2)))
    if bad.size:
        raise RuntimeError(
            f"{system.name} seed {config.seed}: the ground truth of {bad.size} of {len(traj)} "
            f"trajectories is not finite (first {bad[:5].tolist()}): the solve ran out of its "
            f"{MAX_STEPS} steps or diverged; nothing was cached"
        )
    z_train = _windows(traj[: config.n_train], k_start, config.chunk)
    z_test = _windows(traj[config.n_train :], k_start_test, config.test_chunks * config.chunk)

    if config.coordinates == "momentum":
        z_train = to_momentum(system, z_train, args_train)
        z_test = to_momentum(system, z_test, args_test)
    if config.noise > 0:
        z_train = z_train + config.noise * np.asarray(
            jax.random.normal(k_noise, z_train.shape, dtype=jnp.float64)
        )
    return {
        "ts_train": np.arange(config.chunk) * config.dt,
        "z_train": np.ascontiguousarray(z_train, dtype=np.float64),
        "args_train": args_train,
        "ts_test": np.arange(config.test_chunks * config.chunk) * config.dt,
        "z_test": np.ascontiguousarray(z_test, dtype=np.float64),
        "args_test": args_test,
    }


def _checksum(arrays) -> str:
    h = hashlib.sha256()
    for name in _ARRAYS:
        a = np.ascontiguousarray(arrays[name], dtype=np.float64)
        h.update(f"{name}:{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _load(path: Path, config: DatasetConfig):
    if not path.exists():
        return None
    try:
        with np.load(path, allow_pickle=False) as f:
            arrays = {name: np.array(f[name]) for name in _ARRAYS}
            stored_sum = str(f["checksum"])
            stored_config = str(f["config"])
            stored_code = str(f["code"])
    except Exception:  # noqa: BLE001 - any unreadable file is rebuilt, never trusted
        return None
    if (
        stored_config != config.canonical_json()
        or stored_code != source_fingerprint("systems")
        or stored_sum != _checksum(arrays)
    ):
        return None
    return arrays


def _save(path: Path, config: DatasetConfig, arrays) -> None:
    """Write through the one atomic write (:func:`~systems._atomic.atomic_write`): a write
    that fails (a full disk, a file-size limit) raises and leaves no file at ``path`` and no
    temporary behind."""
    atomic_write(
        path,
        lambda tmp: np.savez(
            tmp,
            checksum=np.array(_checksum(arrays)),
            config=np.array(config.canonical_json()),
            code=np.array(source_fingerprint("systems")),
            **arrays,
        ),
    )
