"""The exact engine against an independent fine-grid Mamdani written here, plus properties."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _mamdani_reference import GRID
from _mamdani_reference import mu as independent_mu
from _mamdani_reference import reference as fine_grid_reference

from fuzzkit.errors import EvaluationError
from fuzzkit.fuzzy.inference import Engine, evaluate, evaluate_point
from fuzzkit.fuzzy.model import (
    Compound,
    Consequent,
    Operators,
    Proposition,
    Rule,
    RuleBase,
    Term,
    Variable,
)

LABELS = ("NL", "NM", "NS", "ZR", "PS", "PM", "PL")
ALL_OPERATORS = [
    (imp, agg) for imp in ("min", "product") for agg in ("max", "bounded_sum", "probabilistic_sum")
]
AREA_DEFUZZIFIERS = ("centroid", "bisector")
MAX_DEFUZZIFIERS = ("mean_of_maximum", "smallest_of_maximum", "largest_of_maximum")


def partition(ends: str, width: float = 1 / 3) -> tuple[Term, ...]:
    terms = []
    for k, name in enumerate(LABELS):
        p = -1 + k / 3
        if ends == "shoulder" and k == 0:
            terms.append(Term(name, "left_shoulder", (-1.0, -1 + width)))
        elif ends == "shoulder" and k == 6:
            terms.append(Term(name, "right_shoulder", (1 - width, 1.0)))
        else:
            terms.append(Term(name, "triangle", (p - width, p, p + width)))
    return tuple(terms)


def table_rules(cell: object = None) -> tuple[Rule, ...]:
    rules = []
    for i in range(7):
        for j in range(7):
            out = min(3, max(-3, (i - 3) + (j - 3))) + 3
            rules.append(
                Rule(
                    Compound("and", (Proposition("e", LABELS[i]), Proposition("de", LABELS[j]))),
                    (Consequent("du", LABELS[out]),),
                )
            )
    return tuple(rules)


def macvicar_whelan(
    implication: str = "min",
    aggregation: str = "max",
    defuzzifier: str = "centroid",
    and_: str = "min",
    output_terms: tuple[Term, ...] | None = None,
    **kw: object,
) -> RuleBase:
    return RuleBase(
        name="mw",
        inputs=(
            Variable("e", -1.0, 1.0, partition("shoulder")),
            Variable("de", -1.0, 1.0, partition("shoulder")),
        ),
        outputs=(Variable("du", -1.0, 1.0, output_terms or partition("triangle")),),
        rules=table_rules(),
        operators=Operators(and_, "max", implication, aggregation),
        defuzzifier=defuzzifier,
        **kw,  # type: ignore[arg-type]
    )


def reference(rb: RuleBase, e: float, de: float, n: int = GRID) -> float:
    """The independent fine-grid reference (tests/_mamdani_reference.py) at one (e, de)."""
    value = fine_grid_reference(rb, {"e": e, "de": de}, n)
    assert value is not None, "no rule fires: the tests only use points where one does"
    return value


POINTS = np.random.default_rng(7).uniform(-1.2, 1.2, size=(8, 2))


@pytest.mark.parametrize("implication, aggregation", ALL_OPERATORS)
@pytest.mark.parametrize("defuzzifier", AREA_DEFUZZIFIERS + MAX_DEFUZZIFIERS)
def test_engine_matches_fine_grid_reference(
    implication: str, aggregation: str, defuzzifier: str
) -> None:
    rb = macvicar_whelan(implication, aggregation, defuzzifier)
    got = Engine(rb).evaluate({"e": POINTS[:, 0], "de": POINTS[:, 1]})["du"]
    want = np.array([reference(rb, e, de) for e, de in POINTS])
    # the reference grid step is 1e-5: its centroid error is O(h^2), its maxima O(h)
    tol = 1e-8 if defuzzifier in AREA_DEFUZZIFIERS else 2.5e-5
    np.testing.assert_allclose(got, want, atol=tol, rtol=0)


def test_generic_sweep_path_with_three_overlapping_terms() -> None:
    # width 0.6 > 1/3 spacing: three output terms overlap, so the pairwise fast path
    # does not apply and the general breakpoint sweep computes the centroid
    wide = tuple(
        Term(t.name, "triangle", (t.params[1] - 0.6, t.params[1], t.params[1] + 0.6))
        for t in partition("triangle")
    )
    rb = macvicar_whelan(output_terms=wide)
    eng = Engine(rb)
    assert eng._outputs[0].fast_centroid is None
    got = eng.evaluate({"e": POINTS[:, 0], "de": POINTS[:, 1]})["du"]
    want = np.array([reference(rb, e, de) for e, de in POINTS])
    np.testing.assert_allclose(got, want, atol=1e-8, rtol=0)


def test_product_and_and_rule_weights_against_reference() -> None:
    rb = macvicar_whelan(and_="product")
    weighted = tuple(
        Rule(r.antecedent, r.consequents, weight=0.25 + 0.75 * ((k * 7) % 11) / 10)
        for k, r in enumerate(rb.rules)
    )
    rb = RuleBase(rb.name, rb.inputs, rb.outputs, weighted, rb.operators, "centroid")
    got = evaluate(rb, {"e": POINTS[:, 0], "de": POINTS[:, 1]})["du"]
    want = np.array([reference(rb, e, de) for e, de in POINTS])
    np.testing.assert_allclose(got, want, atol=1e-8, rtol=0)


def test_smooth_output_terms_use_grid_within_bound() -> None:
    gauss = tuple(Term(name, "gaussian", (-1 + k / 3, 0.15)) for k, name in enumerate(LABELS))
    rb = macvicar_whelan(output_terms=gauss)
    got = evaluate(rb, {"e": POINTS[:6, 0], "de": POINTS[:6, 1]})["du"]
    want = np.array([reference(rb, e, de, n=2_000_001) for e, de in POINTS[:6]])
    np.testing.assert_allclose(got, want, atol=1e-9, rtol=0)


def test_label_peak_grid_is_the_closed_form_term_centroids() -> None:
    # at (i/3, j/3) only rule (i, j) fires, with strength 1: the output is the centroid of one
    # whole output term. Interior terms are symmetric triangles (centroid = peak); the outer
    # ones are half triangles clipped by the range: centroid 1/3 of the way in, +-8/9.
    rb = macvicar_whelan()
    k = np.arange(-3, 4)
    e, de = np.meshgrid(k / 3, k / 3, indexing="ij")
    got = evaluate(rb, {"e": e, "de": de})["du"]
    idx = np.clip(k[:, None] + k[None, :], -3, 3)
    want = np.where(np.abs(idx) == 3, np.sign(idx) * 8 / 9, idx / 3)
    np.testing.assert_allclose(got, want, atol=1e-12)


def test_macvicar_whelan_is_odd_symmetric_and_bounded() -> None:
    rb = macvicar_whelan()
    g = np.linspace(-1.1, 1.1, 89)
    e, de = np.meshgrid(g, g, indexing="ij")
    du = evaluate(rb, {"e": e, "de": de})["du"]
    np.testing.assert_allclose(du, -du[::-1, ::-1], atol=1e-12)  # F(-e, -de) = -F(e, de)
    np.testing.assert_allclose(du, du.T, atol=1e-12)  # symmetric table, same terms
    assert np.all(np.abs(du) <= 8 / 9 + 1e-12)


def test_product_sum_macvicar_whelan_is_monotone() -> None:
    # product AND, product implication, bounded sum, centroid over a Ruspini partition is a
    # monotone interpolation of the table
    rb = macvicar_whelan("product", "bounded_sum", and_="product")
    g = np.linspace(-1.1, 1.1, 221)
    e, de = np.meshgrid(g, g, indexing="ij")
    du = evaluate(rb, {"e": e, "de": de})["du"]
    assert np.all(np.diff(du, axis=0) >= -1e-12)
    assert np.all(np.diff(du, axis=1) >= -1e-12)


def test_min_max_centroid_macvicar_whelan_is_not_monotone_and_reference_agrees() -> None:
    # A finding worth knowing before deploying: the paper's min/max/centroid surface dips
    # (about 1 % of the range) where a clipped outer term's area shifts the centroid back.
    rb = macvicar_whelan()
    e0, e1, de = -0.5, -0.475, -0.6
    lo, hi = evaluate_point(rb, e=e0, de=de)["du"], evaluate_point(rb, e=e1, de=de)["du"]
    assert hi < lo - 1e-3
    assert reference(rb, e1, de) < reference(rb, e0, de) - 1e-3
    g = np.linspace(-1.1, 1.1, 221)
    e, dd = np.meshgrid(g, g, indexing="ij")
    assert np.diff(evaluate(rb, {"e": e, "de": dd})["du"], axis=0).min() > -0.01


def test_weighted_average_is_eq10_over_term_centres() -> None:
    rb = macvicar_whelan(defuzzifier="weighted_average")
    e, de = 0.1, -0.45
    # independent: activation per output term = max of the firing strengths of its rules
    mu = {
        v: {t.name: float(independent_mu(t, np.array(x))) for t in rb.input(v).terms}
        for v, x in (("e", e), ("de", de))
    }
    centres = {name: max(-1.0, min(1.0, -1 + k / 3)) for k, name in enumerate(LABELS)}
    act: dict[str, float] = {}
    for i, a in enumerate(LABELS):
        for j, b in enumerate(LABELS):
            out = LABELS[min(3, max(-3, i + j - 6)) + 3]
            act[out] = max(act.get(out, 0.0), min(mu["e"][a], mu["de"][b]))
    want = sum(act[n] * centres[n] for n in act) / sum(act.values())
    assert evaluate_point(rb, e=e, de=de)["du"] == pytest.approx(want, abs=1e-14)


@pytest.mark.parametrize("aggregation, expected", [("max", 0.5), ("bounded_sum", 0.8)])
def test_rules_sharing_a_consequent_are_aggregated(aggregation: str, expected: float) -> None:
    # two rules, same consequent, strengths 0.5 and 0.3 (weights); nothing overwrites
    v_in = Variable("x", 0.0, 1.0, (Term("A", "trapezoid", (-1.0, 0.0, 1.0, 2.0)),))
    v_out = Variable("y", 0.0, 1.0, (Term("S", "singleton", (0.5,)),))
    rules = (
        Rule(Proposition("x", "A"), (Consequent("y", "S"),), weight=0.5),
        Rule(Proposition("x", "A"), (Consequent("y", "S"),), weight=0.3),
    )
    rb = RuleBase(
        "agg",
        (v_in,),
        (v_out,),
        rules,
        Operators(aggregation=aggregation),
        defuzzifier="weighted_average",
    )
    eng = Engine(rb)
    act = eng._outputs[0].pieces.activations(eng.firing_strengths({"x": [0.4]}))
    assert act[0, 0] == pytest.approx(expected)


def test_nan_gives_nan_and_infinity_is_clamped() -> None:
    rb = macvicar_whelan()
    out = evaluate(rb, {"e": [np.nan, 0.2, np.inf, -np.inf, 1e308], "de": [0.0, np.nan, 0, 0, 0]})
    du = out["du"]
    assert np.isnan(du[0]) and np.isnan(du[1])
    edge = evaluate_point(rb, e=1.0, de=0.0)["du"]
    assert du[2] == pytest.approx(edge) and du[4] == pytest.approx(edge)
    assert du[3] == pytest.approx(-edge)


def test_extend_policy_evaluates_outside_the_range() -> None:
    # with narrow input terms (shoulders at +-0.5) `extend` and `clamp` agree; with a triangle
    # whose support ends past the range, `extend` sees membership fall off beyond the end
    inp = (
        Term("N", "triangle", (-2.0, -1.0, 0.0)),
        Term("Z", "triangle", (-1.0, 0.0, 1.0)),
        Term("P", "triangle", (0.0, 1.0, 2.0)),
    )
    outp = (
        Term("N", "triangle", (-2.0, -1.0, 0.0)),
        Term("Z", "triangle", (-1.0, 0.0, 1.0)),
        Term("P", "triangle", (0.0, 1.0, 2.0)),
    )
    rules = tuple(Rule(Proposition("x", n), (Consequent("y", n),)) for n in "NZP")
    base = dict(
        inputs=(Variable("x", -1.0, 1.0, inp),),
        outputs=(Variable("y", -1.0, 1.0, outp, 0.25),),
        rules=rules,
    )
    clamp = RuleBase("c", **base)  # type: ignore[arg-type]
    extend = RuleBase("x", out_of_range="extend", **base)  # type: ignore[arg-type]
    assert evaluate_point(clamp, x=1.5)["y"] == pytest.approx(evaluate_point(clamp, x=1.0)["y"])
    assert evaluate_point(extend, x=1.5)["y"] != pytest.approx(evaluate_point(extend, x=1.0)["y"])
    # beyond every support no rule fires: the output's default
    assert evaluate_point(extend, x=2.5)["y"] == 0.25
    # the scalar path (used by evaluate_point) agrees with the batch path everywhere
    eng = Engine(extend)
    assert eng._scalar is not None
    xs = np.linspace(-3.0, 3.0, 241)
    batch = eng.evaluate({"x": xs})["y"]
    np.testing.assert_allclose([eng.evaluate_point(x=x)["y"] for x in xs], batch, atol=1e-13)


def test_no_rule_firing_gives_default_or_nan() -> None:
    inp = (Term("LO", "left_shoulder", (0.2, 0.5)), Term("HI", "right_shoulder", (0.4, 0.8)))
    outp = (Term("A", "triangle", (0.0, 0.5, 1.0)),)
    rules = (Rule(Proposition("x", "LO"), (Consequent("y", "A"),)),)
    for default, expect_nan in ((None, True), (0.75, False)):
        rb = RuleBase(
            "d", (Variable("x", 0.0, 1.0, inp),), (Variable("y", 0.0, 1.0, outp, default),), rules
        )
        y = evaluate_point(rb, x=0.9)["y"]
        assert math.isnan(y) if expect_nan else y == 0.75
        assert evaluate_point(rb, x=0.1)["y"] == pytest.approx(0.5)


def test_broadcasting_and_shapes() -> None:
    rb = macvicar_whelan()
    e = np.linspace(-1, 1, 5)[:, None]
    de = np.linspace(-1, 1, 3)[None, :]
    du = evaluate(rb, {"e": e, "de": de})["du"]
    assert du.shape == (5, 3)
    assert du[4, 1] == pytest.approx(evaluate_point(rb, e=1.0, de=0.0)["du"])
    assert evaluate(rb, {"e": 0.3, "de": -0.2})["du"].shape == ()


@pytest.mark.parametrize(
    "inputs, match",
    [
        ({"e": [0.1]}, r"missing input\(s\) 'de'"),
        ({"e": 0.1, "de": 0.2, "dx": 1.0}, r"unknown input\(s\) 'dx'"),
        ({"e": "abc", "de": 0.2}, r"input 'e': expected numbers"),
        ({"e": [0.1, 0.2], "de": [0.1, 0.2, 0.3]}, r"do not broadcast"),
    ],
)
def test_bad_inputs_are_clear_errors(inputs: dict[str, object], match: str) -> None:
    with pytest.raises(EvaluationError, match=match):
        Engine(macvicar_whelan()).evaluate(inputs)  # type: ignore[arg-type]


@pytest.mark.parametrize("and_", ["min", "product"])
def test_scalar_path_agrees_with_vectorised_engine(and_: str) -> None:
    rb = macvicar_whelan(and_=and_)
    weighted = tuple(
        Rule(r.antecedent, r.consequents, weight=0.3 + 0.7 * ((k * 5) % 7) / 6)
        for k, r in enumerate(rb.rules)
    )
    rb = RuleBase(rb.name, rb.inputs, rb.outputs, weighted, rb.operators, "centroid")
    eng = Engine(rb)
    assert eng._scalar is not None  # the pure-Python path is the one under test
    rng = np.random.default_rng(11)
    pts = np.vstack(
        [
            rng.uniform(-1.3, 1.3, size=(400, 2)),
            np.array(np.meshgrid(np.arange(-3, 4) / 3, np.arange(-3, 4) / 3)).reshape(2, -1).T,
            [[np.inf, 0.2], [-np.inf, -0.4], [1e300, -1e300]],
        ]
    )
    batch = eng.evaluate({"e": pts[:, 0], "de": pts[:, 1]})["du"]
    single = np.array([eng.evaluate_point(e=e, de=de)["du"] for e, de in pts])
    np.testing.assert_allclose(single, batch, atol=1e-13, rtol=0)
    assert math.isnan(eng.evaluate_point(e=math.nan, de=0.1)["du"])


def test_scalar_path_only_for_its_shape() -> None:
    wide = tuple(
        Term(t.name, "triangle", (t.params[1] - 0.6, t.params[1], t.params[1] + 0.6))
        for t in partition("triangle")
    )
    assert Engine(macvicar_whelan(output_terms=wide))._scalar is None
    assert Engine(macvicar_whelan(defuzzifier="bisector"))._scalar is None
    # the general path still answers single points
    rb = macvicar_whelan(output_terms=wide)
    assert evaluate_point(rb, e=0.2, de=0.1)["du"] == pytest.approx(
        reference(rb, 0.2, 0.1), abs=1e-8
    )


def test_scalar_path_with_three_inputs_agrees_with_vectorised_engine() -> None:
    names = ("N", "Z", "P")
    inp = (
        Term("N", "left_shoulder", (-1.0, 0.0)),
        Term("Z", "triangle", (-1.0, 0.0, 1.0)),
        Term("P", "right_shoulder", (0.0, 1.0)),
    )
    out = tuple(Term(n, "triangle", (k - 2.0, k - 1.0, k + 0.0)) for k, n in enumerate(names))
    rules = []
    for i in range(3):
        for j in range(3):
            for k in range(3):
                label = names[min(2, max(0, i + j + k - 3 + 1))]
                props = tuple(
                    Proposition(v, names[t]) for v, t in zip("abc", (i, j, k), strict=True)
                )
                rules.append(Rule(Compound("and", props), (Consequent("y", label),), 0.5 + k / 4))
    rb = RuleBase(
        "three",
        tuple(Variable(v, -1.0, 1.0, inp) for v in "abc"),
        (Variable("y", -1.0, 1.0, out),),
        tuple(rules),
    )
    eng = Engine(rb)
    assert eng._scalar is not None
    pts = np.random.default_rng(5).uniform(-1.2, 1.2, size=(200, 3))
    batch = eng.evaluate({"a": pts[:, 0], "b": pts[:, 1], "c": pts[:, 2]})["y"]
    single = [eng.evaluate_point(a=a, b=b, c=c)["y"] for a, b, c in pts]
    np.testing.assert_allclose(single, batch, atol=1e-13, rtol=0)
    a, b, c = pts[0]
    assert single[0] == pytest.approx(fine_grid_reference(rb, {"a": a, "b": b, "c": c}), abs=1e-8)


@pytest.mark.parametrize("low, high", [(-1000.0, 1000.0), (0.0, 30.0), (-1e-6, 1e-6)])
def test_output_in_real_units_scales_the_unit_surface(low: float, high: float) -> None:
    # affine map of the output universe: the centroid maps with it (fast and scalar paths)
    def scaled(t: Term) -> Term:
        return Term(t.name, t.shape, tuple(low + (p + 1) / 2 * (high - low) for p in t.params))

    unit = macvicar_whelan()
    out = unit.outputs[0]
    rb = RuleBase(
        "real",
        unit.inputs,
        (Variable("du", low, high, tuple(scaled(t) for t in out.terms)),),
        unit.rules,
    )
    eng = Engine(rb)
    assert eng._outputs[0].fast_centroid is not None and eng._scalar is not None
    pts = np.random.default_rng(2).uniform(-1.1, 1.1, size=(50, 2))
    want = low + (evaluate(unit, {"e": pts[:, 0], "de": pts[:, 1]})["du"] + 1) / 2 * (high - low)
    got = eng.evaluate({"e": pts[:, 0], "de": pts[:, 1]})["du"]
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * (high - low))
    single = [eng.evaluate_point(e=e, de=de)["du"] for e, de in pts]
    np.testing.assert_allclose(single, want, rtol=0, atol=1e-12 * (high - low))
