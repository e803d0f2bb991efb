"""``python -m bench data export | verify``: a profile's exact training and test arrays, in
files any framework reads, with a dataset card.

**Which datasets.** Those the profile's runs train and are tested on for the system: every
experiment is expanded at the profile (:func:`bench.core._experiments.expand`) and the distinct
``systems.DatasetConfig`` of its runs on that system are kept (``--k`` and ``--seeds`` narrow
them), so the arrays are the ones behind the stored results, bit for bit. Each is written in
both coordinate systems, ``z = (q, qdot)`` and ``z = (q, p)`` (the same trajectories: the
momenta are computed from the velocities; they differ for every registered system). A system and
``k`` that no experiment of the profile uses are exported at the profile's defaults, and the
card says that too. ``damped_<system>`` selects the runs of ``<system>`` with friction.

**The card** (``card.json``, and ``README.md`` for people): the system and its parameters, the
protocol (dt, duration, chunking, counts, seeds, keys, noise), the generator and its
tolerances, the suite's version and commit, per dataset its config, hash and the experiments
that use it, and every array's file, key, shape and sha256. The reading side, ``verify``
included, is :mod:`bench.data_loader`, copied into the folder as ``decon_data.py``.
"""

from __future__ import annotations

import dataclasses
import datetime as _dt
import inspect
import shutil
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np

import systems
from systems import MAX_STEPS

from . import data_loader, metrics
from .core import RunConfig, available, expand, profile_defaults

DAMPED_PREFIX = "damped_"
LOADER_NAME = "decon_data.py"


def _effective(c) -> dict:
    """The system parameters of ``c`` as the built system holds them, defaults included, so
    that a parameter given at its default value and one left out read the same."""
    obj = systems.make(c.system, **dict(c.system_params))
    out = {}
    for key in systems.parameters(c.system):
        value = getattr(obj, key, dict(c.system_params).get(key))
        if value is not None and np.ndim(value):
            value = tuple(float(v) for v in np.ravel(value))
        out[key] = value
    return out


def _varying(configs) -> list[str]:
    """The system parameters whose values differ across ``configs``: only these name datasets."""
    values = [_effective(c) for c in configs]
    keys = sorted({key for v in values for key in v})
    return [key for key in keys if len({repr(v.get(key)) for v in values}) > 1]


def _dataset_name(c, varying: Sequence[str]) -> str:
    """Coordinates, training size, noise, friction, the parameters given explicitly (e.g.
    masses1-1) and the seed; k where it differs between the datasets. The values every
    parameter takes, defaults included, are the card entry's ``parameters``."""
    parts = [f"k{dict(c.system_params).get('k')}"] if "k" in varying else []
    parts += [c.coordinates, f"n{c.n_train}"]
    if c.noise:
        parts.append(f"noise{c.noise:g}")
    friction = dict(c.system_params).get("friction")
    if friction:
        parts.append(f"friction{friction:g}")
    if c.random_args:
        parts.append("randomargs")
    for key, value in c.system_params:  # other parameters, e.g. masses1-1
        if key not in ("k", "friction"):
            values = value if isinstance(value, tuple | list) else (value,)
            parts.append(
                key + "-".join(f"{v:g}" if isinstance(v, float) else str(v) for v in values)
            )
    parts.append(f"seed{c.seed}")
    return "_".join(parts)


def select(system: str, profile: str, k=None, seeds=None) -> tuple[dict, list[str]]:
    """(DatasetConfig -> the experiments using it, notes) for ``system`` at ``profile``."""

    from .core import check_choice

    check_choice("system", system, systems.available())
    damped = system.startswith(DAMPED_PREFIX)
    base = system[len(DAMPED_PREFIX) :] if damped else system
    if k is not None and "k" not in systems.parameters(base):
        raise ValueError(f"{system} takes no k; drop --k")
    used: dict = {}
    for name in available():
        for r in expand(name, profile):
            if r.system != base or (r.friction > 0) != damped:
                continue
            if k is not None and r.k != k or seeds is not None and r.seed not in seeds:
                continue
            used.setdefault(r.dataset_config(), set()).add(name)
    notes = []
    if not used:
        defaults, profile_seeds = profile_defaults(profile)
        fields = {f.name for f in dataclasses.fields(RunConfig)}
        kw = {a: b for a, b in defaults.items() if a in fields}
        friction = 0.4 if damped else 0.0
        for s in seeds if seeds is not None else profile_seeds:
            r = RunConfig(system=base, model="node", k=k, friction=friction, seed=s, **kw)
            used[r.dataset_config()] = set()
        notes.append(
            f"no experiment of profile {profile} trains on {system}"
            + (f" with k = {k}" if k is not None else "")
            + f"; exported at the profile's defaults (seeds {sorted({c.seed for c in used})})"
        )
    # both coordinate systems of each
    out: dict = {}
    for c, names in used.items():
        for coords in ("velocity", "momentum"):
            other = dataclasses.replace(c, coordinates=coords)
            out.setdefault(other, set()).update(names if coords == c.coordinates else set())
    return out, notes


