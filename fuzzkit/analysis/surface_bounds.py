"""Sound bounds of the deployed exact surface and its slopes, refined by branch and bound.

The input square [-1, 1]^2 is cut into :data:`SEEDS` x :data:`SEEDS` rectangles; each gets the
enclosure of :mod:`fuzzkit.analysis.surface_enclosure` (``F``, ``dF/dx``, ``dF/dy`` at every
point, kinks included). The slopes the surface attains in a rectangle are measured by secants
of the engine (:data:`PROBES` points inside it, a step of 1e-6 of its width: a secant is a
slope the surface has, by the mean-value theorem). The bounds are read over boxes centred on
the loop's rest point (the certificate's, :meth:`SurfaceBounds.over`), so a rectangle is
judged against the slopes attained in the smallest such box that holds it (every rectangle no
farther from the centre: the Moore-Skelboe pattern, per box): one whose enclosure reaches
farther than ``tolerance`` beyond them is cut in four, down to :data:`MAX_DEPTH` levels and
:data:`MAX_RECTANGLES` rectangles; ``tolerance`` is :data:`RELATIVE_TOLERANCE` of the largest
attained slope. ``gap`` reports the largest remaining distance (a rectangle at the last level
may keep more, where the output bins' resolution dominates); the enclosure is sound whatever
the gap.

:meth:`SurfaceBounds.over` gives the bounds over any box: the hull of the rectangles that meet
it (closed), so a rectangle that only touches the box's edge counts too: the slopes at the
box's boundary (Clarke's gradient there takes the neighbours' in) are inside.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from fuzzkit.analysis.intervals import FloatArray
from fuzzkit.analysis.surface_enclosure import Enclosure, why_unsupported
from fuzzkit.fuzzy.model import RuleBase
from fuzzkit.loop.compiled.table import cache_dir, store_npz

SEEDS = 32
MAX_DEPTH = 6
#: The branch and bound stops splitting before it would hold more rectangles than this.
MAX_RECTANGLES = 40_000
#: Half the certificate's stated 5 %: the probes' secants fall a little short of the extremes.
RELATIVE_TOLERANCE = 0.035
#: Secant probes per rectangle (relative positions in it).
PROBES = ((0.5, 0.5), (0.2, 0.2), (0.2, 0.8), (0.8, 0.2), (0.8, 0.8))
_STEP = 1e-6


@dataclass(frozen=True, slots=True)
class Box:
    """Bounds over a box: ``f``, ``dF/dx``, ``dF/dy`` as ``(low, high)``."""

    f: tuple[float, float]
    dx: tuple[float, float]
    dy: tuple[float, float]


@dataclass(frozen=True, slots=True)
class SurfaceBounds:
    """The leaves of the branch and bound: rectangles and their enclosures (arrays)."""

    rect: FloatArray  # (n, 4): x0, x1, y0, y1
    f: FloatArray  # (n, 2)
    dx: FloatArray  # (n, 2)
    dy: FloatArray  # (n, 2)
    tolerance: float
    gap: float
    method: str = (
        "sound: outward-rounded interval enclosure of the closed-form slopes over rectangles, "
        "branch and bound"
    )

    def over(self, x_lo: float, x_hi: float, y_lo: float, y_hi: float) -> Box:
        """The hull of the bounds over the rectangles meeting ``[x_lo, x_hi] x [y_lo, y_hi]``."""
        r = self.rect
        meet = (r[:, 0] <= x_hi) & (r[:, 1] >= x_lo) & (r[:, 2] <= y_hi) & (r[:, 3] >= y_lo)
        if not np.any(meet):
            raise ValueError(f"no rectangle meets [{x_lo}, {x_hi}] x [{y_lo}, {y_hi}]")

        def hull(a: FloatArray) -> tuple[float, float]:
            return float(np.min(a[meet, 0])), float(np.max(a[meet, 1]))

        return Box(hull(self.f), hull(self.dx), hull(self.dy))

    @property
    def finite(self) -> bool:
        """Every enclosure is finite (no rectangle where no rule may fire)."""
        return bool(np.all(np.isfinite(self.dx)) and np.all(np.isfinite(self.dy)))


def _secants(rb: RuleBase, rect: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Attained slopes: per rectangle, the min and max secant along x and along y, (n, 2)."""
    from fuzzkit.fuzzy.inference import evaluate

    a, b = rb.inputs[0].name, rb.inputs[1].name
    out = rb.outputs[0].name
    wx, wy = rect[:, 1] - rect[:, 0], rect[:, 3] - rect[:, 2]
    sx, sy = [], []
    for px, py in PROBES:
        x = rect[:, 0] + px * wx
        y = rect[:, 2] + py * wy
        hx, hy = _STEP * wx, _STEP * wy
        xs = np.concatenate([x - hx, x + hx, x, x])
        ys = np.concatenate([y, y, y - hy, y + hy])
        f = np.asarray(evaluate(rb, {a: xs, b: ys})[out]).reshape(4, -1)
        sx.append((f[1] - f[0]) / (2 * hx))
        sy.append((f[3] - f[2]) / (2 * hy))
    ax, ay = np.array(sx), np.array(sy)
    return np.stack([ax.min(0), ax.max(0)], 1), np.stack([ay.min(0), ay.max(0)], 1)


