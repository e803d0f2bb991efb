"""The tables of a results folder, rebuilt from its row files: ``runs.parquet``/``runs.csv``
(one row per run), ``curves.parquet`` (per-time curves), ``checkpoints.parquet`` and
``checkpoint_curves.parquet`` (learning curves), the ``bench_meta.json`` that says what they
were built from, and the checks and loaders that read them."""

from __future__ import annotations

import hashlib
import json
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from ._atomic import atomic_write, atomic_write_bytes
from ._store_rows import NESTED, ROWS, read_rows


def _flat(row: dict) -> dict:
    out = {}
    for a, b in row.items():
        if a in NESTED:
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
        by = [c for c in ("experiment", "system", "model", "seed", "config_hash") if c in df]
        df = df.drop_duplicates("config_hash", keep="first").sort_values(by, na_position="last")
        for col in df.columns:  # JSON null -> NaN, "inf" -> inf, where a column is numeric
            if df[col].dtype == object and df[col].map(_numeric_or_null).all():
                df[col] = pd.to_numeric(df[col], errors="coerce").astype(float)
    return df.reset_index(drop=True).copy()  # the copy consolidates the columns set above


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


CHECKPOINT_COLUMNS = ("step", "fraction", "train_seconds", "status")


def checkpoints_frame(rows: Iterable[dict]) -> pd.DataFrame:
    """Learning curves, one row per (run, checkpoint): config_hash, step, fraction,
    train_seconds, status and the checkpoint metrics (``bench.core._evaluate.CHECKPOINT_METRICS``);
    empty (with those first columns) when no row has checkpoints."""
    parts = []
    for r in rows:
        c = r.get("checkpoints")
        if not c or not c.get("step"):
            continue
        d = {"config_hash": r["config_hash"]}
        d.update({k: v for k, v in c.items() if not k.endswith("_t")})
        parts.append(pd.DataFrame(d))
    if not parts:
        return pd.DataFrame(columns=["config_hash", *CHECKPOINT_COLUMNS])
    out = pd.concat(parts, ignore_index=True)
    for col in out.columns:
        if col not in ("config_hash", "status"):
            out[col] = pd.to_numeric(out[col], errors="coerce").astype(float)
    out["step"] = out["step"].astype(int)
    return out


def checkpoint_curves_frame(rows: Iterable[dict]) -> pd.DataFrame:
    """Per-time curves at each checkpoint: config_hash, step, t, rel_error, energy_violation
    (the columns of :func:`curves_frame`, so a claim rule reads them as it reads the final ones)."""
    cols: dict[str, list] = {k: [] for k in ("config_hash", "step", "t", "rel_error")}
    cols["energy_violation"] = []
    for r in rows:
        c, t = r.get("checkpoints"), (r.get("curves") or {}).get("t")
        if not c or not c.get("step") or not t:
            continue
        n, steps = len(t), c["step"]
        for key in ("rel_error", "energy_violation"):
            v = [
                x if x is not None and len(x) == n else [np.nan] * n
                for x in c.get(f"{key}_t") or [None] * len(steps)
            ]
            cols[key].append(np.asarray(v, dtype=float).reshape(-1))
        cols["config_hash"].append(np.repeat(r["config_hash"], n * len(steps)))
        cols["step"].append(np.repeat(np.asarray(steps, dtype=int), n))
        cols["t"].append(np.tile(np.asarray(t, dtype=float), len(steps)))
    if not cols["t"]:
        return pd.DataFrame(columns=list(cols))
    return pd.DataFrame({k: np.concatenate(v) for k, v in cols.items()})


def rebuild_tables(results_dir) -> pd.DataFrame:
    """Rewrite runs.parquet, runs.csv, curves.parquet, checkpoints.parquet and
    checkpoint_curves.parquet from ``.rows/`` (atomically)."""
    results_dir = Path(results_dir)
    digest = rows_digest(results_dir)  # before reading: a row written meanwhile shows as stale
    rows = read_rows(results_dir)
    df = rows_frame(rows)
    results_dir.mkdir(parents=True, exist_ok=True)
    for name, writer in (
        ("runs.parquet", lambda p: df.to_parquet(p, index=False)),
        ("runs.csv", lambda p: df.to_csv(p, index=False)),
        ("curves.parquet", lambda p: curves_frame(rows).to_parquet(p, index=False)),
        ("checkpoints.parquet", lambda p: checkpoints_frame(rows).to_parquet(p, index=False)),
        (
            "checkpoint_curves.parquet",
            lambda p: checkpoint_curves_frame(rows).to_parquet(p, index=False),
        ),
    ):
        atomic_write(results_dir / name, writer)
    record_schema(results_dir, rows_digest=digest)
    return df


