"""Figures a user looks at: ``fuzzkit plot``, surfaces over any two inputs, the report's
figures, the notebook display of a rule base, and that none of it touches pyplot's backend."""

from __future__ import annotations

import html.parser
import math
import re
import struct
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from fuzzkit import evaluate_point, load
from fuzzkit.cli import main
from fuzzkit.formats.yaml_reader import load_file
from fuzzkit.fuzzy.model import RuleBase
from fuzzkit.viz import rulebase_plot
from fuzzkit.viz.figures import figure_bytes
from fuzzkit.viz.rulebase_plot import plot_rulebase
from fuzzkit.viz.study_figures import force_figure, stiffness_figure
from fuzzkit.viz.surface import surface_axes, surface_figure, surface_grid

DATA = Path(__file__).parent / "data"
TEMPERATURE = DATA / "temperature_pd.yaml"
SHIPPED = ("macvicar_whelan", "paper_table1", "gaussian5", "three_input")
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def temperature() -> RuleBase:
    return load_file(TEMPERATURE)


def _table_from_yaml(path: Path) -> list[list[str]]:
    """The cells block of a table rule base read as plain text (independent of the loader)."""
    lines = path.read_text().splitlines()
    start = next(i for i, line in enumerate(lines) if line.strip() == "cells: |") + 1
    return [line.split() for line in lines[start:] if line.strip()]


# --------------------------------------------------------------------------- fuzzkit plot


@pytest.mark.parametrize("name", [*SHIPPED, str(TEMPERATURE)])
def test_plot_writes_a_png(tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str) -> None:
    png = tmp_path / "rb.png"
    code, out, err = run(capsys, "plot", name, "--out", str(png))
    assert code == 0, err
    data = png.read_bytes()
    assert data[:8] == PNG_MAGIC
    width, height = struct.unpack(">II", data[16:24])
    assert width == 1250 and height >= 460
    assert out == f"wrote {png}\n"
    assert [p.name for p in tmp_path.iterdir()] == ["rb.png"]


def test_plot_writes_a_valid_svg_without_a_date(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    first, second = tmp_path / "a.svg", tmp_path / "b.svg"
    for path in (first, second):
        assert run(capsys, "plot", "three_input", "-o", str(path))[0] == 0
    root = ET.parse(first).getroot()
    assert root.tag == "{http://www.w3.org/2000/svg}svg"
    assert first.read_bytes() == second.read_bytes()  # deterministic: no timestamp


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["macvicar_whelan", "--png", "x.pdf"],
            "--png x.pdf: expected a file name ending in .png or .svg",
        ),
        (["macvicar_whelan", "--png", "x"], "got 'no suffix'"),
        (["macvicar_whelan", "--out", "no/such/x.png"], "folder no/such does not exist"),
        (["no_such_rulebase", "--out", "x.png"], "no_such_rulebase"),
    ],
)
def test_plot_refuses_bad_arguments_and_writes_nothing(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    args: list[str],
    message: str,
) -> None:
    monkeypatch.chdir(tmp_path)
    code, _, err = run(capsys, "plot", *args)
    assert code == 2
    assert message in err and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []


