"""``tune --spec SPEC --certify`` certifies the spec as it ships (issue 40 item 4): its front
end, limits, surface and rule base with the candidate gains, not the tuning run's controller."""

from __future__ import annotations

import argparse
import contextlib
import io
import json
from pathlib import Path

import pytest

from fuzzkit.analysis.region import CertifiedOver
from fuzzkit.analysis.regulation import scenario
from fuzzkit.analysis.spec_certificate import SpecCertifiedOver
from fuzzkit.cli import main
from fuzzkit.cli.tuning import _certified_over
from fuzzkit.control.spec_reader import load_spec

EXAMPLE = Path(__file__).resolve().parent.parent / "docs" / "examples" / "controller.yaml"
GAINS = {"kp": 0.2, "ki": 0.05, "kx": 0.0002}


def _spec_with_lowpass(tmp_path: Path, hz: float) -> Path:
    text = EXAMPLE.read_text(encoding="utf-8")
    assert text.count("lowpass_hz: 40.0") == 1
    path = tmp_path / "controller.yaml"
    path.write_text(text.replace("lowpass_hz: 40.0", f"lowpass_hz: {hz}"), encoding="utf-8")
    return path


def _stability_certifies(path: Path) -> bool:
    out = io.StringIO()
    argv = ["stability", "regulate", "--spec", str(path), "--plant", "arm6", "--stiffness",
            "20", "--latency", "0:0", "--json"]  # fmt: skip
    with contextlib.redirect_stdout(out):
        assert main(argv) == 0
    return all(c["certified"] for c in json.loads(out.getvalue())["cells"])


@pytest.mark.parametrize(("hz", "certified"), [(40.0, True), (1.0, False)])
def test_the_predicate_certifies_the_spec_with_its_front_end(
    tmp_path: Path, hz: float, certified: bool
) -> None:
    path = _spec_with_lowpass(tmp_path, hz)
    spec = load_spec(path)
    exp = scenario("regulate")
    shipped = SpecCertifiedOver(exp, spec, "arm6", (20.0,), ((0, 0),))
    assert shipped(GAINS) is certified
    # the same verdict as `fuzzkit stability --spec` on the spec as written
    assert _stability_certifies(path) is certified
    # the tuning run's controller (no front-end filter) would have been certified either way
    assert CertifiedOver(exp, "fuzzy-pi", "arm6", (20.0,), ((0, 0),))(GAINS) is True


def test_tune_with_a_spec_uses_the_specs_predicate(tmp_path: Path) -> None:
    spec = load_spec(EXAMPLE)
    args = argparse.Namespace(certify=[20.0], certify_latency=[(0, 0)], plant="arm6")
    chosen = _certified_over(args, "E1", "fuzzy-pi", "macvicar_whelan", spec)
    assert isinstance(chosen, SpecCertifiedOver) and chosen.spec is spec
    assert isinstance(_certified_over(args, "E1", "fuzzy-pi", "macvicar_whelan"), CertifiedOver)
