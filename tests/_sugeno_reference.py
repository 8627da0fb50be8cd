"""Sugeno rule bases worked by hand, shared by the engine, fuzzylite and codegen tests.

Memberships, firing strengths and consequents are written out here, not taken from fuzzkit.
"""

from __future__ import annotations

from string import Template

import numpy as np

# x: lo falls 1 -> 0 over [2, 8], hi rises; y: small falls over [0, 1], big rises.
# r1: x lo AND y small -> A (4); r2: x hi OR y big -> B (0.5 x - 2 y + 1), weight 0.5;
# r3: x NOT lo -> A again (rules sharing a term count separately).
HAND = Template("""\
name: hand
inputs:
  x: {range: [0, 10], terms: {lo: {shape: left_shoulder, points: [2, 8]},
                              hi: {shape: right_shoulder, points: [2, 8]}}}
  y: {range: [0, 1], terms: {small: {shape: triangle, points: [-1, 0, 1]},
                             big: {shape: triangle, points: [0, 1, 2]}}}
outputs:
  z:
    range: [-10, 10]
    terms:
      A: {shape: constant, value: 4}
      B: {shape: linear, coefficients: {x: 0.5, y: -2}, constant: 1}
operators: {and: $and_, or: $or_, implication: $imp, aggregation: $agg}
defuzzifier: $defuzz
rules:
  - {if: {x: lo, y: small}, then: {z: A}}
  - {if: {or: [{x: hi}, {y: big}]}, then: {z: B}, weight: 0.5}
  - {if: {x: {not: lo}}, then: {z: A}}
""")


def hand_doc(
    defuzz: str = "weighted_average",
    and_: str = "min",
    or_: str = "max",
    imp: str = "min",
    agg: str = "max",
) -> str:
    return HAND.substitute(defuzz=defuzz, and_=and_, or_=or_, imp=imp, agg=agg)


def hand_value(x: float, y: float, defuzz: str, and_: str, or_: str) -> float:
    x, y = min(max(x, 0.0), 10.0), min(max(y, 0.0), 1.0)  # clamp: the default policy
    lo = min(1.0, max(0.0, (8 - x) / 6))
    hi = min(1.0, max(0.0, (x - 2) / 6))
    small, big = max(0.0, 1 - y), max(0.0, y)
    w1 = min(lo, small) if and_ == "min" else lo * small
    w2 = 0.5 * (max(hi, big) if or_ == "max" else hi + big - hi * big)
    w3 = 1 - lo
    num = 4 * w1 + (0.5 * x - 2 * y + 1) * w2 + 4 * w3
    den = w1 + w2 + w3
    return num / den if defuzz == "weighted_average" else num


def _part(x: float) -> tuple[float, float, float]:
    x = min(max(x, -1.0), 1.0)
    return max(0.0, -x), 1 - abs(x), max(0.0, x)


def sugeno_pi_by_hand(e: float, de: float, bound: float = 1.0) -> float:
    """The shipped rule base, one rule at a time; product AND makes the weights sum to 1.

    The local laws see the inputs clamped to ``+-bound``: the range (1) under ``clamp``, the
    engine's 1e100 under ``extend`` (the shoulder terms stay 1 beyond the range either way).
    """
    ec, dc = min(max(e, -bound), bound), min(max(de, -bound), bound)
    gentle, firm, hold = 0.2 * ec + 0.5 * dc, 0.6 * ec + 1.0 * dc, 0.0
    table = [[firm, gentle, gentle], [gentle, hold, gentle], [gentle, gentle, firm]]
    me, md = _part(e), _part(de)
    return sum(me[i] * md[j] * table[i][j] for i in range(3) for j in range(3))


#: The system of :data:`HAND` written by hand in fuzzylite's FLL (no fuzzkit exporter involved).
HAND_FLL = """\
Engine: hand
InputVariable: x
  enabled: true
  range: 0.000 10.000
  lock-range: true
  term: lo Ramp 8.000 2.000
  term: hi Ramp 2.000 8.000
InputVariable: y
  enabled: true
  range: 0.000 1.000
  lock-range: true
  term: small Triangle -1.000 0.000 1.000
  term: big Triangle 0.000 1.000 2.000
OutputVariable: z
  enabled: true
  range: -10.000 10.000
  lock-range: false
  aggregation: none
  defuzzifier: {defuzzifier} TakagiSugeno
  default: nan
  lock-previous: false
  term: A Constant 4.000
  term: B Linear 0.500 -2.000 1.000
RuleBlock: rb
  enabled: true
  conjunction: {conjunction}
  disjunction: {disjunction}
  implication: none
  activation: General
  rule: if x is lo and y is small then z is A
  rule: if x is hi or y is big then z is B with 0.5
  rule: if x is not lo then z is A
"""

#: (fuzzkit defuzzifier, and, or, then the same in fuzzylite's names) per compared case.
HAND_FLL_CASES = [
    ("weighted_average", "min", "max", "WeightedAverage", "Minimum", "Maximum"),
    ("weighted_sum", "min", "max", "WeightedSum", "Minimum", "Maximum"),
    (
        "weighted_average",
        "product",
        "probabilistic_sum",
        "WeightedAverage",
        "AlgebraicProduct",
        "AlgebraicSum",
    ),
]


def hand_fll(fl_defuzz: str, fl_and: str, fl_or: str) -> str:
    """:data:`HAND_FLL` with fuzzylite's defuzzifier, conjunction and disjunction."""
    return HAND_FLL.format(defuzzifier=fl_defuzz, conjunction=fl_and, disjunction=fl_or)


def hand_points() -> list[tuple[float, float]]:
    """The (x, y) points the hand system is compared at, up to 20 % beyond its ranges."""
    pts = np.random.default_rng(6).uniform([-1.0, -0.2], [11.0, 1.2], (300, 2))
    return [(float(x), float(y)) for x, y in pts]


def hand_case_name(defuzz: str, and_: str) -> str:
    """The stem of the committed input and reference of one case of :data:`HAND_FLL_CASES`."""
    return f"sugeno_hand_{defuzz}_{and_}"
