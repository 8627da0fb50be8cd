"""JSON Schema (draft 2020-12) of the rule-base YAML format, for editors and linters."""

from __future__ import annotations

from typing import Any

from fuzzkit.fuzzy.model import (
    AGGREGATIONS,
    AND_OPERATORS,
    COVERAGE_POLICIES,
    DEFUZZIFIERS,
    IMPLICATIONS,
    OR_OPERATORS,
    OUT_OF_RANGE_POLICIES,
    PIECEWISE_LINEAR_SHAPES,
    SHAPE_PARAMS,
    SUGENO_SHAPES,
)
from fuzzkit.fuzzy.partition import PARTITION_ENDS, PARTITION_KINDS
from fuzzkit.fuzzy.type2_model import MAX_RESOLUTION, TYPE_REDUCTIONS
from fuzzkit.fuzzy.validation import MAX_UNITS_CHARS


def json_schema() -> dict[str, Any]:
    """A JSON Schema (draft 2020-12) of the rule-base format, for editors and linters.

    Structural only (keys, types, shapes, operator names); the semantic checks (ordered
    points, known labels, coverage) need :func:`loads_rulebase`.
    """
    number = {"type": "number"}
    name = {"type": "string", "pattern": r"^[A-Za-z_][A-Za-z0-9_]*$"}
    shape_defs: list[dict[str, Any]] = []
    for shape, params in SHAPE_PARAMS.items():
        props: dict[str, Any]
        if shape == "linear":
            props = {
                "coefficients": {
                    "oneOf": [
                        {"type": "object", "propertyNames": name, "additionalProperties": number},
                        {"type": "array", "items": number},
                    ],
                    "description": "one per input: {input: coefficient} (missing = 0) or a "
                    "list in input order",
                },
                "constant": number,
            }
            required = ["shape", "coefficients", "constant"]
        elif shape in PIECEWISE_LINEAR_SHAPES:
            props = {
                "points": {
                    "type": "array",
                    "items": number,
                    "minItems": len(params),
                    "maxItems": len(params),
                    "description": f"{shape} points [{', '.join(params)}]",
                }
            }
            required = ["shape", "points"]
        else:
            props = {p: number for p in params}
            required = ["shape", *params]
        shape_defs.append(
            {
                "type": "object",
                "properties": {"shape": {"const": shape}, **props},
                "required": required,
                "additionalProperties": False,
            }
        )
    scale = {
        "type": "number",
        "exclusiveMinimum": 0,
        "maximum": 1,
        "description": "height of the lower membership function (default 1)",
    }
    lower_defs = [
        {**d, "properties": {**d["properties"], "scale": scale}}
        for d in shape_defs
        if d["properties"]["shape"]["const"] not in SUGENO_SHAPES
    ]
    it2_term = {
        "type": "object",
        "description": "interval type-2 term: upper and lower membership functions",
        "properties": {"upper": {"$ref": "#/$defs/term"}, "lower": {"oneOf": lower_defs}},
        "required": ["upper", "lower"],
        "additionalProperties": False,
    }
    partition = {
        "type": "object",
        "description": "N evenly spaced triangular labels over the range",
        "properties": {
            "partition": {"enum": list(PARTITION_KINDS)},
            "labels": {"type": "array", "items": name, "minItems": 2, "uniqueItems": True},
            "ends": {
                "enum": list(PARTITION_ENDS),
                "description": "outer terms: shoulder (inputs' default) or triangle",
            },
        },
        "required": ["partition", "labels"],
        "additionalProperties": False,
    }

    def explicit_terms(kind: str) -> dict[str, Any]:
        # an input may have no terms when only linear Sugeno terms use it
        return {
            "type": "object",
            "propertyNames": {"allOf": [name, {"not": {"const": "partition"}}]},
            "additionalProperties": {
                "oneOf": [{"$ref": "#/$defs/term"}, {"$ref": "#/$defs/it2_term"}]
            },
            "minProperties": 0 if kind == "input" else 1,
        }

    def variable(kind: str) -> dict[str, Any]:
        props: dict[str, Any] = {
            "range": {
                "type": "array",
                "items": number,
                "minItems": 2,
                "maxItems": 2,
                "description": "[low, high]",
            },
            "terms": {"oneOf": [{"$ref": "#/$defs/partition"}, explicit_terms(kind)]},
            "units": {
                "type": ["string", "null"],
                "minLength": 1,
                "maxLength": MAX_UNITS_CHARS,
                "pattern": r"^\S(.*\S)?$",
                "description": "physical unit of the values, for labels only: N, mm, degC, %",
            },
        }
        if kind == "output":
            props["default"] = {
                "type": ["number", "null"],
                "description": "output when no rule fires (null = NaN)",
            }
        return {
            "type": "object",
            "properties": props,
            "required": ["range", "terms"],
            "additionalProperties": False,
        }

    condition: dict[str, Any] = {
        "type": "object",
        "minProperties": 1,
        "description": "{input: label, ...} (AND), {and: [...]}, {or: [...]}, {not: {input: "
        "label}}, {input: {not: label}}",
        "properties": {
            "and": {"type": "array", "items": {"$ref": "#/$defs/condition"}, "minItems": 2},
            "or": {"type": "array", "items": {"$ref": "#/$defs/condition"}, "minItems": 2},
            "not": {
                "type": "object",
                "minProperties": 1,
                "maxProperties": 1,
                "additionalProperties": name,
            },
        },
        "additionalProperties": {
            "oneOf": [
                name,
                {
                    "type": "object",
                    "properties": {"not": name},
                    "required": ["not"],
                    "additionalProperties": False,
                },
            ]
        },
    }
    rule = {
        "type": "object",
        "properties": {
            "if": {"$ref": "#/$defs/condition"},
            "then": {"type": "object", "minProperties": 1, "additionalProperties": name},
            "weight": {"type": "number", "minimum": 0, "maximum": 1},
        },
        "required": ["if", "then"],
        "additionalProperties": False,
    }
    table = {
        "type": "object",
        "properties": {
            "rows": name,
            "columns": name,
            "output": name,
            "row_labels": {"type": "array", "items": name},
            "column_labels": {"type": "array", "items": name},
            "cells": {
                "oneOf": [{"type": "string"}, {"type": "array", "items": {"type": "string"}}],
                "description": "one line per row, labels separated by spaces, '-' = no rule",
            },
        },
        "required": ["rows", "columns", "cells"],
        "additionalProperties": False,
    }
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": "https://fuzzkit.invalid/schema/rulebase.json",
        "title": "fuzzkit rule base",
        "description": "A Mamdani or Sugeno fuzzy rule base (see docs/rulebase-format.md).",
        "type": "object",
        "properties": {
            "name": {**name, "description": "identifier; the C symbol prefix"},
            "description": {"type": "string"},
            "inputs": {
                "type": "object",
                "minProperties": 1,
                "propertyNames": name,
                "additionalProperties": variable("input"),
            },
            "outputs": {
                "type": "object",
                "minProperties": 1,
                "propertyNames": name,
                "additionalProperties": variable("output"),
            },
            "operators": {
                "type": "object",
                "properties": {
                    "and": {"enum": list(AND_OPERATORS)},
                    "or": {"enum": list(OR_OPERATORS)},
                    "implication": {"enum": list(IMPLICATIONS)},
                    "aggregation": {"enum": list(AGGREGATIONS)},
                },
                "additionalProperties": False,
            },
            "defuzzifier": {"enum": list(DEFUZZIFIERS)},
            "out_of_range": {"enum": list(OUT_OF_RANGE_POLICIES)},
            "coverage": {
                "enum": list(COVERAGE_POLICIES),
                "description": "strict: an input range no term covers is an error; "
                "allow_gaps: a warning",
            },
            "type_reduction": {
                "enum": list(TYPE_REDUCTIONS),
                "description": "interval type-2 rule bases: how the output sets are reduced",
            },
            "resolution": {
                "type": ["integer", "null"],
                "minimum": 2,
                "maximum": MAX_RESOLUTION,
                "description": "interval type-2: sample each output range at N points "
                "(MATLAB, pyit2fls) instead of the exact continuous type reduction",
            },
            "rules": {
                "oneOf": [
                    {"type": "array", "items": {"$ref": "#/$defs/rule"}, "minItems": 1},
                    {
                        "type": "object",
                        "properties": {"table": {"$ref": "#/$defs/table"}},
                        "required": ["table"],
                        "additionalProperties": False,
                    },
                ]
            },
        },
        "required": ["name", "inputs", "outputs", "rules"],
        "additionalProperties": False,
        "$defs": {
            "term": {"oneOf": shape_defs},
            "it2_term": it2_term,
            "partition": partition,
            "condition": condition,
            "rule": rule,
            "table": table,
        },
    }
