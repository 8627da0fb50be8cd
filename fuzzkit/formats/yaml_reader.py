"""Rule-base YAML -> model: strict loading with every problem located.

The format is documented in ``docs/rulebase-format.md``. The document is composed by
:mod:`fuzzkit.located_yaml` (the hardened reader every fuzzkit YAML file goes through: size
and alias limits, control characters, duplicate and boolean keys), then converted by hand so
that every problem, from an unknown key to an uncovered input range, is reported as
``file:line:col: message`` and all of them are raised together in one
:class:`~fuzzkit.errors.RuleBaseError`.

Semantic checks live in :mod:`fuzzkit.fuzzy.validation` (shared with the engines); this module
maps the logical paths that :func:`fuzzkit.fuzzy.validation.check` returns back to YAML
positions. It is about 1,050 lines because it is one walker: variables, terms, rules and the rule
table all record into the same marks and hidden paths that place every semantic problem, so
they stay in one class; the generic YAML layer is :mod:`fuzzkit.located_yaml`. The writer is
:mod:`fuzzkit.formats.yaml_writer`, the schema :mod:`fuzzkit.formats.schema`.

Examples
--------
>>> rb = loads_rulebase(open("rulebases/macvicar_whelan.yaml").read())  # doctest: +SKIP
"""

from __future__ import annotations

import functools
import hashlib
import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path as FsPath

import yaml
from yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode

from fuzzkit.errors import Location, Problem, RuleBaseError, did_you_mean
from fuzzkit.fuzzy import validation
from fuzzkit.fuzzy.model import (
    PIECEWISE_LINEAR_SHAPES,
    SHAPE_PARAMS,
    Compound,
    Consequent,
    Expression,
    Operators,
    Proposition,
    Rule,
    RuleBase,
    RuleTable,
    Source,
    Term,
    Variable,
)
from fuzzkit.fuzzy.partition import PARTITION_ENDS, PARTITION_KINDS, partition_terms
from fuzzkit.fuzzy.type2_model import (
    DEFAULT_TYPE_REDUCTION,
    MAX_RESOLUTION,
    Footprint,
    LowerTerm,
    with_footprint,
)
from fuzzkit.fuzzy.validation import Path
from fuzzkit.located_yaml import (
    BOOL_TAG,
    FLOAT_TAG,
    INT_TAG,
    NULL_TAG,
    STR_TAG,
    DocumentKind,
    NodeReader,
    compose_document,
    describe,
    read_document,
)

TOP_KEYS = (
    "name",
    "description",
    "inputs",
    "outputs",
    "operators",
    "defuzzifier",
    "out_of_range",
    "coverage",
    "type_reduction",
    "resolution",
    "rules",
)
IT2_TERM_KEYS = ("upper", "lower")
OPERATOR_KEYS = ("and", "or", "implication", "aggregation")
PARTITION_KEYS = ("partition", "labels", "ends")
TABLE_KEYS = ("rows", "columns", "output", "cells", "row_labels", "column_labels")
RULE_KEYS = ("if", "then", "weight")
CONNECTIVES = ("and", "or", "not")
EMPTY_CELL = "-"


def shape_param_keys(shape: str) -> tuple[str, ...]:
    """The keys holding a shape's parameters in YAML: ``points`` or the parameter names."""
    return ("points",) if shape in PIECEWISE_LINEAR_SHAPES else SHAPE_PARAMS[shape]


def _is_it2(node: Node) -> bool:
    """A term written as ``{upper: ..., lower: ...}`` (either key makes it one)."""
    return isinstance(node, MappingNode) and any(
        isinstance(k, ScalarNode) and k.value in IT2_TERM_KEYS for k, _ in node.value
    )


