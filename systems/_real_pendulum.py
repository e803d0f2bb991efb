"""The HNN seed's real pendulum (its Task 3): Schmidt & Lipson's measured trajectory, read from
a file the user supplies, or a synthetic stand-in of the same format (a damped pendulum measured
with noise, generated here in float64) when the file is absent. The card: docs/studies/
real_pendulum.md. Nothing here downloads or ships the measured data.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import io
import math
import os
import zipfile
from pathlib import Path

import numpy as np

REAL = "real_pend_h_1"  # the measured file's stem (invar_datasets.zip/real_pend_h_1.txt)
SYNTHETIC = "real_pend_synthetic"  # the stand-in
DATASETS = (REAL, SYNTHETIC)
ENV = "DECON_REAL_PENDULUM"  # a path to real_pend_h_1.txt, or to invar_datasets.zip
COLUMNS = ("trial", "t", "o", "v")  # the file's columns after its header line
# The seed's split (experiment-real/data.py, get_dataset(test_split=0.8)): the first 80% of
# the states train, the next 20% test, in time order (a rounding leftover trains).
TRAIN_SHARE = 0.8
# The seed's fitted energy (experiment-real/data.py, hamiltonian_fn): H = k (1 - cos q) + p^2.
SEED_K = 2.4
# The stand-in: theta'' = -(SEED_K / 2) sin theta - FRICTION theta', so that the seed's H is
# conserved but for the friction; sampled every DT s for DURATION s from (THETA0, 0), with
# Gaussian reading noise NOISE on both columns (a fixed generator: one trajectory, as measured).
STANDIN = {"dt": 0.05, "duration": 50.0, "theta0": 1.0, "friction": 0.02, "noise": 0.001, "seed": 0}


@dataclasses.dataclass(frozen=True)
class Measured:
    """One measured trajectory as the seed uses it: states x = (o, v) (N, 2) at the file's times
    t (N,) but the last, their forward differences dx (N, 2), the seed's split, and where it
    came from (``source``: a label, ``sha256`` of the bytes read, ``synthetic``)."""

    t: np.ndarray
    x: np.ndarray
    dx: np.ndarray
    train: np.ndarray  # indices into x
    test: np.ndarray  # indices into x, contiguous and in time order
    source: str
    sha256: str
    synthetic: bool
    n_trials: int


def seed_energy(z):
    """The seed's H(q, p) = 2.4 (1 - cos q) + p^2 of states (..., 2) (works on numpy and jax)."""
    import jax.numpy as jnp

    return SEED_K * (1.0 - jnp.cos(z[..., 0])) + z[..., 1] ** 2


def default_path() -> Path:
    """Where the measured file is looked for when ``$DECON_REAL_PENDULUM`` is unset."""
    from ._dataset import cache_root

    return cache_root() / "data" / f"{REAL}.txt"


def real_path() -> Path | None:
    """The measured file (``$DECON_REAL_PENDULUM``, else :func:`default_path`) if it exists."""
    p = Path(os.environ.get(ENV) or default_path())
    return p if p.is_file() else None


def absent_message() -> str:
    return (
        f"real pendulum data absent: put Schmidt & Lipson's {REAL}.txt (Science 2009 "
        f"supplementary, invar_datasets.zip) at {default_path()} or set ${ENV} to its path"
    )


