"""The HNN seed's real pendulum (claim 15): the file format, the seed's finite differences and
split, the loader of a user-supplied file (its sha256, the message when it is absent), the
synthetic stand-in, a measured run end to end, and the verdict rule on synthetic tables (the
stand-in alone never gives a signed verdict)."""

from __future__ import annotations

import hashlib
import math
import re
import zipfile

import numpy as np
import pytest
from _markdown import table_rows

from bench.core import RunConfig, _schema, _store, execute_run, expand
from bench.studies.hnn_seed import real_pendulum as P
from systems import _real_pendulum as R

SEEDS = (0, 1, 2, 3, 4)
SPREAD = np.array([-0.4, 0.4, 0.0, -0.2, 0.2])
TEXT = "% o v\n" + "".join(f"1 {0.1 * i:.1f} {np.sin(0.1 * i):.6f} {i:.1f}\n" for i in range(20))


def test_parse_differences_and_the_seeds_split():
    rows = R.parse(TEXT)
    assert rows.shape == (20, 4)
    d = R.from_rows(rows, "x", "0", synthetic=False)
    assert d.x.shape == d.dx.shape == (19, 2)  # the last row has no forward difference
    np.testing.assert_allclose(d.dx[:, 1], 10.0)  # v = i at t = 0.1 i
    np.testing.assert_allclose(d.dx[3, 0], (np.sin(0.4) - np.sin(0.3)) / 0.1, rtol=1e-5)
    # 19 states: the test set is [15, 18), the first 15 and the rounding leftover train
    np.testing.assert_array_equal(d.test, [15, 16, 17])
    np.testing.assert_array_equal(d.train, [*range(15), 18])


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("h\n1 0.0 0.1\n", "line 2: expected 4 numbers"),
        ("h\n" + "1 0.0 a 1\n", "line 2: expected 4 numbers"),
        ("h\n" + "1 0.0 0 0\n" * 12, "strictly increasing"),
        ("h\n1 0.0 0 0\n", ">= 10 rows"),
    ],
)
def test_bad_files_raise_one_line(text, match):
    with pytest.raises(ValueError, match=match):
        R.parse(text)


def test_absent_file_says_where_to_put_it(monkeypatch, tmp_path):
    monkeypatch.setenv(R.ENV, str(tmp_path / "nowhere.txt"))
    with pytest.raises(ValueError, match=r"real pendulum data absent: put .*real_pend_h_1.txt"):
        R.load(R.REAL)
    assert [c.system for c in expand(P.EXPERIMENT, "smoke")] == [R.SYNTHETIC] * 3


@pytest.mark.parametrize("zipped", [False, True])
def test_a_user_file_is_read_and_its_sha256_recorded(monkeypatch, tmp_path, zipped):
    path = tmp_path / "real_pend_h_1.txt"
    path.write_text(TEXT)
    if zipped:
        with zipfile.ZipFile(tmp_path / "invar_datasets.zip", "w") as z:
            z.write(path, "real_pend_h_1.txt")
        path = tmp_path / "invar_datasets.zip"
    monkeypatch.setenv(R.ENV, str(path))
    d = R.load(R.REAL)
    assert not d.synthetic and d.sha256 == hashlib.sha256(TEXT.encode()).hexdigest()
    assert d.source == f"measured: {path.name}"
    assert {c.system for c in expand(P.EXPERIMENT, "smoke")} == {R.REAL, R.SYNTHETIC}


def test_the_stand_in_agrees_with_an_independent_solve(monkeypatch):
    integrate = pytest.importorskip("scipy.integrate")
    monkeypatch.setitem(R.STANDIN, "noise", 0.0)
    rows = R.parse(R.standin_text())
    f = R.STANDIN["friction"]
    sol = integrate.solve_ivp(
        lambda t, y: [y[1], -R.SEED_K / 2 * np.sin(y[0]) - f * y[1]],
        (0.0, rows[-1, 1]),
        [R.STANDIN["theta0"], 0.0],
        t_eval=rows[:, 1],
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
    )
    np.testing.assert_allclose(rows[:, 2:4], sol.y.T, atol=1e-6)  # the file's 6 decimals


