"""What spans every claim's study: the campaigns that run them at the papers' budgets, with
their cost model and verbs (``campaign``), and the report's sections over all claims before the
studies' own (``report``). The studies themselves live by paper: :mod:`bench.studies.decon` and
the seeds' (``hnn_seed``, ``lnn_seed``, ``vin_seed``). Trivial predictors, shared runs, the
spring's initial states and the budgets: docs/studies/paper.md.
"""

from . import campaign, report  # noqa: F401 - the campaigns' verbs and the report's sections
from .campaign import MS_PER_STEP, PAPER_EXPERIMENTS, WALL_S, estimate_seconds, make_bench_seconds

__all__ = ["MS_PER_STEP", "PAPER_EXPERIMENTS", "WALL_S", "estimate_seconds", "make_bench_seconds"]
