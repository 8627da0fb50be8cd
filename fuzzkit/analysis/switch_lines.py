"""Tighter slope enclosures where the rules' min and max switch along one line of a rectangle.

With min AND, a rule's strength is the smaller of its terms' memberships, and an output term's
level the largest of its rules' strengths: which term and which rule is selected switches along
lines. The interval enclosure (:mod:`fuzzkit.analysis.surface_enclosure`) takes each level's
slope as the hull of its candidates independently of the others; where several levels switch
along the same line (the diagonals of a symmetric partition: every rule near the origin of
``macvicar_whelan`` switches on ``|e| = |de|``) that hull loses the correlation and does not
shrink however small the rectangle.

Inside a rectangle between the input terms' kinks every membership is affine, so every
comparison that selects a term or a rule is an affine function of ``(x, y)``, known exactly
from its values at the four corners (the memberships there, as the engine computes them). The
comparisons are those of the terms of one rule (the min), of the rules of one output term (the
max), and of the rules of two output terms whose levels may tie (the order of the levels, on
which the output stage's ``dF/dL_t`` depends). When every comparison that changes sign inside
the rectangle has the same zero line, the selection and the levels' order are constant on each
side of it: the levels' slopes and order there are those at one point strictly inside that
side. On each side ``dF/dL_t`` is enclosed again knowing that order
(:meth:`fuzzkit.analysis.surface_enclosure.Enclosure.ordered_dfdl`); the slope enclosure is
the hull of ``sum_t dF/dL_t * dL_t`` over the two sides, intersected with the independent one.
Where two or more distinct lines cross the rectangle and all pass through one point (the
origin, or where both inputs sit between two terms at 1/2), the same is done on each sector
around that point (:func:`_sectors`); other rectangles keep the independent enclosure.

A corner value within :data:`ON_CORNER` of 0 counts as a line through that corner (rounding of
the memberships there): the other side then has no interior in the rectangle, and its slopes
belong to the neighbouring rectangle that holds it, which every box containing the corner also
holds (:meth:`fuzzkit.analysis.surface_bounds.SurfaceBounds.over` takes closed rectangles).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np
import numpy.typing as npt

from fuzzkit.analysis.intervals import FloatArray, Interval, dot
from fuzzkit.analysis.term_intervals import enclose
from fuzzkit.fuzzy.model import RuleBase

Firing = list[tuple[Interval, Interval, Interval]]


class _Rule(Protocol):
    @property
    def props(self) -> tuple[tuple[int, int, bool], ...]: ...
    @property
    def weight(self) -> float: ...
    @property
    def consequent(self) -> int: ...


class Enclosure(Protocol):
    """What :func:`refine` reads of :class:`fuzzkit.analysis.surface_enclosure.Enclosure`."""

    @property
    def rb(self) -> RuleBase: ...
    @property
    def rules(self) -> Sequence[_Rule]: ...

    def firing(self, x0: FloatArray, x1: FloatArray, y0: FloatArray, y1: FloatArray) -> Firing: ...

    def levels(self, firing: Firing, sl: slice) -> tuple[Interval, Interval, Interval]: ...

    def ordered_dfdl(
        self, firing: Firing, rows: npt.NDArray[np.intp], at: FloatArray
    ) -> Interval: ...


#: Relative agreement of two normalised switch lines that counts as the same line.
SAME_LINE = 1e-9
#: A comparison's corner value (a difference of memberships in [0, 1]) at most this far from 0
#: is rounding of a line through the corner.
ON_CORNER = 1e-12
#: Distance (unit-square coordinates) within which lines count as through one point.
COMMON_POINT = 1e-9
#: How far (share of the way to the centre) a side's point sits inside from its corner.
INSET = 1e-6
_CORNERS = ((0, 0), (1, 0), (0, 1), (1, 1))
BoolArray = npt.NDArray[np.bool_]


def _memberships(enc: Enclosure, rect: FloatArray) -> list[list[FloatArray]]:
    """Per input, per term: the membership at the rectangle's corners, (n, 4)."""
    out = []
    for axis in (0, 1):
        ends = (rect[:, 2 * axis], rect[:, 2 * axis + 1])
        terms = []
        for term in enc.rb.inputs[axis].terms:
            at = [enclose(term, e, e)[0] for e in ends]
            vals = [0.5 * (v.lo + v.hi) for v in at]
            terms.append(np.stack([vals[c[axis]] for c in _CORNERS], 1))
        out.append(terms)
    return out


