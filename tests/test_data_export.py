"""``bench data export | verify`` and the exported folder's loader.

The exported arrays are checked against the datasets the runs of the profile train on (built
independently through ``RunConfig.dataset_config``), the card's checksums against ``hashlib``
on the files' raw arrays, and ``verify`` against folders damaged on purpose (a changed value,
a missing file, a file the card does not name) in both formats. The loader copied into the
folder runs in an isolated interpreter that cannot import the suite."""

import hashlib
import json
import shutil
import subprocess
import sys

import numpy as np
import pytest

from bench import _cli, _data, data_loader
from bench.core._experiments import expand

SYSTEM, K, PROFILE = "chain_pendulum", 2, "smoke"


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    root = tmp_path_factory.mktemp("data")
    cards = {
        fmt: _data.export(SYSTEM, root / fmt, profile=PROFILE, k=K, fmt=fmt, progress=lambda m: 0)
        for fmt in data_loader.FORMATS
    }
    return root, cards


def _copy(exported, fmt, tmp_path):
    root, _ = exported
    shutil.copytree(root / fmt, tmp_path / fmt)
    return tmp_path / fmt


def test_export_holds_the_exact_arrays_the_runs_train_on(exported):
    root, cards = exported
    import systems

    runs = [r for r in expand("second_order", PROFILE) if r.system == SYSTEM and r.k == K]
    assert runs
    expected = systems.make_dataset(runs[0].dataset_config())
    card = cards["npz"]
    name = next(
        n
        for n, e in card["datasets"].items()
        if e["config_hash"] == runs[0].dataset_config().hash()
    )
    assert "second_order" in card["datasets"][name]["used_by_experiments"]
    for fmt in data_loader.FORMATS:
        got = data_loader.load(root / fmt, name)
        for a in data_loader.ARRAYS:
            np.testing.assert_array_equal(got[a], getattr(expected, a))


def test_both_coordinate_systems_of_every_dataset(exported):
    _, cards = exported
    entries = cards["npz"]["datasets"].values()
    pairs = {}
    for e in entries:
        key = json.dumps({**e["config"], "coordinates": None}, sort_keys=True, default=str)
        pairs.setdefault(key, set()).add(e["coordinates"])
    assert pairs and all(v == {"velocity", "momentum"} for v in pairs.values())


def test_card_names_protocol_generator_suite_and_checksums(exported):
    root, cards = exported
    card = json.loads((root / "npz" / "card.json").read_text())
    assert card == json.loads(json.dumps(cards["npz"]))
    assert card["protocol"]["dt"] == 0.03 and card["protocol"]["chunk"] == 5
    assert "rtol=1e-11" in card["generator"]["step_size_controller"]
    assert card["suite"]["commit"] and card["suite"]["version"]
    assert len(card["arrays"]) == 6 * len(card["datasets"])
    for e in card["arrays"][:6]:  # recompute with hashlib on the stored array
        with np.load(root / "npz" / e["file"]) as f:
            raw = np.ascontiguousarray(f[e["key"]], "<f8").tobytes()
        assert hashlib.sha256(raw).hexdigest() == e["sha256"]
    readme = (root / "npz" / "README.md").read_text()
    assert "## Protocol" in readme and card["arrays"][0]["sha256"] in readme


@pytest.mark.parametrize("fmt", data_loader.FORMATS)
def test_verify_passes_then_names_a_damaged_array(exported, fmt, tmp_path, capsys):
    folder = _copy(exported, fmt, tmp_path)
    assert data_loader.verify(folder) == []
    assert _cli.main(["data", "verify", str(folder)]) == 0
    entry = next(e for e in data_loader.read_card(folder)["arrays"] if e["array"] == "z_train")
    if fmt == "npz":
        path = folder / entry["file"]
        with np.load(path) as f:
            arrays = {k: np.array(f[k]) for k in f.files}
        arrays["z_train"][0, 0, 0] += 1e-12  # one value, one ulp-ish change
        np.savez(path, **arrays)
    else:
        import h5py

        with h5py.File(folder / entry["file"], "r+") as f:
            f[entry["key"]][0, 0, 0] += 1e-12
    problems = data_loader.verify(folder)
    assert problems == [
        f"{entry['file']}:{entry['key']}: sha256 differs from the card "
        "(the array was changed or damaged)"
    ]
    capsys.readouterr()
    assert _cli.main(["data", "verify", str(folder)]) == 1
    out = capsys.readouterr().out
    assert f"damaged: {entry['file']}:{entry['key']}" in out
    with pytest.raises(ValueError, match="sha256 differs"):
        data_loader.load(folder, entry["dataset"])


