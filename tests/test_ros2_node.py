"""``fuzzkit ros2`` over a real middleware (issue 39): the node on loopback Fast DDS, fed a
hostile log sample by sample, gives ``fuzzkit replay``'s corrections and status; its parameters,
services, diagnostics and watchdog as ROS users reach them. Without the extra the command says
how to install it."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest
from _codegen_util import needs_cc
from _replay_logs import SPEC, SPEC_PI, run_cli
from test_ros2_logic import DOWN, PERIOD_NS, START_NS, stream

from fuzzkit.control import status as st
from fuzzkit.control.spec_reader import load_spec
from fuzzkit.studies.replay import SensorLog, replay
from fuzzkit.studies.sensor_logs import hostile_segments


def test_without_the_extra_ros2_says_how_to_install_it(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setitem(sys.modules, "rclpy", None)  # import rclpy now raises ImportError
    code, out, err = run_cli(capsys, "ros2", str(SPEC))
    assert code == 2 and out == ""
    assert "pip install 'fuzzkit[ros2]'" in err and "importing rclpy failed" in err
    assert "Traceback" not in err


def test_the_command_spells_the_packages_choices() -> None:
    from fuzzkit.cli import ros2_node
    from fuzzkit.ros2.controller import IMPLS
    from fuzzkit.ros2.messages import OUTPUTS

    assert ros2_node.OUTPUTS == OUTPUTS and ros2_node.IMPLS == IMPLS


@pytest.mark.parametrize(
    "argv, match",
    [
        (["--param", "kp_z"], "--param: expected NAME=NUMBER, got 'kp_z'"),
        (["--param", "kp_z=fast"], "--param: expected NAME=NUMBER"),
        (
            ["--watchdog-periods", "0"],
            "argument --watchdog-periods: expected an integer from 1 to 1000000, got '0'",
        ),
        (["--param", "kp_z=0"], "--param: kp_z must be > 0 (a fuzzy-PI scaling factor), got 0"),
        (["--param", "limit_n=30"], "--param: limit_n is built into the generated controller"),
    ],
)
def test_bad_options_are_clear_errors(
    capsys: pytest.CaptureFixture[str], argv: list[str], match: str
) -> None:
    code, _, err = run_cli(capsys, "ros2", str(SPEC), *argv)
    assert code == 2 and match in err


def _statuses(diagnostics: list, n: int) -> np.ndarray:
    """Each period's status from the diagnostics published on every change."""
    from _ros2 import values

    by_period: dict[int, int] = {}
    for d in diagnostics:
        kv = values(d)
        by_period[int(kv["period"])] = int(kv["status"])
    out = np.zeros(n, dtype=np.int64)
    current = None
    for k in range(n):
        current = by_period.get(k, current)
        assert current is not None, "the first period's status is published"
        out[k] = current
    return out


def _positions(corrections: list) -> np.ndarray:
    """The ``u`` of pose corrections, one row per message."""
    return np.array(
        [[m.pose.position.x, m.pose.position.y, m.pose.position.z] for m in corrections]
    )


def _grid_runs(diagnostics: list) -> list[list]:
    """The diagnostics split where the period falls back (a reset starts a new grid)."""
    from _ros2 import values

    runs: list[list] = [[]]
    last = -1
    for d in diagnostics:
        period = int(values(d)["period"])
        if period < last:
            runs.append([])
        runs[-1].append(d)
        last = period
    return runs


def _feed(rig, forces, arrivals) -> None:
    """Publish the samples in arrival order, each waited for (lockstep): a sample that is not
    late shows as the correction of its period."""
    from _ros2 import wrench

    highest = -1
    for k, stamp in arrivals:
        rig.wrench.publish(wrench(stamp, forces[k]))
        if k > highest:
            highest = k
            rig.until(lambda h=highest: len(rig.corrections) > h, what=f"period {highest}")
    rig.settle()


