"""The IRB 140 in MuJoCo (``--plant mujoco``) against independent references: the kit's own
kinematics, the contact law's closed form, the servo's designed response, the tool's weight,
and runs that must repeat bit for bit."""

from __future__ import annotations

import dataclasses
import math

import mujoco
import numpy as np
import pytest

from fuzzkit.errors import ConfigError, SimulationError
from fuzzkit.loop.adapter import make_plant
from fuzzkit.loop.python_loop import load_surface, run
from fuzzkit.plants.contact import GRAVITY_M_S2, ContactModel, SensorModel, ToolModel, tool_weight
from fuzzkit.plants.contract import ContactPlant, Scenario
from fuzzkit.plants.environment import RoughSurface, Table, Waypoint
from fuzzkit.plants.kinematics import SerialChain
from fuzzkit.plants.mujoco_arm import MujocoArmPlant, servo_step_response
from fuzzkit.plants.mujoco_model import ArmDynamics, profile_pose
from fuzzkit.plants.robot_description import load_robot
from fuzzkit.studies.experiments import experiment

TABLE_Z = -0.30


def _press_scenario(stiffness: float, tool: ToolModel | None = None) -> Scenario:
    return Scenario(
        name="press",
        path=(Waypoint(0.0, 0.45, 0.0, TABLE_Z + 0.02),),
        objects=(Table(TABLE_Z),),
        duration_s=2.0,
        contact=ContactModel(stiffness_n_per_m=stiffness, damping_n_s_per_m=200.0),
        sensor=SensorModel(noise_std_n=0.0),
        tool=tool or ToolModel(),
    )


def test_the_model_has_the_kinematics_of_the_robot_description() -> None:
    """MuJoCo's tool tip and flange against the kit's DH forward kinematics (``arm6``'s) at
    200 random joint configurations within the limits."""
    plant = MujocoArmPlant()
    plant.reset(_press_scenario(1e4))
    m, d = plant.model, plant.data
    tool = load_robot("irb140").with_tool((0.0, 0.0, 0.12))
    chain = SerialChain(tool)
    rng = np.random.default_rng(7)
    lo = np.array([j.lower for j in tool.joints])
    hi = np.array([j.upper for j in tool.joints])
    flange = m.site("flange").id
    tip = m.geom("tip").id
    worst = 0.0
    for _ in range(200):
        q = rng.uniform(lo, hi)
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        rot, p, _, _ = chain.evaluate(q.tolist())
        worst = max(worst, float(np.max(np.abs(d.geom_xpos[tip] - p))))
        # the flange's frame is the TCP's turned by nothing (a pure translation along z)
        assert np.allclose(d.site_xmat[flange].reshape(3, 3), np.array(rot), atol=1e-9)
    assert worst < 1e-9


@pytest.mark.parametrize("stiffness_n_per_mm", [5.0, 100.0, 1000.0])
def test_a_static_press_finds_the_scenarios_contact_stiffness(stiffness_n_per_mm: float) -> None:
    """The tool pressed into the table and held: true force over penetration (from the tip's
    position and the table's height, not from MuJoCo's contact distance) within 5 % of the
    scenario's stiffness, and the flange sensor reads the same force."""
    k = stiffness_n_per_mm * 1e3
    plant = MujocoArmPlant()
    plant.reset(_press_scenario(k))
    target = np.array([0.0, 0.0, -30.0 / k])  # 30 N if the arm were rigid
    for _ in range(400):
        s = plant.step(target, 0.0)
    penetration = (TABLE_Z + 0.02) - s.tool_position[2]
    assert penetration > 0.0 and s.in_contact
    assert s.force_true[2] / penetration == pytest.approx(k, rel=0.05)
    assert s.force[2] == pytest.approx(s.force_true[2], rel=0.01)
    # the servo is compliant: a stiffer contact takes less of the commanded depth
    assert s.force_true[2] < 30.0


def test_the_contact_damping_is_the_scenarios() -> None:
    """Pressing at a constant speed: the force minus the spring part is damping x speed."""
    k, b, v = 1e4, 400.0, 0.01
    scn = dataclasses.replace(
        _press_scenario(k),
        path=(Waypoint(0.0, 0.45, 0.0, TABLE_Z + 0.02), Waypoint(1.0, 0.45, 0.0, TABLE_Z + 0.01)),
        contact=ContactModel(stiffness_n_per_m=k, damping_n_s_per_m=b),
    )
    plant = MujocoArmPlant()
    plant.reset(scn)
    ratios = []
    for i in range(1, 230):
        s = plant.step(np.zeros(3), i * scn.period_s)
        pen = (TABLE_Z + 0.02) - s.tool_position[2]
        if s.t_s > 0.5 and pen > 0:
            ratios.append((s.force_true[2] - k * pen) / (b * v))
    assert len(ratios) > 100
    assert float(np.median(ratios)) == pytest.approx(1.0, abs=0.1)