@dataclass
class _Reader(NodeReader):
    """Converts one composed YAML document into a model, collecting located problems."""

    #: logical path (see fuzzkit.fuzzy.validation) -> node whose position names it
    marks: dict[Path, Node] = field(default_factory=dict)
    #: semantic problems under these paths are consequences of a reported structural one
    hidden_under: set[Path] = field(default_factory=set)
    #: semantic problems exactly at these paths are unreliable (e.g. coverage of a bad range)
    hidden_at: set[Path] = field(default_factory=set)
    broken_vars: set[str] = field(default_factory=set)
    #: the inputs' names in order, once read (linear Sugeno terms name their coefficients)
    input_names: list[str] = field(default_factory=list)
    #: the lower functions of interval type-2 terms, as read
    lowers: list[LowerTerm] = field(default_factory=list)

    def choice(self, node: Node, what: str, path: Path) -> str | None:
        """A name whose allowed values validation checks; records where it is."""
        self.marks[path] = node
        value = self.name(node, what)
        if value is None:
            self.hidden_under.add(path)
        return value

    # ------------------------------------------------------------------ document

    def rule_base(self, root: Node) -> RuleBase | None:
        entries = self.mapping(root, "a rule base (a mapping)")
        if entries is None:
            return None
        self.keys(entries, root, TOP_KEYS, ("name", "inputs", "outputs", "rules"), "the rule base")
        self.marks[()] = root

        name = "rulebase"
        if "name" in entries:
            got = self.choice(entries["name"][1], "the rule-base name (an identifier)", ("name",))
            name = got if got is not None else name
        else:
            self.hidden_under.add(("name",))

        description = ""
        if "description" in entries:
            description = self.text(entries["description"][1], "a description") or ""

        inputs = self.variables(entries, "input", root)
        self.input_names = [v.name for v in inputs]
        outputs = self.variables(entries, "output", root)

        ops = Operators()
        if "operators" in entries:
            onode = entries["operators"][1]
            self.marks[("operators",)] = onode
            omap = self.mapping(onode, "operators as a mapping {and: ..., or: ...}")
            if omap is not None:
                self.keys(omap, onode, OPERATOR_KEYS, (), "operators")
                chosen = {
                    key: self.choice(
                        omap[key][1],
                        f"an {key} operator name"
                        if key[0] in "aeiou"
                        else f"a {key} operator name",
                        ("operators", key),
                    )
                    for key in OPERATOR_KEYS
                    if key in omap
                }
                ops = Operators(
                    and_=chosen.get("and") or ops.and_,
                    or_=chosen.get("or") or ops.or_,
                    implication=chosen.get("implication") or ops.implication,
                    aggregation=chosen.get("aggregation") or ops.aggregation,
                )

        defuzzifier = "centroid"
        if "defuzzifier" in entries:
            defuzzifier = (
                self.choice(entries["defuzzifier"][1], "a defuzzifier name", ("defuzzifier",))
                or defuzzifier
            )
        out_of_range = "clamp"
        if "out_of_range" in entries:
            out_of_range = (
                self.choice(entries["out_of_range"][1], "an out_of_range policy", ("out_of_range",))
                or out_of_range
            )

        coverage = "strict"
        if "coverage" in entries:
            coverage = (
                self.choice(entries["coverage"][1], "a coverage policy", ("coverage",)) or coverage
            )

        footprint = self.footprint(entries)

        rules: list[Rule] = []
        table: RuleTable | None = None
        if "rules" in entries:
            rules, table = self.rules(entries["rules"][1], inputs, outputs)
        else:
            self.hidden_at.add(("rules",))

        rb = RuleBase(
            name=name,
            inputs=tuple(inputs),
            outputs=tuple(outputs),
            rules=tuple(rules),
            operators=ops,
            defuzzifier=defuzzifier,
            out_of_range=out_of_range,
            description=description,
            table=table,
            coverage=coverage,
        )
        if footprint is not None:
            return with_footprint(rb, footprint)
        return rb

    def footprint(self, entries: dict[str, tuple[Node, Node]]) -> Footprint | None:
        """The IT2 part: the lower terms read, ``type_reduction:`` and ``resolution:``."""
        if not self.lowers and "type_reduction" not in entries and "resolution" not in entries:
            return None
        method = DEFAULT_TYPE_REDUCTION
        if "type_reduction" in entries:
            method = (
                self.choice(
                    entries["type_reduction"][1], "a type-reduction method", ("type_reduction",)
                )
                or method
            )
        resolution: int | None = None
        if "resolution" in entries:
            rnode = entries["resolution"][1]
            self.marks[("resolution",)] = rnode
            if not (isinstance(rnode, ScalarNode) and rnode.tag == NULL_TAG):
                resolution = self.integer(
                    rnode, "the output resolution (samples per output range)", 2, MAX_RESOLUTION
                )
        return Footprint(tuple(self.lowers), method, resolution)

    # ------------------------------------------------------------------ variables

    def variables(
        self, entries: dict[str, tuple[Node, Node]], kind: str, root: Node
    ) -> list[Variable]:
        group = kind + "s"
        if group not in entries:
            self.hidden_under.add((group,))
            return []
        node = entries[group][1]
        self.marks[(group,)] = node
        vmap = self.mapping(node, f"the {group} (a mapping of name to {{range, terms}})")
        if vmap is None:
            self.hidden_under.add((group,))
            return []
        return [self.variable(name, knode, vnode, kind) for name, (knode, vnode) in vmap.items()]

    def variable(self, name: str, knode: Node, vnode: Node, kind: str) -> Variable:
        base: Path = (kind + "s", name)
        self.marks[base] = knode
        what = f"{kind} {name!r}"
        entries = self.mapping(vnode, f"{what} as a mapping {{range: [low, high], terms: ...}}")
        if entries is None:
            self.hidden_under.add(base)
            self.broken_vars.add(name)
            return Variable(name, 0.0, 1.0, ())
        allowed = (
            ("range", "terms", "units", "default")
            if kind == "output"
            else ("range", "terms", "units")
        )
        for key, (kn, _) in entries.items():
            if key == "default" and kind == "input":
                self.error(
                    kn, "'default' is only allowed on outputs (the value used when no rule fires)"
                )
        self.keys(
            {k: v for k, v in entries.items() if not (k == "default" and kind == "input")},
            vnode,
            allowed,
            ("range", "terms"),
            what,
        )

        low, high = 0.0, 1.0
        range_ok = False
        if "range" in entries:
            rnode = entries["range"][1]
            self.marks[(*base, "range")] = rnode
            got = self.range(rnode, what)
            if got is not None:
                low, high = got
                range_ok = math.isfinite(low) and math.isfinite(high) and low < high
            else:
                self.hidden_under.add((*base, "range"))
        else:
            self.hidden_under.add((*base, "range"))
        if not range_ok:
            # Coverage and default-in-range are meaningless without a valid range.
            self.hidden_at.update({(*base, "terms"), (*base, "default")})

        terms: tuple[Term, ...] = ()
        if "terms" in entries:
            terms = self.terms(entries["terms"][1], base, kind, low, high, range_ok)
        else:
            self.broken_vars.add(name)
            self.hidden_under.add((*base, "terms"))

        default: float | None = None
        if "default" in entries and kind == "output":
            dnode = entries["default"][1]
            self.marks[(*base, "default")] = dnode
            if not (isinstance(dnode, ScalarNode) and dnode.tag == NULL_TAG):
                default = self.number(dnode, f"the default of {what}")
        units: str | None = None
        if "units" in entries:
            self.marks[(*base, "units")] = entries["units"][1]
            units = self.units(entries["units"][1], what)
        return Variable(name, low, high, terms, default, units)

    def units(self, node: Node, what: str) -> str | None:
        """The ``units:`` of a variable as written (``None`` for null or a non-string)."""
        if isinstance(node, ScalarNode) and node.tag == NULL_TAG:
            return None
        if not (isinstance(node, ScalarNode) and node.tag == STR_TAG):
            hint = ""
            if isinstance(node, ScalarNode) and node.tag in (INT_TAG, FLOAT_TAG, BOOL_TAG):
                hint = "; quote it"
            self.error(
                node,
                f"expected the units of {what} as text such as 'N' or 'mm', "
                f"got {describe(node)}{hint}",
            )
            return None
        return str(node.value)  # its content is checked by validation (path ..., "units")

    def range(self, node: Node, what: str) -> tuple[float, float] | None:
        if not isinstance(node, SequenceNode) or len(node.value) != 2:
            shown = f"{len(node.value)} items" if isinstance(node, SequenceNode) else describe(node)
            self.error(node, f"expected the range of {what} as [low, high], got {shown}")
            return None
        low = self.number(node.value[0], f"the low end of the range of {what}")
        high = self.number(node.value[1], f"the high end of the range of {what}")
        if low is None or high is None:
            return None
        return low, high

    def terms(
        self, node: Node, base: Path, kind: str, low: float, high: float, range_ok: bool
    ) -> tuple[Term, ...]:
        tpath: Path = (*base, "terms")
        self.marks[tpath] = node
        var = base[1]
        entries = self.mapping(
            node,
            f"the terms of {kind} {var!r} as a mapping of label to {{shape: ...}}, or a partition",
        )
        if entries is None:
            self.hidden_under.add(tpath)
            self.broken_vars.add(str(var))
            return ()
        if "partition" in entries:
            return self.partition(entries, node, base, kind, low, high, range_ok)
        return tuple(
            self.it2_term(label, kn, vn, (*tpath, label))
            if _is_it2(vn)
            else self.term(label, kn, vn, (*tpath, label))
            for label, (kn, vn) in entries.items()
        )

    def it2_term(self, label: str, knode: Node, vnode: Node, tpath: Path) -> Term:
        """An interval type-2 term ``{upper: {...}, lower: {..., scale: s}}``: the upper term
        is returned, the lower one (with its scale) recorded in :attr:`lowers`."""
        entries = self.mapping(vnode, f"term {label!r} as a mapping {{upper: ..., lower: ...}}")
        self.marks[tpath] = knode
        placeholder = Term(label, "triangle", (0.0, 0.5, 1.0))
        if entries is None:  # pragma: no cover - _is_it2 saw a mapping
            return placeholder
        self.keys(entries, vnode, IT2_TERM_KEYS, IT2_TERM_KEYS, f"interval type-2 term {label!r}")
        if "upper" not in entries or "lower" not in entries:
            self.hidden_under.add(tpath)
            self.hidden_at.add(tpath[:-1])
            return placeholder
        upper = self.term(label, *entries["upper"], (*tpath, "upper"))
        lkey, lnode = entries["lower"]
        lower_entries = self.mapping(lnode, f"the lower term of {label!r} as a mapping")
        scale = 1.0
        if lower_entries is None:
            self.hidden_under.add(tpath)
            return upper
        if "scale" in lower_entries:
            snode = lower_entries["scale"][1]
            self.marks[(*tpath, "lower", "scale")] = snode
            got = self.number(snode, f"the scale (height) of the lower term of {label!r}")
            if got is None:
                self.hidden_under.add((*tpath, "lower", "scale"))
            scale = 1.0 if got is None else got
        if not isinstance(lnode, MappingNode):  # pragma: no cover - mapping() accepted it
            return upper
        kept = [
            (k, v) for k, v in lnode.value if not (isinstance(k, ScalarNode) and k.value == "scale")
        ]
        shape_node = MappingNode(lnode.tag, kept, lnode.start_mark, lnode.end_mark)
        lower = self.term(label, lkey, shape_node, (*tpath, "lower"))
        self.marks[tpath] = knode
        self.lowers.append(LowerTerm(str(tpath[1]), label, lower, scale))
        return upper

    def partition(
        self,
        entries: dict[str, tuple[Node, Node]],
        node: Node,
        base: Path,
        kind: str,
        low: float,
        high: float,
        range_ok: bool,
    ) -> tuple[Term, ...]:
        tpath: Path = (*base, "terms")
        what = f"the partition of {kind} {base[1]!r}"
        self.keys(entries, node, PARTITION_KEYS, ("partition", "labels"), what)
        pnode = entries["partition"][1]
        got = self.name(pnode, "a partition kind")
        if got is not None and got not in PARTITION_KINDS:
            self.error(
                pnode,
                f"unknown partition {got!r}{did_you_mean(got, PARTITION_KINDS)}; "
                f"expected one of {', '.join(PARTITION_KINDS)}",
            )
        ends = "shoulder" if kind == "input" else "triangle"
        if "ends" in entries:
            enode = entries["ends"][1]
            e = self.name(enode, "partition ends (shoulder or triangle)")
            if e is not None and e not in PARTITION_ENDS:
                self.error(
                    enode,
                    f"unknown partition ends {e!r}{did_you_mean(e, PARTITION_ENDS)}"
                    f"; expected one of {', '.join(PARTITION_ENDS)}",
                )
            elif e is not None:
                ends = e
        labels: list[str] = []
        if "labels" in entries:
            lnode = entries["labels"][1]
            items = self.sequence(lnode, "partition labels")
            for item in items or []:
                label = self.name(item, "a label name")
                if label is not None:
                    labels.append(label)
                    self.marks[(*tpath, label)] = item
            if items is not None and len(items) < 2:
                self.error(lnode, f"a partition needs at least 2 labels, got {len(items)}")
                self.broken_vars.add(str(base[1]))
                self.hidden_at.add(tpath)
                return ()
            if items is None or len(labels) != len(items):
                self.broken_vars.add(str(base[1]))
        else:
            self.broken_vars.add(str(base[1]))
            self.hidden_at.add(tpath)
            return ()
        if not range_ok:
            low, high = 0.0, 1.0  # placeholder: the range problem is reported already
        return partition_terms(labels, low, high, ends)

    def term(self, label: str, knode: Node, vnode: Node, tpath: Path) -> Term:
        self.marks[tpath] = knode
        coverage = tpath[:-1]
        entries = self.mapping(vnode, f"term {label!r} as a mapping {{shape: ..., ...}}")
        if entries is None:
            self.hidden_under.add(tpath)
            self.hidden_at.add(coverage)
            return Term(label, "triangle", (0.0, 0.5, 1.0))
        if "shape" not in entries:
            self.error(
                vnode,
                f"missing required key 'shape' in term {label!r}; expected one of "
                f"{', '.join(SHAPE_PARAMS)}",
            )
            self.hidden_under.add(tpath)
            self.hidden_at.add(coverage)
            return Term(label, "triangle", (0.0, 0.5, 1.0))
        snode = entries["shape"][1]
        self.marks[(*tpath, "shape")] = snode
        shape = self.name(snode, "a shape name")
        if shape is None or shape not in SHAPE_PARAMS:
            # validation reports the unknown shape with a did-you-mean; no parameters to read.
            if shape is None:
                self.hidden_under.add(tpath)
            self.hidden_at.add(coverage)
            return Term(label, shape or "triangle", ())
        param_keys = shape_param_keys(shape)
        self.keys(
            entries,
            vnode,
            ("shape", *param_keys),
            ("shape", *param_keys),
            f"{shape} term {label!r}",
        )
        params: list[float] = []
        if shape == "linear":
            return Term(label, shape, self.linear(entries, tpath))
        if shape in PIECEWISE_LINEAR_SHAPES:
            if "points" not in entries:
                self.hidden_under.add(tpath)
                self.hidden_at.add(coverage)
                return Term(label, shape, (math.nan,) * len(SHAPE_PARAMS[shape]))
            pnode = entries["points"][1]
            self.marks[(*tpath, "points")] = pnode
            items = self.sequence(pnode, f"the points of term {label!r}")
            values = [self.number(i, f"a point of term {label!r}") for i in items or []]
            if items is None or any(v is None for v in values):
                self.hidden_under.add((*tpath, "points"))
                self.hidden_at.add(coverage)
                return Term(label, shape, (math.nan,) * len(SHAPE_PARAMS[shape]))
            params = [v for v in values if v is not None]
        else:
            for key in param_keys:
                value: float | None = None
                if key in entries:
                    self.marks[(*tpath, key)] = entries[key][1]
                    value = self.number(entries[key][1], f"{key} of term {label!r}")
                if value is None:
                    self.hidden_under.add((*tpath, key))
                    self.hidden_at.add(coverage)
                    value = 1.0
                params.append(value)
        return Term(label, shape, tuple(params))

    def linear(self, entries: dict[str, tuple[Node, Node]], tpath: Path) -> tuple[float, ...]:
        """A linear Sugeno term's parameters: coefficients in input order, then the constant.

        ``coefficients`` is a mapping of input name to coefficient (inputs left out have 0) or
        a list in the rule base's input order; ``constant`` is the constant term.
        """
        label = tpath[-1]
        n = len(self.input_names)
        coefs: list[float] = [0.0] * n
        ok = True
        if "coefficients" in entries:
            cnode = entries["coefficients"][1]
            self.marks[(*tpath, "coefficients")] = cnode
            if isinstance(cnode, SequenceNode):
                values = [self.number(i, f"a coefficient of term {label!r}") for i in cnode.value]
                if any(v is None for v in values):
                    ok = False
                elif len(values) != n:
                    self.error(
                        cnode,
                        f"linear term {label!r} has {len(values)} coefficient(s), expected {n} "
                        f"(one per input, in order: {', '.join(self.input_names)})",
                    )
                    ok = False
                else:
                    coefs = [v for v in values if v is not None]
            else:
                cmap = self.mapping(
                    cnode,
                    f"the coefficients of term {label!r} as a mapping {{input: number}} or a "
                    "list in input order",
                )
                if cmap is None:
                    ok = False
                for name, (kn, vn) in (cmap or {}).items():
                    if name not in self.input_names:
                        self.error(
                            kn,
                            f"unknown input {name!r} in the coefficients of term {label!r}"
                            f"{did_you_mean(name, self.input_names)}; expected one of "
                            f"{', '.join(self.input_names) or '(none)'}",
                        )
                        ok = False
                        continue
                    value = self.number(vn, f"the coefficient of {name!r} in term {label!r}")
                    if value is None:
                        ok = False
                    else:
                        coefs[self.input_names.index(name)] = value
        constant = 0.0
        if "constant" in entries:
            self.marks[(*tpath, "constant")] = entries["constant"][1]
            got = self.number(entries["constant"][1], f"the constant of term {label!r}")
            ok = ok and got is not None
            constant = got if got is not None else 0.0
        if not ok:
            self.hidden_under.add(tpath)
        return (*coefs, constant)

    # ------------------------------------------------------------------ rules

    def rules(
        self, node: Node, inputs: list[Variable], outputs: list[Variable]
    ) -> tuple[list[Rule], RuleTable | None]:
        self.marks[("rules",)] = node
        if isinstance(node, SequenceNode):
            rules: list[Rule] = []
            for item in node.value:
                rule = self.rule(item, len(rules))
                if rule is None:
                    self.hidden_at.add(("rules",))
                else:
                    rules.append(rule)
            return rules, None
        if isinstance(node, MappingNode):
            entries = self.mapping(node, "rules as a list or {table: ...}")
            if entries is not None:
                self.keys(entries, node, ("table",), ("table",), "rules (a list, or {table: ...})")
                if "table" in entries:
                    return self.table(entries["table"][1], inputs, outputs)
            self.hidden_at.add(("rules",))
            return [], None
        self.error(
            node,
            f"expected rules as a list of {{if: ..., then: ...}} or as "
            f"{{table: ...}}, got {describe(node)}",
        )
        self.hidden_at.add(("rules",))
        return [], None

    def rule(self, node: Node, k: int) -> Rule | None:
        entries = self.mapping(node, "a rule as a mapping {if: ..., then: ..., weight: ...}")
        if entries is None:
            return None
        self.keys(entries, node, RULE_KEYS, ("if", "then"), "a rule")
        if "if" not in entries or "then" not in entries:
            return None
        base: Path = ("rules", k)
        self.marks[base] = node
        antecedent = self.expression(entries["if"][1], (*base, "if"))
        consequents: list[Consequent] = []
        tnode = entries["then"][1]
        self.marks[(*base, "then")] = tnode
        tmap = self.mapping(tnode, "then as a mapping {output: label, ...}")
        if tmap is None:
            self.hidden_under.add((*base, "then"))
            consequents.append(Consequent("?", "?"))
        else:
            for j, (out, (kn, vn)) in enumerate(tmap.items()):
                self.marks[(*base, "then", j)] = kn
                self.marks[(*base, "then", j, "label")] = vn
                label = self.name(vn, f"a label of output {out!r}")
                if label is None or out in self.broken_vars:
                    self.hidden_under.add((*base, "then", j))
                consequents.append(Consequent(out, label or "?"))
        weight = 1.0
        if "weight" in entries:
            wnode = entries["weight"][1]
            self.marks[(*base, "weight")] = wnode
            w = self.number(wnode, "the rule weight")
            weight = 1.0 if w is None else w
        return Rule(antecedent, tuple(consequents), weight)

    def expression(self, node: Node, path: Path) -> Expression:
        """A condition; on a structural problem a placeholder whose checks are hidden."""
        self.marks[path] = node
        placeholder = Proposition("?", "?")
        entries = self.mapping(
            node, "a condition such as {e: PS}, {and: [...]}, {or: [...]} or {not: {e: PS}}"
        )
        if entries is None:
            self.hidden_under.add(path)
            return placeholder
        if not entries:
            self.error(node, "expected a condition such as {e: PS}, got an empty mapping")
            self.hidden_under.add(path)
            return placeholder
        many = len(entries) > 1
        parts: list[Expression] = []
        for i, (key, (kn, vn)) in enumerate(entries.items()):
            sub: Path = (*path, i) if many else path
            self.marks[sub] = kn
            parts.append(self.entry(key, kn, vn, sub))
        return Compound("and", tuple(parts)) if many else parts[0]

    def entry(self, key: str, knode: Node, vnode: Node, path: Path) -> Expression:
        placeholder = Proposition("?", "?")
        if key in ("and", "or"):
            items = self.sequence(vnode, f"the operands of {key!r}")
            if items is None:
                self.hidden_under.add(path)
                return placeholder
            operands = tuple(self.expression(item, (*path, i)) for i, item in enumerate(items))
            self.marks[path] = knode
            return Compound("and" if key == "and" else "or", operands)
        if key == "not":
            inner = self.mapping(vnode, "the operand of 'not' as a mapping {variable: label}")
            if inner is None:
                self.hidden_under.add(path)
                return placeholder
            if len(inner) != 1 or next(iter(inner)) in CONNECTIVES:
                self.error(
                    vnode,
                    "'not' applies to one condition {variable: label}, got "
                    f"{describe(vnode)} with {len(inner)} entries; negate each "
                    "operand instead (De Morgan)"
                    if len(inner) != 1
                    else "'not' applies to one condition {variable: label}, not to "
                    "and/or; negate each operand instead (De Morgan)",
                )
                self.hidden_under.add(path)
                return placeholder
            var, (_, lnode) = next(iter(inner.items()))
            self.marks[(*path, "label")] = lnode
            label = self.name(lnode, f"a label of input {var!r}")
            return self.proposition(var, label, True, path)
        negated = False
        lnode = vnode
        if isinstance(vnode, MappingNode):
            inner = self.mapping(vnode, f"a label or {{not: label}} for input {key!r}")
            if inner is None or list(inner) != ["not"]:
                self.error(
                    vnode,
                    f"expected a label or {{not: label}} for input {key!r}, got "
                    f"a mapping with keys {', '.join(map(repr, inner or {}))}",
                )
                self.hidden_under.add(path)
                return placeholder
            lnode = inner["not"][1]
            negated = True
        self.marks[(*path, "label")] = lnode
        label = self.name(lnode, f"a label of input {key!r}")
        return self.proposition(key, label, negated, path)

    def proposition(self, var: str, label: str | None, negated: bool, path: Path) -> Expression:
        if label is None or var in self.broken_vars:
            self.hidden_under.add(path)
        return Proposition(var, label or "?", negated)

    def table(
        self, node: Node, inputs: list[Variable], outputs: list[Variable]
    ) -> tuple[list[Rule], RuleTable | None]:
        entries = self.mapping(node, "a rule table as a mapping {rows, columns, output, cells}")
        if entries is None:
            self.hidden_at.add(("rules",))
            return [], None
        self.keys(entries, node, TABLE_KEYS, ("rows", "columns", "cells"), "the rule table")
        names: dict[str, str | None] = {}
        for key in ("rows", "columns", "output"):
            if key in entries:
                names[key] = self.choice(
                    entries[key][1],
                    f"an {key[:-1]} name" if key != "output" else "an output name",
                    ("rules", "table", key),
                )
        if "output" not in entries:
            if len(outputs) == 1:
                names["output"] = outputs[0].name
            else:
                self.error(
                    node,
                    "missing required key 'output' in the rule table (the rule "
                    f"base has {len(outputs)} outputs)",
                )
        rows, cols, out = names.get("rows"), names.get("columns"), names.get("output")
        if rows is None or cols is None or out is None:
            self.hidden_at.add(("rules",))
            return [], None
        table = RuleTable(rows, cols, out)
        row_var = next((v for v in inputs if v.name == rows), None)
        col_var = next((v for v in inputs if v.name == cols), None)
        row_labels = self.header(entries, "row_labels", row_var)
        col_labels = self.header(entries, "column_labels", col_var)
        if (
            row_labels is None
            or col_labels is None
            or "cells" not in entries
            or rows in self.broken_vars
            or cols in self.broken_vars
        ):
            self.hidden_at.add(("rules",))
            return [], table
        grid = self.cells(entries["cells"][1], len(row_labels), len(col_labels), rows, cols)
        if grid is None:
            self.hidden_at.add(("rules",))
            return [], table
        if not grid.ok:
            # the shape is wrong, so cells cannot be paired with labels; still report every
            # cell that names no label of the output (a typo beside a short row)
            self.cell_label_typos(grid.rows, next((v for v in outputs if v.name == out), None))
            self.hidden_at.add(("rules",))
            return [], table
        rules: list[Rule] = []
        for (rlabel, rnode), row in zip(row_labels, grid.rows, strict=True):
            for (clabel, cnode), (cell, cell_loc) in zip(col_labels, row, strict=True):
                # validation reports an empty cell no other rule covers at the cell itself
                self.marks[("rules", "table", "cells", rlabel, clabel)] = cell_loc
                if cell == EMPTY_CELL:
                    continue
                k = len(rules)
                self.marks[("rules", k)] = cell_loc
                self.marks[("rules", k, "if", 0)] = rnode
                self.marks[("rules", k, "if", 1)] = cnode
                self.marks[("rules", k, "if", 0, "label")] = rnode
                self.marks[("rules", k, "if", 1, "label")] = cnode
                rules.append(
                    Rule(
                        Compound("and", (Proposition(rows, rlabel), Proposition(cols, clabel))),
                        (Consequent(out, cell),),
                    )
                )
        if out in self.broken_vars:
            self.hidden_under.update(("rules", k, "then") for k in range(len(rules)))
        return rules, table

    def header(
        self, entries: dict[str, tuple[Node, Node]], key: str, var: Variable | None
    ) -> list[tuple[str, Node]] | None:
        """Row or column labels in table order: given explicitly, or the variable's terms."""
        if key not in entries:
            if var is None:
                return None  # unknown variable: validation reports it at rows/columns
            anchor = entries["cells"][1] if "cells" in entries else None
            return [(t.name, anchor) for t in var.terms] if anchor is not None else None
        lnode = entries[key][1]
        items = self.sequence(lnode, f"{key} (labels in table order)")
        if items is None:
            return None
        labels: list[tuple[str, Node]] = []
        seen: set[str] = set()
        for item in items:
            label = self.name(item, "a label name")
            if label is None:
                return None
            if label in seen:
                self.error(item, f"duplicate label {label!r} in {key}")
                return None
            seen.add(label)
            labels.append((label, item))
        return labels

    def cell_label_typos(self, grid: list[list[tuple[str, Node]]], out: Variable | None) -> None:
        """A located problem for every cell of ``grid`` that is not a label of ``out``."""
        if out is None or out.name in self.broken_vars:
            return  # validation reports the unknown or broken output itself
        for row in grid:
            for cell, cell_loc in row:
                if cell != EMPTY_CELL and cell not in out.term_names:
                    self.error(
                        cell_loc,
                        f"unknown label {cell!r} for output {out.name!r}"
                        f"{did_you_mean(cell, out.term_names)}; expected one of "
                        f"{', '.join(out.term_names)} or {EMPTY_CELL} (no rule)",
                    )

    def cells(self, node: Node, nrows: int, ncols: int, rows: str, cols: str) -> _Grid | None:
        """The table body as rows of (label, node positioned at the cell), and whether its
        shape fits the labels (``None``: not a table body at all)."""
        lines: list[tuple[str, Callable[[int], Node]]] = []
        if isinstance(node, ScalarNode) and node.tag == STR_TAG:
            lines = self.block_lines(node)
        elif isinstance(node, SequenceNode):
            for item in node.value:
                row_text = self.text(item, "a table row (labels separated by spaces)")
                if row_text is None:
                    return None
                lines.append((row_text, self.cell_locator(item, quoted=item.style is not None)))
        else:
            self.error(
                node,
                "expected the cells as a block of rows (cells: |) or a list of row "
                f"strings, got {describe(node)}",
            )
            return None
        grid: list[list[tuple[str, Node]]] = []
        ok = True
        for text, locate in lines:
            row = [(m.group(), locate(m.start())) for m in re.finditer(r"\S+", text)]
            if len(row) != ncols:
                self.problems.append(
                    Problem(
                        self.loc(locate(0)),
                        f"table row {len(grid) + 1} has {len(row)} cells, expected {ncols} "
                        f"(one per label of columns input {cols!r})",
                    )
                )
                ok = False
            grid.append(row)
        if len(grid) != nrows:
            hint = ""
            if isinstance(node, ScalarNode) and node.style != "|":
                hint = "; write the cells as a literal block (cells: |) so each row keeps its line"
            self.error(
                node,
                f"table has {len(grid)} rows, expected {nrows} (one per label of "
                f"rows input {rows!r}){hint}",
            )
            ok = False
        return _Grid(grid, ok)

    def block_lines(self, node: ScalarNode) -> list[tuple[str, Callable[[int], Node]]]:
        """Non-blank lines of a string scalar, each with a function locating a column in it."""
        out: list[tuple[str, Callable[[int], Node]]] = []
        for i, line in enumerate(str(node.value).split("\n")):
            if not line.strip():
                continue
            if node.style == "|":
                src_no = node.start_mark.line + 1 + i
                src = self.lines[src_no] if src_no < len(self.lines) else ""
                indent = len(src.rstrip()) - len(line.rstrip())
                if line.strip() and src.rstrip().endswith(line.rstrip()) and indent >= 0:
                    out.append((line, self.cell_locator(node, line=src_no, column=indent)))
                    continue
            out.append((line, self.cell_locator(node)))
        return out

    def cell_locator(
        self,
        node: Node,
        *,
        quoted: bool = False,
        line: int | None = None,
        column: int | None = None,
    ) -> Callable[[int], Node]:
        """Position of column ``offset`` of a row: a stand-in node whose mark points there."""

        def locate(offset: int) -> Node:
            mark = node.start_mark
            if line is None:
                # Only single-line rows can be located exactly inside a plain or quoted scalar.
                same_line = node.end_mark.line == mark.line
                col = mark.column + (1 if quoted else 0) + offset if same_line else mark.column
                return _At(mark.line, col)
            return _At(line, (column or 0) + offset)

        return locate


