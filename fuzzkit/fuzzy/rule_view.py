"""The rule view of one point's inference (MATLAB's rule viewer): a row per rule that fires.

Each row holds, per input, the term(s) the rule's antecedent names with their membership at
the point, and per output the consequent term with the level it is cut at (its firing
strength, weight applied); :mod:`fuzzkit.viz.explain_plot` draws it. The rows are the
:func:`~fuzzkit.fuzzy.explain.explain` rules, strongest first, the first ``top`` of them.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

from fuzzkit.fuzzy.explain import Explanation
from fuzzkit.fuzzy.model import Expression, Proposition, RuleBase

#: Rules drawn when ``--rules`` is not given, and the most it takes.
DEFAULT_RULES = 12
MAX_RULES = 64


@dataclass(frozen=True, slots=True)
class InputCell:
    """One proposition of a rule on one input: ``variable is [not] term``, and its truth at
    the point (the term's membership, ``1 - mu`` when negated)."""

    term: str
    negated: bool
    truth: float


@dataclass(frozen=True, slots=True)
class OutputCell:
    """One consequent: the output's term and the level it is cut (min) or scaled (product) at."""

    term: str
    level: float


@dataclass(frozen=True, slots=True)
class RuleRow:
    """One rule: its 1-based index, its strength, and its cells by variable name (an input
    the rule does not test, or an output it does not set, has no entry)."""

    index: int
    strength: float
    inputs: dict[str, tuple[InputCell, ...]]
    outputs: dict[str, OutputCell]


def _propositions(expr: Expression) -> Iterator[Proposition]:
    if isinstance(expr, Proposition):
        yield expr
        return
    for sub in expr.operands:
        yield from _propositions(sub)


def rule_rows(rb: RuleBase, explanation: Explanation, top: int = DEFAULT_RULES) -> list[RuleRow]:
    """The rows of the rule view: the ``top`` strongest rules that fire (ties by index)."""
    memberships = {i.name: i.memberships for i in explanation.inputs}
    rows = []
    for fired in explanation.rules[:top]:
        rule = rb.rules[fired.index - 1]
        inputs: dict[str, list[InputCell]] = {}
        for prop in _propositions(rule.antecedent):
            mu = memberships[prop.variable][prop.term]
            cell = InputCell(prop.term, prop.negated, 1.0 - mu if prop.negated else mu)
            inputs.setdefault(prop.variable, []).append(cell)
        outputs = {c.variable: OutputCell(c.term, fired.strength) for c in rule.consequents}
        rows.append(
            RuleRow(fired.index, fired.strength, {k: tuple(v) for k, v in inputs.items()}, outputs)
        )
    return rows
