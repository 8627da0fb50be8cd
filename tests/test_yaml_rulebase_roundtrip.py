"""Model -> YAML -> model gives an equal model; the JSON Schema describes the same format."""

from __future__ import annotations

import dataclasses
import json
import random
from pathlib import Path
from typing import Literal

import pytest
import yaml

from fuzzkit.formats import registry
from fuzzkit.formats.schema import json_schema
from fuzzkit.formats.yaml_writer import dump
from fuzzkit.fuzzy.model import (
    AGGREGATIONS,
    AND_OPERATORS,
    DEFUZZIFIERS,
    IMPLICATIONS,
    OR_OPERATORS,
    OUT_OF_RANGE_POLICIES,
    SHAPE_PARAMS,
    SUGENO_DEFUZZIFIERS,
    Compound,
    Consequent,
    Expression,
    Operators,
    Proposition,
    Rule,
    RuleBase,
    RuleTable,
    Term,
    Variable,
)
from fuzzkit.fuzzy.validation import check

SHIPPED = registry.available()
RULEBASES = Path(__file__).resolve().parent.parent / "rulebases"


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_rule_bases_round_trip(name: str) -> None:
    rb = registry.load(name)
    again = registry.loads(dump(rb))
    assert again == rb
    assert dump(again) == dump(rb)


def test_table_is_written_back_as_a_table_in_its_printed_order() -> None:
    rb = registry.load("paper_table1")
    doc = yaml.safe_load(dump(rb))
    table = doc["rules"]["table"]
    assert table["row_labels"] == ["PL", "PM", "PS", "ZR", "NS", "NM", "NL"]
    assert "column_labels" not in table  # the terms' own order
    assert table["cells"].splitlines()[0].split() == ["NL", "NM", "NS", "ZR", "PM", "PL", "PL"]
    # partitions are written back as the shorthand
    assert doc["inputs"]["e"]["terms"]["partition"] == "triangular"


def _random_variable(rng: random.Random, name: str, kind: str) -> Variable:
    low = rng.choice([-1.0, 0.0, -2.5])
    high = low + rng.choice([1.0, 2.0, 0.3])
    n = rng.randint(2, 5)
    labels = [f"{name}_t{i}" for i in range(n)]
    span = high - low
    terms: list[Term] = []
    # A covering backbone of triangles (inputs must be covered), plus assorted shapes.
    step = span / (n - 1)
    for i, label in enumerate(labels):
        c = low + i * step
        terms.append(Term(label, "triangle", (c - step, c, c + step)))
    shapes = [
        "trapezoid",
        "left_shoulder",
        "right_shoulder",
        "gaussian",
        "bell",
        "sigmoid",
        "gaussian_product",
        "s_shape",
        "z_shape",
        "pi_shape",
        "sigmoid_difference",
        "sigmoid_product",
    ]
    for j in range(rng.randint(0, 3)):
        shape = rng.choice(shapes)
        a = low + rng.random() * span * 0.5
        pts = sorted([a, a + 0.1 * span, a + 0.2 * span, a + 0.3 * span])
        params = {
            "trapezoid": tuple(pts),
            "left_shoulder": tuple(pts[:2]),
            "right_shoulder": tuple(pts[:2]),
            "gaussian": (a, 0.05 + rng.random()),
            "bell": (0.1 + rng.random(), 1.0 + rng.random(), a),
            "sigmoid": (rng.choice([-1, 1]) * (1 + 10 * rng.random()), a),
            "gaussian_product": (pts[0], 0.1 + rng.random(), pts[1], 0.1 + rng.random()),
            "s_shape": tuple(pts[:2]),
            "z_shape": tuple(pts[:2]),
            "pi_shape": tuple(pts),
            "sigmoid_difference": (5.0, pts[0], 3.0 + rng.random(), pts[2]),
            "sigmoid_product": (5.0, pts[0], -3.0 - rng.random(), pts[2]),
        }[shape]
        assert len(params) == len(SHAPE_PARAMS[shape])
        terms.append(Term(f"{name}_x{j}", shape, tuple(float(p) for p in params)))
    default = None
    if kind == "output" and rng.random() < 0.5:
        default = low + rng.random() * span
    return Variable(name, low, high, tuple(terms), default)


