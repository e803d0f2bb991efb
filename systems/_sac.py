"""Soft actor-critic (Haarnoja et al. 2018, with a learned temperature): the policy whose whole
replay buffer, random warm-up included, is the MuJoCo data (docs/studies/mujoco.md).

Policy a = tanh(x), x ~ N(mu(s), sigma(s)^2): log pi(a|s) = log N(x) - sum_i log(1 - tanh^2 x_i).
Twin critics, target y = r + gamma (1 - terminated) (min_j Q'_j(s', a') - alpha log pi(a'|s')),
a' ~ pi(.|s'): a time-limit truncation bootstraps, a termination does not. Actor loss
alpha log pi(a|s) - min_j Q_j(s, a); temperature loss alpha (-log pi - H*), H* = -dim(u);
target critics by Polyak averaging theta' <- tau theta + (1 - tau) theta'.
"""

from __future__ import annotations

import dataclasses
import io
import json
import os
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optax

from . import _mujoco as mj

LOG_STD_MIN, LOG_STD_MAX = -10.0, 2.0


@dataclasses.dataclass(frozen=True)
class SACConfig:
    """Hyperparameters (the usual ones; the reference's jax_rl differs in its target entropy,
    -dim(u)/2, and a gradient-norm clip of 0.5). ``target_entropy`` None means -dim(u);
    ``replay_size`` bounds the window the batches are drawn from (every step is recorded)."""

    hidden: int = 256
    depth: int = 2
    lr: float = 3e-4
    batch: int = 256
    gamma: float = 0.99
    tau: float = 0.005
    init_temperature: float = 1.0
    target_entropy: float | None = None
    replay_size: int = 1_000_000
    warmup: int = 10_000
    eval_every: int = 5_000
    eval_episodes: int = 5
    checkpoint_every: int = 50_000

    def __post_init__(self):
        counts = (self.hidden, self.depth, self.batch, self.replay_size, self.warmup)
        counts += (self.eval_every, self.eval_episodes, self.checkpoint_every)
        if min(counts) < 1 or not 0 < self.tau <= 1 or not 0 < self.gamma <= 1:
            raise ValueError(f"invalid SAC configuration {self}")


class Batch(NamedTuple):
    obs: jax.Array  # (B, n_obs)
    action: jax.Array  # (B, n_act), in [-1, 1]
    reward: jax.Array  # (B,)
    next_obs: jax.Array  # (B, n_obs)
    terminated: jax.Array  # (B,) 1.0 where the episode ended in a terminal state


class MLP(eqx.Module):
    """x -> W_n relu(... relu(W_1 x + b_1) ...) + b_n, float32; the activation is fixed in
    code, so the module holds arrays only and plain ``jax.jit`` takes it (cheap to call)."""

    layers: tuple[eqx.nn.Linear, ...]

    def __init__(self, n_in: int, n_out: int, hidden: int, depth: int, *, key):
        sizes = [n_in] + [hidden] * depth + [n_out]
        keys = jax.random.split(key, depth + 1)
        self.layers = tuple(
            eqx.nn.Linear(a, b, dtype=jnp.float32, key=k)
            for a, b, k in zip(sizes[:-1], sizes[1:], keys, strict=True)
        )

    def __call__(self, x):
        for layer in self.layers[:-1]:
            x = jax.nn.relu(layer(x))
        return self.layers[-1](x)


class Actor(eqx.Module):
    """s -> (mu, log sigma) of the Gaussian before the tanh squashing."""

    mlp: MLP

    def __init__(self, n_obs: int, n_act: int, hidden: int, depth: int, *, key):
        self.mlp = MLP(n_obs, 2 * n_act, hidden, depth, key=key)

    def __call__(self, obs):
        mean, log_std = jnp.split(self.mlp(obs), 2)
        return mean, jnp.clip(log_std, LOG_STD_MIN, LOG_STD_MAX)


class Critic(eqx.Module):
    """Twin Q functions (s, a) -> (Q_1, Q_2), their weights stacked on a leading axis."""

    mlps: MLP

    def __init__(self, n_obs: int, n_act: int, hidden: int, depth: int, *, key):
        def make(k):
            return MLP(n_obs + n_act, 1, hidden, depth, key=k)

        self.mlps = eqx.filter_vmap(make)(jax.random.split(key, 2))

    def __call__(self, obs, action):
        x = jnp.concatenate([obs, action])
        return jax.vmap(lambda m: m(x)[0])(self.mlps)


