"""Principles the verdict engine applies to every claim, pinned on synthetic parts.

Discrimination per system: a system whose best model does not beat the trivial predictors
voids only its own parts; a claim whose parts pool that system with others stays inconclusive.
"""

import numpy as np
import pytest

from bench.studies.paper import kit as R
from bench.studies.paper.kit import Discrimination, greater, margin, verdict

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
    spring = {p.name: p for p in v.parts}["spring edge"]
    assert spring.status == "not tested" and "not discriminating on spring_pendulum" in spring.note
    assert v.verdict == expected, v.detail
    assert v.discriminating is False
    assert v.detail.startswith("not discriminating on spring_pendulum (paper): its parts")


def test_a_part_pooling_an_undiscriminating_system_leaves_the_claim_inconclusive():
    discs = [_disc("chain_pendulum", "yes"), _disc("rotor", "no")]
    v = _claim(CLEAR, CLEAR, discs, pooled=True)
    assert v.verdict == R.INCONCLUSIVE and v.detail.startswith("NOT DISCRIMINATING")


def test_no_system_discriminating_is_inconclusive():
    discs = [_disc("chain_pendulum", "no"), _disc("spring_pendulum", "no")]
    v = _claim(CLEAR, CLEAR, discs)
    assert v.verdict == R.INCONCLUSIVE
    assert {p.status for p in v.parts} == {"not tested"}
