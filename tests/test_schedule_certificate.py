"""Issue 42 item 2: ``fuzzkit stability --spec ADAPTIVE_SPEC`` proves an adaptive spec stable
for any switching of its gain factor (no dwell), or refuses it with the reason and the
estimate error it would need.

The references are independent of the code under test: the factor intervals are worked out by
hand from the example's bands; the certificate's Lyapunov matrix is re-checked in numpy on the
loop's model at factors inside the interval (which the vertex argument says it must cover);
the estimate error needed is the one a schedule's bands allow by construction.
"""

from __future__ import annotations

import dataclasses
import functools
from pathlib import Path

import numpy as np
import pytest

from fuzzkit.analysis.certificate import MIN_MARGIN, verify
from fuzzkit.analysis.inner_loop import identify
from fuzzkit.analysis.loop_model import vertex_matrices
from fuzzkit.analysis.region import axis_loop, fuzzy_part
from fuzzkit.analysis.regulation import regulation_experiment
from fuzzkit.analysis.schedule_certificate import scale_interval
from fuzzkit.analysis.spec_certificate import certify_spec, spec_axis, spec_experiment, spec_gains
from fuzzkit.cli import main
from fuzzkit.control.adaptation_spec import Band
from fuzzkit.control.spec import ControllerSpec, role_ordered
from fuzzkit.control.spec_reader import load_spec

EXAMPLES = Path(__file__).resolve().parent.parent / "docs" / "examples"
ADAPTIVE = EXAMPLES / "controller_adaptive.yaml"


@functools.cache
def adaptive() -> ControllerSpec:
    return load_spec(ADAPTIVE)


def two_bands() -> ControllerSpec:
    """The example with two bands: 0.5 up to 30 N/mm, 0.02 above."""
    spec = adaptive()
    ad = dataclasses.replace(spec.adaptation, bands=(Band(0.5, 30.0), Band(0.02)))
    return dataclasses.replace(spec, adaptation=ad)


@pytest.mark.parametrize(
    ("k_n_mm", "rho", "want"),
    [
        # estimates [10, 30]: band 0 (0.5); the safe and the floor band: 0.02
        (20.0, 0.5, (0.02, 0.5)),
        # [50, 150]: band 1 (0.2); with 0.02
        (100.0, 0.5, (0.02, 0.2)),
        # [25, 75]: bands 0 and 1
        (50.0, 0.5, (0.02, 0.5)),
        # an exact estimate at 500 N/mm: band 2 (0.05)
        (500.0, 0.0, (0.02, 0.05)),
        # 3000 N/mm is beyond k_max: the estimate is projected to 2000, band 3
        (3000.0, 0.5, (0.02, 0.02)),
    ],
)
def test_the_factor_interval_holds_every_band_the_estimate_can_select(
    k_n_mm: float, rho: float, want: tuple[float, float]
) -> None:
    assert scale_interval(adaptive().adaptation, k_n_mm, rho) == want


def test_the_inverse_schedule_s_interval_runs_from_k_max_to_the_lowest_estimate() -> None:
    spec = load_spec(EXAMPLES / "controller_inverse.yaml")
    # estimates [50, 150] N/mm: min(1, 15/k) from 15/2000 (k_max, untrusted) to 15/50
    assert scale_interval(spec.adaptation, 100.0, 0.5) == (15.0 / 2000.0, 0.3)
    # at 5 N/mm the estimate may read 2.5: the factor is capped at 1
    assert scale_interval(spec.adaptation, 5.0, 0.5) == (15.0 / 2000.0, 1.0)


def test_the_self_tuning_factor_interval_is_alpha_s_range() -> None:
    spec = load_spec(EXAMPLES / "controller_selftuning.yaml")
    assert scale_interval(spec.adaptation, 5.0, 0.5) == (0.2, 1.0)


def test_the_lyapunov_function_holds_at_every_factor_inside_the_interval() -> None:
    """A certified cell's P, re-checked on the model at factors strictly inside the interval
    (the vertices' convex hull): every one must decrease V. A certificate built on one end of
    the interval only would not have to."""
    spec = adaptive()
    exp = regulation_experiment(1e4, 12.0)
    k, lat = 20.0, (0, 0)
    region = certify_spec(exp, spec, "arm6", [k], [lat])
    cell = region.cells[0]
    assert cell.certified and cell.lyapunov_p is not None
    lo, hi = scale_interval(spec.adaptation, k, 0.5)
    ax = spec_axis(spec, None)
    task = spec_experiment(exp, spec, ax)
    assert spec.rulebase is not None
    fuzzy = fuzzy_part(role_ordered(spec, spec.rulebase), 1.0, spec.surface)
    inner = identify("arm6")
    sector = cell.contact_sector
    assert sector is not None
    for s in np.linspace(lo, hi, 9):
        loop = axis_loop(task, "fuzzy-pi", spec_gains(spec, ax), inner, fuzzy, k * 1e3, lat,
                         sector[0], spec.sensor.lowpass_hz, (float(s), float(s)))  # fmt: skip
        assert verify(cell.lyapunov_p, vertex_matrices(loop)) >= MIN_MARGIN, s


def test_a_schedule_too_hot_for_its_estimate_error_is_refused_with_the_rho_it_needs() -> None:
    """At 40 N/mm, latency 1:1, the two-band schedule's 0.5 band is not stable; with rho 0.5
    the estimate may read 20-60 N/mm and select it; within rho 0.2 (32-48 N/mm) it cannot."""
    exp = regulation_experiment(1e4, 12.0)
    region = certify_spec(exp, two_bands(), "arm6", [40.0], [(1, 1)])
    ad = region.model["adaptation"]
    assert not region.cells[0].certified
    assert ad["certified_every_cell"] is False and ad["rho_needed"] == 0.2
    assert ad["gain_factor_per_stiffness"] == {"40": [0.02, 0.5]}
    proved = certify_spec(exp, two_bands(), "arm6", [40.0], [(1, 1)], rho=0.2)
    assert proved.cells[0].certified


def test_stability_proves_an_adaptive_spec_or_refuses_it(
    capsys: pytest.CaptureFixture[str],
) -> None:
    args = ["stability", "regulate", "--spec", str(ADAPTIVE), "--plant", "arm6"]
    assert main([*args, "--stiffness", "20,500", "--latency", "0:0"]) == 0
    out = capsys.readouterr().out
    assert "certified 2 of 2 cells" in out
    assert "proved: in every cell, one quadratic Lyapunov function" in out
    assert "20 N/mm [0.02, 0.5], 500 N/mm [0.02, 0.05]" in out
    # at 1:1 the example's own band at 500 N/mm (0.05) has an unstable vertex
    assert main([*args, "--stiffness", "500", "--latency", "1:1"]) == 0
    out = capsys.readouterr().out
    assert "refused: not every cell is certified" in out
    assert "not even with an exact estimate (rho 0)" in out
    assert "spectral radius >= 1" in out
