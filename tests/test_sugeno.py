"""Sugeno (Takagi-Sugeno-Kang) outputs: the engine against hand computations, the format, errors.

The expected values are computed here from the textbook definitions (memberships written out,
one rule at a time), never by the engine.
"""

from __future__ import annotations

import math
import re
from dataclasses import replace
from string import Template

import numpy as np
import pytest
from _sugeno_reference import hand_doc, hand_value, sugeno_pi_by_hand

from fuzzkit.errors import RuleBaseError
from fuzzkit.formats.registry import load, loads
from fuzzkit.fuzzy.inference import Engine
from fuzzkit.fuzzy.model import AGGREGATIONS, IMPLICATIONS

# --------------------------------------------------------------------------- a hand-checkable base

POINTS = np.random.default_rng(15).uniform([-2.0, -0.5], [12.0, 1.5], (400, 2))


@pytest.mark.parametrize("defuzz", ["weighted_average", "weighted_sum"])
@pytest.mark.parametrize(("and_", "or_"), [("min", "max"), ("product", "probabilistic_sum")])
def test_engine_matches_the_hand_computation(defuzz: str, and_: str, or_: str) -> None:
    rb = loads(hand_doc(defuzz, and_, or_))
    got = Engine(rb).evaluate({"x": POINTS[:, 0], "y": POINTS[:, 1]})["z"]
    want = [hand_value(x, y, defuzz, and_, or_) for x, y in POINTS]
    np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-13)


@pytest.mark.parametrize("imp", IMPLICATIONS)
@pytest.mark.parametrize("agg", AGGREGATIONS)
def test_implication_and_aggregation_do_not_apply(imp: str, agg: str) -> None:
    # MATLAB ignores ImpMethod/AggMethod for Sugeno; fuzzylite weighs every activated term.
    rb = loads(hand_doc(imp=imp, agg=agg))
    got = Engine(rb).evaluate({"x": POINTS[:, 0], "y": POINTS[:, 1]})["z"]
    want = [hand_value(x, y, "weighted_average", "min", "max") for x, y in POINTS]
    np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-13)


def test_weighted_sum_is_the_average_times_the_total_firing() -> None:
    avg = loads(hand_doc("weighted_average"))
    total = Engine(avg).firing_strengths({"x": POINTS[:, 0], "y": POINTS[:, 1]}).sum(axis=1)
    a = Engine(avg).evaluate({"x": POINTS[:, 0], "y": POINTS[:, 1]})["z"]
    s = Engine(loads(hand_doc("weighted_sum"))).evaluate({"x": POINTS[:, 0], "y": POINTS[:, 1]})
    np.testing.assert_allclose(s["z"], a * total, rtol=1e-13, atol=1e-13)
    assert np.any(np.abs(total - 1.0) > 0.1)  # the two really differ on these points


@pytest.mark.parametrize("policy", ["clamp", "extend"])
@pytest.mark.parametrize(("and_", "or_"), [("min", "max"), ("product", "probabilistic_sum")])
def test_scalar_and_batch_paths_agree(policy: str, and_: str, or_: str) -> None:
    rb = replace(loads(hand_doc("weighted_average", and_, or_)), out_of_range=policy)
    eng = Engine(rb)
    assert eng._scalar is not None  # the pure-Python path serves this rule base
    batch = eng.evaluate({"x": POINTS[:, 0], "y": POINTS[:, 1]})["z"]
    one = [eng.evaluate_point(x=x, y=y)["z"] for x, y in POINTS]
    f = eng.point_function("z")
    np.testing.assert_allclose(one, batch, rtol=1e-14, atol=1e-14)
    np.testing.assert_array_equal([f(x, y) for x, y in POINTS], one)
    for bad in ((math.nan, 0.5), (5.0, math.nan)):
        assert math.isnan(eng.evaluate_point(x=bad[0], y=bad[1])["z"])
    assert eng.evaluate_point(x=math.inf, y=0.5)["z"] == pytest.approx(
        float(eng.evaluate({"x": math.inf, "y": 0.5})["z"]), rel=1e-14
    )


def test_nan_input_gives_nan_even_with_a_default() -> None:
    text = hand_doc().replace("range: [-10, 10]", "range: [-10, 10]\n    default: 0.5")
    eng = Engine(loads(text))
    got = eng.evaluate({"x": [math.nan, 5.0, 5.0], "y": [0.5, math.nan, 0.5]})["z"]
    assert math.isnan(got[0]) and math.isnan(got[1]) and math.isfinite(got[2])


# --------------------------------------------------------------------------- shipped sugeno_pi


