"""Metric formulas on hand-made arrays, plus the true-energy route through a real system."""

import numpy as np
import pytest

from bench.core import _metrics as M
from bench.core import aggregate


def test_relative_error_known_value():
    # ||(3,0) - (0,4)|| = 5 ; ||(3,0)|| + ||(0,4)|| = 7.
    zhat = np.array([[0.0, 4.0], [3.0, 0.0]])
    z = np.array([[0.0, 4.0], [0.0, 4.0]])
    err = M.relative_error(zhat, z)
    np.testing.assert_allclose(err, [0.0, 5.0 / 7.0])
    # t = 0 is excluded from the summary: a single point left.
    assert M.rollout_error(zhat, z) == pytest.approx(5.0 / 7.0)


def test_geometric_mean_with_clamp():
    x = np.array([1e-2, 1e-4, 0.0])  # 0 clamps to 1e-7
    expected = np.exp(np.mean(np.log([1e-2, 1e-4, 1e-7])))
    assert M.geometric_mean(x) == pytest.approx(expected)
    assert M.geometric_mean(np.array([2.0, 8.0])) == pytest.approx(4.0)
    assert np.isnan(M.geometric_mean(np.array([np.nan, np.nan])))


def test_angle_wrap_invariance():
    rng = np.random.default_rng(0)
    z = rng.normal(size=(3, 6, 4))  # dof 2, both angles
    zhat = z + 0.1 * rng.normal(size=z.shape)
    shift = np.zeros(4)
    shift[:2] = 2 * np.pi * np.array([1, -3])
    base = M.relative_error(zhat, z, angular=(True, True))
    np.testing.assert_allclose(M.relative_error(zhat + shift, z, (True, True)), base, atol=1e-12)
    np.testing.assert_allclose(M.relative_error(zhat, z - shift, (True, True)), base, atol=1e-12)
    # A rate is not an angle: shifting it by 2 pi must change the error.
    rate_shift = np.array([0, 0, 2 * np.pi, 0])
    assert not np.allclose(M.relative_error(zhat + rate_shift, z, (True, True)), base)
    # Wrapped difference: 359 degrees vs 1 degree are 2 degrees apart, not 358.
    a = np.array([[np.deg2rad(1.0), 0.0]])
    b = np.array([[np.deg2rad(359.0), 0.0]])
    d = M.state_difference(a, b, angular=(True,))
    assert d[0, 0] == pytest.approx(np.deg2rad(2.0))
    assert M.mse(zhat + shift, z, (True, True)) == pytest.approx(M.mse(zhat, z, (True, True)))


def test_reference_compatible_includes_t0_and_no_wrap():
    z = np.array([[1.0, 0.0], [1.0, 0.0], [1.0, 0.0]])
    zhat = np.array([[1.0, 0.0], [1.1, 0.0], [1.2, 0.0]])
    e = M.relative_error(zhat, z)
    ours = M.rollout_error(zhat, z)
    ref = M.rollout_error(zhat, z, reference_compatible=True)
    assert ours == pytest.approx(np.sqrt(e[1] * e[2]))
    assert ref == pytest.approx(np.exp(np.mean(np.log([1e-7, e[1], e[2]]))))
    assert ref < ours  # the t = 0 zero shrinks the reference's number
    shifted = zhat.copy()
    shifted[2, 0] += 2 * np.pi
    assert M.rollout_error(shifted, z, (True,)) == pytest.approx(ours)
    assert M.rollout_error(shifted, z, (True,), reference_compatible=True) != pytest.approx(ref)


def test_nonfinite_counts_as_max_error_from_first_bad_time():
    z = np.ones((1, 5, 2))
    zhat = z.copy()
    zhat[0, 2, 0] = np.nan
    zhat[0, 3] = 1.0  # finite again later: still counted as failed
    err = M.relative_error(zhat, z)
    np.testing.assert_array_equal(err[0], [0, 0, 1, 1, 1])
    assert np.isnan(M.mse(zhat, z))
    hp = np.array([[1.0, 1.0, np.inf, 1.0]])
    ev = M.energy_violation_curve(hp, np.ones((1, 4)))
    np.testing.assert_array_equal(ev[0], [0, 0, 1, 1])


def test_energy_violation_formula():
    hp = np.array([[2.0, 3.0, 1.0]])
    ht = np.array([[2.0, 1.0, 1.0]])
    np.testing.assert_allclose(M.energy_violation_curve(hp, ht)[0], [0.0, 0.5, 0.0])
    # Geometric mean over t >= 1: sqrt(0.5 * 1e-7).
    assert M.energy_violation(hp, ht) == pytest.approx(np.sqrt(0.5 * 1e-7))


def test_valid_prediction_time():
    ts = np.array([0.0, 0.1, 0.2, 0.3])
    err = np.array([[0.0, 0.01, 0.03, 0.01], [0.0, 0.0, 0.0, 0.0]])
    np.testing.assert_allclose(M.valid_prediction_time(err, ts), [0.2, 0.3])
    np.testing.assert_allclose(M.valid_prediction_time(err, ts, threshold=0.001), [0.1, 0.3])


def test_energy_pct_max_pe():
    hp = np.array([[0.0, 1.0, 3.0]])
    ht = np.zeros((1, 3))
    assert M.energy_pct_max_pe(hp, ht, 4.0) == pytest.approx(100 * 2.0 / 4.0)
    assert np.isnan(M.energy_pct_max_pe(hp, ht, float("nan")))


def test_true_energy_route_and_floor():
    import systems

    s = systems.make("chain_pendulum", k=1)
    ts = np.arange(6) * 0.03
    z0 = np.array([[0.5, 0.2], [-0.3, 1.0]])
    traj = np.asarray(s.simulate_batch(z0, ts))
    h = M.energies(s, traj)
    # Energy is conserved along the truth and matches the single-state route.
    np.testing.assert_allclose(h, h[:, :1] * np.ones_like(h), rtol=1e-9)
    assert h[0, 0] == pytest.approx(float(s.energy(traj[0, 0])))
    assert M.energy_violation(M.energies(s, traj), h) == pytest.approx(1e-7)  # the clamp
    # An angle shifted by 2 pi has the same true energy.
    shifted = traj.copy()
    shifted[..., 0] += 2 * np.pi
    np.testing.assert_allclose(M.energies(s, shifted), h, rtol=1e-9)
    floor = M.perturbed_floor(s, traj, ts, key=0, scale=1e-4)
    assert 1e-7 <= floor < 1e-3


def test_aggregate_stats():
    import pandas as pd

    df = pd.DataFrame({"model": ["a"] * 4 + ["b"], "err": [1.0, 2.0, 3.0, 4.0, 5.0]})
    out = aggregate(df, ["model"], "err").set_index("model")
    assert out.loc["a", "n"] == 4
    assert out.loc["a", "mean"] == pytest.approx(2.5)
    assert out.loc["a", "sem"] == pytest.approx(np.std([1, 2, 3, 4], ddof=1) / 2)
    assert out.loc["a", "gmean"] == pytest.approx(24 ** (1 / 4))
    assert out.loc["a", "ci_low"] <= 2.5 <= out.loc["a", "ci_high"]
    assert np.isnan(out.loc["b", "ci_low"]) and np.isnan(out.loc["b", "sem"])
