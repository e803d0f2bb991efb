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

from ._tables import (
    _discrimination_lines,
    _experiment_table,
    _fmt,
    _md_escape,
    _missing_cells,
    _perf_section,
    _table_variant,
)
from .core._env import cpu_count
from .core._experiments import get
from .core._provenance import compare_provenance, provenance_markdown
from .core._query import (
    experiment_rows,
    load_tables,
    select,
)
from .core._store import REFERENCE_ROOT, compare_folders, load_runs
from .core._studies import studies
from .studies.paper import (
    TRIVIAL_FACTOR,
    TRIVIAL_MODELS,
)
from .studies.paper._replication import judge
from .studies.paper._sensitivity import margin_dependence

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
    return lines


def _status_counts(runs: pd.DataFrame) -> str:
    if "status" not in runs or not len(runs):
        return "0 runs"
    counts = runs["status"].value_counts().to_dict()
    return f"{len(runs)} runs (" + ", ".join(f"{k}: {v}" for k, v in counts.items()) + ")"


def _disc_mark(v) -> str:
    return {True: "yes", False: "**no**", None: "unknown"}[v.discriminating]


def _ci(lo, hi) -> str:
    return f"[{_fmt(lo)}, {_fmt(hi)}]" if np.isfinite(lo) and np.isfinite(hi) else "-"


def _loso_text(j, key: str) -> str:
    runs = j.loso.get(key, [])
    if not runs:
        return "-"
    changes = j.loso_changes(key)
    if not changes:
        return f"stable (each of {len(runs)} seeds dropped)"
    return "changes: " + "; ".join(f"without seed {s}: {v.verdict}" for s, v in changes)


def _not_run_note(profile) -> list[str]:
    """One line per claim that is not judged at ``profile`` (its experiments do not run there)."""
    from .studies.paper._rules import claims_not_run

    out = []
    for study in claims_not_run(profile):
        names = ", ".join(f"`{e.name}`" for e in study.experiments)
        runs_at = sorted({p for e in study.experiments for p in (e.profiles or ())})
        out.append(
            f"Claim {study.claim} is not run at {profile} ({names} runs at "
            f"{', '.join(runs_at)}): see *Verdicts at both budgets*."
        )
    return [*out, ""] if out else []


