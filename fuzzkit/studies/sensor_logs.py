"""Synthetic wrist-sensor logs that stress a controller: random, and hostile on purpose.

Each segment is what a controller sees from reset: the raw sensor reading (N, task frame,
NaN = missing) and the tool's rotation (world-from-sensor, row-major), built as
``f_raw = contact + m*g*(r31, r32, r33) + bias`` (``docs/controller.md``) so that a spec with
gravity compensation and tare recovers the contact force. They are inputs, not expected
values: the generated controllers and the reference are run on them and compared.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from fuzzkit.control.spec import STANDARD_GRAVITY_M_S2, ControllerSpec

FloatArray = npt.NDArray[np.float64]
Log = tuple[FloatArray, FloatArray]

#: The segments of :func:`hostile_segments`, in order.
SEGMENTS = (
    "random",
    "spike_trains",
    "nan_bursts",
    "dropouts",
    "setpoint_steps",
    "tilted_tool",
    "sustained_over_limit",
)


def _rotation_x(theta: float) -> FloatArray:
    """The tool pointing down (``diag(1, -1, -1)``) turned by ``theta`` about its x axis."""
    c, s = math.cos(theta), math.sin(theta)
    down = np.diag([1.0, -1.0, -1.0])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    turned: FloatArray = down @ rx
    return turned


def _raw(
    spec: ControllerSpec, contact: FloatArray, rotations: FloatArray, bias: FloatArray
) -> FloatArray:
    tool = spec.sensor.tool
    mass = 0.0 if tool is None else tool.mass_kg
    weight = mass * STANDARD_GRAVITY_M_S2 * rotations[:, 6:9]
    return contact + weight + bias


def _segment(
    spec: ControllerSpec, rng: np.random.Generator, n: int, tilt: FloatArray | None = None
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Free air for the tare, then contact near the set points with noise: contact, rotations,
    bias (the raw reading is built from them by :func:`_raw`)."""
    tare = spec.sensor.tare_samples
    angles = np.zeros(n) if tilt is None else tilt
    rotations = np.array([_rotation_x(float(a)).ravel() for a in angles])
    bias = np.tile(rng.normal(0.0, 2.0, 3), (n, 1))
    contact = np.tile(np.array(spec.setpoints), (n, 1)) + rng.normal(0.0, 0.4, (n, 3))
    ramp = np.clip((np.arange(n) - tare - 5) / 20.0, 0.0, 1.0)[:, None]
    contact = contact * ramp + rng.normal(0.0, 0.05, (n, 3)) * (1.0 - ramp)
    return contact, rotations, bias


def hostile_segments(spec: ControllerSpec, n: int = 400, seed: int = 0) -> dict[str, Log]:
    """One log per kind of trouble (:data:`SEGMENTS`), each ``(forces (n, 3), rotations (n, 9))``.

    * random: noise around the set points, 3 % of the cells NaN;
    * spike_trains: isolated spikes and trains of 2-6 consecutive spikes of +-(1.5-4) x the
      spike gate on random axes (shorter trains are rejected, longer ones accepted), and in
      free air during the tare a lone spike and a train the gate confirms;
    * nan_bursts: runs of 1-12 samples with NaN on one or all axes, and +-inf;
    * dropouts: whole samples missing (every axis NaN), rotation NaN for some samples;
    * setpoint_steps: the contact force stepping by up to +-0.8 x the safety limit;
    * tilted_tool: the tool swinging +-60 degrees about x while in contact;
    * sustained_over_limit: contact rising past the safety limit and staying there (trip,
      back-off), with NaN and spikes after the trip.
    """
    rng = np.random.default_rng(seed)
    limit = spec.safety.limit_n
    gate = spec.safety.spike_gate
    out: dict[str, Log] = {}
    for name in SEGMENTS:
        tilt = None
        if name == "tilted_tool":
            tilt = (math.pi / 3.0) * np.sin(np.arange(n) * (2.0 * math.pi / 150.0))
        contact, rot, bias = _segment(spec, rng, n, tilt)
        start = spec.sensor.tare_samples + 30
        if name == "random":
            pass
        elif name == "spike_trains":
            # in free air too: a lone spike the tare must not average in, and a train long
            # enough for the gate to confirm it (which restarts the tare)
            contact[3, 2] += 2.0 * gate
            contact[8 : 8 + spec.safety.spike_confirm + 3, 0] -= 1.5 * gate
            k = start
            while k < n - 10:
                length = int(rng.integers(1, 7))
                axis = int(rng.integers(0, 3))
                sign = 1.0 if rng.random() < 0.5 else -1.0
                contact[k : k + length, axis] += sign * gate * rng.uniform(1.5, 4.0)
                k += length + int(rng.integers(5, 25))
        elif name == "setpoint_steps":
            for k in range(start, n, 60):
                contact[k:, :] += rng.uniform(-0.8, 0.8, 3) * limit * 0.5
            contact = np.clip(contact, -0.8 * limit, 0.8 * limit)
        elif name == "sustained_over_limit":
            k = min(start + 40, n)
            rise = np.linspace(0.0, 1.6 * limit, 30)[: n - k]
            contact[k : k + rise.size, 2] = rise
            contact[k + rise.size :, 2] = 1.6 * limit
        raw = _raw(spec, contact, rot.copy(), bias)
        if name == "random":
            raw[rng.random(raw.shape) < 0.03] = math.nan
        elif name == "nan_bursts":
            k = start
            while k < n - 15:
                length = int(rng.integers(1, 13))
                if rng.random() < 0.5:
                    raw[k : k + length, int(rng.integers(0, 3))] = math.nan
                else:
                    raw[k : k + length, :] = math.nan
                k += length + int(rng.integers(3, 30))
            raw[start + 5, 0] = math.inf
            raw[start + 9, 2] = -math.inf
        elif name == "dropouts":
            drop = rng.random(n) < 0.1
            raw[drop, :] = math.nan
            rot[rng.random(n) < 0.03, 4] = math.nan
        elif name == "sustained_over_limit":
            raw[-40:-35, :] = math.nan
            raw[-20, 2] += 3.0 * gate
        out[name] = (raw, rot)
    return out


def hostile_log(spec: ControllerSpec, n: int = 400, seed: int = 0) -> Log:
    """Every segment of :func:`hostile_segments` end to end (the trip comes last)."""
    parts = hostile_segments(spec, n, seed)
    forces = np.vstack([parts[name][0] for name in SEGMENTS])
    rotations = np.vstack([parts[name][1] for name in SEGMENTS])
    return forces, rotations
