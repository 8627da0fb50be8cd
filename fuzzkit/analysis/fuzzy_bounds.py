"""Bounds on a fuzzy-PI's control surface, computed exactly from the surface that runs.

The fuzzy-PI computes ``du = Kx * F(x, y)`` with ``x = Ki*e`` and ``y = Kp*de`` (clipped to
[-1, 1]). The surface the compiled loop and the generated table code evaluate is the rule base's
lookup table (:func:`fuzzkit.loop.compiled.table.compiled_table`): a continuous piecewise-linear
function on triangles. On such a surface every bound below is exact, from the table's nodes and
triangles, with no sampling between them.

* **PI-like structure** (:func:`phi_bounds`). When ``F`` vanishes on the line ``x + y = 0``
  (``F(x, -x) = 0``, as for the MacVicar-Whelan table) it factors as ``F = phi(x, y) * (x + y)``:
  the fuzzy-PI is then an incremental PI with gains ``Kx*Ki`` and ``Kx*Kp`` multiplied by a
  time-varying ``phi``. On a triangle that does not meet the line, ``phi`` is a ratio of two
  linear functions whose denominator keeps its sign, so its extremes are at the triangle's
  vertices. A triangle that meets the line must be ``F = lam * (x + y)`` on the whole triangle
  (checked: the linear fit's constant and the difference of its slopes vanish to rounding), or
  ``phi`` is unbounded there and the structure does not hold.
* **Gradient bounds** (:func:`gradient_bounds`), the fallback for any other surface: on each
  triangle the slopes ``dF/dx``, ``dF/dy`` are constants; integrating along the segment from
  the loop's rest point ``(x0, 0)`` (where ``F(x0, 0) = 0``,
  :mod:`fuzzkit.analysis.equilibrium`), ``F(x0 + dx, dy) = a*dx + b*dy`` with ``a`` and ``b``
  in the range of the slopes over the triangles the segment crosses (a box around the rest
  point contains the segment).

Both are taken over a box of half-width ``rho`` around the rest point, enlarged to whole table
cells: the certificate is local to the errors for which ``|Ki*(e - e0)| <= rho`` and
``|Kp*de| <= rho``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import ConfigError

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Relative size (of the table's largest |value|) below which a triangle's constant term and
#: slope difference count as rounding when checking ``F = lam * (x + y)`` on it.
STRUCTURE_TOLERANCE = 1e-9
#: Relative distance (of the input range) within which a breakpoint counts as equal to rho.
_BREAKPOINT_ROUNDING = 1e-12


@dataclass(frozen=True, slots=True)
class PhiBounds:
    """``F(x, y) = phi * (x + y)`` with ``phi`` in ``[low, high]`` on the box ``|x|, |y| <= rho``.

    ``rho``: the box actually covered (whole table cells, so at least the one asked for).
    ``small_signal``: ``phi`` on the triangles at the origin. ``residual``: the largest
    ``|F - lam*(x + y)|`` on the triangles crossing the line ``x + y = 0`` (rounding only).
    """

    low: float
    high: float
    rho: float
    small_signal: float
    residual: float
    method: str = "exact: phi at the vertices of the lookup table's triangles"


@dataclass(frozen=True, slots=True)
class GradientBounds:
    """``F(x, y) = a*x + b*y`` with ``a`` in ``a_range``, ``b`` in ``b_range`` on the box."""

    a_range: tuple[float, float]
    b_range: tuple[float, float]
    rho: float
    centre: float = 0.0
    method: str = "exact: slopes of the lookup table's triangles"


class StructureError(ConfigError):
    """The surface is not ``phi * (x + y)``: it does not vanish on ``x + y = 0`` somewhere."""


def triangles(
    bp0: FloatArray,
    bp1: FloatArray,
    values: FloatArray,
    splits: IntArray,
    rho: float,
    centre: float = 0.0,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The table's triangles over the cells meeting ``(centre - rho, centre + rho) x (-rho,
    rho)``.

    Returns ``xs, ys, fs``, each ``(m, 3)``: the vertices' x, y and F. A cell with
    ``splits == 0`` is cut along its main diagonal (node ``i, j`` to ``i+1, j+1``), else along
    its anti-diagonal, as :func:`fuzzkit.loop.compiled.table.table2` interpolates.
    """
    if not (math.isfinite(rho) and rho > 0.0):
        raise ConfigError(f"the fuzzy region must be a number > 0 (got {rho})")
    r = rho - _BREAKPOINT_ROUNDING * float(bp0[-1] - bp0[0])  # a breakpoint at rho is the edge
    ci = [i for i in range(len(bp0) - 1) if bp0[i] < centre + r and bp0[i + 1] > centre - r]
    cj = [j for j in range(len(bp1) - 1) if bp1[j] < r and bp1[j + 1] > -r]
    xs: list[tuple[float, float, float]] = []
    ys: list[tuple[float, float, float]] = []
    fs: list[tuple[float, float, float]] = []
    for i in ci:
        for j in cj:
            x0, x1, y0, y1 = bp0[i], bp0[i + 1], bp1[j], bp1[j + 1]
            node = {
                (0, 0): (x0, y0, values[i, j]),
                (1, 0): (x1, y0, values[i + 1, j]),
                (0, 1): (x0, y1, values[i, j + 1]),
                (1, 1): (x1, y1, values[i + 1, j + 1]),
            }
            if splits[i, j] == 0:
                tris = (((0, 0), (1, 0), (1, 1)), ((0, 0), (0, 1), (1, 1)))
            else:
                tris = (((1, 0), (0, 0), (0, 1)), ((1, 0), (1, 1), (0, 1)))
            for tri in tris:
                pts = [node[c] for c in tri]
                xs.append((pts[0][0], pts[1][0], pts[2][0]))
                ys.append((pts[0][1], pts[1][1], pts[2][1]))
                fs.append((pts[0][2], pts[1][2], pts[2][2]))
    return np.array(xs), np.array(ys), np.array(fs)


