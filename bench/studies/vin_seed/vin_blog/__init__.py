"""The VIN seed's pixel pendulum as its blog and its authors' code run it (claim 12's second
reading): the experiment, the reading's rule, the claim's rule over both readings, a table with
the two protocols side by side, and a figure of the learned embeddings beside the truth.

The blog (the VIN blog) shows "example embedded representations of an ideal pendulum
system": the baselines, (a) a VAE, (b) a dynamic VAE and (c) a Lie group VAE, "fail to capture
the global structure (a)-(b) and/or are discontinuous with respect to the time dimension (c)";
"the VIN-SO(2) (d) learns an embedding that is consistent with the ground truth (f)". Its
evidence is the structure of the embedding; forecasts in pixels are the secondary evidence
(its first figure: a ResNet's forecasts of a 2-D latent going astray). The protocol, ours
beside it, and what the suite cannot copy: docs/studies/vin_blog.md.

This module holds the report's table and figure and registers the study; the experiment and
the rule are in ``_experiments`` and ``_rule``.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pandas as pd

from ....core import (
    Study,
    experiment_rows,
    load_runs,
    pick_profile,
    read_rows,
    register_study,
)
from ....kit import Protocol, by_seed_set, cell_rows, policy, protocol_table, save_figure, subplots
from ..._claims import CLAIM_TITLES
from ...hnn_seed import pixels
from ._experiments import (
    CELLS,
    EXPERIMENTS,
    LABELS,
    SEED_LR,
    SEED_STEPS,
    SHORT,
    VIN_BLOG,
    _cell,
)
from ._rule import _blog_rows, claim_12, defect_per_seed, reading

__all__ = [
    "CELLS",
    "EXPERIMENTS",
    "SEED_LR",
    "SEED_STEPS",
    "STUDY",
    "STUDY_VIN",
    "VIN_BLOG",
    "claim_12",
    "defect_per_seed",
    "figure",
    "reading",
    "section",
]


# ------------------------------------------------------------------- table and figure
def _rows(results_dir) -> tuple[pd.DataFrame, pd.DataFrame, str | None]:
    """(the blog reading's rows, ours (pixel_pendulum_vin), profile) of a results folder."""
    runs = load_runs(results_dir)
    if not len(runs):
        return runs, runs, None
    profile = pick_profile(runs, results_dir)
    if profile is not None:
        runs = runs[runs["profile"] == profile].reset_index(drop=True)
    blog = _blog_rows(experiment_rows(runs, VIN_BLOG.name, profile))
    ours = pixels.pixel_rows(
        experiment_rows(runs, pixels.PIXEL_VIN.name, profile), ("vin", "resnet")
    )
    return blog, ours, profile


def _f(x) -> str:
    return "-" if not np.isfinite(x) else f"{x:.3g}"


def _mean(x) -> float:
    x = pd.to_numeric(pd.Series(x), errors="coerce").to_numpy(float)
    x = x[np.isfinite(x)]
    return float(np.mean(x)) if len(x) else math.nan


def _protocols(blog: pd.DataFrame, ours: pd.DataFrame, profile, runs) -> list[str]:
    """The two readings side by side (:func:`kit.protocol_table`), their stored runs counted in
    ``runs`` (the folder's rows)."""

    def steps(rows):
        return ", ".join(str(int(x)) for x in sorted(set(rows["steps"]))) if len(rows) else "-"

    table = [
        (
            "data",
            "the suite's pendulum (H = 3 (1 - cos q) + p^2), abs(q0) < pi/6, qdot0 ~ U(-1, 1); "
            "dt 0.08 s; frames 28 x 28",
            "the seed's pendulum (m = l = 1, g = 9.82), abs(q0) in [pi/2, pi - 0.1] either sign, "
            "qdot0 ~ U(-1, 1); dt 0.1 s; 3 training trajectories of 50 frames; frames 28 x 28",
        ),
        (
            "latent",
            "two stacked frames -> (w, dw), decoded both; a VIN and a ResNet on it",
            "each frame -> a position (a Gaussian posterior), the integrator carries the "
            "velocity, positions decoded; VIN on SO(2), ResNet on the plane, two static VAEs",
        ),
        (
            "targets",
            "the window's observations (2 of them)",
            "the window's 11 frames, decoded from the rollout from the first two positions",
        ),
        (
            "loss",
            "pixel L2 + the HNN seed's forward-difference latent loss + 0.1 latent dynamics",
            "the seed's negative ELBO: Bernoulli likelihood of every frame + KL (steps of the "
            "positions against N(0, h^2))",
        ),
        (
            "optimiser",
            "AdamW, cosine decay, clipping, weight decay 1e-5",
            "Adam, constant rate (the seed's 3e-4 x its steps / ours), no weight decay",
        ),
        ("steps", steps(ours), f"{steps(blog)} (the seed: {SEED_STEPS} full batches)"),
        (
            "metric",
            "pixel MSE of decoded rollouts (whole horizon, last third)",
            "the embedding's defect against the true circle (bench.core._embedding); pixel MSE "
            "of 10 s forecasts from two frames",
        ),
    ]
    ours_p = Protocol(
        {row: a for row, a, _ in table},
        by_seed_set(ours, profile, pixels.reading_ours, pixels.PIXEL_VIN.name, runs),
    )
    blog_p = Protocol(
        {row: b for row, _, b in table}, by_seed_set(blog, profile, reading, VIN_BLOG.name, runs)
    )
    differs = (
        "no VIN-SO(2)* (true mass matrix) or VIN-VV; the ResNet's first state encoded from "
        "two frames (the seed: an LSTM); grey frames, not binarised thick rods; the loss over "
        "11 frames (the seed: 10); fewer steps than the seed's (the rate raised by as much)"
    )
    return [
        "",
        "The claim's verdict is the seed's protocol's (`pixel_pendulum_vin_blog`) where it has "
        "runs; ours is `pixel_pendulum_vin`.",
        *protocol_table(ours_p, blog_p, differs),
    ]


def section(results_dir) -> str:
    """The blog reading's models side by side, and the two protocols."""
    blog, ours, profile = _rows(Path(results_dir))
    lines = [
        "## VIN seed: the pixel pendulum as its blog ran it (claim 12)",
        "",
        "Single 28 x 28 frames of the seed's pendulum, each encoded to a position; the VIN-SO(2) "
        "and the dynamic VAE forecast from the first two frames, the VAEs have no dynamics "
        f"(profile {profile or '-'}; means over seeds). Embedding defect: max(1 - "
        "trustworthiness, jumps) of the encoder's embedding of the test frames against the "
        "true circle (`bench.core._embedding`; consistent below "
        f"{policy.margin('embedding').label()}). Recon: the test frames through the "
        "autoencoder (mean frame: the trivial one). Pixel MSE: 10 s forecasts from two frames "
        "(static: holding the second). Protocol: `bench/studies/vin_seed/vin_blog/`, "
        "docs/studies/vin_blog.md.",
        "",
        "| model | seeds | failed | embedding defect | trustworthiness | jumps | recon MSE | "
        "mean-frame MSE | pixel MSE | late pixel MSE | static |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    if not len(blog):
        lines.append("| (no runs) | | | | | | | | | | |")
    for name in CELLS:
        g = cell_rows(blog, _cell(name)) if len(blog) else blog
        if not len(g):
            continue
        ok = g[g["status"] == "ok"]
        cells = [
            _mean(ok.get(c, []))
            for c in (
                "embedding_defect",
                "embedding_trust",
                "embedding_jumps",
                "recon_mse",
                "frame_mse_mean",
                "pixel_mse",
                "pixel_mse_late",
                "pixel_mse_static",
            )
        ]
        dyn = CELLS[name][0] != "at_rest"
        shown = [_f(x) if (dyn or i < 5) else "-" for i, x in enumerate(cells)]
        lines.append(
            f"| {LABELS[name]} | {g['seed'].nunique()} | {len(g) - len(ok)} | "
            + " | ".join(shown)
            + " |"
        )
    return "\n".join([*lines, *_protocols(blog, ours, profile, load_runs(results_dir))])


def figure(results_dir) -> list[Path]:
    """The embeddings of the test frames, as the blog draws them: per model (lowest seed) the
    encoder's embedding of the first test trajectories, coloured by the true angle, grey lines
    joining consecutive frames; the truth (the bob on the unit circle) last."""
    blog, _, _ = _rows(Path(results_dir))
    if not len(blog):
        return []
    hashes = set(blog["config_hash"])
    rows = [
        r
        for r in read_rows(Path(results_dir))
        if r.get("config_hash") in hashes
        and r.get("status") == "ok"
        and (r.get("curves") or {}).get("embedding")
    ]
    if not rows:
        return []
    first: dict[str, dict] = {}
    for r in sorted(rows, key=lambda r: r["seed"]):
        latent = dict((str(a), b) for a, b in (r.get("model_options") or [])).get("latent")
        name = next((n for n, v in CELLS.items() if v == (r["model"], latent)), None)
        if name is not None:
            first.setdefault(name, r)
    names = [n for n in CELLS if n in first]
    fig, axes = subplots(1, len(names) + 1, figsize=(2.4 * (len(names) + 1), 2.6))
    axes = np.atleast_1d(axes)
    truth = None
    for ax, name in zip(axes, names, strict=False):
        r = first[name]
        e = np.asarray(r["curves"]["embedding"], dtype=float)  # (n, T, D)
        a = np.asarray(r["curves"]["angles"], dtype=float)
        truth = a
        for tr, ang in zip(e, a, strict=True):
            ax.plot(tr[:, 0], tr[:, 1], color="0.7", lw=0.5, zorder=1)
            ax.scatter(tr[:, 0], tr[:, 1], c=np.cos(ang), cmap="viridis", s=4, zorder=2)
        ax.set_title(
            f"{SHORT[name]} s{r['seed']}\ndefect {_f(float(r.get('embedding_defect', np.nan)))}",
            fontsize=8,
        )
        ax.set_xticks([])
        ax.set_yticks([])
    ax = axes[len(names)]
    if truth is not None:
        for ang in truth:
            x, y = np.sin(ang), -np.cos(ang)
            ax.plot(x, y, color="0.7", lw=0.5, zorder=1)
            ax.scatter(x, y, c=np.cos(ang), cmap="viridis", s=4, zorder=2)
    ax.set_title("ground truth\n(bob on the circle)", fontsize=8)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    fig.suptitle(
        "VIN seed, pixel pendulum: embeddings of test frames (colour: cos of the true angle; "
        "grey: consecutive frames)",
        fontsize=9,
    )
    fig.tight_layout()
    return save_figure(fig, Path(results_dir) / "figures", "fig_vin_blog")


STUDY = register_study(
    Study(
        name="vin_blog",
        experiments=EXPERIMENTS,
        claim=12,
        title=CLAIM_TITLES[12],
        stem="fig_vin_blog",
        results_figure=figure,
        section=section,
        section_title="VIN seed: the pixel pendulum as its blog ran it (claim 12)",
    )
)
# Claim 12's rule reads both readings: its study (pixels.STUDY_VIN) gets this experiment too
# (re-registering by name keeps its place in the report's order).
STUDY_VIN = register_study(
    dataclasses.replace(
        pixels.STUDY_VIN,
        experiments=(pixels.PIXEL_VIN, VIN_BLOG),
        title=CLAIM_TITLES[12],
        rule=claim_12,
    )
)
