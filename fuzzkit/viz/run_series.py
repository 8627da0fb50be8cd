"""Time series and paths every run recording shares, whatever the plant."""

from __future__ import annotations

from typing import Any

import numpy as np

from fuzzkit.plants.environment import nominal_position
from fuzzkit.studies.experiments import AXES
from fuzzkit.studies.runner import RunResult
from fuzzkit.viz.recording import log_series

_AXIS_COLOURS = {"x": (230, 80, 60), "y": (60, 170, 80), "z": (60, 110, 230)}


def log_control_series(rec: Any, result: RunResult, times: Any) -> None:
    """Log the force and control time series of a run (any plant) on the ``times`` column."""
    for i, axis in enumerate(AXES):
        c = _AXIS_COLOURS[axis]
        dim = (int(0.5 * c[0] + 100), int(0.5 * c[1] + 100), int(0.5 * c[2] + 100))
        log_series(
            rec, f"forces/{axis}/measured", times, result.force[:, i], f"f{axis} measured", c
        )
        log_series(rec, f"forces/{axis}/true", times, result.force_true[:, i], f"f{axis} true", dim)
        if result.experiment.selection[i]:
            log_series(
                rec,
                f"forces/{axis}/setpoint",
                times,
                result.setpoint[:, i],
                f"f{axis} set",
                (0, 0, 0),
            )
            log_series(rec, f"control/{axis}/e", times, result.e[:, i], f"e{axis} (N)", c)
            log_series(rec, f"control/{axis}/de", times, result.de[:, i], f"de{axis} (N)", c)
            log_series(rec, f"control/{axis}/du", times, result.du[:, i] * 1e3, f"du{axis} (mm)", c)
            log_series(rec, f"control/{axis}/u", times, result.u[:, i] * 1e3, f"u{axis} (mm)", c)


def log_paths(rec: Any, result: RunResult) -> None:
    """Log the nominal (programmed) path and the path the tool actually took, static."""
    import rerun as rr

    path = result.experiment.scenario.path
    t_path = np.linspace(path[0].t_s, path[-1].t_s, 200)
    nominal = np.array([nominal_position(path, float(t)) for t in t_path])
    rec.log("world/nominal_path", rr.LineStrips3D([nominal], colors=[(150, 150, 150)]), static=True)
    rec.log(
        "world/tool_path",
        rr.LineStrips3D([result.tool_position], colors=[(60, 110, 230)]),
        static=True,
    )