def test_shipped_sugeno_pi_is_the_gain_scheduled_law() -> None:
    rb = load("sugeno_pi")
    pts = np.random.default_rng(1).uniform(-1.3, 1.3, (500, 2))
    got = Engine(rb).evaluate({"e": pts[:, 0], "de": pts[:, 1]})["du"]
    np.testing.assert_allclose(got, [sugeno_pi_by_hand(*p) for p in pts], atol=1e-14)
    # linear consequents are not clamped to the output range's label peaks: 0.6 + 1.0
    assert Engine(rb).evaluate_point(e=1.0, de=1.0)["du"] == pytest.approx(1.6, abs=1e-15)
    # weights sum to 1 here, so the weighted sum is the same law
    summed = Engine(replace(rb, defuzzifier="weighted_sum"))
    np.testing.assert_allclose(summed.evaluate({"e": pts[:, 0], "de": pts[:, 1]})["du"], got)


# --------------------------------------------------------------------------- linear consequents

TERMLESS = """\
name: termless
inputs:
  x: {range: [0, 1], terms: {lo: {shape: left_shoulder, points: [0, 1]},
                             hi: {shape: right_shoulder, points: [0, 1]}}}
  load: {range: [0, 5], terms: {}}
outputs:
  z:
    range: [-1, 1]
    terms:
      flat: {shape: constant, value: 100}
      ramp: {shape: linear, coefficients: [0, 2], constant: 1}
defuzzifier: weighted_average
rules:
  - {if: {x: lo}, then: {z: flat}}
  - {if: {x: hi}, then: {z: ramp}}
"""


@pytest.mark.parametrize("policy", ["clamp", "extend"])
def test_input_without_terms_feeds_linear_terms_and_outputs_are_not_clamped(policy: str) -> None:
    rb = replace(loads(TERMLESS), out_of_range=policy)
    eng = Engine(rb)
    xs = np.array([0.0, 0.25, 1.0, 0.5, 0.5])
    loads_ = np.array([3.0, 3.0, 3.0, 7.0, -2.0])
    got = eng.evaluate({"x": xs, "load": loads_})["z"]
    seen = loads_ if policy == "extend" else np.clip(loads_, 0, 5)
    want = (1 - xs) * 100 + xs * (2 * seen + 1)  # weights 1 - x and x sum to 1
    np.testing.assert_allclose(got, want, rtol=1e-14)
    assert got[0] == 100.0  # far outside the declared range [-1, 1]: not clamped


def test_no_rule_fires_gives_the_default_or_nan_for_both_defuzzifiers() -> None:
    gap = """\
name: gap
coverage: allow_gaps
inputs:
  x: {range: [0, 10], terms: {lo: {shape: triangle, points: [0, 0, 3]},
                              hi: {shape: triangle, points: [7, 10, 10]}}}
outputs:
  z: {range: [-5, 5]$default, terms: {A: {shape: constant, value: 2},
                                      B: {shape: constant, value: -3}}}
defuzzifier: $defuzz
rules:
  - {if: {x: lo}, then: {z: A}}
  - {if: {x: hi}, then: {z: B}}
"""
    for defuzz in ("weighted_average", "weighted_sum"):
        for default, want in (("", math.nan), (", default: 1.5", 1.5)):
            text = Template(gap).substitute(default=default, defuzz=defuzz)
            got = Engine(loads(text)).evaluate({"x": [5.0, 1.5]})["z"]
            assert got[0] == pytest.approx(want, nan_ok=True)
            # one rule fires at x = 1.5 with strength 0.5
            assert got[1] == pytest.approx(2.0 if defuzz == "weighted_average" else 1.0)


# --------------------------------------------------------------------------- bad input

BASE = Template("""\
name: bad
inputs:
  e: {range: [-1, 1], terms: $e_terms}
  de: {range: [-1, 1], terms: {partition: triangular, labels: [N, Z, P]}}
outputs:
  u:
    range: [-1, 1]
    terms:
      A: {shape: constant, value: 0.5}
      B: $b_term
defuzzifier: $defuzz
rules:
  - {if: {e: N}, then: {u: A}}
  - {if: {e: P}, then: {u: B}}
""")
E_PART = "{partition: triangular, labels: [N, Z, P]}"
B_LINEAR = "{shape: linear, coefficients: {e: 1, de: 2}, constant: 0}"


def bad_doc(e_terms: str = E_PART, b_term: str = B_LINEAR, defuzz: str = "weighted_average") -> str:
    return BASE.substitute(e_terms=e_terms, b_term=b_term, defuzz=defuzz)


