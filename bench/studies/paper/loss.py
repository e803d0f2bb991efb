"""Fig. 8 (loss and cost): the experiment, claim 6's verdict rule and the figure."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from ...core._experiments import Experiment, RunConfig
from ...core._query import (
    plain,
    select,
)
from ...core._studies import Study, register_study
from .._figure import save_figure
from ._common import (
    PAPER_MODELS,
    TRIVIAL_MODELS,
    _paper_cell,
    _shared,
    _trivial,
)
from ._plot import (
    MODEL_ORDER,
    _agg,
    _bars,
    _label,
    _order,
    _trivial_lines,
    split_trivial,
)
from ._rules import (
    CLAIM_TITLES,
    _models,
    _verdict,
    discrimination,
)
from ._stats import (
    MODEL_LABELS,
    Verdict,
    _boot,
    _n_bad,
    _Part,
    scored,
)


def _loss_include(c: RunConfig) -> bool:
    return _paper_cell(c) and (not _trivial(c.model) or c.loss == "l2")


LOSS = Experiment(
    name="loss",
    title="Fig. 8: L1 vs L2 training loss, every paper model on chain-2",
    axes={
        "system": ("chain_pendulum",),
        "k": (2,),
        "model": (*PAPER_MODELS, "constant_velocity"),
        "loss": ("l1", "l2"),
    },
    profile_overrides=_shared(),
    include=_loss_include,
    claim=6,
)


def claim_6(runs: pd.DataFrame, curves: pd.DataFrame | None = None) -> Verdict:
    """Claim 6 (Fig. 8): the four paper models on the chain pendulum trained with L1 and L2.

    For each loss and each pair of models the per-seed log error difference is bootstrapped; a
    pair is *resolved* under a loss when its CI excludes 0. Reproduced only when every pair
    resolved under one loss keeps its order under the other (its mean difference there is not
    of the opposite sign) and at least half the pairs are resolved under both; not reproduced
    when a pair is resolved in opposite directions under the two losses; inconclusive
    otherwise.
    Headline: Kendall's tau between the two rankings of mean log error (bootstrapped over seeds).
    """
    p = select(plain(runs), system="chain_pendulum", ok=False)
    p = p[p["model"].isin([*PAPER_MODELS, *TRIVIAL_MODELS])] if len(p) else p
    k = 2 if len(p) and 2 in set(p["k"].dropna()) else None
    if k is not None:
        p = p[p["k"] == k]
    m = _models(p)
    if not len(m) or set(m["loss"].unique()) < {"l1", "l2"}:
        return _verdict(6, CLAIM_TITLES[6], [], None, 0, "Kendall tau L1 vs L2 ranking")
    table = m.assign(le=np.log(scored(m))).pivot_table(
        index="seed", columns=["loss", "model"], values="le", aggfunc="mean"
    )
    models = [x for x in PAPER_MODELS if ("l1", x) in table and ("l2", x) in table]
    table = table[[(loss, x) for loss in ("l1", "l2") for x in models]].dropna()
    n = len(table)
    if n == 0 or len(models) < 2:
        return _verdict(6, CLAIM_TITLES[6], [], None, 0, "Kendall tau L1 vs L2 ranking")
    arr = table.to_numpy().reshape(n, 2, len(models))

    def tau(idx):
        # Kendall's tau-a: mean over model pairs of the product of the two orderings' signs.
        mm = arr[idx].mean(axis=0)
        iu = np.triu_indices(mm.shape[1], 1)
        s0 = np.sign(mm[0][:, None] - mm[0][None, :])[iu]
        s1 = np.sign(mm[1][:, None] - mm[1][None, :])[iu]
        return float(np.mean(s0 * s1))

    tp, tl, th = _boot(np.arange(n), tau)
    both, kept_one, reversed_, flipped, unresolved = [], [], [], [], []
    n_pairs = 0
    for i in range(len(models)):
        for j in range(i + 1, len(models)):
            n_pairs += 1
            signs, means = [], []
            for li in range(2):
                d = arr[:, li, i] - arr[:, li, j]
                _, lo, hi = _boot(d)
                means.append(np.sign(d.mean()))
                signs.append(0 if not np.isfinite(lo) or lo <= 0 <= hi else int(np.sign(lo)))
            name = f"{MODEL_LABELS[models[i]]}/{MODEL_LABELS[models[j]]}"
            if signs[0] and signs[1]:
                (both if signs[0] == signs[1] else reversed_).append(name)
            elif signs[0] or signs[1]:
                s = signs[0] or signs[1]
                other = means[1] if signs[0] else means[0]
                (flipped if other == -s else kept_one).append(name)
            else:
                unresolved.append(name)
    if reversed_:
        status = "contradicts"
    elif not flipped and len(both) >= n_pairs / 2 and n >= 2:
        status = "holds"
    else:
        status = "undecided"
    change = np.abs(arr[:, 0, :] - arr[:, 1, :]).mean()
    part = _Part(
        "ordering",
        status,
        tp,
        tl,
        th,
        n,
        f"resolved under both, same order: {', '.join(both) or '-'}; reversed: "
        f"{', '.join(reversed_) or '-'}; resolved under one, same sign under the other: "
        f"{', '.join(kept_one) or '-'}; resolved under one, opposite sign under the other: "
        f"{', '.join(flipped) or '-'}; unresolved: {', '.join(unresolved) or '-'}; "
        f"{len(both)}/{n_pairs} pairs resolved under both; "
        f"mean |log(err L1 / err L2)| = {change:.3g}",
    )
    return _verdict(
        6,
        CLAIM_TITLES[6],
        [part],
        part,
        n,
        "Kendall tau of L1 vs L2 rankings",
        discs=[discrimination(p, "chain_pendulum")],
        n_failed=_n_bad(m),
    )


def fig_loss(runs, curves, outdir: Path) -> list[Path]:
    """Fig. 8: rollout error per model with L1 and L2 training losses (mean +- sem)."""
    runs, trivial = split_trivial(runs)
    if not len(runs):
        return []
    ag = _agg(runs, ["model", "loss"], "rollout_error")
    fig, ax = plt.subplots(figsize=(7, 4))
    _trivial_lines(ax, trivial)
    _bars(
        ax,
        ag,
        _order(runs["model"], MODEL_ORDER),
        ["l1", "l2"],
        "model",
        "loss",
        lambda s: s.upper(),
        ylabel="rollout error",
    )
    ax.set_xticklabels([_label(m) for m in _order(runs["model"], MODEL_ORDER)])
    ax.set_title("L1 vs L2 loss, chain pendulum")
    return save_figure(fig, outdir, "fig8_loss")


STUDY = register_study(
    Study(
        name="loss",
        experiments=(LOSS,),
        claim=6,
        title=CLAIM_TITLES[6],
        rule=claim_6,
        reads=("energy", "second_order", "coordinates", "loss"),
        figure=fig_loss,
        stem="fig8_loss",
    )
)
