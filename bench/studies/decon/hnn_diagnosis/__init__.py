"""Why the plain (non-separable) HNN on the spring pendulum stalls or diverges at the paper's
budget (claims 1 and 3): its first training steps replayed and probed (``_diagnosis``, a
registered study with a report section and no claim), and its verb ``diagnose-hnn``
(``_commands``). Facts and readings: docs/studies/paper.md.
"""

from . import _commands  # noqa: F401 - registers diagnose-hnn
from ._diagnosis import FILE, STUDY, diagnose, section, stalled_counts, summary

__all__ = ["FILE", "STUDY", "diagnose", "section", "stalled_counts", "summary"]
