"""Adaptive scaling factors (issue 24): the spec's ``adaptation:`` section, the stiffness estimate
and its schedule, the self-tuning gain, in the closed loop on a spring whose stiffness steps
mid-contact (5 -> 500 N/mm), and the generated controllers against the reference there.

The references are independent of the code under test: the true stiffness of the synthetic
data and of the spring bench, the rule table's values at its nodes, the set point.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import re
from pathlib import Path

import jsonschema
import numpy as np
import pytest
from _codegen_util import needs_cc
from _pairwise import verify
from _rerun import rrd_dump

from fuzzkit.control import status as st
from fuzzkit.control.adaptation import ALPHA_TABLE, StiffnessSchedule, alpha
from fuzzkit.control.adaptation_spec import IDENTIFIED_INNER_LOOPS as INNER
from fuzzkit.control.adaptation_spec import NONE, Adaptation, Band, Estimator
from fuzzkit.control.reference import Controller
from fuzzkit.control.spec import ControllerSpec, require_valid
from fuzzkit.control.spec_reader import load_spec, loads_spec
from fuzzkit.control.spec_schema import json_schema
from fuzzkit.control.spec_writer import dump_spec
from fuzzkit.errors import ConfigError, ControllerSpecError
from fuzzkit.loop.controller_code import open_generated
from fuzzkit.studies.spring_loop import SpringBench, run_spring

EXAMPLES = Path(__file__).resolve().parent.parent / "docs" / "examples"
ADAPTIVE = EXAMPLES / "controller_adaptive.yaml"
SELFTUNING = EXAMPLES / "controller_selftuning.yaml"
SETPOINT_N = 12.0


@functools.cache
def adaptive() -> ControllerSpec:
    return load_spec(ADAPTIVE)


def with_delay(spec: ControllerSpec, latency: int) -> ControllerSpec:
    """The spec with the estimator's delay matched to a latency of ``latency`` + ``latency``."""
    ad = spec.adaptation
    est = dataclasses.replace(ad.estimator, delay_periods=1 + 2 * latency)
    return dataclasses.replace(spec, adaptation=dataclasses.replace(ad, estimator=est))


# --------------------------------------------------------------------------------- the spec


def test_examples_read_and_round_trip_through_the_writer() -> None:
    for path in (ADAPTIVE, SELFTUNING):
        spec = load_spec(path)
        assert spec.adaptation.mode in ("stiffness-scheduled", "self-tuning")
        again = loads_spec(dump_spec(spec), "again.yaml")
        assert again.adaptation == spec.adaptation
    spec = adaptive()
    assert [b.scale for b in spec.adaptation.bands] == [0.5, 0.2, 0.05, 0.02]
    assert spec.adaptation.bands[-1].up_to_n_mm is None
    inner = knows_the_loop()
    text = dump_spec(inner)
    assert "inner_loop:" in text and "inner_loop:" not in dump_spec(spec)
    assert loads_spec(text, "inner.yaml").adaptation == inner.adaptation


BASE = ADAPTIVE.read_text(encoding="utf-8").split("adaptation:")[0]


