"""``REPORT.md`` of a results folder: machine, commit, profile, the verdicts, one table and
figure per experiment, and the reference's defects that the suite does not copy.

Entry point: :func:`write_report(results_dir, compare=None) -> Path`. Everything in it is
computed from the stored runs (``bench.core``'s query layer); figures are linked, not
regenerated (:func:`make_figures` draws every registered study's figure). ``compare`` lists
other results folders (e.g. the paper-profile runs) whose verdicts are tabulated beside this
folder's; by default, every subfolder of ``results_dir`` that holds stored runs
(``results/reference/paper``, ``results/reference/paper_gpu``).
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

import models

from ._tables import (
    _discrimination_lines,
    _experiment_table,
    _failed_lines,
    _missing_cells,
    _perf_section,
    _table_variant,
)
from .core import (
    BLOW_UP_RISE,
    ReportContext,
    chosen_profile,
    compare_folders,
    compare_provenance,
    cpu_count,
    describe_profiles,
    experiment_rows,
    get,
    load_runs,
    load_tables,
    profile_counts,
    provenance_markdown,
    report_sections,
    select,
    studies,
)
from .kit import folder_label, md_escape

__all__ = ["write_report"]

DEFECTS = """\
The paper's public code has defects that this suite does not copy:

- its test set was generated with the same seed as the training set (overlapping initial
  conditions); here train and test use independent keys;
- angles were unwrapped across trajectory boundaries, adding 2 pi k offsets that shrink the
  relative error; here angle differences and norms use wrapped angles;
- test chunks only started at t = 0 or 3 s; here test trajectories start at random times;
- the energy metric passed velocities where momenta belong; here the true energy of (q, qdot);
- the t = 0 point (zero error) entered the geometric mean; here it is excluded;
- ground truth was dopri5 at rtol 1e-7 in float32; here float64 with tight tolerances.

`reference_compatible=True` in `bench.core._metrics` reproduces the reference's metric conventions
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
        lines += compute_lines(runs)
    return lines


def compute_lines(runs: pd.DataFrame) -> list[str]:
    """The compute the stored runs took, per device: each run's wall time (one worker each)
    and, where the rows record it, the CPU time measured by the run's process.

    An ensemble member stored before its row carried its share of the ensemble's wall time
    holds only its own evaluation's; its ``train_seconds + compile_seconds`` (its share of
    the ensemble's) is added to the total and named beside it."""
    if "wall_seconds" not in runs or not len(runs):
        return []
    devices = (
        runs["device"].fillna("unknown") if "device" in runs else pd.Series("unknown", runs.index)
    )
    out = []
    for device, rows in runs.groupby(devices, sort=True):
        wall = float(np.nansum(rows["wall_seconds"].to_numpy(float)))
        short, added = _missing_ensemble_share(rows)
        n = f"{len(rows)} run" + ("s" if len(rows) != 1 else "")
        line = f"- compute on {device}: {n}, {_hours(wall + added)} run wall time"
        if short:
            whose = f"{short} rows'" if short != 1 else "1 row's"
            line += (
                f" (with {_hours(added)} of ensemble training that {whose} stored wall time lacks)"
            )
        if "cpu_seconds" in rows and rows["cpu_seconds"].notna().any():
            cpu = rows["cpu_seconds"].dropna()
            line += f", {_hours(float(cpu.sum()))} CPU time (measured by {len(cpu)})"
        out.append(line)
    return out


def _missing_ensemble_share(rows: pd.DataFrame) -> tuple[int, float]:
    """How many ensemble members' stored wall time is below their own share of the
    ensemble's training (``train_seconds + compile_seconds``), and that share's sum."""
    need = ("ensemble_size", "train_seconds", "compile_seconds")
    if not all(c in rows for c in need):
        return 0, 0.0
    share = rows["train_seconds"].fillna(0.0) + rows["compile_seconds"].fillna(0.0)
    short = (rows["ensemble_size"].fillna(1) > 1) & (rows["wall_seconds"] < share)
    return int(short.sum()), float(share[short].sum())


def _hours(seconds: float) -> str:
    return f"{seconds / 3600:.1f} h" if seconds >= 3600 else f"{seconds / 60:.1f} min"


def _status_counts(runs: pd.DataFrame) -> str:
    if "status" not in runs or not len(runs):
        return "0 runs"
    counts = runs["status"].value_counts().to_dict()
    return f"{len(runs)} runs (" + ", ".join(f"{k}: {v}" for k, v in counts.items()) + ")"


