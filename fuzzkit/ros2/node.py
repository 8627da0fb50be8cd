"""The rclpy node: wrench in, correction out, parameters, ``tare``/``reset``, diagnostics.

Import this module only after :func:`fuzzkit.ros2.runtime.require` succeeded (it imports
rclpy at module scope). The node's logic is :class:`~fuzzkit.ros2.stepper.Stepper`'s; this
module wires it to ROS (docs/ros2.md lists the topics, parameters, services and QoS):

* subscriptions (sensor-data QoS: best effort, the last 5): the wrench topic, and for a spec that
  compensates the tool's weight the tool pose (which pose goes with a wrench:
  :mod:`~fuzzkit.ros2.pose_pairing`);
* the correction topic (reliable, depth 10): one message per period stepped;
* ``/diagnostics`` (reliable, depth 10): on every change of the status bits, when the watchdog
  stops the output, and once a second; ``~/status``: the same for every period stepped;
* services ``~/tare`` and ``~/reset`` (``std_srvs/Trigger``);
* parameters: the spec's run-time parameters (:mod:`fuzzkit.ros2.parameters`), each change
  through the generated ``set_params``; ``limit_n`` and ``period_s`` read-only;
* a timer at the spec's period (on the node's clock, ``/clock`` with ``use_sim_time``) that
  checks the watchdog.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped, TwistStamped, WrenchStamped
from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
from rclpy.context import Context
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, qos_profile_sensor_data
from std_srvs.srv import Trigger

from fuzzkit.ros2.controller import NodeController, ParameterRefused
from fuzzkit.ros2.diagnostics import diagnostic_array
from fuzzkit.ros2.messages import correction, force_of, rotation_of, stamp_ns, stop
from fuzzkit.ros2.parameters import READ_ONLY
from fuzzkit.ros2.pose_pairing import PosePairing
from fuzzkit.ros2.stepper import Step, Stepper

#: How often the diagnostics are repeated when nothing changes (s).
HEARTBEAT_S = 1.0
#: The publishers' QoS: reliable, the last 10.
RELIABLE = QoSProfile(depth=10)


@dataclass(frozen=True)
class NodeOptions:
    """How the node is wired (the ``fuzzkit ros2`` options)."""

    output: str = "pose"
    wrench_topic: str = "ft_sensor_wrench"
    pose_topic: str = "current_pose"
    correction_topic: str = "correction"
    frame_id: str | None = None  # None: the wrench's frame
    watchdog_periods: int | None = None  # None: the spec's safety.watchdog.periods
    node_name: str | None = None  # None: the spec's name
    namespace: str | None = None
    use_sim_time: bool = False
    pose_sync: bool = False  # a wrench waits for the pose of its stamp (pose_pairing)


class ControllerNode(Node):
    """The spec's generated controller as a ROS 2 node (module docstring)."""

    def __init__(
        self,
        controller: NodeController,
        options: NodeOptions,
        context: Context | None = None,
    ) -> None:
        spec = controller.spec
        super().__init__(
            options.node_name or spec.name,
            context=context,
            namespace=options.namespace,
            parameter_overrides=[Parameter("use_sim_time", value=options.use_sim_time)],
        )
        self.spec = spec
        self.options = options
        periods = options.watchdog_periods or spec.safety.watchdog_periods
        self.stepper = Stepper(controller, periods)
        self._declare_parameters(controller)
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self._needs_rotation = spec.sensor.tool is not None
        self._rotation: list[float] | None = None  # the latest pose's
        self._pairing: PosePairing[Any] = PosePairing(options.pose_sync, periods)
        self._frame = options.frame_id or ""
        self._reported: int | None = None  # the status bits last published
        out_type = PoseStamped if options.output == "pose" else TwistStamped
        self._out = self.create_publisher(out_type, options.correction_topic, RELIABLE)
        self._diag = self.create_publisher(DiagnosticArray, "/diagnostics", RELIABLE)
        self._status = self.create_publisher(DiagnosticArray, "~/status", RELIABLE)
        self.create_subscription(
            WrenchStamped, options.wrench_topic, self._on_wrench, qos_profile_sensor_data
        )
        if self._needs_rotation:
            self.create_subscription(
                PoseStamped, options.pose_topic, self._on_pose, qos_profile_sensor_data
            )
        self.create_service(Trigger, "~/tare", self._on_tare)
        self.create_service(Trigger, "~/reset", self._on_reset)
        self.create_timer(spec.period_s, self._on_tick)
        self.create_timer(HEARTBEAT_S, self._heartbeat)

    # ---------------------------------------------------------------------------- parameters

    def _declare_parameters(self, controller: NodeController) -> None:
        """Declare every run-time parameter with the controller's value, and the read-only
        ones."""
        for name, value in controller.params.items():
            self.declare_parameter(
                name,
                value,
                ParameterDescriptor(description=f"the spec's {name}, set through set_params"),
            )
        read_only = ParameterDescriptor(read_only=True, description="built into the code")
        self.declare_parameter(READ_ONLY, self.spec.safety.limit_n, read_only)
        self.declare_parameter("period_s", self.spec.period_s, read_only)

    def _on_set_parameters(self, params: list[Parameter[Any]]) -> SetParametersResult:
        """A parameter change: through the generated ``set_params``, or refused with the reason
        (the old values kept). Names that are not the controller's (``use_sim_time``) pass."""
        ours = self.stepper.controller.params
        changes = {p.name: p.value for p in params if p.name in ours}
        if not changes:
            return SetParametersResult(successful=True)
        try:
            self.stepper.controller.set_params(changes)
        except ParameterRefused as exc:
            self.stepper.counters.refused_parameters += 1
            return SetParametersResult(successful=False, reason=exc.reason)
        return SetParametersResult(successful=True)

    # ---------------------------------------------------------------------------- samples

    def _on_pose(self, msg: Any) -> None:
        self._rotation = rotation_of(msg)
        for wrench, rotation in self._pairing.pose(stamp_ns(msg.header), self._rotation):
            self._step(wrench, rotation)

    def _on_wrench(self, msg: Any) -> None:
        if not self._needs_rotation:
            self._step(msg, None)
            return
        for wrench, rotation in self._pairing.wrench(stamp_ns(msg.header), msg):
            self._step(wrench, rotation)

    def _step(self, msg: Any, rotation: list[float] | None) -> None:
        """Step the wrench ``msg`` with the tool's ``rotation``; publish what it gives."""
        was_expired = self.stepper.watchdog.expired
        now = self.get_clock().now().nanoseconds
        steps = self.stepper.sample(stamp_ns(msg.header), force_of(msg), rotation, now)
        frame = self.options.frame_id or msg.header.frame_id
        self._frame = frame
        for step in steps:
            self._out.publish(correction(step, self.options.output, self.spec.period_s, frame))
            self._status.publish(self._array(step))
            if step.status != self._reported:
                self._publish_status(step)
        if self.stepper.watchdog.expired and not was_expired:
            self._stopped(now)

    def _on_tick(self) -> None:
        now = self.get_clock().now().nanoseconds
        if self.stepper.check_watchdog(now):
            self._stopped(now)

    def _stopped(self, now: int) -> None:
        """The watchdog expired: stop the robot (twist output) and say so."""
        last = self.stepper.last
        stamp = now if last is None else last.stamp_ns
        msg = stop(self.options.output, stamp, self._frame)
        if msg is not None:
            self._out.publish(msg)
        self._publish_status(last)
        self.get_logger().error(
            f"watchdog: no wrench sample for {self.stepper.watchdog.periods} periods: the "
            "output is stopped until the reset service is called"
        )

    def _heartbeat(self) -> None:
        self._publish_status(self.stepper.last)

    def _array(self, step: Step | None) -> Any:
        """The diagnostics of ``step`` (None: before the first), stamped with its period."""
        status = 0 if step is None else step.status
        period = -1 if step is None else step.period
        stamp = self.get_clock().now().nanoseconds if step is None else step.stamp_ns
        expired = self.stepper.watchdog.expired
        node = self.get_fully_qualified_name()
        counters = self.stepper.counters
        return diagnostic_array(self.spec.name, node, stamp, status, period, expired, counters)

    def _publish_status(self, step: Step | None) -> None:
        self._reported = 0 if step is None else step.status
        self._diag.publish(self._array(step))

    # ---------------------------------------------------------------------------- services

    def _on_tare(self, request: Any, response: Any) -> Any:
        n = self.spec.sensor.tare_samples
        if n == 0:
            response.success = False
            response.message = f"the spec {self.spec.name!r} has no tare (sensor.tare: 0 samples)"
            return response
        self.stepper.tare()
        response.success = True
        response.message = f"taring: the next {n} valid samples are the new bias (free air)"
        return response

    def _on_reset(self, request: Any, response: Any) -> Any:
        self.stepper.reset()
        self._pairing.clear()  # wrenches waiting for their pose belong to the old grid
        self._reported = None
        response.success = True
        response.message = (
            "reset: no correction, not engaged or tripped, watchdog disarmed; the next sample "
            "starts a new period grid"
        )
        return response


def serve(
    controller: NodeController,
    options: NodeOptions,
    ready: Callable[[ControllerNode], None] = lambda node: None,
) -> None:
    """Run the node on the default context until Ctrl-C (or SIGTERM) shuts it down: rclpy
    initialised, ``ready(node)`` once it exists (the command prints what it runs), spun,
    destroyed, rclpy shut down."""
    import rclpy
    from rclpy.executors import ExternalShutdownException

    rclpy.init()
    try:
        node = ControllerNode(controller, options)
        try:
            ready(node)
            rclpy.spin(node)
        except (KeyboardInterrupt, ExternalShutdownException):
            pass
        finally:
            node.destroy_node()
    finally:
        if rclpy.ok():
            rclpy.shutdown()
