"""The compiled closed loops (fuzzkit.studies.compiled) against the Python reference runner.

Planar plant: the compiled period makes the same Chipmunk calls in the same order and repeats
the Python plant's, sensor's and controller's arithmetic operation for operation in double
precision, so the traces come out bit for bit equal on this machine. The test allows
``PLANAR_FORCE_TOL = 1e-9 N`` (a libm or compiler that rounds a sine differently in the last
place), seven orders below the sensor noise; messages (torque limits, unreachable targets)
must agree exactly.

arm6 plant: the compiled period repeats the Python plant's and controller's arithmetic operation
for operation; what differs is the IK's 6x6 linear solve (LU here, LAPACK in numpy) and the
summation order of small matrix products, a few units in the last place of joint angles. The
force loop is stable, so such rounding does not grow: observed differences are about 1e-11 N.
``FORCE_TOL = 1e-6 N`` leaves five orders of magnitude for that, and is still 1e-5 of the sensor
noise (0.1 N): any modelling difference (a missing term, a sample one period late, another
noise draw) moves the trace by 1e-3 N or more and fails the test. Sample timing must agree
exactly: where the measured force is NaN (no sample, injected fault), engagement and trip times.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from fuzzkit.control.controllers import lookup_table_surface
from fuzzkit.errors import ConfigError
from fuzzkit.studies.compiled.loop import load_table, run_compiled
from fuzzkit.studies.compiled.table import table2, table_arrays
from fuzzkit.studies.experiments import experiment, with_stiffness
from fuzzkit.studies.faults import FAULTS, FaultInjector, Faults, fault, fault_schedule
from fuzzkit.studies.runner import RunResult, run

FORCE_TOL = 1e-6  # N (arm6)
PLANAR_FORCE_TOL = 1e-9  # N
U_TOL = 1e-9  # m: corrections are ~1e-3 m, rounding ~1e-16 m

CONTROLLERS = ("pi", "fuzzy-pi")
PLANTS = ("arm6", "planar")


def _both(
    name: str, controller: str, plant: str = "arm6", **kw: object
) -> tuple[RunResult, RunResult]:
    exp = kw.pop("exp", None) or experiment(name)
    table = load_table() if controller == "fuzzy-pi" else None
    surface = lookup_table_surface(table) if table is not None else None
    py = run(exp, plant, controller, surface=surface, **kw)  # type: ignore[arg-type]
    co = run_compiled(exp, plant, controller, table=table, **kw)  # type: ignore[arg-type]
    return py, co


def _assert_same(py: RunResult, co: RunResult) -> None:
    assert co.loop == "compiled" and py.loop == "python"
    assert co.plant == py.plant
    force_tol = PLANAR_FORCE_TOL if co.plant == "planar" else FORCE_TOL
    if co.plant == "planar":
        assert co.messages == py.messages
    assert py.t.shape == co.t.shape
    np.testing.assert_allclose(co.t, py.t, rtol=0, atol=1e-12)
    # same samples missing (sensor rate, faults, latency), exactly
    np.testing.assert_array_equal(np.isnan(co.force), np.isnan(py.force))
    np.testing.assert_allclose(co.force, py.force, rtol=0, atol=force_tol, equal_nan=True)
    np.testing.assert_array_equal(np.isnan(co.force_sensor), np.isnan(py.force_sensor))
    np.testing.assert_allclose(
        co.force_sensor, py.force_sensor, rtol=0, atol=force_tol, equal_nan=True
    )
    np.testing.assert_allclose(co.force_true, py.force_true, rtol=0, atol=force_tol)
    np.testing.assert_allclose(co.force_normal, py.force_normal, rtol=0, atol=force_tol)
    np.testing.assert_allclose(co.u, py.u, rtol=0, atol=U_TOL)
    np.testing.assert_allclose(co.du, py.du, rtol=0, atol=U_TOL)
    np.testing.assert_allclose(co.e, py.e, rtol=0, atol=force_tol)
    np.testing.assert_allclose(co.de, py.de, rtol=0, atol=force_tol)
    np.testing.assert_allclose(co.tool_position, py.tool_position, rtol=0, atol=1e-9)
    np.testing.assert_allclose(co.nominal_position, py.nominal_position, rtol=0, atol=1e-12)
    np.testing.assert_allclose(co.target_position, py.target_position, rtol=0, atol=1e-9)
    np.testing.assert_allclose(co.joint_angles, py.joint_angles, rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.array(co.arm_points), np.array(py.arm_points), atol=1e-9)
    np.testing.assert_array_equal(co.in_contact, py.in_contact)
    np.testing.assert_array_equal(co.moving, py.moving)
    assert [len(p) for p in co.contact_points] == [len(p) for p in py.contact_points]
    assert co.faults == py.faults
    assert (co.seed, co.latency_periods, co.fault, co.fault_seed) == (
        py.seed,
        py.latency_periods,
        py.fault,
        py.fault_seed,
    )
    assert co.tripped == py.tripped
    assert co.trip_time_s == pytest.approx(py.trip_time_s)
    assert co.engaged_time_s == pytest.approx(py.engaged_time_s)


@pytest.mark.slow
@pytest.mark.parametrize("plant", PLANTS)
@pytest.mark.parametrize("controller", CONTROLLERS)
@pytest.mark.parametrize("name", ["E1", "E2", "E3"])
def test_compiled_loop_equals_python_loop(name: str, controller: str, plant: str) -> None:
    py, co = _both(name, controller, plant, seed=1)
    assert np.any(co.in_contact)  # a run that never touches would prove little
    _assert_same(py, co)


@pytest.mark.slow
@pytest.mark.parametrize("plant", PLANTS)
@pytest.mark.parametrize("controller", CONTROLLERS)
@pytest.mark.parametrize("kind", sorted(set(FAULTS) - {"none"}))
def test_compiled_loop_equals_python_loop_under_faults(
    controller: str, kind: str, plant: str
) -> None:
    # every fault kind at the safety matrix's strength (spikes of 40 N > E2's gate of 30 N)
    py, co = _both("E2", controller, plant, seed=2, faults=fault(kind, 3), duration_s=2.5)
    _assert_same(py, co)
    assert co.fault == kind
    if kind in ("nan", "dropout", "spike"):
        assert co.faults > 0  # NaN samples held, spikes rejected by the gate
    if kind == "delay":
        assert co.latency_periods == (1 + 2, 1)  # the scenario's (1, 1) plus 2 sensor periods


def test_fault_schedule_draws_what_the_injector_draws() -> None:
    faults = Faults(spike_probability=0.3, spike_n=5.0, nan_probability=0.2, seed=7)
    spike, nan = fault_schedule(faults, 400)
    inject = FaultInjector(faults)
    for k in range(400):
        got = inject(0.0, np.zeros(3))
        if nan[k]:
            assert np.all(np.isnan(got))
        else:
            np.testing.assert_array_equal(got, spike[k] * 5.0 * np.array([1.0, 0.0, 1.0]))
    assert 0 < np.count_nonzero(spike) < 400 and 0 < np.count_nonzero(nan) < 400


@pytest.mark.slow
@pytest.mark.parametrize("plant", PLANTS)
@pytest.mark.parametrize("latency", [(1, 0), (0, 3), (2, 2)])
def test_compiled_loop_equals_python_loop_with_latency(
    latency: tuple[int, int], plant: str
) -> None:
    py, co = _both("E1", "fuzzy-pi", plant, latency=latency, duration_s=3.0)
    _assert_same(py, co)


@pytest.mark.slow
@pytest.mark.parametrize("plant", PLANTS)
def test_compiled_loop_equals_python_loop_through_a_safety_trip(plant: str) -> None:
    # 1000 N/mm with the default gains is unstable: the force limit trips and the arm backs off
    exp = with_stiffness(experiment("E2"), 1.0e6)
    py, co = _both("E2", "pi", plant, exp=exp, duration_s=3.0)
    assert py.tripped
    _assert_same(py, co)


def test_table_kernel_reproduces_the_lookup_table_arithmetic() -> None:
    table = load_table()
    ta = table_arrays(table)
    bp0, bp1, tab, splits = ta.bp0, ta.bp1, ta.values, ta.splits
    rng = np.random.default_rng(0)
    pts = np.concatenate(
        [
            rng.uniform(-1.3, 1.3, (2000, 2)),  # inside and clamped
            np.stack(np.meshgrid(bp0[::7], bp1[::5]), axis=-1).reshape(-1, 2),  # on knots
        ]
    )
    ref = table.interpolate([pts[:, 0], pts[:, 1]])[0]
    got = np.array([table2(bp0, bp1, tab, splits, float(a), float(b)) for a, b in pts])
    np.testing.assert_array_equal(got, ref)  # same operations, same order: bit for bit
    assert np.isnan(table2(bp0, bp1, tab, splits, float("nan"), 0.0))


def test_compiled_loop_rejects_what_it_does_not_model() -> None:
    exp = experiment("E1")
    with pytest.raises(ConfigError, match="compiled loop runs on arm6, planar"):
        run_compiled(exp, "moon", "pi")
    with pytest.raises(ConfigError, match="needs a lookup table"):
        run_compiled(exp, "arm6", "fuzzy-pi")
    with pytest.raises(ConfigError, match="latency"):
        run_compiled(exp, "arm6", "pi", latency=(-1, 0))


def test_e3_on_arm6_falls_back_to_the_python_loop_and_says_so() -> None:
    from fuzzkit.studies.batch import RunSpec, run_spec

    result = run_spec(RunSpec("E3", "pi", "arm6", duration_s=0.05))
    assert result.loop.startswith("python") and "HeightField" in result.loop


@pytest.mark.slow
def test_planar_compiled_loop_reports_torque_limits_as_the_python_loop() -> None:
    # 1000 N/mm: the servos saturate pressing in, every period's messages are counted
    exp = with_stiffness(experiment("E2"), 1.0e9)
    py, co = _both("E2", "pi", "planar", exp=exp, duration_s=1.5)
    assert any("torque limit" in m for m in py.messages)
    _assert_same(py, co)


def test_planar_compiled_loop_raises_the_python_loops_error_on_a_non_finite_state() -> None:
    from fuzzkit.errors import SimulationError
    from fuzzkit.planar_sim import PlanarArmPlant
    from fuzzkit.planar_sim.arm import ArmParameters

    exp = experiment("E2")
    broken = ArmParameters(gravity=float("inf"))
    with pytest.raises(SimulationError, match=r"non-finite at t=0\.004 s") as py:
        run(exp, PlanarArmPlant(broken), "pi", duration_s=0.5)
    with pytest.raises(SimulationError, match=r"non-finite at t=0\.004 s") as co:
        run_compiled(exp, PlanarArmPlant(broken), "pi", duration_s=0.5)
    assert str(co.value) == str(py.value)


def test_planar_runs_compiled_by_default_and_falls_back_where_it_cannot(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from fuzzkit.planar_sim import kernel
    from fuzzkit.studies.batch import RunSpec, run_spec

    spec = RunSpec("E2", "pi", "planar", duration_s=0.2)
    assert run_spec(spec).loop == "compiled"
    # a machine whose calling convention the Chipmunk calls are not lowered for
    monkeypatch.setattr(kernel, "calls_supported", lambda: False)
    result = run_spec(spec)
    assert result.loop.startswith("python (fallback:") and "x86-64 and AArch64" in result.loop
    assert result.plant == "planar" and len(result.t) == 50


@pytest.mark.slow
def test_compiled_table_loop_equals_a_loop_running_the_generated_c() -> None:
    """The compiled fuzzy-PI's arithmetic is the generated C's: a Python loop that calls the
    compiled generated C (ctypes) for every sample gives the compiled loop's force traces."""
    from fuzzkit.codegen.toolchain import find_compiler

    if find_compiler() is None:
        pytest.skip("no C compiler found")
    from fuzzkit.studies.batch import RunSpec, run_spec

    spec = RunSpec("E2", "fuzzy-pi", "arm6", seed=4, duration_s=4.0)
    co = run_spec(spec)
    py = run_spec(RunSpec("E2", "fuzzy-pi", "arm6", seed=4, duration_s=4.0, loop="python",
                          fuzzy_impl="c"))  # fmt: skip
    assert "generated C" in py.controller_impl and "lookup table" in co.controller_impl
    _assert_same(py, co)