def test_plot_failure_leaves_the_previous_file_whole(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    target = tmp_path / "rb.png"
    target.write_bytes(b"previous")

    def broken(*args: object, **kwargs: object) -> None:
        raise ValueError("renderer failed")

    monkeypatch.setattr(rulebase_plot, "plot_rulebase", broken)
    code, _, err = run(capsys, "plot", "macvicar_whelan", "--out", str(target))
    # a renderer's own ValueError is fuzzkit's fault, not the user's: an internal error (exit 1)
    assert code == 1 and "internal error" in err and "renderer failed" in err
    assert target.read_bytes() == b"previous"
    assert [p.name for p in tmp_path.iterdir()] == ["rb.png"]


def test_plot_has_one_panel_per_variable_with_units_and_the_rule_table() -> None:
    rb = temperature()
    fig = plot_rulebase(rb)
    panels, rules = fig.axes[:-1], fig.axes[-1]
    assert [ax.get_xlabel() for ax in panels] == [
        "input e [K]",
        "input de [K/s]",
        "output heat [%]",
    ]
    # Every cell of the YAML table, in place: row i, column j at data position (j, i).
    expected = _table_from_yaml(TEMPERATURE)
    cells = {
        (round(t.get_position()[1]), round(t.get_position()[0])): t.get_text() for t in rules.texts
    }
    assert [[cells[i, j] for j in range(5)] for i in range(5)] == expected
    assert [t.get_text() for t in rules.get_xticklabels()] == ["NB", "NS", "ZE", "PS", "PB"]
    assert rules.get_ylabel() == "rows: e [K]"


def test_plotted_membership_functions_are_the_shapes() -> None:
    # Closed forms of the partition's triangles: NS of e peaks at -10, reaches 0 at -20 and 0.
    fig = plot_rulebase(temperature())
    e_panel = fig.axes[0]
    curves = [line for line in e_panel.get_lines() if len(line.get_xdata()) > 2]
    assert len(curves) == 5
    x, mu = (np.asarray(a, dtype=float) for a in curves[1].get_data())
    for at, want in [
        (-20.0, 0.0),
        (-15.0, 0.5),
        (-10.0, 1.0),
        (-2.5, 0.25),
        (0.0, 0.0),
        (15.0, 0.0),
    ]:
        assert np.interp(at, x, mu) == pytest.approx(want, abs=1e-12)
    assert (x[0], x[-1]) == (-20.0, 20.0)


def test_list_rules_are_shown_as_numbered_sentences() -> None:
    rb = load("three_input")
    fig = plot_rulebase(rb)
    assert len(fig.axes) == len(rb.inputs) + len(rb.outputs) + 1
    text = fig.axes[-1].texts[0].get_text().replace("\u00a0", " ")
    assert text.splitlines()[0] == " 1. if e is P and de is P then du is PB"
    assert "12. if r is rough and e is P then du is PS  (weight 0.6)" in text
    assert " 3. if e is Z and de is Z then du is ZE and dv is faster  (weight 0.7)" in text


def test_a_long_rule_list_is_cut_with_a_note() -> None:
    rb = load("three_input")
    many = RuleBase(rb.name, rb.inputs, rb.outputs, rb.rules * 10, rb.operators)
    text = plot_rulebase(many).axes[-1].texts[0].get_text()
    assert "more lines (fuzzkit info lists every rule)" in text.splitlines()[-1]
    assert len(text.splitlines()) < 120


# --------------------------------------------------------------------------- surfaces


def test_surface_over_two_inputs_of_three_holds_the_others() -> None:
    rb = load("three_input")
    x, y, z = surface_grid(rb, 9, "dv", inputs=("e", "r"), fixed={"de": 0.2})
    assert (x[0], x[-1], y[0], y[-1]) == (-1.0, 1.0, 0.0, 1.0)
    for i, j in [(0, 0), (2, 7), (4, 4), (8, 1)]:
        want = evaluate_point(rb, e=x[i], de=0.2, r=y[j])["dv"]
        assert z[i, j] == pytest.approx(want, abs=1e-12)


def test_surface_holds_unfixed_inputs_at_the_middle_of_their_range() -> None:
    rb = load("three_input")
    axes = surface_axes(rb, inputs=("de", "e"))
    assert axes.fixed == {"r": 0.5}
    _, _, z = surface_grid(rb, 5, inputs=("de", "e"))
    assert z[1, 3] == pytest.approx(evaluate_point(rb, de=-0.5, e=0.5, r=0.5)["du"], abs=1e-12)


def test_surface_cli_with_inputs_and_fix(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    png = tmp_path / "s.png"
    code, out, err = run(
        capsys, "surface", "three_input", "--png", str(png), "--inputs", "e,r",
        "--fix", "de=0.5", "--output", "dv", "--resolution", "11",
    )  # fmt: skip
    assert code == 0, err
    assert png.read_bytes()[:8] == PNG_MAGIC
    assert "dv at the label peaks (9 points, de = 0.5)" in out
    lines = out.splitlines()
    assert lines[2].split() == ["e\\r", "smooth", "medium", "rough"]
    rb = load("three_input")
    # Row e=N (peak -1), column r=rough (sigmoid peaks at the range end, 1).
    want = evaluate_point(rb, e=-1.0, de=0.5, r=1.0)["dv"]
    assert float(lines[3].split()[3]) == pytest.approx(want, abs=1e-4)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--inputs", "e"], "--inputs 'e': expected two input names"),
        (["--inputs", "e,x"], "unknown input 'x' for the surface"),
        (["--inputs", "e,,"], "expected two input names"),
        (["--fix", "de"], "--fix 'de': expected NAME=VALUE"),
        (["--fix", "de=abc"], "--fix 'de=abc': expected a number for 'de'"),
        (["--fix", "dd=0"], "unknown input 'dd' (did you mean 'de'?)"),
        (["--fix", "r=0.2", "--fix", "r=0.3"], "input 'r' given twice"),
        (["--fix", "e=0"], "cannot fix 'e': it is one of the surface's two axes (e, de)"),
        (["--inputs", "e,r", "--fix", "de=2"], "inside its range [-1, 1], got 2"),
        (["--inputs", "e,r", "--fix", "de=inf"], "got inf"),
        (["--rrd", "s.rrd"], "--rrd needs a rule base with exactly 2 inputs"),
    ],
)
def test_surface_cli_refuses_bad_inputs_and_fix(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    args: list[str],
    message: str,
) -> None:
    monkeypatch.chdir(tmp_path)
    code, _, err = run(capsys, "surface", "three_input", "--png", "s.png", *args)
    assert code == 2
    assert message in err and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []


