"""The MJCF model of the ABB IRB 140 and its scene, written from the robot description.

:func:`arm_mjcf` turns :class:`~fuzzkit.plants.robot_description.RobotDescription` (the same
DH description the kinematic plant ``arm6`` uses, ``fuzzkit/data/irb140.yaml``) and
:class:`ArmDynamics` into an MJCF document for MuJoCo, with the scenario's objects (table,
blocks, a rough profile as a block kept on its tangent plane under the tool) in it. The plant
that runs it:
:mod:`fuzzkit.plants.mujoco_arm`; what every number is and where it comes from: docs/mujoco.md.

Body chain (standard DH, ``A_i = Rz(q_i + offset_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``): body ``i``
sits at frame ``i-1`` turned by ``Rz(offset_i)`` and turns about its z axis (the joint); its
child sits at ``(a_i, 0, d_i)`` turned by ``Rx(alpha_i)``. After joint 6 the tool body (the
flange, where the F/T sensor site is) carries the probe: a sphere at ``length_m`` along the
flange z axis. With ``elastic=True`` each joint is two hinges on the same axis: the motor's
(actuated, with the rotor inertia, gear damping and friction) and the link's (a spring-damper:
the gearbox and shaft compliance).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from fuzzkit.errors import ConfigError
from fuzzkit.plants.environment import Box, RoughSurface, Table
from fuzzkit.plants.environment import EnvObject as PlanarObject
from fuzzkit.plants.mujoco_servo import userdata_size
from fuzzkit.plants.robot_description import RobotDescription
from fuzzkit.plants.rotations import Quat, quat_multiply

#: Physics time step (s): 1 kHz, four steps per 4 ms controller period.
PHYSICS_DT_S = 0.001


@dataclass(frozen=True, slots=True)
class ArmDynamics:
    """The IRB 140's dynamic parameters, per joint (axis 1 to 6) unless said otherwise.

    Sources (docs/mujoco.md has the table): the total mass (98 kg) is ABB's product
    specification; ABB publishes no per-link masses, inertias, rotor inertias, gear friction,
    torque limits or joint stiffnesses, so those are **estimates** from the link geometry and
    from robots of the same class; the servo bandwidth and damping ratio are **chosen** as an
    industrial position loop's.

    Attributes
    ----------
    link_mass_kg : moving links 1-6 (the fixed foot, ``base_mass_kg``, completes the 98 kg).
    link_radius_m : radius of each link's capsule (its inertia follows from it and the mass).
    armature_kg_m2 : the motor rotor's inertia seen at the joint (rotor inertia x gear ratio^2).
    damping_n_m_s : viscous gear friction (N m s/rad).
    frictionloss_n_m : Coulomb gear friction (N m).
    torque_limit_n_m : the largest torque each servo can give (N m, joint side).
    bandwidth_hz, damping_ratio : the position loop's natural frequency and damping; the gains
        are ``kp = M_ii w^2``, ``kv = 2 zeta w M_ii`` with ``M_ii`` the joint's inertia (links and
        rotor) at :data:`GAIN_POSE`.
    elastic : a spring-damper between each motor and its link, on the joints whose
        ``joint_stiffness_n_m_rad`` is not 0 (by default axes 1-3: the wrist's links are so
        light that a realistic wrist spring would ring above 1 kHz, beyond the physics rate).
    joint_stiffness_n_m_rad, joint_damping_n_m_s : that spring-damper.
    """

    link_mass_kg: tuple[float, ...] = (25.0, 16.0, 11.0, 6.0, 1.6, 0.4)
    base_mass_kg: float = 38.0
    link_radius_m: tuple[float, ...] = (0.12, 0.07, 0.08, 0.05, 0.045, 0.035)
    armature_kg_m2: tuple[float, ...] = (1.5, 1.5, 0.6, 0.08, 0.08, 0.03)
    damping_n_m_s: tuple[float, ...] = (8.0, 8.0, 4.0, 0.8, 0.8, 0.3)
    frictionloss_n_m: tuple[float, ...] = (6.0, 6.0, 3.0, 0.6, 0.6, 0.3)
    torque_limit_n_m: tuple[float, ...] = (350.0, 350.0, 180.0, 40.0, 40.0, 25.0)
    bandwidth_hz: float = 15.0
    damping_ratio: float = 1.0
    elastic: bool = False
    joint_stiffness_n_m_rad: tuple[float, ...] = (1.2e5, 1.2e5, 6.0e4, 0.0, 0.0, 0.0)
    joint_damping_n_m_s: tuple[float, ...] = (60.0, 60.0, 30.0, 0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        positive = (
            "link_mass_kg",
            "link_radius_m",
            "armature_kg_m2",
            "damping_n_m_s",
            "frictionloss_n_m",
            "torque_limit_n_m",
        )
        springs = ("joint_stiffness_n_m_rad", "joint_damping_n_m_s")
        problems = [
            f"{n} needs 6 values" for n in (*positive, *springs) if len(getattr(self, n)) != 6
        ]
        problems += [
            f"{n} must be > 0"
            for n in (*positive, "bandwidth_hz", "damping_ratio")
            if not all(v > 0.0 and math.isfinite(v) for v in _values(getattr(self, n)))
        ]
        problems += [
            f"{n} must be >= 0"
            for n in springs
            if not all(v >= 0.0 and math.isfinite(v) for v in getattr(self, n))
        ]
        if problems:
            raise ConfigError("arm dynamics: " + "; ".join(problems))

    def is_elastic(self, joint: int) -> bool:
        """Whether joint ``joint`` (0-based) has a spring between its motor and its link."""
        return self.elastic and self.joint_stiffness_n_m_rad[joint] > 0.0


def _values(v: float | Sequence[float]) -> Sequence[float]:
    return v if isinstance(v, Sequence) else (v,)


#: Joint angles (rad) at which the servo gains are set from the joint inertias: the posture the
#: shipped scenarios work in (elbow up, wrist down), fixed so that gains never depend on a run.
GAIN_POSE = (0.0, 0.3, 0.3, 0.0, 0.9, math.pi)


def _q_z(angle: float) -> Quat:
    return (math.cos(angle / 2.0), 0.0, 0.0, math.sin(angle / 2.0))


def _q_x(angle: float) -> Quat:
    return (math.cos(angle / 2.0), math.sin(angle / 2.0), 0.0, 0.0)


def _f(v: float) -> str:
    return repr(float(v))


def _vec(*v: float) -> str:
    return " ".join(_f(x) for x in v)


def _link_geom(i: int, a: float, d: float, dyn: ArmDynamics) -> str:
    r, m = dyn.link_radius_m[i], dyn.link_mass_kg[i]
    if math.hypot(a, d) < 1e-9:
        return (
            f'<geom name="link{i + 1}" type="sphere" size="{_f(r)}" mass="{_f(m)}" class="link"/>'
        )
    return (
        f'<geom name="link{i + 1}" type="capsule" fromto="0 0 0 {_vec(a, 0.0, d)}" '
        f'size="{_f(r)}" mass="{_f(m)}" class="link"/>'
    )


def arm_mjcf(
    robot: RobotDescription,
    dyn: ArmDynamics,
    tool_length_m: float,
    tool_radius_m: float,
    tool_mass_kg: float,
    scene: str,
) -> str:
    """The MJCF document: the arm of ``robot`` with ``dyn``, the probe tool, and ``scene``
    (geoms from :func:`scene_geoms`) in the world body."""
    joints = robot.joints
    if len(joints) != 6:
        raise ConfigError(f"the MuJoCo arm needs a 6-joint robot ({robot.name} has {len(joints)})")
    body_open: list[str] = []
    body_close: list[str] = []
    pos = (0.0, 0.0, 0.0)
    turn: Quat = (1.0, 0.0, 0.0, 0.0)
    for i, j in enumerate(joints):
        quat = quat_multiply(turn, _q_z(j.offset))
        lo, hi = j.lower, j.upper
        hinge = (
            f'damping="{_f(dyn.damping_n_m_s[i])}" frictionloss="{_f(dyn.frictionloss_n_m[i])}" '
            f'armature="{_f(dyn.armature_kg_m2[i])}" range="{_vec(lo, hi)}"'
        )
        head = f'<body name="body{i + 1}" pos="{_vec(*pos)}" quat="{_vec(*quat)}" gravcomp="1">'
        if dyn.is_elastic(i):
            body_open.append(
                f'<body name="motor{i + 1}" pos="{_vec(*pos)}" quat="{_vec(*quat)}" gravcomp="1">'
                f'<inertial pos="0 0 0" mass="0.001" diaginertia="1e-6 1e-6 1e-6"/>'
                f'<joint name="motor{i + 1}" {hinge}/>'
                f'<body name="body{i + 1}" gravcomp="1">'
                f'<joint name="{j.name}" stiffness="{_f(dyn.joint_stiffness_n_m_rad[i])}" '
                f'damping="{_f(dyn.joint_damping_n_m_s[i])}"/>'
            )
            body_close.append("</body></body>")
        else:
            body_open.append(head + f'<joint name="{j.name}" {hinge}/>')
            body_close.append("</body>")
        body_open.append(_link_geom(i, j.a, j.d, dyn))
        pos = (j.a, 0.0, j.d)
        turn = _q_x(j.alpha)
    tool = (
        f'<body name="tool" pos="{_vec(*pos)}" quat="{_vec(*turn)}" gravcomp="1">'
        f'<site name="flange" size="0.01"/>'
        f'<geom name="shaft" type="capsule" fromto="0 0 0 0 0 {_f(tool_length_m - tool_radius_m)}" '
        f'size="{_f(0.4 * tool_radius_m)}" mass="0" class="link"/>'
        f'<geom name="tip" type="sphere" pos="0 0 {_f(tool_length_m)}" size="{_f(tool_radius_m)}" '
        f'mass="{_f(tool_mass_kg)}" contype="1" conaffinity="0" condim="3"/>'
        f"</body>"
    )
    actuated = [f"motor{i + 1}" if dyn.is_elastic(i) else j.name for i, j in enumerate(joints)]
    actuators = "".join(
        f'<general name="servo{i + 1}" joint="{name}" gaintype="fixed" biastype="affine" '
        f'forcelimited="true" forcerange="{_vec(-tau, tau)}"/>'
        for i, (name, tau) in enumerate(zip(actuated, dyn.torque_limit_n_m, strict=True))
    )
    return (
        f'<mujoco model="{robot.name}">'
        f'<compiler angle="radian" autolimits="true"/>'
        # the servo callback's per-simulation state (fuzzkit.plants.mujoco_servo)
        f'<size nuserdata="{userdata_size(len(joints))}"/>'
        f'<option timestep="{_f(PHYSICS_DT_S)}" integrator="implicitfast" cone="elliptic" '
        f'gravity="0 0 -9.80665"/>'
        f'<default><default class="link"><geom contype="0" conaffinity="0"/></default></default>'
        f"<worldbody>"
        f'<geom name="foot" type="cylinder" pos="0 0 0.1" size="0.15 0.1" '
        f'mass="{_f(dyn.base_mass_kg)}" class="link"/>'
        f"{scene}"
        f"{''.join(body_open)}{tool}{''.join(reversed(body_close))}"
        f"</worldbody>"
        f"<actuator>{actuators}</actuator>"
        f'<sensor><force name="wrist" site="flange"/></sensor>'
        f"</mujoco>"
    )


#: Half length (x) and half thickness of the block that stands for a rough profile under the
#: tool (m): longer than the probe is wide, thin enough to stay under the profile's wiggles.
PROFILE_HALF_LENGTH_M = 0.03
PROFILE_HALF_THICKNESS_M = 0.01


def profile_pose(
    surface: RoughSurface, x: float, offset: Sequence[float]
) -> tuple[tuple[float, float, float], Quat]:
    """Where the block standing for ``surface`` goes when the tool is at ``x`` (scenario
    frame): its top face on the profile's tangent plane at ``x`` (robot frame position of the
    block's centre, and its orientation), or far below the scene off the profile's ends."""
    if not surface.x_min <= x <= surface.x_max:
        return (0.0, 0.0, -10.0), (1.0, 0.0, 0.0, 0.0)
    h, slope = surface.height(x), surface.slope(x)
    phi = -math.atan(slope)  # turns the block's z axis onto the normal (-slope, 0, 1)
    nx, nz = math.sin(phi), math.cos(phi)
    t = PROFILE_HALF_THICKNESS_M
    return (
        (x - nx * t + offset[0], offset[1], h - nz * t + offset[2]),
        (math.cos(0.5 * phi), 0.0, math.sin(0.5 * phi), 0.0),
    )


def scene_geoms(
    objects: Sequence[PlanarObject],
    offset: Sequence[float],
    half_width: float,
) -> str:
    """The scenario's objects as MuJoCo geoms in the robot frame (``offset``: the scenario
    origin there); a table is a slab, a block a box, a rough workpiece a
    block that :func:`profile_pose` keeps on the profile under the tool.

    Raises
    ------
    ConfigError
        For an object this plant cannot build.
    """
    ox, oy, oz = offset
    geoms: list[str] = []
    for k, obj in enumerate(objects):
        cls = f'contype="0" conaffinity="1" name="obj{k}_{_xml_name(obj.name)}"'
        if isinstance(obj, Table):
            x_lo, x_hi = max(obj.x_min, -1.5), min(obj.x_max, 1.5)
            thick = 0.05
            geoms.append(
                f'<geom {cls} type="box" size="{_vec(0.5 * (x_hi - x_lo), half_width, thick)}" '
                f'pos="{_vec(0.5 * (x_lo + x_hi) + ox, oy, obj.height_m - thick + oz)}"/>'
            )
        elif isinstance(obj, Box):
            geoms.append(
                f'<geom {cls} type="box" '
                f'size="{_vec(0.5 * obj.size_x, half_width, 0.5 * obj.size_z)}" '
                f'pos="{_vec(obj.center_x + ox, oy, obj.center_z + oz)}"/>'
            )
        elif isinstance(obj, RoughSurface):
            # A MuJoCo height field touches a sphere at every prism under it (up to 50
            # contacts, each with the full stiffness), so the profile is a block that a mocap
            # body keeps on the profile's tangent plane under the tool (:func:`profile_pose`):
            # one contact, as arm6's local tangent plane.
            geoms.append(
                f'<body name="profile{k}" mocap="true" pos="0 0 -10">'
                f'<geom {cls} type="box" '
                f'size="{_vec(PROFILE_HALF_LENGTH_M, half_width, PROFILE_HALF_THICKNESS_M)}"/>'
                f"</body>"
            )
        else:
            raise ConfigError(
                f"the mujoco plant cannot build object {obj!r} "
                "(expected Table, Box or RoughSurface)"
            )
    return "".join(geoms)


def _xml_name(name: str) -> str:
    return "".join(c if c.isalnum() else "_" for c in name)
