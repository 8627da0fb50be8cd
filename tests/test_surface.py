"""Control surfaces: the grid against the engine and the table, the .rrd and .png files."""

from __future__ import annotations

import os
import shutil
import stat
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fuzzkit import evaluate_point, load
from fuzzkit.errors import ConfigError, EvaluationError
from fuzzkit.viz.surface import peak_grid, surface_grid, write_surface_png, write_surface_rrd

RERUN = shutil.which("rerun", path=str(Path(sys.executable).parent)) or shutil.which("rerun")


def test_grid_spans_the_ranges_and_matches_point_evaluation() -> None:
    rb = load("gaussian5")
    x, y, z = surface_grid(rb, 15)
    assert x.shape == y.shape == (15,) and z.shape == (15, 15)
    assert (x[0], x[-1], y[0], y[-1]) == (-1.0, 1.0, -1.0, 1.0)
    for i, j in [(0, 0), (3, 11), (7, 7), (14, 2)]:
        assert z[i, j] == pytest.approx(evaluate_point(rb, e=x[i], de=y[j])["du"], abs=1e-12)


def test_macvicar_grid_at_the_label_peaks_is_the_table() -> None:
    # With 7 points per axis the grid lands on the peaks k/3, where one rule fires alone:
    # the output is that label's centroid (k/3 inside, 8/9 for the range-clipped outer ones).
    _, _, z = surface_grid(load("macvicar_whelan"), 7)
    for i in range(7):
        for j in range(7):
            k = max(-3, min(3, i + j - 6))
            expected = k / 3 if abs(k) < 3 else np.sign(k) * 8 / 9
            assert z[i, j] == pytest.approx(expected, abs=1e-12)


def test_peak_grid_points_and_labels() -> None:
    points, labels = peak_grid(load("paper_table1"))
    assert points.shape == (49, 3)
    assert labels[0] == "e=NL, de=NL" and labels[-1] == "e=PL, de=PL"
    # The shoulders' peaks are the range ends.
    assert tuple(points[0, :2]) == (-1.0, -1.0) and tuple(points[-1, :2]) == (1.0, 1.0)
    # Table I, row PL: (e=PL, de=PS) -> PM, the centroid of PM is 2/3.
    index = labels.index("e=PL, de=PS")
    assert points[index, 2] == pytest.approx(2 / 3, abs=1e-12)


@pytest.mark.parametrize(
    ("name", "kwargs", "error", "match"),
    [
        ("three_input", {"inputs": ("e",)}, EvaluationError, "exactly 2 inputs, got 1"),
        ("three_input", {"inputs": ("e", "x")}, EvaluationError, "unknown input 'x'"),
        ("three_input", {"inputs": ("r", "r")}, EvaluationError, "got 'r' twice"),
        ("three_input", {"fixed": {"e": 0.0}}, EvaluationError, "cannot fix 'e': it is one"),
        ("three_input", {"fixed": {"rr": 0.0}}, EvaluationError, "did you mean 'r'"),
        ("three_input", {"fixed": {"r": 1.5}}, EvaluationError, r"inside its range \[0, 1\]"),
        ("three_input", {"fixed": {"r": float("nan")}}, EvaluationError, "got nan"),
        ("three_input", {"output": "dw"}, EvaluationError, "did you mean 'dv'"),
        ("macvicar_whelan", {"resolution": 1}, ConfigError, "between 2 and 1001, got 1"),
        ("macvicar_whelan", {"resolution": 5000}, ConfigError, "between 2 and 1001"),
        ("macvicar_whelan", {"output": "dv"}, EvaluationError, "unknown output 'dv'"),
    ],
)
def test_surface_grid_rejects(
    name: str, kwargs: dict[str, object], error: type[Exception], match: str
) -> None:
    with pytest.raises(error, match=match):
        surface_grid(load(name), **kwargs)  # type: ignore[arg-type]


@pytest.mark.skipif(RERUN is None, reason="the rerun command-line tool is not installed")
def test_rrd_holds_the_mesh_and_the_peaks(tmp_path: Path) -> None:
    rrd = tmp_path / "surface.rrd"
    write_surface_rrd(load("macvicar_whelan"), rrd, resolution=11)
    assert RERUN is not None
    verify = subprocess.run(
        [RERUN, "rrd", "verify", str(rrd)], capture_output=True, text=True, timeout=60
    )
    assert verify.returncode == 0, verify.stderr
    shown = subprocess.run(
        [RERUN, "rrd", "print", "-v", str(rrd)], capture_output=True, text=True, timeout=60
    )
    assert shown.returncode == 0, shown.stderr
    text = shown.stdout + shown.stderr
    assert "/surface/du@Mesh3D:vertex_positions" in text
    assert "/surface/du@Mesh3D:triangle_indices" in text
    assert "/surface/du@Mesh3D:vertex_colors" in text
    assert "/surface/du/label_peaks@Points3D:positions" in text
    assert "/surface/du/label_peaks@Points3D:labels" in text
    assert "RecordingInfo:start_time" not in text  # no timestamp in the file
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(rrd.stat().st_mode) == 0o666 & ~umask  # not mkstemp's 0600


def test_rrd_is_written_atomically(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import rerun as rr

    target = tmp_path / "surface.rrd"
    target.write_bytes(b"previous")

    def broken(*args: object, **kwargs: object) -> None:
        raise RuntimeError("disk full")

    monkeypatch.setattr(rr, "Mesh3D", broken)
    with pytest.raises(RuntimeError, match="disk full"):
        write_surface_rrd(load("macvicar_whelan"), target, resolution=5)
    assert target.read_bytes() == b"previous"
    assert [p.name for p in tmp_path.iterdir()] == ["surface.rrd"]


def test_png_is_a_png_of_the_requested_size(tmp_path: Path) -> None:
    png = tmp_path / "s.png"
    write_surface_png(load("macvicar_whelan"), png, resolution=11)
    data = png.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    width, height = struct.unpack(">II", data[16:24])  # IHDR
    assert (width, height) == (760, 560)
    assert [p.name for p in tmp_path.iterdir()] == ["s.png"]
