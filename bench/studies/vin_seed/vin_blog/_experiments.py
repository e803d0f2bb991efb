"""The VIN seed's pixel pendulum as its authors' code runs it: the experiment and its cells."""

from __future__ import annotations

from ....core import Experiment

# The seed's pendulum (its authors' config/pendulum.gin: m = l = 1, g = 9.82)
SEED_PENDULUM = (("g", 9.82), ("length", 1.0), ("mass", 1.0))
SEED_STEPS, SEED_LR = 8000, 3e-4  # config/pixels.gin: 8000 epochs (one full batch each), Adam
# The blog's panels as (model, latent): a VIN on SO(2), the dynamic VAE (a ResNet on a planar
# latent, the blog's residual baseline), the VAE (no dynamics, planar) and the Lie group VAE
# (no dynamics, SO(2))
CELLS = {
    "vin_so2": ("vin", "so2"),
    "resnet": ("resnet", "r2"),
    "vae": ("at_rest", "r2"),
    "lie_vae": ("at_rest", "so2"),
}
LABELS = {
    "vin_so2": "VIN-SO(2)",
    "resnet": "dynamic VAE (ResNet, planar)",
    "vae": "VAE (planar, no dynamics)",
    "lie_vae": "Lie group VAE (SO(2), no dynamics)",
}
SHORT = {"vin_so2": "VIN-SO(2)", "resnet": "ResNet", "vae": "VAE", "lie_vae": "Lie VAE"}
BASELINES = ("vae", "resnet", "lie_vae")


def _opts(latent: str) -> tuple:
    return (("latent", latent),)


def _cell(name: str) -> dict:
    model, latent = CELLS[name]
    return {"model": model, "opt:latent": latent}


_FIXED = {
    "system": "pendulum",
    "system_params": SEED_PENDULUM,
    "observation": "frames",
    "dt": 0.1,  # the seed's
    "chunk": 11,  # its windows: horizon 10, 11 frames
    "duration": 5.0,  # 50 frames per training trajectory (run_pixels_exp.sh)
    "n_generated": 3,
    "n_train": 3,  # its largest training set: 3 trajectories
    "n_test": 20,
    "test_chunks": 9,  # 99 frames, its 10 s forecasts
    "width": 1000,  # its hidden layers (encoder, decoder, potential and ResNet alike)
    "depth": 1,  # one hidden layer in the dynamics
    "batch": 200,  # >= the 120 windows: full batches
    "lr": SEED_LR,
    "optimizer": "adam_l2",
    "weight_decay": 0.0,
    "lr_schedule": "constant",
    "steps": SEED_STEPS,
    "eval_checkpoints": 0,
    "dtype": "float32",
}
# quick: 3000 steps of 32 windows at width 128 (about 50 CPU seconds a run here, 20 runs),
# lr x steps as the seed's; paper-core: the seed's steps and batches at width 256
QUICK_STEPS = 3000
_QUICK = {
    "width": 128,
    "batch": 32,
    "steps": QUICK_STEPS,
    "lr": float(f"{SEED_LR * SEED_STEPS / QUICK_STEPS:.3g}"),
}
_PAPER_CORE = {"width": 256}
_SMOKE = {
    "n_test": 2,
    "test_chunks": 3,
    "width": 8,
    "batch": 4,
    "steps": 4,
    "seeds": (0,),
}


def _include(c) -> bool:
    return (c.model, dict(c.model_options).get("latent")) in set(CELLS.values())


VIN_BLOG = Experiment(
    name="pixel_pendulum_vin_blog",
    paper="vin",
    title="VIN seed (blog): pixel pendulum, position latents; VIN-SO(2) vs its baselines",
    axes={"model": ("vin", "resnet", "at_rest"), "model_options": (_opts("so2"), _opts("r2"))},
    fixed=_FIXED,
    profile_overrides={"smoke": _SMOKE, "quick": _QUICK, "paper-core": _PAPER_CORE},
    include=_include,
    claim=12,
)
EXPERIMENTS = (VIN_BLOG,)
