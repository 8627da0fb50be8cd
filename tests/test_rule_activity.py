"""Closed-loop recordings carry the fuzzy-PI's strongest rules per period, checked by hand."""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest
from _rerun import rerun_cli

from fuzzkit.formats.registry import load
from fuzzkit.loop.python_loop import load_surface, run
from fuzzkit.loop.result import RunResult
from fuzzkit.studies.experiments import DEFAULT_GAINS, experiment
from fuzzkit.studies.run_table import period_status
from fuzzkit.viz.rule_activity import rule_label, strongest_rules
from fuzzkit.viz.traces import write_run_rrd

LABELS = ("NL", "NM", "NS", "ZR", "PS", "PM", "PL")


@pytest.fixture(scope="module")
def e1() -> RunResult:
    return run(
        experiment("E1"), "planar", "fuzzy-pi", surface=load_surface(), duration_s=2.5, seed=2
    )


def _memberships(x: float) -> np.ndarray:
    """MacVicar-Whelan's seven triangles (peaks k/3, half width 1/3) at ``x``."""
    peaks = np.arange(-3, 4) / 3.0
    return np.clip(1.0 - np.abs(x - peaks) * 3.0, 0.0, 1.0)


def test_strongest_rules_are_the_largest_min_of_memberships(e1: RunResult) -> None:
    rb = load("macvicar_whelan")
    gains = DEFAULT_GAINS["fuzzy-pi"]
    (x_axis, z_axis) = strongest_rules(rb, e1, gains)
    assert (x_axis.axis, z_axis.axis) == ("x", "z")
    engaged = [k for k, s in enumerate(period_status(e1)) if s == "engaged"]
    assert len(z_axis.t) == len(engaged) > 100
    np.testing.assert_array_equal(z_axis.t, e1.t[engaged])
    for row in (0, 1, len(engaged) // 2, len(engaged) - 1):
        k = engaged[row]
        en = min(max(gains["ki"] * e1.e[k, 2], -1.0), 1.0)
        den = min(max(gains["kp"] * e1.de[k, 2], -1.0), 1.0)
        table = np.minimum.outer(_memberships(en), _memberships(den))  # rows e, columns de
        expected = np.sort(table.ravel())[::-1][:3]
        np.testing.assert_allclose(z_axis.strengths[row], expected, atol=1e-12)
        # the strongest rule's antecedent is the cell of the largest strength
        i, j = np.unravel_index(int(np.argmax(table)), table.shape)
        if np.sum(table == table[i, j]) == 1:
            label = rule_label(rb, int(z_axis.rules[row, 0]))
            assert label.startswith(f"e is {LABELS[i]} and de is {LABELS[j]} ->"), label


def test_the_recording_carries_them(e1: RunResult, tmp_path: Path) -> None:
    cli = rerun_cli()
    rb = load("macvicar_whelan")
    path = write_run_rrd(e1, tmp_path / "e1.rrd", fuzzy=(rb, {}))
    res = subprocess.run([cli, "rrd", "print", "-vvv", str(path)], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    dump = res.stdout
    (_, z_axis) = strongest_rules(rb, e1, DEFAULT_GAINS["fuzzy-pi"])
    assert f"with {len(z_axis.t)} rows" in dump and "/control/rules/z " in dump
    first = f"{z_axis.strengths[0, 0]:.2f} {rule_label(rb, int(z_axis.rules[0, 0]))}"
    assert first in dump
    assert "[strongest fuzzy rules per period]" in dump  # the blueprint shows them
    # a PI run's recording has none
    pi = run(experiment("E1"), "planar", "pi", duration_s=0.2)
    res = subprocess.run(
        [cli, "rrd", "print", "-vvv", str(write_run_rrd(pi, tmp_path / "pi.rrd", fuzzy=(rb, {})))],
        capture_output=True,
        text=True,
    )
    assert "/control/rules" not in res.stdout
