"""The pixel experiments (claims 11 and 12): the HNN seed's pixel pendulum under our protocol and
under the seed's, the VIN seed's pixel forecasts, the models' labels and the experiments' stored
rows. The task and the budgets: docs/studies/pixels.md.
"""

from __future__ import annotations

import pandas as pd

from ....core import Experiment, experiment_rows, pick_profile, read_rows

# The HNN seed's pixel-pendulum row (greydanus/hamiltonian-nn README, baseline -> HNN)
SEED_ENERGY_MSE = (9.27e-3, 1.53e-4)
PAPER_CPU_S = 4 * 5 * 430.0  # 10000 steps at ~40 ms (width 200, batch 200) + evaluation

_COMMON = {
    "system": "pendulum",
    "observation": "pixels",
    "dt": 0.08,
    "chunk": 3,  # the seed's (x_t, x_t+1): three frames, two observations, one latent step
    "duration": 8.0,  # 100 frames per trajectory
    "n_generated": 160,
    "n_train": 160,
    "n_test": 40,
    "test_chunks": 34,  # 102 frames: 101 observations, the seed's trajectory length
    "width": 200,
    "depth": 2,
    "batch": 200,
    "lr": 1e-3,
    "steps": 10000,
    "eval_checkpoints": 0,
    "dtype": "float32",
}
_QUICK = {
    "n_generated": 40,
    "n_train": 40,
    "n_test": 20,
    "duration": 4.0,
    "test_chunks": 20,
    "width": 128,
    "batch": 64,
    "steps": 1500,
}
_SMOKE = {
    "n_generated": 4,
    "n_train": 4,
    "n_test": 2,
    "duration": 0.8,
    "test_chunks": 3,
    "width": 8,
    "batch": 4,
    "steps": 4,
    "seeds": (0,),
}


def _experiment(
    name: str, title: str, models: tuple[str, ...], claim: int, paper: str
) -> Experiment:
    return Experiment(
        name=name,
        title=title,
        axes={"model": models},
        fixed=_COMMON,
        profile_overrides={"smoke": _SMOKE, "quick": _QUICK, "paper-core": {}},
        claim=claim,
        paper=paper,
    )


PIXEL_HNN = _experiment(
    "pixel_pendulum_hnn", "HNN seed: pixel pendulum, latent HNN vs MLP", ("hnn", "node"), 11, "hnn"
)
PIXEL_VIN = _experiment(
    "pixel_pendulum_vin",
    "VIN seed: pixel pendulum, latent VIN vs ResNet",
    ("vin", "resnet"),
    12,
    "vin",
)
# The HNN seed's protocol (greydanus/hamiltonian-nn: experiment-pixels/train.py, hnn.py,
# nn_models.py and the analysis notebook analyze-pixels.ipynb; docs/studies/pixels.md):
# PyTorch's Adam with weight_decay=1e-5 (an L2 term in the gradient), lr 1e-3 held constant, no
# clipping; the latent step z + f(z) in the loss (explicit Euler, one unit of latent time per
# frame); the auxiliary weight 1 and the dynamics weight 0.1 (ours too: bench.core._pixels);
# batch 200, 10000 steps; the dynamics network initialised as PyTorch builds the seed's MLP
# (init "hnn_seed": orthogonal at gain 1, PyTorch's uniform biases). Under that L2 our own
# initialisation (gain 0.5, zero biases: an H with no curvature at the origin) decays to a zero
# field (docs/studies/pixels.md). Its energy: the notebook's, an affine map from the latent to
# the state fitted on the training encodings, the true H (``seed_energy_mse``). Its test rollout
# is scipy's RK45 at a unit step per frame (the text: "a fourth-order Runge-Kutta
# integrator"): RK4 here. The data, the autoencoder and the three-term loss are the suite's, as
# in ``pixel_pendulum_hnn``.
SEED_PROTOCOL = {
    "optimizer": "adam_l2",
    "lr_schedule": "constant",
    "weight_decay": 1e-5,
    "train_integrator": "euler",
    "eval_integrator": "rk4",
    "model_options": (("init", "hnn_seed"),),
}
SEED_STEPS = 10000
PIXEL_HNN_SEED = Experiment(
    name="pixel_pendulum_hnn_seed",
    paper="hnn",
    title="HNN seed: pixel pendulum as the seed trained and scored it (Adam + L2, Euler step)",
    axes={"model": ("hnn", "node")},
    fixed={**_COMMON, **SEED_PROTOCOL, "steps": SEED_STEPS},
    # quick keeps the seed's steps (the latent HNN needs 5000-10000 of them, module docs) at
    # quick's data, width and batch
    profile_overrides={
        "smoke": _SMOKE,
        "quick": {**_QUICK, "steps": SEED_STEPS},
        "paper-core": {},
    },
    claim=11,
)
# Claim 11 (c), the seed's "the auxiliary loss did not degrade the autoencoder's performance":
# the seed's protocol's HNN trained again without the auxiliary latent loss (aux weight 0), its
# autoencoder's recon MSE beside the protocol's. A further reading at the paper's budget (quick
# and its 30-minute bench leave it out), judged once every seed of a set is stored.
PIXEL_HNN_SEED_NO_AUX = Experiment(
    name="pixel_pendulum_hnn_seed_no_aux",
    paper="hnn",
    title="HNN seed: the pixel pendulum's latent HNN under the seed's protocol without the "
    "auxiliary loss",
    axes={"model": ("hnn",)},
    fixed={**PIXEL_HNN_SEED.fixed, "aux_weight": 0.0},
    profile_overrides={"smoke": _SMOKE, "paper-core": {}},
    profiles=("smoke", "paper", "paper-core"),
    supplementary=lambda c: True,
    claim=11,
)
EXPERIMENTS = (PIXEL_HNN, PIXEL_VIN)
ALL_EXPERIMENTS = (*EXPERIMENTS, PIXEL_HNN_SEED, PIXEL_HNN_SEED_NO_AUX)

LABELS = {"hnn": "HNN", "node": "MLP (HNN seed's baseline)", "vin": "VIN", "resnet": "ResNet"}
SHORT = {"hnn": "HNN", "node": "MLP", "vin": "VIN", "resnet": "ResNet"}


def _rows(results_dir, experiments=None) -> tuple[list[dict], pd.DataFrame, str | None]:
    """(row dicts with their curves, runs table, profile) of ``experiments`` (default: the
    pixel experiments, the seed's protocol included)."""
    from ....core import load_runs

    experiments = ALL_EXPERIMENTS if experiments is None else experiments
    runs = load_runs(results_dir)
    if not len(runs):
        return [], runs, None
    profile = pick_profile(runs, results_dir)
    if profile is not None:
        runs = runs[runs["profile"] == profile]
    parts = [experiment_rows(runs, e.name, profile) for e in experiments]
    parts = [p for p in parts if len(p)]
    table = pd.concat(parts, ignore_index=True) if parts else runs.iloc[0:0]
    if len(table):
        table = table.drop_duplicates("config_hash").reset_index(drop=True)
    hashes = set(table["config_hash"]) if len(table) else set()
    rows = [r for r in read_rows(results_dir) if r.get("config_hash") in hashes]
    return rows, table, profile
