"""Wrench-in to correction-out latency of ``fuzzkit ros2`` on loopback Fast DDS (issue 39 item 4).

Run: ``.venv/bin/python bench/bench_ros2.py`` (about half a minute; needs the ros2 extra). The
node runs as ``fuzzkit ros2`` in its own process (the example fuzzy-PI spec, its period set to
4 ms and 1 ms), with the generated C and with the generated Python. This process publishes
``WrenchStamped`` samples at the spec's rate from a thread of its own and takes the time each
correction comes back (wall clock, the same on both sides of the loopback: one machine). A
sample whose correction never came is counted as lost. Nothing is asserted: the figures depend
on the machine and its load.
"""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SPEC = ROOT / "docs" / "examples" / "controller.yaml"
RATES_HZ = (250, 1000)
IMPLS = ("c", "python")
SECONDS = 4.0  # of samples per case
DOMAIN = 97  # away from the tests' blocks of domains (0..99 in fours, from the run's id)
ENVIRONMENT = {
    "RMW_IMPLEMENTATION": "rmw_fastrtps_cpp",
    "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
    "FASTDDS_BUILTIN_TRANSPORTS": "UDPv4",
    "ROS_DOMAIN_ID": str(DOMAIN),
}


def _spec_at(rate_hz: int, folder: Path) -> Path:
    """The example spec with its period set to ``1 / rate_hz``, written to ``folder``."""
    from fuzzkit.control.spec_reader import load_spec
    from fuzzkit.control.spec_writer import dump_spec

    spec = load_spec(SPEC)
    spec = dataclasses.replace(spec, period_s=1.0 / rate_hz, rulebase_ref="macvicar_whelan")
    path = folder / f"spec_{rate_hz}.yaml"
    path.write_text(dump_spec(spec), encoding="utf-8")
    return path


def _percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(q * (len(ordered) - 1)))]


def measure(spec_path: Path, rate_hz: int, impl: str) -> tuple[list[float], int]:
    """Latencies (s) of every sample answered, and how many were lost."""
    import rclpy
    from geometry_msgs.msg import PoseStamped, WrenchStamped
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from rclpy.qos import QoSProfile

    from fuzzkit.ros2.messages import stamp_ns, time_msg

    namespace = f"/bench{os.getpid()}"
    node = subprocess.Popen(
        [sys.executable, "-m", "fuzzkit", "ros2", str(spec_path), "--impl", impl,
         "--namespace", namespace, "--watchdog-periods", "100000"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        env={**os.environ, **ENVIRONMENT},
    )  # fmt: skip
    period_ns = round(1e9 / rate_hz)
    sent: dict[int, int] = {}
    answered: dict[int, int] = {}
    ctx = rclpy.context.Context()
    rclpy.init(context=ctx, domain_id=DOMAIN)
    try:
        bench = Node("bench", namespace=namespace, context=ctx)
        qos = QoSProfile(depth=100)
        pub = bench.create_publisher(WrenchStamped, "ft_sensor_wrench", qos)
        pose = bench.create_publisher(PoseStamped, "current_pose", qos)
        start = time.time_ns()

        def on_correction(msg: object) -> None:
            answered[(stamp_ns(msg.header) - start) // period_ns] = time.time_ns()  # type: ignore[attr-defined]

        bench.create_subscription(PoseStamped, "correction", on_correction, qos)
        executor = SingleThreadedExecutor(context=ctx)
        executor.add_node(bench)
        deadline = time.monotonic() + 60.0
        while (
            pub.get_subscription_count() == 0
            or bench.count_publishers(f"{namespace}/correction") == 0
        ):
            if time.monotonic() > deadline or node.poll() is not None:
                raise RuntimeError(
                    f"the node did not come up: {node.stdout.read() if node.stdout else ''}"
                )
            executor.spin_once(timeout_sec=0.05)
        down = PoseStamped()
        down.pose.orientation.x = 1.0  # the tool pointing down: a half turn about x
        for _ in range(5):
            pose.publish(down)
            executor.spin_once(timeout_sec=0.05)
        n = int(SECONDS * rate_hz)
        start = time.time_ns()

        def publish() -> None:
            for k in range(n):
                due = start + k * period_ns
                while (now := time.time_ns()) < due:
                    time.sleep(min(0.0005, (due - now) / 1e9))
                msg = WrenchStamped()
                msg.header.stamp = time_msg(due)
                msg.header.frame_id = "ft_sensor"
                msg.wrench.force.z = 3.0 if k < 100 else 8.0
                sent[k] = time.time_ns()
                pub.publish(msg)

        feeder = threading.Thread(target=publish)
        feeder.start()
        while feeder.is_alive():
            executor.spin_once(timeout_sec=0.01)
        end = time.monotonic() + 0.5
        while time.monotonic() < end:
            executor.spin_once(timeout_sec=0.01)
        executor.shutdown()
        bench.destroy_node()
    finally:
        ctx.try_shutdown()
        node.terminate()
        try:
            node.wait(timeout=10)
        except subprocess.TimeoutExpired:  # never left running
            node.kill()
            node.wait()
    latencies = [(answered[k] - sent[k]) / 1e9 for k in sent if k in answered]
    return latencies, len(sent) - len(latencies)


def step_cpu_us(impl: str, n: int = 2000) -> float:
    """CPU time of one controller step as the node calls it (``NodeController.step``), us."""
    from fuzzkit.control.spec_reader import load_spec
    from fuzzkit.ros2.controller import open_node_controller

    ctl = open_node_controller(load_spec(SPEC), impl)
    down = [1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0]
    for _ in range(30):  # the tare
        ctl.step([0.0, 0.0, 3.0], down)
    start = time.process_time()
    for k in range(n):
        ctl.step([0.1 * (k % 7), 0.0, 8.0 + 0.01 * (k % 13)], down)
    return (time.process_time() - start) / n * 1e6


def main() -> None:
    try:
        import rclpy  # noqa: F401
    except ImportError:
        print("skipped: the ros2 extra is not installed (pip install 'fuzzkit[ros2]')")
        return
    os.environ.update(ENVIRONMENT)
    print(
        "fuzzkit ros2: wrench in -> correction out on loopback Fast DDS (UDPv4), separate "
        f"processes, {SECONDS:g} s of samples per row"
    )
    for impl in IMPLS:
        label = "generated C" if impl == "c" else "generated Python"
        print(f"one controller step as the node calls it, {label}: {step_cpu_us(impl):.1f} us CPU")
    head = (
        f"{'rate':>7} {'period':>8} {'controller':>18} {'p50':>9} {'p99':>9} {'max':>9} {'lost':>6}"
    )
    print(head)
    with tempfile.TemporaryDirectory() as tmp:
        for rate in RATES_HZ:
            spec = _spec_at(rate, Path(tmp))
            for impl in IMPLS:
                lat, lost = measure(spec, rate, impl)
                label = "generated C" if impl == "c" else "generated Python"
                ms = [v * 1e3 for v in lat]
                print(
                    f"{rate:>5} Hz {1e3 / rate:>6.1f} ms {label:>18} "
                    f"{_percentile(ms, 0.5):>6.3f} ms {_percentile(ms, 0.99):>6.3f} ms "
                    f"{max(ms):>6.3f} ms {lost:>6}",
                    flush=True,
                )


if __name__ == "__main__":
    main()
