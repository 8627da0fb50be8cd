"""The exact method over the engine's whole product: every case verifies or is refused by name.

Axes: AND (min, product) x OR (max, probabilistic sum) x implication x aggregation x
defuzzifier (all seven) x output kind (piecewise linear, Gaussian, other smooth shapes,
Gaussian and piecewise linear mixed, Sugeno order 0 and 1) x target (C float, C double,
Python). A case the engine cannot evaluate (a Sugeno output under a Mamdani defuzzifier, say)
must be refused by ``validate``; one it can, by ``--method exact`` either compiled and equal to
the engine (``codegen.verify``: random points, every edge combination, the weak points), or
refused with a reason of one of the classes ``codegen.exact.NOT_YET`` lists, the explicit list
of what the method does not emit yet. ``make test`` runs a covering set (tests/_pairwise.py),
``make verify`` :data:`VERIFY_ROWS` (a quarter of the product: the AND and OR operators, which
act on the firing strengths only, taken in turn over the product of the other axes); the
classification alone runs over the full product in ``make test`` (it compiles nothing).
"""

from __future__ import annotations

import itertools

import pytest
from _codegen_util import needs_cc
from _pairwise import matrix_params, rotated_product

from fuzzkit.codegen.exact import NOT_YET, emit_exact, not_yet, unsupported_reason
from fuzzkit.codegen.toolchain import STRICT_FLAGS
from fuzzkit.codegen.verify import verify_exact_c, verify_exact_python
from fuzzkit.fuzzy import model
from fuzzkit.fuzzy.validation import check

#: Three output terms on [-1, 1] per kind.
OUTPUT_TERMS: dict[str, tuple[model.Term, ...]] = {
    "pwl": (
        model.Term("T0", "triangle", (-1.6, -0.8, 0.0)),
        model.Term("T1", "trapezoid", (-0.6, -0.1, 0.1, 0.6)),
        model.Term("T2", "right_shoulder", (0.2, 0.9)),
    ),
    "gaussian": (
        model.Term("T0", "gaussian", (-0.7, 0.25)),
        model.Term("T1", "gaussian", (0.0, 0.2)),
        model.Term("T2", "gaussian", (0.7, 0.3)),
    ),
    "smooth": (
        model.Term("T0", "bell", (0.3, 2.0, -0.6)),
        model.Term("T1", "pi_shape", (-0.4, -0.1, 0.1, 0.4)),
        model.Term("T2", "sigmoid", (8.0, 0.5)),
    ),
    "mixed": (
        model.Term("T0", "gaussian", (-0.6, 0.25)),
        model.Term("T1", "triangle", (-0.4, 0.0, 0.4)),
        model.Term("T2", "gaussian", (0.6, 0.25)),
    ),
    "sugeno0": (
        model.Term("T0", "constant", (-0.8,)),
        model.Term("T1", "constant", (0.0,)),
        model.Term("T2", "constant", (0.8,)),
    ),
    "sugeno1": (
        model.Term("T0", "linear", (0.5, 0.2, -0.3)),
        model.Term("T1", "linear", (0.1, -0.4, 0.0)),
        model.Term("T2", "linear", (-0.3, 0.6, 0.4)),
    ),
}
KINDS = tuple(OUTPUT_TERMS)
TARGETS = ("c-float", "c-double", "python")
#: Verification points per case (plus every edge combination and the weak points).
POINTS = 300
#: The strict flags without optimisation: compiling is most of a case's time (0.3 s against
#: 0.4-1.4 s at -O2); -O2 and the sanitizers are tests/test_codegen_exact.py's.
FLAGS = (*STRICT_FLAGS, "-O0")


def rulebase(
    and_: str, or_: str, implication: str, aggregation: str, defuzzifier: str, kind: str
) -> model.RuleBase:
    """Two inputs (shoulders and a Gaussian; MATLAB splines); rules with AND, OR, NOT, weights."""
    e = model.Variable(
        "e",
        -1.0,
        1.0,
        (
            model.Term("N", "left_shoulder", (-0.8, 0.0)),
            model.Term("Z", "gaussian", (0.0, 0.3)),
            model.Term("P", "right_shoulder", (0.0, 0.8)),
        ),
    )
    de = model.Variable(
        "de",
        -1.0,
        1.0,
        (
            model.Term("N", "z_shape", (-0.8, 0.0)),
            model.Term("Z", "pi_shape", (-0.8, -0.2, 0.2, 0.8)),
            model.Term("P", "s_shape", (0.0, 0.8)),
        ),
    )
    u = model.Variable("u", -1.0, 1.0, OUTPUT_TERMS[kind])

    def then(term: str) -> tuple[model.Consequent, ...]:
        return (model.Consequent("u", term),)

    def p(var: str, term: str, negated: bool = False) -> model.Proposition:
        return model.Proposition(var, term, negated)

    rules = (
        model.Rule(p("e", "N"), then("T0")),  # every point fires one of the first three
        model.Rule(p("e", "Z"), then("T1")),
        model.Rule(p("e", "P"), then("T2")),
        model.Rule(model.Compound("and", (p("e", "N"), p("de", "P"))), then("T1"), 0.6),
        model.Rule(model.Compound("or", (p("e", "P"), p("de", "N"))), then("T1"), 0.8),
        model.Rule(model.Compound("and", (p("e", "Z", True), p("de", "Z"))), then("T0"), 0.5),
    )
    ops = model.Operators(and_, or_, implication, aggregation)
    name = f"x_{kind}_{defuzzifier[:5]}_{aggregation[:5]}"
    return model.RuleBase(name, (e, de), (u,), rules, ops, defuzzifier)


