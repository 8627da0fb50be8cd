"""ROS 2 messages in and out of the node: a wrench sample, a tool rotation, a correction.

In: ``geometry_msgs/WrenchStamped`` (``wrench.force``, N, in the controller's frame, the wrist
sensor's: as a sensor log's ``fx,fy,fz``) and, for a spec that compensates the tool's weight,
``geometry_msgs/PoseStamped`` (the tool's orientation, world-from-sensor, turned into the
rotation the generated controller takes as the bag reader does,
:func:`fuzzkit.studies.rosbag_log.rotation_matrix`). Out: the correction ``u`` (m) as a
``PoseStamped`` offset (position ``u``, identity orientation) or a ``TwistStamped`` (linear
``du / T``, m/s), stamped with the period's grid time, in the wrench's frame.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fuzzkit.ros2.stepper import Step
from fuzzkit.studies.rosbag_log import rotation_matrix

#: ``--output``: what the correction is published as.
OUTPUTS = ("pose", "twist")


def stamp_ns(header: Any) -> int:
    """A header's stamp in nanoseconds."""
    return int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)


def time_msg(ns: int) -> Any:
    """``builtin_interfaces/Time`` of ``ns`` nanoseconds."""
    from builtin_interfaces.msg import Time

    return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def force_of(msg: Any) -> tuple[float, float, float]:
    """The force of a ``WrenchStamped`` (N)."""
    f = msg.wrench.force
    return (float(f.x), float(f.y), float(f.z))


def rotation_of(msg: Any) -> list[float]:
    """The rotation (row-major 3x3) of a ``PoseStamped``'s orientation; NaN when the quaternion
    is zero or not finite (the controller then holds, as for a missing sample)."""
    q = msg.pose.orientation
    r = rotation_matrix(np.array([q.x, q.y, q.z, q.w], dtype=np.float64))
    return [float(v) for v in r]


def wrench_message(stamp: int, force_n: Any, frame_id: str = "ft_sensor") -> Any:
    """A ``WrenchStamped`` of the force ``force_n`` (N; no torque), stamped ``stamp`` (ns): what
    a sensor driver, or the simulated plant, publishes."""
    from geometry_msgs.msg import WrenchStamped

    msg = WrenchStamped()
    msg.header.stamp = time_msg(stamp)
    msg.header.frame_id = frame_id
    f = msg.wrench.force
    f.x, f.y, f.z = (float(v) for v in force_n)
    return msg


def pose_message(stamp: int, rotation: Any) -> Any:
    """A ``PoseStamped`` whose orientation is ``rotation`` (row-major 3x3, world-from-sensor; not
    finite: the zero quaternion, which :func:`rotation_of` reads back as NaN)."""
    from geometry_msgs.msg import PoseStamped
    from scipy.spatial.transform import Rotation

    msg = PoseStamped()
    msg.header.stamp = time_msg(stamp)
    r = np.asarray(rotation, dtype=np.float64).reshape(3, 3)
    q = msg.pose.orientation
    if np.all(np.isfinite(r)):
        q.x, q.y, q.z, q.w = (float(v) for v in Rotation.from_matrix(r).as_quat())
    else:
        q.x, q.y, q.z, q.w = 0.0, 0.0, 0.0, 0.0
    return msg


def correction(step: Step, output: str, period_s: float, frame_id: str) -> Any:
    """The message the node publishes for ``step`` (``output``: :data:`OUTPUTS`)."""
    if output == "pose":
        from geometry_msgs.msg import PoseStamped

        pose = PoseStamped()
        pose.header.stamp = time_msg(step.stamp_ns)
        pose.header.frame_id = frame_id
        pose.pose.position.x, pose.pose.position.y, pose.pose.position.z = step.u
        pose.pose.orientation.w = 1.0
        return pose
    if output == "twist":
        from geometry_msgs.msg import TwistStamped

        twist = TwistStamped()
        twist.header.stamp = time_msg(step.stamp_ns)
        twist.header.frame_id = frame_id
        lin = twist.twist.linear
        lin.x, lin.y, lin.z = (d / period_s for d in step.du)
        return twist
    raise ValueError(f"unknown output {output!r} (expected one of {', '.join(OUTPUTS)})")


def stop(output: str, stamp: int, frame_id: str) -> Any:
    """What the node sends once when the watchdog stops the output: a zero twist (the robot
    stops moving), or None for a pose offset (the motion controller holds the last target)."""
    if output != "twist":
        return None
    from geometry_msgs.msg import TwistStamped

    twist = TwistStamped()
    twist.header.stamp = time_msg(stamp)
    twist.header.frame_id = frame_id
    return twist
