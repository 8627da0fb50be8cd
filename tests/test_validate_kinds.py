"""``fuzzkit validate`` reads every kind of file the kit reads, recognised by content."""

from __future__ import annotations

from pathlib import Path

import pytest

from fuzzkit.cli import main
from fuzzkit.cli.file_kinds import KINDS, recognise
from fuzzkit.errors import ProblemsError
from fuzzkit.studies.scenario_file import shipped_scenario_text

EXAMPLES = Path(__file__).resolve().parent.parent / "docs" / "examples"
FOREIGN = ("heater.fis", "heater_sugeno.fis", "gripper_iec.fcl", "gripper_named.fcl", "feed.fll")


def _validate(capsys: pytest.CaptureFixture[str], *files: str) -> tuple[int, str, str]:
    code = main(["validate", *files])
    out, err = capsys.readouterr()
    return code, out, err


def test_every_kind_in_every_format_is_recognised_and_checked(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    task = tmp_path / "my_task.yaml"
    task.write_text(shipped_scenario_text("E2"), encoding="utf-8")
    files = [*(str(EXAMPLES / n) for n in FOREIGN), "macvicar_whelan", "E1", str(task)]
    code, out, err = _validate(capsys, *files)
    assert code == 0, err
    lines = out.splitlines()
    assert f"{EXAMPLES / 'heater.fis'}: ok (rule base heater: 2 inputs, 1 output, 6 rules)" in lines
    assert "macvicar_whelan: ok (rule base macvicar_whelan: 2 inputs, 1 output, 49 rules)" in lines
    assert "E1: ok (scenario E1: 5 s, force control x 0 N, z 10 N, safety limit 25 N)" in lines
    assert f"{task}: ok (scenario E2: 12.5 s, force control z 30 N, safety limit 60 N)" in lines


def test_content_not_the_suffix_decides(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    fis = tmp_path / "heater.txt"
    fis.write_text((EXAMPLES / "heater.fis").read_text(encoding="utf-8"), encoding="utf-8")
    scenario = tmp_path / "task.yml"
    scenario.write_text(shipped_scenario_text("E3"), encoding="utf-8")
    assert recognise(str(fis)) == (KINDS[0], ".fis")
    assert recognise(str(scenario))[0].name == "scenario"
    code, out, err = _validate(capsys, str(fis), str(scenario))
    assert code == 0, err
    assert f"{fis}: ok (rule base heater:" in out and f"{scenario}: ok (scenario E3:" in out


def test_a_bad_scenario_gets_every_problem_located(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "task.yaml"
    text = shipped_scenario_text("E1").replace("  z: 10.0", "  q: 10.0")
    text = text.replace("safety_limit_n: 25.0", "safety_limit_n: -3")
    bad.write_text(text, encoding="utf-8")
    line_q = text.splitlines().index("  q: 10.0") + 1
    line_limit = text.splitlines().index("safety_limit_n: -3") + 1
    code, out, err = _validate(capsys, str(bad))
    assert code == 2 and out == ""
    lines = err.splitlines()
    assert any(line.startswith(f"{bad}:{line_q}:3: unknown key 'q'") for line in lines), err
    assert any(line.startswith(f"{bad}:{line_limit}:17: ") for line in lines), err
    assert lines[-1] == "fuzzkit: error: 1 of 1 file invalid"
    assert "Traceback" not in err


def test_a_bad_foreign_rule_base_is_located(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = (EXAMPLES / "heater.fis").read_text(encoding="utf-8")
    bad = tmp_path / "heater.fis"
    bad.write_text(text.replace("NumInputs=2", "NumInputs=two"), encoding="utf-8")
    line = text.splitlines().index("NumInputs=2") + 1
    code, _, err = _validate(capsys, str(bad))
    assert code == 2
    assert err.startswith(f"{bad}:{line}:"), err


def test_a_file_of_no_known_kind_says_what_each_kind_looks_like(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    other = tmp_path / "gains.yaml"
    other.write_text("kp: 0.1\nki: 0.2\n", encoding="utf-8")
    with pytest.raises(ProblemsError, match="not a file fuzzkit reads"):
        recognise(str(other))
    code, _, err = _validate(capsys, str(other), str(tmp_path))
    assert code == 2
    assert f"{other}:1:1: not a file fuzzkit reads (found ki, kp); expected a rule base (" in err
    assert "a scenario (" in err
    assert f"{tmp_path}: is a folder (expected a file)" in err


def test_each_kind_recognises_its_own_shipped_files() -> None:
    for kind in KINDS:
        for name in kind.shipped():
            assert recognise(name)[0] is kind


def test_a_controller_spec_is_one_more_kind() -> None:
    spec = EXAMPLES / "controller.yaml"
    assert recognise(str(spec))[0].name == "controller spec"
    assert [k.name for k in KINDS] == ["rule base", "scenario", "controller spec"]
