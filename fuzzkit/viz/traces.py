"""Rerun recordings of closed-loop runs: one entry point that picks the plant's drawing."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from fuzzkit.studies.runner import RunResult
from fuzzkit.viz import traces_arm6, traces_planar


def write_run_rrd(result: RunResult, path: str | os.PathLike[str], plant: Any = None) -> Path:
    """Write a run's recording with the drawing its plant needs (planar, or 3-D for arm6).

    ``plant``: the plant object that ran it, when it carries parameters the drawing needs (an
    ``Arm6Plant`` with extra 3-D objects, as the 3-D E3's floor and wall).
    """
    if result.joint_angles.ndim == 2 and result.joint_angles.shape[1] == 6:
        return traces_arm6.write_rrd(result, path, params=getattr(plant, "params", None))
    return traces_planar.write_rrd(result, path)
