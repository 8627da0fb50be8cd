"""Loopback Fast DDS for the ROS 2 node's tests (not a test module).

Each xdist worker talks on its own ``ROS_DOMAIN_ID`` (the run's id picks a block of domains,
the worker its place in it), discovery is limited to this machine
(``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``) and Fast DDS's built-in transport to UDPv4, so the
samples cross the loopback interface rather than shared memory. Every test's nodes live in a
namespace of their own, so that even a second run that drew the same domain does not cross.

:class:`Rig` holds the node under test and a tester node in one context, spun by one
single-threaded executor in the test's own thread: nothing runs behind the test's back.
"""

from __future__ import annotations

import itertools
import os
import tempfile
import time
import zlib
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import pytest

rclpy = pytest.importorskip("rclpy", reason="the ros2 extra is in the dev lock")
from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402
from geometry_msgs.msg import PoseStamped, TwistStamped, WrenchStamped  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.qos import QoSProfile  # noqa: E402
from rosgraph_msgs.msg import Clock  # noqa: E402

from fuzzkit.ros2.controller import NodeController  # noqa: E402
from fuzzkit.ros2.messages import stamp_ns, time_msg, wrench_message  # noqa: E402
from fuzzkit.ros2.node import ControllerNode, NodeOptions  # noqa: E402

#: Domains per run: a block of 4 (one per xdist worker) among 0..99.
WORKERS_PER_RUN = 4
ENVIRONMENT = {
    "RMW_IMPLEMENTATION": "rmw_fastrtps_cpp",
    "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
    "FASTDDS_BUILTIN_TRANSPORTS": "UDPv4",
    # rclpy's log files, out of the home folder
    "ROS_LOG_DIR": os.path.join(tempfile.gettempdir(), "fuzzkit-test-ros-log"),
}
_names = itertools.count()


def domain_id() -> int:
    """This worker's domain: distinct for every worker of a run."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "gw0")
    index = int(worker.removeprefix("gw") or 0) % WORKERS_PER_RUN
    run = os.environ.get("PYTEST_XDIST_TESTRUNUID", str(os.getpid()))
    block = zlib.crc32(run.encode()) % (100 // WORKERS_PER_RUN)
    return block * WORKERS_PER_RUN + index


@contextmanager
def ros_context() -> Iterator[Any]:
    """An initialised rclpy context on this worker's domain, shut down afterwards."""
    saved = {k: os.environ.get(k) for k in ENVIRONMENT}
    os.environ.update(ENVIRONMENT)
    ctx = rclpy.context.Context()
    rclpy.init(context=ctx, domain_id=domain_id())
    try:
        yield ctx
    finally:
        ctx.try_shutdown()
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def wrench(stamp: int, force: Any) -> Any:
    return wrench_message(stamp, force)


def pose(stamp: int, quaternion: tuple[float, float, float, float]) -> Any:
    msg = PoseStamped()
    msg.header.stamp = time_msg(stamp)
    q = msg.pose.orientation
    q.x, q.y, q.z, q.w = quaternion
    return msg


#: The tool pointing straight down: a half turn about x (the rotation DOWN of the logic tests).
DOWN_QUATERNION = (1.0, 0.0, 0.0, 0.0)


class Rig:
    """The node under test and a tester node that feeds it and records what it publishes."""

    def __init__(self, ctx: Any, controller: NodeController, **options: Any) -> None:
        self.namespace = f"/t{os.getpid()}_{next(_names)}"
        self.options = NodeOptions(namespace=self.namespace, **options)
        self.node = ControllerNode(controller, self.options, context=ctx)
        self.tester = Node("tester", namespace=self.namespace, context=ctx)
        self.executor = SingleThreadedExecutor(context=ctx)
        self.executor.add_node(self.node)
        self.executor.add_node(self.tester)
        reliable = QoSProfile(depth=1000)
        self.wrench = self.tester.create_publisher(
            WrenchStamped, self.options.wrench_topic, reliable
        )
        self.pose = self.tester.create_publisher(PoseStamped, self.options.pose_topic, reliable)
        self.clock = self.tester.create_publisher(Clock, "/clock", reliable)
        out_type = PoseStamped if self.options.output == "pose" else TwistStamped
        self.corrections: list[Any] = []
        self.diagnostics: list[Any] = []
        self.statuses: list[Any] = []  # the node's ~/status, one per period stepped
        self.tester.create_subscription(
            out_type, self.options.correction_topic, self.corrections.append, reliable
        )
        self.tester.create_subscription(
            DiagnosticArray,
            f"{self.namespace}/{self.node.get_name()}/status",
            lambda m: self.statuses.append(m.status[0]),
            reliable,
        )
        name = f"fuzzkit/{controller.spec.name}"
        ours = self.node.get_fully_qualified_name()  # not another run's node on this domain
        self.tester.create_subscription(
            DiagnosticArray,
            "/diagnostics",
            lambda m: self.diagnostics.extend(
                s for s in m.status if s.name == name and s.hardware_id == ours
            ),
            reliable,
        )
        needs_pose = controller.spec.sensor.tool is not None
        self.until(
            lambda: (
                self.wrench.get_subscription_count() > 0
                and self.node._out.get_subscription_count() > 0
                and self.node._diag.get_subscription_count() > 0
                and self.node._status.get_subscription_count() > 0
                and (needs_pose is False or self.pose.get_subscription_count() > 0)
            ),
            timeout_s=30.0,
            what="discovery",
        )

    def until(self, done: Callable[[], bool], timeout_s: float = 10.0, what: str = "") -> None:
        """Spin until ``done()``; fail after ``timeout_s``."""
        end = time.monotonic() + timeout_s
        while not done():
            if time.monotonic() > end:
                pytest.fail(f"timed out waiting for {what or done}")
            self.executor.spin_once(timeout_sec=0.01)

    def give_pose(self, msg: Any) -> None:
        """Publish ``msg`` on the pose topic until the node has taken its rotation."""
        self.node._rotation = None
        end = time.monotonic() + 10.0
        while self.node._rotation is None:
            if time.monotonic() > end:
                pytest.fail("the node never took the tool pose")
            self.pose.publish(msg)
            for _ in range(5):
                self.executor.spin_once(timeout_sec=0.01)

    def settle(self, quiet_s: float = 0.1) -> None:
        """Spin until nothing has arrived for ``quiet_s``."""
        count = -1
        while count != len(self.corrections) + len(self.diagnostics):
            count = len(self.corrections) + len(self.diagnostics)
            end = time.monotonic() + quiet_s
            while time.monotonic() < end:
                self.executor.spin_once(timeout_sec=0.01)

    def call(self, srv_type: Any, name: str, request: Any) -> Any:
        client = self.tester.create_client(srv_type, name)
        self.until(client.service_is_ready, what=f"service {name}")
        future = client.call_async(request)
        self.until(future.done, what=f"the answer of {name}")
        return future.result()

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()
        self.tester.destroy_node()


def period_of(msg: Any, start_ns: int, period_ns: int) -> int:
    """The period a correction is stamped with."""
    offset = stamp_ns(msg.header) - start_ns
    assert offset % period_ns == 0, "corrections are stamped on the period grid"
    return offset // period_ns


def values(status: Any) -> dict[str, str]:
    return {kv.key: kv.value for kv in status.values}
