"""The notebook protocol's pure LNN at `quick` (2,000 steps, width 128, batch 128, seeds 0-2)
over its peak learning rate, from the notebook's own 1e-5 to the suite's rule (1e-5 x 600,000 /
2,000 = 3e-3), beside constant velocity: does the raised rate stop the LNN from fitting?

    PYTHONPATH=. .venv/bin/python examples/lnn_seed/notebook_lr.py RESULTS_DIR

Runs stored in RESULTS_DIR as experiment ``lnn_notebook_lr`` (not a claim's), then a table.
"""

import dataclasses
import sys

from bench.core import setup_process

LRS = (1e-5, 1e-4, 1e-3, 3e-3)


def main(results: str) -> None:
    setup_process()
    import bench

    configs = {}
    for c in bench.expand("lnn_seed_notebook", "quick", seeds=[0, 1, 2]):
        if c.model == "constant_velocity":
            configs[c.config_hash] = c
        elif c.model == "lnn":
            for lr in LRS:
                r = dataclasses.replace(c, lr=lr)
                configs[r.config_hash] = r
    bench.sweep(
        list(configs.values()), results, experiment="lnn_notebook_lr", profile="quick",
        progress=False,
    )  # fmt: skip
    runs = bench.load_runs(results)
    runs = runs[runs["experiment"] == "lnn_notebook_lr"]
    cols = ["final_loss", "loss_rise", "derivative_mse_test", "rollout_error", "energy_pct_max_pe"]
    print(runs.groupby(["model", "lr"])[cols].median().to_string())


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "results/own/notebook_lr")
