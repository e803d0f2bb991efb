"""Fig. 5 in the paper's form: the error against the number of links k, per model, from the
stored runs of the ``paper`` profile's cells at every k (the claims at every k: the report's
section of ``bench.studies.paper.report``)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..._claims import LINKS
from ..._claims import LINKS_PROFILE as PROFILE

FIGURE_MODELS = ("node", "node_so", "node_so_pq", "hnn", "hnn_so")
# the paper's form of NODE+SO, drawn dashed beside ours
DASHED = ("node_so_pq",)
FIGURE_METRICS = {"rollout_error": "rollout error", "mse": "test MSE"}
# the models whose common seeds a k's points rest on (a campaign under way stores them in turn)
COMPARED = ("node", "node_so", "hnn", "hnn_so")


def common_seeds(rows: pd.DataFrame) -> pd.DataFrame:
    """``rows`` at each k on the seeds where every model of :data:`COMPARED` stored there has
    a row on every system, so that a k's points compare the models on one seed set (a seed
    that only some have reached, mid-campaign, waits); a k where they share none keeps all."""
    keep = []
    for _, g in rows.groupby("k"):
        have = g[g["model"].isin(COMPARED)]
        cells = have.groupby("seed")[["model", "system"]].apply(
            lambda x: len(set(zip(x["model"], x["system"], strict=True)))
        )
        full = cells[cells == len(set(zip(have["model"], have["system"], strict=True)))].index
        keep.append(g[g["seed"].isin(full)] if len(full) else g)
    return pd.concat(keep) if keep else rows


def link_rows(runs: pd.DataFrame) -> pd.DataFrame:
    """The paper's undamped cells of Figs. 4 and 5 at every stored k: the four models and the
    trivial predictors on the chain and on the spring from the paper's start, L2 loss, at the
    ``paper`` profile's cells; failed rows kept (they are scored)."""
    from ....core import experiment_rows, plain, select
    from ....kit import paper_spring

    if not len(runs):
        return runs
    rows = pd.concat(
        [experiment_rows(runs, e, PROFILE) for e in ("coordinates", "second_order")],
        ignore_index=True,
    ).drop_duplicates("config_hash")
    return paper_spring(select(plain(rows), ok=False, loss="l2"))


def fig_links(results_dir) -> list:
    """Fig. 5 in the paper's form: the error against the number of links k per model, the
    chain (angles) and the spring (Cartesian) side by side, the rollout error above and the
    test MSE (what the paper's plotting code draws) below; NODE+SO in the paper's form
    (``node_so_pq``) dashed beside ours. Geometric mean over the stored
    seeds with its 90% t interval, at each k on the seeds the compared models share
    (:func:`common_seeds`); failed and diverged runs enter at the worst error, as the
    verdicts score them, and are marked (x, with their count); a point resting on fewer seeds
    than its k's others (the paper's form) says how many. Nothing where the folder holds
    runs at one k only."""
    from pathlib import Path

    from scipy import stats

    from ....core import load_tables
    from ....kit import (
        COLORS,
        MODEL_LABELS,
        SYSTEM_LABELS,
        TRIVIAL_STYLE,
        bad_rows,
        save_figure,
        scored,
        seed_span,
        subplots,
    )

    runs, _, _ = load_tables(Path(results_dir))
    rows = link_rows(runs)
    if not len(rows) or rows["k"].dropna().nunique() < 2:
        return []
    rows = common_seeds(rows)
    systems = ("chain_pendulum", "spring_pendulum")
    metrics = [m for m in FIGURE_METRICS if m in rows]
    seeds_at = {int(k): g["seed"].nunique() for k, g in rows.groupby("k")}
    fig, axes = subplots(len(metrics), 2, figsize=(9, 3.8 * len(metrics)), squeeze=False)
    for i, metric in enumerate(metrics):
        for j, system in enumerate(systems):
            ax = axes[i][j]
            g = rows[rows["system"] == system]
            for model in (*FIGURE_MODELS, *TRIVIAL_STYLE):
                m = g[g["model"] == model]
                if not len(m):
                    continue
                logs = np.log(scored(m, metric).astype(float))
                bad = bad_rows(m, metric)
                pts = []
                for k, idx in m.groupby("k").groups.items():
                    x = logs.loc[idx].dropna().to_numpy()
                    if not len(x):
                        continue
                    mu = float(x.mean())
                    half = (
                        float(stats.t.ppf(0.95, len(x) - 1) * x.std(ddof=1) / np.sqrt(len(x)))
                        if len(x) > 1
                        else 0.0
                    )
                    pts.append((int(k), mu, half, int(bad.loc[idx].sum()), len(x)))
                if not pts:
                    continue
                ks, mu, half, nbad, n = (np.array(v) for v in zip(*pts, strict=True))
                label = MODEL_LABELS.get(model, model)
                if model in TRIVIAL_STYLE:
                    color, style = TRIVIAL_STYLE[model]
                    ax.plot(
                        ks, np.exp(mu), style, marker="_", markersize=14, color=color, label=label
                    )
                    continue
                ax.errorbar(
                    ks,
                    np.exp(mu),
                    yerr=[np.exp(mu) - np.exp(mu - half), np.exp(mu + half) - np.exp(mu)],
                    marker="o",
                    capsize=3,
                    linestyle="--" if model in DASHED else "-",
                    color=COLORS.get(model),
                    label=label,
                )
                for kk, y, nb, nn in zip(ks, np.exp(mu), nbad, n, strict=True):
                    notes = [f"{nb} failed"] if nb else []
                    if nn < seeds_at[kk]:
                        notes.append(f"{nn} seed" + ("s" if nn > 1 else ""))
                    if nb:
                        ax.plot([kk], [y], "x", color="black", markersize=9)
                    if notes:
                        ax.annotate(
                            ", ".join(notes),
                            (kk, y),
                            textcoords="offset points",
                            xytext=(4, -10) if model in DASHED else (4, 4),
                            fontsize=7,
                        )
            ax.set_yscale("log")
            ax.set_xticks(list(LINKS))
            ax.set_xlabel("number of links k")
            ax.set_ylabel(f"{FIGURE_METRICS[metric]} (geometric mean, 90% CI)")
            ax.set_title(
                SYSTEM_LABELS.get(system, system)
                + (" (angles)" if system == "chain_pendulum" else " (Cartesian)")
            )
            ax.grid(alpha=0.3)
    # one legend under the panels: inside one it covers the trivial predictor's line
    handles, labels = {}, []
    for ax in (a for row in axes for a in row):
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            if lab not in handles:
                handles[lab] = h
                labels.append(lab)
    fig.legend(
        [handles[lab] for lab in labels],
        labels,
        fontsize=7,
        loc="lower center",
        ncol=min(len(labels), 6),
        frameon=False,
    )
    per_k = "; ".join(
        f"k = {int(k)}: seeds {seed_span(sorted(int(s) for s in g['seed'].unique()))}"
        for k, g in rows.groupby("k")
    )
    fig.suptitle(f"Fig. 5 over k: NODE+SO vs HNN+SO by coordinates\n({per_k})", fontsize=10)
    fig.tight_layout(rect=(0, 0.04, 1, 0.95))
    return save_figure(fig, Path(results_dir) / "figures", "fig5_coordinates_links")
