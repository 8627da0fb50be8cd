"""The report's stiffness study runs on the report's plant (issue 41's leftover): an arm6
report's press runs on arm6, not on the planar arm."""

from __future__ import annotations

import pytest

from fuzzkit.loop import python_loop
from fuzzkit.report.stiffness_study import stiffness_study
from fuzzkit.studies.experiments import DEFAULT_GAINS, press_experiment
from fuzzkit.studies.metrics import axis_metrics

KEYS = ("first_contact_s", "overshoot_pct", "settling_time_s", "peak_force_true")


def test_the_stiffness_study_runs_on_the_plant_it_is_given() -> None:
    """The study's press on arm6 (the generated C in the compiled loop) gives the metrics of
    the reference controller's press on arm6 in the Python loop, and not the planar arm's."""
    gains = DEFAULT_GAINS["pi"]
    study = stiffness_study("arm6", {("pi", "default"): gains}, (10.0,), "macvicar_whelan")
    ((k, got),) = study[("pi", "default")]
    assert k == 10.0 and got["tripped"] == 0.0
    press = press_experiment(10e3)
    on_arm6 = axis_metrics(python_loop.run(press, "arm6", "pi", gains=gains), 2)
    on_planar = axis_metrics(python_loop.run(press, "planar", "pi", gains=gains), 2)
    for key in KEYS:
        assert got[key] == pytest.approx(on_arm6[key], rel=1e-9), key
    assert got["peak_force_true"] != pytest.approx(on_planar["peak_force_true"], rel=1e-3)
