"""What the paper-style figures share: labels, colours, bars, trivial-predictor lines, saving.

Each study module draws its own figure (``fig_<experiment>(runs, curves, outdir)``) from the
runs and curves of the chosen profile and returns the files it wrote. Every number drawn comes
from the tables: error bars are the standard error of the mean over seeds. Failed and diverged
runs reach the figures: an error is drawn as the verdicts score it (:func:`scored`: the worst
error) and the runs so scored are marked with their count (:func:`draw_bars`, :func:`mark_failed`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from ..core import aggregate, variant  # noqa: E402
from ._figure import save_figure, subplots  # noqa: E402
from ._models import MODEL_LABELS, TRIVIAL_MODELS  # noqa: E402
from ._seeds import bad_rows, scored  # noqa: E402

FAILED_LABEL = "with failed or diverged runs, scored at the worst error (count)"

SYSTEM_LABELS = {
    "chain_pendulum": "chain pendulum",
    "spring_pendulum": "spring pendulum",
    "relativistic_particle": "relativistic particle",
}
COLORS = {
    "node": "#1f77b4",
    "node_so": "#2ca02c",
    "node_so_pq": "#98df8a",  # NODE+SO as the Deconstructing paper's code builds it
    "hnn": "#d62728",
    "hnn_force": "#d62728",  # the HNN of the MuJoCo tasks (Fig. 7)
    "hnn_force_paper": "#ff9896",  # that HNN as the Deconstructing paper's code builds it
    "hnn_so": "#ff7f0e",
    "hnn_so_diss": "#9467bd",
    "node_symreg": "#17becf",
    "lnn": "#8c564b",
    "vin": "#e377c2",
    "vin_implicit": "#f7b6d2",
    "resnet": "#7f7f7f",
    "mixture_hnn": "#bcbd22",
    "node_so_symreg": "#17becf",
}
# Trivial predictors are drawn as reference lines, never as bars or points.
TRIVIAL_STYLE = {"constant_velocity": ("black", "--"), "at_rest": ("dimgray", ":")}


# ----------------------------------------------------------------------------- tables


def seed_stats(
    df: pd.DataFrame,
    by: Sequence[str],
    metric: str,
    *,
    score: bool = True,
    values: pd.Series | None = None,
) -> pd.DataFrame:
    """Per group of ``by``: n, mean, std and sem (the seed aggregation, without its bootstrap,
    which figures don't use) and ``n_failed``; NaN keys (k of the relativistic particle) group
    as "-". ``score``: every run counts, a failed or diverged one (or a non-finite value) at
    its score (``kit.scored`` over ``df``, or ``values`` where the caller scored them), and
    ``n_failed`` counts them; else (a cost, a parameter count) the finished runs' finite
    values, and ``n_failed`` is 0."""
    df = df.copy()
    for col in by:
        if df[col].isna().any():
            df[col] = df[col].astype(object).where(df[col].notna(), "-")
    if score:
        failed = bad_rows(df, metric) if len(df) else pd.Series(False, index=df.index)
        df[metric] = scored(df, metric) if values is None else values.to_numpy()
        df["_failed"] = failed.to_numpy(bool)
    else:
        if "status" in df:
            df = df[df["status"] == "ok"]
        df["_failed"] = False
    out = aggregate(df, by, metric, bootstrap=False)
    if not len(out):
        return out.assign(n_failed=pd.Series(dtype=int))
    counts = df.groupby(list(by), dropna=False)["_failed"].sum().rename("n_failed")
    return out.merge(counts.reset_index(), on=list(by), how="left")


def draw_bars(
    ax,
    agg: pd.DataFrame,
    groups: Sequence,
    members: Sequence,
    gcol: str,
    mcol: str,
    labels: Callable = str,
    log: bool = True,
    ylabel: str = "",
) -> None:
    """Grouped bars: one group per ``groups`` value, one bar per ``members`` value, sem bars; a
    bar whose mean takes in failed runs (``n_failed`` of :func:`seed_stats`) is hatched and carries
    their count."""
    width = 0.8 / max(1, len(members))
    hatched = False
    for j, m in enumerate(members):
        xs, ys, es, nf = [], [], [], []
        for i, g in enumerate(groups):
            row = agg[(agg[gcol] == g) & (agg[mcol] == m)]
            if not len(row):
                continue
            xs.append(i + (j - (len(members) - 1) / 2) * width)
            ys.append(row["mean"].iloc[0])
            es.append(0.0 if not np.isfinite(row["sem"].iloc[0]) else row["sem"].iloc[0])
            nf.append(int(row["n_failed"].iloc[0]) if "n_failed" in row else 0)
        if xs:
            ys, es = np.asarray(ys), np.asarray(es)
            lower = np.minimum(es, ys * 0.999) if log else es  # keep log bars positive
            bars = ax.bar(
                xs,
                ys,
                width,
                yerr=[lower, es],
                capsize=3,
                label=labels(m),
                color=COLORS.get(str(m)),
            )
            for bar, y, e, n in zip(bars, ys, es, nf, strict=True):
                if n:
                    bar.set_hatch("xx")
                    bar.set_edgecolor("black")
                    ax.annotate(
                        f"{n} failed",
                        (bar.get_x() + bar.get_width() / 2, y + e),
                        xytext=(0, 2),
                        textcoords="offset points",
                        ha="center",
                        fontsize=6,
                    )
                    hatched = True
    ax.set_xticks(range(len(groups)))
    ax.set_xticklabels([SYSTEM_LABELS.get(str(g), str(g)) for g in groups])
    if log:
        ax.set_yscale("log")
    ax.set_ylabel(ylabel)
    if hatched:  # an empty hatched area: the legend's entry, without data to rescale the axes
        ax.fill_between([], [], facecolor="none", edgecolor="black", hatch="xx", label=FAILED_LABEL)
    ax.legend(fontsize=8)


def mark_failed(ax, x, y, n_failed) -> None:
    """An 'x' and the count beside each point whose value takes in failed runs (``n_failed``
    of :func:`seed_stats`), with one legend entry."""
    first = True
    for xi, yi, n in zip(np.asarray(x), np.asarray(y), np.asarray(n_failed), strict=True):
        if n and np.isfinite(yi):
            ax.scatter([xi], [yi], marker="x", color="black", s=30, zorder=5,
                       label=FAILED_LABEL if first else None)  # fmt: skip
            ax.annotate(f"{int(n)}", (xi, yi), xytext=(4, 4), textcoords="offset points",
                        fontsize=6)  # fmt: skip
            first = False


def model_label(m) -> str:
    return MODEL_LABELS.get(str(m), str(m))


def in_order(values, preferred: Sequence) -> list:
    present = list(dict.fromkeys(values))
    return [p for p in preferred if p in present] + [p for p in present if p not in preferred]


MODEL_ORDER = (
    "node",
    "node_so",
    "hnn",
    "hnn_so",
    "hnn_so_diss",
    "mixture_hnn",
    "node_symreg",
    "node_so_symreg",
    "lnn",
    "vin",
    "resnet",
)
SYSTEM_ORDER = ("chain_pendulum", "spring_pendulum", "relativistic_particle")


def curve_mean(curves: pd.DataFrame, hashes, column: str) -> tuple[np.ndarray, np.ndarray]:
    """Geometric mean over runs of a per-time curve (t > 0): (t, value)."""
    c = curves[curves["config_hash"].isin(list(hashes)) & (curves["t"] > 0)]
    c = c[np.isfinite(c[column]) & (c[column] > 0)]
    if not len(c):
        return np.array([]), np.array([])
    g = c.groupby("t")[column].apply(lambda v: float(np.exp(np.mean(np.log(v)))))
    return g.index.to_numpy(float), g.to_numpy(float)


def split_trivial(runs: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame]:
    """(model rows, trivial-predictor rows)."""
    t = runs["model"].isin(TRIVIAL_MODELS) if len(runs) else pd.Series(dtype=bool)
    return runs[~t], runs[t]


def gmean(x) -> float:
    x = pd.to_numeric(pd.Series(x), errors="coerce").to_numpy(float)
    x = x[np.isfinite(x) & (x > 0)]
    return float(np.exp(np.mean(np.log(x)))) if len(x) else float("nan")


def trivial_lines(ax, trivial, metric="rollout_error", groups=None, gcol="system", vertical=False):
    """Each trivial predictor's geometric-mean ``metric`` as a reference line: one segment per
    bar group (``groups`` along x, by ``gcol``), or a full line (vertical with ``vertical``)."""
    if trivial is None or not len(trivial) or metric not in trivial:
        return
    for m, g in trivial.groupby("model"):
        color, ls = TRIVIAL_STYLE.get(m, ("black", "--"))
        label = MODEL_LABELS.get(m, m)
        if groups is None:
            v = gmean(g[metric])
            if np.isfinite(v):
                (ax.axvline if vertical else ax.axhline)(v, color=color, ls=ls, lw=1, label=label)
            continue
        for i, grp in enumerate(groups):
            v = gmean(g.loc[g[gcol] == grp, metric])
            if np.isfinite(v):
                ax.hlines(v, i - 0.45, i + 0.45, colors=color, linestyles=ls, lw=1.2, label=label)
                label = None


# ----------------------------------------------------------------------------- one per figure


def model_bar_values(runs: pd.DataFrame, metric: str = "rollout_error") -> pd.DataFrame:
    """What :func:`model_bars` draws: per system and model variant, the mean over runs of
    ``metric`` as the verdicts score it (failed and diverged runs at the worst error), its
    sem, ``n`` runs and ``n_failed`` of them scored so (trivial predictors left out)."""
    runs, _ = split_trivial(runs)
    if not len(runs):
        return seed_stats(
            runs.assign(variant=pd.Series(dtype=object)), ["system", "variant"], metric
        )
    return seed_stats(runs.assign(variant=variant(runs)), ["system", "variant"], metric)


def model_bars(
    runs,
    outdir: Path,
    stem: str,
    title: str,
    metric: str = "rollout_error",
    ylabel: str = "rollout error (geometric mean)",
) -> list[Path]:
    """One bar per system and model variant (:func:`model_bar_values`), the trivial
    predictors as lines."""
    models_, trivial = split_trivial(runs)
    if not len(models_):
        return []
    df = models_.assign(variant=variant(models_))
    fig, ax = subplots(figsize=(7, 4))
    groups = in_order(df["system"], SYSTEM_ORDER)
    trivial_lines(ax, trivial, metric, groups)
    draw_bars(
        ax,
        model_bar_values(runs, metric),
        groups,
        in_order(df["variant"], MODEL_ORDER),
        "system",
        "variant",
        model_label,
        ylabel=ylabel,
    )
    ax.set_title(title)
    return save_figure(fig, outdir, stem)
