"""A controller that is only a step function, as the simulated closed loop takes a controller:
the face of :class:`fuzzkit.control.controllers.HybridForceController` that
:func:`fuzzkit.loop.python_loop.run` reads (``hybrid=``).

The step function is the generated controller, called in this process or over ROS 2 by a plant
that steps in lockstep with the node (``tests/test_ros2_loop.py``): ``step(force, rotation) ->
(u, status)``. Everything the loop reads besides the correction comes from the status bits
(engaged, tripped, the trip's time, the sensor faults: held or rejected samples after the
tare); the generated controller keeps its error and change of error to itself, so ``e`` and
``de`` are NaN in the run's result.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
import numpy.typing as npt

from fuzzkit.control import status as st
from fuzzkit.control.spec import ControllerSpec

Vec = npt.NDArray[np.float64]
#: ``step(force_n, tool_rotation) -> (u, status)``.
StepFunction = Callable[[Sequence[float], Sequence[float] | None], tuple[Sequence[float], int]]


class StepController:
    """``spec``'s controller as the closed loop sees it, stepping through ``step``."""

    def __init__(self, spec: ControllerSpec, step: StepFunction) -> None:
        self.period_s = spec.period_s
        self._step = step
        self._needs_rotation = spec.sensor.tool is not None
        self.setpoints = np.array(spec.setpoints, dtype=np.float64)
        self.controllers: tuple[object, ...] = ()  # no adaptation seen from here
        self.e = np.full(3, math.nan)
        self.de = np.full(3, math.nan)
        self.du = np.zeros(3)
        self.u = np.zeros(3)
        self.status = 0
        self.faults = 0
        self.engaged = spec.safety.engage_threshold_n is None
        self.tripped = False
        self.trip_time_s: float | None = None
        self._t = 0.0

    def step(self, force: Vec | None, rotation: Vec | None = None, fault: bool = True) -> Vec:
        """One period on ``force`` (N; None or NaN: missing) and the tool's ``rotation``; a held
        or rejected sample counts as a sensor fault unless ``fault`` is False."""
        self._t += self.period_s
        f = [math.nan] * 3 if force is None else [float(v) for v in force]
        rot = None
        if self._needs_rotation and rotation is not None:
            rot = [float(v) for v in np.asarray(rotation).reshape(9)]
        u, status = self._step(f, rot)
        out = np.array([float(v) for v in u], dtype=np.float64)
        self.du = out - self.u
        self.u = out
        self.status = int(status)
        if fault and status & (st.HELD | st.REJECTED) and not status & st.TARING:
            self.faults += 1
        self.engaged = self.engaged or bool(status & st.ENGAGED)
        if status & st.TRIPPED and not self.tripped:
            self.tripped = True
            self.trip_time_s = self._t
        return out.copy()

    def wait(self) -> Vec:
        """A start-up period with no measurement yet: a missing sample to the generated code."""
        return self.step(None, fault=False)
