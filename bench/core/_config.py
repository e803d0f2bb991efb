"""A run as data: the frozen :class:`RunConfig`, its field vocabularies and its hashes.

A :class:`RunConfig` is checked once, when it is built: every field's value, the fields that
apply to one observation kind only (a kind's ``options``) at their defaults on the other kinds,
then the run's own kind's checks (``observation``, :mod:`bench.core._observation`: e.g. a state
run's system with its parameters and the dataset's shape, its ``systems.DatasetConfig``, or a
pixel run's restrictions); each problem is a one-line ValueError naming what is allowed. What
depends on the registered models (the model for the scene, the integrators its rollout accepts)
is asked of the models by :func:`bench.core._runnable.check_runnable` before a sweep runs
anything.

A run's identity is its content: ``config_hash`` = sha256 of the canonical JSON (sorted keys)
of every field (a field declared with :func:`_hashed_unless_default`, e.g. ``eval_checkpoints``
or ``train_target``, counts only when it differs from its default), ``train_hash`` the same over
every field except the ``eval_*`` ones, so runs that differ only in how they are evaluated
share one training. Experiment and profile names are not part of either hash: experiments that
expand to the same run share it.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass

from models import METHODS as INTEGRATORS  # the one list of integrator names

from ._observation import Observation, observation_kind, observation_kinds, observations
from ._vocab import (  # noqa: F401 - the vocabularies, named here for the run's users too
    COORDINATES,
    DTYPES,
    FRAMES_ANGLES,
    LOSSES,
    LR_SCHEDULES,
    OPTIMIZERS,
    PIXEL_MAX_ANGLE,
    PIXEL_MAX_SPEED,
    PIXEL_SIZE,
    TRAIN_TARGETS,
    _as_float,
    _as_int,
    _frozen,
    _hash,
    _is_missing,
    check_choice,
)

_HASHED_AT_DEFAULT = "hashed_at_default"  # a field's metadata: False for the fields below


def _hashed_unless_default(default):
    """A RunConfig field that the hashes leave out while it holds ``default`` (a field the
    stored runs were hashed without: they keep their hashes), read back as ``default`` from a
    row that leaves its column empty."""
    return dataclasses.field(default=default, metadata={_HASHED_AT_DEFAULT: False})


@dataclass(frozen=True)
class RunConfig:
    """One training-and-evaluation run; flat so that every field is a column of the results."""

    system: str
    k: int | None = None
    friction: float = 0.0
    system_params: tuple = ()
    model: str = "node"
    dissipation: bool | None = None
    model_options: tuple = ()
    width: int = 256
    depth: int = 2
    activation: str | None = None  # None: each model's own default (softplus for lnn, else tanh)
    coordinates: str = "velocity"
    random_args: bool = False
    noise: float = 0.0
    n_generated: int = 1000
    n_train: int = 800
    chunk: int = 5
    dt: float = 0.03
    # seconds simulated per trajectory (chunks and test windows in it)
    duration: float = _hashed_unless_default(10.0)
    n_test: int = 200
    test_chunks: int = 20
    steps: int = 8000
    batch: int = 200
    lr: float = 5e-3
    loss: str = "l2"
    train_integrator: str = "rk4_38"
    train_substeps: int = 1
    eval_integrator: str = "rk4_38"
    eval_substeps: int = 1
    eval_rtol: float = 1e-6
    # learning-curve checkpoints (bench.core._fit.checkpoint_steps)
    eval_checkpoints: int = _hashed_unless_default(0)
    dtype: str = "float32"
    seed: int = 0
    # what training fits: "rollout" (the chunks, through the integrator) or "derivative" (the
    # true dz/dt at the chunks' states: the HNN and LNN seeds' protocol; bench.core._train)
    train_target: str = _hashed_unless_default("rollout")
    # what the models observe: the name of a registered kind (bench.core._observation), the
    # built-in ones "state" (z itself), "pixels" (rendered frames of the state, two stacked per
    # observation), "frames" (the VIN seed's single frames), "measured" (a measured trajectory)
    # and "controlled" (a MuJoCo task under recorded controls): bench.core._kinds
    observation: str = _hashed_unless_default("state")
    # the optimisation (bench.core._optim.optimizer): "adamw" (the suite's: clipping, AdamW,
    # decoupled weight decay), "adam_l2" (the seeds': Adam with an L2 term in the gradient,
    # no clipping) or "adam_l2_clip" (the same after clipping the gradient: the Deconstructing
    # paper's MuJoCo code); the learning-rate schedule from ``lr``; the weight decay (None: the
    # observation's default, 1e-4 for states and the HNN seed's 1e-5 for pixels)
    optimizer: str = _hashed_unless_default("adamw")
    lr_schedule: str = _hashed_unless_default("cosine")
    weight_decay: float | None = _hashed_unless_default(None)
    # state runs only: the training states (with train_target "derivative"): () the dataset's
    # chunks, or a box
    # (q_low, q_high, qdot_low, qdot_high) from which fresh states are drawn uniformly for
    # every batch, each coordinate alike (the LNN seed's notebook; bench.core._box)
    train_box: tuple = _hashed_unless_default(())
    # controlled runs only: the networks' inputs and rate outputs standardised with the training
    # windows' statistics (models.Standardisation; the paper's MuJoCo code), or raw
    standardise: bool = _hashed_unless_default(False)
    # pixel runs only: the weight of the HNN seed's auxiliary latent loss in the pixel objective
    # (bench.core._pixels.seed_loss): 1, the seed's; 0 leaves it out
    aux_weight: float = _hashed_unless_default(1.0)

    def __post_init__(self):
        self._canonicalize()
        self._check()

    def _canonicalize(self) -> None:
        """Canonical forms, so that equal runs hash equally however they were written (a list
        read back from JSON is the tuple it was written from: the JSON, and so the hash, is
        the same)."""
        for name in ("system_params", "model_options"):
            value = getattr(self, name)
            if isinstance(value, Mapping):
                value = tuple(value.items())
            object.__setattr__(self, name, tuple(sorted((str(a), _frozen(b)) for a, b in value)))
        if self.k is not None:
            object.__setattr__(self, "k", _as_int(self.k, "k"))
        for name in ("friction", "noise", "dt", "duration", "lr", "eval_rtol"):
            object.__setattr__(self, name, _as_float(getattr(self, name), name))
        for name in ("width", "depth", "n_generated", "n_train", "chunk", "n_test"):
            object.__setattr__(self, name, _as_int(getattr(self, name), name))
        for name in ("test_chunks", "steps", "batch", "train_substeps", "eval_substeps", "seed"):
            object.__setattr__(self, name, _as_int(getattr(self, name), name))
        object.__setattr__(
            self, "eval_checkpoints", _as_int(self.eval_checkpoints, "eval_checkpoints")
        )
        object.__setattr__(self, "aux_weight", _as_float(self.aux_weight, "aux_weight"))
        if self.weight_decay is not None:
            object.__setattr__(self, "weight_decay", _as_float(self.weight_decay, "weight_decay"))
        box = self.train_box
        if isinstance(box, str):
            box = json.loads(box)
        if not isinstance(box, list | tuple):
            raise ValueError(f"train_box must be () or 4 numbers; got {self.train_box!r}")
        object.__setattr__(self, "train_box", tuple(_as_float(b, "train_box") for b in box))
        if self.standardise not in (True, False):  # numpy's bools and 0/1 alike
            raise ValueError(f"standardise must be True or False; got {self.standardise!r}")
        object.__setattr__(self, "standardise", bool(self.standardise))

    @classmethod
    def _candidate(cls, **fields) -> RunConfig:
        """A combination of an experiment's axes in canonical form, not checked: the product
        holds combinations that the experiment's ``include`` drops (a spring's initial state on
        the chain), so :func:`expand` filters candidates and builds only those it keeps."""
        for key in fields.keys() - _defaults():
            check_choice("RunConfig field", key, field_names())
        c = object.__new__(cls)
        for name, default in _defaults().items():
            value = fields.get(name, default)
            if value is dataclasses.MISSING:
                raise ValueError(f"a run needs its {name}")
            object.__setattr__(c, name, value)
        c._canonicalize()
        return c

    def _check(self) -> None:
        """The one check of a configuration (from ``__post_init__``): one-line ValueErrors
        naming what is allowed; the fields of the other kinds' ``options`` at their defaults,
        then the run's observation kind's own checks (:meth:`Observation.check`)."""
        if self.k is not None and self.k < 1:
            raise ValueError(f"k must be an integer >= 1; got {self.k}")
        for name in ("friction", "noise"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"{name} must be a finite number >= 0; got {v}")
        for name in ("dt", "duration", "lr", "eval_rtol"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be a finite number > 0; got {v}")
        for name in ("seed", "eval_checkpoints"):
            if getattr(self, name) < 0:
                raise ValueError(f"{name} must be an integer >= 0; got {getattr(self, name)}")
        for name in ("width", "depth", "n_generated", "n_train", "chunk", "n_test"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be an integer >= 1; got {getattr(self, name)}")
        for name in ("test_chunks", "steps", "batch", "train_substeps", "eval_substeps"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be an integer >= 1; got {getattr(self, name)}")
        if self.n_train > self.n_generated:
            raise ValueError(
                f"n_train ({self.n_train}) must be <= n_generated ({self.n_generated})"
            )
        check_choice("train_integrator", self.train_integrator, INTEGRATORS)
        check_choice("eval_integrator", self.eval_integrator, INTEGRATORS)
        check_choice("coordinates", self.coordinates, COORDINATES)
        check_choice("loss", self.loss, LOSSES)
        check_choice("dtype", self.dtype, DTYPES)
        check_choice("train_target", self.train_target, TRAIN_TARGETS)
        check_choice("observation", self.observation, observations())
        check_choice("optimizer", self.optimizer, OPTIMIZERS)
        check_choice("lr_schedule", self.lr_schedule, LR_SCHEDULES)
        wd = self.weight_decay
        if wd is not None and not (math.isfinite(wd) and wd >= 0):
            raise ValueError(f"weight_decay must be None or a finite number >= 0; got {wd}")
        kind = observation_kind(self.observation)
        self._check_options(kind)
        kind.check(self)

    def _check_options(self, kind: Observation) -> None:
        """The fields that apply to another kind only (its ``options``) at their defaults."""
        mine = {name for name, _ in kind.options}
        for other in observation_kinds().values():
            for name, default in other.options:
                if name not in mine and getattr(self, name) != default:
                    raise ValueError(
                        f"{name} applies to {other.runs} only (observation {other.name!r}); "
                        f"got observation {self.observation!r}; allowed: {default!r}"
                    )

    def to_dict(self) -> dict:
        """Every field, JSON-ready (tuples of pairs become lists)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}

    @classmethod
    def from_dict(cls, d: Mapping) -> RunConfig:
        names = field_names()
        kw = {a: b for a, b in d.items() if a in names}
        for name in ("system_params", "model_options"):
            if name in kw:
                v = kw[name]
                if isinstance(v, str):
                    v = json.loads(v)
                kw[name] = tuple(tuple(p) for p in v)
        for f in dataclasses.fields(cls):  # optional fields come back from tables as NaN
            if f.default is None and f.name in kw and _is_missing(kw[f.name]):
                kw[f.name] = None
            # a field the stored runs were hashed without is empty in their rows: its default
            elif not _hashed_at_default(f) and f.name in kw and _is_missing(kw[f.name]):
                kw[f.name] = f.default
        if "dissipation" in kw and kw["dissipation"] is not None:
            kw["dissipation"] = bool(kw["dissipation"])
        return cls(**kw)

    def system_kwargs(self) -> dict:
        """Keyword arguments of ``systems.make`` for this run."""
        kw = dict(self.system_params)
        if self.k is not None:
            kw["k"] = self.k
        if self.friction:
            kw["friction"] = self.friction
        return kw

    def _dataset_fields(self) -> tuple:
        return (
            ("system", self.system),
            ("system_params", tuple(sorted(self.system_kwargs().items()))),
            ("n_generated", self.n_generated),
            ("n_train", self.n_train),
            ("chunk", self.chunk),
            ("dt", self.dt),
            ("duration", self.duration),
            ("n_test", self.n_test),
            ("test_chunks", self.test_chunks),
            ("noise", self.noise),
            ("coordinates", self.coordinates),
            ("random_args", self.random_args),
            ("seed", self.seed),
        )

    def dataset_config(self):
        """The ``systems.DatasetConfig`` of this run's training and test data (built once per
        run; a state run's when the run is built, which checks it)."""
        built = self.__dict__.get("_dataset")
        if built is None:
            built = _dataset_config(self._dataset_fields())
            object.__setattr__(self, "_dataset", built)
        return built

    def pixel_dataset_config(self):
        """A pixel run's ``systems.PixelDatasetConfig``: ``n_train`` training and ``n_test``
        test trajectories from the :data:`PIXEL_MAX_ANGLE` / :data:`PIXEL_MAX_SPEED` starts
        (observation "frames": |q0| in :data:`FRAMES_ANGLES`), frames of :data:`PIXEL_SIZE`
        pixels ``dt`` apart; a training trajectory spans ``duration`` (``round(duration /
        dt)`` frames), a test trajectory ``chunk * test_chunks`` frames."""
        import systems

        angles = FRAMES_ANGLES if self.observation == "frames" else (0.0, PIXEL_MAX_ANGLE)
        return systems.PixelDatasetConfig(
            system=self.system,
            system_params=tuple(sorted(self.system_kwargs().items())),
            size=PIXEL_SIZE,
            n_train=self.n_train,
            n_test=self.n_test,
            train_points=max(self.chunk, round(self.duration / self.dt)),
            test_points=self.chunk * self.test_chunks,
            dt=self.dt,
            max_angle=angles[1],
            max_speed=PIXEL_MAX_SPEED,
            seed=self.seed,
            min_angle=angles[0],
        )

    def _identity(self) -> dict:
        """The fields a hash covers: every one, except those declared with
        :func:`_hashed_unless_default` that hold their default."""
        unhashed = _unhashed_defaults()
        return {a: b for a, b in self.to_dict().items() if unhashed.get(a, _NO) != b}

    @property
    def config_hash(self) -> str:
        """sha256 (16 hex digits) of the canonical JSON of every field (see ``_identity``)."""
        return _hash(self._identity())

    @property
    def train_hash(self) -> str:
        """sha256 (16 hex digits) of every field except the ``eval_*`` ones."""
        return _hash({a: b for a, b in self._identity().items() if not a.startswith("eval_")})


_NO = object()


def _hashed_at_default(f: dataclasses.Field) -> bool:
    return f.metadata.get(_HASHED_AT_DEFAULT, True)


@functools.cache
def _unhashed_defaults() -> dict:
    """RunConfig field -> the default at which the hashes leave it out (the fields declared
    with :func:`_hashed_unless_default`)."""
    return {f.name: f.default for f in dataclasses.fields(RunConfig) if not _hashed_at_default(f)}


@functools.cache
def _defaults() -> dict:
    """RunConfig field -> its default (``dataclasses.MISSING`` for ``system``)."""
    return {f.name: f.default for f in dataclasses.fields(RunConfig)}


@functools.lru_cache(maxsize=4096)
def _dataset_config(fields: tuple):
    """``systems.DatasetConfig(**fields)``, built once per distinct dataset in a process."""
    import systems

    return systems.DatasetConfig(**dict(fields))


def field_names() -> tuple[str, ...]:
    """The RunConfig field names (the columns every run row carries)."""
    return tuple(f.name for f in dataclasses.fields(RunConfig))
