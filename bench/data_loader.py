"""Read, check and write exported decon-bench datasets (``python -m bench data export``).

Self-contained on purpose: it imports only the standard library and NumPy (h5py for ``.h5``
files and torch for :func:`TorchDataset`, each only when used), and ``bench data export``
copies it into every exported folder as ``decon_data.py``, so that a folder can be loaded and
checked in any framework without installing the suite::

    import decon_data                                  # or: from bench import data_loader
    decon_data.datasets("DIR")                         # the names of the datasets in DIR
    d = decon_data.load("DIR", "velocity_n200_seed0")  # {"z_train": ndarray, ...}, checked
    problems = decon_data.verify("DIR")                # [] when every array matches the card
    rows = decon_data.score("DIR", "predictions.npz")  # the suite's test metrics, NumPy only

    python decon_data.py verify DIR                    # the same from the shell
    python decon_data.py score DIR predictions.npz

A folder holds ``card.json`` (the dataset card: system, parameters, protocol, generator, the
suite's version and commit, and every array's file, key, shape, dtype and sha256), ``README.md``
(the card for people), the arrays, and this file. Each dataset has six float64 arrays:

- ``ts_train`` (C,): the times of a training chunk, ``arange(C) * dt``;
- ``z_train`` (N, C, 2d): N training chunks of C consecutive states;
- ``args_train`` (N, P): each chunk's system parameters;
- ``ts_test`` (T,), ``z_test`` (M, T, 2d), ``args_test`` (M, P): the test windows.

A state is ``z = (q, qdot)`` in velocity coordinates and ``z = (q, p)`` in momentum
(canonical) coordinates. Format ``npz``: one ``<dataset>.npz`` per dataset, keys as above;
format ``hdf5``: one ``data.h5``, dataset ``/<dataset>/<array>``. The sha256 of an array is that
of its C-ordered little-endian float64 bytes (:func:`sha256`), so any reader can recompute it.
Predicted test windows (one array per dataset, named by it, shaped as its ``z_test``, in an
``.npz`` or ``.h5`` file) get the suite's metrics from :func:`score`; the energy violation
where a dataset's card entry carries the system's H in NumPy form (``energy``).
"""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path

import numpy as np

CARD = "card.json"
ARRAYS = ("ts_train", "z_train", "args_train", "ts_test", "z_test", "args_test")
FORMATS = ("npz", "hdf5")
H5_FILE = "data.h5"
CARD_VERSION = 1


def sha256(a) -> str:
    """sha256 of ``a`` as C-ordered little-endian float64 bytes (the card's checksum)."""
    return hashlib.sha256(np.ascontiguousarray(a, dtype="<f8").tobytes()).hexdigest()


# ------------------------------------------------------------------------------- writing
def write(folder, datasets: dict[str, dict[str, np.ndarray]], card: dict, fmt: str) -> dict:
    """Write ``datasets`` (name -> the six arrays) to ``folder`` in format ``fmt`` and the
    card (``card`` plus the array entries) to ``card.json``; returns the card written."""
    if fmt not in FORMATS:
        raise ValueError(f"format {fmt!r}: allowed {', '.join(FORMATS)}")
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    entries = []
    for name, arrays in datasets.items():
        missing = [a for a in ARRAYS if a not in arrays]
        if missing:
            raise ValueError(f"dataset {name!r} lacks {', '.join(missing)}")
        for a in ARRAYS:
            x = np.ascontiguousarray(arrays[a], dtype="<f8")
            file = f"{name}.npz" if fmt == "npz" else H5_FILE
            key = a if fmt == "npz" else f"{name}/{a}"
            entries.append(
                {
                    "dataset": name,
                    "array": a,
                    "file": file,
                    "key": key,
                    "shape": list(x.shape),
                    "dtype": "float64",
                    "sha256": sha256(x),
                }
            )
    if fmt == "npz":
        for name, arrays in datasets.items():
            np.savez(folder / f"{name}.npz", **{a: np.asarray(arrays[a], "<f8") for a in ARRAYS})
    else:
        h5py = _h5py()
        with h5py.File(folder / H5_FILE, "w") as f:
            for name, arrays in datasets.items():
                g = f.create_group(name)
                for a in ARRAYS:
                    g.create_dataset(a, data=np.asarray(arrays[a], "<f8"))
    card = {**card, "card_version": CARD_VERSION, "format": fmt, "arrays": entries}
    (folder / CARD).write_text(json.dumps(card, indent=2, sort_keys=False) + "\n")
    return card


