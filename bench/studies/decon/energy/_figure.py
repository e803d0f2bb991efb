"""Fig. 2 (energy): what the report says about it, drawn. Left: energy violation vs rollout
error, one point per run of the Fig. 2 cells, failed and diverged runs where claim 1 scores them
(the worst error, marked), with claim 1 (c)'s own line: the Theil-Sen slope over the Fig. 2
models' runs (:func:`._cells.proportionality`, the rule's function) and its 90% interval.
Right: energy violation vs time (geometric mean over runs) per model, from the curves."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from ....kit import (
    COLORS,
    MODEL_LABELS,
    MODEL_ORDER,
    SYSTEM_LABELS,
    TRIVIAL_MODELS,
    TRIVIAL_STYLE,
    bad_rows,
    curve_mean,
    gmean,
    in_order,
    model_label,
    required_seeds,
    save_figure,
    seed_sets,
    seed_span,
    subplots,
)

MARKERS = {"chain_pendulum": "o", "spring_pendulum": "s"}


def _seed_sets(runs: pd.DataFrame) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """(the seeds of the report's reading, the replication seeds) of ``runs``, as the
    replication judge takes them: the profile's declared seeds where they are enough for a
    verdict, else every stored seed outside the replication set."""
    labels = runs["profile"].dropna() if "profile" in runs else pd.Series(dtype=object)
    profile = str(labels.mode().iloc[0]) if len(labels) else None
    declared, rep = seed_sets(profile)
    stored = sorted(int(s) for s in runs["seed"].unique()) if len(runs) else []
    if len(declared) >= required_seeds():
        return tuple(declared), tuple(rep)
    return tuple(s for s in stored if s not in rep), tuple(rep)


def _report_seeds(runs: pd.DataFrame, curves) -> tuple[int, ...] | None:
    """The seeds the report reads claim 1 on (:func:`bench.kit.judge`: the profile's
    seeds, or both sets pooled where they agree); None where it cannot be judged."""
    from ....kit import judge

    labels = runs["profile"].dropna() if "profile" in runs else pd.Series(dtype=object)
    profile = str(labels.mode().iloc[0]) if len(labels) else None
    try:
        j = judge(runs, curves, profile, loso=False, claims=[1])
        return next(j.reading_seeds(v.key) for v in j.final if v.claim == 1)
    except Exception:  # noqa: BLE001 - the figure then reads the profile's own seeds
        return None


def fig2_line(runs: pd.DataFrame, curves: pd.DataFrame | None = None) -> dict | None:
    """Claim 1 (c)'s line as the report reads it, from the Fig. 2 cells of ``runs``:
    ``slope``, ``lo``, ``hi`` (the rule's Theil-Sen slope and its 90% interval,
    :func:`._cells.proportionality`) over the Fig. 2 models' scored runs of the reading's
    ``seeds``: the profile's seeds, or (with ``curves``) those the report reads claim 1 on,
    both seed sets pooled where they agree (:func:`_report_seeds`); ``intercept`` (median
    of log EV minus slope times the median of log error, for drawing); ``fitted``, the rows it
    fits; ``sets``, each seed set's (slope, lo, hi, seeds) where the replication seeds are
    stored, else (). None without two runs to fit."""
    from ._cells import FIG2_HNNS, FIG2_NODES, proportionality, scored_cells

    cells = scored_cells(runs)
    models = cells[cells["model"].isin([*FIG2_NODES, *FIG2_HNNS])]
    if len(models) < 2:
        return None
    seeds, rep = _seed_sets(models)
    sets = ()
    if len(models[models["seed"].isin(rep)]) >= 2:
        sets = tuple(
            (*proportionality(models[models["seed"].isin(s)])[:3], tuple(s)) for s in (seeds, rep)
        )
        judged = _report_seeds(runs, curves) if curves is not None else None
        seeds = judged or seeds
    fit = models[models["seed"].isin(seeds)]
    if len(fit) < 2:
        return None
    slope, lo, hi, n = proportionality(fit)
    if not np.isfinite(slope):
        return None
    x, y = np.log(fit["_err"].to_numpy(float)), np.log(fit["_ev"].to_numpy(float))
    return {
        "slope": slope,
        "lo": lo,
        "hi": hi,
        "n": n,
        "intercept": float(np.median(y) - slope * np.median(x)),
        "seeds": tuple(sorted(int(s) for s in fit["seed"].unique())),
        "fitted": fit,
        "sets": sets,
    }


def _line_label(line: dict) -> str:
    def reading(slope, lo, hi) -> str:
        ci = f" [{lo:.3g}, {hi:.3g}]" if np.isfinite(lo) and np.isfinite(hi) else ""
        return f"{slope:.3g}{ci}"

    pooled = " pooled" if line["sets"] and len(line["seeds"]) > len(line["sets"][0][3]) else ""
    slope = reading(line["slope"], line["lo"], line["hi"])
    text = (
        "claim 1 (c): Theil-Sen over HNN+SO, NODE, NODE+SO,\n"
        f"seeds {seed_span(line['seeds'])}{pooled}: slope {slope}"
    )
    others = [
        f"{seed_span(sd)}: {reading(s, lo, hi)}"
        for s, lo, hi, sd in line["sets"]
        if tuple(sd) != tuple(line["seeds"])
    ]
    return text + (f" (seeds {'; '.join(others)})" if others else "")


def _scatter(a, cells: pd.DataFrame, fig2_models) -> int:
    """One point per run at its scored error and violation; failed runs as 'x'. Returns how
    many failed runs are drawn."""
    failed = bad_rows(cells, "rollout_error") | bad_rows(cells, "energy_violation")
    for m in in_order(cells["model"], MODEL_ORDER):
        fitted = "" if m in fig2_models else " (not in the fit)"
        for s, g in cells[cells["model"] == m].groupby("system"):
            bad = failed.loc[g.index]
            a.scatter(
                g.loc[~bad, "_err"],
                g.loc[~bad, "_ev"],
                color=COLORS.get(m),
                marker=MARKERS.get(s, "^"),
                s=22,
                alpha=0.8,
                label=f"{model_label(m)}, {SYSTEM_LABELS.get(s, s)}{fitted}",
            )
            if bad.any():
                a.scatter(
                    g.loc[bad, "_err"], g.loc[bad, "_ev"], color=COLORS.get(m), marker="x", s=40
                )
    n_failed = int(failed.sum())
    if n_failed:  # one legend entry for every failed run, with the count
        label = f"failed or diverged, at the worst score ({n_failed} runs)"
        a.scatter([], [], color="black", marker="x", label=label)
    return n_failed


def fig_energy(runs, curves, outdir: Path) -> list[Path]:
    """Fig. 2 from the Fig. 2 cells (claim 1's: undamped chain and the paper's spring, L2):
    left, energy violation vs rollout error with claim 1 (c)'s Theil-Sen line
    (:func:`fig2_line`), every run at its scored values (failed ones as 'x'), the runs outside
    the fit named in the legend; right, energy violation vs time per model."""
    from ._cells import FIG2_HNNS, FIG2_NODES, energy_cells, scored_cells

    cells = scored_cells(runs)
    if not len(cells):
        return []
    trivial = energy_cells(runs)
    trivial = trivial[trivial["model"].isin(TRIVIAL_MODELS)]
    fig, (a, b) = subplots(1, 2, figsize=(11, 5.2))
    for s, g in trivial.groupby("system"):  # the trivial predictors' error: vertical lines
        for m, gm in g.groupby("model"):
            color, _ = TRIVIAL_STYLE.get(m, ("black", "--"))
            a.axvline(
                gmean(gm["rollout_error"]),
                color=color,
                ls="--" if s == "chain_pendulum" else ":",
                lw=1,
                label=f"{MODEL_LABELS.get(m, m)}, {SYSTEM_LABELS.get(s, s)}",
            )
    _scatter(a, cells, (*FIG2_NODES, *FIG2_HNNS))
    line = fig2_line(runs, curves)
    if line is not None:
        x = np.log(line["fitted"]["_err"].to_numpy(float))
        xs = np.linspace(x.min(), x.max(), 20)
        a.plot(
            np.exp(xs),
            np.exp(line["slope"] * xs + line["intercept"]),
            "k--",
            lw=1,
            label=_line_label(line),
        )
    a.set(
        xscale="log",
        yscale="log",
        xlabel="rollout error (geometric mean; failed runs at the worst)",
        ylabel="energy violation",
        title="Energy violation vs rollout error",
    )
    a.legend(fontsize=6, ncol=2, loc="upper center", bbox_to_anchor=(0.5, -0.16))
    drawn = False
    for m in in_order(cells["model"], MODEL_ORDER):
        for s, g in cells[cells["model"] == m].groupby("system"):
            t, v = curve_mean(curves, g["config_hash"], "energy_violation")
            if len(t):
                drawn = True
                b.plot(
                    t,
                    v,
                    color=COLORS.get(m),
                    ls="-" if s == "chain_pendulum" else ":",
                    label=f"{model_label(m)}, {SYSTEM_LABELS.get(s, s)}",
                )
    if drawn:
        b.set(xscale="log", yscale="log")
        b.legend(fontsize=6, ncol=2)
    b.set(xlabel="time (s)", ylabel="energy violation", title="Energy violation over time")
    return save_figure(fig, outdir, "fig2_energy")
