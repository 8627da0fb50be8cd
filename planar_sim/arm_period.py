"""The planar arm's period as numba code around the same Chipmunk calls: the compiled loop's plant.

:func:`plant_step` is :meth:`fuzzkit.planar_sim.arm.PlanarArmPlant.step` (and the reporting of
its sample) line for line: the path, the analytic IK, and per physics substep the servo rates,
the contact law of :class:`fuzzkit.plants.contact.ContactSolver`, the force on the tool, one
``cpSpaceStep`` and the filter and sampling of :class:`fuzzkit.plants.contact.ForceSensor`. The
rigid-body physics stays pymunk's: the kernel calls the very Chipmunk functions the Python
plant's pymunk wrappers call, in the same order, on the space :meth:`PlanarArmPlant.reset`
built (:mod:`fuzzkit.planar_sim.chipmunk_calls`). Only the Python glue around them is compiled.

The plant is reset in Python and read into arrays by :func:`pack`; the Python objects must stay
alive while the kernel runs (the arrays hold raw pointers into them).

Twins: this is the **compiled copy** of the planar plant's step (IK, angle wrapping, servo,
contact law, sensor); :class:`~fuzzkit.planar_sim.arm.PlanarArmPlant` with
:class:`fuzzkit.plants.contact.ContactSolver` is the independent reference it is tested against
(``tests/test_compiled_loop.py``, ``tests/test_planar_sim.py``), so the two are written twice on
purpose. The rough profile is shared with the 6-DOF compiled plant
(:mod:`fuzzkit.plants.rough_profile`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from fuzzkit.jit import jit
from fuzzkit.planar_sim.arm import PlanarArmPlant
from fuzzkit.planar_sim.chipmunk_calls import (
    F_APPLY_FORCE,
    F_GET_ANGLE,
    F_GET_IMPULSE,
    F_GET_POSITION,
    F_GET_VELOCITY,
    F_MOTOR_SET_RATE,
    F_SPACE_STEP,
    call_d_p,
    call_v_pd,
    call_v_pvv,
    call_vec_p,
    calls_supported,
    function_addresses,
    pointer,
)
from fuzzkit.plants.contact import padded_terms
from fuzzkit.plants.contract import UnsupportedPlant, wrist_sensor_extras
from fuzzkit.plants.environment import Box, RoughSurface, Table, _roughness_terms
from fuzzkit.plants.rough_profile import profile_height_slope

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Object kinds of the compiled contact solver.
KIND_TABLE, KIND_BOX, KIND_ROUGH = 0, 1, 2

# Indices into the float parameter vector (``PlanarArrays.params``).
P_L1, P_L2, P_TOOL_LEN, P_GAIN, P_DT, P_SUBSTEPS = 0, 1, 2, 3, 4, 5
P_TORQUE1, P_TORQUE2, P_RADIUS, P_K, P_C, P_MU, P_KT = 6, 7, 8, 9, 10, 11, 12
P_ALPHA, P_SAMPLE_PERIOD = 13, 14
P_BIAS = 15  # 3 values
N_PARAMS = 18

# Indices into the mutable state vector (``PlanarArrays.state``).
S_T, S_NEXT_SAMPLE, S_FRESH, S_NOISE_INDEX = 0, 1, 2, 3
S_FILTERED = 4  # 3 values
S_LATEST = 7  # 3 values
N_STATE = 10

# Indices into the pointer vector (``PlanarArrays.pointers``).
X_SPACE, X_LINK1, X_LINK2, X_TOOL, X_MOTOR1, X_MOTOR2 = 0, 1, 2, 3, 4, 5

#: plant_step's status codes.
STEP_OK, STEP_NON_FINITE = 0, 1


@dataclass(slots=True)
class PlanarArrays:
    """Everything :func:`plant_step` reads and updates (one run's plant), as arrays."""

    path: FloatArray  # (m, 4): t, x, y, z of the waypoints
    obj_kind: IntArray  # (k,)
    obj_p: FloatArray  # (k, 6) per-kind parameters (see pack)
    obj_terms: FloatArray  # (k, w, 3) roughness sines: wavenumber, amplitude, phase
    obj_nterms: IntArray  # (k,)
    rot: FloatArray  # (3, 3) base-from-task
    params: FloatArray  # (N_PARAMS,)
    functions: IntArray  # Chipmunk function addresses (chipmunk_calls.FUNCTIONS)
    pointers: IntArray  # space, link1, link2, tool, motor1, motor2
    stick: FloatArray  # (k,) tangential stick springs of the contact solver
    state: FloatArray  # (N_STATE,)


def pack(plant: PlanarArmPlant) -> PlanarArrays:
    """Read a freshly reset ``plant`` into the arrays of its compiled twin.

    Raises
    ------
    UnsupportedPlant
        On a machine whose C calling convention the Chipmunk calls are not lowered for, or for
        an environment object other than a table, a box or a rough surface, or a wrist sensor
        with a tool weight or a drifting bias.
    """
    if not calls_supported():
        raise UnsupportedPlant(
            "the compiled planar loop calls Chipmunk directly only on x86-64 and AArch64"
        )
    scn = plant._scenario
    if scn is None:
        raise RuntimeError("PlanarArmPlant.reset(scenario) must be called before pack")
    extras = wrist_sensor_extras(scn)
    if extras:
        raise UnsupportedPlant(f"the compiled planar loop does not model {', '.join(extras)}")
    p = plant.params
    k = len(scn.objects)
    kinds = np.zeros(k, dtype=np.int64)
    obj_p = np.zeros((k, 6))
    term_lists: list[tuple[tuple[float, float, float], ...]] = []
    for i, obj in enumerate(scn.objects):
        terms: tuple[tuple[float, float, float], ...] = ()
        if isinstance(obj, Table):
            kinds[i] = KIND_TABLE
            obj_p[i, :3] = (obj.height_m, obj.x_min, obj.x_max)
        elif isinstance(obj, Box):
            kinds[i] = KIND_BOX
            obj_p[i, :4] = (obj.center_x, obj.center_z, obj.size_x, obj.size_z)
        elif isinstance(obj, RoughSurface):
            kinds[i] = KIND_ROUGH
            obj_p[i, :5] = (obj.x_min, obj.x_max, obj.height_m, obj.offset_m, obj.tilt_rad)
            terms = _roughness_terms(
                obj.seed,
                obj.roughness_rms_m,
                obj.wavelength_min_m,
                obj.wavelength_max_m,
                obj.n_waves,
            )
        else:
            raise UnsupportedPlant(
                f"the compiled planar loop does not model {type(obj).__name__} objects"
            )
        term_lists.append(terms)
    obj_terms, nterms = padded_terms(term_lists)
    sensor, contact = scn.sensor, scn.contact
    dt = plant._dt
    params = np.zeros(N_PARAMS)
    params[P_L1], params[P_L2] = p.link1_m, p.link2_m
    params[P_TOOL_LEN] = plant._tool_len
    params[P_GAIN] = p.servo_gain_per_s
    params[P_DT] = dt
    params[P_SUBSTEPS] = p.substeps
    params[P_TORQUE1], params[P_TORQUE2] = p.torque_limit_nm
    params[P_RADIUS] = scn.tool.radius_m
    params[P_K] = contact.stiffness_n_per_m
    params[P_C] = contact.damping_n_s_per_m
    params[P_MU] = contact.friction
    params[P_KT] = contact.tangential_stiffness_n_per_m
    # ForceSensor.update's expressions, evaluated by the same Python arithmetic
    params[P_ALPHA] = 1.0 - math.exp(-2.0 * math.pi * sensor.cutoff_hz * dt)
    params[P_SAMPLE_PERIOD] = 1.0 / sensor.rate_hz
    params[P_BIAS : P_BIAS + 3] = sensor.bias_n
    state = np.zeros(N_STATE)
    state[S_T] = plant._t
    state[S_NEXT_SAMPLE] = 1.0 / sensor.rate_hz
    state[S_LATEST : S_LATEST + 3] = np.nan
    pointers = np.array(
        [
            pointer(plant._space._space),
            pointer(plant._link1._body),
            pointer(plant._link2._body),
            pointer(plant._tool._body),
            pointer(plant._motor1._constraint),
            pointer(plant._motor2._constraint),
        ],
        dtype=np.int64,
    )
    return PlanarArrays(
        path=np.array([(w.t_s, w.x, w.y, w.z) for w in scn.path], dtype=np.float64),
        obj_kind=kinds,
        obj_p=obj_p,
        obj_terms=obj_terms,
        obj_nterms=nterms,
        rot=np.array(scn.rotation, dtype=np.float64),
        params=params,
        functions=function_addresses(),
        pointers=pointers,
        stick=np.zeros(k),
        state=state,
    )


def sensor_samples(scenario_period_s: float, rate_hz: float, periods: int) -> int:
    """An upper bound of the sensor samples ``periods`` controller periods take (noise rows)."""
    return math.ceil(periods * scenario_period_s * rate_hz) + 2


@jit
def nominal_at(path: FloatArray, t_s: float, out: FloatArray) -> None:
    """``fuzzkit.plants.environment.nominal_position`` of the waypoints ``path`` into ``out``."""
    m = path.shape[0]
    if t_s <= path[0, 0]:
        out[0], out[1], out[2] = path[0, 1], path[0, 2], path[0, 3]
        return
    for i in range(m - 1):
        ta, tb = path[i, 0], path[i + 1, 0]
        if t_s <= tb:
            s = (t_s - ta) / (tb - ta) if tb > ta else 1.0
            for j in range(3):
                out[j] = path[i, 1 + j] + s * (path[i + 1, 1 + j] - path[i, 1 + j])
            return
    out[0], out[1], out[2] = path[m - 1, 1], path[m - 1, 2], path[m - 1, 3]


@jit
def _penetration(
    kind: int, op: FloatArray, terms: FloatArray, nterms: int, x: float, z: float, radius: float,
    out: FloatArray,
) -> bool:  # fmt: skip
    """``penetration`` of Table, Box and RoughSurface: ``out`` = depth, nx, nz, px, pz."""
    if kind == KIND_TABLE:
        if not op[1] <= x <= op[2]:
            return False
        depth = op[0] - (z - radius)
        if depth <= 0.0:
            return False
        out[0], out[1], out[2], out[3], out[4] = depth, 0.0, 1.0, x, op[0]
        return True
    if kind == KIND_BOX:
        hx, hz = 0.5 * op[2], 0.5 * op[3]
        dx, dz = x - op[0], z - op[1]
        qx, qz = min(max(dx, -hx), hx), min(max(dz, -hz), hz)
        ox, oz = dx - qx, dz - qz
        dist = math.hypot(ox, oz)
        if dist > 1e-12:
            depth = radius - dist
            if depth <= 0.0:
                return False
            out[0], out[1], out[2] = depth, ox / dist, oz / dist
            out[3], out[4] = op[0] + qx, op[1] + qz
            return True
        # centre inside: the nearest face; min() over (gap, nx, nz) tuples breaks ties the same
        gap, nx, nz = hx - dx, 1.0, 0.0
        for g, fx, fz in ((hx + dx, -1.0, 0.0), (hz - dz, 0.0, 1.0), (hz + dz, 0.0, -1.0)):
            if (g, fx, fz) < (gap, nx, nz):
                gap, nx, nz = g, fx, fz
        out[0], out[1], out[2], out[3], out[4] = radius + gap, nx, nz, x + nx * gap, z + nz * gap
        return True
    # rough surface
    if not op[0] <= x <= op[1]:
        return False
    h, m = profile_height_slope(op, terms, nterms, x)
    inv = 1.0 / math.sqrt(1.0 + m * m)
    depth = (h - z) * inv + radius
    if depth <= 0.0:
        return False
    out[0], out[1], out[2], out[3], out[4] = depth, -m * inv, inv, x, h
    return True


@jit
def contact_step(
    a_kind: IntArray, a_p: FloatArray, a_terms: FloatArray, a_nterms: IntArray,
    params: FloatArray, stick: FloatArray, x: float, z: float, vx: float, vz: float, dt: float,
    points: FloatArray, normals: FloatArray, force: FloatArray,
) -> int:  # fmt: skip
    """``ContactSolver.step``: force on the tool into ``force`` (base x, z), contact points and
    per-contact normal forces into rows of ``points`` / ``normals``; returns the contact count."""
    k_n, c_n, mu, kt = params[P_K], params[P_C], params[P_MU], params[P_KT]
    radius = params[P_RADIUS]
    fx = fz = 0.0
    count = 0
    pen = np.empty(5)
    for i in range(a_kind.shape[0]):
        if not _penetration(a_kind[i], a_p[i], a_terms[i], a_nterms[i], x, z, radius, pen):
            stick[i] = 0.0
            continue
        depth, nx, nz, px, pz = pen[0], pen[1], pen[2], pen[3], pen[4]
        vn = -(vx * nx + vz * nz)
        fn = k_n * depth + c_n * vn
        if fn <= 0.0:
            stick[i] = 0.0
            continue
        tx, tz = nz, -nx
        s = stick[i] + (vx * tx + vz * tz) * dt
        cap = mu * fn
        ft = -kt * s
        if abs(ft) > cap:
            ft = math.copysign(cap, ft)
            s = -ft / kt if kt else 0.0
        stick[i] = s
        fx += fn * nx + ft * tx
        fz += fn * nz + ft * tz
        points[count, 0], points[count, 1] = px, pz
        normals[count, 0], normals[count, 1] = fn * nx, fn * nz
        count += 1
    force[0], force[1] = fx, fz
    return count


@jit
def _wrap(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


@jit
def plant_step(
    path: FloatArray, a_kind: IntArray, a_p: FloatArray, a_terms: FloatArray,
    a_nterms: IntArray, rot: FloatArray, params: FloatArray, functions: IntArray,
    pointers: IntArray, stick: FloatArray, state: FloatArray, noise: FloatArray,
    correction_base: FloatArray, path_time_s: float,
    # outputs
    nominal: FloatArray, target: FloatArray, force_true: FloatArray,
    force_measured: FloatArray, points: FloatArray, normals: FloatArray, flags: IntArray,
) -> int:  # fmt: skip
    """One period of ``PlanarArmPlant.step``; returns the contact count of the last substep.

    ``flags`` out: [status (STEP_OK | STEP_NON_FINITE), target out of reach, joint 1 at its
    torque limit, joint 2 at its torque limit]. Positions in the base frame, forces in the task
    frame.
    """
    l1, l2, tool_len = params[P_L1], params[P_L2], params[P_TOOL_LEN]
    gain, dt = params[P_GAIN], params[P_DT]
    nominal_at(path, path_time_s, nominal)
    for j in range(3):
        target[j] = nominal[j] + correction_base[j]
    # inverse_kinematics (elbow up), the unreachable target projected onto the workspace
    wx, wz = target[0], target[2] + tool_len
    c2 = (wx * wx + wz * wz - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)
    flags[1] = 0 if -1.0 <= c2 <= 1.0 else 1
    c2 = min(max(c2, -1.0), 1.0)
    q2t = -math.acos(c2)
    q1t = math.atan2(wz, wx) - math.atan2(l2 * math.sin(q2t), l1 + l2 * math.cos(q2t))
    sp, link1, link2 = pointers[X_SPACE], pointers[X_LINK1], pointers[X_LINK2]
    tool = pointers[X_TOOL]
    motor1, motor2 = pointers[X_MOTOR1], pointers[X_MOTOR2]
    sat1 = sat2 = False
    lim1, lim2 = 0.99 * params[P_TORQUE1] * dt, 0.99 * params[P_TORQUE2] * dt
    alpha = params[P_ALPHA]
    fc = np.empty(2)
    count = 0
    for _ in range(int(params[P_SUBSTEPS])):
        q1 = call_d_p(functions[F_GET_ANGLE], link1)
        q2 = call_d_p(functions[F_GET_ANGLE], link2) - q1
        call_v_pd(functions[F_MOTOR_SET_RATE], motor1, -gain * _wrap(q1t - q1))
        call_v_pd(functions[F_MOTOR_SET_RATE], motor2, -gain * _wrap(q2t - q2))
        cx, cz = call_vec_p(functions[F_GET_POSITION], tool)
        tip_x, tip_z = cx, cz - 0.5 * tool_len
        vx, vz = call_vec_p(functions[F_GET_VELOCITY], tool)
        count = contact_step(
            a_kind, a_p, a_terms, a_nterms, params, stick, tip_x, tip_z, vx, vz, dt,
            points, normals, fc,
        )  # fmt: skip
        if count > 0:
            call_v_pvv(functions[F_APPLY_FORCE], tool, fc[0], fc[1], tip_x, tip_z)
        call_v_pd(functions[F_SPACE_STEP], sp, dt)
        state[S_T] += dt
        fbx, fbz = -fc[0], -fc[1]
        for j in range(3):
            # rot_t[j, 0] * fbx + rot_t[j, 2] * fbz with rot_t = rot.T
            force_true[j] = rot[0, j] * fbx + rot[2, j] * fbz
        # ForceSensor.update
        for j in range(3):
            state[S_FILTERED + j] += alpha * (force_true[j] - state[S_FILTERED + j])
        if state[S_T] + 1e-9 >= state[S_NEXT_SAMPLE]:
            k = int(state[S_NOISE_INDEX])
            for j in range(3):
                state[S_LATEST + j] = state[S_FILTERED + j] + params[P_BIAS + j] + noise[k, j]
            state[S_NOISE_INDEX] += 1.0  # noise rows are zeros without noise
            state[S_FRESH] = 1.0
            state[S_NEXT_SAMPLE] += params[P_SAMPLE_PERIOD]
        sat1 = sat1 or abs(call_d_p(functions[F_GET_IMPULSE], motor1)) >= lim1
        sat2 = sat2 or abs(call_d_p(functions[F_GET_IMPULSE], motor2)) >= lim2
    flags[2] = 1 if sat1 else 0
    flags[3] = 1 if sat2 else 0
    a1 = call_d_p(functions[F_GET_ANGLE], link1)
    a2 = call_d_p(functions[F_GET_ANGLE], link2)
    px, pz = call_vec_p(functions[F_GET_POSITION], tool)
    finite = math.isfinite(a1) and math.isfinite(a2) and math.isfinite(px) and math.isfinite(pz)
    flags[0] = STEP_OK if finite else STEP_NON_FINITE
    # ForceSensor.read
    if state[S_FRESH] > 0.0:
        state[S_FRESH] = 0.0
        for j in range(3):
            force_measured[j] = state[S_LATEST + j]
    else:
        force_measured[0] = force_measured[1] = force_measured[2] = np.nan
    return count


@jit
def arm_pose(
    params: FloatArray, functions: IntArray, pointers: IntArray, joints: FloatArray,
    arm: FloatArray,
) -> None:  # fmt: skip
    """``PlanarArmPlant._sample``'s joints ``(q1, q2)`` and arm polyline (base, elbow, wrist,
    tip; ``(4, 3)``, base frame) from the bodies' current state."""
    l1, l2 = params[P_L1], params[P_L2]
    q1 = call_d_p(functions[F_GET_ANGLE], pointers[X_LINK1])
    q2 = call_d_p(functions[F_GET_ANGLE], pointers[X_LINK2]) - q1
    joints[0], joints[1] = q1, q2
    ex, ez = l1 * math.cos(q1), l1 * math.sin(q1)
    wx, wz = ex + l2 * math.cos(q1 + q2), ez + l2 * math.sin(q1 + q2)
    cx, cz = call_vec_p(functions[F_GET_POSITION], pointers[X_TOOL])
    arm[0, 0] = arm[0, 1] = arm[0, 2] = 0.0
    arm[1, 0], arm[1, 1], arm[1, 2] = ex, 0.0, ez
    arm[2, 0], arm[2, 1], arm[2, 2] = wx, 0.0, wz
    arm[3, 0], arm[3, 1], arm[3, 2] = cx, 0.0, cz - 0.5 * params[P_TOOL_LEN]
