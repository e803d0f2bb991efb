"""Paper-style figures, regenerated from the stored runs (``results/.rows`` or the parquet tables).

Entry point: :func:`make_figures(results_dir) -> list[Path]` writes PNG and PDF files to
``results_dir/figures/``. One function per experiment (``fig_<experiment>``); each takes the
runs and curves of the chosen profile and returns the files it wrote, or ``[]`` when the
experiment has no finished runs (the report notes that). Every number drawn comes from the
tables: error bars are the standard error of the mean over seeds (``bench._store.aggregate``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from . import _store  # noqa: E402
from ._claims import MODEL_LABELS, TRIVIAL_MODELS, option, select  # noqa: E402

__all__ = ["FIGURES", "experiment_rows", "load_tables", "make_figures", "pick_profile"]

SYSTEM_LABELS = {
    "chain_pendulum": "chain pendulum",
    "spring_pendulum": "spring pendulum",
    "relativistic_particle": "relativistic particle",
}
COLORS = {
    "node": "#1f77b4",
    "node_so": "#2ca02c",
    "hnn": "#d62728",
    "hnn_so": "#ff7f0e",
    "hnn_so_diss": "#9467bd",
    "node_symreg": "#17becf",
    "lnn": "#8c564b",
    "vin": "#e377c2",
    "resnet": "#7f7f7f",
    "mixture_hnn": "#bcbd22",
    "node_so_symreg": "#17becf",
}
# Trivial predictors are drawn as reference lines, never as bars or points.
TRIVIAL_STYLE = {"constant_velocity": ("black", "--"), "at_rest": ("dimgray", ":")}


# ----------------------------------------------------------------------------- tables


def pick_profile(runs: pd.DataFrame) -> str | None:
    """The profile whose runs the figures show: the one with the most rows (None if untagged)."""
    if "profile" not in runs or not len(runs) or runs["profile"].isna().all():
        return None
    return str(runs["profile"].value_counts().idxmax())


def load_tables(results_dir: Path) -> tuple[pd.DataFrame, pd.DataFrame, str | None]:
    """(runs, curves, profile) restricted to the chosen profile."""
    runs = _store.load_runs(results_dir)
    curves = _store.load_curves(results_dir)
    profile = pick_profile(runs)
    if profile is not None:
        runs = runs[runs["profile"] == profile].reset_index(drop=True)
    if len(curves) and len(runs):
        curves = curves[curves["config_hash"].isin(runs["config_hash"])]
    return runs, curves, profile


def _cell_key(cfg) -> str:
    """Hash of a run's configuration without its seed: the cell it belongs to."""
    from ._experiments import _hash

    return _hash({a: b for a, b in cfg.to_dict().items() if a != "seed"})


def experiment_rows(runs: pd.DataFrame, name: str, profile: str | None) -> pd.DataFrame:
    """The runs of experiment ``name``: every stored run (any seed) whose configuration is one
    of the experiment's cells under ``profile``, shared runs included whichever experiment
    produced them, plus the rows tagged with the experiment (results of older declarations,
    whose cells no longer expand); without a profile, the rows tagged with that experiment."""
    if not len(runs):
        return runs
    if profile is not None:
        try:
            from ._experiments import RunConfig, expand

            cells = {_cell_key(c) for c in expand(name, profile)}
            keys = [_cell_key(RunConfig.from_dict(r)) for r in runs.to_dict("records")]
            match = pd.Series([k in cells for k in keys], index=runs.index)
            if "experiment" in runs:  # rows of older declarations of the same experiment
                match |= runs["experiment"] == name
            return runs[match].reset_index(drop=True)
        except ValueError:
            pass
    if "experiment" in runs:
        return runs[runs["experiment"] == name].reset_index(drop=True)
    return runs.iloc[0:0]


def variant(df: pd.DataFrame) -> pd.Series:
    """Model label key: ``hnn_so_diss`` for an HNN with the dissipation term, else the model."""
    diss = df["dissipation"] if "dissipation" in df else pd.Series(None, index=df.index)
    is_diss = diss.map(lambda v: v is True or v == 1 or v == "True" or v == "true")
    return df["model"].where(~(is_diss & df["model"].str.startswith("hnn")), df["model"] + "_diss")


