"""``fuzzkit validate | info | eval | surface | schema`` as a user runs them."""

from __future__ import annotations

import csv
import io
import json
import math
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from fuzzkit import evaluate_point, load
from fuzzkit.cli import main

ROOT = Path(__file__).resolve().parent.parent
GOOD = ROOT / "rulebases" / "macvicar_whelan.yaml"

BAD = """\
name: bad
inputs:
  e: {range: [1, -1], terms: {partition: triangular, labels: [N, P]}}
outputs:
  du: {range: [-1, 1], terms: {partition: triangular, labels: [N, P]}}
rules:
  - {if: {e: X}, then: {du: N}}
"""


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    try:
        code = main(list(argv))
    except SystemExit as exc:  # a value argparse refuses at the option
        code = int(exc.code or 0)
    out, err = capsys.readouterr()
    return code, out, err


# --------------------------------------------------------------------------- validate


def test_validate_accepts_paths_and_names(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, "validate", str(GOOD), "paper_table1")
    assert code == 0, err
    assert f"{GOOD}: ok (rule base macvicar_whelan: 2 inputs, 1 output, 49 rules)" in out
    assert "paper_table1: ok" in out


def test_validate_lists_every_problem_of_every_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(BAD)
    worse = tmp_path / "worse.yaml"
    worse.write_text("name: x\ninputs: 3\n")
    code, out, err = run(capsys, "validate", str(bad), str(GOOD), str(worse))
    assert code == 2
    assert f"{GOOD}: ok" in out
    lines = err.splitlines()
    assert f"{bad}:3:14: range must be [low, high] with finite low < high, got [1.0, -1.0]" in lines
    assert any(line.startswith(f"{bad}:7:14: unknown label 'X' for input 'e'") for line in lines)
    inputs_msg = "expected the inputs (a mapping of name to {range, terms}), got 3"
    assert f"{worse}:2:9: {inputs_msg}" in lines
    assert any(f"{worse}:1:1: missing required key 'outputs'" in line for line in lines)
    assert lines[-1] == "fuzzkit: error: 2 of 3 files invalid"
    assert "Traceback" not in err


def test_validate_missing_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run(capsys, "validate", str(tmp_path / "nope.yaml"))
    assert code == 2
    assert "nope.yaml: cannot read: No such file or directory" in err


# --------------------------------------------------------------------------- info


def test_info_prints_variables_terms_and_the_table_grid(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code, out, _ = run(capsys, "info", "paper_table1")
    assert code == 0
    assert "e  [-1, 1]" in out
    assert "NL  left_shoulder  a=-1 b=-0.666667" in out
    assert "NL  triangle       a=-1.33333 b=-1 c=-0.666667" in out
    assert "operators: and=min or=max implication=min aggregation=max" in out
    lines = out.splitlines()
    grid = lines[next(i for i, line in enumerate(lines) if "e\\de" in line) :]
    assert grid[0].split() == ["e\\de", "NL", "NM", "NS", "ZR", "PS", "PM", "PL"]
    assert grid[1].split() == ["PL", "NL", "NM", "NS", "ZR", "PM", "PL", "PL"]  # printed order
    assert grid[7].split() == ["NL", "NL", "NL", "NM", "ZR", "PS", "PM", "PL"]
    # aligned: every cell of a column starts at the same offset
    starts = {tuple(m.start() for m in re.finditer(r"\S+", line)) for line in grid[:8]}
    assert len(starts) == 1


def test_info_prints_list_rules_readably(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "info", "three_input")
    assert code == 0
    assert "   4. if (e is P and de is Z) or (e is Z and de is P) then du is PS" in out
    assert "   8. if r is medium and e is not Z then dv is slower  (weight 0.5)" in out
    assert "smooth  sigmoid        slope=-12 centre=0.4" in out
    assert "du  [-1, 1]  default 0" in out


def test_info_unknown_name_is_one_clear_line(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run(capsys, "info", "macvicar")
    assert code == 2
    assert err.startswith("fuzzkit: error: macvicar: no shipped rule base or file called")
    assert "did you mean 'macvicar_whelan'?" in err


# --------------------------------------------------------------------------- eval


def test_eval_point_text_and_json(capsys: pytest.CaptureFixture[str]) -> None:
    expected = evaluate_point(load("macvicar_whelan"), e=0.3, de=-0.2)["du"]
    code, out, _ = run(capsys, "eval", "macvicar_whelan", "--input", "e=0.3", "-i", "de=-0.2")
    assert code == 0
    assert out == f"du = {expected!r}\n"
    code, out, _ = run(capsys, "eval", str(GOOD), "-i", "e=0.3", "-i", "de=-0.2", "--json")
    assert code == 0
    assert json.loads(out) == {"inputs": {"e": 0.3, "de": -0.2}, "outputs": {"du": expected}}


def test_eval_nan_input_gives_null_in_json(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "eval", "macvicar_whelan", "-i", "e=nan", "-i", "de=0", "--json")
    assert code == 0
    assert json.loads(out) == {"inputs": {"e": None, "de": 0.0}, "outputs": {"du": None}}


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["-i", "e=0.3"], "missing --input for de"),
        (["-i", "e=0.3", "-i", "dx=1"], "unknown input 'dx' (did you mean 'de'?)"),
        (["-i", "e=abc", "-i", "de=0"], "expected a number for 'e', got 'abc'"),
        (["-i", "e0.3", "-i", "de=0"], "--input 'e0.3': expected NAME=VALUE"),
        (["-i", "e=1", "-i", "e=2", "-i", "de=0"], "input 'e' given twice"),
    ],
)
def test_eval_bad_inputs(capsys: pytest.CaptureFixture[str], args: list[str], message: str) -> None:
    code, out, err = run(capsys, "eval", "macvicar_whelan", *args)
    assert code == 2
    assert out == ""
    assert err.startswith("fuzzkit: error: ") and message in err


