"""The simulated plant's side of a closed loop over ROS 2: a node that steps in lockstep with the
controller node on simulated time.

Import this module only after :func:`fuzzkit.ros2.runtime.require` succeeded. Each period
:meth:`PlantNode.step` publishes ``/clock`` (the period's time), the tool pose and the wrench
with that one stamp, and waits for the controller node's correction and its ``~/status`` for
that period. It is a generated controller's step function
(:data:`fuzzkit.loop.generated.StepFunction`): :func:`run` hands it to the one closed loop,
:func:`fuzzkit.loop.run.run_loop`, which builds the plant from the loop package's registry
(:func:`fuzzkit.loop.adapter.make_plant`) and steps it in the Python loop, so that nothing of
a period's plant logic lives here. The
controller node must run with ``use_sim_time`` (its watchdog on ``/clock``), ``pose_sync``
(a wrench waits for the pose of its stamp: the two topics may arrive in either order) and the
pose output.
"""

from __future__ import annotations

import itertools
import time
from dataclasses import replace
from typing import Any

import numpy as np
import numpy.typing as npt
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped, WrenchStamped
from rclpy.context import Context
from rclpy.executors import Executor, SingleThreadedExecutor
from rclpy.node import Node
from rosgraph_msgs.msg import Clock

from fuzzkit.control.spec import ControllerSpec
from fuzzkit.errors import SimulationError
from fuzzkit.loop.result import RunResult
from fuzzkit.loop.run import run_loop
from fuzzkit.loop.spec import RunSpec
from fuzzkit.loop.task import Experiment
from fuzzkit.ros2.messages import pose_message, time_msg, wrench_message
from fuzzkit.ros2.node import RELIABLE, NodeOptions

Vec = npt.NDArray[np.float64]

#: ``/clock`` of period 0 (sim time 0 reads as "no clock yet").
START_NS = 1_000_000_000


class PlantNode(Node):
    """The plant's end of the loop, talking to the controller node ``controller`` (its fully
    qualified name) wired as ``options`` say.

    ``executor``: the one to spin while waiting (default: one of its own; give the controller
    node's when both run in one process).
    """

    def __init__(
        self,
        spec: ControllerSpec,
        controller: str,
        options: NodeOptions,
        *,
        context: Context | None = None,
        executor: Executor | None = None,
        timeout_s: float = 10.0,
    ) -> None:
        super().__init__("fuzzkit_plant", namespace=options.namespace, context=context)
        self.spec = spec
        self.controller = controller
        self.timeout_s = timeout_s
        self._period_ns = round(spec.period_s * 1e9)
        self._periods = itertools.count()
        self._clock_out = self.create_publisher(Clock, "/clock", RELIABLE)
        self._wrench = self.create_publisher(WrenchStamped, options.wrench_topic, RELIABLE)
        self._pose = self.create_publisher(PoseStamped, options.pose_topic, RELIABLE)
        self._corrections: dict[int, Any] = {}
        self._statuses: dict[int, int] = {}
        self.create_subscription(
            PoseStamped, options.correction_topic, self._on_correction, RELIABLE
        )
        self.create_subscription(DiagnosticArray, f"{controller}/status", self._on_status, RELIABLE)
        if executor is None:
            executor = SingleThreadedExecutor(context=context)
            executor.add_node(self)
        self._spinner = executor  # (not "executor": Node has that property)

    def _period(self, stamp: Any) -> int:
        ns = int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)
        return (ns - START_NS) // self._period_ns

    def _on_correction(self, msg: Any) -> None:
        p = msg.pose.position
        self._corrections[self._period(msg.header.stamp)] = [p.x, p.y, p.z]

    def _on_status(self, msg: Any) -> None:
        status = msg.status[0]
        values = {kv.key: kv.value for kv in status.values}
        self._statuses[self._period(msg.header.stamp)] = int(values["status"])

    def _until(self, done: Any, what: str) -> None:
        end = time.monotonic() + self.timeout_s
        while not done():
            if time.monotonic() > end:
                raise SimulationError(f"the controller node did not answer: {what}")
            self._spinner.spin_once(timeout_sec=0.01)

    def wait_for_controller(self) -> None:
        """Until the controller node has subscribed to this node's topics, and it to the node's.

        Raises
        ------
        SimulationError
            Not within ``timeout_s``.
        """
        needs_pose = self.spec.sensor.tool is not None
        self._until(
            lambda: (
                self._wrench.get_subscription_count() > 0
                and (not needs_pose or self._pose.get_subscription_count() > 0)
                and all(s.get_publisher_count() > 0 for s in self.subscriptions)
            ),
            "discovery",
        )

    def step(self, force_n: Vec, rotation: Vec, out: Vec) -> int:
        """One period over ROS 2 on the sample ``force_n`` (N; NaN: missing) and the tool's
        ``rotation`` (row-major 3x3; NaN: none, sent as the zero quaternion): the controller
        node's correction ``u`` (m) written into ``out``, and its status bits.

        Raises
        ------
        SimulationError
            No answer within ``timeout_s``.
        """
        k = next(self._periods)
        t = START_NS + k * self._period_ns
        self._clock_out.publish(Clock(clock=time_msg(t)))
        if self.spec.sensor.tool is not None:  # the node waits for the pose of this stamp
            self._pose.publish(pose_message(t, rotation))
        self._wrench.publish(wrench_message(t, force_n))
        self._until(
            lambda: k in self._corrections and k in self._statuses, f"no answer for period {k}"
        )
        out[:] = self._corrections.pop(k)
        return self._statuses.pop(k)


def run(spec: RunSpec, exp: Experiment, plant_node: PlantNode) -> RunResult:
    """``spec`` on ``exp`` (:func:`fuzzkit.studies.batch.resolve`) with the controller node
    behind ``plant_node`` as its generated controller: the Python loop's run
    (:func:`fuzzkit.loop.run.run_loop`, ``loop="python"``) of the registered plant
    ``spec.plant``, each period one step over ROS 2."""
    label = f"the controller node {plant_node.controller} over ROS 2"
    return run_loop(replace(spec, loop="python"), exp, spec.plant, step=(plant_node.step, label))
