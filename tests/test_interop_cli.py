"""``fuzzkit import | export`` and every other command on .fis/.fcl/.fll files."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from fuzzkit.cli import main
from fuzzkit.formats.registry import load

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "docs" / "examples"


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("name", ["heater.fis", "gripper_iec.fcl", "feed.fll"])
def test_import_writes_yaml_that_loads_to_the_same_rule_base(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "rb.yaml"
    code, _, err = run(capsys, "import", str(EXAMPLES / name), "--out", str(out))
    assert code == 0, err
    assert load(out) == load(EXAMPLES / name)


def test_import_refuses_a_bad_file_and_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.fis"
    bad.write_text((EXAMPLES / "heater.fis").read_text().replace("'sigmf'", "'cosinemf'", 1))
    out = tmp_path / "rb.yaml"
    code, _, err = run(capsys, "import", str(bad), "--out", str(out))
    assert code == 2
    assert f"{bad}:26:5: [Input2] MF1 ('falling'): membership function 'cosinemf'" in err
    assert "Traceback" not in err
    assert not out.exists() and list(tmp_path.iterdir()) == [bad]


def test_import_needs_a_foreign_extension(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, _, err = run(
        capsys,
        "import",
        str(ROOT / "rulebases" / "gaussian5.yaml"),
        "--out",
        str(tmp_path / "x.yaml"),
    )
    assert code == 2 and "expected a .fis, .fcl or .fll file, got '.yaml'" in err


@pytest.mark.parametrize(
    "fmt, name", [("fis", "heater.fis"), ("fcl", "gripper_named.fcl"), ("fll", "feed.fll")]
)
def test_export_then_import_gives_back_the_rule_base(
    fmt: str, name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    src = EXAMPLES / name
    out = tmp_path / f"g.{fmt}"
    code, _, err = run(capsys, "export", str(src), "--format", fmt, "--out", str(out))
    assert code == 0, err
    assert load(out) == load(src)


def test_export_refusal_lists_what_is_lost_and_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "mw.fis"
    code, _, err = run(capsys, "export", "macvicar_whelan", "--format", "fis", "--out", str(out))
    assert code == 2
    assert "out_of_range: clamp" in err and "--allow-loss" in err
    assert not out.exists() and list(tmp_path.iterdir()) == []
    code, _, err = run(
        capsys, "export", "macvicar_whelan", "--format", "fis", "--allow-loss", "--out", str(out)
    )
    assert code == 0 and "warning" in err and out.exists()


def test_export_iec_dialect_refuses_smooth_terms(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "g.fcl"
    code, _, err = run(
        capsys,
        "export",
        "gaussian5",
        "--format",
        "fcl",
        "--dialect",
        "iec",
        "--allow-loss",
        "--out",
        str(out),
    )
    assert code == 2 and "IEC point lists draw piecewise-linear terms only" in err
    assert not out.exists()


def test_validate_info_and_eval_read_foreign_files(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    files = [str(EXAMPLES / n) for n in ("heater.fis", "gripper_iec.fcl", "feed.fll")]
    code, out, err = run(capsys, "validate", *files)
    assert code == 0, err
    assert "heater.fis: ok (rule base heater: 2 inputs, 1 output, 6 rules)" in out
    code, out, _ = run(capsys, "info", files[0])
    assert code == 0 and "left_shoulder" in out and "out_of_range: extend" in out
    code, out, _ = run(capsys, "eval", files[2], "-i", "roughness=0.5", "-i", "load=5", "--json")
    assert code == 0
    expected = load(files[2])
    from fuzzkit.fuzzy.inference import evaluate_point

    assert json.loads(out)["outputs"]["feed"] == pytest.approx(
        evaluate_point(expected, {"roughness": 0.5, "load": 5.0})["feed"], abs=1e-15
    )
    points = tmp_path / "p.csv"
    points.write_text("slip,force_err\n0.1,-1\n0.9,3\n")
    code, out, err = run(capsys, "eval", files[1], "--points", str(points))
    assert code == 0, err
    assert out.splitlines()[0] == "slip,force_err,grip" and len(out.splitlines()) == 3


def test_surface_and_compile_read_foreign_files(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    python_verify_points: None,
) -> None:
    src = str(EXAMPLES / "heater.fis")
    png = tmp_path / "s.png"
    code, _, err = run(capsys, "surface", src, "--png", str(png), "--resolution", "21")
    assert code == 0, err
    assert png.stat().st_size > 0
    # a lookup table clamps its inputs, which MATLAB does not: --method table refuses, saying
    # so, and auto takes the exact method, which evaluates the terms where the input is
    code, _, err = run(
        capsys, "compile", src, "--target", "python", "--method", "table",
        "--out", str(tmp_path / "no"),
    )  # fmt: skip
    assert code == 2 and "out_of_range is 'extend'" in err
    code, out, err = run(
        capsys, "compile", src, "--target", "python", "--out", str(tmp_path / "exact"), "--verify"
    )
    assert code == 0, err
    assert "because no table can be made: out_of_range is 'extend'" in out
    src = str(EXAMPLES / "feed.fll")  # lock-range: true, so clamped like the table
    code, _, err = run(
        capsys,
        "compile",
        src,
        "--target",
        "python",
        "--tolerance",
        "0.01",
        "--out",
        str(tmp_path / "gen"),
        "--verify",
    )
    assert code == 0, err
    assert (tmp_path / "gen" / "feed.py").exists()


@pytest.mark.slow
def test_simulate_takes_an_fll_rule_base(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    fll = tmp_path / "mw.fll"
    code, _, err = run(capsys, "export", "macvicar_whelan", "--format", "fll", "--out", str(fll))
    assert code == 0, err
    code, out, err = run(
        capsys,
        "simulate",
        "E2",
        "--controller",
        "fuzzy-pi",
        "--rulebase",
        str(fll),
        "--plant",
        "planar",
        "--json",
    )
    assert code == 0, err
    ours = json.loads(out)
    code, out, err = run(
        capsys,
        "simulate",
        "E2",
        "--controller",
        "fuzzy-pi",
        "--rulebase",
        "macvicar_whelan",
        "--plant",
        "planar",
        "--json",
    )
    theirs = json.loads(out)
    for metrics in (ours, theirs):
        # timing, and which file the controller came from, are not results of the run
        for key in ("wall_time_s", "cpu_time_s", "real_time_factor", "controller_impl", "rulebase"):
            metrics.pop(key)
    assert theirs == ours  # the same rule base, so the same run


def test_plot_draws_a_foreign_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    png = tmp_path / "mf.png"
    code, _, err = run(capsys, "plot", str(EXAMPLES / "feed.fll"), "--out", str(png))
    assert code == 0, err
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    second = tmp_path / "missing.png"
    code, _, err = run(capsys, "plot", str(tmp_path / "missing.fis"), "--out", str(second))
    assert code == 2 and "missing.fis: cannot read" in err
    assert not second.exists()


GAPPY_FIS = """[System]
Name='tipper'
Type='mamdani'
Version=2.0
NumInputs=1
NumOutputs=1
NumRules=2
AndMethod='min'
OrMethod='max'
ImpMethod='min'
AggMethod='max'
DefuzzMethod='centroid'

