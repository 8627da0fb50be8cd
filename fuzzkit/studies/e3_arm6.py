"""Experiment 3 as the paper ran it, on the 6-DOF plant: a path along an uncontrolled direction.

The paper's E3 keeps 30 N along z against the workpiece and 6 N along x against a side wall
while the robot moves; the motion is along the third direction, which the force loop does not
control (selection ``S = diag(1, 0, 1)``). That needs a world that varies along y, which the
planar plant (an x-z world extruded along y) cannot express: its E3
(:func:`fuzzkit.studies.experiments.experiment` ``"E3"``) slides *along x into* the wall
instead, so its x force follows a ramp (docs/simulation.md says how the two differ).

World (scenario frame, like every scenario; the plant places it in the IRB 140's frame):

* a rough floor, a :class:`~fuzzkit.plants.environment3d.HeightField` rough in x *and* y
  (0.2 mm RMS, 2 mm grid), 1 mm higher than the CAD floor at z = -0.30 and tilted by 0.8 deg
  along the path, as E2's workpiece;
* a side wall, a :class:`~fuzzkit.plants.environment3d.Plane` facing -x, 1 mm further away than the
  CAD wall at x = 0.55 where the path starts, and receding by 0.5 deg (1.75 mm over the
  path), so x has a slow disturbance to follow as z has the tilt (down 2.8 mm over the path);
* the nominal path: a diagonal approach at 20 mm/s (22 mm in x and z) onto the CAD corner,
  ending with the tool 1 mm into the CAD wall (so just touching the real one) and 2 mm into
  the CAD floor (programmed interference, as E2); 0.4 s at rest; then 200 mm along +y at
  25 mm/s.

The force loop engages on contact and controls x and z; y follows the path.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from fuzzkit.loop.adapter import make_plant
from fuzzkit.plants.arm6 import Arm6Parameters, Arm6Plant
from fuzzkit.plants.contact import ContactModel
from fuzzkit.plants.contract import ContactPlant, Scenario
from fuzzkit.plants.environment import Waypoint
from fuzzkit.plants.environment3d import EnvObject3, HeightField, Plane
from fuzzkit.studies.experiments import Experiment, experiment

#: CAD heights and positions (scenario frame, m) and the real deviations of the workpiece.
FLOOR_CAD_Z = -0.30
WALL_CAD_X = 0.55
FLOOR_OFFSET_M = 0.001
FLOOR_TILT_DEG = -0.8  # along the path (y)
WALL_OFFSET_M = 0.001  # at the path start the wall is this much further than programmed
WALL_YAW_DEG = 0.5  # the wall is not quite parallel to the path
Y_START, Y_END = -0.10, 0.10
SPEED_M_S = 0.025
#: the approach comes diagonally from this far off both surfaces (m), so that the tool meets
#: floor and wall at nearly the same time instead of dragging along one to reach the other
APPROACH_M = 0.022


def _floor(seed: int) -> HeightField:
    field = HeightField.rough(
        (0.40, WALL_CAD_X + 0.01),
        (Y_START - 0.03, Y_END + 0.03),
        height=FLOOR_CAD_Z + FLOOR_OFFSET_M,
        roughness_rms=0.0002,
        spacing=0.002,
        seed=seed,
        name="floor",
    )
    slope = math.tan(math.radians(FLOOR_TILT_DEG))
    ys = field.y0 + field.dy * np.arange(len(field.heights[0]))
    tilted = np.asarray(field.heights) + slope * (ys - Y_START)[None, :]
    return dataclasses.replace(field, heights=tuple(tuple(float(v) for v in r) for r in tilted))


def _wall() -> Plane:
    yaw = math.radians(WALL_YAW_DEG)
    return Plane(
        point=(WALL_CAD_X + WALL_OFFSET_M, Y_START, FLOOR_CAD_Z),
        normal=(-math.cos(yaw), math.sin(yaw), 0.0),
        x_min=WALL_CAD_X - 0.06,  # the tool's centre is near the wall, never deep inside it
        x_max=WALL_CAD_X + 0.02,
        y_min=Y_START - 0.03,
        y_max=Y_END + 0.03,
        name="side_wall",
    )


def objects(seed: int = 3) -> tuple[EnvObject3, ...]:
    """The floor and the side wall of the 3-D E3, scenario frame."""
    return (_floor(seed), _wall())


def e3_arm6_experiment() -> Experiment:
    """E3 along y: 30 N on z against the rough floor, 6 N on x against the side wall."""
    planar = experiment("E3")
    radius = planar.scenario.tool.radius_m
    x = WALL_CAD_X - radius + 0.001  # 1 mm into the CAD wall
    touch_z = FLOOR_CAD_Z + radius - 0.002  # 2 mm into the CAD floor
    t_land = 1.1
    t_go = 1.5
    t_end = t_go + (Y_END - Y_START) / SPEED_M_S
    path = (
        Waypoint(0.0, x - APPROACH_M, Y_START, touch_z + APPROACH_M),  # diagonal, 20 mm/s
        Waypoint(t_land, x, Y_START, touch_z),
        Waypoint(t_go, x, Y_START, touch_z),
        Waypoint(t_end, x, Y_END, touch_z),
    )
    scn = Scenario(
        name="E3",
        description="slide along y over a rough floor beside a side wall (6-DOF, as the paper)",
        path=path,
        objects=(),  # 3-D objects: see make_e3_arm6_plant
        duration_s=t_end + 1.0,
        contact=ContactModel(stiffness_n_per_m=1.0e4, damping_n_s_per_m=50.0, friction=0.15),
        tool=planar.scenario.tool,
    )
    return dataclasses.replace(
        planar,
        title="path along y over a rough floor beside a wall: 6 N along x, 30 N along z",
        scenario=scn,
    )


def make_e3_arm6_plant() -> Arm6Plant:
    """The IRB 140 plant with the 3-D E3's floor and wall (picklable factory, for tuning)."""
    return Arm6Plant(Arm6Parameters(extra_objects=objects()))


def resolve(name: str, plant: str) -> tuple[Experiment, ContactPlant]:
    """The experiment ``name`` and the plant to run it on.

    ``E3`` on ``arm6`` is the paper's geometry (this module); every other pair is the shared
    definition of :mod:`fuzzkit.studies.experiments` on :func:`~fuzzkit.loop.adapter.make_plant`.
    """
    if name.upper() == "E3" and plant == "arm6":
        return e3_arm6_experiment(), make_e3_arm6_plant()
    return experiment(name), make_plant(plant)