def _affine(enc: Enclosure, rect: FloatArray) -> BoolArray:
    """Whether every input term is affine on each rectangle (one slope, no kink inside)."""
    ok = np.ones(rect.shape[0], dtype=bool)
    for axis in (0, 1):
        for term in enc.rb.inputs[axis].terms:
            _, d = enclose(term, rect[:, 2 * axis], rect[:, 2 * axis + 1])
            ok &= (d.hi - d.lo) <= 1e-9 * (1.0 + np.abs(d.hi))
    return ok


def refine(
    enc: Enclosure, rect: FloatArray, firing: Firing, gx: Interval, gy: Interval, dfdl: Interval
) -> tuple[Interval, Interval]:
    """The slopes ``gx``, ``gy`` (with ``dF/dL_t`` = ``dfdl``, (n, T)) of the rectangles
    ``rect`` (n, 4), tightened where one switch line crosses (module doc)."""
    n = rect.shape[0]
    if n == 0:
        return gx, gy
    level, lgx, lgy = enc.levels(firing, slice(0, n))
    width = np.maximum(lgx.hi - lgx.lo, lgy.hi - lgy.lo).max(axis=1)
    cand = ((width > 1e-9) | _may_tie(level)) & np.isfinite(gx.lo) & np.isfinite(gx.hi)
    cand &= _affine(enc, rect)
    idx = np.nonzero(cand)[0]
    if idx.size == 0:
        return gx, gy
    sub = rect[idx]
    mus = _memberships(enc, sub)
    lines = _comparisons(enc, mus, [(a.lo[idx], a.hi[idx]) for a, _, _ in firing], level, idx)
    options = _sides(sub, lines)
    if options is None:
        return gx, gy
    points, which, valid = options
    # the levels' slopes at each side's point (a point rectangle: one selection, no kink)
    pf = enc.firing(points[:, 0], points[:, 0], points[:, 1], points[:, 1])
    plevel, pgx, pgy = enc.levels(pf, slice(0, points.shape[0]))
    single_x: BoolArray = np.all(pgx.hi - pgx.lo <= 1e-9 * (1 + np.abs(pgx.hi)), axis=1)
    single_y: BoolArray = np.all(pgy.hi - pgy.lo <= 1e-9 * (1 + np.abs(pgy.hi)), axis=1)
    single = single_x & single_y
    # the levels' order on each side is that at its point (no comparison crosses the side);
    # dF/dL_t is enclosed again with it, and intersected with the rectangle's own
    side_dfdl = enc.ordered_dfdl(firing, idx[which], 0.5 * (plevel.lo + plevel.hi)).intersect(
        Interval(dfdl.lo[idx][which], dfdl.hi[idx][which])
    )
    ox, oy = dot(side_dfdl, pgx), dot(side_dfdl, pgy)
    new = [gx.lo.copy(), gx.hi.copy(), gy.lo.copy(), gy.hi.copy()]
    for k, cell in enumerate(idx):
        mine = which == k
        if not (valid[k] and np.all(single[mine])):
            continue
        lo_x, hi_x = ox.lo[mine].min(), ox.hi[mine].max()
        lo_y, hi_y = oy.lo[mine].min(), oy.hi[mine].max()
        new[0][cell], new[1][cell] = max(new[0][cell], lo_x), min(new[1][cell], hi_x)
        new[2][cell], new[3][cell] = max(new[2][cell], lo_y), min(new[3][cell], hi_y)
    return Interval(new[0], new[1]), Interval(new[2], new[3])


