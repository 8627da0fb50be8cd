"""The tests' random rule bases: valid rule bases exercising every construct, from a seed.

:func:`random_rulebase` draws those of the interop tests (every construct the foreign formats
can hold) and, with ``sugeno``, ``depth`` and ``file_options``, those of the YAML round trip
(Sugeno outputs, nested conditions, every file-level option); :func:`edged_rulebase` those of
the comparisons with a fine-grid reference (inference, exact code generation).
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from fuzzkit.fuzzy.model import (
    AGGREGATIONS,
    AND_OPERATORS,
    IMPLICATIONS,
    OR_OPERATORS,
    OUT_OF_RANGE_POLICIES,
    SUGENO_DEFUZZIFIERS,
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


def edged_term(rng: np.random.Generator, name: str, low: float, high: float) -> Term:
    """A piecewise-linear term that may have vertical edges and reach 20 % past ``[low, high]``."""
    w = high - low
    pts = np.sort(rng.uniform(low - 0.2 * w, high + 0.2 * w, 4))
    if rng.random() < 0.3:
        pts[1] = pts[0]  # vertical edge
    if rng.random() < 0.3:
        pts[3] = pts[2]
    kind = int(rng.integers(0, 5))
    if kind == 0:
        return Term(name, "triangle", (pts[0], pts[1], pts[3]))
    if kind in (1, 2):
        return Term(name, "trapezoid", tuple(float(v) for v in pts))
    if kind == 3:
        return Term(name, "left_shoulder", (pts[0], max(pts[1], pts[0] + 0.05 * w)))
    return Term(name, "right_shoulder", (pts[2], max(pts[3], pts[2] + 0.05 * w)))


def _sugeno_output(rng: np.random.Generator, name: str, n_inputs: int) -> Variable:
    """A Sugeno output over [-10, 10]: 1-4 constant or linear terms (some coefficients 0)."""
    terms = []
    for j in range(int(rng.integers(1, 5))):
        if rng.random() < 0.5:
            terms.append(Term(f"C{j}", "constant", (_round(rng.uniform(-5, 5)),)))
        else:
            params = tuple(
                0.0 if rng.random() < 0.5 else _round(rng.uniform(-3, 3))
                for _ in range(n_inputs + 1)
            )
            terms.append(Term(f"L{j}", "linear", params))
    return Variable(name, -10.0, 10.0, tuple(terms), 0.0)


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


def _antecedent(rng: np.random.Generator, inputs: tuple[Variable, ...], depth: int) -> Expression:
    """A rule's condition: propositions (30 % negated) joined by one AND or OR; with ``depth``
    above 1, each operand of the join is itself such a condition, one level shallower."""
    if depth > 1:
        parts = tuple(_antecedent(rng, inputs, depth - 1) for _ in range(int(rng.integers(2, 4))))
        return Compound("and" if rng.random() < 0.5 else "or", parts)
    chosen = rng.permutation(len(inputs))[: int(rng.integers(1, len(inputs) + 1))]
    props: list[Expression] = [
        Proposition(inputs[i].name, str(rng.choice(inputs[i].term_names)), bool(rng.random() < 0.3))
        for i in chosen
    ]
    op: Literal["and", "or"] = "and" if rng.random() < 0.5 else "or"
    return props[0] if len(props) == 1 else Compound(op, tuple(props))


def random_rulebase(
    seed: int,
    out_of_range: str = "extend",
    *,
    matlab_shapes: bool = False,
    sugeno: bool = False,
    depth: int = 1,
    file_options: bool = False,
) -> RuleBase:
    """A valid rule base: 1-3 inputs, 1-2 outputs, NOT, AND/OR, weights, every operator.

    The defuzzifier cycles with ``seed`` through the five Mamdani ones (the two Sugeno ones
    with ``sugeno``, whose outputs are constant and linear terms). With ``matlab_shapes``
    every variable that has a smooth term also gets one of :data:`MATLAB_SHAPES` (named ``M``),
    drawn from a stream of its own; rules may use it. With ``depth`` above 1 conditions nest
    (:func:`_antecedent`); with ``file_options`` the out-of-range policy (instead of
    ``out_of_range``), the coverage and a description with YAML's special characters are
    drawn from a stream of their own. Without these options the draws are the interop tests'
    (tests/peers/make_refs.py), bit for bit.

    Rule bases with a maxima defuzzifier get piecewise-linear outputs, min implication and max
    aggregation, so that their aggregated sets have exactly flat tops or slopes no smaller than
    a term's: fuzzylite 6 counts values within 1e-6 of its running maximum as maximal, which
    lets it drift along a nearly flat top (a bell's peak, a product-scaled edge).
    """
    rng = np.random.default_rng(seed)
    defuzzifiers = SUGENO_DEFUZZIFIERS if sugeno else MAMDANI_DEFUZZIFIERS
    defuzzifier = defuzzifiers[seed % len(defuzzifiers)]  # each one in turn
    maxima = defuzzifier in MAXIMA
    extra = np.random.default_rng([seed, 25]) if matlab_shapes else None
    inputs = tuple(
        _variable(rng, f"x{i}", False, True, extra) for i in range(int(rng.integers(1, 4)))
    )
    outputs = tuple(
        _sugeno_output(rng, f"y{i}", len(inputs))
        if sugeno
        else _variable(rng, f"y{i}", True, not maxima, extra)
        for i in range(int(rng.integers(1, 3)))
    )
    rules: list[Rule] = []
    first = inputs[0]
    for term in first.terms:  # every point fires at least one rule for every output
        then = tuple(Consequent(o.name, str(rng.choice(o.term_names))) for o in outputs)
        rules.append(Rule(Proposition(first.name, term.name), then))
    for _ in range(int(rng.integers(1, 6))):
        cond = _antecedent(rng, inputs, depth)
        outs = [o for o in outputs if rng.random() < 0.7] or [outputs[0]]
        then = tuple(Consequent(o.name, str(rng.choice(o.term_names))) for o in outs)
        rules.append(Rule(cond, then, _round(rng.uniform(0.1, 1.0))))
    options: dict[str, str] = {}
    if file_options:
        fo = np.random.default_rng([seed, 7])
        out_of_range = str(fo.choice(OUT_OF_RANGE_POLICIES))
        options["coverage"] = str(fo.choice(["strict", "allow_gaps"]))
        options["description"] = str(
            fo.choice(["", "plain", "with: colon, # hash and 'quotes'\nand a newline"])
        )
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
        **options,  # type: ignore[arg-type]
    )


def edged_rulebase(rng: np.random.Generator, lo: float, hi: float) -> RuleBase:
    """A rule base for the comparisons with a fine-grid reference, drawn from ``rng``: 1-2
    inputs of one fixed shoulder-triangle-shoulder partition of [-1, 1], one output ``y`` over
    ``[lo, hi]`` of 1-4 :func:`edged_term` terms (no default: NaN where nothing fires), weights
    including 0, NOT, AND/OR, every operator and the non-Sugeno defuzzifiers (centroid twice
    as often). Its distinct peaks rarely tie at one level, which a grid could not resolve."""
    n_in = int(rng.integers(1, 3))
    in_terms = (
        Term("A", "left_shoulder", (-0.5, 0.0)),
        Term("B", "triangle", (-0.5, 0.0, 0.5)),
        Term("C", "right_shoulder", (0.0, 0.5)),
    )
    inputs = tuple(Variable(f"x{i}", -1.0, 1.0, in_terms) for i in range(n_in))
    n_out = int(rng.integers(1, 5))
    out = Variable("y", lo, hi, tuple(edged_term(rng, f"T{k}", lo, hi) for k in range(n_out)))
    rules = []
    for _ in range(int(rng.integers(1, 7))):
        props = tuple(
            Proposition(f"x{i}", "ABC"[int(rng.integers(0, 3))], bool(rng.random() < 0.15))
            for i in range(n_in)
        )
        ante: Expression = (
            props[0] if n_in == 1 else Compound("and" if rng.random() < 0.7 else "or", props)
        )
        weight = float(rng.choice([1.0, 1.0, 0.5, 0.0, float(rng.random())]))
        rules.append(Rule(ante, (Consequent("y", f"T{int(rng.integers(0, n_out))}"),), weight))
    ops = Operators(
        str(rng.choice(["min", "product"])),
        str(rng.choice(["max", "probabilistic_sum"])),
        str(rng.choice(["min", "product"])),
        str(rng.choice(["max", "bounded_sum", "probabilistic_sum"])),
    )
    defuzz = str(rng.choice(["centroid", *MAMDANI_DEFUZZIFIERS]))
    return RuleBase("r", inputs, (out,), tuple(rules), ops, defuzz)


def narrow_rulebase(rng: np.random.Generator) -> RuleBase:
    """A two-input loop-style rule base with a narrow feature, drawn from ``rng``: per input
    2-4 covering triangles or gaussians and one 10-50x narrower term placed anywhere, AND
    min or product, implication min or product (bounded sum with
    product), centroid, a random rule table over 3-5 output triangles, some weights below 1.
    What the certificate's sound surface bounds must hold on (tests/test_stability_sound_bounds.py).
    """
    gaussian = bool(rng.random() < 0.5)

    def terms(prefix: str) -> tuple[Term, ...]:
        # a covering set of 2-4 wide terms, and one narrow term anywhere
        n = int(rng.integers(2, 5))
        peaks = np.sort(rng.uniform(-1.0, 1.0, n))
        peaks[0], peaks[-1] = -1.0, 1.0
        gaps = np.diff(peaks)
        widths = [1.2 * max(gaps[max(k - 1, 0)], gaps[min(k, n - 2)]) for k in range(n)]
        peaks = np.append(peaks, rng.uniform(-0.9, 0.9))
        widths.append(float(rng.uniform(0.3, 0.8)) / float(rng.uniform(10, 50)))
        out = []
        for k, (p, width) in enumerate(zip(peaks, widths, strict=True)):
            if gaussian:
                out.append(Term(f"{prefix}{k}", "gaussian", (_round(float(p)), _round(width / 2))))
            else:
                a, c = _round(float(p) - width), _round(float(p) + width)
                out.append(Term(f"{prefix}{k}", "triangle", (a, _round(float(p)), c)))
        return tuple(out)

    e, de = Variable("e", -1.0, 1.0, terms("E")), Variable("de", -1.0, 1.0, terms("D"))
    n_out = int(rng.integers(3, 6))
    centres = np.linspace(-1.0, 1.0, n_out)
    half = 2.0 / (n_out - 1)
    out = Variable(
        "du",
        -1.0,
        1.0,
        tuple(
            Term(f"O{k}", "triangle", (_round(c - half), _round(c), _round(c + half)))
            for k, c in enumerate(centres)
        ),
    )
    rules = []
    for a in e.terms:
        for b in de.terms:
            weight = 1.0 if rng.random() < 0.8 else _round(float(rng.uniform(0.3, 1.0)))
            ante = Compound("and", (Proposition("e", a.name), Proposition("de", b.name)))
            then = f"O{int(rng.integers(0, n_out))}"
            rules.append(Rule(ante, (Consequent("du", then),), weight))
    implication = str(rng.choice(["min", "product"]))
    aggregation = "bounded_sum" if implication == "product" and rng.random() < 0.3 else "max"
    ops = Operators(str(rng.choice(["min", "product"])), "max", implication, aggregation)
    return RuleBase("narrow", (e, de), (out,), tuple(rules), ops, "centroid")
