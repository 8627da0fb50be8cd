"""A wrist-sensor log from a ROS 2 bag (rosbag2, sqlite3 or MCAP storage): ``replay --forces``.

The force comes from a ``geometry_msgs/msg/WrenchStamped`` topic (``wrench.force``, N, taken as
the task frame, as a CSV log's ``fx,fy,fz``), read with the ``rosbags`` library. It is resampled
to the spec's period by the messages' own stamps (``header.stamp``, not the time the recorder
received them): the grid starts at the first stamp and steps one period; each grid time takes the
last message stamped at or before it (held), and is a missing sample (NaN) when no message was
stamped in the period up to it, i.e. when the held message is one period old or older. Messages
are taken in stamp order. The tool rotation (world-from-sensor) is a fixed matrix, or comes from
a second topic (``QuaternionStamped``, ``PoseStamped`` or ``TransformStamped``) resampled on the
same grid. Every problem is a :class:`~fuzzkit.errors.ProblemsError` naming the bag.
"""

from __future__ import annotations

import math
import sqlite3
import struct
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import Location, Problem, ProblemsError, did_you_mean
from fuzzkit.studies.replay import SensorLog

FloatArray = npt.NDArray[np.float64]

WRENCH = "geometry_msgs/msg/WrenchStamped"


def _quaternion(msg: Any) -> Any:
    return msg.quaternion


def _pose(msg: Any) -> Any:
    return msg.pose.orientation


def _transform(msg: Any) -> Any:
    return msg.transform.rotation


#: The message types a rotation topic may hold, and where each keeps its quaternion.
ROTATION_TYPES: dict[str, Callable[[Any], Any]] = {
    "geometry_msgs/msg/QuaternionStamped": _quaternion,
    "geometry_msgs/msg/PoseStamped": _pose,
    "geometry_msgs/msg/TransformStamped": _transform,
}
#: The longest log resampled (periods): more is taken for an unset stamp, not a recording.
MAX_SAMPLES = 10_000_000
#: What a damaged bag raises from inside rosbags and its storage back ends.
_BAG_ERRORS = (sqlite3.Error, struct.error, EOFError, KeyError, IndexError, ValueError)


def is_bag(path: str | Path) -> bool:
    """True when ``path`` names a rosbag2 bag: a folder, or a ``.db3`` or ``.mcap`` file."""
    p = Path(path)
    return p.is_dir() or p.suffix in (".db3", ".mcap")


@dataclass(frozen=True)
class Series:
    """One topic's messages in stamp order: stamps (ns) and values ``(n, k)``."""

    stamps: npt.NDArray[np.int64]
    values: FloatArray


def _fail(path: str, message: str) -> ProblemsError:
    return ProblemsError([Problem(Location(path), message)])


def _topic_list(topics: dict[str, Any]) -> str:
    return ", ".join(
        f"{name} ({info.msgtype}, {info.msgcount} message{'' if info.msgcount == 1 else 's'})"
        for name, info in topics.items()
    )


def read_bag_log(
    path: str | Path,
    period_s: float,
    topic: str | None,
    rotation_topic: str | None = None,
    frame_rotation: Sequence[float] | None = None,
) -> SensorLog:
    """The wrench of ``topic`` (and the rotation, see the module docstring) on the grid of
    ``period_s``; ``times`` are ``k * period_s`` from the first stamp.

    Raises
    ------
    ProblemsError
        The bag cannot be read, ``topic`` is omitted (the wrench topics are listed), unknown or
        of another type, has no message, or the stamps span more than :data:`MAX_SAMPLES`
        periods.
    """
    from rosbags.rosbag2 import Reader, ReaderError
    from rosbags.typesys import Stores, get_typestore

    name = str(path)
    store = get_typestore(Stores.LATEST)
    try:
        with Reader(Path(path)) as reader:
            topics = reader.topics
            wrenches = {t: i for t, i in topics.items() if i.msgtype == WRENCH}
            if topic is None:
                listed = (
                    _topic_list(wrenches)
                    if wrenches
                    else "none; the bag holds " + (_topic_list(topics) or "no topic")
                )
                raise _fail(
                    name, f"choose the force topic with --topic NAME ({WRENCH} topics: {listed})"
                )
            force = _series(name, reader, store, topic, {WRENCH: lambda m: m.wrench.force})
            rotation = None
            if rotation_topic is not None:
                rotation = _series(name, reader, store, rotation_topic, ROTATION_TYPES)
    except ProblemsError:
        raise  # ours, and a ValueError: not taken for damage below
    except ReaderError as exc:
        raise _fail(name, f"not a readable rosbag2 bag ({exc})") from None
    except FileNotFoundError:
        if not Path(path).exists():
            raise
        raise _fail(name, "not a readable rosbag2 bag (a bag folder holds metadata.yaml)") from None
    except _BAG_ERRORS as exc:
        raise _fail(name, f"the bag is damaged ({type(exc).__name__}: {exc})") from None
    period_ns = round(period_s * 1e9)
    start = int(force.stamps[0])
    n = (int(force.stamps[-1]) - start) // period_ns + 1
    if n > MAX_SAMPLES:
        raise _fail(
            name,
            f"the stamps of {topic} span {(n - 1) * period_s:g} s, {n} periods: more than the "
            f"{MAX_SAMPLES} replay takes (is a header.stamp unset?)",
        )
    grid = start + period_ns * np.arange(n, dtype=np.int64)
    forces = resample(force, grid, period_ns)
    rotations = None
    if rotation is not None:
        rotations = np.array([rotation_matrix(q) for q in resample(rotation, grid, period_ns)])
        rotations = rotations.reshape(n, 9)
    elif frame_rotation is not None:
        rotations = np.tile(np.asarray(frame_rotation, dtype=np.float64), (n, 1))
    times: FloatArray = np.arange(n, dtype=np.float64) * period_s
    return SensorLog(forces, rotations, times)