def _agg(df: pd.DataFrame, by: Sequence[str], metric: str) -> pd.DataFrame:
    """Per group of ``by``: n, mean and sem = std(ddof=1) / sqrt(n) of the finite values
    (the columns of ``bench._store.aggregate``, without its bootstrap, which figures don't use)."""
    df = df.copy()
    for col in by:  # groupby on NaN keys (k of the relativistic particle) needs a value
        if df[col].isna().any():
            df[col] = df[col].astype(object).where(df[col].notna(), "-")
    x = pd.to_numeric(df[metric], errors="coerce")
    df = df.assign(_x=x.where(np.isfinite(x)))
    g = df.groupby(list(by), sort=True)["_x"]
    out = pd.DataFrame({"n": g.count(), "mean": g.mean(), "std": g.std(ddof=1)}).reset_index()
    out["sem"] = out["std"] / np.sqrt(out["n"].clip(lower=1))
    return out


def _save(fig, outdir: Path, stem: str) -> list[Path]:
    outdir.mkdir(parents=True, exist_ok=True)
    out = []
    for ext in ("png", "pdf"):
        p = outdir / f"{stem}.{ext}"
        fig.savefig(p, dpi=130, bbox_inches="tight")
        out.append(p)
    plt.close(fig)
    return out


def _bars(
    ax,
    agg: pd.DataFrame,
    groups: Sequence,
    members: Sequence,
    gcol: str,
    mcol: str,
    labels: Callable = str,
    log: bool = True,
    ylabel: str = "",
) -> None:
    """Grouped bars: one group per ``groups`` value, one bar per ``members`` value, sem bars."""
    width = 0.8 / max(1, len(members))
    for j, m in enumerate(members):
        xs, ys, es = [], [], []
        for i, g in enumerate(groups):
            row = agg[(agg[gcol] == g) & (agg[mcol] == m)]
            if not len(row):
                continue
            xs.append(i + (j - (len(members) - 1) / 2) * width)
            ys.append(row["mean"].iloc[0])
            es.append(0.0 if not np.isfinite(row["sem"].iloc[0]) else row["sem"].iloc[0])
        if xs:
            ys, es = np.asarray(ys), np.asarray(es)
            lower = np.minimum(es, ys * 0.999) if log else es  # keep log bars positive
            ax.bar(
                xs,
                ys,
                width,
                yerr=[lower, es],
                capsize=3,
                label=labels(m),
                color=COLORS.get(str(m)),
            )
    ax.set_xticks(range(len(groups)))
    ax.set_xticklabels([SYSTEM_LABELS.get(str(g), str(g)) for g in groups])
    if log:
        ax.set_yscale("log")
    ax.set_ylabel(ylabel)
    ax.legend(fontsize=8)


def _label(m) -> str:
    return MODEL_LABELS.get(str(m), str(m))


def _order(values, preferred: Sequence) -> list:
    present = list(dict.fromkeys(values))
    return [p for p in preferred if p in present] + [p for p in present if p not in preferred]


MODEL_ORDER = (
    "node",
    "node_so",
    "hnn",
    "hnn_so",
    "hnn_so_diss",
    "mixture_hnn",
    "node_symreg",
    "node_so_symreg",
    "lnn",
    "vin",
    "resnet",
)
SYSTEM_ORDER = ("chain_pendulum", "spring_pendulum", "relativistic_particle")


def _curve_mean(curves: pd.DataFrame, hashes, column: str) -> tuple[np.ndarray, np.ndarray]:
    """Geometric mean over runs of a per-time curve (t > 0): (t, value)."""
    c = curves[curves["config_hash"].isin(list(hashes)) & (curves["t"] > 0)]
    c = c[np.isfinite(c[column]) & (c[column] > 0)]
    if not len(c):
        return np.array([]), np.array([])
    g = c.groupby("t")[column].apply(lambda v: float(np.exp(np.mean(np.log(v)))))
    return g.index.to_numpy(float), g.to_numpy(float)


def split_trivial(runs: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame]:
    """(model rows, trivial-predictor rows)."""
    t = runs["model"].isin(TRIVIAL_MODELS) if len(runs) else pd.Series(dtype=bool)
    return runs[~t], runs[t]


def _gmean(x) -> float:
    x = pd.to_numeric(pd.Series(x), errors="coerce").to_numpy(float)
    x = x[np.isfinite(x) & (x > 0)]
    return float(np.exp(np.mean(np.log(x)))) if len(x) else float("nan")


