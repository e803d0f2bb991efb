"""The verdict rules' shared machinery above the statistics: trivial-predictor discrimination,
the verdict of a claim from its parts, and :func:`evaluate_claims` over the registered studies.
The rules themselves live with their figures (``energy.py``: claim 1, ...); the statistics and
the rules' common conventions are in ``_stats``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ...core._query import experiment_rows, parse_pairs, select
from ...core._studies import studies
from . import policy
from ._common import TRIVIAL_MODELS
from ._stats import (
    INCONCLUSIVE,
    MODEL_LABELS,
    NOT_REPRODUCED,
    PARTLY,
    REPRODUCED,
    WORST_ERROR,
    Gate,
    Verdict,
    _bad,
    _greater,
    _log_per_seed,
    _Part,
    apply_gates,
    gated,
    holm,
    learned,
    required_seeds,
    scored,
    undecided,
)

__all__ = ["claim_studies", "discrimination", "evaluate_claims", "succeeds"]


# ----------------------------------------------------------------------------- trivial baselines


def _variant_key(runs: pd.DataFrame) -> pd.Series:
    """A label per row naming its model variant (model, options, dissipation, coordinates,
    loss, data size and noise where they are not the defaults)."""
    if not len(runs):
        return pd.Series(dtype=object)

    def one(r) -> str:
        s = str(r["model"])
        if r.get("dissipation") is True or r.get("dissipation") == 1.0:
            s += "+rayleigh"
        opts = parse_pairs(r.get("model_options"))
        if opts:
            s += "[" + ",".join(f"{a}={b}" for a, b in sorted(opts.items())) + "]"
        if r.get("coordinates") == "momentum":
            s += " (q,p)"
        if r.get("loss") == "l1":
            s += " L1"
        if "noise" in r and r.get("noise"):
            s += f" noise={float(r['noise']):g}"
        return s

    return runs.apply(one, axis=1)


@dataclass
class _Disc:
    """Whether a group's best model beats the best trivial predictor by the learning margin."""

    group: str
    status: str  # "yes" | "no" | "unknown"
    best: str = ""
    margin: float = math.nan  # min over seeds of log(err trivial / err best)
    trivial: float = math.nan  # mean trivial error

    def text(self) -> str:
        if self.status == "unknown":
            return f"{self.group}: discriminating unknown (no finished trivial-predictor runs)"
        return (
            f"{self.group}: discriminating {self.status} (best {self.best} beats the best "
            f"trivial predictor by {math.exp(self.margin):.3g}x on its worst seed, needs "
            f"{policy.margin('learning').label()})"
        )


def _trivial_log(rows: pd.DataFrame, metric: str = "rollout_error") -> pd.Series:
    """Per-seed log error of the best finished trivial predictor among ``rows``."""
    t = rows[rows["model"].isin(TRIVIAL_MODELS) & ~_bad(rows, metric)] if len(rows) else rows
    if not len(t):
        return pd.Series(dtype=float)
    s = np.log(scored(t, metric))
    return s.groupby([t["seed"], t["model"]]).mean().groupby(level=0).min()


def succeeds(model_log: pd.Series, trivial_log: pd.Series) -> tuple[bool | None, float]:
    """(success, worst-seed log margin): a model succeeds when ``log(trivial / model)`` reaches
    the policy's learning margin on every seed both have; None without paired seeds."""
    m = (trivial_log - model_log).dropna()
    if not len(m):
        return None, math.nan
    worst = float(m.min())
    return bool(worst >= policy.margin("learning").test), worst


def learned_cell(
    rows: pd.DataFrame,
    cell: Mapping,
    label: str | None = None,
    metric: str = "rollout_error",
    trivial: pd.DataFrame | None = None,
    *,
    squared: bool = False,
) -> Gate:
    """The learning gate of one cell of ``rows`` against the best finished trivial predictor
    among ``trivial`` (default: the trivial rows of ``rows``: the same test set); ``squared``
    when ``metric`` is a mean of squares."""
    t = _trivial_log(rows if trivial is None else trivial, metric)
    name = label or MODEL_LABELS.get(str(cell.get("model")), str(cell.get("model")))
    return learned(name, _log_per_seed(rows, cell, metric), t if len(t) else None, squared=squared)