AXES = (
    model.AND_OPERATORS,
    model.OR_OPERATORS,
    model.IMPLICATIONS,
    model.AGGREGATIONS,
    model.DEFUZZIFIERS,
    KINDS,
)


#: ``make verify``'s rows: every implication x aggregation x defuzzifier x kind x target once,
#: the four AND x OR combinations in turn. With these axes' lengths each AND x OR combination
#: meets every aggregation x defuzzifier x kind (checked below); the firing strengths the AND
#: and OR compute reach the output stage only as numbers in [0, 1] (and make test's covering
#: rows meet every AND and OR value with every value of each other axis).
VERIFY_ROWS = rotated_product((*AXES, TARGETS), 2)


def test_the_verify_rows_meet_every_operator_pair_with_every_output_stage() -> None:
    met = {(row[0], row[1], row[3], row[4], row[5]) for row in VERIFY_ROWS}
    assert met == set(itertools.product(*AXES[:2], *AXES[3:]))
    assert len(VERIFY_ROWS) == len(list(itertools.product(*AXES[2:], TARGETS)))


def engine_refuses(defuzzifier: str, kind: str) -> bool:
    """Whether ``validate`` refuses the case: Sugeno terms need a weighted defuzzifier, and
    weighted_sum is for Sugeno terms only."""
    if kind.startswith("sugeno"):
        return defuzzifier not in model.SUGENO_DEFUZZIFIERS
    return defuzzifier == "weighted_sum"


def test_the_refusals_are_exactly_the_not_yet_list() -> None:
    """Over the full product (no compiling): every case the engine evaluates is emitted or
    refused as one of NOT_YET's classes, its reason naming the class, and every class is met."""
    met: set[str] = set()
    emitted = 0
    for row in itertools.product(*AXES):
        rb = rulebase(*row)
        if check(rb):
            assert engine_refuses(row[4], row[5]), (row, check(rb))
            continue  # validate refuses it: the exact method never sees it
        for number_type in ("double", "float"):
            why = unsupported_reason(rb, number_type)
            found = not_yet(rb, rb.outputs[0], number_type)
            assert (why is None) == (found is None), (row, why)
            if found is None:
                emitted += 1
                continue
            met.add(found[0])
            assert NOT_YET[found[0]] in str(why), why
            assert ("--method table" in str(why)) != (found[0] == "float_psum_maxima"), why
    assert met == set(NOT_YET)
    assert emitted >= 600


def _verify(rb: model.RuleBase, target: str) -> None:
    if target == "python":
        result = verify_exact_python(rb, emit_exact(rb, "python"), n=POINTS)
    else:
        number_type = target.split("-")[1]
        files = emit_exact(rb, "c", number_type)
        result = verify_exact_c(rb, number_type, files, n=POINTS, flags=FLAGS)
    assert result.ok, (rb.name, result.describe())


@pytest.mark.parametrize(
    "and_, or_, implication, aggregation, defuzzifier, kind, target, seed",
    matrix_params(
        (*AXES, TARGETS),
        cover_seeds=(0,),
        verify_seeds=(0,),
        full_rows=VERIFY_ROWS,
        marks={"c-float": needs_cc, "c-double": needs_cc},
    ),
)
def test_every_case_verifies_or_is_refused_by_name(
    and_: str,
    or_: str,
    implication: str,
    aggregation: str,
    defuzzifier: str,
    kind: str,
    target: str,
    seed: int,
) -> None:
    rb = rulebase(and_, or_, implication, aggregation, defuzzifier, kind)
    problems = check(rb)
    assert bool(problems) == engine_refuses(defuzzifier, kind), problems
    if problems:  # validate refuses it: the exact method never sees it
        return
    number_type = "float" if target == "c-float" else "double"
    found = not_yet(rb, rb.outputs[0], number_type)
    if found is not None:
        why = unsupported_reason(rb, number_type)
        assert why is not None and NOT_YET[found[0]] in why
        return
    _verify(rb, target)
