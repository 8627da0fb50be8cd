"""The compiled MuJoCo loop (``fuzzkit/loop/compiled/mujoco_run.py``) against the Python loop on
the Python plant (the reference: ``loop.python_loop.run`` stepping ``MujocoArmPlant``), both
running the same generated C controller: every recorded series equal, bit for bit, the same
messages, faults, trip and engagement; and what the kernel does not model runs the Python loop
and says why."""

from __future__ import annotations

import numpy as np
import pytest
from _codegen_util import needs_cc
from _mujoco import servo, uninstall_after

from fuzzkit.loop.compiled.generated_controller import (
    load_generated_controller,
    run_controller_spec,
)
from fuzzkit.loop.compiled_loop import run_compiled
from fuzzkit.loop.faults import fault
from fuzzkit.loop.generated import GeneratedLoopController
from fuzzkit.loop.python_loop import run
from fuzzkit.loop.result import RunResult
from fuzzkit.loop.spec import RunSpec
from fuzzkit.loop.timing import run_faults_and_latency
from fuzzkit.plants.mujoco_arm import ElasticMujocoArmPlant, MujocoArmPlant
from fuzzkit.plants.mujoco_model import ArmDynamics
from fuzzkit.studies.batch import run_spec
from fuzzkit.studies.experiments import experiment

pytestmark = needs_cc

SERIES = (
    "t", "force", "force_sensor", "force_true", "setpoint", "e", "de", "du", "u",
    "tool_position", "nominal_position", "target_position", "joint_angles", "in_contact",
    "force_normal", "moving", "status", "rotation",
)  # fmt: skip


_no_callback_after = pytest.fixture(autouse=True)(uninstall_after)


def _both(
    make: type[MujocoArmPlant],
    name: str,
    controller: str,
    fault_kind: str,
    seed: int,
    duration_s: float,
    latency: tuple[int, int] | None = None,
    dynamics: ArmDynamics | None = None,
) -> tuple[RunResult, RunResult]:
    """(Python loop on the Python plant, compiled loop), one generated controller."""
    exp = experiment(name)
    generated = load_generated_controller(run_controller_spec(exp, controller, None))
    faults = fault(fault_kind, seed)
    _, sensor_delay, _ = run_faults_and_latency(exp, seed, faults, latency)
    reference_plant = make(dynamics=dynamics)
    reference_plant.use_servo_callback(servo())
    hybrid = GeneratedLoopController(generated.spec, sensor_delay, impl="c")
    reference = run(exp, reference_plant, controller, hybrid=hybrid, seed=seed, faults=faults,
                    duration_s=duration_s, latency=latency)  # fmt: skip
    plant = make(dynamics=dynamics)
    plant.use_servo_callback(servo())
    compiled = run_compiled(exp, plant, seed=seed, faults=fault(fault_kind, seed),
                            duration_s=duration_s, latency=latency,
                            generated_controller=generated)  # fmt: skip
    return reference, compiled


def _assert_same(reference: RunResult, compiled: RunResult) -> None:
    assert compiled.loop == "compiled" and reference.loop == "python"
    for key in SERIES:
        a, b = np.asarray(getattr(reference, key)), np.asarray(getattr(compiled, key))
        assert a.shape == b.shape, key
        assert np.array_equal(a, b, equal_nan=True), key
    for a, b in zip(reference.arm_points, compiled.arm_points, strict=True):
        assert np.array_equal(a, b)
    for a, b in zip(reference.contact_points, compiled.contact_points, strict=True):
        assert np.array_equal(a, b)
    assert compiled.messages == reference.messages
    assert (compiled.faults, compiled.tripped) == (reference.faults, reference.tripped)
    assert compiled.engaged_time_s == reference.engaged_time_s
    assert compiled.trip_time_s == reference.trip_time_s


@pytest.mark.parametrize(
    "make, name, controller, fault_kind, latency",
    [
        (MujocoArmPlant, "E1", "fuzzy-pi", "spike", None),
        (ElasticMujocoArmPlant, "E3", "pi", "nan", (2, 1)),  # rough profile: substep by substep
        (MujocoArmPlant, "E2", "pi", "delay", (0, 3)),
    ],
    ids=["rigid-E1-fuzzy-spike", "elastic-E3-pi-nan", "rigid-E2-pi-delay"],
)
def test_the_compiled_loop_gives_the_python_loops_run_bit_for_bit(
    make: type[MujocoArmPlant],
    name: str,
    controller: str,
    fault_kind: str,
    latency: tuple[int, int] | None,
) -> None:
    reference, compiled = _both(make, name, controller, fault_kind, 1, 2.6, latency)
    assert reference.engaged_time_s is not None  # the runs reach contact
    _assert_same(reference, compiled)


def test_the_compiled_loop_counts_the_python_plants_torque_and_speed_limit_periods() -> None:
    dyn = ArmDynamics(torque_limit_n_m=(350.0, 20.0, 20.0, 40.0, 40.0, 25.0))
    reference, compiled = _both(MujocoArmPlant, "E1", "pi", "none", 0, 2.0, dynamics=dyn)
    assert any(m.startswith("servo torque limit on") for m in reference.messages)
    _assert_same(reference, compiled)


def test_plant_mujoco_runs_compiled_and_a_tilting_tool_falls_back_saying_why() -> None:
    ran = run_spec(RunSpec("E1", "fuzzy-pi", plant="mujoco", duration_s=1.0))
    assert ran.loop == "compiled"
    assert ran.controller_impl.endswith("(compiled loop)")
    tilt = "docs/examples/tilt.yaml"
    fell = run_spec(RunSpec(tilt, "pi", plant="mujoco", duration_s=0.5))
    assert fell.loop.startswith("python")
    assert "tilting tool" in fell.loop


def test_the_plant_kept_between_compiled_runs_starts_each_run_afresh() -> None:
    """``--plant mujoco`` keeps one plant per process for its compiled runs: each run of a
    sequence (other scenarios, controllers, seeds, faults, latencies) is the run a fresh plant
    gives."""
    runs = [
        ("E3", "fuzzy-pi", 4, "none", None),
        ("E1", "pi", 9, "spike", (3, 2)),
        ("E3", "fuzzy-pi", 4, "none", None),
    ]
    for name, controller, seed, fault_kind, latency in runs:
        exp = experiment(name)
        generated = load_generated_controller(run_controller_spec(exp, controller, None))
        fresh = MujocoArmPlant()
        fresh.use_servo_callback(servo())
        kept, alone = (
            run_compiled(
                exp,
                plant,
                seed=seed,
                faults=fault(fault_kind, seed),
                duration_s=1.0,
                latency=latency,
                generated_controller=generated,
            )
            for plant in ("mujoco", fresh)
        )
        for key in SERIES:
            a, b = np.asarray(getattr(kept, key)), np.asarray(getattr(alone, key))
            assert np.array_equal(a, b, equal_nan=True), (name, key)
