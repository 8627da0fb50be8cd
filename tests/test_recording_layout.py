"""What a user sees when opening an .rrd: the blueprint, series names with units, colours that
show on the dark theme, separate unit subtrees, and a surface drawn in normalised coordinates.

Read back with ``rerun rrd print -vvv`` (the file as the viewer gets it).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from _rerun import rrd_dump

from fuzzkit.formats.registry import loads
from fuzzkit.loop.python_loop import run
from fuzzkit.loop.result import RunResult
from fuzzkit.studies.experiments import experiment
from fuzzkit.viz.traces import write_run_rrd


def _dump(path: Path) -> str:
    return rrd_dump(path, "-vvv")


def _series_styles(text: str) -> dict[str, tuple[str, int]]:
    """{series name: (entity, colour as 0xRRGGBBAA)} of every SeriesLines in the dump."""
    styles: dict[str, tuple[str, int]] = {}
    entity = ""
    for line in text.splitlines():
        m = re.search(r"with \d+ rows .*? - (/\S+) - ", line)
        if m:
            entity = m.group(1)
            continue
        m = re.search(r"row_\w+\s+┆ \[(\d+)\]\s+┆ \[([^\]]+)\]", line)
        if m and entity.startswith(("/forces/", "/control/", "/joints/")):
            styles[m.group(2)] = (entity, int(m.group(1)))
    return styles


def _luminance(rgba: int) -> float:
    r, g, b = (rgba >> 24) & 255, (rgba >> 16) & 255, (rgba >> 8) & 255
    return 0.2126 * r + 0.7152 * g + 0.0722 * b


@pytest.fixture(scope="module")
def e1() -> RunResult:
    return run(experiment("E1"), "planar", "pi", seed=1, duration_s=2.4)  # engages at 1.9 s


def test_run_series_carry_units_and_visible_colours(e1: RunResult, tmp_path: Path) -> None:
    styles = _series_styles(_dump(write_run_rrd(e1, tmp_path / "e1.rrd")))
    assert "fz measured (N)" in styles and "fz set point (N)" in styles and "uz (mm)" in styles
    for name, (entity, colour) in styles.items():
        unit = re.search(r"\((N|mm|rad|deg)\)$", name)
        assert unit, f"{entity}: series {name!r} has no unit"
        # one unit per subtree: forces and errors in N, corrections in mm
        if entity.startswith(("/forces/", "/control/error/")):
            assert unit.group(1) == "N", (entity, name)
        elif entity.startswith("/control/correction/"):
            assert unit.group(1) == "mm", (entity, name)
        else:
            assert entity.startswith("/joints/"), entity
        # the viewer's background is near black: every line must stand out from it
        assert _luminance(colour) > 60, f"{name} is too dark ({colour:#010x})"
    for axis in ("x", "z"):  # E1 controls x and z
        entity, colour = styles[f"f{axis} set point (N)"]
        assert entity == f"/forces/{axis}/setpoint" and _luminance(colour) > 150
        assert styles[f"e{axis} (N)"][0] == f"/control/error/{axis}/e"
        assert styles[f"de{axis} (N)"][0] == f"/control/error/{axis}/de"
        assert styles[f"du{axis} (mm)"][0] == f"/control/correction/{axis}/du"


def test_run_recording_ships_its_blueprint(e1: RunResult, tmp_path: Path) -> None:
    text = _dump(write_run_rrd(e1, tmp_path / "e1.rrd"))
    assert re.search(r"store_id: StoreId\(\s*Blueprint,", text), "no blueprint in the file"
    flat = " ".join(text.split())
    for axis in ("x", "z"):  # a column per force-controlled axis: force, error, correction
        for view, origin in [
            (f"force {axis} vs set point (N)", f"forces/{axis}"),
            (f"force error e{axis}, de{axis} (N)", f"control/error/{axis}"),
            (f"position correction du{axis}, u{axis} (mm)", f"control/correction/{axis}"),
        ]:
            assert re.search(rf"\[{re.escape(view)}\] ┆ \[{re.escape(origin)}\]", flat), view
    assert "[3-D scene: E1 pi, planar arm (m)]" in flat
    assert "force y vs set point" not in flat  # y is not force-controlled in E1
    # the 3-D scene's axes are labelled
    for label in ("x (m)", "y (m)", "z (m)"):
        assert label in flat


class _Recorder:
    """Stands in for a RecordingStream: keeps every time series sent, by entity."""

    def __init__(self) -> None:
        self.series: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self.styles: dict[str, Any] = {}

    def log(self, entity: str, value: Any, static: bool = False) -> None:
        self.styles[entity] = value

    def send_columns(self, entity: str, indexes: list[Any], columns: Any) -> None:
        (times,) = indexes
        t = np.asarray(times.as_arrow_array().to_numpy(zero_copy_only=False), dtype=float) / 1e9
        (column,) = list(columns)
        values = np.asarray(column.as_arrow_array().flatten().to_numpy(), dtype=float)
        self.series[entity] = (t, values)


def _logged(result: RunResult, axes: tuple[str, ...] = ("x", "y", "z")) -> _Recorder:
    import rerun as rr

    from fuzzkit.viz.run_series import log_control_series

    rec = _Recorder()
    log_control_series(rec, result, rr.TimeColumn("sim_time", duration=result.t), axes)
    return rec


def test_controller_signals_start_when_the_loop_engages(e1: RunResult) -> None:
    """0 N against a 10 N set point before contact is not "no error": nothing is logged."""
    assert e1.engaged_time_s is not None and e1.engaged_time_s > e1.t[0]
    first = int(np.argmax(e1.t >= e1.engaged_time_s))  # independent of engaged_index
    rec = _logged(e1)
    for axis, i in (("x", 0), ("z", 2)):
        for name, column, scale in (("e", e1.e, 1.0), ("de", e1.de, 1.0), ("du", e1.du, 1e3)):
            entity = f"control/{'error' if name != 'du' else 'correction'}/{axis}/{name}"
            t, v = rec.series[entity]
            assert t[0] == pytest.approx(e1.engaged_time_s)
            np.testing.assert_allclose(t, e1.t[first:])
            np.testing.assert_allclose(v, column[first:, i] * scale)
        # the correction the plant received is real data from the start (0 mm before)
        t, v = rec.series[f"control/correction/{axis}/u"]
        assert t[0] == e1.t[0] and np.all(v[:first] == 0.0)


def test_a_run_that_never_engages_logs_no_controller_signals(e1: RunResult) -> None:
    import dataclasses

    idle = dataclasses.replace(e1, engaged_time_s=None)
    rec = _logged(idle)
    assert not [e for e in rec.series if e.endswith(("/e", "/de", "/du"))]
    assert "control/correction/z/u" in rec.series and "forces/z/measured" in rec.series


def test_planar_recording_has_no_y_stream(e1: RunResult, tmp_path: Path) -> None:
    text = _dump(write_run_rrd(e1, tmp_path / "e1.rrd"))
    entities = set(re.findall(r" - (/\S+) - ", text))
    assert "/forces/x/measured" in entities and "/forces/z/true" in entities
    assert not [e for e in entities if e.startswith(("/forces/y", "/control/error/y"))]


def _hue(rgba: int) -> float:
    import colorsys

    r, g, b = (rgba >> 24) & 255, (rgba >> 16) & 255, (rgba >> 8) & 255
    return colorsys.rgb_to_hsv(r / 255, g / 255, b / 255)[0] * 360


def _hue_gap(a: int, b: int) -> float:
    d = abs(_hue(a) - _hue(b)) % 360
    return min(d, 360 - d)


def test_every_plot_tells_its_lines_apart_by_hue(e1: RunResult, tmp_path: Path) -> None:
    """Not by a shade: x and z, e and de, du and u, and every joint differ in hue (or one of
    the pair is a neutral grey)."""
    styles = _series_styles(_dump(write_run_rrd(e1, tmp_path / "e1.rrd")))

    def neutral(rgba: int) -> bool:
        r, g, b = (rgba >> 24) & 255, (rgba >> 16) & 255, (rgba >> 8) & 255
        return max(r, g, b) - min(r, g, b) < 20

    by_plot: dict[str, list[tuple[str, int]]] = {}
    for name, (entity, colour) in styles.items():
        by_plot.setdefault(entity.rsplit("/", 1)[0], []).append((name, colour))
    pairs = [(a, b) for lines in by_plot.values() for a in lines for b in lines if a < b]
    pairs.append((("fx", styles["fx measured (N)"][1]), ("fz", styles["fz measured (N)"][1])))
    assert len(pairs) > 10
    for (name_a, a), (name_b, b) in pairs:
        assert neutral(a) != neutral(b) or _hue_gap(a, b) >= 30, (name_a, name_b)
    joints = [colour for entity, colour in styles.values() if entity.startswith("/joints/")]
    assert len(joints) == 2 and len(set(joints)) == 2


def test_default_camera_sees_the_whole_arm_base_included(e1: RunResult) -> None:
    from fuzzkit.viz.run_series import scene_eye

    eye, target = (np.asarray(v) for v in scene_eye(e1))
    axis = (target - eye) / np.linalg.norm(target - eye)
    points = np.concatenate([np.asarray(p).reshape(-1, 3) for p in e1.arm_points])
    assert np.allclose(points[0], 0.0)  # the planar arm's base is its first point
    rays = points - eye
    angles = np.degrees(np.arccos(rays @ axis / np.linalg.norm(rays, axis=1)))
    # inside a 25 degree half-angle cone: within the viewer's default field of view
    assert angles.max() < 25.0
    # and outside the scene: the camera does not sit in the arm
    assert np.min(np.linalg.norm(rays, axis=1)) > 0.3
    # extra points (the 6-DOF robot's base box) are taken into the view
    far = np.array([[-1.0, -0.5, 0.0]])
    eye2, target2 = (np.asarray(v) for v in scene_eye(e1, far))
    ray = far[0] - eye2
    axis2 = (target2 - eye2) / np.linalg.norm(target2 - eye2)
    assert np.degrees(np.arccos(ray @ axis2 / np.linalg.norm(ray))) < 25.0


class _Capture:
    """Stands in for an archetype class and records what it was given."""

    def __init__(self, real: Any, store: list[dict[str, Any]]) -> None:
        self.real, self.store = real, store

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        self.store.append({"args": args, **kwargs})
        return self.real(*args, **kwargs)


def test_surface_of_a_non_normalised_rule_base_is_drawn_in_a_unit_cube(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import rerun as rr

    from fuzzkit.fuzzy.inference import Engine
    from fuzzkit.viz.surface import write_surface_rrd

    labels = "[NL, NM, NS, ZR, PS, PM, PL]"
    rb = loads(
        f"""
