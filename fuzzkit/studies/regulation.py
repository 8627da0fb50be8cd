"""The regulation task (shipped as ``scenarios/regulate.yaml``): a guarded approach onto a flat
surface, then hold. ``fuzzkit stability`` certifies against it and ``stability --simulate``
runs it, one stiffness per cell.

The file is the task at 10 N/mm. At another stiffness the approach speed changes with it
(:func:`approach_speed`), so that the impact stays small: at 1000 N/mm the impact of a faster
approach passes the safety limit before any controller can react, and the certificate is about
the loop, not the impact. The tool always meets the surface :data:`APPROACH_S` after the start.
"""

from __future__ import annotations

from dataclasses import replace

from fuzzkit.control.impact import impact_speed_for
from fuzzkit.errors import ConfigError
from fuzzkit.loop.task import Experiment
from fuzzkit.plants.environment import Table

#: The scenario name of the regulation task.
REGULATION_NAME = "regulate"
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
    return min(MAX_APPROACH_M_S, impact_speed_for(headroom, stiffness_n_per_m, DESIGN_DELAY_S))


def is_regulation(exp: Experiment) -> bool:
    """Whether ``exp`` is the regulation task (its approach follows the stiffness)."""
    return exp.name == REGULATION_NAME


def surface_height(exp: Experiment) -> float:
    """The height (m, base frame) of the regulation task's table.

    Raises
    ------
    ConfigError
        If ``exp`` has no table.
    """
    tables = [o for o in exp.scenario.objects if isinstance(o, Table)]
    if not tables:
        raise ConfigError(f"{exp.name}: the regulation task needs a table to approach")
    return float(tables[0].height_m)


def regulation_at(exp: Experiment, stiffness_n_per_m: float) -> Experiment:
    """The regulation task ``exp`` on a surface of another stiffness, approached at
    :func:`approach_speed` for it: the path starts ``speed * APPROACH_S`` above the surface and
    descends at that speed for the whole run.

    Raises
    ------
    ConfigError
        If ``exp`` has no table or no force-controlled z axis to approach it with.
    """
    scn = exp.scenario
    if not exp.selection[2]:
        raise ConfigError(f"{exp.name}: the regulation task needs force control on z")
    setpoint = float(exp.setpoints[2])
    speed = approach_speed(stiffness_n_per_m, exp.force_limit_n, setpoint)
    z0 = surface_height(exp) + scn.tool.radius_m + speed * APPROACH_S
    start = scn.path[0]
    end = replace(start, t_s=scn.duration_s, z=z0 - speed * scn.duration_s)
    return replace(
        exp,
        scenario=replace(
            scn,
            path=(replace(start, t_s=0.0, z=z0), end),
            contact=replace(scn.contact, stiffness_n_per_m=stiffness_n_per_m),
        ),
    )