def test_fuzzy_implementation_must_fit_the_loop() -> None:
    from fuzzkit.studies.batch import RunSpec, run_spec

    with pytest.raises(ConfigError, match="compiled loop runs the fuzzy-PI as the lookup table"):
        run_spec(RunSpec("E1", "fuzzy-pi", "arm6", fuzzy_impl="c", duration_s=0.1))
    with pytest.raises(ConfigError, match="unknown fuzzy implementation"):
        run_spec(RunSpec("E1", "fuzzy-pi", "arm6", fuzzy_impl="fast", duration_s=0.1))


def test_table_cache_builds_once_and_rebuilds_a_damaged_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from fuzzkit.formats.registry import load
    from fuzzkit.studies.compiled.table import cached_table

    monkeypatch.setenv("FUZZKIT_CACHE_DIR", str(tmp_path))
    rb = load("macvicar_whelan")
    table = load_table()
    builds: list[int] = []

    def build() -> object:
        builds.append(1)
        return table

    first = cached_table(rb, 1e-3, build)
    second = cached_table(rb, 1e-3, build)
    assert len(builds) == 1
    for a, b in (
        (first.values, second.values),
        (first.bp0, second.bp0),
        (first.splits, second.splits),
    ):
        np.testing.assert_array_equal(a, b)
    assert second.label == first.label
    (cached,) = tmp_path.glob("*.npz")
    cached.write_bytes(b"not a table")
    third = cached_table(rb, 1e-3, build)
    assert len(builds) == 2
    np.testing.assert_array_equal(third.values, first.values)
    cached_table(rb, 2e-3, build)  # another tolerance is another table
    assert len(builds) == 3