def _random_expression(rng: random.Random, inputs: list[Variable], depth: int) -> Expression:
    if depth == 0 or rng.random() < 0.4:
        var = rng.choice(inputs)
        return Proposition(var.name, rng.choice(var.term_names), rng.random() < 0.2)
    op: Literal["and", "or"] = "and" if rng.random() < 0.5 else "or"
    return Compound(
        op, tuple(_random_expression(rng, inputs, depth - 1) for _ in range(rng.randint(2, 3)))
    )


def _sugeno_output(rng: random.Random, name: str, n_inputs: int) -> Variable:
    terms = []
    for j in range(rng.randint(1, 4)):
        if rng.random() < 0.5:
            terms.append(Term(f"{name}_c{j}", "constant", (rng.uniform(-5, 5),)))
        else:
            params = tuple(rng.choice([0.0, rng.uniform(-3, 3)]) for _ in range(n_inputs + 1))
            terms.append(Term(f"{name}_l{j}", "linear", params))
    return Variable(name, -10.0, 10.0, tuple(terms), rng.choice([None, 0.0]))


def _random_rulebase(seed: int) -> RuleBase:
    rng = random.Random(seed)
    sugeno = seed % 3 == 0
    inputs = [_random_variable(rng, f"in{i}", "input") for i in range(rng.randint(1, 3))]
    n_out = rng.randint(1, 2)
    if sugeno:
        outputs = [_sugeno_output(rng, f"out{i}", len(inputs)) for i in range(n_out)]
    else:
        outputs = [_random_variable(rng, f"out{i}", "output") for i in range(n_out)]
    rules = []
    for _ in range(rng.randint(1, 8)):
        cons = tuple(
            Consequent(o.name, rng.choice(o.term_names))
            for o in rng.sample(outputs, rng.randint(1, len(outputs)))
        )
        weight = rng.choice([1.0, 0.5, rng.random()])
        rules.append(Rule(_random_expression(rng, inputs, 2), cons, weight))
    # a few random rules leave label combinations where none fires: a default makes that a
    # warning (an output without one would be refused: issue 28 item 5)
    outputs = [
        o if o.default is not None else dataclasses.replace(o, default=0.5 * (o.low + o.high))
        for o in outputs
    ]
    return RuleBase(
        name=f"random_{seed}",
        inputs=tuple(inputs),
        outputs=tuple(outputs),
        rules=tuple(rules),
        operators=Operators(
            rng.choice(AND_OPERATORS),
            rng.choice(OR_OPERATORS),
            rng.choice(IMPLICATIONS),
            rng.choice(AGGREGATIONS),
        ),
        defuzzifier=rng.choice(
            SUGENO_DEFUZZIFIERS
            if sugeno
            else [d for d in DEFUZZIFIERS if d not in SUGENO_DEFUZZIFIERS]
        ),
        out_of_range=rng.choice(OUT_OF_RANGE_POLICIES),
        coverage=rng.choice(["strict", "allow_gaps"]),
        description=rng.choice(["", "plain", "with: colon, # hash and 'quotes'\nand a newline"]),
    )


@pytest.mark.parametrize("seed", range(40))
def test_random_python_built_models_round_trip(seed: int) -> None:
    rb = _random_rulebase(seed)
    assert check(rb) == [], check(rb)
    assert registry.loads(dump(rb)) == rb


def test_sugeno_input_without_terms_and_coefficient_list_round_trip() -> None:
    text = """
name: tsk
inputs:
  x: {range: [0, 1], terms: {lo: {shape: left_shoulder, points: [0, 1]},
                             hi: {shape: right_shoulder, points: [0, 1]}}}
  load: {range: [0, 5], terms: {}}
outputs:
  z:
    range: [-10, 10]
    terms:
      flat: {shape: constant, value: -1.5}
      ramp: {shape: linear, coefficients: [2.0, -0.5], constant: 0.25}
defuzzifier: weighted_sum
coverage: allow_gaps
rules:
  - {if: {x: lo}, then: {z: flat}}
  - {if: {x: hi}, then: {z: ramp}, weight: 0.5}
"""
    rb = registry.loads(text)
    assert rb.input("load").terms == ()
    assert rb.output("z").term("ramp").params == (2.0, -0.5, 0.25)
    assert rb.coverage == "allow_gaps"
    written = dump(rb)
    assert "coefficients: {x: 2.0, load: -0.5}" in written
    assert registry.loads(written) == rb
    jsonschema = pytest.importorskip("jsonschema", reason="jsonschema is not installed")
    validator = jsonschema.Draft202012Validator(json_schema())
    for doc in (yaml.safe_load(text), yaml.safe_load(written)):
        assert validator.is_valid(doc)
    doc = yaml.safe_load(text)
    doc["outputs"]["z"]["terms"]["ramp"]["coefficients"] = "steep"
    assert not validator.is_valid(doc)


