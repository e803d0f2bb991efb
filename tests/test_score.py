"""``python -m bench score`` and ``compare --scores``: predictions from any framework, scored.

A small export (the chain pendulum at k = 2, smoke profile: angles, both coordinate systems)
gets predictions made from its own test windows (perturbed, some angles shifted by 2 pi, one
trajectory non-finite from some time on). The suite's scorer must give the numbers of a run's
own evaluation (``bench.core._evaluate._score``) on the same predictions, and the exported
loader's NumPy scorer the same within float tolerance, also in an interpreter without the suite.
Bad inputs get one line each; ``compare --scores`` sets the scores beside synthetic reference
runs on the same data (tests/_synthetic.py: no training)."""

import json
import shutil
import subprocess
import sys
import types

import numpy as np
import pandas as pd
import pytest
from _synthetic import synthetic_tables

import systems
from bench import _cli, _data, _score, data_loader, metrics
from bench.core import SCHEMA_VERSION, _evaluate

SYSTEM, K, PROFILE = "chain_pendulum", 2, "smoke"


@pytest.fixture(scope="module")
def export(tmp_path_factory):
    folder = tmp_path_factory.mktemp("score") / "export"
    _data.export(SYSTEM, folder, profile=PROFILE, k=K, progress=lambda m: 0)
    return folder