BAD_CASES = [
    (
        bad_doc(e_terms="{N: {shape: constant, value: -1}, P: {shape: constant, value: 1}}"),
        3,
        r"constant is a Sugeno output term; input terms must be membership functions",
    ),
    (
        bad_doc(b_term="{shape: triangle, points: [0, 0.5, 1]}"),
        9,
        r"output 'u' mixes Sugeno terms \(A\) with membership functions \(B\)",
    ),
    (
        bad_doc(b_term="{shape: linear, coefficients: [1, 2, 3], constant: 0}"),
        10,
        r"linear term 'B' has 3 coefficient\(s\), expected 2 \(one per input, in order: e, de\)",
    ),
    (
        bad_doc(b_term="{shape: linear, coefficients: {e: 1, d: 2}, constant: 0}"),
        10,
        r"unknown input 'd' in the coefficients of term 'B' \(did you mean 'de'\?\)",
    ),
    (
        bad_doc(b_term="{shape: linear, coefficients: {e: one}, constant: 0}"),
        10,
        r"expected a number for the coefficient of 'e' in term 'B', got 'one'",
    ),
    (
        bad_doc(b_term="{shape: linear, coefficients: {e: 1}}"),
        10,
        r"missing required key 'constant' in linear term 'B'",
    ),
    (
        bad_doc(defuzz="centroid"),
        11,
        r"output 'u' has Sugeno terms \(constant/linear\), which need defuzzifier "
        r"weighted_average or weighted_sum, got 'centroid'",
    ),
    (
        bad_doc(e_terms="{}", b_term="{shape: linear, coefficients: {de: 2}, constant: 0}"),
        3,
        r"input 'e' has no terms \(an input may have none only when a linear output term uses it\)",
    ),
    (
        bad_doc().replace("defuzzifier:", "coverage: loose\ndefuzzifier:"),
        11,
        r"unknown coverage policy 'loose'; expected one of strict, allow_gaps",
    ),
]


@pytest.mark.parametrize(("text", "line", "match"), BAD_CASES)
def test_bad_sugeno_input_is_located_and_explained(text: str, line: int, match: str) -> None:
    with pytest.raises(RuleBaseError) as info:
        loads(text, source="bad.yaml")
    hits = [p for p in info.value.problems if re.search(match, p.message)]
    assert hits, [str(p) for p in info.value.problems]
    assert hits[0].location.file == "bad.yaml" and hits[0].location.line == line


def test_weighted_sum_on_a_mamdani_output_is_refused() -> None:
    text = bad_doc(b_term="{shape: triangle, points: [0, 0.5, 1]}", defuzz="weighted_sum").replace(
        "A: {shape: constant, value: 0.5}", "A: {shape: triangle, points: [-1, -0.5, 0]}"
    )
    with pytest.raises(RuleBaseError, match=r"bad.yaml:11:14: weighted_sum is for Sugeno outputs"):
        loads(text, source="bad.yaml")


def test_membership_functions_refuse_sugeno_terms() -> None:
    from fuzzkit.fuzzy.membership import evaluate_term

    term = load("sugeno_pi").output("du").term("gentle")
    with pytest.raises(ValueError, match="'gentle': linear is a Sugeno output term"):
        evaluate_term(term, 0.0)


def test_mamdani_and_sugeno_outputs_side_by_side_follow_their_own_rules() -> None:
    # Two rules conclude the same term. The Mamdani output's weighted average aggregates them
    # per term (max), the Sugeno output counts each rule on its own (MATLAB, fuzzylite).
    text = """\
name: mixed
inputs:
  x: {range: [0, 1], terms: {lo: {shape: left_shoulder, points: [0, 1]},
                             hi: {shape: right_shoulder, points: [0, 1]}}}
outputs:
  m: {range: [0, 10], terms: {A: {shape: singleton, value: 2}, B: {shape: singleton, value: 8}}}
  s: {range: [0, 10], terms: {A: {shape: constant, value: 2}, B: {shape: constant, value: 8}}}
defuzzifier: weighted_average
rules:
  - {if: {x: lo}, then: {m: A, s: A}}
  - {if: {x: hi}, then: {m: A, s: A}, weight: 0.5}
  - {if: {x: hi}, then: {m: B, s: B}}
"""
    eng = Engine(loads(text))
    for x in (0.0, 0.3, 0.5, 0.9, 1.0):
        lo, hi = 1 - x, x
        a_max = max(lo, 0.5 * hi)
        got = eng.evaluate_point(x=x)
        assert got["m"] == pytest.approx((2 * a_max + 8 * hi) / (a_max + hi), rel=1e-14)
        want_s = (2 * lo + 2 * 0.5 * hi + 8 * hi) / (lo + 0.5 * hi + hi)
        assert got["s"] == pytest.approx(want_s, rel=1e-14)
