"""The contact law and the force/torque sensor model that every plant shares.

Penalty contact (stiffness, damping, Coulomb friction) and a filtered, noisy, biased F/T sensor;
the same code runs in the planar and the 6-DOF plants so their force readings compare.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import ConfigError
from fuzzkit.plants.environment import EnvObject

Vec = npt.NDArray[np.float64]


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


#: Standard gravity (m/s^2): the tool's weight per kilogram.
GRAVITY_M_S2 = 9.80665


@dataclass(frozen=True, slots=True)
class SensorModel:
    """The wrist F/T sensor: sample rate, first-order anti-alias filter, Gaussian noise, bias.

    The bias is ``bias_n + bias_drift_n_per_s * t`` at a sample taken at time ``t`` (a slow,
    deterministic drift, as temperature gives a real sensor).
    """

    rate_hz: float = 250.0
    cutoff_hz: float = 60.0
    noise_std_n: float = 0.1
    bias_n: tuple[float, float, float] = (0.0, 0.0, 0.0)
    bias_drift_n_per_s: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass(frozen=True, slots=True)
class ToolModel:
    """The tool below the wrist: tip ``length_m`` along the tool axis, contact disc ``radius_m``.

    ``mass_kg``: what the wrist sensor carries; its weight enters every reading
    (:func:`tool_weight`; 0: a sensor reading the contact force alone). ``com_m``: its centre of
    mass in the sensor frame (m), the lever arm of the weight's torque; the simulated wrist
    sensor reports forces only (a weight is the same force wherever it acts), so no reading
    depends on it.
    """

    length_m: float = 0.12
    radius_m: float = 0.02
    name: str = "probe"
    mass_kg: float = 0.0
    com_m: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        if not self.mass_kg >= 0.0:
            raise ConfigError(f"mass_kg must be >= 0 (got {self.mass_kg})")


def tool_weight(mass_kg: float, rotation: Vec) -> Vec:
    """The tool's weight as the wrist sensor reads it (N, sensor frame).

    The sensor reports the force the wrist exerts on the tool in the sign of the contact force
    (what the tool exerts on the environment), so a tool of mass ``m`` adds
    ``-m * R^T g`` with ``g = (0, 0, -9.80665)`` m/s^2 in the base frame (z up) and ``R`` the
    base-from-sensor rotation: a hanging tool pointing down reads ``-m*g`` along its axis.
    """
    return np.asarray(-mass_kg * (rotation.T @ np.array([0.0, 0.0, -GRAVITY_M_S2])))


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

    def settle(self, force: Vec) -> None:
        """Start the filter at rest on ``force`` (a sensor powered on long before the run, as
        a tool's weight has been on it)."""
        self._filtered = np.array(force, dtype=np.float64)

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
            bias = np.asarray(self.model.bias_n) + np.asarray(self.model.bias_drift_n_per_s) * t_s
            self._latest = self._filtered + bias + noise
            self._fresh = True
            self._next_t += 1.0 / self.model.rate_hz

    def read(self) -> Vec:
        """The newest sample (task frame, N) not yet read, else NaN in every component."""
        if not self._fresh:
            return np.full(3, np.nan)
        self._fresh = False
        return self._latest.copy()


def sensor_noise(noise_std_n: float, seed: int, samples: int) -> Vec:
    """The noise of ``samples`` sensor samples, ``(samples, 3)``: the stream :class:`ForceSensor`
    seeded with ``seed`` draws, in its order (the compiled loops draw it up front)."""
    if noise_std_n <= 0.0:
        return np.zeros((samples, 3))
    rng = np.random.default_rng(seed)
    return rng.normal(0.0, noise_std_n, (samples, 3))


def padded_terms(
    term_lists: Sequence[Sequence[tuple[float, float, float]]],
) -> tuple[Vec, npt.NDArray[np.int64]]:
    """Objects' roughness terms as the compiled loops read them: ``(k, w, 3)`` rows padded with
    zeros to the longest list (``w`` at least 1), and each object's count, ``(k,)``."""
    width = max([1, *(len(t) for t in term_lists)])
    terms = np.zeros((len(term_lists), width, 3))
    counts = np.zeros(len(term_lists), dtype=np.int64)
    for i, rows in enumerate(term_lists):
        counts[i] = len(rows)
        if rows:
            terms[i, : len(rows)] = rows
    return terms, counts
