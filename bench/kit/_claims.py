"""Claim evaluation over the registered studies: the rows each claim reads, and its verdicts.

A claim is a registered :class:`~bench.core.Study` with a verdict rule; the rules themselves
live with their studies (``bench.studies.decon.energy``: claim 1, ...), built from this kit.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping

import pandas as pd

from ..core import expand, experiment_rows, labelled, reading_of, studies
from ._seeds import seed_sets, seed_span
from ._verdict import INCONCLUSIVE, Verdict

__all__ = [
    "claim_studies",
    "claims_not_run",
    "evaluate_claims",
    "further_cells",
    "incomplete_supplements",
    "supplements_waiting",
    "restrict",
    "restrict_all",
    "runs_at",
]


def restrict(runs: pd.DataFrame, study, profile: str | None, keep=None) -> pd.DataFrame:
    """The rows a claim reads: those of its study's experiments (by config hash under
    ``profile``) plus the stored rows tagged with an experiment in ``study.reads`` (results older
    than today's declarations, whose cells no longer expand, still reach the claims that filter
    them). The runs of other experiments that happen to match a claim's field filters, e.g.
    VIN's NODE+SO on the pendulum, are left out, and so are the cells of a further reading
    (:func:`incomplete_supplements`; ``keep``: only the declared cells it accepts count) on a
    seed set where some of them are not stored yet."""
    if profile is None or "config_hash" not in runs:
        return runs
    parts = [experiment_rows(runs, exp.name, profile) for exp in study.experiments]
    if "experiment" in runs:
        parts.append(runs[runs["experiment"].isin(study.reads) & labelled(runs, profile)])
    # ignore_index: experiment_rows resets its index and the tagged rows keep the store's, so
    # labels would repeat (and a rule that aligns on the index would fail)
    rows = pd.concat(parts, ignore_index=True).drop_duplicates("config_hash") if parts else runs
    drop = incomplete_supplements(rows, study, profile, keep)
    return rows[~rows["config_hash"].isin(drop)].reset_index(drop=True) if drop else rows


def further_cells(experiments, profile: str, seeds=None, keep=None) -> dict[str, set]:
    """``{reading: config hashes}`` of the further readings (``Experiment.supplementary``) of
    ``experiments`` at ``profile`` (on ``seeds`` instead of its own; only the cells ``keep``
    accepts): each named reading apart, the unnamed ones under ""."""
    out: dict[str, set] = {}
    for e in experiments:
        if e.supplementary is None:
            continue
        for c in expand(e, profile, seeds=None if seeds is None else list(seeds)):
            name = reading_of(e, c)
            if name is not None and (keep is None or keep(c)):
                out.setdefault(name, set()).add(c.config_hash)
    return out


def incomplete_supplements(rows: pd.DataFrame, study, profile: str, keep=None) -> set:
    """The config hashes of each of ``study``'s further readings (``Experiment.supplementary``,
    :func:`further_cells`) on each seed set of ``profile`` (its own seeds, its replication
    seeds) where ``rows`` lack some of them: a reading joins the verdict whole, never with the
    seeds that happen to be done, and a named reading without waiting for another."""
    if not any(e.supplementary is not None for e in study.experiments):
        return set()
    done = set(rows["config_hash"]) if len(rows) else set()
    drop: set = set()
    for seeds in (s for s in seed_sets(profile) if s):
        for want in further_cells(study.experiments, profile, seeds, keep).values():
            if not want <= done:
                drop |= want
    return drop


def restrict_all(
    runs: pd.DataFrame, profile: str | None, claims: Iterable[int] | None = None, keep=None
) -> dict[int, pd.DataFrame]:
    """``{claim: the rows it reads}`` for every claim study (only ``claims`` where given;
    :func:`restrict`, with ``keep``): the rows a claim reads do not depend on the seed, so one
    restriction serves every seed set."""
    wanted = None if claims is None else set(claims)
    return {
        s.claim: _plain_columns(restrict(runs, s, profile, keep))
        for s in claim_studies()
        if wanted is None or s.claim in wanted
    }


def _plain_columns(df: pd.DataFrame) -> pd.DataFrame:
    """Arrow-backed string columns as plain objects: the rules slice a table thousands of
    times, and taking rows of Arrow strings costs several times more."""
    cols = {c: object for c in df.columns if pd.api.types.is_string_dtype(df[c].dtype)}
    return df.astype(cols).copy() if cols else df  # the copy consolidates the columns


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
                    study.title,
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


def supplements_waiting(runs: pd.DataFrame, profile: str) -> dict[int, str]:
    """``{claim: "its further reading waits for runs: n of m on seeds 0-4, ..."}`` for each
    claim whose further reading (``Experiment.supplementary``) is not stored whole on a seed set
    of ``profile`` (it joins the verdict there only then): its own seeds, and the replication
    seeds where some of it is stored."""
    judged = {s.claim for s in claim_studies()}
    experiments: dict[int, list] = {}
    for study in studies():  # a claim's experiments may be declared by several studies
        if study.claim in judged:
            experiments.setdefault(study.claim, []).extend(study.experiments)
    done = set(runs["config_hash"]) if len(runs) and "config_hash" in runs else set()
    parts: dict[int, list[str]] = {}
    for i, seeds in enumerate(s for s in seed_sets(profile) if s):
        for claim, exps in sorted(experiments.items()):
            for name, want in further_cells(exps, profile, seeds).items():
                n, m = len(want & done), len(want)
                if n < m and (n or not i):
                    said = f"{name}: " if name else ""
                    where = f"{said}{n} of {m} on seeds {seed_span(seeds)}"
                    parts.setdefault(claim, []).append(where)
    return {c: "its further reading waits for runs: " + ", ".join(p) for c, p in parts.items()}
