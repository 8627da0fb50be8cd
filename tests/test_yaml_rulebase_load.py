"""Loading valid rule-base YAML: what each construct of the format becomes in the model."""

from __future__ import annotations

import hashlib

import pytest

from fuzzkit.formats.registry import loads
from fuzzkit.fuzzy.model import Compound, Consequent, Proposition, Rule, RuleTable, Term
from fuzzkit.fuzzy.partition import partition_terms

HEAD = """\
name: demo
inputs:
  e: {range: [-1, 1], terms: {partition: triangular, labels: [N, Z, P]}}
  de: {range: [-2, 2], terms: {partition: triangular, labels: [N, Z, P], ends: triangle}}
outputs:
  du: {range: [0, 3], default: 1.5, terms: {partition: triangular, labels: [L, M, H, X]}}
"""


def test_partition_expands_to_evenly_spaced_triangles_with_shoulders_on_inputs() -> None:
    rb = loads(HEAD + "rules: [{if: {e: N}, then: {du: L}}]\n")
    e, de = rb.inputs
    assert e.terms == (
        Term("N", "left_shoulder", (-1.0, 0.0)),
        Term("Z", "triangle", (-1.0, 0.0, 1.0)),
        Term("P", "right_shoulder", (0.0, 1.0)),
    )
    # ends: triangle -> outer triangles centred on the range ends, one spacing beyond.
    assert de.terms == (
        Term("N", "triangle", (-4.0, -2.0, 0.0)),
        Term("Z", "triangle", (-2.0, 0.0, 2.0)),
        Term("P", "triangle", (0.0, 2.0, 4.0)),
    )
    # outputs default to triangle ends; 4 labels over [0, 3] peak at 0, 1, 2, 3.
    (du,) = rb.outputs
    assert [t.params for t in du.terms] == [
        (-1.0, 0.0, 1.0),
        (0.0, 1.0, 2.0),
        (1.0, 2.0, 3.0),
        (2.0, 3.0, 4.0),
    ]
    assert du.default == 1.5
    assert (du.low, du.high) == (0.0, 3.0)


def test_seven_label_partition_peaks_at_thirds() -> None:
    labels = ["NL", "NM", "NS", "ZR", "PS", "PM", "PL"]
    terms = partition_terms(labels, -1.0, 1.0, "triangle")
    peaks = [t.params[1] for t in terms]
    assert peaks == pytest.approx([k / 3 for k in range(-3, 4)], abs=1e-15)
    assert peaks[0] == -1.0 and peaks[-1] == 1.0  # exact ends, no rounding drift
    assert terms[0].params == pytest.approx((-4 / 3, -1.0, -2 / 3))


def test_explicit_terms_use_points_or_named_parameters() -> None:
    text = """\
name: shapes
inputs:
  x:
    range: [0, 10]
    terms:
      a: {shape: triangle, points: [0, 0, 2]}
      b: {shape: trapezoid, points: [1, 2, 3, 4]}
      c: {shape: left_shoulder, points: [1, 3]}
      d: {shape: right_shoulder, points: [3, 5]}
      g: {shape: gaussian, mean: 5, sigma: 1e-1}
      h: {shape: bell, width: 2, slope: 3, centre: 6}
      s: {shape: sigmoid, slope: -4, centre: 7}
outputs:
  y:
    range: [0, 1]
    default: 0.5  # one rule: elsewhere none fires
    terms:
      lo: {shape: singleton, value: 0.25}
      hi: {shape: singleton, value: 0.75}
defuzzifier: weighted_average
rules: [{if: {x: a}, then: {y: lo}}]
"""
    rb = loads(text)
    assert rb.inputs[0].terms == (
        Term("a", "triangle", (0.0, 0.0, 2.0)),
        Term("b", "trapezoid", (1.0, 2.0, 3.0, 4.0)),
        Term("c", "left_shoulder", (1.0, 3.0)),
        Term("d", "right_shoulder", (3.0, 5.0)),
        Term("g", "gaussian", (5.0, 0.1)),  # 1e-1: YAML 1.2 number syntax is accepted
        Term("h", "bell", (2.0, 3.0, 6.0)),
        Term("s", "sigmoid", (-4.0, 7.0)),
    )
    assert rb.outputs[0].terms == (
        Term("lo", "singleton", (0.25,)),
        Term("hi", "singleton", (0.75,)),
    )
    assert rb.defuzzifier == "weighted_average"


def test_defaults_for_optional_keys() -> None:
    rb = loads(HEAD + "rules: [{if: {e: N}, then: {du: L}}]\n")
    assert rb.operators.and_ == "min" and rb.operators.or_ == "max"
    assert rb.operators.implication == "min" and rb.operators.aggregation == "max"
    assert rb.defuzzifier == "centroid"
    assert rb.out_of_range == "clamp"
    assert rb.description == ""
    assert rb.table is None
    assert rb.rules[0].weight == 1.0


def test_operators_and_policies_are_read() -> None:
    rb = loads(
        HEAD + "operators: {and: product, or: probabilistic_sum, implication: product, "
        "aggregation: bounded_sum}\ndefuzzifier: bisector\nout_of_range: extend\n"
        "rules: [{if: {e: N}, then: {du: L}}]\n"
    )
    ops = rb.operators
    assert (ops.and_, ops.or_, ops.implication, ops.aggregation) == (
        "product",
        "probabilistic_sum",
        "product",
        "bounded_sum",
    )
    assert (rb.defuzzifier, rb.out_of_range) == ("bisector", "extend")