@pytest.mark.parametrize(
    ("section", "line", "match"),
    [
        ("adaptation: gain_schedule\n", 1, "unknown adaptation 'gain_schedule'"),
        (
            "adaptation:\n  mode: self-tuning\n  bands: []\n",
            3,
            "does not apply to mode self-tuning",
        ),
        ("adaptation:\n  mode: stiffness-scheduled\n", 2, "needs at least one band"),
        (
            "adaptation:\n  mode: stiffness-scheduled\n  inverse_n_mm: 15\n  bands: [{scale: 1}]\n",
            3,
            "inverse_n_mm must be a finite number > 0, without bands",
        ),
        (
            "adaptation:\n  mode: stiffness-scheduled\n  inverse_n_mm: -2\n",
            3,
            "inverse_n_mm must be a finite number > 0",
        ),
        (
            "adaptation:\n  mode: stiffness-scheduled\n  bands: [{up_to_n_mm: 10, scale: 1}]\n",
            3,
            "the last band takes every stiffness above",
        ),
        (
            "adaptation:\n  mode: stiffness-scheduled\n  bands: [{scale: 1}, {scale: 0.5}]\n",
            3,
            "only the last band may leave out up_to_n_mm",
        ),
        (
            "adaptation:\n  mode: stiffness-scheduled\n  estimator: {forgetting: 0}\n"
            "  bands: [{scale: 1}]\n",
            3,
            "forgetting must be in (0, 1]",
        ),
        (
            "adaptation:\n  mode: stiffness-scheduled\n  estimator: {range_n_mm: [5, 1]}\n"
            "  bands: [{scale: 1}]\n",
            3,
            "range_n_mm needs 0 < k_min < k_max",
        ),
        (
            "adaptation:\n  mode: stiffness-scheduled\n  estimator: {window_periods: 60, "
            "delay_periods: 10}\n  bands: [{scale: 1}]\n",
            3,
            "at most 64",
        ),
        (
            "adaptation:\n  mode: stiffness-scheduled\n  estimator: {initial_n_mm: 5000}\n"
            "  bands: [{scale: 1}]\n",
            3,
            "initial_n_mm must lie in range_n_mm",
        ),
        (
            "adaptation:\n  mode: self-tuning\n  alpha: {min: 0.8, max: 0.5}\n",
            3,
            "alpha min 0.8 is above max 0.5",
        ),
        (
            "adaptation:\n  mode: stiffness-scheduled\n  estimator:\n    inner_loop: {q: 0.2, a: 1}"
            "\n  bands: [{scale: 1}]\n",
            4,
            "inner_loop.a (a lag's pole) must be in [0, 1)",
        ),
        (
            "adaptation:\n  mode: stiffness-scheduled\n  estimator:\n    inner_loop: {g: 0}"
            "\n  bands: [{scale: 1}]\n",
            4,
            "inner_loop.g must be a finite number > 0",
        ),
        (
            "adaptation:\n  mode: stiffness-scheduled\n  estimator:\n    inner_loop: {p: 0.5}"
            "\n  bands: [{scale: 1}]\n",
            4,
            "p",
        ),
        ("adaptation:\n  mode: stiffness-scheduled\n  bands: [{scale: -2}]\n", 3, "scale must be"),
        ("adaptation:\n  mode: stiffness-scheduled\n  bands: {scale: 1}\n", 3, "got a mapping"),
    ],
)
def test_bad_adaptation_sections_give_located_errors(section: str, line: int, match: str) -> None:
    start = BASE.count("\n") + 1
    with pytest.raises(ControllerSpecError) as info:
        loads_spec(BASE + section, "bad.yaml", EXAMPLES)
    text = str(info.value)
    assert match in text, text
    assert f"bad.yaml:{start + line - 1}:" in text, text


def test_a_pi_needs_the_self_tuning_normalisers() -> None:
    text = SELFTUNING.read_text(encoding="utf-8").replace("  error_n: 12.0", "")
    with pytest.raises(ControllerSpecError, match=r"a pi needs adaptation\.error_n"):
        loads_spec(text, "st.yaml")
    spec = dataclasses.replace(adaptive(), adaptation=Adaptation("stiffness-scheduled"))
    with pytest.raises(ConfigError, match="at least one band"):
        require_valid(spec)


def test_json_schema_accepts_the_examples_and_rejects_a_bad_section() -> None:
    import yaml

    validator = jsonschema.Draft202012Validator(json_schema())
    for path in (ADAPTIVE, SELFTUNING):
        assert list(validator.iter_errors(yaml.safe_load(path.read_text()))) == [], path
    doc = yaml.safe_load(ADAPTIVE.read_text())
    doc["adaptation"]["alpha"] = {"min": 0.5}  # a self-tuning key in a schedule
    assert list(validator.iter_errors(doc))
    doc = yaml.safe_load(ADAPTIVE.read_text())
    doc["adaptation"]["bands"][0]["scale"] = 0
    assert list(validator.iter_errors(doc))


# ------------------------------------------------------------------------- self-tuning alpha


def test_alpha_equals_the_rule_table_at_its_nodes_and_stays_in_range() -> None:
    centres = [-1.0 + i / 3.0 for i in range(7)]
    for i, e in enumerate(centres):
        for j, de in enumerate(centres):
            assert alpha(e, de) == pytest.approx(ALPHA_TABLE[i][j], abs=1e-12)
    grid = np.linspace(-1.0, 1.0, 61)
    values = np.array([[alpha(float(a), float(b)) for b in grid] for a in grid])
    assert values.min() >= 0.0 and values.max() <= 1.0
    # the table is point-symmetric: alpha(-E, -dE) = alpha(E, dE)
    np.testing.assert_allclose(values, values[::-1, ::-1], atol=1e-12)
    assert alpha(0.0, 0.0) == 0.0 and alpha(1.0, 1.0) == 1.0


