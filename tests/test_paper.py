"""The paper's experiment declarations: they expand in every profile, the figures that share
cells share config hashes, and the budgets stay within what each profile promises."""

import pytest

from bench import _experiments as E
from bench import _paper as P

NAMES = [e.name for e in P.PAPER_EXPERIMENTS]


@pytest.mark.parametrize("profile", list(E.PROFILES))
@pytest.mark.parametrize("name", NAMES)
def test_every_experiment_expands_and_validates(name, profile):
    runs = E.expand(name, profile)
    assert runs, (name, profile)
    for c in runs:
        c.validate()
    assert len({c.config_hash for c in runs}) == len(runs)
    seeds = {c.seed for c in runs}
    assert len(seeds) == len(E.profile_defaults(profile)[1])


def test_experiments_are_registered_with_their_claims():
    assert set(NAMES) <= set(E.available())
    claims = {E.get(n).claim for n in NAMES} - {None}
    assert claims == set(range(1, 9))


@pytest.mark.parametrize("profile", list(E.PROFILES))
def test_figures_2_4_5_and_8_share_runs(profile):
    h = {n: {c.config_hash for c in E.expand(n, profile)} for n in NAMES}
    assert h["second_order"] <= h["energy"]
    assert h["coordinates"] <= h["second_order"]
    l2 = {c.config_hash for c in E.expand("loss", profile) if c.loss == "l2"}
    assert l2 and l2 <= h["second_order"]


def test_damped_has_plain_and_dissipative_hnn():
    runs = E.expand("damped", "quick")
    hnn = {(c.system, c.dissipation) for c in runs if c.model == "hnn_so"}
    assert hnn == {(s, d) for s in P.SYSTEMS for d in (False, True)}
    assert all(c.dissipation is None for c in runs if c.model != "hnn_so")
    assert all(c.friction == 0.4 for c in runs)


def test_relativistic_variants():
    cells = {(c.model, c.coordinates) for c in E.expand("relativistic", "quick")}
    assert cells == {("hnn", "velocity"), ("hnn", "momentum"), ("lnn", "velocity")}


def test_smoke_is_small_and_quick_fits_the_budget():
    smoke = P.estimate_seconds("smoke")
    assert smoke["runs"] <= 40
    quick = P.estimate_seconds("quick")
    assert len(E.profile_defaults("quick")[1]) >= 3
    # `make bench` promises at most 30 minutes on 2 cores.
    assert quick["seconds"] <= 30 * 60, quick
