"""README's findings table, generated from the committed reports.

``python -m bench.findings`` rewrites the block between ``<!-- findings:begin -->`` and
``<!-- findings:end -->`` of README.md from the *Claims* tables of
``results/reference/quick/REPORT.md`` and ``results/reference/paper/REPORT.md`` (paper-core);
``--check`` exits 1, naming the file, when the README no longer says what the reports say.
First a few sentences per paper generated from the verdicts (:func:`summary`). Then one row per
claim: the claim, the paper's sentence, the final verdict at both budgets (paper-core's with
its replication: seeds 0-4 and 5-9 where they differ, else whether 5-9 are stored), and the
measured effect behind the paper-core verdict with its 90% interval and the seeds it rests on;
then each budget's margin-dependent claims and the compute the committed runs took (the
reports' *compute on* lines; the GPU folder's beside them). ``--protocols`` prints the seeds'
protocols beside ours. The margins themselves are in
docs/verdicts.md and each report's *Margin policy*.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
BUDGETS = {"quick": "results/reference/quick", "paper-core": "results/reference/paper"}
GPU = "results/reference/paper_gpu"  # the paper profile on a GPU, where one was lent
BEGIN, END = "<!-- findings:begin -->", "<!-- findings:end -->"
FIGURE = "results/reference/headlines"  # each claim's headline at both budgets
_HEADER = "| claim | statement | verdict |"
PROTOCOL_HEADER = "| protocol | ours | the seed's |"  # bench.kit._protocols.HEADER


def claims_table(report: str) -> dict[str, dict[str, str]]:
    """The *Claims* table of a REPORT.md: claim label -> column -> cell text."""
    lines = report.splitlines()
    try:
        start = next(i for i, line in enumerate(lines) if line.startswith(_HEADER))
    except StopIteration:
        raise ValueError(f"no claims table (a line starting {_HEADER!r}) in the report") from None
    cols = [c.strip() for c in lines[start].strip("|").split("|")]
    out = {}
    for line in lines[start + 2 :]:
        if not line.startswith("|"):
            break
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        out[cells[0]] = dict(zip(cols, cells, strict=True))
    return out


def _section(report: str, title: str) -> list[str]:
    lines = report.splitlines()
    try:
        start = lines.index(f"## {title}")
    except ValueError:
        raise ValueError(f"no '## {title}' section in the report") from None
    end = next((i for i in range(start + 1, len(lines)) if lines[i].startswith("## ")), None)
    return lines[start + 1 : end]


def policy_rows(report: str) -> list[tuple[str, str, str]]:
    """(quantity, margin, plausible band) of the report's *Margin policy* table."""
    rows = [x for x in _section(report, "Margin policy") if x.startswith("| ")]
    return [tuple(c.strip() for c in x.strip("|").split("|")[:3]) for x in rows[2:]]


def margin_dependent(report: str) -> str:
    """The report's one-line list of margin-dependent claims ('none' when it has none)."""
    for line in _section(report, "Margin-dependent claims"):
        if line.startswith("Margin-dependent: "):
            return _grouped(line.removeprefix("Margin-dependent: claim ").rstrip("."))
    return "none"


def _grouped(keys: str) -> str:
    """``1, 4 (a, b), 4 (c), 5`` -> ``1, 4 (2 readings), 5``: a claim's readings counted."""
    found: dict[str, list[str]] = {}
    for claim, variant in re.findall(r"(\d+)(?: \(([^)]*)\))?", keys):
        found.setdefault(claim, []).append(variant)
    out = []
    for claim, variants in found.items():
        named = [v for v in variants if v]
        if len(named) > 1:
            out.append(f"{claim} ({len(named)} readings)")
        else:
            out.append(f"{claim} ({named[0]})" if named else claim)
    return ", ".join(out)


def _verdict(row: dict[str, str] | None) -> str:
    if row is None:
        return "not run"
    text = row["verdict"]
    return text + (" (not discriminating)" if _undiscriminating(row) else "")


def _undiscriminating(row: dict[str, str]) -> bool:
    """The claims table's discriminating cell reads no (on every system, or on some)."""
    return row.get("discriminating", "").startswith("**no**")


