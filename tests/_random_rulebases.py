"""Random valid Mamdani rule bases exercising every construct the foreign formats can hold."""

from __future__ import annotations

from typing import Literal

import numpy as np

from fuzzkit.fuzzy.model import (
    AGGREGATIONS,
    AND_OPERATORS,
    IMPLICATIONS,
    OR_OPERATORS,
    Compound,
    Consequent,
    Expression,
    Operators,
    Proposition,
    Rule,
    RuleBase,
    Term,
    Variable,
)

MAMDANI_DEFUZZIFIERS = (
    "centroid",
    "bisector",
    "mean_of_maximum",
    "smallest_of_maximum",
    "largest_of_maximum",
)


def _round(x: float) -> float:
    # a few digits keep the files readable; exactness does not depend on it
    return float(np.round(x, 3))


#: The smooth shapes of MATLAB (gauss2mf, smf, zmf, pimf, dsigmf, psigmf) and fuzzylite.
MATLAB_SHAPES = (
    "gaussian_product",
    "s_shape",
    "z_shape",
    "pi_shape",
    "sigmoid_difference",
    "sigmoid_product",
)


def matlab_term(rng: np.random.Generator, shape: str, low: float, high: float) -> Term:
    """A valid term of one of :data:`MATLAB_SHAPES` inside ``[low, high]``, named ``M``."""
    w = high - low
    a, b, c, d = (_round(low + w * f) for f in np.sort(rng.uniform(0.05, 0.95, 4)))
    if len({a, b, c, d}) < 4:  # rounding merged two points: spread them evenly
        a, b, c, d = (_round(low + w * f) for f in (0.2, 0.4, 0.6, 0.8))
    slope = _round(float(rng.uniform(2, 8)) / w)
    params: tuple[float, ...] = {
        "gaussian_product": (b, _round(w * rng.uniform(0.05, 0.2)), c, _round(w * 0.1)),
        "s_shape": (a, d),
        "z_shape": (b, c),
        "pi_shape": (a, b, c, d),
        "sigmoid_difference": (slope, b, _round(slope * rng.uniform(0.5, 2)), c),
        "sigmoid_product": (slope, a, -slope, d),
    }[shape]
    return Term("M", shape, params)


def _variable(
    rng: np.random.Generator,
    name: str,
    output: bool,
    smooth: bool,
    extra: np.random.Generator | None,
) -> Variable:
    low = _round(rng.uniform(-5, 0))
    high = _round(low + rng.uniform(1, 10))
    n = int(rng.integers(2, 5))
    knots = np.linspace(low, high, n)
    step = float(knots[1] - knots[0])
    terms: list[Term] = []
    for i, c in enumerate(knots):
        c = _round(c)
        a, b = _round(c - step * rng.uniform(0.8, 1.3)), _round(c + step * rng.uniform(0.8, 1.3))
        if i == 0 and not output:
            terms.append(Term(f"T{i}", "left_shoulder", (c, b)))
        elif i == n - 1 and not output:
            terms.append(Term(f"T{i}", "right_shoulder", (a, c)))
        elif rng.random() < 0.3:
            w = _round(step * 0.2)
            terms.append(Term(f"T{i}", "trapezoid", (a, _round(c - w), _round(c + w), b)))
        else:
            terms.append(Term(f"T{i}", "triangle", (a, c, b)))
    if smooth:
        mid = _round((low + high) / 2)
        kind = rng.integers(3)
        if kind == 0:
            terms.append(Term("S", "gaussian", (mid, _round(step * 0.5))))
        elif kind == 1:
            terms.append(Term("S", "bell", (_round(step * 0.5), _round(rng.uniform(1, 3)), mid)))
        elif not output:
            terms.append(Term("S", "sigmoid", (_round(rng.choice([-1, 1]) * 4 / step), mid)))
    if smooth and extra is not None:  # its own stream: the rest is as without MATLAB shapes
        terms.append(matlab_term(extra, str(extra.choice(MATLAB_SHAPES)), low, high))
    return Variable(name, low, high, tuple(terms), (low + high) / 2 if output else None)


MAXIMA = ("mean_of_maximum", "smallest_of_maximum", "largest_of_maximum")


def random_rulebase(
    seed: int, out_of_range: str = "extend", *, matlab_shapes: bool = False
) -> RuleBase:
    """A valid rule base: 1-3 inputs, 1-2 outputs, NOT, AND/OR, weights, every operator.

    The defuzzifier cycles with ``seed`` through the five Mamdani ones. With ``matlab_shapes``
    every variable that has a smooth term also gets one of :data:`MATLAB_SHAPES` (named ``M``),
    drawn from a stream of its own; rules may use it.

    Rule bases with a maxima defuzzifier get piecewise-linear outputs, min implication and max
    aggregation, so that their aggregated sets have exactly flat tops or slopes no smaller than
    a term's: fuzzylite 6 counts values within 1e-6 of its running maximum as maximal, which
    lets it drift along a nearly flat top (a bell's peak, a product-scaled edge).
    """
    rng = np.random.default_rng(seed)
    defuzzifier = MAMDANI_DEFUZZIFIERS[seed % len(MAMDANI_DEFUZZIFIERS)]  # each one in turn
    maxima = defuzzifier in MAXIMA
    extra = np.random.default_rng([seed, 25]) if matlab_shapes else None
    inputs = tuple(
        _variable(rng, f"x{i}", False, True, extra) for i in range(int(rng.integers(1, 4)))
    )
    outputs = tuple(
        _variable(rng, f"y{i}", True, not maxima, extra) for i in range(int(rng.integers(1, 3)))
    )
    rules: list[Rule] = []
    first = inputs[0]
    for term in first.terms:  # every point fires at least one rule for every output
        then = tuple(Consequent(o.name, str(rng.choice(o.term_names))) for o in outputs)
        rules.append(Rule(Proposition(first.name, term.name), then))
    for _ in range(int(rng.integers(1, 6))):
        chosen = rng.permutation(len(inputs))[: int(rng.integers(1, len(inputs) + 1))]
        props: list[Expression] = [
            Proposition(
                inputs[i].name, str(rng.choice(inputs[i].term_names)), bool(rng.random() < 0.3)
            )
            for i in chosen
        ]
        op: Literal["and", "or"] = "and" if rng.random() < 0.5 else "or"
        cond = props[0] if len(props) == 1 else Compound(op, tuple(props))
        outs = [o for o in outputs if rng.random() < 0.7] or [outputs[0]]
        then = tuple(Consequent(o.name, str(rng.choice(o.term_names))) for o in outs)
        rules.append(Rule(cond, then, _round(rng.uniform(0.1, 1.0))))
    return RuleBase(
        name=f"random{seed}",
        inputs=inputs,
        outputs=outputs,
        rules=tuple(rules),
        operators=Operators(
            str(rng.choice(AND_OPERATORS)),
            str(rng.choice(OR_OPERATORS)),
            "min" if maxima else str(rng.choice(IMPLICATIONS)),
            "max" if maxima else str(rng.choice(AGGREGATIONS)),
        ),
        defuzzifier=defuzzifier,
        out_of_range=out_of_range,
    )
