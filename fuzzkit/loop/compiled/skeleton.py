"""The per-period skeleton every compiled loop shares, written once: the loop's start-up state,
the path's clock, the correction into the base frame, the plant-independent part of a period
(faults -> sensor latency -> the generated controller -> command latency) and the recording
of what every plant records alike. A plant's loop over periods (``arm6_run``, ``planar_run``)
is its plant step between :func:`period_start` and :func:`controller_period`, then its own
recording beside :func:`record_period`."""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.jit import jit, jit_inline
from fuzzkit.loop.compiled.generated_controller import generated_step
from fuzzkit.loop.compiled.period import (
    C_COMMAND_DELAY,
    C_PERIOD,
    C_SENSOR_DELAY,
    V_DE,
    V_DU,
    V_E,
    command_latency,
    controller_state,
    inject_faults,
    path_held,
    sensor_latency,
)

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]
IntArray = npt.NDArray[np.int64]

#: What :func:`loop_state` makes: ``(cs, cv, sensor_q, command_q, applied, correction, c_rot,
#: corr_base)``.
LoopState = tuple[
    FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray
]


@jit
def loop_state(cp: FloatArray, reset_force: FloatArray, rot: FloatArray) -> LoopState:
    """The loop's state before period 0: the bookkeeping (``cs``, ``cv``), the sensor queue
    filled with the reset sample's force, the command queue and the applied correction at
    zero, the tool's rotation ``rot`` (base-from-task) row-major for the generated controller,
    and the correction in the base frame."""
    cs, cv = controller_state(cp)
    sd = int(cp[C_SENSOR_DELAY])
    sensor_q = np.empty((sd + 1, 3))
    for k in range(sd + 1):
        sensor_q[k, :] = reset_force
    command_q = np.zeros((int(cp[C_COMMAND_DELAY]) + 1, 3))
    c_rot = np.empty(9)
    for j in range(9):
        c_rot[j] = rot[j // 3, j % 3]
    return cs, cv, sensor_q, command_q, np.zeros(3), np.zeros(3), c_rot, np.zeros(3)


@jit_inline
def period_start(
    cp: FloatArray,
    cs: FloatArray,
    path_t: float,
    rot: FloatArray,
    applied: FloatArray,
    corr_base: FloatArray,
) -> float:
    """A period's start: the path time it runs to (the runner's rule, :func:`path_held`), and
    ``corr_base``, the applied correction in the base frame (``rot`` base-from-task)."""
    if not path_held(cp, cs):
        path_t += cp[C_PERIOD]
    for j in range(3):
        corr_base[j] = rot[j, 0] * applied[0] + rot[j, 1] * applied[1] + rot[j, 2] * applied[2]
    return path_t


@jit_inline
def controller_period(
    k: int,
    cp: FloatArray,
    spike_sign: float,
    nan_sample: bool,
    t_s: float,
    f_meas: FloatArray,
    measured: FloatArray,
    reset_force: FloatArray,
    c_step: Any,
    c_state: FloatArray,
    selection: FloatArray,
    setpoints: FloatArray,
    cs: FloatArray,
    cv: FloatArray,
    sensor_q: FloatArray,
    command_q: FloatArray,
    applied: FloatArray,
    correction: FloatArray,
    c_rot: FloatArray,
) -> tuple[int, FloatArray]:
    """The plant-independent part of period ``k`` after the plant stepped (its measured force
    ``f_meas`` at ``t_s``): faults into ``measured``, the sensor queue, the generated
    controller's step, the command queue. Returns the controller's status and the sample it
    consumed. Before the first measurement arrives (``k`` below the sensor delay) the
    controller waits on the reset sample: no fault counted. The state is
    :func:`loop_state`'s."""
    inject_faults(cp, spike_sign, nan_sample, t_s, f_meas, measured)
    consumed = sensor_latency(k, int(cp[C_SENSOR_DELAY]), sensor_q, measured, reset_force)
    status = generated_step(
        c_step, c_state, c_rot, cp, selection, setpoints, consumed, t_s, cs, cv, correction
    )
    command_latency(k, int(cp[C_COMMAND_DELAY]), command_q, correction, applied)
    return status, consumed


@jit_inline
def record_period(
    k: int,
    t_s: float,
    moving: bool,
    count: int,
    consumed: FloatArray,
    measured: FloatArray,
    f_true: FloatArray,
    cv: FloatArray,
    correction: FloatArray,
    r_t: FloatArray,
    r_moving: BoolArray,
    r_contact: BoolArray,
    r_npoints: IntArray,
    r_force: FloatArray,
    r_force_sensor: FloatArray,
    r_force_true: FloatArray,
    r_e: FloatArray,
    r_de: FloatArray,
    r_du: FloatArray,
    r_u: FloatArray,
    r_force_normal: FloatArray,
) -> None:
    """Row ``k`` of what every plant records alike: time, path motion, contact count, the
    forces (consumed, delivered, true), ``e``, ``de``, ``du``, ``u``; the normal force per axis
    starts at zero (the plant credits its contacts)."""
    e, de, du = cv[V_E], cv[V_DE], cv[V_DU]
    r_t[k] = t_s
    r_moving[k] = moving
    r_contact[k] = count > 0
    r_npoints[k] = count
    for j in range(3):
        r_force[k, j] = consumed[j]
        r_force_sensor[k, j] = measured[j]
        r_force_true[k, j] = f_true[j]
        r_e[k, j] = e[j]
        r_de[k, j] = de[j]
        r_du[k, j] = du[j]
        r_u[k, j] = correction[j]
        r_force_normal[k, j] = 0.0
