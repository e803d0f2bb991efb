"""The side-by-side script of Fig. 9's rigid bodies (bench/sidebyside/decon_rigid.py) without the
paper's code or torch: its one-line errors, the Cartesian starts it hands the paper's integrator,
constant velocity, the two metrics and the stored runs' learning ratio."""

from __future__ import annotations

import jax
import numpy as np
import pandas as pd
import pytest

import systems
from bench.sidebyside import _decon as D
from bench.sidebyside import decon_rigid as R


def _checkouts(tmp_path):
    code, meshes = tmp_path / "decon", tmp_path / "chnn"
    for f in D.EXPECTED:
        (code / f).parent.mkdir(parents=True, exist_ok=True)
        (code / f).write_text("")
    meshes.mkdir()
    return code, meshes


def test_bad_checkouts_and_options_are_one_line(tmp_path, capsys):
    code, meshes = _checkouts(tmp_path)
    base = ["--seed-code", str(code), "--meshes", str(meshes)]
    assert R.main(base) == 2  # the meshes are missing
    for f in R.MESHES:
        (meshes / f).write_text("")
    assert R.main(base + ["--system", "pendulum"]) == 2
    assert R.main(base + ["--model", "lnn"]) == 2
    assert R.main(base + ["--torch-python", str(tmp_path / "nopython")]) == 2
    assert R.main(["--seed-code", str(tmp_path / "absent"), "--meshes", str(meshes)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 5
    assert err[0].startswith("error: --meshes") and "rotor.obj" in err[0]
    assert err[1].startswith("error: --system") and "rotor" in err[1]
    assert err[2].startswith("error: --model") and "node_so" in err[2]
    assert "--torch-python" in err[3] and "pywavefront" in err[3]
    assert err[4].startswith("error: --seed-code") and "decon-hnn" in err[4]


def test_cartesian_starts_are_the_body_points_and_their_velocities():
    systems.enable_x64()
    rotor = systems.make("rotor")
    z0 = np.asarray(rotor.sample_initial(jax.random.PRNGKey(0), 3))
    xv = R.cartesian_starts(rotor, z0)
    assert xv.shape == (3, 2, 4, 3)
    h = 1e-6
    for z, (x, v) in zip(z0, xv, strict=True):
        q, qdot = z[:6], z[6:]
        np.testing.assert_allclose(x, rotor.positions(z), atol=1e-12)
        fd = rotor.positions(np.r_[q + h * qdot, qdot]) - rotor.positions(np.r_[q - h * qdot, qdot])
        np.testing.assert_allclose(v, np.asarray(fd) / (2 * h), atol=1e-6)
        # rigid: the distances between the body points do not change along the motion
        d = x[:, None] - x[None]
        np.testing.assert_allclose(np.einsum("ijk,ijk->ij", d, v[:, None] - v[None]), 0, atol=1e-9)


def test_constant_velocity_is_exact_for_a_translating_rotor():
    systems.enable_x64()
    rotor = systems.make("rotor")
    z0 = np.array([0.1, -0.2, 0.3, 0.4, 1.0, -0.5, 0.2, 0.1, -0.3, 0.0, 0.0, 0.0])
    ts = np.linspace(0.0, 2.0, 41)
    true = np.asarray(rotor.simulate(z0, ts))[None]
    cv = R.constant_velocity(true, ts)
    np.testing.assert_allclose(cv, true, atol=1e-9)
    spinning = np.asarray(rotor.simulate(z0 + np.r_[np.zeros(9), 0.5, 1.0, 0.3], ts))[None]
    assert R.scores(R.constant_velocity(spinning, ts), spinning, rotor.angular)["error"] > 1e-3


def test_the_suite_metric_wraps_angles_the_papers_does_not():
    true = np.zeros((2, 5, 4)) + 0.5
    pred = true.copy()
    pred[:, 1:, 0] += 2 * np.pi  # a whole turn on the angle, none elsewhere
    s = R.scores(pred, true, (True, False))
    assert s["error"] == pytest.approx(1e-7)  # clamped zero
    assert s["paper_gerr"] > 1e4 * s["error"]  # the turn counts, t = 0 (clamped) included


def test_stored_ratio_scores_failed_runs_as_error_one(tmp_path, monkeypatch):
    rows = [("constant_velocity", 0.005, s, "ok", 0.4) for s in range(3)] + [
        ("node", 0.005, 0, "ok", 0.1),
        ("node", 0.005, 1, "ok", 0.2),
        ("node", 0.005, 2, "diverged", 0.3),
    ]
    rows += [("node", 0.001, s, "ok", 0.01) for s in range(3)]  # another rate: not read
    runs = pd.DataFrame(rows, columns=["model", "lr", "seed", "status", "rollout_error"])
    runs["experiment"], runs["system"] = "rigid_bodies", "rotor"
    monkeypatch.setattr("bench.load_runs", lambda _: runs)
    cell = {"experiment": "rigid_bodies", "system": "rotor"}
    ratio, n = R.stored_ratio(tmp_path, cell, "node", lr=0.005)
    assert n == 3
    assert ratio == pytest.approx(np.exp(np.mean(np.log([4.0, 2.0, 0.4]))))
    assert R.learns(ratio).endswith("(does not learn)") and R.learns(2.0).endswith("(learns)")
    gyro = {"experiment": "rigid_bodies", "system": "gyroscope"}
    assert np.isnan(R.stored_ratio(tmp_path, gyro, "node", lr=0.005)[0])


def test_a_failed_prediction_scores_error_one():
    true = np.zeros((2, 5, 4)) + 0.5
    cv = {"error": 0.3, "paper_gerr": 0.2}
    row = R.checkpoint("paper", 7, np.full_like(true, np.nan), true, (), cv)
    assert row["step"] == 7 and row["error"] == 1.0 and row["paper_gerr"] == 1.0
    assert row["cv_ratio"] == pytest.approx(0.3)


def test_the_verdict_reads_the_papers_code_against_our_stored_runs():
    assert R.verdict("node", "rotor", 0.7, 0.8).startswith("verdict: agree: node does not learn")
    assert R.verdict("node", "gyroscope", 3.0, 2.5).startswith("verdict: agree: node learns")
    assert "the paper's code learns it, ours does not" in R.verdict("hnn_so", "rotor", 3.0, 0.4)
    assert "ours learns it" in R.verdict("hnn_so", "rotor", 0.4, 3.0)


def test_rates_read_the_velocity_half():
    z = np.zeros((10, 20, 4))  # 400 rates
    z[..., 2:] = -1.0
    z[1, 2, 3] = -40.0  # one fast window
    z[..., :2] = 1e3  # positions are not rates
    p99, top = R.rates(z)
    assert top == 40.0 and p99 == pytest.approx(1.0)
