"""The paper-core selection and its campaign: the selection's runs are paper runs
(same hashes), every claim has cells, the order settles the unsettled claims first, and the
plan counts what is stored."""

import re
from pathlib import Path

import pytest

from bench import studies as ST
from bench.core import _experiments as E
from bench.core import _store
from bench.studies import paper as P
from bench.studies._claims import SYMREG_WEIGHTS_CORE
from bench.studies.lnn_seed import relativistic as REL
from bench.studies.paper.campaign import _campaign as C
from bench.studies.paper.campaign._budget import run_seconds

NAMES = [e.name for e in P.PAPER_EXPERIMENTS]


def test_selection_has_its_base_profiles_defaults():
    assert E.profile_defaults("paper-core") == E.profile_defaults("paper")


@pytest.mark.parametrize("name", NAMES)
def test_paper_core_runs_are_paper_runs_at_k2_with_5_seeds(name):
    core = E.expand(name, "paper-core")
    paper = {c.config_hash for c in E.expand(name, "paper")}
    assert {c.config_hash for c in core} <= paper  # a subset, hash for hash
    assert all(c.k in (None, 1, 2) for c in core)  # k = 2 (vin: the k = 1 pendulum)
    if core:
        assert {c.seed for c in core} == {0, 1, 2, 3, 4}


def test_paper_core_covers_every_claim_with_its_further_readings_apart():
    claims = {E.get(n).claim for n in C.campaign_experiments("paper-core")}
    assert claims >= set(range(1, 9))

    def split(name):
        e = E.get(name)
        cells = E.expand(e, "paper-core")
        return [c for c in cells if not E.is_supplementary(e, c)], [
            c for c in cells if E.is_supplementary(e, c)
        ]

    # claim 2: the verdict's chain NODE+SO; the spring and the plain regularised NODE further
    sym, more = split("symplectic")
    assert {c.system for c in sym} == {"chain_pendulum"}
    assert {c.model for c in sym} == {"node_so_symreg", "constant_velocity"}
    assert {(c.system, c.model) for c in more} == {
        ("chain_pendulum", "node_symreg"),
        ("spring_pendulum", "node_symreg"),
        ("spring_pendulum", "node_so_symreg"),
        ("spring_pendulum", "constant_velocity"),
    }
    for cells in (sym, more):
        weights = {dict(c.model_options).get("weight") for c in cells} - {None}
        assert sorted(weights) == sorted(SYMREG_WEIGHTS_CORE)
    # claim 5: the Rayleigh HNN further; the plain NODE is the paper profile's alone
    damped, rayleigh = split("damped")
    assert not any(c.dissipation is True or c.model == "node" for c in damped)
    assert {(c.model, c.dissipation) for c in rayleigh} == {("hnn_so", True)}
    # claims 3 and 4: the paper's form of the models further
    _, forms = split("second_order")
    assert {c.model for c in forms} == {"node", "hnn", "hnn_so", "node_so_pq"}
    assert {c.model for c in split("coordinates")[1]} == {"node_so_pq", "hnn_so"}
    rel = {
        (c.model, c.coordinates, c.model_options) for c in E.expand("relativistic", "paper-core")
    }
    assert rel == set(REL.RELATIVISTIC_CELLS)
    # claim 7's second reading, the LNN seed's protocol, every cell
    assert "relativistic_seed" in C.campaign_experiments("paper-core")
    seed = {
        (c.model, c.coordinates, c.model_options)
        for c in E.expand("relativistic_seed", "paper-core")
    }
    assert seed == set(REL.SEED_CELLS)
    coords = E.expand("coordinates", "paper-core")
    assert {c.system_params for c in coords if c.system == "spring_pendulum"} == {
        ST.SPRING_PAPER,
        ST.SPRING_EQUILIBRIUM,
    }


def test_experiments_outside_a_selection_have_no_runs():
    for name in E.available():
        if "paper-core" not in E.get(name).profile_overrides:
            assert E.expand(name, "paper-core") == []