@dataclass(frozen=True, slots=True)
class _Grid:
    """A rule table's cells as read, row by row, and whether rows and columns fit the labels."""

    rows: list[list[tuple[str, Node]]]
    ok: bool


class _At(Node):
    """A pseudo-node marking a position inside a scalar (a table cell)."""

    def __init__(self, line: int, column: int) -> None:
        mark = yaml.error.Mark("", 0, line, column, None, 0)
        super().__init__("tag:fuzzkit:cell", "", mark, mark)


# ---------------------------------------------------------------------------- loading


RULE_BASE_DOCUMENT = DocumentKind(
    "rule base",
    "rule bases",
    "expected a mapping with name, inputs, outputs and rules",
    RuleBaseError,
)


def loads_rulebase(text: str, source: str = "<string>") -> RuleBase:
    """Parse rule-base YAML ``text``; ``source`` names it in messages and in ``rb.source``.

    Coverage gaps are errors unless the document says ``coverage: allow_gaps`` (then they are
    warnings, which :func:`loads_rulebase_with_warnings` returns).

    Raises
    ------
    RuleBaseError
        Listing every problem as ``source:line:col: message``, sorted by position.
    """
    return loads_rulebase_with_warnings(text, source)[0]


def loads_rulebase_with_warnings(
    text: str, source: str = "<string>"
) -> tuple[RuleBase, list[Problem]]:
    """:func:`loads_rulebase`, also returning the warnings (severity ``warning``), located."""
    rb, warnings = _parsed(text, source)
    return rb, list(warnings)


