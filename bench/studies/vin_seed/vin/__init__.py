"""VIN (VIN paper): the experiment, claim 8's verdict rule and the figure."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from ....core import Experiment, RunConfig, Study, register_study, select
from ....kit import (
    BOUNDED_SLOPE,
    COLORS,
    TRIVIAL_MODELS,
    Verdict,
    at_most,
    below,
    curve_mean,
    curve_slopes,
    discrimination,
    foil,
    gated,
    greater,
    learned_cell,
    mark_failed,
    model_label,
    n_bad,
    non_trivial,
    paired,
    policy,
    save_figure,
    seed_stats,
    split_trivial,
    subplots,
    trivial_lines,
    undecided,
    verdict,
)
from ..._claims import CLAIM_TITLES, is_trivial

# Noisy data are at the smallest data size (n_train 8 at every profile), the VIN seed's
# "fewer and noisier" comparison.
VIN_NOISY_N_TRAIN = 8


def _vin_include(c: RunConfig) -> bool:
    if is_trivial(c.model):
        return c.model == "constant_velocity" and c.noise == 0.0 and c.n_train == VIN_NOISY_N_TRAIN
    if c.noise > 0:
        return c.model in ("vin", "resnet") and c.n_train == VIN_NOISY_N_TRAIN
    return True


VIN = Experiment(
    name="vin",
    paper="vin",
    title="VIN seed: pendulum from few and noisy trajectories, long horizon",
    axes={
        "model": ("vin", "resnet", "node_so", "constant_velocity"),
        "n_train": (8, 32, 128),
        "noise": (0.0, 0.01, 0.05),
    },
    # 60 chunks = 300 points (9 s at dt = 0.03): 3x the paper's horizon, the longest window of
    # the protocol's 10 s trajectories
    fixed={"system": "chain_pendulum", "k": 1, "test_chunks": 60},
    profile_overrides={
        "smoke": {
            "n_train": (8, 16),
            "test_chunks": 8,
            "model": ("vin", "resnet", "constant_velocity"),
        },
        # three data sizes at quick too: claim 8's "less data" is judged across them
        "quick": {"model": ("vin", "resnet", "constant_velocity")},
        "paper-core": {},  # every paper cell: 0.7 CPU hours
    },
    include=_vin_include,
    claim=8,
)


def claim_8(runs: pd.DataFrame, curves: pd.DataFrame | None = None) -> Verdict:
    """Claim 8 (VIN seed): VIN vs ResNet on the pendulum (chain, k = 1) over a long horizon.

    Parts on paired per-seed values, each judged where the VIN learned (gates by role: the
    ResNet is the claim's foil, whose failure on few or noisy data is the claim's content, so it
    is never gated; the test set is noise-free: every cell is gated against the same trivial
    predictor): (a)
    *greater* at the error margin, ``log(err ResNet / err VIN)`` at the smallest ``n_train``,
    one part per noise level (the noisy cells are the "noisier data" half); (b) *greater* at the
    energy margin, ``log(EV ResNet / EV VIN)`` at the same cells; (c) bounded energy: the
    per-seed slope of ``log EV`` vs ``log t`` over the second half of VIN's noise-free curves
    at the smallest ``n_train`` is below 0 + the slope margin (a bounded oscillation has slope
    ~0, a linear drift 1); (d) "less data", across the data sizes: for each pair of consecutive
    sizes ``n < m`` (noise 0), VIN trained on ``n`` matches or beats ResNet trained on ``m``,
    an *at most* part at the error margin on ``log(err VIN(n) / err ResNet(m))``. Headline:
    (a) at zero noise.
    """
    v = select(runs, ok=False, system="chain_pendulum", k=1, friction=0.0)
    v = v[v["model"].isin(["vin", "resnet", *TRIVIAL_MODELS])] if len(v) else v
    if not len(non_trivial(v)):
        return verdict(8, CLAIM_TITLES[8], [], None, 0, "log(err ResNet / err VIN), fewest data")
    n_min = non_trivial(v)["n_train"].min()
    at_min = v[v["n_train"] == n_min]
    trivial = v[v["model"].isin(TRIVIAL_MODELS)]
    parts, ns = [], []
    head = None
    err, energy = policy.margin("error"), policy.margin("energy")

    def gates(rows, label):
        # gates by role: the VIN is the model the claim expects to succeed; the ResNet is its
        # foil, whose failure (to learn from few or noisy data) is the claim's content, so it is
        # shown, never gated. The test set is noise-free whatever the training noise: the
        # trivial rows are shared.
        return [
            learned_cell(rows, {"model": "vin"}, f"vin {label}", trivial=trivial),
            foil(learned_cell(rows, {"model": "resnet"}, f"resnet {label}", trivial=trivial)),
        ]

    vin_gate = None
    for noise, g in non_trivial(at_min).groupby("noise"):
        a = paired(g, {"model": "resnet"}, {"model": "vin"})
        e = paired(g, {"model": "resnet"}, {"model": "vin"}, metric="energy_violation")
        both = gates(g, f"n_train={n_min} noise={noise:g}")
        vin_gate = both[0] if noise == 0 else vin_gate
        label = f"n_train={n_min} noise={noise:g}"
        pa = gated(greater(f"(a) {label}: log(err ResNet / VIN)", a.to_numpy(), err), *both)
        parts.append(pa)
        parts.append(
            gated(greater(f"(b) {label}: log(EV ResNet / VIN)", e.to_numpy(), energy), *both)
        )
        ns.append(len(a))
        if head is None:
            head = pa
    vin_runs = select(at_min, model="vin", noise=0.0)
    sl = curve_slopes(vin_runs, curves, t_min_frac=0.5)
    if len(sl):
        ps = sl.groupby("seed")["slope"].mean().to_numpy()
        c = below(
            "(c) VIN late slope of log EV vs log t", ps, BOUNDED_SLOPE, policy.margin("slope")
        )
        parts.append(gated(c, vin_gate) if vin_gate is not None else c)
    else:
        parts.append(undecided("(c) VIN late energy slope", "no curves"))
    clean = non_trivial(v)[non_trivial(v)["noise"] == 0.0]
    sizes = sorted(clean["n_train"].unique())
    for n, m in zip(sizes, sizes[1:], strict=False):
        vin_n, res_m = {"model": "vin", "n_train": n}, {"model": "resnet", "n_train": m}
        d = paired(clean, vin_n, res_m)
        name = f"(d) log(err VIN at n_train={n} / ResNet at n_train={m})"
        parts.append(
            gated(
                at_most(name, d.to_numpy(), err),
                learned_cell(clean, vin_n, f"vin n_train={n}", trivial=trivial),
            )
        )
    rows = (
        pd.concat([non_trivial(at_min), trivial]).drop_duplicates("config_hash")
        if "config_hash" in v
        else pd.concat([non_trivial(at_min), trivial])
    )
    return verdict(
        8,
        CLAIM_TITLES[8],
        parts,
        head,
        min(ns, default=0),
        "log(err ResNet / err VIN), fewest data",
        discs=[discrimination(rows, f"pendulum n_train={n_min}")],
        n_failed=n_bad(non_trivial(v)),
    )


def fig_vin(runs, curves, outdir: Path) -> list[Path]:
    """VIN seed. Left: rollout error vs number of training trajectories (log-log, dashed for
    noisy data). Right: relative error and energy violation vs time at the fewest data."""
    runs, trivial = split_trivial(runs)
    if not len(runs):
        return []
    fig, (a, b) = subplots(1, 2, figsize=(11, 4))
    trivial_lines(a, trivial)
    for (m, noise), g in runs.groupby(["model", "noise"]):
        ag = seed_stats(g, ["n_train"], "rollout_error").sort_values("n_train")
        a.errorbar(
            ag["n_train"],
            ag["mean"],
            yerr=ag["sem"].fillna(0),
            marker="o",
            capsize=3,
            color=COLORS.get(m),
            ls="-" if noise == 0 else "--",
            label=f"{model_label(m)}" + (f", noise {noise:g}" if noise else ""),
        )
        mark_failed(a, ag["n_train"], ag["mean"], ag["n_failed"])
    a.set(
        xscale="log",
        yscale="log",
        xlabel="training trajectories",
        ylabel="rollout error (long horizon)",
        title="Data efficiency, pendulum",
    )
    a.legend(fontsize=8)
    n_min = runs["n_train"].min()
    drawn = False
    for m, g in runs[(runs["n_train"] == n_min) & (runs["noise"] == 0)].groupby("model"):
        for col, ls in (("rel_error", "-"), ("energy_violation", ":")):
            t, v = curve_mean(curves, g["config_hash"], col)
            if len(t):
                drawn = True
                b.plot(
                    t,
                    v,
                    ls=ls,
                    color=COLORS.get(m),
                    label=f"{model_label(m)} {'error' if col == 'rel_error' else 'energy'}",
                )
    if drawn:
        b.set(yscale="log")
        b.legend(fontsize=7)
    b.set(
        xlabel="time (s)",
        ylabel="relative error / energy violation",
        title=f"Long horizon, n_train = {n_min}",
    )
    return save_figure(fig, outdir, "fig_vin")


STUDY = register_study(
    Study(
        name="vin",
        experiments=(VIN,),
        claim=8,
        title=CLAIM_TITLES[8],
        rule=claim_8,
        reads=("vin",),
        figure=fig_vin,
        stem="fig_vin",
    )
)