def test_the_stand_in_is_a_labelled_damped_pendulum():
    text = R.standin_text()
    assert text.startswith("% SYNTHETIC stand-in") and text == R.standin_text()
    d = R.load(R.SYNTHETIC)
    assert d.synthetic and "synthetic" in d.source and d.n_trials == 1
    # the seed's H decays by the friction alone: dH/dt = -2 f v^2 (readings' noise aside)
    h = np.asarray(R.seed_energy(d.x))
    dt = R.STANDIN["dt"]
    loss = np.cumsum(2 * R.STANDIN["friction"] * d.x[:, 1] ** 2) * dt
    np.testing.assert_allclose(h - h[0], -(loss - loss[0]), atol=0.02)
    assert h[-1] < 0.5 * h[0]


def test_measured_runs_check_their_fields():
    base = expand(P.EXPERIMENT, "smoke")[0].to_dict()
    with pytest.raises(ValueError, match="measured dataset.*allowed: real_pend_h_1"):
        RunConfig(**{**base, "system": "pendulum"})
    with pytest.raises(ValueError, match="measured runs support no noise"):
        RunConfig(**{**base, "noise": 0.1})


@pytest.mark.slow
def test_a_measured_run_end_to_end_records_its_data(tmp_path):
    # the stand-in's run (the measured file's runs are declared too where the file is there)
    c = next(
        c for c in expand(P.EXPERIMENT, "smoke") if c.model == "hnn" and c.system == R.SYNTHETIC
    )
    row = execute_run(c, cache_root=tmp_path)
    assert row["status"] == "ok", row["error"]
    assert row["data_source"] == R.load(R.SYNTHETIC).source
    assert row["data_sha256"] == R.load(R.SYNTHETIC).sha256 and row["data_points"] == 1000
    for k in ("energy_mse", "derivative_mse_test", "derivative_mse_train", "rollout_error"):
        assert math.isfinite(row[k]) and row[k] > 0, k
    stored = _store.rows_frame([_store.jsonable({**row, "experiment": "x", "profile": "smoke"})])
    assert all(_schema.documented("runs", col) for col in stored.columns)


# ------------------------------------------------------------------------------ claim 15
def _tables(
    energy_ratio,
    spread=0.0,
    data=(R.REAL,),
    hnn_loss=1e-3,
    frames=False,
    frozen_energy=3e-3,
    rollout=(0.1, 0.01, 0.5),
):
    """Rows of claim 15 on seeds 0-4 (with ``frames``: (runs, curves)): the MLP's energy MSE
    ``energy_ratio`` x the HNN's (1e-2), per seed times exp(spread * SPREAD), the trivial
    field's ``frozen_energy``; test losses MLP 1e-3, HNN ``hnn_loss``, the trivial field 0.3;
    rollout errors MLP, HNN, trivial field ``rollout``."""
    rows = []
    for name in data:
        for model in P.MODELS:
            for s in SEEDS:
                c0 = expand(P.EXPERIMENT, "smoke")[0]
                c = RunConfig(**{**c0.to_dict(), "system": name, "model": model, "seed": s})
                jitter = math.exp(spread * SPREAD[s])
                energy, loss = {
                    "node": (1e-2 * energy_ratio * jitter, 1e-3),
                    "hnn": (1e-2, hnn_loss),
                    "at_rest": (frozen_energy, 0.3),
                }[model]
                row = c.to_dict()
                row.update(
                    config_hash=c.config_hash,
                    train_hash=c.train_hash,
                    experiment=P.EXPERIMENT.name,
                    profile="smoke",
                    status="ok",
                    energy_mse=energy,
                    derivative_mse_test=loss,
                    derivative_mse_train=loss,
                    rollout_error=dict(zip(P.MODELS, rollout, strict=True))[
                        model
                    ],
                    data_source="synthetic stand-in" if name == R.SYNTHETIC else "measured: f",
                    data_sha256="ab" * 32,
                    curves={"t": [0.0, 0.1], "rel_error": [0, 0.1], "energy_violation": [0, 0.1],
                            "z_true": [[0.1, 0.0], [0.1, 0.1]],
                            "z_pred": [[0.1, 0.0], [0.1, 0.2]]},
                )  # fmt: skip
                rows.append(_store.jsonable(row))
    return (
        (_store.rows_frame(rows), _store.curves_frame(rows)) if frames else _store.rows_frame(rows)
    )


