"""The claims kit: what every claim's rule is built from, and the engine that judges the claims.

A rule splits its claim into *parts*, each a one-sided t test on paired per-seed values against
a margin from the policy; *gates* say where a part may be judged at all; :func:`verdict` turns
the parts into the claim's verdict (Holm's correction across them). A new rule reads::

    from bench.kit import gated, greater, learned_cell, margin, paired, verdict

    node, hnn = {"model": "node"}, {"model": "hnn"}
    d = paired(runs, node, hnn)  # per seed log(err NODE / err HNN)
    part = gated(greater("NODE worse than HNN", d, margin("error")), learned_cell(runs, node))
    return verdict(n, title, [part], part, len(d), "log(err NODE / err HNN)")

Parts (:mod:`._stats`), with m the margin on the test scale (log m for ratios) and [lo, hi]
the one-sided (1 - alpha) t bounds of the mean effect:

- ``greater``: holds when lo > m, contradicts when hi < m.
- ``at_most``: holds when hi < m, contradicts when lo > m.
- ``equivalent`` (TOST): holds when -m < lo and hi < m, contradicts when the interval is outside.
- ``band``: centre c, holds when c - m < lo and hi < c + m; ``below``: holds when hi < c + m.
- ``share``: per seed closed - s * gap > 0 at the share margin s ("most of the gap");
  ``so_share``: NODE+SO's share of the NODE -> HNN gap, as claims 3 and 13 read it.
- ``undecided``: a part with nothing to test.

Gates (:mod:`._gates`): ``learned`` (the model beats the best trivial predictor by the learning
margin), ``condition`` (a stated condition of other parts that must hold), ``similar_fit``
("at similar loss": a condition that can only confound, closed only where the favoured model
fits better beyond the loss margin), ``gated``.

Per-seed values (:mod:`._seeds`): ``at_lr`` (the rows at one learning rate), ``scored`` (failed
runs at the worst error; ``velocity_scores``: momentum runs scored on their velocities),
``cell_rows``, ``log_per_seed``, ``paired`` (per seed log(metric A / metric B)),
``curve_slopes``.

Verdict (:mod:`._verdict`, :mod:`._holm`): ``verdict`` is *reproduced* when every part holds,
*partly reproduced* when some hold and some are contradicted, *not reproduced* when some are
contradicted and none holds, else *inconclusive*; ``holm`` corrects both directions.

Policy (:mod:`.policy`): ``margin(quantity)``, ``stated(quantity, value, quote, source)``,
``POLICY``: one margin per quantity, larger only where the paper states a number.

The engine: ``evaluate_claims`` judges every registered study with a rule (``claim_studies``)
on the rows it reads (``restrict``, :mod:`._claims`); ``judge`` judges each claim again on a
disjoint seed set and without each seed (:mod:`._replication`); ``power_table`` says how often a
part signs at its observed effect (:mod:`._power`); ``margin_dependence`` judges each claim
across the plausible band of its margins (:mod:`._sensitivity`); ``Protocol`` and
``protocol_table`` set two readings of a claim side by side (:mod:`._protocols`).

What the studies draw and write with it: the figures' labels, colours, bars and trivial-predictor
lines (:mod:`._plot`, saved by ``save_figure`` on the Agg backend, :mod:`._figure`), each claim's
headline table and figure (:mod:`._headlines`), and the report's text conventions (``fmt``,
``md_escape``, ``folder_label``: :mod:`._text`). Nothing here imports a study.
"""

from __future__ import annotations

