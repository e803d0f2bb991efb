"""Experiments as data: an experiment is a product of axes over :class:`RunConfig` fields.

An :class:`Experiment` names the RunConfig fields it varies (``axes``, expanded as a Cartesian
product), the ones it fixes (``fixed``) and per-profile overrides. :func:`expand` turns it into
the list of runs of one profile. Precedence, lowest first::

    RunConfig defaults < PROFILES[profile] < exp.fixed < exp.profile_overrides[profile] < axes

(an override whose key is an axis replaces that axis' values; ``"seeds"`` replaces the seeds).

A *selection* (:data:`SELECTIONS`, e.g. ``paper-core``) is a profile that picks some cells of
another profile: it has its base profile's defaults, so its runs hash exactly as the base's
runs do, and an experiment takes part in it only where its ``profile_overrides`` name it (the
base's overrides apply first, then the selection's, which usually narrow an axis). A run's
configuration, its checks and its hashes: :mod:`bench.core._config`.
"""

from __future__ import annotations

import importlib
import itertools
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType

from ._config import RunConfig, check_choice, field_names

# The papers an experiment can reproduce: Gruver et al. 2022 and its seeds (the HNN, LNN and
# VIN papers)
PAPERS = ("deconstructing", "hnn", "lnn", "vin")


# ------------------------------------------------------------------------------- profiles
# RunConfig defaults per profile, plus "seeds". The experiments tune them further through
# their profile_overrides.
PROFILES: dict[str, dict[str, object]] = {
    "smoke": {
        "n_generated": 20,
        "n_train": 16,
        "n_test": 4,
        "test_chunks": 4,
        "width": 16,
        "steps": 20,
        "batch": 8,
        "eval_checkpoints": 2,
        "seeds": (0,),
    },
    "quick": {
        "n_generated": 250,
        "n_train": 200,
        "n_test": 40,
        "test_chunks": 20,
        "width": 128,
        "steps": 1000,
        "batch": 100,
        "eval_checkpoints": 4,
        "seeds": (0, 1, 2, 3, 4),
    },
    "paper": {
        "n_generated": 1000,
        "n_train": 800,
        "n_test": 200,
        "test_chunks": 20,
        "width": 256,
        "steps": 8000,
        "batch": 200,
        "eval_checkpoints": 4,
        "seeds": (0, 1, 2, 3, 4),
    },
}
# Selections: name -> the profile whose runs they select from (see the module docstring).
# paper-core: the paper's per-run budget and seeds on the cells each verdict needs at k = 2,
# what a 2-core CPU can finish in a background campaign (`make paper-core`). paper-k: the same
# budget on the paper's other numbers of links (k = 1, 3, 4) of the experiments that sweep k
# (Figs. 2-5), the background campaign after paper-core (`make paper-k`).
SELECTIONS: dict[str, str] = {"paper-core": "paper", "paper-k": "paper"}
for _sel, _base in SELECTIONS.items():
    PROFILES[_sel] = dict(PROFILES[_base])
# A verdict counts when it replicates: each profile's claims are judged again on a
# disjoint seed set, stored beside the profile's own runs (`make replicate` at quick; the
# paper-core campaign runs them after its own seeds). A selection has its base profile's.
REPLICATION_SEEDS: dict[str, tuple[int, ...]] = {"quick": (5, 6, 7, 8, 9), "paper": (5, 6, 7, 8, 9)}


def base_profile(profile: str | None) -> str | None:
    """The profile whose runs ``profile`` selects from: a selection's base, else itself."""
    return SELECTIONS.get(profile, profile) if profile is not None else None


def speaking_profiles(profile: str | None) -> frozenset:
    """The row labels whose tagged rows speak for ``profile`` (rows of older declarations,
    matched by experiment name rather than by cell): the profile itself and, for a base profile
    (``paper``), its selections (``paper-core``, ``paper-k``), whose cells are its own. A
    selection reads its own label only, so that ``paper-core``'s k = 2 verdicts never take in
    ``paper-k``'s other links."""
    if profile is None:
        return frozenset()
    return frozenset({profile, *(s for s, b in SELECTIONS.items() if b == profile)})


def replication_seeds(profile: str | None) -> tuple[int, ...]:
    """The replication seeds of ``profile`` (a selection: its base profile's); () if none."""
    if profile is None:
        return ()
    return REPLICATION_SEEDS.get(SELECTIONS.get(profile, profile), ())


