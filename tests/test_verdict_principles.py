"""Principles the verdict engine applies to every claim, pinned on synthetic parts.

Discrimination per system: a system whose best model does not beat the trivial predictors
voids only its own parts; a claim whose parts pool that system with others stays inconclusive.
"""

import numpy as np
import pytest

from bench import kit as R
from bench.kit import Discrimination, greater, margin, verdict

ERR = margin("error")
CLEAR = np.log([3.0, 3.2, 2.9, 3.1, 3.3])  # a clear 3x edge on five seeds
REVERSED = -CLEAR
TIE = np.log([1.0, 1.02, 0.98, 1.01, 0.99])


def _claim(chain, spring, discs, pooled=False):
    parts = [greater("chain_pendulum: edge", chain, ERR), greater("spring edge", spring, ERR)]
    if pooled:
        parts.append(greater("(a) both systems pooled", np.concatenate([chain, spring]), ERR))
    return verdict(99, "synthetic", parts, parts[0], 5, "edge", discs=discs)


def _disc(group, status):
    return Discrimination(group, status, "model", 3.0 if status == "yes" else 0.1, 1.0)


@pytest.mark.parametrize(
    ("spring", "expected"),
    [(CLEAR, R.REPRODUCED), (REVERSED, R.PARTLY), (TIE, R.PARTLY)],
)
def test_every_system_discriminating_judges_every_part(spring, expected):
    discs = [_disc("chain_pendulum", "yes"), _disc("spring_pendulum (paper)", "yes")]
    assert _claim(CLEAR, spring, discs).verdict == expected


@pytest.mark.parametrize(
    ("chain", "expected"),
    [(CLEAR, R.INCONCLUSIVE), (REVERSED, R.NOT_REPRODUCED), (TIE, R.NOT_REPRODUCED)],
)
def test_an_undiscriminating_system_voids_only_its_own_parts(chain, expected):
    """The spring's test set does not tell models from constant velocity: its part reads *not
    tested* with the reason, whatever its data say, and the chain's part is still read. A
    contradicted chain part decides the claim against it; a chain part that holds cannot
    reproduce the claim alone (a part not tested leaves it inconclusive, as a closed gate
    does)."""
    discs = [_disc("chain_pendulum", "yes"), _disc("spring_pendulum (paper)", "no")]
    v = _claim(chain, REVERSED, discs)
    parts = {p.name: p for p in v.parts}
    spring, rest = parts.pop("spring edge"), list(parts.values())
    assert spring.status == "not tested" and discs[1].group in spring.note  # the reason
    assert rest and all(p.status != "not tested" for p in rest)  # the chain's still read
    assert v.verdict == expected, v.detail
    assert v.discriminating is False
    lead = v.detail.split(";")[0]  # the detail leads with the group that voids its parts
    assert discs[1].group in lead and discs[0].group not in lead
    # the report names the system whose parts went untested, where the verdict stands on others
    from bench.studies.paper.report._comparison import _cell_text, _disc_mark

    assert v.undiscriminating == (discs[1].group,)
    assert _disc_mark(v) == f"**no** on {discs[1].group}"
    assert _cell_text(v).endswith(f"(not discriminating on {discs[1].group})")


def test_a_part_pooling_an_undiscriminating_system_leaves_the_claim_inconclusive():
    discs = [_disc("chain_pendulum", "yes"), _disc("rotor", "no")]
    v = _claim(CLEAR, CLEAR, discs, pooled=True)
    assert v.verdict == R.INCONCLUSIVE and v.discriminating is False, v.detail
    assert v.undiscriminating == ()  # nothing stands on the rest: plainly not discriminating
    assert {p.status for p in v.parts if p.role == "part"} == {"holds"}  # none voids alone
    assert "rotor" in v.detail.split(";")[0]  # the detail leads with why


def test_no_system_discriminating_is_inconclusive():
    discs = [_disc("chain_pendulum", "no"), _disc("spring_pendulum", "no")]
    v = _claim(CLEAR, CLEAR, discs)
    assert v.verdict == R.INCONCLUSIVE and v.undiscriminating == ()
    assert {p.status for p in v.parts} == {"not tested"}


# ----------------------------------------------------------------------------- properties
ORDER = {"contradicts": 0, "undecided": 1, "holds": 2}
draws = np.random.default_rng(7)
SAMPLES = [draws.normal(draws.uniform(-0.5, 1.0), draws.uniform(0.05, 0.6), 5) for _ in range(40)]


@pytest.mark.parametrize("kind", [greater, R.at_most])
def test_moving_every_seed_in_a_parts_favour_never_weakens_it(kind):
    """Monotone: every seed's value moved in the part's favour (up for *greater*, down for *at
    most*) never lowers its status; and the seeds' order never matters."""
    sign = 1.0 if kind is greater else -1.0
    for d in SAMPLES:
        before = kind("p", d, ERR).status
        for shift in (0.05, 0.2, 1.0):
            after = kind("p", d + sign * shift, ERR).status
            assert ORDER[after] >= ORDER[before], (d, shift, before, after)
        assert kind("p", d[::-1], ERR).status == before
        assert kind("p", draws.permutation(d), ERR).status == before


def test_mirrored_effects_give_mirrored_statuses():
    """*greater* and *at most* on the same values read each other's status reversed, and an
    equivalence reads the same on the mirrored values."""
    flip = {"holds": "contradicts", "contradicts": "holds", "undecided": "undecided"}
    for d in SAMPLES:
        assert R.at_most("p", d, ERR).status == flip[greater("p", d, ERR).status]
        assert R.equivalent("p", -d, ERR).status == R.equivalent("p", d, ERR).status


def test_a_closed_gate_or_condition_never_contradicts():
    """A comparison whose model did not learn, or whose condition is contradicted, reads *not
    tested*, and a claim of such parts is inconclusive, never *not reproduced*."""
    from bench.kit import Gate, gated, similar_fit

    closed = Gate("model", False, "model did not learn")
    fit, tied = similar_fit("(b) fit edge", np.log([40.0, 30.0, 35.0, 28.0, 33.0]), margin("loss"))
    assert fit.status == "contradicts" and tied.open is False
    for d in SAMPLES:
        parts = [gated(greater("(a)", d, ERR), closed), gated(greater("(c)", d, ERR), tied), fit]
        v = verdict(99, "synthetic", parts, parts[0], 5, "edge")
        assert [p.status for p in parts[:2]] == ["not tested", "not tested"]
        assert v.verdict == R.INCONCLUSIVE


def test_a_foil_is_shown_and_never_gates():
    """A foil's learning status (the model whose failure is the claim's content) is shown with
    the part's gates but never closes it: the same part reads as without it, for and against."""
    from bench.kit import Gate, foil, gated, learned_text

    failed = foil(Gate("MLP", False, "MLP did not learn"))
    for d in SAMPLES:
        plain = verdict(99, "s", [greater("(a)", d, ERR)], None, 5, "edge")
        part = gated(greater("(a)", d, ERR), Gate("HNN", True, "HNN learned"), failed)
        v = verdict(99, "s", [part], part, 5, "edge")
        assert v.parts[0].status == plain.parts[0].status != "not tested"
        assert v.verdict == plain.verdict
        assert learned_text(v) == "HNN yes, MLP (the foil, not gated) no"
