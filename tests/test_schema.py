"""The results schema: every column the store writes is documented, nothing
documented is unknown to it, and results/SCHEMA.md is the generated text."""

from __future__ import annotations

from pathlib import Path

import pytest

from bench.core import (
    CONTROLLED_COLUMNS,
    FRAME_METRICS,
    MEASURED_COLUMNS,
    PIXEL_METRICS,
    RunConfig,
    _schema,
    _store,
    check_runnable,
    execute_run,
)

ROOT = Path(__file__).resolve().parents[1]
SMOKE = dict(
    n_generated=20, n_train=16, n_test=4, test_chunks=4, width=16, steps=20, batch=8, chunk=5
)
# Columns that only some runs carry: a run that fails has no metrics, an ensemble member sets
# ensemble_size, and the runner adds experiment/profile/ensemble_size when it stores a row.
OPTIONAL = {"error", "diverged_step", "experiment", "profile", "ensemble_size"}
# Pixel, frames, measured and controlled runs' own columns: stored by the sweeps of
# tests/test_pixels.py, tests/test_vin_blog.py, tests/test_real_pendulum.py and
# tests/test_controlled_runs.py.
OPTIONAL |= {*PIXEL_METRICS, *FRAME_METRICS, *MEASURED_COLUMNS, *CONTROLLED_COLUMNS}
OPTIONAL.add("plugin_source")  # plug-in models' rows only: tests/test_plugin_source.py


@pytest.fixture(scope="module")
def rows(tmp_path_factory):
    cache = tmp_path_factory.mktemp("cache")
    out = []
    for cfg in (
        # a trained model in (q, p) with checkpoints, and a trivial predictor
        RunConfig(
            system="chain_pendulum",
            k=1,
            model="node",  # the cheapest model that runs in (q, p)
            coordinates="momentum",
            eval_checkpoints=2,
            **SMOKE,
        ),
        RunConfig(system="chain_pendulum", k=1, model="constant_velocity", **SMOKE),
    ):
        row = execute_run(check_runnable(cfg), cache_root=cache)
        row.update(experiment="schema", profile="smoke", ensemble_size=1)
        out.append(_store.jsonable(row))
    return out


def test_every_stored_column_is_documented_and_every_documented_one_is_stored(rows):
    frames = {
        "runs": _store.rows_frame(rows),
        "curves": _store.curves_frame(rows),
        "checkpoints": _store.checkpoints_frame(rows),
        "checkpoint_curves": _store.checkpoint_curves_frame(rows),
    }
    for table, df in frames.items():
        missing = [c for c in df.columns if not _schema.documented(table, c)]
        assert not missing, f"{table}: undocumented columns {missing}"
        stored = set(df.columns)
        never = [
            c
            for c in _schema.COLUMNS[table]
            if c not in stored and c not in OPTIONAL and not c.endswith("_<i>")
        ]
        assert not never, f"{table}: documented but not stored {never}"
    assert any(c.startswith("z_true_") for c in frames["curves"].columns)


def test_documented_matches_wildcards_only_on_indices():
    assert _schema.documented("curves", "z_pred_11")
    assert not _schema.documented("curves", "z_pred_x")
    assert not _schema.documented("runs", "no_such_column")


def test_every_entry_has_a_unit_and_a_meaning():
    for table, cols in _schema.COLUMNS.items():
        for name, (unit, meaning) in cols.items():
            assert unit and len(meaning) > 5, (table, name)


def test_schema_md_is_current():
    assert (ROOT / "results" / "SCHEMA.md").read_text() == _schema.markdown(), (
        "results/SCHEMA.md is stale: python -m bench.core._schema"
    )
