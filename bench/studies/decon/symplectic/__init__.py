"""Fig. 3 (symplectic regularisation): the experiment, claim 2's verdict rule and the figure."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from ....core import Experiment, RunConfig, Study, option, register_study, select
from ....kit import (
    ALPHA,
    INCONCLUSIVE,
    MODEL_LABELS,
    PARTLY,
    SYSTEM_LABELS,
    TRIVIAL_MODELS,
    Part,
    Verdict,
    at_most,
    bad_rows,
    gated,
    learned,
    mark_failed,
    model_label,
    n_bad,
    paper_spring,
    per_system_discrimination,
    policy,
    save_figure,
    scored,
    seed_stats,
    split_trivial,
    subplots,
    t_bounds_jackknife,
    trivial_lines,
    trivial_log,
    verdict,
)
from ..._claims import (
    CLAIM_TITLES,
    SPRING_PAPER,
    SYMREG_WEIGHTS,
    SYMREG_WEIGHTS_CORE,
    SYMREG_WEIGHTS_QUICK,
    SYSTEMS,
    initial_ok,
    is_trivial,
)


def _symplectic_include(c: RunConfig) -> bool:
    if is_trivial(c.model):
        return c.model == "constant_velocity" and c.model_options == () and initial_ok(c)
    return c.model_options != () and initial_ok(c)


# Claim 2. The penalty ||(J DF)^T - J DF||^2 is only zero for the true field in canonical
# coordinates: the true chain-2 field's penalty is ~1e-29 in (q, p) and 30-180 in (q, qdot), so
# the regulariser is put on models of (q, p) states (coordinates="momentum"). The reference's
# regularised model is NODE+SO in (q, p) with a learned mass matrix (node_so_symreg); the plain
# NODE + penalty on (q, p) (node_symreg) is the simpler row, at the paper profile only (budget).
SYMPLECTIC = Experiment(
    name="symplectic",
    title="Fig. 3: symplectic regulariser weight on NODE+SO in canonical (q, p)",
    axes={
        "system": ("chain_pendulum",),
        "k": (2,),
        "model": ("node_so_symreg", "constant_velocity"),
        "model_options": ((), *((("weight", w),) for w in SYMREG_WEIGHTS_QUICK)),
        "system_params": ((), SPRING_PAPER),
    },
    fixed={"coordinates": "momentum"},
    profile_overrides={
        "smoke": {"model_options": ((), (("weight", 0.0),), (("weight", 1.0),))},
        "paper": {
            "system": SYSTEMS,
            "model": ("node_so_symreg", "node_symreg", "constant_velocity"),
            "model_options": ((), *((("weight", w),) for w in SYMREG_WEIGHTS)),
        },
        # paper-core: five weights 0, 1e-6, 1e-3, 1, 1e3 spanning the paper's grid, at the
        # paper budget; the chain's NODE+SO in (q, p) is the verdict's reading, the spring and
        # the plain regularised NODE a further one (``supplementary``)
        "paper-core": {
            "model": ("node_so_symreg", "node_symreg", "constant_velocity"),
            "model_options": ((), *((("weight", w),) for w in SYMREG_WEIGHTS_CORE)),
        },
        # paper-k: the same cells at k = 3, 4, where Fig. 3 (right) states its negative
        # correlation ("systems with more than a couple degrees of freedom")
        "paper-k": {
            "system": ("chain_pendulum",),
            "k": (3, 4),
            "model": ("node_so_symreg", "constant_velocity"),
            "model_options": ((), *((("weight", w),) for w in SYMREG_WEIGHTS_CORE)),
        },
    },
    include=_symplectic_include,
    claim=2,
    supplementary=lambda c: c.system != "chain_pendulum" or c.model == "node_symreg",
    # Not at quick (the make bench budget): quick's claim-2 verdict did not replicate
    # (inconclusive on seeds 0-4, reproduced on 5-9, changed without seed 2), and its 20 runs
    # were 488 s of run time (~4 min of make bench) that the pixel tasks and claim 9 need; the
    # paper-core campaign runs claim 2 at five weights.
    profiles=("smoke", "paper", "paper-core", "paper-k"),
)


SYMREG_MODELS = ("node_so_symreg", "node_symreg")


def _k(k) -> str:
    return "-" if k is None or (isinstance(k, float) and math.isnan(k)) else str(int(k))


# A perfect ranking is read as |rho| = 0.999 (Fisher z 3.8), so that it has a finite z.
_RHO_CAP = 0.999
# The large-sample variance of Fisher's z of Spearman's rho is 1.06 / (n - 3) (Fieller,
# Hartley and Pearson 1957): the interval that treats every run as an independent draw.
_SPEARMAN_Z_VAR = 1.06


def _spearman_z(x: np.ndarray, y: np.ndarray) -> float:
    """Fisher's z = atanh(rho) of Spearman's rho between ``x`` and ``y``; NaN with fewer than
    three points or a constant variable."""
    if len(x) < 3 or np.ptp(x) == 0 or np.ptp(y) == 0:
        return math.nan
    rho = float(stats.spearmanr(x, y).statistic)
    return math.atanh(min(max(rho, -_RHO_CAP), _RHO_CAP))


def rank_correlation(runs: pd.DataFrame, x: str, y: str) -> tuple[float, float, float, int]:
    """(z, lo, hi, n seeds): Spearman's rho between columns ``x`` and ``y`` over every row of
    ``runs`` (pooled over weights and seeds, as Fig. 3 right pools them), as Fisher's
    z = atanh(rho), with one-sided (1 - alpha) t bounds from the leave-one-seed-out jackknife
    (:func:`t_bounds_jackknife`): the runs of one seed share their initialisation, so the seed,
    not the run, is the independent draw."""
    seeds = np.sort(runs["seed"].unique())
    by_seed = [
        (
            runs.loc[runs["seed"] == s, x].to_numpy(float),
            runs.loc[runs["seed"] == s, y].to_numpy(float),
        )
        for s in seeds
    ]

    def stat(idx) -> float:
        return _spearman_z(
            np.concatenate([by_seed[i][0] for i in idx]),
            np.concatenate([by_seed[i][1] for i in idx]),
        )

    return (*t_bounds_jackknife(stat, len(seeds)), len(seeds))


def _correlation_part(name: str, g: pd.DataFrame, triv: pd.Series, gate) -> Part:
    """Claim 2's correlation part on one cell's regularised runs ``g`` (columns ``_s``:
    achieved symplectic error, ``_e``: log rollout error): the rank correlation at most the
    correlation margin."""
    z, lo, hi, n = rank_correlation(g, "_s", "_e")
    part = gated(at_most(name, (z, lo, hi, n), policy.margin("correlation")), gate)
    m = len(g)
    note = [f"rho = {math.tanh(z):.2f} over {m} runs of {n} seeds"]
    if np.isfinite(lo):
        note[0] += f" (90% CI {math.tanh(lo):.2f} to {math.tanh(hi):.2f}, seed jackknife)"
    if m > 3 and np.isfinite(z):
        half = float(stats.norm.ppf(1 - ALPHA)) * math.sqrt(_SPEARMAN_Z_VAR / (m - 3))
        note.append(
            f"runs as independent draws: {math.tanh(z - half):.2f} to {math.tanh(z + half):.2f}"
        )
    if len(triv):
        # the runs that learned (error below the best trivial predictor's by the learning
        # margin): the strongest weights may fit nothing, and such runs rank lowest in
        # symplectic error and highest in rollout error at once
        floor = g["seed"].map(triv) - policy.margin("learning").test
        ok = g[g["_e"] <= floor]
        if len(ok) > 2:
            zl = _spearman_z(ok["_s"].to_numpy(float), ok["_e"].to_numpy(float))
            note.append(f"over the {len(ok)} runs that learned: rho = {math.tanh(zl):.2f}")
    part.note = "; ".join(note)
    return part


def _statement(parts: list[Part]) -> str:
    """The status of a statement made of ``parts`` read universally: contradicted by one
    contradicting part, holding when every part holds, else undecided."""
    statuses = [p.status for p in parts]
    if "contradicts" in statuses:
        return "contradicts"
    return "holds" if statuses and all(s == "holds" for s in statuses) else "undecided"


def claim_2(runs: pd.DataFrame, curves: pd.DataFrame | None = None) -> Verdict:
    """Claim 2 (Fig. 3): the symplectic regulariser on models of canonical (q, p) states
    (``node_so_symreg``, the reference's NODE+SO with a learned mass matrix, and
    ``node_symreg``, a plain NODE), weight ``w`` on a log grid. Two statements.

    Only ``coordinates="momentum"`` rows count: in (q, qdot) the true field is not symplectic
    (its penalty is 30-180 on chain-2), so older velocity-space rows test nothing.

    (Gain, Fig. 3 left.) For every model, system and weight ``w > 0`` the gain is the per-seed
    ``log(err_{w=0} / err_w)``; an *at most* part per weight at the error margin ("negligible",
    "no real benefit": a weight that hurts also gives no gain, so only the upper of the two
    equivalence tests applies). The statement holds when every weight rules out a gain of the
    margin, and is contradicted by one weight whose gain is shown to exceed it, whatever the
    other weights do: the paper's statement is about the optimally chosen strength.

    (Correlation, Fig. 3 right, Sec. 4.2: the achieved symplectic error "is not positively
    correlated" with the rollout error, "in some cases even negatively".) Per model, system and
    k, Spearman's rho between the achieved symplectic error and the rollout error over the
    figure's runs: the regularised ones (``w > 0``, the caption's "regularized models"), every
    weight and seed pooled, as the paper's plotting notebook pools them per dataset. Its 90%
    interval is Fisher's z with the leave-one-seed-out jackknife's t bounds (the runs of one seed
    share their initialisation: the seed is the independent draw; the interval that treats runs
    as independent, var z = 1.06 / (n - 3), is printed beside it). An *at most* part at the
    correlation margin (policy ``correlation``, on the z scale): holds when the interval excludes
    a positive correlation of that size, contradicts when it lies above it. Universal over cells,
    as the gains are over weights.

    Combination: every part goes through :func:`verdict` read universally (Holm across all
    parts); the two statements are separate sentences of the paper, so where one holds and the
    other is contradicted the claim is *partly reproduced*, as the kit reads separate
    statements. Judged only where the unregularised model (w = 0) learned. Headline: the best
    weight's gain. Discrimination: per system, the best regularised model against constant
    velocity in (q, p).
    """
    p = select(runs, ok=False, coordinates="momentum", noise=0.0, friction=0.0)
    p = paper_spring(p)
    sr = p[p["model"].isin(SYMREG_MODELS)] if len(p) else p
    if not len(sr):
        return verdict(2, CLAIM_TITLES[2], [], None, 0, "log(err_0 / err_w), best w")
    rows = pd.concat([sr, p[p["model"].isin(TRIVIAL_MODELS)]])
    discs = per_system_discrimination(rows)
    sr = sr.assign(weight=option(sr, "weight").astype(float), _e=np.log(scored(sr)))
    if "symplectic_error" in sr:
        sr = sr.assign(_s=pd.to_numeric(sr["symplectic_error"], errors="coerce"))
    else:
        sr = sr.assign(_s=math.nan)
    gains: list[Part] = []
    correlations: list[Part] = []
    seeds: set = set()
    for (model, system, k), g in sr.groupby(["model", "system", "k"], dropna=False):
        base = g[g["weight"] == 0].groupby("seed")["_e"].mean()
        triv = trivial_log(p[(p["system"] == system) & p["model"].isin(TRIVIAL_MODELS)])
        gate = learned(
            f"{MODEL_LABELS.get(model, model)} w=0 on {system}", base, triv if len(triv) else None
        )
        for w, gw in g[g["weight"] > 0].groupby("weight"):
            d = (base - gw.groupby("seed")["_e"].mean()).dropna()
            seeds |= set(d.index)
            name = f"{model} {system} k={_k(k)} w={w:g}: gain"
            gains.append(gated(at_most(name, d.to_numpy(), policy.margin("error")), gate))
        reg = g[(g["weight"] > 0) & np.isfinite(g["_s"]) & np.isfinite(g["_e"])]
        if len(reg):
            name = f"{model} {system} k={_k(k)}: rank correlation of symplectic and rollout error"
            correlations.append(_correlation_part(name, reg, triv, gate))
    best = max(gains, key=lambda q: q.point) if gains else None
    v = verdict(
        2,
        CLAIM_TITLES[2],
        [*gains, *correlations],
        best,
        len(seeds),
        "log(err_0 / err_w) of the best weight",
        discs=discs,
        n_failed=n_bad(sr),
        universal=True,  # "negligible even at an optimally chosen strength" (Sec. 4)
    )
    if {_statement(gains), _statement(correlations)} == {"holds", "contradicts"} and (
        v.verdict != INCONCLUSIVE
    ):
        v = dataclasses.replace(v, verdict=PARTLY)
    return v


def fig_symplectic(runs, curves, outdir: Path) -> list[Path]:
    """Fig. 3. Rollout error vs regulariser weight (weight 0 as a dashed line with its sem
    band), and rollout error vs the achieved symplectic error (log-log)."""
    runs, trivial = split_trivial(runs)
    if not len(runs):
        return []
    df = runs.assign(weight=option(runs, "weight").astype(float))
    fig, (a, b) = subplots(1, 2, figsize=(11, 4))
    trivial_lines(a, trivial)
    trivial_lines(b, trivial)
    for (s, model), g in df.groupby(["system", "model"]):
        ag = seed_stats(g, ["weight"], "rollout_error").sort_values("weight")
        pos = ag[ag["weight"] > 0]
        line = a.errorbar(
            pos["weight"],
            pos["mean"],
            yerr=pos["sem"].fillna(0),
            marker="o",
            capsize=3,
            label=f"{model_label(model)}, {SYSTEM_LABELS.get(s, s)}",
        )
        mark_failed(a, pos["weight"], pos["mean"], pos["n_failed"])
        zero = ag[ag["weight"] == 0]
        if len(zero):
            m0, e0 = zero["mean"].iloc[0], np.nan_to_num(zero["sem"].iloc[0])
            a.axhline(m0, ls="--", color=line[0].get_color(), lw=1)
            a.axhspan(m0 - e0, m0 + e0, color=line[0].get_color(), alpha=0.15)
            if zero["n_failed"].iloc[0]:
                a.annotate(f"w=0: {int(zero['n_failed'].iloc[0])} failed", (1e-7, m0), fontsize=6)
        if "symplectic_error" in g:  # failed runs at the worst error, as 'x', where placeable
            err, bad = scored(g, "rollout_error"), bad_rows(g, "rollout_error")
            label = f"{model_label(model)}, {SYSTEM_LABELS.get(s, s)}"
            for sel, mk in ((~bad, "o" if model == "node_so_symreg" else "^"), (bad, "x")):
                if not sel.any():
                    continue
                b.scatter(
                    g.loc[sel, "symplectic_error"],
                    err[sel],
                    c=np.log10(g.loc[sel, "weight"] + 1e-7),
                    cmap="viridis",
                    vmin=-7,
                    vmax=3,
                    marker=mk,
                    s=20,
                    label=label if mk != "x" else f"{label}: {int(sel.sum())} failed (x)",
                )
    if not (df["weight"] > 0).any():  # e.g. a campaign under way: a log axis needs a range
        a.set_xlim(1e-7, 1e3)
        a.text(0.5, 0.5, "no run with weight > 0 stored yet", transform=a.transAxes, ha="center")
    a.set(
        xscale="log",
        yscale="log",
        xlabel="regulariser weight (dashed: weight 0)",
        ylabel="rollout error",
        title="Symplectic regulariser on (q, p)",
    )
    a.legend(fontsize=8)
    b.set(
        xscale="log",
        yscale="log",
        xlabel="achieved symplectic error ||J DF - (J DF)^T||^2 on (q, p)",
        ylabel="rollout error",
        title="Error vs achieved symplecticity (colour: log10 w, w=0 at -7)",
    )
    b.legend(fontsize=7)
    return save_figure(fig, outdir, "fig3_symplectic")


STUDY = register_study(
    Study(
        name="symplectic",
        experiments=(SYMPLECTIC,),
        claim=2,
        title=CLAIM_TITLES[2],
        rule=claim_2,
        reads=("symplectic",),
        figure=fig_symplectic,
        stem="fig3_symplectic",
    )
)
