"""The MuJoCo arm's servo ramp as a C control callback (``fuzzkit/plants/mujoco_servo.c``)
against the Python ramp it replaces (the reference, one ``mj_step`` per substep): the same
trajectory bit for bit, the same torque-limit periods, its state per ``MjData``, and the Python
ramp, said so, where it cannot be compiled."""

from __future__ import annotations

import copy
import ctypes

import mujoco
import numpy as np
import pytest
from _codegen_util import needs_cc
from _mujoco import servo, uninstall_after

from fuzzkit.loop import mujoco as mujoco_plants
from fuzzkit.loop.adapter import make_plant
from fuzzkit.plants.mujoco_arm import ElasticMujocoArmPlant, MujocoArmPlant
from fuzzkit.plants.mujoco_model import ArmDynamics
from fuzzkit.plants.mujoco_servo import ServoCallback
from fuzzkit.studies.experiments import experiment

_no_callback_after = pytest.fixture(autouse=True)(uninstall_after)


def _drive(
    plant: MujocoArmPlant, experiment_name: str, periods: int
) -> tuple[np.ndarray, dict[str, int]]:
    """Every period's full physics state (qpos, qvel, ctrl, actuator forces) and the plant's
    messages, under a correction that changes every period (so the ramp is never flat)."""
    scn = experiment(experiment_name).scenario
    plant.reset(scn, seed=3)
    d = plant.data
    rows, messages = [], {}
    for k in range(periods):
        correction = np.array([0.0005 * ((k % 5) - 2), 0.0, 0.002 * (k % 7)])
        sample = plant.step(correction, (k + 1) * scn.period_s)
        for m in sample.messages:
            messages[m] = messages.get(m, 0) + 1
        rows.append(np.concatenate([d.qpos, d.qvel, d.ctrl, d.actuator_force, sample.force_true]))
    return np.array(rows), messages


@needs_cc
@pytest.mark.parametrize(
    "plant_cls, name",
    [(MujocoArmPlant, "E1"), (ElasticMujocoArmPlant, "E2"), (MujocoArmPlant, "E3")],
    ids=["rigid-E1", "elastic-E2-profile", "rigid-E3"],
)
def test_the_callback_gives_the_python_ramps_trajectory_bit_for_bit(
    plant_cls: type[MujocoArmPlant], name: str
) -> None:
    """200 periods (E2's rough profile steps substep by substep, the others in one
    ``mj_step(nstep=4)``): every double of the state equal."""
    reference, ref_messages = _drive(plant_cls(), name, 200)
    plant = plant_cls()
    plant.use_servo_callback(servo())
    fast, messages = _drive(plant, name, 200)
    assert np.array_equal(reference, fast)
    assert messages == ref_messages


@needs_cc
def test_the_callback_finds_the_python_ramps_torque_limit_periods() -> None:
    """Axes 2 and 3 limited to 20 N m saturate while the arm moves: the same periods and axes
    (the callback marks substeps 1 to 3, the plant the last one)."""
    dyn = ArmDynamics(torque_limit_n_m=(350.0, 20.0, 20.0, 40.0, 40.0, 25.0))
    reference, ref_messages = _drive(MujocoArmPlant(dynamics=dyn), "E1", 150)
    plant = MujocoArmPlant(dynamics=dyn)
    plant.use_servo_callback(servo())
    fast, messages = _drive(plant, "E1", 150)
    limited = {m: c for m, c in ref_messages.items() if m.startswith("servo torque limit")}
    assert sum(limited.values()) > 100  # the case does saturate
    assert messages == ref_messages
    assert np.array_equal(reference, fast)