def discrimination(
    rows: pd.DataFrame, group: str, metric: str = "rollout_error", scores: pd.Series | None = None
) -> _Disc:
    """Is ``rows`` (one comparison group, trivial rows included) discriminating? The best model
    is the non-trivial variant with the lowest mean log score (``scores`` overrides the metric,
    e.g. claim 7's velocity-space scores)."""
    if not len(rows):
        return _Disc(group, "unknown")
    sc = scores.reindex(rows.index) if scores is not None else scored(rows, metric)
    # a trivial predictor that failed says nothing about the test set: only finished ones count
    finished = ~_bad(rows, metric if scores is None else "rollout_error")
    is_t = rows["model"].isin(TRIVIAL_MODELS) & finished
    if not is_t.any():
        return _Disc(group, "unknown")
    lt = np.log(sc[is_t]).groupby([rows["seed"][is_t], rows["model"][is_t]]).mean()
    triv = lt.groupby(level=0).min()
    m = rows[~rows["model"].isin(TRIVIAL_MODELS)]
    if not len(m):
        return _Disc(group, "unknown")
    key = _variant_key(m)
    per = np.log(sc[m.index]).groupby([key, m["seed"]]).mean()
    means = per.groupby(level=0).mean().sort_values()
    best = str(means.index[0])
    ok, margin = succeeds(per.loc[best], triv)
    status = "unknown" if ok is None else ("yes" if ok else "no")
    return _Disc(group, status, best, margin, float(np.exp(triv).mean()))


def _verdict(
    claim: int,
    title: str,
    parts: list[_Part],
    headline: _Part | None,
    n_seeds: int,
    effect_name: str,
    extra: str = "",
    *,
    discs: Iterable[_Disc] = (),
    n_failed: int = 0,
    variant: str = "",
    universal: bool = False,
) -> Verdict:
    """Combine a claim's parts. First each part is settled: one tested on fewer seeds than a
    verdict needs is undecided; one with a closed gate reads *not tested*; Holm's correction
    runs across the rest; each part gets its margin ranges. Then: *reproduced* when every part
    holds, *not reproduced* when some contradict and none holds, *partly reproduced* when some
    hold and some contradict (the claim's separate statements), else *inconclusive*; a part
    not tested never counts against the claim. Condition parts (``role == "condition"``) are
    shown, not counted. ``universal``: the parts are instances of one statement over a grid
    ("no gain at any weight"), so one contradicting instance refutes it (*not reproduced*,
    never *partly*)."""
    discs = list(discs)
    need = required_seeds()
    for p in parts:  # a part tested on fewer seeds than a verdict needs decides nothing
        if 0 <= p.n < need and p.status not in ("undecided", "not tested"):
            p.note = (p.note + "; " if p.note else "") + f"{p.status} on {p.n} < {need} seeds"
            p.status = "undecided"
            p.decide = None
    apply_gates(parts)
    holm(parts)
    claim_parts = [p for p in parts if p.role == "part"]
    statuses = [p.status for p in claim_parts]
    not_disc = [d for d in discs if d.status == "no"]
    if discs and all(d.status == "yes" for d in discs):
        discriminating = True
    elif not_disc:
        discriminating = False
    else:
        discriminating = None
    if n_seeds < need or not claim_parts or not_disc:
        verdict = INCONCLUSIVE
    elif all(s == "holds" for s in statuses):
        verdict = REPRODUCED
    elif "contradicts" in statuses:
        verdict = PARTLY if "holds" in statuses and not universal else NOT_REPRODUCED
    else:
        verdict = INCONCLUSIVE
    detail = "; ".join(p.text() for p in parts) or "no runs"
    if not_disc:
        detail = f"NOT DISCRIMINATING ({'; '.join(d.text() for d in not_disc)}); {detail}"
    elif discs:
        detail = f"{detail}; " + "; ".join(d.text() for d in discs)
    if n_seeds < need and parts:
        detail = f"fewer than {need} paired seeds or a missing cell; {detail}"
    if n_failed:
        detail = f"{detail}; {n_failed} failed/diverged runs scored as error {WORST_ERROR:g}"
    if extra:
        detail = f"{detail}; {extra}"
    h = headline or (parts[0] if parts else None)
    return Verdict(
        claim=claim,
        title=title,
        verdict=verdict,
        effect=h.point if h else math.nan,
        ci_low=h.lo if h else math.nan,
        ci_high=h.hi if h else math.nan,
        n_seeds=int(n_seeds),
        detail=detail,
        effect_name=effect_name,
        variant=variant,
        n_failed=int(n_failed),
        discriminating=discriminating,
        parts=tuple(parts),
    )


def _k(k) -> str:
    return "-" if k is None or (isinstance(k, float) and math.isnan(k)) else str(int(k))