# ------------------------------------------------------------------------------- reading
def read_card(folder) -> dict:
    """The card of an exported folder (ValueError naming the folder if there is none)."""
    path = Path(folder) / CARD
    try:
        card = json.loads(path.read_text())
    except FileNotFoundError:
        raise ValueError(f"{folder}: no {CARD} (not an exported dataset folder)") from None
    except (OSError, ValueError) as e:
        raise ValueError(f"{path}: unreadable card ({e})") from None
    if not isinstance(card, dict) or not isinstance(card.get("arrays"), list):
        raise ValueError(f"{path}: not a dataset card (no 'arrays' list)")
    return card


def datasets(folder) -> list[str]:
    """The names of the datasets in an exported folder, in the card's order."""
    return list(dict.fromkeys(e["dataset"] for e in read_card(folder)["arrays"]))


def _read(folder: Path, file: str, key: str) -> np.ndarray:
    path = folder / file
    if file.endswith(".npz"):
        with np.load(path, allow_pickle=False) as f:
            return np.array(f[key])
    with _h5py().File(path, "r") as f:
        return np.array(f[key])


def load(folder, dataset: str | None = None, check: bool = True) -> dict[str, np.ndarray]:
    """The six arrays of ``dataset`` (default: the only one, else ValueError naming them);
    ``check``: each array's shape and sha256 against the card (ValueError if one differs)."""
    folder = Path(folder)
    card = read_card(folder)
    names = datasets(folder)
    if dataset is None:
        if len(names) != 1:
            raise ValueError(f"{folder} holds {len(names)} datasets; name one of {names}")
        dataset = names[0]
    if dataset not in names:
        raise ValueError(f"dataset {dataset!r} is not in {folder}; allowed: {', '.join(names)}")
    out = {}
    for e in card["arrays"]:
        if e["dataset"] != dataset:
            continue
        x = _read(folder, e["file"], e["key"])
        if check:
            problem = _problem(e, x)
            if problem:
                raise ValueError(f"{folder}: {problem}")
        out[e["array"]] = x
    return out


def _problem(e: dict, x: np.ndarray) -> str | None:
    where = f"{e['file']}:{e['key']}"
    if list(x.shape) != list(e["shape"]):
        return f"{where}: shape {list(x.shape)}, the card says {e['shape']}"
    if x.dtype != np.float64:
        return f"{where}: dtype {x.dtype}, the card says float64"
    if sha256(x) != e["sha256"]:
        return f"{where}: sha256 differs from the card (the array was changed or damaged)"
    return None


def verify(folder) -> list[str]:
    """Every disagreement between a folder and its card, one line each (empty: all match):
    a missing or unreadable file, a missing key, a shape, dtype or sha256 that differs, and a
    data file the card does not name. A folder in format hdf5 needs h5py: without it, one
    ImportError naming the missing dependency, not every array reported unreadable."""
    folder = Path(folder)
    card = read_card(folder)
    h5 = sorted({e["file"] for e in card["arrays"] if not str(e["file"]).endswith(".npz")})
    if h5:
        try:
            _h5py()
        except ImportError:
            raise ImportError(
                f"{folder}: {', '.join(h5)} cannot be checked: hdf5 files need h5py, which is "
                "not installed (pip install h5py)"
            ) from None
    problems, named = [], set()
    for e in card["arrays"]:
        named.add(e["file"])
        try:
            x = _read(folder, e["file"], e["key"])
        except FileNotFoundError:
            problems.append(f"{e['file']}: missing")
            continue
        except KeyError:
            problems.append(f"{e['file']}:{e['key']}: missing key")
            continue
        except Exception as err:  # noqa: BLE001 - any unreadable file is a finding, not a crash
            problems.append(f"{e['file']}:{e['key']}: unreadable ({type(err).__name__}: {err})")
            continue
        p = _problem(e, x)
        if p:
            problems.append(p)
    extra = sorted(
        p.name for p in folder.iterdir() if p.suffix in (".npz", ".h5") and p.name not in named
    )
    problems += [f"{name}: a data file the card does not name" for name in extra]
    return list(dict.fromkeys(problems))  # a missing file is named once


