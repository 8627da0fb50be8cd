"""Why an output is what it is: one point's inference, step by step.

:func:`explain` returns the value each input's terms see and their memberships, every rule that
fires with its strength (weight applied), and per output the activation of each term and the
aggregated output set, sampled finely enough to draw (and to check the defuzzified value by
numeric integration), next to the exact engine's value. Sugeno outputs have no set: their terms'
values at the point and activations stand in for it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import EvaluationError
from fuzzkit.fuzzy import membership
from fuzzkit.fuzzy.describe import rule_sentence, shown_output
from fuzzkit.fuzzy.model import RuleBase, Variable
from fuzzkit.fuzzy.output_geometry import OutputPieces
from fuzzkit.fuzzy.type2_model import footprint_of

FloatArray = npt.NDArray[np.float64]

#: Samples of the aggregated set across the output range (the terms' breakpoints are added).
SET_SAMPLES = 2001


@dataclass(frozen=True, slots=True)
class InputExplanation:
    """One input: the value given, the value its terms see (clamped), memberships per term."""

    name: str
    value: float
    seen: float
    memberships: dict[str, float]


@dataclass(frozen=True, slots=True)
class FiredRule:
    """A rule with a firing strength > 0 (its weight applied); ``index`` counts from 1."""

    index: int
    text: str
    strength: float


@dataclass(frozen=True, slots=True)
class OutputExplanation:
    """One output: its value (the engine's), the defuzzifier, each term's activation, and the
    aggregated set ``(y, mu)`` (empty for a Sugeno output, whose ``term_values`` say what each
    term contributes at this point)."""

    name: str
    value: float
    defuzzifier: str
    activations: dict[str, float]
    y: FloatArray
    mu: FloatArray
    term_values: dict[str, float]


@dataclass(frozen=True, slots=True)
class Explanation:
    """The whole inference at one point (see the module docstring)."""

    rulebase: str
    operators: dict[str, str]
    inputs: tuple[InputExplanation, ...]
    rules: tuple[FiredRule, ...]
    outputs: tuple[OutputExplanation, ...]

    def as_data(self) -> dict[str, Any]:
        """Plain data for JSON (``fuzzkit eval --explain --json``)."""
        return {
            "rulebase": self.rulebase,
            "operators": self.operators,
            "inputs": [
                {"name": i.name, "value": i.value, "seen": i.seen, "memberships": i.memberships}
                for i in self.inputs
            ],
            "rules": [
                {"index": r.index, "rule": r.text, "strength": r.strength} for r in self.rules
            ],
            "outputs": [
                {
                    "name": o.name,
                    "value": None if math.isnan(o.value) else o.value,
                    "defuzzifier": o.defuzzifier,
                    "activations": o.activations,
                    "aggregated_set": {"y": o.y.tolist(), "mu": o.mu.tolist()},
                    "term_values": o.term_values,
                }
                for o in self.outputs
            ],
        }


def explain(rb: RuleBase, point: Mapping[str, float]) -> Explanation:
    """Explain the inference of ``rb`` at ``point`` (a value for every input, by name).

    Raises
    ------
    EvaluationError
        A missing, unknown or NaN input (a NaN input gives NaN outputs: no rule fires), or an
        interval type-2 rule base (its explanation would need the firing intervals and both
        output sets; not written yet).
    """
    from fuzzkit.fuzzy.inference import engine_for

    if footprint_of(rb) is not None:
        raise EvaluationError(
            f"rule base {rb.name!r} is interval type-2: the explanation shows type-1 inference "
            "only (evaluate it without --explain)"
        )

    engine = engine_for(rb)
    values = {n: float(point[n]) for n in rb.input_names if n in point}
    engine.evaluate_point(values)  # missing and unknown names are reported here
    bad = [n for n, v in values.items() if math.isnan(v)]
    if bad:
        raise EvaluationError(
            f"input {', '.join(bad)} is NaN: every output is NaN and no rule fires; "
            "nothing to explain"
        )
    inputs = tuple(_fuzzify(var, values[var.name], rb.out_of_range) for var in rb.inputs)
    firing = engine.firing_strengths({n: np.array([v]) for n, v in values.items()})
    result = engine.evaluate_point(values)
    rules = tuple(
        sorted(
            (
                FiredRule(r + 1, rule_sentence(rule), float(firing[0, r]))
                for r, rule in enumerate(rb.rules)
                if firing[0, r] > 0.0
            ),
            key=lambda f: (-f.strength, f.index),
        )
    )
    seen = [np.array([i.seen]) for i in inputs]
    outputs = tuple(
        _output(rb, out, firing, seen, shown_output(result[out.name], out)) for out in rb.outputs
    )
    ops = rb.operators
    return Explanation(
        rb.name,
        {
            "and": ops.and_,
            "or": ops.or_,
            "implication": ops.implication,
            "aggregation": ops.aggregation,
        },
        inputs,
        rules,
        outputs,
    )


def _fuzzify(var: Variable, value: float, policy: str) -> InputExplanation:
    seen = min(max(value, var.low), var.high) if policy == "clamp" else value
    mus = {t.name: float(membership.evaluate_term(t, np.array([seen]))[0]) for t in var.terms}
    return InputExplanation(var.name, value, seen, mus)


def _output(
    rb: RuleBase, out: Variable, firing: FloatArray, seen: list[FloatArray], value: float
) -> OutputExplanation:
    pieces = OutputPieces(rb, out)
    act = pieces.activations(firing)[0]
    activations = {t.name: float(a) for t, a in zip(out.terms, act, strict=True)}
    empty = np.zeros(0)
    if out.is_sugeno:
        term_values = {t.name: float(membership.sugeno_value(t, seen)[0]) for t in out.terms}
        return OutputExplanation(
            out.name, value, rb.defuzzifier, activations, empty, empty, term_values
        )
    y = _set_grid(out)
    mu = aggregated_set(rb, out, pieces.levels(firing)[0], pieces.piece_term, y)
    return OutputExplanation(out.name, value, rb.defuzzifier, activations, y, mu, {})


def _set_grid(out: Variable) -> FloatArray:
    marks = [
        b
        for t in out.terms
        if t.is_piecewise_linear
        for b in membership.breakpoints(t)
        if out.low <= b <= out.high
    ]
    return np.unique(np.concatenate([np.linspace(out.low, out.high, SET_SAMPLES), marks]))


def aggregated_set(
    rb: RuleBase, out: Variable, levels: FloatArray, piece_term: npt.NDArray[np.intp], y: FloatArray
) -> FloatArray:
    """The aggregated output set at ``y``: every piece's term, cut (min) or scaled (product) at
    its level, combined by the rule base's aggregation."""
    ops = rb.operators
    term_mu = np.array([membership.evaluate_term(t, y) for t in out.terms])  # (T, len(y))
    implied = term_mu[piece_term]
    lv = levels[:, None]
    implied = np.minimum(implied, lv) if ops.implication == "min" else implied * lv
    if ops.aggregation == "max":
        return np.asarray(implied.max(axis=0, initial=0.0), dtype=np.float64)
    if ops.aggregation == "bounded_sum":
        return np.asarray(np.minimum(implied.sum(axis=0), 1.0), dtype=np.float64)
    return np.asarray(1.0 - np.prod(1.0 - implied, axis=0), dtype=np.float64)
