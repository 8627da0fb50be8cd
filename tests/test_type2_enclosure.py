"""The IT2 value enclosures (fuzzkit/analysis/type2_enclosure.py) hold the exact engine's
``y_l``, ``y_r`` and output at every point of a dense grid in each rectangle."""

from __future__ import annotations

import numpy as np
import pytest

from fuzzkit import load
from fuzzkit.analysis.type2_enclosure import Type2Enclosure
from fuzzkit.fuzzy.inference import Engine
from fuzzkit.fuzzy.type2_kernel import evaluate_points

NAME = "macvicar_whelan_it2"


def _boxes() -> list[np.ndarray]:
    rng = np.random.default_rng(43)
    out = [np.array([[0.05, 0.12], [-0.3, -0.25]]), np.array([[-0.6, -0.2], [0.1, 0.5]])]
    for width in (0.02, 0.1, 0.4):
        for _ in range(3):
            lo = rng.uniform(-1.1, 1.0 - width, size=2)
            out.append(np.stack([lo, lo + width], axis=1))
    return out


@pytest.mark.parametrize("box", _boxes(), ids=lambda b: f"{b[0, 0]:.2f},{b[1, 0]:.2f}")
def test_the_enclosure_holds_the_engine_on_a_dense_grid(box: np.ndarray) -> None:
    rb = load(NAME)
    enc = Type2Enclosure(rb)
    got = enc.enclose(box)
    assert got is not None
    g0, g1 = np.meshgrid(np.linspace(*box[0], 25), np.linspace(*box[1], 25), indexing="ij")
    x = np.stack([g0.ravel(), g1.ravel()], axis=1)
    rows = evaluate_points(x, enc.firing, enc.layout)
    out = Engine(rb).evaluate({"e": x[:, 0], "de": x[:, 1]})["du"]
    for (lo, hi), v in ((got.y_l, rows[:, 0]), (got.y_r, rows[:, 1]), (got.output, out)):
        assert lo <= v.min() and v.max() <= hi, (lo, v.min(), v.max(), hi)


def test_a_point_rectangle_gives_the_engine_s_interval_to_rounding() -> None:
    # independent of the enclosure's footprint argument: at a point both footprints are the
    # engine's own, so the bounds close onto the value
    rb = load(NAME)
    enc = Type2Enclosure(rb)
    got = enc.enclose(np.array([[0.3, 0.3], [-0.2, -0.2]]))
    assert got is not None and got.narrow
    want = Engine(rb).evaluate_point(e=0.3, de=-0.2)["du"]
    assert got.output[0] <= want <= got.output[1]
    assert got.output[1] - got.output[0] < 1e-9


def test_a_small_rectangle_is_tighter_than_the_wide_fallback() -> None:
    # the narrow footprint applies on a small rectangle and gives inner bounds: y_l's upper
    # bound below y_r's lower one (a real interval, not the [y_l^w, y_r^w] fallback)
    enc = Type2Enclosure(load(NAME))
    got = enc.enclose(np.array([[0.3, 0.31], [-0.2, -0.19]]))
    assert got is not None and got.narrow
    assert got.y_l[1] < got.y_r[0]


def test_a_rectangle_where_no_rule_surely_fires_is_refused_with_a_nan_default() -> None:
    # over the whole square every upper level can be 0 at some point (seen per rule, not per
    # point), and the output's default is NaN: no enclosure rather than a wrong one
    rb = load(NAME)
    assert rb.outputs[0].default is None
    assert Type2Enclosure(rb).enclose(np.array([[-1.0, 1.0], [-1.0, 1.0]])) is None
