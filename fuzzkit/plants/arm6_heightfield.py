"""Gridded rough surfaces and tangent-plane contact in compiled code (the arm6 kernel's twin of
:class:`fuzzkit.plants.environment3d.HeightField`).

:func:`pack_height_field` reads a :class:`~fuzzkit.plants.environment3d.HeightField` into a
parameter row and its heights (row-major); :func:`height_field_contact` is
``HeightField.contact`` (bilinear height, its gradient, the local tangent plane) with the same
operations in the same order, so a compiled run over E3's 3-D floor touches where and as hard as
the Python plant does.
:func:`tangent_plane_contact` is the tangent-plane step shared with the extruded profiles of
:mod:`fuzzkit.plants.arm6_period`.

Twins: compiled copy; :class:`fuzzkit.plants.environment3d.HeightField` is the independent
reference it is tested against.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from fuzzkit.jit import jit
from fuzzkit.plants.environment3d import HeightField

FloatArray = npt.NDArray[np.float64]

# Indices into a height field's parameter row (``Arm6Arrays.obj_p``).
H_X0, H_Y0, H_DX, H_DY, H_NX, H_NY, H_Z0 = 0, 1, 2, 3, 4, 5, 6


def pack_height_field(field: HeightField) -> tuple[tuple[float, ...], FloatArray]:
    """The parameter row (see the ``H_*`` indices) and the heights (``nx * ny``, row-major:
    ``heights[i][j]`` at ``i * ny + j``) of ``field``: what :func:`height_field_contact` reads."""
    heights = np.asarray(field.heights, dtype=np.float64)
    nx, ny = heights.shape
    row = (field.x0, field.y0, field.dx, field.dy, float(nx), float(ny), field.z0)
    return row, np.ascontiguousarray(heights.reshape(-1))


@jit
def tangent_plane_contact(
    c: FloatArray,
    radius: float,
    h: float,
    dhdx: float,
    dhdy: float,
    nrm: FloatArray,
    pt: FloatArray,
) -> float:
    """Penetration of the tool sphere at ``c`` into the surface's tangent plane at height ``h``
    with gradient ``(dhdx, dhdy)`` (``> 0`` when touching, else ``-1``); the outward normal and
    the contact point go to ``nrm`` and ``pt`` (``arm6._tangent_plane_contact``)."""
    inv = 1.0 / math.sqrt(1.0 + dhdx * dhdx + dhdy * dhdy)
    depth = (h - c[2]) * inv + radius
    if depth <= 0.0:
        return -1.0
    nrm[0], nrm[1], nrm[2] = -dhdx * inv, -dhdy * inv, inv
    pt[0], pt[1], pt[2] = c[0], c[1], h
    return float(depth)


@jit
def height_field_contact(
    op: FloatArray,
    heights: FloatArray,
    c: FloatArray,
    radius: float,
    nrm: FloatArray,
    pt: FloatArray,
) -> float:
    """``HeightField.contact`` of the field packed in ``op`` / ``heights``: penetration depth
    (``> 0`` when touching, else ``-1``, also off the grid); normal and point out."""
    nx = int(op[H_NX])
    ny = int(op[H_NY])
    u = (c[0] - op[H_X0]) / op[H_DX]
    v = (c[1] - op[H_Y0]) / op[H_DY]
    if not (0.0 <= u <= nx - 1 and 0.0 <= v <= ny - 1):
        return -1.0
    i = min(int(u), nx - 2)
    j = min(int(v), ny - 2)
    fu, fv = u - i, v - j
    h00 = heights[i * ny + j]
    h01 = heights[i * ny + j + 1]
    h10 = heights[(i + 1) * ny + j]
    h11 = heights[(i + 1) * ny + j + 1]
    h = h00 * (1 - fu) * (1 - fv) + h10 * fu * (1 - fv) + h01 * (1 - fu) * fv + h11 * fu * fv
    dhdx = ((h10 - h00) * (1 - fv) + (h11 - h01) * fv) / op[H_DX]
    dhdy = ((h01 - h00) * (1 - fu) + (h11 - h10) * fu) / op[H_DY]
    return tangent_plane_contact(c, radius, h + op[H_Z0], dhdx, dhdy, nrm, pt)
