"""A run's timing: its ``(sensor, command)`` delays in periods, a fault's delay included, the
same for every loop."""

from __future__ import annotations

from fuzzkit.errors import ConfigError
from fuzzkit.loop.faults import Faults, fault
from fuzzkit.loop.task import Experiment


def run_faults_and_latency(
    exp: Experiment, seed: int, faults: Faults | None, latency: tuple[int, int] | None
) -> tuple[Faults, int, int]:
    """The faults and ``(sensor, command)`` delays a run uses: the experiment's where None (its
    fault kind seeded by ``seed``), the fault's delay added to the sensor delay. Both loops (this
    module and :mod:`fuzzkit.loop.compiled`) take them from here."""
    if faults is None:
        faults = fault(exp.fault, seed)
    sensor_delay, command_delay = check_latency(exp.latency_periods if latency is None else latency)
    return faults, sensor_delay + faults.delay_steps, command_delay


def check_latency(latency: tuple[int, int]) -> tuple[int, int]:
    """``(sensor_delay, command_delay)`` as non-negative integers, or a ConfigError."""
    if len(latency) != 2 or any(isinstance(v, bool) or int(v) != v or v < 0 for v in latency):
        raise ConfigError(
            f"latency must be (sensor_delay, command_delay), integers >= 0 (got {latency!r})"
        )
    return int(latency[0]), int(latency[1])
