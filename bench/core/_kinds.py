"""The built-in observation kinds, one final :class:`~bench.core._observation.Observation` each:
state (the models see z itself), pixels (rendered frames of the state, two stacked per
observation: an autoencoder and latent dynamics), frames (the VIN seed's task: single frames
encoded to positions), measured (a measured trajectory read from a file) and controlled (a
MuJoCo task's transitions under recorded controls).

Each kind's checks are light (``systems`` only); its steps import their module
(``bench.core._pixels``, ``_frames``, ``_measured``, ``_controlled``; a state run's
``_build``, ``_fit`` and ``_evaluate``) when they first run, so that a configuration is built
and checked without jax.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path
from typing import final

from ._observation import Member, Observation, register_observation
from ._vocab import check_choice


@register_observation
@final
class State(Observation):
    """The models see the state z = (q, qdot) (or (q, p)) itself: the suite's runs.

    ``train_box`` (training states drawn fresh from a box, :mod:`bench.core._box`) applies to
    state runs only."""

    name = "state"
    options = (("train_box", ()),)

    def check(self, config) -> None:
        box = config.train_box
        if box:
            if len(box) != 4 or not all(math.isfinite(b) for b in box):
                raise ValueError(
                    f"train_box must be () or 4 finite numbers (q_low, q_high, qdot_low, "
                    f"qdot_high); got {box}"
                )
            if not (box[0] < box[1] and box[2] < box[3]):
                raise ValueError(
                    f"train_box needs q_low < q_high and qdot_low < qdot_high; got {box}"
                )
            if config.train_target != "derivative" or config.coordinates != "velocity":
                raise ValueError(
                    "train_box needs train_target 'derivative' and coordinates 'velocity' "
                    f"(states drawn in (q, qdot)); got {config.train_target!r}, "
                    f"{config.coordinates!r}"
                )
            if config.noise or config.random_args:
                raise ValueError(
                    "train_box supports no noise or random_args; allowed: their defaults"
                )
        config.dataset_config()  # the system, its parameters and the dataset's shape

    def check_model(self, config) -> None:
        from ._runnable import check_state_model

        check_state_model(config)

    def build(self, config, cache_root: Path):
        from ._build import build_run

        return build_run(config, cache_root)

    def train(self, config, built, cache_root: Path, progress: bool):
        from ._fit import train_cached

        _, data, _, model = built
        return train_cached(config, model, data, cache_root, progress)

    def evaluate(self, config, built, model, meta: dict, cache_root: Path):
        from ._evaluate import evaluate_state

        return evaluate_state(config, built, model, meta, cache_root)

    @property
    def member(self) -> Member:
        from ._fit import train_config

        return Member(
            train_config=train_config, inputs=_state_inputs, record=_state_record, rollouts=True
        )


def _state_inputs(config, built) -> tuple:
    from ._fit import objective

    return built[3], built[1], objective(config)


def _state_record(config, result, cache_root: Path) -> dict:
    from ._fit import train_config
    from ._params import store_trained

    return store_trained(config, result, cache_root, train_config(config).checkpoints)


class AbstractPixels(Observation):
    """Runs on rendered frames of a renderable system (``systems.reach``): frames of
    :data:`~bench.core._vocab.PIXEL_SIZE` pixels (``RunConfig.pixel_dataset_config``), rollout
    targets, no noise, drawn parameters or friction."""

    fixed = (
        ("noise", 0.0),
        ("random_args", False),
        ("train_target", "rollout"),
        ("friction", 0.0),
    )

    @property
    def runs(self) -> str:
        return "pixel runs"

    def check(self, config) -> None:
        import systems

        if config.chunk < 3:
            raise ValueError(
                f"pixel runs need chunk >= 3 frames (two observations); got chunk={config.chunk}"
            )
        self.check_fixed(config)
        system = _system(config.system, tuple(sorted(config.system_kwargs().items())))
        systems.reach(system)  # the renderable systems (ValueError naming them)
        config.pixel_dataset_config()


@register_observation
@final
class Pixels(AbstractPixels):
    """Two stacked frames per observation, an autoencoder and latent dynamics (the HNN seed's
    task; :mod:`bench.core._pixels`, evaluated by :mod:`bench.core._pixel_eval`).
    ``aux_weight`` (the weight of the seed's auxiliary latent loss) applies to pixel runs
    only."""

    name = "pixels"
    options = (("aux_weight", 1.0),)

    def check(self, config) -> None:
        super().check(config)
        w = config.aux_weight
        if not (math.isfinite(w) and w >= 0):
            raise ValueError(
                f"aux_weight must be a finite number >= 0 (1: the HNN seed's; 0: no auxiliary "
                f"loss); got {w}"
            )

    def check_model(self, config) -> None:
        from ._pixels import check_pixel_model

        check_pixel_model(config)

    def build(self, config, cache_root: Path):
        from ._pixels import build

        return build(config)

    def train(self, config, built, cache_root: Path, progress: bool):
        from ._pixels import train_cached_pixels

        _, data, model = built
        return train_cached_pixels(config, model, data, cache_root, progress)

    def evaluate(self, config, built, model, meta: dict, cache_root: Path):
        from ._pixel_eval import evaluate_pixels

        system, data, _ = built
        metrics, curves = evaluate_pixels(config, system, data, model)
        return {**metrics, "curves": curves}, {}


@register_observation
@final
class Frames(AbstractPixels):
    """Single frames, each encoded to a position (the VIN seed's task:
    :mod:`bench.core._frames`)."""

    name = "frames"

    def check_model(self, config) -> None:
        from ._frames import check_frame_model

        check_frame_model(config)

    def build(self, config, cache_root: Path):
        from ._frames import build

        return build(config)

    def train(self, config, built, cache_root: Path, progress: bool):
        from ._frames import train_cached_frames

        _, data, model = built
        return train_cached_frames(config, model, data, cache_root, progress)

    def evaluate(self, config, built, model, meta: dict, cache_root: Path):
        from ._frames import evaluate_frames

        system, data, _ = built
        metrics, curves = evaluate_frames(config, system, data, model)
        return {**metrics, "curves": curves}, {}


@register_observation
@final
class Measured(Observation):
    """A measured trajectory (the HNN seed's real pendulum; :mod:`bench.core._measured`): the
    states of the file, taken as canonical, and their finite differences as targets."""

    name = "measured"
    fixed = (
        ("noise", 0.0),
        ("random_args", False),
        ("train_target", "derivative"),
        ("coordinates", "momentum"),
        ("friction", 0.0),
        ("system_params", ()),
        ("k", None),
    )

    def check(self, config) -> None:
        from systems import real_pendulum

        allowed = real_pendulum.DATASETS
        check_choice("measured dataset (system of a measured run)", config.system, allowed)
        self.check_fixed(config)

    def check_model(self, config) -> None:
        from ._measured import check_measured_model

        check_measured_model(config)

    def build(self, config, cache_root: Path):
        from ._measured import build

        return build(config)

    def train(self, config, built, cache_root: Path, progress: bool):
        from ._measured import train

        return train(config, built, cache_root, progress)

    def evaluate(self, config, built, model, meta: dict, cache_root: Path):
        from ._measured import evaluate

        return evaluate(config, built, model, meta, cache_root)


@register_observation
@final
class Controlled(Observation):
    """A MuJoCo task's transitions under recorded controls (the paper's Fig. 7;
    :mod:`bench.core._controlled`): the raw state [q, v] of the task, rollout targets.

    ``system_params`` names the data: ``(("data", d),)`` with d in :attr:`DATA` (the task's
    file, or the random-control stand-in of the tests). ``standardise`` (the networks' inputs
    and rate outputs standardised with the training windows' statistics, the paper's MuJoCo
    code) applies to controlled runs only."""

    name = "controlled"
    options = (("standardise", False),)
    fixed = (
        ("noise", 0.0),
        ("random_args", False),
        ("train_target", "rollout"),
        ("coordinates", "velocity"),
        ("friction", 0.0),
        ("k", None),
    )
    DATA = ("file", "stand-in")

    def check(self, config) -> None:
        import systems

        allowed = list(systems.MUJOCO_TASKS)
        check_choice("MuJoCo task (system of a controlled run)", config.system, allowed)
        self.check_fixed(config)
        data = dict(config.system_params)
        if set(data) != {"data"} or data["data"] not in self.DATA:
            raise ValueError(
                f"controlled runs need system_params (('data', d),) with d in {self.DATA}"
                f"; got {config.system_params!r}"
            )
        task_dt = systems.MUJOCO_TASKS[config.system].dt
        if abs(config.dt - task_dt) > 1e-12:
            raise ValueError(f"dt of {config.system} is the task's, {task_dt}; got {config.dt}")
        if config.chunk < 2:
            raise ValueError(f"controlled runs need chunk >= 2 states; got {config.chunk}")

    def check_model(self, config) -> None:
        from ._controlled import check_controlled_model

        check_controlled_model(config)

    def build(self, config, cache_root: Path):
        from ._controlled import build

        return build(config)

    def train(self, config, built, cache_root: Path, progress: bool):
        from ._controlled import train

        return train(config, built, cache_root, progress)

    def evaluate(self, config, built, model, meta: dict, cache_root: Path):
        from ._controlled import evaluate

        return evaluate(config, built, model, meta, cache_root)

    @property
    def member(self) -> Member:
        from . import _controlled as C

        return Member(train_config=C.train_config, inputs=C.member_inputs, record=C.record)


@functools.lru_cache(maxsize=256)
def _system(name: str, params: tuple):
    """``systems.make(name, **params)``, to check a pixel run's system (and ask it whether it
    renders); jax's float32 warning is moot here, where only the parameters are checked."""
    import warnings

    import systems

    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", "Explicitly requested dtype", UserWarning)
        return systems.make(name, **dict(params))
