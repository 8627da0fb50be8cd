"""Model -> rule-base YAML: the inverse of :mod:`fuzzkit.formats.yaml_reader`.

``loads_rulebase(dump(rb)) == rb`` for every rule base (tested); tables are written back as
tables where the rules form one, partitions as the shorthand where the terms are one.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import yaml

from fuzzkit.errors import RuleBaseError
from fuzzkit.formats.yaml_reader import EMPTY_CELL
from fuzzkit.fuzzy import validation
from fuzzkit.fuzzy.model import (
    Compound,
    Consequent,
    Expression,
    Proposition,
    Rule,
    RuleBase,
    RuleTable,
    Term,
    Variable,
)
from fuzzkit.fuzzy.partition import PARTITION_ENDS, partition_terms
from fuzzkit.fuzzy.shapes import shape
from fuzzkit.fuzzy.type2_model import Footprint, footprint_of
from fuzzkit.located_yaml import STR_TAG


class _Flow(list[Any]):
    """A list written in flow style: ``[a, b]``."""


class _FlowMap(dict[str, Any]):
    """A mapping written in flow style: ``{a: 1}``."""


class _Literal(str):
    """A string written as a literal block (``|``)."""

    __slots__ = ()


class _Dumper(yaml.SafeDumper):
    """SafeDumper with flow lists/maps and literal blocks where the format reads best."""


_Dumper.add_representer(
    _Flow, lambda d, v: d.represent_sequence("tag:yaml.org,2002:seq", v, flow_style=True)
)
_Dumper.add_representer(
    _FlowMap, lambda d, v: d.represent_mapping("tag:yaml.org,2002:map", v, flow_style=True)
)
_Dumper.add_representer(_Literal, lambda d, v: d.represent_scalar(STR_TAG, v, style="|"))


def _dump_terms(
    var: Variable, kind: str, input_names: Sequence[str], footprint: Footprint | None = None
) -> dict[str, Any]:
    labels = var.term_names
    lowers = {t.name: footprint.lower(var.name, t.name) for t in var.terms} if footprint else {}
    if (
        len(labels) >= 2
        and math.isfinite(var.low)
        and math.isfinite(var.high)
        and not any(lowers.values())
    ):
        default_ends = "shoulder" if kind == "input" else "triangle"
        for ends in (default_ends, *(e for e in PARTITION_ENDS if e != default_ends)):
            if partition_terms(labels, var.low, var.high, ends) == var.terms:
                spec: dict[str, Any] = {"partition": "triangular", "labels": _Flow(labels)}
                if ends != default_ends:
                    spec["ends"] = ends
                return _FlowMap(spec)
    out: dict[str, Any] = {}
    for t in var.terms:
        lower = lowers.get(t.name)
        if lower is None:
            out[t.name] = _FlowMap(_term_spec(t, input_names))
            continue
        lspec = _term_spec(lower.shape, input_names)
        if lower.scale != 1.0:
            lspec["scale"] = float(lower.scale)
        out[t.name] = {
            "upper": _FlowMap(_term_spec(t, input_names)),
            "lower": _FlowMap(lspec),
        }
    return out


def _term_spec(t: Term, input_names: Sequence[str]) -> dict[str, Any]:
    spec: dict[str, Any] = {"shape": t.shape}
    if t.shape == "linear" and len(t.params) == len(input_names) + 1:
        spec["coefficients"] = _FlowMap(zip(input_names, map(float, t.params[:-1]), strict=True))
        spec["constant"] = float(t.params[-1])
    elif shape(t.shape).piecewise_linear:  # an unregistered shape raises
        spec["points"] = _Flow(float(x) for x in t.params)
    else:
        spec.update(zip(shape(t.shape).params, map(float, t.params), strict=True))
    return spec


def _dump_expression(expr: Expression) -> dict[str, Any]:
    if isinstance(expr, Proposition):
        return {expr.variable: {"not": expr.term} if expr.negated else expr.term}
    flat = expr.op == "and" and all(isinstance(o, Proposition) for o in expr.operands)
    names = [o.variable for o in expr.operands if isinstance(o, Proposition)]
    if flat and len(set(names)) == len(names) and len(names) >= 2:
        merged: dict[str, Any] = {}
        for o in expr.operands:
            merged.update(_dump_expression(o))
        return merged
    return {expr.op: [_dump_expression(o) for o in expr.operands]}


def _table_rules(
    table: RuleTable, rows: Sequence[str], cols: Sequence[str], grid: dict[tuple[str, str], str]
) -> tuple[Rule, ...]:
    return tuple(
        Rule(
            Compound("and", (Proposition(table.rows, r), Proposition(table.columns, c))),
            (Consequent(table.output, grid[r, c]),),
        )
        for r in rows
        for c in cols
        if (r, c) in grid
    )


def _dump_table(rb: RuleBase) -> dict[str, Any] | None:
    """The table form of ``rb.rules`` if they are exactly ``rb.table``, else ``None``."""
    t = rb.table
    if t is None:
        return None
    try:
        row_var, col_var = rb.input(t.rows), rb.input(t.columns)
    except KeyError:
        return None
    grid: dict[tuple[str, str], str] = {}
    seen_rows: list[str] = []
    seen_cols: list[str] = []
    for rule in rb.rules:
        a = rule.antecedent
        if not (
            isinstance(a, Compound)
            and a.op == "and"
            and len(a.operands) == 2
            and rule.weight == 1.0
            and len(rule.consequents) == 1
            and rule.consequents[0].variable == t.output
        ):
            return None
        r, c = a.operands
        if not (
            isinstance(r, Proposition)
            and isinstance(c, Proposition)
            and r.variable == t.rows
            and c.variable == t.columns
            and not r.negated
            and not c.negated
            and r.term in row_var.term_names
            and c.term in col_var.term_names
            and (r.term, c.term) not in grid
        ):
            return None
        grid[r.term, c.term] = rule.consequents[0].term
        seen_rows.append(r.term)
        seen_cols.append(c.term)
    row_orders = [
        list(row_var.term_names),
        list(dict.fromkeys(seen_rows + list(row_var.term_names))),
    ]
    col_orders = [
        list(col_var.term_names),
        list(dict.fromkeys(seen_cols + list(col_var.term_names))),
    ]
    for rows in row_orders:
        for cols in col_orders:
            if _table_rules(t, rows, cols, grid) != rb.rules:
                continue
            cells = [[grid.get((r, c), EMPTY_CELL) for c in cols] for r in rows]
            width = max(len(x) for row in cells for x in row)
            text = "\n".join(" ".join(x.ljust(width) for x in row).rstrip() for row in cells)
            spec: dict[str, Any] = {"rows": t.rows, "columns": t.columns, "output": t.output}
            if rows != list(row_var.term_names):
                spec["row_labels"] = _Flow(rows)
            if cols != list(col_var.term_names):
                spec["column_labels"] = _Flow(cols)
            spec["cells"] = _Literal(text + "\n")
            return {"table": spec}
    return None


#: Stands in for a range that gets a comment; a plain YAML word no rule base has as a range.
_NOTED_RANGE = "fuzzkit_noted_range_{}"


def dump(rb: RuleBase, range_notes: Mapping[str, str] | None = None) -> str:
    """The YAML text of ``rb``; ``loads_rulebase(dump(rb)) == rb`` for every valid model.

    Partitions are written back as the ``partition`` shorthand when the terms are exactly one,
    and the rules as a table when ``rb.table`` is set and the rules are exactly that table.
    ``range_notes`` maps variable names to a comment written after their range (an importer
    saying where a range came from).

    Raises
    ------
    RuleBaseError
        A condition nests deeper than the readers accept
        (:data:`~fuzzkit.fuzzy.validation.MAX_CONDITION_DEPTH`).
    """
    too_deep = validation.depth_problems(rb)
    if too_deep:
        raise RuleBaseError(validation.as_problems(rb, too_deep))
    notes = {name: " ".join(note.split()) for name, note in (range_notes or {}).items()}
    noted: dict[str, str] = {}
    doc: dict[str, Any] = {"name": rb.name}
    if rb.description:
        doc["description"] = rb.description
    for kind, group in (("input", rb.inputs), ("output", rb.outputs)):
        section: dict[str, Any] = {}
        for var in group:
            spec: dict[str, Any] = {"range": _Flow([float(var.low), float(var.high)])}
            if var.name in notes:
                # PyYAML writes no comments: a placeholder, replaced in the text below
                flow = yaml.dump(spec["range"], Dumper=_Dumper, width=100).strip()
                key = _NOTED_RANGE.format(len(noted))
                noted[key] = f"{flow}  # {notes[var.name]}"
                spec["range"] = key
            if var.units is not None:
                spec["units"] = var.units
            if kind == "output" and var.default is not None:
                spec["default"] = float(var.default)
            spec["terms"] = _dump_terms(var, kind, rb.input_names, footprint_of(rb))
            section[var.name] = spec
        doc[kind + "s"] = section
    ops = rb.operators
    doc["operators"] = _FlowMap(
        {
            "and": ops.and_,
            "or": ops.or_,
            "implication": ops.implication,
            "aggregation": ops.aggregation,
        }
    )
    doc["defuzzifier"] = rb.defuzzifier
    doc["out_of_range"] = rb.out_of_range
    if rb.coverage != "strict":
        doc["coverage"] = rb.coverage
    footprint = footprint_of(rb)
    if footprint is not None:
        doc["type_reduction"] = footprint.type_reduction
        if footprint.resolution is not None:
            doc["resolution"] = footprint.resolution
    table = _dump_table(rb)
    if table is not None:
        doc["rules"] = table
    else:
        rules: list[Any] = []
        for rule in rb.rules:
            item: dict[str, Any] = {
                "if": _dump_expression(rule.antecedent),
                "then": {c.variable: c.term for c in rule.consequents},
            }
            if rule.weight != 1.0:
                item["weight"] = float(rule.weight)
            rules.append(_FlowMap(item))
        doc["rules"] = rules
    text = yaml.dump(doc, Dumper=_Dumper, sort_keys=False, allow_unicode=True, width=100)
    for key, value in noted.items():
        text = text.replace(f"range: {key}\n", f"range: {value}\n")
    return text
