"""The compiled closed loops (fuzzkit.loop.compiled) against the Python reference runner.

The compiled loop's controller is the run's spec generated as C (double, the exact surface);
the Python loop's is the reference controller on the exact engine. The two surfaces agree to
rounding (the generated header's bound, ~1e-17 m per period at kx = 2e-4), so the corrections
agree to ``U_TOL``.

Planar plant: the compiled period makes the same Chipmunk calls in the same order and repeats
the Python plant's and sensor's arithmetic operation for operation in double precision. The
test allows
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

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from fuzzkit.errors import ConfigError
from fuzzkit.loop.compiled.table import load_table, table2, table_arrays
from fuzzkit.loop.compiled_loop import run_compiled
from fuzzkit.loop.faults import FAULTS, FaultInjector, Faults, fault, fault_schedule
from fuzzkit.loop.python_loop import load_surface, run
from fuzzkit.loop.result import RunResult
from fuzzkit.plants.arm6 import Arm6Parameters, Arm6Plant
from fuzzkit.plants.arm6_heightfield import height_field_contact, pack_height_field
from fuzzkit.plants.arm6_period import pack
from fuzzkit.plants.contract import ContactPlant, UnsupportedPlant
from fuzzkit.plants.environment3d import HeightField
from fuzzkit.studies.e3_arm6 import e3_arm6_experiment, make_e3_arm6_plant
from fuzzkit.studies.experiments import experiment, with_stiffness

FORCE_TOL = 1e-6  # N (arm6)
PLANAR_FORCE_TOL = 1e-9  # N
U_TOL = 1e-9  # m: corrections are ~1e-3 m, rounding ~1e-16 m

CONTROLLERS = ("pi", "fuzzy-pi")
PLANTS = ("arm6", "planar")


def _both(
    name: str,
    controller: str,
    plant: str | Callable[[], ContactPlant] = "arm6",
    **kw: object,
) -> tuple[RunResult, RunResult]:
    """The Python and the compiled loop on the same run; ``plant``: a plant name (arm6: the
    shared plant of both loops; planar: a fresh one each), or a factory building a fresh plant
    for each loop."""
    exp = kw.pop("exp", None) or experiment(name)
    py_plant = plant if isinstance(plant, str) else plant()
    co_plant = plant if isinstance(plant, str) else plant()
    surface = load_surface() if controller == "fuzzy-pi" else None  # the exact engine
    py = run(exp, py_plant, controller, surface=surface, **kw)  # type: ignore[arg-type]
    co = run_compiled(exp, co_plant, controller, **kw)  # type: ignore[arg-type]
    return py, co


def _assert_same(py: RunResult, co: RunResult, reference_loop: str = "python") -> None:
    """``co`` (a compiled-loop run) repeats ``py`` (a run of ``reference_loop``)."""
    assert co.loop == "compiled" and py.loop == reference_loop
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


@pytest.mark.slow
@pytest.mark.parametrize("controller", CONTROLLERS)
def test_compiled_loop_equals_python_loop_on_e3_arm6(controller: str) -> None:
    # the paper's E3: a rough 3-D height-field floor (30 N on z) and a side wall (6 N on x)
    py, co = _both("E3", controller, plant=make_e3_arm6_plant, exp=e3_arm6_experiment(), seed=1)
    _assert_same(py, co)
    touching = co.in_contact & ~np.isnan(co.force[:, 0])
    assert np.count_nonzero(touching) > 1000  # the whole slide is in contact
    # both surfaces push: floor on z, wall on x
    assert np.max(np.abs(co.force_normal[:, 2])) > 20.0
    assert np.max(np.abs(co.force_normal[:, 0])) > 3.0


@pytest.mark.slow
@pytest.mark.parametrize("kind", sorted(set(FAULTS) - {"none"}))
def test_compiled_loop_equals_python_loop_on_e3_arm6_under_faults(kind: str) -> None:
    py, co = _both(
        "E3",
        "fuzzy-pi",
        plant=make_e3_arm6_plant,
        exp=e3_arm6_experiment(),
        seed=5,
        faults=fault(kind, 5),
        duration_s=3.0,
    )
    _assert_same(py, co)
    assert co.fault == kind
    if kind in ("nan", "dropout", "spike"):
        assert co.faults > 0


def test_height_field_contact_is_the_python_contact() -> None:
    """The compiled height field touches exactly where ``HeightField.contact`` does, with
    the same depth, normal and point (same operations in the same order: bit for bit)."""
    field = HeightField.rough((0.40, 0.56), (-0.13, 0.13), -0.299, 0.0002, seed=3)
    field = HeightField(field.x0, field.y0, field.dx, field.dy, field.heights, z0=0.25)
    row, heights = pack_height_field(field)
    op = np.zeros(12)
    op[: len(row)] = row
    radius = 0.01
    rng = np.random.default_rng(0)
    nx, ny = len(field.heights), len(field.heights[0])
    corners = [
        (field.x0 + i * field.dx, field.y0 + j * field.dy) for i in (0, nx - 1) for j in (0, ny - 1)
    ]
    xy = np.concatenate([rng.uniform((0.39, -0.14), (0.57, 0.14), (3000, 2)), corners])
    z = rng.uniform(-0.05, -0.03, len(xy))  # around the surface (0.25 - 0.299 + radius)
    nrm, pt = np.empty(3), np.empty(3)
    touching = 0
    for (x, y), zc in zip(xy, z, strict=True):
        c = np.array([x, y, zc])
        ref = field.contact((float(x), float(y), float(zc)), radius)
        depth = height_field_contact(op, heights, c, radius, nrm, pt)
        if ref is None:
            assert depth <= 0.0
            continue
        touching += 1
        assert depth == ref[0]
        assert tuple(nrm) == ref[1] and tuple(pt) == ref[2]
    assert 500 < touching < len(xy) - 500  # both touching and clear points were checked


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
    with pytest.raises(
        ConfigError, match="compiled loop runs on arm6, mujoco, mujoco-elastic, planar"
    ):
        run_compiled(exp, "moon", "pi")
    with pytest.raises(ConfigError, match=r"unknown controller 'pid'"):
        run_compiled(exp, "arm6", "pid")
    with pytest.raises(ConfigError, match="latency"):
        run_compiled(exp, "arm6", "pi", latency=(-1, 0))


def test_e3_on_arm6_runs_compiled() -> None:
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import run_spec

    result = run_spec(RunSpec("E3", "pi", "arm6", duration_s=0.05))
    assert result.loop == "compiled"


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
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.planar_sim import arm_period
    from fuzzkit.studies.batch import run_spec

    spec = RunSpec("E2", "pi", "planar", duration_s=0.2)
    assert run_spec(spec).loop == "compiled"
    # a machine whose calling convention the Chipmunk calls are not lowered for
    monkeypatch.setattr(arm_period, "calls_supported", lambda: False)
    result = run_spec(spec)
    assert result.loop.startswith("python (fallback:") and "x86-64 and AArch64" in result.loop
    assert result.plant == "planar" and len(result.t) == 50


def test_what_the_kernel_does_not_model_is_refused_by_name() -> None:
    plant = Arm6Plant(Arm6Parameters(strict=True))
    plant.reset(experiment("E1").scenario)
    with pytest.raises(UnsupportedPlant, match="strict mode"):
        pack(plant)


def _needs_a_c_compiler() -> None:
    from fuzzkit.codegen.toolchain import find_compiler

    if find_compiler() is None:
        pytest.skip("no C compiler found")


@pytest.mark.slow
def test_compiled_loop_calls_the_controller_it_is_given() -> None:
    """Two rule bases' generated controllers through the same compiled kernel in one process:
    each run follows its own rule base (the kernel reads the function's address at every call,
    it is not frozen into the cached machine code)."""
    _needs_a_c_compiler()
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import run_spec

    runs = {}
    for rb in ("macvicar_whelan", "paper_table1"):
        c = run_spec(RunSpec("E2", "fuzzy-pi", "arm6", rulebase=rb, duration_s=2.5))
        assert c.loop == "compiled" and "generated C controller" in c.controller_impl
        runs[rb] = c
    diff = np.nanmax(np.abs(runs["macvicar_whelan"].force - runs["paper_table1"].force))
    assert diff > 0.1  # N: the two rule bases really drive the arm differently


def test_simulate_json_names_the_generated_controller(capsys: pytest.CaptureFixture[str]) -> None:
    _needs_a_c_compiler()
    import json

    from fuzzkit.cli import main

    argv = ["simulate", "E1", "--plant", "arm6", "--controller", "fuzzy-pi", "--json"]
    assert main(argv) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["loop"] == "compiled"
    assert data["controller_impl"].startswith("generated C controller (double) E1_fuzzy_pi")
    assert data["controller_impl"].endswith("(compiled loop)")


def test_without_a_compiler_the_generated_python_runs_and_says_why(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from fuzzkit.loop.compiled import generated_controller
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import run_spec

    monkeypatch.setenv("CC", "/nonexistent/cc")
    monkeypatch.setattr(generated_controller, "_LOADED", {})  # nothing compiled in this process
    monkeypatch.setenv("FUZZKIT_CACHE_DIR", "/nonexistent/cache")  # nor on disk
    spec = RunSpec("E1", "pi", "arm6", duration_s=0.2)
    result = run_spec(spec)
    assert result.loop.startswith("python (fallback: the compiled loop runs the generated C")
    assert "no C compiler found" in result.loop
    assert result.controller_impl.startswith("generated Python controller E1_pi_controller")
    assert len(result.t) == 50
    for explicit in (
        RunSpec("E1", "pi", "arm6", loop="compiled"),
        RunSpec("E1", controller_impl="c"),
    ):
        with pytest.raises(ConfigError, match="no C compiler found"):
            run_spec(explicit)


def test_fuzzy_implementation_is_the_python_loops() -> None:
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import run_spec

    reference = RunSpec("E1", fuzzy_impl="table", controller_impl="reference")
    assert reference.resolved_loop() == "python"
    assert RunSpec("E1", controller_impl="python").resolved_loop() == "python"
    assert RunSpec("E1").resolved_loop() == "compiled"
    with pytest.raises(ConfigError, match="unknown fuzzy implementation"):
        run_spec(RunSpec("E1", "fuzzy-pi", "arm6", fuzzy_impl="fast", duration_s=0.1))
    for impl in ("auto", "c", "python"):  # the reference's surface asks for the reference
        with pytest.raises(ConfigError, match="add --controller-impl reference"):
            run_spec(RunSpec("E1", "fuzzy-pi", "arm6", fuzzy_impl="table", controller_impl=impl))


def test_table_cache_builds_once_and_rebuilds_a_damaged_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from fuzzkit.formats.registry import load
    from fuzzkit.loop.compiled.table import cached_table

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
