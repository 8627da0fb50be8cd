"""The whole closed-loop run on the arm6 plant as one compiled loop over periods.

Per period: the compiled plant step (:func:`fuzzkit.plants.arm6_period.plant_step`) inside the
skeleton every compiled loop shares (:mod:`fuzzkit.loop.compiled.skeleton`: the path's clock,
fault injection, latency queues, the generated controller, the common recording), then the
arm's own recording.
"""

from __future__ import annotations

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
from fuzzkit.plants.arm6_period import plant_step, pose_at

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]


@jit
def run_arm6(
    plant: tuple[Any, ...],
    noise: FloatArray,
    reset_force: FloatArray,
    ctrl: tuple[Any, ...],
    c_step: Any,
    rec: tuple[Any, ...],
    out_scalars: FloatArray,
) -> None:
    """Run as many periods as the recording has rows; fill it and ``out_scalars``.

    Named records, each unpacked once here: ``plant``, the arm's arrays in
    :class:`~fuzzkit.plants.arm6_period.Arm6Arrays` field order; ``ctrl``, the controller's
    (:meth:`~fuzzkit.loop.compiled.common.ControllerArgs.record`); ``c_step``, the generated
    ``NAME_controller_step`` (ctypes); ``rec``, the recording
    (:func:`~fuzzkit.loop.compiled.common.recording`, the arm's ``ik`` and ``limited`` last).
    """
    # what the recording reads of the plant (plant_step takes the whole record)
    (
        _, a_tool_r, a_tool_p, _, _, _, a_path_t, a_path_pos, a_path_quat, a_kind, _, _, _, _,
        a_rot_task, a_offset, _, q, _, _, _, state_p, _,
    ) = plant  # fmt: skip
    cp, selection, setpoints, c_state, spike_sign, nan_flag = ctrl
    (
        r_t, r_force, r_force_sensor, r_force_true, r_e, r_de, r_du, r_u, r_tool, r_nominal,
        r_target, r_joints, r_contact, r_force_normal, r_moving, r_arm, r_points, r_npoints,
        r_status, r_ik, r_limited,
    ) = rec  # fmt: skip
    n_periods = r_t.shape[0]
    dof = q.shape[0]
    n_obj = a_kind.shape[0]
    cs, cv, sensor_q, command_q, applied, correction, c_rot, corr_base = loop_state(
        cp, reset_force, a_rot_task
    )
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
        path_t = period_start(cp, cs, path_t, a_rot_task, applied, corr_base)
        ik_status, count, limited = plant_step(
            plant, noise, corr_base, path_t, nominal, tcp, rot, origins, f_true, f_meas, points,
            normals,
        )  # fmt: skip
        t_s = state_p[0]
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
        record_period(
            k, t_s, moving, count, consumed, measured, f_true, cv, correction, r_t, r_moving,
            r_contact,
            r_npoints, r_force, r_force_sensor, r_force_true, r_e, r_de, r_du, r_u,
            r_force_normal,
        )  # fmt: skip
        r_ik[k] = ik_status
        r_limited[k] = limited
        for j in range(3):
            r_tool[k, j] = tcp[j] - a_offset[j]
            r_nominal[k, j] = nominal[j] - a_offset[j]
            r_target[k, j] = nominal[j] + corr_base[j] - a_offset[j]
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
