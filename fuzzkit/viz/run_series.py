"""Time series and paths every run recording shares, whatever the plant."""

from __future__ import annotations

from typing import Any

import numpy as np

from fuzzkit.control.names import AXES
from fuzzkit.plants.environment import nominal_position
from fuzzkit.studies.runner import RunResult
from fuzzkit.viz.blueprints import ADAPTATION, CORRECTION, ERROR, FORCES, WORLD, run_blueprint
from fuzzkit.viz.recording import log_axes, log_series

_AXIS_COLOURS = {"x": (230, 80, 60), "y": (60, 170, 80), "z": (60, 110, 230)}
#: Set points: amber, visible on the viewer's dark theme and on a light one.
SETPOINT_COLOUR = (250, 190, 30)


def _lighter(c: tuple[int, int, int]) -> tuple[int, int, int]:
    return (int(0.5 * c[0] + 110), int(0.5 * c[1] + 110), int(0.5 * c[2] + 110))


def log_control_series(rec: Any, result: RunResult, times: Any) -> None:
    """Log the force and control time series of a run (any plant) on the ``times`` column.

    Forces under ``forces/<axis>/`` (measured, true, set point; N), the force error and its
    change under ``control/error/<axis>/`` (N), the position correction and its sum under
    ``control/correction/<axis>/`` (mm): each subtree holds one unit, and every series name
    ends with its unit, as the blueprint's plots show them.
    """
    for i, axis in enumerate(AXES):
        c = _AXIS_COLOURS[axis]
        light = _lighter(c)
        f = f"{FORCES}/{axis}"
        log_series(rec, f"{f}/measured", times, result.force[:, i], f"f{axis} measured (N)", c)
        log_series(rec, f"{f}/true", times, result.force_true[:, i], f"f{axis} true (N)", light)
        if result.experiment.selection[i]:
            log_series(
                rec,
                f"{f}/setpoint",
                times,
                result.setpoint[:, i],
                f"f{axis} set point (N)",
                SETPOINT_COLOUR,
            )
            err, cor = f"{ERROR}/{axis}", f"{CORRECTION}/{axis}"
            log_series(rec, f"{err}/e", times, result.e[:, i], f"e{axis} (N)", c)
            log_series(rec, f"{err}/de", times, result.de[:, i], f"de{axis} (N)", light)
            log_series(rec, f"{cor}/du", times, result.du[:, i] * 1e3, f"du{axis} (mm)", light)
            log_series(rec, f"{cor}/u", times, result.u[:, i] * 1e3, f"u{axis} (mm)", c)
            log_adaptation(rec, result, times, i)


def log_adaptation(rec: Any, result: RunResult, times: Any, i: int) -> None:
    """An adaptive run's scheduled output-gain factor (``adaptation/gain_scale/<axis>``) and
    stiffness estimate (``adaptation/stiffness/<axis>``, N/mm) of task axis ``i``."""
    if result.gain_scale is None or result.stiffness_n_mm is None:
        return
    axis, c = AXES[i], _AXIS_COLOURS[AXES[i]]
    log_series(
        rec, f"{ADAPTATION}/gain_scale/{axis}", times, result.gain_scale[:, i],
        f"{axis} output gain factor (1)", c,
    )  # fmt: skip
    k = result.stiffness_n_mm[:, i]
    if not np.all(np.isnan(k)):
        log_series(
            rec, f"{ADAPTATION}/stiffness/{axis}", times, k, f"{axis} stiffness estimate (N/mm)", c
        )


def run_recording_blueprint(result: RunResult, title: str, rules: bool = False) -> Any:
    """The default layout of a run's recording: the force-controlled axes, control, 3-D
    (``rules``: and the fuzzy-PI's strongest rules)."""
    controlled = [a for i, a in enumerate(AXES) if result.experiment.selection[i]]
    return run_blueprint(controlled, title, rules=rules, adaptive=result.gain_scale is not None)


def log_world_axes(rec: Any) -> None:
    """Label the 3-D scene's axes (metres, z up)."""
    import rerun as rr

    rec.log(WORLD, rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    log_axes(rec, f"{WORLD}/axes", ("x (m)", "y (m)", "z (m)"), 0.1)


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