def _render(fig: Any) -> np.ndarray:
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(int).copy()


def _label_to_ticks_px(fig: Any, axis: Any) -> float:
    """Pixels between an axis label and its nearest tick label, measured on the rendered
    image (3-D tick labels report unusable window extents): each is found as the pixels that
    change when it alone is hidden."""
    from scipy import ndimage

    full = _render(fig)
    axis.label.set_visible(False)
    no_label = _render(fig)
    axis.label.set_visible(True)
    for tick in axis.get_ticklabels():
        tick.set_visible(False)
    no_ticks = _render(fig)
    for tick in axis.get_ticklabels():
        tick.set_visible(True)
    label = np.any(full != no_label, axis=2)
    ticks = np.any(full != no_ticks, axis=2)
    assert label.any() and ticks.any()
    return float(ndimage.distance_transform_edt(~ticks)[label].min())


#: The old layout had the ``de`` label 3.6 px from the ``-0.25`` tick label (5.1 px for K/s).
MIN_LABEL_GAP_PX = 10.0


@pytest.mark.parametrize("name", ["macvicar_whelan", "temperature"])
def test_surface_figure_has_units_a_colour_bar_and_no_label_collisions(name: str) -> None:
    rb = temperature() if name == "temperature" else load(name)
    fig = surface_figure(rb, resolution=11)
    ax3d, bar = fig.axes
    out = rb.outputs[0]
    unit = f" [{out.units}]" if out.units else ""
    assert bar.get_ylabel() == out.name + unit
    assert bar.get_ylim() == (out.low, out.high)
    if name == "temperature":
        assert (ax3d.get_xlabel(), ax3d.get_ylabel(), ax3d.get_zlabel()) == (
            "e [K]",
            "de [K/s]",
            "heat [%]",
        )
    for axis in (ax3d.xaxis, ax3d.yaxis, ax3d.zaxis):
        assert _label_to_ticks_px(fig, axis) >= MIN_LABEL_GAP_PX, axis.label.get_text()


# --------------------------------------------------------------------------- report figures


def _fake_run(
    t: np.ndarray,
    fz: np.ndarray,
    contact_at: float,
    fx: np.ndarray | None = None,
    trip_at: float | None = None,
) -> SimpleNamespace:
    force = np.zeros((t.size, 3))
    force[:, 2] = fz
    if fx is not None:
        force[:, 0] = fx
    setpoint = np.zeros((t.size, 3))
    setpoint[:, 2] = 10.0
    return SimpleNamespace(
        t=t,
        force_true=force,
        setpoint=setpoint,
        in_contact=t >= contact_at,
        force_normal=np.full((t.size, 3), np.nan),  # no normal forces: contact is in_contact
        moving=(t >= 2.5) & (t <= 4.0),
        tripped=trip_at is not None,
        trip_time_s=trip_at,
        experiment=SimpleNamespace(selection=(True, False, True)),
    )


