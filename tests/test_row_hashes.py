"""The hashes that name stored runs are a function of their configuration alone: every
committed row under ``results/reference/*/`` hashes, through :class:`RunConfig`, to the
``config_hash`` and ``train_hash`` it was stored under (no training: the rows are read only)."""

from pathlib import Path

import pytest

from bench.core import RunConfig, _store

REFERENCE = Path(__file__).resolve().parents[1] / "results" / "reference"
FOLDERS = sorted(d for d in REFERENCE.iterdir() if (d / _store.ROWS).is_dir())


def test_there_are_committed_rows_to_check():
    assert FOLDERS, f"no folder with {_store.ROWS}/ under {REFERENCE}"


@pytest.mark.parametrize("folder", FOLDERS, ids=lambda d: d.name)
def test_every_committed_row_hashes_to_its_stored_hashes(folder):
    files = [p for p in (folder / _store.ROWS).glob("*.json") if not p.name.startswith(".")]
    rows, damaged = _store.scan_rows(folder, set_aside=False)  # read only: nothing moved
    assert not damaged and len(rows) == len(files) > 0
    wrong = []
    for row in rows:
        config = RunConfig.from_dict(row)
        got = (config.config_hash, config.train_hash)
        if got != (row["config_hash"], row["train_hash"]):
            wrong.append((row["config_hash"], row["train_hash"], *got))
    assert not wrong, (
        f"{len(wrong)} of {len(rows)} rows of {folder.name} rehash otherwise: {wrong[:5]}"
    )
