"""``fuzzkit compile``: outputs, --verify, --gains, and bad input that writes nothing."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest
from _codegen_util import needs_cc, skip_no_cc

from fuzzkit.cli import main


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    try:
        code = main(list(argv))
    except SystemExit as exc:  # argparse usage errors
        code = int(exc.code or 0)
    out, err = capsys.readouterr()
    return code, out, err


def test_python_target_writes_an_importable_module(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "gen"
    code, text, _ = _run(
        capsys,
        "compile",
        "macvicar_whelan",
        "--target",
        "python",
        "--resolution",
        "25",
        "--out",
        str(out),
        "--verify",
    )
    assert code == 0, text
    assert "table 25x25" in text and "verified bound du:" in text
    assert "verify python: ok" in text
    spec = importlib.util.spec_from_file_location("mw_cli", out / "macvicar_whelan.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert len(module.eval((0.1, 0.2))) == 1


@needs_cc
@skip_no_cc
def test_c_target_with_verify_and_baked_gains(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    gains = tmp_path / "gains.yaml"
    gains.write_text("fuzzy-pi:\n  gains: {kp: 0.5, ki: 0.25, kx: 0.01, u_min: -0.2, u_max: 0.2}\n")
    out = tmp_path / "c"
    code, text, err = _run(
        capsys,
        "compile",
        "macvicar_whelan",
        "--target",
        "c",
        "--type",
        "q15",
        "--resolution",
        "25",
        "--out",
        str(out),
        "--verify",
    )
    assert code == 0, err
    assert "verify c (q15): ok" in text
    assert (
        "macvicar_whelan_fpi_step(macvicar_whelan_fpi_t *c, int16_t setpoint"
        in (out / "macvicar_whelan.h").read_text()
    )
    code, text, err = _run(
        capsys,
        "compile",
        "macvicar_whelan",
        "--target",
        "c",
        "--resolution",
        "25",
        "--out",
        str(out),
        "--gains",
        str(gains),
        "--verify",
    )
    assert code == 0, err
    header = (out / "macvicar_whelan.h").read_text()
    assert "#define MACVICAR_WHELAN_FPI_KI 0.25f" in header
    assert "macvicar_whelan_fpi_init_default" in header


@pytest.mark.parametrize(
    "extra, match",
    [
        (["--target", "fortran"], "unknown target 'fortran'"),
        (["--target", "c", "--type", "int8"], "unknown --type 'int8'"),
        (["--target", "python", "--type", "q15"], "applies to the C target"),
        (["--target", "c", "--tolerance", "-1"], "--tolerance: expected a number in (0, 1]"),
        (["--target", "c", "--method", "table", "--tolerance", "1e-7"], "cannot be met within"),
        (["--target", "c", "--method", "fastest"], "unknown --method 'fastest'"),
        (["--target", "c", "--max-bytes", "0"], "--max-bytes: expected an integer from 1"),
        (["--target", "c", "--type", "q15", "--method", "exact"], "only available as a lookup"),
        (["--target", "c", "--tolerance", "1", "--resolution", "5"], "not allowed with"),
        (["--target", "c", "--resolution", "1"], "--resolution: expected an integer from 2 to"),
    ],
)
def test_bad_input_is_a_clear_error_and_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: list[str], match: str
) -> None:
    out = tmp_path / "out"
    code, _, err = _run(capsys, "compile", "macvicar_whelan", *extra, "--out", str(out))
    assert code == 2
    assert match in err
    assert "Traceback" not in err
    assert not out.exists()


def test_output_folder_that_is_a_file_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    target = tmp_path / "afile"
    target.write_text("keep me")
    code, _, err = _run(capsys, "compile", "macvicar_whelan", "--target", "c", "--out", str(target))
    assert code == 2 and "not a directory" in err
    assert target.read_text() == "keep me"


def test_incomplete_gains_file_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    gains = tmp_path / "g.yaml"
    gains.write_text("kp: 0.5\nki: 0.25\n")
    out = tmp_path / "out"
    code, _, err = _run(
        capsys,
        "compile",
        "macvicar_whelan",
        "--target",
        "python",
        "--out",
        str(out),
        "--gains",
        str(gains),
    )
    assert code == 2 and "missing: kx, u_min, u_max" in err
    assert not out.exists()


def test_three_input_base_compiles_without_fpi(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, text, err = _run(
        capsys,
        "compile",
        "three_input",
        "--target",
        "python",
        "--resolution",
        "9",
        "--out",
        str(tmp_path / "o"),
    )
    assert code == 0, err
    assert "note: no fuzzy-PI API (it needs 2 inputs, three_input has 3)" in text


def test_explicit_tolerance_is_enforced_on_an_explicit_resolution() -> None:
    from fuzzkit import load
    from fuzzkit.codegen.table_search import make_table
    from fuzzkit.errors import CodegenError

    with pytest.raises(CodegenError, match=r"resolution 5 .* does not meet the tolerance"):
        make_table(load("macvicar_whelan"), resolution=5, tolerance=1e-4)


@pytest.mark.parametrize(
    "gains, match",
    [
        ("kp: 1.0e39\nki: 1\nkx: 1\nu_min: -1\nu_max: 1\n", "kp: 1e+39 overflows a C float"),
        ("kp: 0.3\nki: 0.06\nkx: 1e-50\nu_min: -1\nu_max: 1\n", "kx: 1e-50 rounds to 0"),
    ],
)
@pytest.mark.parametrize("number_type", ["float", "q15"])
def test_gains_a_c_float_cannot_hold_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], gains: str, match: str, number_type: str
) -> None:
    # Were emitted as `inff` (does not compile) and `0.0f` (silently no correction).
    path = tmp_path / "g.yaml"
    path.write_text(gains)
    out = tmp_path / "out"
    code, _, err = _run(
        capsys,
        "compile",
        "macvicar_whelan",
        "--target",
        "c",
        "--type",
        number_type,
        "--resolution",
        "9",
        "--out",
        str(out),
        "--gains",
        str(path),
    )
    assert code == 2, err
    assert f"{path}: fuzzy-PI gains out of float range" in err and match in err
    assert "Traceback" not in err
    assert not out.exists()


def test_tiny_gains_are_fine_for_double() -> None:
    from fuzzkit import load
    from fuzzkit.codegen.emit import FpiDefaults, emit
    from fuzzkit.codegen.table_search import make_table

    rb = load("macvicar_whelan")
    tab = make_table(rb, number_type="double", resolution=9)
    files = emit(rb, tab, "c", fpi_defaults=FpiDefaults(1e39, 1.0, 1e-50, -1.0, 1.0))
    assert "#define MACVICAR_WHELAN_FPI_KX 1e-50" in files["macvicar_whelan.h"]


def test_gains_the_generated_controller_does_not_implement_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # rate_limit was silently dropped: the shipped controller differed from the simulated one.
    path = tmp_path / "g.yaml"
    path.write_text(
        "fuzzy-pi:\n  gains: {kp: 0.3, ki: 0.06, kx: 0.01, u_min: -0.05, u_max: 0.05, "
        "rate_limit: 0.001}\n"
    )
    out = tmp_path / "out"
    code, _, err = _run(
        capsys,
        "compile",
        "macvicar_whelan",
        "--target",
        "python",
        "--resolution",
        "9",
        "--out",
        str(out),
        "--gains",
        str(path),
    )
    assert code == 2, err
    assert f"{path}: the generated fuzzy-PI does not implement rate_limit" in err
    assert not out.exists()


def test_cli_gain_keys_are_the_emitters() -> None:
    from fuzzkit.cli import codegen_cmd
    from fuzzkit.codegen.emit import FPI_GAIN_KEYS

    assert codegen_cmd.FPI_GAIN_KEYS == FPI_GAIN_KEYS


@needs_cc
@skip_no_cc
def test_user_rule_base_compiles_with_the_defaults_and_says_why(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "gen"
    code, text, err = _run(
        capsys, "compile", "temperature_pd", "--target", "c", "--out", str(out), "--verify"
    )
    assert code == 0, err
    assert (
        "method: the exact inference, no table (rounding error only), because no table within "
        "--max-bytes 8192 meets the tolerance of 0.1 % of the output range." in text.splitlines()
    )
    assert "verify c exact (float): ok on 100160 points" in text
    assert sorted(p.name for p in out.iterdir()) == ["temperature_pd.c", "temperature_pd.h"]
    assert "no lookup table" in (out / "temperature_pd.c").read_text()


def test_auto_takes_a_table_that_fits_and_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "gen"
    code, text, err = _run(
        capsys, "compile", "macvicar_whelan", "--target", "python", "--tolerance", "0.05",
        "--out", str(out),
    )  # fmt: skip
    assert code == 0, err
    line = next(ln for ln in text.splitlines() if ln.startswith("method: "))
    assert line.startswith("method: a lookup table (error within the verified bound above), ")
    assert "table that meets" not in line and line.endswith(
        "-byte table meets the tolerance of 5 % of the output range within --max-bytes 8192."
    )
    # the tolerance reads the same in the summary line and in the generated header
    summary = next(ln for ln in text.splitlines() if "verified bound" in ln)
    bound = summary.split("verified bound ")[1]
    assert bound.endswith("(tolerance 0.1 = 5 %)")
    assert bound in (out / "macvicar_whelan.py").read_text()


def test_auto_q15_has_no_exact_alternative_so_a_table_over_budget_is_taken_and_said(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # make demo's Q15 step: the table meeting 1e-3 is larger than --max-bytes, and Q15 has no
    # exact method, so auto keeps the table and says it is over the budget.
    out = tmp_path / "gen"
    code, text, err = _run(
        capsys, "compile", "macvicar_whelan", "--target", "c", "--type", "q15",
        "--max-bytes", "4096", "--out", str(out),
    )  # fmt: skip
    assert code == 0, err
    line = next(ln for ln in text.splitlines() if ln.startswith("method: "))
    assert line.startswith("method: a lookup table (error within the verified bound above), ")
    size = int(line.split("so it takes the ")[1].split("-byte")[0])
    assert size > 4096
    assert "because the exact method cannot be used (" in line
    assert line.endswith("over --max-bytes 4096.")
    assert sorted(p.name for p in out.iterdir()) == ["macvicar_whelan.c", "macvicar_whelan.h"]


def test_exact_python_with_verify(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    python_verify_points: None,
) -> None:
    out = tmp_path / "gen"
    code, text, err = _run(
        capsys, "compile", "three_input", "--target", "python", "--method", "exact",
        "--out", str(out), "--verify",
    )  # fmt: skip
    assert code == 0, err
    assert (
        "method: the exact inference, no table (rounding error only), because you asked for it "
        "(--method exact)." in text
    )
    assert "verify python exact: ok" in text
