"""Why the plain (non-separable) HNN on the spring pendulum stalls or diverges at the paper's
budget (claims 1 and 3): the first training steps of its runs, replayed and probed.

Each seed's run is replayed through the trainer's own compiled block for :data:`PROBE_STEPS`
steps, in several variants (:data:`VARIANTS`), and probed after every block (loss, the learned
mass matrix's eigenvalues, the predicted motion). ``python -m bench diagnose-hnn`` writes
``hnn_diagnosis.csv``; the probes and variants: docs/studies/paper.md.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd

from ....core import RunConfig, Study, expand, register_study
from ....kit import fmt as _f
from ..._claims import SPRING_PAPER

FILE = "hnn_diagnosis.csv"
PROBE_STEPS = {"smoke": 4, "quick": 300, "paper": 500, "paper-core": 500}
N_STATES = 256
STALL_RATIO = 0.5
LOW_LR = 1e-3
VARIANTS = ("suite", "suite_all_cores", "reference_init", "lr_1e-3")
# The cores each variant's process runs on: 1 as a paper-core campaign worker (two workers,
# one core each), None: every core of the machine (XLA splits its reductions over its threads,
# so the rounding differs)
CORES = {"suite": 1, "suite_all_cores": None, "reference_init": 1, "lr_1e-3": 1}


def cells(profile: str) -> list[RunConfig]:
    """The profile's runs of the plain HNN on the spring pendulum (the paper's start, k = 2)
    in the second-order experiment, one per seed."""
    from ..second_order import SECOND_ORDER

    out = [
        c
        for c in expand(SECOND_ORDER, profile)
        if c.model == "hnn"
        and c.system == "spring_pendulum"
        and c.k == 2
        and c.system_params == SPRING_PAPER
        and c.model_options == ()
    ]
    if not out:
        raise ValueError(f"profile {profile!r} has no plain-HNN spring cell in second_order")
    return out


def reference_biases(model, key):
    """``model`` with the reference's bias init on its H and mass networks: PyTorch's default
    U(-1/sqrt(fan_in), 1/sqrt(fan_in)) per layer, zero on the mass network's output layer."""
    import equinox as eqx
    import jax
    import jax.numpy as jnp

    from models import MLP

    keys = iter(jax.random.split(key, 64))

    def rebias(mlp, zero_last):
        biases = []
        for i, (w, b) in enumerate(zip(mlp.weights, mlp.biases, strict=True)):
            lim = 1.0 / np.sqrt(w.shape[0])
            last = i == len(mlp.biases) - 1
            biases.append(
                jnp.zeros_like(b)
                if zero_last and last
                else jax.random.uniform(next(keys), b.shape, b.dtype, -lim, lim)
            )
        return eqx.tree_at(lambda m: m.biases, mlp, tuple(biases))

    def each(tree, zero_last):
        is_mlp = lambda x: isinstance(x, MLP)  # noqa: E731
        return jax.tree.map(
            lambda x: rebias(x, zero_last) if is_mlp(x) else x, tree, is_leaf=is_mlp
        )

    model = eqx.tree_at(lambda m: m.hamiltonian_part, model, each(model.hamiltonian_part, False))
    return eqx.tree_at(lambda m: m.mass, model, each(model.mass, True))


def _probe(model, z, args, dof):
    """mass eigenvalues (min, max), motion and dq/dt error of ``model`` at states ``z``."""
    import jax
    import jax.numpy as jnp

    f = jax.vmap(lambda zz, a: model.vector_field(0.0, zz, a))(z, args)
    qdot = z[:, dof:]
    rms = jnp.sqrt(jnp.mean(qdot**2))
    mass = jax.vmap(lambda q, a: (lambda c: c @ c.T)(model.mass.factor(q, a)))(z[:, :dof], args)
    eig = jnp.linalg.eigvalsh(mass)
    motion = jnp.sqrt(jnp.mean(f[:, :dof] ** 2)) / rms
    err = jnp.sqrt(jnp.mean((f[:, :dof] - qdot) ** 2)) / rms
    return eig.min(), eig.max(), motion, err


def _stored_losses(cfg: RunConfig, cache_root: Path) -> np.ndarray | None:
    """The stored run's per-step training losses (its parameter cache), where present."""
    path = Path(cache_root) / "params" / cfg.train_hash / "losses.npy"
    try:
        return np.load(path)
    except (OSError, ValueError):
        return None