def _claims_table(j) -> list[str]:
    """One row per claim (claim 4: per metric and spring start): the final verdict, the
    verdicts on the primary and replication seeds and pooled, whether it replicates, and what
    dropping one seed does. Effect and interval are the final reading's."""
    from .studies.paper._replication import seed_span

    ps, rs = seed_span(j.primary_seeds), seed_span(j.replication_seeds)
    both = seed_span(sorted({*j.primary_seeds, *j.replication_seeds}))
    out = [
        f"| claim | statement | verdict | seeds {ps} | seeds {rs or '(none)'} | pooled {both} | "
        "replicates | leave one seed out | effect | 90% CI | discriminating | failed runs |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for v in j.final:
        p = j.reading(v.key)
        r = j.replication.get(v.key)
        pooled = j.pooled.get(v.key)
        rep = {True: "yes", False: "**no**", None: "not run"}[j.replicates(v.key)]
        if v.key in j.replication_pending:
            rep = "pending ({} of {} runs)".format(*j.replication_pending[v.key])
        effect = f"{_fmt(p.effect)} ({p.effect_name})" if p.effect_name else _fmt(p.effect)
        prim = j.primary[v.key]
        out.append(
            f"| {_md_escape(v.key)} | {_md_escape(v.title)} | **{v.verdict}** | {prim.verdict} "
            f"({prim.n_seeds}) | {r.verdict + f' ({r.n_seeds})' if r else '-'} | "
            f"{pooled.verdict + f' ({pooled.n_seeds})' if pooled else '-'} | {rep} | "
            f"{_md_escape(_loso_text(j, v.key))} | {_md_escape(effect)} | "
            f"{_ci(p.ci_low, p.ci_high)} | {_disc_mark(p)} | {p.n_failed} |"
        )
    return out


def _parts_table(j) -> list[str]:
    """Every part of the final reading (pooled where the seed sets agree): its effect, margin,
    the margins at which it holds and is contradicted, its test and level, its status on each
    seed set, and whether dropping one seed reverses it."""
    from .studies.paper._replication import seed_span
    from .studies.paper.kit import margin_ranges

    ps, rs = seed_span(j.primary_seeds), seed_span(j.replication_seeds)
    out = [
        "| claim | part | role | kind | margin | margin range | test (level) | effect [90% CI] | "
        f"seeds {ps} | seeds {rs or '(none)'} | pooled | leave one seed out |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for v in j.final:
        reading = j.reading(v.key)
        prim = {q.name: q for q in j.primary[v.key].parts}
        rep = {q.name: q for q in j.replication[v.key].parts} if v.key in j.replication else {}
        pooled = {q.name: q for q in j.pooled[v.key].parts} if v.key in j.pooled else {}
        loso = [(s, {q.name: q for q in w.parts}) for s, w in j.loso.get(v.key, [])]
        flip = {("holds", "contradicts"), ("contradicts", "holds")}
        for part in reading.parts:
            if part.status != "not tested" and not part.ranges:
                part.ranges = margin_ranges(part)
            moved = [s for s, d in loso if d.get(part.name) and d[part.name].status != part.status]
            reversed_ = [
                s
                for s, d in loso
                if d.get(part.name) and (part.status, d[part.name].status) in flip
            ]
            if not loso:
                lo_text = "-"
            elif reversed_:
                lo_text = "**reversed** without seed " + ", ".join(map(str, reversed_))
            elif moved:
                lo_text = "changes without seed " + ", ".join(map(str, moved))
            else:
                lo_text = "stable"
            test = f"{part.test} ({part.alpha:.3g})" if part.test else "-"
            name = part.name + (
                f" (not tested: {part.note})" if part.status == "not tested" else ""
            )
            cells = [d[part.name].status if part.name in d else "-" for d in (prim, rep, pooled)]
            out.append(
                f"| {_md_escape(v.key)} | {_md_escape(name)} | {part.role} | "
                f"{part.kind or '-'} | {_md_escape(part.margin) or '-'} | "
                f"{_md_escape(part.range_text())} | {_md_escape(test)} | {_fmt(part.point)} "
                f"{_ci(part.lo, part.hi)} | {cells[0]} | {cells[1]} | {cells[2]} | {lo_text} |"
            )
    return out


def _policy_section() -> list[str]:
    """The margin policy: one margin per quantity, its plausible band, the words it covers,
    and the margins the seeds state as numbers."""
    from .studies.paper import policy

    out = [
        "## Margin policy",
        "",
        "One margin per compared quantity, the same for every word the papers use about it "
        "(`bench/studies/paper/policy.py`); a ratio of mean squares (MSE, loss, energy MSE) "
        "uses the square of its quantity's margin. The band is the range of margins a "
        "reasonable reader might pick: *Margin-dependent claims* below re-judges every claim "
        "across it.",
        "",
        "| quantity | margin | plausible band | words | why |",
        "| --- | --- | --- | --- | --- |",
    ]
    for q in policy.POLICY.values():
        fmt = (lambda x: f"{x:.3g}x") if q.ratio else (lambda x: f"{x:g}")
        out.append(
            f"| {q.label} | {fmt(q.margin)} | {fmt(q.band[0])} to {fmt(q.band[1])} | "
            f"{_md_escape(q.words)} | {_md_escape(q.why)} |"
        )
    stated = policy.stated_margins()
    if stated:
        out += ["", "Margins the seeds state as numbers (never varied):", ""]
        for m in stated:
            out.append(f'- {m.quantity}, {m.label()}: "{m.quote}" ({m.source})')
    return [*out, ""]


def _dependence_section(deps, final) -> list[str]:
    out = [
        "## Margin-dependent claims",
        "",
        "Each claim's final reading judged again at the ends and the middle of the plausible "
        "band of each quantity its parts use (one quantity at a time, the others at the policy's; "
        "learning is the learning gate).",
        "",
    ]
    if not deps:
        return [*out, "No verdict changes inside any band.", ""]
    out += [
        "| claim | quantity | verdict at the policy | verdicts across the band |",
        "| --- | --- | --- | --- |",
    ]
    for d in deps:
        out.append(
            f"| {_md_escape(d.key)} | {d.quantity} | {d.at_policy} | {_md_escape(d.text())} |"
        )
    keys = sorted({d.key for d in deps}, key=lambda k: [v.key for v in final].index(k))
    return [*out, "", f"Margin-dependent: claim {', '.join(keys)}.", ""]


def _folder_label(d: Path) -> str:
    """A folder as the report names it: relative to ``results/`` where it lies under it."""
    try:
        return str(Path(d).resolve().relative_to(REFERENCE_ROOT.parent))
    except ValueError:
        return Path(d).name


def _no_runs(v) -> bool:
    """No comparable verdict: no runs at all, a cell the claim needs is missing, or the
    claim's runs are still being computed (``pending``)."""
    return v is None or v.n_seeds == 0 or _is_pending(v)


def _is_pending(v) -> bool:
    """The claim's campaign has not stored all its runs yet (:func:`_pending`)."""
    return v is not None and v.pending is not None


def _outcome(v) -> str:
    """The verdict without the reason of an inconclusive one: *inconclusive (does not
    replicate)* and *inconclusive* agree (neither signs the claim)."""
    return v.verdict.split(" (")[0]


def _absent(v) -> bool:
    """The folder has none of the claim's runs (its cell reads *no runs*)."""
    return v is None or (v.detail == "no runs" and not _is_pending(v))


def _cell_text(v) -> str:
    if _is_pending(v):
        return v.verdict
    if _absent(v):
        return "no runs"
    if v.n_seeds == 0:
        return f"**{v.verdict}** (cells missing)"
    return f"**{v.verdict}**" + (" (not discriminating)" if v.discriminating is False else "")


def _cause(a, b, label_a: str, label_b: str, same_profile_metric: str = "") -> list[str]:
    """The likely causes of two verdicts of one claim disagreeing."""
    if _no_runs(a) or _no_runs(b):
        # name the side that has some runs (pending or cells missing) before one with none
        sides = [(v, lab) for v, lab in ((a, label_a), (b, label_b)) if _no_runs(v)]
        v, label = next(((v, lab) for v, lab in sides if not _absent(v)), sides[0])
        if _is_pending(v):
            return [f"{v.verdict} at {label}: not comparable yet"]
        what = "no runs" if _absent(v) else "cells missing"
        return [f"{what} at {label}: not comparable"]
    causes = []
    # A verdict the replication checks demoted (does not replicate, changes without a seed):
    # where its own seeds read what the other folder reads, the folders agree in direction and
    # the disagreement is that reading's stability, not the budget.
    agree_but_unstable = False
    for v, lab, o, o_lab in ((a, label_a, b, label_b), (b, label_b, a, label_a)):
        if v.primary is None:
            continue
        why = v.verdict.split(" (", 1)[1].rstrip(")")
        if v.primary == _outcome(o):
            agree_but_unstable = o.primary is None
            causes.append(
                f"stability: {lab} reads {v.primary} on its own seeds, as {o_lab} does, but "
                f"{why} ({v.readings})"
            )
        else:
            causes.append(f"stability: at {lab} the verdict {why} ({v.readings})")
    if agree_but_unstable:
        return causes
    if a.discriminating != b.discriminating:
        causes.append(
            f"test set: discriminating {_disc_mark(a)} at {label_a}, {_disc_mark(b)} at {label_b}"
        )
    if a.n_failed != b.n_failed:
        causes.append(f"failed runs ({a.n_failed} vs {b.n_failed})")
    if same_profile_metric:
        causes.append(same_profile_metric)
    if a.n_seeds != b.n_seeds and min(a.n_seeds, b.n_seeds) < 2:
        causes.append("too few seeds on one side")
    causes.append(
        "budget (training steps, data, width and seeds differ between the profiles: "
        "effects that need the longer training show only at the paper profile)"
    )
    return causes


def _comparison_section(verdicts, profile: str | None, others) -> list[str]:
    """Every claim's verdict here and in each other results folder, side by side."""
    if not others:
        return []
    labels = [f"{profile or 'this folder'} (here)" if others else profile or "this folder"] + [
        f"{p or 'unknown'} (`{_folder_label(d)}/`)" for d, p, _ in others
    ]
    head = ["claim", *labels, "agree", "likely cause of a disagreement"]
    out = [
        "## Verdicts at both budgets",
        "",
        "Each claim's verdict from these runs and from the other results folders (same rules; "
        "a folder without a claim's runs says *no runs*). Where they disagree, the likely cause "
        "is named: missing runs, a test set that does not discriminate, failed runs, the "
        "stability of one folder's reading (it does not replicate on seeds 5-9 or changes "
        "without one seed; where its own seeds read as the other folder does, that is the only "
        "cause named), the metric "
        "(claim 4: geometric-mean error vs MSE), or the budget (the paper profile trains 8000 "
        "steps on 800 trajectories at width 256 with 5 seeds; quick 1000 steps on 200 at width "
        "128 with 5). *agree* compares the verdicts (reproduced, partly reproduced, not "
        "reproduced, inconclusive), not an inconclusive verdict's reason: neither "
        "*inconclusive* nor *inconclusive (does not replicate)* signs the claim.",
        "",
        "| " + " | ".join(head) + " |",
        "|" + " --- |" * len(head),
    ]
    maps = [{v.key: v for v in verdicts}] + [{v.key: v for v in vs} for _, _, vs in others]
    keys = list(dict.fromkeys(k for m in maps for k in m))

    def metric_note(m, key) -> str:
        if not key.startswith("4 ("):
            return ""
        other = (
            key.replace("geometric-mean error", "MSE")
            if "geometric" in key
            else key.replace("MSE", "geometric-mean error")
        )
        a, b = m.get(key), m.get(other)
        if a and b and _outcome(a) != _outcome(b) and not (_no_runs(a) or _no_runs(b)):
            return "metric: geometric-mean error and MSE disagree within a profile"
        return ""

    for key in keys:
        vs = [m.get(key) for m in maps]
        claim = next(m[key].claim for m in maps if key in m)
        for i, m in enumerate(maps):  # a key its pending campaign has no rows for yet
            if vs[i] is None:
                vs[i] = next(
                    (v for v in m.values() if v.claim == claim and _is_pending(v)),
                    None,
                )
        cells = [_cell_text(v) for v in vs]
        real = [v for v in vs if not _no_runs(v)]
        agree = (
            "-" if len(real) < 2 else ("yes" if len({_outcome(v) for v in real}) == 1 else "**no**")
        )
        # Causes against the first folder with a comparable verdict (here, unless here is
        # pending or has no runs: then the others' disagreement is still explained).
        base = next((i for i, v in enumerate(vs) if not _no_runs(v)), 0)
        causes = []
        for i in range(len(vs)):
            a, b = vs[base], vs[i]
            # a folder without the claim's runs says so in its cell: no cause to name
            if i == base or (_no_runs(a) and _no_runs(b)) or _absent(b):
                continue
            if a is None or b is None or _outcome(a) != _outcome(b) or _no_runs(a) != _no_runs(b):
                note = metric_note(maps[base], key) or metric_note(maps[i], key)
                causes += _cause(a, b, labels[base], labels[i], note)
        causes = list(dict.fromkeys(causes))  # each cause once, whichever folders share it
        out.append(
            "| "
            + " | ".join([_md_escape(key), *cells, agree, _md_escape("; ".join(causes)) or "-"])
            + " |"
        )
    return out + [""]


def _extra_sections(results_dir: Path) -> list[str]:
    """The sections of the studies with their own tables (trade-off, stability), where their
    data exist, and the performance section."""
    out: list[str] = []
    for study in studies():
        if study.section is None:
            continue
        try:
            out += [study.section(results_dir), ""]
            stem = study.stem or study.name
            if (results_dir / "figures" / f"{stem}.png").exists():
                out += [f"![{stem}](figures/{stem}.png) ([PDF](figures/{stem}.pdf))", ""]
        except Exception as e:  # noqa: BLE001 - a broken section must not lose the report
            title = study.section_title or study.name
            out += [f"## {title}", "", f"(section failed: {_md_escape(str(e))})", ""]
    out += _perf_section(results_dir)
    return out


def _provenance_section(results_dir: Path, runs: pd.DataFrame, others) -> list[str]:
    """Versions, backend and commit of the runs per profile, and where compared folders differ."""
    lines = ["## Provenance", "", provenance_markdown(runs), ""]
    here = _folder_label(results_dir)
    for d in others:
        # named as the verdict table names them: a committed report holds no machine's paths
        there = _folder_label(d)
        warnings = compare_provenance(load_runs(results_dir), load_runs(d), names=(here, there))
        if warnings:
            lines += [f"Differences from `{there}`:", "", *[f"- {w}" for w in warnings], ""]
    return lines


def _pending(d: Path, runs: pd.DataFrame, profile: str | None, verdicts) -> list:
    """The verdicts of a folder of a selection's runs (``paper-core``), each replaced by
    ``pending (n of m runs)`` where fewer of its claim's runs are stored than the selection
    declares (a campaign under way)."""
    import dataclasses

    from .core._experiments import SELECTIONS
    from .studies.paper._replication import stored_counts

    if profile not in SELECTIONS or not len(runs):  # only a campaign's selection is pending
        return verdicts
    want = stored_counts(runs, profile)
    out = []
    for v in verdicts:
        n, m = want.get(v.claim, (0, 0))
        if m and n < m:
            v = dataclasses.replace(v, verdict=f"pending ({n} of {m} runs)", pending=(n, m))
        out.append(v)
    return out


def _load_other(d: Path):
    runs, curves, profile = load_tables(d)
    verdicts = judge(runs, curves, profile).final
    return d, profile, _pending(d, runs, profile, verdicts)


def figure_studies() -> list:
    """The registered studies that draw one figure from their experiment's rows, in order."""
    return [s for s in studies() if s.figure is not None]


def figure_stem(name: str) -> str:
    """The file stem of study ``name``'s figure (for the report's links)."""
    return next(s.stem for s in figure_studies() if s.name == name)


def make_figures(results_dir: Path) -> list[Path]:
    """Every study's figure from the stored runs; returns the files written.

    Runs that did not finish (``status != "ok"``) or have a non-finite error are left out of
    the plots (the report lists them). An experiment without runs draws nothing; one broken
    figure does not stop the others.
    """
    import matplotlib.pyplot as plt

    results_dir = Path(results_dir)
    runs, curves, profile = load_tables(results_dir)
    outdir = results_dir / "figures"
    written: list[Path] = []
    for study in figure_studies():
        rows = experiment_rows(runs, study.name, profile)
        if len(rows):
            rows = select(rows)
        if not len(rows):
            continue
        try:
            written += study.figure(rows, curves, outdir)
        except Exception as e:  # noqa: BLE001 - one broken figure must not stop the others
            plt.close("all")
            print(f"figure {study.name} failed: {type(e).__name__}: {e}")
    for study in studies():
        if study.results_figure is None:
            continue
        try:
            written += list(study.results_figure(results_dir) or [])
        except Exception as e:  # noqa: BLE001
            plt.close("all")
            print(f"figure {study.results_figure.__name__} failed: {type(e).__name__}: {e}")
    return written


def write_report(results_dir: Path, compare=None) -> Path:
    """Write ``results_dir/REPORT.md`` from the stored runs and return its path.

    ``compare``: other results folders whose verdicts are tabulated beside these (default:
    :func:`compare_folders`, the subfolders with stored runs); a folder that cannot be read is
    named in the report and skipped."""
    results_dir = Path(results_dir)
    results_dir.mkdir(parents=True, exist_ok=True)
    runs, curves, profile = load_tables(results_dir)
    j = judge(runs, curves, profile)
    # a campaign's folder states a verdict only where its claim's runs are all stored
    j.final = _pending(results_dir, runs, profile, j.final)
    verdicts = j.final
    others, other_errors = [], []
    for d in compare_folders(results_dir) if compare is None else [Path(c) for c in compare]:
        try:
            others.append(_load_other(d))
        except Exception as e:  # noqa: BLE001 - a broken folder must not lose the report
            other_errors.append(f"- could not read `{d}`: {_md_escape(str(e))[:200]}")
    n_failed = sum(v.n_failed for v in verdicts)
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
        "Verdict rules are in the docstrings of `bench/studies/paper/` (conventions: "
        "`bench/studies/paper/_stats.py`). Each claim is split into the parts its sentences "
        "state; each part is a one-sided t test on paired per-seed values (log ratios of "
        "rollout errors, energy violations, losses or training times; slopes; shares) against "
        "the margin of its quantity (*Margin policy* below). An ordering holds only beyond the "
        'margin; "no gain", "no better" and "matches" hold only when the data rule out the '
        "margin; a difference inside it is a tie. Holm's correction runs across a claim's parts, "
        "for holds and for contradicts alike (the level column). A comparison is judged only "
        "where each of its models learned (beat the best trivial predictor by the learning "
        "margin, geometric mean over seeds) and where the claim's stated condition holds "
        '("at similar loss": a *condition* part); otherwise the part reads *not tested* and '
        "cannot count against the claim. A claim is *reproduced* when every part holds, *partly "
        "reproduced* when some hold and others are contradicted, *not reproduced* when parts "
        "are contradicted and none holds, *inconclusive* otherwise, with fewer than 5 seeds, or "
        "when the experiment is not discriminating (its best model does not beat the best "
        f"trivial predictor by {TRIVIAL_FACTOR:g}x on every seed). Failed and diverged runs "
        "score the worst error, 1, and are counted.",
        "",
        "Replication: every claim is judged on the profile's seeds and again on a disjoint set. "
        "Where both read the same verdict, the final reading is the pooled seeds; where they "
        "differ, the claim is *inconclusive (does not replicate)*. *Leave one seed out* judges "
        "the final reading's seeds without each one in turn; it demotes a verdict to "
        "*inconclusive (changes without a seed)* only where dropping a seed reverses a part "
        "(holds <-> contradicts).",
        "",
        *_claims_table(j),
        "",
        *_not_run_note(profile),
        "### Every part: effect, margin, test, level, and its status on each seed set",
        "",
        *_parts_table(j),
        "",
        f"Failed or diverged runs scored as error 1 in the verdicts: {n_failed}.",
        "",
        *_policy_section(),
        *_dependence_section(margin_dependence(runs, curves, profile, j), j.final),
        *_comparison_section(verdicts, profile, others),
        *other_errors,
    ]
    figdir = results_dir / "figures"
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
        bad = rows[rows["status"] != "ok"] if "status" in rows else rows.iloc[0:0]
        ok = select(rows)
        lines.append(f"{_status_counts(rows)}; mean ± standard error over seeds.")
        lines.append("")
        if len(rows):
            lines += _experiment_table(ok) if len(ok) else []
            lines.append("")
            lines += _discrimination_lines(rows)
            lines.append("")
        lines += _missing_cells(rows, name, profile)
        bad = bad.assign(_label=_table_variant(bad)) if len(bad) else bad
        for _, r in bad.iterrows():
            err = r.get("error") or f"diverged at step {r.get('diverged_step')}"
            coords = " (q, p)" if r.get("coordinates") == "momentum" else ""
            how = (
                "not counted (a trivial predictor)"
                if r["model"] in TRIVIAL_MODELS
                else "scored as error 1"
            )
            lines.append(
                f"- {r['_label']}{coords} on {r['system']} seed {r['seed']}: {r['status']}, "
                f"{how} ({_md_escape(str(err))[:200]})"
            )
        if len(bad):
            lines.append("")
        stem = study.stem
        if (figdir / f"{stem}.png").exists():
            lines += [f"![{name}](figures/{stem}.png) ([PDF](figures/{stem}.pdf))", ""]
        elif not len(ok):
            lines += ["(no figure: no finished runs)", ""]
        else:
            lines += ["(figure not generated: run `python -m bench figures`)", ""]
    lines += _extra_sections(results_dir)
    lines += _provenance_section(results_dir, runs, [o[0] for o in others])
    lines += ["## What the suite does not copy from the reference", "", DEFECTS]
    path = results_dir / "REPORT.md"
    path.write_text("\n".join(lines))
    return path
