"""Rerun recordings of closed-loop runs: one entry point that picks the plant's drawing."""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from fuzzkit.fuzzy.model import RuleBase
from fuzzkit.loop.result import RunResult
from fuzzkit.viz import traces_arm6, traces_planar
from fuzzkit.viz.rule_activity import rule_recording


def write_run_rrd(
    result: RunResult,
    path: str | os.PathLike[str],
    plant: Any = None,
    fuzzy: tuple[RuleBase, Mapping[str, Any]] | None = None,
) -> Path:
    """Write a run's recording with the drawing its plant needs (planar, or 3-D for arm6).

    ``plant``: the plant object that ran it, when it carries parameters the drawing needs (an
    ``Arm6Plant`` with extra 3-D objects, as the 3-D E3's floor and wall). ``fuzzy``: the rule
    base and gain overrides of a fuzzy-PI run: the recording then carries the strongest rules
    of every period (:mod:`fuzzkit.viz.rule_activity`).
    """
    rules = None if fuzzy is None else rule_recording(result, fuzzy[0], fuzzy[1])
    if result.joint_angles.ndim == 2 and result.joint_angles.shape[1] == 6:
        return traces_arm6.write_rrd(
            result, path, params=getattr(plant, "params", None), rules=rules
        )
    return traces_planar.write_rrd(result, path, rules=rules)
