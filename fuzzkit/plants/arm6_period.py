"""The 6-DOF plant's period as compiled code: the twin of :class:`fuzzkit.plants.arm6.Arm6Plant`.

:func:`pack` reads a reset :class:`~fuzzkit.plants.arm6.Arm6Plant` (its start pose, joint limits,
path and 3-D objects) into flat arrays; :func:`plant_step` then advances one period exactly as
``Arm6Plant.step`` does (path interpolation, damped-least-squares IK warm-started from the
previous solution, joint speed limit and servo lag, forward kinematics, penalty contact with
Coulomb friction, the F/T sensor's filter, noise and bias) without leaving compiled code. The
closed loop that calls it every period, with the controller, lives in
:mod:`fuzzkit.loop.compiled` (plants know no controller).

The formulas are the Python plant's, line for line and in the same order of operations; the only
differences are the 6x6 linear solve of the IK step (LU with partial pivoting here, LAPACK in
numpy) and the summation order of small matrix products, which differ in the last bits. The
equivalence test (``tests/test_compiled_loop.py``) bounds what that does to a closed-loop force
trace. Sensor noise is drawn beforehand from the same ``numpy.random.Generator`` stream as the
Python sensor (:func:`fuzzkit.plants.contact.sensor_noise`), so both loops see the same noise.

Twins: this is the **compiled copy** of the 6-DOF plant's math (forward kinematics, Jacobian,
damped least squares, IK, rotation error, contact with friction); the Python plant
(:mod:`fuzzkit.plants.arm6`, :mod:`~fuzzkit.plants.kinematics`,
:mod:`~fuzzkit.plants.environment3d`) is the independent reference it is tested against, so the
two are written twice on purpose. Only compiled code is shared between the compiled plants
(:mod:`fuzzkit.plants.rough_profile`).

Size: about 800 lines, one idea: the whole plant period as one compiled function and the
helpers it inlines (its rough-floor contact is already apart, in
:mod:`fuzzkit.plants.arm6_heightfield`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.jit import jit
from fuzzkit.plants.arm6 import Arm6Plant
from fuzzkit.plants.arm6_heightfield import (
    height_field_contact,
    pack_height_field,
    tangent_plane_contact,
)
from fuzzkit.plants.contact import padded_terms
from fuzzkit.plants.contract import UnsupportedPlant, wrist_sensor_extras
from fuzzkit.plants.environment import _roughness_terms
from fuzzkit.plants.environment3d import Box3, ExtrudedProfile, HeightField, Plane
from fuzzkit.plants.rough_profile import profile_height_slope

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: IK status codes of the compiled plant, indexed like :data:`IK_STATUS_NAMES`.
IK_CONVERGED, IK_MAX_ITERATIONS, IK_UNREACHABLE, IK_LIMIT = 0, 1, 2, 3
IK_STATUS_NAMES = ("converged", "max_iterations", "unreachable", "limit")

#: Object kinds of the compiled contact solver.
KIND_PLANE, KIND_BOX, KIND_PROFILE, KIND_HEIGHT_FIELD = 0, 1, 2, 3

# Indices into the float parameter vector of the plant (``Arm6Arrays.params``).
P_DT, P_LAG, P_RADIUS, P_K, P_C, P_MU, P_KT = 0, 1, 2, 3, 4, 5, 6
P_TOL_P, P_TOL_O, P_IK_ITER, P_CUTOFF, P_RATE, P_NOISE = 7, 8, 9, 10, 11, 12
P_BIAS = 13  # 3 values
N_PARAMS = 16

# Indices into the plant's mutable state vector (``Arm6Arrays.state``).
S_T, S_NEXT_SAMPLE, S_FRESH, S_NOISE_INDEX = 0, 1, 2, 3
S_FILTERED = 4  # 3 values
S_LATEST = 7  # 3 values
S_P_PREV = 10  # 3 values
N_STATE = 13


@dataclass(slots=True)
class Arm6Arrays:
    """Everything :func:`plant_step` reads and updates, as arrays (one run's plant)."""

    links: FloatArray  # (dof, 5): d, a, cos(alpha), sin(alpha), offset
    tool_r: FloatArray  # (3, 3)
    tool_p: FloatArray  # (3,)
    lower: FloatArray
    upper: FloatArray
    dq_max: FloatArray  # joint speed limit per period (rad)
    path_t: FloatArray  # (m,) pose times
    path_pos: FloatArray  # (m, 3) positions, robot base frame
    path_quat: FloatArray  # (m, 4) unit quaternions, consecutive ones on the same hemisphere
    obj_kind: IntArray  # (k,)
    obj_p: FloatArray  # (k, 12) per-kind parameters (see pack)
    obj_terms: FloatArray  # (k, w, 3) roughness sines: wavenumber, amplitude, phase
    obj_nterms: IntArray  # (k,)
    obj_grid: FloatArray  # (k, g) a height field's heights, row-major (arm6_heightfield)
    rot_task: FloatArray  # (3, 3) base-from-task
    offset: FloatArray  # (3,) scenario origin in the robot frame
    params: FloatArray  # (N_PARAMS,)
    q: FloatArray  # actual joints
    q_ref: FloatArray  # joint reference after the speed limit
    q_ik: FloatArray  # last IK solution (the warm start)
    stick: FloatArray  # (k, 3) tangential stick springs
    state: FloatArray  # (N_STATE,)
    work: Arm6Workspace  # plant_step's scratch (workspace), so that a period allocates nothing


def pack(plant: Arm6Plant) -> Arm6Arrays:
    """Read a freshly reset ``plant`` into the arrays of its compiled twin.

    Raises
    ------
    UnsupportedPlant
        For what the twin does not model: an object other than a plane, a box, an extruded
        rough profile or a height field, ``strict`` mode (which raises mid-run), or a wrist
        sensor with a tool weight, a drifting bias or a tilting tool.
    """
    p = plant.params
    if p.strict:
        raise UnsupportedPlant("the compiled arm6 loop does not model strict mode")
    scn = plant.scenario
    extras = wrist_sensor_extras(scn)
    if extras:
        raise UnsupportedPlant(f"the compiled arm6 loop does not model {', '.join(extras)}")
    chain = plant.chain
    links = np.array(chain._links, dtype=np.float64)
    objs = plant.objects
    k = len(objs)
    kinds = np.zeros(k, dtype=np.int64)
    obj_p = np.zeros((k, 12))
    term_lists: list[tuple[tuple[float, float, float], ...]] = []
    grids: list[FloatArray] = []
    for i, obj in enumerate(objs):
        terms: tuple[tuple[float, float, float], ...] = ()
        grid = np.zeros(0)
        if isinstance(obj, Plane):
            kinds[i] = KIND_PLANE
            obj_p[i, :10] = (*obj.point, *obj.normal, obj.x_min, obj.x_max, obj.y_min, obj.y_max)
        elif isinstance(obj, Box3):
            kinds[i] = KIND_BOX
            obj_p[i, :6] = (*obj.center, *obj.half_size)
        elif isinstance(obj, ExtrudedProfile):
            s = obj.surface
            kinds[i] = KIND_PROFILE
            obj_p[i, :10] = (
                s.x_min,
                s.x_max,
                s.height_m,
                s.offset_m,
                s.tilt_rad,
                obj.y_min,
                obj.y_max,
                *obj.offset,
            )
            terms = _roughness_terms(
                s.seed, s.roughness_rms_m, s.wavelength_min_m, s.wavelength_max_m, s.n_waves
            )
        elif isinstance(obj, HeightField):
            kinds[i] = KIND_HEIGHT_FIELD
            row, grid = pack_height_field(obj)
            obj_p[i, : len(row)] = row
        else:
            raise UnsupportedPlant(
                f"the compiled arm6 loop does not model {type(obj).__name__} objects"
            )
        term_lists.append(terms)
        grids.append(grid)
    obj_terms, nterms = padded_terms(term_lists)
    obj_grid = np.zeros((k, max([1, *(g.shape[0] for g in grids)])))
    for i, grid in enumerate(grids):
        obj_grid[i, : grid.shape[0]] = grid
    poses = plant.path.poses
    sensor = scn.sensor
    contact = scn.contact
    params = np.zeros(N_PARAMS)
    params[P_DT] = plant._dt
    params[P_LAG] = plant._lag
    params[P_RADIUS] = scn.tool.radius_m
    params[P_K] = contact.stiffness_n_per_m
    params[P_C] = contact.damping_n_s_per_m
    params[P_MU] = contact.friction
    params[P_KT] = contact.tangential_stiffness_n_per_m
    params[P_TOL_P] = p.ik_position_tolerance
    params[P_TOL_O] = p.ik_orientation_tolerance
    params[P_IK_ITER] = p.ik_iterations
    params[P_CUTOFF] = sensor.cutoff_hz
    params[P_RATE] = sensor.rate_hz
    params[P_NOISE] = sensor.noise_std_n
    params[P_BIAS : P_BIAS + 3] = sensor.bias_n
    state = np.zeros(N_STATE)
    state[S_T] = plant._t
    state[S_NEXT_SAMPLE] = 1.0 / sensor.rate_hz
    state[S_LATEST : S_LATEST + 3] = np.nan
    state[S_P_PREV : S_P_PREV + 3] = plant._p_prev
    return Arm6Arrays(
        links=links,
        tool_r=np.array(chain._tool_r, dtype=np.float64),
        tool_p=np.array(chain._tool_p, dtype=np.float64),
        lower=np.array(chain._lo, dtype=np.float64),
        upper=np.array(chain._hi, dtype=np.float64),
        dq_max=np.array(plant._dq_max, dtype=np.float64),
        path_t=np.array([q.t_s for q in poses], dtype=np.float64),
        path_pos=np.array([q.position for q in poses], dtype=np.float64),
        path_quat=np.array([q.orientation for q in poses], dtype=np.float64),
        obj_kind=kinds,
        obj_p=obj_p,
        obj_terms=obj_terms,
        obj_nterms=nterms,
        obj_grid=obj_grid,
        rot_task=np.array(scn.rotation, dtype=np.float64),
        offset=np.array(plant._offset, dtype=np.float64),
        params=params,
        q=np.array(plant._q, dtype=np.float64),
        q_ref=np.array(plant._q_ref, dtype=np.float64),
        q_ik=np.array(plant._q_ik, dtype=np.float64),
        stick=np.zeros((k, 3)),
        state=state,
        work=workspace(links.shape[0]),
    )


# --------------------------------------------------------------------------------------------
# Kinematics (SerialChain._evaluate, _jacobian_rows, _solve)
# --------------------------------------------------------------------------------------------


@jit
def fk(
    q: FloatArray,
    links: FloatArray,
    tool_r: FloatArray,
    tool_p: FloatArray,
    rot: FloatArray,
    p: FloatArray,
    axes: FloatArray,
    origins: FloatArray,
) -> None:
    """TCP rotation ``rot`` and position ``p``, joint axes and origins (base frame), in place."""
    r00, r01, r02 = 1.0, 0.0, 0.0
    r10, r11, r12 = 0.0, 1.0, 0.0
    r20, r21, r22 = 0.0, 0.0, 1.0
    px = py = pz = 0.0
    for i in range(q.shape[0]):
        axes[i, 0], axes[i, 1], axes[i, 2] = r02, r12, r22
        origins[i, 0], origins[i, 1], origins[i, 2] = px, py, pz
        d, a, ca, sa, off = links[i, 0], links[i, 1], links[i, 2], links[i, 3], links[i, 4]
        th = q[i] + off
        ct, st = math.cos(th), math.sin(th)
        px += r00 * a * ct + r01 * a * st + r02 * d
        py += r10 * a * ct + r11 * a * st + r12 * d
        pz += r20 * a * ct + r21 * a * st + r22 * d
        n00 = r00 * ct + r01 * st
        n01 = -r00 * st * ca + r01 * ct * ca + r02 * sa
        n02 = r00 * st * sa - r01 * ct * sa + r02 * ca
        n10 = r10 * ct + r11 * st
        n11 = -r10 * st * ca + r11 * ct * ca + r12 * sa
        n12 = r10 * st * sa - r11 * ct * sa + r12 * ca
        n20 = r20 * ct + r21 * st
        n21 = -r20 * st * ca + r21 * ct * ca + r22 * sa
        n22 = r20 * st * sa - r21 * ct * sa + r22 * ca
        r00, r01, r02 = n00, n01, n02
        r10, r11, r12 = n10, n11, n12
        r20, r21, r22 = n20, n21, n22
    tx, ty, tz = tool_p[0], tool_p[1], tool_p[2]
    p[0] = px + r00 * tx + r01 * ty + r02 * tz
    p[1] = py + r10 * tx + r11 * ty + r12 * tz
    p[2] = pz + r20 * tx + r21 * ty + r22 * tz
    t = tool_r
    rot[0, 0] = r00 * t[0, 0] + r01 * t[1, 0] + r02 * t[2, 0]
    rot[0, 1] = r00 * t[0, 1] + r01 * t[1, 1] + r02 * t[2, 1]
    rot[0, 2] = r00 * t[0, 2] + r01 * t[1, 2] + r02 * t[2, 2]
    rot[1, 0] = r10 * t[0, 0] + r11 * t[1, 0] + r12 * t[2, 0]
    rot[1, 1] = r10 * t[0, 1] + r11 * t[1, 1] + r12 * t[2, 1]
    rot[1, 2] = r10 * t[0, 2] + r11 * t[1, 2] + r12 * t[2, 2]
    rot[2, 0] = r20 * t[0, 0] + r21 * t[1, 0] + r22 * t[2, 0]
    rot[2, 1] = r20 * t[0, 1] + r21 * t[1, 1] + r22 * t[2, 1]
    rot[2, 2] = r20 * t[0, 2] + r21 * t[1, 2] + r22 * t[2, 2]


@jit
def jacobian(p: FloatArray, axes: FloatArray, origins: FloatArray, jac: FloatArray) -> None:
    """Geometric Jacobian (6 x dof) of the TCP at ``p``, in place."""
    for i in range(axes.shape[0]):
        zx, zy, zz = axes[i, 0], axes[i, 1], axes[i, 2]
        dx, dy, dz = p[0] - origins[i, 0], p[1] - origins[i, 1], p[2] - origins[i, 2]
        jac[0, i] = zy * dz - zz * dy
        jac[1, i] = zz * dx - zx * dz
        jac[2, i] = zx * dy - zy * dx
        jac[3, i] = zx
        jac[4, i] = zy
        jac[5, i] = zz


@jit
def rotation_error(rt: FloatArray, r: FloatArray) -> tuple[float, float, float]:
    """``log(Rt R^T)`` as a rotation vector (fuzzkit.plants.rotations.rotation_error)."""
    # quat_from_matrix (Shepperd) of e = Rt R^T, entry by entry
    r00 = rt[0, 0] * r[0, 0] + rt[0, 1] * r[0, 1] + rt[0, 2] * r[0, 2]
    r01 = rt[0, 0] * r[1, 0] + rt[0, 1] * r[1, 1] + rt[0, 2] * r[1, 2]
    r02 = rt[0, 0] * r[2, 0] + rt[0, 1] * r[2, 1] + rt[0, 2] * r[2, 2]
    r10 = rt[1, 0] * r[0, 0] + rt[1, 1] * r[0, 1] + rt[1, 2] * r[0, 2]
    r11 = rt[1, 0] * r[1, 0] + rt[1, 1] * r[1, 1] + rt[1, 2] * r[1, 2]
    r12 = rt[1, 0] * r[2, 0] + rt[1, 1] * r[2, 1] + rt[1, 2] * r[2, 2]
    r20 = rt[2, 0] * r[0, 0] + rt[2, 1] * r[0, 1] + rt[2, 2] * r[0, 2]
    r21 = rt[2, 0] * r[1, 0] + rt[2, 1] * r[1, 1] + rt[2, 2] * r[1, 2]
    r22 = rt[2, 0] * r[2, 0] + rt[2, 1] * r[2, 1] + rt[2, 2] * r[2, 2]
    tr = r00 + r11 + r22
    if tr >= r00 and tr >= r11 and tr >= r22:
        s = math.sqrt(max(tr + 1.0, 0.0)) * 2.0
        w, x, y, z = 0.25 * s, (r21 - r12) / s, (r02 - r20) / s, (r10 - r01) / s
    elif r00 >= r11 and r00 >= r22:
        s = math.sqrt(max(1.0 + r00 - r11 - r22, 0.0)) * 2.0
        w, x, y, z = (r21 - r12) / s, 0.25 * s, (r01 + r10) / s, (r02 + r20) / s
    elif r11 >= r22:
        s = math.sqrt(max(1.0 + r11 - r00 - r22, 0.0)) * 2.0
        w, x, y, z = (r02 - r20) / s, (r01 + r10) / s, 0.25 * s, (r12 + r21) / s
    else:
        s = math.sqrt(max(1.0 + r22 - r00 - r11, 0.0)) * 2.0
        w, x, y, z = (r10 - r01) / s, (r02 + r20) / s, (r12 + r21) / s, 0.25 * s
    n = math.sqrt(w * w + x * x + y * y + z * z)
    if w < 0.0:
        n = -n
    w, x, y, z = w / n, x / n, y / n, z / n
    # rotvec_from_quat
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    sn = math.sqrt(x * x + y * y + z * z)
    # small angle: angle ~ 2*s/w, exact to machine precision there
    k = (2.0 / w if w > 0.0 else 2.0) if sn < 1e-12 else 2.0 * math.atan2(sn, w) / sn
    return k * x, k * y, k * z


@jit
def _solve6(m: FloatArray, v: FloatArray, x: FloatArray) -> None:
    """Solve ``m x = v`` (small, symmetric positive definite here) by LU with partial
    pivoting; ``m`` and ``v`` are overwritten (the caller's scratch)."""
    n = m.shape[0]
    for c in range(n):
        piv = c
        big = abs(m[c, c])
        for r in range(c + 1, n):
            if abs(m[r, c]) > big:
                big, piv = abs(m[r, c]), r
        if piv != c:
            for j in range(n):
                m[c, j], m[piv, j] = m[piv, j], m[c, j]
            v[c], v[piv] = v[piv], v[c]
        for r in range(c + 1, n):
            f = m[r, c] / m[c, c]
            for j in range(c, n):
                m[r, j] -= f * m[c, j]
            v[r] -= f * v[c]
    for r in range(n - 1, -1, -1):
        acc = v[r]
        for j in range(r + 1, n):
            acc -= m[r, j] * x[j]
        x[r] = acc / m[r, r]


@jit
def _dls(
    jac: FloatArray,
    err: FloatArray,
    lam2: float,
    dq: FloatArray,
    a: FloatArray,
    y: FloatArray,
    v: FloatArray,
) -> None:
    """Damped least squares step ``J^T (J J^T + lam2 I)^-1 err``; ``a`` (rows x rows), ``y``
    and ``v`` (rows) are scratch."""
    rows, n = jac.shape
    for i in range(rows):
        for j in range(rows):
            acc = 0.0
            for c in range(n):
                acc += jac[i, c] * jac[j, c]
            a[i, j] = acc
        a[i, i] += lam2
        v[i] = err[i]
    _solve6(a, v, y)
    for c in range(n):
        acc = 0.0
        for i in range(rows):
            acc += jac[i, c] * y[i]
        dq[c] = acc


@jit
def _ik_error(
    rt: FloatArray, pt: FloatArray, rot: FloatArray, p: FloatArray, e: FloatArray
) -> tuple[float, float]:
    ox, oy, oz = rotation_error(rt, rot)
    e[0], e[1], e[2] = pt[0] - p[0], pt[1] - p[1], pt[2] - p[2]
    e[3], e[4], e[5] = ox, oy, oz
    return (
        math.sqrt(e[0] ** 2 + e[1] ** 2 + e[2] ** 2),
        math.sqrt(ox**2 + oy**2 + oz**2),
    )


@jit
def _at_limit(q: FloatArray, lo: FloatArray, hi: FloatArray) -> bool:
    for i in range(q.shape[0]):  # noqa: SIM110 - a plain loop compiles in nopython mode
        if q[i] <= lo[i] + 1e-12 or q[i] >= hi[i] - 1e-12:
            return True
    return False


#: What :func:`ik` works in, made once (:func:`ik_workspace`) and reused every period: the
#: pose and errors of the current and the trial joints, the Jacobian, the step, the damped
#: least squares' system. A period allocates nothing.
IkWorkspace = tuple[
    FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray,
    FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray,
    FloatArray, FloatArray,
]  # fmt: skip


def ik_workspace(n: int) -> IkWorkspace:
    """:func:`ik`'s scratch for a chain of ``n`` joints."""
    e = np.empty
    return (
        e((3, 3)), e(3), e((n, 3)), e((n, 3)), e(6), e((6, n)), e(n), e(n), e(6), e((3, 3)),
        e(3), e((n, 3)), e((n, 3)), e((6, 6)), e(6), e(6),
    )  # fmt: skip


#: :func:`plant_step`'s scratch beside :func:`ik`'s: the path's quaternion and rotation, the
#: IK target, the joint axes, the tool's velocity and force, a contact's normal and point.
Arm6Workspace = tuple[
    FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray,
    FloatArray, IkWorkspace,
]  # fmt: skip


def workspace(n: int) -> Arm6Workspace:
    """:func:`plant_step`'s scratch for a chain of ``n`` joints, made once per run."""
    e = np.empty
    return e(4), e((3, 3)), e(3), e((n, 3)), e(3), e(3), e(3), e(3), ik_workspace(n)


@jit
def ik(
    rt: FloatArray,
    pt: FloatArray,
    q: FloatArray,
    links: FloatArray,
    tool_r: FloatArray,
    tool_p: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    tol_p: float,
    tol_o: float,
    max_iterations: int,
    work: IkWorkspace,
) -> int:
    """Damped-least-squares IK from the seed ``q`` (updated in place); returns the status code.

    ``SerialChain.ik_fast`` step for step: the seed clamped to the limits, Levenberg-Marquardt
    damping, the active set of joints at a limit, the stationary-point tests. ``work``:
    :func:`ik_workspace` of the chain.
    """
    rot, p, axes, origins, e, jac, dq, q_new, e_new, rot_n, p_n, axes_n, origins_n, a, y, v = work
    max_step = 0.5
    n = q.shape[0]
    for i in range(n):
        q[i] = min(max(q[i], lo[i]), hi[i])
    fk(q, links, tool_r, tool_p, rot, p, axes, origins)
    ep, eo = _ik_error(rt, pt, rot, p, e)
    cost = ep * ep + eo * eo
    mu = 1e-9
    slow = 0
    suspect = False
    iterations = 0
    status = IK_MAX_ITERATIONS
    while True:
        if ep <= tol_p and eo <= tol_o:
            status = IK_CONVERGED
            break
        if iterations >= max_iterations:
            break
        iterations += 1
        jacobian(p, axes, origins, jac)
        lam2 = 0.5 * cost + mu
        _dls(jac, e, lam2, dq, a, y, v)
        blocked = False
        for i in range(n):
            if (q[i] <= lo[i] and dq[i] < 0.0) or (q[i] >= hi[i] and dq[i] > 0.0):
                blocked = True
                for r in range(6):
                    jac[r, i] = 0.0
        if blocked:
            _dls(jac, e, lam2, dq, a, y, v)
        if suspect:
            gg = 0.0
            jj = 0.0
            for c in range(n):
                g = 0.0
                for r in range(6):
                    g += jac[r, c] * e[r]
                    jj += jac[r, c] * jac[r, c]
                gg += g * g
            if gg <= 1e-12 * jj * cost:
                status = IK_LIMIT if blocked else IK_UNREACHABLE
                break
        big = 0.0
        for i in range(n):
            big = max(big, abs(dq[i]))
        scale = max_step / big if big > max_step else 1.0
        for i in range(n):
            q_new[i] = min(max(q[i] + scale * dq[i], lo[i]), hi[i])
        fk(q_new, links, tool_r, tool_p, rot_n, p_n, axes_n, origins_n)
        ep_new, eo_new = _ik_error(rt, pt, rot_n, p_n, e_new)
        cost_new = ep_new * ep_new + eo_new * eo_new
        if cost_new < cost:
            slow = slow + 1 if cost_new > cost * (1.0 - 1e-6) else 0
            suspect = slow > 0
            q[:] = q_new
            rot[:] = rot_n
            p[:] = p_n
            axes[:] = axes_n
            origins[:] = origins_n
            e[:] = e_new
            ep, eo, cost = ep_new, eo_new, cost_new
            mu = max(mu * 0.1, 1e-12)
            if slow >= 5:
                status = IK_LIMIT if _at_limit(q, lo, hi) else IK_UNREACHABLE
                break
        else:
            mu *= 10.0
            suspect = True
            if mu > 1e4:
                status = IK_LIMIT if _at_limit(q, lo, hi) else IK_UNREACHABLE
                break
    return status


# --------------------------------------------------------------------------------------------
# Path, contact, sensor
# --------------------------------------------------------------------------------------------


@jit
def pose_at(
    path_t: FloatArray,
    path_pos: FloatArray,
    path_quat: FloatArray,
    t_s: float,
    pos: FloatArray,
    quat: FloatArray,
) -> None:
    """Position and orientation of the nominal path at ``t_s`` (CartesianPath.pose_at)."""
    m = path_t.shape[0]
    if t_s <= path_t[0] or t_s >= path_t[m - 1]:
        end = 0 if t_s <= path_t[0] else m - 1
        for j in range(3):
            pos[j] = path_pos[end, j]
        for j in range(4):
            quat[j] = path_quat[end, j]
        return
    i = 1
    while path_t[i] < t_s:
        i += 1
    span = path_t[i] - path_t[i - 1]
    s = (t_s - path_t[i - 1]) / span if span > 0.0 else 1.0
    for j in range(3):
        pos[j] = path_pos[i - 1, j] + s * (path_pos[i, j] - path_pos[i - 1, j])
    a0, a1, a2, a3 = (
        path_quat[i - 1, 0],
        path_quat[i - 1, 1],
        path_quat[i - 1, 2],
        path_quat[i - 1, 3],
    )
    b0, b1, b2, b3 = path_quat[i, 0], path_quat[i, 1], path_quat[i, 2], path_quat[i, 3]
    if a0 == b0 and a1 == b1 and a2 == b2 and a3 == b3:
        quat[0], quat[1], quat[2], quat[3] = a0, a1, a2, a3
        return
    dot = a0 * b0 + a1 * b1 + a2 * b2 + a3 * b3
    if dot < 0.0:
        dot = -dot
        b0, b1, b2, b3 = -b0, -b1, -b2, -b3
    if dot > 0.9995:
        o0, o1 = a0 + s * (b0 - a0), a1 + s * (b1 - a1)
        o2, o3 = a2 + s * (b2 - a2), a3 + s * (b3 - a3)
    else:
        theta = math.acos(dot)
        sin_t = math.sin(theta)
        w0 = math.sin((1.0 - s) * theta) / sin_t
        w1 = math.sin(s * theta) / sin_t
        o0, o1, o2, o3 = w0 * a0 + w1 * b0, w0 * a1 + w1 * b1, w0 * a2 + w1 * b2, w0 * a3 + w1 * b3
    nn = math.sqrt(o0 * o0 + o1 * o1 + o2 * o2 + o3 * o3)
    quat[0], quat[1], quat[2], quat[3] = o0 / nn, o1 / nn, o2 / nn, o3 / nn


@jit
def matrix_from_quat(q: FloatArray, r: FloatArray) -> None:
    """Rotation matrix of a quaternion ``(w, x, y, z)`` (normalised here), in place."""
    n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    w, x, y, z = q[0] / n, q[1] / n, q[2] / n, q[3] / n
    r[0, 0], r[0, 1], r[0, 2] = 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)
    r[1, 0], r[1, 1], r[1, 2] = 2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)
    r[2, 0], r[2, 1], r[2, 2] = 2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)