def test_verify_names_a_missing_file_and_an_unknown_one(exported, tmp_path):
    folder = _copy(exported, "npz", tmp_path)
    files = sorted(folder.glob("*.npz"))
    files[0].rename(folder / "renamed.npz")
    problems = data_loader.verify(folder)
    assert problems == [
        f"{files[0].name}: missing",
        "renamed.npz: a data file the card does not name",
    ]


def test_loader_in_the_folder_runs_without_the_suite(exported, tmp_path):
    folder = _copy(exported, "npz", tmp_path)
    code = (
        "import sys; sys.path.insert(0, '.')\n"
        "import importlib.util\n"
        "assert importlib.util.find_spec('bench') is None, 'the suite is importable'\n"
        "import decon_data\n"
        "names = decon_data.datasets('.')\n"
        "d = decon_data.load('.', names[0])\n"
        "t = decon_data.Trajectories('.', names[0], split='test')\n"
        "z, a = t[0]\n"
        "assert z.shape == d['z_test'].shape[1:] and len(t) == len(d['z_test'])\n"
        "print(len(names))\n"
    )
    # -I: isolated (no site-packages of the user, no cwd on the path); -S: no site at all,
    # so the editable install of the suite is invisible; numpy comes in through PYTHONPATH
    import numpy

    env = {"PYTHONPATH": str(__import__("pathlib").Path(numpy.__file__).parents[1])}
    out = subprocess.run(
        [sys.executable, "-S", "-c", code], cwd=folder, capture_output=True, text=True, env=env
    )
    if "the suite is importable" in out.stderr:
        pytest.skip("the suite is installed beside numpy (not an editable install)")
    assert out.returncode == 0, out.stderr
    assert int(out.stdout) == len(data_loader.datasets(folder))
    verify = subprocess.run(
        [sys.executable, "-S", "decon_data.py", "verify", "."],
        cwd=folder,
        capture_output=True,
        text=True,
        env=env,
    )
    assert verify.returncode == 0 and "all" in verify.stdout, verify.stderr


def test_trajectories_items_and_torch_adapter(exported, monkeypatch):
    root, _ = exported
    folder = root / "npz"
    name = data_loader.datasets(folder)[0]
    arrays = data_loader.load(folder, name)
    t = data_loader.Trajectories(folder, name, split="train")
    assert len(t) == len(arrays["z_train"])
    z, a = t[len(t) - 1]
    np.testing.assert_array_equal(z, arrays["z_train"][-1])
    np.testing.assert_array_equal(t.ts, arrays["ts_train"])
    with pytest.raises(ValueError, match="allowed train, test"):
        data_loader.Trajectories(folder, name, split="val")
    with pytest.raises(ValueError, match="name one of"):
        data_loader.load(folder)  # several datasets: which one
    monkeypatch.setitem(sys.modules, "torch", None)  # torch absent: one clear error
    with pytest.raises(ImportError, match=r"decon-bench\[torch\]"):
        data_loader.TorchDataset(folder, name)


def test_torch_dataset_batches_the_arrays(exported):
    torch = pytest.importorskip("torch")
    root, _ = exported
    folder = root / "npz"
    name = data_loader.datasets(folder)[0]
    arrays = data_loader.load(folder, name)
    ds = data_loader.TorchDataset(folder, name, split="test")
    z, a = next(iter(torch.utils.data.DataLoader(ds, batch_size=len(ds))))
    np.testing.assert_array_equal(z.numpy(), arrays["z_test"])
    assert z.dtype == torch.float64 and tuple(ds.ts.shape) == arrays["ts_test"].shape


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["data", "export", "nope", "--out", "X"],
            "unknown system 'nope'; allowed: chain_pendulum",
        ),
        (["data", "export", SYSTEM, "--format", "csv", "--out", "X"], "format 'csv'"),
        (["data", "export", "relativistic_particle", "--k", "2", "--out", "X"], "takes no k"),
        (["data", "export", SYSTEM, "--profile", "huge", "--out", "X"], "profile 'huge'"),
        (["data", "export", SYSTEM, "--seeds", "a", "--out", "X"], "--seeds must be integers"),
        (["data", "verify", "NOFOLDER"], "no card.json"),
    ],
)
def test_bad_input_one_line(argv, message, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert _cli.main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert not (tmp_path / "X").exists()


def test_export_refuses_a_non_empty_folder_and_loses_nothing(tmp_path, capsys):
    (tmp_path / "mine.txt").write_text("keep")
    assert _cli.main(["data", "export", SYSTEM, "--out", str(tmp_path)]) == 2
    assert "not empty" in capsys.readouterr().err
    assert [p.name for p in tmp_path.iterdir()] == ["mine.txt"]
