"""Running the stability cases, and their figure and REPORT.md section."""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from dataclasses import asdict, replace
from pathlib import Path

import numpy as np

from ...core import one_line, provenance
from ...kit import save_figure, subplots
from ._core import (
    COLUMNS,
    METHOD_NOTES,
    OUTCOMES,
    SIZES,
    Row,
    StabilitySize,
    _size,
    fmt_outcome,
    guard,
)
from ._learned import case_high_energy_models, case_long_horizon, case_model_precision
from ._lnn import case_lnn_singular
from ._truth import (
    case_dt_sweep,
    case_high_energy_truth,
    case_precision,
    case_relativistic,
    case_stiffness,
)

CASES: dict[str, Callable[[StabilitySize], list[Row]]] = {
    "dt_sweep": case_dt_sweep,
    "precision": case_precision,
    "high_energy_truth": case_high_energy_truth,
    "stiffness": case_stiffness,
    "relativistic": case_relativistic,
    "lnn_singular": case_lnn_singular,
    "long_horizon": case_long_horizon,
    "high_energy_models": case_high_energy_models,
    "model_precision": case_model_precision,
}


# Cases that share trained models (``_learned``'s cache) run in one process; the long-horizon
# case, most of the study's time, is split by model (its rows are in model order).
LEARNED = ("high_energy_models", "model_precision")
SPLIT_BY_MODEL = ("long_horizon",)
# Longest first (measured at quick), so that the processes finish together.
_ORDER = ("long_horizon", "stiffness", "dt_sweep", "precision", "lnn_singular", "relativistic")


def _run_job(job) -> list[tuple[str, int, list[Row], float]]:
    """A pool task: ``(case, part, size)`` triples run in order, each inside :func:`guard`."""
    from ...core import bound_compiled_programs, configure_compilation_cache

    configure_compilation_cache()
    out = []
    for name, part, size in job:
        start = time.perf_counter()
        rows = guard(name, lambda name=name, size=size: CASES[name](size))
        out.append((name, part, rows, time.perf_counter() - start))
        bound_compiled_programs()
    return out


def _jobs(names, size: StabilitySize) -> list[list]:
    jobs = []
    for name in sorted(names, key=lambda n: _ORDER.index(n) if n in _ORDER else len(_ORDER)):
        if name in LEARNED:
            continue
        if name in SPLIT_BY_MODEL and len(size.models) > 1:
            jobs += [[(name, i, replace(size, models=(m,)))] for i, m in enumerate(size.models)]
        else:
            jobs.append([(name, 0, size)])
    learned = [(n, 0, size) for n in names if n in LEARNED]
    return jobs + ([learned] if learned else [])


def run_cases(profile="quick", cases=None, progress: bool = True, workers: int = 1) -> list[Row]:
    """Every case (or the named ones) at ``profile``'s size, each inside :func:`guard`, in case
    order. ``workers`` > 1: in that many processes (``bench.core._runner.worker_pool``), the
    cases that share trained models (:data:`LEARNED`) in one of them, the long-horizon case
    split by model; the rows are those of one process (a test)."""
    size = _size(profile)
    names = list(CASES) if cases is None else list(cases)
    unknown = [c for c in names if c not in CASES]
    if unknown:
        raise ValueError(f"unknown stability case(s) {unknown}; allowed: {', '.join(CASES)}")
    split = workers > 1
    jobs = _jobs(names, size) if split else [[(n, 0, size)] for n in names]
    got: dict[str, dict[int, list[Row]]] = {}

    def report(done):
        for name, part, rows, seconds in done:
            got.setdefault(name, {})[part] = rows
            if progress:
                outcomes = {o: sum(r.outcome == o for r in rows) for o in OUTCOMES}
                what = f"{name} (model {part + 1})" if split and name in SPLIT_BY_MODEL else name
                print(
                    f"[stability] {what}: {len(rows)} rows {outcomes} in {seconds:.1f}s",
                    flush=True,
                )

    workers = max(1, min(int(workers), len(jobs)))
    if workers == 1:
        for job in jobs:
            report(_run_job(job))
    else:
        from ...core import imap_unordered, worker_pool

        with worker_pool(workers) as pool:
            for done in imap_unordered(pool, _run_job, jobs):
                report(done)
    return [row for n in names for part in sorted(got[n]) for row in got[n][part]]


def to_frame(rows):
    import pandas as pd

    return pd.DataFrame([asdict(r) for r in rows], columns=list(COLUMNS))


def run_stability(results_dir="results", profile: str = "quick", cases=None, workers: int = 1):
    """Run the cases (in ``workers`` processes); write ``stability.csv``/``.parquet`` and the
    figure; return the frame."""
    results_dir = Path(results_dir)
    results_dir.mkdir(parents=True, exist_ok=True)
    df = to_frame(run_cases(profile, cases, workers=workers))
    df.insert(0, "profile", profile)
    for name, value in provenance().items():  # versions, backend, device, commit
        df[name] = value
    df.to_csv(results_dir / "stability.csv", index=False)
    try:
        df.to_parquet(results_dir / "stability.parquet", index=False)
    except Exception as err:  # noqa: BLE001 - parquet is a convenience copy of the CSV
        print(f"[stability] parquet not written: {one_line(err)}")
    stability_figure(results_dir)
    return df


# --------------------------------------------------------------------------- figure and report
def _load(results_dir):
    import pandas as pd

    path = Path(results_dir) / "stability.csv"
    return pd.read_csv(path) if path.exists() else None


