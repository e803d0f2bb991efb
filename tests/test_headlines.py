"""Each claim's headline table and figure (bench.kit._headlines) on synthetic
verdicts."""

import math

import numpy as np

from bench.kit import Part, greater, margin, verdict
from bench.kit import _headlines as H

ERR = margin("error")


def _verdicts():
    clear = greater("(a) edge", np.log([3.0, 3.2, 2.9, 3.1, 3.3]), ERR)
    tie = greater("(b) edge", np.log([1.0, 1.02, 0.98, 1.01, 0.99]), ERR)
    one = verdict(1, "one", [clear, tie], tie, 5, "edge")
    summary = Part("a - b", "", 0.5, 0.4, 0.6, 5)
    two = verdict(
        2, "two", [greater("(a) x", np.log([3.0, 3.1, 2.9, 3.0, 3.2]), ERR)], summary, 5, "d"
    )
    return one, two


def test_a_headline_part_gives_its_margin_and_the_verdict_its_status():
    one, two = _verdicts()
    assert one.label() == "partly reproduced: headline contradicted"
    t = H.headline_rows([one, two]).set_index("claim")
    assert t.loc["1", "headline"] == "(b) edge" and t.loc["1", "kind"] == "greater"
    assert math.isclose(t.loc["1", "margin"], math.log(1.25))
    assert math.isnan(t.loc["2", "margin"])  # a bare summary part: no margin


def test_the_figure_sets_the_budgets_side_by_side(tmp_path):
    one, two = _verdicts()
    for budget in ("quick", "paper"):
        (tmp_path / budget).mkdir()
        H.write_headlines(tmp_path / budget, [one, two])
    paths = H.fig_headlines({b: tmp_path / b for b in ("quick", "paper")}, tmp_path / "h")
    assert {p.suffix for p in paths} == {".png", ".pdf"} and all(p.exists() for p in paths)
    assert H.fig_headlines({"quick": tmp_path / "none"}, tmp_path / "x") == []