def _fake_results(
    fx_peak: dict[str, float] | None = None, trip: tuple[str, str] | None = None
) -> dict[tuple[str, str], SimpleNamespace]:
    t = np.arange(1, 1251) * 0.004
    rise = np.clip(t - 1.9, 0.0, None)
    runs = {}
    for ctrl in ("pi", "fuzzy-pi"):
        for label, tau in (("default", 0.04), ("tuned", 0.02)):
            peak = (fx_peak or {}).get(ctrl, 0.0)
            fx = peak * np.exp(-(((t - 3.0) / 0.2) ** 2))
            trip_at = 4.5 if trip == (ctrl, label) else None
            runs[(ctrl, label)] = _fake_run(t, 10.0 * (1 - np.exp(-rise / tau)), 1.9, fx, trip_at)
    return runs


def _rgba(colour: Any) -> tuple[float, ...]:
    from matplotlib.colors import to_rgba

    return tuple(round(c, 3) for c in to_rgba(colour)[:3])


def _trace_colours(ax: Any) -> set[tuple[float, ...]]:
    """Colours of the data lines of ``ax`` (not the black set point, not trip markers)."""
    return {
        _rgba(line.get_color())
        for line in ax.get_lines()
        if line.get_marker() in ("None", "", None, "o") and _rgba(line.get_color()) != (0, 0, 0)
    }


def _trip_marks(ax: Any) -> list[tuple[float, float]]:
    from fuzzkit.viz.palette import TRIP_STYLE

    return [
        (float(x), float(y))
        for line in ax.get_lines()
        if line.get_marker() == TRIP_STYLE["marker"]
        for x, y in zip(line.get_xdata(), line.get_ydata(), strict=True)
    ]


def test_force_figure_shows_both_gains_in_every_panel_and_one_legend() -> None:
    from fuzzkit.viz.palette import GAINS_STYLE

    fig = force_figure(_fake_results(), "E1", zoom_s=0.3)
    panels = fig.axes  # the insets are children of the panels
    assert len(panels) == 4
    for ax in panels:
        # two runs (default, tuned) and the set point per panel
        assert len(ax.get_lines()) == 3
        widths = sorted(line.get_linewidth() for line in ax.get_lines()[:2])
        # The default is drawn under the tuned line and wider, so it shows around it.
        assert widths == sorted((GAINS_STYLE["tuned"][1], GAINS_STYLE["default"][1]))
        assert ax.get_legend() is None
    assert len(fig.legends) == 1
    assert [t.get_text() for t in fig.legends[0].get_texts()] == [
        "default gains",
        "tuned gains",
        "set point",
    ]


def test_force_figure_rows_share_their_y_scale() -> None:
    """A 25 N and a 41 N peak side by side must not look alike (E3's x rows)."""
    fig = force_figure(_fake_results({"pi": 25.0, "fuzzy-pi": 41.0}), "E3")
    z_row, x_row = fig.axes[0:2], fig.axes[2:4]
    assert z_row[0].get_ylim() == z_row[1].get_ylim()
    assert x_row[0].get_ylim() == x_row[1].get_ylim()
    assert x_row[0].get_ylim()[1] >= 41.0  # the larger peak fits in both panels
    # the bigger peak is drawn higher on the shared scale (pixels, as a reader sees them)
    fig.canvas.draw()
    tops = [
        ax.transData.transform((3.0, peak))[1] for ax, peak in zip(x_row, (25.0, 41.0), strict=True)
    ]
    assert tops[1] > tops[0] + 20


