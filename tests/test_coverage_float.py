"""Coverage is sound in floating point (issue 40 item 3): a term covers only where its computed
membership is above 0, a rule fires only where its computed firing strength is, and ``NOT`` of
a smooth term is decided by sound bounds. The reference is the engine itself, evaluated on a
dense grid: where it returns NaN, the check must have said so."""

from __future__ import annotations

import numpy as np
import pytest
from _small_rulebases import SUM_TABLE_3X3

from fuzzkit.errors import RuleBaseError
from fuzzkit.formats import registry, yaml_reader
from fuzzkit.fuzzy.inference import evaluate
from fuzzkit.fuzzy.model import Term, Variable
from fuzzkit.fuzzy.rule_coverage import rule_gaps
from fuzzkit.fuzzy.validation import diagnose, uncovered


def _grid_nan(rb: object, n: int) -> float:
    """The fraction of an n x n grid of the input box where the engine returns NaN."""
    xs = np.linspace(-1.0, 1.0, n)
    e, de = np.meshgrid(xs, xs, indexing="ij")
    du = evaluate(rb, {"e": e.ravel(), "de": de.ravel()})["du"]  # type: ignore[arg-type]
    return float(np.mean(np.isnan(du)))


def _gaussians(sigma: float, extra: str = "") -> str:
    terms = ", ".join(f"{n}: {{shape: gaussian, mean: {m}, sigma: {sigma}}}"
                      for n, m in (("N", -1), ("Z", 0), ("P", 1)))  # fmt: skip
    return f"""\
name: narrow
inputs:
  e: {{range: [-1, 1], terms: {{{terms}}}}}
  de: {{range: [-1, 1], terms: {{{terms}}}}}
outputs:
  du: {{range: [-1, 1], terms: {{partition: triangular, labels: [N, Z, P]}}}}
operators: {{and: product, or: max, implication: min, aggregation: max}}
{extra}{SUM_TABLE_3X3}"""


def test_narrow_gaussians_under_product_and_are_not_covered_where_the_product_underflows() -> None:
    # 33 sigmas from both means each membership is about 1e-240: positive, but their product
    # underflows to 0, and the engine returns NaN on about 10 % of the box
    text = _gaussians(0.015)
    rb = yaml_reader.loads_rulebase(text + "coverage: allow_gaps\n", "narrow.yaml")
    assert 0.05 < _grid_nan(rb, 201) < 0.2
    with pytest.raises(RuleBaseError) as info:
        yaml_reader.loads_rulebase(text, "narrow.yaml")
    messages = [p.message for p in info.value.problems]
    assert any("floating-point underflow" in m for m in messages), messages
    # wider Gaussians: no NaN anywhere on the grid, and the check agrees
    wide = yaml_reader.loads_rulebase(_gaussians(0.1), "wide.yaml")
    assert _grid_nan(wide, 201) == 0.0


def test_a_gaussian_tail_that_underflows_does_not_cover() -> None:
    var = Variable("x", -1.0, 1.0, (Term("g", "gaussian", (0.0, 0.01)),))
    gaps = uncovered(var)
    assert len(gaps) == 2 and gaps[0][0] == -1.0 and gaps[1][1] == 1.0
    # the gaps end where the computed membership stops being 0, to the float
    from fuzzkit.fuzzy.membership import evaluate_term

    for lo, hi in gaps:
        inside = np.linspace(lo, hi, 1001)
        assert np.all(evaluate_term(var.terms[0], inside) == 0.0)
    edge = gaps[1][0]
    assert evaluate_term(var.terms[0], np.array([np.nextafter(edge, -2.0)]))[0] > 0.0
    assert evaluate_term(var.terms[0], np.array([edge]))[0] == 0.0
    # 0.01 * sqrt(2 * 745.13): where exp(-z) underflows (independent closed form)
    assert edge == pytest.approx(0.01 * np.sqrt(2 * 745.13), rel=1e-3)


def test_a_steep_sigmoid_does_not_cover_where_it_computes_to_0() -> None:
    var = Variable("x", -1.0, 1.0, (Term("s", "sigmoid", (1000.0, 0.3)),))
    ((lo, hi),) = uncovered(var)
    # 1/(1 + exp(z)) is 0 once exp overflows, z > 709.78: x < 0.3 - 0.70978
    assert lo == -1.0 and hi == pytest.approx(0.3 - 709.78 / 1000.0, abs=1e-4)
    assert (hi - lo) / 2.0 > 0.25  # some 30 % of the range


SIGMOID_NOT = """\
name: notsig
inputs:
  e:
    range: [-1, 1]
    terms:
      T: {shape: sigmoid_product, slope1: 500, centre1: -0.9, slope2: -74, centre2: -0.1}
      A: {shape: triangle, points: [-2, -1, 2]}
outputs:
  du: {range: [-1, 1], terms: {partition: triangular, labels: [N, Z, P]}}
rules:
  - {if: {e: {not: T}}, then: {du: Z}}
"""


def test_not_of_a_sigmoid_product_is_decided_by_bounds_not_by_samples() -> None:
    # T saturates to exactly 1 on about [-0.826, -0.6], an interval between the points a
    # sample per region would test (-0.95, -0.5): 'not T' is 0 there and du is NaN
    xs = np.linspace(-1.0, 1.0, 20001)
    rb = yaml_reader.loads_rulebase(SIGMOID_NOT.replace("rules:", "coverage: allow_gaps\nrules:"),
                                    "notsig.yaml")  # fmt: skip
    nan = np.isnan(evaluate(rb, {"e": xs})["du"])
    assert 0.1 < float(np.mean(nan)) < 0.13
    for x in (-0.95, -0.9, -0.5, -0.1):
        assert not np.isnan(evaluate(rb, {"e": np.array([x])})["du"][0])
    with pytest.raises(RuleBaseError) as info:
        yaml_reader.loads_rulebase(SIGMOID_NOT, "notsig.yaml")
    (problem,) = info.value.problems
    assert "no rule fires for output 'du' where e is T" in problem.message
    example = float(problem.message.split("(e.g. at e=")[1].split(")")[0])
    assert np.isnan(evaluate(rb, {"e": np.array([example])})["du"][0])


@pytest.mark.parametrize("seed", range(6))
def test_random_narrow_rule_bases_the_check_passes_give_no_nan(seed: int) -> None:
    # soundness on random rule bases with narrow Gaussians, both AND operators: whenever the
    # check finds nothing, the engine is finite on a dense grid; whenever the grid shows NaN,
    # the check found it
    rng = np.random.default_rng(seed)
    for _ in range(4):
        sigma = float(rng.uniform(0.012, 0.05))
        and_op = str(rng.choice(["min", "product"]))
        text = _gaussians(sigma).replace("and: product", f"and: {and_op}")
        rb = yaml_reader.loads_rulebase(text + "coverage: allow_gaps\n", "r.yaml")
        errors = diagnose(rb, allow_gaps=False).errors  # input and rule coverage
        frac = _grid_nan(rb, 161)
        assert (frac > 0.0) <= bool(errors), (sigma, and_op, frac)
        # under min AND a rule fires wherever both its terms compute above 0: only an input
        # whose terms all underflow somewhere leaves a hole
        assert not rule_gaps(rb)[0] or and_op == "product"


@pytest.mark.parametrize("name", registry.available())
def test_the_shipped_rule_bases_are_covered(name: str) -> None:
    rb = registry.load(name)
    assert rule_gaps(rb) == ([], []) or rb.coverage == "allow_gaps"
    assert all(not uncovered(v) for v in rb.inputs) or rb.coverage == "allow_gaps"
