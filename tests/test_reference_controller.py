"""The reference controller built from a spec: the sensor front end (tare, gravity compensation,
low-pass) against closed forms, the correction limits, the status bits, and faults (NaN, spikes,
dropouts, a missing rotation) through the front end."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from fuzzkit.control import status as st
from fuzzkit.control.reference import Controller, hybrid_from_spec
from fuzzkit.control.spec import ControllerSpec, Limits, SensorSpec, ToolSpec
from fuzzkit.control.spec_reader import load_spec

ROOT = Path(__file__).resolve().parent.parent
FUZZY = load_spec(ROOT / "docs" / "examples" / "controller.yaml")
PI = load_spec(ROOT / "docs" / "examples" / "controller_pi.yaml")
G_WORLD = np.array([0.0, 0.0, -9.80665])
TOOL_DOWN = np.diag([1.0, -1.0, -1.0])


def _rot_y(angle: float) -> np.ndarray:
    """The tool pointing down, tilted by ``angle`` about the world y axis."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]) @ TOOL_DOWN


def _reading(contact: np.ndarray, rot: np.ndarray, mass: float, bias: np.ndarray) -> np.ndarray:
    """What the sensor reads (independent of the code: the wrist force on the tool, F_wt =
    f - m*g_W, expressed in the sensor frame, plus the bias)."""
    return rot.T @ (rot @ contact - mass * G_WORLD) + bias


def _spec(
    base: ControllerSpec = PI,
    tare: int = 0,
    mass: float | None = None,
    lowpass: float | None = None,
    **safety: float | None,
) -> ControllerSpec:
    tool = None if mass is None else ToolSpec(mass, (0.0, 0.0, 0.05))
    return dataclasses.replace(
        base,
        sensor=SensorSpec(tare, tool, lowpass),
        safety=dataclasses.replace(base.safety, **safety),
    )


def _flat(rot: np.ndarray) -> list[float]:
    return [float(v) for v in rot.ravel()]


# --------------------------------------------------------------------------- the front end


def test_gravity_compensation_removes_the_weight_at_any_rotation() -> None:
    mass = 0.8
    ctrl = Controller(_spec(mass=mass, engage_threshold_n=None))
    rng = np.random.default_rng(3)
    for _ in range(40):
        rot = _rot_y(float(rng.uniform(-0.8, 0.8)))
        contact = np.array([rng.uniform(-2, 2), 0.0, rng.uniform(5, 15)])
        ctrl.step(list(_reading(contact, rot, mass, np.zeros(3))), _flat(rot))
        seen = np.asarray(ctrl.spec.setpoints) - ctrl.hybrid.e  # e = f_d - f on force axes
        assert seen[[0, 2]] == pytest.approx(contact[[0, 2]], abs=1e-12)


def test_tare_removes_the_bias_and_then_compensation_follows_the_tilt() -> None:
    mass, bias = 0.35, np.array([1.5, -0.7, 2.2])
    n = 5
    ctrl = Controller(_spec(tare=n, mass=mass, engage_threshold_n=None))
    for _ in range(n):  # free air, tool pointing down
        u, status = ctrl.step(list(_reading(np.zeros(3), TOOL_DOWN, mass, bias)), _flat(TOOL_DOWN))
        assert status & st.TARING and status & st.HELD and u == [0.0, 0.0, 0.0]
    assert ctrl.hybrid.front_end is not None
    assert ctrl.hybrid.front_end.bias == pytest.approx(bias, abs=1e-12)
    tilted = _rot_y(0.3)
    contact = np.array([0.5, 0.0, 10.0])
    _, status = ctrl.step(list(_reading(contact, tilted, mass, bias)), _flat(tilted))
    assert not status & (st.TARING | st.HELD)
    seen = np.asarray(ctrl.spec.setpoints) - ctrl.hybrid.e
    assert seen[[0, 2]] == pytest.approx(contact[[0, 2]], abs=1e-12)


def test_tare_alone_leaves_the_weight_change_of_a_tilt() -> None:
    """Without the tool's mass the tare removes the weight at the tare pose only: a tilt of
    theta about y leaves m*g*(-sin theta, 0, 1 - cos theta) of error (the weight's component
    along the tool axis shrinks), as the closed form says."""
    mass, theta = 0.35, 0.3
    ctrl = Controller(_spec(tare=3, engage_threshold_n=None))
    for _ in range(3):
        ctrl.step(list(_reading(np.zeros(3), TOOL_DOWN, mass, np.zeros(3))))
    contact = np.array([0.0, 0.0, 10.0])
    ctrl.step(list(_reading(contact, _rot_y(theta), mass, np.zeros(3))))
    seen = np.asarray(ctrl.spec.setpoints) - ctrl.hybrid.e
    mg = mass * 9.80665
    assert seen[0] - contact[0] == pytest.approx(-mg * math.sin(theta), rel=1e-9)
    assert seen[2] - contact[2] == pytest.approx(mg * (1.0 - math.cos(theta)), rel=1e-9)