[Input1]
Name='food'
Range=[0 10]
NumMFs=2
MF1='rancid':'trapmf',[0 0 1 3]
MF2='delicious':'trapmf',[7 9 10 10]

[Output1]
Name='tip'
Range=[0 30]
NumMFs=2
MF1='cheap':'trimf',[0 5 10]
MF2='generous':'trimf',[20 25 30]

[Rules]
1, 1 (1) : 1
2, 2 (1) : 1
"""


def test_a_coverage_gap_in_an_imported_file_is_a_located_warning(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Like MATLAB's tipper: no term of 'food' is above zero on (3, 7). The file imports and
    # evaluates (the gap gives the output's default: mid-range for .fis); validate warns,
    # --strict refuses.
    from fuzzkit.cli import main
    from fuzzkit.formats.registry import load_with_warnings

    path = tmp_path / "tipper.fis"
    path.write_text(GAPPY_FIS)
    rb, warnings = load_with_warnings(path)
    assert rb.coverage == "allow_gaps"
    assert len(warnings) == 1 and warnings[0].severity == "warning"
    assert warnings[0].location.line > 0 and "not covered on [3.0, 7.0]" in warnings[0].message
    assert main(["validate", str(path)]) == 0
    out = capsys.readouterr()
    assert "warning" in out.out + out.err and "tipper.fis:" in out.out + out.err
    assert main(["validate", "--strict", str(path)]) == 2
    from fuzzkit.fuzzy.inference import evaluate_point

    assert evaluate_point(rb, food=5.0)["tip"] == 15.0  # the .fis default: mid-range


def test_compile_takes_a_fis_file_exactly_and_refuses_only_a_table(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """interop.md: an unclamped (.fis) rule base compiles by the exact method, inputs out of
    range evaluated where they are (as MATLAB's evalfis); a lookup table, which clamps, is
    refused."""
    import importlib.util
    import math

    from fuzzkit.fuzzy.inference import evaluate_point

    src = str(EXAMPLES / "heater.fis")
    out = tmp_path / "gen"
    # (the same command with --verify passes in test_surface_and_compile_read_foreign_files)
    code, stdout, err = run(capsys, "compile", src, "--target", "python", "--out", str(out))
    assert code == 0 and "wrote" in stdout, err
    spec = importlib.util.spec_from_file_location("heater_gen", out / "heater.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    rb = load(EXAMPLES / "heater.fis")
    assert rb.out_of_range == "extend"
    for err_c, rate in [(14.0, 0.5), (0.0, -2.6), (5.0, 3.0)]:  # outside [-10, 10] x [-2, 2]
        want = evaluate_point(rb, {"err": err_c, "rate": rate})["power"]
        (got,) = module.eval({"err": err_c, "rate": rate})
        assert math.isclose(got, want, rel_tol=0, abs_tol=1e-9)
    # where extending differs from clamping, the compiled module extends
    clamped = evaluate_point(rb, {"err": 0.0, "rate": -2.0})["power"]
    (got,) = module.eval({"err": 0.0, "rate": -2.6})
    assert abs(got - clamped) > 0.05
    code, _, err = run(
        capsys, "compile", src, "--target", "c", "--method", "table", "--out", str(tmp_path / "t")
    )
    assert code == 2 and "a lookup table clamps its inputs" in err
    assert not (tmp_path / "t").exists()
