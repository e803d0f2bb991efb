"""``bench data export | verify`` and the exported folder's loader.

The exported arrays are checked against the datasets the runs of the profile train on (built
independently through ``RunConfig.dataset_config``), the card's checksums against ``hashlib``
on the files' raw arrays, and ``verify`` against folders damaged on purpose (a changed value,
a missing file, a file the card does not name) in both formats. The loader copied into the
folder runs in an isolated interpreter that cannot import the suite."""

import hashlib
import importlib.util
import json
import re
import shutil
import subprocess
import sys

import numpy as np
import pytest
from _markdown import section

from bench import _cli, _data, data_loader
from bench.core import expand

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
    assert section(readme, "Protocol") is not None and card["arrays"][0]["sha256"] in readme
    # self-contained: no file of the suite's maintainers cited, no cache internals, and the
    # card's licence and citation stated
    cited = set(re.findall(r"\b[A-Z][A-Za-z_]*\.md\b", readme)) - {"README.md"}
    assert not cited, cited  # no file outside the export cited
    for internal in ("Cache:", "os.replace"):
        assert internal not in readme, internal
    assert card["license"].startswith("MIT") and "ICLR 2022" in card["citation"]
    assert section(readme, "Licence and citation") is not None


def test_card_names_every_parameter_one_way(exported):
    """The system's parameters and each dataset's are one mapping, keyed by the system's own
    parameter names, defaults included: a parameter given at its default and one left out read
    alike; a parameter that differs between the datasets reads "varies" at the top."""
    import systems

    _, cards = exported
    card = cards["npz"]
    names = systems.parameters(SYSTEM)
    top = card["system"]["parameters"]
    assert list(top) == names and top["k"] == K and top["g"] == 9.81
    for e in card["datasets"].values():
        params = e["parameters"]
        assert list(params) == names
        built = systems.make(SYSTEM, **dict(e["config"]["system_params"]))
        np.testing.assert_allclose(params["lengths"], built.lengths)
        for key, value in dict(e["config"]["system_params"]).items():  # what was given
            np.testing.assert_allclose(params[key], value)
    for key, value in top.items():
        seen = {json.dumps(e["parameters"][key]) for e in card["datasets"].values()}
        assert (value == "varies") == (len(seen) > 1), (key, value, seen)


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


def test_verify_without_h5py_says_so_in_one_line(tmp_path, monkeypatch, capsys):
    """An hdf5 folder checked where h5py is not installed: one line naming the dependency and
    how to install it (exit code 2), not every array of the card reported damaged."""
    names = [f"velocity_n{n}_seed{s}" for n in (10, 20, 40, 80, 160) for s in range(6)]
    card = {name: {a: np.zeros(2) for a in data_loader.ARRAYS} for name in names}
    folder = tmp_path / "h5"
    monkeypatch.setattr(data_loader, "_h5py", lambda: _FakeH5)  # a writer that needs no h5py
    data_loader.write(folder, card, {"system": SYSTEM}, "hdf5")
    monkeypatch.undo()
    assert len(data_loader.read_card(folder)["arrays"]) == 180
    monkeypatch.setitem(sys.modules, "h5py", None)  # import h5py: ImportError
    for main, argv in ((data_loader.main, ["verify"]), (_cli.main, ["data", "verify"])):
        assert main([*argv, str(folder)]) == 2
        out, err = capsys.readouterr()
        assert out == "" and err.count("\n") == 1, (out[:300], err[:300])
        assert err.startswith("error: ") and "data.h5" in err
        assert "need h5py" in err and "pip install h5py" in err
    with pytest.raises(ImportError, match="pip install h5py"):
        data_loader.verify(folder)


class _FakeH5:
    """Just enough of ``h5py.File`` for :func:`data_loader.write` to leave a ``data.h5``."""

    class File:
        def __init__(self, path, mode):
            self.path = path

        def __enter__(self):
            open(self.path, "wb").close()
            return self

        def __exit__(self, *exc):
            return False

        def create_group(self, name):
            return self

        def create_dataset(self, name, data):
            pass


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
    env = {"PYTHONPATH": str(__import__("pathlib").Path(np.__file__).parents[1])}
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


