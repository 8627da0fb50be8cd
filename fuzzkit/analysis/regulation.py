"""The regulation task the certificate is checked against: a guarded approach onto a flat
surface, then hold.

The tool starts above a flat table and descends along task z; when the force loop engages
(1 N on 3 samples, as in E1-E3) the path is held and the loop keeps ``setpoint_n`` along z.
The approach speed is set per stiffness so that the impact stays small
(:func:`approach_speed`): at 1000 N/mm the impact of a faster approach passes the safety limit
before any controller can react (:func:`impact_speed_limit`), and the certificate is about the
loop, not the impact. The tool meets the surface after :data:`APPROACH_S`.
"""

from __future__ import annotations

from dataclasses import replace

from fuzzkit.plants.environment import Table, Waypoint
from fuzzkit.studies.experiments import experiment
from fuzzkit.studies.task import Experiment

#: Height of the flat surface (m, scenario frame) and the tool's x above it.
SURFACE_Z = -0.3
TOOL_X = 0.42
#: Time from the start to the first touch (s).
APPROACH_S = 0.1
#: The reaction delay the approach speed is chosen for (s): engagement (3 samples), 4 + 4
#: periods of latency, the inner loop's lag, with room to spare.
DESIGN_DELAY_S = 0.1
#: Share of the force headroom (limit - set point) the impact may take.
IMPACT_SHARE = 0.2
#: Fastest approach (m/s), for soft surfaces.
MAX_APPROACH_M_S = 5.0e-3


def approach_speed(stiffness_n_per_m: float, limit_n: float, setpoint_n: float) -> float:
    """The approach speed (m/s) whose impact over :data:`DESIGN_DELAY_S` takes
    :data:`IMPACT_SHARE` of the headroom ``limit_n - setpoint_n``, at most
    :data:`MAX_APPROACH_M_S`."""
    headroom = IMPACT_SHARE * max(limit_n - setpoint_n, 0.0)
    return min(MAX_APPROACH_M_S, headroom / (stiffness_n_per_m * DESIGN_DELAY_S))


def regulation_experiment(
    stiffness_n_per_m: float = 1.0e4,
    setpoint_n: float = 10.0,
    duration_s: float = 3.0,
) -> Experiment:
    """A guarded approach onto a flat table at :func:`approach_speed`, then hold ``setpoint_n``.

    The world, sensor, tool, period and safety settings are E1's; only z is force controlled.
    """
    e1 = experiment("E1")
    scn = e1.scenario
    speed = approach_speed(stiffness_n_per_m, e1.force_limit_n, setpoint_n)
    z0 = SURFACE_Z + scn.tool.radius_m + speed * APPROACH_S
    depth = speed * duration_s
    scenario = replace(
        scn,
        name="regulate",
        description="guarded approach onto a flat table, then hold",
        path=(Waypoint(0.0, TOOL_X, 0.0, z0), Waypoint(duration_s, TOOL_X, 0.0, z0 - depth)),
        objects=(Table(height_m=SURFACE_Z),),
        duration_s=duration_s,
        contact=replace(scn.contact, stiffness_n_per_m=stiffness_n_per_m),
    )
    return replace(
        e1,
        name="regulate",
        title=f"guarded approach onto a flat surface, then hold {setpoint_n:g} N along z",
        scenario=scenario,
        setpoints=(0.0, 0.0, setpoint_n),
        selection=(False, False, True),
        hold_path_on_contact=True,
        steady_window_s=0.5,
    )


def impact_speed_limit(
    stiffness_n_per_m: float, limit_n: float, delay_s: float, setpoint_n: float = 0.0
) -> float:
    """The approach speed (m/s) above which the impact alone passes ``limit_n``.

    Before the loop can react to the contact, the tool keeps moving for ``delay_s`` (engagement,
    sensor and command delays, the inner loop's lag): the force reaches about
    ``stiffness * speed * delay_s``, whatever the controller. Above this speed no gains help.
    """
    if delay_s <= 0.0:
        return float("inf")
    return max(limit_n - setpoint_n, 0.0) / (stiffness_n_per_m * delay_s)


#: The scenario name ``fuzzkit stability`` and the validation use for :func:`regulation_experiment`.
REGULATION_NAME = "regulate"


def scenario(name: str) -> Experiment:
    """``regulate`` (:func:`regulation_experiment`), a shipped experiment, or a scenario file."""
    if name.lower() == REGULATION_NAME:
        return regulation_experiment()
    return experiment(name)
