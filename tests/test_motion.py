"""Tests of fuzzkit.plants.arm6: the 6-DOF kinematic plant, its path, servo, contact and wrench."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pytest

from fuzzkit.errors import ConfigError, SimulationError
from fuzzkit.plants.arm6 import Arm6Parameters, Arm6Plant, Arm6Sample, CartesianPath, PathPose
from fuzzkit.plants.contact import ContactModel, ContactSolver, SensorModel
from fuzzkit.plants.contract import ContactPlant, Scenario
from fuzzkit.plants.environment import Box, RoughSurface, Table, Waypoint
from fuzzkit.plants.environment3d import (
    Box3,
    Contact3Solver,
    HeightField,
    Plane,
    objects_from_scenario,
)
from fuzzkit.plants.rotations import matrix_from_quat, quat_from_rotvec, rotation_error

Arr = npt.NDArray[np.float64]
QUIET = SensorModel(noise_std_n=0.0, cutoff_hz=1e6)  # the sensor passes the true force through
K = ContactModel().stiffness_n_per_m


def scenario(
    path: tuple[Waypoint, ...] = (Waypoint(0.0, 0.45, 0.0, 0.05), Waypoint(1.0, 0.45, 0.0, 0.05)),
    objects: tuple[object, ...] = (Table(0.0),),
    contact: ContactModel | None = None,
) -> Scenario:
    return Scenario(
        name="test",
        path=path,
        objects=objects,  # type: ignore[arg-type]
        duration_s=1.0,
        contact=contact or ContactModel(),
        sensor=QUIET,
    )


def run(plant: Arm6Plant, steps: int, correction: Arr, t0: float = 0.0) -> list[Arm6Sample]:
    out = []
    for k in range(steps):
        out.append(plant.step(correction, t0 + (k + 1) * plant.period_s))
    return out


def test_plant_satisfies_the_contract_and_starts_at_the_path() -> None:
    plant = Arm6Plant()
    s = plant.reset(scenario(), seed=0)
    assert isinstance(plant, ContactPlant)  # (period_s is only defined after a reset)
    np.testing.assert_allclose(s.tool_position, [0.45, 0.0, 0.05], atol=1e-8)
    assert plant.chain.within_limits(s.joint_angles)
    # the tool points down: TCP z axis along base -z
    np.testing.assert_allclose(s.tcp_rotation[:, 2], [0, 0, -1], atol=1e-8)
    # the arm polyline starts at the robot base, which sits at -offset in the scenario frame
    np.testing.assert_allclose(s.arm_points[0], [-0.070, 0.0, -0.287], atol=1e-12)
    np.testing.assert_allclose(s.arm_points[-1], s.tool_position, atol=1e-12)


def test_joint_speed_limits_are_never_exceeded() -> None:
    plant = Arm6Plant(Arm6Parameters(servo_time_constant_s=0.0))
    plant.reset(scenario(objects=()), seed=0)
    # a 30 cm jump of the target: far more than one period's motion at full axis speed
    samples = run(plant, 100, np.array([-0.1, 0.2, 0.2]))
    q = np.array([s.joint_angles for s in samples])
    rates = np.abs(np.diff(q, axis=0)) / plant.period_s
    assert np.all(rates <= plant.chain.max_velocity * (1 + 1e-9))
    assert np.any(rates >= plant.chain.max_velocity * 0.999)  # the limit was actually reached
    assert any("joint speed limit" in m for s in samples for m in s.messages)
    # and the arm still gets there
    np.testing.assert_allclose(samples[-1].tool_position, [0.35, 0.2, 0.25], atol=1e-6)


def test_servo_lag_is_first_order() -> None:
    tau = 0.02
    plant = Arm6Plant(Arm6Parameters(servo_time_constant_s=tau))
    plant.reset(scenario(objects=()), seed=0)
    step = 1e-4  # small, so the joint-space lag is linear in Cartesian space too
    samples = run(plant, 50, np.array([0.0, 0.0, step]))
    t = np.array([s.t_s for s in samples])
    rise = np.array([s.tool_position[2] - 0.05 for s in samples]) / step
    np.testing.assert_allclose(rise, 1.0 - np.exp(-t / tau), atol=2e-3)


def test_without_lag_the_tool_is_on_target_every_period() -> None:
    plant = Arm6Plant(Arm6Parameters(servo_time_constant_s=0.0))
    path = (Waypoint(0.0, 0.40, 0.0, 0.10), Waypoint(0.4, 0.50, 0.0, 0.05))
    plant.reset(scenario(path=path, objects=()), seed=0)
    for k in range(120):
        s = plant.step(np.array([0.0, 0.0, 0.001 * math.sin(k / 10)]), (k + 1) * 0.004)
        np.testing.assert_allclose(s.tool_position, s.target_position, atol=1e-7)
        assert s.ik_status == "converged"


def press(depth: float) -> tuple[Arm6Plant, list[Arm6Sample]]:
    """Hold the tool pressed ``depth`` into a frictionless table at z = 0 (tool radius 0.02,
    starting at z = 0.05)."""
    plant = Arm6Plant(Arm6Parameters(servo_time_constant_s=0.0))
    plant.reset(scenario(contact=ContactModel(friction=0.0)), seed=0)
    return plant, run(plant, 20, np.array([0.0, 0.0, -0.03 - depth]))


@pytest.mark.parametrize("depth", [0.0005, 0.001, 0.004])
def test_plane_contact_force_is_stiffness_times_penetration(depth: float) -> None:
    _, samples = press(depth)
    s = samples[-1]
    assert s.in_contact
    # task frame: z points down, the tool pushes the table down -> +k*depth
    np.testing.assert_allclose(s.force_true, [0.0, 0.0, K * depth], atol=1e-6)
    np.testing.assert_allclose(s.force, s.force_true, atol=1e-6)
    np.testing.assert_allclose(s.wrench_base[:3], [0.0, 0.0, -K * depth], atol=1e-6)
    np.testing.assert_allclose(s.contact_points, [[0.45, 0.0, 0.0]], atol=1e-7)


def test_contact_damping_adds_to_the_spring_while_penetrating() -> None:
    model = ContactModel(stiffness_n_per_m=1e4, damping_n_s_per_m=200.0)
    plant = Arm6Plant(Arm6Parameters(servo_time_constant_s=0.0))
    plant.reset(scenario(contact=model), seed=0)
    v = 0.05  # m/s downwards
    prev_depth = 0.0
    for k in range(200):
        s = plant.step(np.array([0.0, 0.0, -v * (k + 1) * 0.004]), (k + 1) * 0.004)
        depth = 0.02 - s.tool_position[2]
        if depth > 0.0 and prev_depth > 0.0:
            rate = (depth - prev_depth) / 0.004
            assert s.force_true[2] == pytest.approx(1e4 * depth + 200.0 * rate, rel=1e-5)
        prev_depth = depth
    assert prev_depth > 0.001


def test_sliding_friction_is_coulomb_and_opposes_the_motion() -> None:
    model = ContactModel(friction=0.3)
    plant = Arm6Plant(Arm6Parameters(servo_time_constant_s=0.0))
    path = (Waypoint(0.0, 0.40, 0.0, 0.05), Waypoint(1.0, 0.50, 0.0, 0.05))
    plant.reset(scenario(path=path, contact=model), seed=0)
    samples = [plant.step(np.array([0.0, 0.0, -0.032]), (k + 1) * 0.004) for k in range(200)]
    s = samples[-1]
    fn = s.force_true[2]
    assert fn == pytest.approx(K * 0.002, rel=1e-6)
    # the tool drags the table forward (+x) with mu * normal force
    assert s.force_true[0] == pytest.approx(0.3 * fn, rel=1e-6)
    # friction acts at the contact point on the table, below the TCP: a moment about the TCP
    lever = s.contact_points[0] - s.tool_position
    assert lever[2] == pytest.approx(-0.018, abs=1e-7)
    np.testing.assert_allclose(s.wrench_base[3:], np.cross(lever, s.wrench_base[:3]), atol=1e-9)


def test_joint_torques_are_the_virtual_work_of_the_wrench() -> None:
    model = ContactModel(friction=0.3)
    plant = Arm6Plant(Arm6Parameters(servo_time_constant_s=0.0))
    path = (Waypoint(0.0, 0.40, 0.0, 0.05), Waypoint(1.0, 0.50, 0.0, 0.05))
    plant.reset(scenario(path=path, contact=model), seed=0)
    s = run(plant, 50, np.array([0.0, 0.0, -0.033]))[-1]
    assert np.linalg.norm(s.wrench_base[3:]) > 0.1  # a moment is part of the check
    chain = plant.chain
    h = 1e-6
    for i in range(6):
        dq = np.zeros(6)
        dq[i] = h
        tp, tm = chain.fk(s.joint_angles + dq), chain.fk(s.joint_angles - dq)
        dp = (tp[:3, 3] - tm[:3, 3]) / (2 * h)
        dth = np.array(rotation_error(tp[:3, :3].tolist(), tm[:3, :3].tolist())) / (2 * h)
        work = s.wrench_base[:3] @ dp + s.wrench_base[3:] @ dth
        assert s.joint_torques[i] == pytest.approx(work, rel=1e-6, abs=1e-6)


def test_sensor_frame_wrench_is_the_base_wrench_seen_from_the_flange() -> None:
    _, samples = press(0.002)
    s = samples[-1]
    r = s.tcp_rotation
    f = s.wrench_base[:3]
    np.testing.assert_allclose(s.wrench_sensor[:3], r.T @ f, atol=1e-9)
    # pressing straight down: the sensor sees +z (tool axis) force and no moment
    assert s.wrench_sensor[2] == pytest.approx(K * 0.002, rel=1e-6)
    np.testing.assert_allclose(s.wrench_sensor[3:], 0.0, atol=1e-9)


def test_unreachable_target_is_reported_not_silent() -> None:
    plant = Arm6Plant()
    plant.reset(scenario(objects=()), seed=0)
    samples = run(plant, 200, np.array([1.0, 0.0, 0.0]))  # 1.45 m away: out of reach
    messages = [m for s in samples for m in s.messages]
    assert any("unreachable" in m for m in messages)
    assert all(plant.chain.within_limits(s.joint_angles) for s in samples)
    assert samples[-1].ik_status == "unreachable"
    # the arm stretches towards it as far as it can: further out than at the start
    assert samples[-1].tool_position[0] > 0.6

    strict = Arm6Plant(Arm6Parameters(strict=True))
    strict.reset(scenario(objects=()), seed=0)
    with pytest.raises(SimulationError, match="unreachable"):
        run(strict, 200, np.array([1.0, 0.0, 0.0]))


def test_path_start_out_of_reach_is_a_clear_error() -> None:
    far = (Waypoint(0.0, 2.0, 0.0, 0.0),)
    with pytest.raises(SimulationError, match="out of reach"):
        Arm6Plant().reset(scenario(path=far), seed=0)


def test_rotation_correction_turns_the_tool() -> None:
    plant = Arm6Plant(Arm6Parameters(servo_time_constant_s=0.0))
    s0 = plant.reset(scenario(objects=()), seed=0)
    for k in range(20):  # axis 6 turns at most 1.8 deg per period
        s = plant.step(np.zeros(3), 0.004 * k, correction_rotation=np.array([0.0, 0.0, 0.2]))
    expected = np.array(matrix_from_quat(quat_from_rotvec((0.0, 0.0, 0.2)))) @ s0.tcp_rotation
    np.testing.assert_allclose(s.tcp_rotation, expected, atol=1e-8)
    np.testing.assert_allclose(s.tool_position, s0.tool_position, atol=1e-8)


def test_cartesian_path_interpolates_position_linearly_and_orientation_by_slerp() -> None:
    q0 = (1.0, 0.0, 0.0, 0.0)
    q1 = quat_from_rotvec((0.0, 0.0, 1.2))
    path = CartesianPath([PathPose(1.0, (0.0, 0.0, 0.0), q0), PathPose(3.0, (1.0, 2.0, 0.0), q1)])
    pos, quat = path.pose_at(1.5)
    np.testing.assert_allclose(pos, [0.25, 0.5, 0.0])
    # a quarter of the way: a quarter of the rotation angle, about the same axis
    np.testing.assert_allclose(
        matrix_from_quat(quat), matrix_from_quat(quat_from_rotvec((0, 0, 0.3))), atol=1e-12
    )
    assert path.pose_at(0.0)[0] == (0.0, 0.0, 0.0)  # held before the start
    assert path.pose_at(9.0)[0] == (1.0, 2.0, 0.0)  # and after the end
    with pytest.raises(ConfigError, match="must not decrease"):
        CartesianPath([PathPose(1.0, (0, 0, 0)), PathPose(0.5, (0, 0, 0))])


def test_3d_contact_matches_the_planar_contact_law_in_the_working_plane() -> None:
    objs = (
        Table(0.0, x_min=0.3, x_max=0.7),
        Box(center_x=0.55, center_z=0.05, size_x=0.04, size_z=0.1, name="hammer"),
        RoughSurface(0.3, 0.7, 0.01, tilt_rad=0.02, roughness_rms_m=0.0005, seed=3),
    )
    sc = scenario(objects=objs, contact=ContactModel(friction=0.4, damping_n_s_per_m=80.0))
    planar = ContactSolver(sc.objects, sc.contact, 0.02)
    spatial = Contact3Solver(objects_from_scenario(sc), sc.contact, 0.02)
    rng = np.random.default_rng(1)
    x, z, dt = 0.35, 0.03, 0.004
    touched = 0
    for _ in range(400):
        vx, vz = rng.normal(0.05, 0.05), rng.normal(0.0, 0.02)
        x, z = x + vx * dt, min(z + vz * dt, 0.04)
        ref = planar.step(x, z, vx, vz, dt)
        got = spatial.step((x, 0.0, z), (vx, 0.0, vz), dt)
        # planar reports the force on the tool; the 3-D solver the force on the environment
        np.testing.assert_allclose(got.force, [-ref.force_x, 0.0, -ref.force_z], atol=1e-9)
        touched += bool(ref.points)
    assert touched > 50


def test_height_field_flat_equals_a_plane_and_rough_has_the_asked_rms() -> None:
    flat = HeightField.rough((0.0, 1.0), (-0.5, 0.5), 0.1, 0.0, spacing=0.05)
    plane = Plane((0.0, 0.0, 0.1), (0.0, 0.0, 1.0))
    for c in [(0.3, 0.1, 0.115), (0.71, -0.2, 0.09)]:
        a, b = flat.contact(c, 0.02), plane.contact(c, 0.02)
        assert a is not None and b is not None
        np.testing.assert_allclose(a[0], b[0])
        np.testing.assert_allclose(a[1], b[1])
    rough = HeightField.rough((0.0, 0.2), (0.0, 0.2), 0.0, 0.001, spacing=0.002, seed=4)
    h = np.array(rough.heights)
    assert float(np.std(h)) == pytest.approx(0.001, rel=1e-9)
    assert HeightField.rough((0.0, 0.2), (0.0, 0.2), 0.0, 0.001, seed=4) == rough
    # the contact normal follows the local slope: tilted field z = 0.1 x
    tilted = HeightField(0.0, 0.0, 0.1, 0.1, ((0.0, 0.0), (0.01, 0.01), (0.02, 0.02)))
    hit = tilted.contact((0.05, 0.05, 0.02), 0.02)
    assert hit is not None
    np.testing.assert_allclose(hit[1], np.array([-0.1, 0.0, 1.0]) / math.sqrt(1.01))
    assert tilted.contact((0.5, 0.05, 0.0), 0.02) is None  # off the grid


def test_box_contact_pushes_out_through_the_nearest_face() -> None:
    box = Box3((0.0, 0.0, 0.0), (0.1, 0.1, 0.05))
    hit = box.contact((0.0, 0.0, 0.06), 0.02)  # above the top face by 1 cm
    assert hit is not None
    assert hit[0] == pytest.approx(0.01)
    assert hit[1] == (0.0, 0.0, 1.0)
    inside = box.contact((0.095, 0.0, 0.0), 0.02)  # centre inside, nearest face +x
    assert inside is not None and inside[1] == (1.0, 0.0, 0.0)
    assert inside[0] == pytest.approx(0.025)
    assert box.contact((0.0, 0.0, 0.08), 0.02) is None


def test_runs_are_deterministic_for_a_seed() -> None:
    sc = Scenario(
        name="noisy",
        path=(Waypoint(0.0, 0.40, 0.0, 0.05), Waypoint(1.0, 0.50, 0.0, 0.05)),
        objects=(Table(0.0),),
        duration_s=1.0,
    )
    forces = []
    for _ in range(2):
        plant = Arm6Plant()
        plant.reset(sc, seed=5)
        forces.append([plant.step(np.array([0, 0, -0.032]), k * 0.004).force for k in range(50)])
    np.testing.assert_array_equal(np.array(forces[0]), np.array(forces[1]))


@pytest.mark.parametrize("bad", [np.zeros(2), np.array([0.0, np.nan, 0.0])])
def test_bad_corrections_are_rejected(bad: Arr) -> None:
    plant = Arm6Plant()
    plant.reset(scenario(), seed=0)
    with pytest.raises(ValueError, match="correction_xyz must be 3 finite numbers"):
        plant.step(bad, 0.004)


# --------------------------------------------------------------------------------------------
# Closed loop: the experiments of fuzzkit.studies.experiments, unchanged, on this plant
# --------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def fuzzy_surface() -> object:
    from fuzzkit.loop.python_loop import load_surface

    return load_surface()


@pytest.mark.parametrize("controller", ["pi", "fuzzy-pi"])
@pytest.mark.parametrize("name", ["E1", "E3"])
def test_experiments_reach_both_set_points_within_1_n(
    name: str, controller: str, fuzzy_surface: object
) -> None:
    from fuzzkit.loop.python_loop import run
    from fuzzkit.studies.experiments import experiment

    exp = experiment(name)
    res = run(
        exp,
        "arm6",
        controller,
        surface=fuzzy_surface if controller == "fuzzy-pi" else None,  # type: ignore[arg-type]
    )
    assert res.plant == "arm6"
    assert not res.tripped
    steady = res.t >= res.t[-1] - exp.steady_window_s
    for axis in (0, 2):  # both x and z are force-controlled in E1 and E3
        assert exp.selection[axis]
        err = res.force_true[steady, axis] - exp.setpoints[axis]
        assert np.max(np.abs(err)) < 1.0, (axis, float(np.max(np.abs(err))))
    # the arm never needed a joint past its limits or an unreachable pose
    assert not any("unreachable" in m or "limit (" in m for m in res.messages)
    assert all(np.all(np.abs(q) < 7.0) for q in res.joint_angles)


def test_selecting_only_z_leaves_x_on_the_nominal_path() -> None:
    from fuzzkit.loop.python_loop import run
    from fuzzkit.studies.experiments import experiment

    exp = experiment("E2")
    assert exp.selection == (False, False, True)
    # ideal servo: the tool is where the IK put it, so x must be the nominal x itself
    res = run(exp, Arm6Plant(Arm6Parameters(servo_time_constant_s=0.0)), "pi")
    assert np.all(res.u[:, 0] == 0.0) and np.all(res.u[:, 1] == 0.0)
    np.testing.assert_allclose(res.tool_position[:, 0], res.nominal_position[:, 0], atol=1e-6)
    np.testing.assert_allclose(res.tool_position[:, 1], 0.0, atol=1e-6)
    # while z really was moved by the force loop
    assert np.max(np.abs(res.tool_position[:, 2] - res.nominal_position[:, 2])) > 1e-3
    steady = res.t >= res.t[-1] - exp.steady_window_s
    assert abs(float(np.mean(res.force_true[steady, 2])) - 30.0) < 1.0

    # with the default 8 ms servo lag, x trails the 25 mm/s path by at most v * tau
    lagged = run(exp, "arm6", "pi")
    np.testing.assert_allclose(
        lagged.tool_position[:, 0], lagged.nominal_position[:, 0], atol=0.025 * 0.008 + 2e-5
    )


def test_arm6_recording_is_written_atomically_and_refuses_planar_runs(tmp_path: Path) -> None:
    from fuzzkit.loop.python_loop import run
    from fuzzkit.studies.experiments import experiment
    from fuzzkit.viz.traces_arm6 import write_rrd

    res = run(experiment("E1"), "arm6", "pi", duration_s=0.5)
    out = write_rrd(res, tmp_path / "e1.rrd")
    data = out.read_bytes()
    assert data[:4] == b"RRF2" and len(data) > 10_000  # a Rerun file with geometry in it
    assert [p.name for p in tmp_path.iterdir()] == ["e1.rrd"]  # no temporary left behind

    planar_like = dataclasses.replace(res, joint_angles=res.joint_angles[:, :2])
    with pytest.raises(ConfigError, match="expected an arm6 run"):
        write_rrd(planar_like, tmp_path / "p.rrd")
    with pytest.raises(ConfigError, match="does not exist"):
        write_rrd(res, tmp_path / "missing" / "x.rrd")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["e1.rrd"]


def test_force_loop_holds_30_n_on_a_3d_rough_field_along_a_diagonal_path() -> None:
    from fuzzkit.loop.python_loop import run
    from fuzzkit.studies.experiments import Experiment

    touch = -0.30 + 0.02 - 0.002  # 2 mm into the nominal surface, as E2 programs it
    field = HeightField.rough((0.30, 0.60), (-0.20, 0.20), -0.30, 0.0002, spacing=0.004, seed=7)
    scn = Scenario(
        name="E2-3D",
        path=(
            Waypoint(0.0, 0.40, -0.10, touch + 0.022),
            Waypoint(1.1, 0.40, -0.10, touch),
            Waypoint(1.5, 0.40, -0.10, touch),
            Waypoint(9.5, 0.46, 0.10, touch),  # diagonal, leaving the x-z plane
        ),
        objects=(),
        duration_s=10.5,
        contact=ContactModel(friction=0.3),
    )
    exp = Experiment(
        name="E2-3D",
        title="diagonal path over a rough height field: 30 N along z",
        scenario=scn,
        setpoints=(0.0, 0.0, 30.0),
        selection=(False, False, True),
        force_limit_n=60.0,
    )
    plant = Arm6Plant(Arm6Parameters(extra_objects=(field,)))
    res = run(exp, plant, "pi")
    assert not res.tripped and not res.messages
    moving = res.moving & (res.t > 3.0)  # sliding over the field after the approach
    assert moving.sum() > 1000
    err = res.force_true[moving, 2] - 30.0
    assert float(np.sqrt(np.mean(err**2))) < 1.0
    # y is not force-controlled: the tool follows the nominal y, within the servo lag
    np.testing.assert_allclose(res.tool_position[:, 1], res.nominal_position[:, 1], atol=3e-4)
    assert np.ptp(res.tool_position[:, 1]) > 0.19


def test_translated_objects_touch_at_the_moved_place() -> None:
    from fuzzkit.plants.environment3d import ExtrudedProfile, translated

    off = (0.07, 0.01, 0.287)
    sphere = 0.02
    objs = [
        Plane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), x_min=-1, x_max=1, y_min=-1, y_max=1),
        Box3((0.0, 0.0, 0.0), (0.05, 0.05, 0.01)),
        HeightField(-0.1, -0.1, 0.1, 0.1, ((0.0,) * 3,) * 3),
        ExtrudedProfile(RoughSurface(-0.1, 0.1, 0.01)),
    ]
    for obj in objs:
        base_hit = obj.contact(
            (0.0, 0.0, 0.015 + 0.01 * isinstance(obj, (Box3, ExtrudedProfile))), sphere
        )
        c = (off[0], off[1], off[2] + 0.015 + 0.01 * isinstance(obj, (Box3, ExtrudedProfile)))
        moved_hit = translated(obj, off).contact(c, sphere)
        assert base_hit is not None and moved_hit is not None, obj
        assert moved_hit[0] == pytest.approx(base_hit[0], abs=1e-12)
        np.testing.assert_allclose(np.subtract(moved_hit[2], base_hit[2]), off, atol=1e-12)