# ----------------------------------------------------------------------------- the estimator


def schedule(**estimator: float) -> StiffnessSchedule:
    est = Estimator(window_periods=4, min_force_n=0.2, min_step_m=1e-7)
    est = dataclasses.replace(est, **estimator)
    ad = Adaptation("stiffness-scheduled", est, (Band(1.0, 30.0), Band(0.1)), dwell_s=0.0)
    return StiffnessSchedule(ad, 0.004)


def feed(
    sched: StiffnessSchedule,
    k_n_mm: float,
    noise_n: float,
    seed: int,
    n: int = 600,
    swing_n: float = 6.0,
) -> None:
    """A correction that wanders (a sum of sines) so that the force swings by about
    ``swing_n``, a spring of ``k_n_mm`` plus a constant drift of the force (the nominal path
    pressing on) and Gaussian noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 0.004
    amplitude = swing_n / (k_n_mm * 1000.0)
    u = amplitude * (np.sin(2 * math.pi * 1.3 * t) + 0.7 * np.sin(2 * math.pi * 3.1 * t + 1.0))
    drift = 2.0 * t  # N/s
    for k in range(n):
        applied = u[k - 1] if k > 0 else 0.0  # delay 1: u of the last period acts now
        force = k_n_mm * 1000.0 * applied + drift[k] + rng.normal(0.0, noise_n)
        sched.observe(force, float(u[k - 1]) if k > 0 else 0.0)


@pytest.mark.parametrize("k_n_mm", [5.0, 20.0, 100.0, 500.0, 1000.0])
def test_estimate_error_is_bounded_under_noise(k_n_mm: float) -> None:
    errors = []
    for seed in range(10):
        sched = schedule(initial_n_mm=50.0)
        feed(sched, k_n_mm, noise_n=0.1, seed=seed)
        assert sched.updates > 50
        errors.append(abs(sched.k - k_n_mm) / k_n_mm)
    # 0.1 N of noise on swings of 6 N: within 6 % on every seed (measured: at most 3.0 %)
    assert max(errors) < 0.06, errors


def test_estimate_is_frozen_without_excitation() -> None:
    sched = schedule(initial_n_mm=50.0)
    rng = np.random.default_rng(0)
    for _ in range(500):  # the correction holds still; the force is noise only
        sched.observe(12.0 + float(rng.normal(0.0, 0.1)), 1e-3)
    assert sched.updates == 0 and sched.jumps == 0 and sched.k == 50.0
    # missing samples (NaN) never update it either, and never make it NaN
    feed(sched, 100.0, 0.05, seed=1, n=200)
    k_before = sched.k
    for _ in range(20):
        sched.observe(math.nan, 1e-3)
    assert sched.k == k_before and math.isfinite(sched.k)


def test_estimate_is_bounded() -> None:
    sched = schedule(initial_n_mm=50.0, k_max_n_mm=200.0, k_min_n_mm=10.0)
    feed(sched, 1000.0, 0.05, seed=2)
    assert sched.k == 200.0
    sched = schedule(initial_n_mm=50.0, k_max_n_mm=200.0, k_min_n_mm=10.0)
    feed(sched, 1.0, 0.001, seed=3)
    assert sched.k == 10.0


def test_estimate_is_frozen_out_of_contact() -> None:
    """Off the surface the force is noise alone while the corrections keep moving (the
    controller presses towards the lost contact): without the contact gate the noise's
    increments over the corrections' pull the estimate towards k_min."""
    sched = schedule(initial_n_mm=50.0)
    feed(sched, 100.0, 0.05, seed=4, n=300)
    k_before, updates = sched.k, sched.updates
    assert abs(k_before - 100.0) < 10.0 and updates > 50
    rng = np.random.default_rng(5)
    t = np.arange(600) * 0.004
    u = 2e-5 * np.sin(2 * math.pi * 1.3 * t)  # 20 um swings, well above min_step_m
    for k in range(600):
        sched.observe(float(rng.normal(0.0, 0.1)), float(u[k]))  # free air: 0 N + noise
    assert sched.updates == updates and sched.k == k_before


