"""The per-period skeleton every compiled loop runs around its plant's step, written once.

A compiled loop (:mod:`~fuzzkit.loop.compiled.arm6_run`, :mod:`~fuzzkit.loop.compiled.planar_run`,
:mod:`~fuzzkit.loop.compiled.mujoco_run`) starts its latency queues with :func:`start_queues`,
turns the applied correction into the base frame with :func:`to_base`, steps its plant, then
runs :func:`controller_period` (faults, the sensor queue, the generated controller, the command
queue: :mod:`fuzzkit.loop.compiled.period`) and records the controller's series with
:func:`record_controller`; what it records of its plant is its own.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.jit import jit
from fuzzkit.loop.compiled.generated_controller import generated_step
from fuzzkit.loop.compiled.period import (
    C_COMMAND_DELAY,
    C_SENSOR_DELAY,
    V_DE,
    V_DU,
    V_E,
    command_latency,
    inject_faults,
    sensor_latency,
)

FloatArray = npt.NDArray[np.float64]


@jit
def start_queues(
    cp: FloatArray, reset_force: FloatArray, rot: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(sensor queue, command queue, rotation)`` at the start of a run: the sensor queue full
    of the reset sample's force, the command queue of zeros (as the Python loop starts them),
    and the task frame ``rot`` (base-from-task) row-major, as the generated controller reads the
    tool's rotation."""
    sd = int(cp[C_SENSOR_DELAY])
    sensor_q = np.empty((sd + 1, 3))
    for k in range(sd + 1):
        sensor_q[k, :] = reset_force
    command_q = np.zeros((int(cp[C_COMMAND_DELAY]) + 1, 3))
    c_rot = np.empty(9)
    for j in range(9):
        c_rot[j] = rot[j // 3, j % 3]
    return sensor_q, command_q, c_rot


@jit
def to_base(rot: FloatArray, v: FloatArray, out: FloatArray) -> None:
    """``out = rot @ v`` (a task-frame vector in the base frame), each row summed in index
    order."""
    for j in range(3):
        out[j] = rot[j, 0] * v[0] + rot[j, 1] * v[1] + rot[j, 2] * v[2]


@jit
def controller_period(
    k: int,
    cp: FloatArray,
    spike_sign: float,
    nan_sample: bool,
    t_s: float,
    f_meas: FloatArray,
    measured: FloatArray,
    sensor_q: FloatArray,
    reset_force: FloatArray,
    c_step: Any,
    c_state: FloatArray,
    c_rot: FloatArray,
    selection: FloatArray,
    setpoints: FloatArray,
    cs: FloatArray,
    cv: FloatArray,
    correction: FloatArray,
    command_q: FloatArray,
    applied: FloatArray,
) -> tuple[int, FloatArray]:
    """Period ``k`` after the plant's step measured ``f_meas`` at ``t_s``: the faults into
    ``measured``, the sensor queue, the generated controller (its ``correction``), the command
    queue (``applied``, for the next period); returns ``(status, the consumed sample)``."""
    inject_faults(cp, spike_sign, nan_sample, t_s, f_meas, measured)
    # before the first measurement arrives (k < sd) the controller waits: no fault counted
    consumed = sensor_latency(k, int(cp[C_SENSOR_DELAY]), sensor_q, measured, reset_force)
    status = generated_step(
        c_step, c_state, c_rot, cp, selection, setpoints, consumed, t_s, cs, cv, correction
    )
    command_latency(k, int(cp[C_COMMAND_DELAY]), command_q, correction, applied)
    return status, consumed


@jit
def record_controller(
    k: int,
    consumed: FloatArray,
    measured: FloatArray,
    f_true: FloatArray,
    cv: FloatArray,
    correction: FloatArray,
    r_force: FloatArray,
    r_force_sensor: FloatArray,
    r_force_true: FloatArray,
    r_e: FloatArray,
    r_de: FloatArray,
    r_du: FloatArray,
    r_u: FloatArray,
) -> None:
    """Row ``k`` of the series every loop records: the consumed and the delivered sample, the
    true force, the controller's ``e``, ``de``, ``du`` and its correction."""
    for j in range(3):
        r_force[k, j] = consumed[j]
        r_force_sensor[k, j] = measured[j]
        r_force_true[k, j] = f_true[j]
        r_e[k, j] = cv[V_E, j]
        r_de[k, j] = cv[V_DE, j]
        r_du[k, j] = cv[V_DU, j]
        r_u[k, j] = correction[j]
