"""The generated lookup table's arithmetic in compiled code (double-precision 2-D tables).

The same operations, in the same order, as ``fuzzkit.codegen.lut.LookupTable.interpolate`` for
``number_type="double"`` and hence as the generated C: clamp to the breakpoint range, locate the
cell, then linear interpolation on the cell's triangle (the diagonal each cell's ``splits`` names).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import ConfigError
from fuzzkit.plants.jit import jit

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


@jit
def _locate(bp: FloatArray, x: float) -> tuple[int, float]:
    """Cell index and fraction of ``x`` clamped to ``bp``'s range (``_locate_float``)."""
    n = bp.shape[0]
    xc = min(max(x, bp[0]), bp[n - 1])
    # searchsorted(bp, xc, side="right") - 1, then clipped to [0, n - 2]
    lo, hi = 0, n
    while lo < hi:
        mid = (lo + hi) // 2
        if bp[mid] <= xc:
            lo = mid + 1
        else:
            hi = mid
    i = min(max(lo - 1, 0), n - 2)
    return i, (xc - bp[i]) / (bp[i + 1] - bp[i])


@jit
def table2(
    bp0: FloatArray, bp1: FloatArray, tab: FloatArray, splits: IntArray, x0: float, x1: float
) -> float:
    """Interpolate a 2-D double table at ``(x0, x1)``; NaN in, NaN out."""
    if math.isnan(x0) or math.isnan(x1):
        return math.nan
    i, t0 = _locate(bp0, x0)
    j, t1 = _locate(bp1, x1)
    v00, v10 = tab[i, j], tab[i + 1, j]
    v01, v11 = tab[i, j + 1], tab[i + 1, j + 1]
    if splits[i, j] != 0:
        s0, w00, w10, w01, w11 = 1.0 - t0, v10, v00, v11, v01
    else:
        s0, w00, w10, w01, w11 = t0, v00, v10, v01, v11
    if s0 >= t1:
        vm, hi_, lo_ = w10, s0, t1
    else:
        vm, hi_, lo_ = w01, t1, s0
    return float(w00 + hi_ * (vm - w00) + lo_ * (w11 - vm))


def table_arrays(table: Any) -> tuple[FloatArray, FloatArray, FloatArray, IntArray]:
    """``(breakpoints e, breakpoints de, values, splits)`` of a 2-input, 1-output double table.

    Raises
    ------
    ConfigError
        If the table is not a double table with two inputs and one output.
    """
    if table.number_type != "double" or len(table.breakpoints) != 2 or len(table.stored) != 1:
        raise ConfigError(
            "the compiled loop runs a double lookup table with inputs (e, de) and one output "
            f"(got {table.number_type}, {len(table.breakpoints)} inputs, "
            f"{len(table.stored)} outputs)"
        )
    tab = np.ascontiguousarray(table.stored[0], dtype=np.float64)
    splits = (
        np.zeros((tab.shape[0] - 1, tab.shape[1] - 1), dtype=np.int64)
        if table.splits is None
        else np.ascontiguousarray(table.splits, dtype=np.int64)
    )
    return (
        np.ascontiguousarray(table.breakpoints[0], dtype=np.float64),
        np.ascontiguousarray(table.breakpoints[1], dtype=np.float64),
        tab,
        splits,
    )