# ----------------------------------------------------------------------------- experiments
@dataclass(frozen=True)
class Experiment:
    """A named family of runs: the product of ``axes`` over the profile's seeds."""

    name: str
    title: str
    axes: Mapping[str, Sequence] = field(default_factory=dict)
    fixed: Mapping[str, object] = field(default_factory=dict)
    profile_overrides: Mapping[str, Mapping[str, object]] = field(default_factory=dict)
    include: Callable[[RunConfig], bool] | None = None
    claim: int | None = None
    # The cells of a further reading of the claim (another form of its models, another system):
    # its claim is never pending on them, and they join its verdict on a seed set only once
    # every one of them the profile declares there is stored (:func:`is_supplementary`). A
    # string names the cell's reading: each named reading joins on its own (:func:`reading_of`).
    supplementary: Callable[[RunConfig], bool | str] | None = None
    # The profiles it runs at (None: every profile); elsewhere it expands to no runs.
    profiles: tuple[str, ...] | None = None
    # The paper it reproduces (one of PAPERS): `bench --papers` runs a paper's experiments.
    paper: str = "deconstructing"

    def __post_init__(self):
        if not self.name or not isinstance(self.name, str):
            raise ValueError("an experiment needs a non-empty string name")
        names = set(field_names())
        for what, keys in (("axes", self.axes), ("fixed", self.fixed)):
            for key in keys:
                if key not in names:
                    check_choice(f"RunConfig field in {self.name}.{what}", key, sorted(names))
        for axis, values in self.axes.items():
            if isinstance(values, str) or len(list(values)) == 0:
                raise ValueError(f"{self.name}.axes[{axis!r}] must be a non-empty sequence")
        check_choice(f"paper of {self.name}", self.paper, list(PAPERS))
        for prof in self.profiles or ():
            check_choice(f"profile in {self.name}.profiles", prof, list(PROFILES))
        for prof, over in self.profile_overrides.items():
            check_choice(f"profile in {self.name}.profile_overrides", prof, list(PROFILES))
            for key in over:
                if key not in names and key != "seeds":
                    check_choice(
                        f"RunConfig field in {self.name}.profile_overrides[{prof!r}]",
                        key,
                        sorted(names | {"seeds"}),
                    )
        object.__setattr__(self, "axes", MappingProxyType(dict(self.axes)))
        object.__setattr__(self, "fixed", MappingProxyType(dict(self.fixed)))


_REGISTRY: dict[str, Experiment] = {}
_LOADED = False
# The built-in studies' package, loaded on the registry's first use (not at ``import bench``)
BUILT_IN_STUDIES = "bench.studies"
# Third-party studies: modules named in this Python entry-point group (see bench.core._studies).
ENTRY_POINT_GROUP = "decon_bench.studies"


def register(exp: Experiment, *, replace: bool = False) -> Experiment:
    """Add an experiment to the registry (ValueError if the name is taken, unless replace)."""
    if not isinstance(exp, Experiment):
        raise ValueError(f"register expects an Experiment; got {type(exp).__name__}")
    if exp.name in _REGISTRY and not replace and _REGISTRY[exp.name] != exp:
        raise ValueError(f"experiment {exp.name!r} is already registered")
    _REGISTRY[exp.name] = exp
    return exp


def load_plugins() -> None:
    """Import, once, on the registry's first use, every study, in this order: the built-in ones
    (:data:`BUILT_IN_STUDIES`, whose imports give the report's order), the modules of the
    entry-point group ``decon_bench.studies`` by entry-point name, and those named in
    ``DECON_EXTRA_EXPERIMENTS`` (comma-separated, for the tests). Importing ``bench`` loads
    none of them."""
    global _LOADED
    if _LOADED:
        return
    _LOADED = True
    from importlib import metadata

    importlib.import_module(BUILT_IN_STUDIES)
    for ep in sorted(metadata.entry_points(group=ENTRY_POINT_GROUP), key=lambda e: e.name):
        ep.load()
    extra = [m.strip() for m in os.environ.get("DECON_EXTRA_EXPERIMENTS", "").split(",")]
    for mod in [m for m in extra if m]:
        importlib.import_module(mod)


def available() -> list[str]:
    """Names of the registered experiments, sorted."""
    load_plugins()
    return sorted(_REGISTRY)


def get(name: str) -> Experiment:
    """The registered experiment ``name`` (ValueError naming the registered ones)."""
    load_plugins()
    if name not in _REGISTRY:
        check_choice("experiment", name, sorted(_REGISTRY) or ["(none registered)"])
    return _REGISTRY[name]


def is_supplementary(exp: Experiment, cfg: RunConfig) -> bool:
    """Whether ``cfg`` is a cell of ``exp``'s further reading (``Experiment.supplementary``)."""
    return exp.supplementary is not None and bool(exp.supplementary(cfg))


def reading_of(exp: Experiment, cfg: RunConfig) -> str | None:
    """The further reading ``cfg`` is a cell of: its name where ``exp.supplementary`` names one,
    "" for the experiment's unnamed one, None for one of its own cells."""
    if exp.supplementary is None:
        return None
    said = exp.supplementary(cfg)
    if not said:
        return None
    return said if isinstance(said, str) else ""


def profile_defaults(profile: str) -> tuple[dict, tuple[int, ...]]:
    """(RunConfig field defaults, seeds) of a profile."""
    check_choice("profile", profile, list(PROFILES))
    d = dict(PROFILES[profile])
    seeds = tuple(d.pop("seeds", (0,)))
    return d, seeds


