"""The results store: one JSON file per finished run, tables rebuilt from them, aggregation.

Layout under ``results_dir``::

    .rows/<config_hash>.json   the truth: one finished run (row fields + small per-time curves)
    runs.parquet, runs.csv     one row per config_hash, rebuilt from .rows/
    curves.parquet             (config_hash, t, rel_error, energy_violation, z_true_i, z_pred_i)

A row file is written to a temporary name and ``os.replace``d into place, and the tables are
rebuilt the same way, so a process killed at any moment leaves either the whole row or none,
and a hash can never appear twice. ``.rows/`` is meant to be committed: results reload from a
fresh clone.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

ROWS = ".rows"
CURVE_KEYS = ("t", "rel_error", "energy_violation", "z_true", "z_pred")


def _atomic_write_bytes(path: Path, data: bytes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-", suffix=path.suffix)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _jsonable(x):
    if isinstance(x, dict):
        return {str(a): _jsonable(b) for a, b in x.items()}
    if isinstance(x, list | tuple):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    if isinstance(x, np.generic):
        return _jsonable(x.item())
    if isinstance(x, float) and not math.isfinite(x):
        return None if math.isnan(x) else ("inf" if x > 0 else "-inf")
    return x


def write_row(results_dir, row: dict) -> Path:
    """Atomically write one finished run as ``.rows/<config_hash>.json``."""
    path = Path(results_dir) / ROWS / f"{row['config_hash']}.json"
    text = json.dumps(_jsonable(row), sort_keys=True, separators=(",", ":"))
    _atomic_write_bytes(path, text.encode())
    return path


def read_rows(results_dir) -> list[dict]:
    """Every stored row (unreadable files, e.g. from a foreign tool, are skipped)."""
    rows = []
    for path in sorted((Path(results_dir) / ROWS).glob("*.json")):
        try:
            rows.append(json.loads(path.read_text()))
        except (OSError, ValueError):
            continue
    return rows


def done_hashes(results_dir) -> set[str]:
    """config_hash of every finished run (whatever its status)."""
    return {p.stem for p in (Path(results_dir) / ROWS).glob("*.json")}


def _flat(row: dict) -> dict:
    out = {}
    for a, b in row.items():
        if a == "curves":
            continue
        if isinstance(b, list | tuple | dict):
            b = json.dumps(b)
        out[a] = b
    return out


def _numeric_or_null(v) -> bool:
    if v is None or isinstance(v, str) and v in ("inf", "-inf"):
        return True
    return isinstance(v, int | float) and not isinstance(v, bool)


def rows_frame(rows: Sequence[dict]) -> pd.DataFrame:
    """The runs table of some rows: one row per config_hash, lists as JSON strings."""
    df = pd.DataFrame([_flat(r) for r in rows])
    if len(df):
        df = df.drop_duplicates("config_hash", keep="first").sort_values(
            ["experiment", "system", "model", "seed", "config_hash"], na_position="last"
        )
        for col in df.columns:  # JSON null -> NaN, "inf" -> inf, where a column is numeric
            if df[col].dtype == object and df[col].map(_numeric_or_null).all():
                df[col] = pd.to_numeric(df[col], errors="coerce").astype(float)
    return df.reset_index(drop=True)


def curves_frame(rows: Iterable[dict]) -> pd.DataFrame:
    """Long table of per-time curves: config_hash, t, rel_error, energy_violation, z_*_i."""
    parts = []
    for r in rows:
        c = r.get("curves")
        if not c or not c.get("t"):
            continue
        d = {"config_hash": r["config_hash"], "t": np.asarray(c["t"], dtype=float)}
        for key in ("rel_error", "energy_violation"):
            v = c.get(key)
            d[key] = np.asarray(v if v is not None else [np.nan] * len(c["t"]), dtype=float)
        for key in ("z_true", "z_pred"):
            z = np.asarray(c.get(key) or [], dtype=float)
            if z.ndim == 2 and len(z) == len(c["t"]):
                for i in range(z.shape[1]):
                    d[f"{key}_{i}"] = z[:, i]
        parts.append(pd.DataFrame(d))
    if not parts:
        return pd.DataFrame(columns=["config_hash", "t", "rel_error", "energy_violation"])
    return pd.concat(parts, ignore_index=True)


def rebuild_tables(results_dir) -> pd.DataFrame:
    """Rewrite runs.parquet, runs.csv and curves.parquet from ``.rows/`` (atomically)."""
    results_dir = Path(results_dir)
    rows = read_rows(results_dir)
    df = rows_frame(rows)
    results_dir.mkdir(parents=True, exist_ok=True)
    for name, writer in (
        ("runs.parquet", lambda p: df.to_parquet(p, index=False)),
        ("runs.csv", lambda p: df.to_csv(p, index=False)),
        ("curves.parquet", lambda p: curves_frame(rows).to_parquet(p, index=False)),
    ):
        fd, tmp = tempfile.mkstemp(dir=results_dir, prefix=".tmp-", suffix=name)
        os.close(fd)
        try:
            writer(tmp)
            os.replace(tmp, results_dir / name)
        finally:
            Path(tmp).unlink(missing_ok=True)
    return df


def load_runs(results_dir="results") -> pd.DataFrame:
    """The runs table: from ``.rows/`` when present (the truth), else runs.parquet."""
    results_dir = Path(results_dir)
    if (results_dir / ROWS).is_dir():
        return rows_frame(read_rows(results_dir))
    if (results_dir / "runs.parquet").exists():
        return pd.read_parquet(results_dir / "runs.parquet")
    return pd.DataFrame()


def load_curves(results_dir="results") -> pd.DataFrame:
    """The per-time curves table (see :func:`curves_frame`)."""
    results_dir = Path(results_dir)
    if (results_dir / ROWS).is_dir():
        return curves_frame(read_rows(results_dir))
    if (results_dir / "curves.parquet").exists():
        return pd.read_parquet(results_dir / "curves.parquet")
    return curves_frame([])


def runs_of(experiment, profile: str, results_dir="results") -> pd.DataFrame:
    """The stored rows of an experiment's runs under a profile (by config_hash, shared runs
    included whichever experiment produced them first)."""
    from ._experiments import expand

    hashes = [c.config_hash for c in expand(experiment, profile)]
    df = load_runs(results_dir)
    if df.empty:
        return df
    return df[df["config_hash"].isin(hashes)].reset_index(drop=True)


def aggregate(
    df: pd.DataFrame, by: Sequence[str], metric: str, *, n_resamples: int = 2000, seed: int = 0
) -> pd.DataFrame:
    """Summaries of ``metric`` per group of ``by`` over the runs (typically the seeds).

    Columns: n (finite values), mean, std (ddof=1), sem = std / sqrt(n), gmean =
    exp(mean(log x)) (NaN unless every value is > 0), median, and the bootstrap 95% interval
    of the mean (scipy.stats.bootstrap, BCa falling back to percentile; NaN when n < 2 or the
    values are all equal).
    """
    from scipy import stats

    by = list(by)
    if metric not in df.columns:
        raise ValueError(f"unknown metric {metric!r}; columns: {', '.join(df.columns)}")
    out = []
    for key, g in df.groupby(by, dropna=False, sort=True):
        x = pd.to_numeric(g[metric], errors="coerce").to_numpy(dtype=float)
        x = x[np.isfinite(x)]
        n = len(x)
        rec = dict(zip(by, key if isinstance(key, tuple) else (key,), strict=True))
        std = float(np.std(x, ddof=1)) if n > 1 else float("nan")
        lo = hi = float("nan")
        if n > 1 and np.ptp(x) > 0:
            for method in ("BCa", "percentile"):
                try:
                    res = stats.bootstrap(
                        (x,), np.mean, n_resamples=n_resamples, method=method, random_state=seed
                    )
                    lo, hi = float(res.confidence_interval.low), float(res.confidence_interval.high)
                    if np.isfinite(lo) and np.isfinite(hi):
                        break
                except Exception:
                    continue
        rec.update(
            n=n,
            mean=float(np.mean(x)) if n else float("nan"),
            std=std,
            sem=std / math.sqrt(n) if n > 1 else float("nan"),
            gmean=float(np.exp(np.mean(np.log(x)))) if n and np.all(x > 0) else float("nan"),
            median=float(np.median(x)) if n else float("nan"),
            ci_low=lo,
            ci_high=hi,
        )
        out.append(rec)
    return pd.DataFrame(out)
