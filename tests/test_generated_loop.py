"""The generated C controller in the compiled closed loop, its only controller (issue 20
item 4, issue 28 item 1, issue 29 item 5).

Per period the generated double controller's correction must equal the reference
controller's (``fuzzkit.control.reference.Controller``, the exact engine as a fuzzy-PI's
surface) to 1e-9 m, with identical status bits: the reference is driven with the very samples
the loop fed the generated code (the run's recorded ``force``, the consumed sample, NaN where
a fault removed it), on both plants, with spike, NaN, dropout and over-limit faults. The
float build, fed the same samples, stays within the per-period bound its header states.

The equality is sensitive to every safety parameter: ``tests/data/safety_e1.yaml`` makes
each act in one of the fault runs (its step and correction limits bind, an over-limit push
within the spike gate trips after ``trip.samples``, one beyond it after ``spike_gate.confirm``,
the back-off completes), and a test changes each parameter in the generated C (floats by
x1.5 and x0.5, counts by +1 and -1) and checks that the comparison fails.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pytest
from _codegen_util import needs_cc
from _pairwise import verify

from fuzzkit.control import status as st
from fuzzkit.control.reference import Controller
from fuzzkit.control.spec import ControllerSpec
from fuzzkit.control.spec_reader import load_spec
from fuzzkit.errors import ConfigError
from fuzzkit.loop.compiled.generated_controller import (
    GeneratedController,
    load_generated_controller,
    run_controller_spec,
)
from fuzzkit.loop.compiled_loop import run_compiled
from fuzzkit.loop.controller_code import generate, open_generated
from fuzzkit.loop.faults import FAULTS, Faults, fault
from fuzzkit.loop.result import RunResult
from fuzzkit.loop.spec import RunSpec
from fuzzkit.loop.task import with_spec
from fuzzkit.studies.batch import execute, run_spec
from fuzzkit.studies.experiments import experiment

pytestmark = needs_cc

#: Per period, the generated double controller equals the reference to this (m).
TOLERANCE_M = 1e-9
#: Short runs that still reach contact (E1 engages at about 1.9 s) and hold the set point.
DURATION_S = 3.0
FloatArray = npt.NDArray[np.float64]


def _reference(spec: ControllerSpec, r: RunResult) -> tuple[FloatArray, npt.NDArray[np.int64]]:
    """The reference controller over the samples the run's controller consumed."""
    rotation = r.experiment.scenario.rotation.reshape(9).tolist()
    ctl = Controller(spec)
    out = np.empty((len(r.t), 3))
    status = np.empty(len(r.t), dtype=np.int64)
    for k, f in enumerate(r.force):
        u, status[k] = ctl.step(f.tolist(), rotation)
        out[k] = u
    return out, status


@functools.cache
def _run(plant: str, controller: str, fault: str, spec_file: str | None = None) -> RunResult:
    return run_spec(
        RunSpec(
            "E1",
            controller,
            plant,
            seed=3,
            fault=fault,
            duration_s=DURATION_S,
            controller_impl="c",
            controller_spec=spec_file,
        )
    )


def _spec_of(controller: str, spec_file: str | None) -> ControllerSpec:
    if spec_file is not None:
        return load_spec(spec_file)
    return run_controller_spec(experiment("E1"), controller, None)


@pytest.mark.parametrize(
    "plant, controller, fault",
    [
        ("arm6", "fuzzy-pi", "spike"),
        ("arm6", "pi", "dropout"),
        ("planar", "fuzzy-pi", "nan"),
        ("planar", "pi", "spike"),
    ],
)
def test_generated_controller_in_the_loop_equals_the_reference_per_period(
    plant: str, controller: str, fault: str
) -> None:
    r = _run(plant, controller, fault)
    assert r.loop == "compiled"
    assert r.controller_impl.startswith("generated C controller (double) E1_")
    assert r.status is not None
    want, want_status = _reference(_spec_of(controller, None), r)
    assert float(np.max(np.abs(r.u - want))) <= TOLERANCE_M
    np.testing.assert_array_equal(r.status, want_status)
    # the run reached contact, the fault reached the controller, and it held
    assert r.status[-1] & st.ENGAGED and not r.tripped
    assert np.count_nonzero(r.status & st.HELD) > 0 and r.faults > 0
    assert float(np.max(np.abs(r.u))) > 1e-4  # the controller did correct


