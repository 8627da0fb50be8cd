"""A floor under the error of every table on given breakpoints, from its cell edges alone.

Along an edge of a cell (the segment between two neighbouring nodes, parallel to an axis), a
table interpolates linearly between the edge's two node values: one input (linear), two
(either triangle: the cell's edges are its triangles' sides) and three (trilinear) alike.
Whatever those node values are (samples, fitted, rounded to float or Q15), the table's error
at the check points of an edge is therefore at least that of the best line through them, and
that is at least half the surface's largest distance from the edge's chord: for points
``a < b < c`` of the edge, errors ``e`` of any line and the chord's deviation ``d_b`` at ``b``,
``e_b - (lam e_a + (1 - lam) e_c) = d_b`` with ``0 < lam < 1``, so ``max |e| >= |d_b| / 2``.

The table search (:mod:`fuzzkit.codegen.table_search`) uses it to prove that a resolution
cannot meet a tolerance without building its table: the certified bound of a table is at
least its largest error on the check grid, which holds every edge's check points.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]


def chord_floor(t: FloatArray, f: FloatArray, factor: int) -> tuple[FloatArray, IntArray]:
    """Half the largest distance of ``f`` from its edges' chords, per line, and where it is.

    ``t`` (n,) are the coordinates of the check points along one axis, ``factor`` per edge
    then the last node (``n = factor * edges + 1``); ``f`` (lines, n) the surface on lines
    parallel to that axis through the nodes. Returns the floor (lines,) and the index into
    ``t`` of the point it was found at (lines,). NaN values (no rule fires) count as no
    evidence.
    """
    edges = (len(t) - 1) // factor
    t0, t1 = t[:-1:factor], t[factor::factor]
    lam = (t[:-1].reshape(edges, factor) - t0[:, None]) / np.where(t1 > t0, t1 - t0, 1.0)[:, None]
    f0, f1 = f[:, :-1:factor], f[:, factor::factor]
    inner = f[:, :-1].reshape(f.shape[0], edges, factor)
    dev = np.abs(inner - (f0[..., None] + (f1 - f0)[..., None] * lam[None]))
    dev = np.where(np.isfinite(dev), dev, 0.0).reshape(f.shape[0], -1)
    worst = np.argmax(dev, axis=1)
    return 0.5 * dev[np.arange(f.shape[0]), worst], worst.astype(np.intp)


__all__ = ["chord_floor"]
