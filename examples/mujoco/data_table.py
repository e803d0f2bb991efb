"""The committed MuJoCo files as a Markdown table, read from their cards and sizes:
``python examples/mujoco/data_table.py``."""

import json

from systems import mujoco_data as D

print(
    "| task | transitions | episodes | test episodes | policy steps "
    "| evaluation return at 5K / 50K / 100K / end | mean episode return | file |"
)
print("|---|---|---|---|---|---|---|---|")
for path in sorted(D.COMMITTED.glob("*.npz")):
    c = json.loads(path.with_suffix(".json").read_text())
    ev = dict((int(s), r) for s, r in c["policy_training"]["eval_returns"])
    at = " / ".join(f"{ev[s]:.0f}" for s in (5000, 50000, 100000) if s in ev)
    print(
        f"| {c['task']} | {c['collection']['transitions']} | {c['collection']['episodes']} "
        f"| {c['sizes']['test_episodes']} | {c['policy_training']['steps']} "
        f"| {at} / {c['policy_return']:.0f} | {c['collection']['mean_episode_return']:.0f} "
        f"| {path.stat().st_size / 1e6:.1f} MB |"
    )
