"""Gaussian output terms under a probabilistic sum (product implication, centroid): the proven
quadrature of ``fuzzkit.fuzzy.smooth_quadrature``, in the engine and the generated code.

The reference is written here: expanding ``1 - prod(1 - L_p g_p)`` over the subsets of the
pieces, each product of Gaussians is one scaled Gaussian, integrated in closed form with erf
(no quadrature at all). It is checked at random points, the corners, and points where every
firing strength is below 1e-20; the generated Python and C (float, double) are checked against
the engine by ``--verify`` (random points, edges, weak points).
"""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest
from _codegen_util import needs_cc
from _mamdani_reference import firing

from fuzzkit.codegen.exact import emit_exact, unsupported_reason
from fuzzkit.codegen.verify import verify_exact_c, verify_exact_python
from fuzzkit.fuzzy import model
from fuzzkit.fuzzy.inference import Engine
from fuzzkit.fuzzy.output_geometry import OutputPieces
from fuzzkit.fuzzy.smooth_quadrature import applies, centroid_bound

OUT_TERMS = ((-0.7, 0.25), (0.0, 0.2), (0.7, 0.3))  # (mean, sigma) on [-1, 1]


def rulebase(sigma_in: float = 0.05) -> model.RuleBase:
    """A 3x3 grid: narrow Gaussian inputs (every strength tiny between their centres)."""
    names = ("N", "Z", "P")
    centres = zip(names, (-0.5, 0.0, 0.5), strict=True)
    terms = tuple(model.Term(n, "gaussian", (c, sigma_in)) for n, c in centres)
    inputs = tuple(model.Variable(v, -1.0, 1.0, terms) for v in ("e", "de"))
    u = model.Variable(
        "u", -1.0, 1.0, tuple(model.Term(f"T{i}", "gaussian", p) for i, p in enumerate(OUT_TERMS))
    )
    rules = tuple(
        model.Rule(
            model.Compound("and", (model.Proposition("e", a), model.Proposition("de", b))),
            (model.Consequent("u", f"T{min(2, max(0, i + j - 1))}"),),
        )
        for (i, a), (j, b) in itertools.product(enumerate(names), repeat=2)
    )
    ops = model.Operators("product", "max", "product", "probabilistic_sum")
    return model.RuleBase("gauss_psum", inputs, (u,), rules, ops, "centroid")


def reference(rb: model.RuleBase, levels: list[float]) -> float | None:
    """The centroid of 1 - prod(1 - L_r g_r) by inclusion-exclusion, in closed form."""
    out = rb.outputs[0]
    lo, hi = out.low, out.high
    pieces = [
        (lv, *out.terms[out.term_index(r.consequents[0].term)].params)
        for lv, r in zip(levels, rb.rules, strict=True)
        if lv > 0.0
    ]
    area = moment = 0.0
    for k in range(1, len(pieces) + 1):
        for sub in itertools.combinations(pieces, k):
            prec = sum(1.0 / s**2 for _, _, s in sub)
            var = 1.0 / prec
            mu = var * sum(m / s**2 for _, m, s in sub)
            log_c = -0.5 * (sum(m * m / s**2 for _, m, s in sub) - mu * mu * prec)
            scale = (-1.0) ** (k + 1) * math.prod(lv for lv, _, _ in sub) * math.exp(log_c)
            sd = math.sqrt(var)
            a = (
                sd
                * math.sqrt(0.5 * math.pi)
                * (
                    math.erf((hi - mu) / (sd * math.sqrt(2)))
                    - math.erf((lo - mu) / (sd * math.sqrt(2)))
                )
            )
            edge = var * (
                math.exp(-0.5 * ((lo - mu) / sd) ** 2) - math.exp(-0.5 * ((hi - mu) / sd) ** 2)
            )
            area += scale * a
            moment += scale * (mu * a + edge)
    return None if area <= 0.0 else moment / area