def test_a_tare_request_takes_the_next_samples() -> None:
    ctrl = Controller(_spec(tare=2, engage_threshold_n=None))
    for _ in range(2):
        ctrl.step([1.0, 0.0, 1.0])
    ctrl.tare()
    for _ in range(2):
        _, status = ctrl.step([3.0, 0.0, 4.0])
        assert status & st.TARING
    assert ctrl.hybrid.front_end is not None
    assert ctrl.hybrid.front_end.bias.tolist() == [3.0, 0.0, 4.0]
    ctrl.reset()  # a reset tares again too
    _, status = ctrl.step([0.0, 0.0, 0.0])
    assert status & st.TARING


def test_lowpass_step_response_is_the_continuous_one_at_the_samples() -> None:
    fc = 20.0
    ctrl = Controller(_spec(lowpass=fc, engage_threshold_n=None))
    tau, period = 1.0 / (2.0 * math.pi * fc), ctrl.spec.period_s
    ctrl.step([0.0, 0.0, 0.0])  # initialises y = 0
    for k in range(1, 30):
        ctrl.step([0.0, 0.0, 5.0])
        seen = ctrl.spec.setpoints[2] - ctrl.hybrid.e[2]
        assert seen == pytest.approx(5.0 * (1.0 - math.exp(-k * period / tau)), rel=1e-12)


# --------------------------------------------------------------------------- faults


def _run(
    ctrl: Controller, samples: list[list[float]], rot: np.ndarray | None = None
) -> list[tuple[list[float], int]]:
    return [ctrl.step(s, None if rot is None else _flat(rot)) for s in samples]


def _contact_series(n: int, seed: int = 0) -> list[list[float]]:
    rng = np.random.default_rng(seed)
    return [[float(rng.normal(0.0, 0.1)), 0.0, 8.0 + float(rng.normal(0.0, 0.1))] for _ in range(n)]


@pytest.mark.parametrize("base", [PI, FUZZY], ids=["pi", "fuzzy-pi"])
def test_nan_and_a_spike_reach_neither_the_filter_nor_the_correction(base: ControllerSpec) -> None:
    """With the front end on, a NaN sample and a gated spike are held (HELD, and REJECTED for
    the spike), and the run afterwards equals the run where they were simply missing."""
    spec = _spec(base, tare=3, mass=0.35, lowpass=40.0)
    rot = TOOL_DOWN
    free = [list(_reading(np.zeros(3), rot, 0.35, np.array([0.4, 0.0, -1.0])))] * 3
    contact = [
        list(_reading(np.array(s), rot, 0.35, np.array([0.4, 0.0, -1.0])))
        for s in _contact_series(60)
    ]
    spiked = [list(s) for s in contact]
    spiked[20][2] += 30.0  # a spike far past the 12.5 N gate
    spiked[30] = [math.nan, 0.0, math.nan]
    holed = [list(s) for s in contact]
    holed[20] = [math.nan] * 3
    holed[30] = [math.nan] * 3
    a = _run(Controller(spec), free + spiked, rot)
    b = _run(Controller(spec), free + holed, rot)
    assert a[3 + 20][1] & st.REJECTED and a[3 + 20][1] & st.HELD
    assert a[3 + 30][1] & st.HELD and not a[3 + 30][1] & st.REJECTED
    assert [u for u, _ in a] == [u for u, _ in b]
    assert a[3 + 20][0] == a[3 + 19][0]  # held
    assert all(not s & st.TRIPPED for _, s in a)


def test_a_dropout_holds_then_resumes() -> None:
    spec = _spec(tare=2, lowpass=40.0, engage_threshold_n=1.0)
    ctrl = Controller(spec)
    _run(ctrl, [[0.0, 0.0, 0.0]] * 2)
    out = _run(ctrl, _contact_series(20))
    u_before = out[-1][0]
    dropped = _run(ctrl, [[math.nan] * 3] * 10)
    assert all(u == u_before and s & st.HELD for u, s in dropped)
    after = _run(ctrl, _contact_series(5, seed=1))
    assert after[-1][0] != u_before and not after[-1][1] & st.HELD
    assert all(s & st.ENGAGED for _, s in after)


def test_a_missing_rotation_holds_the_sample_when_gravity_is_compensated() -> None:
    ctrl = Controller(_spec(mass=0.35, engage_threshold_n=None))
    u, status = ctrl.step([0.0, 0.0, 10.0], None)
    assert status & st.HELD and u == [0.0, 0.0, 0.0] and ctrl.hybrid.faults == 1
    bad = _flat(TOOL_DOWN)
    bad[4] = math.nan
    assert ctrl.step([0.0, 0.0, 10.0], bad)[1] & st.HELD
    assert not ctrl.step([0.0, 0.0, 10.0], _flat(TOOL_DOWN))[1] & st.HELD
    # without a tool no rotation is needed
    assert not Controller(_spec(engage_threshold_n=None)).step([0.0, 0.0, 10.0])[1] & st.HELD