def _replicated(row: dict[str, str] | None) -> str:
    """The final verdict with its replication: both seed sets' readings where they differ,
    else whether the replication seeds agree, are pending or are not run."""
    if row is None:
        return "not run"
    sets = [c for c in row if c.startswith("seeds ")]
    rep = row.get("replicates", "not run")
    if len(sets) < 2:
        return _verdict(row)
    first, second = (re.sub(r" \(\d+\)$", "", row[c]) for c in sets[:2])
    if rep == "**no**":
        spans = [c.removeprefix("seeds ") for c in sets[:2]]
        return f"{_verdict(row)}: {spans[0]} {first}, {spans[1]} {second}"
    if rep == "yes":
        if first != row["verdict"].strip("*").split(":")[0]:  # ten seeds resolve what five did not
            spans = " and ".join(c.removeprefix("seeds ") for c in sets[:2])
            return f"{_verdict(row)}, replicates (pooled; {spans}: {first} each)"
        return f"{_verdict(row)}, replicates"
    return f"{_verdict(row)}; {sets[1].removeprefix('seeds ')} {rep}"


def _why(row: dict[str, str]) -> str:
    """'<what the effect measures>: <value> [<90% interval>] (seeds <span>)' from the effect
    column, with the seeds the final reading rests on: both sets pooled where they replicate,
    else the first set's."""
    m = re.fullmatch(r"(\S+) \((.*)\)", row["effect"])
    what, value = (m.group(2), m.group(1)) if m else ("effect", row["effect"])
    sets = [c.removeprefix("seeds ") for c in row if c.startswith("seeds ")]
    pooled = [c.removeprefix("pooled ") for c in row if c.startswith("pooled ")]
    if row.get("replicates") == "yes" and pooled:
        seeds = f" (seeds {pooled[0]})"
    elif sets:
        seeds = f" (seeds {sets[0]})"
    else:
        seeds = ""
    return f"{what}: {value} {row['90% CI']}{seeds}"


def protocol_rows(text: str) -> dict[str, tuple[str, str]]:
    """The first two-protocol table (``kit.protocol_table``) of ``text``: row -> (ours, the
    seed's); empty without one."""
    lines = text.splitlines()
    if PROTOCOL_HEADER not in lines:
        return {}
    out = {}
    for line in lines[lines.index(PROTOCOL_HEADER) + 2 :]:
        if not line.startswith("|"):
            break
        name, ours, seeds = (c.strip() for c in line.strip().strip("|").split("|"))
        out[name] = (ours, seeds)
    return out


def protocols(report: str) -> dict[int, dict[str, tuple[str, str]]]:
    """claim -> its :func:`protocol_rows`, for every report section ``## ... (claim N)`` (or
    ``(claims N and M)``: the table is claim N's) with a two-protocol table."""
    out = {}
    for part in re.split(r"^(?=## )", report, flags=re.M):
        m = re.match(r"## .*\(claims? (\d+)", part)  # a shared section: its first claim
        rows = protocol_rows(part) if m else {}
        if rows:
            out[int(m.group(1))] = rows
    return out


_READING = re.compile(
    r"(pending|partly reproduced|not reproduced|reproduced|inconclusive|not run)"
    r"[^;]*?seeds ([0-9, -]+)\)"
)


def _short(cell: str) -> str:
    """What a protocol-table verdict cell (``_protocols.verdict_text``: a reading per seed set)
    says in a few words: the first set's verdict and whether the later sets read it alike
    (``replicates``, ``does not replicate``) or are still pending; the cell where it names no
    seed set (``not run``)."""
    sets = _READING.findall(cell)
    if not sets:
        return cell
    first, *rest = (v for v, _ in sets)
    if not rest or first == "pending":
        return first
    if "pending" in rest:
        return f"{first}; {', '.join(s for v, s in sets[1:] if v == 'pending')} pending"
    return f"{first}, {'replicates' if set(rest) == {first} else 'does not replicate'}"


