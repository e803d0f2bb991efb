"""Stability cases at small size: every variant ends in a recorded outcome, and the physics
behind the outcomes holds (stiff RK4 blows up, adaptive does not; the relativistic round trip
is exact to rounding in float64; a regularised Euler-Lagrange solve stays finite where LU
does not)."""

from __future__ import annotations

import math
from dataclasses import replace

import jax
import numpy as np
import pandas as pd
import pytest
from _markdown import section, table_rows

from bench.studies import stability as S

TINY = replace(
    S.SIZES["smoke"],
    horizon=0.6,
    spring_constants=(1e5,),
    stiff_solvers=("tsit5",),
    speeds=(0.999,),
    dts=(0.00125, 0.0025, 0.005),  # euler inside the order fit's window (err < 1e-2)
    dt_methods=("euler", "rk4"),
    lnn_probe=False,
)


def _check_recorded(rows):
    assert rows
    for r in rows:
        assert r.outcome in S.OUTCOMES
        if r.outcome == "ok":
            assert math.isfinite(r.value), r
        if r.outcome == "failed":
            assert r.message, r


def _by_variant(rows, metric):
    return {r.variant: r for r in rows if r.metric == metric}


# ----------------------------------------------------------------------------- guards
def test_guard_records_exceptions_and_relabels_nan():
    def boom():
        raise RuntimeError("solver exploded\nsecond line")

    (row,) = S.guard("x", boom)
    assert row.outcome == "failed" and "solver exploded" in row.message
    assert "\n" not in row.message
    rows = S.guard("x", lambda: [S.Row("x", "v", "m", "ok", float("nan"))])
    assert rows[0].outcome == "diverged"
    rows = S.guard("x", lambda: [S.Row("x", "v", "m", "ok", 1.5)])
    assert rows[0].outcome == "ok" and rows[0].value == 1.5


def test_row_rejects_unknown_outcome():
    with pytest.raises(ValueError, match="outcome"):
        S.Row("x", "v", "m", "fine")


def test_first_bad_step():
    z = np.ones((10, 4))
    assert S.first_bad_step(z) is None
    z[6, 2] = np.nan
    z[8, 0] = np.inf
    assert S.first_bad_step(z) == 6
    z = np.ones((2, 10, 4))
    z[1, 3, 1] = 1e9
    assert S.first_bad_step(z) is None
    assert S.first_bad_step(z, bound=1e3) == 3
    # the bound applies only where the mask says (angles may grow without bound)
    assert S.first_bad_step(z, bound=1e3, mask=[True, False, True, True]) is None


def test_unknown_profile_and_case():
    with pytest.raises(ValueError, match="stability profile"):
        S.run_cases("huge")
    with pytest.raises(ValueError, match="unknown stability case"):
        S.run_cases("smoke", ["nope"])


# ----------------------------------------------------------------------------- physics
@pytest.mark.slow  # keeps make test under 10 min on a 2-core CPU
def test_stiff_rk4_diverges_adaptive_stays_accurate():
    rows = S.case_stiffness(TINY)
    _check_recorded(rows)
    err = _by_variant(rows, "final_error")
    rk4 = err["kappa=100000/rk4"]
    # highest mode omega ~ sqrt(kappa (1/m1 + 1/m2)) ~ 430 rad/s: omega dt ~ 13 >> 2.8
    assert rk4.outcome == "diverged" and rk4.step is not None and rk4.step <= 20
    tsit = err["kappa=100000/tsit5"]
    assert tsit.outcome == "ok" and tsit.value < 1e-4
    nfe = _by_variant(rows, "nfe")
    assert nfe["kappa=100000/tsit5"].value > nfe["kappa=100000/rk4"].value
    # one cost unit for every solver: counted calls of the field (rk4: 4 per step + 0)
    assert {"rk4", "implicit_midpoint", "tsit5"} <= {r.method for r in nfe.values()}
    assert nfe["kappa=100000/rk4"].value == 4 * round(TINY.horizon / S.DT)
    # the A-stable implicit midpoint stays bounded at the step where RK4 blows up
    assert err["kappa=100000/implicit_midpoint"].outcome == "ok"


def test_relativistic_roundtrip_float64_exact_to_rounding():
    import systems

    sysm = systems.make("relativistic_particle")
    rows64 = S.relativistic_roundtrip(sysm, 0.999, "float64")
    rows32 = S.relativistic_roundtrip(sysm, 0.999, "float32")
    _check_recorded(rows64 + rows32)
    rt64 = _by_variant(rows64, "roundtrip_error")["v=0.999/float64"]
    # error in units of (1 - |qdot|) = 1e-3: 1e-10 of that is 1e-13 absolute
    assert rt64.outcome == "ok" and rt64.value < 1e-9
    p64 = _by_variant(rows64, "momentum_error")["v=0.999/float64"]
    p32 = _by_variant(rows32, "momentum_error")["v=0.999/float32"]
    assert p64.value < 1e-14
    # float32: 1 - qdot^2 ~ 2e-3 loses ~3 of float32's 7 digits
    assert 1e-8 < p32.value < 1e-2