def read_bytes(path) -> bytes:
    """The text of the measured file: ``path`` itself, or its member ``real_pend_h_1.txt`` when
    ``path`` is the supplementary zip."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(absent_message())
    if path.suffix == ".zip":
        with zipfile.ZipFile(path) as z:
            names = [n for n in z.namelist() if Path(n).name == f"{REAL}.txt"]
            if not names:
                raise ValueError(f"{path} holds no {REAL}.txt; allowed: the supplementary zip")
            return z.read(names[0])
    return path.read_bytes()


def parse(text: bytes | str) -> np.ndarray:
    """Rows (N, 4) of trial, t, o, v: one header line, then four numbers a line (whitespace or
    comma separated; blank lines skipped). A bad line is a one-line ValueError."""
    if isinstance(text, bytes):
        text = text.decode("utf-8", errors="replace")
    lines = text.splitlines()
    rows = []
    for i, line in enumerate(lines[1:], start=2):
        fields = line.replace(",", " ").split()
        if not fields:
            continue
        try:
            values = [float(f) for f in fields]
        except ValueError:
            values = []
        if len(values) != 4:
            raise ValueError(f"line {i}: expected 4 numbers ({', '.join(COLUMNS)}); got {line!r}")
        rows.append(values)
    rows = np.asarray(rows, dtype=np.float64).reshape(-1, 4)
    if len(rows) < 10:
        raise ValueError(f"a measured trajectory needs >= 10 rows; got {len(rows)}")
    if not np.all(np.isfinite(rows)) or not np.all(np.diff(rows[:, 1]) > 0):
        raise ValueError("the times (column t) must be finite and strictly increasing")
    return rows


def split(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The seed's split of n states: test = [a, b) with a = int(0.8 n), b = a + int(0.2 n);
    train = the rest (the states before a, and any rounding leftover after b)."""
    a = int(n * TRAIN_SHARE)
    b = a + int(n * (1 - TRAIN_SHARE))
    idx = np.arange(n)
    return np.concatenate([idx[:a], idx[b:]]), idx[a:b]


def from_rows(rows: np.ndarray, source: str, sha256: str, synthetic: bool) -> Measured:
    """The seed's arrays (experiment-real/data.py): x the columns o, v; dx the forward
    difference (x[i+1] - x[i]) / (t[i+1] - t[i]) across consecutive rows; the last row dropped."""
    t, x = rows[:, 1], rows[:, 2:4]
    dx = (x[1:] - x[:-1]) / (t[1:] - t[:-1])[:, None]
    train, test = split(len(dx))
    return Measured(
        t=t[:-1],
        x=x[:-1],
        dx=dx,
        train=train,
        test=test,
        source=source,
        sha256=sha256,
        synthetic=synthetic,
        n_trials=len(np.unique(rows[:, 0])),
    )


def standin_text() -> str:
    """The synthetic stand-in, in the measured file's format (header, then trial t o v): the
    damped pendulum of :data:`STANDIN` by classic RK4 in float64 at 10 steps per sample (it
    agrees with an independent DOP853 solve to the file's 6 decimals), then the noise."""
    c = STANDIN
    n, sub = round(c["duration"] / c["dt"]) + 1, 10
    h = c["dt"] / sub

    def field(o, v):
        return v, -SEED_K / 2 * math.sin(o) - c["friction"] * v

    y = np.empty((n, 2))
    o, v = c["theta0"], 0.0
    for i in range(n):
        y[i] = o, v
        for _ in range(sub):
            k1 = field(o, v)
            k2 = field(o + h / 2 * k1[0], v + h / 2 * k1[1])
            k3 = field(o + h / 2 * k2[0], v + h / 2 * k2[1])
            k4 = field(o + h * k3[0], v + h * k3[1])
            o += h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
            v += h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
    y += c["noise"] * np.random.default_rng(c["seed"]).standard_normal((n, 2))
    out = io.StringIO()
    out.write("% SYNTHETIC stand-in for real_pend_h_1 (decon-bench, not measured): trial t o v\n")
    for i, (o, v) in enumerate(y):
        out.write(f"1 {i * c['dt']:.4f} {o:.6f} {v:.6f}\n")
    return out.getvalue()


@functools.cache
def _standin() -> Measured:
    text = standin_text().encode()
    sha = hashlib.sha256(text).hexdigest()
    return from_rows(parse(text), "synthetic stand-in (not measured)", sha, synthetic=True)


def load(name: str) -> Measured:
    """The dataset ``name``: :data:`REAL` (the user's file; ValueError saying where to put it
    when absent) or :data:`SYNTHETIC` (the stand-in)."""
    if name == SYNTHETIC:
        return _standin()
    if name != REAL:
        raise ValueError(f"unknown measured dataset {name!r}; allowed: {', '.join(DATASETS)}")
    path = real_path()
    if path is None:
        raise ValueError(absent_message())
    data = read_bytes(path)
    sha = hashlib.sha256(data).hexdigest()
    return from_rows(parse(data), f"measured: {path.name}", sha, synthetic=False)