def _study_section(study, results_dir: Path, *, figure: bool = True) -> list[str]:
    """A study's own section (and its figure, ``figure``); a broken one is named, not fatal."""
    try:
        out = [study.section(results_dir), ""]
        stem = study.stem or study.name
        if figure and (results_dir / "figures" / f"{stem}.png").exists():
            out += [f"![{stem}](figures/{stem}.png) ([PDF](figures/{stem}.pdf))", ""]
        return out
    except Exception as e:  # noqa: BLE001 - a broken section must not lose the report
        title = study.section_title or study.name
        return [f"## {title}", "", f"(section failed: {md_escape(str(e))})", ""]


def _extra_sections(results_dir: Path) -> list[str]:
    """The sections of the studies with their own tables (trade-off, stability), where their
    data exist, and the performance section. A study that also draws its experiment's figure
    has its section inside its experiment's (``write_report``)."""
    out: list[str] = []
    for study in studies():
        if study.section is None or study.figure is not None:
            continue
        out += _study_section(study, results_dir)
    out += _perf_section(results_dir)
    return out


def _provenance_section(results_dir: Path, runs: pd.DataFrame, others) -> list[str]:
    """Versions, backend and commit of the runs per profile, and where compared folders differ."""
    lines = ["## Provenance", "", provenance_markdown(runs), ""]
    here = folder_label(results_dir)
    for d in others:
        # named as the verdict table names them: a committed report holds no machine's paths
        there = folder_label(d)
        try:
            theirs = load_runs(d)
        except Exception:  # noqa: BLE001 - the verdict table names a folder that cannot be read
            continue
        warnings = compare_provenance(load_runs(results_dir), theirs, names=(here, there))
        if warnings:
            lines += [f"Differences from `{there}`:", "", *[f"- {w}" for w in warnings], ""]
    return lines


def figure_studies() -> list:
    """The registered studies that draw one figure from their experiment's rows, in order."""
    return [s for s in studies() if s.figure is not None]


def figure_stem(name: str) -> str:
    """The file stem of study ``name``'s figure (for the report's links)."""
    return next(s.stem for s in figure_studies() if s.name == name)


def make_figures(results_dir: Path, profile: str | None = None) -> list[Path]:
    """Every study's figure from the stored runs of ``profile`` (default: the one with the
    most rows, :func:`load_tables`); returns the files written.

    Every run of an experiment reaches its figure, failed and diverged ones included: the
    figures score them as the verdicts do (at the worst error, ``kit.scored``) and mark them.
    An experiment without runs draws nothing; one broken figure does not stop the others.
    """
    results_dir = Path(results_dir)
    runs, curves, profile = load_tables(results_dir, profile)
    outdir = results_dir / "figures"
    written: list[Path] = []
    with chosen_profile(results_dir, profile):
        for study in figure_studies():
            rows = experiment_rows(runs, study.name, profile)
            if not len(rows):
                continue
            try:
                written += study.figure(rows, curves, outdir)
            except Exception as e:  # noqa: BLE001 - one broken figure must not stop the others
                print(f"figure {study.name} failed: {type(e).__name__}: {e}")
        for study in studies():
            if study.results_figure is None:
                continue
            try:
                written += list(study.results_figure(results_dir) or [])
            except Exception as e:  # noqa: BLE001
                print(f"figure {study.results_figure.__name__} failed: {type(e).__name__}: {e}")
    return written


def report_profile(args, runs: pd.DataFrame, doing: str) -> str | None:
    """The profile ``figures`` or ``report`` shows: ``args.report_profile`` (``--profile``;
    its rows must be stored, else one line naming the profiles present), else the profile
    ``bench`` just swept (``args.swept_profile``) where its rows are stored, else the one with
    the most rows, named in one line beside the others, so that a smaller profile's rows are
    not left out unseen."""
    from .core import check_profile, pick_profile

    given = getattr(args, "report_profile", None)
    if given is not None:
        check_profile(runs, given, args.results)
        return given
    swept = getattr(args, "swept_profile", None)
    if swept is not None and swept in profile_counts(runs):
        return swept
    kept = pick_profile(runs)
    if kept is not None:
        print(
            f"{args.results} holds {describe_profiles(runs)}: {doing} {kept} "
            "(--profile picks another)"
        )
    return kept


