"""The engine at scale: internal chunking of large batches, and outputs with smooth (gaussian)
terms integrated by the compiled grid kernel, checked against the independent fine-grid
Mamdani of tests/_mamdani_reference.py."""

from __future__ import annotations

import dataclasses
import tracemalloc

import numpy as np
import pytest
from _mamdani_reference import reference as fine_grid_reference

from fuzzkit.formats.registry import load
from fuzzkit.fuzzy.inference import Engine
from fuzzkit.fuzzy.model import RuleBase, Term


def gaussian_output(defuzzifier: str = "centroid", sigma: float = 0.15) -> RuleBase:
    """MacVicar-Whelan with gaussian output terms at the triangles' peaks."""
    rb = load("macvicar_whelan")
    out = rb.outputs[0]
    terms = tuple(Term(t.name, "gaussian", (float(t.params[1]), sigma)) for t in out.terms)
    return dataclasses.replace(
        rb, outputs=(dataclasses.replace(out, terms=terms),), defuzzifier=defuzzifier
    )


# the reference's 200,001-point trapezoid is accurate to ~1e-9 on smooth sets; the maxima are
# located to the reference's grid spacing (1e-5 of the range)
TOLERANCE = {
    "centroid": 1e-7,
    "bisector": 1e-7,
    "smallest_of_maximum": 2e-5,
    "largest_of_maximum": 2e-5,
    "mean_of_maximum": 2e-5,
}


@pytest.mark.parametrize("defuzzifier", sorted(TOLERANCE))
def test_gaussian_outputs_match_the_independent_fine_grid(defuzzifier: str) -> None:
    rb = gaussian_output(defuzzifier)
    eng = Engine(rb)
    rng = np.random.default_rng(7)
    pts = np.concatenate([rng.uniform(-1.1, 1.1, (6, 2)), [[0.0, 0.0], [1.0, -1.0]]])
    got = eng.evaluate({"e": pts[:, 0], "de": pts[:, 1]})["du"]
    for (e, de), value in zip(pts, got, strict=True):
        ref = fine_grid_reference(rb, {"e": float(e), "de": float(de)})
        assert ref is not None
        assert value == pytest.approx(ref, abs=TOLERANCE[defuzzifier]), (e, de)


def test_gaussian_output_batch_equals_pointwise_and_is_antisymmetric() -> None:
    eng = Engine(gaussian_output())
    rng = np.random.default_rng(3)
    e, de = rng.uniform(-1, 1, 40), rng.uniform(-1, 1, 40)
    batch = eng.evaluate({"e": e, "de": de})["du"]
    single = [eng.evaluate_point(e=float(a), de=float(b))["du"] for a, b in zip(e, de, strict=True)]
    np.testing.assert_allclose(batch, single, rtol=0, atol=1e-12)
    # the rule table and the output terms are odd-symmetric: F(-e, -de) = -F(e, de)
    mirrored = eng.evaluate({"e": -e, "de": -de})["du"]
    np.testing.assert_allclose(mirrored, -batch, rtol=0, atol=1e-9)


def test_chunked_evaluation_equals_one_pass(monkeypatch: pytest.MonkeyPatch) -> None:
    eng = Engine(load("macvicar_whelan"))
    rng = np.random.default_rng(0)
    e = rng.uniform(-1.2, 1.2, (301, 70))
    de = rng.uniform(-1.2, 1.2, (301, 70))
    e[5, 5] = np.nan
    chunked = eng.evaluate({"e": e, "de": de})["du"]
    assert e.size > eng.chunk_points  # really split
    monkeypatch.setattr(eng, "chunk_points", 10**9)
    whole = eng.evaluate({"e": e, "de": de})["du"]
    assert chunked.shape == e.shape
    np.testing.assert_array_equal(chunked, whole)
    assert np.isnan(chunked[5, 5])


def test_large_batch_memory_stays_bounded() -> None:
    eng = Engine(load("macvicar_whelan"))
    n = 200_000
    x = np.linspace(-1, 1, n)
    tracemalloc.start()
    try:
        eng.evaluate({"e": x, "de": x[::-1]})
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    # inputs and result are 3 x 1.6 MB; unchunked the intermediates grew to ~290 MB here
    assert peak < 60e6