@functools.lru_cache(maxsize=64)
def _parsed(text: str, source: str) -> tuple[RuleBase, tuple[Problem, ...]]:
    """The rule base and warnings of ``text``, parsed once per process for the same text and
    source: a tuning run or a report builds a controller per candidate and loads its rule base
    each time (the located, hardened reader costs tens of ms a file). The model and the
    problems are frozen, so sharing them is safe; a file is still read every time, so an edit
    is seen. Errors are not cached (``lru_cache`` keeps only returned values)."""
    rb, warnings = _parse(text, source)
    return rb, tuple(warnings)


def _parse(text: str, source: str) -> tuple[RuleBase, list[Problem]]:
    root = compose_document(text, source, RULE_BASE_DOCUMENT)
    reader = _Reader(source, text.split("\n"))
    try:
        rb = reader.rule_base(root)
        found = validation.diagnose(rb) if rb is not None else validation.Diagnosis([], [])
    except RecursionError:
        raise RuleBaseError(
            [
                Problem(
                    Location(source),
                    "conditions nested too deeply (expected a few levels of and/or)",
                )
            ]
        ) from None
    problems = list(reader.problems)
    warnings: list[Problem] = []
    for issues, severity, into in (
        (found.errors, "error", problems),
        (found.warnings, "warning", warnings),
    ):
        for path, message in issues:
            if path in reader.hidden_at or any(path[: len(h)] == h for h in reader.hidden_under):
                continue
            into.append(Problem(_locate(reader, path, root), message, severity))
    if problems:
        unique = list(dict.fromkeys(problems))
        unique.sort(key=lambda p: (p.location.line, p.location.col))
        raise RuleBaseError(unique)
    if rb is None:  # pragma: no cover - a missing model always comes with a problem
        raise RuntimeError("no rule base and no problem")
    digest = hashlib.sha256(text.encode("utf-8")).hexdigest()
    warnings.sort(key=lambda p: (p.location.line, p.location.col))
    return replace(rb, source=Source(source, digest)), warnings


def _locate(reader: _Reader, path: Path, root: Node) -> Location:
    for n in range(len(path), -1, -1):
        node = reader.marks.get(path[:n])
        if node is not None:
            return reader.loc(node)
    return reader.loc(root)


def load_file(path: str | FsPath) -> RuleBase:
    """Read and parse a rule-base YAML file (see :func:`loads_rulebase`)."""
    return load_file_with_warnings(path)[0]


def load_file_with_warnings(path: str | FsPath) -> tuple[RuleBase, list[Problem]]:
    """:func:`load_file`, also returning the warnings (see :func:`loads_rulebase_with_warnings`)."""
    return loads_rulebase_with_warnings(read_document(path, RULE_BASE_DOCUMENT), str(path))