def export(
    system: str,
    out,
    profile: str = "quick",
    k: int | None = None,
    seeds=None,
    fmt: str = "npz",
    force: bool = False,
    progress=print,
) -> dict:
    """Write the datasets of ``system`` at ``profile`` to ``out``; returns the card."""

    from .core import check_choice, provenance

    check_choice("format", fmt, data_loader.FORMATS)
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out {out} is a file; name a folder")
    if out.is_dir() and any(out.iterdir()) and not force:
        raise ValueError(f"--out {out} is not empty; name a new folder or pass --force")
    configs, notes = select(system, profile, k=k, seeds=seeds)
    varying = _varying(configs)
    arrays: dict[str, dict] = {}
    entries: dict[str, dict] = {}
    order = sorted(configs.items(), key=lambda x: (_velocity_twin(x[0]), x[0].coordinates))
    for i, (c, names) in enumerate(order):
        name = _dataset_name(c, varying)
        if name in arrays:  # the same data under two configurations (a default given or not)
            name += f"_{c.hash()[:8]}"
        progress(f"data: {i + 1}/{len(configs)} {name}")
        d = systems.make_dataset(c)
        a = {n: getattr(d, n) for n in data_loader.ARRAYS}
        arrays[name] = a
        entries[name] = {
            "coordinates": c.coordinates,
            "state": "z = (q, qdot)" if c.coordinates == "velocity" else "z = (q, p)",
            "seed": c.seed,
            "config": dataclasses.asdict(c),
            "config_hash": c.hash(),
            "used_by_experiments": sorted(names),
            "angular": list(d.angular),
            "parameters": _effective(c),
            "energy": energy_form(systems.make(c.system, **dict(c.system_params)), d),
        }
    sys_obj = systems.make(next(iter(configs)).system, **dict(next(iter(configs)).system_params))
    prov = provenance()
    first = next(iter(configs))
    card = {
        "title": f"decon-bench data: {system} at profile {profile}",
        "created": _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "system": {
            "name": system,
            "class": type(sys_obj).__name__,
            # as the built systems hold them, defaults included; "varies": see each dataset
            "parameters": {
                key: ("varies" if key in varying else value)
                for key, value in _effective(first).items()
            },
            "dof": sys_obj.dof,
            "angular": list(sys_obj.angular),
            "n_args": sys_obj.n_args,
            "description": inspect.getdoc(type(sys_obj)) or "",
        },
        "profile": profile,
        "protocol": {
            "dt": first.dt,
            "duration": first.duration,
            "points_per_trajectory": first.n_points,
            "chunk": first.chunk,
            "n_generated": sorted({c.n_generated for c in configs}),
            "n_train": sorted({c.n_train for c in configs}),
            "n_test": sorted({c.n_test for c in configs}),
            "test_window": first.test_chunks * first.chunk,
            "seeds": sorted({c.seed for c in configs}),
            "noise_std_train_only": sorted({c.noise for c in configs}),
            "random_args": sorted({c.random_args for c in configs}),
            # the generator's protocol, without the suite's cache internals
            "text": inspect.getdoc(sys.modules[systems.make_dataset.__module__])
            .split("\nCache:")[0]
            .strip(),
        },
        "generator": {
            "library": "diffrax",
            "solver": "Dopri8",
            "step_size_controller": (
                f"PIDController(rtol={sys_obj.ground_truth_tol:g}, "
                f"atol={sys_obj.ground_truth_tol:g})"
            ),
            "max_steps": MAX_STEPS,
            "dtype": "float64",
            "initial_states": inspect.getdoc(type(sys_obj).sample_initial) or "",
        },
        "suite": {
            "name": "decon-bench",
            "version": _version(),
            "commit": prov.get("git_commit"),
            "dirty": prov.get("git_dirty"),
            **{n: prov.get(n) for n in ("jax_version", "diffrax_version", "numpy_version")},
        },
        "license": "MIT (the decon-bench suite's licence; the data are generated by its code)",
        "citation": (
            "Gruver, Finzi, Stanton, Wilson. Deconstructing the Inductive Biases of Hamiltonian "
            "Neural Networks. ICLR 2022 (the protocol); and the decon-bench suite, version "
            f"{_version()}"
        ),
        "notes": notes,
        "datasets": entries,
    }
    out.mkdir(parents=True, exist_ok=True)
    if force:
        for p in out.iterdir():
            if p.suffix in (".npz", ".h5"):
                p.unlink()
    card = data_loader.write(out, arrays, card, fmt)
    shutil.copyfile(data_loader.__file__, out / LOADER_NAME)
    (out / "README.md").write_text(card_markdown(card))
    return card


