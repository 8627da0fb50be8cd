"""The world a scenario describes: the nominal (pre-programmed) path and the environment objects.

Objects live in the base frame's vertical x-z working plane and are extruded along y; see
:mod:`fuzzkit.plants.contract` for frames and signs.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import numpy.typing as npt

Vec = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class Waypoint:
    """A point of the nominal (CAD) path: tool tip at ``(x, y, z)`` m at time ``t_s`` s.

    ``tilt_rad``: the tool turned about the base y axis from the task frame's orientation
    (right-handed, interpolated between waypoints); only the 6-DOF plant turns its tool.
    """

    t_s: float
    x: float
    y: float
    z: float
    tilt_rad: float = 0.0


def nominal_position(path: tuple[Waypoint, ...], t_s: float) -> Vec:
    """Tool-tip position of the nominal path at time ``t_s`` (linear between waypoints, held at
    both ends), base frame, metres."""
    if t_s <= path[0].t_s:
        w = path[0]
        return np.array([w.x, w.y, w.z])
    for a, b in itertools.pairwise(path):
        if t_s <= b.t_s:
            s = (t_s - a.t_s) / (b.t_s - a.t_s) if b.t_s > a.t_s else 1.0
            return np.array([a.x + s * (b.x - a.x), a.y + s * (b.y - a.y), a.z + s * (b.z - a.z)])
    w = path[-1]
    return np.array([w.x, w.y, w.z])


# --------------------------------------------------------------------------------------------
# Environment objects (x-z plane, extruded along y)
# --------------------------------------------------------------------------------------------

#: ``(depth, nx, nz, px, pz)``: penetration depth in metres (> 0 when touching), outward unit
#: normal of the object at the contact, and the contact point on the object surface.
Penetration = tuple[float, float, float, float, float]


@dataclass(frozen=True, slots=True)
class Table:
    """A horizontal table top: solid below ``height_m`` for ``x_min <= x <= x_max``."""

    height_m: float
    x_min: float = -10.0
    x_max: float = 10.0
    name: str = "table"

    def penetration(self, x: float, z: float, radius: float) -> Penetration | None:
        """Contact of a disc of ``radius`` centred at ``(x, z)`` with the table, or None."""
        if not self.x_min <= x <= self.x_max:
            return None
        depth = self.height_m - (z - radius)
        return (depth, 0.0, 1.0, x, self.height_m) if depth > 0.0 else None


@dataclass(frozen=True, slots=True)
class Box:
    """An axis-aligned solid block (the hammer of E1, a wall): centre and size in x and z."""

    center_x: float
    center_z: float
    size_x: float
    size_z: float
    name: str = "box"

    def penetration(self, x: float, z: float, radius: float) -> Penetration | None:
        """Contact of a disc of ``radius`` centred at ``(x, z)`` with the block, or None."""
        hx, hz = 0.5 * self.size_x, 0.5 * self.size_z
        dx, dz = x - self.center_x, z - self.center_z
        qx, qz = min(max(dx, -hx), hx), min(max(dz, -hz), hz)
        ox, oz = dx - qx, dz - qz
        dist = math.hypot(ox, oz)
        if dist > 1e-12:
            depth = radius - dist
            if depth <= 0.0:
                return None
            return (depth, ox / dist, oz / dist, self.center_x + qx, self.center_z + qz)
        # Centre inside the block: push out through the nearest face.
        faces = (
            (hx - dx, 1.0, 0.0),
            (hx + dx, -1.0, 0.0),
            (hz - dz, 0.0, 1.0),
            (hz + dz, 0.0, -1.0),
        )
        gap, nx, nz = min(faces)
        return (radius + gap, nx, nz, x + nx * gap, z + nz * gap)


@dataclass(frozen=True, slots=True)
class RoughSurface:
    """A rough workpiece top between ``x_min`` and ``x_max``, solid below its profile.

    ``height(x) = height_m + offset_m + tan(tilt_rad) * (x - x_min) + r(x)``, where ``offset_m`` and
    ``tilt_rad`` are the calibration error the CAD path does not know about and ``r(x)`` is a
    band-limited roughness: a sum of ``n_waves`` sines with wavelengths log-spaced in
    ``[wavelength_min_m, wavelength_max_m]``, amplitudes proportional to the wavelength and phases
    drawn from ``seed``, scaled so its RMS is ``roughness_rms_m``. Same parameters, same surface.
    """

    x_min: float
    x_max: float
    height_m: float
    tilt_rad: float = 0.0
    offset_m: float = 0.0
    roughness_rms_m: float = 0.0
    wavelength_min_m: float = 0.004
    wavelength_max_m: float = 0.05
    n_waves: int = 12
    seed: int = 0
    name: str = "workpiece"

    def _terms(self) -> tuple[tuple[float, float, float], ...]:
        return _roughness_terms(
            self.seed,
            self.roughness_rms_m,
            self.wavelength_min_m,
            self.wavelength_max_m,
            self.n_waves,
        )

    def height(self, x: float) -> float:
        """Surface height (metres, base z) at ``x``."""
        h = self.height_m + self.offset_m + math.tan(self.tilt_rad) * (x - self.x_min)
        for k, a, ph in self._terms():
            h += a * math.sin(k * x + ph)
        return h

    def slope(self, x: float) -> float:
        """Surface slope dz/dx at ``x``."""
        s = math.tan(self.tilt_rad)
        for k, a, ph in self._terms():
            s += a * k * math.cos(k * x + ph)
        return s

    def penetration(self, x: float, z: float, radius: float) -> Penetration | None:
        """Contact of a disc centred at ``(x, z)`` with the profile (local half-space), or None."""
        if not self.x_min <= x <= self.x_max:
            return None
        h = self.height(x)
        m = self.slope(x)
        inv = 1.0 / math.sqrt(1.0 + m * m)
        depth = (h - z) * inv + radius
        if depth <= 0.0:
            return None
        return (depth, -m * inv, inv, x, h)


@lru_cache(maxsize=64)
def _roughness_terms(
    seed: int, rms: float, lmin: float, lmax: float, n: int
) -> tuple[tuple[float, float, float], ...]:
    """(wavenumber, amplitude, phase) of each sine of a roughness profile, cached per parameters."""
    if rms <= 0.0 or n <= 0:
        return ()
    rng = np.random.default_rng(seed)
    lams = np.geomspace(lmin, lmax, n)
    phases = rng.uniform(0.0, 2.0 * math.pi, n)
    amps = lams / lams.sum()
    # RMS of a sum of incoherent sines is sqrt(sum(a^2)/2).
    amps *= rms / math.sqrt(float(np.sum(amps**2)) / 2.0)
    return tuple(
        (2.0 * math.pi / float(lam), float(a), float(p))
        for lam, a, p in zip(lams, amps, phases, strict=True)
    )


EnvObject = Table | Box | RoughSurface
