"""Each claim's headline at a glance: the table a report writes beside itself, and the figure
that sets the budgets side by side.

Every report writes ``<results>/headlines.csv``: per final verdict, its headline part (the
paper's central sentence, :attr:`Verdict.headline_name`), the part's effect and 90% interval on
its test scale (log for ratios), its margin on that scale, its kind and centre, and the
verdict. :func:`fig_headlines` draws the committed budgets' tables as one picture: each
claim's headline effect in units of its margin (so that every margin sits at +-1 and a band's
centre at 0), with its interval, one marker per budget, coloured by the verdict. A headline
without a margin is listed under the figure instead.
"""

from __future__ import annotations

import math
from pathlib import Path

import pandas as pd

FILE = "headlines.csv"
COLUMNS = (
    "claim", "verdict", "label", "headline", "kind", "effect", "lo", "hi", "margin", "center",
    "n_seeds",
)  # fmt: skip


def headline_rows(verdicts) -> pd.DataFrame:
    """One row per verdict (:data:`COLUMNS`); ``margin`` NaN where the headline has none."""
    rows = []
    for v in verdicts:
        rows.append(
            {
                "claim": v.key,
                "verdict": v.verdict,
                "label": v.label(),
                "headline": v.headline_name,
                "kind": v.headline_kind,
                "effect": v.effect,
                "lo": v.ci_low,
                "hi": v.ci_high,
                "margin": v.headline_margin,
                "center": v.headline_center,
                "n_seeds": v.n_seeds,
            }
        )
    return pd.DataFrame(rows, columns=list(COLUMNS))


def write_headlines(results_dir, verdicts) -> Path:
    """``<results_dir>/headlines.csv`` from the report's final verdicts."""
    from ..core import atomic_write

    out = Path(results_dir) / FILE
    table = headline_rows(verdicts)
    atomic_write(out, lambda tmp: table.to_csv(tmp, index=False))
    return out


COLORS = {
    "reproduced": "#2ca02c",
    "partly reproduced": "#ff7f0e",
    "not reproduced": "#d62728",
}


def fig_headlines(folders: dict[str, Path], out: Path) -> list[Path]:
    """The committed budgets' headlines (``{budget: results folder}``, each with its
    :data:`FILE`) as one figure at ``out`` (a path without suffix: PNG and PDF)."""
    from ._figure import save_figure, subplots

    tables = {}
    for budget, folder in folders.items():
        f = Path(folder) / FILE
        if f.exists():
            tables[budget] = pd.read_csv(f)
    if not tables:
        return []
    keys = []
    for t in tables.values():
        keys += [k for k in t["claim"].astype(str) if k not in keys]
    keys.sort(key=lambda k: (int(k.split()[0]), k))
    fig, ax = subplots(figsize=(8, 0.32 * len(keys) + 1.6))
    markers = dict(zip(tables, ("o", "s", "^", "D"), strict=False))
    offsets = dict(zip(tables, (-0.15, 0.15, 0.0, 0.3), strict=False))
    unscaled = []
    for budget, t in tables.items():
        t = t.assign(claim=t["claim"].astype(str)).set_index("claim")
        for i, key in enumerate(keys):
            if key not in t.index:
                continue
            r = t.loc[key]
            if not (math.isfinite(r["margin"]) and r["margin"] != 0 and math.isfinite(r["effect"])):
                unscaled.append(f"{key} ({budget})")
                continue
            scale = abs(r["margin"])
            c = r["center"] if math.isfinite(r["center"]) else 0.0
            x = (r["effect"] - c) / scale
            lo = (r["lo"] - c) / scale if math.isfinite(r["lo"]) else x
            hi = (r["hi"] - c) / scale if math.isfinite(r["hi"]) else x
            base = str(r["verdict"]).split(" (")[0]
            y = len(keys) - 1 - i + offsets[budget]
            ax.errorbar(
                [x],
                [y],
                xerr=[[x - lo], [hi - x]],
                fmt=markers[budget],
                color=COLORS.get(base, "#7f7f7f"),
                capsize=2,
                markersize=5,
            )
    ax.axvspan(-1, 1, color="0.9", zorder=0)
    ax.axvline(0, color="0.5", lw=0.8)
    ax.set_yticks(range(len(keys)))
    ax.set_yticklabels(list(reversed(keys)), fontsize=7)
    ax.set_xscale("symlog", linthresh=1)
    ax.set_xlabel("headline effect in units of its margin (shaded: within +-1 margin)")
    handles = [ax.plot([], [], markers[b], color="0.3", label=b)[0] for b in tables] + [
        ax.plot([], [], "s", color=c, label=v)[0] for v, c in COLORS.items()
    ]
    handles.append(ax.plot([], [], "s", color="#7f7f7f", label="inconclusive")[0])
    ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_title("Each claim's headline, per budget")
    if unscaled:
        fig.text(0.01, 0.005, "no margin: " + ", ".join(unscaled), fontsize=6, wrap=True)
    return save_figure(fig, out.parent, out.name)