# ----------------------------------------------------------------------------- claims

CLAIM_TITLES = {
    1: "HNNs conserve energy no better than NODEs at equal rollout error; violation grows in time",
    2: "A symplectic regulariser gives no real gain at any weight",
    3: "Second-order structure explains most of the HNN's advantage",
    4: "HNN beats NODE+SO only in complex (angular) coordinates",
    5: "Damped: plain HNN fits poorly; NODE+SO matches the damped HNN, cheaper",
    6: "L1 vs L2 loss does not change the ordering of the models",
    7: "Relativistic particle: HNN on (q, qdot) fails; HNN on (q, p) and LNN succeed",
    8: "VIN: bounded energy over long horizons, learns from less/noisier data than a ResNet",
}

HNN_FAMILY = ("hnn", "hnn_so")
FAMILIES = {"NODEs": ("node", "node_so"), "HNNs": ("hnn", "hnn_so")}


def _models(rows: pd.DataFrame) -> pd.DataFrame:
    return rows[~rows["model"].isin(TRIVIAL_MODELS)] if len(rows) else rows


def _per_system_disc(rows: pd.DataFrame, metric: str = "rollout_error") -> list[_Disc]:
    if not len(rows):
        return []
    return [discrimination(g, str(s), metric) for s, g in rows.groupby("system")]


def _cost_part(d: pd.DataFrame, so: Mapping, mix: Mapping, system: str) -> _Part:
    """Claim 5 (c): NODE+SO is cheaper than the mixture HNN: the per-seed
    ``log(train s mixture / train s NODE+SO)`` exceeds the margin (1.25x, a *greater* part);
    contradicted also when NODE+SO's FLOPs per step (where recorded) are not smaller."""
    rs, rm = select(d, **so), select(d, **mix)  # finished runs only: cost of a failure is moot
    name = f"{system}: (c) cost log(train s mixture HNN / NODE+SO)"
    if not len(rs) or not len(rm) or "train_seconds" not in d:
        return undecided(name, "no runs")
    ts = np.log(rs.groupby("seed")["train_seconds"].mean().astype(float))
    tm = np.log(rm.groupby("seed")["train_seconds"].mean().astype(float))
    dt = (tm - ts).dropna()
    flops = math.nan
    if "flops_per_step" in d:
        fs = pd.to_numeric(rs["flops_per_step"], errors="coerce").mean()
        fm = pd.to_numeric(rm["flops_per_step"], errors="coerce").mean()
        if np.isfinite(fs) and np.isfinite(fm) and fm > 0:
            flops = fs / fm
    note = (
        f"FLOPs/step ratio NODE+SO / mixture {flops:.3g}"
        if np.isfinite(flops)
        else "no flops_per_step recorded"
    ) + f"; params {rs['n_params'].mean():.0f} vs {rm['n_params'].mean():.0f}"
    part = _greater(name, dt.to_numpy(), policy.margin("cost"), note=note)
    if np.isfinite(flops) and flops >= 1:  # more FLOPs per step: not cheaper, at any margin
        part.decide = lambda value, alpha: "contradicts"
        part.status = "contradicts"
    return gated(part, learned_cell(d, so), learned_cell(d, mix))


# Claim 1 (b) and claim 8 (c): slopes of log EV against log t over the late half of the horizon.
# Linear growth has slope 1, a bounded oscillation 0; the tolerance around them is the policy's
# slope margin (0.5: a random walk, sqrt t, lies half-way between the two).
LINEAR_SLOPE = 1.0
BOUNDED_SLOPE = 0.0


def _curve_slopes(runs: pd.DataFrame, curves: pd.DataFrame | None, t_min_frac: float = 0.0):
    """Per-run least-squares slope of log(energy_violation) vs log(t), t > t_min_frac * t_max."""
    cols = ["config_hash", "seed", "model", "slope"]
    if curves is None or not len(curves) or not len(runs):
        return pd.DataFrame(columns=cols)
    c = curves[curves["config_hash"].isin(runs["config_hash"])]
    rows = []
    for h, g in c.groupby("config_hash"):
        t = g["t"].to_numpy(float)
        ev = g["energy_violation"].to_numpy(float)
        keep = (t > t_min_frac * t.max()) & (t > 0) & np.isfinite(ev) & (ev > 0)
        if keep.sum() < 3:
            continue
        slope = np.polyfit(np.log(t[keep]), np.log(ev[keep]), 1)[0]
        r = runs[runs["config_hash"] == h].iloc[0]
        rows.append({"config_hash": h, "seed": r["seed"], "model": r["model"], "slope": slope})
    return pd.DataFrame(rows, columns=cols)


