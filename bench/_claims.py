"""Verdicts on the eight claims of REFERENCE.md, computed from the stored runs.

Every claim is a function ``claim_N(runs, curves=None) -> Verdict``. The runs table is the store's
``results/runs.parquet`` (one row per run: every ``RunConfig`` field and the metrics); the curves
table is ``results/curves.parquet`` (``config_hash, t, rel_error, energy_violation``).

Statistics, shared by all claims:

* Only runs with ``status == "ok"`` and a finite metric enter; the others are counted in ``detail``.
* Comparisons are paired by seed: for two cells A and B (same system, k, ... , different model),
  the per-seed effect is ``d_s = log(err_A,s / err_B,s)``, and the seeds that have both cells are
  the sample. The effect is ``mean_s d_s`` and its 95% interval is a percentile bootstrap over
  seeds (``scipy.stats.bootstrap``, 2000 resamples, fixed generator). With 3 seeds that interval
  is about ``[min_s d_s, max_s d_s]``: "significant" then means every seed agrees.
* A *positive* part ("A is worse than B", an effect expected to be > 0) holds when
  ``ci_low > 0``, contradicts when ``ci_high < delta`` (any effect there is below the smallest
  ratio that matters, ``exp(delta)``), and is undecided otherwise.
* A *null* part ("no real gain") holds when ``ci_high < delta`` (a meaningful gain is ruled out),
  contradicts when ``ci_low > 0`` and the mean exceeds ``delta`` (a significant, meaningful gain),
  and is undecided otherwise.
* A claim is "reproduced" when all its parts hold, "not reproduced" when any part contradicts,
  and "inconclusive" otherwise, or when fewer than two seeds are available.
"""

from __future__ import annotations

import ast
import json
import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import stats

__all__ = [
    "CLAIMS",
    "MODEL_LABELS",
    "Verdict",
    "evaluate_claims",
    "option",
    "params_of",
    "select",
    "synthetic_tables",
]

REPRODUCED = "reproduced"
NOT_REPRODUCED = "not reproduced"
INCONCLUSIVE = "inconclusive"

# Smallest error ratio that "matters": log(1.25). Chosen before looking at results; the paper's
# headline effects (Figs. 4-6) are factors of 2 to 10.
DELTA = math.log(1.25)
# Energy violations and "matching" are judged at a factor of 2.
DELTA_2 = math.log(2.0)

MODEL_LABELS = {
    "node": "NODE",
    "node_so": "NODE+SO",
    "hnn": "HNN",
    "hnn_so": "HNN+SO",
    "hnn_so_diss": "HNN+SO + dissipation",
    "node_symreg": "NODE + symplectic reg.",
    "lnn": "LNN",
    "vin": "VIN",
    "resnet": "ResNet",
}


@dataclass(frozen=True)
class Verdict:
    """The outcome of one claim: ``effect`` (meaning in ``effect_name``) with its 95% CI."""

    claim: int
    title: str
    verdict: str
    effect: float
    ci_low: float
    ci_high: float
    n_seeds: int
    detail: str
    effect_name: str = ""

    def as_row(self) -> dict:
        return {
            "claim": self.claim,
            "title": self.title,
            "verdict": self.verdict,
            "effect": self.effect,
            "effect_name": self.effect_name,
            "ci_low": self.ci_low,
            "ci_high": self.ci_high,
            "n_seeds": self.n_seeds,
            "detail": self.detail,
        }


# ----------------------------------------------------------------------------- table helpers


def _parse_pairs(value) -> dict:
    """``model_options``/``system_params`` as a dict, whatever the store serialised them as."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return {}
    if isinstance(value, Mapping):
        return dict(value)
    if isinstance(value, str):
        text = value.strip()
        if not text:
            return {}
        try:
            value = json.loads(text)
        except ValueError:
            try:
                value = ast.literal_eval(text)
            except (ValueError, SyntaxError):
                return {}
        return _parse_pairs(value)
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, (list, tuple)):
        out = {}
        for item in value:
            if isinstance(item, Mapping):
                out.update(item)
            elif isinstance(item, (list, tuple, np.ndarray)) and len(item) == 2:
                key, v = item[0], item[1]
                out[str(key)] = tuple(v) if isinstance(v, (list, np.ndarray)) else v
        return out
    return {}


def option(runs: pd.DataFrame, name: str, column: str = "model_options") -> pd.Series:
    """The value of option ``name`` in each row's ``column`` (NaN where absent)."""
    if column not in runs:
        return pd.Series(np.nan, index=runs.index)
    return runs[column].map(lambda v: _parse_pairs(v).get(name, np.nan))


def params_of(runs: pd.DataFrame, column: str = "system_params") -> pd.Series:
    """Each row's ``column`` as a dict."""
    if column not in runs:
        return pd.Series([{}] * len(runs), index=runs.index)
    return runs[column].map(_parse_pairs)


