"""Controller specs in the studies: scenario files that reference or embed one, ``simulate
--spec``, sweeps over specs, the compiled loop on a spec, and the spec ``tune`` writes."""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path

import jsonschema
import numpy as np
import pytest

from fuzzkit.cli import main
from fuzzkit.control.spec import SensorSpec
from fuzzkit.control.spec_reader import load_spec, loads_spec
from fuzzkit.control.spec_writer import dump_spec
from fuzzkit.errors import ConfigError, ScenarioError
from fuzzkit.studies.experiments import experiment, with_spec
from fuzzkit.studies.scenario_file import loads_scenario, shipped_scenario_text

ROOT = Path(__file__).resolve().parent.parent
FUZZY = ROOT / "docs" / "examples" / "controller.yaml"
PI = ROOT / "docs" / "examples" / "controller_pi.yaml"
E1_TEXT = shipped_scenario_text("E1")
E1_TASK = (
    "force_control:  # set point per force-controlled task axis (N); other axes follow the path\n"
    "  x: 0.0\n  z: 10.0\nsafety_limit_n: 25.0\n"
    "engage: {threshold_n: 1.0, samples: 3, hold_path: true}\n"
)


def _scenario_with(controller: str) -> str:
    assert E1_TASK in E1_TEXT
    return E1_TEXT.replace(E1_TASK, controller + "engage: {hold_path: true}\n")


# --------------------------------------------------------------------------- scenario files


def test_a_scenario_references_a_spec_relative_to_itself(tmp_path: Path) -> None:
    (tmp_path / "spec.yaml").write_text(PI.read_text())
    exp = loads_scenario(_scenario_with("controller: spec.yaml\n"), "task.yaml", tmp_path)
    assert exp.controller_spec == dataclasses.replace(
        load_spec(tmp_path / "spec.yaml"), source=exp.controller_spec.source
    )
    assert (exp.setpoints, exp.selection, exp.force_limit_n) == (
        (0.0, 0.0, 10.0),
        (True, False, True),
        25.0,
    )
    assert exp.hold_path_on_contact


def test_a_scenario_embeds_a_spec_and_its_errors_are_located_in_the_scenario() -> None:
    body = "".join(
        "  " + line + "\n"
        for line in PI.read_text().splitlines()
        if line and not line.startswith("#")
    )
    exp = loads_scenario(_scenario_with("controller:\n" + body), "task.yaml")
    assert exp.controller_spec is not None and exp.controller_spec.name == "e1_pi"
    bad = body.replace("step_m: 0.001", "step_m: -1")
    with pytest.raises(ScenarioError) as info:
        loads_scenario(_scenario_with("controller:\n" + bad), "task.yaml")
    (problem,) = info.value.problems
    line = (
        _scenario_with("controller:\n" + bad)
        .split("\n")
        .index(next(x for x in bad.split("\n") if "step_m" in x))
        + 1
    )
    assert problem.location.file == "task.yaml" and problem.location.line == line
    assert "limits.step_m must be a finite number > 0" in problem.message


@pytest.mark.parametrize(
    ("args", "exc", "match"),
    [
        (("controller: missing.yaml\n", ""), ScenarioError, "missing.yaml.*cannot read"),
        (
            ("controller: spec.yaml\nsafety_limit_n: 30.0\n", ""),
            ScenarioError,
            "safety_limit_n is the controller spec's",
        ),
        (
            ("controller: spec.yaml\n", "period_s: 0.004"),
            ScenarioError,
            "period_s 0.002 differs from the controller spec's 0.004",
        ),
        (
            ("controller: spec.yaml\nengage: {threshold_n: 2.0}\n", ""),
            ScenarioError,
            "engage threshold_n is the controller spec's",
        ),
        (("", ""), ScenarioError, "missing required key 'force_control'"),
    ],
)
def test_scenario_spec_conflicts_are_errors(
    tmp_path: Path, args: tuple[str, str], exc: type[Exception], match: str
) -> None:
    (tmp_path / "spec.yaml").write_text(PI.read_text())
    controller, period = args
    text = E1_TEXT.replace(E1_TASK, controller)
    if period:
        text = text.replace(period, "period_s: 0.002")
    with pytest.raises(exc, match=match):
        loads_scenario(text, "task.yaml", tmp_path)