@jit
def _object_contact(
    kind: int,
    op: FloatArray,
    terms: FloatArray,
    nterms: int,
    grid: FloatArray,
    c: FloatArray,
    radius: float,
    nrm: FloatArray,
    pt: FloatArray,
) -> float:
    """Penetration depth (> 0 when touching, else <= 0) of the tool sphere; normal and point out.

    Plane.contact, Box3.contact, ExtrudedProfile.contact and HeightField.contact of
    :mod:`fuzzkit.plants.arm6`.
    """
    if kind == KIND_PLANE:
        if not (op[6] <= c[0] <= op[7] and op[8] <= c[1] <= op[9]):
            return -1.0
        nx, ny, nz = op[3], op[4], op[5]
        n = math.sqrt(nx * nx + ny * ny + nz * nz)
        nx, ny, nz = nx / n, ny / n, nz / n
        dist = (c[0] - op[0]) * nx + (c[1] - op[1]) * ny + (c[2] - op[2]) * nz
        depth = radius - dist
        if depth <= 0.0:
            return -1.0
        nrm[0], nrm[1], nrm[2] = nx, ny, nz
        pt[0], pt[1], pt[2] = c[0] - dist * nx, c[1] - dist * ny, c[2] - dist * nz
        return float(depth)
    if kind == KIND_BOX:
        # the offset from the centre, its clamp to the box, and what lies outside, per axis
        d0, d1, d2 = c[0] - op[0], c[1] - op[1], c[2] - op[2]
        q0 = min(max(d0, -op[3]), op[3])
        q1 = min(max(d1, -op[4]), op[4])
        q2 = min(max(d2, -op[5]), op[5])
        o0, o1, o2 = d0 - q0, d1 - q1, d2 - q2
        dist = math.sqrt(o0 * o0 + o1 * o1 + o2 * o2)
        if dist > 1e-12:
            depth = radius - dist
            if depth <= 0.0:
                return -1.0
            nrm[0], nrm[1], nrm[2] = o0 / dist, o1 / dist, o2 / dist
            pt[0], pt[1], pt[2] = op[0] + q0, op[1] + q1, op[2] + q2
            return depth
        best_gap = math.inf
        axis = 0
        best_sign = 1.0
        for i in range(3):
            di = d0 if i == 0 else (d1 if i == 1 else d2)
            for sign in (1.0, -1.0):
                gap = op[3 + i] - sign * di
                if gap < best_gap:
                    best_gap, axis, best_sign = gap, i, sign
        nrm[0] = nrm[1] = nrm[2] = 0.0
        nrm[axis] = best_sign
        for i in range(3):
            pt[i] = c[i] + nrm[i] * best_gap
        return radius + best_gap
    if kind == KIND_HEIGHT_FIELD:
        return height_field_contact(op, grid, c, radius, nrm, pt)
    # extruded rough profile
    x = c[0] - op[7]
    if not (op[0] <= x <= op[1] and op[5] <= c[1] - op[8] <= op[6]):
        return -1.0
    h, slope = profile_height_slope(op, terms, nterms, x)
    return tangent_plane_contact(c, radius, h + op[9], slope, 0.0, nrm, pt)


