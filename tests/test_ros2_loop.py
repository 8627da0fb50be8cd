"""The closed loop over ROS 2 (issue 39 item 3): the simulated plant (planar, arm6) steps in
lockstep with the controller node on simulated time (``/clock``), each period one wrench and
tool pose out over loopback Fast DDS and one correction and status back, and gives the run of
the same loop with the generated controller called in-process, sample for sample, and that of
``fuzzkit simulate`` (the compiled loop) within the compiled loop's own tolerances."""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
import pytest
from _codegen_util import needs_cc
from _replay_logs import SPEC

from fuzzkit.control.spec_reader import load_spec
from fuzzkit.ros2.closed_loop import StepController
from fuzzkit.studies.batch import RunSpec, resolve, run_spec
from fuzzkit.studies.runner import run

START_NS = 1_000_000_000  # /clock of period 0 (1 s: sim time 0 means "no clock yet")
U_TOL = 1e-9  # m, as tests/test_compiled_loop.py holds the compiled loop to the Python loop
FORCE_TOL = {"planar": 1e-9, "arm6": 1e-6}  # N, likewise


def _quaternion(rotation: Any) -> tuple[float, float, float, float]:
    from scipy.spatial.transform import Rotation

    x, y, z, w = Rotation.from_matrix(np.asarray(rotation).reshape(3, 3)).as_quat()
    return (float(x), float(y), float(z), float(w))


def _as_sent(rotation: Any) -> list[float] | None:
    """The rotation as the node receives it: through a PoseStamped's quaternion."""
    from _ros2 import pose

    from fuzzkit.ros2.messages import rotation_of

    return None if rotation is None else rotation_of(pose(0, _quaternion(rotation)))


def over_ros(rig: Any, spec: Any) -> Any:
    """The step function of a plant on the far side of ROS 2: per period /clock, the tool pose
    and the wrench, stamped alike (the node runs with pose_sync: it pairs them by stamp,
    whichever arrives first); then the node's correction and status for that period."""
    from _ros2 import pose, values, wrench
    from rosgraph_msgs.msg import Clock

    from fuzzkit.ros2.messages import time_msg

    periods = itertools.count()
    period_ns = round(spec.period_s * 1e9)
    last = [np.eye(3).reshape(9).tolist()]  # the loop's start-up wait steps without a rotation

    def step(force: list[float], rotation: list[float] | None) -> tuple[list[float], int]:
        k = next(periods)
        t = START_NS + k * period_ns
        rig.clock.publish(Clock(clock=time_msg(t)))
        if spec.sensor.tool is not None:  # the node waits for the pose of this stamp
            last[0] = last[0] if rotation is None else rotation
            rig.pose.publish(pose(t, _quaternion(last[0])))
        rig.wrench.publish(wrench(t, force))
        rig.until(lambda: len(rig.corrections) > k and len(rig.statuses) > k, what=f"period {k}")
        p = rig.corrections[k].pose.position
        return [p.x, p.y, p.z], int(values(rig.statuses[k])["status"])

    return step


def in_process(ctl: Any) -> Any:
    def step(force: list[float], rotation: list[float] | None) -> tuple[list[float], int]:
        return ctl.step(force, _as_sent(rotation))

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
        try:
            _, exp, plant_obj = resolve(run_spec_)
            remote = run(
                exp,
                plant_obj,
                hybrid=StepController(spec, over_ros(rig, spec)),
                seed=0,
                duration_s=duration_s,
            )
        finally:
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
