"""The whole closed-loop run on the MuJoCo IRB 140 as one compiled loop over periods.

Per period, with no Python: the inner loop's reference (the path pose, arm6's compiled IK,
the joint speed limit: :mod:`fuzzkit.plants.arm6_period`), the physics (MuJoCo's C library
called by address: ``fuzzkit_mj_steps`` with the servo ramp as the control callback,
:mod:`fuzzkit.plants.mujoco_servo`; a rough profile's block moved before each substep), the
tool's contact forces (``fuzzkit_tool_contacts``) and the wrist sensor model, then the
plant-independent part shared with the other compiled loops
(:mod:`fuzzkit.loop.compiled.period`: fault injection, latency queues, the generated
controller), then recording. The Python plant
(:class:`~fuzzkit.plants.mujoco_arm.MujocoArmPlant`) is the reference it is held to, bit for
bit (``tests/test_mujoco_compiled.py``); it computes the same doubles in the same order.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.jit import jit
from fuzzkit.loop.compiled.period import credit_normal, store_results
from fuzzkit.loop.compiled.skeleton import (
    controller_period,
    loop_state,
    period_start,
    record_period,
)
from fuzzkit.plants.arm6_period import ik, matrix_from_quat, pose_at
from fuzzkit.plants.rough_profile import profile_height_slope

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]

# Indices into the float parameter vector (``MujocoArrays.params``).
M_DT, M_TOL_P, M_TOL_O, M_IK_ITER, M_CUTOFF, M_RATE = 0, 1, 2, 3, 4, 5
M_BIAS = 6  # 3 values
M_HALF_THICKNESS = 9  # of a rough profile's block
N_M_PARAMS = 10

# Indices into the mutable state vector (``MujocoArrays.state``).
MS_T, MS_NEXT_SAMPLE, MS_FRESH, MS_NOISE_INDEX = 0, 1, 2, 3
MS_FILTERED = 4  # 3 values
MS_LATEST = 7  # 3 values
N_M_STATE = 10

# Indices into the integer layout vector (``MujocoArrays.layout``).
L_MODEL, L_DATA, L_TIP, L_NSUB = 0, 1, 2, 3
N_LAYOUT = 4

#: the most contacts of the tool a period records
MOST_CONTACTS = 8


@jit
def _follow_profiles(
    prof_p: FloatArray,
    prof_terms: FloatArray,
    prof_nterms: IntArray,
    prof_mocap: IntArray,
    offset: FloatArray,
    half_thickness: float,
    tip_x: float,
    mocap_pos: FloatArray,
    mocap_quat: FloatArray,
) -> None:
    """``MujocoArmPlant._follow_profiles`` (``mujoco_model.profile_pose`` per profile)."""
    x = tip_x - offset[0]
    for k in range(prof_mocap.shape[0]):
        mc = prof_mocap[k]
        if not prof_p[k, 0] <= x <= prof_p[k, 1]:
            mocap_pos[mc, 0], mocap_pos[mc, 1], mocap_pos[mc, 2] = 0.0, 0.0, -10.0
            mocap_quat[mc, 0], mocap_quat[mc, 1] = 1.0, 0.0
            mocap_quat[mc, 2], mocap_quat[mc, 3] = 0.0, 0.0
            continue
        h, slope = profile_height_slope(prof_p[k], prof_terms[k], prof_nterms[k], x)
        phi = -math.atan(slope)
        nx, nz = math.sin(phi), math.cos(phi)
        mocap_pos[mc, 0] = x - nx * half_thickness + offset[0]
        mocap_pos[mc, 1] = offset[1]
        mocap_pos[mc, 2] = h - nz * half_thickness + offset[2]
        mocap_quat[mc, 0] = math.cos(0.5 * phi)
        mocap_quat[mc, 1] = 0.0
        mocap_quat[mc, 2] = math.sin(0.5 * phi)
        mocap_quat[mc, 3] = 0.0


@jit
def run_mujoco(
    plant: tuple[Any, ...],
    noise: FloatArray,
    reset_force: FloatArray,
    mj: tuple[Any, ...],
    mj_steps: Any,
    tool_contacts: Any,
    ctrl: tuple[Any, ...],
    c_step: Any,
    rec: tuple[Any, ...],
    out_scalars: FloatArray,
) -> int:
    """Run up to as many periods as the recording has rows; fill it and ``out_scalars``.
    Returns the number of periods run: fewer when the simulation diverged (a bad acceleration
    or a non-finite state in the last period run).

    Named records, each unpacked once here: ``plant``, the arm's arrays in
    :class:`~fuzzkit.loop.mujoco.MujocoArrays` ``plant`` order; ``mj``, the ``MjData`` views;
    ``mj_steps``, ``tool_contacts``, the plant's C helpers; ``ctrl``, the controller's
    (:meth:`~fuzzkit.loop.compiled.common.ControllerArgs.record`); ``c_step``, the generated
    ``NAME_controller_step`` (ctypes); ``rec``, the recording
    (:func:`~fuzzkit.loop.compiled.common.recording`, the arm's ``ik``, ``limited`` and
    ``saturated`` last)."""
    (
        a_links, a_tool_r, a_tool_p, a_lower, a_upper, a_dq_max, a_path_t, a_path_pos,
        a_path_quat, a_rot_task, a_offset, a_kv_over_kp, a_servo_qpos, a_link_qpos, a_elastic,
        a_bodies, prof_p, prof_terms, prof_nterms, prof_mocap, params, layout, q_ref, q_ik,
        ref_prev, state, ik_work,
    ) = plant  # fmt: skip
    d_userdata, d_qpos, d_sensordata, d_geom_xpos, d_xpos, d_mocap_pos, d_mocap_quat = mj
    cp, selection, setpoints, c_state, spike_sign, nan_flag = ctrl
    (
        r_t, r_force, r_force_sensor, r_force_true, r_e, r_de, r_du, r_u, r_tool, r_nominal,
        r_target, r_joints, r_contact, r_force_normal, r_moving, r_arm, r_points, r_npoints,
        r_status, r_ik, r_limited, r_saturated,
    ) = rec  # fmt: skip
    n_periods = r_t.shape[0]
    dof = q_ref.shape[0]
    nu = ref_prev.shape[0]
    n_bodies = a_bodies.shape[0]
    dt = params[M_DT]
    m_addr, d_addr = np.uint64(layout[L_MODEL]), np.uint64(layout[L_DATA])
    tip, n_sub = layout[L_TIP], layout[L_NSUB]
    cs, cv, sensor_q, command_q, applied, correction, c_rot, corr_base = loop_state(
        cp, reset_force, a_rot_task
    )
    nominal = np.empty(3)
    nominal_before = np.empty(3)
    quat = np.empty(4)
    quat_tmp = np.empty(4)
    rt = np.empty((3, 3))
    target = np.empty(3)
    step = np.empty(dof)
    q_try = np.empty(dof)
    total = np.empty(3)
    normals = np.empty(3 * MOST_CONTACTS)
    points = np.empty(3 * MOST_CONTACTS)
    f_true = np.empty(3)
    f_meas = np.empty(3)
    measured = np.empty(3)
    # mujoco_servo's userdata layout: header, then prev, ref, feed, limit, saturated
    h = 4
    alpha = 1.0 - math.exp(-2.0 * math.pi * params[M_CUTOFF] * dt)
    path_t = 0.0
    for k in range(n_periods):
        path_before = path_t
        path_t = period_start(cp, cs, path_t, a_rot_task, applied, corr_base)
        # ---- the inner loop's reference (Arm6Plant._reference_step) ----
        pose_at(a_path_t, a_path_pos, a_path_quat, path_t, nominal, quat)
        matrix_from_quat(quat, rt)
        for j in range(3):
            target[j] = nominal[j] + corr_base[j]
        q_try[:] = q_ik
        status = ik(
            rt,
            target,
            q_try,
            a_links,
            a_tool_r,
            a_tool_p,
            a_lower,
            a_upper,
            params[M_TOL_P],
            params[M_TOL_O],
            int(params[M_IK_ITER]),
            ik_work,
        )
        q_ik[:] = q_try
        scale = 1.0
        limited = 0
        for i in range(dof):
            step[i] = q_ik[i] - q_ref[i]
            if abs(step[i]) > a_dq_max[i]:
                scale = min(scale, a_dq_max[i] / abs(step[i]))
                limited |= 1 << i
        for i in range(dof):
            q_ref[i] += step[i] * scale
        # ---- the physics: the callback ramps the servos (MujocoArmPlant.step) ----
        d_userdata[1] = 0.0
        for i in range(nu):
            d_userdata[h + i] = ref_prev[i]
            d_userdata[h + nu + i] = q_ref[i]
            d_userdata[h + 2 * nu + i] = a_kv_over_kp[i] * (q_ref[i] - ref_prev[i]) / dt
            d_userdata[h + 4 * nu + i] = 0.0
        if prof_mocap.shape[0] == 0:
            bad = mj_steps(m_addr, d_addr, n_sub)
        else:
            bad = 0
            for _ in range(n_sub):
                _follow_profiles(
                    prof_p, prof_terms, prof_nterms, prof_mocap, a_offset,
                    params[M_HALF_THICKNESS], d_geom_xpos[tip, 0], d_mocap_pos, d_mocap_quat,
                )  # fmt: skip
                bad += mj_steps(m_addr, d_addr, 1)
        saturated = 0  # marked by the callback and fuzzkit_mj_steps (mujoco_servo.c)
        for i in range(nu):
            if d_userdata[h + 4 * nu + i] != 0.0:
                saturated |= 1 << i
            ref_prev[i] = q_ref[i]
        state[MS_T] += dt
        t_s = state[MS_T]
        # ForceSensor.update on the flange sensor's force, then read
        for j in range(3):
            state[MS_FILTERED + j] += alpha * (d_sensordata[j] - state[MS_FILTERED + j])
        if t_s + 1e-9 >= state[MS_NEXT_SAMPLE]:
            kn = int(state[MS_NOISE_INDEX])
            for j in range(3):
                state[MS_LATEST + j] = state[MS_FILTERED + j] + params[M_BIAS + j] + noise[kn, j]
            state[MS_NOISE_INDEX] += 1.0
            state[MS_FRESH] = 1.0
            state[MS_NEXT_SAMPLE] += 1.0 / params[M_RATE]
        finite = True
        for i in range(d_qpos.shape[0]):
            if not math.isfinite(d_qpos[i]):
                finite = False
        if bad > 0 or not finite:
            r_t[k] = t_s
            store_results(cs, out_scalars)
            return k
        count = tool_contacts(
            m_addr, d_addr, tip, total.ctypes, normals.ctypes, points.ctypes, MOST_CONTACTS
        )
        for j in range(3):  # the task frame's (the tool does not tilt here)
            f_true[j] = (
                a_rot_task[0, j] * total[0]
                + a_rot_task[1, j] * total[1]
                + a_rot_task[2, j] * total[2]
            )
        if state[MS_FRESH] > 0.0:
            state[MS_FRESH] = 0.0
            for j in range(3):
                f_meas[j] = state[MS_LATEST + j]
        else:
            f_meas[0] = f_meas[1] = f_meas[2] = np.nan
        # ---- the plant-independent part ----
        r_status[k], consumed = controller_period(
            k, cp, spike_sign[k], nan_flag[k], t_s, f_meas, measured, reset_force, c_step,
            c_state, selection, setpoints, cs, cv, sensor_q, command_q, applied, correction,
            c_rot,
        )  # fmt: skip
        # ---- recording ----
        moving = False
        if path_t > path_before:
            pose_at(a_path_t, a_path_pos, a_path_quat, path_before, nominal_before, quat_tmp)
            for j in range(3):
                if abs(nominal[j] - nominal_before[j]) > 1e-9:
                    moving = True
        shown = min(count, MOST_CONTACTS)
        record_period(
            k, t_s, moving, shown, consumed, measured, f_true, cv, correction, r_t, r_moving,
            r_contact, r_npoints, r_force, r_force_sensor, r_force_true, r_e, r_de, r_du, r_u,
            r_force_normal,
        )  # fmt: skip
        r_ik[k] = status
        r_limited[k] = limited
        r_saturated[k] = saturated
        for j in range(3):
            r_tool[k, j] = d_geom_xpos[tip, j] - a_offset[j]
            r_nominal[k, j] = nominal[j] - a_offset[j]
            r_target[k, j] = target[j] - a_offset[j]
        for c in range(shown):
            for j in range(3):
                r_points[k, c, j] = points[3 * c + j] - a_offset[j]
            credit_normal(
                a_rot_task, normals[3 * c], normals[3 * c + 1], normals[3 * c + 2],
                r_force_normal[k],
            )  # fmt: skip
        for i in range(dof):
            r_joints[k, i] = d_qpos[a_servo_qpos[i]]
            if a_elastic[i]:
                r_joints[k, i] += d_qpos[a_link_qpos[i]]
        for b in range(n_bodies):
            for j in range(3):
                r_arm[k, b, j] = d_xpos[a_bodies[b], j] - a_offset[j]
        for j in range(3):
            r_arm[k, n_bodies, j] = d_geom_xpos[tip, j] - a_offset[j]
    store_results(cs, out_scalars)
    return int(n_periods)