def test_estimate_holds_under_poor_excitation() -> None:
    """In contact, with corrections that wander by less than min_step_m (0.1 um here), the
    force's change is noise (100 N/mm x 0.05 um = 5 mN against 0.1 N): the dead zone holds the
    estimate where a fit would follow the noise."""
    sched = schedule(initial_n_mm=50.0)
    rng = np.random.default_rng(7)
    u = 1e-3 + 2e-8 * rng.standard_normal(2000)
    for k in range(1, 2000):
        force = 12.0 + 1e5 * (float(u[k - 1]) - 1e-3) + float(rng.normal(0.0, 0.1))
        sched.observe(force, float(u[k]))
    assert sched.updates == 0 and sched.jumps == 0 and sched.k == 50.0


def test_forgetting_bounds_the_statistics() -> None:
    """The least squares' statistics are sums weighted by lambda^j: the count S_1 stays below
    1/(1-lambda) and S_uu below max(du^2)/(1-lambda), however long the estimator runs (the
    covariance, 1/S_uu, cannot wind up while excited, and does not move while it is not)."""
    sched = schedule(initial_n_mm=50.0, forgetting=0.9)
    feed(sched, 100.0, 0.1, seed=8, n=3000)
    amplitude_mm = 1.7 * 6.0 / 100.0  # the feed's |u| bound (mm): its window increments double it
    assert 0.0 < sched.s_1 <= 1.0 / (1.0 - 0.9) + 1e-9
    assert sched.s_uu <= (2.0 * amplitude_mm) ** 2 / (1.0 - 0.9)


# --------------------------------------------------------------------- in the closed loop


def run(spec: ControllerSpec, bench: SpringBench) -> tuple[Controller, object]:
    ctl = Controller(spec)
    bands: list[int] = []

    def step(force: list[float]) -> tuple[list[float], int]:
        out = ctl.step(force)
        sched = ctl.hybrid.schedules[2]
        bands.append(-1 if sched is None else sched.band)
        return out

    result = run_spring(bench, step)
    return ctl, (result, np.array(bands))


STEP = SpringBench(stiffness=((0.0, 5.0), (6.0, 500.0)), duration_s=8.0, stop_s=2.5)


@pytest.mark.parametrize("seed", [0, pytest.param(1, marks=verify), pytest.param(2, marks=verify)])
@pytest.mark.parametrize("latency", [0, 1, 2, 3])
def test_a_stiffness_step_during_contact_holds_the_force(latency: int, seed: int) -> None:
    """The 5 -> 500 N/mm step in contact at latency 0:0 to 3:3 (issue 42): no trip, settled
    before and after. Measured: the peak is 12-21 N up to 2:2 and 24.9-25.0 N at 3:3 (the
    limit is 25 N for 2 samples), seeds 0-2."""
    bench = dataclasses.replace(STEP, latency_in=latency, latency_out=latency, seed=seed)
    spec = with_delay(adaptive(), latency)
    ctl, (res, bands) = run(spec, bench)
    assert not np.any(res.status & st.TRIPPED)
    before = res.force_n[int(5.6 / 0.004) : int(6.0 / 0.004)]
    assert abs(before.mean() - SETPOINT_N) < 0.05 * SETPOINT_N  # settled on 5 N/mm
    tail = res.force_n[-125:]  # the last 0.5 s, on 500 N/mm
    assert abs(tail.mean() - SETPOINT_N) < 0.05 * SETPOINT_N, tail.mean()
    # below the limit up to 2:2; at 3:3 one sample reaches 25.0 N, which trips nothing (the
    # trip takes 2): the sudden-stiffening test sees the step 7 periods late there
    peak = max(res.force_n)
    assert peak < adaptive().safety.limit_n + (0.1 if latency == 3 else 0.0), peak
    # the schedule moved from the softest band to a stiffer, lower-gain one: the estimate's
    # band once it is trusted again after the step (it reads low: 260-490 N/mm was measured),
    # else the band of k_max
    sched = ctl.hybrid.schedules[2]
    assert sched is not None
    k = float(ctl.hybrid.stiffness_n_mm[2])
    if sched.trusted:
        assert 100.0 < k < 1.5 * 500.0, k
    else:
        assert bands[-1] == spec.adaptation.safe_band()
        assert res.status[-1] & st.UNTRUSTED
    assert bands[int(5.9 / 0.004)] == 0 and bands[-1] >= 1


