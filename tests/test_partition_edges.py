"""Partition edges are exact: at a label peak no neighbouring term has any membership.

A ``partition: triangular`` term's feet are its neighbours' peaks, bit for bit, and a
piecewise-linear membership is exactly 0 at its foot. Before, the slope ``1/(peak - foot)``
was rounded to nearest, so ``1 + (foot - peak) * slope`` could be 1.1e-16: with 11 labels on
``de`` in [-20, 11] and ``ends: triangle`` the term next to the end fired at de = -20 and the
output was -0.9 instead of the rule base's NaN default.

The property is checked on seeded random partitions (label counts, symmetric, asymmetric,
offset, tiny and large ranges, both ``ends``), in the batch engine, the scalar path, and the
generated exact-method Python; outputs where a rule fires are checked against the closed-form
centroid of the one output term it fires.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import fuzzkit
from fuzzkit.codegen.exact import emit_exact
from fuzzkit.codegen.verify import load_module
from fuzzkit.fuzzy.membership import evaluate_term
from fuzzkit.fuzzy.model import Consequent, Proposition, Rule, RuleBase, Term, Variable
from fuzzkit.fuzzy.partition import PARTITION_ENDS, partition_terms
from fuzzkit.fuzzy.validation import check

OUT_LOW, OUT_HIGH = -1.0, 1.0
OUT_LABELS = [f"B{k}" for k in range(11)]


def random_range(rng: np.random.Generator, kind: int) -> tuple[float, float]:
    """A range of one of several families: the edge cases a user's files contain."""
    if kind == 0:  # integers, asymmetric (the issue's [-20, 4] family)
        low = float(rng.integers(-50, 0))
        return low, low + float(rng.integers(1, 60))
    if kind == 1:  # symmetric about 0
        half = float(rng.choice([0.5, 1.0, 3.0, 7.3, 100.0]))
        return -half, half
    if kind == 2:  # decimals with one to three digits
        digits = int(rng.integers(1, 4))
        low = round(float(rng.uniform(-30, 10)), digits)
        return low, round(low + float(rng.uniform(0.1, 40)), digits)
    if kind == 3:  # far from 0: a knot lattice that float rounding does not keep
        low = float(rng.choice([1000.0, -1234.5, 1e6]))
        return low, low + round(float(rng.uniform(0.1, 10)), 2)
    if kind == 4:  # tiny widths
        low = float(rng.uniform(-1e-3, 1e-3))
        return low, low + float(rng.uniform(1e-6, 1e-2))
    low = float(rng.uniform(-1e4, 1e4))  # arbitrary doubles
    return low, low + float(rng.uniform(1e-2, 1e4))


def random_partitions(seed: int, count: int) -> list[tuple[int, float, float, str]]:
    rng = np.random.default_rng(seed)
    return [
        (int(rng.integers(2, 16)), *random_range(rng, k % 6), PARTITION_ENDS[k % 2])
        for k in range(count)
    ]


PARTITIONS = random_partitions(25, 240)


def peaks_of(terms: tuple[Term, ...]) -> list[float]:
    """Each term's peak read from its parameters (a shoulder's peak is its range end)."""
    return [t.params[0] if t.shape == "left_shoulder" else t.params[1] for t in terms]


def test_every_foot_is_its_neighbours_peak_bit_for_bit() -> None:
    for n, low, high, ends in PARTITIONS:
        terms = partition_terms([f"A{k}" for k in range(n)], low, high, ends)
        peaks = peaks_of(terms)
        assert peaks[0] == low and peaks[-1] == high
        for k, term in enumerate(terms):
            p, where = term.params, (n, low, high, ends, k)
            if k > 0:  # a triangle or a right shoulder: the rising foot comes first
                assert term.shape != "left_shoulder", where
                assert p[0].hex() == peaks[k - 1].hex(), where
            if k < n - 1:  # a triangle or a left shoulder: the falling foot comes last
                assert term.shape != "right_shoulder", where
                assert p[-1].hex() == peaks[k + 1].hex(), where


def test_membership_at_every_label_peak_is_exactly_one_or_zero() -> None:
    for n, low, high, ends in PARTITIONS:
        terms = partition_terms([f"A{k}" for k in range(n)], low, high, ends)
        peaks = np.array(peaks_of(terms))
        for j, term in enumerate(terms):
            mu = evaluate_term(term, peaks)
            np.testing.assert_array_equal(mu, np.eye(n)[j], err_msg=f"{n, low, high, ends, j}")


def output_centroid(term: Term) -> float:
    """Closed-form centroid of one output triangle fired at full strength, clipped to the range.

    Interior: ``(a + b + c)/3``. An end term peaks on the range end and only its inner half is
    in range: a right triangle whose centroid is a third of its base from the peak.
    """
    a, b, c = term.params
    if b == OUT_LOW:
        return b + (c - b) / 3
    if b == OUT_HIGH:
        return b - (b - a) / 3
    return (a + b + c) / 3