def test_force_figure_marks_a_trip_where_it_happened() -> None:
    from fuzzkit.viz.palette import TRIP_LABEL

    fig = force_figure(_fake_results(trip=("fuzzy-pi", "tuned")), "E1")
    pi_z, fuzzy_z, pi_x, fuzzy_x = fig.axes
    assert _trip_marks(pi_z) == [] and _trip_marks(pi_x) == []
    for ax in (fuzzy_z, fuzzy_x):
        (mark,) = _trip_marks(ax)
        assert mark[0] == pytest.approx(4.5, abs=0.004)
    assert TRIP_LABEL in [t.get_text() for t in fig.legends[0].get_texts()]
    calm = force_figure(_fake_results(), "E1")
    assert all(_trip_marks(ax) == [] for ax in calm.axes)
    assert TRIP_LABEL not in [t.get_text() for t in calm.legends[0].get_texts()]


def test_force_figure_error_row_shows_the_window_the_rms_counts() -> None:
    runs = _fake_results()
    fig = force_figure(runs, "E2", error_while_moving=True)
    assert len(fig.axes) == 6  # z, x and the error row, per controller
    pi_err, fuzzy_err = fig.axes[4], fig.axes[5]
    assert pi_err.get_ylim() == fuzzy_err.get_ylim()
    # moving from 2.5 s to 4.0 s, contact at 1.9 s: counted from max(2.5, 1.9 + 0.5)
    lo, hi = pi_err.get_xlim()
    assert lo == pytest.approx(2.5, abs=0.005) and hi == pytest.approx(4.0, abs=0.005)
    run = runs[("pi", "default")]
    line = pi_err.get_lines()[0]
    y = np.asarray(line.get_ydata(), dtype=float)
    inside = (run.t >= 2.5) & (run.t <= 4.0)
    np.testing.assert_allclose(y[inside], 10.0 - run.force_true[inside, 2])
    assert np.isnan(y[~inside]).all()
    rms = math.sqrt(float(np.mean((10.0 - run.force_true[inside, 2]) ** 2)))
    assert f"default {rms:.2f} N" in pi_err.get_title(loc="left")


def test_force_figure_zoom_inset_spans_the_first_contact() -> None:
    fig = force_figure(_fake_results(), "E1", zoom_s=0.3)
    insets = [child for ax in fig.axes for child in ax.child_axes]
    assert len(insets) == 4  # one per panel
    for ins in insets:
        lo, hi = ins.get_xlim()
        assert lo < 1.9 < hi and hi - lo == pytest.approx(0.3)
    no_zoom = force_figure(_fake_results(), "E2")
    assert not any(ax.child_axes for ax in no_zoom.axes)


def _metrics(
    overshoot: float | None, settling: float | None, tripped: bool = False
) -> dict[str, Any]:
    return {"overshoot_pct": overshoot, "settling_time_s": settling, "tripped": float(tripped)}


def _study() -> dict[tuple[str, str], list[tuple[float, dict[str, Any]]]]:
    return {
        ("pi", "default"): [(5.0, _metrics(0.0, 0.2)), (50.0, _metrics(3.0, 0.05)),
                            (500.0, _metrics(400.0, None)), (1000.0, _metrics(2842.0, None, True))],
        ("fuzzy-pi", "tuned"): [(5.0, _metrics(1.0, 0.1)), (50.0, _metrics(5.0, None)),
                                (500.0, _metrics(500.0, None)), (1000.0, _metrics(900, 0.3, True))],
    }  # fmt: skip


def test_stiffness_figure_uses_log_axes_and_a_never_settled_row() -> None:
    fig = stiffness_figure(_study())
    overshoot, settling, _, never = fig.axes
    assert overshoot.get_yscale() == settling.get_yscale() == "log"
    assert overshoot.get_xscale() == settling.get_xscale() == "log"
    # Never-settled runs are not drawn at an invented time on the settling axis...
    for line in settling.get_lines():
        y = np.asarray(line.get_ydata(), dtype=float)
        assert np.nanmax(y) <= 0.2
    # ... but as x markers in their own row, at exactly their stiffnesses (tripped runs are
    # in the trip row, not here).
    marks = {
        i: sorted(np.asarray(line.get_xdata(), dtype=float).tolist())
        for i, line in enumerate(never.get_lines())
    }
    assert marks == {0: [500.0], 1: [50.0, 500.0]}
    assert [t.get_text() for t in never.get_yticklabels()] == ["PI default", "fuzzy-PI tuned"]
    assert "never settled" in never.get_title(loc="left")
    # The zero overshoot sits on the floor, with the note explaining the marker.
    assert any("below 0.1 %" in t.get_text() for t in overshoot.texts)
    assert "planar plant" in fig.get_suptitle()
    assert figure_bytes(fig)[:8] == PNG_MAGIC


