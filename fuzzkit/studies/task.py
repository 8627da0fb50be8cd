"""The experiment model: a world (:class:`~fuzzkit.plants.contract.Scenario`) plus the
force-control task in it. Scenario files (:mod:`fuzzkit.studies.scenario_file`) build it."""

from __future__ import annotations

from dataclasses import dataclass

from fuzzkit.plants.contract import Scenario

AXES = ("x", "y", "z")

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
