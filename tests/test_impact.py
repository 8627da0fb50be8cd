"""Issue 31 item 4: the impact speed, checked against the spring bench's physics.

The bench (:mod:`fuzzkit.studies.spring_loop`) is an exact spring; the controller is the ideal
one for this question: it engages on the spec's engagement rule and then retracts by a metre at
once. Above the impact speed the force still passes the safety limit; at ``m / (m + 1)`` of it
(the bound's slack: the contact may start anywhere within a period) it does not.
"""

from __future__ import annotations

import dataclasses
import math
import subprocess
import sys
from pathlib import Path

import pytest

from fuzzkit.control.impact import impact_speed, impact_warning, path_approach_speed
from fuzzkit.control.spec import ControllerSpec
from fuzzkit.control.spec_reader import load_spec
from fuzzkit.plants.environment import Waypoint
from fuzzkit.studies.spring_loop import SpringBench, run_spring

EXAMPLE = Path(__file__).resolve().parents[1] / "docs" / "examples" / "controller_adaptive.yaml"


def spec() -> ControllerSpec:
    return load_spec(EXAMPLE)


def test_the_impact_speed_is_one_formula_wherever_it_is_used() -> None:
    """The spec's impact speed, the report's impact limit and the regulation task's approach
    speed are one closed form, v = force / (stiffness * reaction time)."""
    from fuzzkit.analysis.regulation import impact_speed_limit
    from fuzzkit.control.impact import impact_speed_for
    from fuzzkit.studies.regulation import approach_speed

    assert impact_speed_for(15.0, 2.0e6, 0.042) == 15.0 / (2.0e6 * 0.042)
    assert impact_speed_for(1.0, 1.0e4, 0.0) == math.inf
    assert impact_speed_for(-1.0, 1.0e4, 0.1) == 0.0  # no headroom: no speed is safe
    # the report's limit: the headroom above the set point (25 N limit, 10 N set point)
    assert impact_speed_limit(2.0e6, 25.0, 0.042, 10.0) == impact_speed_for(15.0, 2.0e6, 0.042)
    # the regulation task: a fifth of that headroom over its 0.1 s design delay, at most 5 mm/s
    assert approach_speed(1.0e7, 25.0, 10.0) == pytest.approx(0.2 * 15.0 / (1.0e7 * 0.1))
    assert approach_speed(1.0e3, 25.0, 10.0) == 5.0e-3


def test_the_example_s_impact_speed_is_the_closed_form() -> None:
    s = spec()
    # 25 N limit, k_max 2000 N/mm, 3 engagement samples, 4 ms, latency 0 (delay 1): m = 2
    assert s.safety.limit_n == 25.0 and s.safety.engage_samples == 3
    assert impact_speed(s) == pytest.approx(25.0 / (2.0e6 * 2 * 0.004), rel=1e-12)
    assert impact_speed(s, 4) == pytest.approx(25.0 / (2.0e6 * 6 * 0.004), rel=1e-12)
    fixed = dataclasses.replace(s, adaptation=dataclasses.replace(s.adaptation, mode="none"))
    assert impact_speed(fixed) is None


def ideal_peak(s: ControllerSpec, speed: float, latency: int, gap_m: float) -> float:
    """The peak force on the bench at k_max when the controller retracts at once on engaging
    (``latency`` periods on the sensor and on the command side each)."""
    k_max = s.adaptation.estimator.k_max_n_mm
    threshold = s.safety.engage_threshold_n
    assert threshold is not None
    above = 0

    def step(force: list[float]) -> tuple[list[float], int]:
        nonlocal above
        if above < s.safety.engage_samples:  # once engaged, it stays retracted
            above = above + 1 if force[2] > threshold else 0
        return [0.0, 0.0, -1.0 if above >= s.safety.engage_samples else 0.0], 0

    bench = SpringBench(
        stiffness=((0.0, k_max),),
        duration_s=0.2,
        period_s=s.period_s,
        start_gap_m=gap_m,
        approach_m_s=speed,
        stop_s=None,
        latency_in=latency,
        latency_out=latency,
        noise_std_n=0.0,
    )
    return float(run_spring(bench, step).force_n.max())


@pytest.mark.parametrize("latency", [0, 1, 3])
def test_above_the_impact_speed_the_impact_passes_the_limit_below_it_need_not(
    latency: int,
) -> None:
    s = spec()
    v = impact_speed(s, 2 * latency)
    assert v is not None and math.isfinite(v)
    m = s.safety.engage_samples - 1 + 2 * latency
    limit = s.safety.limit_n
    for frac in (0.01, 0.3, 0.77, 0.99):  # where in a period the contact starts
        gap = v * s.period_s * (5 + frac)
        assert ideal_peak(s, 1.02 * v, latency, 1.02 * gap) > limit
        slow = 0.95 * v * m / (m + 1)
        assert ideal_peak(s, slow, latency, slow / v * gap) < limit


def test_the_warning_names_the_speeds_and_the_path_speed_is_along_force_axes() -> None:
    s = spec()  # z force controlled
    path = (Waypoint(0.0, 0.0, 0.0, 0.0), Waypoint(1.0, 0.5, 0.0, -0.02))
    assert path_approach_speed(path, s.selection) == pytest.approx(0.02)
    assert path_approach_speed(path, (True, False, False)) == pytest.approx(0.5)
    msg = impact_warning(s, 0.02, 0, "the path")
    assert msg is not None and "20 mm/s" in msg and "1.56 mm/s" in msg
    assert impact_warning(s, 1.0e-3, 0, "the path") is None


def test_simulate_warns_on_e2_with_an_adaptive_spec() -> None:
    out = subprocess.run(
        [sys.executable, "-m", "fuzzkit", "simulate", "E2", "--spec", str(EXAMPLE), "--json"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("warning: E2's path approaches contact at 20")
    assert "Traceback" not in out.stderr


def test_validate_warns_on_a_scenario_whose_spec_meets_it_too_fast(tmp_path: Path) -> None:
    from fuzzkit.studies.scenario_file import shipped_scenario_text

    text = shipped_scenario_text("E1")
    task = (
        "force_control:  # set point per force-controlled task axis (N); other axes follow the "
        "path\n  x: 0.0\n  z: 10.0\nsafety_limit_n: 25.0\n"
        "engage: {threshold_n: 1.0, samples: 3, hold_path: true}\n"
    )
    assert task in text
    (tmp_path / "spec.yaml").write_text(EXAMPLE.read_text())
    scenario = tmp_path / "task.yaml"
    scenario.write_text(text.replace(task, "controller: spec.yaml\nengage: {hold_path: true}\n"))
    out = subprocess.run(
        [sys.executable, "-m", "fuzzkit", "validate", str(scenario)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr
    both = out.stdout + out.stderr
    assert f"{scenario}: warning: the path approaches contact at 21.2 mm/s" in both, both
    assert "Traceback" not in both
