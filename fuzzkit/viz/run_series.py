"""Time series, colours and the camera every run recording shares, whatever the plant.

Colours are chosen for the viewer's dark theme and its light one alike: one hue per task axis
(x red, y green, z blue), and within a plot every signal its own hue (never only a shade of
another): measured force in the axis's hue, true force grey, set point amber, the rates (de,
du) purple. Joint angles get one colour each.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.control.names import AXES
from fuzzkit.loop.result import RunResult
from fuzzkit.plants.environment import nominal_position
from fuzzkit.viz.blueprints import (
    ADAPTATION,
    CORRECTION,
    ERROR,
    FORCES,
    JOINTS,
    WORLD,
    run_blueprint,
)
from fuzzkit.viz.recording import AXIS_ARROW_COLOURS, log_axes, log_series

Colour = tuple[int, int, int]

AXIS_COLOURS: dict[str, Colour] = dict(zip(AXES, AXIS_ARROW_COLOURS, strict=True))
#: The plant's true contact force, beside the measured one (which carries the sensor's noise).
TRUE_COLOUR: Colour = (160, 160, 160)
#: Set points: amber, visible on the viewer's dark theme and on a light one.
SETPOINT_COLOUR: Colour = (250, 190, 30)
#: The rates beside their signal: de beside e, du beside u.
RATE_COLOUR: Colour = (170, 90, 225)
#: One colour per joint angle (tab10's mid tones: readable on both themes).
JOINT_COLOURS: tuple[Colour, ...] = (
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (227, 119, 194),
)
#: The arm, in both plants' recordings: orange, readable on both themes.
ARM_COLOUR: Colour = (230, 120, 20)
TOOL_COLOUR: Colour = (0, 140, 220)
#: Direction from the scene's centre to the default camera: in front (-y), a little to the
#: right and above, so the planar arm's x-z plane and the 6-DOF arm are seen at an angle.
EYE_DIRECTION = (0.45, -1.0, 0.5)
#: Camera distance per metre of the scene's largest extent (the whole arm and path in view).
EYE_DISTANCE_PER_EXTENT = 1.5


def engaged_index(result: RunResult) -> int:
    """The first sample at which the force loop was engaged (``len(t)`` if it never was)."""
    if result.engaged_time_s is None:
        return len(result.t)
    return int(np.searchsorted(result.t, result.engaged_time_s - 1e-12))


def log_control_series(
    rec: Any, result: RunResult, times: Any, task_axes: Sequence[str] = AXES
) -> None:
    """Log the force and control time series of a run (any plant) on the ``times`` column.

    Forces under ``forces/<axis>/`` (measured, true, set point; N), the force error and its
    change under ``control/error/<axis>/`` (N), the position correction and its sum under
    ``control/correction/<axis>/`` (mm): each subtree holds one unit, and every series name
    ends with its unit, as the blueprint's plots show them. ``task_axes``: the axes the plant
    has (the planar arm has no y). The controller's own signals (e, de, du) start when the
    loop engages: before, there is no error to speak of (0 N against a 10 N set point is not
    "no error"); u, the correction the plant received, is logged from the start (0 mm).
    """
    import rerun as rr

    start = engaged_index(result)
    engaged = rr.TimeColumn("sim_time", duration=result.t[start:])
    for i, axis in enumerate(AXES):
        if axis not in task_axes:
            continue
        c = AXIS_COLOURS[axis]
        f = f"{FORCES}/{axis}"
        log_series(rec, f"{f}/measured", times, result.force[:, i], f"f{axis} measured (N)", c)
        log_series(
            rec, f"{f}/true", times, result.force_true[:, i], f"f{axis} true (N)", TRUE_COLOUR
        )
        if not result.experiment.selection[i]:
            continue
        log_series(
            rec,
            f"{f}/setpoint",
            times,
            result.setpoint[:, i],
            f"f{axis} set point (N)",
            SETPOINT_COLOUR,
        )
        err, cor = f"{ERROR}/{axis}", f"{CORRECTION}/{axis}"
        log_series(rec, f"{cor}/u", times, result.u[:, i] * 1e3, f"u{axis} (mm)", c)
        if start < len(result.t):
            log_series(rec, f"{err}/e", engaged, result.e[start:, i], f"e{axis} (N)", c)
            log_series(
                rec, f"{err}/de", engaged, result.de[start:, i], f"de{axis} (N)", RATE_COLOUR
            )
            log_series(
                rec,
                f"{cor}/du",
                engaged,
                result.du[start:, i] * 1e3,
                f"du{axis} (mm)",
                RATE_COLOUR,
            )
        log_adaptation(rec, result, times, i)


def log_adaptation(rec: Any, result: RunResult, times: Any, i: int) -> None:
    """An adaptive run's scheduled output-gain factor (``adaptation/gain_scale/<axis>``) and
    stiffness estimate (``adaptation/stiffness/<axis>``, N/mm) of task axis ``i``."""
    if result.gain_scale is None or result.stiffness_n_mm is None:
        return
    axis, c = AXES[i], AXIS_COLOURS[AXES[i]]
    log_series(
        rec, f"{ADAPTATION}/gain_scale/{axis}", times, result.gain_scale[:, i],
        f"{axis} output gain factor (1)", c,
    )  # fmt: skip
    k = result.stiffness_n_mm[:, i]
    if not np.all(np.isnan(k)):
        log_series(
            rec, f"{ADAPTATION}/stiffness/{axis}", times, k, f"{axis} stiffness estimate (N/mm)", c
        )


def log_joint_angles(
    rec: Any, times: Any, angles: npt.ArrayLike, names: Sequence[str], unit: str
) -> None:
    """Log one series per joint under ``joints/<name>``, each in its own colour."""
    values = np.asarray(angles, dtype=np.float64)
    for j, name in enumerate(names):
        colour = JOINT_COLOURS[j % len(JOINT_COLOURS)]
        label = f"{name} ({unit})"
        log_series(rec, f"{JOINTS}/{name.replace(' ', '')}", times, values[:, j], label, colour)


def scene_eye(result: RunResult, extra: npt.ArrayLike | None = None) -> tuple[Any, Any]:
    """Camera position and target (m) that show the whole arm, base included, and its path.

    The scene is every arm point of the run (base to tool), the tool's path and ``extra``
    points (``(n, 3)``: the 6-DOF robot's base box ...).
    """
    pts = [np.asarray(p, dtype=np.float64).reshape(-1, 3) for p in result.arm_points]
    pts.append(np.asarray(result.tool_position, dtype=np.float64).reshape(-1, 3))
    if extra is not None:
        pts.append(np.asarray(extra, dtype=np.float64).reshape(-1, 3))
    cloud = np.concatenate(pts)
    cloud = cloud[np.all(np.isfinite(cloud), axis=1)]
    lo, hi = cloud.min(axis=0), cloud.max(axis=0)
    target = 0.5 * (lo + hi)
    extent = max(float(np.max(hi - lo)), 0.2)
    direction = np.asarray(EYE_DIRECTION) / np.linalg.norm(EYE_DIRECTION)
    eye = target + direction * EYE_DISTANCE_PER_EXTENT * extent
    return tuple(float(v) for v in eye), tuple(float(v) for v in target)


def run_recording_blueprint(
    result: RunResult,
    title: str,
    extra_scene_points: npt.ArrayLike | None = None,
    rules: bool = False,
) -> Any:
    """The default layout of a run's recording: per force-controlled axis its force, error
    and correction; the 3-D scene (camera on the whole arm) and the joint angles beside
    (``rules``: and the fuzzy-PI's strongest rules)."""
    controlled = [a for i, a in enumerate(AXES) if result.experiment.selection[i]]
    end = float(result.t[-1]) if len(result.t) else None
    eye = scene_eye(result, extra_scene_points)
    adaptive = result.gain_scale is not None
    return run_blueprint(controlled, title, eye, end, rules=rules, adaptive=adaptive)


def log_world_axes(rec: Any) -> None:
    """Label the 3-D scene's axes (metres, z up)."""
    import rerun as rr

    rec.log(WORLD, rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    log_axes(rec, f"{WORLD}/axes", ("x (m)", "y (m)", "z (m)"), 0.1)


def log_paths(rec: Any, result: RunResult) -> None:
    """Log the nominal (programmed) path and the path the tool actually took, static."""
    import rerun as rr

    path = result.experiment.scenario.path
    t_path = np.linspace(path[0].t_s, path[-1].t_s, 200)
    nominal = np.array([nominal_position(path, float(t)) for t in t_path])
    rec.log("world/nominal_path", rr.LineStrips3D([nominal], colors=[(150, 150, 150)]), static=True)
    rec.log(
        "world/tool_path",
        rr.LineStrips3D([result.tool_position], colors=[AXIS_COLOURS["z"]]),
        static=True,
    )


def log_geometry(rec: Any, times: npt.ArrayLike, columns: dict[str, Any]) -> None:
    """Log the moving geometry of a run, one row per entry of ``times`` (s) in each entity:
    ``columns`` maps an entity to its archetype's columns (``rr.LineStrips3D.columns(...)``,
    one row per time), sent at once instead of one log call per frame."""
    import rerun as rr

    index = rr.TimeColumn("sim_time", duration=np.asarray(times, dtype=np.float64))
    for entity, cols in columns.items():
        rec.send_columns(entity, indexes=[index], columns=cols)


#: The colour and radius (m) of the drawn contact points.
CONTACT_COLOUR, CONTACT_RADIUS_M = (230, 40, 40), 0.004


def contact_columns(result: RunResult, frames: npt.NDArray[np.int_]) -> list[Any]:
    """The contact points of ``frames`` (indices of ``result.t``) as ``rr.Points3D`` columns:
    each frame's points in one row (none: an empty row), with their colour and radius."""
    import rerun as rr

    points = [np.asarray(result.contact_points[k], dtype=np.float64).reshape(-1, 3) for k in frames]
    counts = [len(p) for p in points]
    positions = np.concatenate(points) if points else np.empty((0, 3))
    n = len(frames)
    return [
        *rr.Points3D.columns(positions=positions).partition(counts),
        *rr.Points3D.columns(colors=[CONTACT_COLOUR] * n, radii=[CONTACT_RADIUS_M] * n),
    ]