def _trivial_lines(ax, trivial, metric="rollout_error", groups=None, gcol="system", vertical=False):
    """Each trivial predictor's geometric-mean ``metric`` as a reference line: one segment per
    bar group (``groups`` along x, by ``gcol``), or a full line (vertical with ``vertical``)."""
    if trivial is None or not len(trivial) or metric not in trivial:
        return
    for m, g in trivial.groupby("model"):
        color, ls = TRIVIAL_STYLE.get(m, ("black", "--"))
        label = MODEL_LABELS.get(m, m)
        if groups is None:
            v = _gmean(g[metric])
            if np.isfinite(v):
                (ax.axvline if vertical else ax.axhline)(v, color=color, ls=ls, lw=1, label=label)
            continue
        for i, grp in enumerate(groups):
            v = _gmean(g.loc[g[gcol] == grp, metric])
            if np.isfinite(v):
                ax.hlines(v, i - 0.45, i + 0.45, colors=color, linestyles=ls, lw=1.2, label=label)
                label = None


# ----------------------------------------------------------------------------- one per figure


def fig_energy(runs, curves, outdir: Path) -> list[Path]:
    """Fig. 2. Left: energy violation vs rollout error (log-log), one point per run, with the
    least-squares line of log EV on log error and its R^2. Right: energy violation vs time
    (geometric mean over runs) per model, from the curves."""
    runs, trivial = split_trivial(runs)
    if not len(runs):
        return []
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    markers = {"chain_pendulum": "o", "spring_pendulum": "s"}
    for s, g in trivial.groupby("system"):  # the trivial predictors' error: vertical lines
        for m, gm in g.groupby("model"):
            color, _ = TRIVIAL_STYLE.get(m, ("black", "--"))
            ls = "--" if s == "chain_pendulum" else ":"
            a.axvline(
                _gmean(gm["rollout_error"]),
                color=color,
                ls=ls,
                lw=1,
                label=f"{MODEL_LABELS.get(m, m)}, {SYSTEM_LABELS.get(s, s)}",
            )
    for m in _order(runs["model"], MODEL_ORDER):
        for s, g in runs[runs["model"] == m].groupby("system"):
            a.scatter(
                g["rollout_error"],
                g["energy_violation"],
                c=COLORS.get(m),
                marker=markers.get(s, "^"),
                s=22,
                alpha=0.8,
                label=f"{_label(m)}, {SYSTEM_LABELS.get(s, s)}",
            )
    ok = runs[(runs["rollout_error"] > 0) & (runs["energy_violation"] > 0)]
    if len(ok) >= 3:
        x, y = np.log10(ok["rollout_error"]), np.log10(ok["energy_violation"])
        slope, icpt = np.polyfit(x, y, 1)
        r2 = 1 - np.sum((y - (slope * x + icpt)) ** 2) / max(np.sum((y - y.mean()) ** 2), 1e-300)
        xs = np.linspace(x.min(), x.max(), 20)
        a.plot(
            10**xs,
            10 ** (slope * xs + icpt),
            "k--",
            lw=1,
            label=f"fit: slope {slope:.2f}, $R^2$ = {r2:.2f}",
        )
    a.set(
        xscale="log",
        yscale="log",
        xlabel="rollout error (geometric mean)",
        ylabel="energy violation",
        title="Energy violation vs rollout error",
    )
    a.legend(fontsize=6, ncol=2)
    drawn = False
    for m in _order(runs["model"], MODEL_ORDER):
        for s, g in runs[runs["model"] == m].groupby("system"):
            t, v = _curve_mean(curves, g["config_hash"], "energy_violation")
            if len(t):
                drawn = True
                b.plot(
                    t,
                    v,
                    color=COLORS.get(m),
                    ls="-" if s == "chain_pendulum" else ":",
                    label=f"{_label(m)}, {SYSTEM_LABELS.get(s, s)}",
                )
    if drawn:
        b.set(xscale="log", yscale="log")
        b.legend(fontsize=6, ncol=2)
    b.set(xlabel="time (s)", ylabel="energy violation", title="Energy violation over time")
    return _save(fig, outdir, "fig2_energy")


