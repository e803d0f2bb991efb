"""Fig. 4 (second-order structure): the experiment, claim 3's verdict rule and the figure."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from ....core import Experiment, Study, plain, register_study, select
from ....kit import (
    Verdict,
    cell_rows,
    discrimination,
    gated,
    greater,
    learned_cell,
    model_bars,
    n_bad,
    paired,
    paper_spring,
    policy,
    so_share,
    verdict,
)
from ..._claims import (
    CLAIM_TITLES,
    PAPER_FORM_OPTIONS,
    PAPER_MODELS,
    SPRING_PAPER,
    SYSTEMS,
    has_paper_form,
    is_paper_cell,
    paper_form,
    paper_form_ok,
    shared_overrides,
    suite_form,
)

# the axes that add the paper-form cells (node_so_pq; node, hnn and hnn_so with their paper
# options)
PAPER_FORM_AXES = {
    "model": (*PAPER_MODELS, "node_so_pq", "constant_velocity"),
    "model_options": tuple(dict.fromkeys(((), *PAPER_FORM_OPTIONS.values()))),
}


def is_suite_cell(c) -> bool:
    """A cell of the suite's form (no paper-form model or options)."""
    return c.model != "node_so_pq" and c.model_options == ()


SECOND_ORDER = Experiment(
    name="second_order",
    title="Fig. 4: second-order structure, NODE vs NODE+SO and HNN vs HNN+SO",
    axes={
        "system": SYSTEMS,
        "k": (2,),
        "model": (*PAPER_MODELS, "constant_velocity"),
        "model_options": ((),),
        "system_params": ((), SPRING_PAPER),
    },
    # the paper's Fig. 4 pools k = 1..4, as Figs. 2 and 5 do; paper-core is k = 2 only. The
    # four models run in the paper's form too (PAPER_FORM, k = 2): a further reading
    # (``supplementary``) that the suite's never waits for
    profile_overrides=shared_overrides(
        {
            "paper": {"k": (1, 2, 3, 4), **PAPER_FORM_AXES},
            "paper-core": {"k": (2,), **PAPER_FORM_AXES},
            "paper-k": {"k": (1, 3, 4)},
        }
    ),
    include=lambda c: is_paper_cell(c) and paper_form_ok(c) and (c.k == 2 or is_suite_cell(c)),
    claim=3,
    supplementary=lambda c: not is_suite_cell(c),
)


# Where the paper claims that second-order structure closes the gap: Sec. 4.4 concedes "a gap
# for some systems ... in each of these cases the system is described in a non-Cartesian
# coordinate system" (Gruver et al. 2022), so (b) is judged on the Cartesian system only.
SHARE_SYSTEMS = ("spring_pendulum",)


def claim_3(runs: pd.DataFrame, curves: pd.DataFrame | None = None) -> list[Verdict]:
    """Claim 3 in the suite's form of the four models, and in the paper's where any of its
    cells is stored (:data:`~bench.studies._claims.PAPER_FORM`; the verdict labelled
    "the paper's models"): :func:`claim_3_form` on each."""
    out = [claim_3_form(suite_form(runs))]
    if has_paper_form(runs, roles=("node", "hnn")):  # not claim 4's NODE+SO cells alone
        out.append(claim_3_form(paper_form(runs), variant="the paper's models"))
    return out


def claim_3_form(runs: pd.DataFrame, variant: str | None = None) -> Verdict:
    """Claim 3 (Fig. 4): second-order structure explains most of the HNN's advantage, in the
    paper's two readings, per system (undamped chain and spring, k = 2 where present):

    (a) pairwise, Fig. 4's caption ("Models with the SO bias significantly outperform those that
    do not", Gruver et al. 2022): *greater* parts at the error margin on ``log(err NODE / err
    NODE+SO)`` and ``log(err HNN / err HNN+SO)``, each judged where both models learned;
    (b) the share of the gap, Sec. 4.3 (NODE+SO "more closely matches HNNs than vanilla NODEs",
    line 136): per seed ``closed = log(err NODE / err NODE+SO)`` and ``gap = log(err NODE /
    err HNN+SO)``; holds when ``closed - s * gap > 0`` at the policy's share ``s`` (one-sided
    t test). Judged on the Cartesian spring only (:data:`SHARE_SYSTEMS`: the paper concedes
    the angular chain) and under the condition that HNN+SO has an advantage to explain (``gap``
    a *greater* part at the error margin); the chain's share is reported, not judged.
    Headline: (b) on the spring.
    """
    p = paper_spring(select(plain(runs), loss="l2", ok=False))
    ks = p["k"].dropna().unique() if "k" in p and len(p) else []
    k = 2 if 2 in set(ks) else None
    base = {"k": k} if k is not None else {}
    parts, discs, notes = [], [], []
    n_failed = 0
    n_seeds = []
    head = None
    err = policy.margin("error")
    for system in ("chain_pendulum", "spring_pendulum"):
        s = {**base, "system": system}
        closed = paired(p, {**s, "model": "node"}, {**s, "model": "node_so"})
        gap = paired(p, {**s, "model": "node"}, {**s, "model": "hnn_so"})
        hnn = paired(p, {**s, "model": "hnn"}, {**s, "model": "hnn_so"})
        both = pd.concat([closed, gap], axis=1, keys=["c", "g"]).dropna()
        if not len(both):
            continue
        n_seeds += [len(both), len(hnn)]
        rows = cell_rows(p, s)
        n_failed += n_bad(cell_rows(p, {**s, "model": ["node", "node_so", "hnn", "hnn_so"]}))
        discs.append(discrimination(rows, system))
        gate = {m: learned_cell(rows, {"model": m}, f"{m} on {system}") for m in PAPER_MODELS}
        parts.append(
            gated(
                greater(f"{system}: (a) log(NODE / NODE+SO)", closed.to_numpy(), err),
                gate["node"],
                gate["node_so"],
            )
        )
        parts.append(
            gated(
                greater(f"{system}: (a) log(HNN / HNN+SO)", hnn.to_numpy(), err),
                gate["hnn"],
                gate["hnn_so"],
            )
        )
        advantage, share_part, _ = so_share(
            p,
            s,
            "hnn_so",
            f"{system}: HNN+SO beats NODE (log(NODE / HNN+SO))",
            f"{system}: (b) share of the gap closed by SO",
            gate,
        )
        if system not in SHARE_SYSTEMS:
            notes.append(
                f"{system}: (b) share {share_part.point:.3g} reported, not judged (the paper "
                "concedes a gap in non-Cartesian coordinates)"
            )
            continue
        parts += [advantage, share_part]
        head = share_part
    if not parts:
        return verdict(
            3, CLAIM_TITLES[3], [], None, 0, "fraction of the log gap closed by SO", variant=variant
        )
    return verdict(
        3,
        CLAIM_TITLES[3],
        parts,
        head,
        min(n_seeds),
        "share of log(NODE / HNN+SO) closed by second-order structure (spring)",
        "; ".join(notes),
        discs=discs,
        n_failed=n_failed,
        variant=variant,
    )


def fig_second_order(runs, curves, outdir: Path) -> list[Path]:
    """Fig. 4: rollout error of NODE, NODE+SO, HNN, HNN+SO per system (mean +- sem)."""
    return model_bars(runs, outdir, "fig4_second_order", "Second-order structure")


STUDY = register_study(
    Study(
        name="second_order",
        experiments=(SECOND_ORDER,),
        claim=3,
        title=CLAIM_TITLES[3],
        rule=claim_3,
        reads=("energy", "second_order", "coordinates", "loss"),
        figure=fig_second_order,
        stem="fig4_second_order",
    )
)
