"""Why the suite's rollout-trained LNN fails on the unit double pendulum: the learned
d2L/dqdot2 along rollouts and at initialisation, computed from real (small) runs.

Two parts, one table (``lnn_diagnosis.csv``; ``python -m bench diagnose-lnn``): ``init``, an
ablation of freshly initialised LNNs (kinetic prior, solve, activation), and ``trained``, the
Hessian along each trained model's own rollout against the step where it blows up. Every number
comes from the models; what it measures: docs/studies/lnn_seed.md.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pandas as pd

from ....core import RunConfig, expand, get, profile_defaults
from ..double_pendulum import DOUBLE_PENDULUM_ENERGY

COND_LIMIT = 1e3
LAG = 5  # steps: a blow-up this soon after a near-singular Hessian counts as caused by it
N_TRAJ = 40
# The adaptive rollouts' step budget over 10 s (RK4 takes 1000 steps): a trajectory that needs
# more (a mean step below 2.4 ms: a stiff or exploding learned field) ends with the unreached
# points at inf, a blow-up (diffrax's default of 100,000 took over 13 CPU minutes at quick).
ADAPTIVE_MAX_STEPS = 4096
FILE = "lnn_diagnosis.csv"
SIZES = {  # (seeds of the init part, seeds of the trained part, rollout-training steps)
    "smoke": ((0,), (0,), 20),
    "quick": ((0, 1, 2), (0, 1, 2), 1000),
    "paper": ((0, 1, 2, 3, 4), (0, 1, 2, 3, 4), 8000),
    # the campaign's own runs: the pure LNNs of the seed's two protocols as paper-core trained
    # them (their parameters from the cache the campaign filled; a missing entry retrains,
    # about 2 CPU hours for a notebook LNN), no rollout-trained LNNs, no ablations
    "paper-core": ((), (0, 1, 2, 3, 4), None),
}


def _eigs(model, zs):
    import jax
    import jax.numpy as jnp

    from models import velocity_hessian

    dof = zs.shape[-1] // 2

    def one(z):
        h = velocity_hessian(lambda q, v: model.lagrangian(q, v, None), z[:dof], z[dof:])
        return jnp.linalg.eigvalsh(h)

    return jax.vmap(one)(zs)


def _field(model, zs):
    import jax

    return jax.vmap(lambda z: model.vector_field(0.0, z, None))(zs)


def _roll(model, z0s, ts, integrator):
    import models

    return models.rollout_batch(model, z0s, ts, None, integrator)


_JIT: dict = {}


def _jit(fn):
    """One ``eqx.filter_jit`` per function, so that seeds of one structure compile once."""
    import equinox as eqx

    return _JIT.setdefault(fn.__name__, eqx.filter_jit(fn))


def hessian_eigs(model, zs):
    """Eigenvalues (ascending) of the learned d2L/dqdot2 at states ``zs`` (N, 2d)."""
    import jax.numpy as jnp

    return np.asarray(_jit(_eigs)(model, jnp.asarray(zs, dtype=model.dtype)), dtype=np.float64)


def condition(eigs) -> np.ndarray:
    """max |eig| / min |eig| per row (inf where an eigenvalue is 0)."""
    a = np.abs(np.asarray(eigs, dtype=np.float64))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(a.min(-1) > 0, a.max(-1) / np.where(a.min(-1) > 0, a.min(-1), 1), np.inf)


def first_step(flags) -> np.ndarray:
    """Per row, the first index where ``flags`` is true; -1 if never."""
    flags = np.asarray(flags, dtype=bool)
    return np.where(flags.any(-1), np.argmax(flags, axis=-1), -1)


def coincide(singular: np.ndarray, blowup: np.ndarray, lag: int = LAG) -> np.ndarray:
    """Whether each blow-up comes at or within ``lag`` steps after the first near-singular H
    (False where there is no blow-up)."""
    singular, blowup = np.asarray(singular), np.asarray(blowup)
    return (blowup >= 0) & (singular >= 0) & (blowup >= singular) & (blowup - singular <= lag)


def _rollout_config(profile: str, seed: int, options, steps: int) -> RunConfig:
    base = expand(DOUBLE_PENDULUM_ENERGY, "smoke")[0]
    d, _ = profile_defaults("paper" if profile == "paper" else profile)
    fields = {k: v for k, v in d.items() if k in RunConfig.__dataclass_fields__}
    fields.update(
        model="lnn",
        model_options=options,
        activation="softplus",
        seed=seed,
        steps=steps,
        eval_checkpoints=0,
    )
    return dataclasses.replace(base, **fields)


def _init_rows(profile: str, cache_root) -> list[dict]:
    import jax.numpy as jnp

    import models

    from ....core import build_run

    seeds, _, steps = SIZES[profile]
    rows = []
    variants = [(kp, "lnn") for kp in (0.0, 0.1)] + [(0.0, "lnn_notebook")]
    for kp, init in variants:
        for solve in ("solve", "pinv", "regularised"):
            for act in ("softplus", "tanh"):
                opts = {"kinetic_prior": kp, "solve": solve}
                if init != "lnn":
                    opts["init"] = init
                opts = tuple(sorted(opts.items()))
                for seed in seeds:
                    cfg = dataclasses.replace(
                        _rollout_config(profile, seed, opts, steps), activation=act
                    )
                    system, data, _, model = build_run(cfg, Path(cache_root))
                    z = np.asarray(data.z_train)  # (N, C, 2d)
                    states = z.reshape(-1, z.shape[-1])
                    eig = hessian_eigs(model, states)
                    acc = _jit(_field)(model, jnp.asarray(states, dtype=model.dtype))
                    acc = np.asarray(acc, dtype=np.float64)[:, system.dof :]
                    pred = _jit(_roll)(
                        model,
                        jnp.asarray(z[:, 0], dtype=model.dtype),
                        jnp.asarray(data.ts_train, dtype=model.dtype),
                        models.Integrator(cfg.train_integrator),
                    )
                    err = (np.asarray(pred, dtype=np.float64) - z) ** 2
                    loss0 = float(np.mean(err))
                    cond = condition(eig)
                    rows.append(
                        {
                            "part": "init",
                            "training": "none (fresh)",
                            "init": init,
                            "kinetic_prior": kp,
                            "solve": solve,
                            "activation": act,
                            "seed": seed,
                            "traj": -1,
                            "n_states": len(states),
                            "frac_indefinite": float(np.mean(eig[:, 0] < 0)),
                            "min_eig": float(np.min(eig[:, 0])),
                            "median_abs_min_eig": float(np.median(np.abs(eig).min(-1))),
                            "cond_median": float(np.median(cond)),
                            "cond_max": float(np.max(cond)),
                            "max_abs_qddot": float(np.nanmax(np.abs(acc)))
                            if np.isfinite(acc).any()
                            else math.inf,
                            "frac_nonfinite_qddot": float(np.mean(~np.isfinite(acc).all(-1))),
                            "loss0": loss0,
                            "loss0_finite": bool(np.isfinite(loss0)),
                        }
                    )
    return rows


def _trained_models(profile: str, cache_root):
    """(label, config) of the trained LNNs the diagnosis reads: rollout-trained with the
    suite's prior, rollout-trained pure with pinv, and the pure LNN of each of the seed's
    protocols (its text's and its notebook's)."""
    _, seeds, steps = SIZES[profile]
    if steps is None:
        return _campaign_models(profile, seeds)
    out = []
    for seed in seeds:
        for label, opts in (
            ("rollout, prior 0.1, solve", (("kinetic_prior", 0.1),)),
            ("rollout, pure, pinv", (("kinetic_prior", 0.0), ("solve", "pinv"))),
        ):
            out.append((label, _rollout_config(profile, seed, opts, steps)))
        lnn_seed = get("lnn_seed_double_pendulum")
        seed_cfgs = [c for c in expand(lnn_seed, profile) if c.model == "lnn" and c.seed == seed]
        out += [("derivative (seed protocol), pure, pinv", c) for c in seed_cfgs]
        # ablation: the seed's protocol with the suite's kinetic prior
        out += [
            (
                "derivative (seed protocol), prior 0.1, pinv",
                dataclasses.replace(c, model_options=(("kinetic_prior", 0.1), ("solve", "pinv"))),
            )
            for c in seed_cfgs
        ]
        # the seed's notebook's protocol (fresh box states, L1, Adam with OneCycle): the claim's
        notebook = get("lnn_seed_notebook")
        out += [
            ("derivative (notebook protocol), pure, pinv", c)
            for c in expand(notebook, profile)
            if c.model == "lnn" and c.seed == seed
        ]
        # ablation: the seed's protocol with the notebook's first optimiser state (appendix B / 200)
        out += [
            (
                "derivative (seed protocol), pure, pinv, init / 200",
                dataclasses.replace(c, model_options=(*c.model_options, ("init", "lnn_notebook"))),
            )
            for c in seed_cfgs
        ]
    return out


def _campaign_models(profile: str, seeds) -> list:
    """(label, config) of the pure LNNs of the seed's text and notebook protocols, exactly as
    the profile's sweep runs them."""
    out = []
    for name, label in (
        ("lnn_seed_double_pendulum", "derivative (seed protocol), pure, pinv"),
        ("lnn_seed_notebook", "derivative (notebook protocol), pure, pinv"),
    ):
        out += [
            (label, c) for c in expand(get(name), profile) if c.model == "lnn" and c.seed in seeds
        ]
    return out


