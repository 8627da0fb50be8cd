"""The 6-DOF kinematic inner loop: an ABB IRB 140 following a Cartesian path plus force corrections.

This is the paper's Fig. 1 inner loop on a 6-axis arm: every controller period (4 ms by
default) the target pose is the nominal (CAD) path pose plus the correction ``S*u`` from the
force loop; inverse kinematics seeded with the previous joints (``q'_k``) turns it into joint
targets, which the joints follow through a speed limit and a first-order servo lag. The tool's
contact with a 3-D environment gives the wrench at the tool and the joint torques it induces,
``tau_e = J^T f`` (eq. 3).

Model
-----
* **Kinematic plant.** The arm has no dynamics of its own: an industrial robot in position
  control is stiff, so all compliance is in the environment (penalty contact, as in
  :mod:`fuzzkit.plants.contract`). Contact force = ``stiffness * penetration + damping *
  penetration rate`` (clamped at zero: a damper cannot pull), plus a tangential stick spring capped
  by Coulomb friction. The force does not move the arm; it is what the sensor reads.
* **Servo.** The joint reference moves towards the IK solution at most ``max_velocity * dt`` per
  period (the robot's axis speed limits, from the robot description); the actual joints follow
  the reference with a first-order lag of time constant ``servo_time_constant_s``, discretised
  exactly for a reference held over the period.
* **IK.** :meth:`fuzzkit.plants.kinematics.SerialChain.ik` (damped least squares), warm-started from
  the previous period's solution; a target moving a fraction of a millimetre per period
  converges in one or two iterations. A target that is unreachable or needs a joint past its
  limit is reported in ``PlantSample.messages`` and the arm goes to the closest pose found, never
  past a limit.

Frames
------
Scenarios (:class:`fuzzkit.plants.contract.Scenario`) live in the planar arm's x-z plane with the
shoulder at the origin. This plant places that frame in the IRB 140 base frame with a pure
translation, :attr:`Arm6Parameters.workspace_offset` (default ``(0.070, 0, 0.287)``: the IRB 140
shoulder axis is at x = 0.070, z = 0.352, and lowering by the flange length d6 = 0.065 puts the
IRB's wrist centre exactly where the planar arm's wrist is when the tool points down, so both arms
take the same posture). Every position in a :class:`PlantSample` is in the scenario frame, like the
planar plant's; the tool points down along the scenario's task z axis.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import ConfigError, SimulationError
from fuzzkit.plants.contact import ContactModel, ForceSensor
from fuzzkit.plants.contract import PlantSample, Scenario, normal_force_by_axis
from fuzzkit.plants.environment import Box, RoughSurface, Table, Waypoint
from fuzzkit.plants.kinematics import ChainEval, IKStatus, RobotDescription, SerialChain, load_robot
from fuzzkit.plants.rotations import (
    Quat,
    Vec3,
    matrix_from_quat,
    quat_from_matrix,
    quat_from_rotvec,
    quat_multiply,
    slerp,
)

FloatArray = npt.NDArray[np.float64]

# --------------------------------------------------------------------------------------------
# Nominal path: straight segments between Cartesian poses
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class PathPose:
    """A pose of the nominal path: TCP position (m) and orientation (unit quaternion w, x, y, z)."""

    t_s: float
    position: Vec3
    orientation: Quat = (1.0, 0.0, 0.0, 0.0)


class CartesianPath:
    """A path of straight segments between poses, timed: position linear, orientation by slerp.

    Before the first pose and after the last, the end pose is held. This is how an off-line
    programmed path from CAD reaches the robot: a list of poses and the time to reach each.

    Raises
    ------
    ConfigError
        If there is no pose, times decrease, or a value is not finite.
    """

    def __init__(self, poses: Sequence[PathPose]) -> None:
        if not poses:
            raise ConfigError("a Cartesian path needs at least one pose")
        for a, b in itertools.pairwise(poses):
            if b.t_s < a.t_s:
                raise ConfigError(f"path pose times must not decrease (got {a.t_s} then {b.t_s})")
        for p in poses:
            vals = (p.t_s, *p.position, *p.orientation)
            if not all(math.isfinite(v) for v in vals):
                raise ConfigError(f"path pose at t={p.t_s} has a non-finite value")
        # Normalise and make consecutive quaternions agree in sign so slerp takes the short arc.
        fixed: list[PathPose] = []
        prev: Quat | None = None
        for p in poses:
            w, x, y, z = p.orientation
            n = math.sqrt(w * w + x * x + y * y + z * z)
            if n == 0.0:
                raise ConfigError(f"path pose at t={p.t_s} has a zero quaternion")
            q: Quat = (w / n, x / n, y / n, z / n)
            if prev is not None and sum(a * b for a, b in zip(prev, q, strict=True)) < 0.0:
                q = (-q[0], -q[1], -q[2], -q[3])
            fixed.append(PathPose(p.t_s, p.position, q))
            prev = q
        self.poses: tuple[PathPose, ...] = tuple(fixed)
        self._times = [p.t_s for p in self.poses]

    @classmethod
    def from_waypoints(
        cls,
        waypoints: Sequence[Waypoint],
        rotation: Sequence[Sequence[float]] | FloatArray,
        offset: Sequence[float] = (0.0, 0.0, 0.0),
    ) -> CartesianPath:
        """Build a path from a scenario's waypoints, all with one orientation (base-from-tool).

        ``offset`` is added to every position (scenario frame -> robot base frame).
        """
        quat = quat_from_matrix(np.asarray(rotation, dtype=float).tolist())
        return cls(
            [
                PathPose(w.t_s, (w.x + offset[0], w.y + offset[1], w.z + offset[2]), quat)
                for w in waypoints
            ]
        )

    def pose_at(self, t_s: float) -> tuple[Vec3, Quat]:
        """Return the position and orientation of the path at time ``t_s``."""
        poses = self.poses
        if t_s <= poses[0].t_s:
            return poses[0].position, poses[0].orientation
        if t_s >= poses[-1].t_s:
            return poses[-1].position, poses[-1].orientation
        # few segments: a linear scan beats bisect's call overhead
        i = 1
        while self._times[i] < t_s:
            i += 1
        a, b = poses[i - 1], poses[i]
        span = b.t_s - a.t_s
        s = (t_s - a.t_s) / span if span > 0.0 else 1.0
        pa, pb = a.position, b.position
        pos: Vec3 = (
            pa[0] + s * (pb[0] - pa[0]),
            pa[1] + s * (pb[1] - pa[1]),
            pa[2] + s * (pb[2] - pa[2]),
        )
        rot = (
            a.orientation
            if a.orientation == b.orientation
            else slerp(a.orientation, b.orientation, s)
        )
        return pos, rot


# --------------------------------------------------------------------------------------------
# 3-D contact environment
# --------------------------------------------------------------------------------------------

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


# --------------------------------------------------------------------------------------------
# The plant
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Arm6Parameters:
    """Settings of the 6-DOF kinematic plant (SI units).

    Parameters
    ----------
    robot:
        The robot description; None loads the shipped ABB IRB 140.
    workspace_offset:
        Scenario origin in the robot base frame (see the module docstring).
    servo_time_constant_s:
        First-order lag of each joint behind its reference (0 = ideal tracking).
    ik_iterations:
        IK iteration budget per period (warm-started, so one or two are used when tracking).
    ik_position_tolerance, ik_orientation_tolerance:
        IK convergence thresholds (m, rad).
    object_half_width:
        Half extent along y of the 3-D objects built from a planar scenario (m).
    strict:
        Raise :class:`fuzzkit.errors.SimulationError` on an unreachable target instead of
        reporting it and going to the closest pose.
    extra_objects:
        3-D objects added to every scenario's environment, in the scenario frame: what a
        planar scenario cannot describe (a height field rough in x and y, a block off the
        working plane).
    """

    robot: RobotDescription | None = None
    workspace_offset: Vec3 = (0.070, 0.0, 0.287)
    servo_time_constant_s: float = 0.008
    ik_iterations: int = 4
    ik_position_tolerance: float = 1e-7
    ik_orientation_tolerance: float = 1e-7
    object_half_width: float = 0.25
    strict: bool = False
    extra_objects: tuple[EnvObject3, ...] = ()


class Arm6Detail:
    """The 6-DOF extras of one period, computed only when asked for (most runs never ask).

    Holds the period's kinematic pass and contact state; :class:`Arm6Sample` exposes the
    results as properties.
    """

    __slots__ = (
        "_ev",
        "_jac",
        "_joint_reference",
        "_state",
        "_tool_length",
        "_wrench",
        "ik_status",
    )

    def __init__(
        self,
        ev: ChainEval,
        state: ContactState,
        tool_length: float,
        joint_reference: Sequence[float],
        ik_status: str,
        jacobian_of: Callable[[ChainEval], FloatArray],
    ) -> None:
        self._ev = ev
        self._state = state
        self._tool_length = tool_length
        self._joint_reference = tuple(joint_reference)
        self.ik_status = ik_status
        self._jac = jacobian_of
        self._wrench: tuple[FloatArray, FloatArray, FloatArray] | None = None

    def wrench(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``(wrench at the TCP in the base frame, wrench at the sensor in its frame, J^T f)``."""
        if self._wrench is None:
            self._wrench = _wrench(self._ev, self._state, self._tool_length, self._jac)
        return self._wrench

    @property
    def joint_reference(self) -> FloatArray:
        """Joint targets after the speed limit (rad)."""
        return np.array(self._joint_reference)

    @property
    def tcp_rotation(self) -> FloatArray:
        """Actual TCP orientation, base-from-tool rotation (3, 3)."""
        return np.array(self._ev[0])


