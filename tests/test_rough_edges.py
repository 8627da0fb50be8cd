"""What a new user met (issue 41, item 8): exact zeros shown as 0, an IT2 output's interval,
and the other small things each checked where the user sees them."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import pytest

from fuzzkit.cli import main
from fuzzkit.fuzzy.describe import ZERO_ULPS, shown_output
from fuzzkit.fuzzy.model import Variable

ROOT = Path(__file__).resolve().parent.parent


def _eval(capsys: pytest.CaptureFixture[str], *argv: str) -> str:
    assert main(["eval", *argv]) == 0
    return capsys.readouterr().out


# ------------------------------------------------------------------ exact zeros


def test_a_zero_by_symmetry_is_printed_as_0(capsys: pytest.CaptureFixture[str]) -> None:
    # MacVicar-Whelan is the saturated sum of the label indices: at de = -e the surface is 0
    # by symmetry (DESIGN.md), whatever the rounding of the centroid's two integrals
    point = ["macvicar_whelan", "-i", "e=0.3", "-i", "de=-0.3"]
    assert _eval(capsys, *point) == "du = 0.0\n"
    assert json.loads(_eval(capsys, *point, "--json"))["outputs"] == {"du": 0.0}
    explained = _eval(capsys, *point, "--explain")
    assert "du = 0.0 (" in explained and "e-1" not in explained.splitlines()[-1]


def test_the_rule_is_64_ulps_of_the_output_scale() -> None:
    var = Variable(name="du", low=-20.0, high=10.0, terms=())
    ulp = math.ulp(20.0)  # the scale is the larger end's magnitude
    assert shown_output(ZERO_ULPS * ulp, var) == 0.0
    assert shown_output(-ZERO_ULPS * ulp, var) == 0.0
    assert shown_output(2 * ZERO_ULPS * ulp, var) == 2 * ZERO_ULPS * ulp
    assert shown_output(1e-9, var) == 1e-9 and shown_output(-0.25, var) == -0.25
    assert math.isnan(shown_output(math.nan, var))


def test_it2_eval_gives_the_centroid_interval(capsys: pytest.CaptureFixture[str]) -> None:
    point = ["macvicar_whelan_it2", "-i", "e=0.3", "-i", "de=0.1"]
    doc = json.loads(_eval(capsys, *point, "--json"))
    lo, hi = doc["intervals"]["du"]
    du = doc["outputs"]["du"]
    # the rule base reduces by Karnik-Mendel: the output is the interval's midpoint
    assert lo < du < hi and du == pytest.approx(0.5 * (lo + hi), abs=1e-15)
    assert f"du = {du!r} (centroid interval [{lo!r}, {hi!r}])" in _eval(capsys, *point)
    type1 = json.loads(_eval(capsys, "macvicar_whelan", "-i", "e=0.3", "-i", "de=0.1", "--json"))
    assert "intervals" not in type1


# ------------------------------------------------------------------ the rule view's labels


def _extent(x: float, ha: str, width: float) -> tuple[float, float]:
    return {
        "left": (x, x + width),
        "right": (x - width, x),
        "center": (x - width / 2, x + width / 2),
    }[ha]


@pytest.mark.parametrize(
    ("peaks", "names"),
    [
        ([-1.0, -0.1, 0.0, 0.1, 1.0], ["NEG_BIG", "NEG", "ZERO", "POS", "POS_BIG"]),
        ([-1.0, -0.5, 0.0, 0.5, 1.0], ["NL", "NS", "ZR", "PS", "PL"]),
        ([0.0, 0.01, 0.02, 0.03], ["AAAA", "BBBB", "CCCC", "DDDD"]),
    ],
)
def test_term_labels_stay_inside_and_never_overlap(peaks: list[float], names: list[str]) -> None:
    from fuzzkit.viz.explain_plot import term_label_layout

    per_char = 0.04  # a 2-unit range 50 characters wide
    placed = term_label_layout(peaks, names, -1.0, 1.0, per_char)
    assert sorted(p[0] for p in placed) == sorted(names)
    boxes = [(level, *_extent(x, ha, per_char * len(n))) for n, x, ha, level in placed]
    for _level, lo, hi in boxes:
        assert lo >= -1.0 - 1e-12 and hi <= 1.0 + 1e-12  # not clipped at either end
    for i, (la, lo_a, hi_a) in enumerate(boxes):
        for lb, lo_b, hi_b in boxes[i + 1 :]:
            assert la != lb or hi_a <= lo_b or hi_b <= lo_a, (names, boxes)
    by_name = {n: (x, ha) for n, x, ha, _ in placed}
    if peaks[0] == -1.0:  # a term peaking at an end: its label aligned to that end
        assert by_name[names[0]] == (-1.0, "left") and by_name[names[-1]] == (1.0, "right")


# ------------------------------------------------------------------ one .fis typo, one message


def test_one_fis_typo_gives_one_message(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text = (ROOT / "docs" / "examples" / "heater.fis").read_text(encoding="utf-8")
    assert "'zero':'trimf'" in text  # the rules below number this input's terms
    bad = tmp_path / "typo.fis"
    bad.write_text(text.replace("'zero':'trimf'", "'zero':'trimff'", 1), encoding="utf-8")
    assert main(["validate", str(bad)]) == 2
    printed = capsys.readouterr()
    lines = (printed.out + printed.err).splitlines()
    problems = [line for line in lines if "typo.fis:" in line]
    assert len(problems) == 1, problems
    assert "'trimff' (did you mean 'trimf'?)" in problems[0]


# ------------------------------------------------------------------ replay's sensor log


def test_a_missing_log_is_named_without_an_errno(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    spec = str(ROOT / "docs" / "examples" / "controller.yaml")
    missing = tmp_path / "nope.csv"
    assert main(["replay", spec, "--forces", str(missing), "--out", str(tmp_path / "u.csv")]) == 2
    err = capsys.readouterr().err
    assert f"{missing}: cannot read: No such file or directory" in err
    assert "Errno" not in err and not (tmp_path / "u.csv").exists()


@pytest.mark.parametrize("cell", ["nan", "-nan", "NaN", "-NaN", "+nan", "NAN", "-nan(ind)", ""])
def test_every_printf_nan_is_a_missing_sample(tmp_path: Path, cell: str) -> None:
    from fuzzkit.studies.replay import read_sensor_log

    log = tmp_path / "log.csv"
    log.write_text(f"fx,fy,fz\n0,0,1.5\n{cell},0,{cell}\n-inf,inf,2\n", encoding="utf-8")
    forces = read_sensor_log(log).forces
    assert forces[0].tolist() == [0.0, 0.0, 1.5]
    assert math.isnan(forces[1, 0]) and forces[1, 1] == 0.0 and math.isnan(forces[1, 2])
    assert forces[2].tolist() == [-math.inf, math.inf, 2.0]


@pytest.mark.parametrize("cell", ["nann", "n/a", "-", "1.5.2", "nan(x"])
def test_what_is_no_number_is_still_refused_at_its_cell(tmp_path: Path, cell: str) -> None:
    from fuzzkit.errors import ProblemsError
    from fuzzkit.studies.replay import read_sensor_log

    log = tmp_path / "log.csv"
    log.write_text(f"fx,fy,fz\n0,{cell},1\n", encoding="utf-8")
    with pytest.raises(ProblemsError, match=r"log.csv:2:\d+: expected a number"):
        read_sensor_log(log)


# ------------------------------------------------------------------ the run CSV's time column


def test_the_run_csv_times_are_the_decimal_periods() -> None:
    import csv
    import io
    from fractions import Fraction

    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import run_spec
    from fuzzkit.studies.run_table import run_csv

    result = run_spec(RunSpec("E1", plant="planar", loop="python", duration_s=2.0))
    assert float(result.t[-1]) != 2.0  # the plants' sum of 4 ms periods has drifted
    rows = list(csv.DictReader(io.StringIO(run_csv(result))))
    times = [row["t_s"] for row in rows]
    for k, text in enumerate(times, start=1):
        # k periods of 4 ms: the double nearest to the decimal k / 250, printed as that decimal
        assert float(text) == float(Fraction(k, 250)), (k, text)
        assert len(text.partition(".")[2]) <= 3, text
    assert times[-1] == "2.0" and times[468] == "1.876"


# ------------------------------------------------------------------ info SPEC


def test_info_of_a_spec_shows_its_gains_limits_safety_and_front_end(
    capsys: pytest.CaptureFixture[str],
) -> None:
    import yaml

    path = ROOT / "docs" / "examples" / "controller_pi.yaml"
    doc = yaml.safe_load(path.read_text(encoding="utf-8"))  # the file's own numbers
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    for axis, entry in doc["axes"].items():
        g = entry["gains"]
        assert (
            f"axis {axis}: set point {entry['setpoint_n']:g} N; kp {g['kp']:g}, ki {g['ki']:g}"
            in out
        )
    lim, safety, sensor = doc["limits"], doc["safety"], doc["sensor"]
    assert f"|u| <= {lim['correction_m']:g} m per axis, |du| <= {lim['step_m']:g} m" in out
    assert f"limit {safety['limit_n']:g} N (trip after {safety['trip']['samples']} samples" in out
    engage = safety["engage"]
    assert f"engage above {engage['threshold_n']:g} N for {engage['samples']} samples" in out
    assert f"spike gate {safety['spike_gate']['threshold_n']:g} N" in out
    assert f"tare over the first {sensor['tare']['samples']} samples" in out
    assert f"gravity compensation of {sensor['tool']['mass_kg']:g} kg at [0, 0, 0.06] m" in out
    assert f"low-pass {sensor['lowpass_hz']:g} Hz" in out
    assert f"period {doc['period_s'] * 1e3:g} ms" in out


# ------------------------------------------------------------------ a .fis that is a table


def test_a_fis_whose_rules_are_a_full_grid_is_shown_as_the_table(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from fuzzkit.formats.registry import load
    from fuzzkit.fuzzy.describe import full_grid, rule_grid

    fis = tmp_path / "mw.fis"
    assert (
        main(["export", "macvicar_whelan", "--format", "fis", "--out", str(fis), "--allow-loss"])
        == 0
    )
    rb = load(str(fis))
    assert rb.table is None  # MATLAB's format lists the rules one by one
    grid = rule_grid(rb)
    assert grid is not None and (grid.row_input, grid.column_input) == ("e", "de")
    labels = ["NL", "NM", "NS", "ZR", "PS", "PM", "PL"]
    # DESIGN.md: the canonical table is the saturated sum of the label indices
    want = [[labels[min(max(i + j - 6, -3), 3) + 3] for j in range(7)] for i in range(7)]
    assert [list(row) for row in grid.cells] == want
    capsys.readouterr()
    assert main(["info", str(fis)]) == 0
    out = capsys.readouterr().out
    assert "(table: rows e, columns de -> du, listed rule by rule in the file)" in out
    assert "  ZR   NL NM NS ZR PS PM PL" in out and " 1. if e is" not in out
    # one rule missing, or weighted, and it is a list again
    assert full_grid(dataclasses.replace(rb, rules=rb.rules[1:])) is None
    weighted = dataclasses.replace(rb.rules[0], weight=0.5)
    assert full_grid(dataclasses.replace(rb, rules=(weighted, *rb.rules[1:]))) is None
    heater = load(str(ROOT / "docs" / "examples" / "heater.fis"))
    assert rule_grid(heater) is None


# ------------------------------------------------------------------ tuned gains, shortest form


@pytest.mark.parametrize(
    ("value", "text"),
    [(0.00020000000000000004, "0.0002"), (0.1 + 0.2, "0.3"), (4e-05, "4e-05"), (0.05, "0.05")],
)
def test_a_tuned_gain_is_written_in_its_shortest_form(value: float, text: str) -> None:
    from fuzzkit.cli.tuning import GAIN_DIGITS_REL, shortest_gain

    assert repr(shortest_gain(value)) == text
    # a gain the search really found keeps what it is, to 1e-12
    found = 10**-3.123456789
    assert abs(shortest_gain(found) - found) <= GAIN_DIGITS_REL * found
    assert shortest_gain(found) != 10**-3.12


# ------------------------------------------------------------------ safety shown (item 1)


def test_limit_exceeded_is_read_from_the_true_force() -> None:
    import numpy as np

    from fuzzkit.studies.outcome import limit_exceeded, limit_text

    t = np.arange(1, 11) * 0.004
    f = np.zeros((10, 3))
    assert limit_exceeded(t, f, 25.0) is None
    f[4, 0], f[5, 2], f[6, 2] = -26.0, 24.0, 40.0  # x passes first (pushing), z higher later
    got = limit_exceeded(t, f, 25.0)
    assert got == {"time_s": t[4], "peak_true_n": 40.0, "axis": "z"}
    text = limit_text(got, 25.0, tripped=False)
    assert (
        text
        == "limit exceeded: 40.0 N true (z) from 0.020 s, limit 25 N; the controller did not trip"
    )
    f[:, :] = 25.0  # at the limit is not past it
    assert limit_exceeded(t, f, 25.0) is None


def test_a_run_past_the_limit_says_so_and_fails_on_trip(
    capsys: pytest.CaptureFixture[str],
) -> None:
    argv = ["simulate", "E1", "--plant", "arm6", "--latency", "300:300"]
    assert main([*argv, "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    over = doc["limit_exceeded"]
    assert over["peak_true_n"] > doc["safety_limit"] and over["axis"] == "z"
    assert over["peak_true_n"] == max(a["peak_force_true"] for a in doc["axes"].values())
    assert main([*argv, "--fail-on-trip"]) == 3
    assert "SAFETY: limit exceeded: " in capsys.readouterr().out


def test_a_latency_longer_than_half_the_run_is_refused_with_the_range(
    capsys: pytest.CaptureFixture[str],
) -> None:
    # E1 runs 5 s at 4 ms: at most 625 periods of delay in all
    assert main(["simulate", "E1", "--latency", "1000:1000"]) == 2
    err = capsys.readouterr().err
    assert "2000 periods of delay (8 s) is more than half of E1's 5 s run" in err
    assert "0 to 625 periods" in err


# ------------------------------------------------------------------ every run names what ran


def test_simulate_names_the_rule_base_the_spec_and_the_gains(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from fuzzkit.viz.run_figure import run_figure

    png = tmp_path / "run.png"
    argv = ["simulate", "E1", "--rulebase", "macvicar_whelan", "--png", str(png)]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "  ran: rule base macvicar_whelan; gains: the defaults" in out
    assert png.read_bytes()[:4] == b"\x89PNG"
    assert main([*argv[:-2], "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert (doc["rulebase"], doc["controller_spec"], doc["gains_source"]) == (
        "macvicar_whelan",
        None,
        "the defaults",
    )
    assert doc["controller_impl"]  # the implementation, as before
    spec = str(ROOT / "docs" / "examples" / "controller_pi.yaml")
    assert main(["simulate", "E1", "--spec", spec, "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert (doc["rulebase"], doc["controller_spec"]) == (None, "e1_pi")
    assert doc["gains_source"] == "controller spec e1_pi"
    # the figure's title carries the same words
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import run_spec

    result = run_spec(RunSpec("E1", plant="planar", duration_s=1.0))
    title = run_figure(result, "rule base gaussian5; gains: the defaults")._suptitle.get_text()
    assert title.endswith("\nrule base gaussian5; gains: the defaults")


def test_a_sweep_row_holds_the_limit_exceeded_flat() -> None:
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import execute

    row = execute(RunSpec("E1", plant="arm6", latency=(300, 300), duration_s=3.0))
    assert row["limit_exceeded_s"] is not None and row["limit_exceeded_peak_n"] > 25.0
    assert "limit_exceeded" not in row  # no dict in a table's cell
    calm = execute(RunSpec("E1", plant="arm6", duration_s=3.0))
    assert calm["limit_exceeded_s"] is None and calm["limit_exceeded_peak_n"] is None