def _trained_rows(profile: str, cache_root) -> list[dict]:
    import jax
    import jax.numpy as jnp

    import models

    from ....core import build_run, train_cached

    rows = []
    for label, cfg in _trained_models(profile, cache_root):
        system, data, _, model = build_run(cfg, Path(cache_root))
        model, meta = train_cached(cfg, model, data, Path(cache_root), False)
        z = np.asarray(data.z_test)[:N_TRAJ]
        pred = _jit(_roll)(
            model,
            jnp.asarray(z[:, 0], dtype=model.dtype),
            jnp.asarray(data.ts_test, dtype=model.dtype),
            models.Integrator(cfg.eval_integrator, substeps=cfg.eval_substeps),
        )
        pred = np.asarray(pred, dtype=np.float64)  # (N, T, 2d)
        n, t, d = pred.shape
        flat = np.nan_to_num(pred.reshape(-1, d), nan=0.0, posinf=0.0, neginf=0.0)
        eig = hessian_eigs(model, flat).reshape(n, t, -1)
        cond = condition(eig)
        energy = jax.jit(jax.vmap(jax.vmap(system.energy)))
        e_true = np.asarray(energy(jnp.asarray(z[:, :1])), dtype=np.float64)  # conserved
        e_pred = np.asarray(energy(jnp.asarray(np.nan_to_num(pred, nan=1e6))), dtype=np.float64)
        finite = np.isfinite(pred).all(-1)
        blow = ~finite | (np.abs(e_pred - e_true) > system.potential_range())
        bad_h = (eig[..., 0] < 0) | (cond > COND_LIMIT)
        bad_h &= finite
        # the same learned field with an adaptive solver (the seed's odeint): a blow-up there
        # is the learned dynamics', not a fixed-step integrator's instability
        pred_ad = _jit(_roll)(
            model,
            jnp.asarray(z[:, 0], dtype=model.dtype),
            jnp.asarray(data.ts_test, dtype=model.dtype),
            models.Integrator("adaptive", rtol=1e-6, atol=1e-8, max_steps=ADAPTIVE_MAX_STEPS),
        )
        pred_ad = np.asarray(pred_ad, dtype=np.float64)
        fin_ad = np.isfinite(pred_ad).all(-1)
        e_ad = np.asarray(energy(jnp.asarray(np.nan_to_num(pred_ad, nan=1e6))), dtype=np.float64)
        bl_ad = first_step(~fin_ad | (np.abs(e_ad - e_true) > system.potential_range()))
        sing, bl = first_step(bad_h), first_step(blow)
        co = coincide(sing, bl)
        before = (sing >= 0) & (bl >= 0) & (sing <= bl)
        opts = dict(cfg.model_options)
        for i in range(n):
            ok = finite[i]
            rows.append(
                {
                    "part": "trained",
                    "training": label,
                    "init": opts.get("init", "lnn"),
                    "kinetic_prior": opts.get("kinetic_prior", 0.1),
                    "solve": opts.get("solve", "solve"),
                    "activation": cfg.activation,
                    "seed": cfg.seed,
                    "traj": i,
                    "n_states": int(ok.sum()),
                    "train_status": meta.get("status"),
                    "frac_indefinite": float(np.mean(eig[i, ok, 0] < 0)) if ok.any() else math.nan,
                    "min_eig": float(np.min(eig[i, ok, 0])) if ok.any() else math.nan,
                    "cond_max": float(np.max(cond[i, ok])) if ok.any() else math.nan,
                    "cond_median": float(np.median(cond[i, ok])) if ok.any() else math.nan,
                    "singular_step": int(sing[i]),
                    "blowup_step": int(bl[i]),
                    "coincide": bool(co[i]),
                    "singular_before_blowup": bool(before[i]),
                    "blowup_step_adaptive": int(bl_ad[i]),
                    "cond_at_blowup": _at_blowup(cond[i], finite[i], bl[i], np.max),
                    "min_eig_at_blowup": _at_blowup(eig[i, :, 0], finite[i], bl[i], np.min),
                }
            )
    return rows


