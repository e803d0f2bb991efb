import time, numpy as np, gymnasium as gym, mujoco, warnings
warnings.filterwarnings("ignore")
N = 5000
for name in ["Hopper-v5", "HalfCheetah-v5", "Swimmer-v5", "Walker2d-v5"]:
    env = gym.make(name, exclude_current_positions_from_observation=False)
    rng = np.random.default_rng(0)
    env.reset(seed=0)
    a = rng.uniform(-1, 1, size=(N, env.action_space.shape[0])) * env.action_space.high
    res = []
    for rep in range(3):
        t = time.perf_counter(); resets = 0
        for i in range(N):
            _, _, term, trunc, _ = env.step(a[i])
            if term or trunc:
                env.reset(); resets += 1
        res.append((time.perf_counter() - t) / N * 1e6)
    # raw physics: frame_skip mj_step calls
    u = env.unwrapped; m, d = u.model, u.data
    t = time.perf_counter()
    for i in range(N):
        d.ctrl[:] = a[i]
        mujoco.mj_step(m, d, nstep=u.frame_skip)
    raw = (time.perf_counter() - t) / N * 1e6
    print(f"{name}: env.step median {np.median(res):.1f} us (runs {', '.join(f'{r:.1f}' for r in res)}), resets {resets}; raw mj_step x{u.frame_skip}: {raw:.1f} us")