class SACState(eqx.Module):
    """The whole agent as one pytree of arrays: networks, optimiser states, key."""

    actor: Actor
    critic: Critic
    target: Critic
    log_alpha: jax.Array
    actor_opt: optax.OptState
    critic_opt: optax.OptState
    alpha_opt: optax.OptState
    key: jax.Array


def _adam(config: SACConfig):
    return optax.adam(config.lr)


@eqx.filter_jit  # n_obs, n_act and config static
def init_state(n_obs: int, n_act: int, config: SACConfig, *, key) -> SACState:
    k_actor, k_critic, key = jax.random.split(key, 3)
    actor = Actor(n_obs, n_act, config.hidden, config.depth, key=k_actor)
    critic = Critic(n_obs, n_act, config.hidden, config.depth, key=k_critic)
    log_alpha = jnp.log(jnp.asarray(config.init_temperature, jnp.float32))
    opt = _adam(config)
    return SACState(
        actor=actor,
        critic=critic,
        target=critic,
        log_alpha=log_alpha,
        actor_opt=opt.init(eqx.filter(actor, eqx.is_array)),
        critic_opt=opt.init(eqx.filter(critic, eqx.is_array)),
        alpha_opt=opt.init(log_alpha),
        key=key,
    )


def log_prob(mean, log_std, x):
    """log pi(tanh x) of the squashed Gaussian, summed over the last axis, with the stable
    log(1 - tanh^2 x) = 2 (log 2 - x - softplus(-2 x))."""
    z = (x - mean) * jnp.exp(-log_std)
    gauss = -0.5 * z**2 - log_std - 0.5 * jnp.log(2 * jnp.pi)
    jac = 2.0 * (jnp.log(2.0) - x - jax.nn.softplus(-2.0 * x))
    return jnp.sum(gauss - jac, axis=-1)


def sample(actor: Actor, obs, noise):
    """a = tanh(mu + sigma eps) for a batch of observations and standard-normal eps; with
    log pi(a|s)."""
    mean, log_std = jax.vmap(actor)(obs)
    x = mean + jnp.exp(log_std) * noise
    return jnp.tanh(x), log_prob(mean, log_std, x)


def _q(critic: Critic, obs, action):
    return jax.vmap(critic)(obs, action)  # (B, 2)


def critic_target(state: SACState, batch: Batch, noise, gamma: float):
    """y = r + gamma (1 - terminated) (min_j Q'_j(s', a') - alpha log pi(a'|s'))."""
    a_next, logp_next = sample(state.actor, batch.next_obs, noise)
    q_next = _q(state.target, batch.next_obs, a_next).min(axis=-1)
    alpha = jnp.exp(state.log_alpha)
    soft = q_next - alpha * logp_next
    return jax.lax.stop_gradient(batch.reward + gamma * (1.0 - batch.terminated) * soft)


def polyak(target, online, tau: float):
    """theta' <- tau theta + (1 - tau) theta', array leaf by array leaf."""
    arrays, static = eqx.partition(target, eqx.is_array)
    mixed = jax.tree.map(
        lambda t, o: tau * o + (1.0 - tau) * t, arrays, eqx.filter(online, eqx.is_array)
    )
    return eqx.combine(mixed, static)


def _critic_loss(critic, batch: Batch, y):
    q = _q(critic, batch.obs, batch.action)
    return jnp.mean(jnp.sum((q - y[:, None]) ** 2, axis=-1))


def _actor_loss(actor, critic, alpha, obs, noise):
    a, logp = sample(actor, obs, noise)
    q = _q(critic, obs, a).min(axis=-1)
    return jnp.mean(alpha * logp - q), -jnp.mean(logp)


