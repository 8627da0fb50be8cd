"""One behaviour across commands (issue 23 item 8): the same defaults and options everywhere, the
gains a run used, start-up samples, --fail-on-trip, CLI wording, shipped scenarios copied out."""

from __future__ import annotations

import argparse
import importlib
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from fuzzkit.cli import EXIT_TRIPPED, build_parser, main
from fuzzkit.cli.simulation import comparison_table
from fuzzkit.errors import ConfigError
from fuzzkit.loop.faults import fault
from fuzzkit.loop.python_loop import run
from fuzzkit.loop.spec import RunSpec
from fuzzkit.studies.batch import run_spec
from fuzzkit.studies.experiments import DEFAULT_GAINS, experiment


def _subparser(name: str) -> argparse.ArgumentParser:
    parser = build_parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    sub: argparse.ArgumentParser = action.choices[name]
    return sub


def _default(command: str, dest: str) -> Any:
    return next(a.default for a in _subparser(command)._actions if a.dest == dest)


def test_the_same_default_plant_for_every_command_that_runs_the_loop() -> None:
    plants = {c: _default(c, "plant") for c in ("simulate", "compare", "sweep", "tune", "report")}
    assert set(plants.values()) == {"planar"}, plants


@pytest.mark.parametrize(
    "command", ["sweep", "tune", "report", "compile", "simulate", "compare", "stability"]
)
def test_quiet_everywhere_a_progress_bar_is(command: str) -> None:
    # every command that runs studies takes --quiet, so that scripts can pass it alike
    assert _default(command, "quiet") is False
    opts = {o for a in _subparser(command)._actions for o in a.option_strings}
    assert "--quiet" in opts


def test_compare_accepts_quiet_and_prints_its_table(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["compare", "E1", "--quiet"]) == 0
    assert "E1" in capsys.readouterr().out


def test_sweeps_old_no_progress_still_means_quiet() -> None:
    parser = build_parser()
    args = parser.parse_args(["sweep", "E1", "--out", "r.csv", "--no-progress"])
    assert args.quiet is True
    assert "--no-progress" not in _subparser("sweep").format_help()  # not advertised


