"""``python -m bench preflight``: each cell once, trained a few steps, nothing stored, and a
cell that cannot run named in one line with exit code 1."""

import dataclasses

import pytest

from bench import _cli
from bench._preflight import cells, preflight
from bench.core import _experiments as E
from bench.studies.decon import mujoco


@pytest.fixture
def broken(monkeypatch):
    """The MuJoCo experiment at smoke with more test trajectories than its stand-in data hold:
    it builds only at run time, as the paper-size Hopper cells once did not."""
    smoke = {**mujoco.EXPERIMENT.profile_overrides["smoke"], "n_test": 10_000}
    exp = dataclasses.replace(
        mujoco.EXPERIMENT, name="broken_mujoco", profile_overrides={"smoke": smoke}
    )
    monkeypatch.setitem(E._REGISTRY, exp.name, exp)
    return exp


def test_each_cell_once_labelled_by_the_axes_that_vary():
    got = cells(["vin"], "smoke")
    runs = E.expand("vin", "smoke")
    distinct = {dataclasses.replace(c, seed=0).config_hash for c in runs}
    assert len(got) == len(distinct) and {c.seed for _, c, _ in got} == {0}
    assert all(name == "vin" for name, _, _ in got)
    labels = [label for _, _, label in got]
    assert len(set(labels)) == len(labels)
    assert labels[0].startswith("model=vin n_train=8 noise=0.0") and labels[0].endswith("seed=0")
    assert "system=" not in labels[0]  # one system at smoke: not a varying axis


def test_a_preflight_trains_its_steps_and_stores_nothing(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    lines = []
    rows = preflight(["hnn_seed_mass_spring"], "smoke", steps=1, echo=lines.append)
    assert [r["status"] for r in rows] == ["ok"] * len(cells(["hnn_seed_mass_spring"], "smoke"))
    assert all(r["steps"] == 1 and r["eval_checkpoints"] == 0 for r in rows)
    assert len(lines) == len(rows) and lines[0].startswith(f"[1/{len(rows)}] ok")
    # no results folder: only the cache a run's data and artifacts go to
    assert [p.name for p in tmp_path.iterdir()] in ([], [".cache"])
    with pytest.raises(ValueError, match="steps must be an integer >= 1"):
        preflight(["hnn_seed_mass_spring"], "smoke", steps=0)


def test_a_cell_that_cannot_run_fails_in_one_line_and_the_verb_exits_1(broken, capsys):
    rows = preflight([broken], "smoke", echo=None)
    trained = [r for r in rows if r["model"] != "constant_velocity"]
    assert trained and all(r["status"] == "failed" for r in rows)
    assert "windows of" in rows[0]["error"] and "asked" in rows[0]["error"]
    assert _cli.main(["preflight", broken.name, "--profile", "smoke"]) == 1
    out = capsys.readouterr().out.splitlines()
    assert out[-1] == f"preflight at smoke: {len(rows)} cells, {len(rows)} failed"
    assert all(" failed " in line and "asked" in line for line in out[:-1])
    assert (
        _cli.main(["preflight", "hnn_seed_mass_spring", "--profile", "smoke", "--steps", "1"]) == 0
    )
