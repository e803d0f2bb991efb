"""Predictions from any framework, scored as the suite scores its runs, beside the reference.

``python -m bench score PREDICTIONS --data EXPORT [--model NAME] [--out FILE]``: the predicted
test rollouts of a folder written by ``python -m bench data export`` (one array per dataset,
named by it and shaped as its ``z_test``, in ``.npz`` or ``.h5``: see
:func:`bench.data_loader.matched`) get the metrics a run's evaluation computes on the same test
windows, with the same functions (:mod:`bench.metrics`, as ``bench.core._evaluate`` calls them):
the rollout error, the energy violation with the system's true energy, the MSE, the valid
prediction time, and in (q, p) coordinates the rollout error and MSE on (q, qdot). A row per
dataset names the system, k, coordinates, training size, noise, seed and profile as the
export's card states them; ``--out`` keeps the rows in a CSV or parquet file (rows of the same
model and dataset replaced, others kept), which pandas reads.

``python -m bench compare [REF] --scores FILE``: for each dataset cell of the scores (its
configuration without the seed), the reference's runs trained and tested on the same data
(matched by the hash of their ``systems.DatasetConfig``, the seed aside), one line per model
cell with the median over its seeds and their range [min, max] (failed and diverged runs scored
1, as the verdicts do), the scored models among them in rank order, and where each scored model
falls against each reference model's seeds (and, on the seeds both have, how often it is the
lower); ``--min-seeds`` (2) leaves out the model cells with fewer seeds.
"""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from . import data_loader, metrics
from .core import Command, register_command

METRICS = (
    "rollout_error",
    "energy_violation",
    "mse",
    "valid_time",
    "rollout_error_velocity",
    "mse_velocity",
)
KEY = ("model", "dataset_hash")  # a scores file holds one row per model and dataset
TABLES = (".csv", ".parquet")


def suite_scores(system, arrays: dict, zhat, coordinates: str, random_args: bool) -> dict:
    """The test metrics of predictions ``zhat`` (N, T, 2d) of a dataset's ``arrays``, computed
    as a run's evaluation computes them (``bench.core._evaluate``: the same calls, in order)."""
    z, ts, angular = arrays["z_test"], arrays["ts_test"], tuple(system.angular)
    h_args = arrays["args_test"] if random_args else None
    err_t = metrics.relative_error(zhat, z, angular)
    h_true = metrics.energies(system, z, h_args, coordinates)
    h_pred = metrics.energies(system, zhat, h_args, coordinates)
    ev_t = metrics.energy_violation_curve(h_pred, h_true)
    err_velocity, mse_velocity = float("nan"), float("nan")
    if coordinates == "momentum":  # also on (q, qdot), decoded with the TRUE velocity map
        import systems

        zv_hat, zv = (
            systems.to_velocity(system, zhat, h_args),
            systems.to_velocity(system, z, h_args),
        )
        err_velocity = float(
            metrics.geometric_mean(metrics.relative_error(zv_hat, zv, angular)[..., 1:])
        )
        mse_velocity = metrics.mse(zv_hat, zv, angular)
    return {
        "rollout_error": float(metrics.geometric_mean(err_t[..., 1:])),
        "energy_violation": float(metrics.geometric_mean(ev_t[..., 1:])),
        "mse": metrics.mse(zhat, z, angular),
        "valid_time": float(np.mean(metrics.valid_prediction_time(err_t, ts))),
        "rollout_error_velocity": err_velocity,
        "mse_velocity": mse_velocity,
    }


def score(predictions, data, model: str | None = None, dataset: str | None = None) -> pd.DataFrame:
    """One row per predicted dataset of export folder ``data``: what the card says of it and
    :func:`suite_scores`. ValueError (one line) for an unknown system or bad predictions."""
    import systems

    from .core import check_choice

    card = data_loader.read_card(data)
    check_choice("system", card["system"]["name"], systems.available())
    if model is None:
        model = Path(predictions).stem if isinstance(predictions, str | Path) else "predictions"
    rows = []
    for name, (zhat, arrays) in data_loader.matched(data, predictions, dataset).items():
        e = card["datasets"][name]
        config = systems.DatasetConfig(**e["config"])
        system = systems.make(config.system, **dict(config.system_params))
        params = dict(config.system_params)
        rows.append(
            {
                "model": model,
                "system": card["system"]["name"],
                "k": params.get("k"),
                "coordinates": config.coordinates,
                "n_train": config.n_train,
                "noise": config.noise,
                "seed": config.seed,
                "profile": card.get("profile"),
                **suite_scores(system, arrays, zhat, config.coordinates, config.random_args),
                "dataset": name,
                "starts_at_z0": bool(np.allclose(zhat[:, 0], arrays["z_test"][:, 0])),
                "n_test": int(zhat.shape[0]),
                "test_points": int(zhat.shape[1]),
                "system_params": json.dumps({k: v for k, v in params.items() if k != "k"}),
                "used_by_experiments": ",".join(e.get("used_by_experiments", [])),
                "dataset_hash": e["config_hash"],
                "cell_hash": cell_hash(e["config"]),
                "dataset_config": json.dumps(e["config"], sort_keys=True),
                "predictions": str(predictions) if isinstance(predictions, str | Path) else "",
                "predictions_sha256": data_loader.sha256(zhat),
                "export_suite": f"{card['suite'].get('version')} {card['suite'].get('commit')}",
            }
        )
    return pd.DataFrame(rows)