def _tiny(folder):
    """An npz folder of one dataset of 3 chunks and 2 test windows (made-up numbers)."""
    rng = np.random.default_rng(0)
    shapes = {"ts_train": (4,), "z_train": (3, 4, 2), "args_train": (3, 1), "ts_test": (5,)}
    shapes.update(z_test=(2, 5, 2), args_test=(2, 1))
    arrays = {a: rng.normal(size=shape) for a, shape in shapes.items()}
    data_loader.write(folder, {"tiny": arrays}, {"system": SYSTEM}, "npz")
    return arrays


def _stub_torch(monkeypatch):
    """Just enough of torch (``from_numpy``, ``utils.data.Dataset``) for the adapter, where
    torch is not installed; the adapter's class is made afresh over it and dropped after."""
    import types

    torch = types.ModuleType("torch")
    torch.from_numpy = lambda a: ("tensor", a)
    utils, data = types.ModuleType("torch.utils"), types.ModuleType("torch.utils.data")
    data.Dataset = type("Dataset", (), {})
    torch.utils, utils.data = utils, data
    for name, module in (("torch", torch), ("torch.utils", utils), ("torch.utils.data", data)):
        monkeypatch.setitem(sys.modules, name, module)
    monkeypatch.setattr(data_loader, "_TORCH_CLASS", [])


@pytest.mark.parametrize("dtype", data_loader.TORCH_DTYPES)
def test_torch_dataset_pickles_and_takes_a_dtype(tmp_path, monkeypatch, dtype):
    """A spawned DataLoader worker gets the dataset by pickle: the round trip gives the same
    items, in the dtype asked for (torch stubbed where it is not installed)."""
    import pickle

    if importlib.util.find_spec("torch") is None:
        _stub_torch(monkeypatch)
    arrays = _tiny(tmp_path)
    ds = data_loader.TorchDataset(tmp_path, split="test", dtype=dtype)
    again = pickle.loads(pickle.dumps(ds))
    assert type(again) is type(ds) and len(again) == len(ds) == 2
    assert again.dtype == dtype
    for i in range(len(ds)):
        for x, want in zip(again[i], (arrays["z_test"][i], arrays["args_test"][i]), strict=True):
            x = np.asarray(x[1] if isinstance(x, tuple) else x)  # the stub's ("tensor", a)
            assert x.dtype == np.dtype(dtype)
            np.testing.assert_array_equal(x, want.astype(dtype))
    with pytest.raises(ValueError, match="dtype 'float16': allowed float64, float32"):
        data_loader.TorchDataset(tmp_path, dtype="float16")


def test_torch_dataset_in_spawned_workers(tmp_path):
    torch = pytest.importorskip("torch")
    arrays = _tiny(tmp_path)
    ds = data_loader.TorchDataset(tmp_path, split="train", dtype="float32")
    loader = torch.utils.data.DataLoader(
        ds, batch_size=3, num_workers=1, multiprocessing_context="spawn"
    )
    (z, args), *rest = list(loader)
    assert not rest and z.dtype == torch.float32 and ds.ts.dtype == torch.float32
    np.testing.assert_array_equal(z.numpy(), arrays["z_train"].astype("float32"))


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


def test_the_docs_state_what_the_export_writes():
    """docs/overview.md's example states the number of datasets and arrays that the export of
    the chain pendulum at k = 2, quick, writes (counted without generating them)."""
    from pathlib import Path

    from bench._data import select

    text = (Path(__file__).resolve().parents[1] / "docs" / "overview.md").read_text()
    m = re.search(r"-> (\d+) datasets .*?, (\d+) arrays", text)
    assert m, "docs/overview.md no longer states the export's counts"
    configs, _ = select("chain_pendulum", "quick", k=2)
    assert int(m.group(1)) == len(configs)
    assert int(m.group(2)) == len(configs) * len(data_loader.ARRAYS)