def _replay(cfg: RunConfig, variant: str, n_steps: int, cache_root: Path) -> list[dict]:
    """The run's first ``n_steps`` (whole blocks) through the training loop's own compiled
    block (``bench.core.Training``), probed before the first step and after each block.
    ``loss``: the batch loss of the step at the probe (the last step's at the end);
    ``block_loss``: the mean over the block before it; ``stored_loss``: the stored run's loss
    at the same step (``suite`` only; NaN where its cache is absent)."""
    import equinox as eqx
    import jax

    from ....core import Training, build_run, prepare, train_config

    if variant not in VARIANTS:
        raise ValueError(f"variant must be one of {', '.join(VARIANTS)}; got {variant!r}")
    _, data, scene, model = build_run(cfg, cache_root)
    tc = train_config(cfg)
    if variant == "reference_init":
        model = reference_biases(model, jax.random.PRNGKey(10_000 + cfg.seed))
    elif variant == "lr_1e-3":
        tc = dataclasses.replace(tc, lr=LOW_LR)
    z_all, args_all = prepare(model, data, tc)[:2]
    training = Training([model], [data], [tc])
    states, states_args = z_all[:N_STATES, 0], args_all[:N_STATES]
    probe = eqx.filter_jit(lambda m: _probe(m, states, states_args, scene.dof))
    stored = _stored_losses(cfg, cache_root) if variant.startswith("suite") else None

    probes = [(0, [float(x) for x in probe(training.model(0))])]
    losses: list[float] = []
    while len(losses) < n_steps and training.done < tc.steps and not bool(training.dead[0]):
        block, _ = training.advance()
        losses.extend(float(x) for x in block[:, 0])
        probes.append((len(losses), [float(x) for x in probe(training.model(0))]))
    same = np.nan
    if stored is not None:  # the leading steps at which the replay's loss is the stored run's
        n = min(len(stored), len(losses))
        off = ~np.isclose(np.asarray(losses[:n]), stored[:n], rtol=1e-6, atol=0.0)
        same = int(np.argmax(off)) if off.any() else n
    rows = []
    for j, (step, (eig_min, eig_max, motion, err)) in enumerate(probes):
        at = min(step, len(losses) - 1)
        before = losses[probes[j - 1][0] : step] if j else losses[:1]
        rows.append(
            {
                "seed": cfg.seed,
                "variant": variant,
                "lr": tc.lr,
                "step": step,
                "loss": losses[at],
                "block_loss": float(np.mean(before)),
                "stored_loss": (
                    float(stored[at]) if stored is not None and at < len(stored) else np.nan
                ),
                "mass_eig_min": eig_min,
                "mass_eig_max": eig_max,
                "motion": motion,
                "dq_error": err,
                "same_as_stored": same,
                "config_hash": cfg.config_hash,
            }
        )
    return rows


def _worker(cores: int) -> None:
    """A replay process's initializer: ``cores`` cores, then the compilation cache."""
    from ....core import setup_process

    setup_process(n=cores)


def _replay_job(cfg_dict: dict, variant: str, n_steps: int, cache_root: str) -> list[dict]:
    from ....core import cpu_count

    rows = _replay(RunConfig.from_dict(cfg_dict), variant, n_steps, Path(cache_root))
    return [{**r, "cores": cpu_count()} for r in rows]


def diagnose(profile: str, results_dir, cache_root=None, steps: int | None = None) -> pd.DataFrame:
    """Replay the first ``steps`` (default :data:`PROBE_STEPS`, rounded up to whole training
    blocks) of every seed's plain-HNN spring run under each of :data:`VARIANTS`, each variant
    in a fresh process on the cores it names (:data:`CORES`); write and return the table."""
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    import systems

    if profile not in PROBE_STEPS:
        raise ValueError(f"profile must be one of {', '.join(PROBE_STEPS)}; got {profile!r}")
    n = PROBE_STEPS[profile] if steps is None else steps
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ValueError(f"steps must be an integer >= 1; got {steps!r}")
    cache_root = str(Path(cache_root or systems.cache_root()))
    todo = cells(profile)
    ctx = mp.get_context("spawn")
    rows = []
    for variant in VARIANTS:
        cores = CORES[variant]
        with ProcessPoolExecutor(1, mp_context=ctx, initializer=_worker, initargs=(cores,)) as ex:
            jobs = [
                ex.submit(_replay_job, c.to_dict(), variant, min(n, c.steps), cache_root)
                for c in todo
            ]
            for job in jobs:
                rows += job.result()
    df = pd.DataFrame(rows)
    out = Path(results_dir) / FILE
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_suffix(".tmp")
    df.to_csv(tmp, index=False)
    tmp.replace(out)
    return df


def stalled(block_loss, first_loss) -> np.ndarray:
    """Whether a run has not left the plateau: its mean loss over the last block is above
    :data:`STALL_RATIO` x its first step's (NaN: False)."""
    ratio = np.asarray(block_loss, dtype=float) / np.asarray(first_loss, dtype=float)
    return ratio > STALL_RATIO