def fig_symplectic(runs, curves, outdir: Path) -> list[Path]:
    """Fig. 3. Rollout error vs regulariser weight (weight 0 as a dashed line with its sem
    band), and rollout error vs the achieved symplectic error (log-log)."""
    runs, trivial = split_trivial(runs)
    if not len(runs):
        return []
    df = runs.assign(weight=option(runs, "weight").astype(float))
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4))
    _trivial_lines(a, trivial)
    _trivial_lines(b, trivial)
    for (s, model), g in df.groupby(["system", "model"]):
        ag = _agg(g, ["weight"], "rollout_error").sort_values("weight")
        pos = ag[ag["weight"] > 0]
        line = a.errorbar(
            pos["weight"],
            pos["mean"],
            yerr=pos["sem"].fillna(0),
            marker="o",
            capsize=3,
            label=f"{_label(model)}, {SYSTEM_LABELS.get(s, s)}",
        )
        zero = ag[ag["weight"] == 0]
        if len(zero):
            m0, e0 = zero["mean"].iloc[0], np.nan_to_num(zero["sem"].iloc[0])
            a.axhline(m0, ls="--", color=line[0].get_color(), lw=1)
            a.axhspan(m0 - e0, m0 + e0, color=line[0].get_color(), alpha=0.15)
        if "symplectic_error" in g:
            b.scatter(
                g["symplectic_error"],
                g["rollout_error"],
                c=np.log10(g["weight"] + 1e-7),
                cmap="viridis",
                vmin=-7,
                vmax=3,
                marker="o" if model == "node_so_symreg" else "^",
                s=20,
                label=f"{_label(model)}, {SYSTEM_LABELS.get(s, s)}",
            )
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
    return _save(fig, outdir, "fig3_symplectic")


def _model_bars(
    runs,
    outdir: Path,
    stem: str,
    title: str,
    metric: str = "rollout_error",
    ylabel: str = "rollout error (geometric mean)",
) -> list[Path]:
    runs, trivial = split_trivial(runs)
    if not len(runs):
        return []
    df = runs.assign(variant=variant(runs))
    ag = _agg(df, ["system", "variant"], metric)
    fig, ax = plt.subplots(figsize=(7, 4))
    groups = _order(df["system"], SYSTEM_ORDER)
    _trivial_lines(ax, trivial, metric, groups)
    _bars(
        ax,
        ag,
        groups,
        _order(df["variant"], MODEL_ORDER),
        "system",
        "variant",
        _label,
        ylabel=ylabel,
    )
    ax.set_title(title)
    return _save(fig, outdir, stem)


def fig_second_order(runs, curves, outdir: Path) -> list[Path]:
    """Fig. 4: rollout error of NODE, NODE+SO, HNN, HNN+SO per system (mean +- sem)."""
    return _model_bars(runs, outdir, "fig4_second_order", "Second-order structure")


def fig_coordinates(runs, curves, outdir: Path) -> list[Path]:
    """Fig. 5: NODE+SO vs HNN+SO in angular (chain) and Cartesian (spring) coordinates."""
    return _model_bars(runs, outdir, "fig5_coordinates", "Complex vs simple coordinates")


def fig_damped(runs, curves, outdir: Path) -> list[Path]:
    """Fig. 6: damped systems; rollout error, parameter count and training time per variant."""
    runs, trivial = split_trivial(runs)
    if not len(runs):
        return []
    df = runs.assign(variant=variant(runs))
    systems_ = _order(df["system"], SYSTEM_ORDER)
    members = _order(df["variant"], MODEL_ORDER)
    lab = lambda m: "HNN+SO (no dissipation)" if m == "hnn_so" else _label(m)
    fig, axes = plt.subplots(1, 3, figsize=(15, 4))
    for ax, metric, ylabel, log in (
        (axes[0], "rollout_error", "rollout error", True),
        (axes[1], "n_params", "parameters", False),
        (axes[2], "train_seconds", "training time (s)", False),
    ):
        _bars(
            ax,
            _agg(df, ["system", "variant"], metric),
            systems_,
            members,
            "system",
            "variant",
            lab,
            log=log,
            ylabel=ylabel,
        )
    _trivial_lines(axes[0], trivial, "rollout_error", systems_)
    axes[0].legend(fontsize=7)
    axes[0].set_title("Damped systems (friction > 0)")
    return _save(fig, outdir, "fig6_damped")


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
    return _save(fig, outdir, "fig8_loss")


def _coord_label(df: pd.DataFrame) -> pd.Series:
    names = {"velocity": "(q, qdot)", "momentum": "(q, p)"}
    opts = {
        "momentum_map=False": "naive ",
        "momentum_map=True": "learned-map ",
    }
    mm = option(df, "momentum_map").map(lambda v: opts.get(f"momentum_map={v}", ""))
    kp = option(df, "kinetic_prior").map(lambda v: f" prior {v:g}" if v == v else "")
    return mm + df["model"].map(_label) + kp + " " + df["coordinates"].map(names)