def _points() -> list[tuple[float, float]]:
    rng = np.random.default_rng(3)
    corners = list(itertools.product((-1.0, 1.0), repeat=2))
    tiny = [(-0.25, 0.25), (0.25, 0.75), (1.0, 0.25), (-0.75, -1.0)]  # between the centres
    return [*corners, *tiny, *map(tuple, rng.uniform(-1, 1, (40, 2)).tolist())]


def test_the_engine_meets_the_proven_bound_against_a_closed_form_reference() -> None:
    rb = rulebase()
    out = rb.outputs[0]
    rule = applies(rb, out, OutputPieces(rb, out))
    assert rule is not None and rule.bound <= 1e-9 * (out.high - out.low)
    engine = Engine(rb)
    pts = _points()
    got = engine.evaluate({"e": np.array([p[0] for p in pts]), "de": np.array([p[1] for p in pts])})
    rounding = 1e-13
    smallest = 1.0
    for (e, de), y in zip(pts, np.asarray(got["u"]), strict=True):
        levels = firing(rb, {"e": e, "de": de})
        smallest = min(smallest, max(levels))
        ref = reference(rb, levels)
        assert ref is not None
        assert abs(y - ref) <= rule.bound + rounding, (e, de, y, ref)
    assert smallest < 1e-20  # the tiny points are tiny


@pytest.mark.parametrize("cells, n", [(2, 6), (4, 3), (4, 4), (8, 2)])
def test_the_bound_holds_for_coarse_rules_where_the_error_shows(cells: int, n: int) -> None:
    """The bound itself, on rules coarse enough that the error is far above rounding (1e-6 to
    1e-3 here): one Gaussian piece on [-1, 1], against its centroid in closed form. (On the
    3x3 grid's nine pieces the finite bounds need rules whose error is already at rounding.)"""
    m, sd = 0.3, 0.2
    rb = rulebase()
    u = dataclasses.replace(rb.outputs[0], terms=(model.Term("T0", "gaussian", (m, sd)),))
    one = dataclasses.replace(rb, rules=(rb.rules[0],), outputs=(u,))
    ref = reference(one, [0.5])
    assert ref is not None
    t, w = np.polynomial.legendre.leggauss(n)
    h = 1.0 / cells
    nodes = ((-1.0 + h * (2 * np.arange(cells) + 1))[:, None] + h * t[None, :]).ravel()
    weights = np.tile(h * w, cells)
    f = np.exp(-0.5 * ((nodes - m) / sd) ** 2)
    error = abs(float((f * weights * nodes).sum() / (f * weights).sum()) - ref)
    bound = centroid_bound(-1.0, 1.0, [m], [sd], cells, n)
    assert 1e-6 < error <= bound < 1.0, (error, bound)


def test_the_header_prints_the_bound_and_other_smooth_classes_stay_refused() -> None:
    rb = rulebase()
    assert unsupported_reason(rb) is None
    text = "".join(emit_exact(rb, "python").values())
    out = rb.outputs[0]
    rule = applies(rb, out, OutputPieces(rb, out))
    assert rule is not None
    assert f"{rule.bound:.2e}" in " ".join(text.split())
    bounded = model.RuleBase(
        rb.name, rb.inputs, rb.outputs, rb.rules,
        model.Operators("product", "max", "product", "bounded_sum"), "centroid",
    )  # fmt: skip
    assert "gaussian" in str(unsupported_reason(bounded))


@pytest.mark.parametrize(
    "target",
    ["python", pytest.param("float", marks=needs_cc), pytest.param("double", marks=needs_cc)],
)
def test_the_generated_code_equals_the_engine(target: str) -> None:
    rb = rulebase()
    if target == "python":
        result = verify_exact_python(rb, emit_exact(rb, "python"), n=300)
    else:
        result = verify_exact_c(rb, target, emit_exact(rb, "c", target), n=300)
    assert result.ok, result.describe()