def _matches(series: pd.Series, value) -> pd.Series:
    if isinstance(value, (list, tuple, set, frozenset)):
        return series.isin(list(value))
    if value is None:
        return series.isna()
    if isinstance(value, float):
        return np.isclose(series.astype(float), value)
    return series == value


def select(runs: pd.DataFrame, *, ok: bool = True, **fields) -> pd.DataFrame:
    """Rows whose fields equal the given values (a list means "any of").

    Defaults that single out the paper's plain cells are NOT applied here; callers name them.
    ``ok=True`` keeps only finished runs with a finite rollout error.
    """
    mask = pd.Series(True, index=runs.index)
    for name, value in fields.items():
        if name == "dissipation":
            col = runs.get("dissipation", pd.Series(None, index=runs.index))
            if value is None:
                mask &= col.isna()
            else:
                mask &= (
                    col.fillna(-1).astype(object).map(lambda v, t=value: v is not None and v == t)
                )
            continue
        if name not in runs:
            if value is None:
                continue
            return runs.iloc[0:0]
        mask &= _matches(runs[name], value)
    out = runs[mask]
    if ok:
        if "status" in out:
            out = out[out["status"] == "ok"]
        out = out[np.isfinite(out["rollout_error"].astype(float))]
    return out


def plain(runs: pd.DataFrame) -> pd.DataFrame:
    """The paper's default cells: no friction, no noise, (q, qdot), fixed args, default params."""
    out = select(
        runs,
        ok=False,
        friction=0.0,
        noise=0.0,
        coordinates="velocity",
        random_args=False,
    )
    return out[params_of(out).map(len) == 0]


def _n_bad(runs: pd.DataFrame) -> int:
    if "status" not in runs:
        return 0
    return int((runs["status"] != "ok").sum())


# ----------------------------------------------------------------------------- statistics


def _boot(values: np.ndarray, stat: Callable | None = None) -> tuple[float, float, float]:
    """(point, ci_low, ci_high): mean (or ``stat`` of an index sample) with a seed bootstrap."""
    values = np.asarray(values, dtype=float)
    n = len(values)
    if stat is None:
        point = float(np.mean(values)) if n else math.nan
        if n < 2:
            return point, math.nan, math.nan
        if np.ptp(values) == 0:
            return point, point, point
        res = stats.bootstrap(
            (values,),
            np.mean,
            n_resamples=2000,
            method="percentile",
            rng=np.random.default_rng(0),
        )
        return point, float(res.confidence_interval.low), float(res.confidence_interval.high)
    idx = np.arange(n, dtype=float)
    point = float(stat(idx.astype(int)))
    if n < 2:
        return point, math.nan, math.nan
    res = stats.bootstrap(
        (idx,),
        lambda s: stat(np.asarray(s).astype(int)),
        n_resamples=999,
        method="percentile",
        vectorized=False,
        rng=np.random.default_rng(0),
    )
    lo, hi = float(res.confidence_interval.low), float(res.confidence_interval.high)
    if not np.isfinite(lo):  # a degenerate bootstrap distribution (all resamples equal)
        lo = hi = point
    return point, lo, hi


def _paired(runs: pd.DataFrame, a: Mapping, b: Mapping, metric: str = "rollout_error") -> pd.Series:
    """Per-seed ``log(metric_A / metric_B)`` over the seeds that have both cells."""
    ra = select(runs, **a)
    rb = select(runs, **b)
    va = np.log(ra.groupby("seed")[metric].mean().astype(float))
    vb = np.log(rb.groupby("seed")[metric].mean().astype(float))
    d = (va - vb).dropna()
    return d[np.isfinite(d)]


@dataclass
class _Part:
    name: str
    status: str  # "holds" | "contradicts" | "undecided"
    point: float
    lo: float
    hi: float
    n: int
    note: str = ""
    extra: dict = field(default_factory=dict)

    def text(self) -> str:
        ci = f"[{self.lo:.3g}, {self.hi:.3g}]" if np.isfinite(self.lo) else "[n/a]"
        s = f"{self.name}: {self.point:.3g} {ci}, n={self.n} -> {self.status}"
        return s + (f" ({self.note})" if self.note else "")


def _positive(name: str, d: Iterable[float] | tuple, delta: float = DELTA, note="") -> _Part:
    point, lo, hi = d if isinstance(d, tuple) else _boot(np.asarray(list(d), dtype=float))
    n = -1 if isinstance(d, tuple) else len(list(d))
    if not np.isfinite(point) or not np.isfinite(lo):
        status = "undecided"
    elif lo > 0:
        status = "holds"
    elif hi < delta:
        status = "contradicts"
    else:
        status = "undecided"
    return _Part(name, status, point, lo, hi, n, note)


