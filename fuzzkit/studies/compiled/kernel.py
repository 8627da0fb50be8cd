"""The whole closed-loop run as one compiled loop over periods (arm6 plant).

Per period, as :func:`fuzzkit.studies.runner.run` does it (the cross-branch timing agreement):
``plant.step(applied correction)`` -> measured force -> fault injection -> sensor-latency queue
(the controller consumes the sample of ``sensor_delay`` periods ago, a delay fault's periods
included; the queue starts filled with the reset sample's force) -> hybrid controller ->
command-latency queue (the plant receives the correction computed ``command_delay`` periods
ago; the queue starts with zeros) -> recording.

The controller is :class:`fuzzkit.control.controllers.HybridForceController` (spike gate,
debounced engagement, trip rule, back-off, sensor faults) over PI or fuzzy-PI
axis controllers, the fuzzy surface being a double lookup table
(:mod:`fuzzkit.studies.compiled.table`) or, when ``c_eval`` is a ctypes function, the generated
C itself (:mod:`fuzzkit.studies.compiled.generated_c`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.jit import jit
from fuzzkit.plants.arm6_kernel import plant_step, pose_at
from fuzzkit.studies.compiled.generated_c import call_c_surface
from fuzzkit.studies.compiled.table import table2

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]

KIND_PI, KIND_FUZZY = 0, 1

# Controller parameter vector (``cp``)
C_KIND, C_KP, C_KI, C_KX, C_UMIN, C_UMAX, C_RATE = 0, 1, 2, 3, 4, 5, 6
C_FORCE_LIMIT, C_ENGAGE_THR, C_TRIP_SAMPLES, C_BACKOFF, C_BACKOFF_SPEED = 7, 8, 9, 10, 11
C_ENGAGE_SAMPLES, C_HOLD, C_PERIOD = 12, 13, 14
C_SENSOR_DELAY, C_COMMAND_DELAY = 15, 16  # the fault's delay included in the sensor delay
C_DROPOUT_START, C_DROPOUT_LENGTH, C_SPIKE_N = 17, 18, 19
C_SPIKE_GATE, C_SPIKE_CONFIRM = 20, 21
N_CP = 22

# Scalar results (``out_scalars``)
R_FAULTS, R_TRIPPED, R_TRIP_TIME, R_ENGAGED_TIME = 0, 1, 2, 3
N_RESULTS = 4


@jit
def _axis_increment(
    cp: FloatArray,
    bp0: FloatArray,
    bp1: FloatArray,
    tab: FloatArray,
    splits: IntArray,
    c_eval: Any,
    c_io: FloatArray,
    e: float,
    de: float,
) -> float:
    if int(cp[C_KIND]) == KIND_PI:
        return float(cp[C_KP] * de + cp[C_KI] * e)
    en = min(max(cp[C_KI] * e, -1.0), 1.0)
    den = min(max(cp[C_KP] * de, -1.0), 1.0)
    if c_eval is None:  # a compile-time branch: c_eval is typed None or a C function
        return float(cp[C_KX] * table2(bp0, bp1, tab, splits, en, den))
    return float(cp[C_KX] * call_c_surface(c_eval, c_io, en, den))


@jit
def run_arm6(
    # plant (see fuzzkit.plants.arm6_kernel.Arm6Arrays)
    a_links: FloatArray,
    a_tool_r: FloatArray,
    a_tool_p: FloatArray,
    a_lower: FloatArray,
    a_upper: FloatArray,
    a_dq_max: FloatArray,
    a_path_t: FloatArray,
    a_path_pos: FloatArray,
    a_path_quat: FloatArray,
    a_kind: IntArray,
    a_p: FloatArray,
    a_terms: FloatArray,
    a_nterms: IntArray,
    a_grid: FloatArray,
    a_rot_task: FloatArray,
    a_offset: FloatArray,
    params: FloatArray,
    q: FloatArray,
    q_ref: FloatArray,
    q_ik: FloatArray,
    stick: FloatArray,
    state: FloatArray,
    noise: FloatArray,
    reset_force: FloatArray,
    # controller
    cp: FloatArray,
    selection: FloatArray,
    setpoints: FloatArray,
    bp0: FloatArray,
    bp1: FloatArray,
    tab: FloatArray,
    splits: IntArray,
    c_eval: Any,  # None: the table above; a generated C's NAME_eval (ctypes): that instead
    # faults, one entry per period: spike sign (0: none), NaN sample
    spike_sign: FloatArray,
    nan_flag: BoolArray,
    # recording, one row per period
    r_t: FloatArray,
    r_force: FloatArray,
    r_force_sensor: FloatArray,
    r_force_true: FloatArray,
    r_e: FloatArray,
    r_de: FloatArray,
    r_du: FloatArray,
    r_u: FloatArray,
    r_tool: FloatArray,
    r_nominal: FloatArray,
    r_target: FloatArray,
    r_joints: FloatArray,
    r_contact: BoolArray,
    r_force_normal: FloatArray,
    r_moving: BoolArray,
    r_ik: IntArray,
    r_limited: BoolArray,
    r_arm: FloatArray,
    r_points: FloatArray,
    r_npoints: IntArray,
    out_scalars: FloatArray,
) -> None:
    """Run ``r_t.shape[0]`` periods; fill the recording arrays and ``out_scalars``."""
    n_periods = r_t.shape[0]
    dof = q.shape[0]
    n_obj = a_kind.shape[0]
    period = cp[C_PERIOD]
    sd = int(cp[C_SENSOR_DELAY])
    cd = int(cp[C_COMMAND_DELAY])
    hold = cp[C_HOLD] > 0.0
    engage_thr = cp[C_ENGAGE_THR]  # NaN: engaged from the start
    rate = cp[C_RATE]  # NaN: no rate limit
    # controller state
    u = np.zeros(3)
    e = np.zeros(3)
    de = np.zeros(3)
    du = np.zeros(3)
    e_last = np.zeros(3)
    has_e_last = False
    ax_u = np.zeros(3)
    ax_prev = np.zeros(3)
    ax_has_prev = np.zeros(3, dtype=np.bool_)
    backoff = np.zeros(3)
    backoff_dir = np.zeros(3)
    faults = 0
    engaged = math.isnan(engage_thr)
    engage_count = 0
    spike_gate = cp[C_SPIKE_GATE]
    spike_confirm = int(cp[C_SPIKE_CONFIRM])
    accepted = np.zeros(3)
    has_accepted = False
    rejected_run = 0
    tripped = False
    trip_time = math.nan
    over = 0
    ctrl_t = 0.0
    engaged_at = math.nan
    # queues
    sensor_q = np.empty((sd + 1, 3))
    for k in range(sd + 1):
        sensor_q[k, :] = reset_force
    command_q = np.zeros((cd + 1, 3))
    applied = np.zeros(3)
    c_io = np.empty(3)
    correction = np.zeros(3)
    corr_base = np.zeros(3)
    # plant outputs
    nominal = np.empty(3)
    nominal_before = np.empty(3)
    quat_tmp = np.empty(4)
    tcp = np.empty(3)
    rot = np.empty((3, 3))
    origins = np.empty((dof, 3))
    f_true = np.empty(3)
    f_meas = np.empty(3)
    points = np.empty((max(n_obj, 1), 3))
    normals = np.empty((max(n_obj, 1), 3))
    measured = np.empty(3)
    f = np.empty(3)
    path_t = 0.0
    for k in range(n_periods):
        held = tripped or (hold and engaged and not math.isnan(engaged_at))
        path_before = path_t
        if not held:
            path_t += period
        for j in range(3):
            corr_base[j] = (
                a_rot_task[j, 0] * applied[0]
                + a_rot_task[j, 1] * applied[1]
                + a_rot_task[j, 2] * applied[2]
            )
        ik_status, count, limited = plant_step(
            a_links,
            a_tool_r,
            a_tool_p,
            a_lower,
            a_upper,
            a_dq_max,
            a_path_t,
            a_path_pos,
            a_path_quat,
            a_kind,
            a_p,
            a_terms,
            a_nterms,
            a_grid,
            a_rot_task,
            params,
            q,
            q_ref,
            q_ik,
            stick,
            state,
            noise,
            corr_base,
            path_t,
            nominal,
            tcp,
            rot,
            origins,
            f_true,
            f_meas,
            points,
            normals,
        )
        t_s = state[0]
        # ---- fault injection (fuzzkit.studies.faults.FaultInjector) ----
        for j in range(3):
            measured[j] = f_meas[j]
        if spike_sign[k] != 0.0:
            s = spike_sign[k] * cp[C_SPIKE_N]
            measured[0] += s * 1.0
            measured[1] += s * 0.0
            measured[2] += s * 1.0
        if nan_flag[k]:
            measured[:] = np.nan
        start = cp[C_DROPOUT_START]
        if not math.isnan(start) and start <= t_s < start + cp[C_DROPOUT_LENGTH]:
            measured[:] = np.nan
        # ---- sensor latency ----
        sensor_q[k % (sd + 1), :] = measured
        consumed = sensor_q[(k + 1) % (sd + 1)] if sd > 0 else measured
        if sd > 0 and k + 1 <= sd:
            consumed = reset_force
        # ---- hybrid controller (HybridForceController.step) ----
        ctrl_t += period
        du[:] = 0.0
        valid = True
        for i in range(3):
            if selection[i] > 0.0 and not math.isfinite(consumed[i]):
                valid = False
        if not valid:
            faults += 1
            engage_count = 0
        else:
            fmax = 0.0
            for i in range(3):
                f[i] = consumed[i] if math.isfinite(consumed[i]) else 0.0
                fmax = max(fmax, abs(f[i]))
            # spike gate (HybridForceController._plausible)
            plausible = True
            if has_accepted and rejected_run < spike_confirm:
                jump = 0.0
                for i in range(3):
                    jump = max(jump, abs(f[i] - accepted[i]))
                if jump > spike_gate:
                    rejected_run += 1
                    plausible = False
            if plausible:
                for i in range(3):
                    accepted[i] = f[i]
                has_accepted = True
                rejected_run = 0
            if not tripped:
                # the trip sees every finite sample, gated or not
                over = over + 1 if fmax > cp[C_FORCE_LIMIT] else 0
                if over >= (int(cp[C_TRIP_SAMPLES]) if plausible else spike_confirm):
                    tripped = True
                    trip_time = ctrl_t
                    nf = math.sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2])
                    for i in range(3):
                        backoff_dir[i] = -f[i] / nf if nf > 0.0 else 0.0
            if not plausible and not tripped:
                faults += 1
                engage_count = 0
            elif tripped:
                step = cp[C_BACKOFF_SPEED] * period
                nb = math.sqrt(backoff[0] ** 2 + backoff[1] ** 2 + backoff[2] ** 2)
                if nb < cp[C_BACKOFF]:
                    for i in range(3):
                        backoff[i] = backoff[i] + step * backoff_dir[i]
            else:
                go = True
                if not engaged:
                    engage_count = engage_count + 1 if fmax > engage_thr else 0
                    if engage_count < int(cp[C_ENGAGE_SAMPLES]):
                        go = False
                    else:
                        engaged = True
                if go:
                    for i in range(3):
                        if selection[i] <= 0.0:
                            continue
                        before = u[i]
                        # _Incremental.step of the axis controller
                        ei = setpoints[i] - f[i]
                        dei = ei - ax_prev[i] if ax_has_prev[i] else 0.0
                        ax_prev[i] = ei
                        ax_has_prev[i] = True
                        inc = _axis_increment(cp, bp0, bp1, tab, splits, c_eval, c_io, ei, dei)
                        if not math.isfinite(inc):
                            inc = 0.0
                        if not math.isnan(rate):
                            inc = min(max(inc, -rate), rate)
                        ax_u[i] = min(max(ax_u[i] + inc, cp[C_UMIN]), cp[C_UMAX])
                        u[i] = ax_u[i]
                        du[i] = u[i] - before
                        e[i] = setpoints[i] - f[i]
                    for i in range(3):
                        de[i] = e[i] - e_last[i] if has_e_last else 0.0
                        e_last[i] = e[i]
                    has_e_last = True
        for i in range(3):
            correction[i] = selection[i] * u[i] + backoff[i]
        if engaged and math.isnan(engaged_at):
            engaged_at = t_s
        # ---- command latency ----
        command_q[k % (cd + 1), :] = correction
        if cd == 0:
            applied[:] = correction
        elif k + 1 <= cd:
            applied[:] = 0.0
        else:
            applied[:] = command_q[(k + 1) % (cd + 1)]
        # ---- recording ----
        moving = False
        if path_t > path_before:
            pose_at(a_path_t, a_path_pos, a_path_quat, path_before, nominal_before, quat_tmp)
            for j in range(3):
                if abs(nominal[j] - nominal_before[j]) > 1e-9:
                    moving = True
        r_t[k] = t_s
        r_moving[k] = moving
        r_ik[k] = ik_status
        r_limited[k] = limited
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
            r_tool[k, j] = tcp[j] - a_offset[j]
            r_nominal[k, j] = nominal[j] - a_offset[j]
            r_target[k, j] = nominal[j] + corr_base[j] - a_offset[j]
            r_force_normal[k, j] = 0.0
        for c in range(count):
            for j in range(3):
                r_points[k, c, j] = points[c, j] - a_offset[j]
            # normal_force_by_axis: credit each contact's normal force to its closest task axis
            best = 0
            best_abs = -1.0
            tv = np.empty(3)
            for j in range(3):
                tv[j] = (
                    a_rot_task[0, j] * normals[c, 0]
                    + a_rot_task[1, j] * normals[c, 1]
                    + a_rot_task[2, j] * normals[c, 2]
                )
                if abs(tv[j]) > best_abs:
                    best, best_abs = j, abs(tv[j])
            r_force_normal[k, best] += tv[best]
        for i in range(dof):
            r_joints[k, i] = q[i]
            for j in range(3):
                r_arm[k, i, j] = origins[i, j] - a_offset[j]
        # flange = TCP minus the tool offset (SerialChain.frames_of)
        for j in range(3):
            back_j = 0.0
            acc = 0.0
            for m in range(3):
                back_j = (
                    a_tool_r[0, m] * a_tool_p[0]
                    + a_tool_r[1, m] * a_tool_p[1]
                    + a_tool_r[2, m] * a_tool_p[2]
                )
                acc += rot[j, m] * back_j
            r_arm[k, dof, j] = tcp[j] - acc - a_offset[j]
            r_arm[k, dof + 1, j] = tcp[j] - a_offset[j]
    out_scalars[R_FAULTS] = faults
    out_scalars[R_TRIPPED] = 1.0 if tripped else 0.0
    out_scalars[R_TRIP_TIME] = trip_time
    out_scalars[R_ENGAGED_TIME] = engaged_at
