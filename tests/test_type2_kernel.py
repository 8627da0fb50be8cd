"""The compiled IT2 kernel (fuzzkit/fuzzy/type2_kernel.py) against independent paths.

The brute force and pyit2fls comparisons (test_type2_inference.py, test_type2_peers.py) run
through the kernel; here its own firing is held to the type-1 engine's numpy fuzzifier and
firing, the scalar path to the batch, its cut to the brute force's sampled sets, and the rule
bases it does not cover (``or``) to an equivalent one it does.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from _type2_reference import centroid_interval

from fuzzkit.formats.registry import load, loads
from fuzzkit.fuzzy.inference import Engine
from fuzzkit.fuzzy.type2_inference import Type2Engine
from fuzzkit.fuzzy.type2_model import Type2RuleBase

OR_RULES = """
name: it2_or
inputs:
  a:
    range: [-1, 1]
    terms:
      N:
        upper: {shape: triangle, points: [-2, -1, 0.3]}
        lower: {shape: triangle, points: [-2, -1, -0.1], scale: 0.7}
      P:
        upper: {shape: triangle, points: [-0.3, 1, 2]}
        lower: {shape: triangle, points: [0.1, 1, 2], scale: 0.9}
  b:
    range: [-1, 1]
    terms:
      N: {shape: left_shoulder, points: [-0.5, 0.4]}
      P:
        upper: {shape: right_shoulder, points: [-0.4, 0.5]}
        lower: {shape: right_shoulder, points: [0.0, 0.6], scale: 0.8}
outputs:
  u:
    range: [-1, 1]
    terms:
      N:
        upper: {shape: triangle, points: [-1.5, -1, 0.4]}
        lower: {shape: triangle, points: [-1.2, -1, 0.0], scale: 0.6}
      P:
        upper: {shape: trapezoid, points: [-0.4, 0.5, 1, 1.5]}
        lower: {shape: triangle, points: [0.0, 1, 1.2], scale: 0.5}
operators: {and: $AND, implication: $IMP}
out_of_range: $OOR
rules:
$RULES
"""

WITH_OR = """
  - {if: {or: [{a: N}, {b: N}]}, then: {u: N}}
  - {if: {and: [{a: P}, {b: P}]}, then: {u: P}, weight: 0.8}
"""
SPLIT = """
  - {if: {a: N}, then: {u: N}}
  - {if: {b: N}, then: {u: N}}
  - {if: {and: [{a: P}, {b: P}]}, then: {u: P}, weight: 0.8}
"""


def or_rules(rules: str, and_: str = "min", imp: str = "min", oor: str = "clamp") -> Type2RuleBase:
    text = OR_RULES.replace("$AND", and_).replace("$IMP", imp).replace("$OOR", oor)
    rb = loads(text.replace("$RULES", rules.strip("\n")))
    assert isinstance(rb, Type2RuleBase)
    return rb


def _type2(rb: Type2RuleBase) -> Type2Engine:
    t2 = Engine(rb)._type2
    assert t2 is not None
    return t2


POINTS = np.random.default_rng(43).uniform(-1.3, 1.3, (300, 2))


@pytest.mark.parametrize(
    "and_, imp, oor",
    [("min", "min", "clamp"), ("product", "product", "extend"), ("min", "product", "extend")],
)
def test_compiled_firing_is_the_numpy_firing(and_: str, imp: str, oor: str) -> None:
    rb = or_rules(SPLIT, and_, imp, oor)
    t2 = _type2(rb)
    assert t2.compiled is not None
    flat = [POINTS[:, 0].copy(), POINTS[:, 1].copy()]
    f_lo, f_up = t2.firing_intervals(flat)  # the type-1 engine's fuzzifier and firing
    (out,) = t2.outputs
    via_levels = out.reduced(f_lo, f_up)
    via_inputs = out.reduced_points(np.stack(flat, axis=1), t2.compiled)
    np.testing.assert_array_equal(via_inputs, via_levels)


def test_scalar_path_is_the_batch_bit_for_bit() -> None:
    eng = Engine(load("macvicar_whelan_it2"))
    batch = eng.evaluate({"e": POINTS[:, 0], "de": POINTS[:, 1]})["du"]
    point = [eng.evaluate_point(e=float(e), de=float(d))["du"] for e, d in POINTS]
    np.testing.assert_array_equal(np.array(point), batch)
    assert np.isnan(eng.evaluate_point(e=float("nan"), de=0.1)["du"])
    assert eng.evaluate_point(e=float("inf"), de=1.0)["du"] == eng.evaluate_point(e=1, de=1)["du"]


def test_or_rules_take_the_numpy_firing_and_equal_the_split_rules() -> None:
    # with max aggregation, "a is N or b is N -> u is N" is the two rules a is N, b is N
    joined, split = or_rules(WITH_OR), or_rules(SPLIT)
    assert _type2(joined).compiled is None and _type2(split).compiled is not None
    pts = {"a": POINTS[:, 0], "b": POINTS[:, 1]}
    got = Engine(joined).centroid_intervals(pts)["u"]
    want = Engine(split).centroid_intervals(pts)["u"]
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-15)


@pytest.mark.parametrize("imp", ["min", "product"])
def test_kernel_interval_matches_the_brute_force_on_rules_of_two_inputs(imp: str) -> None:
    rb = or_rules(SPLIT, imp=imp)
    pts = POINTS[:10]
    y_l, y_r = Engine(rb).centroid_intervals({"a": pts[:, 0], "b": pts[:, 1]})["u"]
    want = np.array([centroid_interval(rb, {"a": a, "b": b}, 20001) for a, b in pts])
    np.testing.assert_allclose(y_l, want[:, 0], atol=1e-7)
    np.testing.assert_allclose(y_r, want[:, 1], atol=1e-7)


def test_a_discretised_universe_leaves_the_compiled_path() -> None:
    rb = load("macvicar_whelan_it2")
    assert isinstance(rb, Type2RuleBase)
    assert _type2(rb).compiled is not None
    sampled = replace(rb, footprint=replace(rb.footprint, resolution=101))
    assert _type2(sampled).compiled is None
