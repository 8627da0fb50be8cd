"""Per-axis first contact and the metrics counted from it (issue 4: metrics per force axis).

A synthetic run with known answers (the tool lands on a floor, slides with friction, then meets
a wall), the normal-force bookkeeping of both plants, and E3 on the real plants.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from fuzzkit.control.controllers import Surface
from fuzzkit.loop.python_loop import load_surface, run
from fuzzkit.loop.result import RunResult
from fuzzkit.plants.contract import TOOL_DOWN, Scenario, normal_force_by_axis
from fuzzkit.plants.environment import Box, Table, Waypoint
from fuzzkit.studies.experiments import DEFAULT_GAINS, experiment
from fuzzkit.studies.metrics import axis_first_contact, axis_metrics, summary

PERIOD = 0.004
MU = 0.15


def _synthetic(*, report_normals: bool = True) -> RunResult:
    """E3's story with round numbers, in the task frame (x forward, z down).

    0-1 s in the air; 1.0 s lands on the floor (f_z normal 30 N); 1.5-5.0 s the nominal path
    slides along x and friction pulls ``MU * 30 = 4.5 N`` along x (more than the 1 N engage
    threshold, but no contact along x); 4.0 s the tool meets the wall: the x force ramps from
    4.5 N to 16 N (the ramp-following error of 10 N) while the path still drives into the
    wall; 5.0 s the path stops and x drops to 6 N within 0.1 s; 5.5-5.6 s the wall is lost.
    """
    exp = experiment("E3")
    t = np.round(np.arange(1, round(6.0 / PERIOD) + 1) * PERIOD, 9)
    n = len(t)
    on_floor = t >= 1.0
    on_wall = (t >= 4.0) & ~((t >= 5.5) & (t < 5.6))
    force_normal = np.zeros((n, 3))
    force_normal[on_floor, 2] = 30.0
    force_true = force_normal.copy()
    sliding = on_floor & (t < 4.0)
    force_true[sliding, 0] = MU * 30.0  # friction only: not a contact along x
    ramp = (t >= 4.0) & (t < 5.0)
    force_true[ramp, 0] = np.minimum(4.5 + (t[ramp] - 4.0) * 250.0, 16.0)
    recover = (t >= 5.0) & (t < 5.1)
    force_true[recover, 0] = 16.0 - 10.0 * (t[recover] - 5.0) / 0.1
    force_true[t >= 5.1, 0] = 6.0
    force_normal[on_wall, 0] = np.maximum(force_true[on_wall, 0], 1.5)
    if not report_normals:
        force_normal[:] = np.nan
    # Nominal path (base frame): descends until 1.0 s, slides along x from 1.5 s to 5.0 s.
    nominal = np.zeros((n, 3))
    nominal[:, 0] = 0.44 + 0.025 * np.clip(t - 1.5, 0.0, 3.5)
    nominal[:, 2] = -0.26 - 0.02 * np.clip(t, 0.0, 1.0)
    moving = (t <= 1.0) | ((t > 1.5) & (t <= 5.0))
    zeros = np.zeros((n, 3))
    return RunResult(
        experiment=exp,
        controller="synthetic",
        plant="synthetic",
        t=t,
        force=force_true.copy(),
        force_sensor=force_true.copy(),
        force_true=force_true,
        setpoint=np.tile(np.array(exp.setpoints), (n, 1)),
        e=zeros,
        de=zeros,
        du=zeros,
        u=zeros,
        tool_position=nominal.copy(),
        nominal_position=nominal,
        target_position=nominal.copy(),
        joint_angles=np.zeros((n, 2)),
        in_contact=on_floor,
        force_normal=force_normal,
        moving=moving,
        arm_points=[],
        contact_points=[],
        faults=0,
        tripped=False,
        seed=0,
        latency_periods=(0, 0),
        fault="none",
        fault_seed=0,
        trip_time_s=None,
        engaged_time_s=1.0,
        wall_time_s=0.0,
    )


def test_each_axis_counts_from_its_own_first_contact() -> None:
    r = _synthetic()
    z, x = axis_metrics(r, 2), axis_metrics(r, 0)
    assert z["first_contact_s"] == pytest.approx(1.0)
    # Friction (4.5 N along x from 1.0 s) is not an x contact; the wall (4.0 s) is.
    assert x["first_contact_s"] == pytest.approx(4.0)
    assert x["overshoot_pct"] == pytest.approx(100.0 * 10.0 / 6.0)
    # Settling counts from 5.0 s, when the path stops pushing into the wall: 0.1 s, not the
    # 4.1 s from the floor contact nor the 1.1 s from the wall contact.
    assert x["settling_time_s"] == pytest.approx(0.1, abs=2 * PERIOD)
    assert z["settling_time_s"] == pytest.approx(0.0, abs=PERIOD)
    assert x["contact_lost_s"] == pytest.approx(0.1, abs=PERIOD / 2)
    assert z["contact_lost_s"] == 0.0
    # RMS while moving: from 0.5 s after the wall contact to the end of the path, all ramp.
    assert x["rms_error"] == pytest.approx(10.0, abs=0.01)


def test_first_contact_falls_back_to_any_contact_without_normal_forces() -> None:
    r = _synthetic(report_normals=False)
    assert axis_first_contact(r, 0) == axis_first_contact(r, 2)
    assert axis_metrics(r, 0)["first_contact_s"] == pytest.approx(1.0)


def test_summary_reports_first_contact_per_axis() -> None:
    axes = summary(_synthetic())["axes"]
    assert axes["z"]["first_contact_s"] == pytest.approx(1.0)
    assert axes["x"]["first_contact_s"] == pytest.approx(4.0)


# -- normal forces by axis ----------------------------------------------------------------------


@pytest.mark.parametrize(
    "normals, expected",
    [
        ([], [0.0, 0.0, 0.0]),
        # floor: the tool pushes down (base -z) = task +z
        ([(0.0, 0.0, -30.0)], [0.0, 0.0, 30.0]),
        # a floor tilted by 10 deg of roughness still credits z only
        ([(30.0 * math.sin(0.17), 0.0, -30.0 * math.cos(0.17))], [0.0, 0.0, 30.0 * math.cos(0.17)]),
        # a wall ahead plus the floor (the corner of E3)
        ([(0.0, 0.0, -30.0), (6.0, 0.0, 0.0)], [6.0, 0.0, 30.0]),
        # pulling a wall behind the tool: negative x
        ([(-2.0, 0.0, 0.5)], [-2.0, 0.0, 0.0]),
    ],
)
def test_normal_force_by_axis(
    normals: list[tuple[float, float, float]], expected: list[float]
) -> None:
    got = normal_force_by_axis(normals, np.asarray(TOOL_DOWN))
    assert got.tolist() == pytest.approx(expected)


def _slide_scenario() -> Scenario:
    """Press 30 N-ish on a table and slide along x (friction 0.3), then into a wall."""
    tip_z = -0.30 + 0.02 - 0.003  # 3 mm into the table: about 30 N at 10 N/mm
    return Scenario(
        name="slide",
        path=(
            Waypoint(0.0, 0.44, 0.0, tip_z),
            Waypoint(0.2, 0.44, 0.0, tip_z),
            Waypoint(1.2, 0.51, 0.0, tip_z),
        ),
        objects=(Table(-0.30), Box(0.50 + 0.02 + 0.025, -0.25, 0.05, 0.12, name="wall")),
        duration_s=1.2,
    )


@pytest.mark.parametrize("plant_name", ["planar", "arm6", "mujoco"])
def test_plants_report_normal_force_without_friction(plant_name: str) -> None:
    from fuzzkit.loop.adapter import make_plant

    plant = make_plant(plant_name)
    scn = _slide_scenario()
    plant.reset(scn, seed=0)
    samples = [plant.step(np.zeros(3), k * scn.period_s) for k in range(1, 301)]
    sliding = [s for s in samples if 0.4 < s.t_s < 0.9]
    for s in sliding:
        assert s.force_normal is not None
        # friction drags along x while sliding; the normal force has no x part
        assert abs(s.force_true[0]) > 1.0
        assert s.force_normal[0] == pytest.approx(0.0)
        assert s.force_normal[2] == pytest.approx(s.force_true[2], rel=1e-6)
    # the wall face is at x = 0.52: the 20 mm disc reaches it at x = 0.50, about 1.06 s
    at_wall = [s for s in samples if s.force_normal is not None and s.force_normal[0] > 1.0]
    assert at_wall and at_wall[0].t_s > 0.95


# -- E3 on the real plants -----------------------------------------------------------------------


@functools.cache
def _surface() -> Surface:
    return load_surface("macvicar_whelan")


@functools.cache
def _e3(plant: str, controller: str) -> RunResult:
    surface = _surface() if controller == "fuzzy-pi" else None
    # The metrics' definitions are under test here, on the loop without latency (one noise
    # excursion out of the 5 % band moves a settling time); tests/test_latency.py covers latency.
    return run(experiment("E3"), plant, controller, surface=surface, seed=0, latency=(0, 0))


@pytest.mark.slow
@pytest.mark.parametrize("plant", ["planar", "arm6"])
def test_e3_x_first_contact_is_the_wall_not_the_floor(plant: str) -> None:
    exp = experiment("E3")
    for controller in ("pi", "fuzzy-pi"):
        r = _e3(plant, controller)
        z, x = axis_metrics(r, 2), axis_metrics(r, 0)
        assert z["first_contact_s"] is not None and x["first_contact_s"] is not None
        assert x["first_contact_s"] > z["first_contact_s"] + 2.0
        # the wall is reached before the nominal path ends (it is 5 mm closer than the CAD)
        assert x["first_contact_s"] < exp.scenario.path[-1].t_s
        # the x force on the floor before the wall is friction (mu * f_z), not contact
        before = (r.t > z["first_contact_s"] + 0.6) & (r.t < x["first_contact_s"] - 0.1)
        assert np.max(np.abs(r.force_true[before, 0])) > exp.engage_threshold_n  # type: ignore[operator]
        assert np.all(r.force_normal[before, 0] == 0.0)
        assert x["settling_time_s"] is not None and x["settling_time_s"] < 0.5


@pytest.mark.slow
def test_e3_x_overshoot_is_the_ramp_following_error() -> None:
    exp = experiment("E3")
    k = exp.scenario.contact.stiffness_n_per_m
    ki = DEFAULT_GAINS["pi"]["ki"]
    v = 0.025  # nominal path speed into the wall
    ramp_error = k * v * exp.scenario.period_s / (ki * k)  # N: 10 N
    pi, fz = axis_metrics(_e3("planar", "pi"), 0), axis_metrics(_e3("planar", "fuzzy-pi"), 0)
    assert pi["overshoot_pct"] == pytest.approx(100.0 * ramp_error / 6.0, rel=0.05)
    assert pi["rms_error"] == pytest.approx(ramp_error, rel=0.05)
    # Noise on de averages the fuzzy surface over a kink along de at Ki*e = -0.5: a lower mean
    # correction per unit of error, so a larger error builds up and the x figures differ.
    assert fz["overshoot_pct"] is not None and pi["overshoot_pct"] is not None
    assert fz["overshoot_pct"] > pi["overshoot_pct"] + 2.0
    assert fz["first_contact_s"] != pi["first_contact_s"]