def stability_figure(results_dir="results") -> list[Path]:
    """Four panels: error vs dt, stiff solvers' evaluations, tolerance vs drift, long horizon."""
    df = _load(results_dir)
    if df is None or df.empty:
        return []
    fig, axes = subplots(2, 2, figsize=(11, 8))

    ax = axes[0, 0]
    d = df[(df.case == "dt_sweep") & (df.metric == "final_error")]
    for method, g in d.groupby("method"):
        ok = g[g.outcome == "ok"]
        ax.loglog(ok.param, ok.value.clip(lower=1e-16), "o-", label=method)
        div = g[g.outcome == "diverged"]
        ax.plot(div.param, np.ones(len(div)), "x", color=ax.lines[-1].get_color(), ms=10)
    ax.set(
        xlabel="dt",
        ylabel="relative error at final time",
        title="chain pendulum: fixed step vs dt (x = diverged)",
    )
    ax.legend()

    ax = axes[0, 1]
    d = df[(df.case == "stiffness") & (df.metric == "nfe")]
    for method, g in d.groupby("method"):
        ax.loglog(g.param, g.value, "o-", label=method)
    e = df[(df.case == "stiffness") & (df.metric == "final_error") & (df.outcome == "diverged")]
    for _, r in e.iterrows():
        same = d[(d.method == r.method) & (d.param == r.param)]
        y = float(same.value.iloc[0]) if len(same) else 1.0
        ax.annotate(
            f"{r.method} diverged @ step {int(r.step)}", (r.param, y), fontsize=7, rotation=20
        )
    ax.set(
        xlabel="spring constant",
        ylabel="vector-field evaluations",
        title="stiff spring pendulum, dt = 0.03",
    )
    ax.legend()

    ax = axes[1, 0]
    d = df[(df.case == "high_energy_truth") & (df.metric == "energy_drift") & (df.outcome == "ok")]
    for label, g in d.groupby(d.variant.str.split("/").str[0]):
        ax.loglog(g.param, g.value.clip(lower=1e-17), "o-", label=label)
    ax.set(xlabel="rtol", ylabel="max energy drift", title="ground truth at high energy")
    ax.legend()

    ax = axes[1, 1]
    d = df[(df.case == "long_horizon") & (df.metric == "divergence_rate")]
    if not d.empty:
        ax.barh(d.variant, d.value.fillna(1.0))
        ax.set(
            xlabel="fraction of trajectories diverged",
            title=f"long horizon ({int(d.param.iloc[0])} steps)",
        )
    else:
        ax.set_axis_off()
    fig.tight_layout()
    return save_figure(fig, Path(results_dir) / "figures", "stability", dpi=120, tight=False)


def stability_section(results_dir="results") -> str:
    """REPORT.md's stability section: one table per case from ``stability.csv``."""
    df = _load(results_dir)
    if df is None or df.empty:
        return (
            "## Numerical stability\n\nNo `stability.csv` yet: run `python -m bench stability`.\n"
        )
    lines = [
        "## Numerical stability",
        "",
        f"Profile `{df.profile.iloc[0]}`. Every variant ends in `ok` (a value), `diverged` "
        "(with the first non-finite or runaway step) or `failed` (with the error). "
        "Errors: relative state error ||zhat - z|| / (||zhat|| + ||z||); energy drift "
        "|H - H0| / (|H| + |H0|) with the true H.",
        "",
    ]
    for case, g in df.groupby("case", sort=False):
        doc = " ".join((CASES[case].__doc__ or "").split()) if case in CASES else ""
        lines += [
            f"### {case}",
            "",
            doc,
            "",
            "| variant | metric | result |",
            "| --- | --- | --- |",
        ]
        for r in g.itertuples():
            lines.append(f"| {r.variant} | {r.metric} | {fmt_outcome(r)} |")
        lines += _summary(case, g)
        lines.append("")
    methods = sorted(set(df.method.dropna().astype(str)) & set(METHOD_NOTES))
    lines += ["Methods: " + "; ".join(f"`{m}` = {METHOD_NOTES[m]}" for m in methods) + ".", ""]
    counts = df.outcome.value_counts().to_dict()
    lines.append(f"Outcomes: {counts}.")
    return "\n".join(lines) + "\n"


def _summary(case: str, g) -> list[str]:
    """A sentence or two under a case's table: orders and costs, or what stiffness costs."""
    ok = g[g.outcome == "ok"]
    out = []
    if case == "dt_sweep":
        order = ok[ok.metric == "order"].set_index("method").value
        cost = ok[ok.metric == "nfe_per_step"].set_index("method").value
        rk4 = cost.get("rk4", float("nan"))
        parts = []
        for m in cost.index:
            o = order.get(m, float("nan"))
            fitted = f"{o:.2f}" if np.isfinite(o) else "no fit (errors outside the window)"
            parts.append(f"{m} {fitted} ({cost[m] / rk4:.2g}x rk4's evaluations per step)")
        if parts:
            out += ["", "Fitted orders: " + "; ".join(parts) + "."]
    if case == "stiffness":
        nfe = ok[ok.metric == "nfe"]
        for kappa, k in nfe.groupby("param"):
            err = g[(g.metric == "final_error") & (g.param == kappa)].set_index("method")
            parts = []
            for r in k.itertuples():
                e = err.loc[r.method] if r.method in err.index else None
                parts.append(
                    f"{r.method} {int(r.value)} evaluations"
                    + (f" ({fmt_outcome(e)})" if e is not None else "")
                )
            out += ["", f"kappa = {kappa:g}: " + "; ".join(parts) + "."]
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.studies.stability", description=__doc__)
    parser.add_argument("--profile", default="quick", choices=list(SIZES))
    parser.add_argument("--results", default="results")
    parser.add_argument("--case", action="append", choices=list(CASES))
    ns = parser.parse_args(argv)
    from ...core import setup_process

    setup_process()
    df = run_stability(ns.results, ns.profile, ns.case)
    print(df.to_string(max_rows=400))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
