"""What a closed-loop run produced: :class:`RunResult`, one row per controller period and a
summary, whichever loop ran it."""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from fuzzkit.loop.task import Experiment

Vec = npt.NDArray[np.float64]


@dataclass(slots=True)
class RunResult:
    """Everything a run produced: time series (one row per controller period) and a summary."""

    experiment: Experiment
    controller: str
    plant: str
    t: Vec
    # the sample the controller consumed (sensor_delay periods old), task frame (n, 3), NaN
    # where no valid sample reached the controller
    force: Vec
    force_sensor: Vec  # what the sensor interface delivered this period (after faults) (n, 3)
    force_true: Vec  # (n, 3)
    setpoint: Vec  # (n, 3)
    e: Vec
    de: Vec
    du: Vec
    u: Vec  # task-frame correction S*u (+ back-off), (n, 3)
    tool_position: Vec  # base frame (n, 3)
    nominal_position: Vec
    target_position: Vec  # nominal + the correction the plant received (base frame)
    joint_angles: Vec
    in_contact: npt.NDArray[np.bool_]  # any object touches the tool
    # normal contact force per task axis (n, 3), friction excluded (PlantSample.force_normal);
    # NaN rows when the plant does not report it
    force_normal: Vec
    moving: npt.NDArray[np.bool_]  # the nominal path was moving during that period
    arm_points: list[Vec]
    contact_points: list[Vec]
    faults: int
    tripped: bool
    seed: int  # of the sensor noise
    latency_periods: tuple[int, int]  # (sensor, command), fault delay included
    fault: str  # the fault kind's name in fuzzkit.loop.faults.FAULTS, or "custom"
    fault_seed: int
    trip_time_s: float | None
    engaged_time_s: float | None
    wall_time_s: float
    messages: dict[str, int] = field(default_factory=dict)
    #: which loop ran: "python" (this module) or "compiled" (fuzzkit.loop.compiled)
    loop: str = "python"
    #: CPU time of the loop alone (s, time.process_time), start-up excluded
    cpu_time_s: float = 0.0
    #: which controller implementation ran (exact engine, lookup table, generated C ...)
    controller_impl: str = ""
    #: adaptation (issue 24), per period and task axis: the factor of the output gain (n, 3)
    #: and the stiffness estimate (N/mm, NaN without a schedule); None for fixed gains
    gain_scale: Vec | None = None
    stiffness_n_mm: Vec | None = None
    #: the controller's status bits per period (fuzzkit.control.status), where it reports them
    #: (the Python loop's controller, the generated C controller); None otherwise
    status: npt.NDArray[np.int64] | None = None
    #: the tool's rotation (world-from-sensor, row-major, (n, 9)) the controller received with
    #: each consumed sample; None where not recorded
    rotation: Vec | None = None

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per CPU second of the loop."""
        return self.sim_time_s / self.cpu_time_s if self.cpu_time_s > 0.0 else math.inf

    @property
    def sim_time_s(self) -> float:
        """Simulated time covered by the run (s)."""
        return float(self.t[-1]) if len(self.t) else 0.0


def implementations(labels: Iterable[str]) -> str:
    """What ran a set of runs, for a header or a report line: their distinct ``controller_impl``
    (:attr:`RunResult.controller_impl`, the one label of what ran), in first-seen order."""
    distinct = list(dict.fromkeys(labels))
    return "; ".join(distinct) if distinct else "(no run)"