def test_report_tunes_on_the_plant_it_reports(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import fuzzkit.report.build as build

    seen: list[str] = []

    def fake_gains_for(ctrl: str, gains_dir: Any, out: Any, setup: Any, *rest: Any) -> Any:
        seen.append(setup.plant)
        raise ConfigError("stop here")

    monkeypatch.setattr(build, "gains_for", fake_gains_for)
    for plant in ("planar", "arm6"):
        for quick in ([], ["--quick"]):
            out = tmp_path / f"r_{plant}_{len(quick)}"
            args = ["report", "--out", str(out), "--plant", plant, "--quiet", *quick]
            assert main(args) == 2
            assert "stop here" in capsys.readouterr().err
            assert seen.pop() == plant
            assert not out.exists()  # nothing half-written


def test_compare_table_keeps_a_long_experiment_name_out_of_the_axis_column() -> None:
    metrics = {
        "setpoint": 10.0, "first_contact_s": 1.0, "overshoot_pct": 2.0, "settling_time_s": 0.1,
        "steady_state_error_mean": 0.0, "steady_state_error_std": 0.1, "rms_error": None,
        "peak_force": 10.5, "contact_lost_s": 0.0,
    }  # fmt: skip
    rows = [
        {"experiment": "my_long_task_name", "controller": "pi", "axes": {"z": metrics}},
        {"experiment": "E1", "controller": "fuzzy-pi", "axes": {"z": metrics}},
    ]
    lines = comparison_table(rows).splitlines()
    axis_col = lines[0].index("axis")
    assert lines[0][:axis_col].rstrip() == "exp"
    for line in lines[2:]:
        assert line[axis_col : axis_col + 5] == "z    "  # the axis stays in its column
        assert line[:axis_col].rstrip() in ("my_long_task_name", "E1")


def test_simulate_prints_and_reports_the_gains_it_ran_with(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    gains = tmp_path / "gains.yaml"
    gains.write_text("kp: 0.3\nki: 0.04\n", encoding="utf-8")
    assert main(["simulate", "E1", "--gains", str(gains), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    expected = {**DEFAULT_GAINS["fuzzy-pi"], "kp": 0.3, "ki": 0.04}
    assert data["gains"] == expected
    assert data["gains_source"] == f"{gains} over the defaults"
    # they are the gains the run used: the same run through the API gives the same metrics
    api = run_spec(RunSpec("E1", "fuzzy-pi", plant="planar", gains=(("ki", 0.04), ("kp", 0.3))))
    from fuzzkit.studies.metrics import summary

    assert summary(api)["axes"] == data["axes"]
    assert main(["simulate", "E1", "--controller", "pi"]) == 0
    text = capsys.readouterr().out
    assert "  gains: kp=4e-05, ki=1e-05, u_min=-0.05, u_max=0.05 (the defaults)" in text


def test_simulate_with_a_controller_spec_reports_its_gains_per_axis(
    capsys: pytest.CaptureFixture[str],
) -> None:
    from fuzzkit.control.spec_reader import load_spec

    path = Path(__file__).resolve().parent.parent / "docs" / "examples" / "controller_pi.yaml"
    spec = load_spec(path)
    args = ["simulate", "E1", "--spec", str(path), "--json", "--loop", "python"]
    assert main(args) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["gains_source"] == f"controller spec {spec.name}"
    assert data["gains"] == {a.axis: {"kp": a.kp, "ki": a.ki} for a in spec.axes}


@pytest.mark.parametrize("loop", ["python", "compiled"])
@pytest.mark.parametrize("sensor_delay", [1, 3])
def test_start_up_samples_are_not_sensor_faults(loop: str, sensor_delay: int) -> None:
    spec = RunSpec("E1", "pi", plant="planar", loop=loop, latency=(sensor_delay, 1), duration_s=1.0)
    result = run_spec(spec)
    # the first sensor_delay samples consumed are the queue's start-up filling (no measurement)
    assert np.all(np.isnan(result.force[:sensor_delay, 2]))
    assert np.all(np.isfinite(result.force[sensor_delay:, 2]))
    assert result.faults == 0


def test_every_missing_sample_after_start_up_is_still_a_fault() -> None:
    exp = experiment("E1")
    result = run(exp, "planar", "pi", faults=fault("nan", 3), duration_s=2.5, seed=3)
    controlled = np.asarray(exp.selection, dtype=bool)
    missing = ~np.all(np.isfinite(result.force[:, controlled]), axis=1)
    sd = result.latency_periods[0]
    assert missing[:sd].all() and missing[sd:].sum() > 0
    # no spike can be rejected in this run (no spike fault): faults = missing samples after start-up
    assert result.faults == int(missing[sd:].sum())
    compiled = run_spec(
        RunSpec("E1", "pi", plant="planar", loop="compiled", fault="nan", seed=3, duration_s=2.5)
    )
    assert compiled.faults == result.faults


def test_fail_on_trip_exit_status(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    base = ["simulate", "E1", "--controller", "pi"]
    assert main([*base, "--stiffness", "100", "--fail-on-trip", "--json"]) == EXIT_TRIPPED == 3
    assert json.loads(capsys.readouterr().out)["tripped"] is True  # everything still printed
    assert main([*base, "--stiffness", "100", "--json"]) == 0  # only on request
    capsys.readouterr()
    assert main([*base, "--fail-on-trip"]) == 0  # no trip, no failure
    capsys.readouterr()
    table = tmp_path / "runs.csv"
    sweep = ["sweep", "E1", "--controller", "pi", "--stiffness", "10,100", "--duration", "2.5"]
    args = [*sweep, "--out", str(table), "--workers", "1", "--quiet", "--fail-on-trip"]
    assert main(args) == EXIT_TRIPPED
    assert "1 of 2 runs tripped the safety limit" in capsys.readouterr().out
    assert table.exists()
    assert "exit with status 3 when a run tripped" in _subparser("compare").format_help()


def test_export_errors_name_the_cli_option(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "pi.fis"
    assert main(["export", "sugeno_pi", "--format", "fis", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "give --allow-loss to export anyway" in err
    assert "allow_loss=True" not in err and not out.exists()
    assert main(["export", "sugeno_pi", "--format", "fis", "--out", str(out), "--allow-loss"]) == 0
    assert out.exists()


@pytest.mark.parametrize("method", ["table", "exact"])
def test_generated_python_eval_takes_inputs_by_name(
    method: str, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    from fuzzkit.formats.registry import load
    from fuzzkit.fuzzy.inference import Engine

    out = tmp_path / method
    args = ["compile", "three_input", "--target", "python", "--method", method, "--out", str(out)]
    args += ["--tolerance", "0.05"] if method == "table" else []
    assert main([*args, "--quiet"]) == 0
    capsys.readouterr()
    monkeypatch.syspath_prepend(str(out))
    sys.modules.pop("three_input", None)
    mod = importlib.import_module("three_input")
    engine = Engine(load("three_input"))
    bound = 0.06 if method == "table" else 1e-9
    for point in ({"e": 0.1, "de": -0.4, "r": 0.7}, {"r": 0.2, "de": 0.9, "e": -0.3}):
        by_name = mod.eval(point)
        assert by_name == mod.eval(tuple(point[n] for n in mod.INPUT_NAMES))
        exact = engine.evaluate_point(point)
        # the table: its stated bound (--tolerance 0.05); the exact method: the engine's numbers
        assert by_name == pytest.approx(tuple(exact.values()), abs=bound)
    with pytest.raises(ValueError, match=r"missing r; unknown x"):
        mod.eval({"e": 0.1, "de": 0.2, "x": 1.0})
    sys.modules.pop("three_input", None)


def test_a_shipped_scenario_copied_out_runs_as_the_shipped_one(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["scenario", "E1"]) == 0
    Path("my_task.yaml").write_text(capsys.readouterr().out, encoding="utf-8")
    assert main(["validate", "my_task.yaml"]) == 0
    capsys.readouterr()
    assert main(["simulate", "./my_task.yaml", "--controller", "pi", "--json"]) == 0
    mine = json.loads(capsys.readouterr().out)
    assert main(["simulate", "E1", "--controller", "pi", "--json"]) == 0
    shipped = json.loads(capsys.readouterr().out)
    assert mine["axes"] == shipped["axes"]
    assert main(["scenario"]) == 0 and "E2  straight path" in capsys.readouterr().out
    assert main(["scenario", "E7"]) == 2
    assert "no shipped scenario 'E7'" in capsys.readouterr().err


def test_compare_runs_at_the_latency_it_is_given(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["compare", "E1", "--latency", "3", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["latency_periods"] for r in rows] == [[3, 1], [3, 1]]  # as simulate --latency 3
    assert main(["compare", "E1", "--latency", "0,2", "--json"]) == 0
    assert {tuple(r["latency_periods"]) for r in json.loads(capsys.readouterr().out)} == {(0, 2)}