def test_campaign_order_settles_claims_6_4_1_3_first():
    names = C.campaign_experiments("paper-core")
    claims = [E.get(n).claim for n in names]
    assert claims[:4] == [6, 4, 1, 3]
    assert claims == sorted(claims, key=C.CAMPAIGN_CLAIMS.index)
    runs = C.campaign_runs("paper-core")
    assert len({c.config_hash for _, c in runs}) == len(runs)
    # the runner starts the largest keys first: sorting by the key gives the claim order
    key = C.priority("paper-core")
    ordered = sorted((c for _, c in runs), key=key, reverse=True)
    first = {c.config_hash for c in E.expand("loss", "paper-core")}
    assert all(c.config_hash in first for c in ordered[: len(first)])
    assert ordered[0].model == "hnn_so"  # longest first within the claim


def test_a_claims_further_readings_follow_its_own_cells_cheapest_first():
    """Within claim 16: its own cells (longest first), then its further readings shortest
    first, so the paper's update-rule cells (NODEs at 5e-3, one-step HNN) are not held behind
    the HNNs at 5e-3 (the costliest runs of the campaign)."""
    runs = [c for n, c in C.campaign_runs("paper-core") if n == "mujoco"]
    key = C.priority("paper-core")
    ordered = sorted(runs, key=key, reverse=True)
    assert [c.config_hash for c in ordered] == [c.config_hash for c in runs]
    further = [E.is_supplementary(E.get("mujoco"), c) for c in ordered]
    first = further.index(True)
    assert first > 0 and all(further[first:])  # own cells, then further readings
    own = [run_seconds(c) for c in ordered[:first]]
    more = [run_seconds(c) for c in ordered[first:]]
    assert own == sorted(own, reverse=True) and more == sorted(more)
    rule = [i for i, c in enumerate(ordered) if c.optimizer == "adam_l2_clip"]
    ours = [i for i, c in enumerate(ordered) if c.model == "hnn_force" and c.lr == 5e-3]
    assert rule and ours and max(rule) < min(ours)


def test_plan_counts_stored_runs_and_their_hours(tmp_path):
    runs = C.campaign_runs("paper-core")
    empty = C.plan("paper-core", tmp_path, workers=2)
    total = empty[empty["claim"] == "total"].iloc[0]
    assert total["runs"] == len(runs) and total["stored"] == 0
    assert total["wall_hours_left"] == pytest.approx(total["cpu_hours_left"] / 2)
    # store the first claim's hnn_so runs as if they had taken twice the estimate
    from bench.studies.paper.campaign._budget import total_seconds

    done = [c for n, c in runs if n == "loss" and c.model == "hnn_so"]
    for c in done:
        _store.write_row(
            tmp_path,
            {
                **c.to_dict(),
                "config_hash": c.config_hash,
                "status": "ok",
                "wall_seconds": 2 * run_seconds(c),
                "train_seconds": run_seconds(c),
                "rollout_seconds": 3.0,
                "checkpoint_seconds": float("nan"),  # absent parts count 0
                **({"cpu_seconds": 100.0} if c.seed < 2 else {}),  # older rows lack it
            },
        )
    df = C.plan("paper-core", tmp_path, workers=2).set_index("claim")
    assert df.loc[6, "stored"] == len(done)
    assert df.loc[1, "stored"] == len([c for c in done if c.loss == "l2"])  # shared cells
    hnn_left = [
        c
        for n, c in runs
        if c.model == "hnn_so" and c.config_hash not in {d.config_hash for d in done}
    ]
    assert df.loc["total", "cpu_hours_done"] == pytest.approx(
        sum(2 * run_seconds(c) for c in done) / 3600
    )
    assert df.loc["total", "train_eval_hours"] == pytest.approx(
        sum(run_seconds(c) + 3.0 for c in done) / 3600
    )
    assert df.loc[6, "train_eval_hours"] == df.loc["total", "train_eval_hours"]
    with_cpu = [c for c in done if c.seed < 2]
    assert df.loc["total", "measured_cpu_runs"] == len(with_cpu) > 0
    assert df.loc["total", "measured_cpu_hours"] == pytest.approx(100.0 * len(with_cpu) / 3600)
    left = [c for _, c in runs if c.config_hash not in {d.config_hash for d in done}]
    # the estimate, not rescaled by the stored runs (a niced run's seconds include waiting)
    assert df.loc["total", "cpu_hours_left"] == pytest.approx(total_seconds(left) / 3600)
    assert hnn_left
    # calibrated: claim 6 by its own measured runs (100 s each against their estimate); the
    # claims without one by the campaign's ratio, here the same runs'
    ratio = 100.0 * len(with_cpu) / sum(run_seconds(c) for c in with_cpu)
    assert df.loc[6, "calibration"] == pytest.approx(ratio)
    assert df.loc[5, "calibration"] == pytest.approx(ratio)
    assert df.loc["total", "cpu_hours_left_calibrated"] == pytest.approx(
        df.loc["total", "cpu_hours_left"] * ratio
    )
    assert df.loc["total", "wall_hours_left_calibrated"] == pytest.approx(
        df.loc["total", "cpu_hours_left"] * ratio / 2
    )
    assert C.plan("paper-core", tmp_path / "none", workers=2)["calibration"].eq(1.0).all()
    table = df.reset_index()
    lines = C.format_plan(table, "paper-core", 2).splitlines()
    # a title, a header, then one line per claim and the total, as the plan has them
    rows = lines[2 : 2 + len(table)]
    assert [r.split()[0] for r in rows] == [str(c) for c in table["claim"]]
    assert [r.split()[1] for r in rows] == [str(int(n)) for n in table["runs"]]


