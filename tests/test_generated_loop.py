"""The whole generated C controller in the compiled closed loop (``--controller-impl c``,
issue 20 item 4).

Per period the generated double controller's correction must equal the reference
controller's (``fuzzkit.control.reference.Controller``, the exact engine as a fuzzy-PI's
surface) to 1e-9 m, with identical status bits: the reference is driven with the very samples
the loop fed the generated code (the run's recorded ``force``, the consumed sample, NaN where
a fault removed it), on both plants, with fault injection. The float build, fed the same
samples, stays within the per-period bound its header states.
"""

from __future__ import annotations

import functools
import re

import numpy as np
import numpy.typing as npt
import pytest
from _codegen_util import needs_cc

from fuzzkit.control import status as st
from fuzzkit.control.reference import Controller
from fuzzkit.control.spec import ControllerSpec
from fuzzkit.control.spec_reader import load_spec
from fuzzkit.errors import ConfigError
from fuzzkit.studies.batch import RunSpec, execute, run_spec
from fuzzkit.studies.compiled.generated_controller import run_controller_spec
from fuzzkit.studies.controller_code import generate, open_generated
from fuzzkit.studies.experiments import experiment
from fuzzkit.studies.runner import RunResult

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


def test_pi_generated_controller_follows_the_loops_own_controller() -> None:
    # two implementations of the same settings: the generated C and the loop's numba controller
    c = _run("arm6", "pi", "dropout")
    numba = run_spec(RunSpec("E1", "pi", "arm6", seed=3, fault="dropout", duration_s=DURATION_S))
    assert numba.status is None and "compiled" in numba.controller_impl
    assert float(np.max(np.abs(c.u - numba.u))) <= TOLERANCE_M
    assert (c.faults, c.tripped, c.engaged_time_s) == (
        numba.faults,
        numba.tripped,
        numba.engaged_time_s,
    )


def test_the_python_loop_records_the_same_status_as_the_generated_controller() -> None:
    # planar: both loops give the same traces bit for bit (test_compiled_loop), so the
    # reference controller in the Python loop must report the generated C's status bits
    c = _run("planar", "pi", "spike")
    py = run_spec(
        RunSpec("E1", "pi", "planar", seed=3, fault="spike", duration_s=DURATION_S, loop="python")
    )
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
        ({"loop": "python"}, "compiled loop"),
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
    assert main([*argv, "--json"]) == 0  # the default: fuzzkit's own controller
    assert "generated" not in json.loads(capsys.readouterr().out)["controller_impl"]


def test_sweep_and_tune_pass_the_choice_on() -> None:
    from fuzzkit.studies.sweep import sweep_specs
    from fuzzkit.studies.tuning.pricing import CaseRunner
    from fuzzkit.studies.tuning.problem import TuningProblem

    specs = sweep_specs(["E1"], ["pi", "fuzzy-pi"], plant="planar", controller_impl="c")
    assert {s.controller_impl for s in specs} == {"c"}
    problem = TuningProblem.build(["E1"], "pi", plant="planar", controller_impl="c")
    r = CaseRunner(problem).run_case(0, {"kp": 3e-5, "ki": 1e-5}, 0.5)
    assert r.controller_impl.startswith("generated C controller (double) E1_pi_controller")
    with pytest.raises(ConfigError, match="compiled loop"):
        TuningProblem.build(["E1"], "pi", plant="planar", loop="python", controller_impl="c")