def test_fixed_default_gains_trip_on_the_same_step() -> None:
    # what the schedule is for: the same spec without adaptation cannot hold 500 N/mm
    fixed = dataclasses.replace(adaptive(), adaptation=NONE)
    _, (res, _) = run(fixed, STEP)
    assert np.any(res.status & st.TRIPPED)


def test_a_band_change_is_bumpless_in_u() -> None:
    spec = adaptive()
    _, (res, bands) = run(spec, STEP)
    kx = spec.axes[0].kx
    assert kx is not None
    switches = np.flatnonzero(np.diff(bands) != 0) + 1
    assert switches.size >= 2  # from the initial band to the soft one, then to a stiff one
    scales = [b.scale for b in spec.adaptation.bands]
    for k in switches:
        jump = abs(res.u_m[k] - res.u_m[k - 1])
        # one increment at most (|F| <= 1) ...
        assert jump <= kx * max(scales[bands[k]], scales[bands[k - 1]]) + 1e-15
        # ... where a positional law u = s * (...) would jump by |s_new/s_old - 1| * |u|
        positional = abs(scales[bands[k]] / scales[bands[k - 1]] - 1.0) * abs(res.u_m[k - 1])
        assert jump < 0.1 * positional, (k, jump, positional)


def test_spikes_and_missing_samples_do_not_move_the_estimate() -> None:
    bench = dataclasses.replace(STEP, stiffness=((0.0, 100.0),), duration_s=4.0)
    clean, _ = run(adaptive(), bench)
    noisy = dataclasses.replace(bench, spikes=tuple(range(700, 900, 37)), drop=(650, 651, 652))
    hit, (res, _) = run(adaptive(), noisy)
    assert not np.any(res.status & st.TRIPPED)
    assert np.count_nonzero(res.status & st.REJECTED) >= 5
    k_clean = float(clean.hybrid.stiffness_n_mm[2])
    k_hit = float(hit.hybrid.stiffness_n_mm[2])
    assert abs(k_hit - 100.0) < 0.5 * 100.0 and abs(k_clean - 100.0) < 0.5 * 100.0


def test_fixed_specs_report_no_estimate_and_unit_scale() -> None:
    spec = dataclasses.replace(adaptive(), adaptation=NONE)
    ctl = Controller(spec)
    ctl.step([0.0, 0.0, 5.0])
    assert np.isnan(ctl.hybrid.stiffness_n_mm).all()
    assert list(ctl.hybrid.gain_scale) == [1.0, 1.0, 1.0]


# ------------------------------------------------------- generated code on a closed-loop log


def knows_the_loop() -> ControllerSpec:
    """The example's estimator knowing the planar arm's identified inner loop, with bands a
    factor 2 apart (so that the estimate's path shows in the corrections)."""
    base = adaptive()
    q, a, g = INNER["planar"]
    est = dataclasses.replace(
        base.adaptation.estimator, inner_q=q, inner_a=a, inner_g=g, initial_n_mm=20.0
    )
    edges = (4.0, 8.0, 16.0, 32.0, 64.0, 128.0, 256.0, 512.0)
    bands = (*(Band(0.5 * 10.0 / e, e) for e in edges), Band(0.005))
    ad = dataclasses.replace(base.adaptation, estimator=est, bands=bands, dwell_s=0.02)
    return dataclasses.replace(base, name="inner", adaptation=ad)


SPECS = {"example": adaptive, "inner_loop": knows_the_loop}


@functools.cache
def closed_loop_log(which: str = "example") -> tuple[np.ndarray, np.ndarray]:
    """The samples the reference saw on the step bench (with spikes and drop-outs), and the
    bands it scheduled: the generated controllers must reproduce it, switches included."""
    bench = dataclasses.replace(STEP, spikes=(300, 1200), drop=(500, 501, 1100))
    _, (res, bands) = run(SPECS[which](), bench)
    forces = np.zeros((len(res.measured_n), 3))
    forces[:, 2] = res.measured_n
    return forces, bands


@pytest.mark.parametrize("which", list(SPECS))
@pytest.mark.parametrize("impl", ["python", pytest.param("c", marks=needs_cc)])
def test_generated_controller_replays_the_closed_loop_log_equal(impl: str, which: str) -> None:
    forces, bands = closed_loop_log(which)
    # the log makes the schedule switch (twice: the example; once: on the planar model)
    assert np.count_nonzero(np.diff(bands)) >= (2 if which == "example" else 1)
    rotations = np.tile(np.eye(3).ravel(), (len(forces), 1))
    spec = SPECS[which]()
    ref = Controller(spec)
    want = np.array([ref.step(f.tolist())[0] for f in forces])
    ref.reset()
    want_status = np.array([ref.step(f.tolist())[1] for f in forces])
    got, status = open_generated(spec, impl, "double").run(forces, rotations)
    assert float(np.max(np.abs(got - want))) <= 1e-9
    np.testing.assert_array_equal(status, want_status)


