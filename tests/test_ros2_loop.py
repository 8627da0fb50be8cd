"""The closed loop over ROS 2 (issue 39 item 3): the simulated plant (planar, arm6) steps in
lockstep with the controller node on simulated time (``/clock``), each period one wrench and
tool pose out over loopback Fast DDS and one correction and status back
(:class:`fuzzkit.ros2.plant_node.PlantNode`, a generated controller's step function, handed to
the one closed loop, :func:`fuzzkit.loop.run.run_loop`, which builds and steps the plant).

The pair proven equal bit for bit: that run and ``fuzzkit simulate --loop python
--controller-impl c`` of the same spec, experiment and seed (the same Python plant, the same
generated C, the same loop; the node only carries the samples and corrections). The default
``simulate`` (the compiled loop: the plant's numba kernel) gives that run bit for bit on planar,
and on arm6 within the compiled loop's own tolerances, as tests/test_compiled_loop.py holds it
to the Python loop.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import pytest
from _codegen_util import needs_cc
from _replay_logs import SPEC

from fuzzkit.loop.generated import open_step
from fuzzkit.loop.run import run_loop
from fuzzkit.loop.spec import RunSpec
from fuzzkit.studies.batch import resolve, run_spec

U_TOL = 1e-9  # m, as tests/test_compiled_loop.py holds arm6's compiled loop to the Python loop
FORCE_TOL = 1e-6  # N, likewise
#: every series the two runs must share bit for bit (NaN where both have none)
SERIES = ("t", "force", "force_sensor", "force_true", "e", "de", "du", "u", "tool_position",
          "joint_angles", "rotation", "status")  # fmt: skip


def assert_same_run(got: Any, want: Any) -> None:
    for name in SERIES:
        np.testing.assert_array_equal(getattr(got, name), getattr(want, name), err_msg=name)
    assert (got.tripped, got.trip_time_s, got.engaged_time_s, got.faults) == (
        want.tripped, want.trip_time_s, want.engaged_time_s, want.faults,
    )  # fmt: skip


def python_loop_spec(plant: str, duration_s: float | None) -> RunSpec:
    """``simulate E1 --plant PLANT --spec SPEC --loop python --controller-impl c``."""
    return RunSpec("E1", plant=plant, controller_spec=str(SPEC), seed=0, duration_s=duration_s,
                   loop="python", controller_impl="c")  # fmt: skip


@needs_cc
def test_a_step_function_is_the_generated_controller_it_stands_for() -> None:
    """The loop's ``step`` hook without ROS: the generated C opened here and handed in as the
    step function gives ``simulate --loop python``'s run, and a step function that is not the
    controller (its output scaled) does not."""
    spec = python_loop_spec("planar", 2.0)
    rs, exp, _ = resolve(spec)
    assert exp.controller_spec is not None
    step, label = open_step(exp.controller_spec, "c")
    got = run_loop(rs, exp, rs.plant, step=(step, label))
    want = run_spec(spec)
    assert want.engaged_time_s is not None  # the run reached contact
    assert_same_run(got, want)

    other, _ = open_step(exp.controller_spec, "c")

    def scaled(force: Any, rotation: Any, out: Any) -> int:
        status = other(force, rotation, out)
        out *= 1.0 + 1e-12
        return status

    off = run_loop(rs, exp, rs.plant, step=(scaled, "scaled"))
    assert not np.array_equal(off.u, want.u)


def test_a_step_function_is_refused_for_the_reference_and_the_compiled_loop() -> None:
    from fuzzkit.errors import ConfigError

    for loop, impl in (("python", "reference"), ("compiled", "c")):
        spec = replace(python_loop_spec("planar", 0.1), loop=loop, controller_impl=impl)
        rs, exp, _ = resolve(spec)
        with pytest.raises(ConfigError, match="step function"):
            run_loop(rs, exp, rs.plant, step=(lambda f, r, o: 0, "none"))


def over_ros(spec: RunSpec) -> Any:
    """``spec`` run with the controller node over Fast DDS as its controller."""
    from _ros2 import Rig, ros_context

    from fuzzkit.ros2.controller import open_node_controller
    from fuzzkit.ros2.plant_node import PlantNode, run

    rs, exp, _ = resolve(spec)
    assert exp.controller_spec is not None
    with ros_context() as ctx:
        ctl = open_node_controller(exp.controller_spec, "c")
        rig = Rig(ctx, ctl, use_sim_time=True, pose_sync=True, watchdog_periods=10**6)
        plant_node = PlantNode(
            exp.controller_spec,
            rig.node.get_fully_qualified_name(),
            rig.options,
            context=ctx,
            executor=rig.executor,  # one process: one executor spins both nodes
        )
        rig.executor.add_node(plant_node)
        try:
            plant_node.wait_for_controller()
            return run(rs, exp, plant_node)
        finally:
            plant_node.destroy_node()
            rig.close()


@needs_cc
@pytest.mark.parametrize(
    "plant, duration_s",
    [
        pytest.param("planar", 0.2, id="planar-free-air"),  # cheap: 50 periods, no contact
        pytest.param("planar", None, id="planar", marks=pytest.mark.verify),
        pytest.param("arm6", None, id="arm6", marks=pytest.mark.verify),
    ],
)
def test_the_loop_over_ros_is_simulate_of_the_same_loop_bit_for_bit(
    plant: str, duration_s: float | None
) -> None:
    spec = python_loop_spec(plant, duration_s)
    remote = over_ros(spec)
    want = run_spec(spec)
    assert duration_s is not None or remote.engaged_time_s is not None  # the whole run: contact
    assert remote.loop == "python" and "over ROS 2" in remote.controller_impl
    assert_same_run(remote, want)
    # fuzzkit simulate's default: the compiled loop, the plant's numba kernel. On planar it is
    # the Python loop's run bit for bit (E1, seed 0); on arm6 the kernel's arithmetic differs
    # (measured: 3.2e-16 m, 5.3e-12 N), so it is held to the compiled loop's own tolerances.
    sim = run_spec(replace(spec, loop="auto", controller_impl="auto"))
    assert sim.loop == "compiled"
    if plant == "planar":
        assert_same_run(remote, sim)
        return
    np.testing.assert_allclose(remote.u, sim.u, rtol=0, atol=U_TOL)
    np.testing.assert_allclose(remote.force, sim.force, rtol=0, atol=FORCE_TOL, equal_nan=True)
    np.testing.assert_array_equal(remote.status, sim.status)
    assert remote.tripped == sim.tripped and remote.engaged_time_s == sim.engaged_time_s