def restrict(runs: pd.DataFrame, study, profile: str | None) -> pd.DataFrame:
    """The rows a claim reads: those of its study's experiments (by config hash under
    ``profile``) plus the stored rows tagged with an experiment in ``study.reads`` (results older
    than today's declarations, whose cells no longer expand, still reach the claims that filter
    them). The runs of other experiments that happen to match a claim's field filters, e.g.
    VIN's NODE+SO on the pendulum, are left out."""
    if profile is None or "config_hash" not in runs:
        return runs
    parts = [experiment_rows(runs, exp.name, profile) for exp in study.experiments]
    if "experiment" in runs:
        parts.append(runs[runs["experiment"].isin(study.reads)])
    # ignore_index: experiment_rows resets its index and the tagged rows keep the store's, so
    # labels would repeat (and a rule that aligns on the index would fail)
    return pd.concat(parts, ignore_index=True).drop_duplicates("config_hash") if parts else runs


def restrict_all(runs: pd.DataFrame, profile: str | None) -> dict[int, pd.DataFrame]:
    """``{claim: the rows it reads}`` for every claim study (:func:`restrict`): the rows a
    claim reads do not depend on the seed, so one restriction serves every seed set."""
    return {s.claim: _plain_columns(restrict(runs, s, profile)) for s in claim_studies()}


def _plain_columns(df: pd.DataFrame) -> pd.DataFrame:
    """Arrow-backed string columns as plain objects: the rules slice a table thousands of
    times, and taking rows of Arrow strings costs several times more."""
    cols = {c: object for c in df.columns if pd.api.types.is_string_dtype(df[c].dtype)}
    return df.astype(cols) if cols else df


def runs_at(study, profile: str | None) -> bool:
    """Whether a study's claim is judged at ``profile``: one of its experiments runs there
    (``Experiment.profiles``). Always with no profile."""
    if profile is None or not study.experiments:
        return True
    return any(e.profiles is None or profile in e.profiles for e in study.experiments)


def claims_not_run(profile: str | None) -> list:
    """The claim studies not judged at ``profile`` (:func:`runs_at`), by claim number."""
    return [s for s in claim_studies() if not runs_at(s, profile)]


def claim_studies() -> list:
    """The registered studies with a verdict rule, by claim number."""
    return sorted((s for s in studies() if s.rule is not None), key=lambda s: s.claim)


def evaluate_claims(
    runs: pd.DataFrame,
    curves: pd.DataFrame | None = None,
    profile: str | None = None,
    claims: Iterable[int] | None = None,
    *,
    seeds: Iterable[int] | None = None,
    restricted: Mapping[int, pd.DataFrame] | None = None,
) -> list[Verdict]:
    """Every verdict (claim 4 gives several); a claim whose computation fails is
    "inconclusive" with the error. With ``profile``, each claim sees only the runs of its
    experiments (by config hash, plus older rows tagged with them) and its verdicts carry it;
    a claim whose experiments do not run at ``profile`` has no verdict (:func:`claims_not_run`).
    ``claims``: only these claim numbers; ``seeds``: only these seeds; ``restricted``: each
    claim's rows already restricted (:func:`restrict_all`), for callers that judge one table on
    many seed sets or margins.
    """
    import dataclasses

    out = []
    wanted = None if claims is None else set(claims)
    for study in claim_studies():
        n = study.claim
        if wanted is not None and n not in wanted:
            continue
        if not runs_at(study, profile):
            continue  # e.g. claim 6 at quick: no verdict, not an inconclusive one
        try:
            rows = restricted[n] if restricted is not None else restrict(runs, study, profile)
            if seeds is not None and len(rows) and "seed" in rows:
                rows = rows[rows["seed"].isin(list(seeds))].reset_index(drop=True)
            got = study.rule(rows, curves)
            got = got if isinstance(got, list) else [got]
        except Exception as e:  # noqa: BLE001 - a report must still be written
            got = [
                Verdict(
                    n,
                    CLAIM_TITLES[n],
                    INCONCLUSIVE,
                    math.nan,
                    math.nan,
                    math.nan,
                    0,
                    f"could not evaluate: {type(e).__name__}: {e}",
                )
            ]
        out += [dataclasses.replace(v, profile=profile) for v in got]
    return out
