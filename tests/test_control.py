"""Tests of the incremental PI, the fuzzy-PI and the hybrid force controller."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fuzzkit.control.controllers import (
    PI,
    FuzzyPI,
    HybridForceController,
    make_axis_controllers,
    saturated_sum_surface,
)
from fuzzkit.errors import ConfigError


def test_pi_matches_closed_form_of_eqs_8_9() -> None:
    kp, ki, sp = 3e-3, 1e-3, 10.0
    measured = [0.0, 2.0, 5.0, 7.5, 9.0, 11.0, 10.2]
    pi = PI(kp, ki)
    errors = [sp - m for m in measured]
    for k, m in enumerate(measured):
        u = pi.step(sp, m)
        # u_k = sum(Kp*de_j + Ki*e_j) = Kp*(e_k - e_0) + Ki*sum(e_0..e_k), with de_0 = 0.
        expected = kp * (errors[k] - errors[0]) + ki * sum(errors[: k + 1])
        assert u == pytest.approx(expected, rel=1e-12)


def test_pi_output_limit_is_anti_windup() -> None:
    pi = PI(kp=0.0, ki=1e-3, u_max=0.002)
    for _ in range(100):
        u = pi.step(10.0, 0.0)  # +10 mm per step wanted, clamped at 2 mm
    assert u == pytest.approx(0.002)
    # No wound-up integral: the first step with a negative error already comes down.
    assert pi.step(10.0, 11.0) < 0.002


def test_rate_limit_caps_each_increment() -> None:
    pi = PI(kp=0.0, ki=1.0, rate_limit=1e-4)
    assert pi.step(10.0, 0.0) == pytest.approx(1e-4)
    assert pi.du == pytest.approx(1e-4)


def test_nan_sample_holds_correction_and_counts_fault() -> None:
    pi = PI(kp=1e-3, ki=1e-3)
    u1 = pi.step(10.0, 4.0)
    assert pi.step(10.0, math.nan) == u1
    assert pi.faults == 1
    # de of the next valid sample is taken against the last valid error (6 N).
    pi.step(10.0, 6.0)
    assert pi.de == pytest.approx(-2.0)


def test_fuzzy_pi_scales_e_by_ki_de_by_kp_output_by_kx() -> None:
    seen: list[tuple[float, float]] = []

    def surface(e: float, de: float) -> float:
        seen.append((e, de))
        return 0.5

    f = FuzzyPI(surface, kp=0.2, ki=0.05, kx=1e-3)
    f.step(10.0, 6.0)  # e = 4, de = 0
    f.step(10.0, 8.0)  # e = 2, de = -2
    assert seen[0] == pytest.approx((0.2, 0.0))
    assert seen[1] == pytest.approx((0.1, -0.4))
    assert f.u == pytest.approx(2 * 0.5e-3)


def test_fuzzy_pi_inputs_clip_and_output_is_bounded_by_kx() -> None:
    f = FuzzyPI(saturated_sum_surface, kp=0.2, ki=0.05, kx=1e-4)
    f.step(1000.0, 0.0)
    assert f.du == pytest.approx(1e-4)
    f2 = FuzzyPI(lambda e, de: e, kp=1.0, ki=1.0, kx=1.0)
    f2.step(50.0, 0.0)
    assert f2.du == pytest.approx(1.0)  # the surface only ever sees [-1, 1]


def test_fuzzy_pi_small_signal_equals_pi() -> None:
    fz = FuzzyPI(saturated_sum_surface, kp=0.2, ki=0.05, kx=2e-4)
    pi = PI(kp=0.2 * 2e-4, ki=0.05 * 2e-4)
    for m in [0.0, 0.5, 1.0, 1.8, 2.0, 1.9]:
        assert fz.step(2.0, m) == pytest.approx(pi.step(2.0, m), rel=1e-12)


def test_surface_answering_nan_never_moves_the_robot() -> None:
    f = FuzzyPI(lambda e, de: math.nan, kp=1.0, ki=1.0, kx=1.0)
    assert f.step(10.0, 0.0) == 0.0
    assert f.faults == 1


def test_reset_clears_state() -> None:
    pi = PI(1e-3, 1e-3)
    pi.step(10.0, 0.0)
    pi.step(10.0, math.nan)
    pi.reset()
    assert (pi.u, pi.faults) == (0.0, 0)


@pytest.mark.parametrize(
    "build, match",
    [
        (lambda: PI(kp=-1.0, ki=1.0), "gains"),
        (lambda: PI(kp=1.0, ki=math.nan), "gains"),
        (lambda: PI(kp=1.0, ki=1.0, u_min=0.1, u_max=0.2), "u_min <= 0 <= u_max"),
        (lambda: PI(kp=1.0, ki=1.0, rate_limit=0.0), "rate_limit"),
        (lambda: FuzzyPI(saturated_sum_surface, kp=1.0, ki=1.0, kx=0.0), "scaling factors"),
        (
            lambda: make_axis_controllers("pid", [True], {"kp": 1.0, "ki": 1.0}),
            "unknown controller",
        ),
        (lambda: make_axis_controllers("fuzzy-pi", [True], {"kp": 1, "ki": 1, "kx": 1}), "surface"),
        (lambda: HybridForceController([None, None], [0.0, 0.0], 0.004), "3 controllers"),
        (
            lambda: HybridForceController([None] * 3, [0.0] * 3, 0.004, force_limit_n=0),
            "force_limit",
        ),
        (
            lambda: HybridForceController([None] * 3, [0.0] * 3, 0.004, engage_samples=0),
            "engage_samples",
        ),
        (
            lambda: HybridForceController([None] * 3, [0.0] * 3, 0.004, spike_gate_n=-1.0),
            "spike_gate_n",
        ),
    ],
)
def test_bad_parameters_are_rejected(build: object, match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        build()  # type: ignore[operator]


def _hybrid(**kw: float) -> HybridForceController:
    axes = [PI(0.0, 1e-4), None, PI(0.0, 1e-4)]
    return HybridForceController(axes, [0.0, 0.0, 10.0], period_s=0.004, **kw)  # type: ignore[arg-type]


def test_selection_matrix_zeroes_motion_only_axes() -> None:
    h = _hybrid()
    out = h.step(np.array([1.0, 5.0, 4.0]))
    assert out[1] == 0.0
    assert out[0] == pytest.approx(-1e-4)  # 0 N wanted, 1 N measured: back away along x
    assert out[2] == pytest.approx(6e-4)  # 10 N wanted, 4 N measured: move into the surface


def test_engagement_waits_for_contact() -> None:
    h = _hybrid(engage_threshold_n=1.0)
    for _ in range(10):
        assert not np.any(h.step(np.array([0.0, 0.0, 0.2])))
    assert not h.engaged
    for _ in range(h.engage_samples - 1):
        h.step(np.array([0.0, 0.0, 2.0]))
        assert not h.engaged
    h.step(np.array([0.0, 0.0, 2.0]))
    assert h.engaged and h.engage_samples == 3


@pytest.mark.parametrize(
    "samples",
    [
        [2.0],  # one sample above the threshold
        [2.0, 2.0],  # two
        [2.0, 2.0, math.nan, 2.0],  # an invalid sample restarts the count
        [2.0, 0.5, 2.0, 2.0],  # so does one below the threshold
        [40.0, 0.0, -40.0, 0.0, 40.0],  # isolated spikes never even pass the gate
    ],
)
def test_engagement_needs_consecutive_valid_samples(samples: list[float]) -> None:
    h = _hybrid(engage_threshold_n=1.0)
    h.step(np.zeros(3))
    for f in samples:
        out = h.step(np.array([0.0, 0.0, f]))
        assert not h.engaged and not np.any(out)


def test_spike_gate_rejects_isolated_spikes_and_follows_a_real_step() -> None:
    h = _hybrid(force_limit_n=30.0)  # gate: half the limit, 15 N
    assert h.spike_gate_n == 15.0
    u0 = h.step(np.array([0.0, 0.0, 10.0])).copy()
    out = h.step(np.array([0.0, 0.0, 50.0]))  # a 40 N spike: held like a NaN
    assert np.array_equal(out, u0) and h.rejected == 1 and h.faults == 1
    u0 = h.step(np.array([0.0, 0.0, 10.0])).copy()  # back to the level: accepted
    # A real step to 28 N: rejected spike_confirm times, then accepted.
    outs = [h.step(np.array([0.0, 0.0, 28.0])).copy() for _ in range(h.spike_confirm + 1)]
    assert all(np.array_equal(o, u0) for o in outs[:-1])
    assert outs[-1][2] < u0[2]  # the controller now sees 28 N > 10 N and backs away
    assert h.rejected == 1 + h.spike_confirm


def test_safety_limit_needs_consecutive_samples_then_latches_and_backs_off() -> None:
    h = _hybrid(force_limit_n=30.0, backoff_m=0.002, backoff_speed_m_s=0.1)
    for f in (10.0, 20.0, 28.0, 34.0, 26.0):  # one sample over the limit: no trip
        h.step(np.array([0.0, 0.0, f]))
    assert not h.tripped
    h.step(np.array([0.0, 0.0, 34.0]))
    out_before = h.step(np.array([0.0, 0.0, 40.0])).copy()
    assert h.tripped
    outs = [h.step(np.array([0.0, 0.0, 35.0])).copy() for _ in range(20)]
    # Moves away from the surface (negative task z) by the back-off distance, then stops.
    assert outs[-1][2] < out_before[2]
    assert outs[-1][2] == pytest.approx(outs[-2][2])
    assert out_before[2] - outs[-1][2] == pytest.approx(0.002, abs=0.0005)
    h.reset()
    assert not h.tripped


@pytest.mark.parametrize(
    "between", [np.array([0.0, 0.0, 0.2]), np.array([0.0, 0.0, math.nan])], ids=["low", "nan"]
)
def test_single_spikes_do_not_engage(between: np.ndarray) -> None:
    h = _hybrid(engage_threshold_n=1.0, engage_samples=3)
    for _ in range(20):  # spike, spike, then a low or missing sample restarts the count
        assert not np.any(h.step(np.array([0.0, 0.0, 40.0])))
        assert not np.any(h.step(np.array([0.0, 0.0, 40.0])))
        h.step(between)
    assert not h.engaged


def test_nan_on_controlled_axis_holds_and_counts_but_not_on_free_axis() -> None:
    h = _hybrid()
    u1 = h.step(np.array([0.0, 0.0, 5.0])).copy()
    assert np.array_equal(h.step(np.array([0.0, 0.0, math.nan])), u1)
    assert np.array_equal(h.step(None), u1)
    assert h.faults == 2
    h.step(np.array([0.0, math.nan, 5.0]))  # y is not force-controlled: not a fault
    assert h.faults == 2


def test_make_axis_controllers_follows_selection() -> None:
    axes = make_axis_controllers("pi", [True, False, True], {"kp": 1e-5, "ki": 1e-5})
    assert axes[1] is None and isinstance(axes[0], PI) and isinstance(axes[2], PI)


def test_the_exact_surface_is_zero_at_the_origin_and_odd() -> None:
    from fuzzkit.control.loop_rulebase import exact_surface
    from fuzzkit.formats.registry import load

    exact = exact_surface(load("macvicar_whelan"))
    assert exact(0.0, 0.0) == pytest.approx(0.0, abs=1e-12)
    assert exact(0.3, 0.1) == pytest.approx(-exact(-0.3, -0.1), abs=1e-9)  # odd symmetry


def test_any_object_with_step_and_reset_is_an_axis_controller() -> None:
    """A generated module's controller class plugs in without an adapter."""

    class Bang:
        def __init__(self) -> None:
            self.u = 0.0

        def step(self, setpoint: float, measured: float) -> float:
            self.u += 1e-4 if setpoint > measured else -1e-4
            return self.u

        def reset(self) -> None:
            self.u = 0.0

    h = HybridForceController([None, None, Bang()], [0.0, 0.0, 10.0], period_s=0.004)
    assert h.step(np.array([0.0, 0.0, 5.0]))[2] == pytest.approx(1e-4)
    assert h.step(np.array([0.0, 0.0, math.nan]))[2] == pytest.approx(1e-4)  # NaN never reaches it


def test_codegen_lookup_table_plugs_in_as_a_surface() -> None:
    from fuzzkit.codegen import table_search
    from fuzzkit.control.controllers import engine_surface, lookup_table_surface
    from fuzzkit.formats.registry import load
    from fuzzkit.fuzzy.inference import Engine

    rb = load("macvicar_whelan")
    table = table_search.build_table(rb, [41, 41], check_factor=4)
    surf, exact = lookup_table_surface(table), engine_surface(Engine(rb), "e", "de", "du")
    for e, de in [(0.0, 0.0), (0.3, -0.2), (-0.9, 0.55), (1.0, 1.0)]:
        assert surf(e, de) == pytest.approx(exact(e, de), abs=0.02)
    f = FuzzyPI(surf, kp=0.2, ki=0.05, kx=2e-4)
    assert f.step(10.0, 5.0) > 0.0


def test_a_real_over_force_faster_than_the_gate_still_trips() -> None:
    h = _hybrid(force_limit_n=30.0)
    h.step(np.array([0.0, 0.0, 10.0]))
    for _ in range(h.spike_confirm):
        assert not h.tripped
        h.step(np.array([0.0, 0.0, 200.0]))  # every sample jumps past the gate
    assert h.tripped
