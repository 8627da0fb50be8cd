"""The whole closed-loop run on the pymunk planar arm as one compiled loop over periods.

Per period: the planar plant step (:func:`fuzzkit.planar_sim.arm_period.plant_step`: numba code
around the same Chipmunk calls the Python plant makes) inside the skeleton every compiled loop
shares (:mod:`fuzzkit.loop.compiled.skeleton`), then the arm's own recording.
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
from fuzzkit.planar_sim.arm_period import STEP_OK, arm_pose, nominal_at, plant_step

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]


@jit
def run_planar(
    plant: tuple[Any, ...],
    noise: FloatArray,
    reset_force: FloatArray,
    ctrl: tuple[Any, ...],
    c_step: Any,
    rec: tuple[Any, ...],
    out_scalars: FloatArray,
) -> int:
    """Run up to as many periods as the recording has rows, filling it and ``out_scalars``;
    returns the periods done (fewer when the arm's state became non-finite: ``r_flags[k, 0]``
    of the last one says so).

    Named records, each unpacked once here: ``plant``, the arm's arrays in
    :class:`~fuzzkit.planar_sim.arm_period.PlanarArrays` field order; ``ctrl``, the
    controller's (:meth:`~fuzzkit.loop.compiled.common.ControllerArgs.record`); ``c_step``,
    the generated ``NAME_controller_step`` (ctypes); ``rec``, the recording
    (:func:`~fuzzkit.loop.compiled.common.recording`, the arm's ``flags`` last).
    """
    (
        a_path, a_kind, a_p, a_terms, a_nterms, a_rot, params, functions, pointers, stick,
        state,
    ) = plant  # fmt: skip
    cp, selection, setpoints, c_state, spike_sign, nan_flag = ctrl
    (
        r_t, r_force, r_force_sensor, r_force_true, r_e, r_de, r_du, r_u, r_tool, r_nominal,
        r_target, r_joints, r_contact, r_force_normal, r_moving, r_arm, r_points, r_npoints,
        r_status, r_flags,
    ) = rec  # fmt: skip
    n_periods: int = r_t.shape[0]
    n_obj = a_kind.shape[0]
    cs, cv, sensor_q, command_q, applied, correction, c_rot, corr_base = loop_state(
        cp, reset_force, a_rot
    )
    nominal = np.empty(3)
    nominal_before = np.empty(3)
    target = np.empty(3)
    f_true = np.empty(3)
    f_meas = np.empty(3)
    points = np.empty((max(n_obj, 1), 2))
    normals = np.empty((max(n_obj, 1), 2))
    measured = np.empty(3)
    path_t = 0.0
    for k in range(n_periods):
        path_before = path_t
        path_t = period_start(cp, cs, path_t, a_rot, applied, corr_base)
        count = plant_step(
            a_path, a_kind, a_p, a_terms, a_nterms, a_rot, params, functions, pointers, stick,
            state, noise, corr_base, path_t,
            nominal, target, f_true, f_meas, points, normals, r_flags[k],
        )  # fmt: skip
        if r_flags[k, 0] != STEP_OK:
            store_results(cs, out_scalars)
            return k
        t_s = state[0]
        r_status[k], consumed = controller_period(
            k, cp, spike_sign[k], nan_flag[k], t_s, f_meas, measured, reset_force, c_step,
            c_state, selection, setpoints, cs, cv, sensor_q, command_q, applied, correction,
            c_rot,
        )  # fmt: skip
        # ---- recording (PlanarArmPlant._sample and the runner's row) ----
        moving = False
        if path_t > path_before:
            nominal_at(a_path, path_before, nominal_before)
            for j in range(3):
                if abs(nominal[j] - nominal_before[j]) > 1e-9:
                    moving = True
        arm_pose(params, functions, pointers, r_joints[k], r_arm[k])
        record_period(
            k, t_s, moving, count, consumed, measured, f_true, cv, correction, r_t, r_moving,
            r_contact,
            r_npoints, r_force, r_force_sensor, r_force_true, r_e, r_de, r_du, r_u,
            r_force_normal,
        )  # fmt: skip
        for j in range(3):
            r_tool[k, j] = r_arm[k, 3, j]
            r_nominal[k, j] = nominal[j]
            r_target[k, j] = target[j]
        for c in range(count):
            r_points[k, c, 0] = points[c, 0]
            r_points[k, c, 1] = 0.0
            r_points[k, c, 2] = points[c, 1]
            # what the tool exerts on the object: minus the normal reaction on the tool
            credit_normal(a_rot, -normals[c, 0], 0.0, -normals[c, 1], r_force_normal[k])
    store_results(cs, out_scalars)
    return n_periods