def _plane(xs: FloatArray, ys: FloatArray, fs: FloatArray) -> FloatArray:
    """Per triangle, ``(alpha, beta, gamma)`` with ``F = alpha*x + beta*y + gamma``."""
    m = np.stack([xs, ys, np.ones_like(xs)], axis=-1)  # (n, 3, 3)
    out: FloatArray = np.linalg.solve(m, fs[..., None])[..., 0].astype(np.float64)
    return out


def covered_rho(bp0: FloatArray, bp1: FloatArray, rho: float, centre: float = 0.0) -> float:
    """The half-width of the box (around ``(centre, 0)``) that the cells meeting
    ``(centre - rho, centre + rho) x (-rho, rho)`` cover, within the universe."""
    r = rho - _BREAKPOINT_ROUNDING * float(bp0[-1] - bp0[0])

    def reach(bp: FloatArray, c: float) -> float:
        up = float(np.min(bp[bp >= c + r])) if np.any(bp >= c + r) else float(bp[-1])
        down = float(np.max(bp[bp <= c - r])) if np.any(bp <= c - r) else float(bp[0])
        return min(up - c, c - down)

    return min(reach(bp0, centre), reach(bp1, 0.0))


def phi_bounds(
    bp0: FloatArray, bp1: FloatArray, values: FloatArray, splits: IntArray, rho: float = 1.0
) -> PhiBounds:
    """Exact bounds of ``phi = F / (x + y)`` over the table's cells meeting ``(-rho, rho)^2``.

    Raises
    ------
    StructureError
        If a triangle meets the line ``x + y = 0`` where ``F`` does not vanish on it.
    """
    xs, ys, fs = triangles(bp0, bp1, values, splits, rho)
    scale = max(float(np.max(np.abs(values))), 1e-300)
    s = xs + ys
    span = max(float(np.max(np.abs(s))), 1e-300)
    # a vertex counts as on the line when |x + y| is rounding of the breakpoints
    on_line = np.abs(s) <= 1e-12 * span
    side_pos = np.all((s > 0.0) | on_line, axis=1)
    side_neg = np.all((s < 0.0) | on_line, axis=1)
    one_side = (side_pos | side_neg) & ~np.all(on_line, axis=1)
    plane = _plane(xs, ys, fs)
    low, high = math.inf, -math.inf
    residual = 0.0
    # Triangles on one side of the line: phi is linear-fractional, extremes at the vertices;
    # a vertex on the line must have F = 0 there (phi is then constant along its edges).
    for t in np.nonzero(one_side)[0]:
        on = on_line[t]
        if np.any(np.abs(fs[t][on]) > STRUCTURE_TOLERANCE * scale):
            raise _broken(xs[t], ys[t])
        residual = max(residual, float(np.max(np.abs(fs[t][on]), initial=0.0)))
        ratios = fs[t][~on] / s[t][~on]
        low, high = min(low, float(np.min(ratios))), max(high, float(np.max(ratios)))
    # Triangles the line crosses: F must be lam * (x + y) on the whole triangle.
    for t in np.nonzero(~one_side)[0]:
        alpha, beta, gamma = plane[t]
        if (
            abs(gamma) > STRUCTURE_TOLERANCE * scale
            or abs(alpha - beta) > STRUCTURE_TOLERANCE * scale / span
        ):
            raise _broken(xs[t], ys[t])
        lam = 0.5 * (alpha + beta)
        residual = max(residual, float(np.max(np.abs(fs[t] - lam * s[t]))))
        low, high = min(low, lam), max(high, lam)
    return PhiBounds(
        low=low,
        high=high,
        rho=covered_rho(bp0, bp1, rho),
        small_signal=_origin_phi(bp0, bp1, values, splits),
        residual=residual,
    )


