"""``fuzzkit validate`` reads every kind of file the kit reads, recognised by content."""

from __future__ import annotations

from pathlib import Path

import pytest

from fuzzkit.cli import main
from fuzzkit.cli.file_kinds import KINDS, recognise
from fuzzkit.errors import ProblemsError
from fuzzkit.studies.scenario_file import shipped_scenario_text

EXAMPLES = Path(__file__).resolve().parent.parent / "docs" / "examples"
SPEC = EXAMPLES / "controller.yaml"
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
    other = tmp_path / "colours.yaml"  # (a gains file was the example here before it was a kind)
    other.write_text("colour: blue\nsize: 3\n", encoding="utf-8")
    with pytest.raises(ProblemsError, match="not a file fuzzkit reads"):
        recognise(str(other))
    code, _, err = _validate(capsys, str(other), str(tmp_path))
    assert code == 2
    found = "not a file fuzzkit reads (found colour, size); expected a rule base ("
    assert f"{other}:1:1: {found}" in err
    assert "a scenario (" in err
    assert f"{tmp_path}: is a folder (expected a file)" in err


def test_each_kind_recognises_its_own_shipped_files() -> None:
    for kind in KINDS:
        for name in kind.shipped():
            assert recognise(name)[0] is kind


def test_a_controller_spec_is_one_more_kind() -> None:
    spec = EXAMPLES / "controller.yaml"
    assert recognise(str(spec))[0].name == "controller spec"
    assert [k.name for k in KINDS] == ["rule base", "scenario", "controller spec", "gains file"]


# ------------------------------------------------------------------ gains files, and wrong kinds
# (issue 33 item 2: `info` on a spec and `validate` on a gains file reported rule-base errors)

GAINS = "fuzzy-pi:\n  gains: {kp: 0.3, ki: 0.06, kx: 0.0002}\npi:\n  kp: 4.0e-5\n  ki: 1.0e-5\n"


def _write(tmp_path: Path, name: str, text: str) -> str:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return str(path)


@pytest.mark.parametrize(
    "text, summary",
    [
        (GAINS, "gains file: pi (kp=4e-05, ki=1e-05); fuzzy-pi (kp=0.3, ki=0.06, kx=0.0002)"),
        ("kp: 4.0e-5\nki: 1.0e-5\n", "gains file: any controller (kp=4e-05, ki=1e-05)"),
    ],
)
def test_validate_recognises_a_gains_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, summary: str
) -> None:
    path = _write(tmp_path, "gains.yaml", text)
    assert main(["validate", path]) == 0
    assert capsys.readouterr().out.strip() == f"{path}: ok ({summary})"


def test_a_bad_gains_file_gets_every_problem_located(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _write(
        tmp_path, "gains.yaml", "fuzzy-pi:\n  gains: {kp: -0.3, ki: 0.06, kz: 1}\npi:\n  ki: .nan\n"
    )
    assert main(["validate", path]) == 2
    err = capsys.readouterr().err
    assert f"{path}:2:" in err and "gain kp must be > 0" in err
    assert "unknown gain 'kz'" in err
    assert f"{path}:4:" in err and "finite number" in err
    assert "rule base" not in err and "defuzzifier" not in err


@pytest.mark.parametrize(
    "argv, kind",
    [
        (["eval", "{gains}", "-i", "e=0", "-i", "de=0"], "gains file"),
        (["eval", str(SPEC), "-i", "e=0"], "controller spec"),
        (["plot", "E1", "--png", "{png}"], "scenario"),
        (["surface", "{gains}", "--png", "{png}"], "gains file"),
    ],
)
def test_a_rule_base_command_given_another_kind_says_what_it_got(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str], kind: str
) -> None:
    gains = _write(tmp_path, "gains.yaml", GAINS)
    png = tmp_path / "x.png"
    args = [a.format(gains=gains, png=png) for a in argv]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert f"is a {kind}, not a rule base (fuzzkit {args[0]} reads rule bases" in err
    assert "did you mean" not in err and "Traceback" not in err
    assert not png.exists()
    if kind == "controller spec":
        assert "its rule base is macvicar_whelan: fuzzkit eval macvicar_whelan" in err


def test_info_names_and_summarises_every_kind(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    gains = _write(tmp_path, "gains.yaml", GAINS)
    assert main(["info", gains]) == 0
    assert capsys.readouterr().out.startswith(f"{gains}: gains file: pi (kp=4e-05")
    assert main(["info", "E1"]) == 0
    assert capsys.readouterr().out.startswith("E1: scenario E1: 5 s, force control x 0 N, z 10 N")
    assert main(["info", str(SPEC)]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"{SPEC}: controller spec e1_fuzzy: fuzzy-pi on macvicar_whelan")
    assert "macvicar_whelan  (" in out  # its rule base, described
    assert "unknown key" not in out