def _comparisons(
    enc: Enclosure,
    mus: list[list[FloatArray]],
    strength: list[tuple[FloatArray, FloatArray]],
    level: Interval,
    idx: npt.NDArray[np.intp],
) -> list[FloatArray]:
    """Corner values (n, 4) of every live comparison (masked with NaN where not live)."""
    n = idx.size
    props: list[list[tuple[FloatArray, BoolArray]]] = []  # per rule: (corner values, can-min)
    for r, rule in enumerate(enc.rules):
        vals = []
        for axis, t, neg in rule.props:
            v = mus[axis][t]
            vals.append(1.0 - v if neg else v)
        vals = [rule.weight * v for v in vals]
        live: BoolArray = (
            np.all([v.max(1) > 0.0 for v in vals], axis=0) if vals else np.ones(n, dtype=bool)
        )
        top = np.min([v.max(1) for v in vals], axis=0) if vals else np.ones(n)
        props.append([(v, live & (v.min(1) <= top)) for v in vals])
        del r
    out: list[FloatArray] = []

    def add(a: FloatArray, b: FloatArray, live: BoolArray) -> None:
        if np.any(live):
            out.append(np.where(live[:, None], a - b, np.nan))

    for rp in props:
        for i in range(len(rp)):
            for j in range(i + 1, len(rp)):
                add(rp[i][0], rp[j][0], rp[i][1] & rp[j][1])
    by_term: dict[int, list[int]] = {}
    for r, rule in enumerate(enc.rules):
        by_term.setdefault(rule.consequent, []).append(r)
    can = {r: strength[r][1] >= level.lo[idx, rule.consequent] for r, rule in enumerate(enc.rules)}
    for rs in by_term.values():
        for a in range(len(rs)):
            for b in range(a + 1, len(rs)):
                for va, ca in props[rs[a]]:
                    for vb, cb in props[rs[b]]:
                        add(va, vb, can[rs[a]] & can[rs[b]] & ca & cb)
    # two levels that may tie: where their order changes (the output stage's switch lines)
    terms = sorted(by_term)
    for i, t in enumerate(terms):
        for u in terms[i + 1 :]:
            tie = (level.lo[idx, t] <= level.hi[idx, u]) & (level.lo[idx, u] <= level.hi[idx, t])
            if not np.any(tie):
                continue
            for a in by_term[t]:
                for b in by_term[u]:
                    both = tie & can[a] & can[b]
                    if not np.any(both):
                        continue
                    for va, ca in props[a]:
                        for vb, cb in props[b]:
                            add(va, vb, both & ca & cb)
    return out


def _may_tie(level: Interval) -> BoolArray:
    """Per rectangle: two levels, one of them above 0, whose ranges overlap."""
    overlap = (level.lo[:, :, None] <= level.hi[:, None, :]) & (
        level.lo[:, None, :] <= level.hi[:, :, None]
    )
    live = (level.hi[:, :, None] > 0.0) | (level.hi[:, None, :] > 0.0)
    off = ~np.eye(level.lo.shape[1], dtype=bool)[None]
    tie: BoolArray = np.any(overlap & live & off, axis=(1, 2))
    return tie


def _sectors(lines: FloatArray) -> list[FloatArray] | None:
    """A point inside each part of the unit square that ``lines`` (m, 3), ``a u + b v + c = 0``
    with ``(a, b)`` of length 1, cut it into, when they all pass through one point ``p`` (else
    None): the lines through ``p`` and the square's edges at ``p`` cut the directions from
    ``p`` into angular intervals, each inside one sector and wholly in or out of the square;
    a point just out from ``p`` along the middle of each interval that is in."""
    a, b, c = lines[:, 0], lines[:, 1], lines[:, 2]
    other = np.nonzero(np.abs(a * b[0] - b * a[0]) > SAME_LINE)[0]
    if other.size == 0:
        return None  # parallel lines
    j = int(other[0])
    det = a[0] * b[j] - a[j] * b[0]
    p = np.array([(-c[0] * b[j] + c[j] * b[0]) / det, (-a[0] * c[j] + a[j] * c[0]) / det])
    if np.any(np.abs(a * p[0] + b * p[1] + c) > COMMON_POINT) or np.any(
        (p < -COMMON_POINT) | (p > 1.0 + COMMON_POINT)
    ):
        return None
    p = np.clip(p, 0.0, 1.0)
    angles = [np.arctan2(a, -b), np.arctan2(-a, b)]
    for k in range(2):  # the square's edges through p
        if p[k] <= COMMON_POINT or p[k] >= 1.0 - COMMON_POINT:
            angles.append(np.array([0.0, np.pi]) + (np.pi / 2 if k == 0 else 0.0))
    theta = np.unique(np.mod(np.concatenate(angles), 2 * np.pi))
    # one direction computed from two lines that agree to rounding
    theta = theta[np.append(True, np.diff(theta) > SAME_LINE)]
    if theta.size > 1 and theta[0] + 2 * np.pi - theta[-1] <= SAME_LINE:
        theta = theta[:-1]
    mids = 0.5 * (theta + np.append(theta[1:], theta[0] + 2 * np.pi))
    out = []
    for t in mids:
        u = p + INSET * np.array([np.cos(t), np.sin(t)])
        if np.any((u <= 0.0) | (u >= 1.0)):
            continue
        if np.any(np.abs(a * u[0] + b * u[1] + c) <= 1e-3 * INSET):
            return None  # too near a line to tell its side
        out.append(u)
    return out


