"""Issue 38's done-when check: the shipped ``sugeno_pi``, a Gaussian-output rule base and a
MATLAB ``.fis`` with ``gaussmf`` outputs through the commands a user runs on them.

Each goes through validate, eval --explain (text and JSON), compile --verify (C float, C
double, Python; the exact method: every rounding bound checked on 1e5 points plus edges),
simulate on every plant, replay (the shipped spec on the rule base, simulated on planar, its
log replayed through the generated C to 0 m), stability, tune and report (``--quick`` on
planar with the shipped gains, about 16 CPU-s each). ``make test`` runs validate and explain
of each; the rest, a few CPU-minutes, runs in ``make verify``.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from fuzzkit.cli import main

DATA = Path(__file__).parent / "data"
RULEBASES = {
    "sugeno_pi": "sugeno_pi",
    "gaussian3x3": str(DATA / "gaussian3x3.yaml"),
    "gauss_outputs_fis": str(DATA / "fis" / "gauss_outputs.fis"),
}
PLANTS = ("planar", "arm6", "mujoco", "mujoco-elastic")


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> str:
    try:
        code = main(list(argv))
    except SystemExit as exc:  # argparse usage errors
        code = int(exc.code or 0)
    out, err = capsys.readouterr()
    assert code == 0, f"fuzzkit {' '.join(argv)}: exit {code}\n{out}\n{err}"
    return out


def _inputs(source: str) -> list[str]:
    """``-i NAME=VALUE`` for each input of the rule base, off its middle."""
    from fuzzkit.formats.registry import load

    rb = load(source)
    args = []
    for k, v in enumerate(rb.inputs):
        args += ["-i", f"{v.name}={v.low + (0.3 + 0.2 * k) * (v.high - v.low)}"]
    return args


@pytest.mark.parametrize("name", sorted(RULEBASES))
def test_validate_and_explain(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    source = RULEBASES[name]
    assert "ok" in _run(capsys, "validate", source)
    text = _run(capsys, "eval", source, "--explain", *_inputs(source))
    json_text = _run(capsys, "eval", source, "--explain", "--json", *_inputs(source))
    value = json.loads(json_text)["outputs"][0]["value"]
    assert f"= {value}" in text  # the text and the JSON show the same number


@pytest.mark.verify
@pytest.mark.parametrize("name", sorted(RULEBASES))
def test_compile_simulate_stability_and_tune(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    source = RULEBASES[name]
    for target, kind in (("c", "float"), ("c", "double"), ("python", "double")):
        folder = str(tmp_path / f"{target}-{kind}")
        out = _run(capsys, "compile", source, "--target", target, "--type", kind, "--method",
                   "exact", "--verify", "--quiet", "--out", folder)  # fmt: skip
        assert ": ok on 100" in out
    for plant in PLANTS:
        run = json.loads(
            _run(capsys, "simulate", "E1", "--rulebase", source, "--plant", plant, "--json")
        )
        assert run["plant"] == plant
    # replay: the shipped spec on this rule base, simulated, then its log through the C
    example = (Path(__file__).parent.parent / "docs" / "examples" / "controller.yaml").read_text()
    spec = tmp_path / "spec.yaml"
    rb_line = (
        f"rulebase: {Path(source).resolve() if source.endswith(('.yaml', '.fis')) else source}"
    )
    spec.write_text(re.sub(r"(?m)^rulebase: .*$", rb_line, example))
    run = tmp_path / "run.csv"
    _run(capsys, "simulate", "E1", "--spec", str(spec), "--plant", "planar", "--csv", str(run))
    out = _run(capsys, "replay", str(spec), "--forces", str(run), "--impl", "c",
               "--out", str(tmp_path / "u.csv"))  # fmt: skip
    assert "largest difference from the run's corrections (u<a>_m): 0 m" in out
    out = _run(capsys, "stability", "E1", "--controller", "fuzzy-pi", "--rulebase", source,
               "--stiffness", "10,20", "--latency", "1:1")  # fmt: skip
    assert "certified" in out
    gains = tmp_path / "gains.yaml"
    out = _run(capsys, "tune", "E1", "--controller", "fuzzy-pi", "--rulebase", source,
               "--budget", "10", "--workers", "1", "--out", str(gains))  # fmt: skip
    assert gains.exists() and "wrote" in out


@pytest.mark.verify
@pytest.mark.parametrize("name", sorted(RULEBASES))
def test_report(name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    source = RULEBASES[name]
    folder = tmp_path / "report"
    gains = Path(__file__).parent.parent / "docs" / "report" / "gains"
    _run(capsys, "report", "--out", str(folder), "--plant", "planar", "--rulebase", source,
         "--quick", "--gains-dir", str(gains), "--no-rrd", "--quiet")  # fmt: skip
    text = (folder / "report.md").read_text("utf-8")
    assert Path(source).stem in text or source in text
    assert (folder / "surface.png").stat().st_size > 0


def test_explain_draws_every_smooth_output_shape(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """eval --explain as text, JSON and the rule-viewer PNG on a rule base whose output has a
    term of every smooth shape but the Gaussian (tests/data/smooth_outputs.yaml)."""
    from fuzzkit.formats.registry import load
    from fuzzkit.fuzzy import shapes
    from fuzzkit.fuzzy.inference import Engine

    source = str(DATA / "smooth_outputs.yaml")
    rb = load(source)
    smooth = {s.name for s in shapes.REGISTRY.values() if s.mu is not None and s.trapezoid is None}
    assert {t.shape for t in rb.outputs[0].terms} == smooth - {"gaussian", "singleton"}
    assert "ok" in _run(capsys, "validate", source)
    point = ["-i", "e=0.2", "-i", "de=-0.3"]
    png = tmp_path / "why.png"
    text = _run(capsys, "eval", source, *point, "--explain", "--png", str(png))
    value = json.loads(_run(capsys, "eval", source, *point, "--explain", "--json"))
    got = value["outputs"][0]["value"]
    assert got == Engine(rb).evaluate_point({"e": 0.2, "de": -0.3})["u"]
    assert f"= {got}" in text
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
