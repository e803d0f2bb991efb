"""The one query layer over the stored tables (``runs.parquet``, ``curves.parquet``).

Loading the tables of a results folder, finding an experiment's rows, selecting rows by field
values, and reading the serialised ``model_options``/``system_params`` columns. Studies, the
report and the CLI read stored runs only through these functions.
"""

from __future__ import annotations

import ast
import json
import math
from collections.abc import Mapping, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path

import numpy as np
import pandas as pd

import models

from . import _store


def parse_pairs(value) -> dict:
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
        return parse_pairs(value)
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
    return runs[column].map(lambda v: parse_pairs(v).get(name, np.nan))


def params_of(runs: pd.DataFrame, column: str = "system_params") -> pd.Series:
    """Each row's ``column`` as a dict."""
    if column not in runs:
        return pd.Series([{}] * len(runs), index=runs.index)
    return runs[column].map(parse_pairs)


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
    """The paper's default cells: no friction, no noise, (q, qdot), fixed args, and no system
    params other than the spring pendulum's ``initial`` state."""
    out = select(
        runs,
        ok=False,
        friction=0.0,
        noise=0.0,
        coordinates="velocity",
        random_args=False,
    )
    return out[params_of(out).map(lambda p: set(p) <= {"initial"})]


def initial_state(runs: pd.DataFrame) -> pd.Series:
    """The spring pendulum's initial state per row: ``"paper"`` or ``"equilibrium"`` (rows
    without the parameter predate it and started from the physical equilibrium)."""
    return params_of(runs).map(lambda p: p.get("initial", "equilibrium"))


def labelled(runs: pd.DataFrame, profile: str | None) -> pd.Series:
    """Whether each row's ``profile`` label speaks for ``profile`` (``speaking_profiles``;
    unlabelled rows always do)."""
    from ._experiments import speaking_profiles

    if "profile" not in runs or profile is None:
        return pd.Series(True, index=runs.index)
    col = runs["profile"]
    return col.isna() | col.isin(list(speaking_profiles(profile)))


def profile_counts(runs: pd.DataFrame) -> dict[str, int]:
    """Rows per ``profile`` label, the most first (empty where the rows carry none)."""
    if "profile" not in runs or not len(runs):
        return {}
    return {str(k): int(v) for k, v in runs["profile"].value_counts().items()}


def describe_profiles(runs: pd.DataFrame) -> str:
    """The profiles of ``runs`` and their row counts: ``quick (310 rows), smoke (12 rows)``."""
    counts = profile_counts(runs)
    if not counts:
        return "no profile labels"
    return ", ".join(f"{p} ({n} row{'s' if n != 1 else ''})" for p, n in counts.items())


# The profile a report or figure run was asked for, per results folder (:func:`chosen_profile`)
_CHOSEN: ContextVar[tuple[Path, str] | None] = ContextVar("chosen_profile", default=None)


@contextmanager
def chosen_profile(results_dir: Path, profile: str | None):
    """Within the block, :func:`load_tables` and :func:`pick_profile` of ``results_dir`` (and
    of no other folder) take ``profile`` instead of the one with the most rows: the sections and
    figures that read the folder themselves show the profile the report was asked for."""
    if profile is None:
        yield
        return
    token = _CHOSEN.set((Path(results_dir).resolve(), profile))
    try:
        yield
    finally:
        _CHOSEN.reset(token)


def _chosen_for(results_dir) -> str | None:
    chosen = _CHOSEN.get()
    if chosen is None or results_dir is None:
        return None
    return chosen[1] if Path(results_dir).resolve() == chosen[0] else None


def check_profile(runs: pd.DataFrame, profile: str, where) -> None:
    """Raise ValueError (one line naming the profiles present) unless rows of ``profile``
    are stored in ``runs``."""
    if profile not in profile_counts(runs):
        raise ValueError(
            f"no runs of profile {profile!r} in {where}; it holds {describe_profiles(runs)}"
        )


def pick_profile(runs: pd.DataFrame, results_dir: Path | None = None) -> str | None:
    """The profile whose runs the figures show: the one with the most rows (None if untagged),
    or the one chosen for ``results_dir`` (:func:`chosen_profile`) where its rows are stored."""
    if "profile" not in runs or not len(runs) or runs["profile"].isna().all():
        return None
    chosen = _chosen_for(results_dir)
    if chosen is not None and chosen in profile_counts(runs):
        return chosen
    return str(runs["profile"].value_counts().idxmax())


def load_tables(
    results_dir: Path, profile: str | None = None
) -> tuple[pd.DataFrame, pd.DataFrame, str | None]:
    """(runs, curves, profile): ``profile`` (default: the one chosen for the folder, else the
    one with the most rows, :func:`pick_profile`) and the rows of its family, every profile with
    the same base (``paper-core`` beside ``paper-k`` and ``paper``: the same budget on other
    cells, which a claim's rule reaches by cell, never by label). A ``profile`` with no stored
    rows raises ValueError naming the profiles present."""
    from ._experiments import base_profile

    runs = _store.load_runs(results_dir)
    curves = _store.load_curves(results_dir)
    if profile is not None:
        check_profile(runs, profile, results_dir)
    else:
        profile = pick_profile(runs, results_dir)
    if profile is not None:
        family = runs["profile"].map(base_profile) == base_profile(profile)
        runs = runs[family].reset_index(drop=True)
    if len(curves) and len(runs):
        curves = curves[curves["config_hash"].isin(runs["config_hash"])]
    return runs, curves, profile