def _protocol_lines(reports: dict[str, str]) -> list[str]:
    quick, core = (protocols(reports[b]) for b in ("quick", "paper-core"))
    if not quick and not core:
        return []
    lines = [
        "",
        "Where a seed's own protocol differs from ours, both run and the seed's decides; each "
        "model's learning gate at each budget (a model that did not learn leaves its "
        "comparison untested, not refuted; REPORT.md sets the protocols side by side):",
        "",
        "| claim | learned at quick: ours / the seed's | quick: ours / the seed's | "
        "learned at paper-core | paper-core: ours / the seed's |",
        "| --- | --- | --- | --- | --- |",
    ]
    for claim in sorted({*quick, *core}):
        q, c = quick.get(claim, {}), core.get(claim, {})

        def pair(rows, key, short=True):
            ours, seeds = rows.get(key, ("not run", "not run"))
            return f"{_short(ours)} / {_short(seeds)}" if short else f"{ours} / {seeds}"

        lines.append(
            f"| {claim} | {pair(q, 'learned', False)} | {pair(q, 'verdict')} | "
            f"{pair(c, 'learned', False)} | {pair(c, 'verdict')} |"
        )
    return lines


PAPER_NAMES = {
    "deconstructing": "The Deconstructing paper",
    "hnn": "The HNN seed",
    "lnn": "The LNN seed",
    "vin": "The VIN seed",
}


def claim_papers() -> dict[int, str]:
    """Claim number -> the paper it comes from (its experiments' ``paper``)."""
    from .core import available, get

    out: dict[int, str] = {}
    for name in available():
        e = get(name)
        if e.claim is not None:
            out.setdefault(e.claim, e.paper)
    return out


def _claim_of(label: str) -> int:
    return int(label.split()[0])


def _reading(row: dict[str, str]) -> str:
    """A claims-table row's verdict in a few words (the headline's status kept)."""
    text = re.sub(r" \(([^)]*)\)", r", \1", row["verdict"].strip("*"))
    if _undiscriminating(row):
        # a signed verdict stands on the systems that discriminate (the others' parts void)
        signed = text.startswith(("reproduced", "partly", "not reproduced"))
        text += ", a system not discriminating" if signed else ", not discriminating"
    return text


def _join(items: list[str]) -> str:
    return ", ".join(items[:-1]) + (" and " if len(items) > 1 else "") + items[-1]


def summary(core: dict, quick: dict, papers: dict[int, str] | None = None) -> list[str]:
    """Two or three sentences per paper, generated from the verdicts (paper-core's where it
    judges a claim, else quick's): what holds, what is contradicted, what could not be decided
    and why. A claim with several readings (claim 4) is named once per distinct verdict."""
    papers = claim_papers() if papers is None else papers
    out = []
    for paper, name in PAPER_NAMES.items():
        labels = [x for x in (*core, *(q for q in quick if q not in core))]
        labels = [x for x in labels if papers.get(_claim_of(x)) == paper]
        if not labels:
            continue
        groups: dict[str, list[str]] = {"holds": [], "against": [], "open": []}
        readings: dict[tuple[int, str], int] = {}
        for label in labels:
            key = (_claim_of(label), _reading(core.get(label) or quick[label]))
            readings[key] = readings.get(key, 0) + 1
        seen: set[tuple[int, str]] = set()
        for label in labels:
            row = core.get(label) or quick[label]
            budget = "" if label in core else " (quick)"
            reading = _reading(row)
            key = (_claim_of(label), reading)
            if key in seen:
                continue
            seen.add(key)
            total = sum(1 for x in labels if _claim_of(x) == key[0])
            if total > 1:
                reading += f", {readings[key]} of {total} readings"
            claim = str(_claim_of(label)) + budget
            if reading.startswith(("reproduced", "partly reproduced: headline holds")):
                groups["holds"].append(f"{claim} ({reading})")
            elif reading.startswith(("not reproduced", "partly reproduced")):
                groups["against"].append(f"{claim} ({reading})")
            else:
                groups["open"].append(f"{claim} ({reading})")
        said = []
        if groups["holds"]:
            said.append(f"holds: claim {_join(groups['holds'])}")
        if groups["against"]:
            said.append(f"contradicted in part or whole: claim {_join(groups['against'])}")
        if groups["open"]:
            said.append(f"not decided: claim {_join(groups['open'])}")
        text = "; ".join(said)
        out.append(f"- **{name}.** {text[:1].upper()}{text[1:]}.")
    return out