def _null(name: str, d, delta: float = DELTA, note="") -> _Part:
    point, lo, hi = d if isinstance(d, tuple) else _boot(np.asarray(list(d), dtype=float))
    n = -1 if isinstance(d, tuple) else len(list(d))
    if not np.isfinite(point) or not np.isfinite(lo):
        status = "undecided"
    elif lo > 0 and point > delta:
        status = "contradicts"
    elif hi < delta:
        status = "holds"
    else:
        status = "undecided"
    return _Part(name, status, point, lo, hi, n, note)


def _verdict(
    claim: int,
    title: str,
    parts: list[_Part],
    headline: _Part | None,
    n_seeds: int,
    effect_name: str,
    extra: str = "",
) -> Verdict:
    statuses = [p.status for p in parts]
    if n_seeds < 2 or not parts:
        verdict = INCONCLUSIVE
    elif "contradicts" in statuses:
        verdict = NOT_REPRODUCED
    elif all(s == "holds" for s in statuses):
        verdict = REPRODUCED
    else:
        verdict = INCONCLUSIVE
    detail = "; ".join(p.text() for p in parts) or "no runs"
    if n_seeds < 2 and parts:
        detail = f"fewer than 2 seeds; {detail}"
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
    )


def _k(k) -> str:
    return "-" if k is None or (isinstance(k, float) and math.isnan(k)) else str(int(k))


# ----------------------------------------------------------------------------- claims

CLAIM_TITLES = {
    1: "HNNs conserve energy no better than NODEs at equal rollout error; violation grows in time",
    2: "A symplectic regulariser gives no real gain at any weight",
    3: "Second-order structure explains most of the HNN's advantage",
    4: "HNN beats NODE+SO only in complex (angular) coordinates",
    5: "Damped: plain HNN fits poorly; NODE+SO matches HNN + dissipation, cheaper",
    6: "L1 vs L2 loss does not change the ordering of the models",
    7: "Relativistic particle: HNN on (q, qdot) fails; HNN on (q, p) and LNN succeed",
    8: "VIN: bounded energy over long horizons, learns from less/noisier data than a ResNet",
}

PAPER_MODELS = ("node", "node_so", "hnn", "hnn_so")
HNN_FAMILY = ("hnn", "hnn_so")


def energy_cells(runs: pd.DataFrame) -> pd.DataFrame:
    """Fig. 2 cells: the four paper models on undamped chain/spring, any k, L2 loss."""
    p = plain(runs)
    return select(
        p, system=["chain_pendulum", "spring_pendulum"], model=list(PAPER_MODELS), loss="l2"
    )


def _curve_slopes(runs: pd.DataFrame, curves: pd.DataFrame | None, t_min_frac: float = 0.0):
    """Per-run least-squares slope of log(energy_violation) vs log(t), t > t_min_frac * t_max."""
    if curves is None or not len(curves) or not len(runs):
        return pd.DataFrame(columns=["config_hash", "seed", "model", "slope"])
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
    return pd.DataFrame(rows, columns=["config_hash", "seed", "model", "slope"])