def test_runs_stored_from_an_accelerator_are_done_but_do_not_calibrate(tmp_path):
    # a GPU's seconds say nothing of a CPU's: the run counts as stored, not as measured
    runs = C.campaign_runs("paper-core")
    done = [c for n, c in runs if n == "loss" and c.model == "hnn_so"][:4]
    for i, c in enumerate(done):
        _store.write_row(
            tmp_path,
            {
                **c.to_dict(),
                "config_hash": c.config_hash,
                "status": "ok",
                "wall_seconds": 50.0,
                "train_seconds": 40.0,
                "cpu_seconds": 45.0,
                "backend": "gpu" if i else "cpu",
            },
        )
    df = C.plan("paper-core", tmp_path, workers=2).set_index("claim")
    assert df.loc[6, "stored"] == 4
    assert df.loc[6, "measured_cpu_runs"] == 1
    assert df.loc[6, "measured_cpu_hours"] == pytest.approx(45.0 / 3600)
    assert df.loc[6, "cpu_hours_done"] == pytest.approx(50.0 / 3600)


def test_the_lnn_seeds_hours_come_from_its_measured_costs(tmp_path, monkeypatch):
    """Claim 9 at paper-core: per seed, one dataset of 150,000 ten-second trajectories (shared
    by its three runs) and 30,000 steps of the LNN and of NODE+SO at the paper's size, each at
    the cost lnn_seed.MEASURED records (the rollout-trained scaling said 0.5 h, not 2.6)."""
    from bench.studies.lnn_seed import notebook as lnn_seed
    from bench.studies.paper.campaign._budget import data_seconds, total_seconds

    m = lnn_seed.MEASURED
    cfgs = E.expand("lnn_seed_double_pendulum", "paper-core")
    assert len({c.seed for c in cfgs}) == 5 and len({c.dataset_config() for c in cfgs}) == 5
    lnn = next(c for c in cfgs if c.model == "lnn")
    assert data_seconds(lnn) == pytest.approx(150_000 * m["ms_per_trajectory_data"] / 1000)
    assert run_seconds(lnn) == pytest.approx(
        30_000 * m["ms_per_step_lnn_paper"] / 1000, abs=m["s_lnn_test_rollouts_paper"] + 5
    )
    # each seed's dataset once, not once per run
    assert total_seconds(cfgs) == pytest.approx(
        sum(run_seconds(c) for c in cfgs) + 5 * data_seconds(lnn)
    )
    plan = C.plan("paper-core", tmp_path, workers=2).set_index("claim")
    # claim 9 reads both protocols: the text's (these runs) and the notebook's
    both = cfgs + E.expand("lnn_seed_notebook", "paper-core")
    assert plan.loc[9, "cpu_hours"] == pytest.approx(total_seconds(both) / 3600)
    assert 2.0 < total_seconds(cfgs) / 3600 < 3.5
    # a stored run of seed 0 means its dataset was made, but only a dataset in this machine's
    # cache is paid: the hours left drop its run, and its data once the file is here
    cache = tmp_path / "cache"
    monkeypatch.setenv("DECON_CACHE", str(cache))
    _store.write_row(tmp_path, {**lnn.to_dict(), "config_hash": lnn.config_hash, "status": "ok"})
    left = C.plan("paper-core", tmp_path, workers=2).set_index("claim").loc[9, "cpu_hours_left"]
    assert left == pytest.approx((total_seconds(both) - run_seconds(lnn)) / 3600)
    made = cache / "datasets" / f"{lnn.dataset_config().hash()}.npz"
    made.parent.mkdir(parents=True)
    made.write_bytes(b"")
    left = C.plan("paper-core", tmp_path, workers=2).set_index("claim").loc[9, "cpu_hours_left"]
    assert left == pytest.approx(
        (total_seconds(both) - run_seconds(lnn) - data_seconds(lnn)) / 3600
    )
    # calibration: the run that generated its dataset is set against its estimate plus the
    # dataset's (its set-up, wall less training, shows it); one that found it made, its own
    lnn1 = next(c for c in cfgs if c.model == "lnn" and c.seed == 1)
    lnn1_node = next(c for c in cfgs if c.model == "node_so" and c.seed == 1)
    d = data_seconds(lnn1)
    for c, setup in ((lnn1, d), (lnn1_node, 2.0)):  # lnn made seed 1's data, node_so found it
        r = run_seconds(c)
        row = {**c.to_dict(), "config_hash": c.config_hash, "status": "ok"}
        _store.write_row(
            tmp_path,
            {**row, "wall_seconds": setup + r, "train_seconds": r, "cpu_seconds": setup + r},
        )
    cal = C.plan("paper-core", tmp_path, workers=2).set_index("claim").loc[9, "calibration"]
    assert cal == pytest.approx(1.0, rel=0.01)  # without the dataset: 3.4x