# ------------------------------------------------------------------------- frameworks
class Trajectories:
    """One split of one dataset as a sequence of ``(z, args)`` pairs (NumPy), with the
    shared times in ``ts``: ``z`` (C, 2d) a training chunk or (T, 2d) a test window."""

    def __init__(self, folder, dataset: str | None = None, split: str = "train", check=True):
        if split not in ("train", "test"):
            raise ValueError(f"split {split!r}: allowed train, test")
        arrays = load(folder, dataset, check=check)
        self.split = split
        self.ts = arrays[f"ts_{split}"]
        self.z = arrays[f"z_{split}"]
        self.args = arrays[f"args_{split}"]

    def __len__(self) -> int:
        return len(self.z)

    def __getitem__(self, i):
        return self.z[i], self.args[i]


TORCH_DTYPES = ("float64", "float32")  # what TorchDataset's tensors may hold


def TorchDataset(  # noqa: N802 - a factory named as the class it returns
    folder, dataset: str | None = None, split: str = "train", check=True, dtype="float64"
):
    """A ``torch.utils.data.Dataset`` over :class:`Trajectories`: item ``i`` is ``(z, args)``
    as tensors of ``dtype`` (one of :data:`TORCH_DTYPES`; the files hold float64, float32
    halves the memory of a batch), ``.ts`` the times (a tensor of ``dtype``). It pickles (its
    arrays and dtype), so a ``DataLoader`` with ``num_workers`` > 0 works under the spawn and
    forkserver start methods too. Imports torch only here (``pip install
    'decon-bench[torch]'`` or torch itself)."""
    _torch()  # before reading any file: a missing torch is the first thing said
    if dtype not in TORCH_DTYPES:
        raise ValueError(f"dtype {dtype!r}: allowed {', '.join(TORCH_DTYPES)}")
    return _torch_dataset(Trajectories(folder, dataset, split, check), dtype)


def _torch():
    try:
        import torch
        from torch.utils.data import Dataset
    except ImportError as e:
        raise ImportError(
            "TorchDataset needs torch: pip install torch (or the suite's extra: "
            "pip install 'decon-bench[torch]')"
        ) from e
    return torch, Dataset


_TORCH_CLASS: list = []  # the Dataset subclass, made once, when torch is first needed


def _torch_dataset(base: Trajectories, dtype: str):
    """The :func:`TorchDataset` over ``base``; what its pickle calls to rebuild it (a
    module-level name, which a worker process finds by importing this module)."""
    if not _TORCH_CLASS:
        torch, Dataset = _torch()

        class _TrajectoryDataset(Dataset):
            def __init__(self, base: Trajectories, dtype: str):
                self.base, self.dtype = base, dtype
                self.ts = torch.from_numpy(np.array(base.ts, dtype=dtype))

            def __len__(self):
                return len(self.base)

            def __getitem__(self, i):
                z, args = self.base[i]
                return (
                    torch.from_numpy(np.array(z, dtype=self.dtype)),
                    torch.from_numpy(np.array(args, dtype=self.dtype)),
                )

            def __reduce__(self):  # the class is local to this function: rebuild it by name
                return _torch_dataset, (self.base, self.dtype)

        _TORCH_CLASS.append(_TrajectoryDataset)
    return _TORCH_CLASS[0](base, dtype)


