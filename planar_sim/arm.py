"""The pymunk two-link arm with joint position servos, a vertical tool and a wrist F/T sensor.

Model
-----
* Two links (``link1_m``, ``link2_m``) on revolute joints at the base and elbow; a tool body hangs
  from the wrist on a third pivot, and a gear joint to the ground keeps it vertical (the
  parallelogram wrist of a palletising arm), so the task frame does not rotate.
* Each joint is a position servo: a proportional position loop (``servo_gain_per_s``) commands a
  joint rate, which a pymunk ``SimpleMotor`` enforces up to ``torque_limit_nm``. Like an industrial
  robot in position control the arm is therefore stiff until a torque limit is reached; all contact
  compliance is in the environment (``fuzzkit.plants.contract.ContactModel``).
* The inner motion loop: target tip = nominal path + correction -> wrist = tip + tool length ->
  analytic two-link IK (elbow up) -> joint targets, recomputed every controller period.
* Contact forces come from ``fuzzkit.plants.contract.ContactSolver`` (penalty spring-damper with
  Coulomb friction), applied to the tool every physics substep; the F/T sensor between wrist and
  tool reads them through ``fuzzkit.plants.contract.ForceSensor`` (tool weight compensated, like a
  calibrated sensor).

Everything is fixed-step: ``substeps`` physics steps per controller period.

Twins: this plant is the **reference** for its compiled copy
(:mod:`fuzzkit.planar_sim.arm_period`, tested against it in ``tests/test_compiled_loop.py``), so
the step's math is kept as a separate implementation on purpose.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pymunk

from fuzzkit.errors import ConfigError, SimulationError
from fuzzkit.plants.contact import ContactSolver, ForceSensor, tool_weight
from fuzzkit.plants.contract import PlantSample, Scenario, normal_force_by_axis
from fuzzkit.plants.environment import nominal_position

Vec = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class ArmParameters:
    """Geometry, masses and servo settings of the planar arm (SI units)."""

    link1_m: float = 0.36
    link2_m: float = 0.38
    mass1_kg: float = 8.0
    mass2_kg: float = 5.0
    tool_mass_kg: float = 1.0
    servo_gain_per_s: float = 60.0
    torque_limit_nm: tuple[float, float] = (250.0, 120.0)
    substeps: int = 4
    gravity: float = 9.81


def forward_kinematics(
    q1: float, q2: float, l1: float, l2: float
) -> tuple[float, float, float, float]:
    """Elbow and wrist positions ``(ex, ez, wx, wz)`` for absolute ``q1`` and relative ``q2``."""
    ex, ez = l1 * math.cos(q1), l1 * math.sin(q1)
    return ex, ez, ex + l2 * math.cos(q1 + q2), ez + l2 * math.sin(q1 + q2)


def inverse_kinematics(wx: float, wz: float, l1: float, l2: float) -> tuple[float, float, bool]:
    """Elbow-up joint angles ``(q1, q2, reachable)`` putting the wrist at ``(wx, wz)``.

    An unreachable target is projected onto the workspace boundary and ``reachable`` is False.
    """
    r2 = wx * wx + wz * wz
    c2 = (r2 - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)
    reachable = -1.0 <= c2 <= 1.0
    c2 = min(max(c2, -1.0), 1.0)
    q2 = -math.acos(c2)  # elbow up for targets in front of and below the shoulder
    q1 = math.atan2(wz, wx) - math.atan2(l2 * math.sin(q2), l1 + l2 * math.cos(q2))
    return q1, q2, reachable


class PlanarArmPlant:
    """The pymunk planar arm as a ``fuzzkit.plants.contract.ContactPlant``.

    Examples
    --------
    >>> plant = PlanarArmPlant()
    >>> sample = plant.reset(scenario, seed=1)          # doctest: +SKIP
    >>> sample = plant.step(np.zeros(3), path_time_s=0.004)  # doctest: +SKIP
    """

    name = "planar"

    def __init__(self, params: ArmParameters | None = None) -> None:
        self.params = params or ArmParameters()
        self._scenario: Scenario | None = None

    @property
    def period_s(self) -> float:
        """Controller period of the current scenario (seconds; 4 ms before the first reset)."""
        return self._scenario.period_s if self._scenario is not None else 0.004

    # -- world building -------------------------------------------------------------------------

    def reset(self, scenario: Scenario, seed: int = 0) -> PlantSample:
        """Build the arm at the start of ``scenario``'s path, at rest; returns the first sample."""
        p = self.params
        if any(w.tilt_rad != 0.0 for w in scenario.path):
            raise ConfigError(
                f"scenario {scenario.name}: the planar arm keeps its tool vertical; a tilting "
                "tool (path tilt_deg) needs the 6-DOF plant (--plant arm6)"
            )
        self._scenario = scenario
        self._tool_len = scenario.tool.length_m
        # what the wrist sensor carries (the tool never turns: a constant weight)
        self._weight = tool_weight(scenario.tool.mass_kg, scenario.rotation)
        self._dt = scenario.period_s / p.substeps
        self._rot_t = scenario.rotation.T
        self._contact = ContactSolver(scenario.objects, scenario.contact, scenario.tool.radius_m)
        self._sensor = ForceSensor(scenario.sensor, seed)
        if scenario.tool.mass_kg != 0.0:
            self._sensor.settle(self._weight)
        self._t = 0.0

        start = nominal_position(scenario.path, 0.0)
        q1, q2, ok = inverse_kinematics(
            float(start[0]), float(start[2]) + self._tool_len, p.link1_m, p.link2_m
        )
        if not ok:
            raise SimulationError(
                f"scenario {scenario.name}: path start {start.tolist()} is out of reach"
            )
        space = pymunk.Space()
        space.gravity = (0.0, -p.gravity)
        space.iterations = 20
        l1, l2 = p.link1_m, p.link2_m
        ex, ez, wx, wz = forward_kinematics(q1, q2, l1, l2)

        link1 = pymunk.Body(p.mass1_kg, p.mass1_kg * l1 * l1 / 12.0)
        link1.position = (0.5 * ex, 0.5 * ez)
        link1.angle = q1
        link2 = pymunk.Body(p.mass2_kg, p.mass2_kg * l2 * l2 / 12.0)
        link2.position = (0.5 * (ex + wx), 0.5 * (ez + wz))
        link2.angle = q1 + q2
        tool = pymunk.Body(p.tool_mass_kg, p.tool_mass_kg * self._tool_len**2 / 12.0)
        tool.position = (wx, wz - 0.5 * self._tool_len)
        ground = space.static_body
        self._motor1 = pymunk.SimpleMotor(ground, link1, 0.0)
        self._motor2 = pymunk.SimpleMotor(link1, link2, 0.0)
        self._motor1.max_force = p.torque_limit_nm[0]
        self._motor2.max_force = p.torque_limit_nm[1]
        space.add(
            link1,
            link2,
            tool,
            pymunk.PivotJoint(ground, link1, (0.0, 0.0)),
            pymunk.PivotJoint(link1, link2, (ex, ez)),
            pymunk.PivotJoint(link2, tool, (wx, wz)),
            pymunk.GearJoint(ground, tool, 0.0, 1.0),
            self._motor1,
            self._motor2,
        )
        self._space, self._link1, self._link2, self._tool = space, link1, link2, tool
        self._q_target = (q1, q2)
        self._target = start
        self._last_points: tuple[tuple[float, float], ...] = ()
        self._last_normals: tuple[tuple[float, float], ...] = ()
        self._true_task = np.zeros(3)
        return self._sample(start, start, ())

    # -- stepping -------------------------------------------------------------------------------

    def step(self, correction_xyz: Vec, path_time_s: float) -> PlantSample:
        """Advance one controller period towards ``nominal(path_time_s) + correction_xyz``."""
        if self._scenario is None:
            raise RuntimeError("PlanarArmPlant.reset(scenario) must be called first")
        p = self.params
        nominal = nominal_position(self._scenario.path, path_time_s)
        target = nominal + np.asarray(correction_xyz, dtype=np.float64)
        messages: list[str] = []
        q1t, q2t, ok = inverse_kinematics(
            float(target[0]), float(target[2]) + self._tool_len, p.link1_m, p.link2_m
        )
        if not ok:
            messages.append("target out of reach: joint targets clamped to the workspace boundary")
        self._q_target = (q1t, q2t)
        self._target = target

        link1, link2, tool = self._link1, self._link2, self._tool
        gain, dt, tool_len = p.servo_gain_per_s, self._dt, self._tool_len
        # plain floats: numpy element access would cost more than the arithmetic, every substep
        r00, r02, r10, r12, r20, r22 = (
            float(self._rot_t[i, j]) for i, j in ((0, 0), (0, 2), (1, 0), (1, 2), (2, 0), (2, 2))
        )
        sat = [False, False]
        for _ in range(p.substeps):
            q1 = link1.angle
            q2 = link2.angle - q1
            # SimpleMotor drives b.w - a.w to -rate, hence the minus signs.
            self._motor1.rate = -gain * _wrap(q1t - q1)
            self._motor2.rate = -gain * _wrap(q2t - q2)
            cx, cz = tool.position
            tip_x, tip_z = cx, cz - 0.5 * tool_len
            vx, vz = tool.velocity
            res = self._contact.step(tip_x, tip_z, vx, vz, dt)
            if res.points:
                tool.apply_force_at_world_point((res.force_x, res.force_z), (tip_x, tip_z))
            self._space.step(dt)
            self._t += dt
            # The sensor measures the force the tool exerts on the environment: minus the reaction.
            fbx, fbz = -res.force_x, -res.force_z
            true_task = np.array(
                [r00 * fbx + r02 * fbz, r10 * fbx + r12 * fbz, r20 * fbx + r22 * fbz]
            )
            self._sensor.update(self._t, dt, true_task + self._weight)
            self._true_task = true_task
            self._last_points = res.points
            self._last_normals = res.normals
            sat[0] = sat[0] or abs(self._motor1.impulse) >= 0.99 * p.torque_limit_nm[0] * dt
            sat[1] = sat[1] or abs(self._motor2.impulse) >= 0.99 * p.torque_limit_nm[1] * dt
        for j, s in enumerate(sat):
            if s:
                messages.append(f"joint {j + 1} at its torque limit ({p.torque_limit_nm[j]:g} N m)")
        if not all(
            math.isfinite(v) for v in (link1.angle, link2.angle, tool.position.x, tool.position.y)
        ):
            raise SimulationError(f"planar arm state became non-finite at t={self._t:.3f} s")
        return self._sample(nominal, target, tuple(messages))

    # -- reporting ------------------------------------------------------------------------------

    def _sample(self, nominal: Vec, target: Vec, messages: tuple[str, ...]) -> PlantSample:
        p = self.params
        q1 = self._link1.angle
        q2 = self._link2.angle - q1
        ex, ez, wx, wz = forward_kinematics(q1, q2, p.link1_m, p.link2_m)
        cx, cz = self._tool.position
        tip = np.array([cx, 0.0, cz - 0.5 * self._tool_len])
        arm = np.array([[0.0, 0.0, 0.0], [ex, 0.0, ez], [wx, 0.0, wz], tip.tolist()])
        pts = np.array([[x, 0.0, z] for x, z in self._last_points]).reshape(-1, 3)
        # What the tool exerts on each object: minus the normal reaction on the tool.
        normal = normal_force_by_axis(
            ((-nx, 0.0, -nz) for nx, nz in self._last_normals), self._rot_t.T
        )
        return PlantSample(
            t_s=self._t,
            force=self._sensor.read(),
            force_true=self._true_task.copy(),
            tool_position=tip,
            nominal_position=np.asarray(nominal, dtype=np.float64).copy(),
            target_position=np.asarray(target, dtype=np.float64).copy(),
            joint_angles=np.array([q1, q2]),
            in_contact=bool(self._last_points),
            contact_points=pts,
            arm_points=arm,
            messages=messages,
            force_normal=normal,
        )


def _wrap(a: float) -> float:
    """Angle difference wrapped to (-pi, pi] so a servo never takes the long way round."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi
