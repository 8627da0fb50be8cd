"""The plant-neutral contract between experiments and simulated robots.

An experiment (``fuzzkit.studies.experiments``) describes a *world* with a :class:`Scenario` and
drives any object that satisfies :class:`ContactPlant`: the pymunk planar arm
(``fuzzkit.planar_sim``) or the 6-DOF kinematic arm (``fuzzkit.plants.arm6``). Both build their own
world from the same Scenario and use the same contact law (:class:`ContactSolver`) and sensor model
(:class:`ForceSensor`) defined here, so their force readings are comparable.

Frames and signs (read this first)
----------------------------------
* **Base frame**: x forward, y left, z up, metres, origin at the robot base. Scenarios live in the
  vertical x-z working plane (``y = 0``); environment objects are extruded along y.
* **Task frame** (``Scenario.task_rotation``, base-from-task rotation): the F/T sensor frame of a
  tool pointing down. Default ``diag(1, -1, -1)``: task x = base x, task z = base -z (down).
* **Force** (``PlantSample.force``): the force the tool exerts *on the environment*, in the task
  frame (the paper's ``f``). Pressing down on a table with 10 N gives ``force[2] = +10``; pushing
  into a wall that faces -x gives ``force[0] > 0``. Hence a *positive* correction along a task axis
  (moving into the surface) *increases* the force: the controllers use positive gains.
* **Correction** (``ContactPlant.step``): the accumulated Cartesian correction ``S*u`` in metres,
  in the *base* frame, added to the nominal path position (use :func:`task_to_base`).
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import ConfigError
from fuzzkit.plants.contact import ContactModel, SensorModel, ToolModel
from fuzzkit.plants.environment import EnvObject, Waypoint

Vec = npt.NDArray[np.float64]

#: Rotation base-from-task of a tool pointing straight down (task z = base -z).
TOOL_DOWN: tuple[tuple[float, float, float], ...] = (
    (1.0, 0.0, 0.0),
    (0.0, -1.0, 0.0),
    (0.0, 0.0, -1.0),
)


# --------------------------------------------------------------------------------------------
# Scenario and samples
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Scenario:
    """The world of one experiment, independent of the robot that runs it.

    ``path`` is the nominal CAD path of the tool tip (base frame, ``y = 0``), ``objects`` the
    environment as it really is (which the path may not expect), ``period_s`` the outer
    (force) loop period: 4 ms like ABB EGM. Set points and gains are not part of the world;
    ``fuzzkit.studies.experiments.Experiment`` adds them.
    """

    name: str
    path: tuple[Waypoint, ...]
    objects: tuple[EnvObject, ...]
    duration_s: float
    contact: ContactModel = field(default_factory=ContactModel)
    sensor: SensorModel = field(default_factory=SensorModel)
    tool: ToolModel = field(default_factory=ToolModel)
    period_s: float = 0.004
    task_rotation: tuple[tuple[float, float, float], ...] = TOOL_DOWN
    description: str = ""

    def __post_init__(self) -> None:
        problems = []
        if len(self.path) < 1:
            problems.append("path needs at least one waypoint")
        if any(b.t_s < a.t_s for a, b in itertools.pairwise(self.path)):
            problems.append("path waypoint times must not decrease")
        if not self.period_s > 0.0:
            problems.append(f"period_s must be > 0 (got {self.period_s})")
        if not self.duration_s > 0.0:
            problems.append(f"duration_s must be > 0 (got {self.duration_s})")
        if not self.contact.stiffness_n_per_m > 0.0:
            problems.append("contact stiffness must be > 0")
        if not self.sensor.rate_hz > 0.0:
            problems.append("sensor rate must be > 0")
        if problems:
            raise ConfigError(f"scenario {self.name}: " + "; ".join(problems))

    @property
    def rotation(self) -> Vec:
        """Base-from-task rotation matrix (3, 3)."""
        return np.asarray(self.task_rotation, dtype=np.float64)


def task_to_base(scenario: Scenario, vec_task: Vec) -> Vec:
    """Express a task-frame vector (correction, force) in the base frame."""
    return scenario.rotation @ vec_task


def normal_force_by_axis(normal_forces_base: Iterable[Sequence[float]], rotation: Vec) -> Vec:
    """The normal contact force per task axis: what tells which task axis touches a surface.

    ``normal_forces_base``: per contact, the normal part (friction excluded) of the force the
    tool exerts on the object, base frame ``(x, y, z)``; ``rotation``: base-from-task.

    Each contact's normal force, in the task frame, is credited to the task axis its surface
    normal lies closest to (the largest component; ties go to the lower axis index): pressing
    down on a floor credits z, even where roughness tilts the floor's normal by 10 degrees,
    and pushing into a wall ahead credits x. Friction never counts, so sliding on a floor
    with a tangential force of ``mu * f_z`` along x gives 0 along x. Returns ``(3,)`` newtons,
    task frame (positive: pushing into a surface that faces the negative task axis).

    Examples
    --------
    >>> import numpy as np
    >>> tool_down = np.diag([1.0, -1.0, -1.0])
    >>> normal_force_by_axis([(0.0, 0.0, -30.0), (6.0, 0.0, 0.0)], tool_down).tolist()
    [6.0, 0.0, 30.0]
    """
    out = np.zeros(3)
    for f in normal_forces_base:
        task = rotation.T @ np.asarray(f, dtype=np.float64)
        i = int(np.argmax(np.abs(task)))
        out[i] += task[i]
    return out


@dataclass(frozen=True, slots=True)
class PlantSample:
    """What a plant reports after one controller period.

    Attributes
    ----------
    t_s : simulation time at the end of the period.
    force : measured force on the environment, task frame, N; NaN when no sensor sample arrived.
    force_true : the true (noise- and filter-free) contact force, task frame, N.
    tool_position, nominal_position, target_position : base frame, m. Target = nominal + correction.
    joint_angles : radians, plant-specific length.
    in_contact : True when any environment object touches the tool.
    contact_points : (k, 3) base-frame points of contact.
    force_normal : the normal contact force per task axis (friction excluded, each contact
        credited to the task axis closest to its surface normal; see
        :func:`normal_force_by_axis`), task frame, N. It says *which axis* touches a surface,
        so metrics can count each force axis from its own first contact. None: the plant does
        not report it (metrics then take any contact as every axis's contact).
    arm_points : (m, 3) base-frame polyline from the base through the joints to the tool tip.
    messages : status and limit messages of this period (torque limit, unreachable target ...).
    tool_rotation : world-from-sensor rotation (3, 3) of the frame ``force`` is in, when the
        tool turns away from the task frame (a tilted tool); None: ``force`` is in the
        scenario's fixed task frame (``Scenario.rotation``).
    """

    t_s: float
    force: Vec
    force_true: Vec
    tool_position: Vec
    nominal_position: Vec
    target_position: Vec
    joint_angles: Vec
    in_contact: bool
    contact_points: Vec
    arm_points: Vec
    messages: tuple[str, ...] = ()
    force_normal: Vec | None = None
    tool_rotation: Vec | None = None


@runtime_checkable
class ContactPlant(Protocol):
    """A simulated robot with an inner motion loop and a wrist F/T sensor.

    ``reset`` builds the world from a Scenario (deterministic for a given ``seed``, which seeds
    sensor noise and nothing else); ``step`` advances one controller period (``period_s``,
    taken from the scenario) with the tool-tip target
    ``nominal_position(path, path_time_s) + correction_xyz`` (base frame) and reports the sample
    at the end of the period. The runner passes ``path_time_s`` so it can hold the path
    (e.g. when the force controller takes over on contact).
    """

    name: str

    @property
    def period_s(self) -> float: ...

    def reset(self, scenario: Scenario, seed: int = 0) -> PlantSample: ...

    def step(self, correction_xyz: Vec, path_time_s: float) -> PlantSample: ...


def wrist_sensor_extras(scenario: Scenario) -> list[str]:
    """What of ``scenario``'s wrist-sensor model goes beyond filter, noise and a constant bias:
    a tool weight, a drifting bias, a tilting tool (the compiled loops model none of them)."""
    out = []
    if scenario.tool.mass_kg != 0.0:
        out.append("a tool weight (tool mass_kg)")
    if any(v != 0.0 for v in scenario.sensor.bias_drift_n_per_s):
        out.append("a drifting sensor bias (sensor bias_drift_n_per_s)")
    if any(w.tilt_rad != 0.0 for w in scenario.path):
        out.append("a tilting tool (path tilt_deg)")
    return out


class UnsupportedPlant(ConfigError):
    """The plant uses something its compiled twin does not model (the Python loop still runs).

    Raised by the compiled loops' ``pack`` functions (:mod:`fuzzkit.plants.arm6_period`,
    :mod:`fuzzkit.planar_sim.arm_period`); callers fall back to the Python loop and say why.
    """
