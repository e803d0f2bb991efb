"""Provenance of a result: the software and hardware that produced a run, as the columns
:data:`PROVENANCE_COLUMNS` of every row and of ``bench_meta.json`` (:func:`provenance`, once
per process), and the tools that compare and backfill them (``python -m bench.provenance show |
compare DIR_A DIR_B | backfill DIR KEY=VALUE..``). Rows from two CPU types or core counts agree
to float32 round-off only; from one CPU type, core count and lock file they are bit-identical.
"""

from __future__ import annotations

import functools
import json
import platform
import subprocess
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

PACKAGES = ("jax", "jaxlib", "equinox", "diffrax", "optax", "optimistix", "numpy")
VERSION_COLUMNS = ("python_version", *(f"{p}_version" for p in PACKAGES))
DEVICE_COLUMNS = ("backend", "device")
CPU_COLUMNS = ("cpu_vendor", "cpu_family_model", "cpu_simd", "xla_flags", "cpu_cores")
GIT_COLUMNS = ("git_commit", "git_dirty")
PROVENANCE_COLUMNS = (*VERSION_COLUMNS, *DEVICE_COLUMNS, *CPU_COLUMNS, *GIT_COLUMNS)
# What they hold:
# - python_version and <package>_version for each of PACKAGES (the installed distribution's);
# - backend (jax.default_backend(): cpu, gpu, tpu) and device (the GPU's device_kind, e.g.
#   "NVIDIA H100 80GB HBM3", or on CPU the processor's model name);
# - the arithmetic: cpu_vendor (e.g. AuthenticAMD), cpu_family_model ("family/model" from
#   /proc/cpuinfo, e.g. 25/1), cpu_simd (the SIMD extensions of SIMD_FLAGS that the CPU has,
#   which XLA's CPU code generator may use, space-separated), xla_flags ($XLA_FLAGS, empty when
#   unset) and cpu_cores (the cores the process may run on, its affinity mask, which sizes XLA's
#   CPU thread pools: a sweep worker is pinned to its own). float32 round-off differs between
#   CPU types (another vector width, another fused reduction) and core counts (XLA splits a
#   reduction over its threads), and round-off can decide a training run's fate:
#   bench.studies.decon.hnn_diagnosis replays a plain-HNN spring run that stalls on one core
#   and learns on two;
# - git_commit (the full hash of this checkout's HEAD) and git_dirty (whether the working tree
#   differs from it outside results/; None when not known).
# A value that could not be determined is UNKNOWN. Rows written before provenance existed lack
# the columns (NaN in the runs table): provenance_markdown counts them as "not recorded" and
# compare_provenance says so, without guessing.
# x86 and Arm vector extensions LLVM can target from XLA's CPU backend (``/proc/cpuinfo`` names)
SIMD_FLAGS = (
    "sse4_1",
    "sse4_2",
    "avx",
    "avx2",
    "fma",
    "f16c",
    "avx512f",
    "avx512dq",
    "avx512bw",
    "avx512vl",
    "avx512_vnni",
    "avx512_bf16",
    "avx512_fp16",
    "amx_tile",
    "amx_bf16",
    "asimd",
    "sve",
    "sve2",
)
UNKNOWN = "unknown"
_REPO = Path(__file__).resolve().parents[2]


# The columns that name the machine a run's times were measured on: times from two machines
# are not comparable.
MACHINE_COLUMNS = ("device", "cpu_family_model")


def machine_key(rows):
    """Per row, the machine it ran on (its :data:`MACHINE_COLUMNS` the table has, joined by a
    space); "" where the row records none of them (rows stored before the fields)."""
    import pandas as pd

    cols = [c for c in MACHINE_COLUMNS if c in rows]
    if not cols or not len(rows):
        return pd.Series("", index=rows.index, dtype="string")
    parts = rows[cols].astype("string").fillna("")
    return parts.agg(lambda r: " ".join(x for x in r if x), axis=1).astype("string")


def _version(package: str) -> str:
    from importlib import metadata

    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        module = sys.modules.get(package)
        return str(getattr(module, "__version__", UNKNOWN))


def _cpu_name() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or UNKNOWN


