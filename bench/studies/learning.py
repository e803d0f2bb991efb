"""Learning curves: every verdict as a function of the training budget.

Each trained run keeps four checkpoints (1/8, 1/4, 1/2 and 1 of its steps); each claim's rule
judges the runs at each checkpoint (:mod:`._along`), and the ``learning_curves`` experiment
(NODE+SO and HNN+SO, chain and spring, k = 2) adds longer runs. A checkpoint is not a shorter
run: its cosine schedule has not annealed. The design and its limits: docs/studies/learning.md.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from ..core import (
    PROFILES,
    Experiment,
    Study,
    load_checkpoints,
    load_tables,
    register_study,
    select,
)
from ..kit import (
    COLORS,
    MODEL_LABELS,
    SYSTEM_LABELS,
    claim_studies,
    restrict,
    save_figure,
    subplots,
)
from ._along import (
    along_row,
    curves_at,
    is_trained,
    runs_at,
    settling,
    settling_table,
    verdicts_along_curve,
)
from ._claims import PAPER_MODELS, SPRING_EQUILIBRIUM, SYSTEMS, initial_ok, shared_overrides

# The cells of the learning curves: undamped, noiseless, in (q, qdot), L2 (the campaign's damped
# runs share system, k and model with them)
_PLAIN = {"k": 2, "loss": "l2", "friction": 0.0, "noise": 0.0, "coordinates": "velocity"}

LEARNING_MODELS = ("node_so", "hnn_so")
# Claims whose rule compares only LEARNING_MODELS (claim 4: the chain and spring edges of
# NODE+SO over HNN+SO): judged again on the learning-curve experiment's longer runs.
LEARNING_CLAIMS = (4,)
PAPER_STEPS = PROFILES["paper"]["steps"]


def _learning_cell(c) -> bool:
    # the chain, and the spring from its physical equilibrium (claim 4's spring, Fig. 5)
    return initial_ok(c, allowed=(SPRING_EQUILIBRIUM,))


LEARNING = Experiment(
    name="learning_curves",
    title="Learning curves: NODE+SO and HNN+SO past the quick budget (chain, spring)",
    axes={"system": SYSTEMS, "k": (2,), "model": LEARNING_MODELS},
    # quick: the shared 1000-step cells (no training of its own, which pays for quick's five
    # seeds; the longer runs are the paper-core campaign's, results/reference/paper/)
    profile_overrides=shared_overrides({"smoke": {"steps": 40}}),
    include=_learning_cell,
)


def verdicts_along_learning(
    runs: pd.DataFrame,
    curves: pd.DataFrame,
    checkpoints: pd.DataFrame,
    cp_curves: pd.DataFrame,
    profile: str | None,
) -> pd.DataFrame:
    """:func:`verdicts_along_curve` on the longer runs of the learning-curve experiment: each
    claim of :data:`LEARNING_CLAIMS` (whose rule compares only the learning models) judged by
    its own rule on those runs and the trivial predictors of the same cells, at each of their
    checkpoints. Verdicts with fewer than 2 seeds (a cell the experiment does not have) are left
    out. Same columns as :func:`verdicts_along_curve`."""
    from ..core import experiment_rows

    cols = ["key", "claim", "position", "fraction", "step", "verdict", "effect"]
    learn = experiment_rows(runs, LEARNING.name, profile) if len(runs) else runs
    learn = learn[learn["config_hash"].isin(checkpoints["config_hash"])] if len(learn) else learn
    base_steps = PROFILES.get(profile or "", {}).get("steps")
    if len(learn) and base_steps is not None:  # longer than the profile's own runs only
        learn = learn[learn["steps"].astype(int) > int(base_steps)]
    if not len(learn):
        return pd.DataFrame(columns=cols)
    cells = set(zip(learn["system"], learn["system_params"].astype(str), strict=True))
    n = int(
        checkpoints[checkpoints["config_hash"].isin(learn["config_hash"])]
        .groupby("config_hash")
        .size()
        .max()
    )
    out = []
    for study in claim_studies():
        mine = restrict(runs, study, profile)
        if not len(mine):
            continue
        if study.claim not in LEARNING_CLAIMS:
            continue
        trivial = mine[~is_trained(mine)]
        same = [
            (a, b) in cells
            for a, b in zip(trivial["system"], trivial["system_params"].astype(str), strict=True)
        ]
        sub = pd.concat([learn, trivial[same]], ignore_index=True)
        for position in range(n):
            runs_i, _ = runs_at(sub, checkpoints, position)
            got = study.rule(runs_i, curves_at(curves, cp_curves, runs_i))
            for v in got if isinstance(got, list) else [got]:
                if v.n_seeds < 2:
                    continue
                out.append(along_row(v, position, n, runs_i["checkpoint_step"].dropna()))
    return pd.DataFrame(out, columns=cols)


# ------------------------------------------------------------------------ loading
def _tables(results_dir: Path):
    runs, curves, profile = load_tables(results_dir)
    cp, cp_curves = load_checkpoints(results_dir)
    if len(cp) and len(runs):
        cp = cp[cp["config_hash"].isin(runs["config_hash"])]
        cp_curves = cp_curves[cp_curves["config_hash"].isin(cp["config_hash"])]
    return runs, curves, cp, cp_curves, profile


def _curve_runs(runs: pd.DataFrame, cp: pd.DataFrame) -> pd.DataFrame:
    """Finished runs with checkpoints of the paper models in the k = 2 cells of Figs. 2, 4 and 5
    (L2, plain models, (q, qdot)), whatever their budget, with their ``cell`` label."""
    ok = select(runs, model=list(PAPER_MODELS), k=2, loss="l2", friction=0.0)
    ok = ok[ok["config_hash"].isin(cp["config_hash"])]
    if not len(ok):
        return ok.assign(cell=pd.Series(dtype=str))
    plain = ok["model_options"].map(lambda o: o in ("[]", "()", "", None) or o != o)
    ok = ok[plain & (ok["coordinates"] == "velocity")]
    return ok.assign(
        cell=[_cell_name(a, b) for a, b in zip(ok["system"], ok["system_params"], strict=True)]
    )


def _paper_reference(results_dir: Path) -> pd.DataFrame:
    """Final errors of the paper-budget runs of the report's other folders (the committed
    ``results/reference/paper*/`` and ``<results>/paper*/``), if any."""
    from ..core import compare_folders

    parts = []
    for d in compare_folders(results_dir):
        if d.name.startswith("paper"):
            try:
                r, _, _ = load_tables(d)
            except Exception:  # noqa: BLE001 - a reference folder is optional
                continue
            if len(r):
                parts.append(r.assign(_folder=d.name))
    return pd.concat(parts, ignore_index=True) if parts else pd.DataFrame()


# ------------------------------------------------------------------------- the figure
def _gmean(x) -> float:
    x = np.asarray(x, float)
    x = x[np.isfinite(x) & (x > 0)]
    return float(np.exp(np.mean(np.log(x)))) if len(x) else math.nan


def fig_learning_curves(results_dir) -> list[Path]:
    """Per cell (system and initial state): rollout error against training steps and against
    training seconds, for the paper models (geometric mean over seeds, min-max band; solid:
    the profile's runs, dashed: the longer runs of the learning-curve experiment), the paper
    budget marked, and the final errors of paper-budget runs stored beside as stars."""
    results_dir = Path(results_dir)
    runs, _, cp, _, _ = _tables(results_dir)
    sel = _curve_runs(runs, cp) if len(cp) else runs.iloc[0:0]
    if not len(sel):
        return []
    ref = _paper_reference(results_dir)
    if len(ref):
        ref = select(ref, model=list(PAPER_MODELS), **_PLAIN)
        ref = ref.assign(
            cell=[
                _cell_name(a, b) for a, b in zip(ref["system"], ref["system_params"], strict=True)
            ]
        )
    cols = ["config_hash", "cell", "model", "seed", "steps"]
    data = cp.merge(sel[cols], on="config_hash")
    cells = sorted(data["cell"].unique())
    fig, axes = subplots(
        len(cells), 2, figsize=(10, 3.4 * len(cells)), squeeze=False, layout="constrained"
    )
    shortest = data["steps"].min()
    for row, cell in enumerate(cells):
        d = data[data["cell"] == cell]
        for col, x in enumerate(("step", "train_seconds")):
            ax = axes[row][col]
            for (model, budget), g in d.groupby(["model", "steps"]):
                s = g.groupby("step").agg(
                    x=(x, "mean"),
                    y=("rollout_error", _gmean),
                    lo=("rollout_error", "min"),
                    hi=("rollout_error", "max"),
                    n=("seed", "nunique"),
                )
                style = "-" if budget == shortest else "--"
                label = f"{MODEL_LABELS.get(model, model)}, {int(budget)} steps (n={s.n.max()})"
                ax.plot(s.x, s.y, style, marker="o", ms=3, color=COLORS.get(model), label=label)
                ax.fill_between(s.x, s.lo, s.hi, color=COLORS.get(model), alpha=0.12)
            if x == "step":
                ax.axvline(PAPER_STEPS, color="gray", lw=0.8, ls=":")
                ax.text(
                    PAPER_STEPS,
                    0.98,
                    "paper budget ",
                    transform=ax.get_xaxis_transform(),
                    va="top",
                    ha="right",
                    fontsize=7,
                    color="gray",
                )
                r = ref[ref["cell"] == cell] if len(ref) else ref
                for model, g in r.groupby("model") if len(r) else []:
                    ax.plot(
                        [g["steps"].median()],
                        [_gmean(g["rollout_error"])],
                        marker="*",
                        ms=10,
                        color=COLORS.get(model),
                        ls="none",
                    )
                ax.set_xlabel("training steps")
            else:
                ax.set_xlabel("training seconds (this machine)")
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.grid(True, which="both", alpha=0.25)
            ax.set_title(cell, fontsize=9)
            if col == 0:
                ax.set_ylabel("test rollout error\n(geometric mean)")
        axes[row][0].legend(fontsize=6, loc="lower left")
    stars = "\nstars: final errors of the paper-budget runs stored beside (n_train 800)"
    fig.suptitle(
        "Learning curves: rollout error at training checkpoints (band: min-max over seeds)"
        + (stars if len(ref) else ""),
        fontsize=9,
    )
    return save_figure(fig, results_dir / "figures", "fig_learning_curves")


# -------------------------------------------------------------------------- the section
def _fmt(x) -> str:
    return "-" if x is None or not np.isfinite(x) else f"{x:.3g}"


def _steps(x) -> str:
    return "-" if x is None or not np.isfinite(x) else f"{x:.0f}"


def _fraction(fraction: float) -> str:
    return "1" if fraction >= 1 else f"1/{round(1 / fraction)}"


def _budget_label(fraction: float, step: float) -> str:
    return f"{_fraction(fraction)} ({_steps(step)} steps)"


def _settling_lines(along: pd.DataFrame) -> list[str]:
    if not len(along):
        return ["No stored run has checkpoints: no verdicts along the curve.", ""]
    table = settling_table(along)
    positions = sorted(along["position"].unique())
    heads = []
    for p in positions:
        g = along[along["position"] == p]
        heads.append(_budget_label(float(g["fraction"].iloc[0]), float(g["step"].median())))
    lines = [
        "| claim | " + " | ".join(f"verdict at {h}" for h in heads) + " | settling budget |",
        "|---" * (len(heads) + 2) + "|",
    ]
    for _, r in table.iterrows():
        settle = f"{_steps(r['settles_at'])} steps"
        if not np.isfinite(r["settles_at"]):  # its runs train for different numbers of steps
            settle = f"{_fraction(r['settles_fraction'])} of its runs' training (their step "
            settle += "budgets differ)"
        if not r["settled"]:
            settle += " (changed at the last checkpoint: not settled)"
        elif r["settles_fraction"] <= min(along["fraction"]):
            settle += " (from the first checkpoint)"
        lines.append(f"| {r['key']} | " + " | ".join(r["verdicts"]) + f" | {settle} |")
    lines.append("")
    if len(positions) < 2:
        return lines + ["One checkpoint per run: nothing to say about settling.", ""]
    moved = table.loc[~table["settled"], "key"].tolist()
    lines.append(
        f"{len(table) - len(moved)} of {len(table)} verdicts no longer change over the last "
        "two checkpoints"
        + (
            f"; {len(moved)} changed at the last one ({', '.join(moved)}): at this budget they "
            "have not settled and may change with longer training."
            if moved
            else "."
        )
    )
    return lines + [""]


def _cell_name(system: str, params) -> str:
    init = "paper" if "paper" in str(params) else "equilibrium"
    label = SYSTEM_LABELS.get(system, system)
    return f"{label} (from {init})" if system == "spring_pendulum" else label


def _seeds_cell(vals) -> str:
    return f"{_fmt(_gmean(vals))} [{', '.join(_fmt(v) for v in vals)}]"


def _paper_budget_note(ref: pd.DataFrame, system: str, params: str) -> str:
    """The final errors of the paper-budget runs of ``ref`` (:func:`_paper_reference`) in the
    curves' cell, per model and folder; "" where there are none."""
    if not len(ref):
        return ""
    r = select(ref, system=system, model=list(LEARNING_MODELS), **_PLAIN)
    r = r[r["system_params"].astype(str) == params] if len(r) else r
    return "; ".join(
        f"{MODEL_LABELS.get(m, m)} {_fmt(_gmean(g['rollout_error']))} "
        f"({int(g['steps'].median())} steps, n_train {int(g['n_train'].median())}, "
        f"n={len(g)}, `{folder}`)"
        for (m, folder), g in r.groupby(["model", "_folder"])
    )


def _learning_lines(runs: pd.DataFrame, cp: pd.DataFrame, results_dir: Path, profile) -> list:
    """The dedicated experiment, per cell: the error of each model at each checkpoint over
    seeds, the NODE+SO / HNN+SO ratio, the same seeds' full-schedule runs at the profile's own
    budget, and the paper-budget runs stored beside."""
    from ..core import experiment_rows

    rows = experiment_rows(runs, LEARNING.name, profile)
    rows = rows[rows["config_hash"].isin(cp["config_hash"])] if len(rows) else rows
    if not len(rows):
        return []
    budget = int(rows["steps"].max())
    base_steps = PROFILES.get(profile or "", {}).get("steps")
    ref = _paper_reference(results_dir)
    keys = ["config_hash", "model", "seed", "system", "system_params"]
    d = cp.merge(rows[keys], on="config_hash")
    d["system_params"] = d["system_params"].astype(str)
    steps = sorted(d["step"].unique())
    lines = [
        f"Dedicated experiment `{LEARNING.name}` ({budget} training steps, seeds "
        f"{sorted(rows['seed'].unique().tolist())}): rollout error at each checkpoint "
        "(geometric mean over seeds, per-seed values in brackets).",
        "",
        "| cell | model | " + " | ".join(f"step {s}" for s in steps) + " |",
        "|---" * (2 + len(steps)) + "|",
    ]
    notes = []
    for (system, params), cell in d.groupby(["system", "system_params"]):
        name = _cell_name(system, params)
        per = {}
        for model, g in cell.groupby("model"):
            cells = []
            for step in steps:
                h = g[g["step"] == step].sort_values("seed")
                cells.append(_seeds_cell(h["rollout_error"].to_numpy()) if len(h) else "-")
                per.setdefault(step, {})[model] = h.set_index("seed")["rollout_error"]
            lines.append(
                f"| {name} | {MODEL_LABELS.get(model, model)} | " + " | ".join(cells) + " |"
            )
        if all(set(LEARNING_MODELS) <= set(v) for v in per.values()):
            cells = [
                _seeds_cell((per[s]["node_so"] / per[s]["hnn_so"]).dropna().to_numpy())
                for s in steps
            ]
            lines.append(f"| {name} | NODE+SO / HNN+SO | " + " | ".join(cells) + " |")
        # the same seeds' full-schedule runs at the profile's own budget
        mine = rows[(rows["system"] == system) & (rows["system_params"].astype(str) == params)]
        own = select(runs, system=system, model=list(LEARNING_MODELS), **_PLAIN)
        if len(own) and base_steps and base_steps < budget:
            own = own[
                (own["steps"] == base_steps)
                & (own["system_params"].astype(str) == params)
                & (own["coordinates"] == "velocity")
                & own["seed"].isin(set(mine["seed"]))
                & (own["n_train"] == mine["n_train"].iloc[0])
            ]
            parts = []
            for model, g in own.groupby("model"):
                at = cell[(cell["model"] == model) & (cell["step"] == base_steps)]
                if len(at):
                    parts.append(
                        f"{MODEL_LABELS.get(model, model)} {_fmt(_gmean(g['rollout_error']))} "
                        f"after a full {base_steps}-step schedule, "
                        f"{_fmt(_gmean(at['rollout_error']))} at step {base_steps} of the "
                        f"{budget}-step one"
                    )
            if parts:
                notes.append(f"- {name}, same seeds: " + "; ".join(parts) + ".")
        note = _paper_budget_note(ref, system, params)
        if note:
            notes.append(f"- {name}, paper budget: {note}.")
    lines.append("")
    if notes:
        lines += [
            "A checkpoint is not a shorter run (its learning rate has not annealed yet), and "
            "the paper budget is more data as well as more steps:",
            "",
            *notes,
            "",
        ]
    return lines


def section(results_dir) -> str:
    results_dir = Path(results_dir)
    runs, curves, cp, cp_curves, profile = _tables(results_dir)
    lines = [
        "## Learning curves and settling budgets",
        "",
        "Every trained run keeps checkpoints at 1/8, 1/4, 1/2 and 1 of its training steps "
        "(rounded to 100-step blocks), evaluated on the whole test set; the last is the final "
        "model. Each claim's own rule is applied to the runs at each checkpoint (trivial "
        "predictors unchanged). The settling budget is the first checkpoint from which the "
        "verdict no longer changes. A checkpoint at step s of a longer cosine schedule is not "
        "a run trained for s steps (`bench/studies/learning.py`), so these are statements "
        "about this profile's training, not predictions for a shorter profile.",
        "",
    ]
    along = verdicts_along_curve(runs, curves, cp, cp_curves, profile)
    lines += _settling_lines(along)
    lines += _learning_lines(runs, cp, results_dir, profile)
    longer = verdicts_along_learning(runs, curves, cp, cp_curves, profile)
    if len(longer):
        lines += [
            "The same rules on the longer runs of the learning-curve experiment (claims whose "
            "models it trains; its cells only, with the trivial predictors of those cells; "
            f"{len(set(longer['key']))} verdicts):",
            "",
            *_settling_lines(longer),
            "A verdict that settles within this profile's own training can still change with a "
            "longer one: compare the two tables, and the paper-budget verdicts above "
            '("Verdicts at both budgets").',
            "",
        ]
    return "\n".join(lines)


STUDY = register_study(
    Study(
        name="learning_curves",
        experiments=(LEARNING,),
        title="Learning curves and settling budgets",
        results_figure=fig_learning_curves,
        section=section,
        section_title="Learning curves and settling budgets",
        stem="fig_learning_curves",
    )
)

__all__ = [
    "LEARNING",
    "curves_at",
    "fig_learning_curves",
    "runs_at",
    "section",
    "settling",
    "settling_table",
    "verdicts_along_curve",
    "verdicts_along_learning",
]
