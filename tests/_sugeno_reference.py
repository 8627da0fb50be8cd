"""Sugeno rule bases worked by hand, shared by the engine, fuzzylite and codegen tests.

Memberships, firing strengths and consequents are written out here, not taken from fuzzkit.
"""

from __future__ import annotations

from string import Template

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


def sugeno_pi_by_hand(e: float, de: float) -> float:
    """The shipped rule base, one rule at a time; product AND makes the weights sum to 1."""
    ec, dc = min(max(e, -1.0), 1.0), min(max(de, -1.0), 1.0)
    gentle, firm, hold = 0.2 * ec + 0.5 * dc, 0.6 * ec + 1.0 * dc, 0.0
    table = [[firm, gentle, gentle], [gentle, hold, gentle], [gentle, gentle, firm]]
    me, md = _part(e), _part(de)
    return sum(me[i] * md[j] * table[i][j] for i in range(3) for j in range(3))
