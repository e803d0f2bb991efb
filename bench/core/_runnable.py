"""Whether the registered models can run a configuration, asked before a sweep starts, of the
run's observation kind: for a state run, the model for the run's scene and the integrators the
model's rollout accepts (a tiny model built and traced once per distinct key, never trained).
The configuration's own values, its system and its dataset's shape were checked when the
:class:`RunConfig` was built."""

from __future__ import annotations

import functools

from ._config import INTEGRATORS, RunConfig, check_choice
from ._observation import observation_kind


def check_runnable(cfg: RunConfig) -> RunConfig:
    """Raise a one-line ValueError, before any training, for a run the models cannot run.

    The model's name, then the model for the run, as its observation kind checks it
    (:meth:`bench.core._observation.Observation.check_model`; a state run's:
    :func:`check_state_model`).
    """
    import models

    check_choice("model", cfg.model, models.available())
    observation_kind(cfg.observation).check_model(cfg)
    return cfg


def check_state_model(cfg: RunConfig) -> None:
    """The model for a state run's scene (its options, the coordinates it accepts) and each
    integrator with that model. The integrator rule is the model's capability, asked of
    ``models.rollout`` itself (an abstract trace, no compile): e.g. leapfrog needs a
    second-order continuous model, so ``node`` with ``leapfrog`` is rejected with the
    integrators that ``node`` allows. Checks are cached per model, scene and method.
    """
    import models

    scene_key = _scene_key(cfg)
    model_key = _model_key(cfg)
    _check_model(model_key, scene_key)
    if cfg.train_target == "derivative":
        if models.spec(cfg.model).discrete:
            allowed = [m for m in models.available() if not models.spec(m).discrete]
            raise ValueError(
                f"train_target 'derivative' needs a model with a vector field; {cfg.model!r} is a "
                f"discrete map; allowed: {', '.join(allowed)}"
            )
    for what in ("train_integrator", "eval_integrator"):
        method = getattr(cfg, what)
        problem = _integrator_problem(model_key, scene_key, method)
        if problem is not None:
            allowed = [
                m for m in INTEGRATORS if _integrator_problem(model_key, scene_key, m) is None
            ]
            raise ValueError(
                f"{what} {method!r} cannot run model {cfg.model!r} ({problem}); "
                f"allowed for {cfg.model!r}: {', '.join(allowed) or '(none)'}"
            )


def _scene_key(cfg: RunConfig) -> tuple:
    return (
        cfg.system,
        tuple(sorted(cfg.system_kwargs().items())),
        cfg.random_args,
        cfg.friction > 0,
        cfg.coordinates == "momentum",
    )


def _model_key(cfg: RunConfig) -> tuple:
    return (cfg.model, cfg.model_options, cfg.dissipation, cfg.activation, cfg.dtype)


@functools.lru_cache(maxsize=256)
def _tiny_model(model_key: tuple, scene_key: tuple):
    """The model of a run at width 2, for its scene (raises the registry's ValueError)."""
    import jax

    import models
    import systems

    name, options, dissipation, activation, dtype = model_key
    system_name, params, random_args, damped, canonical = scene_key
    system = systems.make(system_name, **dict(params))
    scene = models.Scene(
        dof=system.dof,
        angular=tuple(system.angular),
        n_args=system.n_args if random_args else 0,
        damped=damped,
        canonical=canonical,
    )
    model = models.make(
        name,
        scene,
        key=jax.random.PRNGKey(0),
        width=2,
        depth=1,
        activation=activation,
        dtype=dtype,
        dissipation=dissipation,
        **dict(options),
    )
    return model, scene


def _check_model(model_key: tuple, scene_key: tuple) -> None:
    _tiny_model(model_key, scene_key)


@functools.lru_cache(maxsize=1024)
def _integrator_problem(model_key: tuple, scene_key: tuple, method: str) -> str | None:
    """Why ``models.rollout`` refuses ``method`` for this model (None: it traces)."""
    import equinox as eqx
    import jax
    import jax.numpy as jnp

    import models

    model, scene = _tiny_model(model_key, scene_key)
    if isinstance(model, models.AbstractTrivialModel):
        return None  # a closed-form prediction: no integrator is used, any name is accepted
    try:
        integrator = models.Integrator(method)
    except ValueError as e:
        return str(e).splitlines()[0]
    dtype = jnp.dtype(model_key[-1])
    z0 = jax.ShapeDtypeStruct((2 * scene.dof,), dtype)
    ts = jax.ShapeDtypeStruct((2,), dtype)
    args = jax.ShapeDtypeStruct((scene.n_args,), dtype) if scene.n_args else None
    try:
        eqx.filter_eval_shape(
            lambda m, z, t, a: models.rollout(m, z, t, a, integrator), model, z0, ts, args
        )
    except ValueError as e:  # the integrator's own refusal, e.g. leapfrog on a first-order model
        return str(e).split(";")[0].splitlines()[0] if str(e) else type(e).__name__
    except Exception:  # noqa: BLE001 - anything else: cannot tell here, let the run try
        return None
    return None
