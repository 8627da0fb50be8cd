"""Tests of the pymunk planar arm and the shared contact/sensor models of
fuzzkit.plants.contract."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fuzzkit.errors import ConfigError, SimulationError
from fuzzkit.loop.adapter import PLANTS, make_plant
from fuzzkit.planar_sim import PlanarArmPlant, forward_kinematics, inverse_kinematics
from fuzzkit.plants.contact import ContactModel, SensorModel
from fuzzkit.plants.contract import ContactPlant, Scenario
from fuzzkit.plants.environment import Box, RoughSurface, Table, Waypoint, nominal_position

L1, L2 = 0.36, 0.38


def _hold(x: float, z: float, objects: tuple[object, ...] = (), **kw: object) -> Scenario:
    return Scenario(
        name="test",
        path=(Waypoint(0.0, x, 0.0, z),),
        objects=objects,  # type: ignore[arg-type]
        duration_s=1.0,
        **kw,  # type: ignore[arg-type]
    )


def _run(plant: PlanarArmPlant, steps: int, correction: np.ndarray | None = None) -> list:  # type: ignore[type-arg]
    c = np.zeros(3) if correction is None else correction
    return [plant.step(c, (k + 1) * plant.period_s) for k in range(steps)]


@pytest.mark.parametrize("wx", [0.2, 0.45, 0.6])
@pytest.mark.parametrize("wz", [-0.3, -0.1, 0.15])
def test_ik_then_fk_returns_the_target(wx: float, wz: float) -> None:
    q1, q2, ok = inverse_kinematics(wx, wz, L1, L2)
    assert ok
    _, _, x, z = forward_kinematics(q1, q2, L1, L2)
    assert (x, z) == pytest.approx((wx, wz), abs=1e-12)
    ex, ez, _, _ = forward_kinematics(q1, q2, L1, L2)
    # Elbow up: the elbow is above the straight line from shoulder to wrist.
    assert ez > ex * wz / wx


def test_unreachable_target_is_flagged() -> None:
    assert not inverse_kinematics(0.9, 0.0, L1, L2)[2]
    with pytest.raises(SimulationError, match="out of reach"):
        PlanarArmPlant().reset(_hold(0.9, 0.0))


def test_plant_satisfies_the_protocol_and_registry() -> None:
    assert isinstance(PlanarArmPlant(), ContactPlant)
    assert "planar" in PLANTS
    assert isinstance(make_plant("planar"), PlanarArmPlant)
    with pytest.raises(ConfigError, match="unknown plant"):
        make_plant("nope")


def test_free_motion_tracks_the_nominal_path_without_force() -> None:
    scn = Scenario(
        name="free",
        path=(Waypoint(0.0, 0.40, 0.0, -0.20), Waypoint(2.0, 0.50, 0.0, -0.25)),
        objects=(),
        duration_s=2.5,
    )
    plant = PlanarArmPlant()
    plant.reset(scn, seed=0)
    samples = _run(plant, 700)
    late = samples[100:]
    err = max(float(np.linalg.norm(s.tool_position - s.nominal_position)) for s in late)
    assert err < 2e-3  # servo lag at 56 mm/s
    assert all(not s.in_contact for s in samples)
    assert max(float(np.max(np.abs(s.force_true))) for s in samples) == 0.0
    assert samples[-1].tool_position == pytest.approx(np.array([0.50, 0.0, -0.25]), abs=1e-4)


def test_pressing_on_a_table_gives_spring_force_with_positive_task_z() -> None:
    k = 2.0e4
    scn = _hold(0.45, -0.285, (Table(-0.30),), contact=ContactModel(stiffness_n_per_m=k))
    plant = PlanarArmPlant()
    plant.reset(scn)
    s = _run(plant, 250)[-1]
    # The 20 mm probe disc reaches 5 mm below the surface.
    assert s.force_true[2] == pytest.approx(k * 0.005, rel=0.02)
    assert abs(s.force_true[0]) < 0.05
    assert s.force[2] == pytest.approx(k * 0.005, abs=1.0)  # with sensor noise and filter
    assert s.in_contact and s.contact_points.shape == (1, 3)
    # A positive task-z correction (moving down, base -z) pushes harder.
    s2 = _run(plant, 250, np.array([0.0, 0.0, -0.001]))[-1]
    assert s2.force_true[2] == pytest.approx(k * 0.006, rel=0.02)


def test_pushing_into_a_wall_gives_positive_task_x() -> None:
    wall = Box(center_x=0.55, center_z=-0.2, size_x=0.05, size_z=0.3, name="wall")
    scn = _hold(0.507, -0.2, (wall,))  # disc edge 2 mm into the wall face at 0.525
    plant = PlanarArmPlant()
    plant.reset(scn)
    s = _run(plant, 250)[-1]
    assert s.force_true[0] == pytest.approx(1.0e4 * 0.002, rel=0.03)
    assert abs(s.force_true[2]) < 0.1


def test_same_seed_same_run_other_seed_other_noise() -> None:
    scn = _hold(0.45, -0.285, (Table(-0.30),))

    def forces(seed: int) -> np.ndarray:  # type: ignore[type-arg]
        plant = PlanarArmPlant()
        plant.reset(scn, seed=seed)
        return np.array([s.force for s in _run(plant, 50)])

    a, b, c = forces(1), forces(1), forces(2)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


def test_slow_sensor_leaves_nan_between_samples() -> None:
    scn = _hold(0.45, -0.285, (Table(-0.30),), sensor=SensorModel(rate_hz=125.0))
    plant = PlanarArmPlant()
    plant.reset(scn)
    f = np.array([s.force[2] for s in _run(plant, 20)])
    assert np.isnan(f).sum() == 10
    assert np.all(np.isfinite(f[np.isfinite(f)]))


def test_torque_limit_is_reported_when_pushing_far_too_hard() -> None:
    scn = _hold(0.45, -0.30, (Table(-0.30),), contact=ContactModel(stiffness_n_per_m=1e6))
    plant = PlanarArmPlant()
    plant.reset(scn)
    samples = _run(plant, 100, np.array([0.0, 0.0, -0.05]))
    assert any("torque limit" in m for s in samples for m in s.messages)


def test_box_penetration_closed_form() -> None:
    box = Box(center_x=0.0, center_z=0.0, size_x=0.2, size_z=0.1)
    top = box.penetration(0.03, 0.05 + 0.015, 0.02)
    assert top is not None and top[:3] == pytest.approx((0.005, 0.0, 1.0))
    corner = box.penetration(0.1 + 0.01, 0.05 + 0.01, 0.02)
    assert corner is not None
    assert corner[0] == pytest.approx(0.02 - math.sqrt(2) * 0.01)
    assert corner[1:3] == pytest.approx((math.sqrt(0.5), math.sqrt(0.5)))
    assert box.penetration(0.0, 0.2, 0.02) is None


def test_rough_surface_rms_tilt_and_determinism() -> None:
    rs = RoughSurface(
        x_min=0.0, x_max=2.0, height_m=0.1, tilt_rad=0.01, roughness_rms_m=2e-4, seed=7
    )
    xs = np.linspace(0.0, 2.0, 20001)
    h = np.array([rs.height(float(x)) for x in xs])
    trend = 0.1 + math.tan(0.01) * xs
    assert np.sqrt(np.mean((h - trend) ** 2)) == pytest.approx(2e-4, rel=0.1)
    again = RoughSurface(
        x_min=0.0, x_max=2.0, height_m=0.1, tilt_rad=0.01, roughness_rms_m=2e-4, seed=7
    )
    assert again.height(0.3) == rs.height(0.3)
    other = RoughSurface(
        x_min=0.0, x_max=2.0, height_m=0.1, tilt_rad=0.01, roughness_rms_m=2e-4, seed=8
    )
    assert other.height(0.3) != rs.height(0.3)
    # slope() is the derivative of height().
    x0, dx = 0.77, 1e-7
    assert rs.slope(x0) == pytest.approx(
        (rs.height(x0 + dx) - rs.height(x0 - dx)) / (2 * dx), rel=1e-4
    )


def test_nominal_path_interpolates_and_holds() -> None:
    path = (Waypoint(0.0, 0.0, 0.0, 0.0), Waypoint(1.0, 1.0, 0.0, -1.0))
    assert nominal_position(path, 0.5) == pytest.approx(np.array([0.5, 0.0, -0.5]))
    assert nominal_position(path, 5.0) == pytest.approx(np.array([1.0, 0.0, -1.0]))
    assert nominal_position(path, -1.0) == pytest.approx(np.zeros(3))


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"period_s": 0.0}, "period_s"),
        ({"duration_s": -1.0}, "duration_s"),
        ({"path": (Waypoint(1.0, 0, 0, 0), Waypoint(0.5, 0, 0, 0))}, "must not decrease"),
    ],
)
def test_bad_scenarios_are_rejected(kw: dict[str, object], match: str) -> None:
    base: dict[str, object] = {
        "name": "bad",
        "path": (Waypoint(0.0, 0.4, 0.0, -0.2),),
        "objects": (),
        "duration_s": 1.0,
    }
    base.update(kw)
    with pytest.raises(ConfigError, match=match):
        Scenario(**base)  # type: ignore[arg-type]