def fig_relativistic(runs, curves, outdir: Path) -> list[Path]:
    """LNN seed: rollout error of HNN(q, qdot), HNN(q, p), LNN(q, qdot), and the first test
    trajectory's q(t), true vs predicted, of the lowest seed of each variant."""
    if not len(runs):
        return []
    from ._claims import velocity_scores

    scores, _ = velocity_scores(runs)
    runs = runs.assign(score=scores)
    runs, trivial = split_trivial(runs)
    if not len(runs):
        return []
    df = runs.assign(variant=_coord_label(runs))
    ag = _agg(df, ["system", "variant"], "score")
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4))
    vs = list(dict.fromkeys(df["variant"]))
    _trivial_lines(a, trivial, "score", ["relativistic_particle"])
    _bars(
        a,
        ag,
        ["relativistic_particle"],
        vs,
        "system",
        "variant",
        ylabel="rollout error on (q, qdot)",
    )
    a.set_title("Relativistic particle (every model scored on (q, qdot))")
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
    return _save(fig, outdir, "fig_relativistic")


def fig_double_pendulum_energy(runs, curves, outdir: Path) -> list[Path]:
    """LNN seed: energy error in % of the maximum potential energy, unit double pendulum."""
    return _model_bars(
        runs,
        outdir,
        "fig_double_pendulum_energy",
        "Unit double pendulum: energy error",
        metric="energy_pct_max_pe",
        ylabel="energy error, % of max potential energy",
    )


def fig_vin(runs, curves, outdir: Path) -> list[Path]:
    """VIN seed. Left: rollout error vs number of training trajectories (log-log, dashed for
    noisy data). Right: relative error and energy violation vs time at the fewest data."""
    runs, trivial = split_trivial(runs)
    if not len(runs):
        return []
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4))
    _trivial_lines(a, trivial)
    for (m, noise), g in runs.groupby(["model", "noise"]):
        ag = _agg(g, ["n_train"], "rollout_error").sort_values("n_train")
        a.errorbar(
            ag["n_train"],
            ag["mean"],
            yerr=ag["sem"].fillna(0),
            marker="o",
            capsize=3,
            color=COLORS.get(m),
            ls="-" if noise == 0 else "--",
            label=f"{_label(m)}" + (f", noise {noise:g}" if noise else ""),
        )
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
            t, v = _curve_mean(curves, g["config_hash"], col)
            if len(t):
                drawn = True
                b.plot(
                    t,
                    v,
                    ls=ls,
                    color=COLORS.get(m),
                    label=f"{_label(m)} {'error' if col == 'rel_error' else 'energy'}",
                )
    if drawn:
        b.set(yscale="log")
        b.legend(fontsize=7)
    b.set(
        xlabel="time (s)",
        ylabel="relative error / energy violation",
        title=f"Long horizon, n_train = {n_min}",
    )
    return _save(fig, outdir, "fig_vin")


FIGURES: dict[str, Callable] = {
    "energy": fig_energy,
    "symplectic": fig_symplectic,
    "second_order": fig_second_order,
    "coordinates": fig_coordinates,
    "damped": fig_damped,
    "loss": fig_loss,
    "relativistic": fig_relativistic,
    "double_pendulum_energy": fig_double_pendulum_energy,
    "vin": fig_vin,
}


def make_figures(results_dir: Path) -> list[Path]:
    """Every figure of the paper experiments from the stored runs; returns the files written.

    Runs that did not finish (``status != "ok"``) or have a non-finite error are left out of
    the plots (the report lists them). An experiment without runs draws nothing.
    """
    results_dir = Path(results_dir)
    runs, curves, profile = load_tables(results_dir)
    outdir = results_dir / "figures"
    written: list[Path] = []
    for name, fn in FIGURES.items():
        rows = experiment_rows(runs, name, profile)
        if len(rows):
            rows = select(rows)
        if not len(rows):
            continue
        try:
            written += fn(rows, curves, outdir)
        except Exception as e:  # noqa: BLE001 - one broken figure must not stop the others
            plt.close("all")
            print(f"figure {name} failed: {type(e).__name__}: {e}")
    for module, entry in (("_tradeoff", "tradeoff_figure"), ("_stability", "stability_figure")):
        try:
            mod = __import__(f"bench.{module}", fromlist=[entry])
            written += list(getattr(mod, entry)(results_dir) or [])
        except Exception as e:  # noqa: BLE001
            plt.close("all")
            print(f"figure {entry} failed: {type(e).__name__}: {e}")
    return written


def figure_stem(name: str) -> str:
    """The file stem of an experiment's figure (for the report's links)."""
    return {
        "energy": "fig2_energy",
        "symplectic": "fig3_symplectic",
        "second_order": "fig4_second_order",
        "coordinates": "fig5_coordinates",
        "damped": "fig6_damped",
        "loss": "fig8_loss",
    }.get(name, f"fig_{name}")