#: (spec, impl, output): the fuzzy-PI in C with the pose output in make test; the PI, the
#: generated Python and the twist output in make verify.
LOG_CASES = [
    pytest.param(SPEC, "c", "pose", id="fuzzy-c-pose"),
    pytest.param(SPEC_PI, "c", "twist", id="pi-c-twist", marks=pytest.mark.verify),
    pytest.param(SPEC, "python", "twist", id="fuzzy-py-twist", marks=pytest.mark.verify),
    pytest.param(SPEC_PI, "python", "pose", id="pi-py-pose", marks=pytest.mark.verify),
]


@needs_cc
@pytest.mark.parametrize("spec_path, impl, output", LOG_CASES)
def test_a_log_published_through_the_node_gives_replays_corrections(
    spec_path: object, impl: str, output: str
) -> None:
    """NaN, spikes, a trip, gaps, a duplicate and an out-of-order sample, over loopback Fast
    DDS into the node running the generated controller: 0 m from ``replay --impl`` of the log
    of the periods the node stepped (a twist: ``du / T`` of it), every status identical."""
    from _ros2 import DOWN_QUATERNION, Rig, period_of, pose, ros_context

    from fuzzkit.ros2.controller import open_node_controller

    spec = load_spec(spec_path)
    parts = hostile_segments(spec, n=100, seed=5)
    forces = np.vstack(
        [parts[k][0] for k in ("spike_trains", "nan_bursts", "sustained_over_limit")]
    )
    arrivals, used = stream(len(forces), seed=3)
    with ros_context() as ctx:
        ctl = open_node_controller(spec, impl)
        rig = Rig(ctx, ctl, watchdog_periods=1000, output=output)
        try:
            rig.give_pose(pose(START_NS, DOWN_QUATERNION))
            _feed(rig, forces, arrivals)
            corrections = list(rig.corrections)
            diagnostics = list(rig.diagnostics)
        finally:
            rig.close()
    n = len(forces)
    assert [period_of(m, START_NS, PERIOD_NS) for m in corrections] == list(range(n))
    assert {m.header.frame_id for m in corrections} == {"ft_sensor"}
    log = SensorLog(np.where(used[:, None], forces, math.nan), np.tile(DOWN, (n, 1)), None)
    want_u, want_status = replay(spec, log, impl)
    if output == "pose":
        got = np.array(
            [[m.pose.position.x, m.pose.position.y, m.pose.position.z] for m in corrections]
        )
        assert float(np.max(np.abs(got - want_u))) == 0.0
    else:
        got = np.array(
            [[m.twist.linear.x, m.twist.linear.y, m.twist.linear.z] for m in corrections]
        )
        want_du = np.diff(np.vstack([np.zeros(3), want_u]), axis=0) / spec.period_s
        assert float(np.max(np.abs(got - want_du))) == 0.0
    statuses = _statuses(diagnostics, n)
    np.testing.assert_array_equal(statuses, want_status)
    assert all(np.any(statuses & bit) for bit in (st.HELD, st.REJECTED, st.TRIPPED, st.ENGAGED))
    last = {kv.key: kv.value for kv in diagnostics[-1].values}
    assert int(last["late"]) == len(arrivals) - int(used.sum())
    assert set(st.BITS) <= set(last)  # every bit by name


