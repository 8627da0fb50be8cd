"""The plant-neutral contract between experiments and simulated robots.

An experiment (``fuzzkit.experiments``) describes a *world* with a :class:`Scenario` and drives any
object that satisfies :class:`ContactPlant`: the pymunk planar arm (``planar_sim``) or the 6-DOF
kinematic arm (``fuzzkit.motion``). Both build their own world from the same Scenario and use the
same contact law (:class:`ContactSolver`) and sensor model (:class:`ForceSensor`) defined here, so
their force readings are comparable.

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

import importlib
import itertools
import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import ConfigError

Vec = npt.NDArray[np.float64]

#: Rotation base-from-task of a tool pointing straight down (task z = base -z).
TOOL_DOWN: tuple[tuple[float, float, float], ...] = (
    (1.0, 0.0, 0.0),
    (0.0, -1.0, 0.0),
    (0.0, 0.0, -1.0),
)


# --------------------------------------------------------------------------------------------
# Nominal path
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Waypoint:
    """A point of the nominal (CAD) path: tool tip at ``(x, y, z)`` m at time ``t_s`` s."""

    t_s: float
    x: float
    y: float
    z: float


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


# --------------------------------------------------------------------------------------------
# Contact law and sensor (shared by every plant)
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class ContactModel:
    """Compliant contact: normal spring-damper, tangential stick spring capped by Coulomb friction.

    Rigid-body contacts have no stiffness, but the force loop's behaviour is set by it, so the
    environment (workpiece, cup, pad) is modelled as a penalty spring of ``stiffness_n_per_m``.
    """

    stiffness_n_per_m: float = 1.0e4  # 10 N/mm: a plastic cup, a padded tool
    damping_n_s_per_m: float = 50.0
    friction: float = 0.3
    tangential_stiffness_n_per_m: float = 5.0e3


@dataclass(frozen=True, slots=True)
class SensorModel:
    """The wrist F/T sensor: sample rate, first-order anti-alias filter, Gaussian noise, bias."""

    rate_hz: float = 250.0
    cutoff_hz: float = 60.0
    noise_std_n: float = 0.1
    bias_n: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass(frozen=True, slots=True)
class ToolModel:
    """The tool below the wrist: tip ``length_m`` along the tool axis, contact disc ``radius_m``."""

    length_m: float = 0.12
    radius_m: float = 0.02
    name: str = "probe"


@dataclass(frozen=True, slots=True)
class ContactResult:
    """Contact force on the tool (base x, z; newtons) and where the contacts are.

    ``normals`` holds, per contact (in the order of ``points``), the normal part of the force on
    the tool (friction excluded), base ``(x, z)``: what tells a wall from a floor one slides on.
    """

    force_x: float
    force_z: float
    points: tuple[tuple[float, float], ...]
    normals: tuple[tuple[float, float], ...] = ()


class ContactSolver:
    """Evaluates the contact force on the tool's disc against every environment object.

    Stateful (the tangential stick springs), so create one per run and call :meth:`step` once per
    physics substep with the tool tip's position and velocity.
    """

    def __init__(self, objects: tuple[EnvObject, ...], model: ContactModel, radius: float) -> None:
        self.objects = objects
        self.model = model
        self.radius = radius
        self._stick = [0.0] * len(objects)

    def reset(self) -> None:
        """Forget the tangential stick state (all contacts released)."""
        self._stick = [0.0] * len(self.objects)

    def step(self, x: float, z: float, vx: float, vz: float, dt: float) -> ContactResult:
        """Force of the environment on the tool disc at ``(x, z)`` moving with ``(vx, vz)``."""
        m = self.model
        fx = fz = 0.0
        points: list[tuple[float, float]] = []
        normals: list[tuple[float, float]] = []
        for i, obj in enumerate(self.objects):
            pen = obj.penetration(x, z, self.radius)
            if pen is None:
                self._stick[i] = 0.0
                continue
            depth, nx, nz, px, pz = pen
            vn = -(vx * nx + vz * nz)  # rate of penetration
            fn = m.stiffness_n_per_m * depth + m.damping_n_s_per_m * vn
            if fn <= 0.0:  # a damper cannot pull the tool in
                self._stick[i] = 0.0
                continue
            tx, tz = nz, -nx
            s = self._stick[i] + (vx * tx + vz * tz) * dt
            cap = m.friction * fn
            ft = -m.tangential_stiffness_n_per_m * s
            if abs(ft) > cap:  # slipping: the stick spring stays at the Coulomb limit
                ft = math.copysign(cap, ft)
                s = -ft / m.tangential_stiffness_n_per_m if m.tangential_stiffness_n_per_m else 0.0
            self._stick[i] = s
            fx += fn * nx + ft * tx
            fz += fn * nz + ft * tz
            points.append((px, pz))
            normals.append((fn * nx, fn * nz))
        return ContactResult(fx, fz, tuple(points), tuple(normals))


class ForceSensor:
    """A sampled F/T sensor: first-order filter updated every substep, sampled at ``rate_hz``.

    :meth:`update` is called each physics substep with the true force (task frame);
    :meth:`read` returns the newest sample taken since the previous read, or NaN when none was
    taken (a sensor slower than the controller).
    """

    def __init__(self, model: SensorModel, seed: int) -> None:
        self.model = model
        self._rng = np.random.default_rng(seed)
        self._filtered = np.zeros(3)
        self._next_t = 1.0 / model.rate_hz  # samples at k / rate_hz, k = 1, 2, ...
        self._latest = np.full(3, np.nan)
        self._fresh = False

    def update(self, t_s: float, dt: float, true_force: Vec) -> None:
        """Advance the filter by ``dt`` and take a sample if one is due at ``t_s``."""
        alpha = 1.0 - math.exp(-2.0 * math.pi * self.model.cutoff_hz * dt)
        self._filtered += alpha * (true_force - self._filtered)
        if t_s + 1e-9 >= self._next_t:
            noise = (
                self._rng.normal(0.0, self.model.noise_std_n, 3)
                if self.model.noise_std_n > 0
                else 0.0
            )
            self._latest = self._filtered + np.asarray(self.model.bias_n) + noise
            self._fresh = True
            self._next_t += 1.0 / self.model.rate_hz

    def read(self) -> Vec:
        """The newest sample (task frame, N) not yet read, else NaN in every component."""
        if not self._fresh:
            return np.full(3, np.nan)
        self._fresh = False
        return self._latest.copy()


# --------------------------------------------------------------------------------------------
# Scenario and samples
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Scenario:
    """The world of one experiment, independent of the robot that runs it.

    ``path`` is the nominal CAD path of the tool tip (base frame, ``y = 0``), ``objects`` the
    environment as it really is (which the path may not expect), ``period_s`` the outer
    (force) loop period: 4 ms like ABB EGM. Set points and gains are not part of the world;
    ``fuzzkit.experiments.Experiment`` adds them.
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


def base_to_task(scenario: Scenario, vec_base: Vec) -> Vec:
    """Express a base-frame vector in the task frame."""
    return scenario.rotation.T @ vec_base


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


# --------------------------------------------------------------------------------------------
# Plant registry
# --------------------------------------------------------------------------------------------

#: Plant name -> ``"module:factory"``; the factory takes no arguments and returns a ContactPlant.
#: Imported lazily so that choosing one plant never imports another's dependencies.
PLANTS: dict[str, str] = {
    "planar": "planar_sim:PlanarArmPlant",
    "arm6": "fuzzkit.motion:Arm6Plant",  # 6-DOF IRB 140 kinematic plant (issue 5)
}


def make_plant(name: str) -> ContactPlant:
    """Build the plant registered as ``name`` (see :data:`PLANTS`)."""
    target = PLANTS.get(name)
    if target is None:
        raise ConfigError(f"unknown plant {name!r} (expected one of {', '.join(sorted(PLANTS))})")
    module_name, _, attr = target.partition(":")
    factory: Callable[[], ContactPlant] = getattr(importlib.import_module(module_name), attr)
    return factory()
