"""Traces without Rerun: ``simulate --png/--csv``, ``compare``/``sweep`` ``--png-dir/--csv-dir``."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pytest

from fuzzkit.cli import main
from fuzzkit.loop.result import RunResult
from fuzzkit.loop.spec import RunSpec
from fuzzkit.studies.batch import run_spec
from fuzzkit.studies.run_table import run_columns
from fuzzkit.viz.run_figure import run_figure
from fuzzkit.viz.run_files import write_run_traces

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _read(path: Path) -> tuple[list[str], dict[str, npt.NDArray[np.float64]], list[str]]:
    with path.open(newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    header, body = rows[0], rows[1:]
    cols = {
        name: np.array([float(r[j]) for r in body])
        for j, name in enumerate(header)
        if name != "status"
    }
    return header, cols, [r[-1] for r in body]


@pytest.fixture(scope="module")
def e1() -> RunResult:
    return run_spec(RunSpec("E1", "fuzzy-pi", plant="planar"))


@pytest.fixture(scope="module")
def e1_tripped() -> RunResult:
    return run_spec(RunSpec("E1", "fuzzy-pi", plant="planar", stiffness_n_per_mm=100.0))


def test_csv_holds_the_runs_own_arrays_bit_for_bit(e1: RunResult, tmp_path: Path) -> None:
    path = tmp_path / "run.csv"
    write_run_traces(e1, csv=path)
    header, cols, status = _read(path)
    assert header == run_columns(e1)
    assert len(status) == len(e1.t)
    # the times are computed from the period index, not the plant's sum of periods: within
    # rounding of the run's own clock, and exactly k * 4 ms as decimals (test_rough_edges.py)
    np.testing.assert_allclose(cols["t_s"], e1.t, rtol=0, atol=1e-9)
    for i, a in enumerate("xyz"):
        np.testing.assert_array_equal(cols[f"f{a}_measured_n"], e1.force[:, i])
        np.testing.assert_array_equal(cols[f"f{a}_true_n"], e1.force_true[:, i])
    for i, a in ((0, "x"), (2, "z")):  # E1 controls x and z
        np.testing.assert_array_equal(cols[f"f{a}_setpoint_n"], e1.setpoint[:, i])
        np.testing.assert_array_equal(cols[f"e{a}_n"], e1.e[:, i])
        np.testing.assert_array_equal(cols[f"de{a}_n"], e1.de[:, i])
        np.testing.assert_array_equal(cols[f"du{a}_m"], e1.du[:, i])
        np.testing.assert_array_equal(cols[f"u{a}_m"], e1.u[:, i])
    assert "fy_setpoint_n" not in header  # y is not force-controlled in E1


def test_csv_rows_obey_the_loop_equations(e1: RunResult, tmp_path: Path) -> None:
    path = tmp_path / "run.csv"
    write_run_traces(e1, csv=path)
    _, cols, status = _read(path)
    engaged = np.array([s == "engaged" for s in status])
    assert engaged.sum() > 500 and status[-1] == "engaged"
    # nothing moves before the loop engages
    assert all(s in ("approach", "no sample") for s in status[: int(np.argmax(engaged))])
    for a in ("x", "z"):
        e, f, sp = cols[f"e{a}_n"], cols[f"f{a}_measured_n"], cols[f"f{a}_setpoint_n"]
        # eq. 5 on every engaged period: e = set point - measured force
        np.testing.assert_allclose(e[engaged], (sp - f)[engaged], rtol=0, atol=1e-12)
        # eq. 6: de = e - e of the previous engaged period (0 on the first)
        idx = np.flatnonzero(engaged)
        np.testing.assert_allclose(
            cols[f"de{a}_n"][idx[1:]], e[idx[1:]] - e[idx[:-1]], rtol=0, atol=1e-12
        )
        # eq. 8: u accumulates du (no trip, so no back-off)
        np.testing.assert_allclose(cols[f"u{a}_m"], np.cumsum(cols[f"du{a}_m"]), atol=1e-12)
    # the controlled force ends near its set point (the loop works, read from the file)
    tail = engaged & (cols["t_s"] > cols["t_s"][-1] - 1.0)
    assert abs(float(np.mean(cols["fz_true_n"][tail])) - 10.0) < 0.5


def test_a_trip_shows_in_the_status_and_the_figure(e1_tripped: RunResult, tmp_path: Path) -> None:
    assert e1_tripped.tripped and e1_tripped.trip_time_s is not None
    path = tmp_path / "trip.csv"
    write_run_traces(e1_tripped, csv=path)
    _, cols, status = _read(path)
    first = status.index("tripped")
    assert math.isclose(cols["t_s"][first], e1_tripped.trip_time_s, abs_tol=1e-9)
    assert set(status[first:]) == {"tripped"}
    # the trip fired on a force above the limit
    assert float(np.nanmax(np.abs(cols["fz_measured_n"][: first + 1]))) > 25.0
    fig = run_figure(e1_tripped)
    texts = [t.get_text() for ax in fig.axes for t in ax.texts]
    assert texts.count("TRIP") == 6  # force, error, correction panels of E1's two axes
    assert "TRIPPED at" in fig._suptitle.get_text()
    labels = {ax.get_ylabel() for ax in fig.axes}
    assert {"fz [N]", "fx [N]", "uz [mm]", "duz per period [mm]"} <= labels


def test_simulate_writes_png_and_csv_of_the_run_it_reports(
    e1: RunResult, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    png, out = tmp_path / "run.png", tmp_path / "run.csv"
    code = main(["simulate", "E1", "--plant", "planar", "--png", str(png), "--csv", str(out)])
    assert code == 0
    printed = capsys.readouterr().out
    assert f"wrote {png}" in printed and f"wrote {out}" in printed
    assert png.read_bytes().startswith(PNG_MAGIC)
    _, cols, _ = _read(out)
    np.testing.assert_array_equal(cols["fz_true_n"], e1.force_true[:, 2])  # deterministic


def test_bad_trace_paths_fail_before_the_run_and_write_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    good = tmp_path / "run.csv"
    missing = tmp_path / "no" / "run.png"
    assert main(["simulate", "E1", "--csv", str(good), "--png", str(missing)]) == 2
    assert "folder" in capsys.readouterr().err and not good.exists()
    assert main(["simulate", "E1", "--png", str(tmp_path / "run.jpg")]) == 2
    err = capsys.readouterr().err
    assert "--png" in err and "expected a file name ending in .png" in err
    assert list(tmp_path.iterdir()) == []


def test_compare_writes_one_png_and_csv_per_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pngs, csvs = tmp_path / "png", tmp_path / "csv"
    pngs.mkdir()
    csvs.mkdir()
    args = ["compare", "E1", "--png-dir", str(pngs), "--csv-dir", str(csvs), "--json"]
    assert main(args) == 0
    capsys.readouterr()
    assert sorted(p.name for p in pngs.iterdir()) == ["E1_fuzzy-pi.png", "E1_pi.png"]
    assert sorted(p.name for p in csvs.iterdir()) == ["E1_fuzzy-pi.csv", "E1_pi.csv"]
    _, cols, status = _read(csvs / "E1_pi.csv")
    engaged = np.array([s == "engaged" for s in status])
    np.testing.assert_allclose(
        cols["ez_n"][engaged], (cols["fz_setpoint_n"] - cols["fz_measured_n"])[engaged], atol=1e-12
    )


def test_sweep_takes_a_scenario_file_and_writes_traces_named_in_its_table(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from fuzzkit.studies.scenario_file import shipped_scenario_text

    task = tmp_path / "my_task.yaml"
    task.write_text(shipped_scenario_text("E1"), encoding="utf-8")
    pngs, csvs = tmp_path / "png", tmp_path / "csv"
    pngs.mkdir()
    csvs.mkdir()
    table = tmp_path / "runs.csv"
    args = [
        "sweep", str(task), "--controller", "pi", "--seeds", "2", "--duration", "2.5",
        "--out", str(table), "--png-dir", str(pngs), "--csv-dir", str(csvs),
        "--workers", "1", "--quiet",
    ]  # fmt: skip
    assert main(args) == 0
    assert "2 runs" in capsys.readouterr().out
    with table.open(newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["run"] for r in rows] == ["run0", "run1"]
    assert {r["experiment"] for r in rows} == {str(task)}
    assert sorted(p.name for p in pngs.iterdir()) == ["run0.png", "run1.png"]
    for r in rows:
        _, cols, _ = _read(csvs / f"{r['run']}.csv")
        assert len(cols["t_s"]) == round(2.5 / 0.004)
        # the table's peak is the largest true force of that run's trace
        assert float(r["z_peak_force_true"]) == pytest.approx(
            float(np.max(np.abs(cols["fz_true_n"])))
        )
    # the two seeds are two different runs (their noise differs)
    a, b = (_read(csvs / f"run{i}.csv")[1]["fz_measured_n"] for i in (0, 1))
    assert not np.array_equal(a[np.isfinite(a)], b[np.isfinite(b)])


def test_the_figure_draws_no_error_before_engagement(e1: RunResult) -> None:
    # before engagement no error is computed: a 0 there would read "no error" while 0 N meets
    # the set point
    assert e1.engaged_time_s is not None
    fig = run_figure(e1)
    error_axes = [ax for ax in fig.axes if ax.get_ylabel().startswith("e")]
    assert len(error_axes) == 2  # z and x
    for ax in error_axes:
        t, e = ax.lines[0].get_data()
        before, after = np.asarray(t) < e1.engaged_time_s - 1e-9, np.asarray(t) >= e1.engaged_time_s
        assert before.any() and np.all(np.isnan(np.asarray(e)[before]))
        assert np.all(np.isfinite(np.asarray(e)[after]))
