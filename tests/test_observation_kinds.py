"""The observation kinds as one family: every registered kind is a final
:class:`bench.core.Observation` with each of its methods, the vocabulary of
``RunConfig.observation`` is the registry, a field that applies to one kind only is refused on
every other kind in one line, and a kind registered as one class is validated and executed like
the built-in ones."""

from __future__ import annotations

import dataclasses
import inspect
from typing import final

import pytest

import bench.core
import bench.experiments
import systems
from bench.core import (
    OBSERVATIONS,
    Member,
    Observation,
    RunConfig,
    _observation,
    check_runnable,
    execute_run,
    field_names,
    observation_kinds,
    plan_groups,
    register_observation,
)
from systems import real_pendulum

TASK = "HopperFull-v0"
# A valid run of each built-in kind (the state run on derivative targets, so that it may take
# every state option).
RUNS = {
    "state": dict(system="chain_pendulum", k=1, train_target="derivative"),
    "pixels": dict(system="pendulum", observation="pixels"),
    "frames": dict(system="pendulum", observation="frames"),
    "measured": dict(
        system=real_pendulum.DATASETS[0],
        observation="measured",
        train_target="derivative",
        coordinates="momentum",
    ),
    "controlled": dict(
        system=TASK,
        observation="controlled",
        system_params=(("data", "stand-in"),),
        dt=systems.MUJOCO_TASKS[TASK].dt,
    ),
}
# A value away from the default of each kind-only field, valid on its own kind.
AWAY = {"train_box": (-1.0, 1.0, -2.0, 2.0), "standardise": True, "aux_weight": 0.0}
STEPS = ("check", "check_model", "build", "train", "evaluate")


def _options() -> list[tuple[str, str, object]]:
    """(kind, field, default) of every kind-only field of the registered kinds."""
    return [(k.name, f, d) for k in observation_kinds().values() for f, d in k.options]


def test_the_built_in_kinds_are_registered():
    assert tuple(observation_kinds()) == ("state", "pixels", "frames", "measured", "controlled")
    assert set(RUNS) == set(observation_kinds())


@pytest.mark.parametrize("name", list(observation_kinds()))
def test_every_registered_kind_is_a_final_observation(name):
    kind = observation_kinds()[name]
    cls = type(kind)
    assert isinstance(kind, Observation) and kind.name == name
    assert not inspect.isabstract(cls) and getattr(cls, "__final__", False), cls
    for step in STEPS:
        assert callable(getattr(kind, step)), step
        assert not getattr(getattr(cls, step), "__isabstractmethod__", False), step
    assert kind.member is None or isinstance(kind.member, Member)
    if kind.member is not None:
        m = kind.member
        assert callable(m.train_config) and callable(m.inputs) and callable(m.record)
    assert isinstance(kind.runs, str) and kind.runs
    # options and fixed fields are (field, value) pairs of RunConfig's fields
    for field, _ in kind.options + kind.fixed:
        assert field in field_names(), field
    run = RunConfig(**RUNS[name])
    assert run.observation == name
    kind.check(run)  # a valid run of the kind passes its own check again


def test_the_abstract_kind_cannot_be_registered_or_made():
    with pytest.raises(TypeError):
        Observation()
    with pytest.raises(ValueError, match="concrete Observation class"):
        register_observation(Observation)
    with pytest.raises(ValueError, match="concrete Observation class"):
        register_observation(RunConfig)


def test_the_vocabulary_is_the_registry():
    names = tuple(observation_kinds())
    assert OBSERVATIONS == names == bench.experiments.OBSERVATIONS
    with pytest.raises(ValueError) as e:
        RunConfig(system="pendulum", observation="video")
    assert str(e.value).startswith("unknown observation 'video'; allowed: " + ", ".join(names))


def test_each_kind_only_field_is_declared_with_its_default_and_left_out_of_the_hashes():
    defaults = {f.name: f.default for f in dataclasses.fields(RunConfig)}
    options = _options()
    assert {f for _, f, _ in options} == set(AWAY), "give AWAY a value for each kind-only field"
    owners = [f for _, f, _ in options]
    assert len(owners) == len(set(owners)), "a kind-only field belongs to one kind"
    for name, field, default in options:
        assert defaults[field] == default, (name, field)
        for other in RUNS:  # at its default, no run's hashes hold it
            assert field not in RunConfig(**RUNS[other])._identity()


@pytest.mark.parametrize("name, field, default", _options())
def test_a_kind_only_field_is_taken_by_its_kind_and_refused_by_the_others(name, field, default):
    own = RunConfig(**{**RUNS[name], field: AWAY[field]})
    assert getattr(own, field) == AWAY[field] and field in own._identity()
    for other in RUNS:
        if other == name:
            continue
        with pytest.raises(ValueError) as e:
            RunConfig(**{**RUNS[other], field: AWAY[field]})
        msg = str(e.value)
        assert "\n" not in msg
        assert msg == (
            f"{field} applies to {observation_kinds()[name].runs} only (observation {name!r}); "
            f"got observation {other!r}; allowed: {default!r}"
        )


# ------------------------------------------------------------------------------ a new kind
CALLS: list[str] = []  # the steps of Echo, in the order they ran


@final
class Echo(Observation):
    """A kind defined and registered by a test: no data, no model; its run reports its seed."""

    name = "echo"
    fixed = (("noise", 0.0),)

    def check(self, config) -> None:
        CALLS.append("check")
        self.check_fixed(config)
        if config.seed > 100:
            raise ValueError(f"echo runs need seed <= 100; got {config.seed}")

    def check_model(self, config) -> None:
        CALLS.append("check_model")

    def build(self, config, cache_root):
        CALLS.append("build")
        return ("built", config.seed)

    def train(self, config, built, cache_root, progress):
        CALLS.append("train")
        meta = dict(status="ok", train_seconds=0.0, compile_seconds=0.0, train_cached=False)
        return built, meta

    def evaluate(self, config, built, model, meta, cache_root):
        CALLS.append("evaluate")
        assert built == model == ("built", config.seed)
        return {"rollout_error": float(config.seed), "curves": {"t": [0.0]}}, {}


def test_a_kind_registered_as_one_class_is_validated_and_executed(monkeypatch, tmp_path):
    monkeypatch.setattr(_observation, "_KINDS", dict(observation_kinds()))
    CALLS.clear()
    assert register_observation(Echo) is Echo
    assert bench.core.OBSERVATIONS[-1] == "echo"  # the vocabulary, read live
    run = RunConfig(system="chain_pendulum", observation="echo", seed=3)
    assert CALLS == ["check"]
    with pytest.raises(ValueError, match="echo runs support no noise 0.1; allowed: 0.0"):
        RunConfig(system="chain_pendulum", observation="echo", noise=0.1)
    with pytest.raises(ValueError, match="echo runs need seed <= 100"):
        RunConfig(system="chain_pendulum", observation="echo", seed=101)
    with pytest.raises(ValueError, match="standardise applies to controlled runs only"):
        RunConfig(system="chain_pendulum", observation="echo", standardise=True)
    assert check_runnable(run) is run and CALLS[-1] == "check_model"
    CALLS.clear()
    row = execute_run(run, cache_root=tmp_path)
    assert row["status"] == "ok", row["error"]
    assert row["observation"] == "echo" and row["rollout_error"] == 3.0
    assert CALLS == ["build", "train", "evaluate"]
    # no Member: each echo run trains alone
    runs = [dataclasses.replace(run, seed=s) for s in (0, 1)]
    assert plan_groups(runs, None) == [[runs[0]], [runs[1]]]