def _origin_phi(bp0: FloatArray, bp1: FloatArray, values: FloatArray, splits: IntArray) -> float:
    """``phi`` on the triangles touching the origin (their common value for a PI-like table)."""
    tiny = 1e-9 * float(bp0[-1] - bp0[0])
    xs, ys, fs = triangles(bp0, bp1, values, splits, tiny)
    ratios = [
        fs[t][k] / (xs[t][k] + ys[t][k])
        for t in range(len(fs))
        for k in range(3)
        if abs(xs[t][k] + ys[t][k]) > 0.0
    ]
    return float(np.median(ratios)) if ratios else math.nan


def gradient_bounds(
    bp0: FloatArray,
    bp1: FloatArray,
    values: FloatArray,
    splits: IntArray,
    rho: float = 1.0,
    centre: float = 0.0,
) -> GradientBounds:
    """Exact ranges of the slopes ``dF/dx``, ``dF/dy`` over the cells meeting the box of
    half-width ``rho`` around the rest point ``(centre, 0)``.

    ``F(centre + dx, dy) - F(centre, 0) = a*dx + b*dy`` with ``a``, ``b`` in those ranges (the
    mean-value theorem along the segment from the rest point). The box is narrowed to stay in
    the universe (beyond it the input clips and the slope is 0, which the ranges need not
    hold): ``rho`` becomes at most ``1 - |centre|``.
    """
    rho = min(rho, float(bp0[-1]) - centre, centre - float(bp0[0]))
    if not rho > 0.0:
        raise ConfigError(f"the rest point e = {centre:g} is on the universe's edge")
    xs, ys, fs = triangles(bp0, bp1, values, splits, rho, centre)
    plane = _plane(xs, ys, fs)
    return GradientBounds(
        a_range=(float(np.min(plane[:, 0])), float(np.max(plane[:, 0]))),
        b_range=(float(np.min(plane[:, 1])), float(np.max(plane[:, 1]))),
        rho=covered_rho(bp0, bp1, rho, centre),
        centre=centre,
    )


def _broken(xs: FloatArray, ys: FloatArray) -> StructureError:
    return StructureError(
        "the surface is not phi*(e + de): it does not vanish on e + de = 0 in the cell "
        f"e in [{xs.min():.4g}, {xs.max():.4g}], de in [{ys.min():.4g}, {ys.max():.4g}]"
    )