@dataclass(frozen=True, slots=True)
class Arm6Sample(PlantSample):
    """A :class:`fuzzkit.plants.contract.PlantSample` with the 6-DOF plant's extra signals.

    Properties (computed on first use)
    ----------------------------------
    wrench_base : ``[f; m]`` the tool exerts on the environment at the TCP, base frame.
    wrench_sensor : the same wrench about the F/T sensor origin (the flange), sensor frame.
    joint_torques : ``tau_e = J(q)^T wrench_base`` (N m), eq. 3 of the paper.
    joint_reference : joint targets after the speed limit (rad).
    ik_status : status of this period's IK solve.
    tcp_rotation : actual TCP orientation, base-from-tool rotation (3, 3).
    """

    detail: Arm6Detail | None = None

    def _d(self) -> Arm6Detail:
        if self.detail is None:
            raise ValueError("this sample carries no 6-DOF detail")
        return self.detail

    @property
    def wrench_base(self) -> FloatArray:
        """``[f; m]`` the tool exerts on the environment at the TCP, base frame (N, N m)."""
        return self._d().wrench()[0]

    @property
    def wrench_sensor(self) -> FloatArray:
        """The wrench about the sensor origin (flange), in the sensor frame (N, N m)."""
        return self._d().wrench()[1]

    @property
    def joint_torques(self) -> FloatArray:
        """``tau_e = J(q)^T wrench_base`` (N m), eq. 3 of the paper."""
        return self._d().wrench()[2]

    @property
    def joint_reference(self) -> FloatArray:
        """Joint targets after the speed limit (rad)."""
        return self._d().joint_reference

    @property
    def ik_status(self) -> str:
        """Status of this period's IK solve (an :class:`~fuzzkit.plants.kinematics.IKStatus`
        value)."""
        return self._d().ik_status

    @property
    def tcp_rotation(self) -> FloatArray:
        """Actual TCP orientation, base-from-tool rotation (3, 3)."""
        return self._d().tcp_rotation


