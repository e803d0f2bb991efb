"""The metrics of the suite: rollout error, energy violation, valid prediction time and the
symplectic error, on numpy arrays (see :mod:`bench.core._metrics` for their definitions)."""

from .core import (
    CLAMP,
    energies,
    energy_mse,
    energy_pct_max_pe,
    energy_pct_max_pe_last,
    energy_violation,
    energy_violation_curve,
    geometric_mean,
    mse,
    n_params,
    perturbed_floor,
    relative_error,
    rollout_error,
    state_difference,
    symplectic_error,
    valid_prediction_time,
    wrap,
)

__all__ = [
    "CLAMP",
    "energies",
    "energy_mse",
    "energy_pct_max_pe",
    "energy_pct_max_pe_last",
    "energy_violation",
    "energy_violation_curve",
    "geometric_mean",
    "mse",
    "n_params",
    "perturbed_floor",
    "relative_error",
    "rollout_error",
    "state_difference",
    "symplectic_error",
    "valid_prediction_time",
    "wrap",
]