def _predictions(folder) -> dict:
    rng = np.random.default_rng(1)
    out = {}
    for name in data_loader.datasets(folder):
        z = data_loader.load(folder, name)["z_test"]
        t = np.arange(z.shape[1])[None, :, None] / z.shape[1]
        zhat = z + 0.05 * t * rng.standard_normal(z.shape)
        zhat[0, :, :K] += 2 * np.pi  # the same angles: no error
        zhat[-1, z.shape[1] // 2 :, 0] = np.nan  # diverged half-way: scored as 1 from there
        out[name] = zhat
    return out


@pytest.fixture(scope="module")
def predicted(export, tmp_path_factory):
    path = tmp_path_factory.mktemp("pred") / "mine.npz"
    np.savez(path, **_predictions(export))
    return path


def test_the_scorer_gives_the_numbers_of_a_run_evaluation(export, predicted):
    rows = _score.score(predicted, export, model="mine")
    card = data_loader.read_card(export)
    assert list(rows["dataset"]) == data_loader.datasets(export)
    assert set(rows["coordinates"]) == {"velocity", "momentum"}
    preds = data_loader.read_predictions(predicted)
    for row in rows.to_dict("records"):
        e = card["datasets"][row["dataset"]]
        config = systems.DatasetConfig(**e["config"])
        assert config.hash() == e["config_hash"] == row["dataset_hash"]
        data = systems.make_dataset(config)
        system = systems.make(config.system, **dict(config.system_params))
        how = types.SimpleNamespace(coordinates=config.coordinates, random_args=config.random_args)
        expected, *_ = _evaluate._score(how, system, data, preds[row["dataset"]])
        for metric, value in expected.items():
            np.testing.assert_allclose(row[metric], value, rtol=1e-12, err_msg=metric)
        assert 0 < row["rollout_error"] < 1 and 0 < row["energy_violation"] < 1
        assert np.isnan(row["mse"])  # a non-finite prediction: NaN, as the runs record it
        assert (row["model"], row["system"], row["k"], row["seed"]) == ("mine", SYSTEM, K, 0)
        assert row["profile"] == PROFILE and row["n_train"] == config.n_train
        assert not row["starts_at_z0"]  # one trajectory's angles shifted by 2 pi


def test_the_numpy_loader_scores_as_the_suite(export, predicted):
    suite = _score.score(predicted, export).set_index("dataset")
    finite = {n: np.nan_to_num(z) for n, z in data_loader.read_predictions(predicted).items()}
    suite_finite = _score.score(finite, export).set_index("dataset")
    for preds, expected in ((predicted, suite), (finite, suite_finite)):
        for row in data_loader.score(export, preds):
            want = expected.loc[row["dataset"]]
            assert row["energy"].startswith("true H from the card")
            for metric in ("rollout_error", "energy_violation", "mse", "valid_time"):
                np.testing.assert_allclose(row[metric], want[metric], rtol=1e-9, err_msg=metric)


def test_the_loader_scores_in_an_interpreter_without_the_suite(export, predicted, tmp_path):
    folder = tmp_path / "export"
    shutil.copytree(export, folder)
    shutil.copy(predicted, folder / "mine.npz")
    env = {"PYTHONPATH": str(__import__("pathlib").Path(np.__file__).parents[1])}
    out = subprocess.run(
        [sys.executable, "-S", "decon_data.py", "score", ".", "mine.npz"],
        cwd=folder,
        capture_output=True,
        text=True,
        env=env,
    )
    assert out.returncode == 0, out.stderr
    suite = _score.score(predicted, export).set_index("dataset")
    for line in out.stdout.splitlines():
        name, rest = line.split(": ", 1)
        err = float(rest.split("rollout_error ")[1].split(",")[0])
        assert err == pytest.approx(suite.loc[name, "rollout_error"], rel=1e-3)


@pytest.mark.parametrize(
    ("system", "params", "has_form"),
    [
        ("pendulum", {}, True),
        ("mass_spring", {}, True),
        ("chain_pendulum", {"k": 3}, True),
        ("spring_pendulum", {"k": 2}, True),
        ("two_body", {}, True),
        ("three_body", {}, True),
        ("magnet_pendulum", {}, False),
        ("relativistic_particle", {}, False),
    ],
)
def test_numpy_energies_equal_the_systems_own(system, params, has_form):
    s = systems.make(system, **params)
    rng = np.random.default_rng(0)
    z = rng.standard_normal((3, 5, 2 * s.dof))
    for coordinates in ("velocity", "momentum"):
        d = types.SimpleNamespace(z_test=z, config=types.SimpleNamespace(coordinates=coordinates))
        form = _data.energy_form(s, d)
        assert (form is not None) is has_form
        if form is not None:
            json.dumps(form)  # the card holds it
            want = metrics.energies(s, z, None, coordinates)
            got = data_loader.energy(form, z, coordinates)
            np.testing.assert_allclose(got, want, rtol=1e-10)


def test_a_card_without_energy_says_so(export, predicted, tmp_path, capsys):
    folder = tmp_path / "export"
    shutil.copytree(export, folder)
    card = json.loads((folder / "card.json").read_text())
    for e in card["datasets"].values():
        e.pop("energy")
    (folder / "card.json").write_text(json.dumps(card))
    rows = data_loader.score(folder, predicted)
    assert all(np.isnan(r["energy_violation"]) for r in rows)
    assert all(r["energy"] == data_loader.NO_ENERGY for r in rows)
    assert data_loader.main(["score", str(folder), str(predicted)]) == 0
    assert "energy_violation not in the card" in capsys.readouterr().out


def _bad(tmp_path, export, arrays, name="bad.npz"):
    path = tmp_path / name
    np.savez(path, **arrays)
    return path


@pytest.mark.parametrize("case", ["shape", "unknown", "missing", "suffix", "absent", "system"])
def test_bad_input_gets_one_line_naming_what_is_allowed(case, export, tmp_path, capsys):
    names = data_loader.datasets(export)
    z = data_loader.load(export, names[0])["z_test"]
    argv = ["score", None, "--data", str(export)]
    if case == "shape":
        argv[1], message = _bad(tmp_path, export, {names[0]: z[..., :-1]}), "expected"
    elif case == "unknown":
        argv[1], message = _bad(tmp_path, export, {"z_pred": z}), f"allowed: {names[0]}"
    elif case == "missing":
        argv[1] = _bad(tmp_path, export, {names[0]: z})
        argv += ["--dataset", names[1]]
        message = f"has no array '{names[1]}'"
    elif case == "suffix":
        argv[1], message = tmp_path / "pred.txt", "allowed suffixes .npz, .h5, .hdf5"
    elif case == "absent":
        argv[1], message = tmp_path / "none.npz", "does not exist"
    else:
        folder = tmp_path / "export"
        shutil.copytree(export, folder)
        card = json.loads((folder / "card.json").read_text())
        card["system"]["name"] = "nope"
        (folder / "card.json").write_text(json.dumps(card))
        argv[1], argv[3] = _bad(tmp_path, export, {names[0]: z}), str(folder)
        message = "unknown system 'nope'; allowed: chain_pendulum"
    assert _cli.main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1, err


def test_scores_file_rows_are_replaced_per_model_and_dataset(export, predicted, tmp_path):
    out = tmp_path / "scores.parquet"
    first = _score.score(predicted, export, model="a")
    _score.write_scores(first, out)
    _score.write_scores(_score.score(predicted, export, model="b"), out)
    held = _score.write_scores(first.assign(rollout_error=0.5), out)
    assert len(held) == 2 * len(first) and len(pd.read_parquet(out)) == len(held)
    assert (held.loc[held["model"] == "a", "rollout_error"] == 0.5).all()


def test_compare_sets_the_scores_beside_the_reference(export, predicted, tmp_path, capsys):
    runs, _ = synthetic_tables(PROFILE, experiments=["second_order"])
    ref = tmp_path / "ref"
    ref.mkdir()
    runs.to_parquet(ref / "runs.parquet", index=False)
    (ref / "bench_meta.json").write_text(json.dumps({"schema_version": SCHEMA_VERSION}))
    scores = tmp_path / "scores.csv"
    argv = ["score", str(predicted), "--data", str(export), "--model", "mine", "--out", scores]
    assert _cli.main([str(a) for a in argv]) == 0
    assert "python -m bench compare --scores" in capsys.readouterr().out

    md = tmp_path / "beside.md"
    assert _cli.main(["compare", str(ref), "--scores", str(scores), "--out", str(md)]) == 0
    out = capsys.readouterr().out
    assert out == md.read_text()

    text, tables = _score.beside(_score.read_scores(scores), ref)
    assert out.strip() == text.strip()  # what is printed and written: the tables below
    used = pd.read_csv(scores)
    # the momentum twins: no experiment trains on them, so no reference table
    assert set(tables) < set(used["cell_hash"])
    assert all((t["model"] == "**mine** (yours)").sum() == 1 for t in tables.values())
    velocity = used.loc[used["dataset"] == "velocity_n16_seed0", "cell_hash"].iloc[0]
    t = tables[velocity]
    chain = runs[(runs["system"] == SYSTEM) & (runs["k"] == K)]
    assert len(t) == chain["model"].nunique() + 1
    for model, g in chain.groupby("model"):
        r = t[t["model"].str.split().str[0] == model].iloc[0]
        assert r["rollout_error_median"] == pytest.approx(g["rollout_error"].median())
        assert r["rollout_error_min"] == pytest.approx(g["rollout_error"].min())
        assert r["seeds"] == "0-4"
    mine = used.loc[used["dataset"] == "velocity_n16_seed0", "rollout_error"].iloc[0]
    assert t["rollout_error_median"].is_monotonic_increasing
    for r in t[t["model"] != "**mine** (yours)"].to_dict("records"):
        seeds = chain.loc[chain["model"] == r["model"].split()[0], "rollout_error"]
        seed0 = chain.loc[(chain["model"] == r["model"].split()[0]) & (chain["seed"] == 0)]
        lower = int(mine < seed0["rollout_error"].iloc[0])
        expected = _score._position(mine, seeds.to_numpy())
        assert r["vs mine"] == f"{expected}; same data: yours lower on {lower} of 1 seed"


def test_compare_with_scores_takes_one_folder(tmp_path, capsys, export, predicted):
    scores = tmp_path / "s.csv"
    _score.write_scores(_score.score(predicted, export), scores)
    assert _cli.main(["compare", "A", "B", "--scores", str(scores)]) == 2
    assert "takes one folder" in capsys.readouterr().err
    assert _cli.main(["compare", "--scores", str(tmp_path / "none.csv")]) == 2
    assert "not a scores file" in capsys.readouterr().err