def expand(
    exp: Experiment | str,
    profile: str = "quick",
    seeds: Sequence[int] | None = None,
    models: Sequence[str] | None = None,
) -> list[RunConfig]:
    """The runs of ``exp`` under ``profile``: product of the axes x seeds, filtered, unique.

    Combinations rejected by ``exp.include`` or by :func:`valid` (e.g. leapfrog on a
    first-order model) are dropped; runs are unique by ``config_hash``, in expansion order.
    Under a selection (:data:`SELECTIONS`) an experiment that does not declare it has no runs,
    and so has an experiment under a profile outside its ``profiles``.
    ``seeds`` replaces whatever seeds the profile and the experiment give (a replication on
    another seed set, :data:`REPLICATION_SEEDS`). ``models`` replaces the experiment's trained
    models (``--models``, e.g. a plug-in beside the built-ins); its trivial predictors stay.

    The configurations of an experiment's product are built once per process (:func:`_combos`):
    the campaign's plans and the verdicts expand the same experiments many times. What decides
    which of them run (``include``, which may ask whether a data file is there, and
    :func:`valid`) is asked at every call.
    """
    exp = get(exp) if isinstance(exp, str) else exp
    merged = _merged(exp, profile, seeds, models)
    if merged is None:
        return []
    out, seen = [], set()
    for combo in _combos(*merged):
        cand = combo.config
        if not valid(cand) or (exp.include is not None and not exp.include(cand)):
            continue
        config_hash, error = combo.checked()
        if config_hash in seen:
            continue
        seen.add(config_hash)
        if error is not None:
            raise ValueError(f"experiment {exp.name!r} at {profile}: {error}")
        out.append(cand)
    return out


class _Combo:
    """A combination of an experiment's axes: its configuration (canonical, unchecked) and,
    computed once when an expansion keeps it, its config_hash and its check's error."""

    __slots__ = ("config", "_checked")

    def __init__(self, config: RunConfig):
        self.config, self._checked = config, None

    def checked(self) -> tuple[str, str | None]:
        if self._checked is None:
            try:
                self.config._check()  # one that passes is the RunConfig of its fields
                error = None
            except ValueError as e:
                error = str(e)
            self._checked = (self.config.config_hash, error)
        return self._checked


# _combos' memo: repr of (fields, axes) -> the product's combinations
_COMBOS: dict[str, tuple[_Combo, ...]] = {}


def _combos(base: dict, axes: dict) -> tuple[_Combo, ...]:
    """Every combination of ``axes`` over the fields ``base``, in product order; memoised on
    their repr."""
    key = repr((base, axes))
    hit = _COMBOS.get(key)
    if hit is None:
        keys = list(axes)
        hit = _COMBOS[key] = tuple(
            _Combo(RunConfig._candidate(**{**base, **dict(zip(keys, combo, strict=True))}))
            for combo in itertools.product(*(axes[k] for k in keys))
        )
    return hit


def _merged(exp, profile, seeds, models) -> tuple[dict, dict] | None:
    """(fixed fields, axes) of ``exp`` under ``profile`` (:func:`expand`), or None where it
    has no runs there."""
    if exp.profiles is not None and profile not in exp.profiles:
        return None
    replace_seeds = seeds
    base, seeds = profile_defaults(profile)
    base.update(exp.fixed)
    axes = dict(exp.axes)
    overrides = dict(exp.profile_overrides.get(profile, {}))
    if profile in SELECTIONS:  # a selection: only the experiments that declare it
        if profile not in exp.profile_overrides:
            return None
        overrides = {**exp.profile_overrides.get(SELECTIONS[profile], {}), **overrides}
    for key, value in overrides.items():
        if key == "seeds":
            seeds = tuple(value)
        elif key in axes:
            axes[key] = list(value)
        else:
            base[key] = value
    if models is not None:
        import models as _models

        if "model" not in axes:
            raise ValueError(f"experiment {exp.name!r} fixes its model; --models does not apply")
        trivial = set(_models.trivial_models())
        keep = [m for m in axes["model"] if m in trivial]
        axes["model"] = list(dict.fromkeys([*models, *keep]))
    if replace_seeds is not None:
        axes["seed"] = tuple(int(x) for x in replace_seeds)
    elif "seed" not in axes:
        axes["seed"] = seeds
    return base, {k: list(v) for k, v in axes.items()}


def valid(cfg: RunConfig) -> bool:
    """Whether a combination makes sense: leapfrog needs a second-order continuous model."""
    if {"leapfrog", "leapfrog_explicit"} & {cfg.train_integrator, cfg.eval_integrator}:
        return _second_order(cfg.model)
    return True


def _second_order(model: str) -> bool:
    """Whether the registered model ``model`` is continuous and second order (its spec)."""
    import models

    if model not in models.available():  # unknown: let the run fail with the registry's message
        return True
    s = models.spec(model)
    return s.continuous and s.second_order
