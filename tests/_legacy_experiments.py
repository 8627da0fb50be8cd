"""E1-E3 as the Python definitions built them before they became scenario files.

A frozen copy, kept only as the reference the shipped files are compared with
(tests/test_scenario_file.py): the scenario loader must not be its own reference.
"""

from __future__ import annotations

import math

from fuzzkit.plants.contact import ContactModel, SensorModel, ToolModel
from fuzzkit.plants.contract import Scenario
from fuzzkit.plants.environment import Box, RoughSurface, Table, Waypoint
from fuzzkit.studies.experiments import Experiment


def e1() -> Experiment:
    table_z = -0.30
    cup = ToolModel(length_m=0.14, radius_m=0.035, name="cup")
    # The hammer lies on the table where the CAD cell has nothing: 4 cm high.
    hammer = Box(center_x=0.47, center_z=table_z + 0.02, size_x=0.12, size_z=0.04, name="hammer")
    place = (0.52, table_z + cup.radius_m)  # the nominal place pose: cup on the bare table
    start = (0.40, -0.19)
    dist = math.hypot(place[0] - start[0], place[1] - start[1])
    t_end = 0.2 + dist / 0.04  # 40 mm/s approach
    scn = Scenario(
        name="E1",
        description="cup carried towards the table meets an unexpected hammer",
        path=(
            Waypoint(0.0, start[0], 0.0, start[1]),
            Waypoint(0.2, start[0], 0.0, start[1]),
            Waypoint(t_end, place[0], 0.0, place[1]),
        ),
        objects=(Table(table_z), hammer),
        duration_s=5.0,
        contact=ContactModel(stiffness_n_per_m=1.0e4, damping_n_s_per_m=50.0, friction=0.4),
        sensor=SensorModel(rate_hz=250.0, noise_std_n=0.1),
        tool=cup,
    )
    return Experiment(
        name="E1",
        title="cup meets an unexpected hammer: 10 N along z, 0 N along x",
        scenario=scn,
        setpoints=(0.0, 0.0, 10.0),
        selection=(True, False, True),
        force_limit_n=25.0,
        engage_threshold_n=1.0,
        hold_path_on_contact=True,
        steady_window_s=1.0,
    )


def _workpiece(seed: int, x_max: float = 0.70) -> RoughSurface:
    # CAD says the top is flat at z = -0.30; really it is 1 mm higher and tilted down by 0.8 deg.
    return RoughSurface(
        x_min=0.30,
        x_max=x_max,
        height_m=-0.30,
        offset_m=0.001,
        tilt_rad=math.radians(-0.8),
        roughness_rms_m=0.0002,
        seed=seed,
        name="workpiece",
    )


def e2() -> Experiment:
    # Tip height 2 mm into the CAD surface (20 mm probe): the usual programmed interference that
    # makes sure the tool finds a surface whose height is only roughly known.
    touch_z = -0.30 + 0.02 - 0.002
    path = (
        Waypoint(0.0, 0.35, 0.0, touch_z + 0.022),
        Waypoint(1.1, 0.35, 0.0, touch_z),  # 20 mm/s approach
        Waypoint(1.5, 0.35, 0.0, touch_z),
        Waypoint(1.5 + 0.25 / 0.025, 0.60, 0.0, touch_z),  # 25 mm/s along x
    )
    scn = Scenario(
        name="E2",
        description="straight path over a rough, tilted workpiece",
        path=path,
        objects=(_workpiece(seed=2),),
        duration_s=path[-1].t_s + 1.0,
        contact=ContactModel(stiffness_n_per_m=1.0e4, damping_n_s_per_m=50.0, friction=0.3),
    )
    return Experiment(
        name="E2",
        title="straight path on a rough workpiece: 30 N along z",
        scenario=scn,
        setpoints=(0.0, 0.0, 30.0),
        selection=(False, False, True),
        force_limit_n=60.0,
        engage_threshold_n=1.0,
        steady_window_s=1.0,
    )


def e3() -> Experiment:
    touch_z = -0.30 + 0.02 - 0.002
    wall_x = 0.545  # CAD says 0.55: the wall is 5 mm closer than programmed
    path = (
        Waypoint(0.0, 0.44, 0.0, touch_z + 0.022),
        Waypoint(1.1, 0.44, 0.0, touch_z),
        Waypoint(1.5, 0.44, 0.0, touch_z),
        Waypoint(1.5 + 0.09 / 0.025, 0.53, 0.0, touch_z),  # slide towards the CAD corner
    )
    wall = Box(center_x=wall_x + 0.025, center_z=-0.25, size_x=0.05, size_z=0.12, name="wall")
    scn = Scenario(
        name="E3",
        description="slide along a rough floor into a side wall",
        path=path,
        objects=(_workpiece(seed=3, x_max=wall_x + 0.05), wall),
        duration_s=path[-1].t_s + 2.0,
        contact=ContactModel(stiffness_n_per_m=1.0e4, damping_n_s_per_m=50.0, friction=0.15),
    )
    return Experiment(
        name="E3",
        title="floor and wall: 6 N along x, 30 N along z",
        scenario=scn,
        setpoints=(6.0, 0.0, 30.0),
        selection=(True, False, True),
        force_limit_n=60.0,
        engage_threshold_n=1.0,
        steady_window_s=1.0,
    )


LEGACY = {"E1": e1, "E2": e2, "E3": e3}