def _split(rect: FloatArray) -> FloatArray:
    x0, x1, y0, y1 = rect.T
    xm, ym = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
    parts = [
        np.stack(c, 1)
        for c in ((x0, xm, y0, ym), (xm, x1, y0, ym), (x0, xm, ym, y1), (xm, x1, ym, y1))
    ]
    return np.concatenate(parts)


def seed_rectangles(enclosure: Enclosure, cells: int) -> FloatArray:
    """A ``cells`` x ``cells`` grid of the square, also cut at the input terms' kinks (so that
    every rectangle of a piecewise-linear rule base is affine in each membership), (n, 4)."""
    ex = np.union1d(np.linspace(-1.0, 1.0, cells + 1), enclosure.input_kinks(0))
    ey = np.union1d(np.linspace(-1.0, 1.0, cells + 1), enclosure.input_kinks(1))
    x0, y0 = np.meshgrid(ex[:-1], ey[:-1], indexing="ij")
    x1, y1 = np.meshgrid(ex[1:], ey[1:], indexing="ij")
    return np.stack([x0.ravel(), x1.ravel(), y0.ravel(), y1.ravel()], 1)


def _box_attained(
    radius: FloatArray, att_x: FloatArray, att_y: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Per rectangle: the slopes attained (secants, ``(low, high)`` along x and along y) by
    every rectangle no farther from the centre, (n, 2) each."""
    order = np.argsort(radius, kind="stable")
    out = []
    for att in (att_x, att_y):
        lo = np.minimum.accumulate(att[order, 0])
        hi = np.maximum.accumulate(att[order, 1])
        # rectangles at the same radius share the box
        r = radius[order]
        last = np.searchsorted(r, r, side="right") - 1
        got = np.empty_like(att)
        got[order, 0], got[order, 1] = lo[last], hi[last]
        out.append(got)
    return out[0], out[1]


def compute(rb: RuleBase, centre: float = 0.0) -> SurfaceBounds:
    """Branch and bound over [-1, 1]^2 (see the module doc) for the boxes centred on
    ``(centre, 0)``.

    Raises
    ------
    ValueError
        The rule base has no sound enclosure (:func:`why_unsupported` says why).
    """
    enclosure = Enclosure(rb)
    rect = seed_rectangles(enclosure, SEEDS)
    leaves: list[tuple[FloatArray, ...]] = []  # rect, f, dx, dy, secants x, secants y
    tolerance = math.nan
    for depth in range(MAX_DEPTH + 1):
        c = enclosure.enclose(rect[:, 0], rect[:, 1], rect[:, 2], rect[:, 3])
        att_x, att_y = _secants(rb, rect)
        if depth == 0:
            scale = max(float(np.max(np.abs(att_x))), float(np.max(np.abs(att_y))), 1e-12)
            tolerance = RELATIVE_TOLERANCE * scale
        enc = (
            np.stack([c.f.lo, c.f.hi], 1),
            np.stack([c.gx.lo, c.gx.hi], 1),
            np.stack([c.gy.lo, c.gy.hi], 1),
        )
        n_done = sum(len(leaf[0]) for leaf in leaves)
        all_rect = np.concatenate([leaf[0] for leaf in leaves] + [rect])
        radius = _radius(all_rect, centre)
        box_x, box_y = _box_attained(
            radius,
            np.concatenate([leaf[4] for leaf in leaves] + [att_x]),
            np.concatenate([leaf[5] for leaf in leaves] + [att_y]),
        )
        excess = _excess(enc[1], enc[2], box_x[n_done:], box_y[n_done:])
        keep = (excess <= tolerance) | (depth == MAX_DEPTH)
        leaves.append((rect[keep], *(a[keep] for a in enc), att_x[keep], att_y[keep]))
        if np.all(keep) or rect[~keep].shape[0] * 4 + n_done > MAX_RECTANGLES:
            if not np.all(keep):
                leaves.append((rect[~keep], *(a[~keep] for a in enc), att_x[~keep], att_y[~keep]))
            break
        rect = _split(rect[~keep])
    parts = [np.concatenate([leaf[k] for leaf in leaves]) for k in range(6)]
    box_x, box_y = _box_attained(_radius(parts[0], centre), parts[4], parts[5])
    gap = float(np.max(_excess(parts[2], parts[3], box_x, box_y), initial=0.0))
    return SurfaceBounds(parts[0], parts[1], parts[2], parts[3], tolerance, gap)


def _radius(rect: FloatArray, centre: float) -> FloatArray:
    """The half-width of the smallest box centred on ``(centre, 0)`` holding each rectangle."""
    out: FloatArray = np.max(
        np.abs(np.stack([rect[:, 0] - centre, rect[:, 1] - centre, rect[:, 2], rect[:, 3]])),
        axis=0,
    )
    return out


def _excess(dx: FloatArray, dy: FloatArray, box_x: FloatArray, box_y: FloatArray) -> FloatArray:
    """How far each enclosure reaches beyond the slopes attained in its box."""
    e = np.max(
        np.stack(
            [
                dx[:, 1] - box_x[:, 1],
                box_x[:, 0] - dx[:, 0],
                dy[:, 1] - box_y[:, 1],
                box_y[:, 0] - dy[:, 0],
            ]
        ),
        axis=0,
    )
    out: FloatArray = np.where(np.isfinite(e), e, np.inf)
    return out


@lru_cache(maxsize=16)
def surface_bounds(rb: RuleBase, centre: float = 0.0) -> SurfaceBounds | str:
    """The bounds of ``rb``'s exact surface (inputs in role order, clamped) for the boxes
    around ``(centre, 0)``, or why none. They are kept on disk beside the tables
    (:func:`fuzzkit.loop.compiled.table.cache_dir`), so a run does not pay the branch and
    bound each time: the key is the rule base, the centre and the source of the modules that
    compute them, so a change to any of them computes afresh."""
    why = why_unsupported(rb)
    if why is not None:
        return why
    path = cache_dir() / f"bounds-{_key(rb, centre)}.npz"
    try:
        with np.load(path, allow_pickle=False) as z:
            rect, f, dx, dy = (np.asarray(z[k], dtype=np.float64) for k in _FIELDS)
            return SurfaceBounds(rect, f, dx, dy, float(z["tolerance"]), float(z["gap"]))
    except (OSError, KeyError, ValueError):
        pass  # not cached yet, or unreadable: compute
    sb = compute(rb, centre)
    store_npz(path, **{k: getattr(sb, k) for k in _FIELDS}, tolerance=sb.tolerance, gap=sb.gap)
    return sb


_FIELDS = ("rect", "f", "dx", "dy")


def _key(rb: RuleBase, centre: float) -> str:
    from fuzzkit.analysis import intervals, surface_enclosure, switch_lines, term_intervals

    h = hashlib.sha256(f"{rb!r}|{centre!r}".encode())
    for module in (intervals, term_intervals, surface_enclosure, switch_lines):
        h.update(Path(str(module.__file__)).read_bytes())
    h.update(Path(__file__).read_bytes())
    return h.hexdigest()[:32]