def test_symplectic_runs_are_costed_as_measured_with_and_without_the_penalty():
    """Claim 2's paper-core runs: 112 ms a step with the penalty, 34 ms at weight 0 (which
    skips it), measured on the campaign's rows; the quick-to-paper scaling said 550 s for each."""
    cfgs = E.expand("symplectic", "paper-core")
    by_w = {}
    for c in cfgs:
        if c.model == "node_so_symreg" and c.system == "chain_pendulum":
            by_w.setdefault(float(dict(c.model_options)["weight"]), []).append(run_seconds(c))
    assert sorted(by_w) == sorted(SYMREG_WEIGHTS_CORE) and 0.0 in by_w
    assert by_w[0.0] == pytest.approx([8000 * 0.034 + 12.0] * 5)
    for w, secs in by_w.items():
        if w > 0:
            assert secs == pytest.approx([8000 * 0.112 + 12.0] * 5), w


def test_the_replication_phase_runs_the_same_cells_on_seeds_5_to_9(tmp_path):
    """The campaign's second phase: the selection's cells on its replication seeds, in the same
    claim order, counted apart from the first phase, with the first phase's calibration where
    it has measured none of its own."""
    seeds = E.replication_seeds("paper-core")
    assert seeds == (5, 6, 7, 8, 9) == E.replication_seeds("paper")
    assert E.replication_seeds("smoke") == () and E.replication_seeds(None) == ()
    own, rep = C.campaign_runs("paper-core"), C.campaign_runs("paper-core", seeds)
    assert len(rep) == len(own) and {c.seed for _, c in rep} == set(seeds)
    assert not {c.config_hash for _, c in own} & {c.config_hash for _, c in rep}
    strip = [(n, c.to_dict() | {"seed": 0}) for n, c in rep]
    assert sorted(map(str, strip)) == sorted(str((n, c.to_dict() | {"seed": 0})) for n, c in own)
    key = C.priority("paper-core", seeds)
    ordered = sorted((c for _, c in rep), key=key, reverse=True)
    first = {c.config_hash for c in E.expand("loss", "paper-core", seeds=seeds)}
    assert all(c.config_hash in first for c in ordered[: len(first)])
    # a stored run of the first phase counts there only; its calibration carries over
    (_, c), *_ = own
    _store.write_row(
        tmp_path,
        {**c.to_dict(), "config_hash": c.config_hash, "status": "ok", "cpu_seconds": 1.0},
    )
    prior = C.plan("paper-core", tmp_path, workers=2)
    df = C.plan("paper-core", tmp_path, workers=2, seeds=seeds, prior=prior)
    assert prior.iloc[-1]["stored"] == 1 and df.iloc[-1]["stored"] == 0
    assert list(df["calibration"]) == pytest.approx(list(prior["calibration"]))
    assert prior.iloc[-1]["calibration"] != 1.0
    title = C.format_plan(df, "paper-core", 2, seeds).splitlines()[0]
    assert title.startswith("paper-core, ") and all(str(s) in title for s in seeds)


