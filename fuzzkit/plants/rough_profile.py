"""The height and slope of a rough profile in compiled code, shared by both compiled plants.

:func:`profile_height_slope` is :meth:`fuzzkit.plants.environment.RoughSurface.height` and
:meth:`~fuzzkit.plants.environment.RoughSurface.slope` for a surface packed into a parameter row
(``x_min, x_max, height_m, offset_m, tilt_rad``, then whatever the caller adds) and its sine terms
(rows of wavenumber, amplitude, phase, padded by :func:`fuzzkit.plants.contact.padded_terms`).
The 6-DOF plant's extruded profiles (:mod:`fuzzkit.plants.arm6_period`) and the planar arm's
rough surfaces (:mod:`fuzzkit.planar_sim.arm_period`) both read it. The Python ``RoughSurface``
stays a separate implementation on purpose: it is the reference that the compiled-loop
equivalence tests (``tests/test_compiled_loop.py``) hold these loops to.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from fuzzkit.jit import jit

FloatArray = npt.NDArray[np.float64]


@jit
def profile_height_slope(
    op: FloatArray, terms: FloatArray, nterms: int, x: float
) -> tuple[float, float]:
    """``(height, slope)`` of the profile at ``x`` (no range check: the caller's)."""
    tan_tilt = math.tan(op[4])
    h = op[2] + op[3] + tan_tilt * (x - op[0])
    for j in range(nterms):
        h += terms[j, 1] * math.sin(terms[j, 0] * x + terms[j, 2])
    slope = tan_tilt
    for j in range(nterms):
        slope += terms[j, 1] * terms[j, 0] * math.cos(terms[j, 0] * x + terms[j, 2])
    return h, slope