def update(state: SACState, batch: Batch, config: SACConfig) -> tuple[SACState, dict]:
    """One gradient step of critics, then actor, then temperature; then the targets."""
    opt = _adam(config)
    n_act = batch.action.shape[-1]
    target_entropy = -n_act if config.target_entropy is None else config.target_entropy
    key, k1, k2 = jax.random.split(state.key, 3)
    noise1 = jax.random.normal(k1, batch.action.shape, jnp.float32)
    noise2 = jax.random.normal(k2, batch.action.shape, jnp.float32)

    y = critic_target(state, batch, noise1, config.gamma)
    critic_loss, grads = eqx.filter_value_and_grad(_critic_loss)(state.critic, batch, y)
    updates, critic_opt = opt.update(grads, state.critic_opt)
    critic = eqx.apply_updates(state.critic, updates)

    alpha = jnp.exp(state.log_alpha)
    (actor_loss, entropy), grads = eqx.filter_value_and_grad(_actor_loss, has_aux=True)(
        state.actor, critic, alpha, batch.obs, noise2
    )
    updates, actor_opt = opt.update(grads, state.actor_opt)
    actor = eqx.apply_updates(state.actor, updates)

    # d/d(log alpha) of alpha (H - H*), H the entropy estimate of the actor step
    alpha_grad = alpha * (jax.lax.stop_gradient(entropy) - target_entropy)
    updates, alpha_opt = opt.update(alpha_grad, state.alpha_opt)
    log_alpha = optax.apply_updates(state.log_alpha, updates)

    new = SACState(
        actor=actor,
        critic=critic,
        target=polyak(state.target, critic, config.tau),
        log_alpha=log_alpha,
        actor_opt=actor_opt,
        critic_opt=critic_opt,
        alpha_opt=alpha_opt,
        key=key,
    )
    info = dict(critic_loss=critic_loss, actor_loss=actor_loss, entropy=entropy, alpha=alpha)
    return new, info


# The agent state is arrays only: plain jax.jit (its C++ dispatch) instead of filter_jit's
# partitioning on every call, measured ~0.8 ms of Python per call on this pytree.
update_step = jax.jit(update, static_argnums=2)


