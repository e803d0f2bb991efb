"""Training the soft actor-critic of :mod:`collect._sac` on a MuJoCo task: the environment loop,
the recording of every transition (the data), evaluation, atomic checkpoints and resumption
after a kill, and the data card of a finished run.
"""

from __future__ import annotations

import dataclasses
import io
import json
import time
from collections.abc import Callable
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from systems import atomic_write
from systems import mujoco_envs as mj

from ._sac import (
    Actor,
    Batch,
    SACConfig,
    SACState,
    greedy_action,
    init_state,
    sample_action,
    update_step,
)

DEFAULT_CONFIG = SACConfig()  # the usual hyperparameters (:class:`SACConfig`)

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
    """``np.savez`` through the suite's one atomic write: a kill at any moment leaves either
    the previous file or the new one, never a partial one."""
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(path, lambda tmp: np.savez(tmp, **arrays))


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
    config: SACConfig = DEFAULT_CONFIG,
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
    config: SACConfig = DEFAULT_CONFIG,
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
            "equinox": eqx.__version__,
            "optax": _optax.__version__,
            "numpy": np.__version__,
        },
    }
    return card