def stalled_counts(df: pd.DataFrame) -> dict[str, tuple[int, int]]:
    """Per variant (in :data:`VARIANTS` order): how many of its seeds stalled at the last
    probe (:func:`stalled`: the last block's mean loss against the first step's), of how many."""
    out = {}
    for v in VARIANTS:
        flags = [
            bool(stalled(g["block_loss"].iloc[-1], g["loss"].iloc[0]))
            for _, g in df[df["variant"] == v].sort_values("step").groupby("seed")
        ]
        if flags:
            out[v] = (sum(flags), len(flags))
    return out


def summary(df: pd.DataFrame, runs: pd.DataFrame | None = None) -> str:
    """Per seed and variant: the loss of the first step and the mean over the last block, the
    largest mass eigenvalue and the motion at the first and last probe, stalled or not; beside
    the ``suite`` variant how many steps the replay equals the stored run and that run's
    outcome (``runs``, by config hash)."""
    stored = {}
    if runs is not None and len(runs) and "config_hash" in runs:
        for _, r in runs.drop_duplicates("config_hash", keep="last").iterrows():
            stored[r["config_hash"]] = r
    lines = [
        "| seed | variant | lr | cores | steps | loss: first step -> last block | largest eig M | "
        "motion | stalled | replay = stored run (steps) | stored run: status, final loss, "
        "rollout error |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    order = {v: i for i, v in enumerate(VARIANTS)}
    keys = sorted(df.groupby(["seed", "variant"]).groups, key=lambda k: (k[0], order.get(k[1], 99)))
    for seed, variant in keys:
        g = df[(df["seed"] == seed) & (df["variant"] == variant)].sort_values("step")
        a, b = g.iloc[0], g.iloc[-1]
        is_stalled = bool(stalled(b["block_loss"], a["loss"]))
        run = "-"
        if variant.startswith("suite") and a["config_hash"] in stored:
            r = stored[a["config_hash"]]
            run = f"{r['status']}, {_f(float(r['final_loss']))}, {_f(float(r['rollout_error']))}"
        same = b.get("same_as_stored", np.nan)
        lines.append(
            f"| {seed} | {variant} | {a['lr']:g} | {a.get('cores', '-')} | {int(b['step'])} | "
            f"{_f(a['loss'])} -> {_f(b['block_loss'])} | {_f(a['mass_eig_max'])} -> "
            f"{_f(b['mass_eig_max'])} | {_f(a['motion'])} -> {_f(b['motion'])} | "
            f"{'**yes**' if is_stalled else 'no'} | "
            f"{'-' if not np.isfinite(same) else int(same)} | {run} |"
        )
    counts = ", ".join(f"{v}: {n} of {m}" for v, (n, m) in stalled_counts(df).items())
    return "\n".join(
        [
            *lines,
            "",
            f"Stalled at the last probe (mean loss over its last block above {STALL_RATIO} x the "
            f"first step's): {counts}.",
        ]
    )


def section(results_dir) -> str:
    """The report's section: the table where the folder has ``hnn_diagnosis.csv``."""
    from ....core import read_rows, rows_frame

    head = ["## Plain HNN on the spring: the first training steps (claims 1 and 3)", ""]
    path = Path(results_dir) / FILE
    if not path.exists():
        return "\n".join(
            [*head, "(No HNN diagnosis in this folder: `python -m bench diagnose-hnn`.)"]
        )
    df = pd.read_csv(path)
    runs = rows_frame(read_rows(Path(results_dir)))
    text = (
        "The first training steps of each seed's plain-HNN run on the spring (the paper's "
        "start), replayed through the trainer's own compiled block and probed after every "
        "block (`python -m bench diagnose-hnn`; protocol: "
        "`bench/studies/decon/hnn_diagnosis/`). *largest eig M*: of the learned mass "
        "matrix on the first training states; *motion*: rms of the model's dq/dt over the true "
        "rms qdot there; *stalled*: the mean loss over the last block above "
        f"{STALL_RATIO} x the first step's; *replay = stored run*: the leading steps at which "
        "the replay's losses equal the stored run's. Variants: the run as a campaign worker "
        "trained it, on one core (`suite`); the same program on every core, where XLA "
        "splits its reductions differently (`suite_all_cores`); the reference code's bias "
        "init (`reference_init`); lr 1e-3 instead of the paper's 5e-3 (`lr_1e-3`)."
    )
    return "\n".join([*head, text, "", summary(df, runs)])


STUDY = register_study(
    Study(
        name="hnn_diagnosis",
        section=section,
        section_title="Plain HNN on the spring: the first training steps (claims 1 and 3)",
    )
)
