"""Rerun recordings (.rrd) of closed-loop runs on the 6-DOF arm (``--plant arm6``), in 3-D.

Same time series as :mod:`fuzzkit.viz.traces` (so the two plants' recordings compare side by side),
plus the arm in three dimensions. Entity layout (timeline ``sim_time``, a duration in seconds):

* ``forces/<axis>/measured``, ``/true``, ``/setpoint`` (N, task frame)
* ``control/error/<axis>/e``, ``/de`` (N), ``control/correction/<axis>/du``, ``/u`` (mm) for
  every force-controlled axis; every series name ends with its unit
* ``world/axes`` (labelled x, y, z arrows, 0.1 m); the file carries the same blueprint as the
  planar recordings (:mod:`fuzzkit.viz.blueprints`)
* ``joints/axis<i>`` (degrees, one colour each): the IRB 140's six axis angles
* e, de and du start when the force loop engages, u at the start (as the planar recording)
* ``world/arm`` (line strip: base, every DH frame origin, flange, TCP), ``world/tool`` (the tool
  axis from flange to tip and its contact sphere), ``world/force`` (arrow at the tool tip: the
  force the tool exerts on the environment, 2 mm per N), ``world/contacts``
* static: ``world/environment/<name>`` (3-D boxes, table rectangles, the rough workpiece as
  a wire surface), ``world/nominal_path``, ``world/tool_path``, ``world/robot_base``

Everything in ``world/`` is in metres in the scenario frame (the planar arm's frame), in which
the IRB 140's base sits at ``-workspace_offset`` (see :mod:`fuzzkit.plants.arm6`).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import ConfigError
from fuzzkit.loop.result import RunResult
from fuzzkit.plants.arm6 import Arm6Parameters
from fuzzkit.plants.environment3d import (
    Box3,
    EnvObject3,
    ExtrudedProfile,
    HeightField,
    Plane,
    objects_from_scenario,
)
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

Vec = npt.NDArray[np.float64]

_ENV = (140, 110, 80)
#: Arrow length per newton of contact force (m/N).
FORCE_SCALE_M_PER_N = 0.002


def _wire(obj: EnvObject3, x_lo: float, x_hi: float) -> list[Vec]:
    """Line strips drawing a 3-D object that Boxes3D cannot (planes, surfaces)."""
    if isinstance(obj, Plane):
        y0, y1 = max(obj.y_min, -0.3), min(obj.y_max, 0.3)
        nx, ny, nz = obj.normal
        px, py, pz = obj.point
        if abs(nz) < abs(nx):  # a wall: a 100 mm high rectangle in the plane, along y
            corners = [(y0, pz), (y1, pz), (y1, pz + 0.1), (y0, pz + 0.1), (y0, pz)]
            return [
                np.array([[px - (ny * (y - py) + nz * (z - pz)) / nx, y, z] for y, z in corners])
            ]
        lo, hi = max(obj.x_min, x_lo), min(obj.x_max, x_hi)
        z = pz  # the scenario's tables are horizontal
        return [np.array([[lo, y0, z], [hi, y0, z], [hi, y1, z], [lo, y1, z], [lo, y0, z]])]
    if isinstance(obj, ExtrudedProfile):
        s = obj.surface
        xs = np.linspace(s.x_min, s.x_max, max(2, int((s.x_max - s.x_min) / 0.002)))
        hs = np.array([s.height(float(x)) for x in xs])
        strips = [
            np.column_stack([xs, np.full_like(xs, y), hs])
            for y in np.linspace(obj.y_min, obj.y_max, 5)
        ]
        for x, h in ((xs[0], hs[0]), (xs[-1], hs[-1])):
            strips.append(np.array([[x, obj.y_min, h], [x, obj.y_max, h]]))
        return strips
    if isinstance(obj, HeightField):
        grid = np.asarray(obj.heights, dtype=np.float64)
        gx = obj.x0 + obj.dx * np.arange(grid.shape[0])
        gy = obj.y0 + obj.dy * np.arange(grid.shape[1])
        step = max(1, grid.shape[1] // 10)
        return [
            np.column_stack([gx, np.full_like(gx, gy[j]), grid[:, j]])
            for j in range(0, grid.shape[1], step)
        ]
    raise ConfigError(f"cannot draw environment object {obj!r}")


def write_rrd(
    result: RunResult,
    path: str | os.PathLike[str],
    geometry_every: int = 5,
    params: Arm6Parameters | None = None,
    rules: RuleRecording | None = None,
) -> Path:
    """Write an arm6 run as a 3-D Rerun recording at ``path`` (temporary file, then rename).

    Parameters
    ----------
    result:
        A run of :func:`fuzzkit.studies.experiments.run` on the ``arm6`` plant.
    path:
        Output ``.rrd`` file; its folder must exist.
    geometry_every:
        Log the arm, tool, force arrow and contacts every that many periods (time series are
        always complete).
    params:
        The plant parameters of the run (for the robot base position); defaults.

    Raises
    ------
    ConfigError
        If the output path is a folder or its folder is missing, or the run is not 6-DOF.
    """
    import rerun as rr

    if result.joint_angles.ndim != 2 or result.joint_angles.shape[1] != 6:
        raise ConfigError(
            f"run on plant {result.plant!r} has {result.joint_angles.shape[-1]} joints "
            f"(expected an arm6 run; use fuzzkit.viz.traces.write_rrd for the planar arm)"
        )
    p = params or Arm6Parameters()
    exp = result.experiment
    scn = exp.scenario
    base = -np.asarray(p.workspace_offset)
    base_box = base + np.array([[-0.1, -0.1, 0.0], [0.1, 0.1, 0.1]])
    title = f"{exp.name} {result.controller}, 6-DOF arm"
    with open_recording(
        path,
        f"fuzzkit_{exp.name}_{result.controller}_arm6",
        f"{exp.name}-{result.controller}-arm6",
        blueprint=run_recording_blueprint(result, title, base_box, rules=rules is not None),
    ) as rec:
        times = rr.TimeColumn("sim_time", duration=result.t)
        log_control_series(rec, result, times)
        if rules is not None:
            rules.log(rec)
        log_world_axes(rec)
        names = [f"axis {j + 1}" for j in range(6)]
        log_joint_angles(rec, times, np.degrees(result.joint_angles), names, "deg")

        # static world: environment, paths, robot base
        xs = [w.x for w in scn.path] + [float(v) for v in result.tool_position[:, 0]]
        x_lo, x_hi = min(xs) - 0.1, max(xs) + 0.1
        for k, obj in enumerate(objects_from_scenario(scn) + p.extra_objects):
            entity = f"world/environment/{obj.name or k}"
            if isinstance(obj, Box3):
                rec.log(
                    entity,
                    rr.Boxes3D(centers=[obj.center], half_sizes=[obj.half_size], colors=[_ENV]),
                    static=True,
                )
            else:
                rec.log(entity, rr.LineStrips3D(_wire(obj, x_lo, x_hi), colors=[_ENV]), static=True)
        log_paths(rec, result)
        rec.log(
            "world/robot_base",
            rr.Boxes3D(
                centers=[base + np.array([0.0, 0.0, 0.05])],
                half_sizes=[[0.1, 0.1, 0.05]],
                colors=[ARM_COLOUR],
            ),
            static=True,
        )

        # moving geometry
        frames = np.arange(0, len(result.t), max(1, geometry_every))
        arms = [result.arm_points[k] for k in frames]
        tips = np.array([arm[-1] for arm in arms]).reshape(-1, 3)
        forces = np.array([scn.rotation @ np.nan_to_num(result.force_true[k]) for k in frames])
        n = len(frames)
        log_geometry(
            rec,
            result.t[frames],
            {
                "world/arm": rr.LineStrips3D.columns(
                    strips=[arm[:-1] for arm in arms], colors=[ARM_COLOUR] * n, radii=[0.012] * n
                ),
                "world/tool/axis": rr.LineStrips3D.columns(
                    strips=[arm[-2:] for arm in arms], colors=[TOOL_COLOUR] * n, radii=[0.006] * n
                ),
                "world/tool/sphere": rr.Points3D.columns(
                    positions=tips,
                    radii=[scn.tool.radius_m] * n,
                    colors=[(*TOOL_COLOUR, 120)] * n,
                ),
                "world/force": rr.Arrows3D.columns(
                    origins=tips,
                    vectors=forces.reshape(-1, 3) * FORCE_SCALE_M_PER_N,
                    colors=[(220, 30, 30)] * n,
                    radii=[0.003] * n,
                ),
                "world/contacts": contact_columns(result, frames),
            },
        )
    return Path(path)
