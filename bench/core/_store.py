"""The results store: one JSON file per finished run, the tables rebuilt from them.

Layout under ``results_dir``::

    .rows/<config_hash>.json   the truth: one finished run (row fields + small per-time curves)
    runs.parquet, runs.csv     one row per config_hash, rebuilt from .rows/
    curves.parquet             (config_hash, t, rel_error, energy_violation, z_true_i, z_pred_i)
    checkpoints.parquet        learning curves: one row per (run, checkpoint)
    checkpoint_curves.parquet  (config_hash, step, t, rel_error, energy_violation) per checkpoint

Every file is written atomically (``bench.core._atomic``), so a killed process or a full disk
leaves the whole row or none. ``.rows/`` is meant to be committed: results reload from a fresh
clone. This module names the store's parts: row files (``_store_rows``), tables
(``_store_tables``) and results folders (``_store_folders``).
"""

from __future__ import annotations

from ._atomic import TMP_PREFIX, clear_orphans, jsonable, tmp_prefix
from ._store_folders import (
    OWN_DIR,
    REFERENCE_DIRS,
    REFERENCE_ROOT,
    ResultsDirError,
    check_results_dir,
    compare_folders,
    holds_runs,
    reference_dir,
)
from ._store_rows import (
    CHECKSUM,
    CURVE_KEYS,
    DAMAGED,
    NESTED,
    ROWS,
    STATUSES,
    DamagedRowWarning,
    done_hashes,
    read_rows,
    scan_rows,
    unread_rows,
    write_row,
)
from ._store_tables import (
    CHECKPOINT_COLUMNS,
    META,
    TABLES,
    checkpoint_curves_frame,
    checkpoints_frame,
    curves_frame,
    load_checkpoints,
    load_curves,
    load_runs,
    rebuild_tables,
    record_schema,
    rows_digest,
    rows_frame,
    runs_of,
    stale_tables,
)

__all__ = [
    "CHECKPOINT_COLUMNS",
    "CHECKSUM",
    "CURVE_KEYS",
    "DAMAGED",
    "META",
    "NESTED",
    "OWN_DIR",
    "REFERENCE_DIRS",
    "REFERENCE_ROOT",
    "ROWS",
    "STATUSES",
    "TABLES",
    "TMP_PREFIX",
    "DamagedRowWarning",
    "ResultsDirError",
    "check_results_dir",
    "checkpoint_curves_frame",
    "checkpoints_frame",
    "clear_orphans",
    "compare_folders",
    "curves_frame",
    "done_hashes",
    "holds_runs",
    "jsonable",
    "load_checkpoints",
    "load_curves",
    "load_runs",
    "read_rows",
    "rebuild_tables",
    "record_schema",
    "reference_dir",
    "rows_digest",
    "rows_frame",
    "runs_of",
    "scan_rows",
    "stale_tables",
    "tmp_prefix",
    "unread_rows",
    "write_row",
]
