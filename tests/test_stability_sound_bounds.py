"""The sound bounds of the exact surface (fuzzkit.analysis.surface_enclosure, surface_bounds):
every value and every secant slope of a dense evaluation by the engine lies inside the
enclosure of the rectangle it falls in, for the shipped and user-style rule bases and for
random rule bases with narrow features; the interval arithmetic contains the exact results."""

from __future__ import annotations

from dataclasses import replace
from fractions import Fraction

import numpy as np
import pytest

from fuzzkit.analysis.intervals import Interval, exp_decreasing
from fuzzkit.analysis.surface_bounds import compute, seed_rectangles
from fuzzkit.analysis.surface_enclosure import Enclosure, why_unsupported
from fuzzkit.formats.registry import load
from fuzzkit.fuzzy.inference import evaluate
from fuzzkit.fuzzy.model import RuleBase
from tests._random_rulebases import narrow_rulebase

SUPPORTED = (
    "macvicar_whelan",
    "gaussian5",
    "sugeno_pi",
    "paper_table1",
    "tests/data/user/nonuniform5.yaml",
    "tests/data/user/renamed.yaml",
    "tests/data/user/gauss_prod.yaml",
    "tests/data/user/user_pi.fis",
)


def _clamped(name: str) -> RuleBase:
    return replace(load(name), out_of_range="clamp")