@pytest.mark.parametrize("plant", ["arm6", "planar"])
def test_a_spec_with_a_front_end_runs_its_generated_controller_in_the_loop(plant: str) -> None:
    # docs/examples/controller.yaml: tare, gravity compensation and a low-pass, all in the
    # generated code (the loop's own front end stays off)
    path = "docs/examples/controller.yaml"
    r = _run(plant, "fuzzy-pi", "spike", path)
    assert r.controller_impl.startswith("generated C controller (double) e1_fuzzy_controller")
    assert r.status is not None
    want, want_status = _reference(load_spec(path), r)
    assert float(np.max(np.abs(r.u - want))) <= TOLERANCE_M
    np.testing.assert_array_equal(r.status, want_status)
    assert r.status[0] & st.TARING and r.status[-1] & st.ENGAGED


def test_the_python_loop_records_the_same_status_as_the_generated_controller() -> None:
    # planar: both loops give the same traces bit for bit (test_compiled_loop), so the
    # reference controller in the Python loop must report the generated C's status bits
    c = _run("planar", "pi", "spike")
    py = run_spec(
        RunSpec(
            "E1", "pi", "planar", seed=3, fault="spike", duration_s=DURATION_S,
            controller_impl="reference",
        )
    )  # fmt: skip
    assert py.loop == "python" and py.controller_impl.startswith("reference controller")
    assert py.status is not None and c.status is not None
    np.testing.assert_array_equal(py.status, c.status)
    assert float(np.max(np.abs(c.u - py.u))) <= TOLERANCE_M


def test_float_build_stays_within_its_header_bound_on_the_loops_samples() -> None:
    r = _run("arm6", "fuzzy-pi", "spike")
    s = _spec_of("fuzzy-pi", None)
    header = generate(s, "c", "float")[f"{s.name}_controller.h"]
    text = " ".join(line.strip(" */") for line in header.splitlines())
    stated = float(re.search(r"grows by at most (\S+) m per period", text).group(1))  # type: ignore[union-attr]
    f32 = r.force.astype(np.float32).astype(np.float64)
    rot = np.tile(r.experiment.scenario.rotation.reshape(9), (len(f32), 1))
    got, _ = open_generated(s, "c", "float").run(f32, rot.astype(np.float32))
    ref = Controller(s)
    want = np.array([ref.step(f.tolist(), rot[0].tolist())[0] for f in f32])
    err = np.max(np.abs(got - want), axis=1)
    assert np.all(err <= stated * np.arange(1, len(err) + 1)), float(np.max(err))
    assert float(np.max(np.abs(want))) > 1e-4


def test_the_row_names_the_generated_controller() -> None:
    row = execute(RunSpec("E1", "pi", "planar", seed=3, duration_s=0.4, controller_impl="c"))
    assert row["controller_impl"].startswith("generated C controller (double) E1_pi_controller")
    assert re.search(r"sha256 [0-9a-f]{16}", row["controller_impl"])


@pytest.mark.parametrize(
    "changes, match",
    [
        ({"controller_impl": "python", "loop": "compiled"}, "compiled loop"),
        ({"controller_impl": "reference", "loop": "compiled"}, "compiled loop"),
        ({"fuzzy_impl": "table"}, "fuzzy-impl"),
        ({"controller_impl": "rust"}, "unknown controller implementation"),
        ({"gains": (("u_max", float("inf")), ("u_min", float("-inf")))}, "correction_m"),
    ],
)
def test_bad_controller_impl_requests_are_refused(changes: dict[str, object], match: str) -> None:
    base = {"experiment": "E1", "plant": "planar", "duration_s": 0.1, "controller_impl": "c"}
    with pytest.raises(ConfigError, match=match):
        run_spec(RunSpec(**{**base, **changes}))  # type: ignore[arg-type]


