"""The loop package (``fuzzkit.loop``): its plant registry and adapters, and every caller going
through its one entry point (``fuzzkit.loop.run.run_loop``)."""

from __future__ import annotations

from pathlib import Path

import pytest

from fuzzkit.errors import ConfigError
from fuzzkit.loop.adapter import PLANTS, adapter, compiled_plants, compiled_supports, make_plant
from fuzzkit.plants.contract import UnsupportedPlant

TILT = str(Path(__file__).resolve().parent.parent / "docs" / "examples" / "tilt.yaml")


def test_every_registered_plant_has_an_adapter_of_its_name() -> None:
    for name in PLANTS:
        assert adapter(name).name == name
    # every plant has a compiled loop now (the MuJoCo plants' since issue 37 item 4)
    assert compiled_plants() == ("arm6", "mujoco", "mujoco-elastic", "planar")
    assert compiled_supports("mujoco") and not compiled_supports("moon")


def test_an_unknown_plant_is_refused_with_the_registered_names() -> None:
    with pytest.raises(ConfigError, match=r"unknown plant 'moon' \(expected one of arm6, "):
        make_plant("moon")


def test_the_registry_imports_no_plant_until_one_is_built() -> None:
    """``--plant`` help lists every plant from the registration alone: building the parser
    imports neither pymunk nor MuJoCo."""
    import subprocess
    import sys

    code = (
        "import sys; from fuzzkit.loop.adapter import plants_text; plants_text(); "
        "print(sorted(m for m in ('pymunk', 'mujoco') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def _tilt_problem(loop: str):  # type: ignore[no-untyped-def]
    from fuzzkit.studies.tuning import TuningProblem

    return TuningProblem.build(
        [TILT], "fuzzy-pi", plant="arm6", stiffnesses_n_per_mm=None, horizon_s=1.0, loop=loop
    )


def test_tune_prices_a_scenario_the_kernels_lack_as_simulate_runs_it() -> None:
    """The tilt scenario (a tool weight, a drifting bias, a tilting tool) has no compiled
    kernel: ``tune`` prices it in the Python loop with the generated controller, the cost of
    the run ``simulate`` makes with the same gains, never the failed run's price."""
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import run_spec
    from fuzzkit.studies.experiments import DEFAULT_GAINS
    from fuzzkit.studies.tuning import CaseRunner
    from fuzzkit.studies.tuning.cost import run_cost

    problem = _tilt_problem("auto")
    gains = dict(DEFAULT_GAINS["fuzzy-pi"])  # the scenario's spec's own kp, ki, kx
    runner = CaseRunner(problem)
    (cost,) = runner.case_costs(gains)
    assert cost != problem.weights.none
    simulated = run_spec(RunSpec(TILT, plant="arm6", duration_s=1.0))
    assert simulated.loop.startswith("python (fallback: ")
    assert "generated" in simulated.controller_impl
    assert cost == run_cost(simulated, problem.weights)


def test_tune_on_the_compiled_loop_refuses_a_scenario_its_kernels_lack() -> None:
    from fuzzkit.studies.experiments import DEFAULT_GAINS
    from fuzzkit.studies.tuning import CaseRunner

    runner = CaseRunner(_tilt_problem("compiled"))
    with pytest.raises(UnsupportedPlant, match=r"does not model a tool weight.*--loop python"):
        runner.case_costs(dict(DEFAULT_GAINS["fuzzy-pi"]))


def _function_problem(**options):  # type: ignore[no-untyped-def]
    from fuzzkit.control.controllers import saturated_sum_surface
    from fuzzkit.studies.tuning import TuningProblem

    return TuningProblem.build(
        ["E1"], "fuzzy-pi", saturated_sum_surface, plant="planar", stiffnesses_n_per_mm=None,
        horizon_s=2.5, **options,
    )  # fmt: skip


def test_a_surface_given_as_a_function_is_priced_as_a_named_reference_run() -> None:
    """No code is generated from a Python function: tune prices it through the loop's entry
    point as a reference run asked for by name, and every run says so."""
    import numpy as np

    from fuzzkit.control.controllers import saturated_sum_surface
    from fuzzkit.loop import python_loop
    from fuzzkit.studies.experiments import DEFAULT_GAINS, experiment
    from fuzzkit.studies.tuning import CaseRunner

    problem = _function_problem()
    assert problem.controller_impl == "reference"
    runner = CaseRunner(problem)
    gains = dict(DEFAULT_GAINS["fuzzy-pi"])
    got = runner.run_case(0, gains, 2.5)
    assert got.loop == "python"
    assert got.controller_impl == (
        "reference controller, surface given as the Python function saturated_sum_surface (python)"
    )
    assert runner.implementation(gains) == f"{got.controller_impl} [python]"
    # the same run made by the Python loop itself, on the function
    want = python_loop.run(
        experiment("E1"), "planar", "fuzzy-pi", gains=gains, surface=saturated_sum_surface,
        duration_s=2.5,
    )  # fmt: skip
    np.testing.assert_array_equal(got.u, want.u)
    assert float(np.max(np.abs(got.u))) > 1e-5  # in contact: the surface acted
    # the rule base's exact surface is another controller: the function was what ran
    exact = python_loop.run(
        experiment("E1"), "planar", "fuzzy-pi", gains=gains,
        surface=python_loop.load_surface(), duration_s=2.5,
    )  # fmt: skip
    assert float(np.max(np.abs(got.u - exact.u))) > 1e-7


@pytest.mark.parametrize(
    "options, match",
    [
        ({"controller_impl": "c"}, "a surface given as a function has no code"),
        ({"controller_impl": "python"}, "a surface given as a function has no code"),
        ({"loop": "compiled"}, "use loop='python'"),
    ],
)
def test_a_surface_given_as_a_function_refuses_the_generated_controller(
    options: dict[str, str], match: str
) -> None:
    with pytest.raises(ConfigError, match=match):
        _function_problem(**options)


@pytest.mark.parametrize(
    "run, match",
    [
        ({"controller_impl": "auto"}, r"no generated code .*\(controller_impl='reference'\)"),
        ({"controller_impl": "c"}, r"no generated code"),
        ({"controller": "pi", "controller_impl": "reference"}, "a fuzzy-PI's surface"),
        ({"controller_impl": "reference", "fuzzy_impl": "table"}, "leave fuzzy_impl at auto"),
    ],
)
def test_run_loop_takes_a_function_surface_on_the_reference_only(
    run: dict[str, str], match: str
) -> None:
    from fuzzkit.control.controllers import saturated_sum_surface
    from fuzzkit.loop.run import run_loop
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.experiments import experiment

    spec = RunSpec("E1", plant="planar", duration_s=0.1, **run)  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match=match):
        run_loop(spec, experiment("E1"), "planar", surface=saturated_sum_surface)