def test_replication_takes_the_signed_verdicts_first(tmp_path, monkeypatch):
    """Claims whose seeds 0-4 verdict is signed are replicated first; inconclusive and pending
    ones (which no replication can change) after them, each group cheapest first."""
    from bench import kit
    from bench.core import _query

    def v(claim, verdict, pending=None):
        return kit.Verdict(claim, "t", verdict, 0.0, 0.0, 0.0, 5, "d", pending=pending)

    primary = [
        v(6, "inconclusive"),
        v(4, "partly reproduced"),
        v(2, "not reproduced"),
        v(5, "pending (19 of 50 runs)", pending=(19, 50)),
        v(10, "inconclusive (changes without a seed)"),
        v(7, "reproduced"),
    ]
    judged = kit.Judgement(final=primary, primary={x.key: x for x in primary})
    monkeypatch.setattr(kit, "judge", lambda *a, **k: judged)
    counts = {4: (45, 45), 2: (30, 30), 7: (40, 40)}
    monkeypatch.setattr(kit, "stored_counts", lambda *a, **k: counts)
    monkeypatch.setattr(_query, "load_tables", lambda d: (None, None, None))
    seeds = E.replication_seeds("paper-core")

    def cheapest(claims):
        return C.cheapest_first(claims, tmp_path, seeds=seeds)

    # an empty folder: nothing signed, every claim cheapest first
    assert C.replication_order(tmp_path) == cheapest(C.CAMPAIGN_CLAIMS)
    (tmp_path / "runs.parquet").write_bytes(b"")  # a folder with runs (holds_runs)
    order = C.replication_order(tmp_path)
    signed = tuple(c for c in C.CAMPAIGN_CLAIMS if c in (4, 2, 7))
    rest = tuple(c for c in C.CAMPAIGN_CLAIMS if c not in signed)
    assert order == cheapest(signed) + cheapest(rest)
    assert set(order[:3]) == {4, 2, 7} and sorted(order) == sorted(C.CAMPAIGN_CLAIMS)
    names = C.campaign_experiments("paper-core", order)
    assert {E.get(n).claim for n in names[:4]} <= {4, 2, 7}
    # a shared run goes with the first claim that reads it: claim 4 brings the L2 cells
    rep = C.campaign_runs("paper-core", seeds, order)
    coords = {c.config_hash for c in E.expand("coordinates", "paper-core", seeds=seeds)}
    assert {c.config_hash for n, c in rep if n == "coordinates"} == coords
    # the first claim's runs start first
    first = {c.config_hash for n, c in rep if E.get(n).claim == order[0]}
    key = C.priority("paper-core", seeds, order)
    ordered = sorted((c for _, c in rep), key=key, reverse=True)
    assert first and all(c.config_hash in first for c in ordered[: len(first)])
    # make paper-core's first phase: the replication runs of the signed claims alone
    signed = C.signed_claims(tmp_path)
    assert signed == {4, 2, 7}
    only = C.campaign_runs("paper-core", seeds, order, signed)
    assert {E.get(n).claim for n, _ in only} == {4, 2, 7}
    assert {c.config_hash for _, c in only} < {c.config_hash for _, c in rep}
    phase = C.plan("paper-core", tmp_path, seeds=seeds, order=order, claims=signed)
    assert set(phase["claim"][:-1]) == {4, 2, 7} and phase.iloc[-1]["runs"] == len(only)
    # a claim with runs still to store is not signed, whatever one of its readings says
    # (claim 7's second protocol, pending on its own seeds)
    counts[7] = (21, 40)
    assert C.signed_claims(tmp_path) == {4, 2}