def cell_key(cfg) -> str:
    """Hash of a run's configuration without its seed: the cell it belongs to."""
    from ._config import _hash

    return _hash({a: b for a, b in cfg.to_dict().items() if a != "seed"})


_CELL_KEYS: dict[tuple, str] = {}  # row_cell_keys' memo: (columns, values) -> cell key
_CELL_KEYS_MAX = 1 << 17
_NAN = object()  # stands for NaN in a memo key, where NaN != NaN would never match


def row_cell_keys(runs: pd.DataFrame) -> list[str]:
    """:func:`cell_key` of every stored row, in order. The verdicts ask it of the same rows
    many times over, so each distinct row is parsed and hashed once per process (a row with an
    unhashable cell every time). Raises ValueError as ``RunConfig.from_dict`` does."""
    from ._config import RunConfig, field_names

    names = tuple(c for c in runs.columns if c in field_names())
    keys = []
    for values in runs[list(names)].itertuples(index=False, name=None):
        memo = (names, tuple(_NAN if isinstance(v, float) and v != v else v for v in values))
        try:
            key = _CELL_KEYS.get(memo)
        except TypeError:  # a list, dict or pd.NA in a cell: computed, not remembered
            key, memo = None, None
        if key is None:
            key = cell_key(RunConfig.from_dict(dict(zip(names, values, strict=True))))
            if memo is not None:
                if len(_CELL_KEYS) >= _CELL_KEYS_MAX:
                    _CELL_KEYS.clear()
                _CELL_KEYS[memo] = key
        keys.append(key)
    return keys


def experiment_rows(runs: pd.DataFrame, name: str, profile: str | None) -> pd.DataFrame:
    """The runs of experiment ``name``: every stored run (any seed) whose configuration is one
    of the experiment's cells under ``profile``, shared runs included whichever experiment
    produced them, plus the rows tagged with the experiment (results of older declarations,
    whose cells no longer expand); none for an experiment that does not run at ``profile``
    (its ``profiles``); without a profile, the rows tagged with that experiment."""
    if not len(runs):
        return runs
    if profile is not None:
        try:
            from ._experiments import expand, get

            exp = get(name)
            if exp.profiles is not None and profile not in exp.profiles:
                return runs.iloc[0:0]  # not run at this profile: no stored row speaks for it
            cells = {cell_key(c) for c in expand(name, profile)}
            match = pd.Series([k in cells for k in row_cell_keys(runs)], index=runs.index)
            if "experiment" in runs:  # rows of older declarations of the same experiment
                match |= (runs["experiment"] == name) & labelled(runs, profile)
            return runs[match].reset_index(drop=True)
        except ValueError:
            pass
    if "experiment" in runs:
        return runs[runs["experiment"] == name].reset_index(drop=True)
    return runs.iloc[0:0]


def variant(df: pd.DataFrame) -> pd.Series:
    """Model label key: ``<model>_diss`` (e.g. ``hnn_so_diss``) for a model run with its
    dissipation term on, else the model."""
    diss = df["dissipation"] if "dissipation" in df else pd.Series(None, index=df.index)
    is_diss = diss.map(lambda v: v is True or v == 1 or v == "True" or v == "true")
    takes = df["model"].map(lambda m: m in models.available() and models.spec(m).takes_dissipation)
    return df["model"].where(~(is_diss & takes.astype(bool)), df["model"] + "_diss")


def aggregate(
    df: pd.DataFrame,
    by: Sequence[str],
    metric: str,
    *,
    n_resamples: int = 2000,
    seed: int = 0,
    bootstrap: bool = True,
    sort: bool = True,
) -> pd.DataFrame:
    """The seed aggregation: summaries of ``metric`` per group of ``by`` over the runs.

    Columns: n (finite values), mean, std (ddof=1), sem = std / sqrt(n), gmean =
    exp(mean(log x)) (NaN unless every value is > 0), median, and the bootstrap 95% interval
    of the mean (scipy.stats.bootstrap, BCa falling back to percentile; NaN when n < 2, the
    values are all equal, or ``bootstrap`` is False). ``sort``: groups in key order, else in
    order of first appearance.
    """
    from scipy import stats

    by = list(by)
    if metric not in df.columns:
        raise ValueError(f"unknown metric {metric!r}; columns: {', '.join(df.columns)}")
    out = []
    for key, g in df.groupby(by, dropna=False, sort=sort):
        x = pd.to_numeric(g[metric], errors="coerce").to_numpy(dtype=float)
        x = x[np.isfinite(x)]
        n = len(x)
        rec = dict(zip(by, key if isinstance(key, tuple) else (key,), strict=True))
        std = float(np.std(x, ddof=1)) if n > 1 else float("nan")
        lo = hi = float("nan")
        if bootstrap and n > 1 and np.ptp(x) > 0:
            for method in ("BCa", "percentile"):
                try:
                    res = stats.bootstrap(
                        (x,), np.mean, n_resamples=n_resamples, method=method, random_state=seed
                    )
                    lo, hi = float(res.confidence_interval.low), float(res.confidence_interval.high)
                    if np.isfinite(lo) and np.isfinite(hi):
                        break
                except Exception:
                    continue
        rec.update(
            n=n,
            mean=float(np.mean(x)) if n else float("nan"),
            std=std,
            sem=std / math.sqrt(n) if n > 1 else float("nan"),
            gmean=float(np.exp(np.mean(np.log(x)))) if n and np.all(x > 0) else float("nan"),
            median=float(np.median(x)) if n else float("nan"),
            ci_low=lo,
            ci_high=hi,
        )
        out.append(rec)
    return pd.DataFrame(out)
