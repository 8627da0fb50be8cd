"""Gaussian output terms under max aggregation: the engine's closed forms (erf) against a fine
trapezoid (2e6 steps) of the aggregated set written out here, every term from its textbook
formula, for every implication and defuzzifier, at random points and corners. (scipy's
adaptive quad was tried as the reference and is off by 1e-9 at the clip points' kinks.)"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from _mamdani_reference import firing

from fuzzkit.formats.registry import load
from fuzzkit.fuzzy.gaussian_geometry import GaussianGeometry
from fuzzkit.fuzzy.inference import Engine
from fuzzkit.fuzzy.model import RuleBase

FILE = Path(__file__).parent / "data" / "gaussian3x3.yaml"
MAXIMA = ("mean_of_maximum", "smallest_of_maximum", "largest_of_maximum")


def _variant(implication: str, defuzzifier: str) -> RuleBase:
    rb = load(FILE)
    ops = dataclasses.replace(rb.operators, implication=implication)
    return dataclasses.replace(rb, operators=ops, defuzzifier=defuzzifier)


#: Reference grid points: steps of 5e-6 (make test) or 1e-6 (make verify); the trapezoid's
#: error, kinks included, is below 1e-11 either way.
GRIDS = {"cover": 400_001, "full": 2_000_001}


def _set(rb: RuleBase, point: dict[str, float], y: np.ndarray) -> np.ndarray:
    """The aggregated set at ``y``, one rule at a time, each term from its textbook formula."""
    out = rb.outputs[0]
    product = rb.operators.implication == "product"
    agg = np.zeros_like(y)
    for rule, level in zip(rb.rules, firing(rb, point), strict=True):
        m, s = out.term(rule.consequents[0].term).params
        g = np.exp(-((y - m) ** 2) / (2.0 * s * s))
        agg = np.maximum(agg, level * g if product else np.minimum(level, g))
    return agg


def _reference(rb: RuleBase, point: dict[str, float], grid: int) -> float:
    out = rb.outputs[0]
    y = np.linspace(out.low, out.high, grid)
    f = _set(rb, point, y)
    if rb.defuzzifier == "centroid":
        return float(np.trapezoid(f * y, y) / np.trapezoid(f, y))
    if rb.defuzzifier == "bisector":
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(y))])
        return float(np.interp(0.5 * cum[-1], cum, y))
    at = y[f >= f.max() * (1 - 1e-10)]
    som, lom = float(at[0]), float(at[-1])
    return {"smallest_of_maximum": som, "largest_of_maximum": lom}.get(
        rb.defuzzifier, 0.5 * (som + lom)
    )


@pytest.mark.parametrize("depth", ["cover", pytest.param("full", marks=pytest.mark.verify)])
@pytest.mark.parametrize("implication", ["min", "product"])
@pytest.mark.parametrize("defuzzifier", ["centroid", "bisector", *MAXIMA])
def test_gaussian_outputs_in_closed_form_equal_a_fine_trapezoid(
    implication: str, defuzzifier: str, depth: str
) -> None:
    rb = _variant(implication, defuzzifier)
    engine = Engine(rb)
    assert isinstance(engine._outputs[0].geometry, GaussianGeometry)  # type: ignore[union-attr]
    rng = np.random.default_rng(7)
    points = [(-1.0, 1.0), (1.0, 1.0), *rng.uniform(-1, 1, (4, 2)).tolist()]
    if depth == "cover":
        points = points[1:3]
    grid = GRIDS[depth]
    # the maxima are off by up to one reference step
    tol = 2 * 2.0 / (grid - 1) if defuzzifier in MAXIMA else 1e-10
    for e, de in points:
        got = engine.evaluate_point(e=e, de=de)["du"]
        assert got == pytest.approx(_reference(rb, {"e": e, "de": de}, grid), abs=tol), (e, de)


def test_a_101x101_surface_of_gaussian_outputs_is_the_reference_where_sampled() -> None:
    rb = load(FILE)
    g = np.linspace(-1, 1, 101)
    e, de = np.meshgrid(g, g)
    surface = Engine(rb).evaluate({"e": e, "de": de})["du"]
    assert np.all(np.isfinite(surface))
    for i, j in [(50, 50), (13, 77)]:
        want = _reference(rb, {"e": float(e[i, j]), "de": float(de[i, j])}, GRIDS["cover"])
        assert surface[i, j] == pytest.approx(want, abs=1e-10)
