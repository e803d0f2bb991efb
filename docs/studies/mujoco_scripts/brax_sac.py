import sys, time, warnings, os
warnings.filterwarnings("ignore")
import jax, jax.numpy as jnp
# measurement-only shim: brax 0.14.2 calls an API that jax 0.10 removed
jax.device_put_replicated = lambda x, devices: jax.tree.map(lambda a: jnp.broadcast_to(a, (len(devices),) + jnp.shape(a)), x)
from brax import envs
from brax.training.agents.sac import train as sac
n = int(sys.argv[1]); backend = sys.argv[2]
env = envs.get_environment("hopper", backend=backend)
times = []
def progress(step, metrics):
    times.append((step, time.perf_counter(), float(metrics.get("eval/episode_reward", float("nan")))))
t0 = time.perf_counter()
make_policy, params, metrics = sac.train(environment=env, num_timesteps=n, episode_length=1000,
    num_envs=1, num_eval_envs=1, batch_size=256, num_evals=2, min_replay_size=1000,
    max_replay_size=100_000, grad_updates_per_step=1, seed=0, progress_fn=progress)
t1 = time.perf_counter()
print(f"backend={backend} timesteps={n} total {t1-t0:.1f} s; progress: {[(s, round(t-t0,1), r) for s,t,r in times]}")
