"""The relativistic particle (LNN seed): claim 7's two experiments, its verdict rule, its
figures and the report's comparison of the two protocols.

Claim 7 is read twice. ``relativistic`` trains the three models the way the Deconstructing
paper trains every model (rollouts of 5-point chunks, RK4, L2, AdamW at 5e-3);
``relativistic_seed`` trains them the way the LNN seed did (the true time derivatives at random
states, L1, lr 1e-3, batch 32, softplus networks of four hidden layers). The seed's public code,
its data and where ours differs: docs/studies/relativistic.md. Both readings are judged by the
same parts under the same margin policy and fit gate; the claim's verdict (key ``7``) is the
seed's protocol's, the rollout-trained reading is ``7 (rollout loss)``.

``relativistic_seed`` follows the seed's notebooks as far as a declaration can; what differs,
and why: docs/studies/relativistic.md.

This module holds the figures and registers the two studies; the experiments, the verdict rule
and the report section are in ``_experiments``, ``_rule`` and
``_section``.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from ....core import Study, option, register_study
from ....kit import (
    draw_bars,
    model_label,
    save_figure,
    seed_stats,
    split_trivial,
    subplots,
    trivial_lines,
)
from ..._claims import CLAIM_TITLES
from ._experiments import (
    RELATIVISTIC,
    RELATIVISTIC_CELLS,
    RELATIVISTIC_EXTRAS,
    RELATIVISTIC_SEED,
    SEED_CELLS,
)
from ._rule import (
    ROLLOUT_VARIANT,
    claim_7,
    claim_7_ours,
    claim_7_seed,
    train_targets,
    velocity_scores,
)
from ._section import SECTION_TITLE, comparison_section


def _coord_label(df: pd.DataFrame) -> pd.Series:
    names = {"velocity": "(q, qdot)", "momentum": "(q, p)"}
    opts = {
        "momentum_map=False": "naive ",
        "momentum_map=True": "learned-map ",
    }
    mm = option(df, "momentum_map").map(lambda v: opts.get(f"momentum_map={v}", ""))
    kp = option(df, "kinetic_prior").map(lambda v: f" prior {v:g}" if v == v else "")
    return mm + df["model"].map(model_label) + kp + " " + df["coordinates"].map(names)


def _figure(stem: str, title: str):
    def fig(runs, curves, outdir: Path) -> list[Path]:
        """LNN seed: rollout error of HNN(q, qdot), HNN(q, p), LNN(q, qdot), and the first test
        trajectory's q(t), true vs predicted, of the lowest seed of each variant."""
        if not len(runs):
            return []

        scores, _ = velocity_scores(runs)
        runs = runs.assign(score=scores)
        runs, trivial = split_trivial(runs)
        if not len(runs):
            return []
        df = runs.assign(variant=_coord_label(runs))
        ag = seed_stats(df, ["system", "variant"], "rollout_error", values=df["score"])
        fig, (a, b) = subplots(1, 2, figsize=(11, 4))
        vs = list(dict.fromkeys(df["variant"]))
        trivial_lines(a, trivial, "score", ["relativistic_particle"])
        draw_bars(
            a,
            ag,
            ["relativistic_particle"],
            vs,
            "system",
            "variant",
            ylabel="rollout error on (q, qdot)",
        )
        a.set_title(title)
        true_drawn = False
        for v in vs:
            h = df[df["variant"] == v].sort_values("seed")["config_hash"].iloc[0]
            c = curves[curves["config_hash"] == h].sort_values("t") if len(curves) else curves
            if len(c) and "z_pred_0" in c:
                if not true_drawn and "z_true_0" in c:
                    b.plot(c["t"], c["z_true_0"], "k-", lw=2, label="truth")
                    true_drawn = True
                b.plot(c["t"], c["z_pred_0"], "--", label=v)
        b.set(xlabel="time (s)", ylabel="q", title="First test trajectory (lowest seed)")
        if true_drawn:
            b.legend(fontsize=8)
        return save_figure(fig, outdir, stem)

    fig.__name__ = stem
    return fig


fig_relativistic = _figure(
    "fig_relativistic", "Relativistic particle (every model scored on (q, qdot))"
)
fig_relativistic_seed = _figure(
    "fig_relativistic_seed", "The seed's protocol (derivative targets; scored on (q, qdot))"
)

STUDY = register_study(
    Study(
        name="relativistic",
        experiments=(RELATIVISTIC,),
        claim=7,
        title=CLAIM_TITLES[7],
        rule=claim_7,
        reads=("relativistic", "relativistic_seed"),
        figure=fig_relativistic,
        stem="fig_relativistic",
        section=comparison_section,
        section_title=SECTION_TITLE,
    )
)
# The seed's protocol: its runs' table and figure (the report's section after claim 7's); its
# rows are judged by claim 7's rule above (``reads``).
SEED_STUDY = register_study(
    Study(
        name="relativistic_seed",
        experiments=(RELATIVISTIC_SEED,),
        claim=7,
        title="Claim 7 on the LNN seed's protocol (judged by the relativistic study's rule)",
        figure=fig_relativistic_seed,
        stem="fig_relativistic_seed",
    )
)

__all__ = [
    "RELATIVISTIC",
    "RELATIVISTIC_CELLS",
    "RELATIVISTIC_EXTRAS",
    "RELATIVISTIC_SEED",
    "ROLLOUT_VARIANT",
    "SECTION_TITLE",
    "SEED_CELLS",
    "SEED_STUDY",
    "STUDY",
    "claim_7",
    "claim_7_ours",
    "claim_7_seed",
    "comparison_section",
    "fig_relativistic",
    "fig_relativistic_seed",
    "train_targets",
    "velocity_scores",
]
