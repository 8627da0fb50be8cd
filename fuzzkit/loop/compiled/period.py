"""The plant-independent part of one compiled period, shared by every compiled loop.

Per period, as :func:`fuzzkit.loop.python_loop.run` does it (the cross-branch timing agreement):
the plant's measured force -> :func:`inject_faults` -> :func:`sensor_latency` (the controller
consumes the sample of ``sensor_delay`` periods ago, a delay fault's periods included; the queue
starts filled with the reset sample's force) -> the controller -> :func:`command_latency` (the
plant receives the correction computed ``command_delay`` periods ago; the queue starts with
zeros). The plant kernels (:mod:`fuzzkit.loop.compiled.arm6_run` for arm6,
:mod:`fuzzkit.loop.compiled.planar_run` for the pymunk arm,
:mod:`fuzzkit.loop.compiled.mujoco_run` for MuJoCo) wrap their plant step with these, through
:mod:`fuzzkit.loop.compiled.skeleton`.

The controller is the run's controller spec generated as C (double) and called by address,
:func:`fuzzkit.loop.compiled.generated_controller.generated_step`: what ``fuzzkit compile``
emits is what the loop runs; the loop holds no controller logic of its own (one arithmetic,
issue 28). What stays here is the loop's bookkeeping around it, in two arrays made by
:func:`controller_state`: scalars ``cs`` (``CS_*``: engagement and trip times, the fault
count) and 3-vectors ``cv`` (rows ``V_*``: the recorded ``e``, ``de``, ``du``, ``u``).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from fuzzkit.jit import jit, jit_inline

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]

# The loop's parameter vector (``cp``): what the loop itself does around the controller
C_ENGAGE_THR, C_HOLD, C_PERIOD = 0, 1, 2  # engage threshold NaN: engaged from the start
C_SENSOR_DELAY, C_COMMAND_DELAY = 3, 4  # the fault's delay included in the sensor delay
C_DROPOUT_START, C_DROPOUT_LENGTH, C_SPIKE_N = 5, 6, 7
C_OFFSET_START, C_OFFSET_LENGTH, C_OFFSET_N = 8, 9, 10  # the offset fault (start NaN: none)
N_CP = 11

# Scalar results (``out_scalars``)
R_FAULTS, R_TRIPPED, R_TRIP_TIME, R_ENGAGED_TIME = 0, 1, 2, 3
N_RESULTS = 4

# The loop's scalar bookkeeping (``cs``); flags are 0.0 / 1.0, times NaN until they happen
CS_FAULTS, CS_ENGAGED, CS_TRIPPED, CS_TRIP_TIME, CS_CTRL_T = 0, 1, 2, 3, 4
CS_ENGAGED_AT, CS_HAS_E_LAST = 5, 6
N_CS = 7

# The loop's recorded vectors (rows of ``cv``)
V_U, V_E, V_DE, V_DU, V_E_LAST = 0, 1, 2, 3, 4
N_CV = 5


@jit
def controller_state(cp: FloatArray) -> tuple[FloatArray, FloatArray]:
    """A fresh bookkeeping state ``(cs, cv)``: nothing seen, engaged at once without threshold."""
    cs = np.zeros(N_CS)
    cs[CS_ENGAGED] = 1.0 if math.isnan(cp[C_ENGAGE_THR]) else 0.0
    cs[CS_TRIP_TIME] = math.nan
    cs[CS_ENGAGED_AT] = math.nan
    return cs, np.zeros((N_CV, 3))


@jit_inline
def path_held(cp: FloatArray, cs: FloatArray) -> bool:
    """The runner's rule: the path stops after a trip, or once engaged in a hold experiment."""
    return cs[CS_TRIPPED] > 0.0 or (
        cp[C_HOLD] > 0.0 and cs[CS_ENGAGED] > 0.0 and not math.isnan(cs[CS_ENGAGED_AT])
    )


@jit_inline
def inject_faults(
    cp: FloatArray,
    spike_sign: float,
    nan_sample: bool,
    t_s: float,
    f_meas: FloatArray,
    measured: FloatArray,
) -> None:
    """``FaultInjector``: ``measured`` = ``f_meas`` with this period's spike, offset, NaN or
    dropout."""
    for j in range(3):
        measured[j] = f_meas[j]
    if spike_sign != 0.0:
        s = spike_sign * cp[C_SPIKE_N]
        measured[0] += s * 1.0
        measured[1] += s * 0.0
        measured[2] += s * 1.0
    start = cp[C_OFFSET_START]
    if not math.isnan(start) and start <= t_s < start + cp[C_OFFSET_LENGTH]:
        measured[2] += cp[C_OFFSET_N]
    if nan_sample:
        measured[:] = np.nan
    start = cp[C_DROPOUT_START]
    if not math.isnan(start) and start <= t_s < start + cp[C_DROPOUT_LENGTH]:
        measured[:] = np.nan


@jit_inline
def sensor_latency(
    k: int, sd: int, sensor_q: FloatArray, measured: FloatArray, reset_force: FloatArray
) -> FloatArray:
    """Push period ``k``'s sample into the ring ``sensor_q`` (``sd + 1`` rows); the one the
    controller consumes: ``sd`` periods old, the reset sample's force before that."""
    sensor_q[k % (sd + 1), :] = measured
    if sd == 0:
        return measured
    if k + 1 <= sd:
        return reset_force
    oldest: FloatArray = sensor_q[(k + 1) % (sd + 1)]
    return oldest


@jit_inline
def command_latency(
    k: int, cd: int, command_q: FloatArray, correction: FloatArray, applied: FloatArray
) -> None:
    """Push period ``k``'s correction into the ring ``command_q``; ``applied`` = the one
    computed ``cd`` periods ago (zeros before that)."""
    command_q[k % (cd + 1), :] = correction
    if cd == 0:
        applied[:] = correction
    elif k + 1 <= cd:
        applied[:] = 0.0
    else:
        applied[:] = command_q[(k + 1) % (cd + 1)]


@jit_inline
def error_change(cs: FloatArray, cv: FloatArray) -> None:
    """After the axes stepped: ``de = e - e_last`` (0 the first time), then ``e_last = e``."""
    e, de, e_last = cv[V_E], cv[V_DE], cv[V_E_LAST]
    has_e_last = cs[CS_HAS_E_LAST] > 0.0
    for i in range(3):
        de[i] = e[i] - e_last[i] if has_e_last else 0.0
        e_last[i] = e[i]
    cs[CS_HAS_E_LAST] = 1.0


@jit_inline
def credit_normal(rot: FloatArray, nx: float, ny: float, nz: float, out: FloatArray) -> None:
    """``normal_force_by_axis`` for one contact: add its base-frame normal force ``(nx, ny,
    nz)``, in the task frame (``rot`` base-from-task), to the task axis it lies closest to."""
    best = 0
    best_abs = -1.0
    best_v = 0.0
    for j in range(3):
        tv = rot[0, j] * nx + rot[1, j] * ny + rot[2, j] * nz
        if abs(tv) > best_abs:
            best, best_abs, best_v = j, abs(tv), tv
    out[best] += best_v


@jit
def store_results(cs: FloatArray, out_scalars: FloatArray) -> None:
    """The run's scalar results (``R_*``) from the final controller state."""
    out_scalars[R_FAULTS] = cs[CS_FAULTS]
    out_scalars[R_TRIPPED] = cs[CS_TRIPPED]
    out_scalars[R_TRIP_TIME] = cs[CS_TRIP_TIME]
    out_scalars[R_ENGAGED_TIME] = cs[CS_ENGAGED_AT]
