"""Rotation helpers for the kinematics and the 6-DOF plant: quaternions, log/exp maps, slerp.

Conventions: quaternions are ``(w, x, y, z)`` with ``w >= 0`` after normalisation where a sign
choice is needed; rotation vectors are axis * angle in radians (the SO(3) log map); matrices
are 3x3 rotation matrices acting on column vectors. Scalar helpers take and return plain floats
and tuples because the plant calls them every 4 ms step, where numpy's per-call overhead on
tiny arrays dominates.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

Quat = tuple[float, float, float, float]
Vec3 = tuple[float, float, float]
#: A rotation matrix as three row tuples.
Mat3 = tuple[Vec3, Vec3, Vec3]


def quat_from_matrix(r: Sequence[Sequence[float]]) -> Quat:
    """Convert a rotation matrix to a unit quaternion ``(w, x, y, z)``, ``w >= 0``.

    Uses Shepperd's method (pick the largest of w, x, y, z to divide by), which stays accurate
    for every rotation, including half turns where the trace formula loses all precision.
    """
    r00, r01, r02 = r[0][0], r[0][1], r[0][2]
    r10, r11, r12 = r[1][0], r[1][1], r[1][2]
    r20, r21, r22 = r[2][0], r[2][1], r[2][2]
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
    return (w / n, x / n, y / n, z / n)


def matrix_from_quat(q: Sequence[float]) -> Mat3:
    """Convert a quaternion ``(w, x, y, z)`` (normalised here) to a rotation matrix."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    n = math.sqrt(w * w + x * x + y * y + z * z)
    if n == 0.0:
        raise ValueError("zero quaternion has no rotation (expected a non-zero (w, x, y, z))")
    w, x, y, z = w / n, x / n, y / n, z / n
    return (
        (1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
        (2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
        (2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)),
    )


def rotvec_from_quat(q: Sequence[float]) -> Vec3:
    """Return the rotation vector (axis * angle, angle in [0, pi]) of a unit quaternion."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    if w < 0.0:  # same rotation, shorter way round
        w, x, y, z = -w, -x, -y, -z
    s = math.sqrt(x * x + y * y + z * z)
    if s < 1e-12:
        # angle ~ 2*s/w: the first-order expansion is exact to machine precision here
        k = 2.0 / w if w > 0.0 else 2.0
        return (k * x, k * y, k * z)
    k = 2.0 * math.atan2(s, w) / s
    return (k * x, k * y, k * z)


def quat_from_rotvec(v: Sequence[float]) -> Quat:
    """Return the unit quaternion of a rotation vector (the SO(3) exp map)."""
    angle = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    if angle < 1e-12:
        return (1.0, 0.5 * v[0], 0.5 * v[1], 0.5 * v[2])
    s = math.sin(0.5 * angle) / angle
    return (math.cos(0.5 * angle), s * v[0], s * v[1], s * v[2])


def quat_multiply(a: Sequence[float], b: Sequence[float]) -> Quat:
    """Hamilton product ``a * b`` (apply ``b`` first, then ``a``)."""
    aw, ax, ay, az = a[0], a[1], a[2], a[3]
    bw, bx, by, bz = b[0], b[1], b[2], b[3]
    return (
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    )


def slerp(q0: Sequence[float], q1: Sequence[float], s: float) -> Quat:
    """Spherical linear interpolation from ``q0`` (s=0) to ``q1`` (s=1) along the short arc."""
    dot = q0[0] * q1[0] + q0[1] * q1[1] + q0[2] * q1[2] + q0[3] * q1[3]
    b = (q1[0], q1[1], q1[2], q1[3])
    if dot < 0.0:  # q and -q are the same rotation: take the short way
        dot, b = -dot, (-b[0], -b[1], -b[2], -b[3])
    if dot > 0.9995:
        # nearly parallel: sin(theta) ~ 0, so normalised lerp is exact to rounding
        out = tuple(q0[i] + s * (b[i] - q0[i]) for i in range(4))
    else:
        theta = math.acos(dot)
        sin_t = math.sin(theta)
        w0 = math.sin((1.0 - s) * theta) / sin_t
        w1 = math.sin(s * theta) / sin_t
        out = tuple(w0 * q0[i] + w1 * b[i] for i in range(4))
    n = math.sqrt(sum(c * c for c in out))
    return (out[0] / n, out[1] / n, out[2] / n, out[3] / n)


def rotation_error(r_target: Sequence[Sequence[float]], r: Sequence[Sequence[float]]) -> Vec3:
    """Rotation vector, in the base frame, that turns ``r`` into ``r_target``: log(Rt R^T).

    This is the orientation part of the IK error: its norm is the angle between the two
    orientations, valid for every angle up to pi (unlike the small-angle skew formula).
    """
    # E = Rt @ R^T written out (E_ij = sum_k Rt_ik R_jk): this runs every IK iteration
    (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = r_target[0], r_target[1], r_target[2]
    (b00, b01, b02), (b10, b11, b12), (b20, b21, b22) = r[0], r[1], r[2]
    e: Mat3 = (
        (
            a00 * b00 + a01 * b01 + a02 * b02,
            a00 * b10 + a01 * b11 + a02 * b12,
            a00 * b20 + a01 * b21 + a02 * b22,
        ),
        (
            a10 * b00 + a11 * b01 + a12 * b02,
            a10 * b10 + a11 * b11 + a12 * b12,
            a10 * b20 + a11 * b21 + a12 * b22,
        ),
        (
            a20 * b00 + a21 * b01 + a22 * b02,
            a20 * b10 + a21 * b11 + a22 * b12,
            a20 * b20 + a21 * b21 + a22 * b22,
        ),
    )
    return rotvec_from_quat(quat_from_matrix(e))


def rpy_to_matrix(roll: float, pitch: float, yaw: float) -> npt.NDArray[np.float64]:
    """Rotation matrix of fixed-axis roll, pitch, yaw: ``R = Rz(yaw) Ry(pitch) Rx(roll)``."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )
