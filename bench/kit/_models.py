"""The models as the kit names them: their labels in tables and figures, and the trivial
predictors (parameter-free references that every claim's models must beat)."""

from __future__ import annotations

import pandas as pd

import models

from ..core import params_of

__all__ = ["MODEL_LABELS", "TRIVIAL_MODELS", "in_form", "row_options"]

# the parameter-free reference predictors, in the registry's order
TRIVIAL_MODELS = tuple(models.trivial_models())
# The models' names in tables and figures.
MODEL_LABELS = {
    "node": "NODE",
    "node_so": "NODE+SO",
    "node_so_pq": "NODE+SO (paper's form)",
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


def row_options(runs) -> pd.Series:
    """Each row's ``model_options`` as a sorted tuple of (name, value) pairs (``()`` where
    missing or empty), read by the store's one parser (``bench.core.params_of``)."""
    return params_of(runs, "model_options").map(lambda d: tuple(sorted(d.items())))


def in_form(runs, form: dict, others=()) -> pd.DataFrame:
    """``runs`` read in one form of a claim's models: ``form`` maps each role (the model name
    the claim's rule reads, e.g. ``"node_so"``) to the (registered model, options) that plays
    it; those rows are kept, relabelled as the role. Rows of a model named in ``form`` or in
    ``others`` (the models of the claim's other forms) with any other options are dropped,
    so that a rule reading a role by name never mixes two forms; other models pass as they
    are."""
    if not len(runs):
        return runs
    opts = row_options(runs)
    played = {(m, tuple(sorted(o))): role for role, (m, o) in form.items()}
    named = {m for m, _ in form.values()} | set(others)
    key = list(zip(runs["model"], opts, strict=True))
    role = [played.get(k) for k in key]
    keep = [r is not None or m not in named for r, (m, _) in zip(role, key, strict=True)]
    out = runs[keep].copy()
    out["model"] = [r or m for r, (m, _), k in zip(role, key, keep, strict=True) if k]
    return out
