"""Interval type-2 inference: the exact engine against an independent brute force, properties.

The brute force (tests/_type2_reference.py) samples the output sets from textbook memberships
and tries every switch point; the continuous engine must agree with it to the grid's
quadrature error, which must shrink like h^2 (so the engine is the continuous limit, not a
grid of its own), and the discretised engine (``resolution:``) must agree to rounding.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from _type2_reference import centroid_interval, firing_intervals, output_sets, vertex_interval

from fuzzkit.errors import EvaluationError
from fuzzkit.formats.registry import load, loads
from fuzzkit.fuzzy.inference import Engine
from fuzzkit.fuzzy.type2_model import Type2RuleBase, footprint_of, with_footprint

SMALL = """
name: it2_small
inputs:
  e:
    range: [-1, 1]
    terms:
      N:
        upper: {shape: triangle, points: [-2, -1, 0.2]}
        lower: {shape: triangle, points: [-2, -1, -0.2], scale: 0.8}
      P:
        upper: {shape: trapezoid, points: [-0.3, 0.5, 1, 2]}
        lower: {shape: triangle, points: [0.2, 1, 2], scale: 0.7}
outputs:
  u:
    range: [-1, 1]
    terms:
      N:
        upper: {shape: triangle, points: [-1.5, -1, 0.3]}
        lower: {shape: triangle, points: [-1.2, -1, 0.0], scale: 0.6}
      Z: {shape: triangle, points: [-0.5, 0, 0.5]}
      P:
        upper: {shape: trapezoid, points: [-0.3, 0.6, 1, 1.5]}
        lower: {shape: triangle, points: [0.0, 1, 1.2], scale: 0.6}
operators: {and: $AND, implication: $IMP}
type_reduction: $TR
rules:
  - {if: {e: N}, then: {u: N}}
  - {if: {e: P}, then: {u: P}}
  - {if: {e: N}, then: {u: Z}, weight: 0.3}
