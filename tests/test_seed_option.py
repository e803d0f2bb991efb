"""``--seeds`` takes seeds the way the docs write them: integers, ranges with both ends
included, and lists mixing the two; anything else is one line naming the allowed forms."""

from __future__ import annotations

import pandas as pd
import pytest

from bench.core import seed_list


@pytest.mark.parametrize(
    ("given", "seeds"),
    [
        ("5,6,7", (5, 6, 7)),
        ("0-4", (0, 1, 2, 3, 4)),
        ("0-4,7", (0, 1, 2, 3, 4, 7)),
        ("9, 2-3", (9, 2, 3)),  # the order given, spaces allowed
        ("3-3", (3,)),
        ("1-2,2,0-1", (1, 2, 0)),  # each seed once
    ],
)
def test_seeds_accept_integers_ranges_and_mixed_lists(given, seeds):
    assert seed_list(given) == seeds


@pytest.mark.parametrize("bad", ["", "5,x", "-1", "4-2", "0-", "0-4,,7", "1.5", "0--4", "٣"])
def test_bad_seeds_get_one_line_naming_the_forms(bad):
    with pytest.raises(ValueError) as e:
        seed_list(bad)
    message = str(e.value)
    assert message.startswith("--seeds must be integers >= 0 or ranges a-b")
    assert "0-4,7" in message and repr(bad) in message and "\n" not in message


def test_sweep_runs_the_seeds_of_a_range(tmp_path, monkeypatch, capsys):
    """Through the CLI, the runs faked: ``--seeds 0-1,3`` stores seeds 0, 1 and 3; a range
    that runs backwards stops the sweep in one line (exit code 2) before anything is stored."""
    import bench.core._runner as runner
    from bench._cli import main
    from bench.core import base_row

    monkeypatch.setattr(runner, "execute_run", lambda c, **kw: {**base_row(c), "status": "ok"})
    argv = ["sweep", "second_order", "--profile", "smoke", "--models", "node", "--no-progress"]
    assert main(["--results", str(tmp_path / "bad"), *argv, "--seeds", "3-1"]) == 2
    err = capsys.readouterr().err
    assert "--seeds must be integers >= 0 or ranges" in err and err.count("\n") == 1
    assert not (tmp_path / "bad" / ".rows").exists()
    assert main(["--results", str(tmp_path / "ok"), *argv, "--seeds", "0-1,3"]) == 0
    runs = pd.read_parquet(tmp_path / "ok" / "runs.parquet")
    assert set(runs["seed"]) == {0, 1, 3}