def _h5py():
    try:
        import h5py
    except ImportError as e:
        raise ImportError("hdf5 files need h5py: pip install h5py") from e
    return h5py


# ------------------------------------------------------------------------------ scoring
# The suite's test metrics (bench.metrics) in NumPy alone: a predicted rollout ``zhat`` is
# scored against the dataset's ``z_test`` over t >= 1 (t = 0 is the given initial state), angle
# differences (the card's ``angular``) and the angles inside a norm wrapped to (-pi, pi]; from
# the first non-finite predicted state on, a relative error is 1 (the worst possible).
CLAMP = 1e-7  # geometric means clamp below at CLAMP
VALID_THRESHOLD = 0.025  # valid prediction time: until the relative error first exceeds it
PREDICTIONS = "one array per dataset, named by the dataset, shaped as its z_test"
SUFFIXES = (".npz", ".h5", ".hdf5")
NO_ENERGY = "not in the card (no NumPy form of this system's H: python -m bench score has it)"


def read_predictions(path) -> dict[str, np.ndarray]:
    """The arrays of a predictions file, by name: ``.npz`` (``np.savez(path, **{dataset:
    zhat})``) or ``.h5``/``.hdf5`` (``/<dataset>``, needs h5py)."""
    path = Path(path)
    if path.suffix not in SUFFIXES:
        raise ValueError(f"predictions file {path.name}: allowed suffixes {', '.join(SUFFIXES)}")
    if not path.is_file():
        raise ValueError(f"predictions file {path} does not exist")
    if path.suffix == ".npz":
        with np.load(path, allow_pickle=False) as f:
            return {k: np.array(f[k]) for k in f.files}
    with _h5py().File(path, "r") as f:
        return {k: np.array(v) for k, v in f.items() if not hasattr(v, "keys")}


def matched(folder, predictions, dataset=None) -> dict[str, tuple[np.ndarray, dict]]:
    """dataset -> (its predictions as float64, its six arrays) for every predicted dataset.
    ``predictions``: a file, a dict (dataset -> array) or one array (of ``dataset``, or of a
    folder's only one). ValueError in one line, naming what is allowed, for an array named
    after no dataset, a ``dataset`` not predicted, or a shape unlike the dataset's z_test."""
    names, where = datasets(folder), "predictions"
    if isinstance(predictions, str | Path):
        where, predictions = Path(predictions).name, read_predictions(predictions)
    elif not isinstance(predictions, dict):
        if dataset is None and len(names) != 1:
            raise ValueError(f"{folder} holds {len(names)} datasets; name one of {names}")
        predictions = {dataset or names[0]: predictions}
    unknown = [repr(n) for n in predictions if n not in names]
    if unknown or not predictions:
        what = f"{', '.join(unknown)}: no dataset of {folder}" if unknown else "no arrays"
        raise ValueError(f"{where}: {what} ({PREDICTIONS}); allowed: {', '.join(names)}")
    if dataset is not None and dataset not in predictions:
        held = ", ".join(predictions)
        raise ValueError(f"{where} has no array {dataset!r} (it holds {held}; {PREDICTIONS})")
    out = {}
    for name in [dataset] if dataset is not None else [n for n in names if n in predictions]:
        arrays, zhat = load(folder, name), np.asarray(predictions[name])
        if zhat.shape != arrays["z_test"].shape:
            raise ValueError(
                f"{where}[{name!r}]: shape {tuple(zhat.shape)}, expected "
                f"{tuple(arrays['z_test'].shape)} (trajectories, times, state) as its z_test"
            )
        out[name] = (zhat.astype(np.float64), arrays)
    return out


def _wrapped(x, angular):
    """x with the entries of the angles among the first len(angular) wrapped to (-pi, pi]."""
    mask = np.zeros(x.shape[-1], dtype=bool)
    mask[: len(angular)] = np.asarray(angular, dtype=bool)
    return np.where(mask, np.pi - np.mod(np.pi - x, 2 * np.pi), x)


