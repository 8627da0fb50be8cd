"""The paper's three experiments, a plant-agnostic closed-loop runner, and force-control metrics.

* E1: a cup carried along a nominal path meets an unexpected hammer lying on the table; on
  contact the force loop takes over (the path is held) and keeps 10 N along z, 0 N along x.
* E2: a straight path over a rough, slightly tilted and offset workpiece keeping 30 N along z.
* E3: the tool slides along the rough floor of a workpiece towards a side wall it does not know
  precisely, keeping 30 N along z and 6 N along x (pressing into the wall once it reaches it).

The runner drives any ``fuzzkit.plants.contract.ContactPlant``; forces and corrections are in the
task frame (``fuzzkit.plants.contract`` explains frames and signs). Metrics are computed on the
*true* contact force, so the sensor noise is not counted as control error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import ConfigError
from fuzzkit.plants.contact import ContactModel, SensorModel, ToolModel
from fuzzkit.plants.contract import Scenario
from fuzzkit.plants.environment import Box, RoughSurface, Table, Waypoint

Vec = npt.NDArray[np.float64]

AXES = ("x", "y", "z")

#: Default gains, tuned by hand (like the paper's, "by trial and error") for the default contact
#: stiffness of 10 N/mm and a 4 ms period. PI: metres per newton. Fuzzy-PI: Ki scales e and Kp
#: scales de (1/N), Kx scales the output (m per step). Small-signal equivalence with the
#: saturated-sum table: Kx*Ki = 1e-5 m/N = PI ki, Kx*Kp = 4e-5 m/N = PI kp.
DEFAULT_GAINS: dict[str, dict[str, float]] = {
    "pi": {"kp": 4.0e-5, "ki": 1.0e-5, "u_min": -0.05, "u_max": 0.05},
    "fuzzy-pi": {"kp": 0.2, "ki": 0.05, "kx": 2.0e-4, "u_min": -0.05, "u_max": 0.05},
}


#: Default (sensor, command) latency in periods of 4 ms: one period each way, as on an ABB EGM
#: cell (docs/simulation.md, "Latency", says why).
DEFAULT_LATENCY: tuple[int, int] = (1, 1)


@dataclass(frozen=True, slots=True)
class Experiment:
    """One experiment: a world plus what the force loop must do in it.

    ``setpoints`` and ``selection`` are per task axis (x, y, z). ``engage_threshold_n``: the
    force loop takes over when a measured force exceeds it (None: active from the start).
    ``hold_path_on_contact``: the nominal path stops when the loop takes over.
    ``steady_window_s``: the final stretch used for steady-state statistics.
    ``latency_periods``: (sensor-to-controller, controller-to-motion) delays in periods.
    ``engage_samples``: consecutive samples above the threshold needed to engage. ``fault``:
    the sensor fault kind injected by default (a name of ``fuzzkit.studies.faults.FAULTS``).
    """

    name: str
    title: str
    scenario: Scenario
    setpoints: tuple[float, float, float]
    selection: tuple[bool, bool, bool]
    force_limit_n: float
    engage_threshold_n: float | None = 1.0
    hold_path_on_contact: bool = False
    steady_window_s: float = 1.0
    latency_periods: tuple[int, int] = DEFAULT_LATENCY
    engage_samples: int = 3
    fault: str = "none"


def _e1() -> Experiment:
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


def _e2() -> Experiment:
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


def _e3() -> Experiment:
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


EXPERIMENTS = {"E1": _e1, "E2": _e2, "E3": _e3}


def experiment(name: str) -> Experiment:
    """The experiment called ``name`` (E1, E2, E3; case-insensitive)."""
    factory = EXPERIMENTS.get(name.upper())
    if factory is None:
        raise ConfigError(f"unknown experiment {name!r} (expected one of {', '.join(EXPERIMENTS)})")
    return factory()


def with_stiffness(exp: Experiment, stiffness_n_per_m: float) -> Experiment:
    """The same experiment in an environment of another contact stiffness."""
    scn = exp.scenario
    return replace(
        exp,
        scenario=replace(scn, contact=replace(scn.contact, stiffness_n_per_m=stiffness_n_per_m)),
    )


def press_experiment(stiffness_n_per_m: float, gap_m: float = 0.0002) -> Experiment:
    """E1's hammer, approached under force control from ``gap_m`` above it (path held).

    Isolates the force loop's stability from the impact of a moving approach: used for the
    stiffness study (10, 100, 1000 N/mm), where the approach speed is what the controller
    commands for a 10 N error.
    """
    e1 = _e1()
    hammer = next(o for o in e1.scenario.objects if isinstance(o, Box))
    top = hammer.center_z + 0.5 * hammer.size_z
    x = hammer.center_x
    z = top + e1.scenario.tool.radius_m + gap_m
    scn = replace(
        e1.scenario,
        name="press",
        description="press on the hammer from just above it",
        path=(Waypoint(0.0, x, 0.0, z),),
        duration_s=3.0,
        contact=replace(e1.scenario.contact, stiffness_n_per_m=stiffness_n_per_m),
    )
    return replace(
        e1,
        name="press",
        title="press 10 N on the hammer",
        scenario=scn,
        engage_threshold_n=None,
        hold_path_on_contact=False,
    )


def scaled_gains(kind: str, stiffness_n_per_m: float) -> dict[str, float]:
    """Default gains scaled for another contact stiffness (same loop gain ``Ki*k`` per step).

    The loop gain of the incremental force loop is ``Ki * k`` per period; the defaults are tuned
    for ``k = 10 N/mm``, so the correction gains are scaled by ``1e4 / k`` (``kx`` for fuzzy-PI).
    """
    g = dict(DEFAULT_GAINS[kind])
    factor = 1.0e4 / stiffness_n_per_m
    for key in ("kp", "ki") if kind == "pi" else ("kx",):
        g[key] *= factor
    return g