def test_stiffness_figure_ticks_are_plain_numbers_and_the_legend_shows_the_dots() -> None:
    # issue 41: 1-1.5 % overshoot on a log axis was labelled 1.5x10^0 ... 10^0, and the legend
    # drew bare line styles beside series drawn as dots on lines
    rows = [(k, {"overshoot_pct": o, "settling_time_s": s}) for k, o, s in
            ((5.0, 1.0, 0.11), (10.0, 1.2, 0.13), (20.0, 1.5, 0.3))]  # fmt: skip
    fig = stiffness_figure({("pi", "default"): rows, ("fuzzy-pi", "matched"): rows})
    figure_bytes(fig)  # the labels are made at draw time
    overshoot, settling, trip, _ = fig.axes
    for ax in (overshoot, settling):
        labels = [t.get_text() for t in ax.get_yticklabels(which="both") if t.get_text()]
        assert labels and all(re.fullmatch(r"[0-9.]+", t) for t in labels), labels
    assert {"1", "1.5"} <= {t.get_text() for t in overshoot.get_yticklabels(which="both")}
    assert [t.get_text() for t in trip.get_xticklabels()] == ["5", "10", "20"]
    legend = fig.legends[0]
    assert [t.get_text() for t in legend.get_texts()] == ["PI default", "fuzzy-PI matched"]
    assert all(h.get_marker() == "o" for h in legend.legend_handles)


def test_stiffness_figure_marks_trips_instead_of_plotting_their_overshoot() -> None:
    fig = stiffness_figure(_study(), "arm6")
    overshoot, settling, tripped, _ = fig.axes
    for ax in (overshoot, settling):
        for line in ax.get_lines():
            x = np.asarray(line.get_xdata(), dtype=float)
            y = np.asarray(line.get_ydata(), dtype=float)
            assert not np.isfinite(y[x == 1000.0]).any()  # no 2,842 % from a stopped run
    assert sorted(_trip_marks(tripped)) == [(1000.0, 0.0), (1000.0, 1.0)]
    assert "tripped" in tripped.get_title(loc="left")
    assert "arm6 plant" in fig.get_suptitle()


def _sweep_rows() -> list[dict[str, Any]]:
    rows = []
    for ctrl in ("pi", "fuzzy-pi"):
        for seed in range(3):
            never = ctrl == "fuzzy-pi" and seed == 1
            trip = ctrl == "pi" and seed == 2
            rows.append({
                "experiment": "E1", "controller": ctrl, "plant": "arm6", "seed": seed,
                "stiffness_n_per_mm": 10.0, "sensor_delay": 1, "command_delay": 1,
                "gains": "default", "tripped": trip,
                "z_overshoot_pct": 2000.0 if trip else 5.0 + seed,
                "z_settling_time_s": None if never else 0.2 + 0.1 * seed,
                "z_steady_state_error_std": 0.1, "z_peak_force": 60.0 if trip else 12.0,
            })  # fmt: skip
    return rows


def test_sweep_figure_keeps_two_specs_apart_and_names_them() -> None:
    # issue 41: two specs of one kind were one series, their mean drawn as if over seeds
    from fuzzkit.viz.sweep_figure import sweep_figure

    rows = []
    for spec, overshoot in (("specs/a.yaml", 1.0), ("specs/b.yaml", 3.0)):
        row = dict(_sweep_rows()[3], controller_spec=spec, gains=spec, tripped=False)
        rows.append({**row, "z_overshoot_pct": overshoot, "z_settling_time_s": 0.2})
    fig = sweep_figure(rows)
    overshoot = fig.axes[0]
    bars = sorted(p.get_height() for p in overshoot.patches)
    assert bars == [1.0, 3.0]  # one bar per spec, each its own run: no 2.0 mean of both
    names = [t.get_text() for t in fig.legends[0].get_texts()]
    assert names == ["spec a (fuzzy-PI)", "spec b (fuzzy-PI)"]
    colours = {tuple(p.get_facecolor()) for p in overshoot.patches}
    assert len(colours) == 2


