"""The closed loop over ROS 2 (issue 39 item 3): the simulated plant (planar, arm6) steps in
lockstep with the controller node on simulated time (``/clock``), each period one wrench and
tool pose out over loopback Fast DDS and one correction and status back
(:class:`fuzzkit.ros2.plant_node.PlantNode`), and gives the run of
the same loop with the generated controller called in-process, sample for sample, and that of
``fuzzkit simulate`` (the compiled loop) within the compiled loop's own tolerances."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from _codegen_util import needs_cc
from _replay_logs import SPEC

from fuzzkit.control.spec_reader import load_spec
from fuzzkit.loop.python_loop import run
from fuzzkit.loop.spec import RunSpec
from fuzzkit.ros2.closed_loop import StepController
from fuzzkit.studies.batch import resolve, run_spec

U_TOL = 1e-9  # m, as tests/test_compiled_loop.py holds the compiled loop to the Python loop
FORCE_TOL = {"planar": 1e-9, "arm6": 1e-6}  # N, likewise


def in_process(ctl: Any) -> Any:
    """The generated controller called here, with the rotation as the node receives it (through
    a PoseStamped's quaternion)."""
    from fuzzkit.ros2.messages import pose_message, rotation_of

    def step(force: list[float], rotation: list[float] | None) -> tuple[list[float], int]:
        sent = None if rotation is None else rotation_of(pose_message(0, rotation))
        return ctl.step(force, sent)

    return step


@needs_cc
@pytest.mark.parametrize(
    "plant, duration_s",
    [
        pytest.param("planar", None, id="planar"),
        pytest.param("arm6", None, id="arm6"),
    ],
)
@pytest.mark.verify  # 1,250 periods of lockstep over the middleware: several seconds each
def test_the_loop_over_ros_is_the_loop_in_process_and_simulates_run(
    plant: str, duration_s: float | None
) -> None:
    from _ros2 import Rig, ros_context

    from fuzzkit.ros2.controller import open_node_controller
    from fuzzkit.ros2.plant_node import PlantNode

    spec = load_spec(SPEC)
    run_spec_ = RunSpec("E1", plant=plant, controller_spec=str(SPEC), seed=0, duration_s=duration_s)
    _, exp, plant_obj = resolve(run_spec_)
    here = run(
        exp,
        plant_obj,
        hybrid=StepController(spec, in_process(open_node_controller(spec, "c"))),
        seed=0,
        duration_s=duration_s,
    )
    with ros_context() as ctx:
        ctl = open_node_controller(spec, "c")
        rig = Rig(ctx, ctl, use_sim_time=True, pose_sync=True, watchdog_periods=10**6)
        plant_node = PlantNode(
            spec,
            rig.node.get_fully_qualified_name(),
            rig.options,
            context=ctx,
            executor=rig.executor,  # one process: one executor spins both nodes
        )
        rig.executor.add_node(plant_node)
        try:
            plant_node.wait_for_controller()
            _, exp, plant_obj = resolve(run_spec_)
            remote = run(
                exp,
                plant_obj,
                hybrid=StepController(spec, plant_node.step),
                seed=0,
                duration_s=duration_s,
            )
        finally:
            plant_node.destroy_node()
            rig.close()
    assert remote.engaged_time_s is not None  # the run reached contact
    for name in ("t", "u", "force", "force_sensor", "tool_position", "status"):
        np.testing.assert_array_equal(getattr(remote, name), getattr(here, name), err_msg=name)
    # fuzzkit simulate: the compiled loop, the generated C called in-kernel
    sim = run_spec(run_spec_)
    assert sim.loop == "compiled"
    np.testing.assert_allclose(remote.u, sim.u, rtol=0, atol=U_TOL)
    np.testing.assert_allclose(
        remote.force, sim.force, rtol=0, atol=FORCE_TOL[plant], equal_nan=True
    )
    np.testing.assert_array_equal(remote.status, sim.status)
    assert remote.tripped == sim.tripped and remote.engaged_time_s == sim.engaged_time_s