def test_table_with_empty_cells_round_trips_as_a_table() -> None:
    rb = registry.load("macvicar_whelan")
    # Drop two rules: the table keeps '-' cells in their places.
    # (the output's default makes the two empty cells warnings, not errors: issue 28 item 5)
    outputs = (dataclasses.replace(rb.outputs[0], default=0.0),)
    sparse = RuleBase(rb.name, rb.inputs, outputs, rb.rules[:5] + rb.rules[7:], table=rb.table)
    text = dump(sparse)
    assert "table:" in text
    assert yaml.safe_load(text)["rules"]["table"]["cells"].splitlines()[0].split()[5:] == [
        "-",
        "-",
    ]
    assert registry.loads(text) == sparse


def test_table_hint_that_does_not_match_the_rules_falls_back_to_a_list() -> None:
    rb = registry.load("macvicar_whelan")
    reweighted = RuleBase(
        rb.name,
        rb.inputs,
        rb.outputs,
        (Rule(rb.rules[0].antecedent, rb.rules[0].consequents, 0.5), *rb.rules[1:]),
        table=RuleTable("e", "de", "du"),
    )
    again = registry.loads(dump(reweighted))
    assert isinstance(yaml.safe_load(dump(reweighted))["rules"], list)
    assert again.rules == reweighted.rules
    assert again.table is None  # a list cannot carry the hint


def test_awkward_names_and_numbers_survive() -> None:
    x = Variable(
        "x",
        -1e-300,
        1e100,  # the largest range end fuzzkit.fuzzy.resolution accepts
        (
            Term("lo", "left_shoulder", (0.1 + 0.2, 1e99)),
            Term("hi", "right_shoulder", (0.1 + 0.2, 1e99)),
        ),
    )
    y = Variable("y", 0.0, 1.0, (Term("on_", "triangle", (0.0, 0.5, 1.0)),), default=1 / 3)
    rb = RuleBase("Off_", (x,), (y,), (Rule(Proposition("x", "lo"), (Consequent("y", "on_"),)),))
    assert check(rb) == []
    assert registry.loads(dump(rb)) == rb


# ------------------------------------------------------------------------- JSON Schema


def test_schema_is_draft_2020_12_and_lists_the_model_vocabulary() -> None:
    schema = json_schema()
    json.dumps(schema)  # serialisable
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    props = schema["properties"]
    assert set(schema["required"]) == {"name", "inputs", "outputs", "rules"}
    assert props["defuzzifier"]["enum"] == list(DEFUZZIFIERS)
    assert props["out_of_range"]["enum"] == list(OUT_OF_RANGE_POLICIES)
    ops = props["operators"]["properties"]
    assert ops["and"]["enum"] == list(AND_OPERATORS)
    assert ops["aggregation"]["enum"] == list(AGGREGATIONS)
    shapes = [d["properties"]["shape"]["const"] for d in schema["$defs"]["term"]["oneOf"]]
    assert shapes == list(SHAPE_PARAMS)


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_files_validate_against_the_schema(name: str) -> None:
    jsonschema = pytest.importorskip("jsonschema", reason="jsonschema is not installed")
    doc = yaml.safe_load((RULEBASES / f"{name}.yaml").read_text())
    jsonschema.Draft202012Validator(json_schema()).validate(doc)


def test_schema_rejects_unknown_keys_and_shapes() -> None:
    jsonschema = pytest.importorskip("jsonschema", reason="jsonschema is not installed")
    validator = jsonschema.Draft202012Validator(json_schema())
    doc = yaml.safe_load((RULEBASES / "gaussian5.yaml").read_text())
    assert validator.is_valid(doc)
    doc["defuzzifer"] = "centroid"
    assert not validator.is_valid(doc)
    del doc["defuzzifer"]
    doc["inputs"]["e"]["terms"]["NB"]["shape"] = "triangel"
    assert not validator.is_valid(doc)