@needs_cc
def test_the_callbacks_state_is_per_simulation() -> None:
    """Two plants stepped in turn (one callback, two MjData with different ramps) end where
    each ends alone, and an MjData the callback was not armed for keeps its controls."""
    alone_rigid, _ = _drive(_with(MujocoArmPlant()), "E1", 60)
    alone_elastic, _ = _drive(_with(ElasticMujocoArmPlant()), "E3", 60)

    a, b = _with(MujocoArmPlant()), _with(ElasticMujocoArmPlant())
    scn_a, scn_b = experiment("E1").scenario, experiment("E3").scenario
    a.reset(scn_a, seed=3)
    b.reset(scn_b, seed=3)
    ends = []
    for k in range(60):
        correction = np.array([0.0005 * ((k % 5) - 2), 0.0, 0.002 * (k % 7)])
        a.step(correction, (k + 1) * scn_a.period_s)
        b.step(correction, (k + 1) * scn_b.period_s)
    ends = [np.array(a.data.qpos), np.array(b.data.qpos)]
    nq_a, nq_b = len(ends[0]), len(ends[1])
    assert np.array_equal(ends[0], alone_rigid[-1, :nq_a])
    assert np.array_equal(ends[1], alone_elastic[-1, :nq_b])

    other = mujoco.MjData(a.model)  # same model, not armed
    other.ctrl[:] = 0.25
    mujoco.mj_step(a.model, other, nstep=3)
    assert np.all(other.ctrl == 0.25)


def _with(plant: MujocoArmPlant) -> MujocoArmPlant:
    plant.use_servo_callback(servo())
    return plant


@needs_cc
def test_plant_mujoco_runs_the_callback() -> None:
    """``--plant mujoco`` and ``mujoco-elastic`` are built with the compiled ramp."""
    for name in ("mujoco", "mujoco-elastic"):
        plant = make_plant(name)
        assert isinstance(plant, MujocoArmPlant)
        assert isinstance(plant.servo, ServoCallback)


def test_without_a_compiler_the_python_ramp_runs_and_says_so(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv("CC", "/nonexistent/cc")
    mujoco_plants.servo_callback.cache_clear()
    try:
        plant = make_plant("mujoco")
    finally:
        mujoco_plants.servo_callback.cache_clear()
    assert isinstance(plant, MujocoArmPlant)
    assert plant.servo is None
    scn = experiment("E1").scenario
    plant.reset(scn)
    first = plant.step(np.zeros(3), scn.period_s)
    second = plant.step(np.zeros(3), 2 * scn.period_s)
    assert any(
        "servo ramp in Python" in m and "no C compiler found" in m for m in first.messages
    ), first.messages
    assert not any("servo ramp" in m for m in second.messages)


def test_a_library_built_for_other_mujoco_headers_is_refused() -> None:
    class Other:
        fuzzkit_servo_mj_version = staticmethod(lambda: mujoco.mj_version() + 1)
        fuzzkit_servo_ramp = ctypes.CFUNCTYPE(None)(lambda: None)

    with pytest.raises(RuntimeError, match="compiled against MuJoCo"):
        ServoCallback(Other())


@needs_cc
def test_a_limit_reached_only_in_the_periods_last_substep_is_marked() -> None:
    """The callback runs before each substep's forces are computed, so the last substep's are
    marked after ``mj_step`` (``fuzzkit_servo_mark_last``): a limit between the first three
    substeps' force and the last one's, from the Python ramp's forces, marks that servo only."""
    plant = MujocoArmPlant()
    scn = experiment("E1").scenario
    plant.reset(scn)
    for k in range(30):  # moving along the path
        plant.step(np.zeros(3), (k + 1) * scn.period_s)
    m, start = plant.model, plant.data
    prev = np.array(start.ctrl)
    ref, feed = prev + 0.01, np.zeros(m.nu)
    d = copy.copy(start)
    forces = []
    for s in range(1, 5):  # the reference ramp
        d.ctrl[:] = prev + (s / 4) * (ref - prev) + feed
        mujoco.mj_step(m, d)
        forces.append(np.abs(d.actuator_force))
    f = np.array(forces)
    rising = [a for a in range(m.nu) if f[3, a] > 1.001 * f[:3, a].max()]
    assert rising  # a ramp up: some servo's torque grows to the last substep
    a = rising[0]
    limits = np.full(m.nu, 1e9)
    limits[a] = 0.5 * (f[3, a] + f[:3, a].max()) / 0.999
    callback = servo()
    fast = copy.copy(start)
    u = callback.arm(fast, 4, limits)
    callback.install()
    marked = callback.period(m, fast, u, prev, ref, feed)
    assert np.flatnonzero(marked).tolist() == [a]
    assert np.array_equal(fast.qpos, d.qpos)