@pytest.mark.parametrize("impl", ["python", pytest.param("c", marks=needs_cc)])
def test_generated_controller_freezes_its_estimate_off_contact_as_the_reference(
    impl: str,
) -> None:
    """The step bench's log up to the stiffness step, then the tool lifted off (the force falls
    to 0 N plus noise while the integrator keeps moving the correction): the reference's
    estimate stays where it was once the force is below the contact gate, and the generated
    code follows the reference sample for sample. (On this log the dead zone and the spread
    test already stop every free-air update: the gate itself is covered by
    test_estimate_is_frozen_out_of_contact.)"""
    forces = closed_loop_log("inner_loop")[0][: int(5.9 / 0.004)]  # settled on 5 N/mm
    rng = np.random.default_rng(11)
    off = np.zeros((400, 3))
    # the force falls to 0 over 100 periods (a lift-off the spike gate lets through)
    ramp = np.clip(1.0 - np.arange(400) / 100.0, 0.0, 1.0) * forces[-1, 2]
    off[:, 2] = ramp + rng.normal(0.0, 0.1, 400)
    forces = np.vstack([forces, off])
    rotations = np.tile(np.eye(3).ravel(), (len(forces), 1))
    spec = knows_the_loop()
    ref = Controller(spec)
    want, k_ref = [], []
    for f in forces:
        want.append(ref.step(f.tolist())[0])
        k_ref.append(float(ref.hybrid.stiffness_n_mm[2]))
    k_lift = k_ref[len(forces) - 300]  # once the force is below the contact gate's 1 N
    assert all(k == k_lift for k in k_ref[-300:])
    got, _ = open_generated(spec, impl, "double").run(forces, rotations)
    assert float(np.max(np.abs(got - np.array(want)))) <= 1e-9
    moved = float(np.max(np.abs(np.array(want)[-300:, 2] - want[-301][2])))
    assert moved > 1e-4  # the correction did move while the estimate was frozen


# ------------------------------------------------------------- runs, sweeps, recordings, CLI