def _at_blowup(x, finite, step: int, reduce, window: int = 3) -> float:
    """``reduce`` of ``x`` over the finite states of the ``window`` steps up to a blow-up."""
    if step < 0:
        return math.nan
    lo = max(0, step - window)
    sel = np.asarray(x[lo : step + 1])[np.asarray(finite[lo : step + 1])]
    return float(reduce(sel)) if len(sel) else math.nan


def diagnose(profile: str, results_dir, cache_root=None) -> pd.DataFrame:
    """Run both parts and write ``<results_dir>/lnn_diagnosis.csv``; return the table."""
    import systems

    if profile not in SIZES:
        raise ValueError(f"diagnose-lnn: profile must be one of {sorted(SIZES)}, got {profile!r}")
    cache_root = Path(cache_root or systems.cache_root())
    df = pd.DataFrame(_init_rows(profile, cache_root) + _trained_rows(profile, cache_root))
    out = Path(results_dir) / FILE
    out.parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(out, index=False)
    return df


def _count(g: pd.DataFrame, column: str) -> str:
    return str(int((g[column] >= 0).sum())) if column in g else "-"


def summary(df: pd.DataFrame) -> str:
    """The diagnosis as Markdown tables (the report's subsection)."""
    if df is None or not len(df):
        return ""
    lines = ["### Diagnosis of the LNN's failures (`lnn_diagnosis.csv`)", ""]
    init = df[df["part"] == "init"]
    if len(init):
        lines += [
            "Fresh LNNs on the rollout-trained experiment's training chunks (means over seeds): "
            "share of states with an indefinite d2L/dqdot2, median condition number, largest "
            "|qddot|, seeds whose step-0 rollout loss is finite.",
            "",
            "| init | kinetic prior | solve | activation | indefinite | cond (median) | "
            "max abs qddot | step-0 loss finite |",
            "|---|---|---|---|---|---|---|---|",
        ]
        keys = ["init", "kinetic_prior", "solve", "activation"]
        for (ini, kp, solve, act), g in init.groupby(keys):
            name = {"lnn": "appendix B", "lnn_notebook": "appendix B / 200"}.get(ini, ini)
            lines.append(
                f"| {name} | {kp:g} | {solve} | {act} | {g['frac_indefinite'].mean():.2f} | "
                f"{g['cond_median'].median():.3g} | {g['max_abs_qddot'].max():.3g} | "
                f"{int(g['loss0_finite'].sum())}/{len(g)} |"
            )
        lines.append("")
    tr = df[df["part"] == "trained"]
    if len(tr):
        lines += [
            f"Trained LNNs along their own test rollouts ({N_TRAJ} trajectories per seed): "
            f"trajectories whose d2L/dqdot2 turns indefinite or has condition > {COND_LIMIT:g} "
            "(near-singular), that blow up (energy error above the potential's range or "
            f"non-finite), and blow-ups within {LAG} steps after a near-singular Hessian.",
            "",
            "| training | seeds | trajectories | near-singular H | indefinite at t = 0 | "
            "blow-ups | blow-ups after a near-singular H | of those within "
            f"{LAG} steps | P(blow-up given near-singular) | P(blow-up otherwise) | "
            "median smallest eigenvalue | median cond at blow-up | blow-ups, adaptive solver |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
        ]
        for label, g in tr.groupby("training", sort=False):
            sing, blow = g["singular_step"] >= 0, g["blowup_step"] >= 0
            p_s = blow[sing].mean() if sing.any() else math.nan
            p_n = blow[~sing].mean() if (~sing).any() else math.nan
            lines.append(
                f"| {label} | {g['seed'].nunique()} | {len(g)} | {int(sing.sum())} | "
                f"{int((g['singular_step'] == 0).sum())} | {int(blow.sum())} | "
                f"{int(g['singular_before_blowup'].sum())} | {int(g['coincide'].sum())} | "
                f"{p_s:.2f} | {p_n:.2f} | {g['min_eig'].median():.3g} | "
                f"{g['cond_at_blowup'].median():.3g} | {_count(g, 'blowup_step_adaptive')} |"
            )
    return "\n".join(lines)
