"""Why an output is what it is: one point's inference, step by step.

:func:`explain` returns the value each input's terms see and their memberships, every rule that
fires with its strength (weight applied), and per output the activation of each term and the
aggregated output set, sampled finely enough to draw (and to check the defuzzified value by
numeric integration), next to the exact engine's value. Sugeno outputs have no set: their terms'
values at the point and activations stand in for it.

An interval type-2 rule base is explained with its intervals: each input's lower memberships
beside the upper ones, each rule's firing interval ``[lower, upper]`` (a rule fires when its
upper strength is above 0; it is ranked by it), and per output the lower set beside the upper
(aggregated) one and the centroid interval ``[y_l, y_r]``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import EvaluationError
from fuzzkit.fuzzy import membership
from fuzzkit.fuzzy.describe import rule_sentence, shown_output
from fuzzkit.fuzzy.model import RuleBase, Variable
from fuzzkit.fuzzy.output_geometry import OutputPieces
from fuzzkit.fuzzy.type2_model import Footprint, footprint_of

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
    lower_memberships: dict[str, float] | None = None  # interval type-2 only


@dataclass(frozen=True, slots=True)
class FiredRule:
    """A rule with a firing strength > 0 (its weight applied); ``index`` counts from 1."""

    index: int
    text: str
    strength: float
    lower: float | None = None  # interval type-2: the lower firing strength (``strength``: upper)


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
    #: Interval type-2 only: the lower set at ``y`` (``mu`` is the upper one), each term's
    #: lower activation, and the centroid interval ``(y_l, y_r)``.
    mu_lower: FloatArray | None = None
    lower_activations: dict[str, float] | None = None
    interval: tuple[float, float] | None = None


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
            "inputs": [_input_data(i) for i in self.inputs],
            "rules": [_rule_data(r) for r in self.rules],
            "outputs": [_output_data(o) for o in self.outputs],
        }


def _input_data(i: InputExplanation) -> dict[str, Any]:
    data: dict[str, Any] = {
        "name": i.name, "value": i.value, "seen": i.seen, "memberships": i.memberships
    }  # fmt: skip
    if i.lower_memberships is not None:
        data["lower_memberships"] = i.lower_memberships
    return data


def _rule_data(r: FiredRule) -> dict[str, Any]:
    data: dict[str, Any] = {"index": r.index, "rule": r.text, "strength": r.strength}
    if r.lower is not None:
        data["firing_interval"] = [r.lower, r.strength]
    return data


def _output_data(o: OutputExplanation) -> dict[str, Any]:
    data: dict[str, Any] = {
        "name": o.name,
        "value": None if math.isnan(o.value) else o.value,
        "defuzzifier": o.defuzzifier,
        "activations": o.activations,
        "aggregated_set": {"y": o.y.tolist(), "mu": o.mu.tolist()},
        "term_values": o.term_values,
    }
    if o.interval is not None:
        data["lower_activations"] = o.lower_activations
        data["lower_set"] = {
            "y": o.y.tolist(),
            "mu": [] if o.mu_lower is None else o.mu_lower.tolist(),
        }
        data["interval"] = [None if math.isnan(v) else v for v in o.interval]
    return data


def explain(rb: RuleBase, point: Mapping[str, float]) -> Explanation:
    """Explain the inference of ``rb`` at ``point`` (a value for every input, by name).

    Raises
    ------
    EvaluationError
        A missing, unknown or NaN input (a NaN input gives NaN outputs: no rule fires).
    """
    from fuzzkit.fuzzy.inference import engine_for

    engine = engine_for(rb)
    values = {n: float(point[n]) for n in rb.input_names if n in point}
    engine.evaluate_point(values)  # missing and unknown names are reported here
    bad = [n for n, v in values.items() if math.isnan(v)]
    if bad:
        raise EvaluationError(
            f"input {', '.join(bad)} is NaN: every output is NaN and no rule fires; "
            "nothing to explain"
        )
    footprint = footprint_of(rb)
    inputs = tuple(_fuzzify(var, values[var.name], rb.out_of_range, footprint) for var in rb.inputs)
    points = {n: np.array([v]) for n, v in values.items()}
    lower: FloatArray | None = None
    if footprint is None:
        firing = engine.firing_strengths(points)
    else:
        lower, firing = engine.firing_intervals(points)
    result = engine.evaluate_point(values)
    rules = tuple(
        sorted(
            (
                FiredRule(
                    r + 1,
                    rule_sentence(rule),
                    float(firing[0, r]),
                    None if lower is None else float(lower[0, r]),
                )
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
    if footprint is not None and lower is not None:
        intervals = engine.centroid_intervals(points)
        outputs = tuple(
            _lower_side(rb, out, o, lower, intervals[out.name], footprint)
            for out, o in zip(rb.outputs, outputs, strict=True)
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


def _fuzzify(
    var: Variable, value: float, policy: str, footprint: Footprint | None
) -> InputExplanation:
    seen = min(max(value, var.low), var.high) if policy == "clamp" else value
    x = np.array([seen])
    mus = {t.name: float(membership.evaluate_term(t, x)[0]) for t in var.terms}
    if footprint is None:
        return InputExplanation(var.name, value, seen, mus)
    shapes, scales = footprint.lower_terms(var)
    lows = {
        t.name: min(h * float(membership.evaluate_term(t, x)[0]), mus[t.name])
        for t, h in zip(shapes, scales, strict=True)
    }
    return InputExplanation(var.name, value, seen, mus, lows)


def _lower_side(
    rb: RuleBase,
    out: Variable,
    upper: OutputExplanation,
    lower: FloatArray,
    interval: tuple[FloatArray, FloatArray],
    footprint: Footprint,
) -> OutputExplanation:
    """``upper`` (the type-1 style explanation on the upper firing) with the lower side."""
    pieces = OutputPieces(rb, out)
    act = pieces.activations(lower)[0]
    acts = {t.name: float(a) for t, a in zip(out.terms, act, strict=True)}
    y_l, y_r = (shown_output(float(v[0]), out) for v in interval)
    mu_lower = None
    if len(upper.y):
        shapes, scales = footprint.lower_terms(out)
        low_var = replace(out, terms=shapes)
        mu = aggregated_set(
            rb, low_var, pieces.levels(lower)[0], pieces.piece_term, upper.y, np.array(scales)
        )
        mu_lower = np.minimum(mu, upper.mu)
    return replace(upper, mu_lower=mu_lower, lower_activations=acts, interval=(y_l, y_r))


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
    rb: RuleBase,
    out: Variable,
    levels: FloatArray,
    piece_term: npt.NDArray[np.intp],
    y: FloatArray,
    heights: FloatArray | None = None,
) -> FloatArray:
    """The aggregated output set at ``y``: every piece's term (times its height, an IT2 lower
    term's scale), cut (min) or scaled (product) at its level, combined by the rule base's
    aggregation."""
    ops = rb.operators
    term_mu = np.array([membership.evaluate_term(t, y) for t in out.terms])  # (T, len(y))
    if heights is not None:
        term_mu = term_mu * heights[:, None]
    implied = term_mu[piece_term]
    lv = levels[:, None]
    implied = np.minimum(implied, lv) if ops.implication == "min" else implied * lv
    if ops.aggregation == "max":
        return np.asarray(implied.max(axis=0, initial=0.0), dtype=np.float64)
    if ops.aggregation == "bounded_sum":
        return np.asarray(np.minimum(implied.sum(axis=0), 1.0), dtype=np.float64)
    return np.asarray(1.0 - np.prod(1.0 - implied, axis=0), dtype=np.float64)
