"""One wrench sample in, the controller steps of the periods it closes out: the node's logic
without ROS.

:class:`Stepper` places each sample on the period grid (:mod:`~fuzzkit.ros2.sample_clock`),
steps the generated controller once for every period a sample missed (a NaN force: held) and
once for the sample itself, feeds the :mod:`~fuzzkit.ros2.watchdog`, and returns what the node
publishes. A late sample, or any sample after the watchdog expired, steps nothing.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from fuzzkit.ros2.controller import NodeController
from fuzzkit.ros2.sample_clock import SampleClock
from fuzzkit.ros2.watchdog import Watchdog

#: A missing sample, as the generated controller takes one.
MISSING = (math.nan, math.nan, math.nan)


@dataclass(frozen=True, slots=True)
class Step:
    """One controller period: its index and grid stamp (ns), the correction ``u`` and its change
    ``du`` since the previous period (m, x y z), and the status bits."""

    period: int
    stamp_ns: int
    u: tuple[float, float, float]
    du: tuple[float, float, float]
    status: int


@dataclass
class Counters:
    """What the node has seen since its start (the diagnostics report them)."""

    samples: int = 0
    steps: int = 0
    missing: int = 0
    late: int = 0
    refused_parameters: int = 0


class Stepper:
    """The node's controller loop (module docstring); ``watchdog_periods``: its timeout."""

    def __init__(self, controller: NodeController, watchdog_periods: int) -> None:
        self.controller = controller
        self.clock = SampleClock(controller.spec.period_s)
        self.watchdog = Watchdog(self.clock.period_ns, watchdog_periods)
        self.counters = Counters()
        self.last: Step | None = None

    def sample(
        self, stamp_ns: int, force_n: Sequence[float], rotation: Sequence[float] | None, now_ns: int
    ) -> list[Step]:
        """Step the sample stamped ``stamp_ns`` that arrived at ``now_ns`` (node clock): the steps
        taken, in period order (empty: late, or the watchdog has stopped the output)."""
        self.counters.samples += 1
        if self.watchdog.expired:
            return []
        placed = self.clock.place(stamp_ns)
        if placed.late:
            self.counters.late += 1
            return []
        if placed.missing >= self.watchdog.periods:
            self.watchdog.expire()  # the stamps say the sensor was silent that long
            return []
        self.watchdog.feed(now_ns)
        first = placed.period - placed.missing
        steps = [self._step(first + j, MISSING, rotation) for j in range(placed.missing)]
        self.counters.missing += placed.missing
        steps.append(self._step(placed.period, force_n, rotation))
        return steps

    def _step(
        self, period: int, force_n: Sequence[float], rotation: Sequence[float] | None
    ) -> Step:
        u, status = self.controller.step(force_n, rotation)
        prev = (0.0, 0.0, 0.0) if self.last is None else self.last.u
        ut = (float(u[0]), float(u[1]), float(u[2]))
        du = (ut[0] - prev[0], ut[1] - prev[1], ut[2] - prev[2])
        self.last = Step(period, self.clock.stamp_ns(period), ut, du, int(status))
        self.counters.steps += 1
        return self.last

    def check_watchdog(self, now_ns: int) -> bool:
        """True when the watchdog expires at this check (the node then reports it)."""
        return self.watchdog.check(now_ns)

    def reset(self) -> None:
        """The controller's reset, a new grid from the next sample, the watchdog disarmed."""
        self.controller.reset()
        self.clock.restart()
        self.watchdog.reset()
        self.last = None

    def tare(self) -> None:
        """The controller's tare request."""
        self.controller.tare()