@needs_cc
def test_adaptive_controller_runs_and_reports_its_estimate(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import json

    from fuzzkit.cli import main

    rrd = tmp_path / "run.rrd"
    args = ["simulate", "E1", "--controller", "adaptive-fuzzy-pi", "--stiffness", "20"]
    assert main([*args, "--json", "--rrd", str(rrd)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["loop"] == "compiled"
    assert data["controller_impl"].startswith(
        "generated C controller (double) adaptive_fuzzy_pi_controller"
    )
    k = data["stiffness_estimate_n_mm"]["z"]
    assert 1.0 <= k <= 2000.0 and k != 300.0  # it moved off the initial estimate
    assert data["gain_scale_final"]["z"] in (0.5, 0.2, 0.05, 0.02)
    # the recording carries the factor and the estimate over time
    dump = rrd_dump(rrd, "-vvv")
    assert "/adaptation/gain_scale/z" in dump and "/adaptation/stiffness/z" in dump
    # the reference runs it only when asked for, and says so
    assert main([*args, "--json", "--controller-impl", "reference"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["loop"] == "python"
    assert data["controller_impl"].startswith("spec adaptive_fuzzy_pi: reference controller")


def test_sweep_rows_name_the_adaptive_controller_and_its_estimate() -> None:
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import execute

    row = execute(
        RunSpec("E1", controller="adaptive-pi", plant="planar", stiffness_n_per_mm=20.0,
                duration_s=2.0)
    )  # fmt: skip
    assert row["controller"] == "adaptive-pi"
    assert math.isfinite(row["z_stiffness_estimate_n_mm"])
    assert row["z_gain_scale_final"] in (0.5, 0.2, 0.05, 0.02)


def test_the_example_is_the_kits_default_schedule() -> None:
    from fuzzkit.control.adaptation_spec import default_schedule

    assert adaptive().adaptation == default_schedule(0)
    assert default_schedule(2).estimator.delay_periods == 3


@needs_cc
def test_tune_tunes_the_base_gains_under_the_schedule(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from fuzzkit.cli import main
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import run_spec

    out = tmp_path / "gains.yaml"
    args = ["tune", "E1", "--controller", "adaptive-pi", "--plant", "planar", "--stiffness", "20"]
    assert main([*args, "--budget", "10", "--out", str(out), "--workers", "1", "--quiet"]) == 0
    assert "tuned pi on E1" in capsys.readouterr().out and out.is_file()
    # an adaptive run executes its generated controller, and says where it ran
    run = run_spec(RunSpec("E1", "adaptive-pi", "planar", duration_s=0.2))
    assert run.loop == "compiled"
    assert run.controller_impl.startswith("generated C controller (double) adaptive_pi_controller")


@pytest.mark.parametrize("seed", range(2))
def test_self_tuning_settles_where_the_fixed_gains_oscillate(seed: int) -> None:
    # the guarded press at 20 N/mm with 1+1 periods of latency (bench/adaptive_press.py)
    bench = SpringBench(
        stiffness=((0.0, 20.0),), duration_s=6.0, latency_in=1, latency_out=1, seed=seed
    )
    base = adaptive()
    tail = slice(-250, None)  # the last second
    tuning = dataclasses.replace(base, adaptation=Adaptation("self-tuning"))
    res = run_spring(bench, Controller(tuning).step)
    assert not np.any(res.status & st.TRIPPED)
    assert np.all(np.abs(res.force_n[tail] - SETPOINT_N) <= 0.05 * SETPOINT_N)
    fixed = run_spring(bench, Controller(dataclasses.replace(base, adaptation=NONE)).step)
    assert np.max(np.abs(fixed.force_n[tail] - SETPOINT_N)) > 0.05 * SETPOINT_N


# ------------------------------------------------------------------------------- the report


def _summary(tripped: bool, settling: float | None) -> dict[str, object]:
    return {"tripped": tripped, "axes": {"z": {"settling_time_s": settling}}}


@pytest.mark.parametrize(
    ("adaptive_run", "fixed_run", "verdict"),
    [
        ((False, 1.0), (True, None), "better"),
        ((True, None), (False, 5.0), "worse"),
        ((True, None), (True, None), "same"),
        ((False, 2.0), (False, None), "better"),
        ((False, None), (False, 2.0), "worse"),
        ((False, 1.0), (False, 2.0), "better"),
        ((False, 2.0), (False, 1.0), "worse"),
        ((False, 1.95), (False, 2.0), "same"),
    ],
)
def test_adaptive_verdict_per_setting(
    adaptive_run: tuple[bool, float | None], fixed_run: tuple[bool, float | None], verdict: str
) -> None:
    from fuzzkit.report.specs import adaptive_verdict

    assert adaptive_verdict(_summary(*adaptive_run), _summary(*fixed_run), "z") == verdict


def test_report_section_runs_each_adaptive_spec_beside_its_fixed_twin() -> None:
    from fuzzkit.report.specs import adaptive_rows, adaptive_section

    fixed_only = EXAMPLES / "controller_pi.yaml"
    rows = adaptive_rows([ADAPTIVE, fixed_only], ["planar"], ["E2"])
    assert len(rows) == 1  # the fixed spec has no twin to compare
    assert rows[0]["adaptive"]["stiffness_estimate_n_mm"]["z"] is not None
    assert "stiffness_estimate_n_mm" not in rows[0]["fixed"]
    text = "\n".join(adaptive_section(rows))
    assert "## Adaptive against fixed scaling factors" in text
    assert re.search(r"\| (better|worse|same) \|", text)
    assert "of 1 settings" in text


# ------------------------------------------------------------------ safe before the estimate


def test_the_schedule_runs_the_band_of_k_max_until_its_estimate_is_trusted() -> None:
    """Issue 42 item 3: from the start until the estimate is trusted the band is the one of
    k_max (the schedule's gain for the stiffest contact its range admits) and UNTRUSTED is
    set; on a 20 N/mm contact it is trusted within the run and leaves that band."""
    spec = adaptive()
    safe = spec.adaptation.safe_band()
    assert safe == len(spec.adaptation.bands) - 1  # k_max 2000 N/mm: the last band
    bench = dataclasses.replace(STEP, stiffness=((0.0, 20.0),), duration_s=4.0)
    _, (res, bands) = run(spec, bench)
    untrusted = (res.status & st.UNTRUSTED) != 0
    assert untrusted[0] and not untrusted[-1]
    first = int(np.argmin(untrusted))  # the first trusted period
    assert (bands[:first] == safe).all()
    assert bands[-1] == spec.adaptation.band_of(20.0) == 0
    assert not np.any(res.status & (st.TRIPPED | st.OUT_OF_RANGE))
    assert abs(res.force_n[-125:].mean() - SETPOINT_N) < 0.05 * SETPOINT_N


def test_the_nine_band_schedule_is_not_starved_by_its_safe_band() -> None:
    """The safe band of the 9-band schedule (scale 0.005) makes too little excitation for
    the windowed least squares on 5 N/mm; the secant since the first contact period trusts
    the estimate all the same, and the schedule reaches a soft band before the step."""
    spec = knows_the_loop()
    safe = spec.adaptation.safe_band()
    _, (res, bands) = run(spec, STEP)
    before = int(5.9 / 0.004)
    assert not res.status[before] & st.UNTRUSTED
    assert bands[before] < safe - 2, bands[before]
    assert not np.any(res.status[:before] & st.TRIPPED)


def test_a_contact_stiffer_than_k_max_runs_the_most_conservative_band_and_says_so() -> None:
    """A range that ends at 100 N/mm on a 500 N/mm contact: the reading beyond k_max sets
    OUT_OF_RANGE and the schedule drops to its smallest scale (not merely the band of k_max),
    and the force is held without a trip."""
    spec = beyond_k_max()
    ad = spec.adaptation
    assert ad.safe_band() == 1 and ad.floor_band() == 3
    bench = dataclasses.replace(STEP, stiffness=((0.0, 500.0),), duration_s=4.0)
    ctl, (res, bands) = run(spec, bench)
    beyond = (res.status & st.OUT_OF_RANGE) != 0
    assert beyond.any() and beyond[-1]
    assert (bands[beyond] == ad.floor_band()).all()
    assert float(ctl.hybrid.stiffness_n_mm[2]) == 100.0  # pinned at k_max
    assert not np.any(res.status & st.TRIPPED)
    assert abs(res.force_n[-125:].mean() - SETPOINT_N) < 0.05 * SETPOINT_N


def beyond_k_max() -> ControllerSpec:
    """The example with its range ending at 100 N/mm."""
    base = adaptive()
    est = dataclasses.replace(base.adaptation.estimator, k_max_n_mm=100.0, initial_n_mm=100.0)
    return dataclasses.replace(
        base, name="beyond", adaptation=dataclasses.replace(base.adaptation, estimator=est)
    )


@pytest.mark.parametrize("impl", ["python", pytest.param("c", marks=needs_cc)])
@pytest.mark.parametrize("which", ["beyond", "nine_bands"])
def test_generated_code_follows_the_safe_start_as_the_reference(impl: str, which: str) -> None:
    """The generated controllers on the logs of the two safe-start paths (a reading beyond
    k_max; trust by the secant under the 9-band schedule's safe band): the same corrections,
    status bits (UNTRUSTED, OUT_OF_RANGE included) and bands as the reference."""
    spec = beyond_k_max() if which == "beyond" else knows_the_loop()
    k = 500.0 if which == "beyond" else 5.0
    bench = dataclasses.replace(STEP, stiffness=((0.0, k),), duration_s=4.0, seed=1)
    _, (res, _) = run(spec, bench)
    forces = np.zeros((len(res.measured_n), 3))
    forces[:, 2] = res.measured_n
    ref = Controller(spec)
    want, want_status, want_band = [], [], []
    for f in forces:
        u, bits = ref.step(f.tolist())
        want.append(u)
        want_status.append(bits)
        sched = ref.hybrid.schedules[2]
        assert sched is not None
        want_band.append(sched.band)
    assert any(b & (st.OUT_OF_RANGE if which == "beyond" else st.UNTRUSTED) for b in want_status)
    ctl = open_generated(spec, impl, "double")
    got, status, band = [], [], []
    for f in forces:
        u, bits = ctl.step(f.tolist())
        got.append(u)
        status.append(bits)
        band.append(ctl.adaptation()[2][2])
    assert float(np.max(np.abs(np.array(got) - np.array(want)))) <= 1e-9
    assert status == want_status
    assert band == want_band
