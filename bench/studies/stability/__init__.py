"""Numerical stability at the extremes: long horizons, high energy, stiffness, speed, precision.

Not a training sweep: a list of small cases, each a function ``case(size) -> list[Row]`` that
ends in a recorded outcome for every variant it tries:

- ``ok`` with a finite ``value`` (the metric named in ``metric``),
- ``diverged`` with ``step``, the first integration step whose state is non-finite or beyond a
  bound (a trajectory that runs away is as useless as a NaN one),
- ``failed`` with the error message (an exception, a solver that ran out of ``max_steps``).

Every case runs inside :func:`guard`, which turns exceptions into ``failed`` rows and relabels an
``ok`` row whose value is not finite as ``diverged``, so no NaN leaves this package unlabelled.
Nothing hangs: every solve has a bounded number of steps.

The cases stand on the shared machinery: ground truth from ``systems``' simulate (with its
``rtol``/``atol``/``solver`` options), rollouts from ``models.rollout`` (the true field wrapped
as a model), errors, energy drift and valid-prediction time from ``bench.core._metrics``.

Run all cases with ``python -m bench stability [--profile smoke|quick|paper] [--results DIR]``
or :func:`run_stability`; it writes ``stability.csv`` / ``stability.parquet`` and the figure
``figures/stability.png`` / ``.pdf``; :func:`stability_section` renders REPORT.md's section.

Modules: ``_core`` (rows, guards, sizes, integration helpers), ``_truth`` (cases of the true
dynamics), ``_lnn`` (the Euler-Lagrange solve), ``_learned`` (small learned models), ``_run``
(running, figure, report section).
"""

from ...core import Study, register_study
from ._core import (
    BOUND_FACTOR,
    COLUMNS,
    DT,
    METHOD_NOTES,
    OUTCOMES,
    SIZES,
    Row,
    StabilitySize,
    energy_drift,
    first_bad_step,
    fixed_step,
    guard,
    relative_error,
    rollout_true,
    solve,
    true_model,
    valid_time,
)
from ._learned import case_high_energy_models, case_long_horizon, case_model_precision
from ._lnn import SOLVES, case_lnn_singular
from ._run import (
    CASES,
    main,
    run_cases,
    run_stability,
    stability_figure,
    stability_section,
    to_frame,
)
from ._truth import (
    REFERENCE_SETTING,
    case_dt_sweep,
    case_high_energy_truth,
    case_precision,
    case_relativistic,
    case_stiffness,
    high_energy_states,
    relativistic_roundtrip,
)

__all__ = [
    "BOUND_FACTOR",
    "CASES",
    "COLUMNS",
    "DT",
    "METHOD_NOTES",
    "OUTCOMES",
    "REFERENCE_SETTING",
    "SIZES",
    "SOLVES",
    "Row",
    "StabilitySize",
    "case_dt_sweep",
    "case_high_energy_models",
    "case_high_energy_truth",
    "case_lnn_singular",
    "case_long_horizon",
    "case_model_precision",
    "case_precision",
    "case_relativistic",
    "case_stiffness",
    "energy_drift",
    "first_bad_step",
    "fixed_step",
    "guard",
    "high_energy_states",
    "main",
    "relative_error",
    "relativistic_roundtrip",
    "rollout_true",
    "run_cases",
    "run_stability",
    "solve",
    "stability_figure",
    "stability_section",
    "to_frame",
    "true_model",
    "valid_time",
]

from . import _commands  # noqa: E402, F401 - registers `python -m bench stability`

STUDY = register_study(
    Study(
        name="stability",
        stem="stability",
        results_figure=stability_figure,
        section=stability_section,
        section_title="Numerical stability",
    )
)
