"""The speed/accuracy trade-off: how rollout error buys compute, per model and scene.

The ``tradeoff`` experiment trains node, node_so, hnn_so, lnn and vin on the chain and spring
pendulums (k = 2) and evaluates each trained model under many integrators, one factor at a time
around the paper's cell (:data:`EVAL_GRID`, training variants of width, steps and integrator).
The analysis is pure functions of the runs table (:mod:`._pareto`, :func:`tradeoff_table`).
The design: docs/studies/tradeoff.md.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

import models

from ..core import (
    PROFILES,
    Experiment,
    RunConfig,
    Study,
    expand,
    experiment_rows,
    load_runs,
    machine_key,
    pick_profile,
    register_study,
)
from ..kit import save_figure, subplots
from ._pareto import ERROR, aggregate_seeds, cheapest_within, pareto_front

MODELS = ("node", "node_so", "hnn_so", "lnn", "vin")
# The LNN's evaluations were two thirds of the quick trade-off's cost (821 of 1248 s of run time
# measured at quick: every adaptive and implicit evaluation solves its Hessian at each stage), so at
# quick it runs in the paper profile only and the 30-minute budget of `make bench` holds.
PROFILE_MODELS = {"smoke": MODELS, "quick": ("node", "node_so", "hnn_so", "vin"), "paper": MODELS}
SYSTEMS = ("chain_pendulum", "spring_pendulum")
BASE_TRAIN_INTEGRATOR = "rk4_38"
BASE_EVAL = ("rk4_38", 1)
DEFAULT_RTOL = RunConfig.__dataclass_fields__["eval_rtol"].default

# Fixed-step methods and the substeps evaluated per profile (adaptive: the rtol axis).
EVAL_GRID: dict[str, dict[str, tuple[int, ...]]] = {
    "smoke": {"rk4": (2,), "rk4_38": (1,), "leapfrog": (1,), "implicit_midpoint": (1,)},
    "quick": {
        "euler": (1,),
        "rk4": (1, 4),
        "rk4_38": (1,),
        "leapfrog": (1,),
        "implicit_midpoint": (1,),
    },
    "paper": {
        "euler": (1, 2, 4, 8),
        "rk4": (1, 2, 4, 8),
        "rk4_38": (1, 2, 4, 8),
        "leapfrog": (1, 2, 4, 8),
        "leapfrog_explicit": (1, 2, 4, 8),
        "implicit_midpoint": (1, 2, 4, 8),
    },
}
RTOLS = {
    "smoke": (1e-3, DEFAULT_RTOL),
    "quick": (1e-3, DEFAULT_RTOL, 1e-9),  # adaptive runs at 1e-3 and 1e-9 (see include)
    "paper": (1e-3, 1e-4, 1e-5, DEFAULT_RTOL, 1e-7, 1e-8, 1e-9),
}
# Training variants: (width, steps, train_integrator) values beside the profile's base.
WIDTHS = {"smoke": (8, 16), "quick": (64, 128, 256), "paper": (64, 128, 256)}
# quick: the training-budget axis is the learning-curve experiment's (bench.studies.learning:
# checkpoints of 4000-step NODE+SO and HNN+SO runs on the chain, 2 seeds), not 300/3000-step runs
STEPS = {"smoke": (10, 20), "quick": (1000,), "paper": (2000, 8000, 16000)}
TRAIN_INTEGRATORS = ("rk4_38", "euler", "leapfrog")
# smoke: a handful of runs (the CLI tests sweep every experiment at smoke).
SMOKE_AXES = {
    "system": ("chain_pendulum",),
    "model": ("node_so", "vin"),
    "width": (PROFILES["smoke"]["width"],),
    "steps": (PROFILES["smoke"]["steps"],),
    "train_integrator": ("rk4_38",),
}
SUBSTEPS = (1, 2, 4, 8)
# Which (model, system) get training variants, and whether a variant is also evaluated with
# its own training integrator. quick keeps the two cheap-to-train continuous SO models on the
# chain: the whole trade-off must fit beside the paper experiments in ``make bench``.
TRAIN_VARIANTS = {
    "smoke": {"models": (), "systems": (), "own_eval": False},
    # quick: NODE+SO only (HNN+SO's width and integrator variants were 106 s of the trade-off's
    # 274 s of run time, which the five seeds of the verdicts need)
    "quick": {"models": ("node_so",), "systems": ("chain_pendulum",), "own_eval": False},
    "paper": {"models": MODELS, "systems": SYSTEMS, "own_eval": True},
}
QUICK_TRAIN_INTEGRATORS = ("rk4_38", "euler")


def _discrete(model) -> bool:
    """Whether ``model`` (a name from a stored row) is a learned map (its own integrator)."""
    return model in models.available() and models.spec(model).discrete


def profile_of(cfg: RunConfig) -> str:
    """The profile a run was expanded under, recognised by its data size (n_generated,
    n_train), which each profile sets and this experiment does not change."""
    for name, d in PROFILES.items():
        if cfg.n_generated == d.get("n_generated") and cfg.n_train == d.get("n_train"):
            return name
    return "paper"


def _train_changes(cfg: RunConfig, profile: str) -> list[str]:
    base = PROFILES[profile]
    changed = []
    if cfg.width != base["width"]:
        changed.append("width")
    if cfg.steps != base["steps"]:
        changed.append("steps")
    if cfg.train_integrator != BASE_TRAIN_INTEGRATOR:
        changed.append("train_integrator")
    return changed


def _is_base_eval(cfg: RunConfig) -> bool:
    return (cfg.eval_integrator, cfg.eval_substeps) == BASE_EVAL and cfg.eval_rtol == DEFAULT_RTOL


def include(cfg: RunConfig) -> bool:
    """Whether a combination of the trade-off axes is a run (see the module docstring)."""
    profile = profile_of(cfg)
    changed = _train_changes(cfg, profile)
    if len(changed) > 1:
        return False
    rule = TRAIN_VARIANTS[profile]
    if changed and (cfg.model not in rule["models"] or cfg.system not in rule["systems"]):
        return False
    if models.spec(cfg.model).discrete:
        return "train_integrator" not in changed and _is_base_eval(cfg)
    if cfg.eval_integrator == "adaptive":
        if cfg.eval_substeps != 1:
            return False
        if profile != "paper" and cfg.eval_rtol == DEFAULT_RTOL and len(RTOLS[profile]) > 2:
            return False  # quick: the two ends of the tolerance range only
    else:
        if cfg.eval_rtol != DEFAULT_RTOL:
            return False
        if cfg.eval_substeps not in EVAL_GRID[profile].get(cfg.eval_integrator, ()):
            return False
    if changed:
        if profile == "quick" and cfg.train_integrator not in QUICK_TRAIN_INTEGRATORS:
            return False
        own = cfg.eval_integrator == cfg.train_integrator and cfg.eval_substeps == 1
        return _is_base_eval(cfg) or (rule["own_eval"] and own)
    return True


# quick evaluates on the chain only (the spring's evaluations were 78 s of run time; the paper
# profile keeps both)
PROFILE_SYSTEMS = {"smoke": SYSTEMS, "quick": ("chain_pendulum",), "paper": SYSTEMS}


def _axes(profile: str) -> dict:
    methods = (*EVAL_GRID[profile], "adaptive")
    return {
        "system": PROFILE_SYSTEMS[profile],
        "model": PROFILE_MODELS[profile],
        "width": WIDTHS[profile],
        "steps": STEPS[profile],
        "train_integrator": TRAIN_INTEGRATORS,
        "eval_integrator": methods,
        "eval_substeps": SUBSTEPS,
        "eval_rtol": RTOLS[profile],
    }


TRADEOFF = Experiment(
    name="tradeoff",
    title="Speed/accuracy trade-off: integrator, substeps, tolerance, width, training budget",
    axes=_axes("paper"),
    fixed={"k": 2},
    profile_overrides={
        "smoke": {**_axes("smoke"), **SMOKE_AXES, "seeds": (0,)},
        "quick": {**_axes("quick"), "seeds": (0,)},
        "paper": {"seeds": (0, 1, 2)},
    },
    include=include,
    claim=None,
)


# ----------------------------------------------------------------------------- the budget
def estimate(
    profile: str = "quick",
    *,
    ms_per_step: dict | None = None,
    eval_seconds: float = 6.0,
    train_overhead_s: float = 12.0,
    workers: int = 2,
    exclude_shared: bool = True,
) -> dict:
    """Run count and wall-time estimate of the trade-off at ``profile``.

    Training cost per unique ``train_hash`` with the per-step costs of
    :data:`bench.studies.paper.MS_PER_STEP` (scaled by batch / 200 and, for spring, by the dof the
    same way :func:`bench.studies.paper.estimate_seconds` does), plus ``eval_seconds`` (compile and
    rollouts) per run; runs shared with the paper experiments are left out when
    ``exclude_shared`` (``make bench`` runs them anyway).
    """
    import math

    from .paper.campaign import MS_PER_STEP, PAPER_EXPERIMENTS

    ms = dict(MS_PER_STEP)
    ms.update(ms_per_step or {})
    runs = expand(TRADEOFF, profile)
    shared = set()
    if exclude_shared:
        for exp in PAPER_EXPERIMENTS:
            shared |= {c.config_hash for c in expand(exp, profile)}
    new = [c for c in runs if c.config_hash not in shared]
    trained_elsewhere = {c.train_hash for c in runs if c.config_hash in shared}
    trainings = {}
    for c in new:
        if c.train_hash not in trained_elsewhere:
            trainings.setdefault(c.train_hash, c)
    total = 0.0
    for c in trainings.values():
        dof = 3 * (c.k or 1) if c.system == "spring_pendulum" else (c.k or 1)
        free = models.spec(c.model).structure is None
        g = 1.0 if free else max(1.0, dof / 2) ** (math.log(60 / 35) / math.log(3))
        width = (c.width / 128) ** 1.5  # between linear (small widths) and quadratic
        steps_ms = ms.get(c.model, 20.0) * (min(c.batch, c.n_train) / 200) * g * width
        total += c.steps * steps_ms / 1000 + train_overhead_s
    total += eval_seconds * len(new)
    return {
        "runs": len(runs),
        "new_runs": len(new),
        "trainings": len(trainings),
        "seconds": total / max(1, workers),
    }


# ----------------------------------------------------------------------------- analysis
def label(df: pd.DataFrame) -> pd.Series:
    """A short text per configuration: ``rk4x2``, ``adaptive@1e-09``, ``w256``, ``s3000``..."""

    def one(r):
        if _discrete(r.get("model")):
            ev = "native"  # a discrete model is its own integrator
        elif r.get("eval_integrator") == "adaptive":
            ev = f"adaptive@{float(r['eval_rtol']):.0e}"
        else:
            ev = f"{r.get('eval_integrator')}x{int(r.get('eval_substeps', 1))}"
        extra = []
        if r.get("train_integrator", BASE_TRAIN_INTEGRATOR) != BASE_TRAIN_INTEGRATOR:
            extra.append(f"train {r['train_integrator']}")
        extra.append(f"w{int(r['width'])}" if "width" in r else "")
        extra.append(f"s{int(r['steps'])}" if "steps" in r else "")
        return " ".join([ev, *[x for x in extra if x]])

    return df.apply(one, axis=1) if len(df) else pd.Series([], dtype=str)


def tradeoff_table(runs: pd.DataFrame, cost: str = "rollout_seconds_per_traj") -> pd.DataFrame:
    """The Pareto front per (system, model) of the seed-aggregated runs in (cost, error), plus,
    for every evaluation method with no configuration on the front, its lowest-error one
    (``on_front`` = no), so that every method evaluated appears in the table."""
    agg = aggregate_seeds(runs)
    if not len(agg):
        return agg
    fronts = []
    for _, g in agg.groupby(["system", "model"], sort=True):
        f = pareto_front(g, cost).assign(on_front="yes")
        if "eval_integrator" in g and not g["model"].map(_discrete).all():
            e = pd.to_numeric(g[ERROR], errors="coerce")
            c = pd.to_numeric(g[cost], errors="coerce")
            rest = g[np.isfinite(e) & np.isfinite(c) & ~g.index.isin(f.index)]
            missing = set(rest["eval_integrator"]) - set(f.get("eval_integrator", []))
            for method in sorted(missing):
                r = rest[rest["eval_integrator"] == method]
                best = r.loc[[pd.to_numeric(r[ERROR], errors="coerce").idxmin()]]
                f = pd.concat([f, best.assign(on_front="no")])
        fronts.append(f.assign(config=label(f)))
    cols = ["system", "model", "config", ERROR, cost, "on_front", "n_seeds", "diverged"]
    return pd.concat(fronts)[[c for c in cols if c in agg.columns or c in ("config", "on_front")]]


def methods_legend(runs: pd.DataFrame) -> str:
    """One line naming what each evaluation method in ``runs`` is."""
    from models import DESCRIPTIONS

    names = sorted(set(runs.get("eval_integrator", pd.Series([], dtype=str)).dropna().astype(str)))
    parts = [f"`{m}` = {DESCRIPTIONS[m]}" for m in names if m in DESCRIPTIONS]
    return ("Methods: " + "; ".join(parts) + ".") if parts else ""


def machines_line(runs: pd.DataFrame) -> str:
    """Which machines measured the costs (``device``, and ``cpu_family_model`` where recorded),
    with a warning where there are several: a time measured on one machine against a time on
    another measures the machines too, so a front drawn across them is not a trade-off."""
    key = machine_key(runs)
    if not key.str.len().gt(0).any():
        return "Costs measured on: not recorded."
    counts = key.replace("", "not recorded").value_counts().sort_index()
    text = "; ".join(f"{m} ({n} runs)" for m, n in counts.items())
    if len(counts) == 1:
        return f"Costs measured on one machine: {text}."
    return (
        f"Costs measured on {len(counts)} machines: {text}. Times from different machines are "
        "not comparable: rerun the trade-off on one machine before reading its fronts."
    )


def _runs(results_dir, profile=None) -> tuple[pd.DataFrame, str | None]:
    runs = load_runs(results_dir)
    if not len(runs):
        return runs, None
    if profile is None:
        profile = pick_profile(runs, results_dir)
    if profile is not None:
        runs = runs[runs["profile"] == profile]
    return experiment_rows(runs.reset_index(drop=True), "tradeoff", profile), profile


def _md(df: pd.DataFrame) -> list[str]:
    def f(v):
        if isinstance(v, float):
            return f"{v:.3g}"
        return str(v)

    lines = ["| " + " | ".join(map(str, df.columns)) + " |", "|" + " --- |" * len(df.columns)]
    for r in df.itertuples(index=False):
        lines.append("| " + " | ".join(f(v) for v in r) + " |")
    return lines


def tradeoff_section(results_dir="results", profile: str | None = None) -> str:
    """REPORT.md's trade-off section: Pareto fronts and the cheapest config within 10%."""
    runs, profile = _runs(results_dir, profile)
    head = ["## Speed/accuracy trade-off", ""]
    if not len(runs):
        return "\n".join(head + ["No trade-off runs yet: `python -m bench sweep tradeoff`.", ""])
    agg = aggregate_seeds(runs)
    lines = head + [
        f"Profile `{profile}`: {len(runs)} runs, {len(agg)} configurations (seeds aggregated: "
        "geometric-mean rollout error, mean costs). Cost = rollout seconds per test "
        "trajectory after compilation; `nfe` = vector-field evaluations per trajectory.",
        "",
        "### Pareto front per model (error vs rollout seconds per trajectory)",
        "",
    ]
    legend = methods_legend(runs)
    if legend:
        lines += [legend, ""]
    lines += [machines_line(runs), ""]
    if "rollout_seconds_per_traj" in agg:
        lines += _md(tradeoff_table(runs))
    else:
        lines.append("(no `rollout_seconds_per_traj` column in the runs table)")
    for cost, what in (
        ("rollout_seconds_per_traj", "rollout seconds"),
        ("nfe", "evaluations"),
        ("train_seconds", "training seconds"),
    ):
        if cost not in agg or not np.isfinite(pd.to_numeric(agg[cost], errors="coerce")).any():
            continue
        pick = cheapest_within(agg, cost)
        pick = pick.assign(config=label(pick))
        cols = ["system", "model", "config", ERROR, "best_error", "error_ratio", cost]
        lines += [
            "",
            f"### Cheapest configuration within 10% of the best error, by {what}",
            "",
            *_md(pick[[c for c in cols if c in pick.columns]]),
        ]
    return "\n".join(lines) + "\n"