def test_float32_velocity_stagnates_near_light_speed():
    # at v = 0.999 the float32 RK4 velocity never changes while float64's does:
    # the case must flag it, so that its float32 "drift" is not read as a measurement
    import systems
    from bench.studies.stability._truth import _relativistic_rk4

    sysm = systems.make("relativistic_particle")
    ts = np.arange(21) * S.DT
    rows = _relativistic_rk4(sysm, np.array([0.0, 0.999]), ts, np.array([1.0]), 0.999, "g")
    _check_recorded(rows)
    change = {r.dtype: r.value for r in rows if r.metric == "velocity_change"}
    assert change["float64"] > 0 and change["float32"] == 0.0
    (flag,) = [r for r in rows if r.metric == "stagnant"]
    assert flag.value == 1.0 and "stagnant" in flag.message
    rows = _relativistic_rk4(sysm, np.array([0.0, 0.9]), ts, np.array([1.0]), 0.9, "g")
    (flag,) = [r for r in rows if r.metric == "stagnant"]
    assert flag.value == 0.0


def test_regularised_lnn_solve_finite_where_lu_is_not():
    rows = S.case_lnn_singular(TINY)
    _check_recorded(rows)
    err = _by_variant(rows, "accel_error")
    # a singular velocity Hessian: LU returns non-finite values, recorded as diverged
    assert err["degenerate/solve"].outcome == "diverged"
    norms = _by_variant(rows, "accel_norm")
    assert norms["degenerate/regularised"].outcome == "ok"
    assert norms["degenerate/pinv"].outcome == "ok"
    # well conditioned (cond ~ 4e2): every solve agrees with the float64 truth
    assert err["m1=0.01/solve"].value < 1e-3 and err["m1=0.01/pinv"].value < 1e-3
    # the condition number grows like 1/m1
    cond = {r.variant.split("/")[0]: r.param for r in rows if r.method == "solve" and r.param}
    assert cond["m1=1e-08"] > 1e5 * cond["m1=0.01"]


@pytest.mark.slow
def test_dt_sweep_convergence_orders():
    rows = S.case_dt_sweep(TINY)
    _check_recorded(rows)
    order = {r.method: r.value for r in rows if r.metric == "order"}
    assert 0.8 < order["euler"] < 1.3
    assert 3.5 < order["rk4"] < 4.6


def test_parallel_plan_splits_the_long_horizon_by_model_and_keeps_shared_models_together():
    size = S.SIZES["quick"]
    jobs = S._run._jobs(list(S.CASES), size)
    flat = [(name, part) for job in jobs for name, part, _ in job]
    assert sorted(flat) == sorted(
        [(n, 0) for n in S.CASES if n != "long_horizon"]
        + [("long_horizon", i) for i in range(len(size.models))]
    )
    assert [sz.models for job in jobs for n, _, sz in job if n == "long_horizon"] == [
        (m,) for m in size.models
    ]
    assert [n for n, _, _ in jobs[-1]] == list(S._run.LEARNED)  # one process: shared models
    assert jobs[0][0][0] == "long_horizon"  # the longest first


@pytest.mark.slow
def test_cases_in_worker_processes_give_the_rows_of_one_process():
    cases = ["high_energy_truth", "long_horizon", "precision"]
    one = S.to_frame(S.run_cases("smoke", cases, progress=False))
    two = S.to_frame(S.run_cases("smoke", cases, progress=False, workers=2))
    assert list(one["case"]) == list(two["case"]) and len(one) > 4
    timed = one["metric"].str.contains("seconds")  # wall-clock rows may differ, nothing else
    pd.testing.assert_frame_equal(one[~timed], two[~timed])


@pytest.mark.slow
def test_run_stability_smoke_writes_everything(tmp_path):
    df = S.run_stability(tmp_path, "smoke", workers=2)
    assert (tmp_path / "stability.csv").exists()
    assert (tmp_path / "figures" / "stability.png").exists()
    assert set(df["outcome"]) <= set(S.OUTCOMES)
    ok = df[df["outcome"] == "ok"]
    assert np.all(np.isfinite(ok["value"]))
    assert set(df["case"]) == set(S.CASES)
    text = section(S.stability_section(tmp_path), "Numerical stability")
    for case, g in df.groupby("case"):  # one table per case, a row per variant and metric
        assert len(table_rows(section(text, case), "|")) == len(g), case


@pytest.mark.slow  # keeps make test under 10 min on a 2-core CPU
def test_simulate_takes_tolerance_and_solver():
    # the stability study's ground truth and solver variants go through systems' simulate
    import systems

    sysm = systems.make("chain_pendulum", k=2)
    z0 = np.asarray(sysm.sample_initial(jax.random.PRNGKey(0), 2))
    ts = np.linspace(0.0, 0.5, 4)
    truth = np.asarray(sysm.simulate_batch(z0, ts))
    ys, info = sysm.simulate_batch(z0, ts, rtol=1e-8, atol=1e-10, solver="tsit5", stats=True)
    assert np.max(np.abs(np.asarray(ys) - truth)) < 1e-5
    assert np.all(np.asarray(info["ok"])) and np.all(np.asarray(info["nfe"]) > 6)
    loose = sysm.simulate(z0[0], ts, rtol=1e-3, atol=1e-5, solver="tsit5")
    assert 0 < np.max(np.abs(np.asarray(loose) - truth[0])) < 1e-1
    with pytest.raises(ValueError, match="allowed"):
        sysm.simulate(z0[0], ts, solver="euler")