def _ratio(num, den, bad) -> np.ndarray:
    """num / den (0 where den is 0), 1 from the first True of ``bad`` (last axis) on."""
    r = np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)
    return np.where(np.cumsum(bad, axis=-1) > 0, 1.0, r)


def relative_error(zhat, z, angular=()) -> np.ndarray:
    """(..., T): ||zhat - z|| / (||zhat|| + ||z||) as bench.metrics.relative_error."""
    zhat, z = np.asarray(zhat, dtype=np.float64), np.asarray(z, dtype=np.float64)
    zh, norm = np.where(np.isfinite(zhat), zhat, 0.0), np.linalg.norm
    num = norm(_wrapped(zh - z, angular), axis=-1)
    den = norm(_wrapped(zh, angular), axis=-1) + norm(_wrapped(z, angular), axis=-1)
    return _ratio(num, den, ~np.all(np.isfinite(zhat), axis=-1))


def geometric_mean(x) -> float:
    """exp(mean(log(max(x, CLAMP)))), NaN entries left out."""
    x = np.asarray(x, dtype=np.float64)
    logs = np.log(np.maximum(x[~np.isnan(x)], CLAMP))
    return float(np.exp(np.mean(logs))) if logs.size else float("nan")


def energy(form: dict, zs, coordinates: str) -> np.ndarray:
    """The true H at states ``zs`` (..., 2d) from a dataset's NumPy form of it (the card's
    ``energy``): H = 1/2 qdot . M(q) qdot + V(q), with qdot = M(q)^-1 p in (q, p) coordinates;
    NaN at a non-finite state."""
    zs = np.asarray(zs, dtype=np.float64)
    finite = np.all(np.isfinite(zs), axis=-1)
    zs = np.where(finite[..., None], zs, 0.0)
    d = zs.shape[-1] // 2
    q, v, kin, pot = zs[..., :d], zs[..., d:], form["kinetic"], form["potential"]
    m = np.asarray(kin["masses"], dtype=np.float64)
    if kin["kind"] == "chain":  # M_ij = l_i l_j cos(q_i - q_j) sum_{k >= max(i, j)} m_k
        tail = np.cumsum(m[::-1])[::-1][np.maximum.outer(np.arange(d), np.arange(d))]
        lengths = np.asarray(kin["lengths"], dtype=np.float64)
        mass = tail * np.outer(lengths, lengths) * np.cos(q[..., :, None] - q[..., None, :])
        v = np.linalg.solve(mass, v[..., None])[..., 0] if coordinates == "momentum" else v
        t = 0.5 * np.einsum("...i,...ij,...j->...", v, mass, v)
    else:  # "diagonal": one mass per coordinate
        v = v / m if coordinates == "momentum" else v
        t = 0.5 * np.sum(m * v**2, axis=-1)
    return np.where(finite, t + _potential(pot, q), np.nan)


def _potential(pot: dict, q: np.ndarray) -> np.ndarray:
    kind, m = pot["kind"], np.asarray(pot.get("masses", ()), dtype=np.float64)
    if kind == "cosine":  # V = c sum (1 - cos q)
        return pot["c"] * np.sum(1.0 - np.cos(q), axis=-1)
    if kind == "quadratic":  # V = 1/2 k |q|^2
        return 0.5 * pot["k"] * np.sum(q**2, axis=-1)
    if kind == "chain_gravity":  # V = g sum_i m_i y_i, y_i = -sum_{j <= i} l_j cos q_j
        return pot["g"] * np.sum(m * -np.cumsum(pot["lengths"] * np.cos(q), axis=-1), axis=-1)
    if kind == "spring_chain":  # gravity, springs of rest length 0 (the first) and 1 (others)
        x = q.reshape(*q.shape[:-1], -1, 3)
        stretch = np.linalg.norm(np.diff(x, axis=-2), axis=-1) - 1.0
        springs = np.sum(x[..., 0, :] ** 2, axis=-1) + np.sum(stretch**2, axis=-1)
        return pot["g"] * np.sum(m * x[..., 2], axis=-1) + 0.5 * pot["k"] * springs
    if kind == "gravitation":  # V = -G sum_{i<j} m_i m_j / |x_i - x_j|, bodies in a plane
        x, n = q.reshape(*q.shape[:-1], -1, 2), len(m)
        pairs = [(i, j) for i in range(n) for j in range(i + 1, n)]
        r = [np.linalg.norm(x[..., i, :] - x[..., j, :], axis=-1) for i, j in pairs]
        return -pot["G"] * sum(m[i] * m[j] / rij for (i, j), rij in zip(pairs, r, strict=True))
    raise ValueError(f"energy form {kind!r} is unknown to this loader; update decon_data.py")


