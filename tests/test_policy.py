"""The margin policy: every rule reads its margins from bench.kit.policy.

A margin typed into a rule (a number, a log of a number, a Margin built by hand) fails here:
statically, no part constructor in the rule modules receives a literal, and no rule module
takes the log of a number; at run time, every part of every claim on the synthetic tables has a
margin of the policy (or one a seed states), and moves when the policy's margin moves.
"""

import ast
import math
from pathlib import Path

import pytest
from _synthetic import synthetic_tables

import bench.studies as S
from bench import kit as R
from bench.kit import policy

STUDIES = Path(S.__file__).parent
KIT = Path(R.__file__).parent
CONSTRUCTORS = {"greater", "at_most", "equivalent", "band", "below", "share", "_part"}
# the kit's modules that build parts and gates
KIT_RULES = {"_stats.py", "_gates.py", "_discrimination.py", "_claims.py"}
# the folders of the claims' studies, by paper (the campaign's and the report's hold no rule)
PAPERS = ("decon", "hnn_seed", "lnn_seed", "vin_seed")


def _rule_modules():
    """The modules that hold rules: every module of the studies' folders and the kit's modules
    that build parts."""
    studies = (p for paper in PAPERS for p in (STUDIES / paper).rglob("*.py"))
    return sorted([*studies, *(KIT / name for name in KIT_RULES)])


def _is_number(node) -> bool:
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)):
        return True
    if isinstance(node, ast.UnaryOp):
        return _is_number(node.operand)
    return isinstance(node, ast.BinOp) and _is_number(node.left) and _is_number(node.right)


@pytest.mark.parametrize(
    "path", _rule_modules(), ids=lambda p: str(p.relative_to(STUDIES.parents[1]))
)
def test_no_rule_types_a_margin(path):
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        name = getattr(node.func, "id", None) or getattr(node.func, "attr", None)
        if name in CONSTRUCTORS:
            margin = [*node.args[2:], *(k.value for k in node.keywords if k.arg == "mg")]
            for arg in margin:
                assert not _is_number(arg), f"{path}:{node.lineno}: a typed margin"
                assert not (isinstance(arg, ast.Call) and getattr(arg.func, "attr", "") == "log")
        if name == "log" and node.args and _is_number(node.args[0]):
            raise AssertionError(f"{path}:{node.lineno}: log of a number (a margin?)")
        if name == "Margin":
            raise AssertionError(f"{path}:{node.lineno}: a Margin built outside the policy")


def test_the_policy_table():
    for q in policy.POLICY.values():
        lo, hi = q.band
        assert lo <= q.margin <= hi, q.name
        assert q.words and q.why
    assert policy.margin("error", squared=True).value == pytest.approx(1.25**2)
    assert policy.POLICY["loss"].margin == pytest.approx(policy.POLICY["error"].margin ** 2)
    with policy.override(error=1.5):
        assert policy.margin("error").value == 1.5
        assert policy.margin("error", squared=True).value == pytest.approx(2.25)
    assert policy.margin("error").value == 1.25  # restored
    with pytest.raises(ValueError, match="unknown quantity"):
        with policy.override(errors=1.5):
            pass
    assert policy.band_points("error") == pytest.approx([1.1, math.sqrt(2.2), 2.0])


@pytest.fixture(scope="module")
def tables():
    return synthetic_tables("smoke", noise=0.05)


def _margins(verdicts):
    return [
        (v.key, p.name, p.quantity, p.margin_value, p.margin)
        for v in verdicts
        for p in v.parts
        if p.quantity
    ]


def test_every_part_has_a_margin_of_the_policy(tables):
    stated = {(m.quantity, m.value) for m in policy.stated_margins()}
    got = _margins(R.evaluate_claims(*tables))
    assert len({k for k, *_ in got}) >= 8  # every claim of these tables has parts
    for key, name, q, value, label in got:
        base = policy.POLICY[q].margin
        ok = value in (pytest.approx(base), pytest.approx(base**2)) or (q, value) in stated
        assert ok, (key, name, q, value, label)


def test_every_part_moves_with_the_policy(tables):
    before = _margins(R.evaluate_claims(*tables))
    moved = {q: policy.POLICY[q].band[1] for q in policy.POLICY}
    with policy.override(**moved):
        after = _margins(R.evaluate_claims(*tables))
    assert [(k, q) for k, _, q, *_ in before] == [(k, q) for k, _, q, *_ in after]
    for (key, name, q, v0, label), (*_, v1, _l) in zip(before, after, strict=True):
        if "(stated:" in label:
            assert v1 == v0, (key, name)  # a number the seed states does not move
        else:
            assert v1 != pytest.approx(v0), (key, name, q, v0)


def test_part_constructors_refuse_a_number():
    with pytest.raises(TypeError):
        R.at_most("x", [0.1, 0.2, 0.3], 2.0)
    with pytest.raises(TypeError):
        R.share("x", [1.0] * 5, [1.0] * 5, 0.5)
