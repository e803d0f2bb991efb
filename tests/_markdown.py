"""Reading rendered Markdown in tests: a section's text by its heading and a table's rows as
dicts, so a test asserts on headings and cell values rather than on whole sentences."""

from __future__ import annotations

import re

__all__ = ["cells", "section", "table_rows"]

_HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*$")
_PIPE = re.compile(r"(?<!\\)\|")


def _title(text: str) -> str:
    return text.lstrip("#").strip()


def section(md: str, title: str) -> str | None:
    """The text under the first heading named ``title`` (any level; ``"## Claims"`` and
    ``"Claims"`` both match, as does a heading that adds `` (...)`` or ``: ...`` such as
    ``"## energy (claim 1)"`` for ``"energy"``), up to the next heading of the same or a higher
    level; None where no such heading exists."""
    want = _title(title)
    lines = md.splitlines()
    for i, line in enumerate(lines):
        m = _HEADING.match(line)
        if not m or not (m.group(2) == want or m.group(2).startswith((want + " (", want + ":"))):
            continue
        level = len(m.group(1))
        body = []
        for x in lines[i + 1 :]:
            h = _HEADING.match(x)
            if h and len(h.group(1)) <= level:
                break
            body.append(x)
        return "\n".join(body)
    return None


def cells(line: str) -> list[str]:
    """The cells of one Markdown table line, stripped, escaped pipes read as ``|``."""
    inner = line.strip().removeprefix("|").removesuffix("|")
    return [c.strip().replace("\\|", "|") for c in _PIPE.split(inner)]


def table_rows(md: str, header_startswith: str) -> list[dict[str, str]]:
    """The rows of the first Markdown table in ``md`` whose header line starts with
    ``header_startswith`` (compared cell by cell, so ``"| claim | part"`` and ``"claim | part"``
    match alike; ``"|"`` matches any table), each a dict from column name to cell; a repeated
    column name gets `` (2)``, `` (3)``... Raises LookupError where no such table exists."""
    want = cells(header_startswith)
    if want and want[-1] == "":
        want = want[:-1]
    lines = md.splitlines()
    for i, line in enumerate(lines):
        if not line.lstrip().startswith("|"):
            continue
        head = cells(line)
        if want and (head[: len(want) - 1] != want[:-1] or len(head) < len(want)):
            continue
        if want and not head[len(want) - 1].startswith(want[-1]):
            continue
        names = [
            h if head[:j].count(h) == 0 else f"{h} ({head[:j].count(h) + 1})"
            for j, h in enumerate(head)
        ]
        rows = []
        for x in lines[i + 2 :]:  # past the header and its --- line
            if not x.lstrip().startswith("|"):
                break
            rows.append(dict(zip(names, cells(x), strict=False)))
        return rows
    raise LookupError(f"no table whose header starts with {header_startswith!r}")