def _series(
    path: str,
    reader: Any,
    store: Any,
    topic: str,
    types: dict[str, Callable[[Any], Any]],
) -> Series:
    """The messages of ``topic``, checked to be of one of ``types``, in stamp order."""
    topics = reader.topics
    if topic not in topics:
        raise _fail(
            path,
            f"no topic {topic!r} in the bag{did_you_mean(topic, topics)} (topics: "
            f"{_topic_list(topics) or 'none'})",
        )
    info = topics[topic]
    if info.msgtype not in types:
        raise _fail(path, f"topic {topic} holds {info.msgtype}, expected {' or '.join(types)}")
    pick = types[info.msgtype]
    stamps: list[int] = []
    values: list[list[float]] = []
    from rosbags.serde import SerdeError

    for count, (conn, _, raw) in enumerate(reader.messages(connections=info.connections)):
        try:
            msg = store.deserialize_cdr(raw, conn.msgtype)
        except SerdeError as exc:
            raise _fail(
                path,
                f"the bag is damaged: message {count + 1} of {topic} cannot be decoded ({exc})",
            ) from None
        stamps.append(int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec))
        v = pick(msg)
        values.append(
            [float(v.x), float(v.y), float(v.z)] + ([float(v.w)] if hasattr(v, "w") else [])
        )
    if not stamps:
        raise _fail(path, f"topic {topic} has no message")
    order = np.argsort(np.asarray(stamps, dtype=np.int64), kind="stable")
    return Series(np.asarray(stamps, dtype=np.int64)[order], np.asarray(values)[order])


def resample(series: Series, grid: npt.NDArray[np.int64], period_ns: int) -> FloatArray:
    """``series`` on ``grid``: the last message stamped at or before each grid time, NaN where
    that message is one period old or older (or there is none)."""
    last = np.searchsorted(series.stamps, grid, side="right") - 1
    held = series.values[np.maximum(last, 0)].copy()
    stale = (last < 0) | (grid - series.stamps[np.maximum(last, 0)] >= period_ns)
    held[stale] = math.nan
    return held


def rotation_matrix(q: FloatArray) -> FloatArray:
    """The rotation of the quaternion ``(x, y, z, w)`` as a row-major 3x3 (normalised first;
    NaN when it is zero or not finite)."""
    x, y, z, w = (float(v) for v in q)
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if not math.isfinite(norm) or norm == 0.0:
        return np.full(9, math.nan)
    x, y, z, w = x / norm, y / norm, z / norm, w / norm
    return np.array(
        [
            1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
            2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
            2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y),
        ]
    )  # fmt: skip


def parse_frame_rotation(text: str) -> tuple[float, ...]:
    """``--frame-rotation``: nine numbers r11,r12,...,r33 (row-major, world-from-sensor) that
    form a rotation (orthonormal to 1e-6, determinant +1).

    Raises
    ------
    ProblemsError
        Not nine finite numbers, or not a rotation.
    """
    where = Location("--frame-rotation")
    cells = [c.strip() for c in text.split(",")]
    try:
        values = tuple(float(c) for c in cells)
    except ValueError:
        values = ()
    if len(values) != 9 or not all(math.isfinite(v) for v in values):
        raise ProblemsError(
            [Problem(where, f"expected nine finite numbers r11,r12,...,r33, got {text!r}")]
        )
    m = np.array(values).reshape(3, 3)
    if not np.allclose(m @ m.T, np.eye(3), atol=1e-6) or np.linalg.det(m) < 0:
        raise ProblemsError(
            [Problem(where, f"{text!r} is not a rotation (orthonormal, determinant +1)")]
        )
    return values
