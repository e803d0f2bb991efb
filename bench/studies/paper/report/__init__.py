"""The paper's sections of REPORT.md before the experiments' own (``_sections``: registered at
import): the claims and their replication, every part of every claim, the margin policy, the
claims that depend on a margin, the verdicts at both budgets (``_comparison``) and the claims at
every number of links (``_links``).
"""

from . import _sections  # noqa: F401 - registers the paper's report sections
from ._links import LINKS, PROFILE

__all__ = ["LINKS", "PROFILE"]