def score(folder, predictions, dataset=None) -> list[dict]:
    """The suite's test metrics of ``predictions`` (as :func:`matched` takes them), one dict per
    dataset naming it as the card does: rollout_error, mse and valid_time always, and
    energy_violation where the card carries the system's H in NumPy form (else NaN, and
    ``energy`` says so)."""
    card, rows = read_card(folder), []
    for name, (zhat, a) in matched(folder, predictions, dataset).items():
        e, z = card["datasets"][name], a["z_test"]
        err = relative_error(zhat, z, e["angular"])
        over, t = err > VALID_THRESHOLD, a["ts_test"] - a["ts_test"][0]
        diff = _wrapped(zhat - z, e["angular"])[:, 1:]
        row = {
            "dataset": name,
            "system": card["system"]["name"],
            "k": dict(e["config"]["system_params"]).get("k"),
            "coordinates": e["coordinates"],
            **{k: e["config"][k] for k in ("n_train", "noise", "seed")},
            "profile": card.get("profile"),
            "n_test": len(z),
            "rollout_error": geometric_mean(err[..., 1:]),
            "energy_violation": float("nan"),
            "mse": float(np.mean(diff**2)) if np.all(np.isfinite(zhat)) else float("nan"),
            "valid_time": float(np.mean(np.where(over.any(-1), t[np.argmax(over, -1)], t[-1]))),
            "energy": NO_ENERGY,
        }
        if e.get("energy"):
            hp, ht = (energy(e["energy"], x, e["coordinates"]) for x in (zhat, z))
            finite = np.isfinite(hp)
            hp = np.where(finite, hp, 0.0)
            ev = _ratio(np.abs(hp - ht), np.abs(hp) + np.abs(ht), ~finite)
            row["energy_violation"] = geometric_mean(ev[..., 1:])
            row["energy"] = f"true H from the card: {e['energy']['text']}"
        rows.append(row)
    return rows


def main(argv=None) -> int:
    """``python decon_data.py verify DIR``: exit 0 when every array matches the card, 1 when
    some do not (each named on a line), 2 when the folder cannot be checked (no card, or h5py
    missing for an hdf5 folder: one line). ``python decon_data.py score DIR PREDICTIONS``: the
    metrics of each predicted dataset (:func:`score`), a line each; a bad input: one line, 2."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or len(argv) != {"verify": 2, "score": 3}.get(argv[0]):
        print("usage: python decon_data.py verify DIR | score DIR PREDICTIONS", file=sys.stderr)
        return 2
    try:
        if argv[0] == "score":
            for r in score(argv[1], argv[2]):
                ev = r["energy_violation"]
                print(
                    f"{r['dataset']}: rollout_error {r['rollout_error']:.4g}, mse {r['mse']:.4g}"
                    f", valid_time {r['valid_time']:.3g} s, energy_violation "
                    + (f"{ev:.4g} (true H from the card)" if ev == ev else r["energy"])
                )
            return 0
        problems = verify(argv[1])
    except (ValueError, ImportError) as e:  # no card, or a missing dependency: one line
        print(f"error: {e}", file=sys.stderr)
        return 2
    for p in problems:
        print(f"damaged: {p}")
    n = len(read_card(argv[1])["arrays"])
    if problems:
        print(f"{argv[1]}: {len(problems)} problem(s): the folder does not match its card")
        return 1
    print(f"{argv[1]}: all {n} arrays match the card")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