def test_plan_reads_a_stored_run_of_every_claim(tmp_path):
    """One stored run of each campaign experiment (a pixel task's included, whose data are its
    own and whose config describes no trajectory dataset): the plan counts each, and fails on
    none (the status once stopped at the first stored pixel run)."""

    runs = C.campaign_runs("paper-core")
    first = {}
    for name, c in runs:
        first.setdefault(name, c)
    assert {"pixel_pendulum_hnn", "pixel_pendulum_vin"} <= set(first)
    for c in first.values():
        _store.write_row(tmp_path, {**c.to_dict(), "config_hash": c.config_hash, "status": "ok"})
    plan = C.plan("paper-core", tmp_path, workers=2)
    total = plan.set_index("claim").loc["total"]
    assert total["stored"] >= len(first)


def test_the_cheapest_claims_run_first(tmp_path):
    """A claim with fewer hours left starts before a longer one, whatever the campaign order
    says (ties keep that order); a claim whose runs are all stored keeps its place."""
    first = C.cheapest_first(C.CAMPAIGN_CLAIMS, tmp_path)
    hours = C.plan("paper-core", tmp_path).set_index("claim")["cpu_hours_left"]
    assert sorted(first) == sorted(C.CAMPAIGN_CLAIMS)
    assert [hours[c] for c in first] == sorted(hours[c] for c in C.CAMPAIGN_CLAIMS)
    assert hours[first[0]] < hours[first[-1]]
    assert C.cheapest_first((), tmp_path) == ()


def test_status_names_the_trainings_saved_mid_way(tmp_path):
    """A run whose training was interrupted with its state saved is listed with its step, and
    as restarting where other code saved it; stored runs and unsaved ones are not listed."""
    import json

    from bench.core import DATA_TAG, RESUME, code_fingerprint, params_dir

    runs = C.campaign_runs("paper-core")
    (name, first), (_, second) = runs[:2]
    # a controlled run's state names its data file beside the code
    controlled = next(
        c for _, c in runs if c.observation == "controlled" and c.model != "constant_velocity"
    )
    saved = (
        (first, code_fingerprint()),
        (second, "other code"),
        (controlled, f"{code_fingerprint()}{DATA_TAG}abc"),
    )
    for cfg, code in saved:
        folder = params_dir(tmp_path, cfg.train_hash) / RESUME
        folder.mkdir(parents=True)
        record = {"done": 300, "train_seconds": 7200.0, "code": code}
        (folder / "resume.json").write_text(json.dumps(record))
    lines = C.saved_trainings("paper-core", None, cache_root=tmp_path)
    assert len(lines) == 3, lines
    said = [_saved(x) for x in lines]
    steps = f"{first.steps:,}"
    assert said[0] == (str(E.get(name).claim), name, first.model, str(first.seed), "300", steps,
                       "2.00", "resumes")  # fmt: skip
    assert said[1][-1].startswith("restarts")  # saved by other code
    assert said[2][1:4] == ("mujoco", controlled.model, str(controlled.seed))
    assert said[2][-1] == "resumes"  # its data file beside this code
    # a stored run is not listed
    results = tmp_path / "results"
    row = {"config_hash": first.config_hash, "status": "ok", "system": first.system}
    _store.write_row(results, {**row, "model": first.model, "seed": first.seed})
    assert len(C.saved_trainings("paper-core", results, cache_root=tmp_path)) == 2


def _saved(line):
    """A saved training's line read back: (claim, experiment, model, seed, step, steps, hours
    trained, resumes or restarts)."""
    return re.fullmatch(
        r"claim (\d+), (\S+), (\S+) seed (\d+): step (\S+) of (\S+) \((\S+) h trained; (.+)\)",
        line,
    ).groups()


def test_campaign_claims_runs_only_those_claims(tmp_path, monkeypatch, capsys):
    """``campaign --claims 9,12`` runs the two claims' experiments and nothing else; with
    --signed, only those of them that are signed."""
    from bench._cli import main
    from bench.studies.paper.campaign import _commands

    ran = []
    monkeypatch.setattr(
        _commands, "sweep_from_args", lambda args, names, **kw: ran.append(names) or {}
    )
    assert main(["--results", str(tmp_path), "campaign", "--claims", "9, 12"]) == 0
    want = {n for n in C.campaign_experiments("paper-core") if E.get(n).claim in (9, 12)}
    assert set(ran[0]) == want and len(want) == 4
    monkeypatch.setattr(C, "signed_claims", lambda *a: frozenset({12, 5}))
    assert main(["--results", str(tmp_path), "campaign", "--claims", "9,12", "--signed"]) == 0
    assert {E.get(n).claim for n in ran[1]} == {12}
    assert "(signed verdicts: claims 12)" in capsys.readouterr().out


