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

Twins: this is the **reference** copy of the 6-DOF plant step; the compiled loop's
copy (:mod:`fuzzkit.plants.arm6_period`) is tested against it (``tests/test_compiled_loop.py``),
so it is kept as a separate implementation on purpose.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import ConfigError, SimulationError
from fuzzkit.plants.contact import ForceSensor, tool_weight
from fuzzkit.plants.contract import PlantSample, Scenario, normal_force_by_axis
from fuzzkit.plants.environment import Waypoint
from fuzzkit.plants.environment3d import (
    Contact3Solver,
    ContactState,
    EnvObject3,
    objects_from_scenario,
    translated,
)
from fuzzkit.plants.kinematics import ChainEval, IKStatus, SerialChain
from fuzzkit.plants.robot_description import RobotDescription, load_robot
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
        """Build a path from a scenario's waypoints with the orientation ``rotation``
        (base-from-tool), turned by each waypoint's ``tilt_rad`` about the base y axis.

        ``offset`` is added to every position (scenario frame -> robot base frame).
        """
        base = np.asarray(rotation, dtype=float)
        quat = quat_from_matrix(base.tolist())

        def orientation(tilt: float) -> Quat:
            if tilt == 0.0:
                return quat
            c, s = math.cos(tilt), math.sin(tilt)
            turn = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
            return quat_from_matrix((turn @ base).tolist())

        return cls(
            [
                PathPose(
                    w.t_s,
                    (w.x + offset[0], w.y + offset[1], w.z + offset[2]),
                    orientation(w.tilt_rad),
                )
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
        # A tilting tool turns the wrist sensor with it: its readings (and the true force
        # reported beside them) are then in the sensor frame, reported as tool_rotation.
        self._tilts = any(w.tilt_rad != 0.0 for w in scenario.path)
        self._rot_sensor = (
            np.asarray(matrix_from_quat(self.path.pose_at(0.0)[1])) if self._tilts else None
        )
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
        self._sensor.settle(self._with_weight(self._true_task))
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
        pos, quat, target_pos, messages = self._reference_step(
            correction_xyz, path_time_s, correction_rotation
        )
        q, q_ref, lag = self._q, self._q_ref, self._lag
        for i in range(len(q)):
            q[i] += lag * (q_ref[i] - q[i])
        self._t += self._dt

        # Contact at the actual TCP, velocity by finite difference over the period.
        tcp = self.chain.evaluate(q)[1]
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
        if self._tilts:
            self._rot_sensor = np.asarray(matrix_from_quat(quat))
            true_task = self._rot_sensor.T @ np.asarray(f, dtype=float)
        self._sensor.update(self._t, self._dt, self._with_weight(true_task))
        self._true_task = true_task
        return self._sample(self._to_scenario(pos), self._to_scenario(target_pos), tuple(messages))

    def _reference_step(
        self,
        correction_xyz: FloatArray | Sequence[float],
        path_time_s: float,
        correction_rotation: FloatArray | Sequence[float] | None,
    ) -> tuple[Vec3, Quat, Vec3, list[str]]:
        """The inner loop's reference for one period: the path pose plus the correction, through
        IK and the joint speed limit into ``self._q_ref``; returns ``(path position, path
        orientation, target position, messages)``. Shared with :mod:`fuzzkit.plants.mujoco_arm`,
        whose servos follow the same reference."""
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
        q_ref = self._q_ref
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
        if limited:
            messages.append(f"joint speed limit on {', '.join(limited)}")
        return pos, quat, target_pos, messages

    def _with_weight(self, force: FloatArray) -> FloatArray:
        """The sensor's input: the contact force plus the tool's weight (if it has a mass)."""
        mass = self.scenario.tool.mass_kg
        if mass == 0.0:
            return force
        return force + tool_weight(mass, self._sensor_rotation())

    def _sensor_rotation(self) -> FloatArray:
        """Base-from-sensor rotation: the task frame's, or the tilting tool's of this period."""
        return self._rot_task if self._rot_sensor is None else self._rot_sensor

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
            force_normal=normal_force_by_axis(state.normal_forces, self._sensor_rotation()),
            tool_rotation=None if self._rot_sensor is None else self._rot_sensor.copy(),
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
