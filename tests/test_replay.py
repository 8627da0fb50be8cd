"""``fuzzkit replay`` (issue 20 item 3) and ``fuzzkit compile SPEC``: the reference and the
generated C on one hostile log, strict CSV reading with located errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import numpy.typing as npt
import pytest
from _codegen_util import needs_cc
from _replay_logs import SPEC, SPEC_PI, read_out, run_cli, write_log

from fuzzkit.control.reference import Controller
from fuzzkit.control.spec_reader import load_spec
from fuzzkit.studies.sensor_logs import hostile_log


def hostile_csv(
    tmp_path: Path, n: int, seed: int
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], Path]:
    """A hostile log for the fuzzy-PI example spec, written as ``log.csv``: forces, rotations,
    the file."""
    forces, rotations = hostile_log(load_spec(SPEC), n=n, seed=seed)
    log = tmp_path / "log.csv"
    write_log(log, forces, rotations)
    return forces, rotations, log


@needs_cc
def test_replay_reference_and_c_agree_on_a_hostile_log(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    spec = load_spec(SPEC)
    forces, rotations = hostile_log(spec, n=200, seed=3)
    log = tmp_path / "log.csv"
    write_log(log, forces, rotations, nan_word=True)
    outs = {}
    for impl in ("reference", "c"):
        out = tmp_path / f"u_{impl}.csv"
        code, stdout, err = run_cli(
            capsys, "replay", str(SPEC), "--forces", str(log), "--out", str(out), "--impl", impl
        )
        assert code == 0, err
        assert f"{len(forces)} samples replayed" in stdout
        outs[impl] = read_out(out)
    head, py = outs["reference"]
    assert head == ["t", "ux", "uy", "uz", "status"] and outs["c"][0] == head
    c = outs["c"][1]
    assert py.shape == (len(forces), 5)
    np.testing.assert_array_equal(py[:, 0], np.arange(len(forces)) * 0.004)
    assert float(np.max(np.abs(py[:, 1:4] - c[:, 1:4]))) <= 1e-9
    np.testing.assert_array_equal(py[:, 4], c[:, 4])
    # --impl reference is the reference controller itself, sample by sample
    ref = Controller(spec)
    want = [ref.step(list(f), list(r)) for f, r in zip(forces, rotations, strict=True)]
    np.testing.assert_array_equal(py[:, 1:4], np.array([u for u, _ in want]))
    np.testing.assert_array_equal(py[:, 4], [s for _, s in want])
    assert len(set(py[:, 4].astype(int))) >= 6  # the log is hostile: many kinds of status


def test_replay_without_time_or_rotation_for_a_spec_without_a_tool(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import dataclasses

    from fuzzkit.control.spec import SensorSpec

    spec = dataclasses.replace(load_spec(SPEC_PI), sensor=SensorSpec())
    forces, _ = hostile_log(spec, n=60, seed=1)
    log = tmp_path / "log.csv"
    write_log(log, forces, None, times=False)
    spec_file = tmp_path / "pi.yaml"
    text = SPEC_PI.read_text()
    spec_file.write_text(text.split("sensor:")[0] + "adaptation: none\n")
    out = tmp_path / "u.csv"
    code, _, err = run_cli(
        capsys, "replay", str(spec_file), "--forces", str(log), "--out", str(out),
        "--impl", "reference",
    )  # fmt: skip
    assert code == 0, err
    head, got = read_out(out)
    assert head == ["ux", "uy", "uz", "status"]
    ref = Controller(load_spec(spec_file))
    want = np.array([ref.step(list(f))[0] for f in forces])
    np.testing.assert_array_equal(got[:, :3], want)


GOOD_HEAD = "t,fx,fy,fz"


@pytest.mark.parametrize(
    "text, where, message",
    [
        ("", ":1:1", "expected a header row"),
        ("fx,fy\n1,2\n", ":1:1", "column 'fz' is missing"),
        ("t,fx,fy,fz,fw\n0,1,2,3,4\n", ":1:12", "unknown column 'fw'"),
        ("fx,fy,fz,fx\n1,2,3,4\n", ":1:10", "column 'fx' appears twice"),
        ("fx,fy,fz,r11,r12\n1,2,3,1,0\n", ":1:1", "rotation columns incomplete"),
        (GOOD_HEAD + "\n0,1,2\n", ":2:6", "expected 4 cells"),
        (GOOD_HEAD + "\n0,1,abc,3\n", ":2:5", "got 'abc'"),
        (GOOD_HEAD + "\n0,1,1_000,3\n", ":2:5", "got '1_000'"),
        (GOOD_HEAD + '\n0,1,"2",3\n', ":2:5", "got '\"2\"'"),
        (GOOD_HEAD + "\n0,1,2,3\n\n0.1,1,2,3\n", ":3:1", "blank line inside the log"),
        (GOOD_HEAD + "\n0,1,2,3\n0,1,2,3\n", ":3:1", "t must increase"),
        (GOOD_HEAD + "\n,1,2,3\n", ":2:1", "t must be a finite time"),
        (GOOD_HEAD + "\n", ":2:1", "header but no rows"),
    ],
)
def test_malformed_logs_are_located_errors_and_nothing_is_written(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, where: str, message: str
) -> None:
    log = tmp_path / "log.csv"
    log.write_text(text)
    out = tmp_path / "u.csv"
    code, _, err = run_cli(capsys, "replay", str(SPEC_PI), "--forces", str(log), "--out", str(out))
    assert code == 2
    assert f"{log}{where}: " in err and message in err, err
    assert "Traceback" not in err
    assert not out.exists() and list(tmp_path.iterdir()) == [log]


def test_a_log_without_rotation_for_a_spec_with_a_tool_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "log.csv"
    log.write_text("fx,fy,fz\n1,2,3\n")
    out = tmp_path / "u.csv"
    code, _, err = run_cli(capsys, "replay", str(SPEC), "--forces", str(log), "--out", str(out))
    assert code == 2 and f"{log}:1:1: " in err and "r11,r12,...,r33" in err
    assert not out.exists()


def test_a_log_that_is_not_utf8_is_a_located_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "log.csv"
    log.write_bytes(b"fx,fy,fz\n1,2,3\n\xff\xfe,1,2\n")
    code, _, err = run_cli(
        capsys, "replay", str(SPEC_PI), "--forces", str(log), "--out", str(tmp_path / "u.csv")
    )
    assert code == 2 and f"{log}:3: not UTF-8 text" in err


# ------------------------------------------------------------------------- fuzzkit compile SPEC


@pytest.mark.parametrize(
    "target, extra, files",
    [
        ("python", [], ["e1_fuzzy_controller.py"]),
        pytest.param(
            "c", ["--type", "double"],
            [f"e1_fuzzy_{part}.{ext}" for part in ("controller", "surface") for ext in "ch"],
            marks=needs_cc,
        ),
    ],
)  # fmt: skip
def test_compile_spec_verifies_and_writes_the_controller(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    target: str,
    extra: list[str],
    files: list[str],
) -> None:
    out = tmp_path / "gen"
    code, stdout, err = run_cli(
        capsys, "compile", str(SPEC), "--target", target, *extra, "--out", str(out), "--verify"
    )
    assert code == 0, err
    assert "verify: ok" in stdout and "0 status mismatches" in stdout
    assert sorted(p.name for p in out.iterdir()) == files


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--target", "c", "--method", "table"], "--method table applies to rule bases"),
        (["--target", "c", "--tolerance", "1e-3"], "--tolerance applies to rule bases"),
        (["--target", "c", "--type", "q15"], "the controller computes in float or double"),
        (["--target", "python", "--type", "float"], "the python target computes in double"),
        (["--target", "rust"], "unknown target 'rust'"),
    ],
)
def test_compile_spec_refuses_options_it_cannot_honour(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str], message: str
) -> None:
    out = tmp_path / "gen"
    code, _, err = run_cli(capsys, "compile", str(SPEC), *argv, "--out", str(out))
    assert code == 2 and message in err, err
    assert not out.exists()


def test_compile_of_a_bad_spec_is_a_located_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(SPEC_PI.read_text().replace("limit_n: 25.0", "limit_n: 5.0"))
    code, _, err = run_cli(
        capsys, "compile", str(bad), "--target", "c", "--out", str(tmp_path / "gen")
    )
    assert code == 2 and f"{bad}:" in err and "Traceback" not in err
    assert not (tmp_path / "gen").exists()


# ------------------------------------------------------------- issue 33 item 3: a readable replay


def test_log_problems_are_sorted_by_line_with_plain_numbers(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "log.csv"
    # row 5 has a cell too few: it is skipped, and the time check must still name lines right
    log.write_text(
        GOOD_HEAD + "\n0.0,1,2,3\n0.016,1,2,3\n0.008,1,x,3\n0.024,1,2\n0.02,1,2,3\n0.012,1,2,3\n"
    )
    code, _, err = run_cli(
        capsys, "replay", str(SPEC_PI), "--forces", str(log), "--out", str(tmp_path / "u.csv")
    )
    assert code == 2 and "np.float64" not in err, err
    lines = [line for line in err.splitlines() if line.startswith(str(log))]
    assert lines == [
        f"{log}:4:1: t must increase (got 0.008 s after 0.016 s)",
        f"{log}:4:9: expected a number, an empty cell or nan, got 'x'",
        f"{log}:5:10: expected 4 cells (as the header), got 3",
        f"{log}:7:1: t must increase (got 0.012 s after 0.02 s)",
    ]


def test_a_bad_header_lists_every_problem_and_a_bad_body_the_first_20(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "log.csv"
    names = [f"w{k}" for k in range(25)]
    log.write_text("fx," + ",".join(names) + ",fx\n")
    code, _, err = run_cli(
        capsys, "replay", str(SPEC_PI), "--forces", str(log), "--out", str(tmp_path / "u.csv")
    )
    assert code == 2
    located = [line for line in err.splitlines() if line.startswith(f"{log}:1:")]
    # 25 unknown columns, fx twice, fy and fz missing: all 28, by column
    assert len(located) == 28 and "28 problems found" in err
    cols = [int(line.split(":")[2]) for line in located]
    assert cols == sorted(cols)
    # a body with 30 bad rows: the first 20 by line, and a word that the reader stopped
    log.write_text(GOOD_HEAD + "\n" + "".join(f"{k},1,oops,3\n" for k in range(30)))
    code, _, err = run_cli(
        capsys, "replay", str(SPEC_PI), "--forces", str(log), "--out", str(tmp_path / "u.csv")
    )
    located = [line for line in err.splitlines() if line.startswith(f"{log}:")]
    assert code == 2 and "the reader stopped there" in err
    assert [int(line.split(":")[1]) for line in located] == list(range(2, 22))


def test_status_names_decode_the_bits(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from fuzzkit.control import status as st

    *_, log = hostile_csv(tmp_path, 120, 2)
    outs = {}
    for fmt in ("bits", "names"):
        out = tmp_path / f"u_{fmt}.csv"
        code, _, err = run_cli(
            capsys, "replay", str(SPEC), "--forces", str(log), "--out", str(out),
            "--status", fmt,
        )  # fmt: skip
        assert code == 0, err
        outs[fmt] = [line.split(",")[-1] for line in out.read_text().splitlines()[1:]]
    seen = set()
    for bits, names in zip(outs["bits"], outs["names"], strict=True):
        # decoded independently: each name is set exactly when its bit is
        want = [name for name, bit in st.BITS.items() if int(bits) & bit]
        assert names == ("|".join(want) or "0")
        seen.update(want)
    assert {"ENGAGED", "HELD", "TRIPPED", "TARING"} <= seen


def test_impl_python_runs_the_generated_module(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    spec = load_spec(SPEC)
    forces, rotations, log = hostile_csv(tmp_path, 150, 5)
    out = tmp_path / "u.csv"
    code, stdout, err = run_cli(
        capsys, "replay", str(SPEC), "--forces", str(log), "--out", str(out),
        "--impl", "python",
    )  # fmt: skip
    assert code == 0 and "generated Python controller" in stdout, err
    _, got = read_out(out)
    # the module that `compile --target python` writes, imported here on its own
    from fuzzkit.codegen.verify import load_module
    from fuzzkit.loop.controller_code import generate

    module = load_module(generate(spec, "python"), f"{spec.name}_controller")
    ctl = module.Controller()
    want = [ctl.step(list(f), list(r)) for f, r in zip(forces, rotations, strict=True)]
    np.testing.assert_array_equal(got[:, 1:4], np.array([list(u) for u, _ in want]))
    np.testing.assert_array_equal(got[:, 4], [s for _, s in want])


@needs_cc
def test_replay_runs_the_generated_controller_unless_the_reference_is_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # --impl has simulate --controller-impl's names and meaning: auto (the default) is the
    # generated C where a compiler exists, python the generated Python, reference the reference
    forces, rotations, log = hostile_csv(tmp_path, 150, 4)
    runs, said = {}, {}
    for impl in ("auto", "c", "python", "reference"):
        out = tmp_path / f"u_{impl}.csv"
        extra = [] if impl == "auto" else ["--impl", impl]
        code, stdout, err = run_cli(
            capsys, "replay", str(SPEC), "--forces", str(log), "--out", str(out), *extra
        )
        assert code == 0, err
        runs[impl], said[impl] = read_out(out)[1], stdout.splitlines()[0]
    assert "by the generated C (double) controller" in said["auto"] == said["c"]
    assert "by the generated Python controller" in said["python"]
    assert "by the reference controller" in said["reference"]
    np.testing.assert_array_equal(runs["auto"], runs["c"])
    # the reference is the reference controller itself, and the generated code is not it
    ref = Controller(load_spec(SPEC))
    want = np.array([ref.step(list(f), list(r))[0] for f, r in zip(forces, rotations, strict=True)])
    np.testing.assert_array_equal(runs["reference"][:, 1:4], want)
    assert float(np.max(np.abs(runs["c"][:, 1:4] - want))) <= 1e-9


def test_every_command_names_the_implementations_alike() -> None:
    from fuzzkit.loop.generated import GENERATED_IMPLS
    from fuzzkit.loop.spec import CONTROLLER_IMPLS
    from fuzzkit.ros2.controller import IMPLS as ROS2_IMPLS
    from fuzzkit.studies.replay import IMPLS

    assert IMPLS == CONTROLLER_IMPLS == ("auto", "c", "python", "reference")
    assert ROS2_IMPLS == GENERATED_IMPLS == CONTROLLER_IMPLS[:3]


@needs_cc
def test_compare_prints_the_largest_difference_per_column(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    *_, log = hostile_csv(tmp_path, 150, 7)
    runs = {}
    for impl in ("reference", "python", "c"):
        out = tmp_path / f"u_{impl}.csv"
        argv = ["--out", str(out), "--impl", impl, "--type", "float"]
        assert run_cli(capsys, "replay", str(SPEC), "--forces", str(log), *argv)[0] == 0
        runs[impl] = read_out(out)[1]
    code, stdout, err = run_cli(
        capsys, "replay", str(SPEC), "--forces", str(log), "--compare", "--type", "float"
    )
    assert code == 0, err
    assert "generated C (float)" in stdout
    for k, col in enumerate(("ux (m)", "uy (m)", "uz (m)")):
        gen, c = (float(x) for x in _row(stdout, col))
        ref = runs["reference"][:, 1 + k]
        # printed to 3 significant digits
        want_gen = float(np.max(np.abs(runs["python"][:, 1 + k] - ref)))
        want_c = float(np.max(np.abs(runs["c"][:, 1 + k] - ref)))
        assert gen == pytest.approx(want_gen, rel=5e-3) and c == pytest.approx(want_c, rel=5e-3)
    assert float(_row(stdout, "uz (m)")[1]) > 0  # float C does differ from the double reference
    want_status = [
        int(np.count_nonzero(runs[i][:, 4] != runs["reference"][:, 4])) for i in ("python", "c")
    ]
    assert [int(v) for v in _row(stdout, "status (rows differing)")] == want_status


def _row(stdout: str, label: str) -> list[str]:
    """The cells after ``label`` in the printed comparison table."""
    for line in stdout.splitlines():
        if line.strip().startswith(label):
            return line.strip()[len(label) :].split()
    raise AssertionError(f"no row {label!r} in {stdout}")
