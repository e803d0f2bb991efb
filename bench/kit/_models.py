"""The models as the kit names them: their labels in tables and figures, and the trivial
predictors (parameter-free references that every claim's models must beat)."""

from __future__ import annotations

import models

__all__ = ["MODEL_LABELS", "TRIVIAL_MODELS"]

# the parameter-free reference predictors, in the registry's order
TRIVIAL_MODELS = tuple(models.trivial_models())
# The models' names in tables and figures.
MODEL_LABELS = {
    "node": "NODE",
    "node_so": "NODE+SO",
    "hnn": "HNN",
    "hnn_so": "HNN+SO",
    "hnn_so_diss": "HNN+SO + Rayleigh dissipation",
    "mixture_hnn": "mixture HNN (paper's damped HNN)",
    "node_symreg": "NODE + symplectic reg.",
    "node_so_symreg": "NODE+SO + symplectic reg.",
    "lnn": "LNN",
    "vin": "VIN",
    "resnet": "ResNet",
    "constant_velocity": "constant velocity (trivial)",
    "at_rest": "at rest (trivial)",
}