@jit
def contact_step(
    a_kind: IntArray,
    a_p: FloatArray,
    a_terms: FloatArray,
    a_nterms: IntArray,
    a_grid: FloatArray,
    stick: FloatArray,
    params: FloatArray,
    c: FloatArray,
    v: FloatArray,
    force: FloatArray,
    points: FloatArray,
    normals: FloatArray,
    nrm: FloatArray,
    pt: FloatArray,
) -> int:
    """Contact3Solver.step: force the tool exerts (base, into ``force``), contact points and
    per-contact normal forces (rows of ``points`` / ``normals``); returns the contact count.
    ``nrm`` and ``pt`` (3 each) are scratch."""
    k_n, c_n, mu, kt = params[P_K], params[P_C], params[P_MU], params[P_KT]
    dt = params[P_DT]
    radius = params[P_RADIUS]
    fx = fy = fz = 0.0
    count = 0
    for i in range(a_kind.shape[0]):
        depth = _object_contact(
            a_kind[i], a_p[i], a_terms[i], a_nterms[i], a_grid[i], c, radius, nrm, pt
        )
        if depth <= 0.0:
            stick[i, 0] = stick[i, 1] = stick[i, 2] = 0.0
            continue
        nx, ny, nz = nrm[0], nrm[1], nrm[2]
        vn = v[0] * nx + v[1] * ny + v[2] * nz
        fn = k_n * depth - c_n * vn
        if fn <= 0.0:
            stick[i, 0] = stick[i, 1] = stick[i, 2] = 0.0
            continue
        s0x, s0y, s0z = stick[i, 0], stick[i, 1], stick[i, 2]
        s0n = s0x * nx + s0y * ny + s0z * nz
        px_, py_, pz_ = s0x - s0n * nx, s0y - s0n * ny, s0z - s0n * nz
        old = math.sqrt(s0x * s0x + s0y * s0y + s0z * s0z)
        proj = math.sqrt(px_ * px_ + py_ * py_ + pz_ * pz_)
        k_turn = old / proj if proj > 1e-15 else 0.0
        sx = px_ * k_turn + (v[0] - vn * nx) * dt
        sy = py_ * k_turn + (v[1] - vn * ny) * dt
        sz = pz_ * k_turn + (v[2] - vn * nz) * dt
        ft_mag = kt * math.sqrt(sx * sx + sy * sy + sz * sz)
        cap = mu * fn
        if ft_mag > cap and ft_mag > 0.0:
            scale = cap / ft_mag
            sx, sy, sz = sx * scale, sy * scale, sz * scale
        stick[i, 0], stick[i, 1], stick[i, 2] = sx, sy, sz
        fx += fn * nx - kt * sx
        fy += fn * ny - kt * sy
        fz += fn * nz - kt * sz
        points[count, 0], points[count, 1], points[count, 2] = pt[0], pt[1], pt[2]
        normals[count, 0], normals[count, 1], normals[count, 2] = -fn * nx, -fn * ny, -fn * nz
        count += 1
    force[0], force[1], force[2] = -fx, -fy, -fz
    return count