def test_sweep_specs_name_a_specs_gains_after_it() -> None:
    from fuzzkit.studies.sweep import sweep_specs

    spec = str(Path(__file__).parent.parent / "docs" / "examples" / "controller.yaml")
    runs = sweep_specs(["E1"], ["pi"], controller_specs=[spec])
    assert [r.gains_label for r in runs] == [spec]


def test_sweep_figure_keeps_never_settled_and_tripped_runs_and_names_the_plant() -> None:
    from fuzzkit.viz.palette import TRIP_LABEL
    from fuzzkit.viz.sweep_figure import NEVER_SETTLED_LABEL, sweep_figure

    fig = sweep_figure(_sweep_rows())
    overshoot, settling, _, peak = fig.axes
    assert "arm6 plant" in fig.get_suptitle()
    assert [ax.get_ylabel() for ax in fig.axes] == [
        "overshoot [%]",
        "settling time [s]",
        "steady error std [N]",
        "peak force [N]",
    ]
    case = peak.get_xticklabels()[0].get_text()
    assert "10 N/mm" in case and "latency 1:1 periods" in case

    def dots(ax: Any) -> list[float]:
        return sorted(
            float(y) for line in ax.get_lines() if line.get_marker() == "o"
            for y in line.get_ydata()
        )  # fmt: skip

    # the tripped PI run's 2,000 % is not a dot; its 60 N peak force is
    assert 2000.0 not in dots(overshoot) and 60.0 in dots(peak)
    # the never-settled fuzzy-PI run is a cross on the settling panel, the trip a red X
    crosses = [line for line in settling.get_lines() if line.get_marker() == "x"]
    assert len(crosses) == 1 and len(crosses[0].get_xdata()) == 1
    assert len(_trip_marks(overshoot)) == len(_trip_marks(settling)) == 1
    assert _trip_marks(peak) == []
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert any(NEVER_SETTLED_LABEL in t for t in legend)
    assert any(TRIP_LABEL in t for t in legend)
    assert figure_bytes(fig)[:8] == PNG_MAGIC


def test_each_controller_keeps_one_colour_in_every_figure() -> None:
    from fuzzkit.studies.latency_sweep import StabilityMap
    from fuzzkit.viz.latency import stability_figure
    from fuzzkit.viz.sweep_figure import sweep_figure

    seen: dict[str, set[tuple[float, ...]]] = {"pi": set(), "fuzzy-pi": set()}
    force = force_figure(_fake_results(), "E1", zoom_s=0.3)
    for ax in force.axes:
        ctrl = "pi" if ax.get_title() == "PI" or ax in force.axes[0::2] else "fuzzy-pi"
        seen[ctrl] |= _trace_colours(ax)
        for ins in ax.child_axes:
            seen[ctrl] |= _trace_colours(ins)
    study = stiffness_figure(_study())
    for line in study.axes[0].get_lines() + study.axes[1].get_lines():
        ctrl = "fuzzy-pi" if line.get_label().startswith("fuzzy") else "pi"
        if not line.get_label().startswith("_"):
            seen[ctrl].add(_rgba(line.get_color()))
    sweep = sweep_figure(_sweep_rows())
    for patch, ctrl in zip(sweep.legends[0].get_patches(), ("pi", "fuzzy-pi"), strict=True):
        seen[ctrl].add(_rgba(patch.get_facecolor()))
    maps = [
        StabilityMap(c, (1.0, 2.0), (0, 1), ((True, True), (True, False)))
        for c in ("pi", "fuzzy-pi")
    ]
    for line, ctrl in zip(
        stability_figure(maps).axes[0].get_lines()[:2], ("pi", "fuzzy-pi"), strict=True
    ):
        seen[ctrl].add(_rgba(line.get_color()))
    assert len(seen["pi"]) == 1 and len(seen["fuzzy-pi"]) == 1, seen
    assert seen["pi"] != seen["fuzzy-pi"]


# --------------------------------------------------------------------------- notebooks