def _wrench(
    ev: ChainEval,
    state: ContactState,
    length: float,
    jacobian_of: Callable[[ChainEval], FloatArray],
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Wrench at the TCP (base), about the flange (sensor frame), and ``J^T f``.

    The tool offset is a pure translation along flange z, so TCP and flange share axes and the
    lever from flange to TCP is ``length * z_tcp``: ``m_s = m_tcp + (p_tcp - p_flange) x f``.
    """
    (fx, fy, fz), (mx, my, mz) = state.force, state.moment
    rot = ev[0]
    lx, ly, lz = rot[0][2] * length, rot[1][2] * length, rot[2][2] * length
    mfx, mfy, mfz = mx + ly * fz - lz * fy, my + lz * fx - lx * fz, mz + lx * fy - ly * fx
    w_sensor = np.array(
        [
            rot[0][0] * fx + rot[1][0] * fy + rot[2][0] * fz,
            rot[0][1] * fx + rot[1][1] * fy + rot[2][1] * fz,
            rot[0][2] * fx + rot[1][2] * fy + rot[2][2] * fz,
            rot[0][0] * mfx + rot[1][0] * mfy + rot[2][0] * mfz,
            rot[0][1] * mfx + rot[1][1] * mfy + rot[2][1] * mfz,
            rot[0][2] * mfx + rot[1][2] * mfy + rot[2][2] * mfz,
        ]
    )
    w_base = np.array([fx, fy, fz, mx, my, mz])
    if state.points:
        tau: FloatArray = jacobian_of(ev).T @ w_base
    else:  # no contact, no torque: skip the Jacobian
        tau = np.zeros(len(ev[2]))
    return w_base, w_sensor, tau


#: IK seeds tried, in order, for the first pose of a path: elbow up, wrist flipped down.
_START_SEEDS = (
    (0.0, 0.3, 0.3, 0.0, 0.9, math.pi),
    (0.0, 0.0, 0.0, 0.0, 1.5, math.pi),
    (0.0, 0.6, -0.2, 0.0, 1.2, math.pi),
    (0.0, 0.3, 0.3, 0.0, 0.9, 0.0),
)


class Arm6Plant:
    """The ABB IRB 140 kinematic plant as a :class:`fuzzkit.plants.contract.ContactPlant` (name
    ``arm6``).

    Examples
    --------
    >>> plant = Arm6Plant()
    >>> sample = plant.reset(scenario, seed=1)                     # doctest: +SKIP
    >>> sample = plant.step(np.zeros(3), path_time_s=0.004)        # doctest: +SKIP
    """

    name = "arm6"

    def __init__(self, params: Arm6Parameters | None = None) -> None:
        self.params = params or Arm6Parameters()
        robot = self.params.robot or load_robot("irb140")
        self._robot_base = robot
        self.chain = SerialChain(robot)
        self._scenario: Scenario | None = None

    @property
    def period_s(self) -> float:
        """Controller period of the current scenario (seconds)."""
        if self._scenario is None:
            raise RuntimeError("Arm6Plant.reset(scenario) must be called first")
        return self._scenario.period_s

    @property
    def scenario(self) -> Scenario:
        """The scenario of the current run."""
        if self._scenario is None:
            raise RuntimeError("Arm6Plant.reset(scenario) must be called first")
        return self._scenario

    # -- world building -------------------------------------------------------------------------

    def reset(self, scenario: Scenario, seed: int = 0) -> Arm6Sample:
        """Put the arm at the start of ``scenario``'s path, at rest; return the first sample.

        Raises
        ------
        SimulationError
            If the path's first pose cannot be reached within the joint limits.
        """
        p = self.params
        self._scenario = scenario
        # The TCP is the tool tip (the contact sphere's centre), along the flange z axis.
        self.chain = SerialChain(self._robot_base.with_tool((0.0, 0.0, scenario.tool.length_m)))
        off = p.workspace_offset
        self._offset = off
        self._offset_arr = np.array(off, dtype=float)
        self._rot_task = scenario.rotation
        self._rot_task_t = [list(r) for r in scenario.rotation.T]
        self.path = CartesianPath.from_waypoints(scenario.path, scenario.rotation, off)
        self.objects = objects_from_scenario(scenario, off, p.object_half_width) + tuple(
            translated(obj, off) for obj in p.extra_objects
        )
        self._contact = Contact3Solver(self.objects, scenario.contact, scenario.tool.radius_m)
        self._sensor = ForceSensor(scenario.sensor, seed)
        self._dt = scenario.period_s
        tau = p.servo_time_constant_s
        self._lag = 1.0 - math.exp(-self._dt / tau) if tau > 0.0 else 1.0
        self._dq_max = [v * self._dt for v in self.chain.max_velocity]
        self._t = 0.0

        pos, quat = self.path.pose_at(0.0)
        target = _pose_matrix(pos, quat)
        best = None
        for seed_q in _START_SEEDS:
            res = self.chain.ik(target, seed_q, max_iterations=200)
            if res.converged:
                best = res
                break
        if best is None:
            res = self.chain.ik_restarts(target, _START_SEEDS[0], max_iterations=200)
            best = res if res.converged else None
        if best is None:
            raise SimulationError(
                f"scenario {scenario.name}: path start {list(pos)} (robot frame) is out of "
                f"reach of {self._robot_base.name} with the tool pointing down"
            )
        q0 = [float(v) for v in best.q]
        self._q = list(q0)
        self._q_ref = list(q0)
        self._q_ik = list(q0)
        self._ik_status = IKStatus.CONVERGED
        self._tool_length = scenario.tool.length_m
        self._p_prev = self.chain.evaluate(q0)[1]
        self._state = self._contact.step(self._p_prev, (0.0, 0.0, 0.0), self._dt)
        self._contact.reset()
        self._true_task = np.zeros(3)
        nominal = self._to_scenario(pos)
        return self._sample(nominal, nominal, ())

    # -- stepping -------------------------------------------------------------------------------

    def step(
        self,
        correction_xyz: FloatArray | Sequence[float],
        path_time_s: float,
        correction_rotation: FloatArray | Sequence[float] | None = None,
    ) -> Arm6Sample:
        """Advance one period towards ``nominal(path_time_s) + correction``.

        Parameters
        ----------
        correction_xyz:
            Translation correction ``S*u`` (m, base frame), added to the nominal position.
        path_time_s:
            Time along the nominal path (the runner may hold it).
        correction_rotation:
            Optional rotation correction, a rotation vector (rad, base frame) applied on top of
            the nominal orientation.

        Raises
        ------
        SimulationError
            With ``strict=True``, when the target is unreachable.
        ValueError
            If a correction is not 3 finite numbers.
        """
        if self._scenario is None:
            raise RuntimeError("Arm6Plant.reset(scenario) must be called first")
        cx, cy, cz = _vec3(correction_xyz, "correction_xyz")
        pos, quat = self.path.pose_at(path_time_s)
        if correction_rotation is not None:
            quat = quat_multiply(quat_from_rotvec(_vec3(correction_rotation, "rotation")), quat)
        target_pos = (pos[0] + cx, pos[1] + cy, pos[2] + cz)
        messages: list[str] = []
        chain = self.chain
        p = self.params

        res = chain.ik_fast(
            matrix_from_quat(quat),
            target_pos,
            self._q_ik,
            position_tolerance=p.ik_position_tolerance,
            orientation_tolerance=p.ik_orientation_tolerance,
            max_iterations=p.ik_iterations,
        )
        self._ik_status = res.status
        if res.status is not IKStatus.CONVERGED:
            where = ", ".join(chain.robot.joints[i].name for i in res.at_limit)
            msg = {
                IKStatus.UNREACHABLE: "target unreachable: going to the closest pose",
                IKStatus.LIMIT: f"target needs motion past a joint limit ({where})",
                IKStatus.MAX_ITERATIONS: "IK not converged this period",
            }[res.status]
            messages.append(
                f"{msg} (position error {res.position_error * 1e3:.3f} mm, "
                f"orientation error {math.degrees(res.orientation_error):.3f} deg)"
            )
            if p.strict and res.status in (IKStatus.UNREACHABLE, IKStatus.LIMIT):
                raise SimulationError(f"t={self._t + self._dt:.3f} s: {messages[-1]}")
        q_ik = res.q.tolist()
        self._q_ik = q_ik

        # Joint reference: towards the IK solution, the whole step scaled down together when
        # any axis would exceed its speed limit, so the reference keeps its direction (a robot
        # controller slows the path down rather than bending it).
        q_ref, q, lag = self._q_ref, self._q, self._lag
        dq_max = self._dq_max
        d = [q_ik[i] - q_ref[i] for i in range(len(q_ref))]
        scale = 1.0
        limited: list[str] = []
        for i, lim in enumerate(dq_max):
            if abs(d[i]) > lim:
                scale = min(scale, lim / abs(d[i]))
                limited.append(chain.robot.joints[i].name)
        for i in range(len(q_ref)):
            q_ref[i] += d[i] * scale
            q[i] += lag * (q_ref[i] - q[i])
        if limited:
            messages.append(f"joint speed limit on {', '.join(limited)}")
        self._t += self._dt

        # Contact at the actual TCP, velocity by finite difference over the period.
        tcp = chain.evaluate(q)[1]
        pp = self._p_prev
        v = ((tcp[0] - pp[0]) / self._dt, (tcp[1] - pp[1]) / self._dt, (tcp[2] - pp[2]) / self._dt)
        self._p_prev = tcp
        self._state = self._contact.step(tcp, v, self._dt)
        f = self._state.force
        rt = self._rot_task_t
        true_task = np.array(
            [
                rt[0][0] * f[0] + rt[0][1] * f[1] + rt[0][2] * f[2],
                rt[1][0] * f[0] + rt[1][1] * f[1] + rt[1][2] * f[2],
                rt[2][0] * f[0] + rt[2][1] * f[1] + rt[2][2] * f[2],
            ]
        )
        self._sensor.update(self._t, self._dt, true_task)
        self._true_task = true_task
        return self._sample(self._to_scenario(pos), self._to_scenario(target_pos), tuple(messages))

    # -- reporting ------------------------------------------------------------------------------

    def _to_scenario(self, p: Sequence[float]) -> FloatArray:
        o = self._offset
        return np.array([p[0] - o[0], p[1] - o[1], p[2] - o[2]])

    def wrench(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Current wrench at the TCP (base frame), at the sensor (sensor frame), and ``J^T f``.

        The sensor frame is the flange frame (the F/T sensor sits between wrist and tool); its
        moment is taken about the flange origin: ``m_s = m_tcp + (p_tcp - p_flange) x f``.
        """
        return _wrench(
            self.chain.evaluate(self._q), self._state, self._tool_length, self.chain.jacobian_of
        )

    def _sample(
        self, nominal: FloatArray, target: FloatArray, messages: tuple[str, ...]
    ) -> Arm6Sample:
        q = self._q
        ev = self.chain.evaluate(q)
        ox, oy, oz = self._offset
        arm = self.chain.frames_of(ev)
        arm -= self._offset_arr
        state = self._state
        pts = np.array(state.points, dtype=float) - self._offset_arr if state.points else _NO_POINTS
        p = ev[1]
        return Arm6Sample(
            t_s=self._t,
            force=self._sensor.read(),
            force_true=self._true_task.copy(),
            tool_position=np.array([p[0] - ox, p[1] - oy, p[2] - oz]),
            nominal_position=nominal,
            target_position=target,
            joint_angles=np.array(q),
            in_contact=bool(state.points),
            contact_points=pts,
            arm_points=arm,
            messages=messages,
            force_normal=normal_force_by_axis(state.normal_forces, self._rot_task),
            detail=Arm6Detail(
                ev,
                state,
                self._tool_length,
                self._q_ref,
                self._ik_status.value,
                self.chain.jacobian_of,
            ),
        )


_NO_POINTS = np.zeros((0, 3))
_NO_POINTS.flags.writeable = False


def _pose_matrix(pos: Sequence[float], quat: Sequence[float]) -> FloatArray:
    t = np.eye(4)
    t[:3, :3] = matrix_from_quat(quat)
    t[:3, 3] = pos
    return t


def _vec3(v: FloatArray | Sequence[float], what: str) -> Vec3:
    a = np.asarray(v, dtype=float).reshape(-1)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{what} must be 3 finite numbers (got {np.asarray(v).tolist()!r})")
    return (float(a[0]), float(a[1]), float(a[2]))