def findings(root: Path = ROOT) -> str:
    """The findings block from the committed reports under ``root``: a few generated sentences
    per paper, then the claims table."""
    reports = {b: (root / d / "REPORT.md").read_text() for b, d in BUDGETS.items()}
    quick, core = (claims_table(reports[b]) for b in ("quick", "paper-core"))
    lines = [
        "At paper-core (quick where paper-core does not judge a claim), generated from the "
        "verdicts:",
        "",
        *summary(core, quick),
        "",
        f"![each claim's headline effect per budget]({FIGURE}.png) ({FIGURE}.pdf: "
        "the headline effect in units of its margin, coloured by verdict)",
        "",
        "| claim | the paper says | quick | paper-core (seeds 0-4, then 5-9) | "
        "measured at paper-core (90% CI) |",
        "| --- | --- | --- | --- | --- |",
    ]
    said = None  # a claim's further readings follow it: its statement once
    for label in [*core, *(label for label in quick if label not in core)]:
        row = core.get(label) or quick[label]
        why = _why(core[label]) if label in core else "-"
        statement = "as above" if row["statement"] == said else row["statement"]
        said = row["statement"]
        lines.append(
            f"| {label} | {statement} | {_verdict(quick.get(label))} | "
            f"{_replicated(core.get(label))} | {why} |"
        )
    dependent = "; ".join(f"at {b}, claims {margin_dependent(r)}" for b, r in reports.items())
    lines += ["", f"Margin-dependent inside the bands: {dependent}."]
    lines += ["", compute_sentence(root)]
    return "\n".join(lines)


def compute_lines(report: str) -> list[str]:
    """The report's ``- compute on DEVICE: ...`` lines, without the bullet."""
    return [x[2:] for x in report.splitlines() if x.startswith("- compute on ")]


def compute_sentence(root: Path = ROOT) -> str:
    """What the committed runs of paper-core (and of the GPU folder, if any) took."""
    parts = []
    for label, folder in (("paper-core", BUDGETS["paper-core"]), ("paper_gpu", GPU)):
        path = root / folder / "REPORT.md"
        if path.exists():
            parts += [
                f"{label} on {x[len('compute on ') :]}" for x in compute_lines(path.read_text())
            ]
    return "Compute of the committed runs: " + ("; ".join(parts) or "not recorded") + "."


def _split(text: str) -> tuple[str, str, str]:
    if BEGIN not in text or END not in text:
        raise ValueError(f"README.md has no {BEGIN} ... {END} block")
    head, rest = text.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    return head, rest.split(END, 1)[0], tail


def current(readme: Path = README) -> str:
    """The findings block README.md holds now."""
    return _split(readme.read_text())[1].strip("\n")


def draw(root: Path = ROOT) -> list[Path]:
    """The headline figure from the budgets' ``headlines.csv`` (each report writes its own)."""
    from .kit import fig_headlines

    return fig_headlines({b: root / d for b, d in BUDGETS.items()}, root / FIGURE)


def write(readme: Path = README, root: Path = ROOT) -> bool:
    """Rewrite README's block from the reports, and the headline figure; True when the block
    changed."""
    draw(root)
    head, old, tail = _split(readme.read_text())
    new = "\n" + findings(root) + "\n"
    if new == old:
        return False
    readme.write_text(head + BEGIN + new + END + tail)
    return True


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m bench.findings", description=__doc__)
    p.add_argument("--check", action="store_true", help="exit 1 if README.md is out of date")
    p.add_argument(
        "--protocols",
        action="store_true",
        help="print the table of the seeds' protocols beside ours (learning gates, verdicts)",
    )
    args = p.parse_args(argv)
    if args.protocols:
        reports = {b: (ROOT / d / "REPORT.md").read_text() for b, d in BUDGETS.items()}
        print("\n".join(_protocol_lines(reports)).strip("\n"))
        return 0
    if args.check:
        if current() != findings():
            print(f"{README}: findings table out of date; run python -m bench.findings")
            return 1
        return 0
    print(f"{README}: {'rewritten' if write() else 'already up to date'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