def _cpu() -> dict[str, str]:
    """``cpu_vendor``, ``cpu_family_model``, ``cpu_simd`` (see :data:`SIMD_FLAGS`),
    ``xla_flags`` and ``cpu_cores`` of this machine and process."""
    import os

    from ._env import cpu_count

    info: dict[str, str] = {}
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            key, _, value = line.partition(":")
            key = key.strip()
            if key in ("vendor_id", "cpu family", "model", "flags", "Features", "CPU implementer"):
                info.setdefault(key, value.strip())
            if not line.strip() and info:  # the first processor is enough
                break
    except OSError:
        pass
    flags = set((info.get("flags") or info.get("Features") or "").split())
    vendor = info.get("vendor_id") or info.get("CPU implementer") or platform.machine()
    family_model = (
        f"{info['cpu family']}/{info['model']}" if "cpu family" in info and "model" in info else ""
    )
    return {
        "cpu_vendor": vendor or UNKNOWN,
        "cpu_family_model": family_model or UNKNOWN,
        "cpu_simd": " ".join(f for f in SIMD_FLAGS if f in flags) if flags else UNKNOWN,
        "xla_flags": os.environ.get("XLA_FLAGS", ""),
        "cpu_cores": str(cpu_count()),
    }


def _device() -> tuple[str, str]:
    """(backend, device name) of JAX's default backend (initialises it)."""
    try:
        import jax

        backend = jax.default_backend()
        if backend == "cpu":
            return backend, _cpu_name()
        return backend, str(jax.devices()[0].device_kind)
    except Exception:  # noqa: BLE001 - provenance never stops a run
        return UNKNOWN, UNKNOWN


