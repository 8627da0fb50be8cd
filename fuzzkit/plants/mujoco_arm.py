"""The ABB IRB 140 as a dynamic plant in MuJoCo (``--plant mujoco``).

The same task and the same inner loop as :mod:`fuzzkit.plants.arm6`: every controller period
the nominal path pose plus the force loop's correction goes through the kit's inverse
kinematics and the joint speed limits into joint references
(:meth:`~fuzzkit.plants.arm6.Arm6Plant._reference_step`, shared). What differs is everything
after that, which MuJoCo computes rather than this kit:

* **Rigid-body dynamics** of the six links (masses, inertias, gravity; the controller
  compensates gravity with its model, as an industrial controller does) and of the motors
  (rotor inertia seen through the gear, viscous and Coulomb gear friction).
* **Servos**: one PD position loop per joint with velocity feed-forward, gains set for a
  chosen bandwidth from the joint inertia, and a torque limit; the reference is interpolated
  linearly over the physics steps of a period. The servo is compliant: a contact force
  deflects the arm by ``J K^-1 J^T f``.
* **Joint elasticity** (optional, :attr:`ArmDynamics.elastic`): a spring-damper between each
  motor and its link.
* **Contact**: MuJoCo's soft contact between the probe's sphere and the scene (table, blocks,
  a rough profile as a height field), with its ``solref``/``solimp`` set so that the static
  contact stiffness and damping are the scenario's (:func:`contact_solref`, checked by
  ``tests/test_mujoco_arm.py``). Friction is MuJoCo's (elliptic cone, the scenario's
  coefficient).
* **Wrist force**: a MuJoCo ``force`` sensor at the flange (the force the wrist exerts on the
  tool: contact force, tool weight and tool inertia), through the kit's sensor model
  (:class:`~fuzzkit.plants.contact.ForceSensor`: filter, noise, bias, sample rate; latency is
  the runner's) as on ``arm6``.

The physics runs at 1 kHz (:data:`~fuzzkit.plants.mujoco_model.PHYSICS_DT_S`), four steps per
4 ms period: one ``mj_step(m, d, nstep=4)`` with the servo ramp as a C control callback when the
plant is given one (:mod:`fuzzkit.plants.mujoco_servo`; ``--plant mujoco`` builds it through
:mod:`fuzzkit.loop.mujoco`), else four calls with the ramp in Python. Runs are
deterministic for a seed (MuJoCo is, single-threaded; the seed draws the sensor noise).
docs/mujoco.md lists every parameter and its source.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from functools import lru_cache

import mujoco
import numpy as np
import numpy.typing as npt

from fuzzkit.errors import ConfigError, SimulationError
from fuzzkit.plants import arm6_period
from fuzzkit.plants.arm6 import Arm6Parameters, Arm6Plant
from fuzzkit.plants.contact import ContactModel, SensorModel
from fuzzkit.plants.contract import PlantSample, Scenario, normal_force_by_axis
from fuzzkit.plants.environment import RoughSurface, Waypoint
from fuzzkit.plants.kinematics import IKResult, IKStatus
from fuzzkit.plants.mujoco_model import (
    GAIN_POSE,
    PHYSICS_DT_S,
    ArmDynamics,
    arm_mjcf,
    profile_pose,
    scene_geoms,
)
from fuzzkit.plants.mujoco_servo import ServoCallback
from fuzzkit.plants.rotations import Mat3, Vec3, matrix_from_quat

FloatArray = npt.NDArray[np.float64]

#: MuJoCo's constraint impedance of every contact (``solimp`` with ``dmin = dmax``): constant,
#: so the contact stiffness does not depend on the depth.
IMPEDANCE = 0.01


def contact_solref(
    model: ContactModel, inverse_weight: float, impedance: float = IMPEDANCE
) -> tuple[float, float]:
    """MuJoCo's ``solref`` (its "direct" form, both negative) that gives a contact the
    scenario's static stiffness and damping.

    MuJoCo's soft contact force at rest is ``f = k r / ((1 - d) A)`` with ``solref = (-k, -b)``,
    ``d`` the impedance and ``A`` the approximate inverse inertia at the contact, the
    contacting body's ``body_invweight0`` (the scene is static); the damping scales the same
    way. So ``k = K (1 - d) A`` and ``b = B (1 - d) A`` for a stiffness ``K`` (N/m) and
    damping ``B`` (N s/m).
    """
    scale = (1.0 - impedance) * inverse_weight
    return -model.stiffness_n_per_m * scale, -model.damping_n_s_per_m * scale


def _quiet(_message: str) -> None:
    """MuJoCo's warning printer, silenced: the plant reads MuJoCo's warning counters
    (``MjData.warning``) after every period and raises a located error instead."""


@lru_cache(maxsize=16)
def _compiled(xml: str) -> mujoco.MjModel:
    """The compiled model of an MJCF document (cached: compiling the height field is slow).

    Callers get their own copy, so their runtime changes (gains, contact) never leak."""
    return mujoco.MjModel.from_xml_string(xml)


class MujocoArmPlant(Arm6Plant):
    """The ABB IRB 140 in MuJoCo as a :class:`fuzzkit.plants.contract.ContactPlant` (name
    ``mujoco``).

    Examples
    --------
    >>> from fuzzkit.studies.experiments import experiment
    >>> plant = MujocoArmPlant()
    >>> sample = plant.reset(experiment("E1").scenario, seed=1)
    >>> sample = plant.step(np.zeros(3), path_time_s=0.004)
    >>> round(plant.period_s, 3), sample.joint_angles.shape
    (0.004, (6,))
    """

    name = "mujoco"

    def __init__(
        self, params: Arm6Parameters | None = None, dynamics: ArmDynamics | None = None
    ) -> None:
        super().__init__(params)
        self.dynamics = dynamics or ArmDynamics()
        #: IK through arm6's compiled twin (False: the Python reference, for comparison)
        self.compiled_ik = True
        self._ik_arrays: tuple[FloatArray, ...] | None = None
        self._ik_work: arm6_period.IkWorkspace | None = None  # the compiled IK's scratch
        #: the servo ramp in C as MuJoCo's control callback, when given
        #: (:meth:`use_servo_callback`); None: the Python ramp, one ``mj_step`` per substep
        self.servo: ServoCallback | None = None
        #: why the ramp runs in Python, said once in the first period's messages
        self.servo_note = ""

    def use_servo_callback(self, servo: ServoCallback | None, why_not: str = "") -> None:
        """Run the servo ramp as ``servo`` (from the next :meth:`reset` on), or in Python
        with ``why_not`` said in the first period's messages."""
        self.servo = servo
        self.servo_note = "" if servo is not None else why_not

    # -- world building -------------------------------------------------------------------------

    def reset(self, scenario: Scenario, seed: int = 0) -> PlantSample:  # type: ignore[override]
        """Build the MuJoCo world of ``scenario`` and put the arm at rest at the path's start.

        Raises
        ------
        ConfigError
            If the scenario holds an object the MuJoCo scene cannot build, or the plant's
            parameters add 3-D objects (``extra_objects``), which it does not model.
        SimulationError
            If the path's first pose cannot be reached within the joint limits.
        """
        if self.params.extra_objects:
            raise ConfigError("the mujoco plant does not model extra 3-D objects (extra_objects)")
        super().reset(scenario, seed)
        dyn = self.dynamics
        tool = scenario.tool
        xml = arm_mjcf(
            self._robot_base,
            dyn,
            tool.length_m,
            tool.radius_m,
            tool.mass_kg,
            scene_geoms(scenario.objects, self._offset, self.params.object_half_width),
        )
        mujoco.set_mju_user_warning(_quiet)
        m = _compiled(xml).__copy__()
        d = mujoco.MjData(m)
        self.model, self.data = m, d
        n_sub = round(scenario.period_s / PHYSICS_DT_S)
        if n_sub < 1 or abs(n_sub * PHYSICS_DT_S - scenario.period_s) > 1e-9:
            raise ConfigError(
                f"scenario {scenario.name}: the mujoco plant needs a period that is a multiple "
                f"of its {PHYSICS_DT_S * 1e3:g} ms physics step (got {scenario.period_s} s)"
            )
        self._n_sub = n_sub
        self._link_qpos = np.array(
            [m.jnt_qposadr[m.joint(j.name).id] for j in self._robot_base.joints]
        )
        self._servo_qpos = np.array(
            [m.jnt_qposadr[m.actuator_trnid[a, 0]] for a in range(m.nu)], dtype=np.int64
        )
        self._elastic = np.array([dyn.is_elastic(i) for i in range(m.nu)])
        self._tip = m.geom("tip").id
        self._arm_bodies = [m.body(f"body{i + 1}").id for i in range(m.nu)] + [m.body("tool").id]
        self._tool_body = m.body("tool").id
        self._set_gains(m, d)
        self._set_contact(m, scenario.contact)
        self._profiles = [
            (int(m.body(f"profile{k}").mocapid[0]), obj)
            for k, obj in enumerate(scenario.objects)
            if isinstance(obj, RoughSurface)
        ]

        mujoco.mj_resetData(m, d)
        q0 = np.array(self._q)
        d.qpos[self._link_qpos] = q0
        d.qpos[self._servo_qpos] = q0
        d.qpos[self._link_qpos[self._elastic]] = 0.0
        d.ctrl[:] = q0
        self._ref_prev = q0.copy()
        mujoco.mj_kinematics(m, d)
        self._follow_profiles()
        mujoco.mj_forward(m, d)
        self._sensor.settle(self._wrist())
        self._userdata: FloatArray | None = None
        if self.servo is not None:
            self._userdata = self.servo.arm(d, n_sub, np.array(m.actuator_forcerange[:, 1]))
            self.servo.install()
        self._note = self.servo_note
        chain = self.chain
        self._ik_arrays = (
            (
                np.array(chain._links, dtype=np.float64),
                np.array(chain._tool_r, dtype=np.float64),
                np.array(chain._tool_p, dtype=np.float64),
                np.array(chain.lower, dtype=np.float64),
                np.array(chain.upper, dtype=np.float64),
            )
            if self.compiled_ik
            else None
        )
        self._true_task = np.zeros(3)
        self._normals: list[tuple[float, float, float]] = []
        self._contacts: list[FloatArray] = []
        self._q = self._link_angles().tolist()
        nominal = self._to_scenario(self.path.pose_at(0.0)[0])
        return self._mj_sample(nominal, nominal, ())

    def _set_gains(self, m: mujoco.MjModel, d: mujoco.MjData) -> None:
        """PD gains of every servo from its joint's inertia at :data:`GAIN_POSE`: ``kp = M w^2``,
        ``kv = 2 zeta w M`` less the gear's viscous damping (which damps the joint already)."""
        dyn = self.dynamics
        d.qpos[self._servo_qpos] = GAIN_POSE
        mujoco.mj_forward(m, d)
        full = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, full)
        w = 2.0 * math.pi * dyn.bandwidth_hz
        self._kv_over_kp = np.zeros(m.nu)
        for a in range(m.nu):
            dof = m.jnt_dofadr[m.actuator_trnid[a, 0]]
            inertia = full[dof, dof]
            kp, kv = inertia * w * w, 2.0 * dyn.damping_ratio * w * inertia
            # the gear's viscous friction already damps: the servo adds the rest
            kv = max(kv - dyn.damping_n_m_s[a], 0.0)
            m.actuator_gainprm[a, 0] = kp
            m.actuator_biasprm[a, :3] = (0.0, -kp, -kv)
            self._kv_over_kp[a] = kv / kp
        self.servo_gains = np.array(
            [(m.actuator_gainprm[a, 0], -m.actuator_biasprm[a, 2]) for a in range(m.nu)]
        )

    def _set_contact(self, m: mujoco.MjModel, contact: ContactModel) -> None:
        """The scenario's stiffness, damping and friction on the tip and every scene geom."""
        solref = contact_solref(contact, float(m.body_invweight0[self._tool_body, 0]))
        for g in range(m.ngeom):
            m.geom_solref[g] = solref
            m.geom_solimp[g] = (IMPEDANCE, IMPEDANCE, 0.001, 0.5, 2.0)
            m.geom_friction[g, 0] = contact.friction

    def _solve_ik(self, rotation: Mat3, position: Vec3) -> IKResult:
        """arm6's IK, through its compiled twin (:func:`fuzzkit.plants.arm6_period.ik`, held
        step for step to ``SerialChain.ik_fast`` by ``tests/test_compiled_loop.py``): a period
        is mostly Python otherwise. A solve that does not converge is redone by the reference
        for its errors and the joints at a limit, which the messages name."""
        if self._ik_arrays is None:
            return super()._solve_ik(rotation, position)
        links, tool_r, tool_p, lo, hi = self._ik_arrays
        if self._ik_work is None:
            self._ik_work = arm6_period.ik_workspace(links.shape[0])
        q = np.array(self._q_ik, dtype=np.float64)
        p = self.params
        status = arm6_period.ik(
            np.asarray(rotation, dtype=np.float64),
            np.asarray(position, dtype=np.float64),
            q,
            links,
            tool_r,
            tool_p,
            lo,
            hi,
            p.ik_position_tolerance,
            p.ik_orientation_tolerance,
            p.ik_iterations,
            self._ik_work,
        )
        if status != arm6_period.IK_CONVERGED:
            return super()._solve_ik(rotation, position)
        return IKResult(q, IKStatus.CONVERGED, 0.0, 0.0, 0)

    # -- stepping -------------------------------------------------------------------------------

    def step(  # type: ignore[override]
        self,
        correction_xyz: FloatArray | Sequence[float],
        path_time_s: float,
        correction_rotation: FloatArray | Sequence[float] | None = None,
    ) -> PlantSample:
        """Advance one period: the reference through IK, then the physics at 1 kHz.

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
        m, d = self.model, self.data
        ref = np.array(self._q_ref)
        prev = self._ref_prev
        n = self._n_sub
        feed = self._kv_over_kp * (ref - prev) / self._dt
        follow = self._follow_profiles if self._profiles else None
        if self.servo is not None and self._userdata is not None:
            saturated = self.servo.period(m, d, self._userdata, prev, ref, feed, follow)
        else:
            # the reference ramp, which mujoco_servo.c computes alike in its callback
            limits = m.actuator_forcerange[:, 1]
            saturated = np.zeros(m.nu, dtype=bool)
            for s in range(1, n + 1):
                d.ctrl[:] = prev + (s / n) * (ref - prev) + feed
                if follow is not None:
                    follow()
                mujoco.mj_step(m, d)
                saturated |= np.abs(d.actuator_force) >= 0.999 * limits
        if self._note:
            messages.append(self._note)
            self._note = ""
        t0 = self._t
        self._ref_prev = ref
        self._t = t0 + self._dt
        # the sensor model advances once per period on the period's last force, as on arm6
        self._sensor.update(self._t, self._dt, self._wrist())
        if saturated.any():
            names = ", ".join(self._robot_base.joints[i].name for i in np.flatnonzero(saturated))
            messages.append(f"servo torque limit on {names}")
        if d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number or not np.all(np.isfinite(d.qpos)):
            raise SimulationError(
                f"t={self._t:.3f} s: the MuJoCo simulation diverged (a contact or joint "
                "stiffness too high for its 1 kHz physics step)"
            )
        force = self._contact_force()
        if self._tilts:
            self._rot_sensor = np.asarray(matrix_from_quat(quat))
        self._true_task = self._sensor_rotation().T @ force
        self._q = self._link_angles().tolist()
        return self._mj_sample(
            self._to_scenario(pos), self._to_scenario(target_pos), tuple(messages)
        )

    def _follow_profiles(self) -> None:
        """Put each rough profile's block on the profile's tangent plane under the tool."""
        x = float(self.data.geom_xpos[self._tip, 0]) - self._offset[0]
        for mocap, surface in self._profiles:
            pos, quat = profile_pose(surface, x, self._offset)
            self.data.mocap_pos[mocap] = pos
            self.data.mocap_quat[mocap] = quat

    # -- reading MuJoCo -------------------------------------------------------------------------

    def _link_angles(self) -> FloatArray:
        """The links' joint angles (rad): motor plus spring deflection when elastic."""
        d = self.data
        q = np.array(d.qpos[self._servo_qpos])
        q[self._elastic] += d.qpos[self._link_qpos[self._elastic]]
        return q

    def deflection(self) -> FloatArray:
        """The joint springs' deflections, link minus motor angle (rad); zeros when rigid."""
        out = np.zeros(len(self._link_qpos))
        out[self._elastic] = self.data.qpos[self._link_qpos[self._elastic]]
        return out

    def _wrist(self) -> FloatArray:
        """The flange sensor's force (N, sensor frame), in the kit's sign: the force the wrist
        exerts on the tool, as the tool's contact force is the one it exerts on the world
        (MuJoCo's force sensor reports the parent's force on the child, in the site frame)."""
        return np.array(self.data.sensordata[:3])

    def _contact_force(self) -> FloatArray:
        """Sum of the contact forces the tool exerts on the scene (N, base frame); keeps each
        contact's normal part and point for the sample."""
        m, d = self.model, self.data
        total = np.zeros(3)
        normals: list[tuple[float, float, float]] = []
        points: list[FloatArray] = []
        out = np.zeros(6)
        for i in range(d.ncon):
            c = d.contact[i]
            if self._tip not in (c.geom1, c.geom2):
                continue
            mujoco.mj_contactForce(m, d, i, out)
            frame = c.frame.reshape(3, 3)
            # the force geom1 exerts on geom2, in the contact frame (normal first)
            on_geom2 = frame.T @ out[:3]
            by_tool = on_geom2 if c.geom1 == self._tip else -on_geom2
            normal = frame[0] * float(frame[0] @ by_tool)
            total += by_tool
            normals.append((float(normal[0]), float(normal[1]), float(normal[2])))
            points.append(np.array(c.pos))
        self._normals, self._contacts = normals, points
        return total

    def _mj_sample(
        self, nominal: FloatArray, target: FloatArray, messages: tuple[str, ...]
    ) -> PlantSample:
        q = self._q
        d = self.data
        # base, the joints' frame origins, the flange, the tool tip: arm6's polyline
        tip = d.geom_xpos[self._tip] - self._offset_arr
        arm = np.vstack((d.xpos[self._arm_bodies] - self._offset_arr, tip))
        pts = np.array(self._contacts) - self._offset_arr if self._contacts else np.zeros((0, 3))
        return PlantSample(
            t_s=self._t,
            force=self._sensor.read(),
            force_true=self._true_task.copy(),
            tool_position=tip,
            nominal_position=nominal,
            target_position=target,
            joint_angles=np.array(q),
            in_contact=bool(self._contacts),
            contact_points=pts,
            arm_points=arm,
            messages=messages,
            force_normal=normal_force_by_axis(self._normals, self._sensor_rotation()),
            tool_rotation=None if self._rot_sensor is None else self._rot_sensor.copy(),
        )