# --------------------------------------------------------------------------- limits, status


def test_correction_limits_clamp_and_report_saturation() -> None:
    spec = dataclasses.replace(
        _spec(engage_threshold_n=None),
        limits=Limits(correction_m=0.002, step_m=0.0003),
    )
    ctrl = Controller(spec)
    saturated = 0
    prev = [0.0, 0.0, 0.0]
    for _ in range(40):
        u, status = ctrl.step([0.0, 0.0, 0.0])  # 10 N of error on z: Ki*e = 1e-4 per step
        assert abs(u[2]) <= 0.002 + 1e-15 and abs(u[2] - prev[2]) <= 0.0003 + 1e-15
        saturated += bool(status & st.SATURATED)
        prev = u
    assert u[2] == pytest.approx(0.002)  # reached the clamp
    assert saturated > 0
    # the first step, du = Ki*e = 1e-4, is inside both limits
    fresh = Controller(spec)
    assert not fresh.step([0.0, 0.0, 0.0])[1] & st.SATURATED


def test_trip_and_retreat_bits() -> None:
    spec = _spec(engage_threshold_n=None)
    ctrl = Controller(spec)
    for f in (5.0, 12.0, 19.0):  # a ramp the spike gate (12.5 N) lets through
        ctrl.step([0.0, 0.0, f])
    bits = [ctrl.step([0.0, 0.0, f])[1] for f in (26.0, 30.0)]
    assert not bits[0] & st.TRIPPED and bits[1] & st.TRIPPED and bits[1] & st.RETREATING
    s = spec.safety
    steps = math.ceil(s.backoff_m / (s.backoff_speed_m_s * spec.period_s))
    later = [ctrl.step([0.0, 0.0, 0.0])[1] for _ in range(steps + 3)]
    retreating = [bool(b & st.RETREATING) for b in [bits[1], *later]]
    assert retreating == [True] * steps + [False] * 4
    assert all(b & st.TRIPPED for b in later)


def test_status_bits_are_distinct_single_bits() -> None:
    values = list(st.BITS.values())
    assert len(set(values)) == len(values)
    assert all(v > 0 and v & (v - 1) == 0 for v in values)
    assert st.describe(st.ENGAGED | st.HELD) == "ENGAGED|HELD" and st.describe(0) == "0"


# --------------------------------------------------------------------------- the closed loop's


@pytest.mark.parametrize("base", [PI, FUZZY], ids=["pi", "fuzzy-pi"])
def test_spec_controller_is_the_closed_loops_controller(base: ControllerSpec) -> None:
    """Without a front end, the example spec's controller steps exactly like the runner's E1
    controller (default gains, E1's task) plus the spec's correction limits."""
    from fuzzkit.loop.python_loop import build_controller, load_surface
    from fuzzkit.studies.experiments import experiment

    spec = dataclasses.replace(base, sensor=SensorSpec())
    surface = load_surface("macvicar_whelan") if base.kind == "fuzzy-pi" else None
    ours = hybrid_from_spec(spec, surface)
    gains = {"rate_limit": spec.limits.step_m}
    theirs = build_controller(experiment("E1"), base.kind, gains, surface)
    rng = np.random.default_rng(5)
    for k in range(300):
        f = np.array([rng.normal(0, 1), 0.0, 12.0 * (1 - math.exp(-k / 30)) + rng.normal(0, 1)])
        if k % 37 == 0:
            f[2] = math.nan
        assert ours.step(f).tolist() == theirs.step(f).tolist()


def test_the_spike_gate_keeps_spikes_out_of_the_tare() -> None:
    ctrl = Controller(_spec(tare=6, engage_threshold_n=None))
    level = [0.5, 0.0, -2.0]
    samples = [level, level, [40.5, 0.0, 38.0], level, level, level, level]
    bits = [ctrl.step(s)[1] for s in samples]
    assert bits[2] & st.REJECTED and bits[2] & st.TARING and bits[2] & st.HELD
    assert all(b & st.TARING for b in bits)
    assert ctrl.hybrid.front_end is not None
    assert ctrl.hybrid.front_end.bias.tolist() == level  # the mean of the six good samples
    assert not ctrl.hybrid.front_end.taring


def test_a_spike_first_restarts_the_tare_once_the_gate_confirms_the_level() -> None:
    """A first sample that is a spike is accepted (nothing to compare it with); the real level
    is rejected ``confirm`` times, then confirmed, and the tare starts again from it."""
    spec = _spec(tare=3, engage_threshold_n=None)
    ctrl = Controller(spec)
    level = [0.0, 0.0, 1.0]
    confirm = spec.safety.spike_confirm
    ctrl.step([30.0, 0.0, 30.0])
    for _ in range(confirm):
        assert ctrl.step(level)[1] & st.REJECTED
    for _ in range(3):
        ctrl.step(level)
    assert ctrl.hybrid.front_end is not None
    assert ctrl.hybrid.front_end.bias.tolist() == level