_BODIES = "1/2 sum_i m_i |v_i|^2"


def _form(system) -> tuple[dict, dict, str] | None:
    """(kinetic, potential, text) of ``system``'s H for :func:`bench.data_loader.energy`."""
    name, f = type(system).__name__, [float(x) for x in getattr(system, "masses", ())]
    fs = "[" + ", ".join(f"{x:.6g}" for x in f) + "]"  # the masses in the text
    if name == "Pendulum":
        ml2, mgl = system.mass * system.length**2, system.mass * system.g * system.length
        kin, pot = {"kind": "diagonal", "masses": [ml2]}, {"kind": "cosine", "c": mgl}
        return kin, pot, f"1/2 m l^2 qdot^2 + m g l (1 - cos q), m l^2 = {ml2:g}, m g l = {mgl:g}"
    if name == "MassSpring":
        m, k = system.mass, system.spring_constant
        kin, pot = {"kind": "diagonal", "masses": [m]}, {"kind": "quadratic", "k": k}
        return kin, pot, f"1/2 m qdot^2 + 1/2 k q^2, m = {m:g}, k = {k:g}"
    if name == "ChainPendulum":
        lengths, g = [float(x) for x in system.lengths], system.g
        kin = {"kind": "chain", "masses": f, "lengths": lengths}
        pot = {"kind": "chain_gravity", "masses": f, "lengths": lengths, "g": g}
        ls = "[" + ", ".join(f"{x:.6g}" for x in lengths) + "]"
        text = f"{_BODIES} + g sum_i m_i y_i (bob i), masses {fs}, lengths {ls}, g = {g:g}"
        return kin, pot, text
    if name == "SpringPendulum":
        g, k = system.g, system.spring_constant
        pot = {"kind": "spring_chain", "masses": f, "g": g, "k": k}
        text = (
            f"{_BODIES} + g sum_i m_i z_i + 1/2 k |x_1|^2 + 1/2 k sum_(i>1) (|x_i - x_(i-1)| - "
            f"1)^2, masses {fs}, g = {g:g}, k = {k:g}"
        )
        return {"kind": "diagonal", "masses": [m for m in f for _ in range(3)]}, pot, text
    if name in ("TwoBody", "ThreeBody"):
        pot = {"kind": "gravitation", "masses": f, "G": system.gravity}
        text = f"{_BODIES} - G sum_(i<j) m_i m_j / |x_i - x_j|, masses {fs}, G = {system.gravity:g}"
        return {"kind": "diagonal", "masses": [m for m in f for _ in range(2)]}, pot, text
    return None


def energy_form(system, d) -> dict | None:
    """The true H of ``system`` in the NumPy form of :func:`bench.data_loader.energy` (the
    card's ``energy`` of dataset ``d``, which decon_data.score reads), checked against the
    suite's own energies on the test states; None for a system without one here (a system with
    per-trajectory parameters among them), or one that does not match."""
    form = None if system.n_args else _form(system)
    if form is None:
        return None
    out = {"kinetic": form[0], "potential": form[1], "text": "H = " + form[2]}
    z = d.z_test[:8]
    numpy_h = data_loader.energy(out, z, d.config.coordinates)
    suite_h = metrics.energies(system, z, None, d.config.coordinates)
    return out if np.allclose(numpy_h, suite_h, rtol=1e-9, atol=1e-12) else None