def test_list_rules_cover_and_or_not_and_weights() -> None:
    text = (
        HEAD
        + """\
rules:
  - {if: {e: P, de: N}, then: {du: M}, weight: 0.25}
  - {if: {e: {not: Z}}, then: {du: L}}
  - {if: {not: {de: P}}, then: {du: H}}
  - {if: {or: [{e: N}, {and: [{e: Z}, {de: {not: N}}]}]}, then: {du: X}}
  - {if: {e: Z, or: [{de: N}, {de: P}]}, then: {du: M}}
"""
    )
    rules = loads(text).rules
    P, C = Proposition, Compound
    assert rules == (
        Rule(C("and", (P("e", "P"), P("de", "N"))), (Consequent("du", "M"),), 0.25),
        Rule(P("e", "Z", negated=True), (Consequent("du", "L"),)),
        Rule(P("de", "P", negated=True), (Consequent("du", "H"),)),
        Rule(
            C("or", (P("e", "N"), C("and", (P("e", "Z"), P("de", "N", negated=True))))),
            (Consequent("du", "X"),),
        ),
        Rule(
            C("and", (P("e", "Z"), C("or", (P("de", "N"), P("de", "P"))))),
            (Consequent("du", "M"),),
        ),
    )


def test_rule_with_several_outputs() -> None:
    text = """\
name: two
inputs: {x: {range: [0, 1], terms: {partition: triangular, labels: [lo, hi]}}}
outputs:
  a: {range: [0, 1], default: 0, terms: {partition: triangular, labels: [lo, hi]}}
  b: {range: [0, 1], default: 0, terms: {partition: triangular, labels: [lo, hi]}}
rules: [{if: {x: hi}, then: {a: lo, b: hi}}]
"""
    (rule,) = loads(text).rules
    assert rule.consequents == (Consequent("a", "lo"), Consequent("b", "hi"))


TABLE = """\
rules:
  table:
    rows: e
    columns: de
    output: du
    cells: |
      L  L  M
      L  -  H
      M  H  X
"""


def test_table_becomes_row_major_and_rules_skipping_empty_cells() -> None:
    rb = loads(HEAD + TABLE)
    assert rb.table == RuleTable("e", "de", "du")
    expected = [
        ("N", "N", "L"),
        ("N", "Z", "L"),
        ("N", "P", "M"),
        ("Z", "N", "L"),
        ("Z", "P", "H"),
        ("P", "N", "M"),
        ("P", "Z", "H"),
        ("P", "P", "X"),
    ]
    assert rb.rules == tuple(
        Rule(
            Compound("and", (Proposition("e", r), Proposition("de", c))),
            (Consequent("du", o),),
            1.0,
        )
        for r, c, o in expected
    )


def test_table_cells_as_a_list_of_rows_and_explicit_label_order() -> None:
    text = HEAD + (
        "rules:\n  table:\n    rows: e\n    columns: de\n"
        "    row_labels: [P, Z, N]\n    column_labels: [P, Z, N]\n"
        "    cells: ['X H M', 'H - L', 'M L L']\n"
    )
    reordered = loads(text)
    # The same table written in the other label order: same cells, other rule order.
    plain = loads(HEAD + TABLE)
    assert set(reordered.rules) == set(plain.rules)
    assert reordered.rules[0].antecedent == Compound(
        "and", (Proposition("e", "P"), Proposition("de", "P"))
    )
    assert reordered.rules != plain.rules


def test_table_output_defaults_to_the_only_output() -> None:
    rb = loads(HEAD + TABLE.replace("    output: du\n", ""))
    assert rb.table == RuleTable("e", "de", "du")


def test_source_records_path_and_sha256_but_not_equality() -> None:
    text = HEAD + TABLE
    a = loads(text, source="a.yaml")
    b = loads(text + "# a comment changes the hash, not the model\n", source="b.yaml")
    assert a.source is not None and b.source is not None
    assert a.source.path == "a.yaml"
    assert a.source.sha256 == hashlib.sha256(text.encode()).hexdigest()
    assert a.source.sha256 != b.source.sha256
    assert a == b


def test_quoted_labels_that_yaml_would_read_as_booleans() -> None:
    text = """\
name: toggle
inputs: {x: {range: [0, 1], terms: {partition: triangular, labels: ['off', 'on']}}}
outputs: {y: {range: [0, 1], default: 0, terms: {partition: triangular, labels: ['no', 'yes']}}}
rules: [{if: {x: 'on'}, then: {y: 'yes'}}]
"""
    rb = loads(text)
    assert rb.inputs[0].term_names == ("off", "on")
    assert rb.rules[0].consequents == (Consequent("y", "yes"),)


def test_null_default_means_none() -> None:
    # (without a default, the empty cell of TABLE would be an error: filled here)
    rb = loads(HEAD.replace("default: 1.5", "default: null") + TABLE.replace("L  -  H", "L  M  H"))
    assert rb.outputs[0].default is None