from . import policy
from ._claims import (
    claim_studies,
    claims_not_run,
    evaluate_claims,
    further_cells,
    incomplete_supplements,
    restrict,
    restrict_all,
    runs_at,
    supplements_waiting,
)
from ._discrimination import (
    TRIVIAL_FACTOR,
    Discrimination,
    LinkGates,
    discrimination,
    learned_at_each_k,
    learned_cell,
    non_trivial,
    per_system_discrimination,
    several_rates,
    succeeds,
    trivial_log,
)
from ._figure import new_figure, save_figure, subplots
from ._gates import Gate, apply_gates, condition, foil, gated, learned, similar_fit, waiting
from ._headlines import fig_headlines, headline_rows, write_headlines
from ._holm import holm, margin_ranges
from ._models import MODEL_LABELS, TRIVIAL_MODELS, in_form, row_options
from ._plot import (
    COLORS,
    FAILED_LABEL,
    MODEL_ORDER,
    SYSTEM_LABELS,
    SYSTEM_ORDER,
    TRIVIAL_STYLE,
    curve_mean,
    draw_bars,
    gmean,
    in_order,
    mark_failed,
    model_bar_values,
    model_bars,
    model_label,
    seed_stats,
    split_trivial,
    trivial_lines,
)
from ._power import power_lines, power_table
from ._protocols import Protocol, by_seed_set, decided_by, learned_text, protocol_table
from ._replication import (
    CHANGES_WITHOUT_A_SEED,
    DOES_NOT_REPLICATE,
    Judgement,
    costs_apart,
    estimates_differ,
    judge,
    pooled_moves,
    stored_counts,
    why_not_replicated,
)
from ._seeds import (
    BOUNDED_SLOPE,
    LINEAR_SLOPE,
    MIN_SEEDS,
    WORST_ERROR,
    at_lr,
    bad_rows,
    cell_rows,
    curve_slopes,
    log_per_seed,
    min_seeds,
    n_bad,
    paired,
    paper_spring,
    required_seeds,
    scored,
    seed_sets,
    seed_span,
    velocity_scores,
)
from ._sensitivity import Dependence, margin_dependence
from ._so_share import so_share
from ._stats import (
    ALPHA,
    Part,
    at_most,
    band,
    below,
    equivalent,
    greater,
    share,
    t_bounds,
    t_bounds_jackknife,
    undecided,
)
from ._text import fmt, folder_label, md_escape
from ._verdict import (
    INCONCLUSIVE,
    NOT_REPRODUCED,
    PARTLY,
    REPRODUCED,
    VERDICTS,
    Verdict,
    verdict,
)
from .policy import POLICY, Margin, margin, override, stated

__all__ = [
    # parts
    "ALPHA",
    "Part",
    "at_most",
    "band",
    "below",
    "equivalent",
    "greater",
    "share",
    "so_share",
    "t_bounds",
    "t_bounds_jackknife",
    "undecided",
    # gates
    "Gate",
    "apply_gates",
    "condition",
    "foil",
    "gated",
    "learned",
    "LinkGates",
    "learned_at_each_k",
    "learned_cell",
    "similar_fit",
    "waiting",
    # per-seed values
    "BOUNDED_SLOPE",
    "LINEAR_SLOPE",
    "MIN_SEEDS",
    "WORST_ERROR",
    "at_lr",
    "bad_rows",
    "cell_rows",
    "curve_slopes",
    "log_per_seed",
    "min_seeds",
    "n_bad",
    "paired",
    "paper_spring",
    "required_seeds",
    "scored",
    "velocity_scores",
    "seed_sets",
    "seed_span",
    # trivial predictors
    "MODEL_LABELS",
    "in_form",
    "row_options",
    "TRIVIAL_FACTOR",
    "TRIVIAL_MODELS",
    "Discrimination",
    "discrimination",
    "non_trivial",
    "per_system_discrimination",
    "several_rates",
    "succeeds",
    "trivial_log",
    # the verdict
    "INCONCLUSIVE",
    "NOT_REPRODUCED",
    "PARTLY",
    "REPRODUCED",
    "VERDICTS",
    "Verdict",
    "holm",
    "margin_ranges",
    "verdict",
    # the policy
    "POLICY",
    "Margin",
    "margin",
    "override",
    "policy",
    "stated",
    # the claims judged: over the registry, replicated, their power and margin dependence
    "claim_studies",
    "claims_not_run",
    "evaluate_claims",
    "restrict",
    "restrict_all",
    "further_cells",
    "incomplete_supplements",
    "supplements_waiting",
    "runs_at",
    "CHANGES_WITHOUT_A_SEED",
    "DOES_NOT_REPLICATE",
    "Judgement",
    "judge",
    "costs_apart",
    "estimates_differ",
    "pooled_moves",
    "stored_counts",
    "why_not_replicated",
    "power_lines",
    "power_table",
    "Dependence",
    "margin_dependence",
    # two readings of a claim: the suite's protocol and the seed's
    "Protocol",
    "by_seed_set",
    "decided_by",
    "learned_text",
    "protocol_table",
    # figures, headlines and text
    "COLORS",
    "FAILED_LABEL",
    "MODEL_ORDER",
    "SYSTEM_LABELS",
    "SYSTEM_ORDER",
    "TRIVIAL_STYLE",
    "curve_mean",
    "draw_bars",
    "gmean",
    "in_order",
    "mark_failed",
    "model_bar_values",
    "model_bars",
    "model_label",
    "seed_stats",
    "split_trivial",
    "trivial_lines",
    "new_figure",
    "save_figure",
    "subplots",
    "fig_headlines",
    "headline_rows",
    "write_headlines",
    "fmt",
    "folder_label",
    "md_escape",
]