def test_the_servo_follows_a_step_as_designed() -> None:
    """Each joint's position loop against its designed closed loop, a critically damped
    second-order response at the stated bandwidth: ``1 - (1 + w t) exp(-w t)``."""
    dyn = ArmDynamics()
    w = 2.0 * math.pi * dyn.bandwidth_hz
    for joint in range(6):
        t, q = servo_step_response(joint, step_rad=0.01, duration_s=0.3)
        designed = 1.0 - (1.0 + w * t) * np.exp(-w * t)
        assert np.max(np.abs(q / 0.01 - designed)) < 0.12, joint
        assert q[-1] / 0.01 == pytest.approx(1.0, abs=0.05), joint
        assert np.max(q) / 0.01 < 1.1, joint  # no marked overshoot


def test_the_elastic_joints_deflect_under_load() -> None:
    """With joint elasticity the links lag their motors under a contact load, and the static
    press still finds the contact's stiffness (the spring is in the arm, not the contact)."""
    k = 1e5
    plant = MujocoArmPlant(dynamics=ArmDynamics(elastic=True))
    plant.reset(_press_scenario(k))
    for _ in range(400):
        s = plant.step(np.array([0.0, 0.0, -30.0 / k]), 0.0)
    assert np.max(np.abs(plant.deflection())) > 1e-6
    penetration = (TABLE_Z + 0.02) - s.tool_position[2]
    assert s.force_true[2] / penetration == pytest.approx(k, rel=0.05)


def test_the_wrist_sensor_carries_the_tools_weight() -> None:
    """A 1.5 kg tool hanging free: the flange sensor reads the kit's tool weight."""
    plant = MujocoArmPlant()
    scn = dataclasses.replace(_press_scenario(1e4), tool=ToolModel(mass_kg=1.5))
    scn = dataclasses.replace(scn, path=(Waypoint(0.0, 0.45, 0.0, TABLE_Z + 0.1),))
    plant.reset(scn)
    for _ in range(100):
        s = plant.step(np.zeros(3), 0.0)
    expected = tool_weight(1.5, scn.rotation)
    assert expected[2] == pytest.approx(-1.5 * GRAVITY_M_S2)
    assert np.allclose(s.force, expected, atol=0.02)
    assert np.all(s.force_true == 0.0)


def test_the_rough_profile_block_sits_on_the_profile() -> None:
    """The block standing for a rough profile: its top face passes through the profile's
    height at x, its normal is the profile's."""
    surface = RoughSurface(0.3, 0.7, -0.3, tilt_rad=-0.014, roughness_rms_m=0.0002, seed=2)
    for x in np.linspace(0.31, 0.69, 17):
        (cx, _, cz), (w, _, y, _) = profile_pose(surface, float(x), (0.0, 0.0, 0.0))
        phi = 2.0 * math.atan2(y, w)
        normal = np.array([math.sin(phi), math.cos(phi)])
        slope = surface.slope(float(x))
        assert np.allclose(normal, np.array([-slope, 1.0]) / math.hypot(slope, 1.0))
        top = np.array([cx, cz]) + normal * 0.01
        assert top == pytest.approx([x, surface.height(float(x))], abs=1e-12)
    assert profile_pose(surface, 0.8, (0.0, 0.0, 0.0))[0][2] == -10.0


def test_the_plant_satisfies_the_contract_and_repeats_bit_for_bit() -> None:
    exp = experiment("E2")
    plant = make_plant("mujoco")
    plant.reset(exp.scenario, seed=0)
    assert isinstance(plant, ContactPlant) and plant.name == "mujoco"
    a = run(exp, "mujoco", "pi", seed=3, duration_s=1.5)
    b = run(exp, "mujoco", "pi", seed=3, duration_s=1.5)
    c = run(exp, "mujoco", "pi", seed=4, duration_s=1.5)
    assert np.array_equal(a.force, b.force, equal_nan=True)
    assert np.array_equal(a.force_true, b.force_true)
    assert np.array_equal(a.joint_angles, b.joint_angles)
    assert not np.array_equal(a.force, c.force, equal_nan=True)  # the seed draws the noise


