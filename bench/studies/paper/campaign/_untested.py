"""What more training would decide: the claims with a part left *not tested* because a model it
gates on did not learn, and what the longer profile's cells of the claim would cost.

A closed learning gate leaves a part untested, never refuted; whether more training could open
it depends on whether a longer profile trains that claim longer. This reads, per claim: the
models that did not learn (the gates' own text), the training steps of the claim's cells here
and at the longer profile (``paper``, the papers' own budgets where a CPU affords less), and
the longer profile's cells on the same seeds, costed by the campaign's estimator
(:func:`._budget.total_seconds`, from the measured step costs of ``costs.json``) times the
claim's calibration here (the measured CPU time of its stored runs over their estimate, as
``python -m bench estimate`` rescales its hours). Where the longer profile trains no longer,
the table says so: the models did not learn at the budget the claim's paper used, and more
training is not what the claim lacks.
"""

from __future__ import annotations

import math
import re

import pandas as pd

from ....core import available, expand, get
from ....kit import TRIVIAL_MODELS, seed_sets
from ._budget import run_seconds, total_seconds

LONGER = "paper"


def closed_learning_gates(v) -> list:
    """The binding learning gates of ``v``'s parts that are closed (a model that did not
    learn), one per model label, in the order the parts state them; a stated condition ("at
    similar loss") or a model whose runs are not stored yet is not a learning gate."""
    out, seen = [], set()
    for p in v.parts:
        for g in p.gates:
            if g.binding and g.open is False and g.kind == "learning":
                if g.label not in seen:
                    seen.add(g.label)
                    out.append(g)
    return out


_GATE = re.compile(
    r"did not learn: (\S+x (?:below|above)) the best trivial predictor \(geometric mean over "
    r"\d+ seeds; the gate is ([^)]+)\)"
)


def _short(gate) -> str:
    """``pure LNN (1.09x below the trivial predictor; gate 2x)``, or the gate's whole text."""
    m = _GATE.search(gate.text)
    return f"{gate.label} ({m[1]} the trivial predictor; gate {m[2]})" if m else gate.text


def _experiments(claim: int) -> list[str]:
    return [n for n in available() if get(n).claim == claim]


def _trained(cfgs) -> list:
    return [c for c in cfgs if c.model not in TRIVIAL_MODELS]


def _steps(cfgs) -> tuple[int, int] | None:
    s = [int(c.steps) for c in _trained(cfgs)]
    return (min(s), max(s)) if s else None


def _calibration(cfgs, runs: pd.DataFrame) -> float:
    """Measured CPU seconds over the estimate of the stored CPU runs among ``cfgs``; NaN
    where none records ``cpu_seconds``."""
    need = {"config_hash", "cpu_seconds"}
    if not len(runs) or not need <= set(runs.columns):
        return math.nan
    rows = runs
    if "backend" in rows:
        rows = rows[rows["backend"].fillna("cpu") == "cpu"]
    by_hash = {c.config_hash: c for c in cfgs}
    rows = rows[rows["config_hash"].isin(by_hash) & rows["cpu_seconds"].notna()]
    rows = rows.drop_duplicates("config_hash")
    estimate = sum(run_seconds(by_hash[h]) for h in rows["config_hash"])
    return float(rows["cpu_seconds"].sum()) / estimate if estimate > 0 else math.nan


def training_gap(verdicts, runs: pd.DataFrame, profile: str, longer: str = LONGER) -> pd.DataFrame:
    """One row per verdict with a closed learning gate: ``claim`` (its key), ``models`` (the
    gates' texts), ``steps_here`` and ``steps_longer`` ((min, max) over the claim's trained
    cells, None where it has none), ``runs_longer`` (the longer profile's cells on this
    profile's seeds), ``cpu_hours_longer`` (their estimate), ``calibration`` and
    ``cpu_hours_calibrated`` (NaN where no stored run records its CPU time: then the estimate
    alone), and ``longer`` (whether the longer profile trains the claim longer)."""
    primary, replication = seed_sets(profile)
    seeds = tuple(sorted({*primary, *replication})) or None
    rows = []
    for v in verdicts:
        gates = closed_learning_gates(v)
        if not gates:
            continue
        names = _experiments(v.claim)
        here = [c for n in names for c in expand(n, profile, seeds=seeds)]
        there = [c for n in names for c in expand(n, longer, seeds=seeds)]
        s_here, s_there = _steps(here), _steps(there)
        hours = total_seconds(there) / 3600
        cal = _calibration(here, runs)
        rows.append(
            {
                "claim": v.key,
                "models": "; ".join(_short(g) for g in gates),
                "steps_here": s_here,
                "steps_longer": s_there,
                "runs_longer": len(there),
                "cpu_hours_longer": hours,
                "calibration": cal,
                "cpu_hours_calibrated": hours * cal if math.isfinite(cal) else math.nan,
                "longer": bool(s_here and s_there and s_there[1] > s_here[1]),
            }
        )
    return pd.DataFrame(rows)


def _span(s) -> str:
    if s is None:
        return "-"
    lo, hi = s
    return f"{lo:,}" if lo == hi else f"{lo:,}-{hi:,}"


def training_gap_lines(table: pd.DataFrame, profile: str, longer: str = LONGER) -> list[str]:
    """The report's table of :func:`training_gap`, or nothing where every gate is open."""
    if not len(table):
        return []
    out = [
        "### What more training would decide",
        "",
        "Parts left *not tested* because a model they gate on did not learn, and what the "
        f"`{longer}` profile's cells of the claim (the papers' training budgets) would cost on "
        "the seeds judged here, in CPU hours on this kind of machine: the campaign's estimate "
        "(measured step costs) times the claim's calibration here (the measured CPU time of "
        "its stored runs over their estimate). Where that profile trains no longer than "
        f"{profile}, the models did not learn at the budget the claim's paper used: more "
        f"training is not what the claim lacks. `python -m bench estimate --profile {longer} "
        "--claims N` gives the plan.",
        "",
        f"| claim | did not learn | steps at {profile} | steps at {longer} | runs | CPU hours |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for r in table.to_dict("records"):
        if not r["longer"]:
            cost = f"- ({longer} trains no longer)"
        elif math.isfinite(r["cpu_hours_calibrated"]):
            cost = (
                f"{r['cpu_hours_calibrated']:,.0f} ({r['cpu_hours_longer']:,.0f} estimated x "
                f"{r['calibration']:.2f})"
            )
        else:
            cost = f"{r['cpu_hours_longer']:,.0f} (estimated; no run here records CPU time)"
        out.append(
            f"| {r['claim']} | {r['models']} | {_span(r['steps_here'])} | "
            f"{_span(r['steps_longer'])} | {r['runs_longer']} | {cost} |"
        )
    return [*out, ""]
