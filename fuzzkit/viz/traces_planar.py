"""Rerun recordings (.rrd) of closed-loop runs on the planar plant, written atomically, viewable
with ``rerun FILE``.

Entity layout (timeline ``sim_time``, a duration in seconds):

* ``forces/<axis>/measured``, ``forces/<axis>/true`` (N, task frame; x and z: the planar arm
  has no y) and ``forces/<axis>/setpoint`` for every force-controlled axis
* ``control/error/<axis>/e``, ``/de`` (N) and ``control/correction/<axis>/du`` (mm) from the
  moment the force loop engages, ``control/correction/<axis>/u`` (mm) from the start, for every
  force-controlled axis; every series name ends with its unit
* ``control/rules/<axis>`` (text: the fuzzy-PI's strongest rules and strengths per controlled
  period) and ``control/rules/<axis>/strongest`` (0-1), when the writer is given the rule base
* ``world/axes`` (labelled x, y, z arrows, 0.1 m)
* ``joints/q<i>`` (rad, one colour each)
* ``world/arm`` (line strip base -> joints -> tool tip), ``world/tool`` (tool contact disc),
  ``world/contacts`` (contact points), ``world/tool_path`` and ``world/nominal_path`` (static),
  ``world/environment/<name>`` (static outlines of the table, hammer, workpiece, wall)

Everything in ``world/`` is in metres, base frame, z up. The file carries a blueprint
(:mod:`fuzzkit.viz.blueprints`): the viewer opens on force vs set point per axis, the control
signals and the 3-D scene (:mod:`fuzzkit.viz.run_series` for the colours and the camera).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import ConfigError
from fuzzkit.loop.result import RunResult
from fuzzkit.plants.environment import Box, EnvObject, RoughSurface, Table
from fuzzkit.viz.recording import open_recording
from fuzzkit.viz.rule_activity import RuleRecording
from fuzzkit.viz.run_series import (
    ARM_COLOUR,
    TOOL_COLOUR,
    contact_columns,
    log_control_series,
    log_geometry,
    log_joint_angles,
    log_paths,
    log_world_axes,
    run_recording_blueprint,
)

#: The task axes of the planar arm (it moves in the x-z plane).
PLANAR_AXES = ("x", "z")

Vec = npt.NDArray[np.float64]


def _outline(obj: EnvObject, x_lo: float, x_hi: float) -> Vec:
    """A polyline (k, 3) drawing an environment object in the x-z plane."""
    if isinstance(obj, Table):
        lo, hi = max(obj.x_min, x_lo), min(obj.x_max, x_hi)
        return np.array([[lo, 0.0, obj.height_m], [hi, 0.0, obj.height_m]])
    if isinstance(obj, Box):
        hx, hz = 0.5 * obj.size_x, 0.5 * obj.size_z
        cx, cz = obj.center_x, obj.center_z
        corners = [(-hx, -hz), (hx, -hz), (hx, hz), (-hx, hz), (-hx, -hz)]
        return np.array([[cx + a, 0.0, cz + b] for a, b in corners])
    if isinstance(obj, RoughSurface):
        xs = np.linspace(obj.x_min, obj.x_max, max(2, int((obj.x_max - obj.x_min) / 0.001)))
        return np.array([[x, 0.0, obj.height(float(x))] for x in xs])
    raise ConfigError(f"cannot draw environment object {obj!r}")


def _circle(cx: float, cz: float, r: float, n: int = 24) -> list[list[float]]:
    a = np.linspace(0.0, 2.0 * math.pi, n + 1)
    return [[cx + r * math.cos(t), 0.0, cz + r * math.sin(t)] for t in a]


def write_rrd(
    result: RunResult,
    path: str | os.PathLike[str],
    geometry_every: int = 5,
    rules: RuleRecording | None = None,
) -> Path:
    """Write ``result`` as a Rerun recording at ``path`` (temporary file, then rename).

    ``geometry_every``: log the arm and contacts every that many controller periods (the
    time series are always complete).
    """
    import rerun as rr

    exp = result.experiment
    with open_recording(
        path,
        f"fuzzkit_{exp.name}_{result.controller}",
        f"{exp.name}-{result.controller}",
        blueprint=run_recording_blueprint(
            result, f"{exp.name} {result.controller}, planar arm", rules=rules is not None
        ),
    ) as rec:
        times = rr.TimeColumn("sim_time", duration=result.t)
        log_control_series(rec, result, times, PLANAR_AXES)
        if rules is not None:
            rules.log(rec)
        log_world_axes(rec)
        names = [f"q{j + 1}" for j in range(result.joint_angles.shape[1])]
        log_joint_angles(rec, times, result.joint_angles, names, "rad")

        scn = exp.scenario
        xs = [w.x for w in scn.path] + [float(p[0]) for p in result.tool_position]
        x_lo, x_hi = min(xs) - 0.1, max(xs) + 0.1
        for k, obj in enumerate(scn.objects):
            rec.log(
                f"world/environment/{obj.name or k}",
                rr.LineStrips3D([_outline(obj, x_lo, x_hi)], colors=[(140, 110, 80)]),
                static=True,
            )
        log_paths(rec, result)
        frames = np.arange(0, len(result.t), max(1, geometry_every))
        arms = [result.arm_points[k] for k in frames]
        radius = scn.tool.radius_m
        tools = [_circle(float(arm[-1][0]), float(arm[-1][2]), radius) for arm in arms]
        log_geometry(
            rec,
            result.t[frames],
            {
                "world/arm": rr.LineStrips3D.columns(
                    strips=arms, colors=[ARM_COLOUR] * len(frames), radii=[0.006] * len(frames)
                ),
                "world/tool": rr.LineStrips3D.columns(
                    strips=tools, colors=[TOOL_COLOUR] * len(frames)
                ),
                "world/contacts": contact_columns(result, frames),
            },
        )
    return Path(path)
