"""Learning from pixels: the HNN seed's pixel pendulum (claim 11) and the VIN seed's pixel
forecasts (claim 12), their verdict rules, a table beside the seeds' numbers and a figure of
predicted frames against the truth.

An autoencoder maps two stacked 28 x 28 frames of the pendulum to a 2-number latent on which a
registered dynamics model (HNN, MLP field, VIN, ResNet) runs. Claim 11 is read twice: under our
protocol (``pixel_pendulum_hnn``) and under the HNN seed's (``pixel_pendulum_hnn_seed``: its
optimiser, latent step, initialisation and energy metric); the verdict is the seed's where it
has runs. The task, the models, the budgets, the seed's protocol read from its code, and why
quick's latent HNN does not learn the motion: docs/studies/pixels.md.

This module holds the figure and registers the two studies; the experiments, the verdict rules
and the report section are in ``_experiments``, ``_rule`` and ``_section``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ....core import Study, register_study
from ....kit import gmean, new_figure, save_figure
from ..._claims import CLAIM_TITLES
from . import _commands  # noqa: F401 - registers the diagnoses' verbs
from ._experiments import (
    ALL_EXPERIMENTS,
    EXPERIMENTS,
    LABELS,
    PIXEL_HNN,
    PIXEL_HNN_SEED,
    PIXEL_HNN_SEED_NO_AUX,
    PIXEL_VIN,
    SEED_ENERGY_MSE,
    SEED_PROTOCOL,
    SHORT,
    _rows,
)
from ._rule import claim_11, pixel_rows, reading, reading_ours, readings, seed_protocol
from ._section import section


def figure(results_dir) -> list[Path]:
    """Predicted frames against the truth (first test trajectory of the lowest seed, first
    frame of each observation at a few times) and pixel MSE against time per model."""

    rows, _, _ = _rows(Path(results_dir), EXPERIMENTS)
    rows = [
        r for r in rows if r.get("status") == "ok" and (r.get("curves") or {}).get("frames_pred")
    ]
    if not rows:
        return []
    order = {m: i for i, m in enumerate(("hnn", "node", "vin", "resnet"))}
    first = {}
    for r in sorted(rows, key=lambda r: (order.get(r["model"], 9), r["seed"])):
        first.setdefault(r["model"], r)
    picked = list(first.values())
    c0 = picked[0]["curves"]
    n = len(c0["frame_index"])
    fig = new_figure(figsize=(1.1 * n + 3.6, 1.1 * (len(picked) + 1) + 0.4))
    # n frame columns, a spacer, the curves
    grid = fig.add_gridspec(
        len(picked) + 1, n + 2, width_ratios=[1] * n + [0.3, 3.2], wspace=0.08, hspace=0.12
    )
    dt = c0["t"][1] - c0["t"][0] if len(c0["t"]) > 1 else 1.0
    panels = [("truth", c0["frames_true"])] + [
        (f"{SHORT[r['model']]} s{r['seed']}", r["curves"]["frames_pred"]) for r in picked
    ]
    for i, (label, frames) in enumerate(panels):
        for j in range(n):
            ax = fig.add_subplot(grid[i, j])
            ax.imshow(np.asarray(frames[j]), cmap="gray", vmin=0, vmax=1)
            ax.set_xticks([])
            ax.set_yticks([])
            if j == 0:  # one short horizontal label per row, left of its first frame
                ax.set_ylabel(label, fontsize=8, rotation=0, ha="right", va="center", labelpad=6)
            if i == 0:
                ax.set_title(f"t={c0['frame_index'][j] * dt:.1f}s", fontsize=7)
    ax = fig.add_subplot(grid[:, n + 1])
    ax.set_yscale("log")  # before the ticks move: a scale change resets them
    for r in rows:
        c = r["curves"]
        color = f"C{order.get(r['model'], 4)}"
        ax.plot(c["t"][1:], c["pixel_mse"][1:], color=color, lw=0.8, alpha=0.6)
    for m, i in order.items():
        if m in first:
            ax.plot([], [], color=f"C{i}", label=LABELS[m])
    static = [gmean([r["pixel_mse_static"]]) for r in rows]
    ax.axhline(np.nanmean(static), color="k", ls=":", lw=1, label="hold first frame")
    # ticks and their label on the right, clear of the frames on the left
    ax.yaxis.tick_right()
    ax.yaxis.set_label_position("right")
    ax.tick_params(axis="y", which="both", left=False, labelleft=False, right=True, labelright=True)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("pixel MSE (per seed)", rotation=270, va="bottom", labelpad=4)
    ax.legend(fontsize=6)
    fig.suptitle("Pixel pendulum: decoded latent rollouts against the true frames", fontsize=9)
    return save_figure(fig, Path(results_dir) / "figures", "fig_pixels")


STUDY_HNN = register_study(
    Study(
        name="pixel_pendulum_hnn",
        experiments=(PIXEL_HNN, PIXEL_HNN_SEED, PIXEL_HNN_SEED_NO_AUX),
        claim=11,
        title=CLAIM_TITLES[11],
        rule=claim_11,
        stem="fig_pixels",
        results_figure=figure,
        section=section,
        section_title="Learning from pixels (claims 11 and 12)",
    )
)
STUDY_VIN = register_study(
    Study(
        name="pixel_pendulum_vin",
        experiments=(PIXEL_VIN,),
        claim=12,
        title=CLAIM_TITLES[12],
        # ours alone; bench.studies.vin_seed.vin_blog registers it again with the seed's
        # protocol's experiment and the rule over both readings (vin_blog.claim_12)
        rule=reading_ours,
    )
)

__all__ = [
    "ALL_EXPERIMENTS",
    "EXPERIMENTS",
    "PIXEL_HNN",
    "PIXEL_HNN_SEED",
    "PIXEL_HNN_SEED_NO_AUX",
    "PIXEL_VIN",
    "SEED_ENERGY_MSE",
    "SEED_PROTOCOL",
    "STUDY_HNN",
    "STUDY_VIN",
    "claim_11",
    "figure",
    "pixel_rows",
    "reading",
    "reading_ours",
    "readings",
    "section",
    "seed_protocol",
]