@needs_cc
@pytest.mark.verify  # the same as test_ros2_logic's schedule test, over the middleware
def test_parameter_changes_over_ros_give_replay_with_a_schedule() -> None:
    """Gains and a set point changed through the parameter service between samples, a refused
    change, ``~/tare`` and ``~/reset``: the node's corrections are the reference's replayed
    with the same changes as ``replay --schedule``, within 1e-9 m, the same status."""
    from _ros2 import DOWN_QUATERNION, Rig, pose, ros_context, wrench
    from rcl_interfaces.srv import SetParameters
    from rclpy.parameter import Parameter
    from std_srvs.srv import Trigger

    from fuzzkit.ros2.controller import open_node_controller
    from fuzzkit.studies.param_schedule import Change

    spec = load_spec(SPEC)
    parts = hostile_segments(spec, n=100, seed=8)
    forces = np.vstack([parts[k][0] for k in ("random", "setpoint_steps")])
    changes = {40: {"kx_z": 0.0004, "setpoint_z": 6.0}, 70: {"kp_x": 0.1}, 90: {"ki_z": 0.02}}
    events = {130: "tare", 160: "reset"}
    with ros_context() as ctx:
        rig = Rig(ctx, open_node_controller(spec, "c"), watchdog_periods=100_000)
        node = f"{rig.namespace}/{spec.name}"
        try:
            rig.give_pose(pose(START_NS, DOWN_QUATERNION))
            for k, f in enumerate(forces):
                if k in changes:
                    req = SetParameters.Request()
                    req.parameters = [
                        Parameter(n, value=v).to_parameter_msg() for n, v in changes[k].items()
                    ]
                    results = rig.call(SetParameters, f"{node}/set_parameters", req).results
                    assert all(r.successful for r in results)
                if k == 60:
                    req = SetParameters.Request()
                    req.parameters = [Parameter("kx_z", value=-1.0).to_parameter_msg()]
                    (refused,) = rig.call(SetParameters, f"{node}/set_parameters", req).results
                    assert not refused.successful and "kx_z must be > 0" in refused.reason
                if k in events:
                    assert rig.call(Trigger, f"{node}/{events[k]}", Trigger.Request()).success
                rig.wrench.publish(wrench(START_NS + k * PERIOD_NS, f))
                rig.until(lambda k=k: len(rig.corrections) > k, what=f"sample {k}")
            rig.settle()
            corrections = list(rig.corrections)
            diagnostics = list(rig.diagnostics)
        finally:
            rig.close()
    schedule = [Change(k, n, v) for k, c in changes.items() for n, v in c.items()]
    schedule += [Change(k, e, 1.0) for k, e in events.items()]
    n = len(forces)
    log = SensorLog(forces, np.tile(DOWN, (n, 1)), None)
    want_u, want_status = replay(spec, log, "reference", schedule=schedule)
    got = _positions(corrections)
    assert float(np.max(np.abs(got - want_u))) <= 1e-9
    # the reset restarts the grid: the statuses from there are periods 0, 1, ... again
    runs = _grid_runs(diagnostics)
    assert len(runs) == 2
    before, after = _statuses(runs[0], 160), _statuses(runs[1], n - 160)
    np.testing.assert_array_equal(np.concatenate([before, after]), want_status)
    plain_u, _ = replay(spec, log, "reference")
    assert float(np.max(np.abs(plain_u - want_u))) > 1e-4  # the changes mattered


@needs_cc
def test_parameters_services_and_diagnostics_as_ros_users_reach_them() -> None:
    from _ros2 import DOWN_QUATERNION, Rig, pose, ros_context, values, wrench
    from rcl_interfaces.srv import GetParameters, SetParameters
    from rclpy.parameter import Parameter
    from std_srvs.srv import Trigger

    from fuzzkit.ros2.controller import open_node_controller

    spec = load_spec(SPEC_PI)
    with ros_context() as ctx:
        rig = Rig(ctx, open_node_controller(spec, "auto"), watchdog_periods=100_000)
        try:
            node = f"{rig.namespace}/{spec.name}"

            def set_(**changes: float) -> list:
                req = SetParameters.Request()
                req.parameters = [
                    Parameter(k, value=v).to_parameter_msg() for k, v in changes.items()
                ]
                return list(rig.call(SetParameters, f"{node}/set_parameters", req).results)

            def get(*names: str) -> list[float]:
                req = GetParameters.Request()
                req.names = list(names)
                return [
                    v.double_value
                    for v in rig.call(GetParameters, f"{node}/get_parameters", req).values
                ]

            assert get("kp_z", "setpoint_z", "limit_n") == [4.0e-5, 10.0, 25.0]
            (refused,) = set_(setpoint_z=30.0)
            assert not refused.successful and "below the safety limit" in refused.reason
            assert get("setpoint_z") == [10.0]  # the old value kept
            (ok,) = set_(setpoint_z=6.0)
            assert ok.successful and get("setpoint_z") == [6.0]
            assert rig.node.stepper.controller.params["setpoint_z"] == 6.0
            (read_only,) = set_(limit_n=30.0)
            assert not read_only.successful and get("limit_n") == [25.0]

            tare = rig.call(Trigger, f"{node}/tare", Trigger.Request())
            assert tare.success and "next 25 valid samples" in tare.message
            rig.give_pose(pose(START_NS, DOWN_QUATERNION))
            for k in range(30):  # 25 in free air (the tare's 3 N bias), then 3 N of contact
                fz = 3.0 if k < 25 else 6.0
                rig.wrench.publish(wrench(START_NS + k * PERIOD_NS, (0.0, 0.0, fz)))
                rig.until(lambda k=k: len(rig.corrections) > k, what=f"period {k}")
            rig.settle()
            kv = values(rig.diagnostics[-1])
            assert kv["TARING"] == "false" and kv["ENGAGED"] == "true"
            assert rig.diagnostics[-1].message == st.describe(int(kv["status"]))
            reset = rig.call(Trigger, f"{node}/reset", Trigger.Request())
            assert reset.success
            rig.wrench.publish(wrench(START_NS + 10**9, (0.0, 0.0, 3.0)))
            rig.until(lambda: len(rig.corrections) > 30, what="the first period after reset")
            rig.settle()
            assert values(rig.diagnostics[-1])["period"] == "0"  # a new grid
            assert values(rig.diagnostics[-1])["TARING"] == "true"  # the tare starts again
        finally:
            rig.close()