def test_eval_points_csv_appends_outputs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    points = tmp_path / "p.csv"
    points.write_text("id,de,e\nA,0.1,-0.5\nB,-0.2,0.3\nC,0,nan\n\nD,1,1\n")
    code, out, err = run(capsys, "eval", "macvicar_whelan", "--points", str(points))
    assert code == 0, err
    rows = list(csv.reader(io.StringIO(out)))
    assert rows[0] == ["id", "de", "e", "du"]
    assert [r[:3] for r in rows[1:]] == [
        ["A", "0.1", "-0.5"],
        ["B", "-0.2", "0.3"],
        ["C", "0", "nan"],
        ["D", "1", "1"],
    ]
    rb = load("macvicar_whelan")
    for row in rows[1:]:
        expected = evaluate_point(rb, e=float(row[2]), de=float(row[1]))["du"]
        got = float(row[3])
        # the CSV path evaluates in batch, evaluate_point on the scalar path: same to rounding
        assert (math.isnan(got) and math.isnan(expected)) or abs(got - expected) < 1e-13


def test_eval_points_with_two_outputs(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    points = tmp_path / "p.csv"
    points.write_text("e,de,r\n0,0,0.05\n")
    code, out, _ = run(capsys, "eval", "three_input", "--points", str(points))
    assert code == 0
    header, row = list(csv.reader(io.StringIO(out)))
    assert header == ["e", "de", "r", "du", "dv"]
    expected = evaluate_point(load("three_input"), e=0.0, de=0.0, r=0.05)
    # du is 0 by symmetry at e = de = 0; the engine's -1.2e-15 is rounding noise, printed as 0
    assert float(row[3]) == 0.0 and abs(expected["du"]) < 1e-14
    assert float(row[4]) == expected["dv"]


def test_eval_points_unreadable(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run(capsys, "eval", "macvicar_whelan", "--points", str(tmp_path / "no.csv"))
    assert code == 2 and "no.csv: cannot read: No such file or directory" in err
    code, _, err = run(capsys, "eval", "macvicar_whelan", "--points", str(tmp_path))
    assert code == 2 and "is a directory (expected a CSV file)" in err


@pytest.mark.parametrize(
    ("text", "messages"),
    [
        ("e,x\n0,1\n", ["p.csv:1: missing column de"]),
        ("", ["p.csv: CSV file is empty"]),
        (
            "e,de\n0.1,0.2\n0.3\n0.5,zz\nabc,1\n",
            [
                "p.csv:3: expected 2 cells, got 1",
                "p.csv:4: expected a number for 'de', got 'zz'",
                "p.csv:5: expected a number for 'e', got 'abc'",
            ],
        ),
        ("e,de,du\n0,0,0\n", ["p.csv:1: column du would be overwritten"]),
    ],
)
def test_eval_points_bad_csv_names_the_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, messages: list[str]
) -> None:
    points = tmp_path / "p.csv"
    points.write_text(text)
    code, out, err = run(capsys, "eval", "macvicar_whelan", "--points", str(points))
    assert code == 2
    assert out == ""
    for message in messages:
        assert f"{tmp_path}{os.sep}{message}" in err
    assert "Traceback" not in err


# --------------------------------------------------------------------------- surface, schema


def test_surface_writes_rrd_and_png(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rrd, png = tmp_path / "s.rrd", tmp_path / "s.png"
    code, out, err = run(
        capsys, "surface", "macvicar_whelan", "--rrd", str(rrd), "--png", str(png),
        "--resolution", "21",
    )  # fmt: skip
    assert code == 0, err
    assert rrd.stat().st_size > 1000
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "du at the label peaks (49 points): min -0.888889, max 0.888889" in out
    lines = out.splitlines()
    grid = lines[lines.index(next(x for x in lines if "e\\de" in x)) :]
    assert grid[0].split() == ["e\\de", "NL", "NM", "NS", "ZR", "PS", "PM", "PL"]
    # Row e=ZR is the table's middle row: du = de's label centre (outer ones clipped: 8/9).
    assert grid[4].split() == ["ZR", "-0.8889", "-0.6667", "-0.3333", "+0.0000", "+0.3333",
                               "+0.6667", "+0.8889"]  # fmt: skip
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.png", "s.rrd"]  # no temp files


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["three_input", "--rrd", "x.rrd"], "needs a rule base with exactly 2 inputs"),
        (["macvicar_whelan"], "nothing to write"),
        (["macvicar_whelan", "--rrd", "x.png"], "expected a file name ending in .rrd"),
        (["macvicar_whelan", "--rrd", "x.rrd", "--resolution", "1"], "from 2 to 1001"),
        (["macvicar_whelan", "--rrd", "x.rrd", "--output", "dv"], "unknown output 'dv'"),
        (["macvicar_whelan", "--rrd", "no/such/dir/x.rrd"], "does not exist"),
    ],
)
def test_surface_errors(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    args: list[str],
    message: str,
) -> None:
    monkeypatch.chdir(tmp_path)
    code, _, err = run(capsys, "surface", *args)
    assert code == 2
    assert message in err
    assert list(tmp_path.iterdir()) == []  # nothing half-written