def _sides(
    rect: FloatArray, lines: list[FloatArray]
) -> tuple[FloatArray, npt.NDArray[np.intp], BoolArray] | None:
    """Points inside each side of the one switch line per rectangle.

    Returns ``(points (m, 2), rectangle index of each point (m,), valid (n,))``; a rectangle
    with no crossing comparison gets its centre, one with a single line a point on each side,
    one with several lines through one point a point in each sector, any other is not valid.
    """
    n = rect.shape[0]
    if not lines:
        return None
    g = np.stack(lines, 1)  # (n, M, 4)
    # a corner value within rounding of 0: the line passes through that corner (module doc)
    g = np.where(np.abs(g) <= ON_CORNER, 0.0, g)
    live = ~np.isnan(g[:, :, 0])
    gmin = np.where(live, np.nanmin(np.where(live[..., None], g, np.inf), axis=2), 0.0)
    gmax = np.where(live, np.nanmax(np.where(live[..., None], g, -np.inf), axis=2), 0.0)
    cross = live & (gmin < 0.0) & (gmax > 0.0)
    # an affine function's coefficients on the unit square, normalised, sign fixed
    c0 = g[:, :, 0]
    a = g[:, :, 1] - c0
    b = g[:, :, 2] - c0
    affine = np.abs(g[:, :, 3] - (c0 + a + b)) <= 1e-12 * (
        np.abs(c0) + np.abs(a) + np.abs(b) + 1e-300
    )
    norm = np.hypot(a, b)
    norm = np.where(norm > 0.0, norm, 1.0)
    sign = np.where((a > 0.0) | ((a == 0.0) & (b > 0.0)), 1.0, -1.0)
    coef = np.stack([a, b, c0], 2) * (sign / norm)[..., None]
    first = np.argmax(cross, axis=1)
    ref = coef[np.arange(n), first]  # (n, 3)
    same = np.all(np.abs(coef - ref[:, None, :]) <= SAME_LINE * (1.0 + np.abs(ref[:, None, :])), 2)
    n_cross = cross.sum(1)
    one_line = np.all(~cross | same, axis=1)
    valid = np.all(~cross | affine, axis=1)
    corners = np.array(_CORNERS, dtype=np.float64)
    pts, which = [], []
    for k in range(n):
        x0, x1, y0, y1 = rect[k]
        span = np.array([x1 - x0, y1 - y0])
        base = np.array([x0, y0])
        if n_cross[k] == 0:
            pts.append(base + 0.5 * span)
            which.append(k)
            continue
        if not valid[k]:
            continue
        if not one_line[k]:
            # several lines: the sectors around their common point, if they have one
            sectors = _sectors(coef[k, cross[k]])
            if sectors is None:
                valid[k] = False
                continue
            for u in sectors:
                pts.append(base + u * span)
                which.append(k)
            continue
        gk = g[k, first[k]]
        for corner in (int(np.argmin(gk)), int(np.argmax(gk))):
            # the point just inside from the corner where the line's function is extreme
            u = corners[corner] + INSET * (0.5 - corners[corner])
            val = gk[0] + (gk[1] - gk[0]) * u[0] + (gk[2] - gk[0]) * u[1]
            if np.sign(val) != np.sign(gk[corner]) or val == 0.0:
                valid[k] = False
            pts.append(base + u * span)
            which.append(k)
    if not pts:
        return None
    return np.array(pts), np.array(which, dtype=np.intp), valid