def test_a_period_off_the_physics_step_and_unknown_objects_are_refused() -> None:
    plant = MujocoArmPlant()
    with pytest.raises(ConfigError, match="multiple of its 1 ms physics step"):
        plant.reset(dataclasses.replace(_press_scenario(1e4), period_s=0.0025))
    with pytest.raises(ConfigError, match="arm dynamics: link_mass_kg needs 6 values"):
        ArmDynamics(link_mass_kg=(1.0,))


@pytest.mark.parametrize(
    "plant, controller",
    [("mujoco", "pi"), ("mujoco", "fuzzy-pi"), ("mujoco-elastic", "fuzzy-pi")],
)
@pytest.mark.parametrize("name", ["E1", "E2", "E3"])
def test_the_paper_experiments_hold_their_set_points_on_it(
    name: str, plant: str, controller: str
) -> None:
    """E1-E3 with the default gains on the dynamic arm, rigid and elastic: below the safety
    limit, no trip, the set points held at the end."""
    exp = experiment(name)
    surface = load_surface("macvicar_whelan") if controller == "fuzzy-pi" else None
    r = run(exp, plant, controller, surface=surface, seed=0)
    assert not r.tripped
    assert float(np.max(np.abs(r.force_true))) < exp.force_limit_n
    tail = r.t >= r.t[-1] - 0.5
    for axis in (i for i in range(3) if exp.selection[i] and exp.setpoints[i]):
        assert float(np.mean(r.force_true[tail, axis])) == pytest.approx(
            exp.setpoints[axis], abs=1.5
        )


def test_the_servo_figure_draws_every_joint_beside_the_design() -> None:
    from fuzzkit.viz.servo_step import servo_step_figure

    fig = servo_step_figure(duration_s=0.05)
    lines = fig.axes[0].get_lines()
    assert [ln.get_label() for ln in lines] == [f"axis {i}" for i in range(1, 7)] + ["design"]
    # every joint has started towards the step by 50 ms and none has run away
    assert all(0.3 < ln.get_ydata()[-1] < 1.1 for ln in lines[:6])


@pytest.mark.slow
@pytest.mark.xdist_group("dask")
def test_a_dask_cluster_gives_the_in_process_results_on_it(dask_scheduler: str) -> None:
    """``fuzzkit sweep --plant mujoco --scheduler``: the same rows from two Dask worker
    processes as in this process (the plant is rebuilt from its name in each worker)."""
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import execute
    from fuzzkit.studies.sweep import map_runs

    specs = [
        RunSpec("E1", "pi", plant="mujoco", loop="python", seed=s, duration_s=2.5) for s in (0, 1)
    ]
    local = [execute(s) for s in specs]
    remote = map_runs(execute, specs, scheduler=dask_scheduler)
    keys = ("plant", "seed", "z_peak_force_true", "z_steady_state_error_mean", "tripped")
    assert [[r[k] for k in keys] for r in remote] == [[r[k] for k in keys] for r in local]
    assert local[0]["plant"] == "mujoco"
    assert local[0]["z_steady_state_error_mean"] != local[1]["z_steady_state_error_mean"]


def test_a_diverging_model_is_a_clear_error_and_prints_nothing(
    capfd: pytest.CaptureFixture[str],
) -> None:
    """A wrist spring far too stiff for the 1 kHz step: MuJoCo's instability becomes a
    SimulationError naming the cause, and MuJoCo's own warning is not printed."""
    plant = MujocoArmPlant(
        dynamics=ArmDynamics(
            elastic=True,
            joint_stiffness_n_m_rad=(1.2e5, 1.2e5, 6.0e4, 0.0, 0.0, 8.0e3),
            joint_damping_n_m_s=(60.0, 60.0, 30.0, 0.0, 0.0, 2.0),
        )
    )
    plant.reset(_press_scenario(1e4))
    with pytest.raises(SimulationError, match="the MuJoCo simulation diverged"):
        for _ in range(100):
            plant.step(np.array([0.0, 0.0, -0.003]), 0.0)
    out, err = capfd.readouterr()
    assert out == "" and err == ""


def test_the_compiled_ik_gives_the_reference_ik_run() -> None:
    """The plant's IK through arm6's compiled twin against the Python reference: the same run
    to within rounding (E1, PI, seed 0)."""
    exp = experiment("E1")
    fast, ref = MujocoArmPlant(), MujocoArmPlant()
    ref.compiled_ik = False
    a = run(exp, fast, "pi", seed=0)
    b = run(exp, ref, "pi", seed=0)
    assert np.max(np.abs(a.force_true - b.force_true)) < 1e-6
    assert np.max(np.abs(a.joint_angles - b.joint_angles)) < 1e-9
    assert np.max(np.abs(a.force_true[:, 2])) > 9.0  # the run did press
