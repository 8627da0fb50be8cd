"""Robot descriptions: the joints (standard DH parameters and limits) and tool offset of a serial
robot, loaded from a small YAML file or a shipped name (``load_robot("irb140")`` reads
``fuzzkit/data/irb140.yaml``). The kinematics of a description: :mod:`fuzzkit.plants.kinematics`.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import ConfigError, ConfigFileError
from fuzzkit.located_yaml import (
    DocumentKind,
    compose_document,
    locations,
    read_document,
    to_python,
)
from fuzzkit.plants.rotations import rpy_to_matrix

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class Joint:
    """One revolute joint of a serial chain: standard DH parameters and limits (SI units).

    Parameters
    ----------
    name:
        Label used in messages and recordings (``axis1`` ...).
    d, a, alpha, offset:
        Standard DH parameters in metres / radians; ``theta = q + offset``.
    lower, upper:
        Joint position limits in radians (``lower < upper``).
    max_velocity:
        Joint speed limit in rad/s (``> 0``).
    """

    name: str
    d: float
    a: float
    alpha: float
    offset: float
    lower: float
    upper: float
    max_velocity: float


@dataclass(frozen=True, slots=True)
class RobotDescription:
    """A serial robot: joints base to flange, a tool offset, and where the numbers come from.

    ``tool_xyz`` (m) and ``tool_rpy`` (rad, R = Rz(yaw) Ry(pitch) Rx(roll)) place the TCP in the
    flange frame of the last joint.
    """

    name: str
    joints: tuple[Joint, ...]
    tool_xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    tool_rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    description: str = ""
    source: str = ""

    @property
    def dof(self) -> int:
        """Number of joints."""
        return len(self.joints)

    def tool_transform(self) -> FloatArray:
        """Return the 4x4 transform of the TCP in the flange frame."""
        t = np.eye(4)
        t[:3, :3] = rpy_to_matrix(*self.tool_rpy)
        t[:3, 3] = self.tool_xyz
        return t

    def with_tool(
        self, xyz: Sequence[float], rpy: Sequence[float] = (0.0, 0.0, 0.0)
    ) -> RobotDescription:
        """Return a copy with another tool offset (same joints)."""
        if len(xyz) != 3 or len(rpy) != 3:
            raise ConfigError(
                f"tool offset needs 3 numbers each (expected xyz and rpy, got {len(xyz)}, "
                f"{len(rpy)})"
            )
        return RobotDescription(
            name=self.name,
            joints=self.joints,
            tool_xyz=(float(xyz[0]), float(xyz[1]), float(xyz[2])),
            tool_rpy=(float(rpy[0]), float(rpy[1]), float(rpy[2])),
            description=self.description,
            source=self.source,
        )


_TOP_KEYS = {"name", "description", "source", "angle_unit", "joints", "tool"}
_JOINT_KEYS = {"name", "d", "a", "alpha", "offset", "limits", "max_velocity"}


ROBOT_DOCUMENT = DocumentKind(
    "robot description",
    "robot descriptions",
    "expected a mapping with name, angle_unit and joints",
    ConfigFileError,
)


def _node_lines(text: str) -> tuple[int, dict[str, int], list[int]]:
    """Line numbers (1-based) of the document, its top-level keys and its joint entries."""
    try:
        where = locations(compose_document(text, "<robot>", ROBOT_DOCUMENT), "<robot>")
    except ConfigError:
        return 0, {}, []
    keys = {str(p[0]): loc.line for p, loc in where.items() if len(p) == 1}
    joints = [loc.line for p, loc in where.items() if len(p) == 2 and p[0] == "joints"]
    return where[()].line, keys, joints


def _number(value: Any) -> float | None:
    # bool is an int subclass: `limits: [yes, no]` must not load as [1, 0]
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    out = float(value)
    return out if math.isfinite(out) else None


def robot_from_mapping(
    data: Any, source: str = "<robot>", text: str | None = None
) -> RobotDescription:
    """Build a :class:`RobotDescription` from parsed YAML, checking everything at once.

    Parameters
    ----------
    data:
        The parsed document (see ``fuzzkit/data/irb140.yaml`` for the format).
    source:
        File name used in error messages.
    text:
        The YAML text, if available, to put line numbers in error messages.

    Returns
    -------
    RobotDescription

    Raises
    ------
    ConfigError
        Listing every problem as ``file:line: what is wrong (expected X, got Y)``.
    """
    doc_line, key_lines, joint_lines = _node_lines(text) if text is not None else (0, {}, [])
    problems: list[str] = []

    def where(line: int) -> str:
        line = line or doc_line  # a missing key: the document's start
        return f"{source}:{line}" if line > 0 else source

    if not isinstance(data, Mapping):
        raise ConfigError(
            f"{where(1)}: a robot description must be a mapping (got {type(data).__name__})"
        )
    for key in sorted(set(data) - _TOP_KEYS):
        problems.append(
            f"{where(key_lines.get(str(key), 0))}: unknown key {key!r} "
            f"(expected one of {', '.join(sorted(_TOP_KEYS))})"
        )
    name = data.get("name")
    if not isinstance(name, str) or not name:
        problems.append(f"{where(key_lines.get('name', 0))}: 'name' must be a non-empty string")
    unit = data.get("angle_unit", "rad")
    if unit not in ("deg", "rad"):
        problems.append(
            f"{where(key_lines.get('angle_unit', 0))}: angle_unit must be 'deg' or 'rad' "
            f"(got {unit!r})"
        )
    scale = math.pi / 180.0 if unit == "deg" else 1.0

    joints: list[Joint] = []
    raw_joints = data.get("joints")
    if not isinstance(raw_joints, list) or not raw_joints:
        problems.append(
            f"{where(key_lines.get('joints', 0))}: 'joints' must be a non-empty list of joints"
        )
        raw_joints = []
    for i, raw in enumerate(raw_joints):
        loc = where(joint_lines[i] if i < len(joint_lines) else key_lines.get("joints", 0))
        label = f"joint {i + 1}"
        if not isinstance(raw, Mapping):
            problems.append(f"{loc}: {label} must be a mapping (got {type(raw).__name__})")
            continue
        for key in sorted(set(raw) - _JOINT_KEYS):
            problems.append(
                f"{loc}: {label}: unknown key {key!r} "
                f"(expected one of {', '.join(sorted(_JOINT_KEYS))})"
            )
        values: dict[str, float] = {}
        for key in ("d", "a", "alpha", "offset", "max_velocity"):
            if key not in raw:
                if key == "offset":
                    values[key] = 0.0
                    continue
                problems.append(f"{loc}: {label}: missing {key!r}")
                continue
            num = _number(raw[key])
            if num is None:
                problems.append(
                    f"{loc}: {label}: {key!r} must be a finite number (got {raw[key]!r})"
                )
            else:
                values[key] = num
        lims = raw.get("limits")
        lo = hi = None
        if isinstance(lims, list) and len(lims) == 2 and all(_number(v) is not None for v in lims):
            lo, hi = float(lims[0]), float(lims[1])
            if not lo < hi:
                problems.append(
                    f"{loc}: {label}: limits must be [lower, upper] with lower < upper "
                    f"(got {lims!r})"
                )
        else:
            problems.append(
                f"{loc}: {label}: 'limits' must be [lower, upper] numbers (got {lims!r})"
            )
        if "max_velocity" in values and values["max_velocity"] <= 0:
            problems.append(
                f"{loc}: {label}: max_velocity must be > 0 (got {values['max_velocity']})"
            )
        jname = raw.get("name", f"joint{i + 1}")
        if not isinstance(jname, str):
            problems.append(f"{loc}: {label}: 'name' must be a string (got {jname!r})")
            jname = f"joint{i + 1}"
        if len(values) == 5 and lo is not None and hi is not None:
            joints.append(
                Joint(
                    name=jname,
                    d=values["d"],
                    a=values["a"],
                    alpha=values["alpha"] * scale,
                    offset=values["offset"] * scale,
                    lower=lo * scale,
                    upper=hi * scale,
                    max_velocity=values["max_velocity"] * scale,
                )
            )

    tool_xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    tool_rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    tool = data.get("tool", {})
    tloc = where(key_lines.get("tool", 0))
    if not isinstance(tool, Mapping):
        problems.append(f"{tloc}: 'tool' must be a mapping with xyz and rpy (got {tool!r})")
    else:
        for key in sorted(set(tool) - {"xyz", "rpy"}):
            problems.append(f"{tloc}: tool: unknown key {key!r} (expected xyz, rpy)")
        for key in ("xyz", "rpy"):
            vec = tool.get(key, [0.0, 0.0, 0.0])
            nums = [_number(v) for v in vec] if isinstance(vec, list) else []
            if len(nums) != 3 or any(n is None for n in nums):
                problems.append(f"{tloc}: tool: {key} must be 3 finite numbers (got {vec!r})")
                continue
            x, y, z = (float(n) for n in nums if n is not None)
            if key == "xyz":
                tool_xyz = (x, y, z)
            else:
                tool_rpy = (x * scale, y * scale, z * scale)
    if problems:
        raise ConfigError(
            problems[0]
            if len(problems) == 1
            else f"{len(problems)} problems found:\n" + "\n".join(problems)
        )
    return RobotDescription(
        name=str(name),
        joints=tuple(joints),
        tool_xyz=tool_xyz,
        tool_rpy=tool_rpy,
        description=str(data.get("description", "")),
        source=str(data.get("source", "")),
    )


def load_robot(name_or_path: str | Path = "irb140") -> RobotDescription:
    """Load a robot description: a shipped name (``"irb140"``) or a path to a YAML file.

    Raises
    ------
    ConfigError
        If the name is unknown, the file unreadable or malformed (every problem listed).
    """
    path = Path(name_or_path)
    if path.suffix in (".yaml", ".yml") or path.exists():
        text = read_document(path, ROBOT_DOCUMENT)
        source = str(path)
    else:
        resource = resources.files("fuzzkit").joinpath("data", f"{name_or_path}.yaml")
        if not resource.is_file():
            raise ConfigError(
                f"unknown robot {str(name_or_path)!r} (expected a shipped name such as "
                f"'irb140' or a path to a .yaml file)"
            )
        text = resource.read_text(encoding="utf-8")
        source = f"fuzzkit/data/{name_or_path}.yaml"
    return _parsed(text, source)


@functools.lru_cache(maxsize=16)
def _parsed(text: str, source: str) -> RobotDescription:
    """The robot of ``text``, parsed once per process for the same text and source: every plant
    built (one per tuning candidate and case) loads its robot (the located reader costs about
    0.1 s a file). The description is frozen, so sharing it is safe; the file is still read
    every time, so an edit is seen."""
    # the hardened reader: size and alias limits, duplicate and boolean keys, located
    data = to_python(compose_document(text, source, ROBOT_DOCUMENT), source, ROBOT_DOCUMENT)
    return robot_from_mapping(data, source=source, text=text)
