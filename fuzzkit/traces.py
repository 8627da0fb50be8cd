"""Rerun recordings (.rrd) of closed-loop runs, written atomically, viewable with ``rerun FILE``.

Entity layout (timeline ``sim_time``, a duration in seconds):

* ``forces/<axis>/measured``, ``forces/<axis>/setpoint``, ``forces/<axis>/true`` (N, task frame)
* ``control/<axis>/e``, ``/de`` (N), ``/du``, ``/u`` (mm) for every force-controlled axis
* ``joints/q<i>`` (rad)
* ``world/arm`` (line strip base -> joints -> tool tip), ``world/tool`` (tool contact disc),
  ``world/contacts`` (contact points), ``world/tool_path`` and ``world/nominal_path`` (static),
  ``world/environment/<name>`` (static outlines of the table, hammer, workpiece, wall)

Everything in ``world/`` is in metres, base frame.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import ConfigError
from fuzzkit.experiments import AXES, RunResult
from fuzzkit.plant import Box, EnvObject, RoughSurface, Table, nominal_position
from fuzzkit.rrd import log_series, open_recording

Vec = npt.NDArray[np.float64]

_AXIS_COLOURS = {"x": (230, 80, 60), "y": (60, 170, 80), "z": (60, 110, 230)}


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


def log_control_series(rec: Any, result: RunResult, times: Any) -> None:
    """Log the force and control time series of a run (any plant) on the ``times`` column."""
    for i, axis in enumerate(AXES):
        c = _AXIS_COLOURS[axis]
        dim = (int(0.5 * c[0] + 100), int(0.5 * c[1] + 100), int(0.5 * c[2] + 100))
        log_series(
            rec, f"forces/{axis}/measured", times, result.force[:, i], f"f{axis} measured", c
        )
        log_series(rec, f"forces/{axis}/true", times, result.force_true[:, i], f"f{axis} true", dim)
        if result.experiment.selection[i]:
            log_series(
                rec,
                f"forces/{axis}/setpoint",
                times,
                result.setpoint[:, i],
                f"f{axis} set",
                (0, 0, 0),
            )
            log_series(rec, f"control/{axis}/e", times, result.e[:, i], f"e{axis} (N)", c)
            log_series(rec, f"control/{axis}/de", times, result.de[:, i], f"de{axis} (N)", c)
            log_series(rec, f"control/{axis}/du", times, result.du[:, i] * 1e3, f"du{axis} (mm)", c)
            log_series(rec, f"control/{axis}/u", times, result.u[:, i] * 1e3, f"u{axis} (mm)", c)


def log_paths(rec: Any, result: RunResult) -> None:
    """Log the nominal (programmed) path and the path the tool actually took, static."""
    import rerun as rr

    path = result.experiment.scenario.path
    t_path = np.linspace(path[0].t_s, path[-1].t_s, 200)
    nominal = np.array([nominal_position(path, float(t)) for t in t_path])
    rec.log("world/nominal_path", rr.LineStrips3D([nominal], colors=[(150, 150, 150)]), static=True)
    rec.log(
        "world/tool_path",
        rr.LineStrips3D([result.tool_position], colors=[(60, 110, 230)]),
        static=True,
    )


def write_rrd(result: RunResult, path: str | os.PathLike[str], geometry_every: int = 5) -> Path:
    """Write ``result`` as a Rerun recording at ``path`` (temporary file, then rename).

    ``geometry_every``: log the arm and contacts every that many controller periods (the
    time series are always complete).
    """
    import rerun as rr

    exp = result.experiment
    with open_recording(
        path, f"fuzzkit_{exp.name}_{result.controller}", f"{exp.name}-{result.controller}"
    ) as rec:
        times = rr.TimeColumn("sim_time", duration=result.t)
        log_control_series(rec, result, times)
        for j in range(result.joint_angles.shape[1]):
            log_series(
                rec,
                f"joints/q{j + 1}",
                times,
                result.joint_angles[:, j],
                f"q{j + 1} (rad)",
                (120, 120, 120),
            )

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
        radius = scn.tool.radius_m
        for k in range(0, len(result.t), max(1, geometry_every)):
            rec.set_time("sim_time", duration=float(result.t[k]))
            arm = result.arm_points[k]
            rec.log("world/arm", rr.LineStrips3D([arm], colors=[(40, 40, 40)], radii=[0.006]))
            tip = arm[-1]
            rec.log(
                "world/tool",
                rr.LineStrips3D(
                    [_circle(float(tip[0]), float(tip[2]), radius)], colors=[(0, 120, 200)]
                ),
            )
            pts = result.contact_points[k]
            rec.log(
                "world/contacts",
                rr.Points3D(pts.reshape(-1, 3), colors=[(230, 40, 40)], radii=[0.004]),
            )
    return Path(path)


def write_run_rrd(result: RunResult, path: str | os.PathLike[str]) -> Path:
    """Write a run's recording with the drawing its plant needs (planar, or 3-D for arm6)."""
    if result.joint_angles.ndim == 2 and result.joint_angles.shape[1] == 6:
        from fuzzkit.traces_arm6 import write_rrd as write_arm6_rrd

        return write_arm6_rrd(result, path)
    return write_rrd(result, path)
