"""Whether a model learned, as the verdicts gate it, for the side-by-side checks: constant
velocity from each window's first state, the suite's and the paper's error of a prediction,
the stored runs' ratio of constant velocity's error over a model's, and the verdict that sets
the paper's code beside ours. A model *learns* where it beats constant velocity by the
verdicts' learning margin (``policy.margin("learning")``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bench.kit import policy

LEARN = policy.margin("learning").value  # the verdicts' gate over the best trivial predictor


def constant_velocity(z: np.ndarray, ts: np.ndarray) -> np.ndarray:
    """q0 + qdot0 t, qdot0, from each window's first state: (N, T, 2d)."""
    d = z.shape[-1] // 2
    q0, v0 = z[:, :1, :d], z[:, :1, d:]
    qt = q0 + v0 * (ts - ts[0])[None, :, None]
    return np.concatenate([qt, np.broadcast_to(v0, qt.shape)], -1)


def scores(pred: np.ndarray, true: np.ndarray, angular) -> dict:
    """The suite's rollout error (angles wrapped, from t = 1) and the paper's (angles as stored,
    t = 0 included), geometric means over windows and times."""
    from bench.core import geometric_mean, relative_error

    ours = relative_error(pred, true, angular)
    paper = relative_error(pred, true, angular, reference_compatible=True)
    return {
        "error": float(geometric_mean(ours[..., 1:])),
        "paper_gerr": float(geometric_mean(paper)),
    }


def stored_ratio(results: Path, cell: dict, model: str, **match) -> tuple[float, int]:
    """From the stored runs of ``cell`` (column -> value, e.g. system and k): the geometric mean
    over seeds of constant velocity's rollout error over ``model``'s in the suite's own form (no
    model options) and ``match`` (e.g. its learning rate), failed runs scored 1 as the verdicts
    score them; and the seeds it rests on."""
    from bench import load_runs
    from bench.core import parse_pairs

    r = load_runs(results)
    for col, value in cell.items():
        r = r[r[col] == value]
    if "model_options" in r:
        r = r[r["model_options"].map(lambda v: not parse_pairs(v))]
    cv = r[r["model"] == "constant_velocity"].groupby("seed")["rollout_error"].first()
    m = r[r["model"] == model]
    for col, value in match.items():
        m = m[m[col] == value]
    err = m["rollout_error"].where(m["status"] == "ok", 1.0).groupby(m["seed"]).first()
    seeds = sorted(set(cv.index) & set(err.index))
    if not seeds:
        return float("nan"), 0
    return float(np.exp(np.mean(np.log(cv[seeds].to_numpy() / err[seeds].to_numpy())))), len(seeds)


def verdict(name: str, system: str, paper: float, stored: float) -> str:
    """Does the paper's code learn where ours does not? Its model on its own data (one seed)
    against our stored runs (the seeds judged): agree where both learn or neither does."""
    if (paper >= LEARN) == (stored >= LEARN):
        both = "learns" if paper >= LEARN else "does not learn"
        return f"verdict: agree: {name} {both} {system} in the paper's code and in ours"
    who = "the paper's code learns it, ours does not" if paper >= LEARN else "ours learns it"
    return f"verdict: DIFFER: {name} on {system}: {who} (gate {LEARN:g}x constant velocity)"


def learns(ratio: float) -> str:
    return f"{ratio:.3g}x {'(learns)' if ratio >= LEARN else '(does not learn)'}"
