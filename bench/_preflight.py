"""``python -m bench preflight``: every cell of some experiments at a profile's sizes, trained a
few steps, so that a long campaign (paper-core on this CPU, the paper profile on a GPU or a
cluster) does not find a broken cell hours in.

A cell is a run configuration up to its seed: the profile's first seed stands for the others.
Each is built (its data at the profile's sizes, generated or read, and cached as a real run's
would be), trained ``steps`` steps without learning-curve checkpoints and evaluated by the
sweep's own pipeline (:func:`bench.core._execute.execute_run`). Nothing is stored in a results
folder: what counts is the failures (a size the data cannot give, a model a scene refuses, a
missing file), one line per cell. Smoke-sized tests cannot catch those: they run other sizes.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Iterable

from .core import Experiment, RunConfig, expand, get

__all__ = ["cells", "preflight"]

STEPS = 2


def cells(
    experiments: Iterable[str | Experiment], profile: str, models=None
) -> list[tuple[str, RunConfig, str]]:
    """(experiment name, configuration, label) of each cell of ``experiments`` at ``profile``,
    once: the first seed of the configurations that differ only in their seed. The label names
    the cell by the axes that vary at ``profile`` (``model=vin n_train=8 noise=0.0 seed=0``)."""
    out, seen = [], set()
    for exp in experiments:
        exp = get(exp) if isinstance(exp, str) else exp
        runs = expand(exp, profile, models=models)
        axes = [k for k in exp.axes if k != "seed" and len({repr(getattr(c, k)) for c in runs}) > 1]
        for c in runs:
            key = dataclasses.replace(c, seed=0).config_hash
            if key not in seen:
                seen.add(key)
                label = " ".join(f"{k}={_value(getattr(c, k))}" for k in axes)
                out.append((exp.name, c, f"{label} seed={c.seed}".lstrip()))
    return out


def _value(v) -> str:
    if isinstance(v, tuple) and all(isinstance(x, tuple) and len(x) == 2 for x in v):
        return "{" + ", ".join(f"{a}: {b}" for a, b in v) + "}"  # options, system_params
    return str(v)


def preflight(
    experiments: Iterable[str | Experiment],
    profile: str,
    *,
    steps: int = STEPS,
    models=None,
    echo: Callable[[str], None] | None = print,
) -> list[dict]:
    """Run every cell of ``experiments`` at ``profile`` for ``steps`` training steps (at most
    its own) and return their rows (``experiment`` and ``seconds`` added; never stored).
    ``echo`` gets one line per cell as it ends."""
    from .core import bound_compiled_programs, configure_numerics, execute_run

    configure_numerics()  # the precisions a sweep's workers have
    if steps < 1:
        raise ValueError(f"steps must be an integer >= 1; got {steps}")
    todo = cells(experiments, profile, models)
    rows = []
    for i, (name, c, label) in enumerate(todo, 1):
        run = dataclasses.replace(c, steps=min(steps, c.steps), eval_checkpoints=0)
        t = time.perf_counter()
        row = {**execute_run(run), "experiment": name, "seconds": time.perf_counter() - t}
        rows.append(row)
        bound_compiled_programs()  # many cells in one process: keep its memory maps bounded
        if echo is not None:
            error = f"  {str(row.get('error') or '')[:300]}" if row["status"] == "failed" else ""
            echo(
                f"[{i}/{len(todo)}] {row['status']:8s} {row['seconds']:6.1f} s  {name}: "
                f"{label}{error}"
            )
    return rows