def tradeoff_figure(results_dir="results", profile: str | None = None) -> list[Path]:
    """Error vs rollout cost and vs training cost per scene, each model's Pareto front drawn."""

    runs, _ = _runs(results_dir, profile)
    if not len(runs):
        return []
    agg = aggregate_seeds(runs)
    scenes = sorted(agg["system"].unique())
    fig, axes = subplots(len(scenes), 2, figsize=(11, 4 * len(scenes)), squeeze=False)
    for i, scene in enumerate(scenes):
        d = agg[agg["system"] == scene]
        for j, cost in enumerate(("rollout_seconds_per_traj", "train_seconds")):
            ax = axes[i, j]
            if cost not in d:  # rows stored without this cost
                ax.set_axis_off()
                continue
            for model, g in d.groupby("model"):
                pts = ax.loglog(g[cost], g[ERROR], "o", alpha=0.35, label=None)
                f = pareto_front(g, cost)
                ax.loglog(f[cost], f[ERROR], "-o", color=pts[0].get_color(), label=model)
            ax.set(
                xlabel=cost.replace("_", " "),
                ylabel="rollout error (geo. mean)",
                title=f"{scene} k=2",
            )
            ax.legend(fontsize=8)
    fig.tight_layout()
    return save_figure(fig, Path(results_dir) / "figures", "tradeoff", dpi=120, tight=False)


STUDY = register_study(
    Study(
        name="tradeoff",
        experiments=(TRADEOFF,),
        stem="tradeoff",
        results_figure=tradeoff_figure,
        section=tradeoff_section,
        section_title="Speed/accuracy trade-off",
    )
)
