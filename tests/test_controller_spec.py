"""The controller spec: the shipped examples, located errors (all at once), the JSON Schema, and
``fuzzkit validate`` / ``fuzzkit schema --controller`` as a user runs them."""

from __future__ import annotations

import dataclasses
import json
import math
import shutil
from pathlib import Path

import jsonschema
import pytest

from fuzzkit.cli import main
from fuzzkit.control.spec import (
    AxisSpec,
    ControllerSpec,
    Limits,
    Safety,
    SensorSpec,
    require_valid,
)
from fuzzkit.control.spec_reader import TOP_KEYS, load_spec, loads_spec
from fuzzkit.control.spec_schema import json_schema
from fuzzkit.errors import ConfigError, ControllerSpecError
from fuzzkit.studies.experiments import DEFAULT_GAINS, experiment

ROOT = Path(__file__).resolve().parent.parent
FUZZY = ROOT / "docs" / "examples" / "controller.yaml"
PI = ROOT / "docs" / "examples" / "controller_pi.yaml"
FUZZY_TEXT = FUZZY.read_text(encoding="utf-8")


# --------------------------------------------------------------------------- the examples


@pytest.mark.parametrize(("path", "kind"), [(FUZZY, "fuzzy-pi"), (PI, "pi")])
def test_examples_hold_e1s_task_and_the_closed_loops_default_gains(path: Path, kind: str) -> None:
    spec = load_spec(path)
    e1 = experiment("E1")
    assert spec.kind == kind
    assert (spec.selection, spec.setpoints) == (e1.selection, e1.setpoints)
    assert spec.period_s == e1.scenario.period_s
    assert spec.safety.limit_n == e1.force_limit_n
    assert (spec.safety.engage_threshold_n, spec.safety.engage_samples) == (
        e1.engage_threshold_n,
        e1.engage_samples,
    )
    defaults = DEFAULT_GAINS[kind]
    for a in spec.axes:
        gains = {"kp": a.kp, "ki": a.ki} | ({"kx": a.kx} if a.kx is not None else {})
        assert gains == {k: v for k, v in defaults.items() if k in ("kp", "ki", "kx")}
    assert -spec.limits.correction_m == defaults["u_min"]
    assert spec.limits.correction_m == defaults["u_max"]
    # the sensor front end is complete: tare, tool and filter are all set
    assert spec.sensor.tare_samples > 0 and spec.sensor.tool is not None
    assert spec.sensor.lowpass_hz is not None
    assert spec.source is not None and len(spec.source.sha256) == 64


def test_fuzzy_example_loads_its_rule_base() -> None:
    spec = load_spec(FUZZY)
    assert spec.rulebase is not None and spec.rulebase.name == "macvicar_whelan"
    assert spec.rulebase_ref == "macvicar_whelan"
    assert load_spec(PI).rulebase is None


def test_a_rule_base_path_is_read_relative_to_the_spec(tmp_path: Path) -> None:
    folder = tmp_path / "cell"
    folder.mkdir()
    shutil.copy(ROOT / "rulebases" / "paper_table1.yaml", folder / "table1.yaml")
    (folder / "spec.yaml").write_text(
        FUZZY_TEXT.replace("rulebase: macvicar_whelan", "rulebase: table1.yaml")
    )
    spec = load_spec(folder / "spec.yaml")
    assert spec.rulebase is not None and spec.rulebase.name == "paper_table1"


def test_lowpass_alpha_is_the_exact_discretisation() -> None:
    """The filter's step response at t = kT equals the continuous one, 1 - exp(-t/tau)."""
    fc, period = 40.0, 0.004
    alpha = SensorSpec(lowpass_hz=fc).lowpass_alpha(period)
    tau = 1.0 / (2.0 * math.pi * fc)
    y = 0.0
    for k in range(1, 50):
        y += alpha * (1.0 - y)
        assert y == pytest.approx(1.0 - math.exp(-k * period / tau), rel=1e-12)
    assert SensorSpec().lowpass_alpha(period) == 1.0