@needs_cc
def test_the_watchdog_stops_the_output_on_sim_time() -> None:
    """On /clock: samples, then the clock runs on without one for more than the watchdog's
    periods: a zero twist, ERROR in the diagnostics, and no correction for later samples until
    the reset service."""
    import dataclasses

    from _ros2 import Rig, ros_context, values, wrench
    from rosgraph_msgs.msg import Clock
    from std_srvs.srv import Trigger

    from fuzzkit.ros2.controller import open_node_controller
    from fuzzkit.ros2.messages import time_msg

    spec = load_spec(SPEC_PI)
    spec = dataclasses.replace(spec, safety=dataclasses.replace(spec.safety, watchdog_periods=5))
    with ros_context() as ctx:  # the spec's safety.watchdog.periods: 5
        rig = Rig(ctx, open_node_controller(spec, "auto"), output="twist", use_sim_time=True)
        try:
            t = START_NS

            def tick(ns: int) -> None:
                rig.clock.publish(Clock(clock=time_msg(ns)))
                rig.until(lambda: rig.node.get_clock().now().nanoseconds == ns, what="/clock")

            tick(t)
            for k in range(10):
                tick(t + k * PERIOD_NS)
                rig.wrench.publish(wrench(t + k * PERIOD_NS, (0.0, 0.0, 0.5)))
                rig.until(lambda k=k: len(rig.corrections) > k, what=f"period {k}")
            rig.settle()
            assert values(rig.diagnostics[-1])["watchdog"] == "ok"
            for k in range(10, 17):  # the clock runs on, no sample
                tick(t + k * PERIOD_NS)
            rig.until(lambda: values(rig.diagnostics[-1])["watchdog"] == "expired", what="expiry")
            rig.settle()
            assert rig.diagnostics[-1].level == bytes([2])
            stop = rig.corrections[-1]
            assert len(rig.corrections) == 11 and stop.twist.linear.z == 0.0
            rig.wrench.publish(wrench(t + 17 * PERIOD_NS, (0.0, 0.0, 0.5)))
            rig.settle()
            assert len(rig.corrections) == 11  # stopped
            assert rig.call(
                Trigger, f"{rig.namespace}/{spec.name}/reset", Trigger.Request()
            ).success
            rig.wrench.publish(wrench(t + 18 * PERIOD_NS, (0.0, 0.0, 0.5)))
            rig.until(lambda: len(rig.corrections) == 12, what="the output after reset")
        finally:
            rig.close()


