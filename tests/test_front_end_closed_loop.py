"""Item 5 of issue 20: the sensor front end in closed loop on arm6.

The shipped tilt scenario (``docs/examples/tilt.yaml``): a 1.5 kg tool presses 10 N on a table
along its axis, then tilts 30 degrees in contact; the wrist sensor reads the contact force, the
tool's weight and a drifting bias in its own turning frame. With gravity compensation the steady
force error stays within the sensor noise; with the tare alone it is the weight's lost share
along the tool axis, ``m*g*(1 - cos 30 deg)``, as the closed form says.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from fuzzkit.loop.spec import RunSpec
from fuzzkit.plants.contact import GRAVITY_M_S2
from fuzzkit.studies.batch import run_spec
from fuzzkit.studies.metrics import summary
from fuzzkit.studies.scenario_file import load_scenario

EXAMPLES = Path(__file__).resolve().parent.parent / "docs" / "examples"
TILT = str(EXAMPLES / "tilt.yaml")
TARE_ONLY = str(EXAMPLES / "controller_tilt_tare_only.yaml")


def _steady(fault: str | None = None, spec: str | None = None) -> tuple[float, float, object]:
    result = run_spec(RunSpec(TILT, plant="arm6", fault=fault, controller_spec=spec))
    z = summary(result)["axes"]["z"]
    return z["steady_state_error_mean"], z["steady_state_error_std"], result


def test_the_scenario_is_what_the_docs_say() -> None:
    exp = load_scenario(TILT)
    scn = exp.scenario
    assert scn.tool.mass_kg == 1.5 and scn.sensor.bias_drift_n_per_s[2] > 0.0
    assert math.degrees(scn.path[-1].tilt_rad) == pytest.approx(30.0)
    assert exp.controller_spec is not None and exp.controller_spec.sensor.tool is not None
    assert exp.selection == (False, False, True) and exp.setpoints[2] == 10.0


def test_compensation_keeps_the_force_within_the_noise_and_the_tare_alone_does_not() -> None:
    noise = load_scenario(TILT).scenario.sensor.noise_std_n
    on, on_std, result = _steady()
    off, _, _ = _steady(spec=TARE_ONLY)
    # the Python loop (the compiled plants model no tool weight, drift or tilt), running the
    # generated controller
    assert "does not model" in result.loop and result.plant == "arm6"  # type: ignore[attr-defined]
    assert "generated C controller" in result.controller_impl  # type: ignore[attr-defined]
    assert abs(on) < noise and on_std < noise
    closed_form = 1.5 * GRAVITY_M_S2 * (1.0 - math.cos(math.radians(30.0)))  # 1.97 N
    assert off == pytest.approx(closed_form, abs=0.1)
    assert off > 10 * abs(on)


@pytest.mark.parametrize("fault", ["spike", "nan", "dropout"])
def test_faults_still_work_through_the_front_end(fault: str) -> None:
    noise = load_scenario(TILT).scenario.sensor.noise_std_n
    mean, _, result = _steady(fault)
    assert abs(mean) < noise, fault
    assert not result.tripped and result.faults > 1  # type: ignore[attr-defined]


def test_the_sensor_reads_weight_and_drift_in_its_turning_frame() -> None:
    """Free air at the start: the reading is the weight of a tool pointing down plus the bias;
    at the end the reported rotation is the 30 degree tilt about y."""
    from fuzzkit.plants.arm6 import Arm6Plant

    exp = load_scenario(TILT)
    scn = exp.scenario
    plant = Arm6Plant()
    sample = plant.reset(scn, seed=0)
    readings = []
    for k in range(1, 11):
        sample = plant.step(np.zeros(3), k * scn.period_s)
        readings.append(sample.force)
    mean = np.nanmean(readings, axis=0)
    t_mid = 5.5 * scn.period_s
    expected = np.array(scn.sensor.bias_n) + np.array(scn.sensor.bias_drift_n_per_s) * t_mid
    expected[2] -= 1.5 * GRAVITY_M_S2  # hanging: -m*g along the tool axis
    assert mean == pytest.approx(expected, abs=0.1)
    assert sample.tool_rotation is not None
    for k in range(11, round(2.6 / scn.period_s)):
        sample = plant.step(np.zeros(3), k * scn.period_s)
    c, s = math.cos(math.radians(30.0)), math.sin(math.radians(30.0))
    tilted = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]) @ np.diag([1.0, -1.0, -1.0])
    assert sample.tool_rotation == pytest.approx(tilted, abs=1e-9)


def test_the_planar_arm_refuses_a_tilt_and_the_compiled_arm6_hands_over() -> None:
    from fuzzkit.errors import ConfigError
    from fuzzkit.planar_sim import PlanarArmPlant
    from fuzzkit.plants.arm6 import Arm6Plant
    from fuzzkit.plants.arm6_period import pack
    from fuzzkit.plants.contract import UnsupportedPlant

    scn = load_scenario(TILT).scenario
    with pytest.raises(ConfigError, match="keeps its tool vertical"):
        PlanarArmPlant().reset(scn)
    plant = Arm6Plant()
    plant.reset(scn)
    with pytest.raises(UnsupportedPlant, match=r"tool weight.*drifting sensor bias.*tilting"):
        pack(plant)