def _surface(rb: RuleBase, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    xx, yy = np.meshgrid(xs, ys, indexing="ij")
    a, b = rb.inputs[0].name, rb.inputs[1].name
    out = evaluate(rb, {a: xx.ravel(), b: yy.ravel()})[rb.outputs[0].name]
    return np.asarray(out).reshape(xx.shape)


def _violations(rb: RuleBase, cells: int, per_cell: int) -> list[str]:
    """Check the enclosure of a cells x cells grid against per_cell x per_cell samples each
    (values, and the secants between neighbouring samples of one cell)."""
    edges = np.linspace(-1.0, 1.0, cells + 1)
    x0, y0 = np.meshgrid(edges[:-1], edges[:-1], indexing="ij")
    x1, y1 = np.meshgrid(edges[1:], edges[1:], indexing="ij")
    enc = Enclosure(rb).enclose(x0.ravel(), x1.ravel(), y0.ravel(), y1.ravel())
    dense = np.linspace(-1.0, 1.0, cells * per_cell + 1)
    f = _surface(rb, dense, dense)
    step = dense[1] - dense[0]
    bad = []
    for i in range(cells):
        for j in range(cells):
            k = i * cells + j
            block = f[i * per_cell : (i + 1) * per_cell + 1, j * per_cell : (j + 1) * per_cell + 1]
            sx = np.diff(block, axis=0) / step
            sy = np.diff(block, axis=1) / step
            # the secant's own rounding: a few ulps of F over the step
            slack = 8 * np.finfo(float).eps * max(1.0, float(np.max(np.abs(block)))) / step
            checks = (
                ("F", block, enc.f.lo[k], enc.f.hi[k], 0.0),
                ("dF/dx", sx, enc.gx.lo[k], enc.gx.hi[k], slack),
                ("dF/dy", sy, enc.gy.lo[k], enc.gy.hi[k], slack),
            )
            for what, vals, lo, hi, tol in checks:
                if vals.min() < lo - tol or vals.max() > hi + tol:
                    bad.append(
                        f"{what} in [{vals.min():.6g}, {vals.max():.6g}] outside "
                        f"[{lo:.6g}, {hi:.6g}] at cell {edges[i]:.4g}, {edges[j]:.4g}"
                    )
    return bad


@pytest.mark.parametrize("name", SUPPORTED)
def test_the_enclosure_holds_every_dense_value_and_slope(name: str) -> None:
    rb = _clamped(name)
    assert why_unsupported(rb) is None
    assert _violations(rb, cells=16, per_cell=8) == []


@pytest.mark.parametrize("seed", range(6))
def test_the_enclosure_holds_on_random_rule_bases_with_narrow_features(seed: int) -> None:
    rb = narrow_rulebase(np.random.default_rng(seed))
    assert why_unsupported(rb) is None
    assert _violations(rb, cells=16, per_cell=16) == []


@pytest.mark.verify
@pytest.mark.parametrize("seed", range(6, 40))
def test_the_enclosure_holds_on_many_random_rule_bases(seed: int) -> None:
    rb = narrow_rulebase(np.random.default_rng(seed))
    assert _violations(rb, cells=32, per_cell=32) == []


@pytest.mark.verify
@pytest.mark.parametrize("name", SUPPORTED)
def test_the_refined_bounds_hold_on_a_4097_grid(name: str) -> None:
    rb = _clamped(name)
    sb = compute(rb)
    dense = np.linspace(-1.0, 1.0, 4097)
    f = _surface(rb, dense, dense)
    step = dense[1] - dense[0]
    slack = 8 * np.finfo(float).eps * max(1.0, float(np.max(np.abs(f)))) / step
    sx, sy = np.diff(f, axis=0) / step, np.diff(f, axis=1) / step
    bad = 0
    for (x0, x1, y0, y1), fb, dx, dy in zip(sb.rect, sb.f, sb.dx, sb.dy, strict=True):
        i0, i1 = (
            np.searchsorted(dense, [x0, x1], side="left")[0],
            np.searchsorted(dense, x1, side="right"),
        )
        j0, j1 = np.searchsorted(dense, y0, side="left"), np.searchsorted(dense, y1, side="right")
        block = f[i0:i1, j0:j1]
        if block.size == 0:
            continue
        bad += int(block.min() < fb[0] or block.max() > fb[1])
        bx, by = sx[i0 : i1 - 1, j0:j1], sy[i0:i1, j0 : j1 - 1]
        if bx.size:
            bad += int(bx.min() < dx[0] - slack or bx.max() > dx[1] + slack)
        if by.size:
            bad += int(by.min() < dy[0] - slack or by.max() > dy[1] + slack)
    assert bad == 0


def test_what_has_no_enclosure_is_named() -> None:
    rb = _clamped("macvicar_whelan")
    assert "bisector" in (why_unsupported(replace(rb, defuzzifier="bisector")) or "")


@pytest.mark.parametrize("seed", range(3))
def test_interval_operations_contain_the_exact_results(seed: int) -> None:
    rng = np.random.default_rng(seed)
    a_lo, b_lo = rng.normal(size=200), rng.normal(size=200)
    a = Interval(a_lo, a_lo + rng.uniform(0, 1, 200) * rng.integers(0, 2, 200))
    b = Interval(b_lo, b_lo + rng.uniform(0, 1, 200) * rng.integers(0, 2, 200))
    pos = Interval(np.abs(b.lo) + 0.1, np.abs(b.hi) + 0.2)
    results = {
        "+": (a + b, lambda x, y: x + y, b),
        "-": (a - b, lambda x, y: x - y, b),
        "*": (a * b, lambda x, y: x * y, b),
        "/": (a.divide_positive(pos), lambda x, y: x / y, pos),
    }
    for op, (got, exact, other) in results.items():
        for k in range(200):
            for x in (a.lo[k], a.hi[k]):
                for y in (other.lo[k], other.hi[k]):
                    v = exact(Fraction(float(x)), Fraction(float(y)))
                    assert Fraction(float(got.lo[k])) <= v <= Fraction(float(got.hi[k])), op


def test_exp_enclosure_contains_a_finer_computation() -> None:
    import decimal

    t = np.linspace(0.0, 40.0, 997)
    e = exp_decreasing(t, t)
    with decimal.localcontext() as ctx:
        ctx.prec = 60
        for k, tk in enumerate(t):
            v = (-decimal.Decimal(float(tk))).exp()
            assert decimal.Decimal(float(e.lo[k])) <= v <= decimal.Decimal(float(e.hi[k]))


def _rect_violations(rb: RuleBase, rect: np.ndarray, per_cell: int) -> list[str]:
    """The enclosure of each rectangle (n, 4) against per_cell x per_cell engine samples in it
    (values, and the secants between neighbouring samples)."""
    enc = Enclosure(rb).enclose(*rect.T)
    u = np.linspace(0.0, 1.0, per_cell)
    xs = rect[:, :1] + u * (rect[:, 1:2] - rect[:, :1])  # (n, p)
    ys = rect[:, 2:3] + u * (rect[:, 3:4] - rect[:, 2:3])
    xx = np.repeat(xs[:, :, None], per_cell, axis=2)
    yy = np.repeat(ys[:, None, :], per_cell, axis=1)
    a, b = rb.inputs[0].name, rb.inputs[1].name
    f = np.asarray(evaluate(rb, {a: xx.ravel(), b: yy.ravel()})[rb.outputs[0].name])
    f = f.reshape(xx.shape)
    hx, hy = xs[:, 1] - xs[:, 0], ys[:, 1] - ys[:, 0]
    sx = np.diff(f, axis=1) / hx[:, None, None]
    sy = np.diff(f, axis=2) / hy[:, None, None]
    assert np.all(np.isfinite(sx)) and np.all(np.isfinite(sy))
    bad = []
    for k in range(rect.shape[0]):
        slack = 8 * np.finfo(float).eps * max(1.0, float(np.max(np.abs(f[k]))))
        for what, vals, iv, tol in (
            ("dF/dx", sx[k], enc.gx, slack / hx[k]),
            ("dF/dy", sy[k], enc.gy, slack / hy[k]),
        ):
            if vals.min() < iv.lo[k] - tol or vals.max() > iv.hi[k] + tol:
                bad.append(
                    f"{what} in [{vals.min():.6g}, {vals.max():.6g}] outside "
                    f"[{iv.lo[k]:.6g}, {iv.hi[k]:.6g}] on {rect[k]}"
                )
    return bad


def _kink_cells(rb: RuleBase, cells: int) -> np.ndarray:
    """A cells x cells grid cut at the input terms' kinks, as the branch and bound seeds it:
    every rectangle of a piecewise-linear rule base is then affine, so its switch lines and
    the levels' order per side are used."""
    rect = seed_rectangles(Enclosure(rb), cells)
    # a kink an ulp from a grid line leaves a sliver no sample can tell apart: dropped
    wide = (rect[:, 1] - rect[:, 0] > 1e-9) & (rect[:, 3] - rect[:, 2] > 1e-9)
    return rect[wide]


@pytest.mark.parametrize("name", ["macvicar_whelan", "tests/data/user/nonuniform5.yaml"])
def test_the_enclosure_on_cells_cut_at_the_kinks_holds_every_dense_slope(name: str) -> None:
    rb = _clamped(name)
    assert _rect_violations(rb, _kink_cells(rb, 24), per_cell=9) == []


@pytest.mark.parametrize("seed", [1, 5, 9, 13])
def test_the_switch_lines_hold_on_random_piecewise_linear_rule_bases(seed: int) -> None:
    rb = narrow_rulebase(np.random.default_rng(seed))
    rb = replace(
        rb, operators=replace(rb.operators, and_="min", implication="min", aggregation="max")
    )
    assert _rect_violations(rb, _kink_cells(rb, 16), per_cell=9) == []


def test_the_levels_order_per_side_of_a_switch_line_tightens_the_slopes() -> None:
    # macvicar_whelan at e in [0, 1/32], de in [-1, -31/32]: the levels of NM and NS tie along
    # e = de + 1, through a corner; without their order per side the enclosure of dF/de holds
    # each level's whole range (about [0, 9.8]); the engine's secants there lie in [1.04, 4.27]
    rb = _clamped("macvicar_whelan")
    rect = np.array([[0.0, 1.0 / 32.0, -1.0, -31.0 / 32.0]])
    loose = Enclosure(rb).enclose(*rect.T, tighten=False).gx
    tight = Enclosure(rb).enclose(*rect.T).gx
    xs = np.linspace(0.0, 1.0 / 32.0, 65)
    ys = np.linspace(-1.0, -31.0 / 32.0, 65)
    f = _surface(rb, xs, ys)
    sx = np.diff(f, axis=0) / (xs[1] - xs[0])
    assert tight.lo[0] <= sx.min() and sx.max() <= tight.hi[0]
    assert loose.hi[0] > 2.0 * sx.max()
    assert tight.hi[0] - sx.max() < 0.15 * sx.max()


def test_where_several_switch_lines_meet_each_sector_is_taken() -> None:
    # macvicar_whelan at e = de = 1/6: ZR and PS of both inputs are 1/2, so four switch lines
    # (e = de, e + de = 1/3, e = 1/6, de = 1/6) meet there; each of the eight sectors has its
    # own selection, and their slopes' hull is what the surface attains around the point
    rb = _clamped("macvicar_whelan")
    h = 1.0 / 96.0
    rect = np.array([[1 / 6 - h, 1 / 6 + h, 1 / 6 - h, 1 / 6 + h]])
    assert _rect_violations(rb, rect, per_cell=65) == []
    loose = Enclosure(rb).enclose(*rect.T, tighten=False).gx
    tight = Enclosure(rb).enclose(*rect.T).gx
    xs = np.linspace(1 / 6 - h, 1 / 6 + h, 129)
    sx = np.diff(_surface(rb, xs, xs), axis=0) / (xs[1] - xs[0])
    assert tight.hi[0] - tight.lo[0] < 0.5 * (loose.hi[0] - loose.lo[0])
    # what is left is the output bins' resolution (256 bins), not the sectors
    assert tight.hi[0] - sx.max() < 0.3 * sx.max() and sx.min() - tight.lo[0] < 0.3 * sx.max()


@pytest.mark.parametrize("name", ["gaussian5", "macvicar_whelan"])
def test_the_output_terms_integrals_per_bin_hold_a_fine_quadrature(name: str) -> None:
    # the bins where a bounded sum stays below 1 use each term's own integrals, int C and
    # int y C; summed over the output axis they must hold a fine trapezoidal quadrature of
    # the engine's membership (error ~1e-13 at 2e6 points)
    from fuzzkit.fuzzy.membership import evaluate_term

    rb = _clamped(name)
    enc = Enclosure(rb)
    ic, iyc = enc._term_integrals
    out = rb.outputs[0]
    y = np.linspace(out.low, out.high, 2_000_001)
    for t, term in enumerate(out.terms):
        mu = evaluate_term(term, y)
        area, moment = np.trapezoid(mu, y), np.trapezoid(y * mu, y)
        for got, want in ((ic, area), (iyc, moment)):
            lo, hi = float(got.lo[t].sum()), float(got.hi[t].sum())
            assert lo - 1e-9 <= want <= hi + 1e-9, term.name
            assert hi - lo < 1e-9
