"""The regulation task the certificate is checked against (``fuzzkit scenario regulate``): a
guarded approach onto a flat surface, then hold.

The tool starts above a flat table and descends along task z; when the force loop engages
(1 N on 3 samples, as in E1-E3) the path is held and the loop keeps ``setpoint_n`` along z.
The task is the shipped scenario file ``regulate.yaml`` (:mod:`fuzzkit.studies.regulation`);
at another stiffness its approach speed follows the stiffness, so that the impact stays small
(at 1000 N/mm the impact of a faster approach passes the safety limit before any controller can
react, :func:`impact_speed_limit`, and the certificate is about the loop, not the impact).
"""

from __future__ import annotations

from dataclasses import replace

from fuzzkit.control.impact import impact_speed_for
from fuzzkit.loop.task import Experiment
from fuzzkit.studies.experiments import experiment, with_stiffness
from fuzzkit.studies.regulation import (
    APPROACH_S,
    REGULATION_NAME,
    approach_speed,
    regulation_at,
)

__all__ = [
    "APPROACH_S",
    "REGULATION_NAME",
    "approach_speed",
    "impact_speed_limit",
    "regulation_at",
    "regulation_experiment",
    "scenario",
]


def regulation_experiment(
    stiffness_n_per_m: float = 1.0e4,
    setpoint_n: float = 10.0,
) -> Experiment:
    """The shipped ``regulate`` scenario at ``stiffness_n_per_m``, holding ``setpoint_n``."""
    exp = experiment(REGULATION_NAME)
    if setpoint_n != exp.setpoints[2]:
        exp = replace(
            exp,
            title=f"guarded approach onto a flat surface, then hold {setpoint_n:g} N along z",
            setpoints=(0.0, 0.0, setpoint_n),
        )
    return with_stiffness(exp, stiffness_n_per_m)


def impact_speed_limit(
    stiffness_n_per_m: float, limit_n: float, delay_s: float, setpoint_n: float = 0.0
) -> float:
    """The approach speed (m/s) above which the impact alone passes ``limit_n``.

    Before the loop can react to the contact, the tool keeps moving for ``delay_s`` (engagement,
    sensor and command delays, the inner loop's lag): the force rises by about
    ``stiffness * speed * delay_s`` above the set point, whatever the controller
    (:func:`fuzzkit.control.impact.impact_speed_for`). Above this speed no gains help.
    """
    return impact_speed_for(limit_n - setpoint_n, stiffness_n_per_m, delay_s)


def scenario(name: str) -> Experiment:
    """``regulate``, a shipped experiment, or a scenario file."""
    return experiment(name)