class ElasticMujocoArmPlant(MujocoArmPlant):
    """The MuJoCo IRB 140 with a spring-damper between motor and link on axes 1-3 (name
    ``mujoco-elastic``; :class:`~fuzzkit.plants.mujoco_model.ArmDynamics`)."""

    name = "mujoco-elastic"

    def __init__(
        self, params: Arm6Parameters | None = None, dynamics: ArmDynamics | None = None
    ) -> None:
        super().__init__(params, dynamics or ArmDynamics(elastic=True))


def servo_step_response(
    joint: int,
    step_rad: float,
    duration_s: float,
    dynamics: ArmDynamics | None = None,
) -> tuple[FloatArray, FloatArray]:
    """One joint's position loop answering a reference step, the arm in free space at rest at
    E1's start: ``(t, link angle change)`` sampled every physics step (s, rad). The other joints
    hold their references, so the coupling through the arm's inertia is in the answer."""
    plant = MujocoArmPlant(dynamics=dynamics)
    scenario = Scenario(
        name="servo step",
        path=(Waypoint(0.0, 0.4, 0.0, -0.19),),
        objects=(),
        duration_s=duration_s,
        sensor=SensorModel(noise_std_n=0.0),
    )
    plant.reset(scenario)
    m, d = plant.model, plant.data
    start = plant._link_angles()[joint]
    d.ctrl[joint] += step_rad
    n = round(duration_s / PHYSICS_DT_S)
    t: FloatArray = np.arange(1, n + 1, dtype=np.float64) * PHYSICS_DT_S
    q = np.empty(n)
    for i in range(n):
        mujoco.mj_step(m, d)
        q[i] = plant._link_angles()[joint] - start
    return t, q