def test_with_spec_needs_the_scenarios_period() -> None:
    spec = dataclasses.replace(load_spec(PI), period_s=0.002)
    with pytest.raises(ConfigError, match="the periods must agree"):
        with_spec(experiment("E1"), spec)


def test_scenario_schema_takes_a_spec_path_or_mapping() -> None:
    import yaml

    from fuzzkit.studies.scenario_file import json_schema

    validator = jsonschema.Draft202012Validator(json_schema())
    for text in (
        _scenario_with("controller: spec.yaml\n"),
        _scenario_with(
            "controller: "
            + yaml.safe_dump(yaml.safe_load(PI.read_text()), default_flow_style=True, width=1e9)
        ),
        E1_TEXT,
    ):
        assert list(validator.iter_errors(yaml.safe_load(text))) == []
    both = yaml.safe_load(E1_TEXT)
    both["controller"] = "spec.yaml"  # and force_control, safety_limit_n: twice
    assert list(validator.iter_errors(both))


# --------------------------------------------------------------------------- runs


def test_simulate_spec_runs_the_specs_controller(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["simulate", "E1", "--spec", str(PI), "--json", "--plant", "planar"])
    data = json.loads(capsys.readouterr().out)
    assert code == 0
    assert data["controller"] == "pi" and "controller (double) e1_pi" in data["controller_impl"]
    assert data["loop"] == "compiled"  # front end and all
    assert abs(data["axes"]["z"]["steady_state_error_mean"]) < 0.1
    assert main(["simulate", "E1", "--spec", str(PI), "--gains", str(PI)]) == 2
    assert "give --spec or --gains" in capsys.readouterr().err


@pytest.mark.parametrize("fault", ["none", "spike", "nan"])
@pytest.mark.parametrize("path", [FUZZY, PI], ids=["fuzzy-pi", "pi"])
def test_a_spec_runs_compiled_as_in_python(path: Path, fault: str) -> None:
    """The compiled loop runs a spec (its generated C), sensor front end included (tare
    screened by the gate, gravity compensation, low-pass), with the spec's gains and limits,
    and repeats the Python loop's run on the reference controller (exact engine): the same
    samples in, the same corrections out."""
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import run_spec

    kw = {"plant": "arm6", "controller_spec": str(path), "fault": fault, "duration_s": 2.5}
    co = run_spec(RunSpec("E1", loop="compiled", **kw))  # type: ignore[arg-type]
    py = run_spec(RunSpec("E1", controller_impl="reference", **kw))  # type: ignore[arg-type]
    name = load_spec(path).name
    assert co.loop == "compiled" and f"generated C controller (double) {name}" in co.controller_impl
    assert np.any(co.in_contact)
    np.testing.assert_array_equal(np.isnan(co.force), np.isnan(py.force))
    np.testing.assert_allclose(co.u, py.u, rtol=0, atol=1e-12)
    np.testing.assert_allclose(co.force_true, py.force_true, rtol=0, atol=1e-9)
    assert (co.faults, co.engaged_time_s) == (py.faults, py.engaged_time_s)


def test_a_spec_with_different_gains_per_axis_runs_compiled(tmp_path: Path) -> None:
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import run_spec

    spec = load_spec(PI)
    x, z = spec.axes
    uneven = dataclasses.replace(spec, axes=(x, dataclasses.replace(z, kp=2 * z.kp)))
    path = tmp_path / "uneven.yaml"
    path.write_text(dump_spec(uneven))
    result = run_spec(RunSpec("E1", plant="arm6", controller_spec=str(path), duration_s=0.5))
    assert result.loop == "compiled"  # the generated controller holds per-axis gains