"""


def small(and_: str = "min", imp: str = "min", tr: str = "karnik-mendel") -> Type2RuleBase:
    rb = loads(SMALL.replace("$AND", and_).replace("$IMP", imp).replace("$TR", tr))
    assert isinstance(rb, Type2RuleBase)
    return rb


MW_POINTS = np.random.default_rng(32).uniform(-1.1, 1.1, (12, 2))


@pytest.mark.parametrize("imp", ["min", "product"])
def test_small_system_interval_matches_the_brute_force(imp: str) -> None:
    rb = small(imp=imp)
    xs = np.linspace(-1, 1, 23)
    y_l, y_r = Engine(rb).centroid_intervals({"e": xs})["u"]
    for n in (4001, 16001):
        want = np.array([centroid_interval(rb, {"e": float(x)}, n) for x in xs])
        err = max(np.abs(y_l - want[:, 0]).max(), np.abs(y_r - want[:, 1]).max())
        if n == 4001:
            coarse = err
    # second-order convergence of the reference towards the engine: 16x finer grid error
    assert err < 2e-7
    assert err < coarse / 8


@pytest.mark.parametrize("and_", ["min", "product"])
def test_macvicar_whelan_it2_interval_matches_the_brute_force(and_: str) -> None:
    rb = load("macvicar_whelan_it2")
    rb = replace(rb, operators=replace(rb.operators, and_=and_))
    got = Engine(rb).centroid_intervals({"e": MW_POINTS[:, 0], "de": MW_POINTS[:, 1]})["du"]
    want = np.array(
        [centroid_interval(rb, {"e": float(e), "de": float(d)}, 20001) for e, d in MW_POINTS]
    )
    np.testing.assert_allclose(got[0], want[:, 0], atol=1e-7)
    np.testing.assert_allclose(got[1], want[:, 1], atol=1e-7)
    # the crisp output is the interval's midpoint
    crisp = Engine(rb).evaluate({"e": MW_POINTS[:, 0], "de": MW_POINTS[:, 1]})["du"]
    np.testing.assert_allclose(crisp, 0.5 * (got[0] + got[1]), atol=1e-15)


@pytest.mark.parametrize("n", [11, 101])
def test_discretised_mode_is_the_plain_sum_karnik_mendel(n: int) -> None:
    rb = small()
    rb = replace(rb, footprint=replace(rb.footprint, resolution=n))
    xs = np.linspace(-1, 1, 17)
    y_l, y_r = Engine(rb).centroid_intervals({"e": xs})["u"]
    want = np.array([centroid_interval(rb, {"e": float(x)}, n, trapezoid=False) for x in xs])
    np.testing.assert_allclose(y_l, want[:, 0], atol=1e-13)
    np.testing.assert_allclose(y_r, want[:, 1], atol=1e-13)


def test_without_uncertainty_it2_is_the_type1_centroid() -> None:
    # no term has a lower function: every embedded set is the type-1 set, y_l = y_r = centroid
    t1 = load("macvicar_whelan")
    it2 = with_footprint(t1, replace(footprint_of(load("macvicar_whelan_it2")), lowers=()))
    x = np.random.default_rng(4).uniform(-1, 1, (200, 2))
    pts = {"e": x[:, 0], "de": x[:, 1]}
    y_l, y_r = Engine(it2).centroid_intervals(pts)["du"]
    want = Engine(t1).evaluate(pts)["du"]
    np.testing.assert_allclose(y_l, want, atol=1e-12)
    np.testing.assert_allclose(y_r, want, atol=1e-12)


def test_interval_contains_the_upper_and_lower_centroids() -> None:
    # the upper and the lower set are embedded sets: their centroids lie in [y_l, y_r]
    rb = small()
    xs = np.linspace(-0.95, 0.95, 39)
    y_l, y_r = Engine(rb).centroid_intervals({"e": xs})["u"]
    y = np.linspace(-1, 1, 40001)
    for k, x in enumerate(xs):
        up, lo = output_sets(rb, {"e": float(x)}, y)
        for f in (up, lo):
            if f.sum() > 0:
                c = float((f * y).sum() / f.sum())
                assert y_l[k] - 1e-6 <= c <= y_r[k] + 1e-6
        assert y_l[k] <= y_r[k]


def test_nie_tan_and_wu_mendel_against_their_formulas() -> None:
    y = np.linspace(-1, 1, 40001)
    w = np.ones_like(y)
    w[0] = w[-1] = 0.5
    xs = np.linspace(-1, 1, 9)
    nt = Engine(small(tr="nie-tan")).evaluate({"e": xs})["u"]
    wm = Engine(small(tr="wu-mendel")).evaluate({"e": xs})["u"]
    checked = 0
    for k, x in enumerate(xs):
        up, lo = output_sets(small(), {"e": float(x)}, y)
        a_u, a_l = (w * up).sum(), (w * lo).sum()
        m_u, m_l = (w * up * y).sum(), (w * lo * y).sum()
        assert nt[k] == pytest.approx((m_u + m_l) / (a_u + a_l), abs=1e-7)
        if a_l == 0.0:
            continue  # the bounds divide by the lower set's area (docs/type2.md)
        checked += 1
        # Wu and Mendel (2002), eqs. for the outer and inner bounds of y_l and y_r
        # the support of the upper set: the feet of the fired consequents, in the range
        rb = small()
        fired = [
            rb.output("u").term(r.consequents[0].term).params
            for r, (_, f_up) in zip(rb.rules, firing_intervals(rb, {"e": float(x)}), strict=True)
            if f_up > 0
        ]
        y1, yn = max(min(p[0] for p in fired), -1.0), min(max(p[-1] for p in fired), 1.0)
        c_l, c_u = m_l / a_l, m_u / a_u
        gap = (a_u - a_l) / (a_u * a_l)
        d1_l, dn_u = (w * lo * (y - y1)).sum(), (w * up * (yn - y)).sum()
        d1_u, dn_l = (w * up * (y - y1)).sum(), (w * lo * (yn - y)).sum()
        yl_bar = min(c_l, c_u)
        yl_low = yl_bar - gap * d1_l * dn_u / (d1_l + dn_u)
        yr_low = max(c_l, c_u)
        yr_bar = yr_low + gap * d1_u * dn_l / (d1_u + dn_l)
        want = 0.5 * (0.5 * (yl_bar + yl_low) + 0.5 * (yr_low + yr_bar))
        assert wm[k] == pytest.approx(want, abs=1e-6)
    assert checked >= 5


def test_ekm_is_the_karnik_mendel_interval() -> None:
    xs = np.linspace(-1, 1, 21)
    a = Engine(small(tr="karnik-mendel")).evaluate({"e": xs})["u"]
    b = Engine(small(tr="ekm")).evaluate({"e": xs})["u"]
    np.testing.assert_array_equal(a, b)


def test_firing_intervals_match_the_reference() -> None:
    rb = load("macvicar_whelan_it2")
    from fuzzkit.fuzzy.type2_inference import Type2Engine

    eng = Engine(rb)
    assert isinstance(eng._type2, Type2Engine)
    lo, up = eng._type2.firing_intervals([MW_POINTS[:, 0].copy(), MW_POINTS[:, 1].copy()])
    for k, (e, d) in enumerate(MW_POINTS):
        want = np.array(firing_intervals(rb, {"e": float(e), "de": float(d)}))
        np.testing.assert_allclose(lo[k], want[:, 0], atol=1e-15)
        np.testing.assert_allclose(up[k], want[:, 1], atol=1e-15)


SUGENO = """
name: it2_sugeno
inputs:
  x:
    range: [0, 10]
    terms:
      lo:
        upper: {shape: left_shoulder, points: [2, 7]}
        lower: {shape: left_shoulder, points: [1, 5], scale: 0.9}
      hi:
        upper: {shape: right_shoulder, points: [3, 8]}
        lower: {shape: right_shoulder, points: [5, 9], scale: 0.9}
  y:
    range: [0, 1]
    terms:
      s:
        upper: {shape: left_shoulder, points: [0, 0.8]}
        lower: {shape: left_shoulder, points: [0, 0.5]}
      b:
        upper: {shape: right_shoulder, points: [0.2, 1]}
        lower: {shape: right_shoulder, points: [0.5, 1]}