def test_simulate_cli_runs_the_generated_controller(capsys: pytest.CaptureFixture[str]) -> None:
    import json

    from fuzzkit.cli import main

    argv = ["simulate", "E1", "--plant", "planar", "--controller", "pi"]
    assert main([*argv, "--controller-impl", "c", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["controller_impl"].startswith("generated C controller (double) E1_pi_controller")
    assert data["loop"] == "compiled"
    assert main([*argv, "--json"]) == 0  # the default: the same, in the compiled loop
    data = json.loads(capsys.readouterr().out)
    assert data["controller_impl"].startswith("generated C controller (double) E1_pi_controller")
    assert main([*argv, "--controller-impl", "python", "--json"]) == 0  # the generated Python
    data = json.loads(capsys.readouterr().out)
    assert data["controller_impl"].startswith("generated Python controller E1_pi_controller")
    assert data["loop"] == "python"
    assert main([*argv, "--loop", "python", "--json"]) == 0  # the loop, not the controller
    data = json.loads(capsys.readouterr().out)
    assert data["controller_impl"].startswith("generated C controller (double) E1_pi_controller")
    assert data["loop"] == "python"
    assert main([*argv, "--controller-impl", "reference", "--json"]) == 0  # asked for by name
    data = json.loads(capsys.readouterr().out)
    assert data["controller_impl"].startswith("reference controller, pi")
    assert "generated" not in data["controller_impl"] and data["loop"] == "python"
    assert main([*argv, "--fuzzy-impl", "table"]) == 2  # the reference's surface: asked for


def test_sweep_and_tune_pass_the_choice_on() -> None:
    from fuzzkit.studies.sweep import sweep_specs
    from fuzzkit.studies.tuning.pricing import CaseRunner
    from fuzzkit.studies.tuning.problem import TuningProblem

    specs = sweep_specs(["E1"], ["pi", "fuzzy-pi"], plant="planar", controller_impl="c")
    assert {s.controller_impl for s in specs} == {"c"}
    problem = TuningProblem.build(["E1"], "pi", plant="planar", controller_impl="c")
    r = CaseRunner(problem).run_case(0, {"kp": 3e-5, "ki": 1e-5}, 0.5)
    assert r.controller_impl.startswith("generated C controller (double) E1_pi_controller")
    # --loop python names the loop: the generated C runs there too
    problem = TuningProblem.build(["E1"], "pi", plant="planar", loop="python", controller_impl="c")
    r = CaseRunner(problem).run_case(0, {"kp": 3e-5, "ki": 1e-5}, 0.5)
    assert r.loop == "python"
    assert r.controller_impl.startswith("generated C controller (double) E1_pi_controller")


# --------------------------------------------------------------------------- safety parameters

SAFETY_SPEC = str(Path(__file__).resolve().parent / "data" / "safety_e1.yaml")
#: The fault runs of the safety spec: the kinds of ``FAULTS``; two over-limit pushes on z at
#: 2.5 s (in contact at 10 N) for 0.2 s: 11 N (within the 12.5 N spike gate, 21 N against a
#: 20 N limit: trips after trip.samples) and 16 N (beyond the gate: trips after
#: spike_gate.confirm); and two pushes in free air at 1.0 s for 0.1 s: 15 N (beyond the gate,
#: below the limit: accepted after spike_gate.confirm, engages) and 0.75 N (below the engage
#: threshold, above half of it).
SAFETY_FAULTS: dict[str, Faults] = {
    "spike": fault("spike", 3),
    "nan": fault("nan", 3),
    "dropout": fault("dropout", 3),
    "over-limit within the gate": Faults(offset=(2.5, 0.2, 11.0)),
    "over-limit beyond the gate": Faults(offset=(2.5, 0.2, 16.0)),
    "confirmed step in free air": Faults(offset=(1.0, 0.1, 15.0)),
    "push below the engage threshold": Faults(offset=(1.0, 0.1, 0.75)),
}


def _safety_run(generated: GeneratedController, faults: Faults, plant: str = "arm6") -> RunResult:
    exp = with_spec(experiment("E1"), generated.spec)
    return run_compiled(
        exp, plant, generated_controller=generated, faults=faults, seed=3, duration_s=DURATION_S
    )


def _differences(spec: ControllerSpec, r: RunResult) -> tuple[float, int]:
    """Largest per-period correction difference from the reference (m), periods whose status
    bits differ."""
    want, want_status = _reference(spec, r)
    assert r.status is not None
    return float(np.max(np.abs(r.u - want))), int(np.count_nonzero(r.status != want_status))


@pytest.mark.parametrize("plant", ["arm6", "planar"])
@pytest.mark.parametrize("kind", sorted(SAFETY_FAULTS))
def test_every_safety_parameter_acts_and_the_generated_controller_equals_the_reference(
    kind: str, plant: str
) -> None:
    spec = load_spec(SAFETY_SPEC)
    r = _safety_run(load_generated_controller(spec), SAFETY_FAULTS[kind], plant)
    assert r.loop == "compiled" and r.status is not None
    worst, status_periods = _differences(spec, r)
    assert worst <= TOLERANCE_M and status_periods == 0, (worst, status_periods)
    assert np.count_nonzero(r.status & st.SATURATED) > 0  # the step or correction limit acts
    engaged_at = r.engaged_time_s
    assert engaged_at is not None
    if kind.startswith("over-limit"):
        assert r.tripped and np.count_nonzero(r.status & st.RETREATING) > 0
        # the back-off completes within the run: its distance decides where u ends
        assert not r.status[-1] & st.RETREATING
        return
    assert not r.tripped
    if kind == "confirmed step in free air":
        assert 1.0 < engaged_at < 1.1  # the gate let the level through
    else:
        assert engaged_at > 1.8  # at contact (E1 reaches the hammer at about 1.9 s)
    if kind in FAULTS:
        assert r.faults > 0


#: The safety parameters held as a ``static const double`` in the generated C: spec key ->
#: (the constant's name after ``NAME_controller_``, its value in the spec).
FLOAT_PARAMETERS: dict[str, tuple[str, Callable[[ControllerSpec], float]]] = {
    "limits.correction_m": ("correction", lambda c: c.limits.correction_m),
    "limits.step_m": ("step_limit", lambda c: c.limits.step_m),
    "safety.limit_n": ("limit", lambda c: c.safety.limit_n),
    "safety.spike_gate.threshold_n": ("spike_gate", lambda c: c.safety.spike_gate),
    "safety.backoff.distance_m": ("backoff", lambda c: c.safety.backoff_m),
    "safety.backoff.speed_m_s": (
        "backoff_step",
        lambda c: c.safety.backoff_speed_m_s * c.period_s,
    ),
    "safety.engage.threshold_n": ("engage_threshold", lambda c: c.safety.engage_threshold_n or 0.0),
}
#: The sample counts, written as literals in the generated C: name -> (the text around the
#: count, with ``{}`` for it; the count in the spec).
COUNT_PARAMETERS: dict[str, tuple[str, Callable[[ControllerSpec], int]]] = {
    "safety.spike_gate.confirm": ("< {}u", lambda c: c.safety.spike_confirm),
    "safety.spike_gate.confirm (trip)": (": {}u)", lambda c: c.safety.spike_confirm),
    "safety.trip.samples": ("? {}u :", lambda c: c.safety.trip_samples),
    "safety.engage.samples": ("above < {}u", lambda c: c.safety.engage_samples),
}
FLOAT_FACTORS = (1.5, 0.5)
COUNT_STEPS = (1, -1)
#: Every mutant: (mutation class, the parameter it changes). The class is the change made,
#: ``float x1.5``, ``float x0.5``, ``count +1`` or ``count -1``: one code path of this test
#: builds every mutant of a class, so one per class proves that path in ``make test``.
MUTANTS = [(f"float x{f}", key) for f in FLOAT_FACTORS for key in FLOAT_PARAMETERS] + [
    (f"count {step:+d}", key) for step in COUNT_STEPS for key in COUNT_PARAMETERS
]


def _cover_mutants() -> list[tuple[str, str]]:
    """One mutant per class, each class on a different parameter (the i-th class on its i-th
    parameter), so that ``make test`` changes as many distinct parameters as it has classes."""
    classes = list(dict.fromkeys(cls for cls, _ in MUTANTS))
    return [[m for m in MUTANTS if m[0] == cls][i] for i, cls in enumerate(classes)]


def test_make_test_changes_one_parameter_per_mutant_class() -> None:
    cover = _cover_mutants()
    assert set(cover) <= set(MUTANTS) and len(MUTANTS) == 22
    assert sorted(cls for cls, _ in cover) == sorted({cls for cls, _ in MUTANTS})  # once each
    assert len({key for _, key in cover}) == len(cover)  # on distinct parameters


def _mutant(spec: ControllerSpec, source: str, cls: str, key: str) -> tuple[str, str]:
    """(exact text in the generated C ``source``, its replacement) for the mutant of class
    ``cls`` of parameter ``key``; checks first that the text holds the spec's value."""
    m = f"{spec.name}_controller"
    if cls.startswith("float"):
        const, value_of = FLOAT_PARAMETERS[key]
        value = value_of(spec)
        found = re.search(rf"static const double {m}_{const} = ([^;]+);", source)
        assert found is not None and float(found.group(1)) == value, (key, const)
        factor = float(cls.removeprefix("float x"))
        return found.group(0), f"static const double {m}_{const} = {value * factor!r};"
    pattern, count_of = COUNT_PARAMETERS[key]
    n, step = count_of(spec), int(cls.removeprefix("count "))
    return pattern.format(n), pattern.format(n + step)


@pytest.mark.slow
@pytest.mark.parametrize(
    "cls, key",
    [pytest.param(cls, key, id=f"cover-{cls}-{key}") for cls, key in _cover_mutants()]
    + [pytest.param(cls, key, marks=verify, id=f"full-{cls}-{key}") for cls, key in MUTANTS],
)
def test_changing_any_safety_parameter_of_the_generated_code_fails_the_equality(
    cls: str, key: str
) -> None:
    """Issue 29 item 5: the equality above is not blind to the safety logic. A mutant of the
    generated C (one parameter changed, everything else as generated) runs the same fault
    runs; in at least one a period's correction or status differs from the reference's.
    ``make test`` runs one mutant per class, ``make verify`` all 22."""
    from fuzzkit.codegen.backends.c.run import CompiledController

    spec = load_spec(SAFETY_SPEC)
    files = generate(spec, "c", "double")
    source = f"{spec.name}_controller.c"
    old, new = _mutant(spec, files[source], cls, key)
    assert files[source].count(old) >= 1, (key, old)
    mutated = {**files, source: files[source].replace(old, new)}
    ctl = CompiledController(mutated, f"{spec.name}_controller", "double")
    generated = GeneratedController(
        spec, ctl.step_function, ctl.init_function, len(ctl.state), f"mutant {cls} {key}", ctl
    )
    for faults in SAFETY_FAULTS.values():
        worst, status_periods = _differences(spec, _safety_run(generated, faults))
        if worst > TOLERANCE_M or status_periods:
            return  # caught by this fault run
    pytest.fail(f"the loop equality does not see {cls} of {key} in any fault run")
