"""The report's per-experiment Markdown: the table of cells, the discrimination lines, the
cells without runs, and the performance table. Part of the report layer (``bench._report``).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from .core import cell_key, expand, option, params_of, parse_pairs, row_cell_keys, variant
from .kit import (
    MODEL_LABELS,
    TRIVIAL_MODELS,
    discrimination,
    seed_span,
    several_rates,
    velocity_scores,
)
from .kit import fmt as _fmt
from .kit import md_escape as _md_escape


def _pm(mean, sem) -> str:
    if not np.isfinite(mean):
        return "-"
    return _fmt(mean) if not np.isfinite(sem) else f"{_fmt(mean)} ± {_fmt(sem, 2)}"


# Columns that tell the cells of an experiment apart, in display order.
CELL_COLUMNS = (
    "system",
    "k",
    "friction",
    "initial",
    "variant",
    "coordinates",
    "lr",
    "loss",
    "weight",
    "n_train",
    "noise",
)


def _table_variant(rows: pd.DataFrame) -> pd.Series:
    """Model label key plus the model options other than the regulariser weight; the Rayleigh
    HNN is named as the damped HNN of claim 5's further reading."""
    base = variant(rows).replace({"hnn_so_diss": "hnn_so + Rayleigh"})

    def opts(v) -> str:
        o = {a: b for a, b in parse_pairs(v).items() if a != "weight"}
        return "[" + ", ".join(f"{a}={b}" for a, b in sorted(o.items())) + "]" if o else ""

    extra = rows["model_options"].map(opts) if "model_options" in rows else ""
    return base + extra


def _initial(rows: pd.DataFrame) -> pd.Series:
    return params_of(rows).map(lambda p: p.get("initial", "-"))


def _cells(rows: pd.DataFrame) -> tuple[pd.DataFrame, list[str]]:
    """``rows`` with the table's cell columns filled in, and those of :data:`CELL_COLUMNS` that
    tell the experiment's cells apart (the variant and coordinates always)."""
    df = rows.assign(
        variant=_table_variant(rows), weight=option(rows, "weight"), initial=_initial(rows)
    )
    cells = [
        c
        for c in CELL_COLUMNS
        if c in df
        and (df[c].astype(str).nunique() > 1 or c in ("variant", "coordinates"))
        and (c != "lr" or several_rates(rows))
    ]
    return df, cells


def _failed_lines(rows: pd.DataFrame, trivial) -> list[str]:
    """The failed and diverged runs of an experiment, a line per cell: its model, the cell as
    the table names it (the columns that tell the cells apart), what happened on which seeds
    (a diverged run: the training step at which it went non-finite; a failed run: its error)
    and how the verdicts count it (a model's: error 1; a trivial predictor's: not at all)."""
    if "status" not in rows or not (rows["status"] != "ok").any():
        return []
    df, cells = _cells(rows)
    bad = df[df["status"] != "ok"].copy()
    shown = [c for c in cells if c not in ("system", "variant", "coordinates")]
    bad["_where"] = bad.apply(_where, axis=1, shown=shown)
    bad["_what"] = bad.apply(_what_happened, axis=1)
    out = []
    for (where, what), g in bad.groupby(["_where", "_what"], sort=False):
        counted = g["model"].iloc[0] not in trivial
        how = "scored as error 1" if counted else "not counted (a trivial predictor)"
        seeds = seed_span(g["seed"].astype(int))
        which = f"seed {seeds}" if len(g) == 1 else f"seeds {seeds} ({len(g)} runs)"
        steps = pd.to_numeric(g["diverged_step"], errors="coerce").dropna().astype(int)
        if what == "diverged" and len(steps):
            lo, hi = steps.min(), steps.max()
            what = f"diverged at step {lo}" if lo == hi else f"diverged at steps {lo}-{hi}"
        out.append(f"- {where}, {which}: {what}; {how}")
    return [*out, ""]


def _where(r, shown) -> str:
    """A run's model (its coordinates where canonical), system and the cell columns ``shown``."""
    coords = " (q, p)" if r.get("coordinates") == "momentum" else ""
    cell = ", ".join(f"{c}={r[c]}" for c in shown)
    return f"{r['variant']}{coords} on {r['system']}" + (f" ({cell})" if cell else "")


def _what_happened(r) -> str:
    """A failed run's error (one line, 200 characters), or the word for its status."""
    err = r.get("error")
    if isinstance(err, str) and err and r["status"] != "diverged":
        return _md_escape(err)[:200]
    return str(r["status"])


def _experiment_table(rows: pd.DataFrame) -> list[str]:
    df, cells = _cells(rows)
    for c in cells:
        df[c] = df[c].astype(object).where(df[c].notna(), "-")
    metrics = [
        ("rollout_error", "rollout error"),
        ("rollout_error_velocity", "error on (q, qdot)"),
        ("mse", "MSE"),
        ("energy_violation", "energy violation"),
        ("energy_pct_max_pe", "energy % max PE"),
        ("energy_mse", "energy MSE"),
        ("derivative_mse_test", "test loss dz/dt"),
        ("symplectic_error", "symplectic error"),
        ("n_params", "params"),
        ("train_seconds", "train s"),
        ("flops_per_step", "FLOPs/step"),
    ]
    metrics = [m for m in metrics if m[0] in df and pd.to_numeric(df[m[0]], "coerce").notna().any()]
    head = [*cells, "seeds", *[label for _, label in metrics]]
    out = ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    for key, g in df.groupby(cells, sort=True):
        key = key if isinstance(key, tuple) else (key,)
        vals = []
        for col, _ in metrics:
            x = pd.to_numeric(g[col], errors="coerce").to_numpy(float)
            x = x[np.isfinite(x)]
            sem = np.std(x, ddof=1) / math.sqrt(len(x)) if len(x) > 1 else math.nan
            if col == "n_params" and len(x):
                vals.append(f"{np.mean(x):.0f}")
                continue
            vals.append(_pm(float(np.mean(x)) if len(x) else math.nan, sem))
        label = [
            f"{k} (trivial)"
            if c == "variant" and str(k).split("[")[0] in TRIVIAL_MODELS
            else str(k)
            for c, k in zip(cells, key, strict=True)
        ]
        out.append("| " + " | ".join([*label, str(g["seed"].nunique()), *vals]) + " |")
    return out