@jax.jit
def sample_action(actor: Actor, obs, key, step) -> jax.Array:
    """An exploring action a ~ pi(.|s) for one observation, its noise from
    fold_in(key, step): a function of the step, so a resumed run draws the same."""
    noise = jax.random.normal(
        jax.random.fold_in(key, step), (1, actor.mlp.layers[-1].out_features // 2), jnp.float32
    )
    return sample(actor, obs[None], noise)[0][0]


@jax.jit
def greedy_action(actor: Actor, obs) -> jax.Array:
    """The deterministic action tanh(mu(s)) of the evaluations."""
    return jnp.tanh(actor(obs)[0])


# --- the environment loop, recording, checkpoints ----------------------------------------


@dataclasses.dataclass
class SACRun:
    """A finished (or resumed and finished) training: the recorded transitions, the replay
    arrays the agent learnt from, the evaluation returns, the final agent."""

    name: str
    seed: int
    steps: int
    config: SACConfig
    recorder: mj.Recorder
    replay: dict[str, np.ndarray]  # obs, action (in [-1, 1]), next_obs: float32
    eval_steps: np.ndarray
    eval_returns: np.ndarray
    state: SACState
    seconds: float

    def episodes(self) -> mj.Episodes:
        """The recorded buffer as the :class:`Episodes` that ``split_episodes`` takes."""
        return self.recorder.episodes()

    def buffer(self) -> dict[str, np.ndarray]:
        """Every recorded array, the replay's and the raw state's, filled rows only."""
        rec = self.recorder.arrays()
        rec.pop("counters")
        return {**rec, **{k: v[: self.recorder.n] for k, v in self.replay.items()}}


def _env_snapshot(env) -> dict[str, np.ndarray]:
    """What continues an episode exactly: the simulator's integration state (MuJoCo: time,
    qpos, qvel, act, warm-start accelerations, ...) and the reset generator."""
    from gymnasium.envs.classic_control.pendulum import PendulumEnv
    from gymnasium.envs.mujoco.mujoco_env import MujocoEnv

    u = env.unwrapped
    if isinstance(u, MujocoEnv):
        import mujoco

        what = mujoco.mjtState.mjSTATE_INTEGRATION
        sim = np.empty(mujoco.mj_stateSize(u.model, what))
        mujoco.mj_getState(u.model, u.data, sim, what)
    elif isinstance(u, PendulumEnv):
        sim = np.asarray(u.state, np.float64).copy()
    else:
        raise TypeError(f"no snapshot for {type(u).__name__}")
    return {"sim": sim, "env_rng": np.array(json.dumps(u.np_random.bit_generator.state))}


def _env_restore(env, snap) -> None:
    from gymnasium.envs.mujoco.mujoco_env import MujocoEnv

    u = env.unwrapped
    if isinstance(u, MujocoEnv):
        import mujoco

        mujoco.mj_setState(u.model, u.data, snap["sim"], mujoco.mjtState.mjSTATE_INTEGRATION)
    else:
        u.state = np.asarray(snap["sim"]).copy()
    u.np_random.bit_generator.state = json.loads(str(snap["env_rng"]))


def save_atomic(path: Path, arrays: dict[str, np.ndarray]) -> None:
    """np.savez to a temporary file in the same folder, fsync, os.replace: a kill at any
    moment leaves either the previous file or the new one, never a partial one."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.stem, suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            np.savez(f, **arrays)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _config_json(name: str, seed: int, config: SACConfig) -> str:
    # The networks are float32 either way, but under jax's 64-bit mode some constants (log 2 pi,
    # Adam's bias corrections) are rounded from float64: the last bits, and so the run, differ.
    x64 = bool(jax.config.jax_enable_x64)
    return json.dumps(
        {"name": name, "seed": seed, "jax_x64": x64, **dataclasses.asdict(config)}, sort_keys=True
    )


def _state_arrays(state: SACState) -> dict[str, np.ndarray]:
    buf = io.BytesIO()
    eqx.tree_serialise_leaves(buf, state)
    return {"agent": np.frombuffer(buf.getvalue(), np.uint8)}


def _state_from(arrays, like: SACState) -> SACState:
    return eqx.tree_deserialise_leaves(io.BytesIO(arrays["agent"].tobytes()), like)


def evaluate(actor: Actor, env, *, seeds, limit: int) -> float:
    """Mean return of deterministic-policy episodes, one per reset seed."""
    low, high = mj.control_range(env)
    total = 0.0
    for s in seeds:
        obs, _ = env.reset(seed=int(s))
        for _ in range(limit):
            a = np.asarray(greedy_action(actor, jnp.asarray(obs, jnp.float32)), np.float64)
            obs, r, terminated, truncated, _ = env.step(low + (a + 1.0) * (high - low) / 2)
            total += float(r)
            if terminated or truncated:
                break
    return total / len(seeds)


def train_sac(
    name: str,
    make_env: Callable[[], object],
    state_fn: Callable[[object], np.ndarray],
    *,
    steps: int,
    seed: int,
    config: SACConfig = SACConfig(),
    checkpoint: Path | None = None,
    progress: Callable[[int, dict], None] | None = None,
) -> SACRun:
    """Train SAC for ``steps`` env steps, one update per step once ``config.warmup`` uniform
    random steps are in the buffer, recording every transition (``state_fn``'s state before
    the control, the control in the env's range, reward, episode, termination/truncation).
    The agent observes gymnasium's observation. Reproducible given the seed and jax's 64-bit
    mode (see ``_config_json``). With ``checkpoint`` (a file), the run resumes
    from it when present and saves it atomically every ``config.checkpoint_every`` steps and
    at the end. ``progress(step, info)`` is called at each evaluation."""
    if steps < 1:
        raise ValueError(f"steps must be >= 1, got {steps}")
    t0 = time.perf_counter()
    env, eval_env = make_env(), make_env()
    n_obs, n_act = env.observation_space.shape[0], env.action_space.shape[0]
    low, high = mj.control_range(env)
    limit = env.spec.max_episode_steps
    eval_seeds = 10_000 * (seed + 1) + np.arange(config.eval_episodes)
    conf = _config_json(name, seed, config)

    key, act_key = jax.random.split(jax.random.PRNGKey(seed))
    state = init_state(n_obs, n_act, config, key=key)
    rng = np.random.default_rng(seed)
    rec = mj.Recorder(name, steps, seed=seed, limit=limit)
    replay = {
        "obs": np.zeros((steps, n_obs), np.float32),
        "action": np.zeros((steps, n_act), np.float32),
        "next_obs": np.zeros((steps, n_obs), np.float32),
    }
    evals: list[tuple[int, float]] = []
    obs, _ = env.reset(seed=seed)

    if checkpoint is not None:  # a kill during a save leaves its temporary file behind
        for tmp in Path(checkpoint).parent.glob(f"{Path(checkpoint).stem}*.tmp"):
            tmp.unlink(missing_ok=True)
    if checkpoint is not None and Path(checkpoint).exists():
        with np.load(checkpoint) as f:
            ck = {k: f[k] for k in f.files}
        if str(ck["config"]) != conf:
            raise ValueError(f"{checkpoint} holds another run: {ck['config']}")
        state = _state_from(ck, state)
        rng.bit_generator.state = json.loads(str(ck["rng"]))
        rec.restore({k[4:]: v for k, v in ck.items() if k.startswith("rec_")})
        for k in replay:
            replay[k][: rec.n] = ck[f"replay_{k}"]
        evals = [(int(s), float(r)) for s, r in ck["evals"]]
        _env_restore(env, {"sim": ck["sim"], "env_rng": ck["env_rng"]})
        obs = ck["obs"]

    def save():
        arrays = {
            "config": np.array(conf),
            "rng": np.array(json.dumps(rng.bit_generator.state)),
            "obs": np.asarray(obs),
            "evals": np.array(evals, np.float64).reshape(-1, 2),
            **_state_arrays(state),
            **_env_snapshot(env),
            **{f"rec_{k}": v for k, v in rec.arrays().items()},
            **{f"replay_{k}": v[: rec.n] for k, v in replay.items()},
        }
        save_atomic(Path(checkpoint), arrays)

    for i in range(rec.n, steps):
        z = state_fn(env)
        if i < config.warmup:
            a = rng.uniform(-1.0, 1.0, n_act)
        else:
            a = sample_action(state.actor, jnp.asarray(obs, jnp.float32), act_key, np.uint32(i))
            a = np.asarray(a, np.float64)
        u = np.clip(low + (a + 1.0) * (high - low) / 2, low, high)
        next_obs, r, terminated, _, _ = env.step(u)
        replay["obs"][i], replay["action"][i], replay["next_obs"][i] = obs, a, next_obs
        obs = env.reset()[0] if rec.add(z, u, r, terminated) else next_obs

        n = i + 1
        if n >= config.warmup:
            idx = rng.integers(max(0, n - config.replay_size), n, config.batch)
            batch = Batch(
                replay["obs"][idx],
                replay["action"][idx],
                rec.rows["reward"][idx].astype(np.float32),
                replay["next_obs"][idx],
                rec.rows["terminated"][idx].astype(np.float32),
            )
            state, _ = update_step(state, batch, config)
        if n % config.eval_every == 0 or n == steps:
            ret = evaluate(state.actor, eval_env, seeds=eval_seeds, limit=limit)
            evals.append((n, ret))
            if progress is not None:
                info = dict(
                    eval_return=ret, episodes=rec.episode, alpha=float(jnp.exp(state.log_alpha))
                )
                progress(n, {**info, "seconds": time.perf_counter() - t0})
        if checkpoint is not None and (n % config.checkpoint_every == 0 or n == steps):
            save()

    env.close(), eval_env.close()
    ev = np.array(evals, np.float64).reshape(-1, 2)
    return SACRun(
        name,
        seed,
        steps,
        config,
        rec,
        replay,
        ev[:, 0].astype(np.int64),
        ev[:, 1],
        state,
        time.perf_counter() - t0,
    )


def train_policy(
    task_name: str,
    steps: int,
    seed: int,
    checkpoint_dir: Path | str | None = None,
    progress: Callable[[int, dict], None] | None = None,
    config: SACConfig = SACConfig(),
) -> SACRun:
    """SAC on a MuJoCo task of the task table, recording the raw state [q, v] of every step;
    the checkpoint is ``checkpoint_dir/sac-<task>-seed<seed>.npz``."""
    t = mj.task(task_name)
    ck = None if checkpoint_dir is None else Path(checkpoint_dir) / f"sac-{t.name}-seed{seed}.npz"
    return train_sac(
        t.name,
        lambda: mj.make_env(t.name),
        mj.raw_state,
        steps=steps,
        seed=seed,
        config=config,
        checkpoint=ck,
        progress=progress,
    )


def data_card(run: SACRun, split: mj.Split) -> dict:
    """``_mujoco.data_card`` of a split of the run's buffer, with the policy's training."""
    import equinox
    import optax as _optax

    c = run.config
    card = mj.data_card(
        split,
        run.episodes(),
        policy=(
            f"SAC (this suite's systems._sac), {c.depth}x{c.hidden} ReLU MLPs, Adam {c.lr}, "
            f"batch {c.batch}, gamma {c.gamma}, tau {c.tau}, target entropy "
            f"{c.target_entropy if c.target_entropy is not None else '-dim(u)'}"
        ),
        policy_budget=f"{run.steps} env steps, the first {c.warmup} uniform random",
        policy_return=float(run.eval_returns[-1]) if len(run.eval_returns) else None,
    )
    card["policy_training"] = {
        "steps": run.steps,
        "seed": run.seed,
        "final_eval_return": card["policy_return"],
        "eval_episodes": c.eval_episodes,
        "config": dataclasses.asdict(c),
        "jax_x64": bool(jax.config.jax_enable_x64),
        "versions": {
            "jax": jax.__version__,
            "equinox": equinox.__version__,
            "optax": _optax.__version__,
            "numpy": np.__version__,
        },
    }
    return card