def test_the_correction_messages_carry_u_and_du_over_t() -> None:
    """A pose offset holds ``u``, a twist ``du / T`` (m/s), both stamped with the period's grid
    time in the wrench's frame; the tool pose's quaternion becomes the rotation the controller
    takes."""
    pytest.importorskip("geometry_msgs.msg", reason="the ros2 extra is in the dev lock")
    from _ros2 import DOWN_QUATERNION, pose

    from fuzzkit.ros2.messages import correction, rotation_of, stamp_ns, stop
    from fuzzkit.ros2.stepper import Step

    step = Step(7, START_NS + 7 * PERIOD_NS, (1e-4, -2e-4, 3e-3), (4e-6, 0.0, -1e-6), 1)
    p = correction(step, "pose", 0.004, "ft_sensor")
    assert (p.pose.position.x, p.pose.position.y, p.pose.position.z) == step.u
    assert (p.pose.orientation.w, p.pose.orientation.x) == (1.0, 0.0)
    t = correction(step, "twist", 0.004, "ft_sensor")
    assert (t.twist.linear.x, t.twist.linear.y, t.twist.linear.z) == (1e-3, 0.0, -2.5e-4)
    assert (t.twist.angular.x, t.twist.angular.y, t.twist.angular.z) == (0.0, 0.0, 0.0)
    for msg in (p, t):
        assert stamp_ns(msg.header) == step.stamp_ns and msg.header.frame_id == "ft_sensor"
    assert stop("pose", 0, "f") is None
    assert stop("twist", step.stamp_ns, "f").twist.linear.z == 0.0
    assert rotation_of(pose(0, DOWN_QUATERNION)) == list(DOWN)
    assert all(math.isnan(v) for v in rotation_of(pose(0, (0.0, 0.0, 0.0, 0.0))))
    # the plant's side: a rotation matrix out as a pose and back, NaN as NaN
    from scipy.spatial.transform import Rotation

    from fuzzkit.ros2.messages import force_of, pose_message, wrench_message

    tilt = Rotation.from_euler("xyz", [170.0, 20.0, -35.0], degrees=True).as_matrix().ravel()
    np.testing.assert_allclose(rotation_of(pose_message(0, tilt)), tilt, rtol=0, atol=1e-15)
    assert all(math.isnan(v) for v in rotation_of(pose_message(0, [math.nan] * 9)))
    w = wrench_message(step.stamp_ns, (1.0, -2.0, 3.5))
    assert force_of(w) == (1.0, -2.0, 3.5) and stamp_ns(w.header) == step.stamp_ns


