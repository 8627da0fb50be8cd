"""Scenario files: the shipped E1-E3 equal the former Python definitions; bad files give
located errors; the JSON Schema accepts the shipped files."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import Any

import pytest

from fuzzkit.errors import ScenarioError
from fuzzkit.studies.experiments import EXPERIMENTS, experiment
from fuzzkit.studies.scenario_file import (
    json_schema,
    load_scenario,
    loads_scenario,
    shipped_scenario_text,
)
from tests._legacy_experiments import LEGACY


def _same(a: Any, b: Any, where: str = "") -> list[str]:
    """Differences between two values, floats compared to 1e-12 (the files round 1e-17s)."""
    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        if type(a) is not type(b):
            return [f"{where}: {type(a).__name__} vs {type(b).__name__}"]
        return [
            d
            for f in dataclasses.fields(a)
            for d in _same(getattr(a, f.name), getattr(b, f.name), f"{where}.{f.name}")
        ]
    if isinstance(a, tuple) and isinstance(b, tuple):
        if len(a) != len(b):
            return [f"{where}: {len(a)} vs {len(b)} items"]
        pairs = enumerate(zip(a, b, strict=True))
        return [d for i, (x, y) in pairs for d in _same(x, y, f"{where}[{i}]")]
    if isinstance(a, float) and isinstance(b, float):
        return [] if math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-15) else [f"{where}: {a} vs {b}"]
    return [] if a == b else [f"{where}: {a!r} vs {b!r}"]


@pytest.mark.parametrize("name", EXPERIMENTS)
def test_shipped_scenarios_equal_the_former_python_definitions(name: str) -> None:
    loaded = experiment(name)
    # the former definitions had no latency, engagement debounce or fault fields: the files
    # add the documented defaults
    assert (loaded.latency_periods, loaded.engage_samples, loaded.fault) == ((1, 1), 3, "none")
    assert _same(LEGACY[name](), loaded) == []


def test_the_comparison_catches_a_changed_quantity() -> None:
    e1 = experiment("E1")
    changed = dataclasses.replace(e1, setpoints=(0.0, 0.0, 10.5))
    assert _same(e1, changed) == [".setpoints[2]: 10.0 vs 10.5"]


def test_experiment_accepts_a_users_scenario_file(tmp_path: Path) -> None:
    text = (
        shipped_scenario_text("E2")
        .replace("name: E2", "name: my_task")
        .replace("z: 30.0", "z: 20.0")
    )
    path = tmp_path / "my_task.yaml"
    path.write_text(text)
    exp = experiment(str(path))
    assert exp.name == "my_task" and exp.setpoints == (0.0, 0.0, 20.0)
    assert exp == load_scenario(path)


E1_TEXT = shipped_scenario_text("E1")


def _line_col(text: str, needle: str) -> tuple[int, int]:
    for i, line in enumerate(text.split("\n"), start=1):
        if needle in line:
            return i, line.index(needle) + 1
    raise AssertionError(needle)


@pytest.mark.parametrize(
    "old, new, needle, match",
    [
        ("duration_s: 5.0", "duration_s: -5.0", "-5.0", "duration_s must be a finite number > 0"),
        ("duration_s: 5.0", "duraton_s: 5.0", "duraton_s", "did you mean 'duration_s'"),
        ("fault: none", "fault: spikes", "spikes", "unknown fault 'spikes'"),
        ("  z: 10.0\n", "  w: 10.0\n", "w: 10.0", "unknown key 'w' in force_control"),
        ("  z: 10.0\n", "  z: ten\n", "ten", "expected a number for the z set point"),
        ("sensor: 1, command: 1", "sensor: -1, command: 1", "-1", "integer >= 0"),
        ("samples: 3", "samples: 0", "0,", "integer >= 1 for engage samples"),
        ("hold_path: true", "hold_path: maybe", "maybe", "true or false"),
        ("  - table: {", "  - tabel: {", "tabel", "did you mean 'table'"),
        ("size_x: 0.12, ", "", "box:", "missing required key 'size_x'"),
        ("{t_s: 0.2,", "{t_s: 9.0,", "3.737742", "time 3.73774 s is before the previous 9 s"),
        ("friction: 0.4", "friction: 0.4, mu: 1", "mu: 1", "unknown key 'mu' in contact"),
        ("name: cup,", "name: 3,", "3,", "expected a name"),
        ("radius_m: 0.035}", "radius_m: 0.035, mass_kg: -1}", "{name: cup", "mass_kg must be >= 0"),
        ("x: 0.52, z: -0.265}", "x: 0.52, z: -0.265, tilt_deg: .inf}", ".inf", "finite"),
        # hostile values (issue 25): bounded, finite, located
        (
            "duration_s: 5.0",
            "duration_s: 1e9",
            "1e9",
            "duration_s must be a finite number > 0 and <= 600",
        ),
        ("period_s: 0.004", "period_s: 1e-300", "1e-300", "period_s must be >= 0.0001 s"),
        (
            "sensor: 1, command: 1",
            "sensor: 1000000000000, command: 1",
            "1000000000000",
            "(at most 1000)",
        ),
        ("{t_s: 0.2, x: 0.4,", "{t_s: 0.2, x: .nan,", ".nan", "path[1] x must be a finite number"),
        (
            "{t_s: 0.2, x: 0.4,",
            "{t_s: 0.2, x: 1" + "0" * 400 + ",",
            "1000",
            "integer of 401 digits",
        ),
        ("  z: 10.0\n", "  z: .inf\n", ".inf", "the z set point must be a finite number"),
        (
            "friction: 0.4",
            "friction: 0.4, tilt_deg: 3",
            "tilt_deg",
            "unknown key 'tilt_deg' in contact",
        ),
        ("noise_std_n: 0.1", "noise_std_n: -.inf", "-.inf", "sensor noise_std_n must be a finite"),
    ],
)
def test_bad_scenarios_give_located_errors(old: str, new: str, needle: str, match: str) -> None:
    assert old in E1_TEXT
    text = E1_TEXT.replace(old, new, 1)
    with pytest.raises(ScenarioError) as info:
        loads_scenario(text, "task.yaml")
    line, col = _line_col(text, needle if needle != "0," else "samples: 0")
    if needle == "0,":
        col += len("samples: ")
    messages = [str(p) for p in info.value.problems]
    assert any(match in m for m in messages), messages
    hit = next(p for p in info.value.problems if match in p.message)
    assert (hit.location.file, hit.location.line) == ("task.yaml", line)
    if needle not in ("box:",):
        assert hit.location.col == col, messages


@pytest.mark.parametrize(
    "text, match",
    [
        ("", "file is empty"),
        ("name: [1\n", "task.yaml:2:1: invalid YAML"),
        ("- 1\n", r"task.yaml:1:1: expected a scenario \(a mapping\)"),
        ("name: x\nduration_s: !!python/object:os.system 1\n", "unsupported YAML tag"),
        ("name: x\n", "missing required key 'path' in the scenario"),
    ],
)
def test_malformed_documents(text: str, match: str) -> None:
    with pytest.raises(ScenarioError, match=match) as info:
        loads_scenario(text, "task.yaml")
    assert "rule base" not in str(info.value)


def test_every_problem_is_reported_at_once() -> None:
    text = E1_TEXT.replace("duration_s: 5.0", "duration_s: 0").replace("fault: none", "fault: x")
    with pytest.raises(ScenarioError) as info:
        loads_scenario(text, "task.yaml")
    assert len(info.value.problems) == 2


def test_unknown_experiment_name_and_missing_file(tmp_path: Path) -> None:
    from fuzzkit.errors import ConfigError

    with pytest.raises(ConfigError, match="unknown experiment 'E9'"):
        experiment("E9")
    with pytest.raises(ScenarioError, match="cannot read"):
        experiment(str(tmp_path / "nope.yaml"))


def test_json_schema_accepts_the_shipped_files_and_rejects_unknown_keys() -> None:
    jsonschema = pytest.importorskip("jsonschema")
    import yaml

    schema = json_schema()
    jsonschema.Draft202012Validator.check_schema(schema)
    validator = jsonschema.Draft202012Validator(schema)
    for name in EXPERIMENTS:
        doc = yaml.safe_load(shipped_scenario_text(name))
        assert list(validator.iter_errors(doc)) == [], name
    doc = yaml.safe_load(E1_TEXT)
    doc["contact"]["mu"] = 1.0
    assert list(validator.iter_errors(doc))
    json.dumps(schema)


def test_cli_schema_scenario(capsys: pytest.CaptureFixture[str]) -> None:
    from fuzzkit.cli import main

    assert main(["schema", "--scenario"]) == 0
    assert json.loads(capsys.readouterr().out) == json_schema()


def test_yaml_11_integer_spellings_are_read_in_integer_fields() -> None:
    # 0x1 (hex), 1_0 (digit groups), 1:30 (base 60) as the rule-base reader reads them
    text = E1_TEXT.replace("sensor: 1, command: 1", "sensor: 0x1, command: 1_0").replace(
        "samples: 3", "samples: 1:30"
    )
    exp = loads_scenario(text, "task.yaml")
    assert exp.latency_periods == (1, 10) and exp.engage_samples == 90


def test_nan_tilt_and_too_many_periods_are_refused_at_their_line() -> None:
    e2 = shipped_scenario_text("E2")
    text = e2.replace("tilt_deg: -0.8", "tilt_deg: .nan")
    with pytest.raises(ScenarioError, match=r"task.yaml:23:17: .*tilt_deg must be a finite"):
        loads_scenario(text, "task.yaml")
    many = E1_TEXT.replace("duration_s: 5.0", "duration_s: 500").replace(
        "period_s: 0.004", "period_s: 0.0001"
    )
    line, col = _line_col(many, "500")
    with pytest.raises(ScenarioError, match=rf"task.yaml:{line}:{col}: .*limited to 1000000 "):
        loads_scenario(many, "task.yaml")