# --------------------------------------------------------------------------- errors


def _line_col(text: str, needle: str) -> tuple[int, int]:
    """Line and column of the first line holding ``needle``, at its ``|`` (or its start)."""
    bare = needle.replace("|", "")
    for i, line in enumerate(text.split("\n"), start=1):
        if bare in line:
            return i, line.index(bare) + 1 + max(needle.find("|"), 0)
    raise AssertionError(needle)


@pytest.mark.parametrize(
    ("args", "exc", "match"),
    [
        # (old, new, where the error points), the exception, what it says
        (("name: e1_fuzzy", "name: int", "int "), ControllerSpecError, "'int' is a C keyword"),
        (("name: e1_fuzzy", "name: lambda", "lambda"), ControllerSpecError, "Python keyword"),
        (("name: e1_fuzzy", "name: e1-fuzzy", "e1-fuzzy"), ControllerSpecError, "identifier"),
        (
            ("rulebase: macvicar_whelan", "rulebase: macvicar", "macvicar "),
            ControllerSpecError,
            "cannot load rule base 'macvicar'.*did you mean 'macvicar_whelan'",
        ),
        (
            ("rulebase: macvicar_whelan", "rulebase: missing.yaml", "missing.yaml"),
            ControllerSpecError,
            "cannot load rule base 'missing.yaml'.*cannot read",
        ),
        (
            ("rulebase: macvicar_whelan", "rulebase: three_input", "three_input"),
            ControllerSpecError,
            "has 3 inputs; a fuzzy-PI needs exactly 2",
        ),
        (
            ("rulebase: macvicar_whelan", "rulebase: temperature_pd", "temperature_pd"),
            ControllerSpecError,
            r"spans \[.*\]; a fuzzy-PI clips its scaled inputs to \[-1, 1\]",
        ),
        (("  x: ", "  w: ", "w:"), ControllerSpecError, "unknown key 'w' in axes"),
        (
            (
                "gains: {kp: 0.2, ki: 0.05, kx: 0.0002}  #",
                "gains: {kp: .nan, ki: 0.05, kx: 1}  #",
                ".nan",
            ),
            ControllerSpecError,
            "gain kp must be finite",
        ),
        (
            ("    setpoint_n: 10.0", "    setpoint_n: 30.0", "30.0"),
            ControllerSpecError,
            "set point 30 N is not below the safety limit 25 N",
        ),
        (
            ("limit_n: 25.0", "limit_n: 8.0", "setpoint_n: |10.0"),
            ControllerSpecError,
            "set point 10 N is not below the safety limit 8 N",
        ),
        (
            (
                "gains: {kp: 0.2, ki: 0.05, kx: 0.0002}  #",
                "gains: {kp: 0.2, ki: 0.05}  #",
                "gains: |{kp: 0.2, ki: 0.05}",
            ),
            ControllerSpecError,
            "missing required key 'kx' in axes.x.gains",
        ),
        (
            ("step_m: 0.001", "step_m: 0", "step_m: |0"),
            ControllerSpecError,
            "step_m must be a finite",
        ),
        (
            ("lowpass_hz: 40.0", "lowpass_hz: 200.0", "200.0"),
            ControllerSpecError,
            "not below the Nyquist frequency 125 Hz",
        ),
        (
            ("lowpass_hz: 40.0", "lowpass_hz: 1e-300", "1e-300"),
            ControllerSpecError,
            "too low for period_s 0.004: the filter would never move",
        ),
        (
            ("period_s: 0.004", "period_s: 1e-300", "1e-300"),
            ControllerSpecError,
            r"period_s must be in \[1e-05, 10\] s",
        ),
        (
            ("samples: 25}", "samples: 2.5}", "samples: |2.5"),
            ControllerSpecError,
            "expected an integer",
        ),
        (
            ("controller: fuzzy-pi", "controller: pid", "pid"),
            ControllerSpecError,
            "unknown controller 'pid'",
        ),
        (
            ("adaptation: none", "adaptation: gain_schedule", "gain_schedule"),
            ControllerSpecError,
            "unknown adaptation 'gain_schedule'",
        ),
        (
            ("com_m: [0.0, 0.0, 0.06]", "com_m: [0.0, 0.06]", "[0.0, 0.06]"),
            ControllerSpecError,
            "expected 3 numbers",
        ),
        (
            ("  trip: {samples: 2}", "  trip: {samples: 2, delay: 1}", "delay"),
            ControllerSpecError,
            "unknown key 'delay' in safety.trip",
        ),
        (
            ("  trip: {samples: 2}", "  trip: {samples: 2}\n  watchdog: {periods: 0}", "0}"),
            ControllerSpecError,
            r"safety.watchdog.periods must be an integer >= 1 \(got 0\)",
        ),
        (
            ("period_s: 0.004", "period: 0.004", "period:"),
            ControllerSpecError,
            "unknown key 'period' in the controller spec .did you mean 'period_s'",
        ),
    ],
)
def test_bad_specs_give_located_errors(
    args: tuple[str, ...], exc: type[Exception], match: str
) -> None:
    old, new, needle = args
    assert old in FUZZY_TEXT, old
    text = FUZZY_TEXT.replace(old, new, 1)
    with pytest.raises(exc) as info:
        loads_spec(text, "spec.yaml")
    assert isinstance(info.value, ControllerSpecError)
    import re

    hits = [p for p in info.value.problems if re.search(match, p.message)]
    assert hits, [str(p) for p in info.value.problems]
    line, col = _line_col(text, needle)
    assert (hits[0].location.file, hits[0].location.line) == ("spec.yaml", line), str(hits[0])
    assert hits[0].location.col == col, str(hits[0])
    assert isinstance(info.value, ValueError)  # catchable without importing fuzzkit