def cell_hash(config: dict) -> str:
    """The hash of a dataset's configuration with its seed set aside (its cell's datasets)."""
    import systems

    return systems.DatasetConfig(**{**config, "seed": 0}).hash()[:16]


def write_scores(rows: pd.DataFrame, out) -> pd.DataFrame:
    """Add ``rows`` to the scores file ``out`` (.csv or .parquet; rows of the same model and
    dataset replaced); returns what it now holds."""
    out = Path(out)
    if out.suffix not in TABLES:
        raise ValueError(f"--out {out.name}: allowed suffixes {', '.join(TABLES)}")
    if out.exists():
        old = read_scores(out)
        keep = ~old.set_index(list(KEY)).index.isin(rows.set_index(list(KEY)).index)
        rows = pd.concat([old[keep], rows], ignore_index=True)
    out.parent.mkdir(parents=True, exist_ok=True)
    rows.to_csv(out, index=False) if out.suffix == ".csv" else rows.to_parquet(out, index=False)
    return rows


def read_scores(path) -> pd.DataFrame:
    """A scores file of :func:`write_scores` (ValueError naming what it lacks)."""
    path = Path(path)
    if path.suffix not in TABLES or not path.is_file():
        raise ValueError(f"--scores {path}: not a scores file (.csv or .parquet of bench score)")
    df = pd.read_csv(path) if path.suffix == ".csv" else pd.read_parquet(path)
    missing = [c for c in (*KEY, "cell_hash", "dataset_config", "rollout_error") if c not in df]
    if missing:
        raise ValueError(
            f"--scores {path}: no column {', '.join(missing)} (write it with bench score)"
        )
    return df


# ------------------------------------------------------------------------------- beside
_NOT_LABELS = {"system", "system_params", "k", "friction", "model", "seed", "coordinates"}
_NOT_LABELS |= {"noise", "random_args", "n_generated", "n_train", "chunk", "dt", "duration"}
_NOT_LABELS |= {"n_test", "test_chunks", "eval_checkpoints"}  # the data's, or no model's


def reference_cells(runs: pd.DataFrame, systems_: set[str]) -> pd.DataFrame:
    """Per reference row of ``systems_`` with a state dataset: ``cell_hash`` (:func:`cell_hash`
    of its dataset) and ``label``, its model and the fields (the data's aside) where its
    configuration differs from most rows on the same data."""
    from .core import RunConfig

    out = {}
    for i, row in runs[runs["system"].isin(systems_)].iterrows():
        try:
            cfg = RunConfig.from_dict(row.to_dict())
            h = dataclasses.replace(cfg.dataset_config(), seed=0).hash()[:16]
        except (ValueError, TypeError):
            continue
        fields = {k: json.dumps(v, default=str) for k, v in cfg.to_dict().items()}
        out[i] = {**fields, "cell_hash": h, "model": cfg.model}
    t = pd.DataFrame.from_dict(out, orient="index")
    if t.empty:
        return pd.DataFrame(columns=["cell_hash", "label"])
    labels = pd.Series("", index=t.index)
    for _, g in t.groupby("cell_hash"):
        fields = [f for f in g.columns if f not in _NOT_LABELS | {"cell_hash"}]
        common = g[fields].mode().iloc[0]
        labels[g.index] = g["model"] + g[fields].apply(
            lambda r, fs=fields, c=common: "".join(
                f" {f}={r[f].strip(chr(34))}" for f in fs if r[f] != c[f]
            ),
            axis=1,
        )
    return pd.DataFrame({"cell_hash": t["cell_hash"], "label": labels})


def _position(mine: float, seeds: np.ndarray) -> str:
    """Where value ``mine`` falls against a reference model's per-seed values."""
    n = len(seeds)
    if mine < seeds.min():
        return f"yours lower than all {n}"
    if mine > seeds.max():
        return f"yours higher than all {n}"
    return f"inside: {int((seeds < mine).sum())} of {n} lower"