def test_schema_prints_json(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "schema")
    assert code == 0
    schema = json.loads(out)
    assert schema["$schema"].endswith("2020-12/schema")
    assert "macvicar" not in out


# --------------------------------------------------------------------------- console script


def test_console_script_runs_end_to_end(tmp_path: Path) -> None:
    exe = shutil.which("fuzzkit", path=str(Path(sys.executable).parent))
    argv = [exe] if exe else [sys.executable, "-m", "fuzzkit.cli"]
    bad = tmp_path / "bad.yaml"
    bad.write_text(BAD)
    ok = subprocess.run(
        [*argv, "eval", "macvicar_whelan", "-i", "e=0.3", "-i", "de=-0.2", "--json"],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert ok.returncode == 0, ok.stderr
    assert json.loads(ok.stdout)["outputs"]["du"] == pytest.approx(
        evaluate_point(load("macvicar_whelan"), e=0.3, de=-0.2)["du"], abs=0
    )
    failed = subprocess.run(
        [*argv, "validate", str(bad)], capture_output=True, text=True, timeout=60
    )
    assert failed.returncode == 2
    assert "Traceback" not in failed.stderr
    assert f"{bad}:3:14: range must be" in failed.stderr


def test_eval_points_oversized_csv_field_is_a_located_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    csv_path = tmp_path / "big.csv"
    csv_path.write_text("e,de\n0.1,0.2\n1," + "x" * 200_000 + "\n")
    code, out, err = run(capsys, "eval", "macvicar_whelan", "--points", str(csv_path))
    assert code == 2 and out == ""
    assert f"{csv_path}:3: bad CSV: field larger than field limit" in err
    assert "Traceback" not in err


def test_surface_checks_every_output_before_writing_any(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rrd = tmp_path / "s.rrd"
    code, _, err = run(
        capsys, "surface", "macvicar_whelan", "--rrd", str(rrd), "--png", str(tmp_path / "no/s.png")
    )
    assert code == 2 and "does not exist" in err
    assert list(tmp_path.iterdir()) == []  # the .rrd was not written either