def test_the_stand_in_alone_gives_no_signed_verdict():
    stand = _tables(energy_ratio=1000.0, spread=0.1, data=(R.SYNTHETIC,))
    v = P.claim_15(stand)
    assert v.verdict == "inconclusive" and v.variant == P.NOT_RUN, v.detail
    assert [p.status for p in v.parts] == ["undecided"]
    check, n = P._part(stand)  # the pipeline check: the part on the stand-in, in the detail
    assert (check.status, n) == ("holds", 5) and check.text() in v.detail


def test_real_data_far_below_is_reproduced_and_equal_is_not():
    v = P.claim_15(_tables(energy_ratio=1000.0, spread=0.1, data=(R.REAL, R.SYNTHETIC)))
    assert v.verdict == "reproduced" and not v.variant, v.detail
    assert v.effect == pytest.approx(math.log(1000.0), rel=1e-6)
    assert P.claim_15(_tables(energy_ratio=1.0, spread=0.1)).verdict == "not reproduced"


def test_real_data_not_discriminating_when_no_model_beats_the_frozen_state():
    v = P.claim_15(_tables(energy_ratio=1000.0, spread=0.1, rollout=(0.5, 0.4, 0.5)))
    assert v.verdict == "inconclusive" and v.discriminating is False, v.detail
    v = P.claim_15(_tables(energy_ratio=1000.0, spread=0.1))
    assert v.verdict == "reproduced" and v.discriminating is True, v.detail


def test_a_frozen_state_as_conserving_as_the_hnn_is_said():
    """The seed's energy MSE on data that loses energy: a frozen state within the energy
    margin of the HNN's score is named beside the verdict (which it does not change); one far
    above it is not."""
    rows = _tables(energy_ratio=1000.0, spread=0.1, frozen_energy=1.2e-2)
    tied, note = P.claim_15(rows), P._frozen_note(rows)
    assert tied.verdict == "reproduced" and note and note in tied.detail, tied.detail
    errors = dict(
        x.split(" ") for x in re.search(r"rollout error (.+)\)$", note).group(1).split(", ")
    )
    assert errors == {"MLP": "0.1", "HNN": "0.01", "frozen": "0.5"}, note
    rows = _tables(energy_ratio=1000.0, spread=0.1, frozen_energy=1.0)
    far = P.claim_15(rows)
    assert far.verdict == "reproduced" and P._frozen_note(rows) == "", far.detail


def test_real_data_undecided_at_the_margin_or_unlearned():
    from bench.kit import policy

    margin = policy.margin("energy", squared=True).value
    v = P.claim_15(_tables(energy_ratio=margin, spread=1.0))
    assert v.verdict == "inconclusive" and v.parts[0].status == "undecided", v.detail
    # the HNN's test loss within the trivial field's factor 4 (the gate squared): not tested
    v = P.claim_15(_tables(energy_ratio=1000.0, spread=0.1, hnn_loss=0.2))
    assert v.parts[0].status == "not tested", v.detail


def test_section_and_figure_say_which_data(tmp_path):
    r, curves = _tables(energy_ratio=100.0, data=(R.SYNTHETIC,), frames=True)
    r.to_parquet(tmp_path / "runs.parquet", index=False)
    curves.to_parquet(tmp_path / "curves.parquet", index=False)
    table = {row["data"]: row for row in table_rows(P.section(tmp_path), "| data | sha256")}
    assert list(table) == ["the seed's", "synthetic stand-in"]  # one line per data source
    mlp, hnn = P.SEED_NUMBERS["energy_mse"]
    assert table["the seed's"]["energy MSE MLP / HNN"] == f"{mlp:.3g} / {hnn:.3g}"
    assert table["synthetic stand-in"]["energy MSE MLP / HNN"] == "1 / 0.01"  # 100x, built
    paths = P.figure(tmp_path)
    assert {p.suffix for p in paths} == {".png", ".pdf"}
