"""``results/REPORT.md``: machine, commit, profile, the eight verdicts, one table and figure per
experiment, and the reference's defects that the suite does not copy.

Entry point: :func:`write_report(results_dir) -> Path`. Everything in it is computed from the
stored runs (``bench._store``); figures are linked, not regenerated (``make_figures`` does that).
"""

from __future__ import annotations

import datetime as _dt
import json
import math
import os
import platform
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd

from ._claims import CLAIM_EXPERIMENTS, evaluate_claims, option, select
from ._env import cpu_count
from ._figures import FIGURES, experiment_rows, figure_stem, load_tables, variant

__all__ = ["write_report"]

DEFECTS = """\
The reference implementation has defects that this suite does not copy (REFERENCE.md):

- its test set was generated with the same seed as the training set (overlapping initial
  conditions); here train and test use independent keys;
- angles were unwrapped across trajectory boundaries, adding 2 pi k offsets that shrink the
  relative error; here angle differences and norms use wrapped angles;
- test chunks only started at t = 0 or 3 s; here test trajectories start at random times;
- the energy metric passed velocities where momenta belong; here the true energy of (q, qdot);
- the t = 0 point (zero error) entered the geometric mean; here it is excluded;
- ground truth was dopri5 at rtol 1e-7 in float32; here float64 with tight tolerances.

`reference_compatible=True` in `bench._metrics` reproduces the reference's metric conventions
(t = 0 included, no angle wrapping) for comparison with the paper's printed numbers only; the
verdicts and tables here never use it.
"""


def _git_commit() -> str:
    try:
        out = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, timeout=10
        )
        return out.stdout.strip() or "unknown"
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def _fmt(x, digits: int = 3) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    return f"{x:.{digits}g}"


def _pm(mean, sem) -> str:
    if not np.isfinite(mean):
        return "-"
    return _fmt(mean) if not np.isfinite(sem) else f"{_fmt(mean)} ± {_fmt(sem, 2)}"


