"""The pixel pendulum (claim 11) over seeds: the HNN seed's own code against the committed rows.

    for s in 0 1 2 3 4 5 6 7 8 9; do
        python -m bench.sidebyside.hnn_seed --seed-code /path/to/hamiltonian-nn \
            --torch-python PATH --steps 10000 --log-every 1000 --eval-every 5000 \
            --curves seed --seed $s --out results/own/sidebyside/hnn_seed/seed$s
    done
    python -m bench.sidebyside.hnn_seed_seeds [--root results/own/sidebyside/hnn_seed] \
        [--results results/reference/paper]

Reads each ``<root>/seed<N>/curves.csv`` that :mod:`.hnn_seed` wrote (its ``seed`` curve: the
seed's code trained on the suite's data and batches for that seed) at its last evaluated step,
and the committed rows of the seed's protocol (``pixel_pendulum_hnn_seed``, paper-core) in
``--results``. Per seed and model: how far each side's decoded rollout is below holding the
first frame (``pixel_mse_static / pixel_mse``; claim 11's learning gate is
:func:`~bench.kit.policy.margin` ("learning", squared) of it) and the seed's energy MSE. Then the
geometric means over the seeds both sides have, how many seeds pass the gate, and the energy
ratio MLP / HNN of claim 11 (a) on each side. Writes ``<root>/seeds.csv`` and prints the table
as markdown. A root without runs, or rows without the experiment: one line, exit status 2.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd

EXPERIMENT = "pixel_pendulum_hnn_seed"
MODELS = {"hnn": "HNN", "node": "MLP"}


def seed_code_rows(root: Path) -> pd.DataFrame:
    """The seed's code's last evaluated step per seed and model: seed, model, step, pixel_mse,
    pixel_mse_static, seed_energy_mse (empty where ``root`` has no ``seed<N>/curves.csv``)."""
    out = []
    for f in sorted(Path(root).glob("seed*/curves.csv")):
        tail = f.parent.name[len("seed") :]
        if not tail.isdigit():
            continue
        c = pd.read_csv(f)
        c = c[(c["curve"] == "seed") & c["pixel_mse"].notna()]
        for model, g in c.groupby("model"):
            last = g.loc[g["step"].idxmax()]
            out.append(
                {
                    "seed": int(tail),
                    "model": model,
                    "step": int(last["step"]),
                    **{k: float(last[k]) for k in ("pixel_mse", "pixel_mse_static")},
                    "seed_energy_mse": float(last["seed_energy_mse"]),
                }
            )
    return pd.DataFrame(out)


def committed_rows(results: Path) -> pd.DataFrame:
    """The committed rows of the seed's protocol: seed, model, pixel_mse, pixel_mse_static,
    seed_energy_mse."""
    from bench.core import load_runs

    r = load_runs(results)
    if not len(r) or "experiment" not in r:
        return pd.DataFrame()
    r = r[(r["experiment"] == EXPERIMENT) & (r["status"] == "ok") & r["model"].isin(MODELS)]
    cols = ["seed", "model", "pixel_mse", "pixel_mse_static", "seed_energy_mse"]
    return r[cols].astype({"seed": int}).reset_index(drop=True)


def table(seed_code: pd.DataFrame, ours: pd.DataFrame) -> pd.DataFrame:
    """Per seed and model, both sides: ``gain`` (static / pixel MSE) and the seed's energy MSE,
    on the seeds both sides have."""
    keep = ["seed", "model", "pixel_mse", "pixel_mse_static", "seed_energy_mse"]
    m = seed_code[keep].merge(ours[keep], on=["seed", "model"], suffixes=("_code", "_ours"))
    for side in ("code", "ours"):
        m[f"gain_{side}"] = m[f"pixel_mse_static_{side}"] / m[f"pixel_mse_{side}"]
    return m.sort_values(["model", "seed"]).reset_index(drop=True)


def markdown(t: pd.DataFrame, gate: float) -> list[str]:
    """Per model: each seed's gain on both sides, their geometric means and how many seeds
    pass ``gate``; then the energy ratio MLP / HNN (claim 11 (a)) on both sides."""
    from bench.kit import gmean

    seeds = sorted(t["seed"].unique())
    head = "| model | side | " + " | ".join(f"seed {s}" for s in seeds)
    lines = [head + f" | geometric mean | seeds at {gate:g}x |"]
    lines.append("|" + " --- |" * (len(seeds) + 4))
    for model, label in MODELS.items():
        g = t[t["model"] == model].set_index("seed")
        for side, name in (("code", "seed's code"), ("ours", "committed row")):
            v = g[f"gain_{side}"].reindex(seeds)
            cells = " | ".join(f"{x:.2f}" for x in v)
            n = int((v >= gate).sum())
            lines.append(f"| {label} | {name} | {cells} | {gmean(v):.2f} | {n} of {len(seeds)} |")
    ratios = []
    for side, name in (("code", "seed's code"), ("ours", "committed row")):
        e = t.pivot(index="seed", columns="model", values=f"seed_energy_mse_{side}")
        if set(MODELS) <= set(e.columns):
            ratios.append(f"{name} {gmean(e['node'] / e['hnn']):.3g}x")
    if ratios:
        lines += ["", "Energy MSE (the seed's metric) MLP / HNN: " + ", ".join(ratios) + "."]
    return lines


def main(argv=None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m bench.sidebyside.hnn_seed_seeds",
        description="The HNN seed's code on the pixel pendulum over seeds, beside the committed "
        "rows of its protocol.",
    )
    p.add_argument("--root", default="results/own/sidebyside/hnn_seed")
    p.add_argument("--results", default="results/reference/paper")
    a = p.parse_args(argv)
    code = seed_code_rows(Path(a.root))
    if not len(code):
        print(f"error: {a.root}: no seed<N>/curves.csv with the seed curve", file=sys.stderr)
        return 2
    ours = committed_rows(Path(a.results))
    if not len(ours):
        print(f"error: {a.results}: no ok rows of {EXPERIMENT}", file=sys.stderr)
        return 2
    from bench.kit import policy

    t = table(code, ours)
    if not len(t):
        print("error: no seed on both sides", file=sys.stderr)
        return 2
    t.to_csv(Path(a.root) / "seeds.csv", index=False)
    print("\n".join(markdown(t, policy.margin("learning", squared=True).value)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
