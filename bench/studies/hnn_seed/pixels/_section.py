"""The pixel study's report section: the pixel models side by side with the HNN seed's printed
row, claim 11's two protocols side by side with their verdicts, and which seeds learn the
motion (with the VIN diagnosis, where the folder has one).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from ....core import Experiment
from ....kit import (
    Protocol,
    bad_rows,
    by_seed_set,
    fmt,
    gmean,
    learned_text,
    policy,
    protocol_table,
)
from . import _ablation
from ._aux import protocol_rows
from ._experiments import LABELS, PIXEL_HNN, PIXEL_HNN_SEED, SEED_ENERGY_MSE, SHORT, _rows
from ._rule import reading, readings, seed_protocol


def _span(lo: float, hi: float, fmt=fmt) -> str:
    """``lo - hi``, or one number where they print alike."""
    a, b = fmt(lo), fmt(hi)
    return a if a == b else f"{a} - {b}"


_TABLE_COLUMNS = (
    "pixel_loss_test",
    "recon_mse",
    "pixel_mse",
    "pixel_mse_late",
    "pixel_mse_static",
    "decoded_energy_mse",
    "seed_energy_mse",
    "seed_energy_mse_floor",
)


def section(results_dir) -> str:
    """The pixel models side by side, the HNN seed's pixel row beside ours; claim 11's two
    protocols side by side with their verdicts; which seeds learn, and why not."""
    _, t_all, profile = _rows(Path(results_dir))
    t = protocol_rows(t_all)  # the tables: the protocols' runs (claim 11 (c)'s in its verdict)
    lines = [
        "## Learning from pixels (claims 11 and 12)",
        "",
        f"Pendulum rendered to 28 x 28 frames, two stacked per observation (profile "
        f"{profile or '-'}; geometric means over seeds). Pixel MSE: decoded latent rollouts "
        "against the true frames over the test horizon (late: its last third; static: holding "
        "the first observation). Decoded energy MSE (ours): the true energy of the state read "
        "off the decoded frames (the angle of each frame, a finite-difference velocity over one "
        "frame) against the same reading of the true ones. Seed's energy MSE: the HNN seed's "
        "metric, the decoded frames encoded again and mapped to the state by an affine map "
        "fitted on the training encodings, the true energy against the true states' (floor: "
        "the map applied to the encoded true frames). The seed's printed numbers are of its "
        "Gym pendulum and its energy scale: compare orders of magnitude only. Latent drift: "
        "range of the learned conserved scalar along a rollout over its spread across test "
        "starts. Protocol: `bench/studies/hnn_seed/pixels/`, `bench/core/_pixels.py`.",
        "",
        "| model | protocol | seeds | test loss | recon MSE | pixel MSE | late pixel MSE | "
        "static | decoded energy MSE (ours) | seed's energy MSE | its floor | "
        "energy MSE (HNN seed's number) | latent drift |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    if not len(t):
        return "\n".join([*lines, "| (no runs) |" + " |" * 12])

    seed_numbers = {"node": SEED_ENERGY_MSE[0], "hnn": SEED_ENERGY_MSE[1]}
    protocol = seed_protocol(t)
    for model in ("hnn", "node", "vin", "resnet"):
        for is_seed, name in ((False, "ours"), (True, "seed's")):
            g = t[(t["model"] == model) & (protocol == is_seed) & ~bad_rows(t, "pixel_mse")]
            if not len(g):
                continue
            cells = [gmean(g[c]) if c in g else math.nan for c in _TABLE_COLUMNS]
            lines.append(
                f"| {LABELS[model]} | {name} | {g['seed'].nunique()} | "
                + " | ".join(fmt(x) for x in cells)
                + f" | {fmt(seed_numbers.get(model, math.nan))} | "
                f"{fmt(gmean(g.get('latent_energy_drift')))} |"
            )
    diag = _ablation.read(_ablation.VIN, results_dir, profile)
    seed_diag = _ablation.read(_ablation.HNN_SEED, results_dir, profile)
    return "\n".join(
        [
            *lines,
            "",
            *protocols(t_all, profile),
            *variant_lines(seed_diag),
            "",
            *seed_lines(t, diag, seed_diag),
            *_ablation.lines(results_dir, profile),
        ]
    )


_OPTIMISERS = {
    "adamw": "AdamW (decoupled weight decay), gradient clipped at norm 1",
    "adam_l2": "Adam with the weight decay as an L2 term in the gradient, no clipping",
}
_SCHEDULES = {
    "cosine": "cosine decay",
    "constant": "constant",
    "onecycle": "one-cycle",
}


_INITS = {
    "orthogonal": "orthogonal at gain 0.5, zero biases (the paper's)",
    "hnn_seed": "orthogonal at gain 1, PyTorch's uniform biases (the seed's)",
}


def _config(exp: Experiment, profile: str | None):
    from ....core import expand

    for p in (profile, "paper"):
        try:
            cfgs = expand(exp, p) if p else []
        except (KeyError, ValueError):
            cfgs = []
        if cfgs:
            return cfgs[0]
    return None


def protocols(t: pd.DataFrame, profile: str | None) -> list[str]:
    """Claim 11 under our protocol and under the seed's, side by side: what each trains on,
    how, what it scores, and its verdict (from the rows ``t``; the configurations are the
    experiments' at ``profile``)."""
    from ....core import AE_LOSS, CC_LOSS, DYN_LOSS, WEIGHT_DECAY

    is_seed = seed_protocol(t) if len(t) else pd.Series(False, index=t.index)
    cols = {"ours": _config(PIXEL_HNN, profile), "seed": _config(PIXEL_HNN_SEED, profile)}
    desc = {
        "euler": "explicit Euler z + f(z)",
        "rk4": "classical RK4",
        "rk4_38": "RK4 (3/8 rule)",
    }

    def cell(key, what):
        c = cols[key]
        if c is None:
            return "-"
        if what == "data":
            frames = max(c.chunk, round(c.duration / c.dt))
            return (
                f"{c.n_train} trajectories of {frames} frames {c.dt:g} s apart, windows of "
                f"{c.chunk} frames; test {c.n_test} of {c.chunk * c.test_chunks} frames"
            )
        if what == "targets":
            return (
                f"the next observation's encoding after one latent step "
                f"({desc.get(c.train_integrator, c.train_integrator)}, unit step per frame)"
            )
        if what == "loss":
            return (
                f"{AE_LOSS:g} x pixel L2 + {CC_LOSS:g} x auxiliary latent loss + "
                f"{DYN_LOSS:g} x latent dynamics"
            )
        if what == "optimiser":
            wd = WEIGHT_DECAY if c.weight_decay is None else c.weight_decay
            return (
                f"{_OPTIMISERS.get(c.optimizer, c.optimizer)}; lr {c.lr:g} "
                f"{_SCHEDULES.get(c.lr_schedule, c.lr_schedule)}, weight decay {wd:g}, batch "
                f"{c.batch}, width {c.width}"
            )
        if what == "steps":
            return f"{c.steps}"
        if what == "init":
            init = dict(c.model_options).get("init", "orthogonal")
            return _INITS.get(init, init)
        if what == "metric":
            roll = desc.get(c.eval_integrator, c.eval_integrator)
            if key == "ours":
                return (
                    f"decoded energy MSE: latent rollout ({roll}), decoded, angle and "
                    "finite-difference velocity read off the frames, true H against the truth "
                    "read alike"
                )
            return (
                f"seed's energy MSE: latent rollout ({roll}), decoded, encoded again, affine "
                "map to the state fitted on the training encodings, true H against the true "
                "states' (decoded energy MSE beside it, not tested)"
            )
        raise ValueError(f"unknown protocol row {what!r}")

    names = {
        "data": "data",
        "targets": "targets",
        "loss": "loss",
        "optimiser": "optimiser",
        "steps": "steps",
        "init": "dynamics network's initialisation",
        "metric": "metric",
    }
    ours, seed = (
        Protocol(
            {label: cell(key, what) for what, label in names.items()},
            by_seed_set(t[mask], profile, lambda r, k=key: readings(r)[k], exp.name, t),
        )
        for key, mask, exp in (
            ("ours", ~is_seed, PIXEL_HNN),
            ("seed", is_seed, PIXEL_HNN_SEED),
        )
    )
    differs = (
        "our pendulum and renderer (the seed: Gym's Pendulum-v0); zero autoencoder biases; both "
        "observations reconstructed (the seed: the first); RK4 test rollouts (the seed: RK45); "
        "every test trajectory (the seed: one)"
    )
    return [
        "Claim 11 under two protocols (the verdict is the seed's protocol's where it has runs; "
        "`claim_11`):",
        *protocol_table(ours, seed, differs),
    ]


def seed_lines(
    t: pd.DataFrame, diag: pd.DataFrame | None = None, seed_diag: pd.DataFrame | None = None
) -> list[str]:
    """Which models learn the motion on which seed (pixel MSE below holding the first frame by
    the learning gate), the seed's autoencoder reconstruction, and for a seed where no model
    learns, what its runs, the VIN diagnosis (``diag``, trained without the auxiliary loss, the
    same data and autoencoder initialisation) and the HNN seed's protocol diagnosis
    (``seed_diag``, one element ours) say about it. Every number from the rows."""
    if not len(t) or "pixel_mse_static" not in t:
        return []
    gate = policy.margin("learning", squared=True).value
    t = t.assign(_gain=_ablation.gain(t), _protocol=np.where(seed_protocol(t), "seed's", "ours"))
    t = t.assign(_learned=t["_gain"] >= gate)
    ablation = None
    if diag is not None and len(diag):
        ablation = diag[diag["variant"] != _ablation.PROTOCOL].copy()
        ablation["_gain"] = _ablation.gain(ablation)
    lines = [
        f"Per seed: the models that learn the motion (pixel MSE {gate:g}x below holding the "
        "first frame, the claims' gate), the rest with their factor, and the autoencoder's "
        "reconstruction MSE over the seed's runs (every model, both protocols).",
        "",
        "| seed | learned | not learned (x below holding the first frame) | recon MSE "
        "| VIN without the auxiliary loss: recon MSE, x below |",
        "|---|---|---|---|---|",
    ]

    def label(r):
        return f"{SHORT[r['model']]} ({r['_protocol']})"

    recon = pd.to_numeric(t.get("recon_mse", pd.Series(np.nan, index=t.index)), errors="coerce")
    learned_recon = float(np.median(recon[t["_learned"]])) if t["_learned"].any() else math.nan
    notes = []
    for s, g in t.groupby("seed"):
        ok = [label(r) for _, r in g.iterrows() if r["_learned"]]
        bad = [f"{label(r)} {r['_gain']:.2g}" for _, r in g.iterrows() if not r["_learned"]]
        rec = recon[g.index]
        abl = ablation[ablation["seed"] == s] if ablation is not None else None
        abl_text = "-"
        if abl is not None and len(abl):
            a = abl.iloc[0]
            abl_text = f"{fmt(float(a['recon_mse']))}, {a['_gain']:.3g}x"
        lines.append(
            f"| {s} | {', '.join(ok) or 'none'} | {', '.join(bad) or '-'} | "
            f"{_span(rec.min(), rec.max())} | {abl_text} |"
        )
        if ok or not t["_learned"].any():
            continue
        note = f"Seed {s}: no model learns the motion ({len(g)} runs)"
        if np.isfinite(learned_recon) and rec.notna().any():
            ratio = _span(
                rec.min() / learned_recon, rec.max() / learned_recon, lambda x: f"{x:.2g}"
            )
            note += (
                f"; they reconstruct at {_span(rec.min(), rec.max())}, {ratio}x the median "
                f"of the runs that learn ({fmt(learned_recon)})"
            )
        note += "."
        if abl is not None and len(abl):
            a = abl.iloc[0]
            if a["_gain"] >= gate:
                note += (
                    f" Trained without the auxiliary latent loss (the VIN diagnosis: the same "
                    f"frames and autoencoder initialisation) it reconstructs at "
                    f"{fmt(float(a['recon_mse']))} and learns ({a['_gain']:.3g}x below holding "
                    "the first frame): the seed's frames and autoencoder initialisation can be "
                    "learned, so its runs' failure is not the autoencoder's alone; it comes with "
                    "the protocol's loss, which every run of the table shares."
                )
            else:
                note += (
                    f" Trained without the auxiliary latent loss (the VIN diagnosis) it "
                    f"reconstructs at {fmt(float(a['recon_mse']))} and does not learn either "
                    f"({a['_gain']:.3g}x)."
                )
        if seed_diag is not None and len(seed_diag):
            sd = seed_diag[(seed_diag["seed"] == s) & (seed_diag["variant"] != _ablation.PROTOCOL)]
            gains = _ablation.gain(sd)
            runs = [
                f"{SHORT.get(r['model'], r['model'])} {r['variant']} {x:.3g}x"
                for (_, r), x in zip(sd.iterrows(), gains, strict=True)
            ]
            if runs:
                n = int((gains >= gate).sum())
                note += (
                    " The HNN seed's protocol with elements ours (its diagnosis's variants) "
                    f"learns there in {n} of {len(runs)} runs: {', '.join(runs)}."
                )
        notes.append(note)
    return [*lines, *([""] + notes if notes else [])]


def variant_lines(diag: pd.DataFrame | None) -> list[str]:
    """Claim 11's seed reading (:func:`reading`) on the runs of each variant of the HNN seed's
    protocol diagnosis that covers both models on two seeds or more (``diag``, the rows of
    ``hnn_seed_pixel_diagnosis.csv``): what the seed's protocol would read with the variant's
    elements ours. Not a verdict (the claim's is the seed's protocol's); it says what keeps that
    one untested."""
    if diag is None or not len(diag):
        return []
    out = []
    d = diag[diag["variant"] != _ablation.PROTOCOL]
    for name, g in d.groupby("variant", sort=False):
        if set(g["model"]) != {"hnn", "node"} or g["seed"].nunique() < 2:
            continue
        g = g.assign(observation="pixels")
        g["status"] = np.where(np.isfinite(pd.to_numeric(g["pixel_mse"])), "ok", "failed")
        v = reading(g, "seed", aux=False)  # the energy statement under the variant
        head = v.parts[0] if v.parts else None
        why = f"; (a) {head.status}" + (f": {head.note}" if head and head.note else "")
        out.append(
            f"- The seed's protocol, variant *{name}* (the diagnosis below, not a verdict): "
            f"**{v.verdict}** ({v.n_seeds} seeds; {v.effect_name} {v.effect:.3g} = "
            f"{math.exp(v.effect):.3g}x{why if head else ''}); learned: {learned_text(v)}."
        )
    return ["", *out] if out else []