def _velocity_twin(c) -> str:
    return dataclasses.replace(c, coordinates="velocity").canonical_json()


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("decon-bench")
    except PackageNotFoundError:
        return "unknown"


def card_markdown(card: dict) -> str:
    """The dataset card for people (README.md of an exported folder)."""
    s, p, g, u = card["system"], card["protocol"], card["generator"], card["suite"]
    lines = [
        f"# {card['title']}",
        "",
        f"Exported {card['created']} by decon-bench {u['version']} (commit {u['commit']}"
        + (", with uncommitted changes" if u.get("dirty") else "")
        + f"; jax {u.get('jax_version')}, diffrax {u.get('diffrax_version')}). "
        f"Format: {card['format']}. Check it: `python decon_data.py verify .`",
        "",
        "## System",
        "",
        f"`{s['name']}` ({s['class']}): {s['dof']} degrees of freedom, angular coordinates "
        f"{s['angular']}, {s['n_args']} per-trajectory parameters (`args_*`); parameters "
        + ", ".join(f"{k} = {v}" for k, v in s["parameters"].items())
        + " (varies: named in each dataset's name and its card entry's `parameters`).",
        "",
        s["description"],
        "",
        "## Protocol",
        "",
        f"- dt = {p['dt']}, trajectories of {p['duration']} s ({p['points_per_trajectory']} "
        f"points); training chunks of {p['chunk']} points, test windows of {p['test_window']}",
        f"- training trajectories n_train = {p['n_train']} (of n_generated = "
        f"{p['n_generated']} drawn), test trajectories n_test = {p['n_test']}",
        f"- seeds {p['seeds']}; Gaussian noise std {p['noise_std_train_only']} on the training "
        f"set only; random per-trajectory parameters: {p['random_args']}",
        "",
        p["text"],
        "",
        "## Generator",
        "",
        f"{g['library']} {g['solver']}, {g['step_size_controller']}, max_steps "
        f"{g['max_steps']}, {g['dtype']}. Initial states: {g['initial_states']}",
        "",
    ]
    if card["notes"]:
        lines += ["## Notes", "", *[f"- {n}" for n in card["notes"]], ""]
    if card.get("license") or card.get("citation"):
        lines += ["## Licence and citation", ""]
        lines += [f"- licence: {card['license']}"] if card.get("license") else []
        lines += [f"- cite: {card['citation']}"] if card.get("citation") else []
        lines += [""]
    lines += [
        "## Datasets",
        "",
        "| dataset | state | seed | used by experiments | config hash |",
        "|---|---|---|---|---|",
    ]
    for name, e in card["datasets"].items():
        used = ", ".join(e["used_by_experiments"]) or "(none: the other coordinates)"
        lines.append(
            f"| `{name}` | {e['state']} | {e['seed']} | {used} | `{e['config_hash'][:16]}` |"
        )
    forms = list(
        dict.fromkeys((e.get("energy") or {}).get("text", "") for e in card["datasets"].values())
    )
    lines += [
        "",
        "True energy in NumPy form (the datasets' `energy`, which `decon_data.score` reads for "
        "the energy violation): "
        + ("; ".join(f for f in forms if f) or "none for this system")
        + ("" if all(forms) else " (where none: `python -m bench score` computes it)"),
    ]
    lines += [
        "",
        "## Arrays",
        "",
        "sha256 of the C-ordered little-endian float64 bytes (`decon_data.sha256`).",
        "",
        "| file | key | shape | sha256 |",
        "|---|---|---|---|",
    ]
    for e in card["arrays"]:
        lines.append(f"| {e['file']} | {e['key']} | {tuple(e['shape'])} | `{e['sha256']}` |")
    lines += [
        "",
        "## Loading",
        "",
        "```python",
        "import decon_data  # this folder's loader: NumPy only (h5py for .h5, torch optional)",
        "names = decon_data.datasets('.')",
        "arrays = decon_data.load('.', names[0])  # checked against the card",
        "train = decon_data.TorchDataset('.', names[0], split='train')  # needs torch",
        "# predictions: np.savez('pred.npz', **{name: zhat}), zhat shaped as the z_test of name",
        "rows = decon_data.score('.', 'pred.npz')  # the suite's test metrics, NumPy only",
        "```",
        "",
    ]
    return "\n".join(lines)
