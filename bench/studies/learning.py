"""Learning curves: every verdict as a function of the training budget (issue 16).

Every trained run of the ``quick`` and ``paper`` profiles keeps ``eval_checkpoints = 4``
snapshots of its parameters, on the halving grid 1/8, 1/4, 1/2, 1 of its steps (rounded to the
100-step training blocks: 100, 300, 500, 1000 at quick; 1000, 2000, 4000, 8000 at paper), and
evaluates each on the whole test set after training (``checkpoints.parquet``). The last
checkpoint is the final model, so a curve ends on its run's row.

What a checkpoint is, and is not. The checkpoint at step s of a run trained for S steps is that
run's model after s updates of a cosine schedule that decays over S steps: the learning rate is
still high at s < S. It is therefore NOT the run one would get with a budget of s steps (whose
schedule would have annealed by then); the section below measures the difference on the
learning-curve cells (the quick 1000-step runs against the 1000-step checkpoint of the
4000-step runs of the same seeds; at quick on 2026-11-22 the checkpoint of HNN+SO was the
better of the two, 0.065 against 0.093 on the chain). Verdicts along the curve answer "from
which point of THIS training does the verdict stop changing", not what a profile with a
shorter schedule would conclude.

Verdicts along the curve (:func:`verdicts_along_curve`): the runs table at checkpoint i is the
runs table with every trained run's scores (``bench.core._execute.CHECKPOINT_METRICS``), status
and training seconds replaced by those of its i-th checkpoint, and its per-time curves by the
checkpoint's; trivial predictors (nothing to train) keep theirs. Each claim's own rule
(``bench.studies.paper``) judges each of these tables. A claim whose trained runs lack
checkpoints (rows stored before them) is left out. The *settling budget* (:func:`settling`) of
a verdict is the first checkpoint from which it no longer changes; a verdict that changes at the
last checkpoint is marked not settled (a longer budget may change it again).

The dedicated experiment (``learning_curves``): NODE+SO and HNN+SO on the chain pendulum and
on the spring pendulum from its physical equilibrium (k = 2: the cells of Figs. 2/4 and of
Fig. 5, where claim 4's verdict differs between the budgets). Until issue 20 it trained them
4000 steps at quick, 2 seeds, checkpoints at 500, 1000, 2000, 4000 (what follows describes
that design); since issue 20 it has no training of its own at quick (its cells are the shared
1000-step runs, and the five seeds of the verdicts needed its 7 minutes), and the longer runs
are the paper-core campaign's (``results/reference/paper/``, 8000 steps, checkpoints at 1000, 2000,
4000, 8000), whose report carries this section. Only runs longer than their profile's own
steps count as "longer runs". The two models are those whose ratio
decides claims 3 and 4 and whose quick errors sit furthest from the paper budget's (HNN+SO
11-14x, NODE+SO about 3x, issue 16); 2 seeds are what fit beside the other quick experiments in
``make bench``'s 30 minutes. They replace the trade-off's 300- and 3000-step training variants
at quick. At ``paper`` the experiment is the Fig. 2/5 cells of the two models (the same runs,
no new training).
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

import models  # noqa: E402

from ..core._execute import CHECKPOINT_METRICS as SCORES  # noqa: E402 - what a checkpoint replaces
from ..core._experiments import PROFILES, Experiment  # noqa: E402
from ..core._query import load_tables, select  # noqa: E402
from ..core._store import load_checkpoints  # noqa: E402
from ..core._studies import Study, register_study  # noqa: E402
from ._figure import save_figure  # noqa: E402
from .paper._common import PAPER_MODELS, SPRING_EQUILIBRIUM, SYSTEMS, initial_ok, shared_overrides  # noqa: E402
from .paper._plot import COLORS, SYSTEM_LABELS  # noqa: E402
from .paper._rules import claim_studies, evaluate_claims, restrict  # noqa: E402
from .paper.kit import MODEL_LABELS  # noqa: E402

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
    # quick: the shared 1000-step cells (no training of its own since issue 20, whose five
    # seeds it pays for; the longer runs are the paper-core campaign's, results/reference/paper/)
    profile_overrides=shared_overrides({"smoke": {"steps": 40}}),
    include=_learning_cell,
)


# ------------------------------------------------------------------- runs at a checkpoint
def _trained(runs: pd.DataFrame) -> pd.Series:
    known = set(models.available())
    return runs["model"].map(lambda m: not (m in known and models.spec(m).trivial))


def runs_at(
    runs: pd.DataFrame, checkpoints: pd.DataFrame, position: int
) -> tuple[pd.DataFrame, set]:
    """(the runs table at checkpoint ``position`` counted from each run's first, the
    config hashes of trained runs that have no such checkpoint and were dropped)."""
    out = runs.copy()
    trained = _trained(out)
    cp = checkpoints[checkpoints["config_hash"].isin(out["config_hash"])]
    cp = cp.sort_values(["config_hash", "step"])
    at = cp.groupby("config_hash").nth(position) if len(cp) else cp
    at = at.set_index("config_hash") if len(at) else at
    has = out["config_hash"].isin(at.index) if len(at) else pd.Series(False, index=out.index)
    missing = set(out.loc[trained & ~has, "config_hash"])
    out = out[~trained | has].copy()
    rows = out["config_hash"].isin(at.index) if len(at) else pd.Series(False, index=out.index)
    if rows.any():
        src = at.loc[out.loc[rows, "config_hash"]]
        for col in (*SCORES, "status", "train_seconds"):
            if col in src.columns:
                out.loc[rows, col] = src[col].to_numpy()
        out.loc[rows, "checkpoint_step"] = src["step"].to_numpy()
    return out.reset_index(drop=True), missing


def curves_at(curves: pd.DataFrame, cp_curves: pd.DataFrame, runs_i: pd.DataFrame) -> pd.DataFrame:
    """Per-time curves of ``runs_i`` (a :func:`runs_at` table): a trained run's at its
    checkpoint step, a trivial predictor's own."""
    if "checkpoint_step" not in runs_i:
        return curves
    steps = runs_i.dropna(subset=["checkpoint_step"])[["config_hash", "checkpoint_step"]]
    parts = []
    if len(steps) and len(cp_curves):
        keyed = cp_curves.merge(
            steps.rename(columns={"checkpoint_step": "step"}).astype({"step": int}),
            on=["config_hash", "step"],
        )
        parts.append(keyed.drop(columns=["step"]))
    rest = runs_i.loc[runs_i["checkpoint_step"].isna(), "config_hash"]
    if len(curves):
        parts.append(curves[curves["config_hash"].isin(rest)])
    return pd.concat(parts, ignore_index=True) if parts else curves.iloc[0:0]


