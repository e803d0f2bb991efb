"""Claim 7's report section: its two protocols side by side, what each trains on and how, the
verdicts on each stored seed set, and each model's error under each protocol.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from ....core import Experiment, RunConfig, TrainConfig, expand
from ....kit import Protocol, bad_rows, by_seed_set, cell_rows, protocol_table
from ._experiments import RELATIVISTIC, RELATIVISTIC_SEED
from ._rule import _HNN_P, _NAIVE, _PURE_LNN, ROLLOUT_VARIANT, _particle_rows, velocity_scores

SECTION_TITLE = "Claim 7: ours and the LNN seed's protocol"
_MODEL_ROWS = (
    ("naive HNN (q, qdot)", _NAIVE),
    ("HNN (q, p)", _HNN_P),
    ("pure LNN (q, qdot)", _PURE_LNN),
    ("constant velocity", {"model": "constant_velocity"}),
)


def _one(exp: Experiment, profile: str) -> RunConfig | None:
    """The declaration of ``exp``'s pure LNN cell at ``profile`` (None: no runs there)."""
    cfgs = [c for c in expand(exp, profile) if c.model == "lnn"]
    return cfgs[0] if cfgs else None


def _protocol(c: RunConfig | None) -> dict[str, str]:
    """The table's cells of one protocol, from its declaration (the LNN cell)."""
    if c is None:
        return {}
    p = dict(c.system_params)
    states = c.n_train * (c.chunk if c.train_target == "derivative" else 1)
    tc = TrainConfig()
    if c.train_target == "derivative":
        data = (
            f"{states:,} states: chunks of {c.chunk} ({c.dt:g} s apart) at a random time of "
            f"{c.n_train:,} trajectories of {c.duration:g} s"
        )
        targets = "the true dz/dt at each state (no integrator)"
        loss = f"{c.loss.upper()} of dz/dt"
        batch = f"{c.batch * c.chunk} states"
    else:
        data = f"{c.n_train:,} chunks of {c.chunk} points ({c.dt:g} s apart), one per trajectory"
        targets = f"the chunk's states, rolled out from its first ({c.train_integrator})"
        loss = f"{c.loss.upper()} of the rollout states"
        batch = f"{c.batch} chunks"
    data += (
        f"; g ~ U({p.get('g_min', '?')}, {p.get('g_max', '?')}) per trajectory, start speeds "
        f"U(-{p.get('v0_max', '?')}, {p.get('v0_max', '?')}); {c.dtype}"
    )
    act = c.activation or "softplus (LNN), tanh (HNN)"
    return {
        "data": data,
        "targets": targets,
        "loss": loss,
        "optimiser": (
            f"AdamW lr {c.lr:g}, cosine to {c.lr * tc.lr_floor:g}, weight decay "
            f"{tc.weight_decay:g}, clip {tc.clip:g}; batch {batch}"
        ),
        "steps": f"{c.steps:,}",
        "network": f"{c.depth} x {c.width}, {act}",
        "metric": (
            f"geometric-mean relative error on (q, qdot) (the (q, p) HNN decoded), "
            f"{c.n_test} test trajectories of {c.chunk * c.test_chunks} points "
            f"({c.dt * (c.chunk * c.test_chunks - 1):g} s) from the same draw"
        ),
    }


def _errors(runs: pd.DataFrame, target: str) -> dict[str, str]:
    """Per model: geometric mean over seeds of the error on (q, qdot) [min, max], failed."""
    r = _particle_rows(runs, target) if len(runs) else runs
    if not len(r):
        return {}
    sc, _ = velocity_scores(r)
    r = r.assign(_s=sc)
    out = {}
    for label, cell in _MODEL_ROWS:
        rows = cell_rows(r, cell)
        if not len(rows):
            continue
        per = np.exp(np.log(rows["_s"]).groupby(rows["seed"]).mean())
        failed = int(bad_rows(rows).sum())
        out[label] = (
            f"{float(np.exp(np.log(per).mean())):.3g} [{per.min():.3g}, {per.max():.3g}], "
            f"{len(per)} seeds" + (f", {failed} failed" if failed else "")
        )
    return out


def comparison_section(results_dir) -> str:
    """Claim 7's two protocols side by side: what each trains on and how, and its verdicts."""
    from ....core import load_tables
    from ....kit import evaluate_claims

    runs, curves, profile = load_tables(Path(results_dir))
    at = profile or "quick"

    def read(key):
        def rule(r: pd.DataFrame):
            return {v.key: v for v in evaluate_claims(r, curves, profile, claims=[7])}.get(key)

        return rule

    ours = Protocol(
        _protocol(_one(RELATIVISTIC, at)),
        by_seed_set(runs, profile, read(f"7 ({ROLLOUT_VARIANT})"), RELATIVISTIC.name),
    )
    seed = Protocol(
        _protocol(_one(RELATIVISTIC_SEED, at)),
        by_seed_set(runs, profile, read("7"), RELATIVISTIC_SEED.name),
    )
    lines = [
        f"### {SECTION_TITLE}",
        "",
        f"Claim 7 read on two protocols (profile {at}), with the same parts, margin policy "
        "and fit gate (`claim_7` in `bench/studies/lnn_seed/relativistic/`). The claim's "
        "verdict, row 7 of the claims table, is the seed's protocol's: where the two differ, "
        "the seed's protocol decides; ours is row 7 (rollout loss). The seed's code and where "
        "its protocol here still differs from it: `docs/studies/relativistic.md`. Both in "
        "their own units: the seed's protocol runs the seed's physics with time and length "
        "10x longer (qdot(t) is the seed's), so that g has the spread the seed's networks see.",
        "",
        "Ours is `relativistic`, the seed's protocol `relativistic_seed`.",
        *protocol_table(
            ours,
            seed,
            "time and length 10x the seed's (its input scaling); g uniform (the seed: normal); "
            "states from trajectories (the seed: independent draws); unweighted L1; the (q, p) "
            "HNN trained in (q, p); AdamW with cosine decay (the seed: Adam, one cycle); the "
            "suite's rollout error as the metric (the seed: a figure)",
        ),
    ]
    errs = {t: _errors(runs, t) for t in ("rollout", "derivative")}
    if any(errs.values()):
        lines += [
            "",
            "Error on (q, qdot), geometric mean over seeds [seed range] (each protocol on its "
            "own test set):",
            "",
            "| model | ours | seed's protocol |",
            "| --- | --- | --- |",
        ]
        for label, _ in _MODEL_ROWS:
            a, b = errs["rollout"].get(label, "-"), errs["derivative"].get(label, "-")
            lines.append(f"| {label} | {a} | {b} |")
    return "\n".join(lines)