def _group_columns(rows: pd.DataFrame) -> list[str]:
    return [c for c in ("system", "k", "friction", "initial") if c in rows]


def _discrimination_lines(rows: pd.DataFrame) -> list[str]:
    """One "discriminating: yes/no" line per comparison group (system, k, friction, initial)."""
    out = []
    for d in discrimination_groups(rows):
        mark = {"yes": "yes", "no": "**no**", "unknown": "unknown"}[d.status]
        text = (
            d.text().split(f"discriminating {d.status} ", 1)[-1]
            if d.status != "unknown"
            else "no finished trivial-predictor runs"
        )
        out.append(f"- discriminating: {mark} ({d.group}): {text}")
    return out


def discrimination_groups(rows: pd.DataFrame) -> list:
    """Whether an experiment's test set discriminates, per comparison group (system, k,
    friction, initial state): :func:`bench.kit.discrimination` of each group,
    named ``"system=..., k=..."``."""
    if not len(rows):
        return []
    df = rows.assign(initial=_initial(rows))
    metric_rows = df
    scores = None
    if (
        "rollout_error_velocity" in df
        and (df["coordinates"] == "momentum").any()
        and (df["coordinates"] == "velocity").any()
    ):
        scores, _ = velocity_scores(df)
    out = []
    cols = _group_columns(df)
    for key, g in metric_rows.groupby(cols, dropna=False, sort=True):
        key = key if isinstance(key, tuple) else (key,)
        name = ", ".join(
            f"{c}={_fmt(k) if isinstance(k, float) else k}"
            for c, k in zip(cols, key, strict=True)
            if str(k) not in ("nan", "-", "0.0")
        )
        out.append(
            discrimination(g, name, scores=scores.loc[g.index] if scores is not None else None)
        )
    return out


def _missing_cells(rows: pd.DataFrame, name: str, profile: str | None) -> list[str]:
    """The declared cells of experiment ``name`` at ``profile`` that have no stored run."""
    if profile is None:
        return []
    try:
        want = {}
        for c in expand(name, profile):
            want.setdefault(cell_key(c), c)
        have = set(row_cell_keys(rows))
    except ValueError:
        return []
    missing = [c for k, c in want.items() if k not in have]
    if not missing:
        return []
    declared = list(want.values())
    lr_varies = several_rates(
        pd.DataFrame({"model": [c.model for c in declared], "lr": [c.lr for c in declared]})
    )
    labels = sorted(
        {
            f"{MODEL_LABELS.get(c.model, c.model)} on {c.system}"
            + (f" k={c.k}" if c.k else "")
            + (f" {dict(c.model_options)}" if c.model_options else "")
            + (f" {dict(c.system_params)}" if c.system_params else "")
            + (f" ({c.coordinates})" if c.coordinates != "velocity" else "")
            + (f" noise={c.noise:g}" if c.noise else "")
            + (f" n_train={c.n_train}" if name == "vin" else "")
            + (f" lr={c.lr:g}" if lr_varies else "")
            for c in missing
        }
    )
    shown = "; ".join(labels[:12]) + (
        f"; ... ({len(labels) - 12} more)" if len(labels) > 12 else ""
    )
    return [f"No runs for {len(missing)} declared cells (every seed): {_md_escape(shown)}.", ""]


def _perf_section(results_dir: Path) -> list[str]:
    """The performance table of ``results/perf.csv`` (written by ``python -m bench perf``)."""
    path = results_dir / "perf.csv"
    head = ["## Performance (training step and test rollout)", ""]
    if not path.exists():
        return head + ["No `perf.csv` yet: `python -m bench perf`.", ""]
    df = pd.read_csv(path)
    cols = [
        c
        for c in (
            "model",
            "ms_per_step_median",
            "reference_step_ms",
            "speedup_step",
            "flop_floor_ms",
            "rollout_ms_median",
            "reference_rollout_ms",
            "speedup_rollout",
            "compile_s",
        )
        if c in df
    ]
    when = df["date"].iloc[0] if "date" in df else "?"
    load = f", load average {df['load_avg'].median():.1f}" if "load_avg" in df else ""
    lines = head + [
        f"Measured by `python -m bench perf` ({when}{load}) at the reference setting: chain-2, "
        "2 x 256 tanh, batch 200, chunk 5, RK4 (3/8) one step per dt, float32. Reference = the "
        "paper's PyTorch code timed on this machine class; speedup = reference / ours; "
        "FLOP floor = the step's FLOPs (XLA cost analysis) over the measured matmul peak.",
        "",
        "| " + " | ".join(cols) + " |",
        "|" + "---|" * len(cols),
    ]
    for _, r in df.iterrows():
        lines.append("| " + " | ".join(_fmt(r[c]) if c != "model" else r[c] for c in cols) + " |")
    return lines + [""]