BACKEND_SCRIPT = """
import sys, matplotlib
before = matplotlib.get_backend()
import fuzzkit
from fuzzkit.viz.rulebase_plot import plot_rulebase, write_rulebase_plot
from fuzzkit.viz.surface import surface_figure, write_surface_png
rb = fuzzkit.load("three_input")
fig1 = plot_rulebase(rb)
fig2 = surface_figure(rb, resolution=5, inputs=("e", "r"))
write_rulebase_plot(rb, sys.argv[1] + "/p.png")
write_surface_png(rb, sys.argv[1] + "/s.png", resolution=5)
print(before, matplotlib.get_backend(), "matplotlib.pyplot" in sys.modules,
      type(fig1).__name__, type(fig2).__name__)
"""


def test_no_global_backend_change_and_no_pyplot(tmp_path: Path) -> None:
    # A notebook's backend must survive: run where the backend is set to a non-Agg one.
    proc = subprocess.run(
        [sys.executable, "-c", BACKEND_SCRIPT, str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=120,
        env={"MPLBACKEND": "svg", "PATH": "/usr/bin:/bin"},
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["svg", "svg", "False", "Figure", "Figure"]


class _Collect(html.parser.HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.stack: list[str] = []
        self.cells: list[str] = []
        self.ok = True

    def handle_starttag(self, tag: str, attrs: Any) -> None:
        self.stack.append(tag)

    def handle_endtag(self, tag: str) -> None:
        self.ok &= bool(self.stack) and self.stack.pop() == tag

    def handle_data(self, data: str) -> None:
        if {"td", "th", "li"} & set(self.stack):
            self.cells.append(data)


def test_markdown_repr_lists_variables_units_operators_and_the_table() -> None:
    rb = temperature()
    md = rb._repr_markdown_()
    assert "| input | `e` | [-20, 20] | K | NB NS ZE PS PB |" in md
    assert "| input | `de` | [-2, 2] | K/s | NB NS ZE PS PB |" in md
    assert "| output | `heat` | [0, 100] | % | NONE LOW MID HIGH FULL |" in md
    assert "and=min, or=max, implication=min, aggregation=max; defuzzifier centroid" in md
    rows = [line for line in md.splitlines() if line.startswith("| **")]
    table = [[c.strip() for c in row.strip("|").split("|")][1:] for row in rows]
    assert table == _table_from_yaml(TEMPERATURE)


def test_html_repr_is_well_formed_escaped_and_complete() -> None:
    rb = temperature()
    hostile = RuleBase(
        rb.name,
        rb.inputs,
        rb.outputs,
        rb.rules,
        rb.operators,
        description="<script>x</script> & co",
    )
    text = hostile._repr_html_()
    assert "<script>" not in text and "&lt;script&gt;x&lt;/script&gt; &amp; co" in text
    parser = _Collect()
    parser.feed(rb._repr_html_())
    assert parser.ok and parser.stack == []
    start = parser.cells.index("input")
    assert parser.cells[start : start + 5] == ["input", "e", "[-20, 20]", "K", "NB NS ZE PS PB"]
    table = _table_from_yaml(TEMPERATURE)
    for label in ("NONE", "LOW", "MID", "HIGH", "FULL"):  # one cell each, as in the YAML
        assert parser.cells.count(label) == sum(row.count(label) for row in table)


def test_list_rules_repr_has_every_rule_as_a_sentence() -> None:
    rb = load("three_input")
    md = rb._repr_markdown_()
    assert "1. if e is P and de is P then du is PB" in md
    assert "8. if r is medium and e is not Z then dv is slower  (weight 0.5)" in md
    parser = _Collect()
    parser.feed(rb._repr_html_())
    assert parser.ok
    items = [c for c in parser.cells if c.startswith("if ")]
    assert len(items) == len(rb.rules) == 12


def test_display_mixin_keeps_the_model_a_frozen_slotted_record() -> None:
    rb = temperature()
    assert not hasattr(rb, "__dict__")  # slots survive the mixin
    with pytest.raises(AttributeError):
        rb.name = "other"  # type: ignore[misc]
    assert hash(rb) == hash(temperature()) and rb == temperature()
