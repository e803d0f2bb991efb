"""The paper's sections of REPORT.md before the experiments' own (``_sections``: registered at
import): the claims and their replication, every part of every claim, the margin policy, the
claims that depend on a margin, the verdicts at both budgets (``_comparison``) and the claims at
every number of links (``_links``); and the verb ``power`` (``_commands``), which writes the
engine's power that the claims section reads.
"""

from . import _commands, _sections  # noqa: F401 - registers the power verb and the sections
from ._links import LINKS, PROFILE

__all__ = ["LINKS", "PROFILE"]