def test_every_problem_is_reported_at_once() -> None:
    text = (
        FUZZY_TEXT.replace("name: e1_fuzzy", "name: int")
        .replace("step_m: 0.001", "step_m: -1")
        .replace("    setpoint_n: 10.0", "    setpoint_n: 30.0")
        .replace("samples: 25}", "samples: x}")
        .replace("limits:", "limit:\n  extra: 1\nlimits:")
    )
    with pytest.raises(ControllerSpecError) as info:
        loads_spec(text, "spec.yaml")
    messages = [p.message for p in info.value.problems]
    assert len(messages) == 5, messages
    lines = [p.location.line for p in info.value.problems]
    assert lines == sorted(lines)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("", "file is empty"),
        ("name: [1\n", "spec.yaml:2:1: invalid YAML"),
        ("- 1\n", r"spec.yaml:1:1: expected the controller spec \(a mapping\)"),
        ("name: x\n", "missing required key 'axes' in the controller spec"),
        ("name: x\nperiod_s: !!python/object:os.system 1\n", "unsupported YAML tag"),
    ],
)
def test_malformed_documents(text: str, match: str) -> None:
    with pytest.raises(ControllerSpecError, match=match):
        loads_spec(text, "spec.yaml")


def test_a_spec_built_in_code_is_checked_too() -> None:
    good = load_spec(PI)
    assert require_valid(good) is good
    bad = dataclasses.replace(
        good,
        axes=(AxisSpec("z", 10.0, kp=math.inf, ki=1e-5),),
        limits=Limits(0.05, -1.0),
        safety=Safety(limit_n=5.0),
    )
    with pytest.raises(ConfigError) as info:
        require_valid(bad)
    text = str(info.value)
    assert "axes.z.gains.kp: gain kp must be finite" in text
    assert "limits.step_m: limits.step_m must be a finite number > 0" in text
    assert "axes.z.setpoint_n: set point 10 N is not below the safety limit 5 N" in text
    fuzzy = dataclasses.replace(good, kind="fuzzy-pi", rulebase=None)
    with pytest.raises(ConfigError, match="fuzzy-pi needs a rule base"):
        require_valid(fuzzy)
    assert ControllerSpec(
        "ok", "pi", 0.004, (AxisSpec("z", 1.0, 1e-5, 1e-5),), Limits(1.0, 1.0), Safety(2.0)
    ).selection == (False, False, True)


