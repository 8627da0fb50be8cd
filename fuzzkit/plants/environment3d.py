"""The 3-D environment of the 6-DOF arm and the tool's contact with it.

Objects (:class:`Plane`, :class:`Box3`, :class:`HeightField`, :class:`ExtrudedProfile`) answer
where a tool sphere touches them (depth, outward normal, point); :func:`objects_from_scenario`
builds them from a planar :class:`~fuzzkit.plants.contract.Scenario` (extruded along y);
:class:`Contact3Solver` turns the touches of one period into the force and moment the tool
exerts (penalty normal force, Coulomb friction with a stick spring). The plant that moves the
tool through this world: :mod:`fuzzkit.plants.arm6`.

Twins: this is the **reference** copy of the 6-DOF 3-D contact with friction; the compiled loop's
copy (:mod:`fuzzkit.plants.arm6_period`) is tested against it (``tests/test_compiled_loop.py``),
so it is kept as a separate implementation on purpose.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import ConfigError
from fuzzkit.plants.contact import ContactModel
from fuzzkit.plants.contract import Scenario
from fuzzkit.plants.environment import Box, RoughSurface, Table
from fuzzkit.plants.rotations import (
    Vec3,
)

FloatArray = npt.NDArray[np.float64]


#: ``(depth, normal, point)``: penetration of the tool sphere (> 0 when touching), the outward
#: unit normal of the object there, and the contact point on the object's surface.
Contact3 = tuple[float, Vec3, Vec3]


@dataclass(frozen=True, slots=True)
class Plane:
    """A solid half-space behind a plane (a table top, a wall), limited to a rectangle.

    ``normal`` points out of the solid; contact is only counted while the sphere centre's x and
    y lie within ``[x_min, x_max]`` and ``[y_min, y_max]`` (a table has edges).
    """

    point: Vec3
    normal: Vec3
    x_min: float = -math.inf
    x_max: float = math.inf
    y_min: float = -math.inf
    y_max: float = math.inf
    name: str = "plane"

    def contact(self, c: Vec3, radius: float) -> Contact3 | None:
        """Contact of a sphere of ``radius`` centred at ``c``, or None."""
        if not (self.x_min <= c[0] <= self.x_max and self.y_min <= c[1] <= self.y_max):
            return None
        nx, ny, nz = self.normal
        n = math.sqrt(nx * nx + ny * ny + nz * nz)
        nx, ny, nz = nx / n, ny / n, nz / n
        dist = (
            (c[0] - self.point[0]) * nx + (c[1] - self.point[1]) * ny + (c[2] - self.point[2]) * nz
        )
        depth = radius - dist
        if depth <= 0.0:
            return None
        return depth, (nx, ny, nz), (c[0] - dist * nx, c[1] - dist * ny, c[2] - dist * nz)


@dataclass(frozen=True, slots=True)
class Box3:
    """An axis-aligned solid block (the hammer of experiment 1, a fixture): centre, half sizes."""

    center: Vec3
    half_size: Vec3
    name: str = "box"

    def contact(self, c: Vec3, radius: float) -> Contact3 | None:
        """Contact of a sphere of ``radius`` centred at ``c``, or None."""
        d = [c[i] - self.center[i] for i in range(3)]
        h = self.half_size
        q = [min(max(d[i], -h[i]), h[i]) for i in range(3)]
        o = [d[i] - q[i] for i in range(3)]
        dist = math.sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2])
        if dist > 1e-12:
            depth = radius - dist
            if depth <= 0.0:
                return None
            n: Vec3 = (o[0] / dist, o[1] / dist, o[2] / dist)
            pt: Vec3 = (
                self.center[0] + q[0],
                self.center[1] + q[1],
                self.center[2] + q[2],
            )
            return depth, n, pt
        # Centre inside the block: push out through the nearest face.
        best = (math.inf, 0, 1.0)
        for i in range(3):
            for sign in (1.0, -1.0):
                gap = h[i] - sign * d[i]
                if gap < best[0]:
                    best = (gap, i, sign)
        gap, axis, sign = best
        nv = [0.0, 0.0, 0.0]
        nv[axis] = sign
        n = (nv[0], nv[1], nv[2])
        return radius + gap, n, (c[0] + n[0] * gap, c[1] + n[1] * gap, c[2] + n[2] * gap)


@dataclass(frozen=True, slots=True)
class HeightField:
    """A rough surface ``z = h(x, y)`` on a regular grid (bilinear), solid below it.

    ``heights[i, j]`` is the height at ``x = x0 + i*dx``, ``y = y0 + j*dy``. Outside the grid
    there is no surface. Contact uses the local tangent plane (penetration along the normal),
    which is accurate while the tool radius is small against the roughness wavelength.
    """

    x0: float
    y0: float
    dx: float
    dy: float
    heights: tuple[tuple[float, ...], ...]
    name: str = "height field"
    #: added to every height (moving a field into another frame without rebuilding it)
    z0: float = 0.0

    @classmethod
    def rough(
        cls,
        x_range: tuple[float, float],
        y_range: tuple[float, float],
        height: float,
        roughness_rms: float,
        spacing: float = 0.002,
        seed: int = 0,
        name: str = "rough workpiece",
    ) -> HeightField:
        """A seeded random rough surface around ``height`` with the given RMS roughness.

        White noise smoothed by a 3x3 box filter (so the slope stays bounded), rescaled to the
        asked RMS. Same arguments, same surface.
        """
        nx = max(2, round((x_range[1] - x_range[0]) / spacing) + 1)
        ny = max(2, round((y_range[1] - y_range[0]) / spacing) + 1)
        rng = np.random.default_rng(seed)
        noise = rng.normal(0.0, 1.0, (nx + 2, ny + 2))
        smooth = sum(noise[i : i + nx, j : j + ny] for i in range(3) for j in range(3)) / 9.0
        smooth = np.asarray(smooth, dtype=float)
        std = float(np.std(smooth))
        z = height + (smooth - float(np.mean(smooth))) * (roughness_rms / std if std > 0 else 0.0)
        return cls(
            x0=x_range[0],
            y0=y_range[0],
            dx=(x_range[1] - x_range[0]) / (nx - 1),
            dy=(y_range[1] - y_range[0]) / (ny - 1),
            heights=tuple(tuple(float(v) for v in row) for row in z),
            name=name,
        )

    def height_and_gradient(self, x: float, y: float) -> tuple[float, float, float] | None:
        """Height and its gradient ``(h, dh/dx, dh/dy)`` at ``(x, y)``, or None off the grid."""
        u = (x - self.x0) / self.dx
        v = (y - self.y0) / self.dy
        hs = self.heights
        nx, ny = len(hs), len(hs[0])
        if not (0.0 <= u <= nx - 1 and 0.0 <= v <= ny - 1):
            return None
        i = min(int(u), nx - 2)
        j = min(int(v), ny - 2)
        fu, fv = u - i, v - j
        h00, h01, h10, h11 = hs[i][j], hs[i][j + 1], hs[i + 1][j], hs[i + 1][j + 1]
        h = h00 * (1 - fu) * (1 - fv) + h10 * fu * (1 - fv) + h01 * (1 - fu) * fv + h11 * fu * fv
        dhdx = ((h10 - h00) * (1 - fv) + (h11 - h01) * fv) / self.dx
        dhdy = ((h01 - h00) * (1 - fu) + (h11 - h10) * fu) / self.dy
        return h + self.z0, dhdx, dhdy

    def contact(self, c: Vec3, radius: float) -> Contact3 | None:
        """Contact of a sphere of ``radius`` centred at ``c`` (local tangent plane), or None."""
        hg = self.height_and_gradient(c[0], c[1])
        if hg is None:
            return None
        return _tangent_plane_contact(c, radius, *hg)


@dataclass(frozen=True, slots=True)
class ExtrudedProfile:
    """A scenario's rough workpiece (a profile ``z = h(x)``) extruded along y over a width.

    Uses the profile's analytic height and slope, so along ``y = 0`` it touches exactly where
    the planar plant's contact does.
    """

    surface: RoughSurface
    y_min: float = -0.25
    y_max: float = 0.25
    offset: Vec3 = (0.0, 0.0, 0.0)

    @property
    def name(self) -> str:
        """Name of the scenario object."""
        return self.surface.name

    def contact(self, c: Vec3, radius: float) -> Contact3 | None:
        """Contact of a sphere of ``radius`` centred at ``c`` (local tangent plane), or None."""
        s = self.surface
        x = c[0] - self.offset[0]
        if not (s.x_min <= x <= s.x_max and self.y_min <= c[1] - self.offset[1] <= self.y_max):
            return None
        return _tangent_plane_contact(c, radius, s.height(x) + self.offset[2], s.slope(x), 0.0)


def _tangent_plane_contact(
    c: Vec3, radius: float, h: float, dhdx: float, dhdy: float
) -> Contact3 | None:
    inv = 1.0 / math.sqrt(1.0 + dhdx * dhdx + dhdy * dhdy)
    n: Vec3 = (-dhdx * inv, -dhdy * inv, inv)
    depth = (h - c[2]) * inv + radius
    if depth <= 0.0:
        return None
    return depth, n, (c[0], c[1], h)


EnvObject3 = Plane | Box3 | HeightField | ExtrudedProfile


def objects_from_scenario(
    scenario: Scenario, offset: Vec3 = (0.0, 0.0, 0.0), half_width: float = 0.25
) -> tuple[EnvObject3, ...]:
    """Turn a scenario's planar objects (extruded along y) into 3-D objects in the robot frame.

    Tables become bounded planes, blocks become boxes ``2 * half_width`` deep in y, rough
    workpieces keep their exact profile. ``offset`` is the scenario origin in the robot frame.

    Raises
    ------
    ConfigError
        For an object type this plant does not know.
    """
    ox, oy, oz = offset
    out: list[EnvObject3] = []
    for obj in scenario.objects:
        if isinstance(obj, Table):
            out.append(
                Plane(
                    point=(ox, oy, obj.height_m + oz),
                    normal=(0.0, 0.0, 1.0),
                    x_min=obj.x_min + ox,
                    x_max=obj.x_max + ox,
                    y_min=oy - half_width,
                    y_max=oy + half_width,
                    name=obj.name,
                )
            )
        elif isinstance(obj, Box):
            out.append(
                Box3(
                    center=(obj.center_x + ox, oy, obj.center_z + oz),
                    half_size=(0.5 * obj.size_x, half_width, 0.5 * obj.size_z),
                    name=obj.name,
                )
            )
        elif isinstance(obj, RoughSurface):
            out.append(ExtrudedProfile(obj, -half_width, half_width, offset))
        else:
            raise ConfigError(
                f"scenario {scenario.name}: object {obj!r} has no 3-D counterpart "
                f"(expected Table, Box or RoughSurface)"
            )
    return tuple(out)


def translated(obj: EnvObject3, offset: Vec3) -> EnvObject3:
    """Return ``obj`` moved by ``offset`` (scenario frame -> robot frame)."""
    ox, oy, oz = offset
    if isinstance(obj, Plane):
        return dataclasses.replace(
            obj,
            point=(obj.point[0] + ox, obj.point[1] + oy, obj.point[2] + oz),
            x_min=obj.x_min + ox,
            x_max=obj.x_max + ox,
            y_min=obj.y_min + oy,
            y_max=obj.y_max + oy,
        )
    if isinstance(obj, Box3):
        c = obj.center
        return dataclasses.replace(obj, center=(c[0] + ox, c[1] + oy, c[2] + oz))
    if isinstance(obj, HeightField):
        return dataclasses.replace(obj, x0=obj.x0 + ox, y0=obj.y0 + oy, z0=obj.z0 + oz)
    o = obj.offset
    return dataclasses.replace(obj, offset=(o[0] + ox, o[1] + oy, o[2] + oz))


@dataclass(frozen=True, slots=True)
class ContactState:
    """The contact of one period: forces, wrench at the TCP, where and with what."""

    #: force the tool exerts on the environment, robot base frame (N)
    force: Vec3
    #: moment about the TCP of the force the tool exerts on the environment, base frame (N m)
    moment: Vec3
    points: tuple[Vec3, ...]
    names: tuple[str, ...]
    #: per contact, the normal part (friction excluded) of the force the tool exerts on the
    #: object, base frame (N): tells a wall from the floor the tool slides on
    normal_forces: tuple[Vec3, ...] = ()


class Contact3Solver:
    """Penalty contact of the tool sphere with 3-D objects, with Coulomb friction.

    Per touching object: normal force ``k * depth + c * rate`` (never pulling), tangential force
    from a stick spring (``tangential_stiffness``) on the accumulated tangential slip, capped at
    ``friction * normal force`` (slip). The same law as
    :class:`fuzzkit.plants.contract.ContactSolver`, in three dimensions. Stateful: one per run,
    :meth:`step` once per period.
    """

    def __init__(self, objects: Sequence[EnvObject3], model: ContactModel, radius: float) -> None:
        self.objects = tuple(objects)
        self.model = model
        self.radius = radius
        self._stick: list[Vec3] = [(0.0, 0.0, 0.0)] * len(self.objects)

    def reset(self) -> None:
        """Release every contact (forget the stick springs)."""
        self._stick = [(0.0, 0.0, 0.0)] * len(self.objects)

    def step(self, c: Vec3, v: Vec3, dt: float) -> ContactState:
        """Contact of the sphere at ``c`` moving with velocity ``v`` over a period ``dt``."""
        m = self.model
        fx = fy = fz = 0.0
        mx = my = mz = 0.0
        points: list[Vec3] = []
        names: list[str] = []
        normals: list[Vec3] = []
        for i, obj in enumerate(self.objects):
            hit = obj.contact(c, self.radius)
            if hit is None:
                self._stick[i] = (0.0, 0.0, 0.0)
                continue
            depth, (nx, ny, nz), pt = hit
            vn = v[0] * nx + v[1] * ny + v[2] * nz
            fn = m.stiffness_n_per_m * depth - m.damping_n_s_per_m * vn
            if fn <= 0.0:
                self._stick[i] = (0.0, 0.0, 0.0)
                continue
            # The old stick spring is turned into the current tangent plane keeping its length
            # (the normal turns as the tool slides over a rough profile), then this period's
            # tangential motion is added: the planar law's scalar spring, in 3-D.
            s0x, s0y, s0z = self._stick[i]
            s0n = s0x * nx + s0y * ny + s0z * nz
            px_, py_, pz_ = s0x - s0n * nx, s0y - s0n * ny, s0z - s0n * nz
            old = math.sqrt(s0x * s0x + s0y * s0y + s0z * s0z)
            proj = math.sqrt(px_ * px_ + py_ * py_ + pz_ * pz_)
            k_turn = old / proj if proj > 1e-15 else 0.0
            sx = px_ * k_turn + (v[0] - vn * nx) * dt
            sy = py_ * k_turn + (v[1] - vn * ny) * dt
            sz = pz_ * k_turn + (v[2] - vn * nz) * dt
            kt = m.tangential_stiffness_n_per_m
            ft_mag = kt * math.sqrt(sx * sx + sy * sy + sz * sz)
            cap = m.friction * fn
            if ft_mag > cap and ft_mag > 0.0:  # slipping: spring held at the Coulomb limit
                scale = cap / ft_mag
                sx, sy, sz = sx * scale, sy * scale, sz * scale
            self._stick[i] = (sx, sy, sz)
            # force of the object on the tool
            tx, ty, tz = fn * nx - kt * sx, fn * ny - kt * sy, fn * nz - kt * sz
            fx += tx
            fy += ty
            fz += tz
            # lever arm from the TCP (sphere centre) to the contact point
            rx, ry, rz = pt[0] - c[0], pt[1] - c[1], pt[2] - c[2]
            mx += ry * tz - rz * ty
            my += rz * tx - rx * tz
            mz += rx * ty - ry * tx
            points.append(pt)
            names.append(obj.name)
            normals.append((-fn * nx, -fn * ny, -fn * nz))
        # Report what the tool does to the environment (the paper's f): minus the reaction.
        return ContactState(
            force=(-fx, -fy, -fz),
            moment=(-mx, -my, -mz),
            points=tuple(points),
            names=tuple(names),
            normal_forces=tuple(normals),
        )