outputs:
  z:
    range: [-100, 100]
    terms:
      c1: {shape: constant, value: -3}
      l1: {shape: linear, coefficients: {x: 1.5, y: -2}, constant: 1}
      l2: {shape: linear, coefficients: {x: -0.5, y: 4}, constant: 2}
defuzzifier: weighted_average
type_reduction: $TR
rules:
  - {if: {and: [{x: lo}, {y: s}]}, then: {z: c1}}
  - {if: {and: [{x: lo}, {y: b}]}, then: {z: l1}}
  - {if: {and: [{x: hi}, {y: s}]}, then: {z: l2}}
  - {if: {and: [{x: hi}, {y: b}]}, then: {z: c1}, weight: 0.5}
"""


def test_it2_sugeno_interval_is_the_extreme_over_every_weight_corner() -> None:
    rb = loads(SUGENO.replace("$TR", "karnik-mendel"))
    pts = np.random.default_rng(9).uniform([0, 0], [10, 1], (60, 2))
    y_l, y_r = Engine(rb).centroid_intervals({"x": pts[:, 0], "y": pts[:, 1]})["z"]
    for k, (x, y) in enumerate(pts):
        fi = firing_intervals(rb, {"x": float(x), "y": float(y)})
        z = [-3.0, 1.5 * x - 2 * y + 1, -0.5 * x + 4 * y + 2, -3.0]
        want = vertex_interval(z, fi)
        assert y_l[k] == pytest.approx(want[0], abs=1e-12)
        assert y_r[k] == pytest.approx(want[1], abs=1e-12)


def test_nan_input_gives_nan_and_no_firing_gives_the_default() -> None:
    rb = load("macvicar_whelan_it2")
    got = Engine(rb).evaluate({"e": [np.nan, 0.2], "de": [0.1, np.nan]})["du"]
    assert np.isnan(got).all()
    lo, hi = Engine(rb).centroid_intervals({"e": [np.nan], "de": [0.0]})["du"]
    assert np.isnan(lo).all() and np.isnan(hi).all()


def test_type1_rule_base_has_no_interval() -> None:
    with pytest.raises(EvaluationError, match="type-1"):
        Engine(load("macvicar_whelan")).centroid_intervals({"e": 0.0, "de": 0.0})


def test_macvicar_whelan_it2_is_odd_symmetric_and_bounded() -> None:
    x = np.linspace(-1, 1, 41)
    ee, dd = np.meshgrid(x, x, indexing="ij")
    z = Engine(load("macvicar_whelan_it2")).evaluate({"e": ee, "de": dd})["du"]
    np.testing.assert_allclose(z, -z[::-1, ::-1], atol=1e-14)
    np.testing.assert_allclose(z, z.T, atol=1e-14)  # the table is symmetric in e and de
    assert np.abs(z).max() < 1.0
    assert z[-1, -1] > 0.85 and abs(z[20, 20]) < 1e-15