def rows_digest(results_dir) -> str:
    """sha256 over the row files' names and bytes: what the tables were built from. Recorded
    by :func:`rebuild_tables` in ``bench_meta.json``; :func:`stale_tables` compares it, so a row
    rewritten under the same hash (a rerun) marks the tables stale too."""
    h = hashlib.sha256()
    rows_dir = Path(results_dir) / ROWS
    for p in sorted(rows_dir.glob("*.json")) if rows_dir.is_dir() else ():
        if p.name.startswith("."):  # a temporary being written (see scan_rows)
            continue
        try:
            data = p.read_bytes()
        except OSError:
            continue
        h.update(p.name.encode() + b"\0" + hashlib.sha256(data).digest())
    return h.hexdigest()


META = "bench_meta.json"


def _read_meta(results_dir) -> dict:
    try:
        meta = json.loads((Path(results_dir) / META).read_text())
    except (OSError, ValueError):
        return {}
    return meta if isinstance(meta, dict) else {}


def record_schema(results_dir, rows_digest: str | None = None) -> None:
    """Record the tables' schema version (:data:`bench.core._schema.SCHEMA_VERSION`) in
    ``bench_meta.json`` (other keys kept; ``python -m bench compare`` checks it), and the
    :func:`rows_digest` the tables were built from, where given."""
    from ._schema import SCHEMA_VERSION

    path = Path(results_dir) / META
    meta = _read_meta(results_dir)
    want = {"schema_version": SCHEMA_VERSION}
    if rows_digest is not None:
        want["rows_digest"] = rows_digest
    if all(meta.get(a) == b for a, b in want.items()):
        return
    meta.update(want)
    atomic_write_bytes(path, json.dumps(meta, indent=1).encode())


TABLES = (
    "runs.parquet",
    "runs.csv",
    "curves.parquet",
    "checkpoints.parquet",
    "checkpoint_curves.parquet",
)


def stale_tables(results_dir) -> list[tuple[str, str]]:
    """The tables of ``results_dir`` that do not match ``.rows/`` (the truth), as
    ``(file name, why)``: missing, unreadable (truncated, not a table), for the runs tables
    holding other runs than the row files, or built from other row files than those stored now
    (the :func:`rows_digest` recorded at the last rebuild differs: a row rewritten under its
    hash; folders built before digests were recorded skip this check). Empty without
    ``.rows/`` (nothing to rebuild from)."""
    results_dir = Path(results_dir)
    if not (results_dir / ROWS).is_dir():
        return []
    rows = {p.stem for p in (results_dir / ROWS).glob("*.json") if not p.name.startswith(".")}
    out = []
    for name in TABLES:
        path = results_dir / name
        if not path.exists():
            if rows:
                out.append((name, "missing"))
            continue
        try:
            df = pd.read_csv(path) if name.endswith(".csv") else pd.read_parquet(path)
        except Exception as e:  # noqa: BLE001 - any reader error means a damaged table
            out.append((name, f"unreadable ({type(e).__name__})"))
            continue
        if name.startswith("runs.") and set(df.get("config_hash", pd.Series(dtype=str))) != rows:
            out.append((name, "other runs than the row files"))
    recorded = _read_meta(results_dir).get("rows_digest")
    if recorded is not None and recorded != rows_digest(results_dir):
        flagged = {name for name, _ in out}
        out += [
            (name, "built from other row files (rows added or rewritten since)")
            for name in TABLES
            if name not in flagged
        ]
    return out


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


def load_checkpoints(results_dir="results") -> tuple[pd.DataFrame, pd.DataFrame]:
    """(checkpoints, checkpoint curves) tables (see :func:`checkpoints_frame`)."""
    results_dir = Path(results_dir)
    if (results_dir / ROWS).is_dir():
        rows = read_rows(results_dir)
        return checkpoints_frame(rows), checkpoint_curves_frame(rows)
    out = []
    for name, empty in (
        ("checkpoints.parquet", checkpoints_frame),
        ("checkpoint_curves.parquet", checkpoint_curves_frame),
    ):
        path = results_dir / name
        out.append(pd.read_parquet(path) if path.exists() else empty([]))
    return out[0], out[1]


def runs_of(experiment, profile: str, results_dir="results") -> pd.DataFrame:
    """The stored rows of an experiment's runs under a profile (by config_hash, shared runs
    included whichever experiment produced them first)."""
    from ._experiments import expand

    hashes = [c.config_hash for c in expand(experiment, profile)]
    df = load_runs(results_dir)
    if df.empty:
        return df
    return df[df["config_hash"].isin(hashes)].reset_index(drop=True)