def _paired(mine: dict, theirs: dict) -> str:
    """On the seeds (the same data) both have: how often ``mine`` is the lower."""
    shared = sorted(set(mine) & set(theirs))
    if not shared:
        return ""
    lower = sum(mine[s] < theirs[s] for s in shared)
    n = len(shared)
    return f"; same data: yours lower on {lower} of {n} seed{'s' if n > 1 else ''}"


def _row(model: str, experiments: str, g: pd.DataFrame, err, ev, mse) -> dict:
    e = g[err].to_numpy(dtype=float)
    return {
        "model": model,
        "experiments": experiments,
        "seeds": _seed_text(g["seed"]),
        "rollout_error_median": float(np.median(e)),
        "rollout_error_min": float(e.min()),
        "rollout_error_max": float(e.max()),
        "energy_violation": float(np.median(g[ev])),
        "mse": float(np.median(g[mse])),
        "_seeds": e,
        "_by_seed": g.groupby("seed")[err].median().to_dict(),
    }


def beside(scores: pd.DataFrame, reference, min_seeds: int = 2) -> tuple[str, dict]:
    """(Markdown, cell hash -> table): per dataset cell of ``scores``, the scored models and
    the reference's model cells with at least ``min_seeds`` seeds on the same data, ranked by
    their median rollout error over seeds."""
    from .core import load_runs, row_cell_keys
    from .kit import scored

    if not Path(reference).is_dir():
        raise ValueError(f"reference folder {reference} does not exist")
    runs = load_runs(Path(reference))
    if runs.empty:
        raise ValueError(f"{reference} holds no stored runs")
    profile = ", ".join(sorted(runs["profile"].dropna().astype(str).unique()))
    pairs = zip(scores["cell_hash"], scores["dataset_config"], strict=True)
    configs = {h: json.loads(c) for h, c in pairs}
    found = reference_cells(runs, {c["system"] for c in configs.values()})
    lines = [f"# Scored predictions beside `{reference}` (profiles {profile})", ""]
    tables = {}
    for h, config in configs.items():
        mine = scores[scores["cell_hash"] == h]
        params = ", ".join(f"{k} = {v}" for k, v in dict(config["system_params"]).items())
        lines += [
            f"## {config['system']} ({params or 'defaults'}), {config['coordinates']} "
            f"coordinates, n_train {config['n_train']}, noise {config['noise']:g}",
            "",
        ]
        ref = runs.loc[found.index[found["cell_hash"] == h]]
        if ref.empty:
            used = "" if "used_by_experiments" not in mine else mine["used_by_experiments"]
            why = (
                " (no experiment of the export's profile trains on it)"
                if not any(isinstance(u, str) and u for u in used)
                else ""
            )
            lines += [f"No run of `{reference}` on these data{why}: nothing to set beside.", ""]
            continue
        ref = ref.assign(
            _cell=row_cell_keys(ref),
            _label=found.loc[ref.index, "label"],
            **{f"_{m}": scored(ref, m) for m in ("rollout_error", "energy_violation", "mse")},
        )
        rows = [_row(f"**{m}** (yours)", "-", g, *METRICS[:3]) for m, g in mine.groupby("model")]
        few = []
        for _, g in ref.groupby("_cell", sort=False):
            if g["seed"].nunique() < min_seeds:
                few.append(g)
                continue
            exps = ", ".join(sorted(set(g["experiment"].astype(str))))
            rows.append(
                _row(g["_label"].iloc[0], exps, g, "_rollout_error", "_energy_violation", "_mse")
            )
        t = pd.DataFrame(rows).sort_values("rollout_error_median", kind="stable")
        t.insert(0, "rank", range(1, len(t) + 1))
        for model, g in mine.groupby("model"):
            m, by_seed = (
                float(np.median(g["rollout_error"])),
                dict(zip(g["seed"], g["rollout_error"], strict=True)),
            )
            t[f"vs {model}"] = [
                "-" if "(yours)" in name else _position(m, seeds) + _paired(by_seed, theirs)
                for name, seeds, theirs in zip(t["model"], t["_seeds"], t["_by_seed"], strict=True)
            ]
        tables[h] = t = t.drop(columns=["_seeds", "_by_seed"]).reset_index(drop=True)
        lines += _cell_text(t, mine, ref, few, min_seeds)
    return "\n".join(lines) + "\n", tables


def _seed_text(seeds: pd.Series) -> str:
    s = sorted(int(x) for x in set(seeds))
    if len(s) > 2 and s == list(range(s[0], s[-1] + 1)):
        return f"{s[0]}-{s[-1]}"
    return ",".join(map(str, s))


