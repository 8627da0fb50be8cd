"""The whole closed-loop run on the arm6 plant as one compiled loop over periods.

Per period: the compiled plant step (:func:`fuzzkit.plants.arm6_period.plant_step`), then the
plant-independent part shared with the planar loop (:mod:`fuzzkit.loop.compiled.period`:
fault injection, latency queues, the hybrid controller), then recording.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.jit import jit
from fuzzkit.loop.compiled.period import (
    C_PERIOD,
    controller_state,
    credit_normal,
    path_held,
    store_results,
)
from fuzzkit.loop.compiled.skeleton import (
    controller_period,
    record_controller,
    start_queues,
    to_base,
)
from fuzzkit.plants.arm6_period import plant_step, pose_at

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]


@jit
def run_arm6(
    # plant (see fuzzkit.plants.arm6_period.Arm6Arrays)
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
    # the generated NAME_controller_step (ctypes) and its state
    c_step: Any,
    c_state: FloatArray,
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
    r_status: IntArray,
    out_scalars: FloatArray,
) -> None:
    """Run ``r_t.shape[0]`` periods; fill the recording arrays and ``out_scalars``."""
    n_periods = r_t.shape[0]
    dof = q.shape[0]
    n_obj = a_kind.shape[0]
    period = cp[C_PERIOD]
    cs, cv = controller_state(cp)
    sensor_q, command_q, c_rot = start_queues(cp, reset_force, a_rot_task)
    applied = np.zeros(3)
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
    path_t = 0.0
    for k in range(n_periods):
        path_before = path_t
        if not path_held(cp, cs):
            path_t += period
        to_base(a_rot_task, applied, corr_base)
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
        r_status[k], consumed = controller_period(
            k, cp, spike_sign[k], nan_flag[k], t_s, f_meas, measured, sensor_q, reset_force,
            c_step, c_state, c_rot, selection, setpoints, cs, cv, correction, command_q, applied,
        )  # fmt: skip
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
        record_controller(
            k, consumed, measured, f_true, cv, correction,
            r_force, r_force_sensor, r_force_true, r_e, r_de, r_du, r_u,
        )  # fmt: skip
        for j in range(3):
            r_tool[k, j] = tcp[j] - a_offset[j]
            r_nominal[k, j] = nominal[j] - a_offset[j]
            r_target[k, j] = nominal[j] + corr_base[j] - a_offset[j]
            r_force_normal[k, j] = 0.0
        for c in range(count):
            for j in range(3):
                r_points[k, c, j] = points[c, j] - a_offset[j]
            credit_normal(
                a_rot_task, normals[c, 0], normals[c, 1], normals[c, 2], r_force_normal[k]
            )
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
    store_results(cs, out_scalars)