def claim_1(runs: pd.DataFrame, curves: pd.DataFrame | None = None) -> Verdict:
    """Claim 1 (Fig. 2). Two parts.

    (a) Energy at equal error: over the Fig. 2 cells, fit by least squares
    ``log EV = a + b log(rollout_error) + c [model is an HNN] (+ one intercept per system)``;
    the HNN advantage is ``-c`` (how much lower an HNN's log energy violation is than a NODE's at
    the same rollout error). Bootstrap resamples whole seeds. A *null* part at ``delta = log 2``:
    holds when a 2x advantage is ruled out, contradicts when the advantage is significant and
    above 2x.
    (b) Growth in time: for every NODE/HNN run with a stored curve, the slope of
    ``log EV`` against ``log t``; the per-seed mean slope must be > 0 (a *positive* part with
    ``delta = 0.1``). Without curves this part is undecided.
    """
    cells = energy_cells(runs)
    cells = cells[np.isfinite(cells["energy_violation"].astype(float))]
    cells = cells[(cells["energy_violation"] > 0) & (cells["rollout_error"] > 0)]
    seeds = np.sort(cells["seed"].unique())
    parts: list[_Part] = []
    extra = ""
    if (
        len(cells)
        and cells["model"].isin(HNN_FAMILY).any()
        and (~cells["model"].isin(HNN_FAMILY)).any()
    ):
        systems = sorted(cells["system"].unique())

        def design(df: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
            cols = [np.log(df["rollout_error"].to_numpy(float))]
            cols.append(df["model"].isin(HNN_FAMILY).to_numpy(float))
            for s in systems:
                cols.append((df["system"] == s).to_numpy(float))
            return np.stack(cols, axis=1), np.log(df["energy_violation"].to_numpy(float))

        by_seed = [design(cells[cells["seed"] == s]) for s in seeds]

        def stat(idx) -> float:
            x = np.concatenate([by_seed[i][0] for i in idx])
            y = np.concatenate([by_seed[i][1] for i in idx])
            coef, *_ = np.linalg.lstsq(x, y, rcond=None)
            return -float(coef[1])

        point, lo, hi = _boot(np.arange(len(seeds)), stat)
        a = _null("HNN energy advantage at equal error, -c (log)", (point, lo, hi), DELTA_2)
        a.n = len(seeds)
        parts.append(a)
        x = np.log(cells["rollout_error"].to_numpy(float))
        y = np.log(cells["energy_violation"].to_numpy(float))
        r = np.corrcoef(x, y)[0, 1] if len(x) > 2 else math.nan
        extra = f"corr(log err, log EV) = {r:.2f} over {len(cells)} runs"
    sl = _curve_slopes(cells, curves)
    if len(sl):
        per_seed = sl.groupby("seed")["slope"].mean()
        parts.append(_positive("slope of log EV vs log t", per_seed.to_numpy(), 0.1))
    else:
        parts.append(
            _Part(
                "slope of log EV vs log t",
                "undecided",
                math.nan,
                math.nan,
                math.nan,
                0,
                "no curves",
            )
        )
    n_bad = _n_bad(energy_cells(select(runs, ok=False)))
    if n_bad:
        extra += f"; {n_bad} runs not ok excluded"
    return _verdict(
        1,
        CLAIM_TITLES[1],
        parts,
        parts[0],
        len(seeds),
        "-c: log EV advantage of HNNs at equal error",
        extra,
    )


def claim_2(runs: pd.DataFrame, curves: pd.DataFrame | None = None) -> Verdict:
    """Claim 2 (Fig. 3): ``node_symreg`` on the chain pendulum, regulariser weight ``w``.

    For every weight ``w > 0`` the gain is the per-seed ``log(err_{w=0} / err_w)`` (same system
    and k). A *null* part per weight (``delta = log 1.25``): the claim holds when no weight gives
    a significant gain above 25% and every weight rules one out. The headline effect is the
    gain of the best weight.
    """
    p = plain(runs)
    sr = select(p, model="node_symreg")
    if not len(sr):
        return _verdict(2, CLAIM_TITLES[2], [], None, 0, "log(err_0 / err_w), best w")
    sr = sr.assign(weight=option(sr, "weight").astype(float))
    parts = []
    seeds: set = set()
    for (system, k), g in sr.groupby(["system", "k"], dropna=False):
        base = g[g["weight"] == 0].groupby("seed")["rollout_error"].mean()
        for w, gw in g[g["weight"] > 0].groupby("weight"):
            d = (np.log(base) - np.log(gw.groupby("seed")["rollout_error"].mean())).dropna()
            seeds |= set(d.index)
            parts.append(_null(f"{system} k={_k(k)} w={w:g}: gain", d.to_numpy()))
    best = max(parts, key=lambda q: q.point) if parts else None
    return _verdict(
        2, CLAIM_TITLES[2], parts, best, len(seeds), "log(err_0 / err_w) of the best weight"
    )


def claim_3(runs: pd.DataFrame, curves: pd.DataFrame | None = None) -> Verdict:
    """Claim 3 (Fig. 4): on undamped chain and spring (k = 2 where present, else all k),
    ``log(err NODE / err NODE+SO)`` and ``log(err HNN / err HNN+SO)`` per seed, averaged over
    the systems present; each is a *positive* part (``delta = log 1.25``). Headline: the
    per-seed mean of both log-ratios."""
    p = select(plain(runs), loss="l2", ok=False)
    ks = p["k"].dropna().unique() if "k" in p else []
    k = 2 if 2 in set(ks) else None
    base = {"k": k} if k is not None else {}
    pairs = {"NODE/NODE+SO": ("node", "node_so"), "HNN/HNN+SO": ("hnn", "hnn_so")}
    parts, per_pair = [], {}
    notes = []
    for name, (a, b) in pairs.items():
        ds = []
        for system in ("chain_pendulum", "spring_pendulum"):
            d = _paired(
                p, {**base, "system": system, "model": a}, {**base, "system": system, "model": b}
            )
            if len(d):
                ds.append(d)
                notes.append(f"{system} {name}: {d.mean():.3g}")
        if not ds:
            continue
        d = pd.concat(ds, axis=1).dropna().mean(axis=1)
        per_pair[name] = d
        parts.append(_positive(f"log {name}", d.to_numpy()))
    if len(per_pair) == 2:
        both = pd.concat(per_pair.values(), axis=1).dropna().mean(axis=1)
        head = _positive("mean of both", both.to_numpy())
    else:
        head = parts[0] if parts else None
    n = min((len(d) for d in per_pair.values()), default=0)
    if len(parts) < 2:
        parts.append(_Part("missing comparison", "undecided", math.nan, math.nan, math.nan, 0))
    return _verdict(
        3,
        CLAIM_TITLES[3],
        parts,
        head,
        n,
        "mean log error ratio (without SO / with SO)",
        ", ".join(notes),
    )


def claim_4(runs: pd.DataFrame, curves: pd.DataFrame | None = None) -> Verdict:
    """Claim 4 (Fig. 5): edge of HNN+SO over NODE+SO, ``e = log(err NODE+SO / err HNN+SO)``
    per seed (k = 2 where present).

    Chain pendulum (angles): a *positive* part. Spring pendulum (Cartesian): the HNN must not keep
    a significant, meaningful edge: contradicts when ``ci_low > 0`` and the mean exceeds
    ``log 1.25``, holds otherwise (when at least two seeds exist). Headline: the spring edge
    minus the chain edge (negative when the edge shrinks in simple coordinates).
    """
    p = select(plain(runs), loss="l2", ok=False)
    k = 2 if "k" in p and 2 in set(p["k"].dropna()) else None
    base = {"k": k} if k is not None else {}
    dc = _paired(
        p,
        {**base, "system": "chain_pendulum", "model": "node_so"},
        {**base, "system": "chain_pendulum", "model": "hnn_so"},
    )
    ds = _paired(
        p,
        {**base, "system": "spring_pendulum", "model": "node_so"},
        {**base, "system": "spring_pendulum", "model": "hnn_so"},
    )
    parts = [_positive("chain edge log(NODE+SO/HNN+SO)", dc.to_numpy())]
    point, lo, hi = _boot(ds.to_numpy())
    if len(ds) < 2:
        status = "undecided"
    elif lo > 0 and point > DELTA:
        status = "contradicts"
    else:
        status = "holds"
    parts.append(_Part("spring edge log(NODE+SO/HNN+SO)", status, point, lo, hi, len(ds)))
    both = pd.concat([ds, dc], axis=1).dropna()
    diff = (both.iloc[:, 0] - both.iloc[:, 1]).to_numpy() if len(both) else np.array([])
    hp, hl, hh = _boot(diff)
    head = _Part("spring edge - chain edge", "", hp, hl, hh, len(diff))
    return _verdict(
        4, CLAIM_TITLES[4], parts, head, min(len(dc), len(ds)), "spring edge minus chain edge (log)"
    )


def claim_5(runs: pd.DataFrame, curves: pd.DataFrame | None = None) -> Verdict:
    """Claim 5 (Fig. 6): damped chain and spring (friction > 0, k = 2 where present).

    Parts, per system: (a) *positive*: ``log(err HNN+SO plain / err NODE+SO)`` (the plain HNN,
    ``dissipation=False``, fits worse); (b) NODE+SO matches HNN+SO with dissipation: contradicts
    when ``log(err NODE+SO / err HNN+diss)`` has ``ci_low > 0`` and a mean above ``log 2``, holds
    otherwise; (c) NODE+SO has fewer parameters and a smaller mean training time (holds or
    contradicts). Headline: (a) averaged over systems per seed.
    """
    d = select(runs, ok=False, noise=0.0, coordinates="velocity", loss="l2")
    d = d[d["friction"].astype(float) > 0]
    k = 2 if "k" in d and 2 in set(d["k"].dropna()) else None
    base = {"k": k} if k is not None else {}
    parts, heads, seeds = [], [], []
    for system in ("chain_pendulum", "spring_pendulum"):
        s = {**base, "system": system}
        plain_hnn = {**s, "model": "hnn_so", "dissipation": False}
        diss = {**s, "model": "hnn_so", "dissipation": True}
        so = {**s, "model": "node_so"}
        a = _paired(d, plain_hnn, so)
        b = _paired(d, so, diss)
        if not len(a) and not len(b):
            continue
        heads.append(a)
        seeds.append(min(len(a), len(b)))
        parts.append(_positive(f"{system}: log(HNN plain / NODE+SO)", a.to_numpy()))
        bp, bl, bh = _boot(b.to_numpy())
        st = "undecided" if len(b) < 2 else ("contradicts" if bl > 0 and bp > DELTA_2 else "holds")
        parts.append(_Part(f"{system}: log(NODE+SO / HNN+diss)", st, bp, bl, bh, len(b)))
        rs, rd = select(d, **so), select(d, **diss)
        if len(rs) and len(rd):
            np_so, np_d = rs["n_params"].mean(), rd["n_params"].mean()
            t_so, t_d = rs["train_seconds"].mean(), rd["train_seconds"].mean()
            ok = np_so < np_d and t_so < t_d
            parts.append(
                _Part(
                    f"{system}: cost NODE+SO vs HNN+diss",
                    "holds" if ok else "contradicts",
                    float(np.log(t_so / t_d)),
                    math.nan,
                    math.nan,
                    len(rs),
                    f"params {np_so:.0f} vs {np_d:.0f}, train {t_so:.1f}s vs {t_d:.1f}s",
                )
            )
    head = None
    if heads:
        h = pd.concat(heads, axis=1).dropna().mean(axis=1).to_numpy()
        head = _positive("mean log(HNN plain / NODE+SO)", h)
    if not parts:
        return _verdict(5, CLAIM_TITLES[5], [], None, 0, "log(err HNN plain / err NODE+SO)")
    return _verdict(5, CLAIM_TITLES[5], parts, head, min(seeds), "log(err HNN plain / err NODE+SO)")


def claim_6(runs: pd.DataFrame, curves: pd.DataFrame | None = None) -> Verdict:
    """Claim 6 (Fig. 8): the four paper models on the chain pendulum trained with L1 and L2.

    For each loss and each pair of models the per-seed log error ratio is bootstrapped; a pair is
    *ordered* under a loss when its CI excludes 0. The claim contradicts when some pair is
    ordered in opposite directions under the two losses, holds when at least one pair is ordered
    the same way under both and none is reversed, and is undecided otherwise. Headline: Kendall's
    tau between the two rankings of mean log error (bootstrapped over seeds, paired).
    """
    p = select(plain(runs), system="chain_pendulum", model=list(PAPER_MODELS), ok=True)
    k = 2 if "k" in p and 2 in set(p["k"].dropna()) else None
    if k is not None:
        p = p[p["k"] == k]
    if not len(p) or set(p["loss"].unique()) < {"l1", "l2"}:
        return _verdict(6, CLAIM_TITLES[6], [], None, 0, "Kendall tau L1 vs L2 ranking")
    table = p.assign(le=np.log(p["rollout_error"].astype(float))).pivot_table(
        index="seed", columns=["loss", "model"], values="le", aggfunc="mean"
    )
    models = [m for m in PAPER_MODELS if ("l1", m) in table and ("l2", m) in table]
    table = table[[(loss, m) for loss in ("l1", "l2") for m in models]].dropna()
    n = len(table)
    if n == 0 or len(models) < 2:
        return _verdict(6, CLAIM_TITLES[6], [], None, 0, "Kendall tau L1 vs L2 ranking")
    arr = table.to_numpy().reshape(n, 2, len(models))

    def tau(idx):
        # Kendall's tau-a: mean over model pairs of the product of the two orderings' signs.
        m = arr[idx].mean(axis=0)
        iu = np.triu_indices(m.shape[1], 1)
        s0 = np.sign(m[0][:, None] - m[0][None, :])[iu]
        s1 = np.sign(m[1][:, None] - m[1][None, :])[iu]
        return float(np.mean(s0 * s1))

    tp, tl, th = _boot(np.arange(n), tau)
    same, reversed_, unresolved = [], [], []
    for i in range(len(models)):
        for j in range(i + 1, len(models)):
            signs = []
            for li in range(2):
                d = arr[:, li, i] - arr[:, li, j]
                _, lo, hi = _boot(d)
                signs.append(0 if not np.isfinite(lo) or lo <= 0 <= hi else int(np.sign(lo)))
            name = f"{MODEL_LABELS[models[i]]}/{MODEL_LABELS[models[j]]}"
            if signs[0] and signs[1] and signs[0] != signs[1]:
                reversed_.append(name)
            elif signs[0] and signs[0] == signs[1]:
                same.append(name)
            else:
                unresolved.append(name)
    status = "contradicts" if reversed_ else ("holds" if same and n >= 2 else "undecided")
    change = np.abs(arr[:, 0, :] - arr[:, 1, :]).mean()
    part = _Part(
        "ordering",
        status,
        tp,
        tl,
        th,
        n,
        f"same order: {', '.join(same) or '-'}; reversed: {', '.join(reversed_) or '-'}; "
        f"unresolved: {', '.join(unresolved) or '-'}; mean |log(err L1 / err L2)| = {change:.3g}",
    )
    return _verdict(6, CLAIM_TITLES[6], [part], part, n, "Kendall tau of L1 vs L2 rankings")


def claim_7(runs: pd.DataFrame, curves: pd.DataFrame | None = None) -> Verdict:
    """Claim 7 (LNN seed): relativistic particle with per-trajectory g.

    *Positive* parts (``delta = log 1.25``): ``log(err HNN(q, qdot) / err HNN(q, p))`` and
    ``log(err HNN(q, qdot) / err LNN(q, qdot))``. Headline: the smaller of the two means.
    """
    r = select(runs, ok=False, system="relativistic_particle", noise=0.0)
    vel = {"model": "hnn", "coordinates": "velocity"}
    a = _paired(r, vel, {"model": "hnn", "coordinates": "momentum"})
    b = _paired(r, vel, {"model": "lnn", "coordinates": "velocity"})
    parts = [
        _positive("log(HNN(q,qdot) / HNN(q,p))", a.to_numpy()),
        _positive("log(HNN(q,qdot) / LNN)", b.to_numpy()),
    ]
    head = min(parts, key=lambda q: q.point if np.isfinite(q.point) else math.inf)
    return _verdict(
        7, CLAIM_TITLES[7], parts, head, min(len(a), len(b)), "log error ratio, weaker of the two"
    )


def claim_8(runs: pd.DataFrame, curves: pd.DataFrame | None = None) -> Verdict:
    """Claim 8 (VIN seed): VIN vs ResNet on the pendulum (chain, k = 1) over a long horizon.

    Parts: (a) *positive*: ``log(err ResNet / err VIN)`` at the smallest ``n_train`` (each noise
    level a part); (b) *positive*: ``log(EV ResNet / EV VIN)`` at the same cells; (c) bounded
    energy: the per-seed slope of ``log EV`` vs ``log t`` over the second half of VIN's curves
    is below 0.5 (holds when ``ci_high < 0.5``, contradicts when ``ci_low > 0.5``; a bounded
    oscillation has slope ~0, a linear drift slope 1). Headline: (a) at zero noise.
    """
    v = select(runs, ok=False, system="chain_pendulum", k=1, friction=0.0, model=["vin", "resnet"])
    if not len(v):
        return _verdict(8, CLAIM_TITLES[8], [], None, 0, "log(err ResNet / err VIN), fewest data")
    n_min = v["n_train"].min()
    parts, ns = [], []
    head = None
    for noise, g in v[v["n_train"] == n_min].groupby("noise"):
        a = _paired(g, {"model": "resnet"}, {"model": "vin"})
        e = _paired(g, {"model": "resnet"}, {"model": "vin"}, metric="energy_violation")
        pa = _positive(f"n_train={n_min} noise={noise:g}: log(err ResNet / VIN)", a.to_numpy())
        parts.append(pa)
        parts.append(
            _positive(f"n_train={n_min} noise={noise:g}: log(EV ResNet / VIN)", e.to_numpy())
        )
        ns.append(len(a))
        if head is None:
            head = pa
    vin_runs = select(v, model="vin")
    sl = _curve_slopes(vin_runs, curves, t_min_frac=0.5)
    if len(sl):
        ps = sl.groupby("seed")["slope"].mean().to_numpy()
        sp, slo, shi = _boot(ps)
        st = (
            "undecided"
            if len(ps) < 2
            else ("holds" if shi < 0.5 else ("contradicts" if slo > 0.5 else "undecided"))
        )
        parts.append(_Part("VIN late slope of log EV vs log t", st, sp, slo, shi, len(ps)))
    else:
        parts.append(
            _Part(
                "VIN late energy slope", "undecided", math.nan, math.nan, math.nan, 0, "no curves"
            )
        )
    return _verdict(
        8,
        CLAIM_TITLES[8],
        parts,
        head,
        min(ns, default=0),
        "log(err ResNet / err VIN), fewest data",
    )


CLAIMS: dict[int, Callable[..., Verdict]] = {
    1: claim_1,
    2: claim_2,
    3: claim_3,
    4: claim_4,
    5: claim_5,
    6: claim_6,
    7: claim_7,
    8: claim_8,
}


# The experiments whose runs each claim reads (the runs of other experiments that happen to
# match a claim's field filters, e.g. VIN's NODE+SO on the pendulum, are left out).
CLAIM_EXPERIMENTS = {
    1: ("energy",),
    2: ("symplectic",),
    3: ("second_order",),
    4: ("coordinates",),
    5: ("damped",),
    6: ("loss",),
    7: ("relativistic",),
    8: ("vin",),
}


def _restrict(runs: pd.DataFrame, claim: int, profile: str | None) -> pd.DataFrame:
    if profile is None or "config_hash" not in runs:
        return runs
    from ._figures import experiment_rows

    parts = [experiment_rows(runs, name, profile) for name in CLAIM_EXPERIMENTS[claim]]
    return pd.concat(parts).drop_duplicates("config_hash") if parts else runs


def evaluate_claims(
    runs: pd.DataFrame, curves: pd.DataFrame | None = None, profile: str | None = None
) -> list[Verdict]:
    """All eight verdicts; a claim whose computation fails is "inconclusive" with the error.

    With ``profile``, each claim sees only the runs of its experiments (by config hash).
    """
    out = []
    for n, fn in CLAIMS.items():
        try:
            out.append(fn(_restrict(runs, n, profile), curves))
        except Exception as e:  # noqa: BLE001 - a report must still be written
            out.append(
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
            )
    return out


# ----------------------------------------------------------------------------- synthetic tables


def _synthetic_error(c, contradict: bool) -> tuple[float, float]:
    """(geometric-mean rollout error, energy violation / error) of a synthetic cell."""
    w = _parse_pairs(c.model_options).get("weight")
    k = c.k or 1
    if c.system == "relativistic_particle":
        table = {("hnn", "velocity"): 0.3, ("hnn", "momentum"): 0.02, ("lnn", "velocity"): 0.03}
        if contradict:
            table = {("hnn", "velocity"): 0.01, ("hnn", "momentum"): 0.1, ("lnn", "velocity"): 0.1}
        return table.get((c.model, c.coordinates), 0.1), 0.3
    if c.model in ("vin", "resnet") or (c.test_chunks >= 50 and c.k == 1):
        r = 128 / c.n_train
        err = {"vin": 0.02 * r**0.3, "resnet": 0.1 * r**0.6, "node_so": 0.05 * r**0.5}[c.model]
        if contradict and c.model in ("vin", "resnet"):
            err = {"vin": 0.2, "resnet": 0.02}[c.model]
        return err * (1 + 10 * c.noise), 0.3 if c.model == "vin" else 1.0
    if c.friction > 0:
        m = "hnn_diss" if c.dissipation else c.model
        table = {"node": 0.08, "node_so": 0.03, "hnn_so": 0.3, "hnn_diss": 0.028}
        if contradict:
            table = {"node": 0.08, "node_so": 0.1, "hnn_so": 0.01, "hnn_diss": 0.01}
        return table[m], 0.3
    if c.model == "node_symreg":
        base = 0.097
        if w and contradict:
            return base / 3, 0.3
        return (base * 1.5 if w and w >= 10 else base), 0.3
    if c.model == "lnn":
        return 0.02, 0.05
    table = {
        ("chain_pendulum", False): {"node": 0.097, "node_so": 0.059, "hnn": 0.05, "hnn_so": 0.013},
        ("spring_pendulum", False): {"node": 0.036, "node_so": 0.015, "hnn": 0.03, "hnn_so": 0.018},
        ("chain_pendulum", True): {"node": 0.05, "node_so": 0.1, "hnn": 0.05, "hnn_so": 0.2},
        ("spring_pendulum", True): {"node": 0.01, "node_so": 0.05, "hnn": 0.01, "hnn_so": 0.005},
    }
    err = table[(c.system, contradict)][c.model] * 1.5 ** (k - 2)
    if c.loss == "l1":
        err = 1e-4 / err if contradict else err * 1.1
    ratio = 0.003 if contradict and c.model in HNN_FAMILY else 0.3
    return err, ratio


def synthetic_tables(
    profile: str = "smoke",
    *,
    seeds: Iterable[int] = (0, 1, 2),
    noise: float = 0.05,
    contradict: bool = False,
    rng: int = 0,
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """(runs, curves) in the store's format for every paper experiment, WITHOUT training.

    A fixture for tests and demos of the figures, verdicts and report: the errors follow the
    calibration of REFERENCE.md (``contradict=False``: every claim holds by construction) or
    its reversal (``contradict=True``), times ``exp(noise * N(0, 1))`` per run. No number of
    it is a result.
    """
    from . import _store
    from ._experiments import expand
    from ._paper import PAPER_EXPERIMENTS

    gen = np.random.default_rng(rng)
    seeds = tuple(seeds)
    rows, seen = [], set()
    for exp in PAPER_EXPERIMENTS:
        for c0 in expand(exp, profile):
            if c0.seed != min(c0.seed, 0):  # expand once per cell, then add our seeds
                continue
            for s in seeds:
                c = type(c0)(**{**c0.to_dict(), "seed": s})
                if c.config_hash in seen:
                    continue
                seen.add(c.config_hash)
                err, ratio = _synthetic_error(c, contradict)
                err *= math.exp(noise * gen.standard_normal())
                ev = ratio * err * math.exp(noise * gen.standard_normal())
                t = c.dt * np.arange(1, c.chunk * c.test_chunks + 1)
                growth = t / t.mean()
                if contradict and c.model in HNN_FAMILY:
                    growth = 1 / growth
                if c.model == "vin":
                    growth = (1.0 + 0.2 * np.sin(t)) if not contradict else growth
                ev_t = ev * growth * np.exp(noise * gen.standard_normal(len(t)))
                q = np.sin(t)[:, None] * np.ones((1, 2 * max(1, c.k or 1)))
                w = _parse_pairs(c.model_options).get("weight", 0.0)
                row = c.to_dict()
                row.update(
                    config_hash=c.config_hash,
                    train_hash=c.train_hash,
                    experiment=exp.name,
                    profile=profile,
                    status="ok",
                    diverged_step=None,
                    error=None,
                    rollout_error=err,
                    energy_violation=ev,
                    mse=err**2,
                    valid_time=1.0 / err,
                    floor_error=1e-5,
                    energy_pct_max_pe=100 * ev,
                    symplectic_error=1.0 / (1.0 + 100 * w) if c.model == "node_symreg" else 1.0,
                    train_seconds=(40.0 if c.model.startswith("hnn") else 10.0) + 5 * s,
                    compile_seconds=3.0,
                    rollout_seconds=0.5,
                    nfe=4 * len(t),
                    n_params=(40_000 if c.dissipation else 30_000)
                    if c.model.startswith("hnn")
                    else 20_000,
                    curves={
                        "t": t,
                        "rel_error": err * growth,
                        "energy_violation": ev_t,
                        "z_true": q,
                        "z_pred": q * (1 + err),
                    },
                )
                rows.append(row)
    rows = [_store._jsonable(r) for r in rows]
    return _store.rows_frame(rows), _store.curves_frame(rows)