def _cell_text(t: pd.DataFrame, mine, ref, few: list, min_seeds: int) -> list[str]:
    n_ref = len(t) - mine["model"].nunique()
    lines = [
        f"{n_ref} model cells of the reference trained and tested on these data (seeds "
        f"{_seed_text(ref['seed'])}); yours on seeds {_seed_text(mine['seed'])}. Rollout "
        "error: median over seeds and [min, max] (failed and diverged runs scored 1); energy "
        "violation and MSE: medians over seeds; *vs*: your median against each model's "
        "seeds.",
        "",
    ]
    if few:
        exps = ", ".join(sorted({str(x) for g in few for x in g["experiment"]}))
        lines += [
            f"Not shown: {len(few)} model cells with fewer than {min_seeds} seeds ({exps}; "
            "`--min-seeds 1` shows them).",
            "",
        ]
    vs = [c for c in t if c.startswith("vs ")]
    head = ["rank", "model", "experiments", "seeds", "rollout error", "[min, max]"]
    head += ["energy violation", "MSE", *vs]
    lines += ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    for r in t.to_dict("records"):
        cells = [
            str(r["rank"]),
            r["model"],
            r["experiments"],
            r["seeds"],
            f"{r['rollout_error_median']:.4g}",
            f"[{r['rollout_error_min']:.4g}, {r['rollout_error_max']:.4g}]",
            f"{r['energy_violation']:.3g}",
            f"{r['mse']:.3g}",
            *[r[c] for c in vs],
        ]
        lines.append("| " + " | ".join(cells) + " |")
    return lines + [""]


# ------------------------------------------------------------------------------- verbs
def _print_table(rows: pd.DataFrame) -> None:
    names = ["model", "system", "k", "coordinates", "n_train", "noise", "seed", "profile"]
    cols = [c for c in (*names, *METRICS) if c in rows and rows[c].notna().any()]
    print(rows[cols].to_string(index=False, float_format=lambda x: f"{x:.4g}"))


def _score_arguments(p) -> None:
    p.add_argument(
        "predictions",
        help="a .npz or .h5 file: one array per dataset of the export, named by the dataset, "
        "shaped as its z_test",
    )
    p.add_argument(
        "--data",
        required=True,
        metavar="EXPORT",
        help="the folder python -m bench data export wrote",
    )
    p.add_argument(
        "--model",
        default=None,
        help="the name of your model in the table (default: the file's name)",
    )
    p.add_argument("--dataset", default=None, help="score only this dataset of the file")
    p.add_argument(
        "--out",
        default=None,
        metavar="FILE",
        help="add the rows to this .csv or .parquet (rows of the same model and dataset replaced)",
    )


def _score_run(args) -> int:
    rows = score(args.predictions, args.data, args.model, args.dataset)
    _print_table(rows)
    for name in rows.loc[~rows["starts_at_z0"], "dataset"]:
        print(f"note: {name}: the predictions do not start at z_test[:, 0] (t = 0 is not scored)")
    if args.out:
        held = write_scores(rows, args.out)
        print(
            f"scores: {args.out} ({len(held)} rows); beside the reference: "
            f"python -m bench compare --scores {args.out}"
        )
    return 0


COMMAND = register_command(
    Command(
        "score",
        "predicted test rollouts of an exported folder scored with the suite's metrics",
        _score_run,
        _score_arguments,
        __doc__.split("\n\n")[1],
    )
)


def compare_arguments(parser) -> None:
    """``compare``'s ``--scores`` option."""
    parser.add_argument(
        "--scores",
        default=None,
        metavar="FILE",
        help="the scores of python -m bench score --out FILE, beside the reference's models on "
        "the same data (A: the reference, default results/reference/<the scores' profile>)",
    )
    parser.add_argument(
        "--min-seeds",
        type=int,
        default=2,
        metavar="N",
        help="with --scores: the reference's model cells with at least N seeds (default 2)",
    )


def compare_verb(fallback):
    """``compare`` with ``--scores``: :func:`beside`; without: ``fallback``."""

    def run(args) -> int:
        if not getattr(args, "scores", None):
            return fallback(args)
        from .core import reference_dir

        if args.b:
            raise ValueError(f"compare --scores takes one folder, the reference; got also {args.b}")
        scores = read_scores(args.scores)
        profile = str(scores["profile"].iloc[0]) if "profile" in scores else None
        ref = Path(args.a) if args.a else reference_dir(profile) if profile else None
        if ref is None or not ref.is_dir():
            raise ValueError(
                f"no reference folder for profile {profile}; name one: "
                f"python -m bench compare REF --scores {args.scores}"
            )
        if ref.is_absolute() and ref.is_relative_to(Path.cwd()):
            ref = ref.relative_to(Path.cwd())
        text, _ = beside(scores, ref, args.min_seeds)
        print(text, end="")
        if args.out:
            Path(args.out).parent.mkdir(parents=True, exist_ok=True)
            Path(args.out).write_text(text)
            print(f"written: {args.out}", file=sys.stderr)
        return 0

    return run