def test_by_reading_runs_a_cheap_reading_on_both_seed_sets_before_a_costly_one(
    tmp_path, monkeypatch, capsys
):
    """``campaign --claims 16 --by-reading``: the claim's own cells on seeds 0-4 then 5-9,
    then its further readings cheapest run first, each cost on both sets: the paper's HNN
    (about 3 CPU min a run) on seeds 5-9 before our HNN at 5e-3 (about 42) on seeds 0-4. A
    replication run waits for its cell's own seeds: here none is stored, so every replication
    step keeps nothing."""
    from bench._cli import main
    from bench.studies.paper.campaign import _commands

    calls = []

    def sweep(args, names, *, order, seeds, where):
        cfgs = [c for n in names for c in E.expand(n, args.profile, seeds=seeds)]
        calls.append((seeds, [c for c in cfgs if where(c)]))
        return {}

    monkeypatch.setattr(_commands, "sweep_from_args", sweep)
    # every cell's own seeds stored: replication steps run what their tier keeps
    monkeypatch.setattr(C, "replicable", lambda *a: lambda c: True)
    argv = ["--results", str(tmp_path), "campaign", "--claims", "16", "--by-reading"]
    assert main(argv) == 0
    sets = [(tuple(s) if s else None) for s, _ in calls]
    assert sets[0] is None and sets[1] == (5, 6, 7, 8, 9) and sets == sets[:2] * (len(sets) // 2)
    own = {c.config_hash for _, cfgs in calls[:2] for c in cfgs}
    assert own and not any(E.get("mujoco").supplementary(c) for _, cf in calls[:2] for c in cf)
    step = {}  # the first step that runs each further run
    for i, (_, cfgs) in enumerate(calls[2:], start=2):
        for c in cfgs:
            step.setdefault(c.config_hash, (i, c))
    paper_hnn = [i for i, c in step.values() if c.model == "hnn_force_paper"]
    ours = [i for i, c in step.values() if c.model == "hnn_force" and c.lr == 0.005]
    assert paper_hnn and ours and max(paper_hnn) < min(ours)
    assert len(step) + len(own) == len(
        {
            c.config_hash
            for s in (None, range(5, 10))
            for c in E.expand("mujoco", "paper-core", seeds=s)
        }
    )
    assert "further readings up to" in capsys.readouterr().out
    # the same with nothing stored: no replication run is kept
    monkeypatch.undo()
    monkeypatch.setattr(_commands, "sweep_from_args", sweep)
    calls.clear()
    assert main(argv) == 0
    assert all(not cfgs for s, cfgs in calls if s)
    assert main([*argv, "--replication"]) == 2
    assert "drop --replication" in capsys.readouterr().err


@pytest.mark.slow
def test_paper_gpu_packs_every_stored_row_into_its_out_folder(tmp_path):
    # the device returns a few files, never a folder of rows: the target packs them as they
    # arrive and at the end, so a call stopped at its limit still returns what it stored
    import subprocess
    import sys
    import tarfile

    root = Path(__file__).resolve().parents[1]
    results, out = tmp_path / "res", tmp_path / "out"
    out.mkdir()
    done = subprocess.run(
        ["make", "-s", "paper-gpu", f"GPU_PY={sys.executable}", "GPU_PROFILE=smoke",
         f"GPU_DIR={results}", "GPU_SEEDS=0", "GPU_EXPERIMENTS=energy", f"GPU_OUT={out}",
         "GPU_SECONDS=300", "GPU_WORKERS=2"],
        cwd=root, capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    rows = sorted(p.name for p in (results / ".rows").glob("*.json"))
    assert rows and f", {len(rows)} in {results}" in done.stdout
    with tarfile.open(out / "rows.tgz") as tar:
        packed = sorted(Path(m.name).name for m in tar.getmembers() if m.name.endswith(".json"))
    assert packed == rows
    assert not (out / "rows.part").exists()


def test_the_rayleigh_hnn_costs_its_measured_factor_over_the_plain_one():
    """Claim 5's Rayleigh HNN (hnn_so, dissipation on) took 1.31x the plain HNN's CPU time on
    the campaign's rows; the estimate without the factor charged it as the plain model."""
    from bench.studies.paper.campaign import _budget as B

    cells = {}
    for c in E.expand("damped", "paper-core"):
        if c.model in ("hnn_so", "node_so") and c.seed == 0:
            cells[(c.model, c.system, c.dissipation)] = run_seconds(c)
    for system in ("chain_pendulum", "spring_pendulum"):
        plain, ray = cells[("hnn_so", system, False)], cells[("hnn_so", system, True)]
        assert ray == pytest.approx(plain * B.DISSIPATION) and B.DISSIPATION > 1.2


def test_the_papers_mujoco_hnn_costs_a_fraction_of_ours():
    """The paper's MuJoCo HNN (M = I, one Euler step per transition) measured 158-202 CPU s a
    paper-core run, ours (a learned M(q), 8 steps) 2,600-4,000: without its own row the
    estimate charged the paper's as ours."""
    cost = {}
    for c in E.expand("mujoco", "paper-core"):
        if c.seed == 0 and c.lr == 0.005 and c.system == "HopperFull-v0":
            cost[(c.model, c.optimizer)] = run_seconds(c)
    paper = cost[("hnn_force_paper", "adamw")]
    assert 150 < paper < 250 and cost[("hnn_force", "adamw")] > 10 * paper
    assert cost[("hnn_force_paper", "adam_l2_clip")] == paper


def test_the_measured_costs_are_read_from_their_data_file():
    from bench.studies.paper.campaign import _budget as B

    assert all(table["about"] for name, table in B.COSTS.items() if name != "about")
    assert B.WALL_S[("node", None)] == (2.9, 3.4)
    assert B.STEP_COST[("pixels", "hnn", 200, 200)] == (15.0, 4.7)
    assert B.DATA_MS_PER_S[("three_body", None)] == 1.8
    assert B.TRADEOFF_S == (274.0 - 106.0 - 78.0) / 2 and B.SWEEP_RATIO == 25.2 / 23.4


def test_a_replication_runs_only_cells_whose_own_seeds_are_stored(tmp_path):
    """A replication run waits for its cell on every one of the profile's own seeds: a cell
    declared since the last campaign runs seeds 0-4 before 5-9."""
    own = E.expand("coordinates", "paper-core")
    cell = [c for c in own if c.model == "node_so" and c.system == "chain_pendulum"]
    assert sorted(c.seed for c in cell) == [0, 1, 2, 3, 4]
    for c in cell[:4]:  # four of its five own seeds
        _store.write_row(tmp_path, {**c.to_dict(), "config_hash": c.config_hash, "status": "ok"})
    rep = E.expand("coordinates", "paper-core", seeds=E.replication_seeds("paper-core"))
    mine = [c for c in rep if c.model == "node_so" and c.system == "chain_pendulum"]
    ready = C.replicable(tmp_path, "paper-core", ["coordinates"])
    assert mine and not any(map(ready, mine))
    last = cell[4]
    _store.write_row(tmp_path, {**last.to_dict(), "config_hash": last.config_hash, "status": "ok"})
    ready = C.replicable(tmp_path, "paper-core", ["coordinates"])
    assert all(map(ready, mine))
    assert not any(ready(c) for c in rep if c.system == "spring_pendulum")  # none stored


def test_sweeps_order_their_runs_by_the_registered_cost_model(monkeypatch):
    """The paper's campaign registers its ``run_seconds`` as the suite's cost model; without
    one a run costs its training work; a cost model must be callable."""
    import bench
    from bench.core import _studies
    from bench.studies.paper.campaign import run_seconds

    c = bench.expand("second_order", "quick", seeds=[0])[0]
    assert _studies.run_cost(c) == run_seconds(c) > 0
    monkeypatch.setattr(_studies, "_COST_MODEL", [])
    assert _studies.run_cost(c) == c.steps * c.batch * c.width
    with pytest.raises(ValueError, match="callable"):
        _studies.register_cost_model(3)