def settling(verdicts) -> int:
    """The first index from which ``verdicts`` no longer change (``len - 1`` when the last one
    differs from the one before; 0 when all agree)."""
    verdicts = list(verdicts)
    i = len(verdicts) - 1
    while i > 0 and verdicts[i - 1] == verdicts[-1]:
        i -= 1
    return max(i, 0)


def _along_row(v, position: int, n: int, steps: pd.Series) -> dict:
    """One row of a verdicts-along-the-curve table: verdict ``v`` at checkpoint ``position``
    of ``n`` (nominal fraction 2^(position - n + 1)), at the median of ``steps``."""
    return {
        "key": v.key,
        "claim": v.claim,
        "position": position,
        "fraction": 2.0 ** (position - n + 1),
        "step": float(np.nanmedian(steps)) if len(steps) else math.nan,
        "verdict": v.verdict,
        "effect": v.effect,
    }


def verdicts_along_curve(
    runs: pd.DataFrame,
    curves: pd.DataFrame,
    checkpoints: pd.DataFrame,
    cp_curves: pd.DataFrame,
    profile: str | None,
) -> pd.DataFrame:
    """One row per (verdict, checkpoint): key, claim, position, fraction (nominal, of the
    budget), step (median over the claim's trained runs), verdict, effect. Claims whose trained
    runs lack checkpoints are left out. Empty when no run has checkpoints."""
    cols = ["key", "claim", "position", "fraction", "step", "verdict", "effect"]
    if not len(checkpoints) or not len(runs):
        return pd.DataFrame(columns=cols)
    cp = checkpoints[checkpoints["config_hash"].isin(runs["config_hash"])]
    if not len(cp):
        return pd.DataFrame(columns=cols)
    n = int(cp.groupby("config_hash").size().max())
    judged = {}
    for study in claim_studies():
        mine = restrict(runs, study, profile)
        if not len(mine):
            continue
        hashes = set(mine.loc[_trained(mine), "config_hash"])
        per_run = cp[cp["config_hash"].isin(hashes)].groupby("config_hash").size()
        if hashes and len(per_run) == len(hashes) and (per_run == n).all():
            judged[study.claim] = hashes
    out = []
    for position in range(n):
        runs_i, _ = runs_at(runs, cp, position)
        curves_i = curves_at(curves, cp_curves, runs_i)
        for v in evaluate_claims(runs_i, curves_i, profile):
            if v.claim not in judged:
                continue
            steps = runs_i.loc[runs_i["config_hash"].isin(judged[v.claim]), "checkpoint_step"]
            out.append(_along_row(v, position, n, steps))
    return pd.DataFrame(out, columns=cols)


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
    from ..core._query import experiment_rows

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
        trivial = mine[~_trained(mine)]
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
                out.append(_along_row(v, position, n, runs_i["checkpoint_step"].dropna()))
    return pd.DataFrame(out, columns=cols)


def settling_table(along: pd.DataFrame) -> pd.DataFrame:
    """Per verdict key: the verdict at each checkpoint, the settling step and whether the
    verdict changed at the last checkpoint (``settled`` False)."""
    rows = []
    for key, g in along.groupby("key", sort=False):
        g = g.sort_values("position")
        i = settling(g["verdict"])
        rows.append(
            {
                "key": key,
                "claim": int(g["claim"].iloc[0]),
                "verdicts": list(g["verdict"]),
                "steps": list(g["step"]),
                "settles_at": float(g["step"].iloc[i]),
                "settles_fraction": float(g["fraction"].iloc[i]),
                "settled": bool(len(g) == 1 or i < len(g) - 1),
            }
        )
    return pd.DataFrame(rows)


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
    from ..core._store import compare_folders

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
    fig, axes = plt.subplots(
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


def _budget_label(fraction: float, step: float) -> str:
    frac = "1" if fraction >= 1 else f"1/{round(1 / fraction)}"
    return f"{frac} ({_steps(step)} steps)"


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
    from ..core._query import experiment_rows

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