# --------------------------------------------------------------------------- schema


def test_json_schema_accepts_the_examples_and_rejects_what_the_reader_rejects() -> None:
    import yaml

    schema = json_schema()
    jsonschema.Draft202012Validator.check_schema(schema)
    validator = jsonschema.Draft202012Validator(schema)
    for path in (FUZZY, PI):
        assert list(validator.iter_errors(yaml.safe_load(path.read_text()))) == [], path
    assert set(schema["properties"]) == set(TOP_KEYS)
    doc = yaml.safe_load(FUZZY_TEXT)
    doc["sensor"]["tool"]["volume"] = 1.0
    assert list(validator.iter_errors(doc))
    doc = yaml.safe_load(PI.read_text())
    doc["rulebase"] = "macvicar_whelan"  # a pi takes none
    assert list(validator.iter_errors(doc))
    doc = yaml.safe_load(FUZZY_TEXT)
    del doc["rulebase"]  # a fuzzy-pi needs one
    assert list(validator.iter_errors(doc))


# --------------------------------------------------------------------------- CLI


def test_cli_validate_recognises_specs_by_content(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "cell.yaml"
    bad.write_text(FUZZY_TEXT.replace("step_m: 0.001", "step_m: 0"))
    code = main(["validate", str(FUZZY), str(PI), "macvicar_whelan", str(bad)])
    out, err = capsys.readouterr()
    assert code == 2
    assert f"{FUZZY}: ok (controller spec e1_fuzzy: fuzzy-pi on macvicar_whelan; " in out
    assert f"{PI}: ok (controller spec e1_pi: pi; x 0 N, z 10 N)" in out
    assert "macvicar_whelan: ok" in out
    line, col = _line_col(bad.read_text(), "step_m: |0")
    assert f"{bad}:{line}:{col}: limits.step_m must be a finite number > 0 (got 0.0)" in err
    assert err.splitlines()[-1] == "fuzzkit: error: 1 of 4 files invalid"
    assert "Traceback" not in err


def test_cli_schema_controller(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["schema", "--controller"]) == 0
    schema = json.loads(capsys.readouterr().out)
    assert schema == json_schema()
    assert schema["title"] == "fuzzkit controller spec"


def test_with_gains_moves_the_lead_axis_and_keeps_the_others_ratios() -> None:
    from fuzzkit.control.spec import lead_axis, with_gains

    root = Path(__file__).resolve().parent
    spec = load_spec(root / "data" / "user" / "spec_user_pi.yaml")  # x: 0.25, 0.04, 1.5e-4
    x, z = spec.axes  #                                                 z: 0.2, 0.05, 2e-4
    assert lead_axis(spec) is z  # the force set point's axis, listed second
    # the lead's own gains: the spec itself, bit for bit (the search's baseline)
    assert with_gains(spec, {"kp": z.kp, "ki": z.ki, "kx": z.kx}) == spec
    moved = with_gains(spec, {"kp": 0.4, "ki": 0.01, "kx": 0.0003, "u_min": -1.0})
    mx, mz = moved.axes
    assert (mz.kp, mz.ki, mz.kx) == (0.4, 0.01, 0.0003)
    assert (mx.kp, mx.ki, mx.kx) == pytest.approx((0.5, 0.008, 0.000225), rel=1e-15)
    assert moved.limits == spec.limits
    # a lead gain of 0 scales nothing: a 0 follows the gain given, another value stays
    pi = dataclasses.replace(
        spec,
        kind="pi",
        axes=(dataclasses.replace(x, kx=None), dataclasses.replace(z, ki=0.0, kx=None)),
    )
    px, pz = with_gains(pi, {"kp": 0.1, "ki": 0.03}).axes
    assert (pz.kp, pz.ki) == (0.1, 0.03) and (px.kp, px.ki) == (0.125, 0.04)
