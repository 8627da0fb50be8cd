"""Model -> YAML -> model gives an equal model; the JSON Schema describes the same format."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest
import yaml
from _random_rulebases import random_rulebase

from fuzzkit.formats import registry
from fuzzkit.formats.schema import json_schema
from fuzzkit.formats.yaml_writer import dump
from fuzzkit.fuzzy.model import (
    AGGREGATIONS,
    AND_OPERATORS,
    DEFUZZIFIERS,
    OUT_OF_RANGE_POLICIES,
    SHAPE_PARAMS,
    Compound,
    Consequent,
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


def _random_rulebase(seed: int) -> RuleBase:
    """Every third a Sugeno rule base; nested conditions, every shape and file-level option."""
    return random_rulebase(
        seed, sugeno=seed % 3 == 0, matlab_shapes=True, depth=2, file_options=True
    )


@pytest.mark.parametrize("seed", range(40))
def test_random_python_built_models_round_trip(seed: int) -> None:
    rb = _random_rulebase(seed)
    assert check(rb) == [], check(rb)
    assert registry.loads(dump(rb)) == rb


def test_the_random_round_trips_hold_every_shape_and_option() -> None:
    rbs = [_random_rulebase(seed) for seed in range(40)]
    shapes = {t.shape for rb in rbs for v in (*rb.inputs, *rb.outputs) for t in v.terms}
    assert shapes == set(SHAPE_PARAMS) - {"singleton"}, set(SHAPE_PARAMS) - shapes
    assert {rb.defuzzifier for rb in rbs} == set(DEFUZZIFIERS)
    assert {rb.out_of_range for rb in rbs} == set(OUT_OF_RANGE_POLICIES)
    assert {rb.coverage for rb in rbs} == {"strict", "allow_gaps"}
    assert any(
        isinstance(op, Compound) for rb in rbs for r in rb.rules
        if isinstance(r.antecedent, Compound) for op in r.antecedent.operands
    )  # fmt: skip


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
