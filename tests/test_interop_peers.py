"""Numerical equivalence with independent implementations: fuzzylite 6 and pyfuzzylite 8.

Files fuzzkit writes are read and evaluated by the peer; files the peer writes are imported by
fuzzkit; the outputs are compared on random points (inside and up to 10 % beyond the input
ranges, where clamping or its absence matters). Tolerances, as fractions of the output range:

* centroid: 1e-6 (fuzzylite integrates on RESOLUTION steps; fuzzkit is exact);
* bisector and the maxima: 2 / RESOLUTION (one integration step). fuzzylite 6 takes values
  within 1e-6 of its running maximum as maximal and samples at step midpoints, so where two
  maxima are that close (a near tie) it may pick the other one: at most 3 % of the points may
  differ for the maxima defuzzifiers, and the rest must agree.

Run them all with ``make interop`` (installs the fuzzylite program and builds .venv-interop).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from _peers import (
    RESOLUTION,
    fuzzylite_convert,
    fuzzylite_eval,
    needs_fuzzylite,
    needs_pyfuzzylite,
    pyfuzzylite_eval,
    pyfuzzylite_export,
)
from _random_rulebases import MAXIMA, random_rulebase

from fuzzkit.formats import fcl, fis, fll
from fuzzkit.formats.registry import dumps, load
from fuzzkit.fuzzy.inference import evaluate
from fuzzkit.fuzzy.model import RuleBase

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "docs" / "examples"
MAMDANI_EXAMPLES = ["heater.fis", "gripper_named.fcl", "feed.fll"]
N_POINTS = 200


def _points(rb: RuleBase, seed: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    return {
        v.name: rng.uniform(
            v.low - 0.1 * (v.high - v.low), v.high + 0.1 * (v.high - v.low), N_POINTS
        )
        for v in rb.inputs
    }


def largest_difference(
    rb: RuleBase, ours: dict[str, np.ndarray], theirs: dict[str, np.ndarray]
) -> float:
    """Check ``theirs`` against ``ours`` with the module's tolerances; the largest difference
    (as a fraction of the output range) over the points that must agree."""
    worst = 0.0
    for var in rb.outputs:
        width = var.high - var.low
        diff = np.abs(ours[var.name] - theirs[var.name]) / width
        assert not np.any(np.isnan(diff)), f"{var.name}: NaN on one side only"
        if rb.defuzzifier == "centroid":
            tol, share = 1e-6, 1.0
        else:
            tol = 2.0 / RESOLUTION
            share = 0.97 if rb.defuzzifier in MAXIMA else 1.0
        agree = diff <= tol
        assert agree.mean() >= share, (
            f"{var.name} ({rb.defuzzifier}): {np.sum(~agree)} of {diff.size} points differ by "
            f"more than {tol:g} of the range, up to {diff.max():.3g}"
        )
        worst = max(worst, float(diff[agree].max()))
    return worst


# ---------------------------------------------------------------------------- fuzzylite 6

FUZZYLITE_FORMATS = ["fis", "fcl", "fll"]


@needs_fuzzylite
@pytest.mark.parametrize("fmt", FUZZYLITE_FORMATS)
@pytest.mark.parametrize("seed", range(16))
def test_files_fuzzkit_writes_evaluate_the_same_in_fuzzylite(
    seed: int, fmt: str, tmp_path: Path
) -> None:
    rb = random_rulebase(seed)
    if fmt == "fis" and fis.refusals(rb):
        pytest.skip(f"not expressible in .fis: {fis.refusals(rb)}")
    path = tmp_path / f"{rb.name}.{fmt}"
    path.write_text(dumps(rb, fmt))
    points = _points(rb, seed)
    largest_difference(rb, evaluate(rb, points), fuzzylite_eval(path, fmt, points, tmp_path))


@needs_fuzzylite
@pytest.mark.parametrize("name", MAMDANI_EXAMPLES)
def test_examples_evaluate_the_same_in_fuzzylite(name: str, tmp_path: Path) -> None:
    path = EXAMPLES / name
    rb = load(path)
    points = _points(rb, 1)
    largest_difference(
        rb, evaluate(rb, points), fuzzylite_eval(path, path.suffix[1:], points, tmp_path)
    )


@needs_fuzzylite
@pytest.mark.parametrize("name", MAMDANI_EXAMPLES)
@pytest.mark.parametrize("fmt", ["fis", "fcl", "fll"])
def test_files_fuzzylite_writes_import_to_the_same_outputs(
    name: str, fmt: str, tmp_path: Path
) -> None:
    src = EXAMPLES / name
    if (name, fmt) == ("feed.fll", "fis"):
        pytest.skip("feed.fll has a rule mixing and/or, which .fis cannot hold")
    written = fuzzylite_convert(src, src.suffix[1:], tmp_path / f"by_fuzzylite.{fmt}")
    rb = load(written)
    points = _points(rb, 2)
    expected = fuzzylite_eval(written, fmt, points, tmp_path)
    largest_difference(rb, evaluate(rb, points), expected)


@needs_fuzzylite
def test_fuzzylite_reads_the_iec_dialect_point_lists_the_same(tmp_path: Path) -> None:
    # fuzzylite reads ACCU only inside DEFUZZIFY and rules in lower case; the point lists and
    # everything else are left as fuzzkit wrote them
    rb = load(EXAMPLES / "gripper_iec.fcl")
    text = fcl.dumps(rb, dialect="iec").replace("  ACCU : MAX;\n", "")
    text = text.replace("  METHOD : COG;", "  METHOD : COG;\n  ACCU : MAX;")
    rules = [
        ln.split(":", 1)[0] + ":" + ln.split(":", 1)[1].lower() if "RULE " in ln else ln
        for ln in text.split("\n")
    ]
    path = tmp_path / "gripper.fcl"
    path.write_text("\n".join(rules))
    points = _points(rb, 3)
    largest_difference(rb, evaluate(rb, points), fuzzylite_eval(path, "fcl", points, tmp_path))


# ---------------------------------------------------------------------------- pyfuzzylite 8


@needs_pyfuzzylite
@pytest.mark.parametrize("seed", range(16))
def test_fll_fuzzkit_writes_evaluates_the_same_in_pyfuzzylite(seed: int, tmp_path: Path) -> None:
    rb = random_rulebase(seed, out_of_range="clamp" if seed % 2 else "extend")
    path = tmp_path / f"{rb.name}.fll"
    path.write_text(fll.dumps(rb).replace(f" {fll.RESOLUTION}", f" {RESOLUTION}"))
    points = _points(rb, seed)
    largest_difference(rb, evaluate(rb, points), pyfuzzylite_eval(path, points, tmp_path))


@needs_pyfuzzylite
@pytest.mark.parametrize("name", ["feed.fll", "heater.fis", "gripper_iec.fcl"])
def test_fll_pyfuzzylite_writes_imports_to_the_same_outputs(name: str, tmp_path: Path) -> None:
    rb = load(EXAMPLES / name)
    ours = tmp_path / "ours.fll"
    ours.write_text(dumps(rb, "fll").replace(f" {fll.RESOLUTION}", f" {RESOLUTION}"))
    theirs = tmp_path / "by_pyfuzzylite.fll"
    theirs.write_text(pyfuzzylite_export(ours))
    imported = load(theirs)
    points = _points(imported, 4)
    largest_difference(
        imported, evaluate(imported, points), pyfuzzylite_eval(theirs, points, tmp_path)
    )


@needs_fuzzylite
@pytest.mark.parametrize("name", ["heater_sugeno.fis", "feed_sugeno.fll"])
def test_sugeno_examples_evaluate_the_same_in_fuzzylite(name: str, tmp_path: Path) -> None:
    # no integration on either side: weighted averages agree to rounding
    path = EXAMPLES / name
    rb = load(path)
    points = _points(rb, 5)
    theirs = fuzzylite_eval(path, path.suffix[1:], points, tmp_path)
    ours = evaluate(rb, points)
    for var in rb.outputs:
        np.testing.assert_allclose(ours[var.name], theirs[var.name], rtol=0, atol=1e-9)
