"""How ``fuzzkit stability`` presents a verdict (issue 40 item 4): a reason for every cell not
certified, fixed-width numbers, and a figure whose labels are whole and whose title names the
controller and its gains."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest

from fuzzkit.cli import main
from fuzzkit.viz.stability_figure import region_title

ARGV = ["stability", "regulate", "--controller", "fuzzy-pi", "--plant", "arm6",
        "--stiffness", "5,20,100", "--latency", "0:0,1:1"]  # fmt: skip


@pytest.fixture(scope="module")
def outputs(tmp_path_factory: pytest.TempPathFactory) -> tuple[str, dict[str, Any], Path]:
    import contextlib
    import io

    png = tmp_path_factory.mktemp("st") / "region.png"
    text, data = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(text):
        assert main([*ARGV, "--png", str(png)]) == 0
    with contextlib.redirect_stdout(data):
        assert main([*ARGV, "--json"]) == 0
    return text.getvalue(), json.loads(data.getvalue()), png


def test_every_cell_not_certified_gets_its_reason(outputs: tuple[str, Any, Path]) -> None:
    text, data, _ = outputs
    refused = [c for c in data["cells"] if not c["certified"]]
    assert refused  # 100 N/mm is refused at both latencies
    lines = text.splitlines()
    for c in refused:
        lat = ":".join(str(p) for p in c["latency_periods"])
        want = f"  {lat}, {c['stiffness_n_per_mm']:g} N/mm: {c['why_not_certified']}"
        assert want in lines, want
    assert f"certified {len(data['cells']) - len(refused)} of {len(data['cells'])} cells" in text


def test_numbers_are_fixed_width(outputs: tuple[str, Any, Path]) -> None:
    text, data, _ = outputs
    # no raw float reprs such as 1.9637458031620783
    assert not re.search(r"\d\.\d{7,}", text), text
    lo, hi = data["model"]["fuzzy"]["phi"]
    assert f"[{lo:9.4f}, {hi:9.4f}]" in text
    lines = text.splitlines()
    start = next(i for i, ln in enumerate(lines) if ln.startswith("region_n (N)"))
    rows = lines[start + 1 : start + 3]
    assert len({len(r) for r in rows}) == 1  # even widths
    cells = [cell for r in rows for cell in r[15:].split()]
    assert all(cell == "-" or re.fullmatch(r"\d+\.\d\d", cell) for cell in cells), cells
    certified = [c for c in data["cells"] if c["certified"]]
    assert sorted(float(x) for x in cells if x != "-") == sorted(
        round(c["region_n"], 2) for c in certified
    )


def test_the_figures_labels_are_whole_and_its_title_names_the_controller(
    outputs: tuple[str, Any, Path],
) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from fuzzkit.viz.stability_figure import region_figure

    _, data, png = outputs
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert region_title(data["model"]) == (
        "regulate: fuzzy-pi on arm6\nfuzzy-pi on macvicar_whelan (exact surface)\n"
        "kp=0.2, ki=0.05, kx=0.0002"
    )
    from fuzzkit.analysis.region import certify_region
    from fuzzkit.analysis.regulation import scenario
    from fuzzkit.analysis.spec_certificate import assumed

    region = certify_region(
        scenario("regulate"), "fuzzy-pi", "arm6", [5.0, 20.0, 100.0], [(0, 0), (1, 1)],
        deployed=assumed("fuzzy-pi", {}, "macvicar_whelan"),
    )  # fmt: skip
    fig = region_figure(region)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    box = fig.bbox
    ax = fig.axes[0]
    artists = [ax.xaxis.label, ax.yaxis.label, ax.title, *fig.legends]
    for artist in artists:
        ext = artist.get_window_extent(renderer)
        assert box.x0 <= ext.x0 and ext.x1 <= box.x1 and box.y0 <= ext.y0 and ext.y1 <= box.y1


def test_a_spec_is_named_in_the_title() -> None:
    model = {
        "scenario": "regulate", "controller": "fuzzy-pi", "plant": "arm6",
        "deployed": {"spec": "e1_fuzzy", "file": "controller.yaml", "axis": "z",
                     "surface": "exact"},
        "gains": {"kp": 0.2, "ki": 0.05, "kx": 0.0002, "u_min": -0.05},
    }  # fmt: skip
    assert region_title(model) == (
        "regulate: fuzzy-pi on arm6\nspec e1_fuzzy, axis z, surface exact\n"
        "kp=0.2, ki=0.05, kx=0.0002"
    )


def test_a_surface_with_no_rest_point_prints_its_bounds_as_none(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Every rule of ``no_rest.yaml`` says positive, so the bounds are of kind ``none``: the
    text says so and why, with the cell's reason (it used to raise KeyError)."""
    rulebase = Path(__file__).parent / "data" / "stability" / "no_rest.yaml"
    argv = ["stability", "regulate", "--controller", "fuzzy-pi", "--plant", "arm6",
            "--rulebase", str(rulebase), "--stiffness", "5", "--latency", "0:0"]  # fmt: skip
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "fuzzy bounds (none): none (" in text
    assert "0:0, 5 N/mm: no rest point: F(e, 0) stays above 0" in text
    assert "certified 0 of 1 cells" in text