def peak_rulebase(
    n: int, low: float, high: float, ends: str, rng: np.random.Generator, default: float | None
) -> tuple[RuleBase, dict[int, int]]:
    """One input partition; rules on a random half of its labels, each to a random output label."""
    fired = sorted(rng.choice(n, size=max(1, n // 2), replace=False).tolist())
    to = {i: int(rng.integers(0, len(OUT_LABELS))) for i in fired}
    rb = RuleBase(
        name="edges",
        inputs=(
            Variable("x", low, high, partition_terms([f"A{k}" for k in range(n)], low, high, ends)),
        ),
        outputs=(
            Variable(
                "y",
                OUT_LOW,
                OUT_HIGH,
                partition_terms(OUT_LABELS, OUT_LOW, OUT_HIGH, "triangle"),
                default,
            ),
        ),
        rules=tuple(
            Rule(Proposition("x", f"A{i}"), (Consequent("y", OUT_LABELS[o]),))
            for i, o in to.items()
        ),
    )
    assert check(rb) == []
    return rb, to


@pytest.mark.parametrize("default", [None, 0.25])
def test_output_is_the_default_at_every_label_peak_where_no_rule_fires(
    default: float | None,
) -> None:
    rng = np.random.default_rng(2025)
    out_terms = partition_terms(OUT_LABELS, OUT_LOW, OUT_HIGH, "triangle")
    for n, low, high, ends in PARTITIONS[:120]:
        rb, to = peak_rulebase(n, low, high, ends, rng, default)
        peaks = peaks_of(rb.inputs[0].terms)
        batch = fuzzkit.evaluate(rb, {"x": np.array(peaks)})["y"]
        for i, x in enumerate(peaks):
            point = fuzzkit.evaluate_point(rb, {"x": x})["y"]
            where = f"{n} labels on [{low!r}, {high!r}], ends {ends}, peak {i} (x = {x!r})"
            for got in (float(batch[i]), point):
                if i not in to:
                    assert math.isnan(got) if default is None else got == default, where
                else:
                    want = output_centroid(out_terms[to[i]])
                    assert got == pytest.approx(want, abs=1e-12), where


def repro_yaml(high: float) -> str:
    labels = ", ".join(f"A{k}" for k in range(11))
    out = ", ".join(OUT_LABELS)
    return f"""
name: edges
inputs:
  de:
    range: [-20, {high}]
    terms: {{partition: triangular, labels: [{labels}], ends: triangle}}
outputs:
  du:
    range: [-1, 1]
    default: 0
    terms: {{partition: triangular, labels: [{out}], ends: triangle}}
rules:
  - {{if: {{de: A1}}, then: {{du: B0}}}}
"""


def repro(high: float) -> RuleBase:
    """The issue's rule base without its default: a file is refused for the label peaks where
    no rule fires (issue 28 item 5), a model built in Python evaluates them to NaN."""
    rb = fuzzkit.loads(repro_yaml(high))
    return dataclasses.replace(rb, outputs=(dataclasses.replace(rb.outputs[0], default=None),))


@pytest.mark.parametrize("high", [4, 11])
def test_issue_case_the_term_next_to_the_end_does_not_fire_at_the_range_end(high: int) -> None:
    # [-20, 11] is where the rounded slope left 1.1e-16 at de = -20 (the output was -0.9);
    # [-20, 4], the issue's range, rounded the right way already
    rb = repro(high)
    a1 = rb.inputs[0].terms[1]
    assert a1.params[0] == -20.0
    assert evaluate_term(a1, np.array([-20.0]))[0] == 0.0
    assert math.isnan(fuzzkit.evaluate_point(rb, {"de": -20.0})["du"])
    assert math.isnan(fuzzkit.evaluate(rb, {"de": np.array([-20.0])})["du"][0])
    # at A1's own peak the rule fires at full strength: the B0 end term's centroid
    peak = rb.inputs[0].terms[1].params[1]
    b0 = rb.outputs[0].terms[0]
    want = -1.0 + (b0.params[2] + 1.0) / 3
    assert fuzzkit.evaluate_point(rb, {"de": peak})["du"] == pytest.approx(want, abs=1e-12)


def test_generated_exact_python_gives_the_default_at_every_label_peak() -> None:
    # the generated code embeds the engine's slopes: the same exact zeros at the feet
    rb = repro(11)
    module = load_module(emit_exact(rb, "python", "double"), rb.name)
    peaks = peaks_of(rb.inputs[0].terms)
    for i, x in enumerate(peaks):
        (got,) = module.eval((x,))
        if i == 1:
            assert got == pytest.approx(fuzzkit.evaluate_point(rb, {"de": x})["du"], abs=1e-12)
        else:
            assert math.isnan(got), (i, x, got)
