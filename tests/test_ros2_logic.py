"""The ROS 2 node's logic without ROS (issue 39): the period grid, the steps a stream of stamped
samples makes against ``fuzzkit replay`` of the same samples, parameters through the generated
``set_params`` against ``replay --schedule``, and the watchdog."""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
import pytest
from _codegen_util import needs_cc
from _replay_logs import SPEC, SPEC_PI

from fuzzkit.control import status as st
from fuzzkit.control.spec_reader import load_spec
from fuzzkit.ros2.controller import NodeController, ParameterRefused, open_node_controller
from fuzzkit.ros2.parameters import refusal, tunable_values
from fuzzkit.ros2.sample_clock import SampleClock
from fuzzkit.ros2.stepper import Stepper
from fuzzkit.ros2.watchdog import Watchdog
from fuzzkit.studies.param_schedule import Change, parameter_names
from fuzzkit.studies.replay import SensorLog, replay
from fuzzkit.studies.sensor_logs import hostile_log

PERIOD_NS = 4_000_000  # both example specs run at 4 ms
START_NS = 1_700_000_000_123_456_789  # a real clock's stamp, not a multiple of the period
DOWN = (1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0)  # the tool pointing straight down


def stream(n: int, seed: int) -> tuple[list[tuple[int, int]], npt.NDArray[np.bool_]]:
    """Sample arrivals ``(row, stamp ns)`` for a log of ``n`` rows, in arrival order: stamps
    jittered by up to 0.4 periods from the first one's grid, about 10 % of the rows never sent
    (a gap), a second sample in some periods (late: dropped), and row 20 arriving after row 21
    (out of order: late, so its period is stepped as missing). Also which rows the node steps
    with their sample."""
    rng = np.random.default_rng(seed)
    arrivals: list[tuple[int, int]] = []
    used = np.zeros(n, dtype=bool)
    for k in range(n):
        if 0 < k < n - 1 and k not in (20, 21) and rng.random() < 0.1:
            continue  # never sent
        jitter = int(rng.uniform(-0.4, 0.4) * PERIOD_NS) if k else 0  # the first is the anchor
        arrivals.append((k, START_NS + k * PERIOD_NS + jitter))
        used[k] = True
        if 0 < k < n - 1 and k not in (20, 21) and rng.random() < 0.08:
            arrivals.append((k, START_NS + k * PERIOD_NS + PERIOD_NS // 3))  # the same period
    i20 = next(i for i, (k, _) in enumerate(arrivals) if k == 20)
    arrivals[i20], arrivals[i20 + 1] = arrivals[i20 + 1], arrivals[i20]
    used[20] = False  # arrives after period 21 was stepped
    return arrivals, used


def test_every_period_is_stepped_once_in_order_by_the_nearest_sample() -> None:
    clock = SampleClock(0.004)
    arrivals, used = stream(300, seed=1)
    stepped: list[int] = []
    for k, stamp in arrivals:
        placed = clock.place(stamp)
        if placed.late:
            assert placed.period <= (stepped[-1] if stepped else -1)
            continue
        stepped += list(range(placed.period - placed.missing, placed.period + 1))
        # the sample fills the period whose grid time is nearest its stamp
        assert abs(clock.stamp_ns(placed.period) - stamp) < PERIOD_NS / 2
        assert placed.period == k
    assert stepped == list(range(300))  # each period once, in order, none skipped
    late = len(arrivals) - int(used.sum())
    assert late >= 3  # duplicates and the out-of-order one were dropped


def _open(spec_path: object, impl: str) -> NodeController:
    return open_node_controller(load_spec(spec_path), impl)


def _steps_of(stepper: Stepper, forces: npt.NDArray[np.float64], arrivals: list[tuple[int, int]]):
    out = []
    for k, stamp in arrivals:
        out += stepper.sample(stamp, list(forces[k]), list(DOWN), now_ns=stamp)
    return out


@needs_cc
@pytest.mark.parametrize("impl", ["c", "python"])
def test_a_stream_steps_as_replay_of_the_log_it_makes(impl: str) -> None:
    """Gaps, late and out-of-order samples, NaN, spikes and a trip: the node's steps equal
    ``fuzzkit replay --impl`` of the log with a NaN row for each period it had no sample for,
    0 m apart, the same status; and the reference within the C-versus-Python rounding."""
    spec = load_spec(SPEC)
    forces, _ = hostile_log(spec, n=100, seed=5)
    arrivals, used = stream(len(forces), seed=2)
    stepper = Stepper(open_node_controller(spec, impl), watchdog_periods=50)
    steps = _steps_of(stepper, forces, arrivals)
    assert [s.period for s in steps] == list(range(len(forces)))
    got_u = np.array([s.u for s in steps])
    got_status = np.array([s.status for s in steps])
    seen = np.where(used[:, None], forces, math.nan)
    log = SensorLog(seen, np.tile(DOWN, (len(forces), 1)), None)
    want_u, want_status = replay(spec, log, impl)
    np.testing.assert_array_equal(got_u, want_u)
    np.testing.assert_array_equal(got_status, want_status)
    ref_u, ref_status = replay(spec, log, "reference")
    assert float(np.max(np.abs(got_u - ref_u))) <= 1e-9
    np.testing.assert_array_equal(got_status, ref_status)
    # the log is hostile: held, rejected and tripped periods all occur
    assert all(np.any(got_status & bit) for bit in (st.HELD, st.REJECTED, st.TRIPPED))
    du = np.diff(np.vstack([np.zeros(3), got_u]), axis=0)
    np.testing.assert_array_equal(np.array([s.du for s in steps]), du)
    assert stepper.counters.late == len(arrivals) - int(used.sum())
    assert stepper.counters.missing == len(forces) - int(used.sum())


@pytest.mark.parametrize(
    "spec_path, name, value, match",
    [
        (SPEC, "kp_z", 0.0, "kp_z must be > 0"),
        (SPEC, "kx_x", -1e-4, "kx_x must be > 0"),
        (SPEC, "ki_z", math.nan, "ki_z must be a finite number"),
        (SPEC, "setpoint_z", 25.0, "below the safety limit limit_n = 25 N"),
        (SPEC, "setpoint_x", -30.0, "below the safety limit"),
        (SPEC, "correction_m", 0.0, "correction_m must be > 0"),
        (SPEC, "step_m", math.inf, "step_m must be a finite number"),
        (SPEC, "limit_n", 30.0, "built into the generated controller"),
        (SPEC, "kp_y", 0.1, "kp_y is not a run-time parameter"),
        (SPEC_PI, "kp_z", -1e-5, "kp_z must be >= 0"),
        (SPEC_PI, "kx_z", 1.0, "kx_z is not a run-time parameter"),
        (SPEC, "kp_z", True, "must be a number"),
    ],
)
def test_refused_values_say_why(spec_path: object, name: str, value: float, match: str) -> None:
    spec = load_spec(spec_path)
    why = refusal(spec, tunable_values(spec), {name: value})
    assert why is not None and match in why


def test_the_parameters_are_the_fmus_and_the_schedules() -> None:
    for path in (SPEC, SPEC_PI):
        spec = load_spec(path)
        values = tunable_values(spec)
        names = set(parameter_names(spec)) - {"limit_n"}
        assert set(values) == names | {"correction_m", "step_m"}
        assert values["setpoint_z"] == 10.0 and values["kp_z"] == spec.axes[-1].kp
        assert refusal(spec, values, {"kp_z": 0.0 if spec.kind == "pi" else 0.1}) is None


@needs_cc
@pytest.mark.parametrize("impl", ["c", "python"])
def test_parameter_changes_step_as_replay_with_a_schedule(impl: str) -> None:
    """Gains and set points changed mid-run through the generated set_params, a refused change
    between them, a tare and a reset: the same corrections as the reference replayed with the
    same changes as a schedule (``replay --schedule``)."""
    spec = load_spec(SPEC)
    forces, _ = hostile_log(spec, n=200, seed=8)
    forces = forces[:150]
    changes = {
        40: {"kx_z": 0.0004, "setpoint_z": 6.0},
        70: {"kp_x": 0.1},
        90: {"ki_z": 0.02},
    }
    ctl = open_node_controller(spec, impl)
    out = []
    for k, f in enumerate(forces):
        if k in changes:
            ctl.set_params(changes[k])
        if k == 60:
            before = dict(ctl.params)
            with pytest.raises(ParameterRefused, match="kx_z must be > 0"):
                ctl.set_params({"ki_z": 0.03, "kx_z": -1.0})  # all or nothing
            assert ctl.params == before
        if k == 100:
            ctl.tare()
        if k == 120:
            ctl.reset()
        out.append(ctl.step(list(f), list(DOWN)))
    schedule = [Change(k, n, v) for k, c in changes.items() for n, v in c.items()]
    schedule += [Change(100, "tare", 1.0), Change(120, "reset", 1.0)]
    log = SensorLog(forces, np.tile(DOWN, (len(forces), 1)), None)
    want_u, want_status = replay(spec, log, "reference", schedule=schedule)
    got_u = np.array([u for u, _ in out])
    assert float(np.max(np.abs(got_u - want_u))) <= 1e-9
    np.testing.assert_array_equal([s for _, s in out], want_status)
    # the changes mattered: without them the corrections differ by far more
    plain_u, _ = replay(spec, log, "reference")
    assert float(np.max(np.abs(plain_u - want_u))) > 1e-4


def test_the_watchdog_expires_after_its_periods_and_stays_so() -> None:
    dog = Watchdog(PERIOD_NS, periods=5)
    assert not dog.check(10**12)  # disarmed before the first sample
    dog.feed(0)
    assert not dog.check(5 * PERIOD_NS)  # exactly 5 periods: not yet
    assert dog.check(5 * PERIOD_NS + 1)
    assert dog.expired and not dog.check(10 * PERIOD_NS)  # reported once, latched
    dog.feed(11 * PERIOD_NS)
    assert dog.expired  # a sample does not clear it
    dog.reset()
    assert not dog.expired and not dog.check(10**15)


@needs_cc
def test_a_gap_in_the_stamps_stops_the_output_until_reset() -> None:
    spec = load_spec(SPEC)
    stepper = Stepper(open_node_controller(spec, "c"), watchdog_periods=5)
    f = [0.0, 0.0, 2.0]
    for k in range(30):
        assert len(stepper.sample(START_NS + k * PERIOD_NS, f, DOWN, now_ns=0)) == 1
    # 4 periods missing: stepped as missing samples, then the sample
    steps = stepper.sample(START_NS + 34 * PERIOD_NS, f, DOWN, now_ns=0)
    assert [s.period for s in steps] == [30, 31, 32, 33, 34]
    assert all(s.status & st.HELD for s in steps[:4])
    # 5 periods missing: the watchdog's timeout, nothing stepped from now on
    assert stepper.sample(START_NS + 40 * PERIOD_NS, f, DOWN, now_ns=0) == []
    assert stepper.watchdog.expired
    assert stepper.sample(START_NS + 41 * PERIOD_NS, f, DOWN, now_ns=0) == []
    stepper.reset()
    steps = stepper.sample(START_NS + 99 * PERIOD_NS, f, DOWN, now_ns=0)
    assert [s.period for s in steps] == [0] and steps[0].u == (0.0, 0.0, 0.0)
    assert steps[0].status & st.TARING  # the reset restarted the tare


def test_the_watchdog_periods_are_the_specs() -> None:
    """``safety.watchdog.periods``: 10 when left out; read, written back and used by the node."""
    from fuzzkit.control.spec_reader import loads_spec
    from fuzzkit.control.spec_writer import dump_spec

    text = SPEC.read_text(encoding="utf-8")
    assert "watchdog" not in text and load_spec(SPEC).safety.watchdog_periods == 10
    assert "watchdog" not in dump_spec(load_spec(SPEC))  # the default is not written
    text = text.replace("  trip: {samples: 2}", "  trip: {samples: 2}\n  watchdog: {periods: 3}")
    spec = loads_spec(text, "spec.yaml")
    assert spec.safety.watchdog_periods == 3
    assert loads_spec(dump_spec(spec), "again.yaml").safety.watchdog_periods == 3


def test_auto_runs_the_generated_python_where_c_does_not_compile(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import fuzzkit.loop.controller_code as controller_code
    from fuzzkit.errors import ToolchainError

    real = controller_code.open_generated

    def no_compiler(spec: object, target: str, number_type: str | None = None) -> object:
        if target == "c":
            raise ToolchainError("no C compiler found")
        return real(spec, target, number_type)

    monkeypatch.setattr(controller_code, "open_generated", no_compiler)
    spec = load_spec(SPEC_PI)
    ctl = open_node_controller(spec, "auto")
    assert ctl.impl == "python"
    u, status = ctl.step([0.0, 0.0, 1.0], list(DOWN))
    assert u == [0.0, 0.0, 0.0] and status & st.TARING
    with pytest.raises(ToolchainError, match="no C compiler"):
        open_node_controller(spec, "c")


@needs_cc
def test_a_bag_of_on_grid_samples_replays_as_the_node_steps(tmp_path) -> None:
    """The samples the node stepped, recorded as a bag (stamps on the grid, in order, gaps
    included): ``fuzzkit replay --forces BAG`` resamples it to what the node stepped."""
    from test_replay_bags import wrench as bag_wrench
    from test_replay_bags import write_bag

    from fuzzkit.studies.rosbag_log import read_bag_log

    spec = load_spec(SPEC)
    forces, _ = hostile_log(spec, n=80, seed=9)
    rng = np.random.default_rng(4)
    sent = [k for k in range(len(forces)) if k in (0, len(forces) - 1) or rng.random() > 0.1]
    stepper = Stepper(open_node_controller(spec, "c"), watchdog_periods=50)
    steps = []
    for k in sent:
        steps += stepper.sample(START_NS + k * PERIOD_NS, list(forces[k]), list(DOWN), 0)
    msgs = [
        (START_NS + k * PERIOD_NS + 10_000, bag_wrench(START_NS + k * PERIOD_NS, forces[k]))
        for k in sent
    ]
    bag = tmp_path / "bag"
    write_bag(bag, "mcap", {"/ft": ("geometry_msgs/msg/WrenchStamped", msgs)})
    log = read_bag_log(bag, spec.period_s, "/ft", frame_rotation=DOWN)
    want_u, want_status = replay(spec, log, "c")
    assert len(sent) < len(forces) and len(steps) == len(forces) == len(want_u)
    np.testing.assert_array_equal(np.array([s.u for s in steps]), want_u)
    np.testing.assert_array_equal([s.status for s in steps], want_status)


def test_a_wrench_takes_the_pose_of_its_stamp_whatever_arrives_first() -> None:
    from fuzzkit.ros2.pose_pairing import PosePairing

    def rot(k: int) -> list[float]:
        return [float(k)] * 9

    latest: PosePairing[str] = PosePairing(wait=False, depth=4)
    assert latest.wrench(0, "w0") == [("w0", None)]  # no pose yet: none
    latest.pose(5, rot(5))
    latest.pose(3, rot(3))  # arrived last, stamped earlier: still the latest received
    assert latest.wrench(4, "w4") == [("w4", rot(3))]

    synced: PosePairing[str] = PosePairing(wait=True, depth=4)
    assert synced.wrench(10, "w10") == []  # waits for a pose stamped at or after 10
    assert synced.pose(8, rot(8)) == []
    assert synced.pose(12, rot(12)) == [("w10", rot(8))]  # the latest at or before its stamp
    assert synced.pose(20, rot(20)) == []
    assert synced.wrench(20, "w20") == [("w20", rot(20))]  # its pose came first
    assert synced.wrench(19, "w19") == [("w19", rot(12))]
    # a silent pose topic: beyond depth waiting wrenches the oldest goes on with what there is
    for k in range(30, 34):
        assert synced.wrench(k, f"w{k}") == []
    assert synced.wrench(34, "w34") == [("w30", rot(20))]
    synced.clear()  # the reset service: the waiting wrenches are forgotten
    assert synced.pose(40, rot(40)) == []