def _git(*args: str) -> str | None:
    try:
        out = subprocess.run(
            ["git", "-C", str(_REPO), *args], capture_output=True, text=True, timeout=10
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout if out.returncode == 0 else None


def _git_state() -> tuple[str, bool | None]:
    """(commit, dirty) of the checkout this package was imported from.

    Only when the package's own folder is the top of a git work tree (an installed copy inside
    some other repository is not this code's history). ``dirty``: tracked or untracked
    (not ignored) changes outside ``results/``, which a sweep itself writes to.
    """
    out = _git("rev-parse", "--show-toplevel", "HEAD")
    lines = (out or "").split()
    if len(lines) != 2 or Path(lines[0]).resolve() != _REPO:
        return UNKNOWN, None
    status = _git("status", "--porcelain", "--", ".", ":(exclude)results")
    return lines[1], None if status is None else bool(status.strip())


@functools.cache
def provenance() -> dict[str, str | bool | None]:
    """This process's provenance, one value per :data:`PROVENANCE_COLUMNS` (computed once).

    Asks JAX for its default backend, which initialises it: call it where JAX runs anyway.
    """
    out: dict[str, str | bool | None] = {"python_version": platform.python_version()}
    out.update({f"{p}_version": _version(p) for p in PACKAGES})
    out["backend"], out["device"] = _device()
    out.update(_cpu())
    out["git_commit"], out["git_dirty"] = _git_state()
    return out


# ------------------------------------------------------------------------ tables and checks
def _values(df, column: str) -> tuple[list[tuple[str, int]], int]:
    """(value, count) of the recorded values of ``column``, and the number not recorded."""
    if column not in df:
        return [], len(df)
    col = df[column]
    missing = int(col.isna().sum())
    counts = col.dropna().map(_label).value_counts()
    return [(str(v), int(n)) for v, n in counts.items()], missing


def _label(v) -> str:
    if isinstance(v, bool | np.bool_):
        return "dirty" if v else "clean"
    return str(v)


# the most distinct values a cell or a warning lists (a folder filled over many commits has
# a hundred git_commit values); the rest are counted
MAX_LISTED = 8


def _cell(values: list[tuple[str, int]], missing: int, total: int, short: bool = False) -> str:
    parts = []
    for v, n in values[:MAX_LISTED]:
        text = v[:10] if short and v != UNKNOWN else v
        parts.append(text if n == total else f"{text} ({n})")
    rest = values[MAX_LISTED:]
    if rest:
        parts.append(f"{len(rest)} more ({sum(n for _, n in rest)})")
    if missing:
        parts.append("not recorded" if missing == total else f"not recorded ({missing})")
    return ", ".join(parts).replace("|", "\\|") or "-"


def provenance_markdown(runs, by: str = "profile") -> str:
    """A markdown table of the provenance of the runs, one column per ``by`` value (profile).

    Each cell lists the distinct values recorded for that field with their run counts where
    they are not unanimous; rows written before provenance existed count as "not recorded".
    """
    if runs is None or len(runs) == 0:
        return "No runs."
    groups = sorted(runs[by].fillna("?").astype(str).unique()) if by in runs else ["all"]
    header = "| field | " + " | ".join(f"{by} `{g}`" for g in groups) + " |"
    lines = [header, "|" + " --- |" * (len(groups) + 1)]
    parts = [runs[runs[by].fillna("?").astype(str) == g] if by in runs else runs for g in groups]
    lines.append("| runs | " + " | ".join(str(len(p)) for p in parts) + " |")
    for column in PROVENANCE_COLUMNS:
        cells = [_cell(*_values(p, column), len(p), short=column == "git_commit") for p in parts]
        lines.append(f"| {column} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _listed(values, column: str) -> str:
    """A set of recorded values in words: all of them up to :data:`MAX_LISTED` (commits
    shortened), else how many and the first few."""
    vals = sorted(v[:10] if column == "git_commit" else v for v in values)
    if len(vals) > MAX_LISTED:
        return f"{len(vals)} values ({', '.join(vals[:3])}, ...)"
    return ", ".join(vals)


def compare_provenance(df_a, df_b, names: Sequence[str] = ("a", "b")) -> list[str]:
    """Warnings (one line each) where two runs tables differ in provenance.

    For each of :data:`PROVENANCE_COLUMNS` except ``git_dirty``: a warning when both sides
    recorded the field and the sets of values differ, else when either side has runs without
    it (not recorded or ``unknown``), since then the two cannot be shown to match. An empty
    list: every run of both sides recorded every field, with the same sets of values.
    """
    a_name, b_name = names
    warnings = []
    for column in (c for c in PROVENANCE_COLUMNS if c != "git_dirty"):
        va, ma = _values(df_a, column)
        vb, mb = _values(df_b, column)
        sa = {v for v, _ in va if v != UNKNOWN}
        sb = {v for v, _ in vb if v != UNKNOWN}
        ua = ma + sum(n for v, n in va if v == UNKNOWN)
        ub = mb + sum(n for v, n in vb if v == UNKNOWN)
        if sa and sb and sa != sb:
            show = _listed(sa, column), _listed(sb, column)
            warnings.append(f"{column} differs: {show[0]} ({a_name}) vs {show[1]} ({b_name})")
        elif ua or ub:
            unk = " and ".join(f"{n} runs of {s}" for n, s in ((ua, a_name), (ub, b_name)) if n)
            known = "; ".join(
                f"{s}: {_listed(v, column)}" for v, s in ((sa, a_name), (sb, b_name)) if v
            )
            warnings.append(f"{column} not recorded for {unk}" + (f" ({known})" if known else ""))
    return warnings


def compare_results(dir_a, dir_b) -> list[str]:
    """:func:`compare_provenance` of the stored runs of two results folders."""
    from ._store import load_runs

    return compare_provenance(load_runs(dir_a), load_runs(dir_b), names=(str(dir_a), str(dir_b)))


def backfill(results_dir, known: Mapping[str, object]) -> int:
    """Add provenance to the stored rows of ``results_dir`` that have none; rebuild its tables.

    ``known`` maps columns of :data:`PROVENANCE_COLUMNS` to the values known to have produced
    those rows; every other column becomes :data:`UNKNOWN` (``git_dirty``: ``None``). Rows that
    already carry provenance are left alone. Returns the number of rows changed.
    """
    from ._store import ROWS, read_rows, rebuild_tables, write_row

    bad = sorted(set(known) - set(PROVENANCE_COLUMNS))
    if bad:
        raise ValueError(f"unknown provenance fields {bad}; allowed: {list(PROVENANCE_COLUMNS)}")
    if not (Path(results_dir) / ROWS).is_dir():
        raise ValueError(f"{results_dir} has no {ROWS}/ folder of stored rows")
    changed = 0
    for row in read_rows(results_dir):
        if any(c in row for c in PROVENANCE_COLUMNS):
            continue
        for column in PROVENANCE_COLUMNS:
            row[column] = known.get(column, None if column == "git_dirty" else UNKNOWN)
        write_row(results_dir, row)
        changed += 1
    if changed:
        rebuild_tables(results_dir)
    return changed


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    verb = args.pop(0) if args else ""
    if verb == "show" and not args:
        print(json.dumps(provenance(), indent=1))
        return 0
    if verb == "compare" and len(args) == 2:
        warnings = compare_results(*args)
        print("\n".join(f"warning: {w}" for w in warnings) or "same provenance")
        return 0
    if verb == "backfill" and args:
        pairs = [a.split("=", 1) for a in args[1:]]
        if any(len(p) != 2 for p in pairs):
            raise ValueError("backfill takes DIR then KEY=VALUE pairs")
        print(f"{backfill(args[0], dict(pairs))} rows given provenance")
        return 0
    print("usage: python -m bench.provenance show | compare DIR_A DIR_B | backfill DIR K=V ...")
    return 2
