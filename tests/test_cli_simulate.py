"""``fuzzkit simulate``: stiffness, latency, fault and seed reach the run and its output."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from fuzzkit.cli import main
from fuzzkit.studies.scenario_file import shipped_scenario_text


def _json(capsys: pytest.CaptureFixture[str], *args: str) -> dict[str, object]:
    assert main(["simulate", *args, "--json"]) == 0
    data: dict[str, object] = json.loads(capsys.readouterr().out)
    return data


def test_json_holds_the_run_conditions_and_true_next_to_measured_peaks(
    capsys: pytest.CaptureFixture[str],
) -> None:
    data = _json(
        capsys,
        "E1", "--controller", "pi", "--stiffness", "20", "--latency", "2,0",
        "--fault", "spike", "--seed", "3",
    )  # fmt: skip
    assert data["stiffness"] == 20.0
    assert data["latency_periods"] == [2, 0]
    assert (data["fault"], data["seed"], data["safety_limit"]) == ("spike", 3, 25.0)
    axes = data["axes"]
    assert isinstance(axes, dict) and list(axes) == ["z", "x"]
    z = axes["z"]
    # 40 N spikes reach the sensor's output, not the contact: the true peak stays near 10 N
    assert z["peak_force_measured"] > 40.0
    assert 9.0 < z["peak_force_true"] < data["safety_limit"]  # type: ignore[operator]
    assert z["peak_force_true"] == z["peak_force"]


def test_defaults_come_from_the_scenario(capsys: pytest.CaptureFixture[str]) -> None:
    data = _json(capsys, "E1", "--controller", "pi", "--latency", "3")
    assert data["stiffness"] == 10.0  # E1.yaml: 1.0e4 N/m
    assert data["latency_periods"] == [3, 1]  # one number: the sensor delay only
    assert (data["fault"], data["seed"]) == ("none", 0)


def test_delay_fault_adds_to_the_sensor_latency(capsys: pytest.CaptureFixture[str]) -> None:
    data = _json(capsys, "E1", "--controller", "pi", "--fault", "delay", "--latency", "1,1")
    assert data["latency_periods"] == [3, 1]  # the delay fault: 2 more periods


def test_human_output_prints_the_conditions(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["simulate", "E1", "--controller", "pi", "--fault", "nan", "--seed", "4"]) == 0
    out = capsys.readouterr().out
    assert (
        "stiffness 10 N/mm, latency 1:1 periods (sensor:command), fault nan, seed 4, "
        "safety limit 25 N" in out
    )
    assert " N true (" in out and " N measured)" in out


def test_a_users_scenario_file_runs_on_either_plant(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    task = tmp_path / "my_task.yaml"
    task.write_text(
        shipped_scenario_text("E1")
        .replace("name: E1", "name: my_task")
        .replace("duration_s: 5.0", "duration_s: 2.5")
    )
    for plant in ("planar", "arm6"):
        data = _json(capsys, str(task), "--controller", "pi", "--plant", plant)
        assert (data["experiment"], data["plant"]) == ("my_task", plant)
        axes = data["axes"]
        assert isinstance(axes, dict) and axes["z"]["first_contact_s"] is not None


@pytest.mark.parametrize(
    "args, match",
    [
        (["--latency", "1,2,3"], "SENSOR:COMMAND (or SENSOR,COMMAND)"),
        (["--latency", "-1"], "integers 0 to 1000"),
        (["--stiffness", "0"], "expected a stiffness > 0"),
        (["--fault", "spikes"], "invalid choice"),
    ],
)
def test_bad_options_are_refused(
    args: list[str], match: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as info:
        main(["simulate", "E1", *args])
    assert info.value.code == 2
    assert match in capsys.readouterr().err


def test_bad_scenario_file_gives_a_located_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    task = tmp_path / "task.yaml"
    task.write_text(shipped_scenario_text("E1").replace("fault: none", "fault: spikes"))
    assert main(["simulate", str(task)]) == 2
    err = capsys.readouterr().err
    assert f"{task}:" in err and "unknown fault 'spikes'" in err and "Traceback" not in err


@pytest.mark.parametrize(
    "old, new", [("z: 10.0", "z: .nan"), ("x: 0.4, z: -0.19", "x: .inf, z: 0")]
)
def test_a_nan_scenario_is_refused_and_json_prints_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], old: str, new: str
) -> None:
    task = tmp_path / "task.yaml"
    task.write_text(shipped_scenario_text("E1").replace(old, new, 1))
    assert main(["simulate", str(task), "--json"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and f"{task}:" in err and "must be a finite number" in err


def test_json_is_strict_json_when_metrics_have_no_value(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # the tool never touches anything: force metrics have no value, printed as null, not NaN
    text = (
        shipped_scenario_text("E1")
        .replace("height_m: -0.3", "height_m: -3.0")
        .replace("center_z: -0.28", "center_z: -2.8")
        .replace("duration_s: 5.0", "duration_s: 1.0")
    )
    task = tmp_path / "air.yaml"
    task.write_text(text)
    assert main(["simulate", str(task), "--json"]) == 0

    def refuse(name: str) -> None:
        raise AssertionError(f"{name} is not JSON")

    data = json.loads(capsys.readouterr().out, parse_constant=refuse)
    assert None in [v for axis in data["axes"].values() for v in axis.values()]
