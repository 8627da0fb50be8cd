"""The fuzzy surface's bounds (fuzzkit.analysis.fuzzy_bounds) against closed forms."""

from __future__ import annotations

import numpy as np
import pytest

from fuzzkit.analysis.fuzzy_bounds import (
    StructureError,
    gradient_bounds,
    phi_bounds,
)


def _table(fn, n: int = 11, split: int = 1):
    bp = np.linspace(-1.0, 1.0, n)
    x, y = np.meshgrid(bp, bp, indexing="ij")
    splits = np.full((n - 1, n - 1), split, dtype=np.int64)
    return bp, bp.copy(), fn(x, y), splits


def test_a_linear_pi_surface_has_phi_equal_to_its_slope():
    bp0, bp1, v, s = _table(lambda x, y: 1.7 * (x + y))
    b = phi_bounds(bp0, bp1, v, s, 1.0)
    assert b.low == pytest.approx(1.7, abs=1e-12)
    assert b.high == pytest.approx(1.7, abs=1e-12)


@pytest.mark.parametrize(
    ("rho", "covered", "low"), [(0.4, 0.4, 1.0), (0.5, 0.6, 1.0 / 1.2), (1.0, 1.0, 0.5)]
)
def test_the_saturated_sum_has_phi_between_one_over_the_largest_sum_and_one(rho, covered, low):
    # clip(x + y, -1, 1) is piecewise linear with kinks on x + y = +-1: the anti-diagonal
    # splits of an 11-point grid put them on triangle edges, so the table is the surface itself
    # and phi = min(1, 1 / |x + y|) over the box of whole cells (step 0.2) covering the one
    # asked for: 1 while |x + y| <= 1, 1 / 1.2 on [-0.6, 0.6]^2, 1/2 at the corners (1, 1).
    bp0, bp1, v, s = _table(lambda x, y: np.clip(x + y, -1.0, 1.0))
    b = phi_bounds(bp0, bp1, v, s, rho)
    assert b.low == pytest.approx(low, abs=1e-12)
    assert b.high == pytest.approx(1.0, abs=1e-12)
    assert b.rho == pytest.approx(covered)


def test_a_surface_that_does_not_vanish_on_the_anti_diagonal_has_no_phi_but_gradient_bounds():
    bp0, bp1, v, s = _table(lambda x, y: x + 0.5 * y, split=0)
    with pytest.raises(StructureError, match="does not vanish on e \\+ de = 0"):
        phi_bounds(bp0, bp1, v, s, 1.0)
    g = gradient_bounds(bp0, bp1, v, s, 1.0)
    assert g.a_range == pytest.approx((1.0, 1.0), abs=1e-12)
    assert g.b_range == pytest.approx((0.5, 0.5), abs=1e-12)


@pytest.mark.slow
def test_macvicar_whelan_phi_bounds_hold_on_the_table_between_its_nodes():
    from fuzzkit.loop.compiled.table import compiled_table, table2

    t = compiled_table("macvicar_whelan")
    b = phi_bounds(t.bp0, t.bp1, t.values, t.splits, 1.0)
    # the issue's own measurement over the clamped universe: up to about 1.94, small-signal 1.5
    assert 1.9 < b.high < 1.95
    assert 0.0 < b.low < 1.0
    assert b.small_signal == pytest.approx(1.5, abs=0.05)
    rng = np.random.default_rng(3)
    pts = rng.uniform(-1.0, 1.0, (20000, 2))
    pts = pts[np.abs(pts.sum(axis=1)) > 1e-6]
    phi = np.array([table2(t.bp0, t.bp1, t.values, t.splits, x, y) / (x + y) for x, y in pts])
    assert np.all(phi >= b.low - 1e-9)
    assert np.all(phi <= b.high + 1e-9)
    # the upper bound is attained (exact, not padded): at a table node near the line
    x, y = np.meshgrid(t.bp0, t.bp1, indexing="ij")
    s = x + y
    nodes = np.abs(s) > 1e-9
    assert np.max(t.values[nodes] / s[nodes]) == pytest.approx(b.high, abs=1e-12)
    # so is the lower bound (docs/stability.md: phi in [0.444, 1.933]): 4/9, at a node too
    assert np.min(t.values[nodes] / s[nodes]) == pytest.approx(b.low, abs=1e-12)
    assert b.low == pytest.approx(4.0 / 9.0, abs=1e-9)
