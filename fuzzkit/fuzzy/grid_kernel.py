"""Compiled integration of an aggregated output set on a fine grid (outputs with smooth terms).

The exact engine integrates outputs with gaussian or bell terms on a grid whose spacing comes
from an a-priori error bound (``output_geometry.GridGeometry``: up to 2^20 points). Done with numpy,
every evaluated point materialised an (N grid points x K pieces) array. This kernel computes the
same trapezoid sums (area, moment, cumulative area for the bisector, height and extent of the
maximum), with the same formulas, in O(1) extra memory per point:

* memberships are stored piece-major (K, N), and pieces whose level is 0 are skipped (under
  every implication and aggregation here they contribute exactly nothing), so only the firing
  pieces' rows are read;
* a batch walks the grid in blocks that stay in cache, every point of the batch per block;
  the bisector and the maxima keep each block's area and largest value, so their second pass
  rescans only the block that holds the answer.

Only the summation order differs from numpy's (blocked and sequential here, pairwise there): a
relative difference of order 1e-12, far below the grid's 1e-9 error bound.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from fuzzkit.jit import jit

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

IMPLICATIONS = {"min": 0, "product": 1}
AGGREGATIONS = {"max": 0, "bounded_sum": 1, "probabilistic_sum": 2}
DEFUZZIFIERS = {
    "centroid": 0,
    "bisector": 1,
    "smallest_of_maximum": 2,
    "largest_of_maximum": 3,
    "mean_of_maximum": 4,
}

#: Grid points per block: K pieces x BLOCK doubles stay in a core's L2 cache.
BLOCK = 2048


@jit
def _aggregate_block(
    levels: FloatArray,
    active: IntArray,
    n_active: int,
    mu_t: FloatArray,
    start: int,
    stop: int,
    imp_code: int,
    agg_code: int,
    f: FloatArray,
) -> None:
    """Aggregated membership at grid points ``start:stop`` into ``f[0:stop-start]``."""
    m = stop - start
    if agg_code == 2:
        for j in range(m):
            f[j] = 0.0  # log of the product of (1 - p) first
    else:
        for j in range(m):
            f[j] = 0.0
    for a in range(n_active):
        k = active[a]
        lk = levels[k]
        row = mu_t[k]
        for j in range(m):
            v = min(lk, row[start + j]) if imp_code == 0 else lk * row[start + j]
            if agg_code == 0:
                f[j] = max(f[j], v)
            elif agg_code == 1:
                f[j] += v
            else:
                f[j] += math.log1p(-min(v, 1.0))
    if agg_code == 1:
        for j in range(m):
            f[j] = min(f[j], 1.0)
    elif agg_code == 2:
        for j in range(m):
            f[j] = -math.expm1(f[j])


@jit
def grid_defuzzify(
    levels: FloatArray,
    mu_t: FloatArray,
    y: FloatArray,
    dy: float,
    imp_code: int,
    agg_code: int,
    defuzz_code: int,
    default: float,
) -> FloatArray:
    """Defuzzified value per row of ``levels`` (B, K) over the grid ``y`` (N,) with piece
    memberships ``mu_t`` (K, N); ``default`` where the output set is empty."""
    b_n, k_n = levels.shape
    n = y.shape[0]
    out = np.empty(b_n)
    actives = np.zeros((b_n, k_n), dtype=np.int64)
    counts = np.zeros(b_n, dtype=np.int64)
    for b in range(b_n):
        for k in range(k_n):
            if levels[b, k] != 0.0:
                actives[b, counts[b]] = k
                counts[b] += 1
    total = np.zeros(b_n)
    moment = np.zeros(b_n)
    height = np.zeros(b_n)
    f_prev = np.zeros(b_n)
    f = np.empty(BLOCK + 1)
    # per block: area of its cells and largest value, so that the second pass of the bisector
    # and of the maxima rescans only the block that holds the answer
    n_blocks = (n + BLOCK - 1) // BLOCK
    keep = defuzz_code >= 1
    block_area = np.zeros((b_n if keep else 0, n_blocks))
    block_max = np.zeros((b_n if keep else 0, n_blocks))
    # pass 1, blocked over the grid: area, moment, height
    for start in range(0, n, BLOCK):
        stop = min(start + BLOCK, n)
        for b in range(b_n):
            _aggregate_block(
                levels[b], actives[b], counts[b], mu_t, start, stop, imp_code, agg_code, f
            )
            i0 = 0
            f0 = f_prev[b]
            if start == 0:
                f0 = f[0]
                i0 = 1
                height[b] = max(height[b], f0)
            tot = total[b]
            mom = moment[b]
            hb = height[b]
            area = 0.0
            bmax = f0 if start == 0 else 0.0
            for j in range(i0, stop - start):
                i = start + j
                f1 = f[j]
                cell = 0.5 * dy * (f0 + f1)
                tot += cell
                area += cell
                mom += dy / 6 * (y[i - 1] * (2 * f0 + f1) + y[i] * (f0 + 2 * f1))
                hb = max(hb, f1)
                bmax = max(bmax, f1)
                f0 = f1
            total[b] = tot
            moment[b] = mom
            height[b] = hb
            f_prev[b] = f0
            if keep:
                block_area[b, start // BLOCK] = area
                block_max[b, start // BLOCK] = bmax
    for b in range(b_n):
        if defuzz_code == 0:
            out[b] = moment[b] / total[b] if total[b] > 1e-300 else default
        elif defuzz_code == 1:
            out[b] = _bisector(
                levels[b], actives[b], counts[b], mu_t, y, dy, imp_code, agg_code, total[b],
                default, f, block_area[b],
            )  # fmt: skip
        else:
            out[b] = _maximum(
                levels[b], actives[b], counts[b], mu_t, y, imp_code, agg_code, height[b],
                defuzz_code, default, f, block_max[b],
            )  # fmt: skip
    return out


@jit
def _bisector(
    lv: FloatArray,
    active: IntArray,
    n_active: int,
    mu_t: FloatArray,
    y: FloatArray,
    dy: float,
    imp_code: int,
    agg_code: int,
    total: float,
    default: float,
    f: FloatArray,
    block_area: FloatArray,
) -> float:
    """Where the cumulative trapezoid area first reaches half the total.

    The block where it does is found from the per-block areas; only that block is rescanned
    (with the point before it, for its first cell).
    """
    if not total > 1e-300:
        return default
    n = y.shape[0]
    half = 0.5 * total
    cum = 0.0
    blk = block_area.shape[0] - 1
    for q in range(block_area.shape[0]):
        if cum + block_area[q] >= half:
            blk = q
            break
        cum += block_area[q]
    start = blk * BLOCK
    stop = min(start + BLOCK, n)
    first = max(start - 1, 0)  # the cell from the previous block's last point
    _aggregate_block(lv, active, n_active, mu_t, first, stop, imp_code, agg_code, f)
    f0 = f[0]
    for j in range(1, stop - first):
        f1 = f[j]
        cell = 0.5 * dy * (f0 + f1)
        before = cum
        cum += cell
        if cum >= half:
            frac = (half - before) / cell if cell != 0.0 else 0.0
            return float(y[first + j - 1] + (frac if math.isfinite(frac) else 0.0) * dy)
        f0 = f1
    return float(y[stop - 1])


@jit
def _maximum(
    lv: FloatArray,
    active: IntArray,
    n_active: int,
    mu_t: FloatArray,
    y: FloatArray,
    imp_code: int,
    agg_code: int,
    height: float,
    defuzz_code: int,
    default: float,
    f: FloatArray,
    block_max: FloatArray,
) -> float:
    """Smallest, largest or mean of the maximum: grid points within 1e-10 of the height (a share).

    Only the first and the last block whose largest value qualifies are rescanned.
    """
    if not height > 0.0:
        return default
    n = y.shape[0]
    threshold = height * (1.0 - 1e-10)  # a share of the height, as output_geometry.TIE
    n_blocks = block_max.shape[0]
    q_first = 0
    while q_first < n_blocks - 1 and not block_max[q_first] >= threshold:
        q_first += 1
    q_last = n_blocks - 1
    while q_last > 0 and not block_max[q_last] >= threshold:
        q_last -= 1
    start = q_first * BLOCK
    stop = min(start + BLOCK, n)
    _aggregate_block(lv, active, n_active, mu_t, start, stop, imp_code, agg_code, f)
    som = math.inf
    for j in range(stop - start):
        if f[j] >= threshold:
            som = y[start + j]
            break
    start = q_last * BLOCK
    stop = min(start + BLOCK, n)
    _aggregate_block(lv, active, n_active, mu_t, start, stop, imp_code, agg_code, f)
    lom = -math.inf
    for j in range(stop - start - 1, -1, -1):
        if f[j] >= threshold:
            lom = y[start + j]
            break
    if defuzz_code == 2:
        return som
    if defuzz_code == 3:
        return lom
    return 0.5 * (som + lom)