@jit
def plant_step(
    plant: tuple[Any, ...],
    noise: FloatArray,
    correction_base: FloatArray,
    path_time_s: float,
    # outputs
    nominal: FloatArray,
    tcp: FloatArray,
    rot: FloatArray,
    origins: FloatArray,
    force_true: FloatArray,
    force_measured: FloatArray,
    points: FloatArray,
    normals: FloatArray,
) -> tuple[int, int, bool]:
    """One period of ``Arm6Plant.step``; returns ``(ik status, contact count, speed limited)``.

    ``nominal`` and ``tcp`` come out in the robot base frame; forces in the task frame.
    ``plant``: the arrays of :class:`Arm6Arrays`, in its field order (the run's scratch,
    :func:`workspace`, last).
    """
    (
        a_links, a_tool_r, a_tool_p, a_lower, a_upper, a_dq_max, a_path_t, a_path_pos,
        a_path_quat, a_kind, a_p, a_terms, a_nterms, a_grid, a_rot_task, _, params, q, q_ref,
        q_ik, stick, state, work,
    ) = plant  # fmt: skip
    n = q.shape[0]
    quat, rt, target, axes, v, f, nrm, pt, ik_work = work
    pose_at(a_path_t, a_path_pos, a_path_quat, path_time_s, nominal, quat)
    matrix_from_quat(quat, rt)
    for j in range(3):
        target[j] = nominal[j] + correction_base[j]
    status = ik(
        rt,
        target,
        q_ik,
        a_links,
        a_tool_r,
        a_tool_p,
        a_lower,
        a_upper,
        params[P_TOL_P],
        params[P_TOL_O],
        int(params[P_IK_ITER]),
        ik_work,
    )
    lag = params[P_LAG]
    scale = 1.0
    limited = False
    for i in range(n):
        d = q_ik[i] - q_ref[i]
        if abs(d) > a_dq_max[i]:
            scale = min(scale, a_dq_max[i] / abs(d))
            limited = True
    for i in range(n):
        q_ref[i] += (q_ik[i] - q_ref[i]) * scale
        q[i] += lag * (q_ref[i] - q[i])
    dt = params[P_DT]
    state[S_T] += dt
    fk(q, a_links, a_tool_r, a_tool_p, rot, tcp, axes, origins)
    for j in range(3):
        v[j] = (tcp[j] - state[S_P_PREV + j]) / dt
        state[S_P_PREV + j] = tcp[j]
    count = contact_step(
        a_kind, a_p, a_terms, a_nterms, a_grid, stick, params, tcp, v, f, points, normals, nrm,
        pt,
    )  # fmt: skip
    r = a_rot_task
    for j in range(3):
        force_true[j] = r[0, j] * f[0] + r[1, j] * f[1] + r[2, j] * f[2]
    # ForceSensor.update then read
    alpha = 1.0 - math.exp(-2.0 * math.pi * params[P_CUTOFF] * dt)
    for j in range(3):
        state[S_FILTERED + j] += alpha * (force_true[j] - state[S_FILTERED + j])
    if state[S_T] + 1e-9 >= state[S_NEXT_SAMPLE]:
        k = int(state[S_NOISE_INDEX])
        for j in range(3):
            state[S_LATEST + j] = state[S_FILTERED + j] + params[P_BIAS + j] + noise[k, j]
        state[S_NOISE_INDEX] += 1.0
        state[S_FRESH] = 1.0
        state[S_NEXT_SAMPLE] += 1.0 / params[P_RATE]
    if state[S_FRESH] > 0.0:
        state[S_FRESH] = 0.0
        for j in range(3):
            force_measured[j] = state[S_LATEST + j]
    else:
        force_measured[0] = force_measured[1] = force_measured[2] = np.nan
    return status, count, limited
