"""``fuzzkit ros2``: a controller spec's generated controller as a ROS 2 node (docs/ros2.md)."""

from __future__ import annotations

import argparse
from typing import Any

from fuzzkit.cli import numbers

EXIT_OK = 0
#: Kept here so that building the parser imports nothing of ROS (fuzzkit.ros2.messages.OUTPUTS,
#: fuzzkit.ros2.controller.IMPLS; a test holds them equal).
OUTPUTS = ("pose", "twist")
IMPLS = ("auto", "c", "python")


def register(sub: Any) -> None:
    """Add ``ros2`` to the ``fuzzkit`` parser."""
    p = sub.add_parser(
        "ros2",
        help="run a controller spec's generated controller as a ROS 2 node (the ros2 extra)",
        description="Run the generated controller of a spec (C where a compiler exists, else "
        "the generated Python) as an rclpy node: each geometry_msgs/WrenchStamped sample on "
        "the wrench topic (sensor-data QoS) is one controller step, on the period grid of the "
        "spec (a period without a sample is stepped as a missing one; a late sample is "
        "dropped), and the correction u is published as a PoseStamped offset or a TwistStamped "
        "(du / T) in the wrench's frame. The spec's gains, set points and correction limits "
        "are ROS parameters, changed through the controller's set_params; ~/tare and ~/reset "
        "are std_srvs/Trigger services; the status bits are published on /diagnostics; a "
        "watchdog stops the output when no sample came for the spec's safety.watchdog.periods "
        "periods. Needs "
        "the ROS 2 Python packages: pip install 'fuzzkit[ros2]'. Ctrl-C stops the node.",
        epilog="examples:\n"
        "  fuzzkit ros2 docs/examples/controller.yaml\n"
        "  fuzzkit ros2 docs/examples/controller_pi.yaml --output twist --wrench-topic /ft/wrench\n"
        "  fuzzkit ros2 SPEC --param kp_z=0.3 --use-sim-time\n"
        "  ros2 param set /e1_fuzzy kx_z 0.0003      (from another shell)\n"
        "  ros2 service call /e1_fuzzy/tare std_srvs/srv/Trigger",
    )
    p.add_argument("spec", metavar="SPEC", help="controller spec (YAML)")
    p.add_argument(
        "--output",
        choices=OUTPUTS,
        default="pose",
        help="pose: geometry_msgs/PoseStamped, position = u (m), for a motion controller's "
        "target offset; twist: geometry_msgs/TwistStamped, linear = du / T (m/s)",
    )
    p.add_argument(
        "--wrench-topic", default="ft_sensor_wrench", help="the F/T sensor's WrenchStamped topic"
    )
    p.add_argument(
        "--pose-topic",
        default="current_pose",
        help="the tool's PoseStamped (its orientation), read when the spec compensates the "
        "tool's weight (sensor.tool)",
    )
    p.add_argument(
        "--pose-sync",
        action="store_true",
        help="pair each wrench with the tool pose of its stamp: a wrench waits until a pose "
        "stamped at or after it came (a plant stepping in lockstep publishes both); default: the "
        "latest pose received, no waiting",
    )
    p.add_argument("--correction-topic", default="correction", help="where u is published")
    p.add_argument(
        "--frame-id",
        default=None,
        metavar="FRAME",
        help="the corrections' header.frame_id (default: the wrench messages' frame)",
    )
    p.add_argument(
        "--impl",
        choices=IMPLS,
        default="auto",
        help="auto: the generated C (double) where a compiler exists, else the generated "
        "Python; c; python (the names of simulate --controller-impl)",
    )
    p.add_argument(
        "--watchdog-periods",
        type=numbers.WATCHDOG_PERIODS,
        default=None,
        metavar="N",
        help="stop the output when no sample came for N periods (default: the spec's "
        "safety.watchdog.periods, 10 when it has none)",
    )
    p.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="start with this run-time parameter (kp_z, ki_z, kx_z, setpoint_z, correction_m, "
        "step_m, ...), checked as a parameter change is (repeatable) (default: the spec's)",
    )
    p.add_argument("--node-name", default=None, metavar="NAME", help="default: the spec's name")
    p.add_argument(
        "--namespace", default=None, metavar="NS", help="the node's namespace (default: none)"
    )
    p.add_argument(
        "--use-sim-time",
        action="store_true",
        help="the node's clock (watchdog) follows /clock (rosgraph_msgs/Clock)",
    )
    p.set_defaults(handler=cmd_ros2)


def _overrides(items: list[str]) -> dict[str, float]:
    from fuzzkit.errors import ConfigError

    out: dict[str, float] = {}
    for item in items:
        name, sep, text = item.partition("=")
        try:
            value = float(text)
        except ValueError:
            value = float("nan")
        if not sep or not name.strip() or value != value:
            raise ConfigError(f"--param: expected NAME=NUMBER, got {item!r}")
        out[name.strip()] = value
    return out


def cmd_ros2(args: argparse.Namespace) -> int:
    """Handler of ``fuzzkit ros2``."""
    from fuzzkit.errors import ConfigError
    from fuzzkit.ros2 import runtime

    overrides = _overrides(args.param)
    runtime.require()  # before the spec: without the extra, say how to install it first
    from fuzzkit.control.spec_reader import load_spec
    from fuzzkit.ros2.controller import ParameterRefused, open_node_controller

    spec = load_spec(args.spec)
    controller = open_node_controller(spec, args.impl)
    try:
        controller.set_params(overrides)
    except ParameterRefused as exc:
        raise ConfigError(f"--param: {exc.reason}") from None

    from fuzzkit.ros2.node import NodeOptions, serve

    options = NodeOptions(
        output=args.output,
        wrench_topic=args.wrench_topic,
        pose_topic=args.pose_topic,
        correction_topic=args.correction_topic,
        frame_id=args.frame_id,
        watchdog_periods=args.watchdog_periods or spec.safety.watchdog_periods,
        node_name=args.node_name,
        namespace=args.namespace,
        use_sim_time=args.use_sim_time,
        pose_sync=args.pose_sync,
    )
    impl = "generated C (double)" if controller.impl == "c" else "generated Python"

    def ready(node: Any) -> None:
        print(
            f"{spec.name}: the {impl} controller at {1.0 / spec.period_s:g} Hz as node "
            f"{node.get_name()}: {node.resolve_topic_name(options.wrench_topic)} -> "
            f"{node.resolve_topic_name(options.correction_topic)} ({args.output}); services "
            f"{node.resolve_service_name('~/tare')}, {node.resolve_service_name('~/reset')}; "
            f"watchdog {options.watchdog_periods} periods. Ctrl-C stops.",
            flush=True,
        )

    serve(controller, options, ready)
    return EXIT_OK
