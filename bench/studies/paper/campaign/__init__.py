"""The paper's campaigns: the runs of a profile swept claim by claim, resumable (``_campaign``),
the wall-time budget that orders and plans them (``_budget``, from the measured costs of
``costs.json``), and the paper's verbs of ``python -m bench`` (``_commands``: registered at
import). The selection, the order and how hours are estimated: docs/studies/campaign.md.
"""

from ....core import register_cost_model
from . import _commands  # noqa: F401 - registers the paper's verbs
from ._budget import (
    MS_PER_STEP,
    PAPER_EXPERIMENTS,
    WALL_S,
    data_seconds,
    estimate_seconds,
    make_bench_seconds,
    run_seconds,
    total_seconds,
)
from ._campaign import CAMPAIGN_CLAIMS, campaign_experiments, plan, priority

register_cost_model(run_seconds)  # sweeps run the longest runs first by it

__all__ = [
    "CAMPAIGN_CLAIMS",
    "MS_PER_STEP",
    "PAPER_EXPERIMENTS",
    "WALL_S",
    "campaign_experiments",
    "data_seconds",
    "estimate_seconds",
    "make_bench_seconds",
    "plan",
    "priority",
    "run_seconds",
    "total_seconds",
]