def _md_escape(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _meta(results_dir: Path, runs: pd.DataFrame) -> list[str]:
    lines = []
    meta_path = results_dir / "bench_meta.json"
    meta = {}
    if meta_path.exists():
        try:
            meta = json.loads(meta_path.read_text())
        except ValueError:
            meta = {}
    wall = meta.get("wall_seconds")
    if wall is None and "start" in meta and "end" in meta:
        try:
            wall = float(meta["end"]) - float(meta["start"])
        except (TypeError, ValueError):
            wall = None
    if wall is not None:
        n_exec = meta.get("runs_executed")
        which = f", {n_exec} runs executed, the rest already stored" if n_exec is not None else ""
        lines.append(f"- sweep wall time: {float(wall) / 60:.1f} min (bench_meta.json{which})")
    else:
        lines.append("- sweep wall time: not recorded (no results/bench_meta.json)")
    if meta.get("note"):
        lines.append(f"- note: {meta['note']}")
    if len(runs):
        parts = [c for c in ("train_seconds", "compile_seconds", "rollout_seconds") if c in runs]
        total = float(np.nansum(runs[parts].to_numpy(float))) if parts else math.nan
        lines.append(f"- sum of per-run {' + '.join(parts)}: {total / 60:.1f} min")
    return lines


def _status_counts(runs: pd.DataFrame) -> str:
    if "status" not in runs or not len(runs):
        return "0 runs"
    counts = runs["status"].value_counts().to_dict()
    return f"{len(runs)} runs (" + ", ".join(f"{k}: {v}" for k, v in counts.items()) + ")"


def _claims_table(verdicts) -> list[str]:
    out = [
        "| claim | statement | verdict | effect | 95% CI | seeds | detail |",
        "| --- | --- | --- | --- | --- | --- | --- |",
    ]
    for v in verdicts:
        ci = f"[{_fmt(v.ci_low)}, {_fmt(v.ci_high)}]" if np.isfinite(v.ci_low) else "-"
        effect = f"{_fmt(v.effect)} ({v.effect_name})" if v.effect_name else _fmt(v.effect)
        out.append(
            f"| {v.claim} | {_md_escape(v.title)} | **{v.verdict}** | {_md_escape(effect)} | "
            f"{ci} | {v.n_seeds} | {_md_escape(v.detail)} |"
        )
    return out


# Columns that tell the cells of an experiment apart, in display order.
CELL_COLUMNS = (
    "system",
    "k",
    "friction",
    "variant",
    "coordinates",
    "loss",
    "weight",
    "n_train",
    "noise",
)


def _experiment_table(rows: pd.DataFrame) -> list[str]:
    df = rows.assign(variant=variant(rows), weight=option(rows, "weight"))
    cells = [c for c in CELL_COLUMNS if c in df and df[c].astype(str).nunique() > 1]
    if not cells:
        cells = ["variant"]
    for c in cells:
        df[c] = df[c].astype(object).where(df[c].notna(), "-")
    metrics = [
        ("rollout_error", "rollout error"),
        ("energy_violation", "energy violation"),
        ("energy_pct_max_pe", "energy % max PE"),
        ("n_params", "params"),
        ("train_seconds", "train s"),
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
        label = [str(k) for k in key]
        out.append("| " + " | ".join([*label, str(g["seed"].nunique()), *vals]) + " |")
    return out


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
        "paper's PyTorch code on this machine class (REFERENCE.md); speedup = reference / ours; "
        "FLOP floor = the step's FLOPs (XLA cost analysis) over the measured matmul peak.",
        "",
        "| " + " | ".join(cols) + " |",
        "|" + "---|" * len(cols),
    ]
    for _, r in df.iterrows():
        lines.append("| " + " | ".join(_fmt(r[c]) if c != "model" else r[c] for c in cols) + " |")
    return lines + [""]


def _extra_sections(results_dir: Path) -> list[str]:
    """Trade-off, stability and performance sections (issue 6), where their data exist."""
    out: list[str] = []
    try:
        from ._tradeoff import tradeoff_section

        out += [tradeoff_section(results_dir), ""]
        if (results_dir / "figures" / "tradeoff.png").exists():
            out += ["![tradeoff](figures/tradeoff.png) ([PDF](figures/tradeoff.pdf))", ""]
    except Exception as e:  # noqa: BLE001 - a broken section must not lose the report
        out += ["## Speed/accuracy trade-off", "", f"(section failed: {_md_escape(str(e))})", ""]
    try:
        from ._stability import stability_section

        out += [stability_section(results_dir), ""]
        if (results_dir / "figures" / "stability.png").exists():
            out += ["![stability](figures/stability.png) ([PDF](figures/stability.pdf))", ""]
    except Exception as e:  # noqa: BLE001
        out += ["## Numerical stability", "", f"(section failed: {_md_escape(str(e))})", ""]
    out += _perf_section(results_dir)
    return out


def write_report(results_dir: Path) -> Path:
    """Write ``results_dir/REPORT.md`` from the stored runs and return its path."""
    results_dir = Path(results_dir)
    results_dir.mkdir(parents=True, exist_ok=True)
    runs, curves, profile = load_tables(results_dir)
    verdicts = evaluate_claims(runs, curves, profile)
    now = _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%d %H:%M UTC")
    lines = [
        "# decon-bench report",
        "",
        "Reproduction of Gruver et al. (ICLR 2022), *Deconstructing the inductive biases of "
        "Hamiltonian neural networks*, and of the HNN/LNN/VIN seed papers. Generated by "
        "`python -m bench report` from the stored runs; every number below is computed from "
        "`results/runs.parquet` and `results/curves.parquet`.",
        "",
        f"- machine: {platform.platform()}, {platform.processor() or platform.machine()}, "
        f"{cpu_count()} cores available (os.cpu_count = {os.cpu_count()})",
        f"- date: {now}",
        f"- commit: {_git_commit()}",
        f"- profile: {profile or 'unknown'}",
        f"- runs: {_status_counts(runs)}",
        *_meta(results_dir, runs),
        "",
        "## Claims",
        "",
        "Verdict rules are in the docstrings of `bench/_claims.py`: effects are per-seed log "
        "ratios of geometric-mean rollout errors (paired by seed) with a 95% percentile "
        "bootstrap over seeds; a claim is *reproduced* when every part holds, *not reproduced* "
        "when a part is contradicted, *inconclusive* otherwise or with fewer than 2 seeds. With "
        "3 seeds the bootstrap interval is about [min, max] over seeds.",
        "",
        *_claims_table(verdicts),
        "",
    ]
    figdir = results_dir / "figures"
    for name in FIGURES:
        rows = experiment_rows(runs, name, profile)
        claim = next((c for c, e in CLAIM_EXPERIMENTS.items() if name in e), None)
        lines += [f"## {name}" + (f" (claim {claim})" if claim else ""), ""]
        try:
            from ._experiments import get

            lines += [get(name).title, ""]
        except (ImportError, ValueError):
            pass
        if not len(rows):
            lines += ["No runs of this experiment are stored: figure and table skipped.", ""]
            continue
        bad = rows[rows["status"] != "ok"] if "status" in rows else rows.iloc[0:0]
        ok = select(rows)
        lines.append(f"{_status_counts(rows)}; mean ± standard error over seeds.")
        lines.append("")
        if len(ok):
            lines += _experiment_table(ok)
            lines.append("")
        for _, r in bad.iterrows():
            err = r.get("error") or f"diverged at step {r.get('diverged_step')}"
            lines.append(
                f"- {r['model']} on {r['system']} seed {r['seed']}: {r['status']} "
                f"({_md_escape(str(err))[:200]})"
            )
        if len(bad):
            lines.append("")
        stem = figure_stem(name)
        if (figdir / f"{stem}.png").exists():
            lines += [f"![{name}](figures/{stem}.png) ([PDF](figures/{stem}.pdf))", ""]
        else:
            lines += ["(figure not generated: run `python -m bench figures`)", ""]
    lines += _extra_sections(results_dir)
    lines += ["## What the suite does not copy from the reference", "", DEFECTS]
    path = results_dir / "REPORT.md"
    path.write_text("\n".join(lines))
    return path
