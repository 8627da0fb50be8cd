"""Numerical equivalence with independent implementations: fuzzylite 6 and pyfuzzylite 8.

Files fuzzkit writes are read and evaluated by the peer; files the peer writes are imported by
fuzzkit; the outputs are compared on random points (inside and up to 10 % beyond the input
ranges, where clamping or its absence matters), with the tolerances of
``_peers.largest_difference``. These are the live comparisons; ``make test`` compares with the
peers' committed outputs instead (tests/test_peer_refs.py).

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
    largest_difference,
    needs_fuzzylite,
    needs_pyfuzzylite,
    peer_points,
    pyfuzzylite_eval,
    pyfuzzylite_export,
)
from _random_rulebases import random_rulebase

from fuzzkit.formats import fcl, fis, fll
from fuzzkit.formats.registry import dumps, load
from fuzzkit.fuzzy.inference import evaluate

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "docs" / "examples"
MAMDANI_EXAMPLES = ["heater.fis", "gripper_named.fcl", "feed.fll"]
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
    points = peer_points(rb, seed)
    largest_difference(rb, evaluate(rb, points), fuzzylite_eval(path, fmt, points, tmp_path))


@needs_fuzzylite
@pytest.mark.parametrize("name", MAMDANI_EXAMPLES)
def test_examples_evaluate_the_same_in_fuzzylite(name: str, tmp_path: Path) -> None:
    path = EXAMPLES / name
    rb = load(path)
    points = peer_points(rb, 1)
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
    points = peer_points(rb, 2)
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
    points = peer_points(rb, 3)
    largest_difference(rb, evaluate(rb, points), fuzzylite_eval(path, "fcl", points, tmp_path))


# ---------------------------------------------------------------------------- pyfuzzylite 8


@needs_pyfuzzylite
@pytest.mark.parametrize("seed", range(16))
def test_fll_fuzzkit_writes_evaluates_the_same_in_pyfuzzylite(seed: int, tmp_path: Path) -> None:
    rb = random_rulebase(seed, out_of_range="clamp" if seed % 2 else "extend")
    path = tmp_path / f"{rb.name}.fll"
    path.write_text(fll.dumps(rb).replace(f" {fll.RESOLUTION}", f" {RESOLUTION}"))
    points = peer_points(rb, seed)
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
    points = peer_points(imported, 4)
    largest_difference(
        imported, evaluate(imported, points), pyfuzzylite_eval(theirs, points, tmp_path)
    )


@needs_fuzzylite
@pytest.mark.parametrize("name", ["heater_sugeno.fis", "feed_sugeno.fll"])
def test_sugeno_examples_evaluate_the_same_in_fuzzylite(name: str, tmp_path: Path) -> None:
    # no integration on either side: weighted averages agree to rounding
    path = EXAMPLES / name
    rb = load(path)
    points = peer_points(rb, 5)
    theirs = fuzzylite_eval(path, path.suffix[1:], points, tmp_path)
    ours = evaluate(rb, points)
    for var in rb.outputs:
        np.testing.assert_allclose(ours[var.name], theirs[var.name], rtol=0, atol=1e-9)