def _blown_up_lines(rows: pd.DataFrame) -> list[str]:
    """The finished runs whose training blew up with a finite loss (``loss_rise`` above
    :data:`BLOW_UP_RISE`): stored as ``ok`` and scored as they are, named so that a reader
    does not take them for models that merely fit poorly. Empty where none did."""
    if not len(rows) or "loss_rise" not in rows:
        return []
    rise = pd.to_numeric(rows["loss_rise"], errors="coerce")
    hit = rows[(rows["status"] == "ok") & (rise > BLOW_UP_RISE)]
    if not len(hit):
        return []
    hit = hit.assign(_label=_table_variant(hit))
    lines = [
        "Training blew up with a finite loss (its last stretch's median loss over "
        f"{BLOW_UP_RISE:g}x its best; status ok, scored as it is):",
        "",
    ]
    for _, r in hit.sort_values(["system", "_label", "seed"]).iterrows():
        rise_r = float(r["loss_rise"])
        lines.append(
            f"- {r['_label']} on {r['system']} seed {r['seed']}: ended {rise_r:.3g}x above its best"
        )
    recorded = int(rise.notna().sum())
    if recorded < len(rows):
        lines.append(f"- ({recorded} of {len(rows)} runs record it; older rows do not)")
    return [*lines, ""]


def _profile_line(results_dir: Path, profile: str | None) -> str:
    """The header's profile line: the profile judged and, where the folder holds others,
    which (with their row counts)."""
    stored = load_runs(results_dir)
    if profile is None or len(profile_counts(stored)) < 2:
        return f"- profile: {profile or 'unknown'}"
    return (
        f"- profile: {profile} (judged here; the folder holds {describe_profiles(stored)}; "
        "`python -m bench report --profile NAME` reports another)"
    )


def write_report(results_dir: Path, compare=None, profile: str | None = None) -> Path:
    """Write ``results_dir/REPORT.md`` from the stored runs of ``profile`` (default: the one
    with the most rows, :func:`load_tables`) and return its path.

    ``compare``: other results folders whose verdicts are tabulated beside these (default:
    :func:`compare_folders`, the subfolders with stored runs); a folder that cannot be read is
    named in the report and skipped."""
    results_dir = Path(results_dir)
    results_dir.mkdir(parents=True, exist_ok=True)
    runs, curves, profile = load_tables(results_dir, profile)
    with chosen_profile(results_dir, profile):
        return _write_report(results_dir, compare, runs, curves, profile)


def _write_report(results_dir: Path, compare, runs, curves, profile) -> Path:
    others = compare_folders(results_dir) if compare is None else [Path(c) for c in compare]
    ctx = ReportContext(results_dir, runs, curves, profile, tuple(others))
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
        _profile_line(results_dir, profile),
        f"- runs: {_status_counts(runs)}",
        *_meta(results_dir, runs),
        "",
    ]
    for section in report_sections():  # the studies' sections: the claims, their verdicts
        lines += section.render(ctx)
    figdir = results_dir / "figures"
    trivial = models.trivial_models()
    for study in figure_studies():
        name = study.name
        rows = experiment_rows(runs, name, profile)
        claim = study.claim
        lines += [f"## {name}" + (f" (claim {claim})" if claim else ""), ""]
        try:
            lines += [get(name).title, ""]
        except ValueError:
            pass
        if not len(rows):
            lines += ["No runs of this experiment are stored: figure and table skipped.", ""]
            lines += _missing_cells(rows, name, profile)
            continue
        ok = select(rows)
        lines.append(f"{_status_counts(rows)}; mean ± standard error over seeds.")
        lines.append("")
        if len(rows):
            lines += _experiment_table(ok) if len(ok) else []
            lines.append("")
            lines += _discrimination_lines(rows)
            lines.append("")
        lines += _missing_cells(rows, name, profile)
        lines += _failed_lines(rows, trivial)
        lines += _blown_up_lines(rows)
        stem = study.stem
        if (figdir / f"{stem}.png").exists():
            lines += [f"![{name}](figures/{stem}.png) ([PDF](figures/{stem}.pdf))", ""]
        elif not len(ok):
            lines += ["(no figure: no finished runs)", ""]
        else:
            lines += ["(figure not generated: run `python -m bench figures`)", ""]
        if study.section is not None:  # its own table closes its experiment's section
            lines += _study_section(study, results_dir, figure=False)
    lines += _extra_sections(results_dir)
    lines += _provenance_section(results_dir, runs, others)
    lines += ["## What the suite does not copy from the reference", "", DEFECTS]
    path = results_dir / "REPORT.md"
    path.write_text("\n".join(lines))
    return path