name: heater
inputs:
  e:  {{range: [-20, 20], terms: {{partition: triangular, labels: {labels}, ends: shoulder}}}}
  de: {{range: [-2, 2], terms: {{partition: triangular, labels: {labels}, ends: shoulder}}}}
outputs:
  power: {{range: [0, 100], terms: {{partition: triangular, labels: {labels}}}}}
defuzzifier: centroid
rules:
  table:
    rows: e
    columns: de
    output: power
    cells: |
      NL NL NL NL NM NS ZR
      NL NL NL NM NS ZR PS
      NL NL NM NS ZR PS PM
      NL NM NS ZR PS PM PL
      NM NS ZR PS PM PL PL
      NS ZR PS PM PL PL PL
      ZR PS PM PL PL PL PL
"""
    )
    meshes: list[dict[str, Any]] = []
    points: list[dict[str, Any]] = []
    texts: list[dict[str, Any]] = []
    monkeypatch.setattr(rr, "TextDocument", _Capture(rr.TextDocument, texts))
    monkeypatch.setattr(rr, "Mesh3D", _Capture(rr.Mesh3D, meshes))
    monkeypatch.setattr(rr, "Points3D", _Capture(rr.Points3D, points))
    path = write_surface_rrd(rb, tmp_path / "heater.rrd", resolution=21)
    (mesh,) = meshes
    v = np.asarray(mesh["vertex_positions"])
    # every axis spans [-1, 1] (the output may not reach its range ends)
    assert v[:, 0].min() == -1.0 and v[:, 0].max() == 1.0
    assert v[:, 1].min() == -1.0 and v[:, 1].max() == 1.0
    assert v[:, 2].min() >= -1.0 and v[:, 2].max() <= 1.0 and np.ptp(v[:, 2]) > 1.0
    # and maps back to the engine's raw values, independently evaluated
    e_raw = -20.0 + (v[:, 0] + 1.0) * 20.0
    de_raw = -2.0 + (v[:, 1] + 1.0) * 2.0
    power = np.asarray(Engine(rb).evaluate({"e": e_raw, "de": de_raw})["power"])
    np.testing.assert_allclose(v[:, 2], power / 50.0 - 1.0, atol=1e-12)
    # tick labels carry raw values at the ends of each axis
    ticks = next(p for p in points if any(lb == "e=-20" for lb in p.get("labels", [])))
    assert {"e=20", "de=-2", "de=2", "power=0", "power=100"} <= set(ticks["labels"])
    # each tick in its axis's colour (x red, y green, z blue), not grey on the grey grid
    for label, colour in zip(ticks["labels"], ticks["colors"], strict=True):
        r, g, b = colour
        assert max(r, g, b) - min(r, g, b) > 100, (label, colour)
        expected = {"e": r, "de": g, "power": b}[label.split("=")[0]]
        assert expected == max(colour), (label, colour)
    flat = " ".join(_dump(path).split())
    assert "e [input 1]" in flat and "power [output]" in flat
    (about,) = texts
    assert "e [-20, 20] (x), de [-2, 2] (y), power [0, 100] (z)" in about["args"][0]
    assert re.search(r"store_id: StoreId\( Blueprint,", flat)


def test_arm6_recording_has_every_axis_and_one_colour_per_joint(tmp_path: Path) -> None:
    from fuzzkit.viz.traces_arm6 import write_rrd

    res = run(experiment("E1"), "arm6", "pi", duration_s=0.3)
    text = _dump(write_rrd(res, tmp_path / "e1_arm6.rrd"))
    entities = set(re.findall(r" - (/\S+) - ", text))
    # the 6-DOF arm has a y axis: its force is recorded (not force-controlled in E1)
    assert {"/forces/y/measured", "/forces/y/true", "/world/robot_base"} <= entities
    assert "/forces/y/setpoint" not in entities
    styles = _series_styles(text)
    joints = {name: colour for name, (entity, colour) in styles.items() if "/joints/" in entity}
    assert sorted(joints) == [f"axis {j} (deg)" for j in range(1, 7)]
    assert len(set(joints.values())) == 6
    for colour in joints.values():
        assert _luminance(colour) > 60  # visible on the dark theme