@needs_cc
@pytest.mark.verify  # a node start of its own, a few seconds: make verify
def test_fuzzkit_ros2_runs_the_node_until_ctrl_c() -> None:
    """The command itself, in its own process: it says what it runs, answers samples with
    twists (``--output twist``, a ``--param`` applied), and stops on SIGINT with status 0."""
    import os
    import signal
    import subprocess
    import time

    from _ros2 import DOWN_QUATERNION, ENVIRONMENT, domain_id, pose, ros_context, wrench
    from geometry_msgs.msg import PoseStamped, TwistStamped, WrenchStamped
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from rclpy.qos import QoSProfile

    namespace = f"/cli{os.getpid()}"
    env = {**os.environ, **ENVIRONMENT, "ROS_DOMAIN_ID": str(domain_id())}
    argv = ["ros2", str(SPEC_PI), "--output", "twist", "--namespace", namespace]
    argv += ["--param", "setpoint_z=6", "--watchdog-periods", "100000"]
    proc = subprocess.Popen(
        [sys.executable, "-m", "fuzzkit", *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        with ros_context() as ctx:
            tester = Node("tester", namespace=namespace, context=ctx)
            executor = SingleThreadedExecutor(context=ctx)
            executor.add_node(tester)
            qos = QoSProfile(depth=100)
            got: list = []
            pub = tester.create_publisher(WrenchStamped, "ft_sensor_wrench", qos)
            poses = tester.create_publisher(PoseStamped, "current_pose", qos)
            tester.create_subscription(TwistStamped, "correction", got.append, qos)
            end = time.monotonic() + 120.0  # a cold start compiles the controller
            while pub.get_subscription_count() == 0 or not tester.count_publishers(
                f"{namespace}/correction"
            ):
                assert proc.poll() is None, proc.communicate()
                assert time.monotonic() < end, "the node did not come up"
                executor.spin_once(timeout_sec=0.05)
            for _ in range(10):  # no acknowledgement of a pose: give it time to arrive
                poses.publish(pose(START_NS, DOWN_QUATERNION))
                executor.spin_once(timeout_sec=0.02)
            end = time.monotonic() + 30.0
            for k in range(40):
                pub.publish(wrench(START_NS + k * PERIOD_NS, (0.0, 0.0, 2.0 if k < 25 else 9.0)))
                while len(got) <= k:
                    assert time.monotonic() < end, f"no correction for period {k}"
                    executor.spin_once(timeout_sec=0.02)
            executor.shutdown()
            tester.destroy_node()
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            out, err = proc.communicate(timeout=20)
        except subprocess.TimeoutExpired:  # never left running
            proc.kill()
            out, err = proc.communicate()
    assert proc.returncode == 0, err
    assert "e1_pi: the generated C (double) controller at 250 Hz as node e1_pi" in out
    assert f"{namespace}/ft_sensor_wrench -> {namespace}/correction (twist)" in out
    assert f"{namespace}/e1_pi/tare" in out
    assert len(got) == 40
    # engaged pushing at 9 N against the 6 N set point (after the 2 N tare): the tool moves
    # back (du < 0 along z)
    assert all(m.twist.linear.z == 0.0 for m in got[:25]) and got[-1].twist.linear.z < 0.0


@needs_cc
@pytest.mark.verify  # the tool swinging: a pose with every sample, paired by stamp
def test_a_tilting_tool_through_the_node_gives_replays_corrections() -> None:
    """The tool swinging by up to 60 degrees while in contact, then dropouts with NaN rotations
    (a zero quaternion) among them: each
    wrench and its pose published with one stamp (``--pose-sync``), the node's corrections are
    ``replay --impl c`` of the log with the rotations the poses carry, 0 m apart."""
    from _ros2 import Rig, period_of, pose, ros_context, wrench
    from scipy.spatial.transform import Rotation

    from fuzzkit.ros2.controller import open_node_controller
    from fuzzkit.ros2.messages import rotation_of

    spec = load_spec(SPEC)
    parts = hostile_segments(spec, n=150, seed=2)
    forces = np.vstack([parts[k][0] for k in ("tilted_tool", "dropouts")])
    rotations = np.vstack([parts[k][1] for k in ("tilted_tool", "dropouts")])
    n = len(forces)
    quats = []
    for r in rotations:
        finite = bool(np.all(np.isfinite(r)))
        q = Rotation.from_matrix(r.reshape(3, 3)).as_quat() if finite else [0.0, 0.0, 0.0, 0.0]
        quats.append(tuple(float(v) for v in q))
    sent = np.array([rotation_of(pose(0, q)) for q in quats])  # what the node receives
    with ros_context() as ctx:
        rig = Rig(ctx, open_node_controller(spec, "c"), pose_sync=True, watchdog_periods=10**6)
        try:
            for k in range(n):
                t = START_NS + k * PERIOD_NS
                if k % 2:  # either order: the stamps pair them
                    rig.pose.publish(pose(t, quats[k]))
                    rig.wrench.publish(wrench(t, forces[k]))
                else:
                    rig.wrench.publish(wrench(t, forces[k]))
                    rig.pose.publish(pose(t, quats[k]))
                rig.until(lambda k=k: len(rig.corrections) > k, what=f"period {k}")
            rig.settle()
            corrections = list(rig.corrections)
            diagnostics = list(rig.diagnostics)
        finally:
            rig.close()
    assert [period_of(m, START_NS, PERIOD_NS) for m in corrections] == list(range(n))
    got = _positions(corrections)
    want_u, want_status = replay(spec, SensorLog(forces, sent, None), "c")
    assert float(np.max(np.abs(got - want_u))) == 0.0
    np.testing.assert_array_equal(_statuses(diagnostics, n), want_status)
    assert np.ptp(sent[np.all(np.isfinite(sent), axis=1), 8]) > 0.4  # it did swing
    assert np.isnan(sent).any() and np.any(want_status & st.HELD)