def test_sweep_over_specs() -> None:
    from fuzzkit.studies.sweep import run_sweep, sweep_specs

    specs = sweep_specs(
        ["E1"], ["pi"], controller_specs=[str(PI), str(FUZZY)], plant="planar", duration_s=0.5
    )
    assert [(s.controller, s.controller_spec) for s in specs] == [
        ("pi", str(PI)),
        ("fuzzy-pi", str(FUZZY)),
    ]
    rows = run_sweep(specs, workers=1)
    assert [r["controller_spec"] for r in rows] == [str(PI), str(FUZZY)]
    with pytest.raises(ConfigError, match="specs or gains"):
        sweep_specs(["E1"], ["pi"], controller_specs=[str(PI)], gains={"g": {"pi": {"kp": 1.0}}})


def test_the_spec_tune_writes_reads_back_with_the_tuned_gains() -> None:
    from fuzzkit.formats.registry import load
    from fuzzkit.loop.task import spec_for

    gains = {"kp": 0.31, "ki": 0.062, "kx": 1.8e-4, "u_min": -0.04, "u_max": 0.05}
    spec = spec_for(
        experiment("E1"), "fuzzy-pi", gains, "tuned", load("macvicar_whelan"), "macvicar_whelan"
    )
    back = loads_spec(dump_spec(spec), "tuned.yaml")
    assert [(a.axis, a.setpoint_n, a.kp, a.ki, a.kx) for a in back.axes] == [
        ("x", 0.0, 0.31, 0.062, 1.8e-4),
        ("z", 10.0, 0.31, 0.062, 1.8e-4),
    ]
    assert back.limits.correction_m == 0.04 and back.safety.limit_n == 25.0
    assert back.sensor == SensorSpec()  # the tuned loop had no front end
    assert dataclasses.replace(back, source=None, rulebase_source=None) == dataclasses.replace(
        spec, rulebase_source=None
    )


def test_tune_a_spec_writes_it_back_with_the_tuned_gains(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from fuzzkit.control.gains import read_gains

    # issue 41: the spec's own correction limit (0.04 here, not the defaults' 0.05) is what
    # the gains file's u_min/u_max say, the comparison is with the spec's gains, and every
    # number is written in its shortest form (no 0.00020000000000000004)
    text = PI.read_text(encoding="utf-8")
    assert "correction_m: 0.05 " in text
    spec = tmp_path / "pi.yaml"
    spec.write_text(text.replace("correction_m: 0.05 ", "correction_m: 0.04 "), encoding="utf-8")
    out, spec_out = tmp_path / "gains.yaml", tmp_path / "tuned.yaml"
    argv = ["tune", "E1", "--spec", str(spec), "--stiffness", "10", "--budget", "10"]
    argv += ["--workers", "1", "--quiet", "--out", str(out), "--spec-out", str(spec_out)]
    assert main(argv) == 0
    printed = capsys.readouterr()
    assert f"wrote {spec_out}" in printed.out
    assert f"vs the gains of {spec} " in printed.out and "default gains" not in printed.out
    gains = read_gains(out, "pi")
    assert (gains["u_min"], gains["u_max"]) == (-0.04, 0.04)
    for written in (out.read_text(encoding="utf-8"), spec_out.read_text(encoding="utf-8")):
        assert not re.search(r"\d(0{6,}|9{6,})\d", written), written
    tuned, original = load_spec(spec_out), load_spec(spec)
    assert all((a.kp, a.ki) == (gains["kp"], gains["ki"]) for a in tuned.axes)
    # everything but the gains is the spec's: task, limits, safety, front end
    assert dataclasses.replace(tuned, axes=original.axes, source=None) == dataclasses.replace(
        original, source=None
    )


def test_tune_a_spec_refuses_what_it_cannot_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    never = str(tmp_path / "never.yaml")
    argv = ["tune", "E3", "--spec", str(PI), "--plant", "arm6", "--out", never]
    assert main(argv) == 2
    assert "E3 on arm6" in capsys.readouterr().err
    assert not (tmp_path / "never.yaml").exists()
